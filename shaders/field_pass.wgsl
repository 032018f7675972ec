// What every field pass shares: for every texel of the billboard's W x W field texture, a pass integrates the
// energy field along the texel's ray S -> E into the texture (METHOD.md section 3), B and beside it the tint of
// the sources' colors: memory is the texture alone, O(W^2). The passes (one WGSL file each: simpson.wgsl, adaptive_smooth.wgsl, adaptive_curves.wgsl, the
// last two after adaptive.wgsl) are each assembled into a module of their own by src/gpu/shaders.rs: the
// constants generated from the f64 twin, field_common.wgsl, this file, then the pass. Rust side:
// src/gpu/field_pass.rs (gpu_data holds the mirror of FieldParams; a test checks the layout). CPU twin:
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
fn load_scalars() {
    ALPHA = params.alpha;
    BETA = params.beta;
    EPSILON = params.epsilon;
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
    let seg = texel_segment(id);
    return Texel(id, seg[0], seg[1], true);
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

// The decay zeta(t) along the ray.
fn zeta_at(t: f32) -> f32 {
    return ALPHA / ((t + BETA) * (t + BETA));
}
