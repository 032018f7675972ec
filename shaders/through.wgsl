// The glow seen through translucent objects: each texel's glow up to the first surface of any object (front),
// up to the last translucent surface it crosses (exit) and up to the first opaque one (the field the frame
// integrates, behind), blended by the shares of the glow inside and past the translucent objects that reach the
// eye: front + inside (exit - front) + behind (behind - exit), every layer (B, then the tint). One layer a z; the
// last holds B up to the first opaque surface undimmed, what the glow's edge fades by (shaders/billboard.wgsl).
// Rust side: src/gpu/through_pass.rs. CPU twin: reference::field_pass::see_through.

struct ThroughParams {
    resolution: u32,
    layers: u32,        // the field's; the output has one more: B behind them undimmed
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> through: ThroughParams;
// Each texel's exit clip and shares inside and behind, three numbers, rows from the top
// (objects::clip::crossings).
@group(0) @binding(1) var<storage, read> shares: array<f32>;
@group(0) @binding(2) var front: texture_2d_array<f32>;
@group(0) @binding(3) var behind: texture_2d_array<f32>;
@group(0) @binding(4) var output: texture_storage_2d_array<r32float, write>;
@group(0) @binding(5) var exit: texture_2d_array<f32>;

@compute @workgroup_size(8, 8)
fn see_through(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = through.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    let p = vec2<i32>(id.xy);
    if id.z == through.layers {
        textureStore(output, p, i32(id.z), vec4<f32>(textureLoad(behind, p, 0, 0).x, 0.0, 0.0, 1.0));
        return;
    }
    let layer = i32(id.z);
    let k = 3u * (id.y * w + id.x);
    let a = textureLoad(front, p, layer, 0).x;
    let x = textureLoad(exit, p, layer, 0).x;
    let b = textureLoad(behind, p, layer, 0).x;
    let value = a + shares[k + 1u] * (x - a) + shares[k + 2u] * (b - x);
    textureStore(output, p, layer, vec4<f32>(value, 0.0, 0.0, 1.0));
}
