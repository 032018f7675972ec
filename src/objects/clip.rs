//! Hidden-surface removal, exact: every texel's integral runs from S only to the first surface its ray meets.
//!
//! A texel's ray leaves the eye V through S (on the billboard) and ends at `E = V + nu (S - V)`: with
//! `X(tau) = V + tau (S - V)`, S is at tau = 1 and E at tau = nu. The first surface at `tau_h` keeps the share
//! `c = (tau_h - 1) / (nu - 1)` of S -> E, clamped to [0, 1]: 0 where a surface lies between the eye and the
//! billboard (the texel's glow is hidden entirely), 1 where none lies before E. In the method's s in [0, 1] the
//! clipped integral is the integral over [0, c] with the decay unchanged, which is the whole integral of the
//! shortened ray `S -> S + c (E - S)` with the settings `Integration::on_ray(c)` (the decay mapped onto it as
//! `geometry::Reach` maps it onto a ray of several decay lengths): the integrators run unchanged.

use glam::DVec3;
use rayon::prelude::*;

use super::{Object, first_hit};
use crate::geometry::{Billboard, Reach};

/// The share of the texel ray through `s` (from `eye`, ending at `nu` times `s - eye`) before its first surface.
pub fn clip_fraction(objects: &[Object], eye: DVec3, s: DVec3, nu: f64) -> f64 {
    match first_hit(objects, eye, s - eye, 0.0, nu) {
        None => 1.0,
        Some((_, tau)) => ((tau - 1.0) / (nu - 1.0)).clamp(0.0, 1.0),
    }
}

/// `clip_fraction` for every texel of a `w` x `w` billboard, row-major from the top, on every core; none
/// without objects.
pub fn clip_fractions(
    objects: &[Object],
    eye: DVec3,
    billboard: &Billboard,
    reach: Reach,
    w: u32,
) -> Option<Vec<f64>> {
    if objects.is_empty() {
        return None;
    }
    Some(per_texel(billboard, w, |s| {
        clip_fraction(objects, eye, s, reach.nu)
    }))
}

/// How each texel's ray of a `w` x `w` billboard crosses the translucent objects among `objects`
/// (`translucent::crossing`, its glow ending at the first of `opaque` or the ray's end; `sources` and `epsilon`
/// weigh the glow inside), row-major from the top, three numbers a texel: the share of the ray S -> E before the
/// last translucent surface crossed (the clip of the glow up to it), and the shares of the glow inside and past
/// it that reach the eye. A texel that crosses none has 0, 1, 1. None without translucent objects.
#[allow(clippy::too_many_arguments)]
pub fn crossings(
    objects: &[Object],
    opaque: &[Object],
    (sources, epsilon): (&crate::field::Sources, f64),
    eye: DVec3,
    billboard: &Billboard,
    reach: Reach,
    w: u32,
) -> Option<Vec<f64>> {
    if !objects.iter().any(|o| o.translucent.is_some()) {
        return None;
    }
    let field = sources.field();
    let psi = |p: DVec3| field.psi(p, epsilon);
    let mut out = vec![0.0; 3 * (w as usize) * (w as usize)];
    out.par_chunks_mut(3 * w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, c) in row.chunks_exact_mut(3).enumerate() {
                let s = billboard.texel_center(i as u32, j as u32, w);
                let end = first_hit(opaque, eye, s - eye, 0.0, reach.nu).map_or(reach.nu, |h| h.1);
                let x = super::translucent::crossing(objects, eye, s, end, &psi);
                c.copy_from_slice(&match x {
                    None => [0.0, 1.0, 1.0],
                    Some(x) => [
                        ((x.exit - 1.0) / (reach.nu - 1.0)).clamp(0.0, 1.0),
                        x.inside,
                        x.behind,
                    ],
                });
            }
        });
    Some(out)
}

/// `f` at the center of every texel of a `w` x `w` billboard, row-major from the top, on every core.
fn per_texel(billboard: &Billboard, w: u32, f: impl Fn(DVec3) -> f64 + Sync) -> Vec<f64> {
    let mut out = vec![1.0; (w as usize) * (w as usize)];
    out.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, c) in row.iter_mut().enumerate() {
                *c = f(billboard.texel_center(i as u32, j as u32, w));
            }
        });
    out
}
