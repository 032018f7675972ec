// The viewer's ground grid and axes: colored line segments in world space, drawn behind the billboard so the
// glow blends over them. Rust side: src/viewer/viewport.rs (gpu_data::GridParams, GridVertex; keep in sync).

struct GridParams {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> params: GridParams;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) color: vec4<f32>) -> VertexOut {
    var out: VertexOut;
    out.position = params.view_proj * vec4<f32>(position, 1.0);
    out.color = color;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return in.color;
}
