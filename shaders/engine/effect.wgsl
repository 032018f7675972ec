// The effect as a shader a game engine runs (thesis 6.2): the camera-facing billboard drawn as a quad, each
// fragment integrating the energy field along its own ray S -> E by the papers' Simpson rule (n = DIVISIONS
// samples, the scene's structure fixed in engine/structure.wgsl, every value in the `effect` uniform block, so
// that the game animates them), then the glow premultiplied by its alpha min(B, 1) for the engine's "over"
// blend (ONE, ONE_MINUS_SRC_ALPHA), as energywave's transparent export. The same terms, the same decays and the
// same order of sums as shaders/simpson.wgsl, without its dispatch chunks (a fragment integrates its ray whole)
// and without the scene's objects (the game's own geometry hides the glow by the depth test). Written from this
// file by naga as GLSL 4.50 and ES 3.00, HLSL and MSL (src/engine). Entry points: vs_main (the quad, a triangle
// strip of four vertices), fs_glow (the glow) and fs_brightness (B and the tint, for checking against the field
// pass).
#import engine/globals.wgsl
#import shared/brightest.wgsl

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
}

// A triangle strip of four corners: uv (0,0) top-left, (1,0), (0,1), (1,1), on the billboard.
@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    let v = effect.view.params;
    let uv = vec2<f32>(f32(index & 1u), f32(index >> 1u));
    let world = v.center + v.right * (v.size * (uv.x - 0.5)) + v.up * (v.size * (0.5 - uv.y));
    var out: VertexOut;
    out.position = effect.view.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    return out;
}

// Sample k of n on S -> E: its position, and its Simpson weight (1 4 2 4 ... 4 1) times zeta(s), squared for the
// rms decay.
fn sample_at(s_point: vec3<f32>, e_point: vec3<f32>, k: u32) -> vec4<f32> {
    let s = f32(k) / f32(DIVISIONS);
    var weight = 1.0;
    if k != 0u && k != DIVISIONS {
        weight = select(2.0, 4.0, (k & 1u) == 1u);
    }
    let zeta = zeta_at(s);
    return vec4<f32>(mix(s_point, e_point, s), weight * select(zeta, zeta * zeta, RMS));
}

fn raised(v: f32) -> f32 {
    return select(v, v * v, RMS);
}

fn point_samples(s_point: vec3<f32>, e_point: vec3<f32>, src: PointSource) -> f32 {
    var sum = 0.0;
    for (var k = 0u; k <= DIVISIONS; k++) {
        let x = sample_at(s_point, e_point, k);
        sum += x.w * raised(falloff(length(x.xyz - src.position), EPSILON));
    }
    return raised(src.coefficient) * sum;
}

fn line_samples(s_point: vec3<f32>, e_point: vec3<f32>, src: LineSource) -> f32 {
    var sum = 0.0;
    for (var k = 0u; k <= DIVISIONS; k++) {
        let x = sample_at(s_point, e_point, k);
        sum += x.w * raised(falloff(line_distance(x.xyz, src.point, src.direction), EPSILON));
    }
    return raised(src.coefficient) * sum;
}

fn torus_samples(s_point: vec3<f32>, e_point: vec3<f32>, src: TorusSource) -> f32 {
    var sum = 0.0;
    for (var k = 0u; k <= DIVISIONS; k++) {
        let x = sample_at(s_point, e_point, k);
        sum += x.w * raised(falloff(torus_distance(x.xyz, src.center, src.axis, src.major_radius), EPSILON));
    }
    return raised(src.coefficient) * sum;
}

// A curve's term at p and that times its color series at t (twin of simpson.wgsl's curve_field).
fn curve_field(c: CurveSource, held: HeldChain, p: vec3<f32>) -> vec4<f32> {
    let best = curve_point(c, held, p);
    let f = c.coefficient * wseries(c, held.weights, best.x) * falloff(best.y, EPSILON);
    return vec4<f32>(f, f * color_series(c, best.x));
}

fn curve_samples(s_point: vec3<f32>, e_point: vec3<f32>, c: CurveSource) -> vec4<f32> {
    var sum = vec4<f32>(0.0);
    let held = held_chain(c);
    for (var k = 0u; k <= DIVISIONS; k++) {
        let x = sample_at(s_point, e_point, k);
        let g = curve_field(c, held, x.xyz);
        sum += x.w * select(g, g.x * g, RMS);
    }
    return sum;
}

// Simpson's common factor h / 3, h = 1 / n.
const SCALE: f32 = 1.0 / (3.0 * f32(DIVISIONS));

// A term's part of (B, tint) from its sums: B_i and B_i (Ce_i - Ce), a curve's color series adding its own
// integral; for the distance decay before the common factor SCALE (applied once, to the sum over the terms, as
// the field pass does), for the rms decay its signed root.
fn term_glow(t: u32, sums: vec4<f32>, coefficient: f32) -> vec4<f32> {
    if RMS {
        let b = signed_root(sums.x * SCALE, coefficient);
        var glow = vec4<f32>(b, b * effect.tints[t].xyz);
        if sums.x > 0.0 {
            glow += vec4<f32>(0.0, b * sums.yzw / sums.x);
        }
        return glow;
    }
    return vec4<f32>(sums.x, sums.x * effect.tints[t].xyz + sums.yzw);
}

// (B, tint) of the ray through the billboard's point s_point: B, and the tint sum B_i (Ce_i - Ce), so that the
// glow's color is B Ce + tint.
fn brightness_at(s_point: vec3<f32>) -> vec4<f32> {
    load_scalars();
    let v = effect.view.params;
    let e_point = v.eye + v.nu * (s_point - v.eye);
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < POINTS; i++) {
        let src = effect.points[i];
        sum += term_glow(i, vec4<f32>(point_samples(s_point, e_point, src), 0.0, 0.0, 0.0), src.coefficient);
    }
    for (var i = 0u; i < LINES; i++) {
        let src = effect.lines[i];
        let t = POINTS + i;
        sum += term_glow(t, vec4<f32>(line_samples(s_point, e_point, src), 0.0, 0.0, 0.0), src.coefficient);
    }
    for (var i = 0u; i < TORI; i++) {
        let src = effect.tori[i];
        let t = POINTS + LINES + i;
        sum += term_glow(t, vec4<f32>(torus_samples(s_point, e_point, src), 0.0, 0.0, 0.0), src.coefficient);
    }
    for (var i = 0u; i < CURVES; i++) {
        let c = effect.curves[i];
        let t = POINTS + LINES + TORI + i;
        sum += term_glow(t, curve_samples(s_point, e_point, c), c.coefficient);
    }
    return select(sum * SCALE, sum, RMS);
}

@fragment
fn fs_brightness(in: VertexOut) -> @location(0) vec4<f32> {
    return brightness_at(in.world);
}

// The glow, premultiplied by its alpha min(B, 1), B faded out at the glow's edge (scene::edge_fade): composited
// "over" the scene behind (blend ONE, ONE_MINUS_SRC_ALPHA) it is energywave's blend (1 - B) Cb + B Ce wherever
// B <= 1. Unclamped above: an HDR target keeps the glow of B > 1.
@fragment
fn fs_glow(in: VertexOut) -> @location(0) vec4<f32> {
    return glow_at(in.world);
}

// fs_glow's value at the billboard's point s_point: what an engine's own shader calls (a Unity Custom Function,
// an Unreal Custom node) with the fragment's world position on its quad.
fn glow_at(s_point: vec3<f32>) -> vec4<f32> {
    var field = brightness_at(s_point);
    let c = effect.view.cutoff;
    let fade = select(1.0, smoothstep(c, 2.0 * c, abs(field.x)), c > 0.0);
    field = field * fade;
    let b = field.x;
    let glow = b * effect.view.energy + field.yzw;
    return vec4<f32>(max(glow, vec3<f32>(0.0)), clamp(b, 0.0, 1.0));
}
