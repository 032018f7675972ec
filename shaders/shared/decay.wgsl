// The decay along a texel's ray, and the integrand's scalars every integrator reads from registers: set once an
// invocation by its load_scalars (the field pass's from its parameter block, shared/field_pass.wgsl; the engine's
// from its uniform block, engine/globals.wgsl). Twin: integrate::Integration (zeta, finish).
var<private> ALPHA: f32;
var<private> BETA: f32;
var<private> EPSILON: f32;
// The rays' span in decay lengths: the rms decay's unit.
var<private> STRETCH: f32;

// The rms decay's B_i from the integral of its squared weighed energy over s: sign(c) sqrt(integral / stretch),
// the root taking back the sign of the term's coefficient that the square dropped (twin of Integration::finish).
fn signed_root(integral: f32, coefficient: f32) -> f32 {
    return select(1.0, -1.0, coefficient < 0.0) * sqrt(max(integral, 0.0) / STRETCH);
}

// The decay zeta(t) along the ray.
fn zeta_at(t: f32) -> f32 {
    return ALPHA / ((t + BETA) * (t + BETA));
}
