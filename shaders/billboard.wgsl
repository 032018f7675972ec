// The billboard pass: draws the camera-facing billboard as a quad in 3D and blends its brightness B and colored
// sum G = sum B_i Ce_i (B Ce with one color) over what lies behind it, color = clamp((1 - B) Cb + G) (METHOD.md
// section 4). Cb is read from a copy of the
// background at the fragment's pixel, so the blend is exact for any B (fixed-function blending cannot apply
// the negative weight 1 - B that blows the glow out when B > 1). Rust side: src/gpu/billboard_pass.rs
// (gpu_data holds the mirror of BillboardParams; keep in sync). CPU twin: src/reference/billboard.rs.

struct BillboardParams {
    view_proj: mat4x4<f32>,
    center: vec3<f32>,
    size: f32,
    right: vec3<f32>,
    resolution: u32,   // W of the field texture
    up: vec3<f32>,
    mode: u32,         // 0: clamp((1 - B) Cb + G); 1: premultiplied G and alpha min(B, 1), unclamped;
                       // 2: clamp(G + (1 - min(B, 1)) Cb) (gpu::billboard_pass::BlendMode); plus 4
                       // (UNCLAMPED): 0 and 2 clamped below 0 only, for an HDR export; plus 8
                       // (THRESHOLD_PREVIEW): 0 and 2 with the glow at or below energy.w dimmed
    energy: vec4<f32>, // Ce in rgb, its intensity applied; w: the previewed glare threshold
    near: f32,         // the projection's depth range (gpu::billboard_pass::depth_range)
    far: f32,
    nu: f32,           // E = V + nu (S - V)
    cutoff: f32,       // the glow's edge: B at or below it transparent, faded in up to twice it; 0 for none
    edge: f32,         // the band along each edge the glow fades over, a share of the side (geometry::edge_window)
}

// The glow's window at uv (twin of geometry::edge_window): 1 inside, smoothly to 0 at the edges across the band.
fn edge_window(uv: vec2<f32>) -> f32 {
    let e = params.edge;
    let ramp = smoothstep(vec2<f32>(0.0), vec2<f32>(e), min(uv, vec2<f32>(1.0) - uv));
    return select(1.0, ramp.x * ramp.y, e > 0.0);
}

// Whether the field texture holds the tint (layers 1 to 3) beside B: false where every source has the scene's
// color. A constant, so that the tint's loads are compiled out where there is none (gpu::billboard_pass keeps
// a pipeline of each).
override TINTED: bool = true;
// Whether the scene has objects (gpu::billboard_pass keeps a pipeline of each): then a pixel whose object lies
// in front of the billboard shows no glow, and the glow elsewhere is interpolated from the texels whose rays
// end about where the pixel's does (sample_near_clip), so that an object's edge is as sharp as its pixels.
override OBJECTS: bool = false;
// The field's last layer holds B without the translucent objects' dimming (shaders/through.wgsl): the glow's edge
// fades by it, not by the glow dimmed by them (which would cut the glow off wherever an object dims it below the
// cutoff, in wedges along the object's chords).
override THROUGH: bool = false;

@group(0) @binding(0) var<uniform> params: BillboardParams;
// The field pass's texture: layer 0 B, layers 1 to 3 the tint sum B_i (Ce_i - Ce), G = B Ce + tint.
@group(0) @binding(1) var field: texture_2d_array<f32>;
@group(0) @binding(2) var background: texture_2d<f32>;
// The objects' depth in the frame's projection (cleared to 1 where none is drawn), read where OBJECTS: the bits
// of the depth the objects pass writes beside its color (gpu::formats::DEPTH_VALUE_FORMAT: GL reads no depth
// texture).
@group(0) @binding(3) var depth: texture_2d<u32>;
// Each texel's share c of its ray S -> E before the first surface (objects::clip), rows from the top, read where
// OBJECTS.
@group(0) @binding(4) var<storage, read> clips: array<f32>;

// Texels whose clip differs from the pixel's by more than this share of the ray do not shade it.
const CLIP_MATCH: f32 = 0.05;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

// A triangle strip of four corners: uv (0,0) top-left, (1,0), (0,1), (1,1).
@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    let uv = vec2<f32>(f32(index & 1u), f32(index >> 1u));
    let world = params.center + params.right * (params.size * (uv.x - 0.5)) + params.up * (params.size * (0.5 - uv.y));
    var out: VertexOut;
    out.position = params.view_proj * vec4<f32>(world, 1.0);
    out.uv = uv;
    return out;
}

// Bilinear filtering by hand (r32float is not filterable everywhere), texel centers at (i + 0.5) / W,
// clamped at the edges, of every layer: (B, tint), the tint only where the scene has one. Twin of
// reference::billboard::sample_bilinear.
struct Bilinear {
    i0: vec2<i32>,
    i1: vec2<i32>,
    f: vec2<f32>,
}

fn bilinear_at(uv: vec2<f32>) -> Bilinear {
    let w = i32(params.resolution);
    let x = uv * f32(w) - 0.5;
    let x0 = floor(x);
    let i0 = clamp(vec2<i32>(x0), vec2<i32>(0), vec2<i32>(w - 1));
    let i1 = clamp(vec2<i32>(x0) + 1, vec2<i32>(0), vec2<i32>(w - 1));
    return Bilinear(i0, i1, x - x0);
}

fn sample_layer(s: Bilinear, layer: i32) -> f32 {
    let b00 = textureLoad(field, vec2<i32>(s.i0.x, s.i0.y), layer, 0).r;
    let b10 = textureLoad(field, vec2<i32>(s.i1.x, s.i0.y), layer, 0).r;
    let b01 = textureLoad(field, vec2<i32>(s.i0.x, s.i1.y), layer, 0).r;
    let b11 = textureLoad(field, vec2<i32>(s.i1.x, s.i1.y), layer, 0).r;
    return mix(mix(b00, b10, s.f.x), mix(b01, b11, s.f.x), s.f.y);
}

fn sample_field(uv: vec2<f32>) -> vec4<f32> {
    let s = bilinear_at(uv);
    var out = vec4<f32>(sample_layer(s, 0), 0.0, 0.0, 0.0);
    if TINTED {
        out = vec4<f32>(out.x, sample_layer(s, 1), sample_layer(s, 2), sample_layer(s, 3));
    }
    return out;
}

// The distance along the view axis of a depth in [0, 1] of the frame's projection.
fn view_depth(d: f32) -> f32 {
    return params.near * params.far / (params.far - d * (params.far - params.near));
}

// sample_field over the texels whose ray ends about where the pixel's does (their clip within CLIP_MATCH of
// `clip`, the pixel's own), their weights renormalised; where none does, the texel whose clip is nearest. An
// object's edge then cuts the glow as sharply as its pixels rather than in a staircase of texels: the glow on
// either side is read from the texels on that side. Twin of reference::billboard::sample_near_clip. Written out
// corner by corner (no array indexed in a loop, which lavapipe keeps in memory).
fn sample_near_clip(uv: vec2<f32>, clip: f32) -> NearClip {
    let s = bilinear_at(uv);
    let w = i32(params.resolution);
    let c00 = vec2<i32>(s.i0.x, s.i0.y);
    let c10 = vec2<i32>(s.i1.x, s.i0.y);
    let c01 = vec2<i32>(s.i0.x, s.i1.y);
    let c11 = vec2<i32>(s.i1.x, s.i1.y);
    let gap = abs(vec4<f32>(
        clips[c00.y * w + c00.x],
        clips[c10.y * w + c10.x],
        clips[c01.y * w + c01.x],
        clips[c11.y * w + c11.x],
    ) - vec4<f32>(clip));
    let near = gap <= vec4<f32>(CLIP_MATCH);
    let bilinear = vec4<f32>((1.0 - s.f.x) * (1.0 - s.f.y), s.f.x * (1.0 - s.f.y), (1.0 - s.f.x) * s.f.y, s.f.x * s.f.y);
    // Away from every edge, all four match: the plain bilinear weights.
    var weights = bilinear;
    if !all(near) {
        let kept = select(vec4<f32>(0.0), bilinear, near);
        let total = kept.x + kept.y + kept.z + kept.w;
        if total > 0.0 {
            weights = kept / total;
        } else {
            // None matches: the texel whose clip is nearest.
            var best = gap.x;
            weights = vec4<f32>(1.0, 0.0, 0.0, 0.0);
            if gap.y < best {
                best = gap.y;
                weights = vec4<f32>(0.0, 1.0, 0.0, 0.0);
            }
            if gap.z < best {
                best = gap.z;
                weights = vec4<f32>(0.0, 0.0, 1.0, 0.0);
            }
            if gap.w < best {
                weights = vec4<f32>(0.0, 0.0, 0.0, 1.0);
            }
        }
    }
    var out = NearClip(
        weights.x * texel_at(c00) + weights.y * texel_at(c10) + weights.z * texel_at(c01) + weights.w * texel_at(c11),
        0.0,
    );
    if THROUGH {
        out.undimmed = weights.x * undimmed_at(c00) + weights.y * undimmed_at(c10) + weights.z * undimmed_at(c01)
            + weights.w * undimmed_at(c11);
    }
    return out;
}

// A pixel's field (B, tint) and, where the scene has translucent objects, its B undimmed by them.
struct NearClip {
    field: vec4<f32>,
    undimmed: f32,
}

// The layer past B and the tint (THROUGH).
fn undimmed_at(at: vec2<i32>) -> f32 {
    return textureLoad(field, at, select(1, 4, TINTED), 0).r;
}

fn texel_at(at: vec2<i32>) -> vec4<f32> {
    var texel = vec4<f32>(textureLoad(field, at, 0, 0).r, 0.0, 0.0, 0.0);
    if TINTED {
        texel = vec4<f32>(
            texel.x,
            textureLoad(field, at, 1, 0).r,
            textureLoad(field, at, 2, 0).r,
            textureLoad(field, at, 3, 0).r,
        );
    }
    return texel;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    var field: vec4<f32>;
    // What the glow's edge fades by: B, or B undimmed by the translucent objects.
    var edge_b = 0.0;
    if OBJECTS {
        // An opaque object in front of the billboard hides the glow at this pixel; a translucent one (the depth's
        // lowest bit set, shaders/objects.wgsl) lets through the glow the field blended for it.
        let bits = textureLoad(depth, vec2<i32>(in.position.xy), 0).r;
        let d = bitcast<f32>(bits & ~1u);
        if d < in.position.z && (bits & 1u) == 0u {
            field = vec4<f32>(0.0);
        } else {
            // The pixel's own clip: where along S -> E its ray meets the object behind the billboard (1: none).
            var clip = 1.0;
            if d < 1.0 {
                let tau = view_depth(d) / view_depth(in.position.z);
                clip = clamp((tau - 1.0) / (params.nu - 1.0), 0.0, 1.0);
            }
            let near = sample_near_clip(in.uv, clip);
            field = near.field;
            edge_b = select(field.x, near.undimmed, THROUGH);
        }
    } else {
        field = sample_field(in.uv);
        edge_b = field.x;
    }
    // The glow's edge (scene::edge_fade), by |B| (a negative glow has its edge too): B and the tint alike, so
    // the colored sum G fades with B. A select, not a branch: the cutoff is a value per edit.
    let c = params.cutoff;
    let fade = select(1.0, smoothstep(c, 2.0 * c, abs(edge_b)), c > 0.0);
    // And where the billboard's edge lies inside the frame, the glow fades out before it, not cut off square.
    field = field * (fade * edge_window(in.uv));
    let b = field.x;
    let glow = b * params.energy.rgb + field.yzw;
    let cb = textureLoad(background, vec2<i32>(in.position.xy), 0);
    let mode = params.mode & 3u;
    // The opaque blends' upper bound: 1 for the display, none for an HDR export.
    let top = select(1.0, 3.0e38, (params.mode & 4u) != 0u);
    if mode == 1u {
        // Associated (premultiplied) alpha, unclamped: "over" any background Cb gives (1 - B) Cb + G wherever
        // B <= 1, and over black G everywhere (clamped on display, as the opaque blend). B < 0 is transparent.
        // Over what lies behind (transparent, or the objects, opaque), premultiplied "over" again.
        let a = clamp(b, 0.0, 1.0);
        return vec4<f32>(max(glow, vec3<f32>(0.0)) + (1.0 - a) * cb.rgb, a + (1.0 - a) * cb.a);
    }
    var color: vec3<f32>;
    if mode == 2u {
        // The transparent export composited over the background, for every B.
        color = max(glow, vec3<f32>(0.0)) + (1.0 - clamp(b, 0.0, 1.0)) * cb.rgb;
    } else {
        color = (1.0 - b) * cb.rgb + glow;
    }
    color = clamp(color, vec3<f32>(0.0), vec3<f32>(top));
    // The threshold preview: the glow that does not glare dimmed to a quarter.
    let dim = (params.mode & 8u) != 0u && b <= params.energy.w;
    return vec4<f32>(select(color, 0.25 * color, dim), cb.a);
}
