//! The f64 CPU reference renderer: the billboard's brightness texture B and the composed frame, formula for
//! formula as METHOD.md states them, on every core. It is the oracle the GPU passes are tested against, and
//! `energywave render --backend cpu`.
//!
//! One module for each GPU pass it twins, named after the pass's WGSL file in `shaders/`; the parts the passes
//! share, in `shaders/shared/`, are the f32 twins of `crate::field` and of the modules here, named alike. Every
//! WGSL file is in this table, with its twin or the reason it has none (`tests/module_graph.rs` checks):
//!
//! | WGSL (`shaders/`)             | f64 twin                                                              |
//! |-------------------------------|-----------------------------------------------------------------------|
//! | `shared/field.wgsl`           | `crate::field`: the source structs, their distances                   |
//! | `shared/cubic.wgsl`           | `crate::field::cubic`: Cardano's formula                              |
//! | `shared/curve.wgsl`           | `crate::field::curve`: a segment's points and its nearest point       |
//! | `shared/wseries.wgsl`         | `crate::field::wseries`: the W series and the color series            |
//! | `shared/brightest.wgsl`       | `crate::field::brightest`: the point a chain's term reads             |
//! | `shared/field_params.wgsl`    | none of its own: the field pass's parameter block, filled from the frame (`frame::FrameSetup`), its Rust mirror `gpu::field_pass::FieldParams` (`tests/gpu_layout.rs`) |
//! | `shared/decay.wgsl`           | `crate::integrate::Integration`: the decay zeta and the rms decay's root (`finish`) |
//! | `shared/field_pass.wgsl`      | [`field_pass`]: each texel's ray, its bindings, the brightness texture |
//! | `shared/adaptive.wgsl`        | [`adaptive`]: the adaptive integrator's shared parts (Gauss-Kronrod, pieces, cuts) |
//! | `simpson.wgsl`                | [`simpson`]: the papers' rule (and the shifted rectangle rule with jitter) |
//! | `adaptive_smooth.wgsl`        | [`adaptive_smooth`]: points, lines (in closed form where it holds) and tori |
//! | `adaptive_curves.wgsl`        | [`adaptive_curves`]: curve chains                                     |
//! | `adaptive_curves/scan.wgsl`   | `adaptive_curves::scan`: a chain's scan along the ray, its features |
//! | `adaptive_curves/kinks.wgsl`  | `adaptive_curves::kinks`: the kinks and jumps of a chain's term     |
//! | `refine.wgsl`                 | [`refine`]: the field refined in image space, texels predicted where the detail is small |
//! | `through.wgsl`                | [`field_pass::see_through`]: the glow seen through translucent objects |
//! | `tau_table.wgsl`              | `crate::objects::translucent::table::Table::of`: the optical-thickness table |
//! | `objects.wgsl`                | [`objects`]: the objects, lit at every pixel                          |
//! | `particles.wgsl`              | [`particles`]: the smoke by sheet-buffer splatting                    |
//! | `glare.wgsl`                  | [`glare`]: the fog glow, the excess over a threshold blurred and added back |
//! | `billboard.wgsl`              | [`billboard`]: the blend and the composed frame                       |
//! | `engine/globals.wgsl`         | none of its own: the field pass's parameter block and the shared files read from one uniform block (`crate::engine`) |
//! | `engine/effect.wgsl`          | [`simpson`] along each fragment's ray, then [`billboard`]'s transparent blend (`tests/engine.rs` holds it to the field pass) |
//! | `average.wgsl`                | none: the viewer's running mean of jittered frames, no formula of the method |
//! | `grid.wgsl`                   | none: the viewer's ground grid                                        |
//! | `blit.wgsl`                   | none: copies the viewer's frame into the window                       |
//!
//! [`particles`] renders particle sets by image-aligned sheet-buffer splatting along a ray, in f64, beside the
//! finely ray-marched medium it converges to. The integrators share one trait, [`TermIntegrator`]: a term's part
//! of B on a texel's ray ([`TexelRay`]). [`converged`] is the value both twins are held to: Simpson refined until
//! converged, knowing nothing of either integrator.
//!
//! The shader constants the twins share are written into the WGSL from the definitions here
//! (`gpu::shaders::shared_constants`).

pub mod adaptive;
pub mod adaptive_curves;
pub mod adaptive_smooth;
pub mod billboard;
pub mod converged;
pub mod field_pass;
pub mod glare;
pub mod objects;
pub mod particles;
pub mod refine;
pub mod simpson;

pub use billboard::{Backdrop, compose_frame, compose_frame_over, compose_frame_unclamped};

/// A texel's ray as the integrators take it: from S on the billboard to its end E, and the texel's jitter offset
/// `xi` (the jittered Simpson rule's; the others ignore it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelRay {
    pub start: glam::DVec3,
    pub end: glam::DVec3,
    pub xi: f64,
}

/// What every integrator twin gives, each the f64 twin of a WGSL integrator: the part of B of one term on a
/// texel's ray. `k` counts the terms the integrator takes: every term for `simpson::Simpson` and
/// `field_pass::FieldPass` (the scene's integrator, as the field pass runs it), the points, lines and tori for
/// `adaptive_smooth::AdaptiveSmooth`, the curves for `adaptive_curves::AdaptiveCurves`.
pub trait TermIntegrator {
    fn term_brightness(
        &self,
        sources: &crate::field::Sources,
        k: usize,
        settings: &crate::integrate::Integration,
        ray: TexelRay,
    ) -> f64;
}
pub use field_pass::{BrightnessTexture, brightness, render_brightness, texel_brightness};
