//! The converged reference of B: for each texel, f64 Simpson on a fine uniform grid, refined wherever its
//! estimated error exceeds `REFERENCE_TOLERANCE`, formulated in the scene's own terms (depth past the billboard in
//! decay lengths) rather than through the integrators' normalised ray. It knows nothing of the adaptive
//! integrator's features: the independent value both integrators, on the CPU and on the GPU, are held to (the
//! equal-error study of `energywave bench`, the tests).

use rayon::prelude::*;
use serde::Serialize;

use super::simpson::{simpson, simpson_refined};
use crate::frame::FrameSetup;
use crate::integrate::{Decay, zeta};
use crate::objects::first_hit;
use crate::scene::Scene;

/// The converged reference: f64 Simpson with this many divisions, refined (`simpson::simpson_refined`) wherever
/// its estimated error exceeds `REFERENCE_TOLERANCE` on B.
pub const REFERENCE_DIVISIONS: u32 = 4096;
/// The reference's estimated error on B, texel by texel.
pub const REFERENCE_TOLERANCE: f64 = 1e-7;
/// How many times the reference splits an interval at most (down to a width of 2^-40).
pub const REFERENCE_MAX_DEPTH: u32 = 28;

/// The converged f64 reference of B (`REFERENCE_DIVISIONS`, `REFERENCE_TOLERANCE`) for every `stride`-th
/// texel of `scene`'s billboard (rows, then columns), and how it was reached.
pub fn converged_reference(scene: &Scene, stride: u32) -> (Vec<f64>, ReferenceStats) {
    let s = scene;
    let w = s.billboard.resolution;
    let setup = FrameSetup::placed(s, 1.0);
    let (billboard, reach) = (setup.billboard, setup.reach);
    let plane = (billboard.center - s.camera.eye).dot(-billboard.normal);
    let texels: Vec<(u32, u32)> = (0..w)
        .step_by(stride as usize)
        .flat_map(|j| (0..w).step_by(stride as usize).map(move |i| (i, j)))
        .collect();
    let field = s.sources.field();
    let opaque: Vec<crate::objects::Object> = (s.objects.iter())
        .filter(|o| o.translucent.is_none())
        .cloned()
        .collect();
    let translucent = opaque.len() < s.objects.len();
    let opaque = &opaque[..];
    let out: Vec<(f64, u64)> = texels
        .par_iter()
        .map(|&(i, j)| {
            // In the scene's own terms, not the integrators' normalised s: sigma is the depth past the
            // billboard in decay lengths, zeta(sigma) = alpha / (sigma + beta)^2, and the ray ends at
            // sigma = reach.stretch.
            let p = billboard.texel_center(i, j, w);
            let i = &s.integration;
            let per_depth = (p - s.camera.eye) / plane;
            let span = reach.stretch;
            // Up to the first surface the ray meets past the billboard (none before it: hidden), at depth
            // t = keep, the integrals over [0, keep] written over [0, 1] by t = keep u.
            let keep_of = |objects: &[crate::objects::Object]| match first_hit(
                objects,
                s.camera.eye,
                p - s.camera.eye,
                0.0,
                f64::INFINITY,
            ) {
                None => 1.0,
                Some((_, tau)) => ((tau - 1.0) * plane / (span * i.decay_length)).clamp(0.0, 1.0),
            };
            let b_of = |keep: f64| -> (f64, u64) {
                if keep == 0.0 {
                    return (0.0, 0);
                }
                let at = |t: f64| p + per_depth * (keep * t * span * i.decay_length);
                let zeta = |t: f64| zeta(keep * t * span, i.alpha, i.beta);
                let span = keep * span;
                match i.decay {
                    Decay::Distance => simpson_refined(
                        |t| field.psi(at(t), i.epsilon) * zeta(t) * span,
                        REFERENCE_DIVISIONS,
                        REFERENCE_TOLERANCE,
                        REFERENCE_MAX_DEPTH,
                    ),
                    // Each term the root of its own integral J of the square. An error dJ costs dJ / (2 sqrt(J))
                    // of B, so J is refined to the tolerance times sqrt(J) (J first estimated unrefined), and at
                    // least to its square (|sqrt(x) - sqrt(y)| <= sqrt(|x - y|)). The root takes the sign of the
                    // term's coefficient back (the square dropped it): a negative source subtracts.
                    Decay::Rms => (0..s.sources.len())
                        .map(|k| {
                            let f =
                                |t: f64| (field.term(k, at(t), i.epsilon) * zeta(t)).powi(2) * span;
                            let rough = simpson(f, REFERENCE_DIVISIONS);
                            let tolerance = (REFERENCE_TOLERANCE * rough.max(0.0).sqrt())
                                .max(REFERENCE_TOLERANCE * REFERENCE_TOLERANCE);
                            let (sq, n) = simpson_refined(
                                f,
                                REFERENCE_DIVISIONS,
                                tolerance,
                                REFERENCE_MAX_DEPTH,
                            );
                            (
                                sq.max(0.0).sqrt().copysign(s.sources.coefficient(k)),
                                n + REFERENCE_DIVISIONS as u64 + 1,
                            )
                        })
                        .fold((0.0, 0), |(b, n), (x, m)| (b + x, n + m)),
                }
            };
            // Only opaque objects end the glow; the glow inside and behind translucent ones is seen through them
            // (`reference::field_pass::render_brightness`): the glow up to the first surface of any object, up
            // to the last translucent surface crossed and up to the first opaque one, blended by the shares of
            // the glow inside and behind that reach the eye.
            let behind = keep_of(opaque);
            if !translucent {
                return b_of(behind);
            }
            let end = 1.0 + behind * span * i.decay_length / plane;
            let psi = |x: glam::DVec3| field.psi(x, i.epsilon);
            let Some(x) =
                crate::objects::translucent::crossing(&s.objects, s.camera.eye, p, end, &psi)
            else {
                return b_of(behind);
            };
            let exit = ((x.exit - 1.0) * plane / (span * i.decay_length)).clamp(0.0, 1.0);
            let (bf, nf) = b_of(keep_of(&s.objects));
            let (bx, nx) = b_of(exit);
            let (bb, nb) = b_of(behind);
            (
                bf + x.inside * (bx - bf) + x.behind * (bb - bx),
                nf + nx + nb,
            )
        })
        .collect();
    // Without refinement, a texel spends the n + 1 samples and 2 more a pair of intervals, to check them.
    let unrefined = 2 * REFERENCE_DIVISIONS as u64 + 1;
    let stats = ReferenceStats {
        refined_share: out.iter().filter(|(_, e)| *e > unrefined).count() as f64
            / out.len().max(1) as f64,
        mean_evaluations: out.iter().map(|(_, e)| *e as f64).sum::<f64>() / out.len().max(1) as f64,
        max_evaluations: out.iter().map(|(_, e)| *e).max().unwrap_or(0),
    };
    (out.into_iter().map(|(b, _)| b).collect(), stats)
}

/// How the converged reference of one render was reached.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ReferenceStats {
    /// Share of texels refined beyond the uniform `REFERENCE_DIVISIONS` (and its check).
    pub refined_share: f64,
    /// Evaluations of the integrand a texel, on average and at most.
    pub mean_evaluations: f64,
    pub max_evaluations: u64,
}

impl std::fmt::Display for ReferenceStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "f64 CPU, Simpson n = {REFERENCE_DIVISIONS} refined to an estimated {REFERENCE_TOLERANCE:e} on B ({:.1}% of texels refined; {:.0} evaluations a texel on average, {} at most)",
            100.0 * self.refined_share,
            self.mean_evaluations,
            self.max_evaluations,
        )
    }
}
