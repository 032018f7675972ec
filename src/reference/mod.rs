//! The f64 CPU reference renderer: the billboard's brightness texture B and the composed frame, formula for
//! formula as METHOD.md states them, on every core. It is the oracle the GPU passes are tested against, and
//! `energywave render --backend cpu`.
//!
//! One module for each GPU pass it twins, named after the pass's WGSL file in `shaders/`; the parts the passes
//! share, in `shaders/shared/`, are the f32 twins of `crate::field` and of the modules here, named alike:
//!
//! | WGSL (`shaders/`)             | f64 twin                                                              |
//! |-------------------------------|-----------------------------------------------------------------------|
//! | `shared/field.wgsl`           | `crate::field`: the source structs, their distances                   |
//! | `shared/cubic.wgsl`           | `crate::field::cubic`: Cardano's formula                              |
//! | `shared/curve.wgsl`           | `crate::field::curve`: a segment's points and its nearest point       |
//! | `shared/wseries.wgsl`         | `crate::field::wseries`: the W series and the color series            |
//! | `shared/brightest.wgsl`       | `crate::field::brightest`: the point a chain's term reads             |
//! | `shared/field_pass.wgsl`      | [`field_pass`]: each texel's ray, its bindings, the brightness texture |
//! | `shared/adaptive.wgsl`        | [`adaptive`]: the adaptive integrator's shared parts (Gauss-Kronrod, pieces, cuts) |
//! | `simpson.wgsl`                | [`simpson`]: the papers' rule (and the shifted rectangle rule with jitter) |
//! | `adaptive_smooth.wgsl`        | [`adaptive_smooth`]: points, lines (in closed form where it holds) and tori |
//! | `adaptive_curves.wgsl`        | [`adaptive_curves`]: curve chains, their scan, jumps and kinks        |
//! | `objects.wgsl`                | [`objects`]: the objects, lit at every pixel                          |
//! | `glare.wgsl`                  | [`glare`]: the fog glow, the excess over a threshold blurred and added back |
//! | `billboard.wgsl`              | [`billboard`]: the blend and the composed frame                       |
//!
//! [`particles`] renders particle sets by image-aligned sheet-buffer splatting along a ray, in f64, beside the
//! finely ray-marched medium it converges to.
//!
//! The other shaders only display or resample a field already integrated (`average.wgsl`, the viewer's running
//! mean of jittered frames; `upsample.wgsl`, `grid.wgsl`, `blit.wgsl`) and have no twin. [`converged`] is the
//! value both twins are held to: Simpson refined until converged, knowing nothing of either integrator.
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
pub mod simpson;

pub use billboard::{Backdrop, compose_frame, compose_frame_over, compose_frame_unclamped};
pub use field_pass::{BrightnessTexture, brightness, render_brightness, texel_brightness};
