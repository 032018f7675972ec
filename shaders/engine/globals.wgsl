// What the field's shared functions read (shaders/shared/wseries.wgsl and brightest.wgsl name the curves' buffers
// and EPSILON), for the effect shader a game engine runs (src/engine): one uniform block, `effect`, holding the
// view and every source, sized for the scene's structure (engine/structure.wgsl, written for the scene: the counts
// and each array's length, at least 1). Uniforms only, so that GLSL ES 3.0 runs it: the composer reads the curves'
// `segments[i]`, `pieces[i]` and `colors[i]` as `effect.segments[i]`..., and `weights[i]` as `weight_at(i)` (a
// uniform array's elements are 16 bytes apart: the W series is packed four to a vec4). Stands in for
// shared/field_pass.wgsl there. Rust side: src/engine/mod.rs (`View`, the block's layout).
#import engine/structure.wgsl
#import shared/field.wgsl
#import shared/field_params.wgsl
#import shared/decay.wgsl

// The camera-dependent part: the view-projection for vs_main, the field pass's own parameter block (the billboard
// and the rays' reach as the frame of the scene's camera places them, frame::FrameSetup; the decay), and the
// blend's energy color and edge. A game moving the camera sets them again (docs/engines/README.md).
struct View {
    view_proj: mat4x4<f32>, // the engine's projection times view, for vs_main
    params: FieldParams,    // shared/field_params.wgsl: eye V, nu, center C, size l, right, up, alpha, beta, ...
    energy: vec3<f32>,      // Ce, its intensity applied
    cutoff: f32,            // the glow's edge (scene::edge_fade); 0: none
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

// The decay's scalars (shared/decay.wgsl), read once an invocation, as the field pass does.
fn load_scalars() {
    ALPHA = effect.view.params.alpha;
    BETA = effect.view.params.beta;
    EPSILON = effect.view.params.epsilon;
    STRETCH = effect.view.params.stretch;
}
