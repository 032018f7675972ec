//! Rust mirrors of the WGSL structs of `shaders/shared/field_pass.wgsl` and `shaders/shared/field.wgsl` (keep in
//! sync; `tests/gpu_layout.rs` checks them against naga's layout).

use bytemuck::{Pod, Zeroable};

/// `FieldParams` in `shaders/shared/field_pass.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FieldParams {
    pub center: [f32; 3],    // 0
    pub size: f32,           // 12
    pub right: [f32; 3],     // 16
    pub resolution: u32,     // 28
    pub up: [f32; 3],        // 32
    pub divisions: u32,      // 44
    pub eye: [f32; 3],       // 48
    pub nu: f32,             // 60
    pub alpha: f32,          // 64
    pub beta: f32,           // 68
    pub epsilon: f32,        // 72
    pub point_count: u32,    // 76
    pub line_count: u32,     // 80
    pub torus_count: u32,    // 84
    pub curve_count: u32,    // 88
    pub integrator: u32,     // 92: 0 simpson, 1 adaptive
    pub term_tolerance: f32, // 96
    pub jitter: u32,         // 100
    pub seed: u32,           // 104
    pub gauss_order: u32, // 108: adaptive: n of the Gauss-Kronrod pair (integrate::adaptive::kronrod_order)
    pub layers: u32, // 112: the field texture's layers written: 1 (B) or FIELD_LAYERS (and the tint)
    pub search: u32, // 116: which curves' terms read their brightest point, 0 none, 1 some, 2 all (the SEARCH constant)
    pub decay: u32,  // 120: 0 distance, 1 rms (integrate::Decay)
    pub stretch: f32, // 124: the rays' span in decay lengths, the rms decay's unit
    pub clipped: u32, // 128: 1 where the scene has objects: each texel's ray ends at its clip (binding 13)
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
}
const _: () = assert!(size_of::<FieldParams>() == 144);

/// `Chunk` in `shaders/shared/field_pass.wgsl`: one dispatch's range of samples or terms.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Chunk {
    pub first: u32,      // 0
    pub count: u32,      // 4
    pub accumulate: u32, // 8
    pub pipeline: u32,   // 12: which of `FieldRenderer`'s pipelines runs it (read on the CPU only)
    pub row_offset: u32, // 16: the first texel row of its band
    pub term: u32,       // 20: simpson with the rms decay: the one term it integrates
    pub stage: u32, // 24: that term's sums: bit 0, add the scratch's; bit 1, finish (else keep)
    pub listed: u32, // 28: 1: over the texels a refined level lists (indirect), not a band of rows
}
const _: () = assert!(size_of::<Chunk>() == 32);

/// `PointSource` in `shaders/shared/field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PointSource {
    pub position: [f32; 3], // 0
    pub coefficient: f32,   // 12
}
const _: () = assert!(size_of::<PointSource>() == 16);

/// `LineSource` in `shaders/shared/field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LineSource {
    pub point: [f32; 3],     // 0
    pub coefficient: f32,    // 12
    pub direction: [f32; 3], // 16
    pub pad0: f32,           // 28
}
const _: () = assert!(size_of::<LineSource>() == 32);

/// `TorusSource` in `shaders/shared/field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TorusSource {
    pub center: [f32; 3],  // 0
    pub major_radius: f32, // 12
    pub axis: [f32; 3],    // 16
    pub coefficient: f32,  // 28
}
const _: () = assert!(size_of::<TorusSource>() == 32);

/// `CurveSource` in `shaders/shared/field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CurveSource {
    pub first_segment: u32, // 0
    pub segment_count: u32, // 4
    pub first_weight: u32,  // 8
    pub weight_count: u32,  // 12
    pub coefficient: f32,   // 16
    pub first_color: u32,   // 20
    pub color_count: u32,   // 24: 0, no color series
    pub first_piece: u32,   // 28
    pub piece_count: u32,   // 32: 0, the term reads the nearest point
    pub pad0: u32,          // 36
    pub pad1: u32,          // 40
    pub pad2: u32,          // 44
}
const _: () = assert!(size_of::<CurveSource>() == 48);

/// `CurvePiece` in `shaders/shared/field.wgsl` (twin of `field::brightest::Piece`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CurvePiece {
    pub c2: [f32; 3],     // 0
    pub s2: f32,          // 12
    pub c1: [f32; 3],     // 16
    pub s1: f32,          // 28
    pub c0: [f32; 3],     // 32
    pub s0: f32,          // 44
    pub center: [f32; 3], // 48
    pub radius: f32,      // 60
    pub t0: f32,          // 64
    pub t1: f32,          // 68
    pub weight_max: f32,  // 72
    pub zero_end: f32,    // 76: the end of S's double zero, 0 or 1, else -1
}
const _: () = assert!(size_of::<CurvePiece>() == 80);

/// `CurveSegment` in `shaders/shared/field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CurveSegment {
    pub c2: [f32; 3], // 0
    pub pad0: f32,    // 12
    pub c1: [f32; 3], // 16
    pub pad1: f32,    // 28
    pub c0: [f32; 3], // 32
    pub pad2: f32,    // 44
}
const _: () = assert!(size_of::<CurveSegment>() == 48);
