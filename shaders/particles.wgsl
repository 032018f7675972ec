// Particle sets by image-aligned sheet-buffer splatting (METHOD.md section 10, after paper 002_): the smoke's own
// image, a ray through each pixel's center, slabs perpendicular to the view. Each tile of TILE x TILE pixels (a
// workgroup) has its segments (a particle cut by a slab) in slab order; a pixel adds the optical depth of its slab's
// segments (commutative: no order among them, so no popping) and their color times the light each particle
// scatters back along the ray plus the light it gives off by itself, then composites the slab over what lies behind it, front to back. The glow is taken
// to lie where its weight along the ray does (particles::view::GlowPlace): the slabs whose middle lies in front of
// it make the front image, laid over the glow; the others the back image, under it. A
// dispatch takes at most `params.chunk` segments a pixel (lavapipe stops a loop past 65535 iterations): the
// pixel's state carries over to the next dispatch in `state`. Then `fs_back` lays the back image over the
// frame's background and objects and `fs_front` the front one over the glow, premultiplied. Rust side:
// src/gpu/particle_pass.rs (gpu_data; keep in sync). CPU twin: src/reference/particles.rs (smoke_pixel).

struct SmokeParams {
    eye: vec3<f32>,
    tan_half: f32,      // tan of half the vertical field of view
    forward: vec3<f32>,
    aspect: f32,        // the frame's width / height
    right: vec3<f32>,
    near: f32,          // the first slab's front, a depth along `forward`
    up: vec3<f32>,
    width: f32,         // a slab's width along `forward`
    size: vec2<u32>,    // the smoke image's
    tiles_x: u32,
    chunk: u32,         // the most segments a pixel takes in one dispatch
    frame: vec2<u32>,   // the frame's size (its objects' depth's)
    objects: u32,       // 1: the objects' depth ends the rays
    pad0: u32,
    depth_near: f32,    // the frame's projection's depth range (gpu::billboard_pass::depth_range)
    depth_far: f32,
    pad1: f32,
    pad2: f32,
}

// A particle as the GPU reads it (128 bytes: a million fit one storage binding): its light as
// `AMBIENT + iso + v^T M v` per channel toward the unit v (particles::light::ParticleLight, the ambient share in
// `iso`), each channel's M diagonal in xyz with its `iso` in w, and its off-diagonal (xy, xz, yz) with the
// channel's emission (the radiance it gives off by itself per unit of optical depth, particles::Particle) in w.
struct SmokeParticle {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,   // its material's color times its set's albedo
    density: f32,
    diag_r: vec4<f32>,
    off_r: vec4<f32>,
    diag_g: vec4<f32>,
    off_g: vec4<f32>,
    diag_b: vec4<f32>,
    off_b: vec4<f32>,
}

// Which dispatch of the frame this is.
struct SmokeChunk {
    index: u32,
    last: u32,          // 1 on the last: the pixels' final slab is composited and the state left as the image
    pad0: u32,
    pad1: u32,
}

const TILE: u32 = 4u;
// particles::view::GLOW_CELL.
const GLOW_CELL: u32 = 16u;
// particles::KERNEL_PEAK and KERNEL_FALLOFF.
const KERNEL_PEAK: f32 = 0.446;
const KERNEL_FALLOFF: f32 = 2.0;

@group(0) @binding(0) var<uniform> params: SmokeParams;
@group(0) @binding(1) var<storage, read> particles: array<SmokeParticle>;
// Each particle's ball (center, radius), read alone first: most segments of a tile miss a given pixel.
@group(0) @binding(9) var<storage, read> balls: array<vec4<f32>>;
// (slab, particle) a segment, each tile's in slab order.
@group(0) @binding(2) var<storage, read> segments: array<vec2<u32>>;
// Each tile's first segment; one more than tiles.
@group(0) @binding(3) var<storage, read> starts: array<u32>;
// The glow's depth along the view axis at the glow cells' corners (one more than cells a row): the slabs in front of
// it go over the glow (particles::view::SmokeView::split_at).
@group(0) @binding(8) var<storage, read> glow: array<f32>;
// Four a pixel: the front image (radiance, transmittance) once the billboard's plane is passed, the image so far,
// the open slab's (sum of tau color light, sum of tau), and the open slab's index and whether the plane is
// passed in x and y (as bits). After the last dispatch the first two are the front and the back image.
@group(0) @binding(4) var<storage, read_write> state: array<vec4<f32>>;
// The objects' depth in the frame's projection (the bits gpu::formats::DEPTH_VALUE_FORMAT holds).
@group(0) @binding(5) var depth: texture_2d<u32>;
@group(0) @binding(6) var<uniform> chunk: SmokeChunk;
// The image, read by fs_main (the same buffer as `state`).
@group(0) @binding(7) var<storage, read> image: array<vec4<f32>>;

// erf by Abramowitz and Stegun 7.1.26 (error below 1.5e-7).
fn erf_approx(x: f32) -> f32 {
    let a = abs(x);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t;
    return sign(x) * (1.0 - poly * exp(-a * a));
}

// The distance along the view axis of a depth in [0, 1] of the frame's projection.
fn view_depth(d: f32) -> f32 {
    return params.depth_near * params.depth_far / (params.depth_far - d * (params.depth_far - params.depth_near));
}

// The light particle p scatters toward the unit v.
fn light_toward(p: SmokeParticle, v: vec3<f32>) -> vec3<f32> {
    let sq = v * v;
    let cross_terms = vec3<f32>(v.x * v.y, v.x * v.z, v.y * v.z);
    let q = vec3<f32>(
        dot(p.diag_r.xyz, sq) + 2.0 * dot(p.off_r.xyz, cross_terms),
        dot(p.diag_g.xyz, sq) + 2.0 * dot(p.off_g.xyz, cross_terms),
        dot(p.diag_b.xyz, sq) + 2.0 * dot(p.off_b.xyz, cross_terms),
    );
    return max(vec3<f32>(p.diag_r.w, p.diag_g.w, p.diag_b.w) + q, vec3<f32>(0.0));
}

// The open slab composited behind what `acc` holds: its light over its opacity 1 - exp(-tau).
fn close_slab(acc: vec4<f32>, open: vec4<f32>) -> vec4<f32> {
    if open.w <= 0.0 {
        return acc;
    }
    let through = exp(-open.w);
    return vec4<f32>(acc.xyz + acc.w * open.xyz / open.w * (1.0 - through), acc.w * through);
}

// The open slab composited into the image so far; the first slab whose middle lies past the glow (`behind`)
// begins the back image, what came before it kept as the front image.
fn close_into(front: ptr<function, vec4<f32>>, acc: ptr<function, vec4<f32>>, passed: ptr<function, u32>, open: vec4<f32>, behind: bool) {
    if *passed == 0u && behind {
        *front = *acc;
        *acc = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        *passed = 1u;
    }
    *acc = close_slab(*acc, open);
}

@compute @workgroup_size(4, 4)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.size.x || gid.y >= params.size.y {
        return;
    }
    let pixel = gid.y * params.size.x + gid.x;
    let tile = (gid.y / TILE) * params.tiles_x + gid.x / TILE;
    let end = starts[tile + 1u];
    let first = min(starts[tile] + chunk.index * params.chunk, end);
    let last = min(end, first + params.chunk);
    let ndc = vec2<f32>(
        2.0 * (f32(gid.x) + 0.5) / f32(params.size.x) - 1.0,
        1.0 - 2.0 * (f32(gid.y) + 0.5) / f32(params.size.y),
    );
    let dir = normalize(params.forward + params.right * (ndc.x * params.tan_half * params.aspect) + params.up * (ndc.y * params.tan_half));
    let along = dot(dir, params.forward);
    // The first object on the ray ends it: the slabs whose front lies at or past its depth are left out.
    var until = 3.0e38;
    if params.objects != 0u {
        let at = vec2<u32>((vec2<f32>(gid.xy) + 0.5) * vec2<f32>(params.frame) / vec2<f32>(params.size));
        // A translucent surface (the depth's lowest bit set, shaders/objects.wgsl) does not end the smoke.
        let bits = textureLoad(depth, vec2<i32>(min(at, params.frame - 1u)), 0).r;
        let d = bitcast<f32>(bits);
        if d < 1.0 && (bits & 1u) == 0u {
            until = view_depth(d);
        }
    }
    // Where the glow lies along the ray, bilinear between the glow cells' corners.
    let g = (vec2<f32>(gid.xy) + 0.5) / f32(GLOW_CELL);
    let cells = (params.size + GLOW_CELL - 1u) / GLOW_CELL;
    let c = min(vec2<u32>(g), cells - 1u);
    let f = g - vec2<f32>(c);
    let row = cells.x + 1u;
    let at = c.y * row + c.x;
    let top = glow[at] + (glow[at + 1u] - glow[at]) * f.x;
    let bottom = glow[at + row] + (glow[at + row + 1u] - glow[at + row]) * f.x;
    let split = top + (bottom - top) * f.y;
    let none = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    var front = none;
    var acc = none;
    var open = vec4<f32>(0.0);
    var slab = 0xffffffffu;
    var passed = 0u;
    if chunk.index > 0u {
        front = state[4u * pixel];
        acc = state[4u * pixel + 1u];
        open = state[4u * pixel + 2u];
        let marks = state[4u * pixel + 3u];
        slab = bitcast<u32>(marks.x);
        passed = bitcast<u32>(marks.y);
    }
    let toward_eye = -dir;
    // What the loop reads, in registers (lavapipe loads a buffer again at every pass of a loop).
    let near = params.near;
    let width = params.width;
    let eye = params.eye;
    let per_depth = 1.0 / along;
    for (var i = first; i < last; i++) {
        let s = segments[i];
        if s.x != slab {
            if slab != 0xffffffffu {
                close_into(&front, &acc, &passed, open, near + (f32(slab) + 0.5) * width >= split);
            }
            open = vec4<f32>(0.0);
            slab = s.x;
        }
        let slab_front = near + f32(s.x) * width;
        if slab_front >= until {
            continue;
        }
        let ball = balls[s.y];
        let radius = ball.w;
        let to = ball.xyz - eye;
        let closest = dot(to, dir);
        let u = length(to - dir * closest) / radius;
        if u >= 1.0 {
            continue;
        }
        let half = sqrt(1.0 - u * u);
        let a = max((slab_front * per_depth - closest) / radius, -half);
        let b = min(((slab_front + width) * per_depth - closest) / radius, half);
        if b <= a {
            continue;
        }
        let p = particles[s.y];
        let k = sqrt(KERNEL_FALLOFF);
        // particles::segment_integral in scene units: rho R G(u) sqrt(pi / (4 falloff)) (erf(k b) - erf(k a)).
        let tau = p.density * radius * KERNEL_PEAK * exp(-KERNEL_FALLOFF * u * u)
            * sqrt(3.14159265 / (4.0 * KERNEL_FALLOFF)) * (erf_approx(k * b) - erf_approx(k * a));
        if tau > 0.0 {
            let emission = vec3<f32>(p.off_r.w, p.off_g.w, p.off_b.w);
            open += vec4<f32>(tau * (p.color * light_toward(p, toward_eye) + emission), tau);
        }
    }
    if chunk.last != 0u {
        if slab != 0xffffffffu {
            close_into(&front, &acc, &passed, open, near + (f32(slab) + 0.5) * width >= split);
        }
        if passed == 0u {
            front = acc;
            acc = none;
        }
        state[4u * pixel] = front;
        state[4u * pixel + 1u] = acc;
    } else {
        state[4u * pixel] = front;
        state[4u * pixel + 1u] = acc;
        state[4u * pixel + 2u] = open;
        state[4u * pixel + 3u] = vec4<f32>(bitcast<f32>(slab), bitcast<f32>(passed), 0.0, 0.0);
    }
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
}

// One triangle over the whole frame.
@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

fn image_at(at: vec2<i32>, which: u32) -> vec4<f32> {
    let c = clamp(at, vec2<i32>(0), vec2<i32>(params.size) - 1);
    return image[4u * (u32(c.y) * params.size.x + u32(c.x)) + which];
}

// An image (0: front, 1: back) at a frame pixel, bilinear between the smoke image's pixel centers: its light and
// its coverage 1 - T, premultiplied, for the blend over what lies behind.
fn smoke_at(position: vec2<f32>, which: u32) -> vec4<f32> {
    let x = position * vec2<f32>(params.size) / vec2<f32>(params.frame) - 0.5;
    let x0 = floor(x);
    let f = x - x0;
    let i0 = vec2<i32>(x0);
    let s = mix(
        mix(image_at(i0, which), image_at(i0 + vec2<i32>(1, 0), which), f.x),
        mix(image_at(i0 + vec2<i32>(0, 1), which), image_at(i0 + vec2<i32>(1, 1), which), f.x),
        f.y,
    );
    return vec4<f32>(s.xyz, 1.0 - s.w);
}

@fragment
fn fs_front(in: VertexOut) -> @location(0) vec4<f32> {
    return smoke_at(in.position.xy, 0u);
}

@fragment
fn fs_back(in: VertexOut) -> @location(0) vec4<f32> {
    return smoke_at(in.position.xy, 1u);
}
