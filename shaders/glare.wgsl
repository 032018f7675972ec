// The glare pass: a fog glow in the billboard's plane, over a field texture (B, then the tint where the scene
// has one). Each texel's excess over the threshold, compressed, E = e / (1 + e) with e = max(B - T, 0), in the
// texel's own color (the tint
// scaled alike, E tint / B), blurred by a separable Gaussian (glare_rows, then glare_columns; edges clamped)
// and added back strength times. One layer a z. Rust side: src/gpu/glare_pass.rs. CPU twin:
// src/reference/glare.rs.

// A storage buffer, not a uniform: lavapipe compiles a shader again for every value of a uniform that bounds
// a loop, and the radius bounds the blur's.
struct GlareParams {
    threshold: f32,
    strength: f32,
    radius: u32,   // the kernel's half-width: weights[0 ..= 2 radius]
    undimmed: u32, // the layer of B undimmed by translucent objects (shaders/through.wgsl), glared as B; 0: none
}

@group(0) @binding(0) var<storage, read> glare: GlareParams;
@group(0) @binding(1) var<storage, read> weights: array<f32>;
@group(0) @binding(2) var field: texture_2d_array<f32>;
@group(0) @binding(3) var rows: texture_2d_array<f32>;
@group(0) @binding(4) var output: texture_storage_2d_array<r32float, write>;

// Layer `layer`'s excess at texel p: B's, or the tint's in the texel's color.
fn excess(p: vec2<i32>, layer: u32) -> f32 {
    // B undimmed has its own excess, as B has.
    let own = layer == glare.undimmed && layer != 0u;
    let b = textureLoad(field, p, select(0u, layer, own), 0).x;
    if b <= glare.threshold {
        return 0.0;
    }
    // Compressed, E / (1 + E) (the CPU twin says why).
    let e0 = b - glare.threshold;
    let e = e0 / (1.0 + e0);
    if layer == 0u || own {
        return e;
    }
    return e * textureLoad(field, p, layer, 0).x / b;
}

// The excess blurred along the rows, into the output (the columns' pass reads it as `rows`).
@compute @workgroup_size(8, 8)
fn glare_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(output));
    let p = vec2<i32>(id.xy);
    if p.x >= size.x || p.y >= size.y {
        return;
    }
    let r = i32(glare.radius);
    var sum = 0.0;
    for (var o = -r; o <= r; o++) {
        let x = clamp(p.x + o, 0, size.x - 1);
        sum += weights[u32(o + r)] * excess(vec2<i32>(x, p.y), id.z);
    }
    textureStore(output, p, id.z, vec4<f32>(sum, 0.0, 0.0, 1.0));
}

// The rows' blur blurred along the columns, times the strength, added to the field.
@compute @workgroup_size(8, 8)
fn glare_columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(output));
    let p = vec2<i32>(id.xy);
    if p.x >= size.x || p.y >= size.y {
        return;
    }
    let r = i32(glare.radius);
    var sum = 0.0;
    for (var o = -r; o <= r; o++) {
        let y = clamp(p.y + o, 0, size.y - 1);
        sum += weights[u32(o + r)] * textureLoad(rows, vec2<i32>(p.x, y), id.z, 0).x;
    }
    let base = textureLoad(field, p, id.z, 0).x;
    textureStore(output, p, id.z, vec4<f32>(base + glare.strength * sum, 0.0, 0.0, 1.0));
}
