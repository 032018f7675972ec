//! What every field pass shares, the f64 twin of `shaders/shared/field_pass.wgsl`: each texel's ray S -> E, B along it
//! by the scene's integrator (`simpson`, or the two families of `adaptive`), and the billboard's whole brightness
//! texture, on every core.

use glam::DVec3;
use rayon::prelude::*;

use super::simpson::jitter_offset;
use super::{TermIntegrator, TexelRay, adaptive_curves, adaptive_smooth, simpson};
use crate::field::{Sources, wseries};
use crate::frame::FrameSetup;
use crate::geometry::ray_end;
use crate::integrate::{Decay, Integration, Integrator};
use crate::objects::clip::clip_fraction;

/// The brightness B of the segment from `s` to `e` (3.30): the integral over [0, 1] of
/// `psi((1 - t) S + t E) zeta(t)`, by the scene's integrator. `xi` is the texel's jitter offset (used by the
/// jittered `simpson` integrator only).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3, xi: f64) -> f64 {
    match settings.integrator {
        Integrator::Simpson => simpson::brightness(sources, settings, s, e, xi),
        Integrator::Adaptive => adaptive(sources, settings, s, e),
    }
}

/// B by the adaptive integrator: its two families, as its two GPU passes add into the texture.
pub fn adaptive(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    adaptive_smooth::brightness(sources, settings, s, e)
        + adaptive_curves::brightness(sources, settings, s, e)
}

/// The scene's integrator as the field pass runs it: Simpson's rule, or the adaptive integrator's two families.
pub struct FieldPass;

impl TermIntegrator for FieldPass {
    /// The part of B of term `k` alone (points, lines, tori, curves, as `Sources::term` counts), by the scene's
    /// integrator as `brightness` integrates it.
    fn term_brightness(
        &self,
        sources: &Sources,
        k: usize,
        settings: &Integration,
        ray: TexelRay,
    ) -> f64 {
        let smooth = sources.first_curve();
        match settings.integrator {
            Integrator::Simpson => simpson::Simpson.term_brightness(sources, k, settings, ray),
            Integrator::Adaptive if k < smooth => {
                (adaptive_smooth::AdaptiveSmooth).term_brightness(sources, k, settings, ray)
            }
            Integrator::Adaptive => (adaptive_curves::AdaptiveCurves).term_brightness(
                sources,
                k - smooth,
                settings,
                ray,
            ),
        }
    }
}

/// The tint of the segment from `s` to `e`: `sum B_i (Ce_i - Ce)` over the frame's terms (`Term::tint`); what
/// the field pass integrates beside B, so that the colored sum `sum B_i Ce_i` is `B Ce + tint`. Terms in the
/// scene's color add nothing and are not integrated. A curve with a color series adds, beside its B_i times
/// `-Ce`, its term with the series in the place of the constant color, channel by channel, each within the term's
/// share of the tolerance times the channel's largest value.
pub fn tint_of(
    setup: &FrameSetup,
    settings: &Integration,
    (s, e): (DVec3, DVec3),
    xi: f64,
) -> [f64; 3] {
    let sources = &setup.scene.sources;
    let colors = &setup.scene.colors;
    let mut sum = [0.0; 3];
    for (k, term) in setup.terms.iter().enumerate() {
        let t = term.tint;
        if t.iter().any(|&x| x != 0.0) {
            let ray = TexelRay {
                start: s,
                end: e,
                xi,
            };
            let b = FieldPass.term_brightness(sources, k, settings, ray);
            (0..3).for_each(|c| sum[c] += b * t[c]);
        }
        let Some(curve) = setup.series_curve(k) else {
            continue;
        };
        let index = k - setup.first_curve();
        for (c, out) in sum.iter_mut().enumerate() {
            let color = |t: f64| colors.color_along(curve, t)[c];
            let largest = (curve.color_series.iter()).fold(0.0f64, |m, x| m.max(x[c]));
            let scale = largest * term.intensity;
            if scale == 0.0 {
                continue;
            }
            // The integral of the term (to the decay's power) weighed by `weight(t)` in the place of its W series.
            let weighed = |weight: &dyn Fn(f64) -> f64, scale: f64| match settings.integrator {
                Integrator::Simpson => simpson::curve_weighted(curve, settings, (s, e), xi, weight),
                Integrator::Adaptive => {
                    adaptive_curves::term_weighted(sources, index, settings, (s, e), weight, scale)
                }
            };
            let w = |t: f64| wseries::evaluate(&curve.weights, t);
            *out += match settings.decay {
                // The term times the series.
                Decay::Distance => weighed(&|t| w(t) * color(t), scale),
                // B_i times the series' mean, weighed as B_i's integral weighs the term: its square.
                Decay::Rms => {
                    let i = weighed(&|t| w(t) * w(t), 1.0);
                    let j = weighed(&|t| w(t) * w(t) * color(t), scale);
                    if i > 0.0 {
                        settings.finish(i, curve.coefficient) * j / i
                    } else {
                        0.0
                    }
                }
            };
        }
    }
    sum
}

/// The billboard's field texture: `resolution` x `resolution` texels, row-major, rows from the top, each B and
/// the tint `sum B_i (Ce_i - Ce)` (zero where every source has the scene's color).
#[derive(Clone, Debug, PartialEq)]
pub struct BrightnessTexture {
    pub resolution: u32,
    pub values: Vec<f64>,
    pub tint: Vec<[f64; 3]>,
    /// Where translucent objects dim the glow: B behind them undimmed (up to the first opaque surface), what the
    /// glow's edge fades by (`compose_frame`); empty elsewhere.
    pub undimmed: Vec<f64>,
}

/// Integrates B and the tint for every texel of the frame's billboard (METHOD.md section 3). Where the scene has
/// translucent objects, the glow inside and behind them is seen through them:
/// `B = B_front + inside (B_exit - B_front) + behind (B - B_exit)`, the texel's glow up to the first surface of
/// any object, up to the last translucent surface it crosses and up to the first opaque one, blended by the
/// shares of the glow inside and behind that reach the eye (`objects::clip::crossings`); the tint alike.
pub fn render_brightness(setup: &FrameSetup) -> BrightnessTexture {
    let behind = render_clipped(setup, None);
    if !setup.translucent() {
        return behind;
    }
    let x = crate::objects::clip::crossings(
        &setup.scene.objects,
        setup.clip_objects(),
        (&setup.scene.sources, setup.integration.epsilon),
        setup.eye(),
        &setup.billboard,
        setup.reach,
        setup.resolution,
    )
    .expect("translucent objects");
    let exits: Vec<f64> = x.chunks_exact(3).map(|c| c[0]).collect();
    let front = render_clipped(&setup.front(), None);
    let exit = render_clipped(setup, Some(&exits));
    see_through([&front, &exit, &behind], &x)
}

/// `front + inside (exit - front) + behind (behind_field - exit)`, texel by texel, B and tint, with each
/// texel's shares `crossings[3 k + 1]` and `[3 k + 2]` (`objects::clip::crossings`).
pub fn see_through(
    [front, exit, behind]: [&BrightnessTexture; 3],
    crossings: &[f64],
) -> BrightnessTexture {
    let n = crossings.len() / 3;
    let mix = |k: usize, a: f64, x: f64, b: f64| {
        a + crossings[3 * k + 1] * (x - a) + crossings[3 * k + 2] * (b - x)
    };
    BrightnessTexture {
        resolution: behind.resolution,
        values: (0..n)
            .map(|k| mix(k, front.values[k], exit.values[k], behind.values[k]))
            .collect(),
        tint: (0..n)
            .map(|k| {
                std::array::from_fn(|c| {
                    mix(k, front.tint[k][c], exit.tint[k][c], behind.tint[k][c])
                })
            })
            .collect(),
        undimmed: behind.values.clone(),
    }
}

/// The texture of `setup`, each texel's ray ending at its own surface, or at `clips[k]` where given: refined in
/// image space as `setup.refine` says (`refine`), the GPU's levels and decisions, or every texel integrated.
fn render_clipped(setup: &FrameSetup, clips: Option<&[f64]>) -> BrightnessTexture {
    let w = setup.resolution;
    let exact = |i: u32, j: u32| {
        let clip = clips.map(|c| c[(j * w + i) as usize]);
        let ray = texel_ray_clipped(setup, i, j, clip);
        if ray.hidden {
            return [0.0; 4];
        }
        let b = brightness(&setup.scene.sources, &ray.settings, ray.s, ray.e, ray.xi);
        let t = tint_of(setup, &ray.settings, (ray.s, ray.e), ray.xi);
        [b, t[0], t[1], t[2]]
    };
    let refined = (setup.refine.tolerance()).zip(setup.refine.levels(w));
    let values: Vec<[f64; 4]> = match refined {
        Some((tolerance, levels)) => {
            let edges: Option<Vec<f32>> = match clips {
                Some(c) => Some(c.iter().map(|&c| c as f32).collect()),
                None => setup.clips().map(|c| c.to_vec()),
            };
            super::refine::refine_clipped(&levels, tolerance, edges.as_deref(), exact).values
        }
        None => {
            let n = (w as usize) * (w as usize);
            (0..n)
                .into_par_iter()
                .map(|k| exact(k as u32 % w, k as u32 / w))
                .collect()
        }
    };
    BrightnessTexture {
        resolution: w,
        values: values.iter().map(|v| v[0]).collect(),
        tint: values.iter().map(|v| [v[1], v[2], v[3]]).collect(),
        undimmed: Vec::new(),
    }
}

/// B of a single texel, for tests that probe one ray.
pub fn texel_brightness(setup: &FrameSetup, i: u32, j: u32) -> f64 {
    let ray = texel_ray(setup, i, j);
    if ray.hidden {
        return 0.0;
    }
    brightness(&setup.scene.sources, &ray.settings, ray.s, ray.e, ray.xi)
}

/// A texel's ray and what its integral needs.
struct ClippedRay {
    s: DVec3,
    e: DVec3,
    xi: f64,
    settings: Integration,
    /// A surface lies between the eye and the billboard: the texel shows no glow.
    hidden: bool,
}

/// The ray of texel `(i, j)` of the frame, up to the first surface of the scene's objects (`objects::clip`, in
/// f64 at the texel itself): the shortened ray with the decay mapped onto it.
fn texel_ray(setup: &FrameSetup, i: u32, j: u32) -> ClippedRay {
    texel_ray_clipped(setup, i, j, None)
}

/// `texel_ray`, its clip `clip` where given.
fn texel_ray_clipped(setup: &FrameSetup, i: u32, j: u32, clip: Option<f64>) -> ClippedRay {
    let (w, eye, reach) = (setup.resolution, setup.eye(), setup.reach);
    let s: DVec3 = setup.billboard.texel_center(i, j, w);
    let e = ray_end(s, eye, reach.nu);
    let xi = (setup.integration.jitter).map_or(0.5, |seed| jitter_offset(seed, i, j, w));
    let settings = setup.integration.clone();
    let c = clip.unwrap_or_else(|| clip_fraction(setup.clip_objects(), eye, s, reach.nu));
    if c < 1.0 && c > 0.0 {
        return ClippedRay {
            s,
            e: s + (e - s) * c,
            xi,
            settings: settings.on_ray(c),
            hidden: false,
        };
    }
    ClippedRay {
        s,
        e,
        xi,
        settings,
        hidden: c <= 0.0,
    }
}
