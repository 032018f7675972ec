// Smooth upsampling of a low-resolution brightness texture to the billboard's W x W (the viewer's preview while
// the view moves; paper 000, 5.1: a low-resolution field, smoothly upsampled). Catmull-Rom in each direction
// over the 4 x 4 nearest source texels, texel centers at (i + 0.5) / size on both textures, edges clamped:
// C1 (no blocks, no creases at texel boundaries), exact on quadratics away from the edges, and interpolating,
// so a texel that lands on a source texel's center takes its value. Every layer alike (B, then the tint); B
// is not negative where no coefficient is, and the cubic's overshoot beside a thin bright core is clipped at 0
// (the tint, of either sign, is not). Rust side: src/gpu/upsample.rs.

@group(0) @binding(0) var low: texture_2d_array<f32>;
@group(0) @binding(1) var upsampled: texture_storage_2d_array<r32float, write>;

// The Catmull-Rom weights of the four texels around a point at fraction t past the second of them.
fn catmull_rom(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return 0.5 * vec4<f32>(-t3 + 2.0 * t2 - t, 3.0 * t3 - 5.0 * t2 + 2.0, -3.0 * t3 + 4.0 * t2 + t, t3 - t2);
}

@compute @workgroup_size(8, 8)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(upsampled);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let n = vec2<i32>(textureDimensions(low));
    let x = (vec2<f32>(id.xy) + 0.5) * vec2<f32>(n) / vec2<f32>(size) - 0.5;
    let base = floor(x);
    let f = x - base;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let b = vec2<i32>(base);
    // One layer a z (B, then the tint where the scene has one: gpu::upsample dispatches that many).
    let layer = id.z;
    {
        var sum = 0.0;
        for (var j = 0; j < 4; j++) {
            let y = clamp(b.y - 1 + j, 0, n.y - 1);
            var row = 0.0;
            for (var i = 0; i < 4; i++) {
                let column = clamp(b.x - 1 + i, 0, n.x - 1);
                row += wx[i] * textureLoad(low, vec2<i32>(column, y), layer, 0).x;
            }
            sum += wy[j] * row;
        }
        if layer == 0u {
            sum = max(sum, 0.0);
        }
        textureStore(upsampled, vec2<i32>(id.xy), layer, vec4<f32>(sum, 0.0, 0.0, 1.0));
    }
}
