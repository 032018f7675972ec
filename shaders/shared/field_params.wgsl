// The field pass's parameter block: the billboard, the rays' reach, the decay and the integration of one frame
// (read from a storage buffer by the field passes, shared/field_pass.wgsl; from the uniform block by the engine's
// effect, engine/globals.wgsl). Rust mirror: src/gpu/field_pass/gpu_data.rs (`FieldParams`; a test checks the
// layout), filled from the frame (`gpu::field_pass::frame_bindings`).
struct FieldParams {
    center: vec3<f32>,  // billboard center C
    size: f32,          // side length l
    right: vec3<f32>,
    resolution: u32,    // W
    up: vec3<f32>,
    divisions: u32,     // Simpson's n, even
    eye: vec3<f32>,     // V
    nu: f32,
    alpha: f32,
    beta: f32,
    epsilon: f32,
    point_count: u32,
    line_count: u32,
    torus_count: u32,
    curve_count: u32,
    integrator: u32,    // 0: simpson, 1: adaptive
    term_tolerance: f32, // adaptive: the error allowed on each term's part of B (the tolerance over the sources)
    jitter: u32,        // simpson: 1 for the randomly shifted rectangle rule
    seed: u32,
    gauss_order: u32,   // adaptive: n of the Gauss-Kronrod pair (n and 2n + 1 nodes; adaptive::kronrod_order)
    layers: u32,        // the texture's layers written: 1 (B alone, every source in the scene's color) or 4
    search: u32,        // which curves' terms read their brightest point: 0 none, 1 some, 2 all (read on the CPU: the SEARCH constant)
    decay: u32,         // 0: distance (the papers'), 1: rms (integrate::Decay)
    stretch: f32,       // the rays' span in decay lengths: the rms decay's unit
    clipped: u32,       // 1 where the scene has objects: each texel's ray ends at its clip (binding 13)
    pad0: u32,
    pad1: u32,
    pad2: u32,
}
