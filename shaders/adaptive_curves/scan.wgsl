// A chain's features from its scan along the ray: its closest approaches, its ends, joints and W's knots, and the
// jumps between scan samples, each cut where the kink search places it. Twin:
// src/reference/adaptive_curves/scan.rs.
#import adaptive_curves/kinks.wgsl

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
        let whole = miss(x, y);
        if round == 0u {
            // Twin of the suspect interval's middle look (SUSPECT_MISS).
            if whole <= SUSPECT_MISS * JUMP {
                return vec4<f32>(-1.0, 0.0, -1.0, 0.0);
            }
            if whole <= JUMP {
                let m = chain_sample(ray, 0.5 * (a.t + b.t), false);
                if miss(a, m) > JUMP {
                    y = m;
                } else if miss(m, b) > JUMP {
                    x = m;
                } else {
                    return vec4<f32>(-1.0, 0.0, -1.0, 0.0);
                }
            }
        } else if whole <= JUMP {
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
    let c = CHAIN;
    let h = y.t - x.t;
    for (var k = 0u; k <= c.piece_count; k++) {
        let end = k == 0u || k == c.piece_count;
        var at = select(0.0, 1.0, k == c.piece_count);
        if !end {
            at = chain_piece(c, HELD, c.first_piece + k).t0;
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
    var s = chain_segment(c, HELD, j - 1u);
    if all(end_tangent(s) == vec3<f32>(0.0)) && j >= 2u {
        s = chain_segment(c, HELD, j - 2u);
    }
    return vec4<f32>(end_tangent(s), select(0.0, 1.0, ends_at_rest(s)));
}

fn tangent_out_of(c: CurveSource, j: u32) -> vec4<f32> {
    var s = chain_segment(c, HELD, j);
    if all(start_tangent(s) == vec3<f32>(0.0)) && j + 1u < c.segment_count {
        s = chain_segment(c, HELD, j + 1u);
    }
    return vec4<f32>(start_tangent(s), select(0.0, 1.0, starts_at_rest(s)));
}


// The cuts where the nearest point crosses a knot of the W series between two samples x and y, (t, param), with
// no jump between them: the parameter's linear interpolation, then one Newton step on a sample there. Twin of
// knot_cuts.
fn knot_cuts(ray: Ray, x: vec2<f32>, y: vec2<f32>, kinks: ptr<function, Kinks>) {
    let n = CHAIN.weight_count;
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
    let c = CHAIN;
    for (var j = 1u; j < c.segment_count; j++) {
        let pj = f32(j) / f32(c.segment_count);
        if (x.y - pj) * (y.y - pj) > 0.0 {
            continue;
        }
        let joint = chain_segment(c, HELD, j).c0;
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

// The MINIMA (3) deepest local minima of d^2, offered in order (ties to the left), deepest first. Twin of Minima:
// three named slots, shifted down by comparisons (an array indexed by a variable lives in memory on lavapipe).
struct Minima {
    best0: ChainSample,
    best1: ChainSample,
    best2: ChainSample,
    count: u32,
}

fn offer(m: ptr<function, Minima>, x: ChainSample, g_left: f32, g_right: f32) {
    if !(x.d2 < g_left && x.d2 <= g_right) {
        return;
    }
    let c = (*m).count;
    if c == 0u || x.d2 < (*m).best0.d2 {
        (*m).best2 = (*m).best1;
        (*m).best1 = (*m).best0;
        (*m).best0 = x;
    } else if c == 1u || x.d2 < (*m).best1.d2 {
        (*m).best2 = (*m).best1;
        (*m).best1 = x;
    } else if c == 2u || x.d2 < (*m).best2.d2 {
        (*m).best2 = x;
    }
    (*m).count = min(c + 1u, MINIMA);
}

// The minimum in slot 0, 1 or 2, by comparisons.
fn minimum_at(m: Minima, slot: u32) -> ChainSample {
    if slot == 1u {
        return m.best1;
    } else if slot == 2u {
        return m.best2;
    }
    return m.best0;
}

// The local minima of a segment's distance squared to the ray's line, as (d2, t) with t the foot on the line
// (d2 < 0 in a slot without one): slots 0 and 1 the segment's ends where the distance rises into it, 2 to 4 the
// stationary cubic's roots inside it where the distance curves up. Twin of approaches (which keeps the same order).
struct Approaches {
    d2: vec4<f32>,
    t: vec4<f32>,
    d2_last: f32,
    t_last: f32,
    falls_out: bool,  // the distance falls into the segment's end (an inner joint then ends no peak of the chain)
}

fn approach_at(a: Approaches, i: u32) -> vec2<f32> {
    if i == 4u {
        return vec2<f32>(a.d2_last, a.t_last);
    }
    return vec2<f32>(a.d2[i], a.t[i]);
}

// The candidate at u of the projected segment q (across the ray) and the segment itself, (d2, t), or none.
fn approach_of(q: CurveSegment, seg: CurveSegment, ray: Ray, u: f32, minimum: bool) -> vec2<f32> {
    if !minimum {
        return vec2<f32>(-1.0, 0.0);
    }
    let x = segment_at(q, u);
    return vec2<f32>(dot(x, x), dot(ray.dir, segment_at(seg, u) - ray.start) / dot(ray.dir, ray.dir));
}

fn root_approach(q: CurveSegment, seg: CurveSegment, ray: Ray, k: vec4<f32>, root: f32) -> vec2<f32> {
    // One Newton step on the cubic: Cardano loses digits near double roots.
    let bend = (3.0 * k.x * root + 2.0 * k.y) * root + k.z;
    var u = root;
    if bend != 0.0 {
        u = root - (((k.x * root + k.y) * root + k.z) * root + k.w) / bend;
    }
    let curving = (3.0 * k.x * u + 2.0 * k.y) * u + k.z;
    return approach_of(q, seg, ray, u, u > 0.0 && u < 1.0 && curving > 0.0);
}

// An end that is no local minimum of the chain's distance (an inner joint the distance does not fall into from the
// neighbour: twin of approaches' `peak`) keeps its d2 but gets t = -1, outside the ray.
fn approaches(seg: CurveSegment, ray: Ray, falls_in: bool, last: bool) -> Approaches {
    let a = dot(ray.dir, ray.dir);
    var q = seg;
    q.c2 = seg.c2 - ray.dir * (dot(ray.dir, seg.c2) / a);
    q.c1 = seg.c1 - ray.dir * (dot(ray.dir, seg.c1) / a);
    let c0 = seg.c0 - ray.start;
    q.c0 = c0 - ray.dir * (dot(ray.dir, c0) / a);
    let k = stationary_cubic(q, vec3<f32>(0.0));
    let falls_out = k.x + k.y + k.z + k.w < 0.0;
    var e0 = approach_of(q, seg, ray, 0.0, k.w > 0.0);
    var e1 = approach_of(q, seg, ray, 1.0, falls_out);
    e0.y = select(-1.0, e0.y, falls_in);
    e1.y = select(-1.0, e1.y, last);
    let roots = solve_cubic(k.x, k.y, k.z, k.w);
    let r0 = root_approach(q, seg, ray, k, roots.values.x);
    let r1 = root_approach(q, seg, ray, k, roots.values.y);
    let r2 = root_approach(q, seg, ray, k, roots.values.z);
    return Approaches(vec4<f32>(e0.x, e1.x, r0.x, r1.x), vec4<f32>(e0.y, e1.y, r0.y, r1.y), r2.x, r2.y, falls_out);
}

// A chain's segments seen from the ray's line, in one pass over them. Twin of Survey: the two that come nearest the
// line by their closest approach, (d2, segment) nearest first (d2 = F32_MAX for none), and the EXACT_SAMPLES (4)
// deepest closest approaches inside the ray, d2 and t, deepest first.
struct Survey {
    nearest0: vec2<f32>,
    nearest1: vec2<f32>,
    candidate_d2: vec4<f32>,
    candidate_t: vec4<f32>,
    candidate_count: u32,
}

fn survey_of(ray: Ray) -> Survey {
    let c = CHAIN;
    var r = Survey(vec2<f32>(F32_MAX, 0.0), vec2<f32>(F32_MAX, 0.0), vec4<f32>(F32_MAX), vec4<f32>(0.0), 0u);
    var falls_in = true;
    for (var j = 0u; j < c.segment_count; j++) {
        let a = approaches(chain_segment(c, HELD, j), ray, falls_in, j + 1u == c.segment_count);
        falls_in = a.falls_out;
        var least = F32_MAX;
        for (var i = 0u; i < 5u; i++) {
            let x = approach_at(a, i);
            if x.x < 0.0 {
                continue;
            }
            least = min(least, x.x);
            if !(x.y > 0.0 && x.y < 1.0) {
                continue;
            }
            // Into its place among the deepest, by comparisons (the last dropped where all are taken): the slots
            // deeper than it stay, the first other takes it, the rest shift down one.
            let d = r.candidate_d2;
            let t = r.candidate_t;
            let stays = d <= vec4<f32>(x.x);
            let here = vec4<bool>(!stays.x, stays.x && !stays.y, stays.y && !stays.z, stays.z && !stays.w);
            let d_shifted = vec4<f32>(x.x, d.x, d.y, d.z);
            let t_shifted = vec4<f32>(x.y, t.x, t.y, t.z);
            r.candidate_d2 = select(select(d_shifted, d, stays), vec4<f32>(x.x), here);
            r.candidate_t = select(select(t_shifted, t, stays), vec4<f32>(x.y), here);
            r.candidate_count = min(r.candidate_count + 1u, EXACT_SAMPLES);
        }
        if least < r.nearest0.x {
            r.nearest1 = r.nearest0;
            r.nearest0 = vec2<f32>(least, f32(j));
        } else if least < r.nearest1.x {
            r.nearest1 = vec2<f32>(least, f32(j));
        }
    }
    return r;
}

// Twin of reach_between: the farthest the chain can be from the ray, squared, between samples x and y.
fn reach_between(x: ChainSample, y: ChainSample, ray: Ray) -> f32 {
    let e = x.point - y.point;
    let slope = -2.0 * dot(ray.dir, e);
    let at_zero = dot(x.point, x.point) - dot(y.point, y.point) - 2.0 * dot(ray.start, e);
    var cross = x.t;
    if slope != 0.0 {
        cross = clamp(-at_zero / slope, x.t, y.t);
    }
    let fx = ray.start + ray.dir * cross - x.point;
    let fy = ray.start + ray.dir * cross - y.point;
    return max(max(x.d2, y.d2), min(dot(fx, fx), dot(fy, fy)));
}

fn segment_of(param: f32, k: u32) -> u32 {
    return min(u32(floor(clamp(param, 0.0, 1.0) * f32(k))), k - 1u);
}

fn inner_joint(param: f32, k: u32) -> bool {
    let x = param * f32(k);
    let r = round(x);
    return r > 0.0 && r < f32(k) && abs(x - r) <= END_SNAP * f32(k);
}

// Twin of Survey::suspect: why the scan samples the interval between x and y SUB_SCAN times finer, as Suspicion: 0
// not at all, 1 for events (the samples on different segments or on a joint), 2 for a rival segment.
fn suspect(r: Survey, x: ChainSample, y: ChainSample, ray: Ray) -> u32 {
    let k = CHAIN.segment_count;
    if k < 2u {
        return 0u;
    }
    let jx = segment_of(x.param, k);
    if inner_joint(x.param, k) || inner_joint(y.param, k) || jx != segment_of(y.param, k) {
        return 1u;
    }
    let rival = select(r.nearest0.x, r.nearest1.x, u32(r.nearest0.y) == jx);
    return select(0u, 2u, rival <= RIVAL_MARGIN * reach_between(x, y, ray));
}

// Twin of closest_approaches: the chain's closest approaches found segment by segment, in place of the scan's
// minima inside the ray.
fn closest_approaches(ray: Ray, survey: Survey, scanned: Minima) -> Minima {
    var exact: Minima;
    exact.count = 0u;
    for (var i = 0u; i < survey.candidate_count; i++) {
        let m = chain_sample(ray, survey.candidate_t[i], false);
        if m.d2 >= EXACT_SLACK * survey.candidate_d2[i] {
            offer(&exact, m, F32_MAX, F32_MAX);
        }
    }
    if exact.count == 0u {
        return scanned;
    }
    for (var slot = 0u; slot < scanned.count; slot++) {
        let x = minimum_at(scanned, slot);
        if x.t == 0.0 || x.t == 1.0 {
            offer(&exact, x, F32_MAX, F32_MAX);
        }
    }
    return exact;
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
    let c = CHAIN;
    let first = HELD.s0;
    let last = chain_segment(c, HELD, c.segment_count - 1u);
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
    let nearest_kinks = !(reads_brightest(c));
    var minima: Minima;
    minima.count = 0u;
    var kinks: Kinks;
    kinks.count = 0u;
    kinks.singular = 0u;
    // The ends' peaks, where the ray crosses their normal planes (with_ends).
    var ends: array<Peak, 2>;
    var end_count = 0u;
    // The scan's samples every step, and SUB_SCAN times finer over an interval it suspects (twin of the
    // reference's loop, whose samples come in another order: one call site of chain_sample in the loop, which
    // takes each coarse sample one interval ahead and decides then whether the interval up to it is suspect).
    let survey = survey_of(ray);
    let fine = SCAN * SUB_SCAN;
    let fine_step = step / f32(SUB_SCAN);
    var before = chain_sample(ray, 0.0, false);
    var ahead = chain_sample(ray, step, false);
    var why = suspect(survey, before, ahead, ray);
    var g_before_before = F32_MAX;
    for (var i = 1u; i <= fine; i++) {
        let coarse = i % SUB_SCAN == 0u;
        var t_sample = f32(i) * fine_step;
        if coarse {
            t_sample = f32(i / SUB_SCAN + 1u) * step;
        }
        var taken = ahead;
        if (coarse && i < fine) || (!coarse && why != 0u) {
            taken = chain_sample(ray, t_sample, false);
        }
        var after = taken;
        if coarse {
            after = ahead;
            ahead = taken;
        } else if why == 0u {
            continue;
        }
        offer(&minima, before, g_before_before, after.d2);
        // The interval's parts between the ends' normal planes inside it (one call site of search_jumps). calm
        // starts the stretch since the last jump, which the joints' cuts look at: (t, param).
        var left = before;
        var calm = vec2<f32>(before.t, before.param);
        var e = 0u;
        // An interval suspected for a rival alone is searched for jumps whole too, before its first finer part, as
        // an interval the scan does not suspect is (where no end's normal plane splits it): a first pass of this
        // loop, which keeps the kinks only (one call site of search_jumps still).
        let split = (end_t.x > before.t && end_t.x <= ahead.t) || (end_t.y > before.t && end_t.y <= ahead.t);
        var checking = !coarse && (i - 1u) % SUB_SCAN == 0u && why == 2u && nearest_kinks && !split;
        for (var part = 0u; part < 4u; part++) {
            var right = after;
            var next_left = after;
            var cut = -1.0;
            var end_sample = after;
            if checking {
                right = ahead;
                e = 2u;
            }
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
            if checking {
                checking = false;
                e = 0u;
                continue;
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
        if coarse && i < fine {
            why = suspect(survey, before, ahead, ray);
        }
    }
    offer(&minima, before, g_before_before, F32_MAX);
    minima = closest_approaches(ray, survey, minima);
    if !nearest_kinks {
        bright_kinks(ray, &kinks);
    }
    var found: Peaks;
    found.count = 0u;
    for (var slot = 0u; slot < minima.count; slot++) {
        var x = minimum_at(minima, slot);
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
