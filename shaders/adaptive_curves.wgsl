// The adaptive integrator's pass for curve chains (entry point integrate_adaptive_curves): the chain's
// features from a scan along the ray, cuts at its kinks, jumps, knots and joints, then Gauss-Kronrod pairs in u
// between the cuts with the nearest point carried node to node. Twin: src/reference/adaptive_curves.rs.
#import shared/adaptive.wgsl

// A chain's nearest point to the ray's point at t. Twin of ChainSample.
struct ChainSample {
    t: f32,
    param: f32,      // the chain parameter of the nearest point
    d2: f32,
    known: f32,      // 1 where the velocity is known, 0 where it is infinite (a center of curvature)
    point: vec3<f32>,
    slope: f32,      // d(d^2)/dt
    velocity: vec3<f32>,
    curvature: f32,  // d^2(d^2)/dt^2, -F32_MAX where the velocity is unknown
    rate: f32,       // the rate of the chain parameter along the ray (0 where the velocity is)
    at_joint: bool,  // the nearest point is an end or a joint of the chain (within END_SNAP)
}

// Twin of ChainSample::at: the nearest point, its velocity along the ray from the stationarity
// (C(u) - L(t)) . C'(u) = 0, at rest at an end of the chain unless `moving`.
fn chain_sample(ray: Ray, t: f32, moving: bool) -> ChainSample {
    let c = curves[ray.index];
    let p = ray.start + ray.dir * t;
    let n = curve_nearest(c, p);
    let k = c.segment_count;
    let x = clamp(n.x, 0.0, 1.0) * f32(k);
    let j = min(u32(floor(x)), k - 1u);
    let seg = segments[c.first_segment + j];
    let local = x - f32(j);
    let point = segment_at(seg, local);
    let d1 = 2.0 * seg.c2 * local + seg.c1;
    let denominator = dot(d1, d1) - dot(p - point, 2.0 * seg.c2);
    var velocity = vec3<f32>(0.0);
    var rate = 0.0;
    var known = 1.0;
    var curvature = 2.0 * dot(ray.dir, ray.dir);
    if moving || (local > 0.0 && local < 1.0) {
        if denominator > 0.0 {
            rate = dot(d1, ray.dir) / denominator;
            velocity = d1 * rate;
            curvature = 2.0 * dot(ray.dir, ray.dir - velocity);
        } else {
            known = 0.0;
            curvature = -F32_MAX;
        }
    }
    let at_joint = abs(x - round(x)) <= END_SNAP * f32(k);
    return ChainSample(t, n.x, n.y * n.y, known, point, 2.0 * dot(p - point, ray.dir), velocity, curvature, rate / f32(k), at_joint);
}

// Where the nearest point would be at t had it moved on smoothly from x. Twin of ChainSample::predict.
fn predict(x: ChainSample, t: f32) -> vec3<f32> {
    return x.point + x.velocity * (t - x.t);
}

// The width of the peak of d^2 seen from x (0 where d^2 is not convex). Twin of ChainSample::width.
fn chain_width(x: ChainSample) -> f32 {
    if x.curvature > 0.0 {
        let d2 = max(x.d2 - 0.5 * x.slope * x.slope / x.curvature, 0.0);
        return sqrt(2.0 * d2 / x.curvature);
    }
    return 0.0;
}

// A Newton step toward the minimum of d^2 from x, in [lo, hi]. Twin of ChainSample::newton.
fn chain_newton(x: ChainSample, lo: f32, hi: f32) -> f32 {
    var t = select(lo, hi, x.slope <= 0.0);
    if x.curvature > 0.0 {
        t = x.t - x.slope / x.curvature;
    }
    if abs(t) > 1e30 || t != t {
        return x.t;
    }
    return clamp(t, lo, hi);
}

// How far the nearest point lands at b from its smooth motion from a, relative to the distance (at least eps),
// or its chain parameter from its rate's, relative to PARAM_JUMP. Twin of miss.
fn miss(a: ChainSample, b: ChainSample) -> f32 {
    if b.t <= a.t {
        return 0.0;
    }
    if a.known == 0.0 || b.known == 0.0 {
        return F32_MAX;
    }
    let glide = (a.velocity + b.velocity) * (0.5 * (b.t - a.t));
    let spatial = length(b.point - a.point - glide) / max(sqrt(min(a.d2, b.d2)), max(EPSILON, 1e-30));
    let param = select(abs(b.param - a.param - 0.5 * (a.rate + b.rate) * (b.t - a.t)) / PARAM_JUMP, 0.0, a.at_joint || b.at_joint);
    let m = max(spatial, JUMP * param);
    return select(F32_MAX, m, m < F32_MAX);
}

// The ray's crossing of the bisector plane of a and b, clamped to [lo, hi]. Twin of bisector.
fn bisector(ray: Ray, a: vec3<f32>, b: vec3<f32>, lo: f32, hi: f32) -> f32 {
    let n = b - a;
    let along = dot(ray.dir, n);
    var t = 0.5 * (lo + hi);
    if along != 0.0 {
        t = dot(0.5 * (a + b) - ray.start, n) / along;
    }
    if abs(t) > 1e30 || t != t {
        return 0.5 * (lo + hi);
    }
    return clamp(t, lo, hi);
}

// Where the two branches' models (each nearest point moving on with its velocity) are equally far from the
// ray's point: (1, t), or (0, 0) where they do not cross on [a.t, b.t]. Twin of model_crossing.
fn model_crossing(ray: Ray, a: ChainSample, b: ChainSample) -> vec2<f32> {
    let ra = ray.start - a.point + a.velocity * a.t;
    let qa = ray.dir - a.velocity;
    let rb = ray.start - b.point + b.velocity * b.t;
    let qb = ray.dir - b.velocity;
    let c2 = dot(qa, qa) - dot(qb, qb);
    let c1 = 2.0 * (dot(ra, qa) - dot(rb, qb));
    let c0 = dot(ra, ra) - dot(rb, rb);
    let fa = (c2 * a.t + c1) * a.t + c0;
    let fb = (c2 * b.t + c1) * b.t + c0;
    if !(fa * fb <= 0.0) {
        return vec2<f32>(0.0);
    }
    let disc = max(c1 * c1 - 4.0 * c2 * c0, 0.0);
    let q = -0.5 * (c1 + select(-1.0, 1.0, c1 >= 0.0) * sqrt(disc));
    // The first root inside, of q / c2, c0 / q and the secant's (no array: lavapipe would keep it in memory).
    let roots = vec3<f32>(q / c2, c0 / q, a.t + (b.t - a.t) * fa / (fa - fb));
    let inside = (abs(roots) < vec3<f32>(1e30)) & (roots >= vec3<f32>(a.t)) & (roots <= vec3<f32>(b.t));
    if inside.x {
        return vec2<f32>(1.0, roots.x);
    }
    if inside.y {
        return vec2<f32>(1.0, roots.y);
    }
    if inside.z {
        return vec2<f32>(1.0, roots.z);
    }
    return vec2<f32>(0.0);
}

// The estimate of a kink between a and b. Twin of the estimates in find_kink.
fn kink_estimate(ray: Ray, a: ChainSample, b: ChainSample) -> f32 {
    let m = model_crossing(ray, a, b);
    if m.x > 0.0 {
        return m.y;
    }
    return bisector(ray, a.point, b.point, a.t, b.t);
}

// The kink where the nearest point jumps between *a and *b: returns it, and leaves the final bracket in *a, *b.
// Twin of find_kink.
fn find_kink(ray: Ray, a: ptr<function, ChainSample>, b: ptr<function, ChainSample>) -> f32 {
    var last_moved = 0i;
    var stale = false;
    for (var round = 0u; round < KINK_ROUNDS; round++) {
        if (*b).t - (*a).t <= select(FINE_KINK_BRACKET, KINK_BRACKET, gauss_order() <= COARSE_ORDER) {
            break;
        }
        var guess = 0.5 * ((*a).t + (*b).t);
        if !stale {
            guess = kink_estimate(ray, *a, *b);
        }
        let tau = KINK_PROBE * ((*b).t - (*a).t);
        var moved_a = false;
        var moved_b = false;
        for (var side = 0u; side < 2u; side++) {
            let probe = guess + select(-tau, tau, side == 1u);
            if probe <= (*a).t || probe >= (*b).t {
                continue;
            }
            let m = chain_sample(ray, probe, false);
            if length(m.point - predict(*a, probe)) <= length(m.point - predict(*b, probe)) {
                *a = m;
                moved_a = true;
            } else {
                *b = m;
                moved_b = true;
            }
        }
        var moved = 0i;
        if moved_a && !moved_b {
            moved = -1i;
        } else if moved_b && !moved_a {
            moved = 1i;
        }
        stale = moved != 0i && moved == last_moved;
        last_moved = moved;
    }
    return kink_estimate(ray, *a, *b);
}

// The kinks of a chain along the ray, at most MAX_KINKS (more are dropped). Twin of Kinks.
// Bit k of singular: the nearest point leaves a point at rest there, or jumps (see Kinks).
struct Kinks {
    at: array<f32, MAX_KINKS>,
    count: u32,
    singular: u32,
}

fn push_kink(kinks: ptr<function, Kinks>, t: f32, singular: bool) {
    if (*kinks).count < MAX_KINKS {
        (*kinks).at[(*kinks).count] = t;
        (*kinks).singular |= select(0u, 1u, singular) << (*kinks).count;
        (*kinks).count++;
    }
}

// The jumps of the nearest point between a and b: the kink where it lands far from its smooth motion, and
// where the bracket left around it still jumps, one more search on either side. Returns the bracket left around
// the first kink, (t, param) of either end, t = -1 where there was none. Twin of search_jumps (one call site of
// find_kink: drivers inline every call).
fn search_jumps(ray: Ray, a: ChainSample, b: ChainSample, kinks: ptr<function, Kinks>) -> vec4<f32> {
    var a1 = a;
    var b1 = b;
    for (var round = 0u; round < 3u; round++) {
        var x = a;
        var y = b;
        if round == 1u {
            y = a1;
        } else if round == 2u {
            x = b1;
        }
        if miss(x, y) <= JUMP {
            if round == 0u {
                return vec4<f32>(-1.0, 0.0, -1.0, 0.0);
            }
            continue;
        }
        push_kink(kinks, find_kink(ray, &x, &y), false);
        if round == 0u {
            a1 = x;
            b1 = y;
            if miss(a1, b1) <= JUMP {
                break;
            }
        }
    }
    return vec4<f32>(a1.t, a1.param, b1.t, b1.param);
}

// The continuous W form's brightest point seen from the ray's point at t. Twin of BrightSample.
struct BrightSample {
    t: f32,
    param: f32,
    rate: f32,
    value: f32,
    slope: f32,
}

fn bright_sample(ray: Ray, t: f32) -> BrightSample {
    let p = ray.start + ray.dir * t;
    let b = curve_search(curves[ray.index], p);
    let m = bright_motion(b, p, ray.dir);
    return BrightSample(t, b.t, m.x, b.value, m.y);
}

// How far the brightest point's parameter lands at b from where its rates would have taken it from a. Twin of
// bright_miss.
fn bright_miss(a: BrightSample, b: BrightSample) -> f32 {
    let m = abs(b.param - a.param - 0.5 * (a.rate + b.rate) * (b.t - a.t));
    return select(F32_MAX, m, m < F32_MAX);
}

// Where the two branches' values, each moving on with its slope, meet between a and b (else the middle).
fn bright_estimate(a: BrightSample, b: BrightSample) -> f32 {
    let t = (b.value - a.value + a.slope * a.t - b.slope * b.t) / (a.slope - b.slope);
    return select(0.5 * (a.t + b.t), t, t > a.t && t < b.t);
}

// The continuous W form's kinks along the ray (twin of bright_kinks): a scan of BRIGHT_SCAN intervals; where the
// brightest point jumps in one, the jump is bracketed (each round probes either side of the estimate, or of the
// middle where the same side moved twice in a row, and gives each probe to the end whose branch it continues; twin
// of find_bright_kink), then the rest of the interval before and after the bracket is searched once more; between
// jumps, the cuts where the point passes a piece's end (bright_cuts). One loop, one call of the search: each pass
// takes the next scan sample or the next probe, so that drivers, which inline every call, compile the search once.
fn bright_kinks(ray: Ray, kinks: ptr<function, Kinks>) {
    let bracket = select(FINE_KINK_BRACKET, KINK_BRACKET, gauss_order() <= COARSE_ORDER);
    var i = 0u;
    var before: BrightSample;
    var after: BrightSample;
    // stage 0: scanning; 1: the interval's first jump; 2 and 3: the rest of the interval before and after it.
    var stage = 0u;
    var a: BrightSample;
    var b: BrightSample;
    var a1: BrightSample;
    var b1: BrightSample;
    var round = 0u;
    var side = 2u;
    var guess = 0.0;
    var tau = 0.0;
    var moved_a = false;
    var moved_b = false;
    var last_moved = 0i;
    var stale = false;
    var t = 0.0;
    loop {
        if stage == 0u {
            if i > BRIGHT_SCAN {
                break;
            }
            t = f32(i) / f32(BRIGHT_SCAN);
        }
        let m = bright_sample(ray, t);
        if stage == 0u {
            i++;
            if i == 1u {
                before = m;
                continue;
            }
            after = m;
            // Once the kinks are full, further searches would be dropped: none is made.
            if bright_miss(before, after) <= PARAM_JUMP || (*kinks).count >= MAX_KINKS {
                bright_cuts(ray, before, after, kinks);
                before = after;
                continue;
            }
            stage = 1u;
            a = before;
            b = after;
            round = 0u;
            side = 2u;
            last_moved = 0i;
            stale = false;
        } else {
            let pa = a.param + a.rate * (m.t - a.t);
            let pb = b.param + b.rate * (m.t - b.t);
            if abs(m.param - pa) <= abs(m.param - pb) {
                a = m;
                moved_a = true;
            } else {
                b = m;
                moved_b = true;
            }
            side++;
        }
        // On to the next probe: the round's other side, the next round, or the search's end and what follows it.
        loop {
            if side < 2u {
                t = guess + select(-tau, tau, side == 1u);
                if t > a.t && t < b.t {
                    break;
                }
                side++;
                continue;
            }
            if side == 2u && round > 0u {
                // The round ends.
                var moved = 0i;
                if moved_a && !moved_b {
                    moved = -1i;
                } else if moved_b && !moved_a {
                    moved = 1i;
                }
                stale = moved != 0i && moved == last_moved;
                last_moved = moved;
            }
            if b.t - a.t > bracket && round < KINK_ROUNDS {
                // A round begins.
                guess = 0.5 * (a.t + b.t);
                if !stale {
                    guess = bright_estimate(a, b);
                }
                tau = KINK_PROBE * (b.t - a.t);
                moved_a = false;
                moved_b = false;
                round++;
                side = 0u;
                continue;
            }
            // The search ends: its kink, then the rest of the interval, then the cuts and the scan.
            push_kink(kinks, bright_estimate(a, b), false);
            if stage == 1u {
                a1 = a;
                b1 = b;
            }
            var next = 0u;
            let room = (*kinks).count < MAX_KINKS;
            if stage == 1u && bright_miss(before, a1) > PARAM_JUMP && room {
                next = 2u;
                a = before;
                b = a1;
            } else if stage <= 2u && bright_miss(b1, after) > PARAM_JUMP && room {
                next = 3u;
                a = b1;
                b = after;
            }
            if next != 0u {
                stage = next;
                round = 0u;
                side = 2u;
                last_moved = 0i;
                stale = false;
                continue;
            }
            bright_cuts(ray, before, a1, kinks);
            bright_cuts(ray, b1, after, kinks);
            before = after;
            stage = 0u;
            break;
        }
    }
}

// The cuts where the brightest point passes the end of a piece (a joint or a knot of W) between samples x and y with
// no jump between them, or comes to rest at (or leaves) an end of the chain: its parameter's cubic Hermite
// interpolant between them crossing the piece's end, by bisection; a rest at an end where the moving sample's rate
// takes it there. Twin of bright_cuts.
fn bright_cuts(ray: Ray, x: BrightSample, y: BrightSample, kinks: ptr<function, Kinks>) {
    if y.t <= x.t || x.param == y.param {
        return;
    }
    let c = curves[ray.index];
    let h = y.t - x.t;
    for (var k = 0u; k <= c.piece_count; k++) {
        let end = k == 0u || k == c.piece_count;
        var at = select(0.0, 1.0, k == c.piece_count);
        if !end {
            at = pieces[c.first_piece + k].t0;
        }
        var t = 0.0;
        if end {
            if (x.param == at) == (y.param == at) {
                continue;
            }
            var m = x;
            if x.param == at {
                m = y;
            }
            t = m.t + (at - m.param) / m.rate;
        } else {
            if (x.param - at) * (y.param - at) >= 0.0 {
                continue;
            }
            var lo = x.t;
            var hi = y.t;
            for (var r = 0u; r < CUT_BISECTIONS; r++) {
                let mid = 0.5 * (lo + hi);
                let u = (mid - x.t) / h;
                let u2 = u * u;
                let u3 = u2 * u;
                let value = (2.0 * u3 - 3.0 * u2 + 1.0) * x.param + (u3 - 2.0 * u2 + u) * h * x.rate
                    + (-2.0 * u3 + 3.0 * u2) * y.param + (u3 - u2) * h * y.rate;
                if (value - at) * (x.param - at) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            t = 0.5 * (lo + hi);
        }
        push_kink(kinks, select(0.5 * (x.t + y.t), clamp(t, x.t, y.t), abs(t) < 1e30), false);
    }
}

// Twin of curve::Segment::start_tangent and end_tangent: the direction in which a segment leaves its start or
// arrives at its end, the second derivative's where the speed vanishes there.
fn start_tangent(s: CurveSegment) -> vec3<f32> {
    return select(s.c1, s.c2, starts_at_rest(s));
}

fn end_tangent(s: CurveSegment) -> vec3<f32> {
    return select(2.0 * s.c2 + s.c1, -s.c2, ends_at_rest(s));
}

// Twin of curve::tangent_into and tangent_out_of: past one segment of zero length; w is 1 where that segment's
// speed vanishes there (Segment::ends_at_rest, starts_at_rest).
fn tangent_into(c: CurveSource, j: u32) -> vec4<f32> {
    var s = segments[c.first_segment + j - 1u];
    if all(end_tangent(s) == vec3<f32>(0.0)) && j >= 2u {
        s = segments[c.first_segment + j - 2u];
    }
    return vec4<f32>(end_tangent(s), select(0.0, 1.0, ends_at_rest(s)));
}

fn tangent_out_of(c: CurveSource, j: u32) -> vec4<f32> {
    var s = segments[c.first_segment + j];
    if all(start_tangent(s) == vec3<f32>(0.0)) && j + 1u < c.segment_count {
        s = segments[c.first_segment + j + 1u];
    }
    return vec4<f32>(start_tangent(s), select(0.0, 1.0, starts_at_rest(s)));
}


// The cuts where the nearest point crosses a knot of the W series between two samples x and y, (t, param), with
// no jump between them: the parameter's linear interpolation, then one Newton step on a sample there. Twin of
// knot_cuts.
fn knot_cuts(ray: Ray, x: vec2<f32>, y: vec2<f32>, kinks: ptr<function, Kinks>) {
    let n = curves[ray.index].weight_count;
    if n < 4u || x.y == y.y || y.x <= x.x {
        return;
    }
    let spans = f32(n - 2u);
    for (var i = 1u; i < n - 2u; i++) {
        let knot = f32(i) / spans;
        if (x.y - knot) * (y.y - knot) > 0.0 {
            continue;
        }
        let guess = clamp(x.x + (y.x - x.x) * (knot - x.y) / (y.y - x.y), x.x, y.x);
        let m = chain_sample(ray, guess, false);
        var t = m.t;
        if m.rate != 0.0 {
            t = m.t + (knot - m.param) / m.rate;
        }
        push_kink(kinks, select(m.t, clamp(t, x.x, y.x), abs(t) < 1e30), false);
    }
}

// The cuts at the chain's joints between two samples x and y, (t, param), with no jump between them: where the
// nearest point passes a joint, the joint's normal plane (two at a corner) where the samples lie on either side
// of the joint. Twin of joint_cuts.
fn joint_cuts(ray: Ray, x: vec2<f32>, y: vec2<f32>, kinks: ptr<function, Kinks>) {
    let c = curves[ray.index];
    for (var j = 1u; j < c.segment_count; j++) {
        let pj = f32(j) / f32(c.segment_count);
        if (x.y - pj) * (y.y - pj) > 0.0 {
            continue;
        }
        let joint = segments[c.first_segment + j].c0;
        let into = tangent_into(c, j);
        let out_of = tangent_out_of(c, j);
        let t_in = into.xyz;
        let t_out = out_of.xyz;
        let cr = cross(t_in, t_out);
        let corner = dot(cr, cr) > 1e-12 * dot(t_in, t_in) * dot(t_out, t_out);
        for (var plane = 0u; plane < select(1u, 2u, corner); plane++) {
            let tangent = select(t_out, t_in, plane == 1u);
            let rest = select(out_of.w > 0.0 || (!corner && into.w > 0.0), into.w > 0.0, plane == 1u);
            let t = dot(joint - ray.start, tangent) / dot(ray.dir, tangent);
            if t > x.x && t <= y.x {
                push_kink(kinks, t, rest);
            }
        }
    }
}

// The two deepest local minima of d^2 on the scan, offered in order (ties to the left). Twin of Minima.
struct Minima {
    best0: ChainSample,
    best1: ChainSample,
    count: u32,
}

fn offer(m: ptr<function, Minima>, x: ChainSample, g_left: f32, g_right: f32) {
    if !(x.d2 < g_left && x.d2 <= g_right) {
        return;
    }
    if (*m).count == 0u {
        (*m).best0 = x;
        (*m).count = 1u;
    } else if x.d2 < (*m).best0.d2 {
        (*m).best1 = (*m).best0;
        (*m).best0 = x;
        (*m).count = 2u;
    } else if (*m).count == 1u {
        (*m).best1 = x;
        (*m).count = 2u;
    } else if x.d2 < (*m).best1.d2 {
        (*m).best1 = x;
    }
}

// A chain's features along the ray: its closest approaches (each owning its piece) and its kinks.
struct CurveFeatures {
    found: Peaks,
    kinks: array<f32, MAX_KINKS>,
    kink_count: u32,
    kink_singular: u32,
}

// Twin of chain_features and chain_peaks: one pass over the scan's intervals, each split at the normal planes
// of the chain's ends and searched for jumps, then the closest approaches refined by Newton.
fn curve_features(ray: Ray) -> CurveFeatures {
    let c = curves[ray.index];
    let first = segments[c.first_segment];
    let last = segments[c.first_segment + c.segment_count - 1u];
    let first_tangent = tangent_out_of(c, 0u);
    let last_tangent = tangent_into(c, c.segment_count);
    var end_t = vec2<f32>(
        dot(first.c0 - ray.start, first_tangent.xyz) / dot(ray.dir, first_tangent.xyz),
        dot(last.c2 + last.c1 + last.c0 - ray.start, last_tangent.xyz) / dot(ray.dir, last_tangent.xyz),
    );
    var end_at = vec2<f32>(0.0, 1.0);
    // Whether the chain is at rest at each end (its normal plane is then a singular cut).
    var end_rest = vec2<f32>(first_tangent.w, last_tangent.w);
    if end_t.y < end_t.x {
        end_t = end_t.yx;
        end_at = end_at.yx;
        end_rest = end_rest.yx;
    }
    // The nearest point moving at each end's normal plane, sampled once up front rather than where the scan's
    // loop reaches the plane: a heavy call inside that loop's branches weighs on every interval on lavapipe
    // (about 5 % of the curve pass, measured).
    let end_moving0 = chain_sample(ray, end_t.x, true);
    let end_moving1 = chain_sample(ray, end_t.y, true);
    let step = 1.0 / f32(SCAN);
    // The kinks of the nearest point, or in the continuous W form those of the brightest point (bright_kinks).
    let nearest_kinks = !(SEARCH != 0u && c.piece_count > 0u);
    var minima: Minima;
    minima.count = 0u;
    var kinks: Kinks;
    kinks.count = 0u;
    kinks.singular = 0u;
    // The ends' peaks, where the ray crosses their normal planes (with_ends).
    var ends: array<Peak, 2>;
    var end_count = 0u;
    var before: ChainSample;
    var g_before_before = F32_MAX;
    for (var i = 0u; i <= SCAN; i++) {
        let after = chain_sample(ray, f32(i) * step, false);
        if i == 0u {
            before = after;
            continue;
        }
        offer(&minima, before, g_before_before, after.d2);
        // The interval's parts between the ends' normal planes inside it (one call site of search_jumps). calm
        // starts the stretch since the last jump, which the joints' cuts look at: (t, param).
        var left = before;
        var calm = vec2<f32>(before.t, before.param);
        var e = 0u;
        for (var part = 0u; part < 3u; part++) {
            var right = after;
            var next_left = after;
            var cut = -1.0;
            var end_sample = after;
            for (; e < 2u; e++) {
                let t = end_t[e];
                let at_end = end_at[e];
                if !(t > before.t && t <= after.t) || (abs(before.param - at_end) > END_SNAP && abs(after.param - at_end) > END_SNAP) {
                    continue;
                }
                var moving = end_moving0;
                if e == 1u {
                    moving = end_moving1;
                }
                end_sample = moving;
                var at_rest = moving;
                at_rest.velocity = vec3<f32>(0.0);
                at_rest.rate = 0.0;
                at_rest.curvature = 2.0 * dot(ray.dir, ray.dir);
                right = moving;
                next_left = at_rest;
                if abs(left.param - at_end) <= END_SNAP {
                    right = at_rest;
                    next_left = moving;
                }
                cut = t;
                e++;
                break;
            }
            if cut >= 0.0 {
                push_kink(&kinks, cut, end_rest[e - 1u] > 0.0);
                var end = first.c0;
                if end_at[e - 1u] == 1.0 {
                    end = last.c2 + last.c1 + last.c0;
                }
                let a = dot(ray.dir, ray.dir);
                let center = dot(end - ray.start, ray.dir) / a;
                let off = ray.start + ray.dir * center - end;
                ends[end_count] = make_peak(center, dot(off, off), a);
                end_count++;
                // Through the end closer than eps: the flat top ends where the end point is eps away.
                let eps = EPSILON;
                if end_sample.d2 < eps * eps {
                    let q = ray.start - end_sample.point;
                    let a = dot(ray.dir, ray.dir);
                    let b = dot(ray.dir, q);
                    let root = sqrt(max(b * b - a * (dot(q, q) - eps * eps), 0.0));
                    for (var r = 0u; r < 2u; r++) {
                        let t = (-b + select(-root, root, r == 1u)) / a;
                        if t > 0.0 && t < 1.0 {
                            push_kink(&kinks, t, false);
                        }
                    }
                }
            }
            var bracket = vec4<f32>(-1.0);
            if nearest_kinks {
                bracket = search_jumps(ray, left, right, &kinks);
            }
            if bracket.x >= 0.0 {
                // Up to the jump, and inside its bracket (the nearest point may have passed a joint as well).
                for (var q = 0u; q < 2u; q++) {
                    joint_cuts(ray, select(calm, bracket.xy, q == 1u), select(bracket.xy, bracket.zw, q == 1u), &kinks);
                }
                knot_cuts(ray, calm, bracket.xy, &kinks);
                calm = bracket.zw;
            }
            if cut < 0.0 {
                break;
            }
            left = next_left;
        }
        // The stretch since the last jump.
        if nearest_kinks {
            joint_cuts(ray, calm, vec2<f32>(after.t, after.param), &kinks);
            knot_cuts(ray, calm, vec2<f32>(after.t, after.param), &kinks);
        }
        g_before_before = before.d2;
        before = after;
    }
    offer(&minima, before, g_before_before, F32_MAX);
    if !nearest_kinks {
        bright_kinks(ray, &kinks);
    }
    var found: Peaks;
    found.count = 0u;
    for (var slot = 0u; slot < minima.count; slot++) {
        var x = minima.best0;
        if slot == 1u {
            x = minima.best1;
        }
        let lo = max(x.t - step, 0.0);
        let hi = min(x.t + step, 1.0);
        for (var k = 0u; k < PEAK_NEWTON; k++) {
            let next = chain_newton(x, lo, hi);
            if abs(next - x.t) <= PEAK_SETTLED * chain_width(x) {
                break;
            }
            x = chain_sample(ray, next, false);
        }
        var center = x.t;
        var d2 = x.d2;
        if x.curvature > 0.0 {
            center = chain_newton(x, lo, hi);
            d2 = x.d2 - 0.5 * x.slope * x.slope / x.curvature;
        }
        found.peaks[found.count] = make_peak(center, max(d2, 0.0), 0.5 * max(x.curvature, 0.0));
        found.count++;
    }
    if found.count == 0u {
        // A flat scan (constant distance): one uniform piece.
        found.peaks[0] = make_peak(0.0, 0.0, 0.0);
        found.count = 1u;
    }
    // Twin of with_ends: each end's peak whose map at its center is more than twice as dense as every feature's
    // before it.
    for (var k = 0u; k < end_count; k++) {
        let end = ends[k];
        var sharper = found.count < MAX_PEAKS;
        for (var i = 0u; i < found.count; i++) {
            let p = found.peaks[i];
            let gap = end.center - p.center;
            sharper = sharper && 4.0 * end.width * end.width < p.width * p.width + gap * gap;
        }
        if sharper {
            found.peaks[found.count] = end;
            found.count++;
        }
    }
    share_ray(&found);
    var out: CurveFeatures;
    out.found = found;
    out.kinks = kinks.at;
    out.kink_count = kinks.count;
    out.kink_singular = kinks.singular;
    return out;
}

// No segment known yet (nearest_on_chain_from).
const NO_SEGMENT: u32 = 0xffffffffu;

// Twin of curve::nearest_on_chain_from: the nearest point of the chain to p where it lies on segment *segment
// (NO_SEGMENT where not known) or has moved on from it through a joint: that segment's nearest point unless it
// sits at one of the segment's joints, and then the whole chain's, leaving *segment on its segment. (param, d).
fn nearest_on_chain_from(c: CurveSource, p: vec3<f32>, segment: ptr<function, u32>) -> vec2<f32> {
    var lo = 0u;
    var hi = c.segment_count;
    if *segment < c.segment_count {
        lo = *segment;
        hi = lo + 1u;
    }
    var best = vec2<f32>(0.0, F32_MAX);
    var best_j = lo;
    // Two passes at most: the piece's segment, then (at a joint) the whole chain. One call site of the solver.
    loop {
        for (var j = lo; j < hi; j++) {
            let n = nearest_on_segment(segments[c.first_segment + j], p);
            if n.y < best.y {
                best = n;
                best_j = j;
            }
        }
        let at_joint = (best.x == 0.0 && best_j > 0u) || (best.x == 1.0 && best_j + 1u < c.segment_count);
        if hi - lo == c.segment_count || !at_joint {
            break;
        }
        lo = 0u;
        hi = c.segment_count;
        best = vec2<f32>(0.0, F32_MAX);
        best_j = 0u;
    }
    *segment = best_j;
    return vec2<f32>((f32(best_j) + best.x) / f32(c.segment_count), best.y);
}

// A node's nearest point is carried from the last node's by TRACK_NEWTON Newton steps (generated: the field
// pass's iteration budget counts them).
// A node keeps Newton's nearest point where the last step moved it less than this along its segment.
const TRACK_SETTLED: f32 = 1e-4;
// The longest way along its segment (in u) a nearest point is carried from the last node.
const TRACK_REACH: f32 = 0.05;

// The nearest point carried along a piece of a curve's ray, node to node in order along it: its segment
// (NO_SEGMENT before the piece's first node), its parameter u on that segment, and du/dt there.
struct Track {
    segment: u32,
    u: f32,
    rate: f32,
    t: f32,
    whole: bool,  // solve every node on the whole chain (a part whose ends lie on different segments)
}

// The rate du/dt of a nearest point at u on segment s: from the stationarity (C(u) - L(t)) . C'(u) = 0, C'(u) . dir
// over its u derivative; 0 at the segment's ends or where the derivative is not positive.
fn track_rate(s: CurveSegment, u: f32, off: vec3<f32>, dir: vec3<f32>) -> f32 {
    let d1 = 2.0 * s.c2 * u + s.c1;
    let dg = dot(d1, d1) + 2.0 * dot(off, s.c2);
    return select(0.0, dot(d1, dir) / dg, u > 0.0 && u < 1.0 && dg > 0.0);
}

// The nearest point of the chain to the ray's point at t, (param, d), carried from the track's last node: the
// track's segment, its u predicted by du/dt and then TRACK_NEWTON Newton steps on the stationarity. Between a
// piece's cuts the nearest point neither jumps nor passes a joint, so this follows it. Where Newton has not
// settled, the segment's stationarity is not a minimum, or the piece has just begun, it is solved in closed
// form (nearest_on_chain_from); so too where the point reaches a joint, which the cuts at joint planes already
// exclude (a safety net against a missed cut). Leaves the track at this node.
fn track_nearest(c: CurveSource, ray: Ray, t: f32, track: ptr<function, Track>) -> vec2<f32> {
    let p = ray.start + ray.dir * t;
    let k = c.segment_count;
    let j = (*track).segment;
    // Carried only over a short way along the segment: where the nearest point races (near a center of
    // curvature) a long prediction can lead Newton to another stationary point.
    let reach = abs((*track).rate * (t - (*track).t));
    if (*track).whole {
        var segment = NO_SEGMENT;
        return nearest_on_chain_from(c, p, &segment);
    }
    if j < k && reach <= TRACK_REACH {
        let s = segments[c.first_segment + j];
        var u = clamp((*track).u + (*track).rate * (t - (*track).t), 0.0, 1.0);
        var step = 0.0;
        var convex = true;
        for (var i = 0u; i < TRACK_NEWTON; i++) {
            let d1 = 2.0 * s.c2 * u + s.c1;
            let off = segment_at(s, u) - p;
            let dg = dot(d1, d1) + 2.0 * dot(off, s.c2);
            convex = convex && dg > 0.0;
            let next = select(u, clamp(u - dot(off, d1) / dg, 0.0, 1.0), dg > 0.0);
            step = next - u;
            u = next;
        }
        let at_joint = (u == 0.0 && j > 0u) || (u == 1.0 && j + 1u < k);
        if convex && abs(step) <= TRACK_SETTLED && !at_joint {
            let off = segment_at(s, u) - p;
            *track = Track(j, u, track_rate(s, u, off, ray.dir), t, false);
            return vec2<f32>((f32(j) + u) / f32(k), length(off));
        }
    }
    var segment = j;
    let n = nearest_on_chain_from(c, p, &segment);
    let s = segments[c.first_segment + segment];
    let u = clamp(n.x * f32(k) - f32(segment), 0.0, 1.0);
    *track = Track(segment, u, track_rate(s, u, segment_at(s, u) - p, ray.dir), t, false);
    return n;
}

// The brightest point of a chain (the continuous W form) at the ray's point t, carried from the track's last node
// (whose segment, u and rate here name its piece, x and dx/dt): between a part's cuts it stays on one piece and
// moves smoothly (the cuts are where it jumps or passes a piece's end), so TRACK_NEWTON Newton steps on the piece's
// h from where its rate takes it find it, and it stands where every other piece's bound is below its value. Else
// (a part's first node, a step that has not settled, a point at a piece's end or on the flat top, or a part solved
// whole) the whole chain is searched (curve_search, one call site). The f64 twin searches every node; both find the
// same point, to f32 rounding.
fn bright_track(c: CurveSource, ray: Ray, t: f32, track: ptr<function, Track>) -> Bright {
    let p = ray.start + ray.dir * t;
    let k = (*track).segment;
    if k != NO_SEGMENT && !(*track).whole && abs((*track).rate * (t - (*track).t)) <= TRACK_REACH {
        let q = pieces[k];
        let h = stationary_quartic(q, p);
        var x = clamp((*track).u + (*track).rate * (t - (*track).t), 0.0, 1.0);
        var step = 1.0;
        var falls = true;
        for (var i = 0u; i < TRACK_NEWTON; i++) {
            let f = quartic_at(h, x);
            falls = f.y < 0.0;
            let next = select(x, clamp(x - f.x / f.y, 0.0, 1.0), falls);
            step = next - x;
            x = next;
        }
        let d = length(piece_at(q, x) - p);
        let value = piece_weight(q, x) / max(EPSILON, d);
        var stands = falls && abs(step) <= TRACK_SETTLED && x > 0.0 && x < 1.0 && d > EPSILON;
        for (var i = 0u; i < c.piece_count; i++) {
            let j = c.first_piece + i;
            let o = pieces[j];
            let bound = o.weight_max / max(EPSILON, length(p - o.center) - o.radius);
            stands = stands && (j == k || bound <= value);
        }
        if stands {
            *track = Track(k, x, piece_rate(q, x, p, ray.dir), t, false);
            return Bright(value, mix(q.t0, q.t1, x), d, x, k);
        }
    }
    let b = curve_search(c, p);
    let whole = (*track).whole;
    *track = Track(NO_SEGMENT, 0.0, 0.0, t, whole);
    if b.x > 0.0 && b.x < 1.0 && b.distance > EPSILON {
        *track = Track(b.piece, b.x, piece_rate(pieces[b.piece], b.x, p, ray.dir), t, whole);
    }
    return b;
}

// The Kronrod and Gauss values on [a, b] in u of a curve's term: f = w / max(eps, d) zeta(t) (before the
// coefficient) at each node, t clamped to the piece. The nodes go in order along the ray, so that each carries
// the nearest point on from the last (track_nearest). Twin of kronrod.
// The Kronrod and Gauss values (kg) and, of the term times the curve's color series (zero without one), the
// Kronrod value (colored): its nodes are B's, and B's pair decides the refinement.
struct CurveRule {
    kg: vec2<f32>,
    colored: vec3<f32>,
}

fn curve_kronrod(ray: Ray, p: Peak, a: f32, b: f32, panel: vec2<f32>, singular: vec2<bool>, track: ptr<function, Track>) -> CurveRule {
    let c = curves[ray.index];
    let mid = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    var sum = vec2<f32>(0.0);
    var colored = vec3<f32>(0.0);
    for (var i = 0u; i <= 2u * gauss_order(); i++) {
        let node = kronrod_node(i);
        let toward = toward_singular(mid + r * node.x, panel, singular);
        let m = map_node(p, toward.x);
        // The continuous W form searches the whole chain at every node (twin of integrate_weighted).
        var n: vec2<f32>;
        if SEARCH != 0u && c.piece_count > 0u {
            let b = bright_track(c, ray, m.x, track);
            n = vec2<f32>(b.t, b.distance);
        } else {
            n = track_nearest(c, ray, m.x, track);
        }
        let w = wseries(c, n.x);
        var f = toward.y * m.y * w * falloff(n.y, EPSILON) * zeta_at(m.x);
        if params.decay == 1u {
            // The rms decay's square of the weighed energy (the map's derivatives stay to the first power).
            let v = w * falloff(n.y, EPSILON) * zeta_at(m.x);
            f = toward.y * m.y * v * v;
        }
        sum += node.yz * f;
        colored += node.y * f * color_series(c, n.x);
    }
    return CurveRule(r * sum, r * colored);
}

// Twin of toward_singular: u at v on the panel [a, b] with the nodes drawn toward its singular ends, and du/dv.
fn toward_singular(v: f32, panel: vec2<f32>, singular: vec2<bool>) -> vec2<f32> {
    let x = (v - panel.x) / (panel.y - panel.x);
    var phi = vec2<f32>(x, 1.0);
    if singular.x && singular.y {
        phi = vec2<f32>(x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x));
    } else if singular.x {
        phi = vec2<f32>(x * x, 2.0 * x);
    } else if singular.y {
        phi = vec2<f32>(x * (2.0 - x), 2.0 - 2.0 * x);
    }
    return vec2<f32>(panel.x + (panel.y - panel.x) * phi.x, phi.y);
}

// A curve's term on the panel [a, b] in u, refined where the pair disagrees. Twin of integrate_panel.
fn curve_panel(ray: Ray, p: Peak, a: f32, b: f32, singular: vec2<bool>, allowance: f32, refinements: ptr<function, u32>, track: ptr<function, Track>) -> vec4<f32> {
    let end = 1u << MAX_DEPTH;
    var at = 0u;
    var level = 0u;
    var sum = vec4<f32>(0.0);
    while at < end {
        let x = part_bounds(a, b, at, level);
        let rule = curve_kronrod(ray, p, x.x, x.y, vec2<f32>(a, b), singular, track);
        let kg = rule.kg;
        if settled(kg, allowance, x.y - x.x) || level == MAX_DEPTH || *refinements == 0u {
            sum += vec4<f32>(kg.x, rule.colored);
            let next = next_part(at, level);
            at = next.x;
            level = next.y;
        } else {
            // Back to the part's start: the nearest point is solved afresh there rather than carried back over
            // the whole part, where Newton could settle on another stationary point.
            (*track).segment = NO_SEGMENT;
            *refinements -= 1u;
            level++;
        }
    }
    return sum;
}

// Twin of curve::nearest_segment_index: the segment of the chain's nearest point to the ray's point at u of
// p's map, NO_SEGMENT where that point is a joint.
fn nearest_segment_index(c: CurveSource, ray: Ray, p: Peak, u: f32) -> u32 {
    var segment = NO_SEGMENT;
    let n = nearest_on_chain_from(c, ray.start + ray.dir * map_node(p, u).x, &segment);
    let local = n.x * f32(c.segment_count) - f32(segment);
    // The chain parameter's f32 rounding: a joint's local parameter comes back within a few ulps of 0 or 1.
    let at_joint = (local <= 1e-5 && segment > 0u) || (local >= 1.0 - 1e-5 && segment + 1u < c.segment_count);
    return select(segment, NO_SEGMENT, at_joint);
}

// A curve's term of B over its pieces, each cut at its kinks, and that term times its color series (zero
// without one). Twin of integrate_term and, for the series, of integrate_weighted.
fn integrate_curve_term(index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> vec4<f32> {
    let coefficient = curves[index].coefficient;
    if coefficient == 0.0 {
        return vec4<f32>(0.0);
    }
    let ray = Ray(s_point, e_point - s_point, 3u, index, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    let c = curves[index];
    // A chain with a segment at rest at an end (or of zero length) is solved on the whole chain at every node:
    // the tracking of the nearest point along one segment loses it there.
    var degenerate = false;
    for (var j = 0u; j < c.segment_count; j++) {
        let s = segments[c.first_segment + j];
        degenerate = degenerate || starts_at_rest(s) || ends_at_rest(s);
    }
    let features = curve_features(ray);
    let length = pieces_length(features.found);
    var allowance = params.term_tolerance / (abs(coefficient) * max(length, 1e-30));
    // The rms decay's allowance comes from an estimate of its integral: the same panels unrefined, a pass before.
    let passes = select(1u, 2u, params.decay == 1u);
    var sum = vec4<f32>(0.0);
    for (var sweep = 0u; sweep < passes; sweep++) {
    var refinements = select(COARSE_REFINEMENTS, MAX_REFINEMENTS, gauss_order() > COARSE_ORDER);
    if sweep + 1u < passes {
        refinements = 0u;
    }
    sum = vec4<f32>(0.0);
    for (var k = 0u; k < features.found.count; k++) {
        let p = features.found.peaks[k];
        let u0 = stable_asinh((p.lo - p.center) / p.width);
        let u1 = stable_asinh((p.hi - p.center) / p.width);
        if u1 <= u0 {
            continue;
        }
        // The piece cut in order at the kinks inside it and, closer than eps, at the ends of the falloff's flat
        // top, -kf and kf (twin of cuts): each part ends at the least cut past its start, so that no array is
        // written (see integrate_smooth_term).
        let kf = select(F32_MAX, stable_asinh(p.flat / p.width), p.flat > 0.0);
        // Ordinary kinks within SINGULAR_MERGE of a singular one are dropped (twin of cuts): bit m of kept.
        var kept = 0u;
        for (var m = 0u; m < features.kink_count; m++) {
            let um = stable_asinh((features.kinks[m] - p.center) / p.width);
            var shadowed = false;
            for (var q = 0u; q < features.kink_count; q++) {
                let uq = stable_asinh((features.kinks[q] - p.center) / p.width);
                shadowed = shadowed || (((features.kink_singular >> q) & 1u) == 1u && abs(uq - um) <= SINGULAR_MERGE);
            }
            if ((features.kink_singular >> m) & 1u) == 1u || !shadowed {
                kept |= 1u << m;
            }
        }
        // Cuts within CUT_MERGE of the first of a cluster are one: at its first singular cut if any, singular if
        // any is (twin of cuts' merging). start: the cluster's first cut.
        var singular_b = false;
        for (var m = 0u; m < features.kink_count; m++) {
            let u = stable_asinh((features.kinks[m] - p.center) / p.width);
            singular_b = singular_b || (u > u0 && u <= u0 + CUT_MERGE && ((features.kink_singular >> m) & 1u) == 1u);
        }
        var b = u0;
        var start = u0;
        while b < u1 {
            let a = b;
            let singular_a = singular_b;
            var next = u1;
            for (var m = 0u; m < features.kink_count; m++) {
                let u = stable_asinh((features.kinks[m] - p.center) / p.width);
                if u > start + CUT_MERGE && u < u1 && ((kept >> m) & 1u) == 1u {
                    next = min(next, u);
                }
            }
            if -kf > start + CUT_MERGE && -kf < u1 {
                next = min(next, -kf);
            } else if kf > start + CUT_MERGE && kf < u1 {
                next = min(next, kf);
            }
            start = next;
            b = next;
            singular_b = false;
            var first_singular = F32_MAX;
            for (var m = 0u; m < features.kink_count; m++) {
                let u = stable_asinh((features.kinks[m] - p.center) / p.width);
                if u >= next && u <= next + CUT_MERGE && u < u1 && ((features.kink_singular >> m) & 1u) == 1u {
                    singular_b = true;
                    first_singular = min(first_singular, u);
                }
            }
            if singular_b {
                b = first_singular;
            }
            if u1 - next <= CUT_MERGE {
                b = u1;
            }
            // The safety net behind the cuts (twin of split_at_switch): a part whose ends' nearest points lie on
            // different segments holds a missed jump; it is split where the segment changes, found by bisection,
            // and both sides are solved on the whole chain at every node. So is a part that begins or ends at rest,
            // where the nodes crowd toward the cut.
            let inset = SWITCH_INSET * (b - a);
            // (Not for a curve that reads its brightest point: its nearest point's segments say nothing of it.)
            var ends = vec2<u32>(0u);
            if !(SEARCH != 0u && c.piece_count > 0u) {
                ends = vec2<u32>(nearest_segment_index(c, ray, p, a + inset), nearest_segment_index(c, ray, p, b - inset));
            }
            let switched = ends.x != ends.y;
            var split = b;
            if switched {
                var lo = a + inset;
                var hi = b - inset;
                for (var r = 0u; r < SWITCH_ROUNDS; r++) {
                    let mid = 0.5 * (lo + hi);
                    if nearest_segment_index(c, ray, p, mid) == ends.x {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                split = 0.5 * (lo + hi);
            }
            for (var part = 0u; part < select(1u, 2u, switched); part++) {
                let pa0 = select(a, split, part == 1u);
                let pb0 = select(split, b, part == 1u || !switched);
                let first = part == 0u;
                let last = part == 1u || !switched;
                // In f32 the bisection can end on a part's end, leaving the other part empty.
                if pb0 <= pa0 {
                    continue;
                }
                let panels = u32(clamp(ceil((pb0 - pa0) / U_PANEL), 1.0, f32(MAX_GAUSS_PANELS)));
                let width = (pb0 - pa0) / f32(panels);
                var track = Track(NO_SEGMENT, 0.0, 0.0, 0.0, switched || singular_a || singular_b || degenerate);
                for (var i = 0u; i < panels; i++) {
                    let pa = pa0 + width * f32(i);
                    let singular = vec2<bool>(singular_a && first && i == 0u, singular_b && last && i + 1u == panels);
                    sum += curve_panel(ray, p, pa, pa + width, singular, allowance, &refinements, &track);
                }
            }
        }
    }
    if sweep + 1u < passes {
        allowance = rms_allowance(sum.x, coefficient * coefficient, length);
    }
    }
    if params.decay == 1u {
        // B_i, and the color series' mean weighed by the term's square (twin of tint_of).
        let b = finish(coefficient * coefficient * sum.x, coefficient);
        return vec4<f32>(b, select(vec3<f32>(0.0), b * sum.yzw / sum.x, sum.x > 0.0));
    }
    return coefficient * sum;
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive_curves(@builtin(global_invocation_id) gid: vec3<u32>) {
    let texel = begin_texel(gid);
    if !texel.inside {
        return;
    }
    let first_curve = point_count() + line_count() + torus_count();
    var b = vec4<f32>(0.0);
    // The range holds curves only (gpu::field_pass::plan_chunks).
    for (var t = chunk.first; t < chunk.first + chunk.count; t++) {
        let term = integrate_curve_term(t - first_curve, texel.start, texel.end);
        b += glow_of(t, term.x) + vec4<f32>(0.0, term.yzw);
    }
    store(texel.id, b);
}
