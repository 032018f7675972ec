// Copies the viewer's offscreen viewport (display values in a float texture) into egui's frame, filling the
// viewport egui sets for the paint callback. `fs_display` writes the values as they are (non-sRGB targets);
// `fs_srgb` decodes them first, for sRGB targets that encode on write, so both show the same colors. Where an
// object's silhouette crosses a pixel (its depth jumps against a neighbour's), the pixel is a tent over its
// 3 x 3 neighbourhood: the one-sample staircase of the edge softened over about a pixel. Elsewhere, and in a
// scene without objects (its depth all 1), the copy is exact. Screenshots and exports are not copied here.
// Rust side: src/gpu/blit_pass.rs, src/viewer/viewport.rs.

@group(0) @binding(0) var viewport_color: texture_2d<f32>;
@group(0) @binding(1) var viewport_sampler: sampler;
// The bits of the objects' depth in the frame (gpu::formats::DEPTH_VALUE_FORMAT), 1 where none is drawn.
@group(0) @binding(2) var viewport_depth: texture_2d<u32>;

// The jump between neighbours that marks a silhouette, as a share of the distance: in a perspective depth d,
// 1 - d goes as 1 / distance (nearly: the far plane is far), so the share needs no near or far plane. A
// surface's own slope stays below it, but for a floor seen at a grazing angle near its horizon.
const EDGE: f32 = 0.05;

// 1 - depth at p: 0 where no object is drawn, larger the nearer the surface.
fn nearness(p: vec2<i32>, size: vec2<i32>) -> f32 {
    return 1.0 - bitcast<f32>(textureLoad(viewport_depth, clamp(p, vec2<i32>(0), size - 1), 0).r);
}

// Whether the surfaces at `a` and `b` (nearness) differ by more than `EDGE` of the nearer one's distance.
fn jumps(a: f32, b: f32) -> bool {
    return abs(a - b) > EDGE * max(a, b);
}

fn color_at(p: vec2<i32>, size: vec2<i32>) -> vec3<f32> {
    return textureLoad(viewport_color, clamp(p, vec2<i32>(0), size - 1), 0).rgb;
}

// The viewport's color at `uv`: the texel itself, or on a silhouette the tent over its neighbourhood.
fn viewport_at(uv: vec2<f32>) -> vec3<f32> {
    let c = textureSample(viewport_color, viewport_sampler, uv).rgb;
    let size = vec2<i32>(textureDimensions(viewport_color));
    let p = clamp(vec2<i32>(uv * vec2<f32>(size)), vec2<i32>(0), size - 1);
    let a = nearness(p, size);
    let edge = jumps(a, nearness(p + vec2<i32>(1, 0), size)) || jumps(a, nearness(p - vec2<i32>(1, 0), size))
        || jumps(a, nearness(p + vec2<i32>(0, 1), size)) || jumps(a, nearness(p - vec2<i32>(0, 1), size));
    // The neighbourhood is read only on a silhouette, a few pixels in a hundred.
    if !edge {
        return c;
    }
    return (4.0 * color_at(p, size)
        + 2.0 * (color_at(p + vec2<i32>(1, 0), size) + color_at(p - vec2<i32>(1, 0), size)
            + color_at(p + vec2<i32>(0, 1), size) + color_at(p - vec2<i32>(0, 1), size))
        + color_at(p + vec2<i32>(1, 1), size) + color_at(p - vec2<i32>(1, 1), size)
        + color_at(p + vec2<i32>(1, -1), size) + color_at(p + vec2<i32>(-1, 1), size)) / 16.0;
}

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
    return vec4<f32>(viewport_at(in.uv), 1.0);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_srgb(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(srgb_to_linear(viewport_at(in.uv)), 1.0);
}
