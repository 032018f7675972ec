// The kinks of a chain's term along the ray: samples of its nearest point (and, in the continuous W form, of its
// brightest point) along the ray, how far one lands from where the last would have moved on, and the bracket of a
// jump between two of them narrowed round by round. Twin: src/reference/adaptive_curves/kinks.rs.
#import shared/adaptive.wgsl

// The chain whose term the invocation integrates (integrate_curve_term sets them): its source and its first
// segments and pieces, read from their buffers once a term and kept in registers for every scan sample and node, which
// reach them through CHAIN, chain_segment and chain_piece, not the buffers (see held_chain).
var<private> CHAIN: CurveSource;
var<private> HELD: HeldChain;

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
    let c = CHAIN;
    let p = ray.start + ray.dir * t;
    let n = curve_nearest(c, HELD, p);
    let k = c.segment_count;
    let x = clamp(n.x, 0.0, 1.0) * f32(k);
    let j = min(u32(floor(x)), k - 1u);
    let seg = chain_segment(c, HELD, j);
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
    let b = curve_search(CHAIN, HELD, p);
    let m = bright_motion(CHAIN, HELD, b, p, ray.dir);
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
