//! The adaptive integrator's curve chains, the f64 twin of `shaders/adaptive_curves.wgsl` (entry point
//! `integrate_adaptive_curves`): the chain's closest approaches and kinks from a scan along the ray (its nearest
//! point's jumps, its ends, joints and W's knots), cuts there, and Gauss-Kronrod pairs on the pieces between them
//! (`super::adaptive`, whose module text describes the method).

//!
//! `scan` finds a chain's features along the ray, `kinks` where its nearest or brightest point jumps; this file
//! integrates a chain's term on the pieces they cut.

mod kinks;
mod scan;

use std::cell::Cell;

use glam::DVec3;

use super::adaptive::{Features, Kinks, integrate_pieces, peak, share_ray};
use crate::field::{Curve, Sources, brightest, curve, falloff, wseries};
use crate::integrate::adaptive::{MAX_PEAKS, SCAN, kink_bracket, kronrod_order};
use crate::integrate::{Decay, Integration, zeta};
use kinks::BrightSample;
use scan::{bright_kinks, chain_features, split_at_switch};

/// The features of a chain along `s -> e` (at most `MAX_PEAKS`), sorted along the ray, each owning its piece,
/// and its kinks: those of its nearest point, or in the continuous W form (`pieces` not empty) those of its
/// brightest point (`bright_kinks`).
fn features(
    c: &Curve,
    pieces: &[brightest::Piece],
    s: DVec3,
    e: DVec3,
    (scan, eps, bracket): (u32, f64, f64),
) -> Features {
    let dir = e - s;
    let mut out = [peak(0.0, 0.0, 0.0, eps); MAX_PEAKS];
    let mut kinks = Kinks::default();
    let nearest_kinks = pieces.is_empty();
    let (found, count) = chain_features(c, s, dir, (scan, eps, bracket, nearest_kinks), &mut kinks);
    if !nearest_kinks {
        let sample = |t: f64| BrightSample::at(pieces, s, dir, t, eps);
        bright_kinks(&sample, pieces, bracket, &mut kinks);
    }
    out[..count].copy_from_slice(&found[..count]);
    share_ray(&mut out[..count]);
    Features {
        peaks: out,
        count,
        kinks,
    }
}

/// One chain's part of B along `s -> e` within `tolerance`, on the pieces of its features, cut at its kinks.
fn integrate_term(c: &Curve, s: DVec3, e: DVec3, settings: &Integration, tolerance: f64) -> f64 {
    let power = settings.power();
    let integral = integrate_weighted(c, s, e, settings, tolerance, &|t| {
        wseries::evaluate(&c.weights, t).powi(power)
    });
    settings.finish(integral, c.coefficient)
}

/// A chain's term to the decay's power without its W series, times `weight(t)` at the point the term reads:
/// the integral of `(b falloff zeta)^power weight(t)` along `s -> e` within `tolerance` on B, on the same features
/// and cuts whatever the weight (as `simpson::curve_weighted`).
fn integrate_weighted(
    c: &Curve,
    s: DVec3,
    e: DVec3,
    settings: &Integration,
    tolerance: f64,
    weight: &dyn Fn(f64) -> f64,
) -> f64 {
    if c.coefficient == 0.0 {
        return 0.0;
    }
    let order = kronrod_order(settings.tolerance);
    let pieces = c.pieces();
    let found = features(
        c,
        &pieces,
        s,
        e,
        (SCAN, settings.epsilon, kink_bracket(order)),
    );
    let dir = e - s;
    let cp = &c.control_points;
    // A chain's nearest point stays on one segment between cuts, or passes a joint continuously: each cut
    // piece starts with a whole-chain search, at its first node, and then solves that segment only.
    // A safety net behind the cuts: where the nearest points at a part's two ends lie on different segments, a
    // jump was missed (the kink search can lose a branch that starts at rest), and the part is split where the
    // segment changes and solved on the whole chain at every node (`split_at_switch`).
    let segment = Cell::new(None);
    let tracking = Cell::new(true);
    // So is every part of a chain with a segment at rest at an end (`curve::is_degenerate`): the shader's
    // tracking loses the nearest point there.
    let degenerate = curve::is_degenerate(cp);
    // In the continuous form every node searches the whole chain for its brightest point (the term is continuous,
    // with kinks where that point jumps, cut at by `bright_kinks`).
    let power = settings.power();
    let f = |t: f64| {
        let p = s + dir * t;
        let n = if !pieces.is_empty() {
            brightest::brightest(&pieces, p, settings.epsilon)
        } else if tracking.get() {
            let mut on = segment.get();
            let n = curve::nearest_on_chain_from(cp, p, &mut on);
            segment.set(on);
            n
        } else {
            curve::nearest_on_chain(cp, p)
        };
        (falloff(n.distance, settings.epsilon) * zeta(t, settings.alpha, settings.beta)).powi(power)
            * weight(n.t)
    };
    let rms = (settings.decay == Decay::Rms).then_some(settings.stretch);
    integrate_pieces(
        &found,
        (c.coefficient.powi(power), &f),
        order,
        (tolerance, rms),
        |p, (a, singular_a), (b, singular_b)| {
            let at = |u: f64| s + dir * (p.center + p.width * f64::sinh(u)).clamp(p.lo, p.hi);
            // (Not for a curve that reads its brightest point: its nearest point's segments say nothing of it.)
            let (parts, count, home) = if pieces.is_empty() {
                split_at_switch(|u| curve::nearest_segment_index(cp, at(u)), (a, b))
            } else {
                ([(a, b); 2], 1, None)
            };
            segment.set(home);
            // A part that begins or ends at rest is solved on the whole chain too: its nodes crowd toward the
            // cut, which the shader's tracking of the nearest point does not follow reliably.
            tracking.set(count == 1 && !singular_a && !singular_b && !degenerate);
            (parts, count)
        },
    )
}

/// The curves' part of the brightness B of the segment `s -> e`, each chain within an equal share of the
/// tolerance among all the scene's sources (the points', lines' and tori's are `adaptive_smooth::brightness`).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    let share = settings.term_tolerance(sources.len());
    sources
        .curves
        .iter()
        .map(|c| integrate_term(c, s, e, settings, share))
        .sum()
}

/// Curve `k`'s term to the decay's power times `weight(t)` in the place of its W series (`integrate_weighted`),
/// within its share of the tolerance times `scale` (the weight's largest size against the W series').
pub fn term_weighted(
    sources: &Sources,
    k: usize,
    settings: &Integration,
    (s, e): (DVec3, DVec3),
    weight: &dyn Fn(f64) -> f64,
    scale: f64,
) -> f64 {
    let share = settings.term_tolerance(sources.len()) * scale;
    (sources.curves.get(k)).map_or(0.0, |c| {
        integrate_weighted(c, s, e, settings, share, weight)
    })
}

/// The adaptive integrator's curve chains: `adaptive_curves.wgsl`'s twin.
pub struct AdaptiveCurves;

impl crate::reference::TermIntegrator for AdaptiveCurves {
    /// The part of B of curve `k` alone, as `brightness` integrates it.
    fn term_brightness(
        &self,
        sources: &Sources,
        k: usize,
        settings: &Integration,
        ray: crate::reference::TexelRay,
    ) -> f64 {
        let share = settings.term_tolerance(sources.len());
        (sources.curves.get(k)).map_or(0.0, |c| {
            integrate_term(c, ray.start, ray.end, settings, share)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::testing::assert_within_each_tolerance;
    use super::*;
    use crate::integrate::adaptive::KINK_BRACKET;

    /// An arch, one segment from (-1, 0, 0) over (0, 2, 0) to (1, 0, 0), symmetric about x = 0.
    fn arch() -> Curve {
        Curve {
            control_points: vec![
                DVec3::new(-1.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
            ],
            coefficient: 1.0,
            weights: vec![],
            look: Default::default(),
            color_series: Vec::new(),
            w_form: crate::field::WForm::Nearest,
        }
    }

    #[test]
    fn a_jump_the_racing_nearest_point_nearly_glides_across_is_found() {
        // A wavy chain of seven segments and a ray past it on which the nearest point races toward a jump (near a
        // center of curvature, its parameter's rate 40 times the usual): over a scan of 12 the two ends' average
        // velocity carried it most of the way across the jump, the interval missed by 0.083 (under JUMP), the
        // jump went uncut, and the tracked segment lost the nearest point: B off by 1.75e-2. Where it jumps is
        // found here by brute force, sampling the nearest point densely along the ray.
        let xs = [
            [-3.5, 0.0, 0.3],
            [-3.0, 0.713, 0.229],
            [-2.5, 0.2935, 0.039],
            [-2.0, -0.126, -0.151],
            [-1.5, -0.345, -0.216],
            [-1.0, -0.564, -0.281],
            [-0.5, 0.1135, -0.1125],
            [0.0, 0.791, 0.056],
            [0.5, 0.2125, 0.178],
            [1.0, -0.366, 0.3],
            [1.5, -0.363, 0.173],
            [2.0, -0.36, 0.046],
            [2.5, 0.2145, -0.119],
            [3.0, 0.789, -0.284],
            [3.5, 0.121, -0.279],
        ];
        let c = Curve {
            control_points: xs.iter().map(|&p| DVec3::from_array(p)).collect(),
            ..arch()
        };
        let s = DVec3::new(-1.0961705825666836, -0.6690911348134301, 4.184534772785047);
        let e = DVec3::new(-2.267743719134842, -1.3842072051862018, -4.168534772785051);
        let dir = e - s;
        let n = 200_000;
        let param = |t: f64| curve::nearest_on_chain(&c.control_points, s + dir * t).t;
        let jumps: Vec<f64> = (1..=n)
            .map(|k| k as f64 / n as f64)
            .filter(|&t| (param(t) - param(t - 1.0 / n as f64)).abs() > 2e-3)
            .collect();
        assert!(
            jumps.iter().any(|&t| (t - 0.0863).abs() < 1e-3),
            "the racing jump: {jumps:?}"
        );
        for scan in [SCAN, 12] {
            let found = features(&c, &[], s, e, (scan, 0.01, KINK_BRACKET));
            let kinks = &found.kinks.at[..found.kinks.count];
            for &jump in &jumps {
                assert!(
                    kinks
                        .iter()
                        .any(|&k| (k - jump).abs() < 2.0 / n as f64 + KINK_BRACKET),
                    "scan {scan}: the jump at {jump} in {kinks:?}"
                );
            }
        }
    }

    #[test]
    fn a_chain_s_kinks_are_found_where_the_nearest_point_jumps_and_at_its_ends() {
        // Under the arch, on x = 0 the two halves are equally near: a ray along x crosses that medial plane at
        // t = 0.5 (a kink, found to second order in its bracket), and the normal planes at the arch's ends, where
        // the nearest point stops at the end: (p - end) . tangent = 0 with tangents (1, 2, 0) at (-1, 0, 0) and
        // (1, -2, 0) at (1, 0, 0). The ray passes under the arch's center of curvature, where the nearest point
        // races along the arch: the search may cut there too (a cut costs work, never accuracy).
        let c = arch();
        let (y, z) = (0.3, 0.2);
        let (s, e) = (DVec3::new(-3.0, y, z), DVec3::new(3.0, y, z));
        let found = features(&c, &[], s, e, (SCAN, 0.01, KINK_BRACKET));
        let kinks = &found.kinks.at[..found.kinks.count];
        let near = |t: f64, within: f64| kinks.iter().any(|&k| (k - t).abs() < within);
        assert!(near(0.5, 1e-5), "the medial crossing: {kinks:?}");
        // The ends' normal planes: x + 2 y = -1 and x - 2 y = 1, at x = -1 - 2 y and 1 + 2 y.
        for x in [-1.0 - 2.0 * y, 1.0 + 2.0 * y] {
            assert!(
                near((x + 3.0) / 6.0, 1e-12),
                "the end plane at x = {x}: {kinks:?}"
            );
        }
        // Far above the arch the nearest point moves smoothly: no kink but the ends'.
        let (s, e) = (DVec3::new(-3.0, 3.0, z), DVec3::new(3.0, 3.0, z));
        let found = features(&c, &[], s, e, (SCAN, 0.01, KINK_BRACKET));
        assert!(
            found.kinks.count <= 2,
            "{:?}",
            &found.kinks.at[..found.kinks.count]
        );
    }

    #[test]
    fn a_beam_seen_end_on_is_integrated_within_the_tolerance() {
        // A straight chain along the view direction, rays along it and nearly so, inside eps and outside. Along
        // the beam the distance is flat (the nearest point moves with the ray); past each end it is the distance
        // to the end point, so the integrand falls off the plateau as a point source's half peak, as narrow as
        // the ray is near the axis. The scan's minimum sits on the flat stretch, where d^2 has no curvature and
        // its map is uniform: only the ends' own maps resolve the fall.
        let sources = Sources {
            curves: vec![Curve {
                control_points: vec![
                    DVec3::new(0.0, 0.0, -3.0),
                    DVec3::new(0.0, 0.0, -3.8),
                    DVec3::new(0.0, 0.0, -5.0),
                ],
                coefficient: 0.4,
                weights: vec![],
                look: Default::default(),
                color_series: Vec::new(),
                w_form: crate::field::WForm::Nearest,
            }],
            ..Default::default()
        };
        let mut rays = Vec::new();
        for x in [0.0, 0.004, 0.0099, 0.02, 0.1, 0.5] {
            let s = DVec3::new(x, 0.3 * x, 0.0);
            rays.push((s, s + DVec3::new(0.0, 0.0, -10.0)));
        }
        // Tilted through the beam's middle, by 1e-3 and 1e-2 radians.
        for tilt in [1e-3, 1e-2] {
            let s = DVec3::new(4.0 * tilt, 0.0, 0.0);
            rays.push((s, s + DVec3::new(-tilt, 0.0, -1.0) * 10.0));
        }
        assert_within_each_tolerance(brightness, &sources, &rays, &[1e-3, 1e-4, 1e-5]);
    }

    #[test]
    fn a_chain_is_integrated_within_the_tolerance_across_its_kinks_and_steps() {
        // The mixed scene's chain: two segments with a W series, so where the nearest point jumps W steps too.
        // Rays from an eye through a grid around it: over the segments, through the medial surfaces, past the
        // ends, one passing closer than eps. Against Simpson with 2^18 intervals (its own error here is under
        // 1e-6: W's steps converge at first order).
        let sources = Sources {
            curves: vec![Curve {
                control_points: vec![
                    DVec3::new(-3.0, 2.0, 0.0),
                    DVec3::new(-1.0, -1.0, 1.0),
                    DVec3::new(1.0, 0.0, 0.0),
                    DVec3::new(3.0, 1.0, -1.0),
                    DVec3::new(3.5, 3.0, 0.0),
                ],
                coefficient: 3.0,
                weights: vec![0.3, 1.0, 0.5, 1.0],
                look: Default::default(),
                color_series: Vec::new(),
                w_form: crate::field::WForm::Nearest,
            }],
            ..Default::default()
        };
        let eye = DVec3::new(0.5, 1.0, 9.0);
        let mut rays: Vec<(DVec3, DVec3)> = (0..7)
            .flat_map(|i| (0..5).map(move |j| (i, j)))
            .map(|(i, j)| {
                let target = DVec3::new(-3.6 + 1.2 * i as f64, -1.5 + 1.0 * j as f64, 0.0);
                (eye, eye + (target - eye) * 2.0)
            })
            .collect();
        // Through the chain's joint, 0.004 off it.
        let joint = DVec3::new(1.0, 0.004, 0.0);
        rays.push((eye, eye + (joint - eye) * 2.0));
        // From the mixed scene's view: the nearest point jumps off the chain's end and then passes the joint
        // continuously, within one interval of the scan (the joint's cut is found after the jump).
        rays.push((
            DVec3::new(1.2128, 3.1659, 4.3950),
            DVec3::new(-1.5744, 1.3317, -6.2100),
        ));
        assert_within_each_tolerance(brightness, &sources, &rays, &[1e-3, 1e-4, 1e-5]);
    }
}
