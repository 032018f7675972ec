// Particle sets by image-aligned sheet-buffer splatting (docs/METHOD.md section 9, after paper 002_): the smoke's own
// image, a ray through each pixel's center, slabs perpendicular to the view. A pixel adds, in each slab, the
// optical depth of the particles' parts that lie in it (commutative: no order among them, so no popping) and their
// color times the light each particle scatters back along the ray plus the light it gives off by itself, then
// composites the slabs front to back. The loop is particle-major: each tile of TILE x TILE pixels (a workgroup)
// has its particles in the order of the first slab their ball reaches, and a pixel passes over each once, adding
// its exact footprint (an erf a slab boundary) to the few slabs its chord crosses, kept open in a ring of RING;
// a slab is closed (composited) once the next particle starts past it. A pixel stops adding once the light that
// still comes through it is below CUTOFF. The glow is spread through the slabs as its weight along the ray lies
// (particles::view::GlowPlace, 13 depths a ray): a slab's light is covered by the share of the glow in front of
// it, and the glow within and behind a slab is dimmed by it (reference::particles::SmokeLayers); the pixel is
// written as two images, the front one laid over the glow and the back one under it, which compose to
// `S - B occluded + B seen Ce + (1 - B) T X`. Only the tiles with particles are dispatched, the busiest first; a
// dispatch takes at most `params.chunk` particles a tile (lavapipe stops a loop past 65535 iterations in all),
// the tiles with more carry their pixels' state to the next in `state`. The loops over a tile's particles and
// over the slabs they close run as often for every pixel of the tile; the slab loop runs over the pixel's own
// chord, none where it misses (a count that differs between lanes, which llvmpipe's GL has read wrong after
// elsewhere: the GPU-against-twin tests run on GL). The last
// dispatch writes the front and back images as textures, which `fs_back` lays over the frame's background and
// objects and `fs_front` over the glow, filtered, premultiplied. Rust side: src/gpu/particle_pass.rs (gpu_data;
// keep in sync). CPU twin: src/reference/particles.rs (smoke_pixel).

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
    chunk: u32,         // the most particles a tile takes in one dispatch
    frame: vec2<u32>,   // the frame's size (its objects' depth's)
    objects: u32,       // 1: the objects' depth ends the rays
    pad0: u32,
    depth_near: f32,    // the frame's projection's depth range (gpu::billboard_pass::depth_range)
    depth_far: f32,
    pad1: f32,
    pad2: f32,
    bb_center: vec3<f32>, // the billboard: its center, side, axes and normal (geometry::Billboard)
    bb_size: f32,
    bb_right: vec3<f32>,
    glass_w: u32,       // the texels a side of `glass`, 0 for none
    bb_up: vec3<f32>,
    glass_offset: u32,  // where `glow` holds the texels' crossings
    bb_normal: vec3<f32>,
    pad4: f32,
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

// Where the glow lies along a pixel's ray: 13 depths along the view axis (particles::view::GlowDepths), the last
// repeated to fill four vec4s; the share of the glow in front of a depth is piecewise linear through them.
struct GlowDepths {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<f32>,
}

// Which dispatch of the frame this is.
struct SmokeChunk {
    index: u32,
    last: u32,          // 1 on the last
    pad0: u32,
    pad1: u32,
}

const TILE: u32 = 4u;
// particles::view::GLOW_CELL.
const GLOW_CELL: u32 = 16u;
// particles::view::RING: the most slabs open at once along a ray (the plan keeps a particle's slabs under it).
const RING: u32 = 32u;
// particles::TRANSMITTANCE_CUTOFF.
const CUTOFF: f32 = 1e-4;
// particles::KERNEL_PEAK and KERNEL_FALLOFF.
const KERNEL_PEAK: f32 = 0.446;
const KERNEL_FALLOFF: f32 = 2.0;
// A pixel's state between dispatches, in vec4s: the smoke so far, what the glow covers of it and what it loses of
// the glow, the marks, the ring, the light through the smoke behind a translucent surface.
const STATE: u32 = 36u;
// particles::view::GLOW_LEVELS, as the shares of the glow between each two of a ray's depths.
const GLOW_SHARE_A: vec4<f32> = vec4<f32>(1.0 / 64.0, 3.0 / 64.0, 1.0 / 16.0, 0.125);
const GLOW_SHARE_B: vec4<f32> = vec4<f32>(0.125, 0.125, 0.125, 0.125);
const GLOW_SHARE_C: vec4<f32> = vec4<f32>(0.125, 1.0 / 16.0, 3.0 / 64.0, 1.0 / 64.0);
// reference::particles::SEEN_FLOOR.
const SEEN_FLOOR: f32 = 1e-4;

// In a storage buffer: lavapipe compiles a shader anew for every value of a uniform that bounds a loop (the slabs
// a pixel's chord crosses follow the view's slices).
@group(0) @binding(0) var<storage, read> params: SmokeParams;
@group(0) @binding(1) var<storage, read> particles: array<SmokeParticle>;
// Each particle's ball (center, radius), read alone first: a pixel misses most of its tile's particles.
@group(0) @binding(9) var<storage, read> balls: array<vec4<f32>>;
// A tile's particles (the first slab its ball reaches | the slabs past it it may reach << 24, particle), by their
// first slab.
@group(0) @binding(2) var<storage, read> entries: array<vec2<u32>>;
// The tiles with particles, the busiest first (the workgroups of a dispatch): (tile, first entry, end entry).
@group(0) @binding(3) var<storage, read> work: array<vec4<u32>>;
// Where the glow lies along the rays of the glow cells' corners (one more than cells a row), four vec4s a corner
// (particles::view::SmokeView::glow_at); then, from `params.glass_offset`, how each field texel's ray crosses the
// translucent objects, a vec4 a texel, rows from the top: its exit clip and the shares of the glow inside and
// behind them that reach the eye (objects::clip::crossings). One buffer: GL gives a compute stage as few as 8.
@group(0) @binding(8) var<storage, read> glow: array<vec4<f32>>;
// STATE a pixel of the tiles that take more than one dispatch, by their place in `work`.
@group(0) @binding(4) var<storage, read_write> state: array<vec4<f32>>;
// The objects' depth in the frame's projection (the bits gpu::formats::DEPTH_VALUE_FORMAT holds).
@group(0) @binding(5) var depth: texture_2d<u32>;
@group(0) @binding(6) var<uniform> chunk: SmokeChunk;
// The images, two a pixel (front, back: radiance and transmittance), rows from the top, in f32 (read back).
@group(0) @binding(10) var<storage, read_write> image: array<vec4<f32>>;
// The images as the draw passes read them, light and coverage (cleared to none where no tile is dispatched).
@group(0) @binding(11) var front_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(12) var back_out: texture_storage_2d<rgba16float, write>;

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

// reference::particles::held_within: the share of a light spread evenly through a slab of optical depth tau (and
// opacity 1 - exp(-tau)) that the slab holds back.
fn held_within(tau: f32, opacity: f32) -> f32 {
    if tau < 1e-2 {
        return tau * (0.5 - tau * (1.0 / 6.0 - tau / 24.0));
    }
    return 1.0 - opacity / tau;
}

// A pixel's smoke so far (reference::particles::SmokeLayers): its light and transmittance, the light the glow
// covers and the share of the glow lost, whether the pixel is done (its light spent or its ray ended), and the
// share of the glow in front of slab `next`'s front, kept from the slab before it.
struct Composite {
    acc: vec4<f32>,
    occ: vec4<f32>,
    done: bool,
    next: u32,
    next_share: f32,
    // The light through the slabs past a translucent surface, among themselves.
    glassed: f32,
}

// Where the glow lies along the pixel's ray, up to its end (`until`), as `share_before` reads it: each stretch
// between two of its depths as its start and the reciprocal of its length (worked out once a pixel: the share is
// read at every slab that holds smoke), and the reciprocal of the share in front of `until`.
struct GlowRay {
    start_a: vec4<f32>,
    start_b: vec4<f32>,
    start_c: vec4<f32>,
    per_a: vec4<f32>,
    per_b: vec4<f32>,
    per_c: vec4<f32>,
    last: f32,
    until: f32,
    per_whole: f32,
    // The depth of a translucent surface the ray meets first (3e38 for none), and the light that comes through the
    // translucent objects to what lies behind them.
    glass: f32,
    behind: f32,
}

fn glow_ray_of(g: GlowDepths, until: f32, glass: f32, behind: f32) -> GlowRay {
    let tiny = vec4<f32>(1e-30);
    var r: GlowRay;
    r.start_a = g.a;
    r.start_b = g.b;
    r.start_c = g.c;
    r.per_a = 1.0 / max(vec4<f32>(g.a.yzw, g.b.x) - g.a, tiny);
    r.per_b = 1.0 / max(vec4<f32>(g.b.yzw, g.c.x) - g.b, tiny);
    r.per_c = 1.0 / max(vec4<f32>(g.c.yzw, g.d.x) - g.c, tiny);
    r.last = g.d.x;
    r.until = until;
    r.glass = glass;
    r.behind = behind;
    // The field pass integrates the glow up to the surface: the shares are of that part (all of it in front
    // where none lies before the surface).
    var whole = 1.0;
    if until < 3.0e38 {
        whole = glow_share(r, until);
    }
    r.per_whole = select(0.0, 1.0 / whole, whole > 0.0);
    return r;
}

// The share of all the glow on the ray in front of depth `at` (particles::view::glow_before): piecewise linear
// through its depths.
fn glow_share(g: GlowRay, at: f32) -> f32 {
    let a = clamp((at - g.start_a) * g.per_a, vec4<f32>(0.0), vec4<f32>(1.0));
    let b = clamp((at - g.start_b) * g.per_b, vec4<f32>(0.0), vec4<f32>(1.0));
    let c = clamp((at - g.start_c) * g.per_c, vec4<f32>(0.0), vec4<f32>(1.0));
    return dot(GLOW_SHARE_A, a) + dot(GLOW_SHARE_B, b) + dot(GLOW_SHARE_C, c);
}

// The share of the glow on the pixel's ray in front of depth `d`, of the glow up to its end.
fn share_before(g: GlowRay, d: f32) -> f32 {
    let at = min(d, g.until);
    // None of it in front of the first depth; all of it past the last (and where none lies before the end).
    if at <= g.start_a.x {
        return select(0.0, 1.0, g.per_whole == 0.0);
    }
    if at >= g.last || g.per_whole == 0.0 {
        return 1.0;
    }
    return min(glow_share(g, at) * g.per_whole, 1.0);
}

// Slab j's sums (sum of tau color light, sum of tau) composited behind what `c` holds: its light over its opacity
// 1 - exp(-tau), covered by the share of the glow in front of it; the glow behind it dimmed by its opacity, the
// glow within it by what it holds back. Once the light through the pixel is below CUTOFF it is done.
fn close_slab(c: ptr<function, Composite>, open: vec4<f32>, j: u32, glow_ray: GlowRay) {
    if open.w <= 0.0 || (*c).done {
        return;
    }
    let front = params.near + f32(j) * params.width;
    // Past a translucent surface (reference::particles::smoke_layers): the slab is seen through the objects, its
    // light dimmed by the light they let through and by the slabs in front, covered by the glow as the surface
    // is; it dims neither the surface nor the glow (the objects are drawn opaque, the glow through them is the
    // see-through pass's).
    if front >= glow_ray.glass {
        let through = exp(-open.w);
        let light = (*c).acc.w * (*c).glassed * glow_ray.behind * open.xyz / open.w * (1.0 - through);
        (*c).acc = vec4<f32>((*c).acc.xyz + light, (*c).acc.w);
        (*c).occ = vec4<f32>((*c).occ.xyz + light, (*c).occ.w);
        (*c).glassed *= through;
        (*c).done = (*c).glassed < CUTOFF;
        return;
    }
    var f0 = (*c).next_share;
    if (*c).next != j {
        f0 = share_before(glow_ray, front);
    }
    let f1 = share_before(glow_ray, front + params.width);
    (*c).next = j + 1u;
    (*c).next_share = f1;
    let through = exp(-open.w);
    let opacity = 1.0 - through;
    let acc = (*c).acc;
    let light = acc.w * open.xyz / open.w * opacity;
    let lost = acc.w * ((1.0 - f1) * opacity + (f1 - f0) * held_within(open.w, opacity));
    (*c).acc = vec4<f32>(acc.xyz + light, acc.w * through);
    (*c).occ += vec4<f32>(light * (0.5 * (f0 + f1)), lost);
    (*c).done = (*c).acc.w < CUTOFF;
}

// A tile's TILE x TILE pixels as one row of invocations: lavapipe runs a workgroup in SIMD chunks of 8 lanes along
// x, row by row, so a 4 x 4 workgroup ran as four chunks half empty, every pass of the loops paid twice (the
// particles bench's 500 particles: 54 ms a frame as 4 x 4, 37.5 as one row of 16).
@compute @workgroup_size(TILE * TILE)
fn splat(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    let local = vec2<u32>(index % TILE, index / TILE);
    let job = work[group.x];
    let tile = job.x;
    let xy = vec2<u32>((tile % params.tiles_x) * TILE + local.x, (tile / params.tiles_x) * TILE + local.y);
    if xy.x >= params.size.x || xy.y >= params.size.y {
        return;
    }
    let first = min(job.y + chunk.index * params.chunk, job.z);
    let last = min(job.z, first + params.chunk);
    let ndc = vec2<f32>(
        2.0 * (f32(xy.x) + 0.5) / f32(params.size.x) - 1.0,
        1.0 - 2.0 * (f32(xy.y) + 0.5) / f32(params.size.y),
    );
    let dir = normalize(params.forward + params.right * (ndc.x * params.tan_half * params.aspect) + params.up * (ndc.y * params.tan_half));
    let along = dot(dir, params.forward);
    // The first opaque object on the ray ends it: the slabs whose front lies at or past its depth are left out, the
    // one it lies in cut there.
    var until = 3.0e38;
    var glass_at = 3.0e38;
    var behind = 1.0;
    if params.objects != 0u {
        // The frame pixel the smoke pixel's center falls in, floor((xy + 1/2) frame / size) exactly (in f32 a
        // center that falls on a pixel's edge could round to the pixel before, where the twin takes the next).
        let at = min((2u * xy + 1u) * params.frame / (2u * params.size), params.frame - 1u);
        // A translucent surface (the depth's lowest bit set, shaders/objects.wgsl) does not end the smoke: the
        // smoke past it is seen through the objects, dimmed by the light the field texel's ray keeps through them
        // (the texel the ray through the depth's pixel meets, nearest).
        let both = textureLoad(depth, vec2<i32>(at), 0);
        let bits = both.r;
        let d = bitcast<f32>(bits);
        // The nearest opaque surface, behind the translucent one where the first is that.
        let opaque = bitcast<f32>(both.g);
        if opaque < 1.0 {
            until = view_depth(opaque);
        }
        if d < 1.0 && (bits & 1u) != 0u && params.glass_w > 0u {
            glass_at = view_depth(d);
            let p = 2.0 * (vec2<f32>(at) + 0.5) / vec2<f32>(params.frame) - 1.0;
            let ray = params.forward + params.right * (p.x * params.tan_half * params.aspect) - params.up * (p.y * params.tan_half);
            let t = dot(params.bb_center - params.eye, params.bb_normal) / dot(ray, params.bb_normal);
            let h = params.eye + ray * t - params.bb_center;
            let uv = vec2<f32>(dot(h, params.bb_right) / params.bb_size + 0.5, 0.5 - dot(h, params.bb_up) / params.bb_size);
            if t > 0.0 && all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) {
                let texel = min(vec2<u32>(uv * f32(params.glass_w)), vec2<u32>(params.glass_w - 1u));
                behind = glow[params.glass_offset + texel.y * params.glass_w + texel.x].z;
            }
        }
    }
    // Where the glow lies along the ray, each depth bilinear between the glow cells' corners'.
    let g = (vec2<f32>(xy) + 0.5) / f32(GLOW_CELL);
    let cells = (params.size + GLOW_CELL - 1u) / GLOW_CELL;
    let c = min(vec2<u32>(g), cells - 1u);
    let f = g - vec2<f32>(c);
    let row = cells.x + 1u;
    let at = 4u * (c.y * row + c.x);
    let below = 4u * row;
    var depths: GlowDepths;
    depths.a = mix(mix(glow[at], glow[at + 4u], f.x), mix(glow[at + below], glow[at + below + 4u], f.x), f.y);
    depths.b = mix(mix(glow[at + 1u], glow[at + 5u], f.x), mix(glow[at + below + 1u], glow[at + below + 5u], f.x), f.y);
    depths.c = mix(mix(glow[at + 2u], glow[at + 6u], f.x), mix(glow[at + below + 2u], glow[at + below + 6u], f.x), f.y);
    depths.d = mix(mix(glow[at + 3u], glow[at + 7u], f.x), mix(glow[at + below + 3u], glow[at + below + 7u], f.x), f.y);
    let glow_ray = glow_ray_of(depths, until, glass_at, behind);
    let none = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    // No slab's share cached yet (a slab index no ray reaches, kept below 2^30: saved shifted by one bit in a
    // float's bits between dispatches, it must not make a NaN).
    var comp = Composite(none, vec4<f32>(0.0), false, 0x3fffffffu, 0.0, 1.0);
    // The open slabs lo..end (the same for the tile's pixels), slab j's sums at ring[j % RING].
    var ring: array<vec4<f32>, RING>;
    var lo = 0u;
    var end = 0u;
    let slot = (group.x * TILE * TILE + local.y * TILE + local.x) * STATE;
    if chunk.index > 0u {
        comp.acc = state[slot];
        comp.occ = state[slot + 1u];
        let marks = bitcast<vec4<u32>>(state[slot + 2u]);
        lo = marks.x;
        end = marks.y;
        comp.done = (marks.z & 1u) != 0u;
        comp.next = marks.z >> 1u;
        comp.next_share = bitcast<f32>(marks.w);
        for (var k = 0u; k < RING; k++) {
            ring[k] = state[slot + 3u + k];
        }
        comp.glassed = state[slot + 3u + RING].x;
    }
    let toward_eye = -dir;
    // What the loop reads, in registers (lavapipe loads a buffer again at every pass of a loop).
    let near = params.near;
    let width = params.width;
    let eye = params.eye;
    let per_depth = 1.0 / along;
    let k_erf = sqrt(KERNEL_FALLOFF);
    for (var i = first; i < last; i++) {
        let e = entries[i];
        let head = e.x & 0xffffffu;
        let span = e.x >> 24u;
        // No particle after this one reaches a slab before its first: those are final.
        let closing = min(end, head);
        for (; lo < closing; lo++) {
            close_slab(&comp, ring[lo % RING], lo, glow_ray);
            ring[lo % RING] = vec4<f32>(0.0);
        }
        lo = max(lo, head);
        end = max(end, head + span + 1u);
        // Its chord along this pixel's ray, in radii from the point nearest its center.
        let ball = balls[e.y];
        let radius = ball.w;
        let to = ball.xyz - eye;
        let closest = dot(to, dir);
        let u = length(to - dir * closest) / radius;
        let hit = u < 1.0 && !comp.done && near + f32(head) * width < until;
        // The slabs its chord crosses, within those its ball reaches (none where it misses).
        var j0 = 1u;
        var j1 = 0u;
        var half = 0.0;
        var weight = 0.0;
        var lit = vec3<f32>(0.0);
        if hit {
            half = sqrt(1.0 - u * u);
            let p = particles[e.y];
            // particles::segment_integral in scene units: rho R G(u) sqrt(pi / (4 falloff)) (erf(k b) - erf(k a)).
            weight = p.density * radius * KERNEL_PEAK * exp(-KERNEL_FALLOFF * u * u) * sqrt(3.14159265 / (4.0 * KERNEL_FALLOFF));
            lit = p.color * light_toward(p, toward_eye) + vec3<f32>(p.off_r.w, p.off_g.w, p.off_b.w);
            let slab_of = (vec2<f32>(closest - half * radius, closest + half * radius) * along - near) / width;
            let slabs = clamp(vec2<i32>(floor(slab_of)), vec2<i32>(i32(head)), vec2<i32>(i32(head + span)));
            j0 = u32(slabs.x);
            j1 = u32(slabs.y);
        }
        // Its part in each: an erf a boundary, the slabs at or past the ray's end left out, the last cut there.
        var below = erf_approx(k_erf * clamp(((near + f32(j0) * width) * per_depth - closest) / radius, -half, half));
        for (var j = j0; j <= j1; j++) {
            let slab_front = near + f32(j) * width;
            // The surfaces cut the smoke where they lie, inside their slab: the first opaque one ends it (behind a
            // translucent one too), the slabs past a translucent one are seen through it.
            var back = min(slab_front + width, until);
            if slab_front < glass_at {
                back = min(back, glass_at);
            }
            let above = erf_approx(k_erf * clamp((back * per_depth - closest) / radius, -half, half));
            let tau = weight * (above - below);
            below = above;
            // Cut at a translucent surface, the slab's part past it is left out: the next slab starts at its own
            // front (reference::particles::smoke_layers alike).
            if back < min(slab_front + width, until) {
                below = erf_approx(k_erf * clamp(((slab_front + width) * per_depth - closest) / radius, -half, half));
            }
            if tau > 0.0 && slab_front < until {
                ring[j % RING] += vec4<f32>(tau * lit, tau);
            }
        }
    }
    // The dispatch that takes a tile's last particles closes its pixels' slabs and writes their images; the tiles
    // with more left carry their state to the next (they are the first ones of it: the busiest first).
    if job.z - job.y <= (chunk.index + 1u) * params.chunk {
        for (; lo < end; lo++) {
            close_slab(&comp, ring[lo % RING], lo, glow_ray);
        }
        // The two images (reference::particles::SmokeLayers::images): front over the glow, back under it.
        let seen = max(max(1.0 - comp.occ.w, comp.acc.w), SEEN_FLOOR);
        let front = vec4<f32>(comp.acc.xyz - comp.occ.xyz, seen);
        let back = vec4<f32>(comp.occ.xyz / seen, comp.acc.w / seen);
        let pixel = xy.y * params.size.x + xy.x;
        image[2u * pixel] = front;
        image[2u * pixel + 1u] = back;
        // What the draw passes filter (the sums, linear in each pixel's smoke; the images are made after
        // filtering, as a share of the glow divides the back one): the smoke's light less what the glow covers,
        // and the share of the glow lost; what the glow covers, and the smoke's coverage.
        textureStore(front_out, vec2<i32>(xy), vec4<f32>(comp.acc.xyz - comp.occ.xyz, 1.0 - seen));
        textureStore(back_out, vec2<i32>(xy), vec4<f32>(comp.occ.xyz, 1.0 - comp.acc.w));
    } else {
        state[slot] = comp.acc;
        state[slot + 1u] = comp.occ;
        let marks = vec4<u32>(lo, end, u32(comp.done) | (comp.next << 1u), bitcast<u32>(comp.next_share));
        state[slot + 2u] = bitcast<vec4<f32>>(marks);
        for (var k = 0u; k < RING; k++) {
            state[slot + 3u + k] = ring[k];
        }
        state[slot + 3u + RING] = vec4<f32>(comp.glassed, 0.0, 0.0, 0.0);
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

// The sums as the passes read them (`front_out` and `back_out` written), filtered between the smoke image's pixel
// centers, clamped at its edges.
@group(0) @binding(13) var front_in: texture_2d<f32>;
@group(0) @binding(14) var back_in: texture_2d<f32>;
@group(0) @binding(15) var smoke_sampler: sampler;

// The two images at a frame pixel, light and coverage 1 - T, premultiplied, for the blend over what lies behind
// (reference::particles::SmokeLayers::images, of the filtered sums). The front one is its sums as they are (each
// pixel's share of the glow seen is at least its transmittance and SEEN_FLOOR, and so is a blend of them).
@fragment
fn fs_front(in: VertexOut) -> @location(0) vec4<f32> {
    return textureSampleLevel(front_in, smoke_sampler, in.position.xy / vec2<f32>(params.frame), 0.0);
}

@fragment
fn fs_back(in: VertexOut) -> @location(0) vec4<f32> {
    let uv = in.position.xy / vec2<f32>(params.frame);
    let seen = max(1.0 - textureSampleLevel(front_in, smoke_sampler, uv, 0.0).w, SEEN_FLOOR);
    let b = textureSampleLevel(back_in, smoke_sampler, uv, 0.0);
    // At most 1 through: the sums are stored in f16, each rounded alone.
    return vec4<f32>(b.xyz / seen, 1.0 - min((1.0 - b.w) / seen, 1.0));
}
