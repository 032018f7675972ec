// The energy field's sources as every pass that evaluates the field reads them: the source structs, mirrored in
// src/gpu/field_pass/gpu_data.rs (keep in sync), and the distance functions. METHOD.md section 1. Twin:
// src/field/mod.rs.
#import shared/constants.wgsl

struct PointSource {
    position: vec3<f32>,
    coefficient: f32,
}

struct LineSource {
    point: vec3<f32>,
    coefficient: f32,
    direction: vec3<f32>, // unit length
    pad0: f32,
}

struct TorusSource {
    center: vec3<f32>,
    major_radius: f32,
    axis: vec3<f32>, // unit length
    coefficient: f32,
}

// A chain of quadratic Bezier segments: its segments, W series and color series are ranges of the segment,
// weight and color buffers.
struct CurveSource {
    first_segment: u32,
    segment_count: u32,
    first_weight: u32,
    weight_count: u32, // 0: all weights 1
    coefficient: f32,
    first_color: u32,
    color_count: u32,  // 0: no color series (the curve's one color is its tint)
    first_piece: u32,
    piece_count: u32,  // 0: the term reads the nearest point (the papers' form, or a uniform W series)
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// A stretch of a chain between its joints and W's knots, for the continuous W form (twin of field::brightest::Piece):
// the curve C(x) = c2 x^2 + c1 x + c0 and S(x) = s2 x^2 + s1 x + s0 in its own x in [0, 1], the chain parameters at
// its ends, a ball holding it, S's largest value on it and the end where S has a double zero.
struct CurvePiece {
    c2: vec3<f32>,
    s2: f32,
    c1: vec3<f32>,
    s1: f32,
    c0: vec3<f32>,
    s0: f32,
    center: vec3<f32>,
    radius: f32,
    t0: f32,
    t1: f32,
    weight_max: f32,
    zero_end: f32,  // the end (0 or 1) where S has a double zero, S = s2 (x - zero_end)^2; else -1
}

// One segment in power form, C(t) = c2 t^2 + c1 t + c0 (computed from the control points in f64).
struct CurveSegment {
    c2: vec3<f32>,
    pad0: f32,
    c1: vec3<f32>,
    pad1: f32,
    c0: vec3<f32>,
    pad2: f32,
}

const PI: f32 = 3.14159265358979;
const F32_MAX: f32 = 3.0e38;

// 1 / max(eps, d): the falloff of every kind of source.
fn falloff(d: f32, eps: f32) -> f32 {
    return 1.0 / max(eps, d);
}

// Distance from p to the line through m along the unit direction d (thesis 3.3).
fn line_distance(p: vec3<f32>, m: vec3<f32>, d: vec3<f32>) -> f32 {
    // The part of p - m across the line, not the difference of squares, which rounding ruins close to the
    // line far from m. Twin of field::line_distance.
    let q = p - m;
    return length(q - d * dot(q, d));
}

// Distance from p to the major circle of a torus (thesis 3.7 in the torus's own frame).
fn torus_distance(p: vec3<f32>, center: vec3<f32>, axis: vec3<f32>, major_radius: f32) -> f32 {
    let q = p - center;
    let z = dot(q, axis);
    let rho = sqrt(max(dot(q, q) - z * z, 0.0));
    let dr = rho - major_radius;
    return sqrt(dr * dr + z * z);
}

