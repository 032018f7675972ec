// What every field pass shares: for every texel of the billboard's W x W field texture, a pass integrates the
// energy field along the texel's ray S -> E into the texture (METHOD.md section 3), B and beside it the tint of
// the sources' colors: memory is the texture alone, O(W^2). The passes (one WGSL file each: simpson.wgsl,
// adaptive_smooth.wgsl, adaptive_curves.wgsl) import this file; src/gpu/shaders.rs composes each into a module of
// its own. Rust side: src/gpu/field_pass/ (gpu_data.rs holds the mirror of FieldParams; a test checks the
// layout). CPU twin: src/reference/field_pass.rs.
#import shared/curve.wgsl
#import shared/field_params.wgsl
#import shared/decay.wgsl


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
// Which curves' terms read their brightest point (the continuous W form, gpu::field_pass::Structure; reads_brightest):
// 0 none, and the pipeline holds no search; 1 some; 2 all, and it holds no nearest point.
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

// The integrand's scalars (shared/decay.wgsl), copied from params once an invocation (load_scalars, first thing in
// every entry point): lavapipe does not hoist a storage-buffer load out of a loop, so a value read from params (or
// any source buffer) inside the loops over samples and nodes is loaded again, lane by lane, at every pass. Reading
// the torus and these from registers made simpson on the torus 16x faster there (measured). STRETCH is this
// texel's share of the rays' span once clipped (begin_texel).
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
    listed: u32,      // 1: the dispatch is indirect, over part row_offset of the texels listed (binding 14)
}

// The texels a refined field integrates at one level (refine.wgsl lists them): how many, the list's parts as
// (first, count, invocations a row of the part's indirect dispatch holds, 0), and each texel's (x, y) as
// x | y << 16.
struct TexelList {
    count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    parts: array<vec4<u32>, 5>,
    texels: array<u32>,
}

@group(0) @binding(14) var<storage, read> listed: TexelList;

// The texel an invocation integrates: its dispatch covers a band of rows from chunk.row_offset, or the listed
// texels (one past the texture where the invocation overhangs the list).
fn texel_of(gid: vec3<u32>) -> vec2<u32> {
    if chunk.listed != 0u {
        let part = listed.parts[chunk.row_offset];
        let k = gid.y * part.z + gid.x;
        if k >= part.y {
            return vec2<u32>(params.resolution);
        }
        let packed = listed.texels[part.x + k];
        return vec2<u32>(packed & 0xffffu, packed >> 16u);
    }
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
