// What the field's shared functions read (shaders/shared/wseries.wgsl and brightest.wgsl name the curves' buffers
// and EPSILON), for the effect shader a game engine runs (src/engine): one uniform block, `effect`, holding the
// view and every source, sized for the scene's structure (engine/structure.wgsl, written for the scene: the counts
// and each array's length, at least 1). Uniforms only, so that GLSL ES 3.0 runs it: the composer reads the curves'
// `segments[i]`, `pieces[i]` and `colors[i]` as `effect.segments[i]`..., and `weights[i]` as `weight_at(i)` (a
// uniform array's elements are 16 bytes apart: the W series is packed four to a vec4). Stands in for
// shared/field_pass.wgsl there. Rust side: src/engine/mod.rs (`View`, the block's layout).
#import engine/structure.wgsl
#import shared/field.wgsl

// The camera-dependent part: the billboard and the rays' reach as the frame of the scene's camera places them
// (frame::FrameSetup); a game moving the camera sets them again (docs/engines/README.md).
struct View {
    view_proj: mat4x4<f32>, // the engine's projection times view, for vs_main
    eye: vec3<f32>,         // V
    nu: f32,                // E = V + nu (S - V)
    center: vec3<f32>,      // the billboard's center C
    size: f32,              // its side l
    right: vec3<f32>,
    alpha: f32,             // the decay on the ray's s in [0, 1] (Integration::on_ray)
    up: vec3<f32>,
    beta: f32,
    energy: vec3<f32>,      // Ce, its intensity applied
    cutoff: f32,            // the glow's edge (scene::edge_fade); 0: none
    epsilon: f32,
    stretch: f32,           // the rays' span in decay lengths (the rms decay's unit)
    pad0: f32,
    pad1: f32,
}

struct Effect {
    view: View,
    points: array<PointSource, POINT_SLOTS>,
    lines: array<LineSource, LINE_SLOTS>,
    tori: array<TorusSource, TORUS_SLOTS>,
    curves: array<CurveSource, CURVE_SLOTS>,
    segments: array<CurveSegment, SEGMENT_SLOTS>,
    pieces: array<CurvePiece, PIECE_SLOTS>,
    // Each term's Ce_i - Ce (points, lines, tori, curves), as in the field pass.
    tints: array<vec4<f32>, TERM_SLOTS>,
    colors: array<vec4<f32>, COLOR_SLOTS>,
    // The W series, four to a vec4.
    weights: array<vec4<f32>, WEIGHT_SLOTS>,
}

@group(0) @binding(0) var<uniform> effect: Effect;

fn weight_at(i: u32) -> f32 {
    return effect.weights[i / 4u][i % 4u];
}

// The decay's scalars, read once an invocation (load_scalars), as the field pass does.
var<private> ALPHA: f32;
var<private> BETA: f32;
var<private> EPSILON: f32;
var<private> STRETCH: f32;
fn load_scalars() {
    ALPHA = effect.view.alpha;
    BETA = effect.view.beta;
    EPSILON = effect.view.epsilon;
    STRETCH = effect.view.stretch;
}

// The decay zeta(t) along the ray.
fn zeta_at(t: f32) -> f32 {
    return ALPHA / ((t + BETA) * (t + BETA));
}

// The rms decay's B_i from the integral of its squared weighed energy (twin of Integration::finish).
fn signed_root(integral: f32, coefficient: f32) -> f32 {
    return select(1.0, -1.0, coefficient < 0.0) * sqrt(max(integral, 0.0) / STRETCH);
}
