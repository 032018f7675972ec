// A quadratic Bezier segment in power form: its points, and its nearest point to p from the stationary cubic.
// Twin: src/field/curve.rs.
#import shared/cubic.wgsl

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

// The coefficients (k3, k2, k1, k0) of the segment's stationary cubic at p, C'(t).(C(t) - p) = 0.
fn stationary_cubic(s: CurveSegment, p: vec3<f32>) -> vec4<f32> {
    let d = s.c0 - p;
    return vec4<f32>(2.0 * dot(s.c2, s.c2), 3.0 * dot(s.c1, s.c2), 2.0 * dot(s.c2, d) + dot(s.c1, s.c1), dot(s.c1, d));
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
    let k = stationary_cubic(s, p);
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
    // At rest at its start (as solved), the segment is straight, c0 + c2 x^2, and its nearest x^2 a projection:
    // near the resting end the cubic's three roots crowd around 0 and f32 cannot part them (it gave the end itself,
    // W read 0.002 away from where it should on a chain whose last two points coincide: 1.5e-4 of B on GL). Its distance
    // is the true one's to f32's rounding, and so are the others' near the resting end: a tie goes to it.
    let c22 = dot(s.c2, s.c2);
    if starts_at_rest(s) && c22 > 0.0 {
        let x = sqrt(clamp(-dot(s.c2, d) / c22, 0.0, 1.0));
        let distance = length(segment_at(s, x) - p);
        if distance <= best.y * (1.0 + 4e-7) {
            best = vec2<f32>(x, distance);
        }
    }
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

