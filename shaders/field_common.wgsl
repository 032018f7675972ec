// Shared by every pass that evaluates the energy field (prepended to them by src/gpu/shaders.rs):
// the source structs, mirrored in src/gpu/field_pass/gpu_data.rs (keep in sync), and the f32 twins of
// the f64 reference in src/field/: distance functions, Cardano's formula, the nearest point on a quadratic
// Bezier segment, and the W series basis. METHOD.md sections 1-2.

struct PointSource {
    position: vec3<f32>,
    coefficient: f32,
}

struct LineSource {
    point: vec3<f32>,
    coefficient: f32,
    direction: vec3<f32>, // unit length
    pad0: f32,
}

struct TorusSource {
    center: vec3<f32>,
    major_radius: f32,
    axis: vec3<f32>, // unit length
    coefficient: f32,
}

// A chain of quadratic Bezier segments: its segments, W series and color series are ranges of the segment,
// weight and color buffers.
struct CurveSource {
    first_segment: u32,
    segment_count: u32,
    first_weight: u32,
    weight_count: u32, // 0: all weights 1
    coefficient: f32,
    first_color: u32,
    color_count: u32,  // 0: no color series (the curve's one color is its tint)
    first_piece: u32,
    piece_count: u32,  // 0: the term reads the nearest point (the papers' form, or a uniform W series)
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// A stretch of a chain between its joints and W's knots, for the continuous W form (twin of field::brightest::Piece):
// the curve C(x) = c2 x^2 + c1 x + c0 and S(x) = s2 x^2 + s1 x + s0 in its own x in [0, 1], the chain parameters at
// its ends, a ball holding it and S's largest value on it.
struct CurvePiece {
    c2: vec3<f32>,
    s2: f32,
    c1: vec3<f32>,
    s1: f32,
    c0: vec3<f32>,
    s0: f32,
    center: vec3<f32>,
    radius: f32,
    t0: f32,
    t1: f32,
    weight_max: f32,
    pad0: f32,
}

// One segment in power form, C(t) = c2 t^2 + c1 t + c0 (computed from the control points in f64).
struct CurveSegment {
    c2: vec3<f32>,
    pad0: f32,
    c1: vec3<f32>,
    pad1: f32,
    c0: vec3<f32>,
    pad2: f32,
}

const PI: f32 = 3.14159265358979;
const F32_MAX: f32 = 3.0e38;

// 1 / max(eps, d): the falloff of every kind of source.
fn falloff(d: f32, eps: f32) -> f32 {
    return 1.0 / max(eps, d);
}

// Distance from p to the line through m along the unit direction d (thesis 3.3).
fn line_distance(p: vec3<f32>, m: vec3<f32>, d: vec3<f32>) -> f32 {
    // The part of p - m across the line, not the difference of squares, which rounding ruins close to the
    // line far from m. Twin of field::line_distance.
    let q = p - m;
    return length(q - d * dot(q, d));
}

// Distance from p to the major circle of a torus (thesis 3.7 in the torus's own frame).
fn torus_distance(p: vec3<f32>, center: vec3<f32>, axis: vec3<f32>, major_radius: f32) -> f32 {
    let q = p - center;
    let z = dot(q, axis);
    let rho = sqrt(max(dot(q, q) - z * z, 0.0));
    let dr = rho - major_radius;
    return sqrt(dr * dr + z * z);
}

// Up to three real roots; unused slots hold a value outside any range a caller accepts.
struct Roots {
    values: vec3<f32>,
    count: u32,
}

fn real_cbrt(x: f32) -> f32 {
    return sign(x) * pow(abs(x), 1.0 / 3.0);
}

// Cardano's formula for x^3 + a x^2 + b x + c = 0, trigonometric form for three real roots, with the - a/3
// shift (METHOD.md section 1, corrected). Twin of field::cubic::solve_monic_cubic.
fn solve_monic_cubic(a: f32, b: f32, c: f32) -> Roots {
    let shift = a / 3.0;
    let p = -a * a / 9.0 + b / 3.0;
    let q = a * a * a / 27.0 - a * b / 6.0 + c / 2.0;
    let r = p * p * p + q * q;
    if r >= 0.0 {
        // u on the side of -q -/+ sqrt(r) without cancellation, v = -p / u (u v = -p).
        let t = -q - select(-1.0, 1.0, q >= 0.0) * sqrt(r);
        let u = real_cbrt(t);
        let v = select(-p / u, 0.0, u == 0.0);
        return Roots(vec3<f32>(u + v - shift, F32_MAX, F32_MAX), 1u);
    }
    let m = 2.0 * sqrt(-p);
    let theta = atan2(sqrt(-r), -q);
    return Roots(
        vec3<f32>(
            m * cos(theta / 3.0) - shift,
            m * cos((theta + 2.0 * PI) / 3.0) - shift,
            m * cos((theta + 4.0 * PI) / 3.0) - shift,
        ),
        3u,
    );
}

// Real roots of k3 x^3 + k2 x^2 + k1 x + k0, falling back to lower degrees when the leading coefficients
// vanish relative to the largest (tiny = 1e-6 in f32). Twin of field::cubic::solve_cubic.
fn solve_cubic(k3: f32, k2: f32, k1: f32, k0: f32) -> Roots {
    let tiny = 1e-6;
    let scale = max(max(abs(k3), abs(k2)), max(abs(k1), abs(k0)));
    if scale == 0.0 {
        return Roots(vec3<f32>(F32_MAX), 0u);
    }
    if abs(k3) > tiny * scale {
        return solve_monic_cubic(k2 / k3, k1 / k3, k0 / k3);
    }
    if abs(k2) > tiny * scale {
        let disc = k1 * k1 - 4.0 * k2 * k0;
        if disc < 0.0 {
            return Roots(vec3<f32>(F32_MAX), 0u);
        }
        let s = sqrt(disc);
        var t = -0.5 * (k1 + s);
        if k1 < 0.0 {
            t = -0.5 * (k1 - s);
        }
        if t == 0.0 {
            return Roots(vec3<f32>(0.0, F32_MAX, F32_MAX), 1u);
        }
        return Roots(vec3<f32>(t / k2, k0 / t, F32_MAX), 2u);
    }
    if abs(k1) > tiny * scale {
        return Roots(vec3<f32>(-k0 / k1, F32_MAX, F32_MAX), 1u);
    }
    return Roots(vec3<f32>(F32_MAX), 0u);
}

fn segment_at(s: CurveSegment, t: f32) -> vec3<f32> {
    return (s.c2 * t + s.c1) * t + s.c0;
}

// Two Newton steps on the stationary cubic k, keeping the start if a step is not finite.
fn polish(k: vec4<f32>, t0: f32) -> f32 {
    // A step that fails leaves t as it was, and fails again from there: two calls are the loop's two steps
    // with its break, without the loop (which lavapipe keeps as one).
    return newton_step(k, newton_step(k, t0));
}

// One Newton step on the stationary cubic k from t; t itself where the step is not finite.
fn newton_step(k: vec4<f32>, t: f32) -> f32 {
    let f = ((k.x * t + k.y) * t + k.z) * t + k.w;
    let df = (3.0 * k.x * t + 2.0 * k.y) * t + k.z;
    let next = t - f / df;
    if df == 0.0 || abs(next) > 1e6 || next != next {
        return t;
    }
    return next;
}

// Nearest point of a segment to p: (t, distance). Candidates are both end points and the real roots of
// C'(t).(C(t) - P) = 0 in [-0.5, 1.5], raw and polished, clamped to [0, 1]. Twin of Segment::nearest.
fn nearest_on_segment(segment: CurveSegment, p: vec3<f32>) -> vec2<f32> {
    // A segment at rest at its end (its last two control points coincide) is solved from that end: there the
    // stationary cubic has a double root, which f32 finds only to the square root of its rounding (W off by
    // 1e-4 along the stretch where the nearest point leaves the end); from the other side it is a simple root.
    var s = segment;
    let flip = ends_at_rest(segment) && !starts_at_rest(segment);
    if flip {
        let d1 = 2.0 * segment.c2 + segment.c1;
        s = CurveSegment(segment.c2, 0.0, -d1, 0.0, segment.c2 + segment.c1 + segment.c0, 0.0);
    }
    let d = s.c0 - p;
    let k = vec4<f32>(
        2.0 * dot(s.c2, s.c2),
        3.0 * dot(s.c1, s.c2),
        2.0 * dot(s.c2, d) + dot(s.c1, s.c1),
        dot(s.c1, d),
    );
    var best = vec2<f32>(0.0, length(d));
    let end = length(segment_at(s, 1.0) - p);
    if end < best.y {
        best = vec2<f32>(1.0, end);
    }
    // Each of the three slots in turn, unrolled (a slot past the roots found holds F32_MAX, out of range):
    // indexing the roots by a loop variable kept them in memory on lavapipe.
    let roots = solve_cubic(k.x, k.y, k.z, k.w);
    best = offer_root(best, s, p, k, roots.values.x);
    best = offer_root(best, s, p, k, roots.values.y);
    best = offer_root(best, s, p, k, roots.values.z);
    return select(best, vec2<f32>(1.0 - best.x, best.y), flip);
}

// nearest_on_segment's candidates from one root of the stationary cubic k, raw and polished, clamped to
// [0, 1], where the root lies in [-0.5, 1.5]: the nearer of them and `best`.
fn offer_root(best: vec2<f32>, s: CurveSegment, p: vec3<f32>, k: vec4<f32>, root: f32) -> vec2<f32> {
    if !(root >= -0.5 && root <= 1.5) {
        return best;
    }
    var out = best;
    let raw = clamp(root, 0.0, 1.0);
    let raw_distance = length(segment_at(s, raw) - p);
    if raw_distance < out.y {
        out = vec2<f32>(raw, raw_distance);
    }
    let polished = clamp(polish(k, root), 0.0, 1.0);
    let polished_distance = length(segment_at(s, polished) - p);
    if polished_distance < out.y {
        out = vec2<f32>(polished, polished_distance);
    }
    return out;
}


// Whether a segment's speed vanishes at its start (its first two control points coincide). Twin of
// curve::Segment::starts_at_rest.
fn starts_at_rest(s: CurveSegment) -> bool {
    return dot(s.c1, s.c1) <= DEGENERATE * dot(s.c2, s.c2);
}

// Whether a segment's speed vanishes at its end (its last two control points coincide). Twin of
// curve::Segment::ends_at_rest.
fn ends_at_rest(s: CurveSegment) -> bool {
    let d1 = 2.0 * s.c2 + s.c1;
    return dot(d1, d1) <= DEGENERATE * dot(s.c2, s.c2);
}

// Knot u_i of the clamped uniform quadratic knot vector for n >= 3 weights. Twin of wseries::knot.
fn wseries_knot(n: u32, i: u32) -> f32 {
    if i <= 2u {
        return 0.0;
    }
    if i >= n {
        return 1.0;
    }
    return f32(i - 2u) / f32(n - 2u);
}

// Knot span index (2..=n-1) holding t, for n >= 3 weights; t = 1 belongs to the last span.
fn wseries_span(n: u32, t: f32) -> u32 {
    let segments = n - 2u;
    let k = clamp(i32(floor(t * f32(segments))), 0, i32(segments) - 1);
    return u32(k) + 2u;
}

// The three non-zero quadratic basis functions N_{span-2}, N_{span-1}, N_span at t (NURBS Book A2.2).
// Twin of wseries::basis.
fn wseries_basis(n: u32, t: f32) -> vec3<f32> {
    let span = wseries_span(n, t);
    let left1 = t - wseries_knot(n, span);
    let right1 = wseries_knot(n, span + 1u) - t;
    let left2 = t - wseries_knot(n, span - 1u);
    let right2 = wseries_knot(n, span + 2u) - t;
    // Degree 1: N_{span-1,1}, N_{span,1}.
    var d = right1 + left1;
    var temp = select(1.0 / d, 0.0, d == 0.0);
    let a0 = right1 * temp;
    let a1 = left1 * temp;
    // Degree 2.
    d = right1 + left2;
    temp = select(a0 / d, 0.0, d == 0.0);
    let b0 = right1 * temp;
    var saved = left2 * temp;
    d = right2 + left1;
    temp = select(a1 / d, 0.0, d == 0.0);
    let b1 = saved + right2 * temp;
    let b2 = left1 * temp;
    return vec3<f32>(b0, b1, b2);
}
