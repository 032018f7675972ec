// Copies the viewer's offscreen viewport (display values in a float texture) into egui's frame, filling the
// viewport egui sets for the paint callback. `fs_display` writes the values as they are (non-sRGB targets);
// `fs_srgb` decodes them first, for sRGB targets that encode on write, so both show the same colors.
// Rust side: src/viewer/viewport.rs.

@group(0) @binding(0) var viewport_color: texture_2d<f32>;
@group(0) @binding(1) var viewport_sampler: sampler;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

// One triangle covering the viewport.
@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_display(in: VertexOut) -> @location(0) vec4<f32> {
    let c = textureSample(viewport_color, viewport_sampler, in.uv);
    return vec4<f32>(c.rgb, 1.0);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_srgb(in: VertexOut) -> @location(0) vec4<f32> {
    let c = textureSample(viewport_color, viewport_sampler, in.uv);
    return vec4<f32>(srgb_to_linear(c.rgb), 1.0);
}
