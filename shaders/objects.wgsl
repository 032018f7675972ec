// The scene's objects: triangles lit at their vertices by the sources (objects::lighting, in f64 on the CPU),
// drawn with depth behind the billboard, so that the glow blends over them as over the background. Rust side:
// src/gpu/object_pass.rs (gpu_data::ObjectParams, ObjectVertex; keep in sync). CPU twin:
// src/reference/objects.rs (the same triangles ray-cast, their vertex colors interpolated).

struct ObjectParams {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> params: ObjectParams;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) color: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) color: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.position = params.view_proj * vec4<f32>(position, 1.0);
    out.color = color;
    return out;
}

struct FragmentOut {
    // The lit color, unclamped (an HDR export keeps it; the display clamps), opaque.
    @location(0) color: vec4<f32>,
    // The bits of the fragment's depth, a copy of what the depth test keeps, for the billboard to read (a depth
    // texture cannot be read on GL, nor r32float rendered there: gpu::object_pass::DEPTH_VALUE_FORMAT).
    @location(1) depth: u32,
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    return FragmentOut(vec4<f32>(in.color, 1.0), bitcast<u32>(in.position.z));
}
