// The running mean of jittered frames while nothing changes (the viewer's accumulation): frame k = 1, 2, ...
// of the field pass moves each texel's mean by (B - mean) / k, and each layer of the tint likewise. The first
// frame overwrites whatever the mean texture held. Rust side: gpu::frame_average.

struct AverageParams {
    weight: f32,   // 1 / k
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

@group(0) @binding(0) var<uniform> average: AverageParams;
@group(0) @binding(1) var frame: texture_2d_array<f32>;
@group(0) @binding(2) var mean: texture_storage_2d_array<r32float, read_write>;

@compute @workgroup_size(8, 8)
fn average_frames(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(mean);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    // One layer a z (B, then the tint where the scene has one: gpu::frame_average dispatches that many).
    let texel = vec2<i32>(id.xy);
    let b = textureLoad(frame, texel, id.z, 0).x;
    var m = b;
    if average.weight < 1.0 {
        let old = textureLoad(mean, texel, id.z).x;
        m = old + (b - old) * average.weight;
    }
    textureStore(mean, texel, id.z, vec4<f32>(m, 0.0, 0.0, 1.0));
}
