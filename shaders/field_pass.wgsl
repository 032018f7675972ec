// What every field pass shares: for every texel of the billboard's W x W field texture, a pass integrates the
// energy field along the texel's ray S -> E into the texture (METHOD.md section 3), B and beside it the tint of
// the sources' colors: memory is the texture alone, O(W^2). The passes (one WGSL file each: simpson.wgsl, adaptive_smooth.wgsl, adaptive_curves.wgsl, the
// last two after adaptive.wgsl) are each assembled into a module of their own by src/gpu/shaders.rs: the
// constants generated from the f64 twin, field_common.wgsl, this file, then the pass. Rust side:
// src/gpu/field_pass/ (gpu_data.rs holds the mirror of FieldParams; a test checks the layout). CPU twin:
// src/reference/field_pass.rs.

struct FieldParams {
    center: vec3<f32>,  // billboard center C
    size: f32,          // side length l
    right: vec3<f32>,
    resolution: u32,    // W
    up: vec3<f32>,
    divisions: u32,     // Simpson's n, even
    eye: vec3<f32>,     // V
    nu: f32,
    alpha: f32,
    beta: f32,
    epsilon: f32,
    point_count: u32,
    line_count: u32,
    torus_count: u32,
    curve_count: u32,
    integrator: u32,    // 0: simpson, 1: adaptive
    term_tolerance: f32, // adaptive: the error allowed on each term's part of B (the tolerance over the sources)
    jitter: u32,        // simpson: 1 for the randomly shifted rectangle rule
    seed: u32,
    gauss_order: u32,   // adaptive: n of the Gauss-Kronrod pair (n and 2n + 1 nodes; adaptive::kronrod_order)
    layers: u32,        // the texture's layers written: 1 (B alone, every source in the scene's color) or 4
    search: u32,        // 1 where some curve's term reads its brightest point (read on the CPU: the SEARCH constant)
    decay: u32,         // 0: distance (the papers'), 1: rms (integrate::Decay)
    stretch: f32,       // the rays' span in decay lengths: the rms decay's unit
    clipped: u32,       // 1 where the scene has objects: each texel's ray ends at its clip (binding 13)
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> params: FieldParams;

// The scene's structure, fixed when a pipeline is specialised to it (gpu::field_pass::Structure sets these
// pipeline-overridable constants): the compiler then folds the loops and branches they bound, drops the code
// of the source kinds the scene lacks and unrolls the Gauss-Kronrod rules. GENERIC, the default, reads each
// from params instead: the generic pipelines serve every scene while a specialised one compiles.
const GENERIC: u32 = 4294967295u;
override POINT_COUNT: u32 = 4294967295u;
override LINE_COUNT: u32 = 4294967295u;
override TORUS_COUNT: u32 = 4294967295u;
override CURVE_COUNT: u32 = 4294967295u;
override GAUSS_ORDER: u32 = 4294967295u;
override JITTER: u32 = 4294967295u;
// Whether some curve's term reads its brightest point (the continuous W form, gpu::field_pass::Structure): 0
// drops that search from the pipeline, so that scenes without it compile none of it.
override SEARCH: u32 = 0u;
fn point_count() -> u32 {
    if POINT_COUNT == GENERIC {
        return params.point_count;
    }
    return POINT_COUNT;
}

fn line_count() -> u32 {
    if LINE_COUNT == GENERIC {
        return params.line_count;
    }
    return LINE_COUNT;
}

fn torus_count() -> u32 {
    if TORUS_COUNT == GENERIC {
        return params.torus_count;
    }
    return TORUS_COUNT;
}

fn curve_count() -> u32 {
    if CURVE_COUNT == GENERIC {
        return params.curve_count;
    }
    return CURVE_COUNT;
}

fn gauss_order() -> u32 {
    if GAUSS_ORDER == GENERIC {
        return params.gauss_order;
    }
    return GAUSS_ORDER;
}

fn jittered() -> bool {
    if JITTER == GENERIC {
        return params.jitter != 0u;
    }
    return JITTER != 0u;
}

// The integrand's scalars, copied from params once an invocation (load_scalars, first thing in every entry point):
// lavapipe does not hoist a storage-buffer load out of a loop, so a value read from params (or any source buffer)
// inside the loops over samples and nodes is loaded again, lane by lane, at every pass. Reading the torus and
// these from registers made simpson on the torus 16x faster there (measured).
var<private> ALPHA: f32;
var<private> BETA: f32;
var<private> EPSILON: f32;
// The rays' span in decay lengths (the rms decay's unit), this texel's share of it once clipped (begin_texel).
var<private> STRETCH: f32;
fn load_scalars() {
    ALPHA = params.alpha;
    BETA = params.beta;
    EPSILON = params.epsilon;
    STRETCH = params.stretch;
}

@group(0) @binding(1) var<storage, read> points: array<PointSource>;
@group(0) @binding(2) var<storage, read> lines: array<LineSource>;
@group(0) @binding(3) var<storage, read> tori: array<TorusSource>;
@group(0) @binding(4) var<storage, read> curves: array<CurveSource>;
@group(0) @binding(5) var<storage, read> segments: array<CurveSegment>;
@group(0) @binding(6) var<storage, read> weights: array<f32>;
// The field texture: layer 0 holds B, layers 1 to 3 the tint sum B_i (Ce_i - Ce) in red, green and blue
// (gpu::context::FIELD_LAYERS), so that the colored sum is B Ce + tint = sum B_i Ce_i.
@group(0) @binding(7) var field: texture_storage_2d_array<r32float, read_write>;
// Each term's Ce_i - Ce in rgb (points, then lines, tori, curves): zero for a source in the scene's color;
// -Ce for a curve with a color series, whose pass adds the integral of its term times the series.
@group(0) @binding(9) var<storage, read> tints: array<vec4<f32>>;
// The curves' color series (CurveSource::first_color, color_count), their intensity applied.
@group(0) @binding(10) var<storage, read> colors: array<vec4<f32>>;
// The pieces of the curves whose term reads their brightest point (CurveSource::first_piece, piece_count).
@group(0) @binding(11) var<storage, read> pieces: array<CurvePiece>;
// The share c of each texel's ray S -> E before the first surface of the scene's objects, row-major from the
// top (objects::clip, computed in f64 on the CPU); a single 1 where the scene has no objects.
@group(0) @binding(13) var<storage, read> clips: array<f32>;

// One dispatch's share of the work: a range of Simpson samples, or of the adaptive integrator's terms (points,
// then lines, tori, curves). A texel's loops must stay under what some drivers allow one invocation (Mesa's
// llvmpipe and lavapipe stop every loop of an invocation after 65535 iterations in all, silently), so long
// integrals are split over several dispatches that add into the texture. Rust side: gpu_data::Chunk.
struct Chunk {
    first: u32,
    count: u32,
    accumulate: u32,  // 0: the first dispatch writes, else adds to what the texel holds
    pipeline: u32,    // the entry point that runs it (read on the CPU only)
    row_offset: u32,  // the first texel row of the dispatch: a band of rows (the viewer refines in bands)
    term: u32,        // simpson with the rms decay: the one term whose samples first .. first + count it sums
    stage: u32,       // and what it does with its sums: bit 0, add the scratch's; bit 1, finish the term (else keep)
}

// The texel an invocation integrates: its dispatch covers a band of rows from chunk.row_offset.
fn texel_of(gid: vec3<u32>) -> vec2<u32> {
    return vec2<u32>(gid.x, gid.y + chunk.row_offset);
}

@group(0) @binding(8) var<storage, read> chunk: Chunk;
// Writes a texel's (B, tint), or adds it to what the texel holds: B alone where the tint is zero (no reader
// looks at the tint layers then).
fn store(id: vec2<u32>, value: vec4<f32>) {
    store_layer(id, 0u, value.x);
    if params.layers > 1u {
        store_layer(id, 1u, value.y);
        store_layer(id, 2u, value.z);
        store_layer(id, 3u, value.w);
    }
}

fn store_layer(id: vec2<u32>, layer: u32, value: f32) {
    var v = value;
    if chunk.accumulate != 0u {
        v += textureLoad(field, vec2<i32>(id), layer).x;
    }
    textureStore(field, vec2<i32>(id), layer, vec4<f32>(v, 0.0, 0.0, 1.0));
}

// A term's part of the texel's (B, tint): its B_i, and B_i (Ce_i - Ce) from its tint (index t of tints).
fn glow_of(t: u32, b: f32) -> vec4<f32> {
    return vec4<f32>(b, b * tints[t].xyz);
}

// Sw(t) of a curve's W series (METHOD.md section 2). Twin of wseries::evaluate.
fn wseries(c: CurveSource, t_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    let n = c.weight_count;
    let w = c.first_weight;
    if n == 0u {
        return 1.0;
    }
    if n == 1u {
        return weights[w];
    }
    if n == 2u {
        return mix(weights[w], weights[w + 1u], t);
    }
    let b = wseries_basis(n, t);
    let first = w + wseries_span(n, t) - 2u;
    return b.x * weights[first] + b.y * weights[first + 1u] + b.z * weights[first + 2u];
}

// A curve's color series at t (twin of Colors::color_along): the quadratic B-spline of its colors, as wseries
// of its weights; zero without a series.
fn color_series(c: CurveSource, t_in: f32) -> vec3<f32> {
    let t = clamp(t_in, 0.0, 1.0);
    let n = c.color_count;
    let k = c.first_color;
    if n == 0u {
        return vec3<f32>(0.0);
    }
    if n == 1u {
        return colors[k].xyz;
    }
    if n == 2u {
        return mix(colors[k].xyz, colors[k + 1u].xyz, t);
    }
    let b = wseries_basis(n, t);
    let first = k + wseries_span(n, t) - 2u;
    return b.x * colors[first].xyz + b.y * colors[first + 1u].xyz + b.z * colors[first + 2u].xyz;
}

// The nearest point of a curve chain: (t* = (j + t) / k over all segments, distance).
fn curve_nearest(c: CurveSource, p: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(0.0, F32_MAX);
    for (var j = 0u; j < c.segment_count; j++) {
        let n = nearest_on_segment(segments[c.first_segment + j], p);
        if n.y < best.y {
            best = vec2<f32>((f32(j) + n.x) / f32(c.segment_count), n.y);
        }
    }
    return best;
}

// The point of a chain its term reads at p, (t, distance): the brightest point in the continuous W form
// (piece_count > 0), else the nearest. The term is b Sw(t) / max(eps, distance) at it.
fn curve_point(c: CurveSource, p: vec3<f32>) -> vec2<f32> {
    if SEARCH != 0u && c.piece_count > 0u {
        return curve_brightest(c, p);
    }
    return curve_nearest(c, p);
}

// The continuous W form (twin of field::brightest): the chain parameter t of the largest Sw(t) / max(eps, |p - C(t)|)
// and its distance from p.
fn curve_brightest(c: CurveSource, p: vec3<f32>) -> vec2<f32> {
    let b = curve_search(c, p);
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
fn curve_search(c: CurveSource, p: vec3<f32>) -> Bright {
    var best = Bright(-1.0, 0.0, F32_MAX, 0.0, c.first_piece);
    var first = 0u;
    var top = -1.0;
    for (var i = 0u; i <= c.piece_count; i++) {
        let k = c.first_piece + min(i, c.piece_count - 1u);
        let q = pieces[k];
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
        let q = pieces[k];
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
fn bright_motion(b: Bright, p: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    let q = pieces[b.piece];
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
            x = bracketed_root(a, q, p, 0u, u, v);
        } else if changes >= 2u {
            x = 0.5 * (u + v);
        }
        if x >= 0.0 {
            best = offer_point(best, q, k, x, p);
        }
        at += size;
        while level > 0u && (at & ((end >> (level - 1u)) - 1u)) == 0u {
            level--;
        }
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
    for (var side = 0u; side < 2u; side++) {
        let far = f32(side);
        var x = far;
        if length(piece_at(q, far) - p) > EPSILON {
            x = bracketed_root(unused, q, p, 1u, nearest.x, far);
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
// differ at u and v: Newton's method from the secant's root, kept in the bracket. Twin of bracketed_root.
fn bracketed_root(a: Quartic, q: CurvePiece, p: vec3<f32>, mode: u32, u: f32, v: f32) -> f32 {
    let fu = root_function(a, q, p, mode, u).x;
    let fv = root_function(a, q, p, mode, v).x;
    // lo keeps the sign of u, hi that of v.
    var lo = u;
    var hi = v;
    var x = clamp(u + (v - u) * fu / (fu - fv), min(u, v), max(u, v));
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

// What every entry point does first: copy the scalars (load_scalars) and find its texel and the texel's ray.
// inside is false for the invocations of the last workgroups that overhang the texture.
struct Texel {
    id: vec2<u32>,
    start: vec3<f32>,
    end: vec3<f32>,
    inside: bool,
}

fn begin_texel(gid: vec3<u32>) -> Texel {
    load_scalars();
    let id = texel_of(gid);
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return Texel(id, vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    var seg = texel_segment(id);
    // Up to the first surface: the shortened ray S -> S + c (E - S), the decay mapped onto it as
    // Integration::on_ray(c) maps it (alpha / c, beta / c, the span times c); where a surface hides the texel
    // (c = 0) every integrand is zero with alpha.
    let c = clip_of(id);
    if c < 1.0 {
        if c > 0.0 {
            seg[1] = seg[0] + c * (seg[1] - seg[0]);
            ALPHA /= c;
            BETA /= c;
            STRETCH *= c;
        } else {
            ALPHA = 0.0;
        }
    }
    return Texel(id, seg[0], seg[1], true);
}

fn clip_of(id: vec2<u32>) -> f32 {
    if params.clipped == 0u {
        return 1.0;
    }
    return clips[id.y * params.resolution + id.x];
}

// The texel's segment S -> E (4.2, 4.3): texel center on the billboard, column from the left, row from the top.
fn texel_segment(id: vec2<u32>) -> array<vec3<f32>, 2> {
    let w = params.resolution;
    let u = (f32(id.x) + 0.5) / f32(w) - 0.5;
    let v = 0.5 - (f32(id.y) + 0.5) / f32(w);
    let s_point = params.center + params.right * (params.size * u) + params.up * (params.size * v);
    let e_point = params.eye + params.nu * (s_point - params.eye);
    return array<vec3<f32>, 2>(s_point, e_point);
}

// The rms decay's B_i from the integral of its squared weighed energy over s: sign(c) sqrt(integral / stretch),
// the root taking back the sign of the term's coefficient that the square dropped (twin of Integration::finish).
fn signed_root(integral: f32, coefficient: f32) -> f32 {
    return select(1.0, -1.0, coefficient < 0.0) * sqrt(max(integral, 0.0) / STRETCH);
}

// The decay zeta(t) along the ray.
fn zeta_at(t: f32) -> f32 {
    return ALPHA / ((t + BETA) * (t + BETA));
}
