// The point of a chain its term reads: the nearest, or in the continuous W form the brightest (the largest
// Sw(t) / max(eps, |p - C(t)|)), searched piece by piece. Twin: src/field/brightest.rs (and Curve::point_seen in
// src/field/mod.rs).
#import shared/wseries.wgsl

// A chain's first HELD_SEGMENTS segments and, in the continuous W form, its first HELD_PIECES pieces, read from
// their buffers once (held_chain) and kept in registers for every point the chain is evaluated at. lavapipe loads
// a storage buffer again at every pass of a loop, lane by lane: simpson's loop over a ray's samples, reading the
// segments at each, spent most of its time loading them (the Bezier scene at 256, n = 64 to 256: 2.5 to 3x faster
// held, the same texels to the bit). Those past them are read from the buffers where they are used.
const HELD_SEGMENTS: u32 = 4u;
const HELD_PIECES: u32 = 4u;
struct HeldChain {
    s0: CurveSegment,
    s1: CurveSegment,
    s2: CurveSegment,
    s3: CurveSegment,
    q0: CurvePiece,
    q1: CurvePiece,
    q2: CurvePiece,
    q3: CurvePiece,
    weights: HeldWeights,
}

fn held_chain(c: CurveSource) -> HeldChain {
    var held: HeldChain;
    let last = c.first_segment + max(c.segment_count, 1u) - 1u;
    held.s0 = segments[c.first_segment];
    held.s1 = segments[min(c.first_segment + 1u, last)];
    held.s2 = segments[min(c.first_segment + 2u, last)];
    held.s3 = segments[min(c.first_segment + 3u, last)];
    held.weights = held_weights(c);
    if reads_brightest(c) {
        let final_piece = c.first_piece + c.piece_count - 1u;
        held.q0 = pieces[c.first_piece];
        held.q1 = pieces[min(c.first_piece + 1u, final_piece)];
        held.q2 = pieces[min(c.first_piece + 2u, final_piece)];
        held.q3 = pieces[min(c.first_piece + 3u, final_piece)];
    }
    return held;
}

// Piece k (an index of the pieces buffer) of a chain whose first pieces are held: from the registers, else from
// the buffer.
fn chain_piece(c: CurveSource, held: HeldChain, k: u32) -> CurvePiece {
    let i = k - c.first_piece;
    if i == 0u {
        return held.q0;
    }
    if i == 1u {
        return held.q1;
    }
    if i == 2u {
        return held.q2;
    }
    if i == 3u {
        return held.q3;
    }
    return pieces[k];
}

// Segment j of a chain whose first segments are held: from the registers, else from the buffer.
fn chain_segment(c: CurveSource, held: HeldChain, j: u32) -> CurveSegment {
    if j == 0u {
        return held.s0;
    }
    if j == 1u {
        return held.s1;
    }
    if j == 2u {
        return held.s2;
    }
    if j == 3u {
        return held.s3;
    }
    return segments[c.first_segment + j];
}

// The nearest point of a chain: (t* = (j + t) / k over all segments, distance).
fn curve_nearest(c: CurveSource, held: HeldChain, p: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(0.0, F32_MAX);
    for (var j = 0u; j < c.segment_count; j++) {
        let n = nearest_on_segment(chain_segment(c, held, j), p);
        if n.y < best.y {
            best = vec2<f32>((f32(j) + n.x) / f32(c.segment_count), n.y);
        }
    }
    return best;
}

// Whether a chain's term reads its brightest point (the continuous W form), not its nearest. SEARCH (FieldParams::search):
// 0 no chain's does, 1 some do (those with pieces), 2 every chain's does, and a pass then holds no code for the
// nearest point (lavapipe pays for the code a pass holds, taken or not).
fn reads_brightest(c: CurveSource) -> bool {
    return SEARCH == 2u || (SEARCH == 1u && c.piece_count > 0u);
}

// The point of a chain its term reads at p, (t, distance): the brightest point in the continuous W form
// (piece_count > 0), else the nearest. The term is b Sw(t) / max(eps, distance) at it.
fn curve_point(c: CurveSource, held: HeldChain, p: vec3<f32>) -> vec2<f32> {
    if reads_brightest(c) {
        return curve_brightest(c, held, p);
    }
    return curve_nearest(c, held, p);
}

// The continuous W form (twin of field::brightest): the chain parameter t of the largest Sw(t) / max(eps, |p - C(t)|)
// and its distance from p.
fn curve_brightest(c: CurveSource, held: HeldChain, p: vec3<f32>) -> vec2<f32> {
    let b = curve_search(c, held, p);
    return vec2<f32>(b.t, b.distance);
}

// The brightest point of a chain (twin of brightest::Brightest): the term's value there without its coefficient, its
// chain parameter and distance, and where it lies (the index of its piece in pieces, and x on it).
struct Bright {
    value: f32,
    t: f32,
    distance: f32,
    x: f32,
    piece: u32,
}

// Twin of brightest::search: the pieces' ends first (each piece's start, and the chain's end), then the insides of
// the pieces that could still beat the best (their largest weight over their ball's distance), the most promising
// first, so that near the chain one search settles the best and the rest fall to their bounds: the maxima of
// S / sqrt(D) inside, and where a piece comes within eps of p, the ends of that stretch and S's vertex.
fn curve_search(c: CurveSource, held: HeldChain, p: vec3<f32>) -> Bright {
    var best = Bright(-1.0, 0.0, F32_MAX, 0.0, c.first_piece);
    var first = 0u;
    var top = -1.0;
    for (var i = 0u; i <= c.piece_count; i++) {
        let k = c.first_piece + min(i, c.piece_count - 1u);
        let q = chain_piece(c, held, k);
        best = offer_point(best, q, k, select(0.0, 1.0, i == c.piece_count), p);
        let bound = q.weight_max / max(EPSILON, length(p - q.center) - q.radius);
        if i < c.piece_count && bound > top {
            top = bound;
            first = i;
        }
    }
    for (var j = 0u; j < c.piece_count; j++) {
        // The most promising piece, then the others in order.
        var i = first;
        if j > 0u {
            i = select(j, j - 1u, j <= first);
        }
        let k = c.first_piece + i;
        let q = chain_piece(c, held, k);
        let reach = length(p - q.center) - q.radius;
        if q.weight_max / max(EPSILON, reach) <= best.value {
            continue;
        }
        // The maxima inside; within eps of p also the ends of the flat top's stretch and S's vertex on it.
        best = piece_maxima(best, q, k, p);
        if reach < EPSILON {
            best = flat_top(best, q, k, p);
        }
    }
    return best;
}

// Twin of Brightest::motion: how the brightest point and the term move as p moves along dir, (the rate of its chain
// parameter, the slope of the value): the rate 0 where it rests at a piece's end or on the flat top.
fn bright_motion(c: CurveSource, held: HeldChain, b: Bright, p: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    let q = chain_piece(c, held, b.piece);
    let x = b.x;
    let off = piece_at(q, x) - p;
    let d = length(off);
    if d <= EPSILON {
        return vec2<f32>(0.0);
    }
    let slope = piece_weight(q, x) * dot(off, dir) / (d * d * d);
    if x <= 0.0 || x >= 1.0 {
        return vec2<f32>(0.0, slope);
    }
    return vec2<f32>(piece_rate(q, x, p, dir) * (q.t1 - q.t0), slope);
}

// dx/dt of a maximum of S / sqrt(D) at x inside piece q as p moves along dir: along the stationary curve
// h(x, p) = 0, -(dh/dp . dir) / (dh/dx), with D = |off|^2, D' = 2 C'.off, D'' = 2 (|C'|^2 + C''.off),
// dD/dp = -2 off and dD'/dp = -2 C'; 0 where that is not finite.
fn piece_rate(q: CurvePiece, x: f32, p: vec3<f32>, dir: vec3<f32>) -> f32 {
    let off = piece_at(q, x) - p;
    let s = piece_weight(q, x);
    let ds = 2.0 * q.s2 * x + q.s1;
    let d1 = 2.0 * q.c2 * x + q.c1;
    let dd = 2.0 * dot(d1, off);
    let ddd = 2.0 * (dot(d1, d1) + dot(2.0 * q.c2, off));
    let dh_dx = 4.0 * q.s2 * dot(off, off) + ds * dd - s * ddd;
    let dh_dp = -4.0 * ds * off + 2.0 * s * d1;
    let rate = -dot(dh_dp, dir) / dh_dx;
    return select(0.0, rate, abs(rate) < 1e30);
}

fn piece_at(q: CurvePiece, x: f32) -> vec3<f32> {
    return (q.c2 * x + q.c1) * x + q.c0;
}

fn piece_weight(q: CurvePiece, x: f32) -> f32 {
    return (q.s2 * x + q.s1) * x + q.s0;
}

// The better of best and point x of piece k (q).
fn offer_point(best: Bright, q: CurvePiece, k: u32, x: f32, p: vec3<f32>) -> Bright {
    let d = length(piece_at(q, x) - p);
    let value = piece_weight(q, x) / max(EPSILON, d);
    if value > best.value {
        return Bright(value, mix(q.t0, q.t1, x), d, x, k);
    }
    return best;
}

// A quartic a0 + a1 x + ... + a4 x^4: (a0, a1, a2, a3) and a4.
struct Quartic {
    low: vec4<f32>,
    a4: f32,
}

// h = 2 S' D - S D' on a piece, D = |C(x) - p|^2: S / sqrt(D) rises where h > 0. Twin of stationary_quartic.
fn stationary_quartic(q: CurvePiece, p: vec3<f32>) -> Quartic {
    let e = q.c0 - p;
    let d0 = dot(e, e);
    let d1 = 2.0 * dot(q.c1, e);
    let d2 = dot(q.c1, q.c1) + 2.0 * dot(q.c2, e);
    let d3 = 2.0 * dot(q.c1, q.c2);
    let d4 = dot(q.c2, q.c2);
    // S = s2 (x - r)^2, its double zero at an end r: h = s2 (x - r) (4 D - (x - r) D') with (x - r) taken out, in
    // the sign it has inside the piece; without h's root at r, which rounding put on either side of the end and hid a
    // maximum next to it (a W series gone dark beyond a knot).
    let r = q.zero_end;
    if r >= 0.0 {
        let sign = select(q.s2, -q.s2, r > 0.5);
        return Quartic(
            sign * vec4<f32>(4.0 * d0 + r * d1, 3.0 * d1 + 2.0 * r * d2, 2.0 * d2 + 3.0 * r * d3, d3 + 4.0 * r * d4),
            0.0,
        );
    }
    return Quartic(
        vec4<f32>(
            2.0 * q.s1 * d0 - q.s0 * d1,
            4.0 * q.s2 * d0 + q.s1 * d1 - 2.0 * q.s0 * d2,
            3.0 * q.s2 * d1 - 3.0 * q.s0 * d3,
            2.0 * q.s2 * d2 - q.s1 * d3 - 4.0 * q.s0 * d4,
        ),
        q.s2 * d3 - 2.0 * q.s1 * d4,
    );
}

// The quartic and its derivative at x.
fn quartic_at(a: Quartic, x: f32) -> vec2<f32> {
    let f = (((a.a4 * x + a.low.w) * x + a.low.z) * x + a.low.y) * x + a.low.x;
    let df = ((4.0 * a.a4 * x + 3.0 * a.low.w) * x + 2.0 * a.low.z) * x + a.low.y;
    return vec2<f32>(f, df);
}

// The Bernstein coefficients of the quartic on [u, v] (twin of bernstein_on): Taylor shift to u, scaling by v - u,
// then power to Bernstein form.
fn bernstein_on(a: Quartic, u: f32, v: f32) -> Quartic {
    var q0 = a.low.x;
    var q1 = a.low.y;
    var q2 = a.low.z;
    var q3 = a.low.w;
    var q4 = a.a4;
    // Synthetic division by (x - u), four rounds, unrolled (an array indexed by loop variables would live in memory).
    q3 += u * q4; q2 += u * q3; q1 += u * q2; q0 += u * q1;
    q3 += u * q4; q2 += u * q3; q1 += u * q2;
    q3 += u * q4; q2 += u * q3;
    q3 += u * q4;
    let w = v - u;
    q1 *= w;
    q2 *= w * w;
    q3 *= w * w * w;
    q4 *= w * w * w * w;
    return Quartic(
        vec4<f32>(
            q0,
            q0 + 0.25 * q1,
            q0 + 0.5 * q1 + q2 / 6.0,
            q0 + 0.75 * q1 + 0.5 * q2 + 0.25 * q3,
        ),
        q0 + q1 + q2 + q3 + q4,
    );
}

// The sign changes along Bernstein coefficients b, zeros skipped. Twin of sign_changes.
fn sign_changes(b: Quartic) -> u32 {
    var changes = 0u;
    var last = b.low.x;
    let c = vec4<f32>(b.low.yzw, b.a4);
    // Each coefficient in turn, unrolled (see bernstein_on).
    changes += select(0u, 1u, c.x != 0.0 && last != 0.0 && (c.x > 0.0) != (last > 0.0));
    last = select(last, c.x, c.x != 0.0);
    changes += select(0u, 1u, c.y != 0.0 && last != 0.0 && (c.y > 0.0) != (last > 0.0));
    last = select(last, c.y, c.y != 0.0);
    changes += select(0u, 1u, c.z != 0.0 && last != 0.0 && (c.z > 0.0) != (last > 0.0));
    last = select(last, c.z, c.z != 0.0);
    changes += select(0u, 1u, c.w != 0.0 && last != 0.0 && (c.w > 0.0) != (last > 0.0));
    return changes;
}

// The maxima of S / sqrt(D) inside a piece (twin of piece_maxima): the roots of h where it falls through zero,
// isolated on dyadic parts of [0, 1] by their Bernstein coefficients' signs, visited in order without a stack (as
// next_part walks panels).
fn piece_maxima(best_in: Bright, q: CurvePiece, k: u32, p: vec3<f32>) -> Bright {
    var best = best_in;
    let a = stationary_quartic(q, p);
    let end = 1u << ROOT_LEVELS;
    var at = 0u;
    var level = 0u;
    var visits = 0u;
    while at < end {
        let size = end >> level;
        let u = f32(at) / f32(end);
        let v = f32(at + size) / f32(end);
        let b = bernstein_on(a, u, v);
        let changes = sign_changes(b);
        visits++;
        if changes >= 2u && level < ROOT_LEVELS && visits < ROOT_VISITS {
            level++;
            continue;
        }
        // A maximum where h falls through zero; where the walk gave up halving a part, its middle stands in for
        // its maxima.
        var x = -1.0;
        if b.low.x > 0.0 && b.a4 < 0.0 {
            x = bracketed_root(a, q, p, 0u, u, v, -1.0);
        } else if changes >= 2u {
            x = 0.5 * (u + v);
        }
        if x >= 0.0 {
            best = offer_point(best, q, k, x, p);
        }
        at += size;
        // Up as many levels as the parts this one ends: the trailing zeros of at / size (at most 64), from its
        // lowest set bit by comparisons (a loop here spent lavapipe's budget of loop iterations, and GLSL ES 3.00,
        // the engine shader's, has no findLSB for countTrailingZeros).
        let k = at / size;
        let low = k & (~k + 1u);
        let zeros = select(0u, 1u, low >= 2u) + select(0u, 1u, low >= 4u) + select(0u, 1u, low >= 8u)
            + select(0u, 1u, low >= 16u) + select(0u, 1u, low >= 32u) + select(0u, 1u, low >= 64u);
        level -= min(level, zeros);
    }
    return best;
}

// Within eps of p the falloff is flat and the term S / eps (twin of flat_top): the best of best and the largest S on
// the stretch of the piece within eps around its nearest point, at the stretch's ends or at S's vertex.
fn flat_top(best_in: Bright, q: CurvePiece, k: u32, p: vec3<f32>) -> Bright {
    var best = best_in;
    let nearest = nearest_on_segment(CurveSegment(q.c2, 0.0, q.c1, 0.0, q.c0, 0.0), p);
    if nearest.y >= EPSILON {
        return best;
    }
    // The stretch's ends: where |C(x) - p| crosses eps between the nearest point and each end of the piece (one call
    // site of the root finder, in a loop).
    let unused = Quartic(vec4<f32>(0.0), 0.0);
    var ends = vec2<f32>(0.0, 1.0);
    // Newton on D - eps^2 from next to D's minimum crawls (its slope is nearly zero there, and where the stretch is
    // short the two ends nearly meet): it starts instead where D's quadratic model around the nearest point,
    // distance^2 + |C'|^2 (x - x*)^2, reaches eps^2 (the secant from the nearest point stopped a few 1e-5 short of
    // the end in f32 within ROOT_NEWTON steps, where a steep W series made that 0.5 % of the term).
    let speed = length(2.0 * q.c2 * nearest.x + q.c1);
    let half = sqrt(max(EPSILON * EPSILON - nearest.y * nearest.y, 0.0)) / max(speed, 1e-30);
    for (var side = 0u; side < 2u; side++) {
        let far = f32(side);
        var x = far;
        if length(piece_at(q, far) - p) > EPSILON {
            x = bracketed_root(unused, q, p, 1u, nearest.x, far, nearest.x + select(-half, half, side == 1u));
        }
        if side == 0u {
            ends.x = x;
        } else {
            ends.y = x;
        }
        best = offer_point(best, q, k, x, p);
    }
    if q.s2 < 0.0 {
        let vertex = -q.s1 / (2.0 * q.s2);
        if vertex > ends.x && vertex < ends.y {
            best = offer_point(best, q, k, vertex, p);
        }
    }
    return best;
}

// The root between u and v of h (mode 0) or of D - eps^2 (mode 1, evaluated from the point itself), whose signs
// differ at u and v: Newton's method from start where it lies inside, else from the secant's root, kept in the
// bracket. Twin of bracketed_root.
fn bracketed_root(a: Quartic, q: CurvePiece, p: vec3<f32>, mode: u32, u: f32, v: f32, start: f32) -> f32 {
    let fu = root_function(a, q, p, mode, u).x;
    let fv = root_function(a, q, p, mode, v).x;
    // lo keeps the sign of u, hi that of v.
    var lo = u;
    var hi = v;
    var x = clamp(u + (v - u) * fu / (fu - fv), min(u, v), max(u, v));
    if start > min(u, v) && start < max(u, v) {
        x = start;
    }
    for (var i = 0u; i < ROOT_NEWTON; i++) {
        let f = root_function(a, q, p, mode, x);
        if f.x == 0.0 {
            break;
        }
        if (f.x > 0.0) == (fu > 0.0) {
            lo = x;
        } else {
            hi = x;
        }
        var next = x - f.x / f.y;
        if !(next > min(lo, hi) && next < max(lo, hi)) {
            next = 0.5 * (lo + hi);
        }
        let settled = abs(next - x) <= 1e-7 * max(abs(x), 1e-3);
        x = next;
        if settled {
            break;
        }
    }
    return x;
}

// The function bracketed_root solves and its derivative at x.
fn root_function(a: Quartic, q: CurvePiece, p: vec3<f32>, mode: u32, x: f32) -> vec2<f32> {
    if mode == 1u {
        let off = piece_at(q, x) - p;
        return vec2<f32>(dot(off, off) - EPSILON * EPSILON, 2.0 * dot(off, 2.0 * q.c2 * x + q.c1));
    }
    return quartic_at(a, x);
}

