// The field refined in image space (src/frame/refine.rs states the plan): the texture is built level by level,
// coarse to fine; each level's texels are first predicted from the level above by cubic interpolation, and the
// field pass (simpson.wgsl, adaptive_*.wgsl) integrates exactly only those this pass lists: where the detail
// measured one level up exceeds the tolerance, or where the texel is forced (border, no stencil, an edge of
// the clips). The list is compacted (one append a workgroup) and the field pass dispatched indirectly over it,
// so that a texel kept as predicted costs no invocation of the field pass at all. Rust side:
// src/gpu/field_pass/refine.rs. Twin: src/reference/refine.rs.
//
// Per level: `begin` empties the list; `mark` predicts every texel of the level and lists those to integrate;
// `arguments` writes the indirect dispatch's size; the field pass integrates the listed texels; `detail`
// measures how far each listed texel's prediction was off, for the next level's decisions.

// One level's settings (gpu::field_pass::refine::Level), bound with a dynamic offset.
struct Level {
    resolution: u32,
    layers: u32,     // the field texture's layers written: 1 (B) or 4 (B and the tint)
    level: u32,      // l: this level's texels lie on the grid of stride 2^l, off the grid of stride 2^(l+1)
    coarsest: u32,   // L: the coarsest level, integrated whole
    tolerance: f32,  // the detail above which a texel's neighbours are integrated
    slot: u32,       // where this level's indirect arguments go in `arguments_out` (in u32s)
    measured_top: u32, // 1: the coarsest level's own detail decides the level below it (else integrated whole)
    pad1: u32,
}

// The texels to integrate: their count; the list cut into PARTS parts (the viewer integrates a fine level's over
// several frames) and, last, the whole list, each as (first, count, invocations a row of its indirect dispatch
// holds, 0); and each texel's (x, y) packed as x | y << 16. The field pass reads the same buffer
// (shared/field_pass.wgsl, TexelList; the chunk names the part).
struct List {
    count: atomic<u32>,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    parts: array<vec4<u32>, 5>,
    texels: array<u32>,
}

const PARTS: u32 = 4u;

@group(0) @binding(0) var<storage, read> level: Level;
@group(0) @binding(1) var field: texture_storage_2d_array<r32float, read_write>;
// Each texel's detail: |exact - predicted|, the largest over the layers (0 where it was kept as predicted).
@group(0) @binding(2) var<storage, read_write> detail: array<f32>;
// The texels integrated whatever the prediction says, a bit each (frame::refine::forced_mask).
@group(0) @binding(3) var<storage, read> forced: array<u32>;
@group(0) @binding(4) var<storage, read_write> list: List;
// The indirect dispatches' sizes: x, y, z and a pad for each level.
@group(0) @binding(5) var<storage, read_write> arguments_out: array<u32>;

// How many workgroups of 64 a row of the indirect dispatch holds at most (the rest go to further rows).
const ROW_GROUPS: u32 = 4096u;

// Where a texel lies along one axis of the grid of stride 2s it is predicted from: its four nodes (all the same
// on a node of the grid) and their weights; fits is false where no stencil of four nodes fits (twin: axis).
struct Stencil {
    nodes: vec4<i32>,
    weights: vec4<f32>,
    fits: bool,
}

fn axis(x: i32, s: i32, last: i32) -> Stencil {
    let step = vec4<i32>(0, 2, 4, 6) * s;
    if x % (2 * s) == 0 {
        return Stencil(vec4<i32>(x), vec4<f32>(1.0, 0.0, 0.0, 0.0), true);
    }
    if x + s > last {
        return Stencil(vec4<i32>(x), vec4<f32>(0.0), false);
    }
    if x - 3 * s >= 0 && x + 3 * s <= last {
        return Stencil(vec4<i32>(x - 3 * s) + step, vec4<f32>(-1.0, 9.0, 9.0, -1.0) / 16.0, true);
    }
    if x + 5 * s <= last {
        return Stencil(vec4<i32>(x - s) + step, vec4<f32>(5.0, 15.0, -5.0, 1.0) / 16.0, true);
    }
    if x - 5 * s >= 0 {
        return Stencil(vec4<i32>(x - 5 * s) + step, vec4<f32>(1.0, -5.0, 15.0, 5.0) / 16.0, true);
    }
    return Stencil(vec4<i32>(x), vec4<f32>(0.0), false);
}

// The prediction of texel t of the level (stride s) from the nodes of stride 2s, every layer: four fixed loops
// of four (lavapipe keeps no loop bound it can avoid reading).
fn predict(t: vec2<i32>, s: i32) -> vec4<f32> {
    let last = i32(level.resolution) - 1;
    let ax = axis(t.x, s, last);
    let ay = axis(t.y, s, last);
    let layers = level.layers;
    var sum = vec4<f32>(0.0);
    for (var b = 0; b < 4; b++) {
        let wy = ay.weights[b];
        if wy == 0.0 {
            continue;
        }
        for (var a = 0; a < 4; a++) {
            let w = ax.weights[a] * wy;
            if w == 0.0 {
                continue;
            }
            let at = vec2<i32>(ax.nodes[a], ay.nodes[b]);
            sum.x += w * textureLoad(field, at, 0).x;
            if layers > 1u {
                sum.y += w * textureLoad(field, at, 1).x;
                sum.z += w * textureLoad(field, at, 2).x;
                sum.w += w * textureLoad(field, at, 3).x;
            }
        }
    }
    return sum;
}

fn store(t: vec2<i32>, v: vec4<f32>) {
    textureStore(field, t, 0, vec4<f32>(v.x, 0.0, 0.0, 1.0));
    if level.layers > 1u {
        textureStore(field, t, 1, vec4<f32>(v.y, 0.0, 0.0, 1.0));
        textureStore(field, t, 2, vec4<f32>(v.z, 0.0, 0.0, 1.0));
        textureStore(field, t, 3, vec4<f32>(v.w, 0.0, 0.0, 1.0));
    }
}

fn load(t: vec2<i32>) -> vec4<f32> {
    var v = vec4<f32>(textureLoad(field, t, 0).x, 0.0, 0.0, 0.0);
    if level.layers > 1u {
        v.y = textureLoad(field, t, 1).x;
        v.z = textureLoad(field, t, 2).x;
        v.w = textureLoad(field, t, 3).x;
    }
    return v;
}

// The level texel (x, y) is introduced at (frame::refine::Levels::level_of).
fn level_of(x: u32, y: u32) -> u32 {
    return min(countTrailingZeros(x | y), level.coarsest);
}

// Whether a node of stride 2s within 3s of t on both axes, introduced at the level above, showed a detail
// above the tolerance (frame::refine::window).
fn detail_near(t: vec2<i32>, s: i32) -> bool {
    let w = i32(level.resolution);
    var first = t - 3 * s;
    if t.x % (2 * s) == 0 {
        first.x = t.x - 2 * s;
    }
    if t.y % (2 * s) == 0 {
        first.y = t.y - 2 * s;
    }
    var found = false;
    for (var b = 0; b < 4; b++) {
        let ny = first.y + 2 * s * b;
        for (var a = 0; a < 4; a++) {
            let nx = first.x + 2 * s * a;
            let inside = nx >= 0 && ny >= 0 && nx < w && ny < w && abs(nx - t.x) <= 3 * s && abs(ny - t.y) <= 3 * s;
            if inside && level_of(u32(nx), u32(ny)) == level.level + 1u {
                found = found || detail[u32(ny * w + nx)] > level.tolerance;
            }
        }
    }
    return found;
}

@compute @workgroup_size(1)
fn begin() {
    atomicStore(&list.count, 0u);
}

var<workgroup> group_count: atomic<u32>;
var<workgroup> group_base: u32;

// Over the level's grid (stride s = 2^l): each texel of the level is predicted (kept as predicted unless
// listed) and listed where it must be integrated; a workgroup appends its texels in one reservation, in order.
@compute @workgroup_size(8, 8)
fn mark(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let s = 1u << level.level;
    let w = level.resolution;
    let t = gid.xy * s;
    let ours = t.x < w && t.y < w && level_of(t.x, t.y) == level.level;
    var listed = false;
    if ours {
        let ti = vec2<i32>(t);
        let si = i32(s);
        let i = t.y * w + t.x;
        if level.level == level.coarsest {
            listed = true;
            detail[i] = 0.0;
        } else {
            let stencil_fits = axis(ti.x, si, i32(w) - 1).fits && axis(ti.y, si, i32(w) - 1).fits;
            listed = (level.level + 1u == level.coarsest && level.measured_top == 0u) || !stencil_fits || (forced[i / 32u] >> (i % 32u) & 1u) != 0u
                || detail_near(ti, si);
            if stencil_fits {
                store(ti, predict(ti, si));
            }
            detail[i] = 0.0;
        }
    }
    if lane == 0u {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
    var slot = 0u;
    if listed {
        slot = atomicAdd(&group_count, 1u);
    }
    workgroupBarrier();
    if lane == 0u {
        group_base = atomicAdd(&list.count, atomicLoad(&group_count));
    }
    workgroupBarrier();
    if listed {
        list.texels[group_base + slot] = t.x | (t.y << 16u);
    }
}

// The indirect dispatches over the list's parts and over the whole list (the fifth): workgroups of 64, up to
// ROW_GROUPS a row; each slot x, y, z and the count of texels it covers.
@compute @workgroup_size(1)
fn arguments() {
    let n = atomicLoad(&list.count);
    for (var p = 0u; p < PARTS + 1u; p++) {
        var first = n * p / PARTS;
        var count = n * (p + 1u) / PARTS - first;
        if p == PARTS {
            first = 0u;
            count = n;
        }
        let groups = (count + 63u) / 64u;
        let x = min(groups, ROW_GROUPS);
        let y = select(0u, (groups + x - 1u) / x, x > 0u);
        list.parts[p] = vec4<u32>(first, count, 8u * x, 0u);
        let at = level.slot + 4u * p;
        arguments_out[at] = x;
        arguments_out[at + 1u] = y;
        arguments_out[at + 2u] = 1u;
        arguments_out[at + 3u] = count;
    }
}

// Over the list, once the field pass has integrated it: how far each texel's prediction was off.
@compute @workgroup_size(8, 8)
fn measure(@builtin(global_invocation_id) gid: vec3<u32>) {
    let whole = list.parts[PARTS];
    let k = gid.y * whole.z + gid.x;
    if k >= whole.y {
        return;
    }
    let packed = list.texels[k];
    let t = vec2<i32>(i32(packed & 0xffffu), i32(packed >> 16u));
    let s = i32(1u << level.level);
    let last = i32(level.resolution) - 1;
    if !(axis(t.x, s, last).fits && axis(t.y, s, last).fits) {
        return;
    }
    let d = abs(load(t) - predict(t, s));
    detail[u32(t.y) * level.resolution + u32(t.x)] = max(max(d.x, d.y), max(d.z, d.w));
}
