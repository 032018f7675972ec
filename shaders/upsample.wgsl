// Smooth upsampling of a low-resolution brightness texture to the billboard's W x W (the viewer's preview while
// the view moves; paper 000, 5.1: a low-resolution field, smoothly upsampled). Catmull-Rom in each direction
// over the 4 x 4 nearest source texels, texel centers at (i + 0.5) / size on both textures, edges clamped:
// C1 (no blocks, no creases at texel boundaries), exact on quadratics away from the edges, and interpolating,
// so a texel that lands on a source texel's center takes its value. Every layer alike (B, then the tint); B
// is not negative where no coefficient is, and the cubic's overshoot beside a thin bright core is clipped at 0
// (the tint, of either sign, is not). Rust side: src/gpu/upsample.rs.
//
// Where the scene has objects (OBJECTS), a coarse texel's ray ends at the first surface it meets, and so does a
// fine one's: near an object's silhouette the coarse texels either side of it hold glow integrated up to the
// object and glow integrated past it. A fine texel reads only the coarse texels whose ray ends about where a
// ray from there would end on the fine texel's own surface: their clip within CLIP_MATCH of the fine texel's
// clip carried to them along its slope (a floor seen at a grazing angle changes its clip smoothly, by more
// than CLIP_MATCH a coarse texel; a silhouette jumps). Catmull-Rom where all sixteen do, else the bilinear
// weights of the four around it that do, else tent weights over the sixteen that do, else the one whose clip
// is nearest. The object's edge then cuts the preview's glow as sharply as the fine texels' clips, not in
// blocks of coarse texels.

@group(0) @binding(0) var low: texture_2d_array<f32>;
@group(0) @binding(1) var upsampled: texture_storage_2d_array<r32float, write>;
// Each texel's share of its ray before the first surface (objects::clip), rows from the top: the coarse
// texture's and the upsampled one's. Read where OBJECTS.
@group(0) @binding(2) var<storage, read> low_clips: array<f32>;
@group(0) @binding(3) var<storage, read> clips: array<f32>;

// Whether the scene has objects (gpu::upsample keeps a pipeline of each).
override OBJECTS: bool = false;

// Coarse texels whose clip differs from the fine texel's by more than this share of the ray are not read
// (the billboard's CLIP_MATCH).
const CLIP_MATCH: f32 = 0.05;

// The Catmull-Rom weights of the four texels around a point at fraction t past the second of them.
fn catmull_rom(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return 0.5 * vec4<f32>(-t3 + 2.0 * t2 - t, 3.0 * t3 - 5.0 * t2 + 2.0, -3.0 * t3 + 4.0 * t2 + t, t3 - t2);
}

// A fine texel's clip and its slope, carried to the coarse texels around it.
struct Guide {
    // The fine texel's clip.
    clip: f32,
    // Its slope per coarse texel, in x and y.
    slope: vec2<f32>,
    // The fine texel's center in coarse texels (the coarse texel k's center at k).
    at: vec2<f32>,
}

// The smaller of two differences of one sign, else 0: the slope on the smooth side of a jump.
fn minmod(a: f32, b: f32) -> f32 {
    return select(0.0, select(b, a, abs(a) < abs(b)), a * b > 0.0);
}

// The fine texel `p`'s clip, clamped to the texture.
fn fine_clip(p: vec2<i32>, size: vec2<i32>) -> f32 {
    let q = clamp(p, vec2<i32>(0), size - 1);
    return clips[q.y * size.x + q.x];
}

// How far coarse texel `k`'s clip lies from the guide's surface carried to it.
fn clip_gap(g: Guide, k: vec2<i32>, n: vec2<i32>) -> f32 {
    return abs(low_clips[k.y * n.x + k.x] - (g.clip + dot(g.slope, vec2<f32>(k) - g.at)));
}

// The coarse texels around a fine one at fraction `f` past texel `b`, read where their clip matches the fine
// texel's (`clip_gap`): bilinear over the four nearest, else tents of radius 2 over the sixteen, else the
// nearest clip. Positive weights only, so B stays non-negative. Layer `layer`.
fn near_clip(g: Guide, b: vec2<i32>, f: vec2<f32>, n: vec2<i32>, layer: u32) -> f32 {
    var sum = 0.0;
    var total = 0.0;
    for (var j = 0; j < 2; j++) {
        let y = clamp(b.y + j, 0, n.y - 1);
        let wy = select(1.0 - f.y, f.y, j == 1);
        for (var i = 0; i < 2; i++) {
            let k = vec2<i32>(clamp(b.x + i, 0, n.x - 1), y);
            let w = wy * select(1.0 - f.x, f.x, i == 1);
            if w > 0.0 && clip_gap(g, k, n) <= CLIP_MATCH {
                sum += w * textureLoad(low, k, layer, 0).x;
                total += w;
            }
        }
    }
    if total > 0.0 {
        return sum / total;
    }
    var nearest = clamp(b, vec2<i32>(0), n - 1);
    var gap = 1e30;
    for (var j = 0; j < 4; j++) {
        let y = clamp(b.y - 1 + j, 0, n.y - 1);
        let wy = max(2.0 - abs(f32(j - 1) - f.y), 0.0);
        for (var i = 0; i < 4; i++) {
            let k = vec2<i32>(clamp(b.x - 1 + i, 0, n.x - 1), y);
            let w = wy * max(2.0 - abs(f32(i - 1) - f.x), 0.0);
            let d = clip_gap(g, k, n);
            if d < gap {
                gap = d;
                nearest = k;
            }
            if w > 0.0 && d <= CLIP_MATCH {
                sum += w * textureLoad(low, k, layer, 0).x;
                total += w;
            }
        }
    }
    if total > 0.0 {
        return sum / total;
    }
    return textureLoad(low, nearest, layer, 0).x;
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
    if OBJECTS {
        let p = vec2<i32>(id.xy);
        let fine = vec2<i32>(size.xy);
        let clip = fine_clip(p, fine);
        let slope = vec2<f32>(
            minmod(fine_clip(p + vec2<i32>(1, 0), fine) - clip, clip - fine_clip(p - vec2<i32>(1, 0), fine)),
            minmod(fine_clip(p + vec2<i32>(0, 1), fine) - clip, clip - fine_clip(p - vec2<i32>(0, 1), fine)),
        ) * vec2<f32>(size.xy) / vec2<f32>(n);
        let g = Guide(clip, slope, x);
        var all_near = true;
        for (var j = 0; j < 4; j++) {
            let y = clamp(b.y - 1 + j, 0, n.y - 1);
            for (var i = 0; i < 4; i++) {
                let k = vec2<i32>(clamp(b.x - 1 + i, 0, n.x - 1), y);
                all_near = all_near && clip_gap(g, k, n) <= CLIP_MATCH;
            }
        }
        if !all_near {
            textureStore(upsampled, p, layer, vec4<f32>(near_clip(g, b, f, n, layer), 0.0, 0.0, 1.0));
            return;
        }
    }
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
