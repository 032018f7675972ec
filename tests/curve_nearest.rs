//! The nearest point on quadratic Bezier curves and chains, and Cardano's roots, against brute force.

mod common;

use energywave::field::cubic::{solve_cubic, solve_monic_cubic};
use energywave::field::curve::{Segment, nearest_on_chain};
use glam::DVec3;
use proptest::prelude::*;

/// Brute force: the curve sampled at `samples + 1` parameters, then the best sample refined by golden-section
/// search on its two neighbouring intervals. Returns (t, distance).
fn brute_nearest(seg: &Segment, p: DVec3) -> (f64, f64) {
    const SAMPLES: usize = 4000;
    let dist = |t: f64| (seg.at(t) - p).length();
    let mut best = (0.0, dist(0.0));
    for k in 1..=SAMPLES {
        let t = k as f64 / SAMPLES as f64;
        let d = dist(t);
        if d < best.1 {
            best = (t, d);
        }
    }
    let around = (
        (best.0 - 1.0 / SAMPLES as f64).max(0.0),
        (best.0 + 1.0 / SAMPLES as f64).min(1.0),
    );
    let t = common::golden_section_min(dist, around, 100);
    if dist(t) < best.1 { (t, dist(t)) } else { best }
}

fn vec3(range: f64) -> impl Strategy<Value = DVec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// Tolerance of a distance for a curve and point of the given scale: the brute force refines to ~1e-12
/// relative; Cardano plus polishing lands within a few ulps of the true stationary point.
fn tolerance(scale: f64) -> f64 {
    1e-9 * scale.max(1.0)
}

fn check(seg: &Segment, p: DVec3) -> Result<(), TestCaseError> {
    let got = seg.nearest(p);
    let (bt, bd) = brute_nearest(seg, p);
    let scale = seg.c0.length() + seg.c1.length() + seg.c2.length() + p.length();
    prop_assert!((0.0..=1.0).contains(&got.t));
    // The reported distance is the distance of the reported parameter.
    prop_assert!(((seg.at(got.t) - p).length() - got.distance).abs() <= tolerance(scale));
    // Never farther than brute force finds (it may be slightly nearer: brute force is approximate).
    prop_assert!(
        got.distance <= bd + tolerance(scale),
        "cardano {} at t={} vs brute {} at t={}",
        got.distance,
        got.t,
        bd,
        bt
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn random_curves(b0 in vec3(5.0), b1 in vec3(5.0), b2 in vec3(5.0), p in vec3(8.0)) {
        check(&Segment::from_bezier(b0, b1, b2), p)?;
    }

    #[test]
    fn straight_curves(a in vec3(5.0), b in vec3(5.0), f in 0.0..1.0f64, p in vec3(8.0)) {
        // The middle control point on the chord: c2 = 0 exactly when f = 0.5, a non-uniform line otherwise.
        check(&Segment::from_bezier(a, a + (b - a) * f, b), p)?;
    }

    #[test]
    fn nearly_straight_curves(a in vec3(5.0), b in vec3(5.0), bend in vec3(1.0), exp in -12.0..-3.0f64, p in vec3(8.0)) {
        let mid = (a + b) * 0.5 + bend * 10f64.powf(exp);
        check(&Segment::from_bezier(a, mid, b), p)?;
    }

    #[test]
    fn coincident_control_points(a in vec3(5.0), b in vec3(5.0), which in 0..4u8, p in vec3(8.0)) {
        let seg = match which {
            0 => Segment::from_bezier(a, a, b),
            1 => Segment::from_bezier(a, b, b),
            2 => Segment::from_bezier(a, b, a),
            _ => Segment::from_bezier(a, a, a),
        };
        check(&seg, p)?;
    }

    #[test]
    fn points_on_the_curve(b0 in vec3(5.0), b1 in vec3(5.0), b2 in vec3(5.0), t in 0.0..=1.0f64) {
        let seg = Segment::from_bezier(b0, b1, b2);
        let got = seg.nearest(seg.at(t));
        let scale = b0.length() + b1.length() + b2.length();
        prop_assert!(got.distance <= 1e-7 * scale.max(1.0), "distance {} for a point on the curve", got.distance);
    }

    #[test]
    fn chains_take_the_nearest_segment(
        points in prop::collection::vec(vec3(5.0), 5..=9),
        p in vec3(8.0),
    ) {
        let n = if points.len() % 2 == 0 { points.len() - 1 } else { points.len() };
        let cps = &points[..n];
        let k = (n - 1) / 2;
        let got = nearest_on_chain(cps, p);
        // Oracle: brute force over every segment, mapping its local t to (j + t) / k.
        let mut best = (0.0, f64::INFINITY);
        for j in 0..k {
            let seg = Segment::from_bezier(cps[2 * j], cps[2 * j + 1], cps[2 * j + 2]);
            let (t, d) = brute_nearest(&seg, p);
            if d < best.1 {
                best = ((j as f64 + t) / k as f64, d);
            }
        }
        prop_assert!(got.distance <= best.1 + 1e-9 * 30.0);
        prop_assert!((got.distance - best.1).abs() <= 1e-6);
        // Where the nearest point is unique, the chain parameter agrees with brute force.
        let pt = |chain_t: f64| {
            let x = chain_t * k as f64;
            let j = (x.floor() as usize).min(k - 1);
            Segment::from_bezier(cps[2 * j], cps[2 * j + 1], cps[2 * j + 2]).at(x - j as f64)
        };
        prop_assert!(((pt(got.t) - p).length() - got.distance).abs() < 1e-9 * 30.0);
    }

    /// Every root returned is a root: the residual is small against the size of the polynomial's terms.
    #[test]
    fn cardano_residuals(a in -50.0..50.0f64, b in -50.0..50.0f64, c in -50.0..50.0f64) {
        for &x in solve_monic_cubic(a, b, c).as_slice() {
            let residual = ((x + a) * x + b) * x + c;
            let size = x.abs().powi(3) + (a * x * x).abs() + (b * x).abs() + c.abs();
            prop_assert!(residual.abs() <= 1e-10 * size.max(1.0), "x={x} residual={residual}");
        }
    }

    /// No real root in [0, 1] is missed: cubics built from known roots give each of them back.
    #[test]
    fn cardano_finds_known_roots(r in prop::collection::vec(-2.0..2.0f64, 3), lead in prop_oneof![-5.0..-0.1f64, 0.1..5.0f64]) {
        let (a, b, c) = (-(r[0] + r[1] + r[2]), r[0] * r[1] + r[0] * r[2] + r[1] * r[2], -r[0] * r[1] * r[2]);
        let found = solve_cubic(lead, lead * a, lead * b, lead * c, 1e-12);
        for &want in &r {
            // The worst conditioning is a (near) triple root, where roots move with the cube root of rounding.
            let closest = found.as_slice().iter().map(|x| (x - want).abs()).fold(f64::INFINITY, f64::min);
            prop_assert!(closest < 2e-5, "root {want} of {r:?} missed: {:?}", found.as_slice());
        }
    }

    /// On real curves: every sign change of the stationary cubic on [0, 1] has a returned root in it.
    #[test]
    fn stationary_points_are_not_missed(b0 in vec3(5.0), b1 in vec3(5.0), b2 in vec3(5.0), p in vec3(8.0)) {
        let seg = Segment::from_bezier(b0, b1, b2);
        let k = seg.stationary_cubic(p);
        let f = |t: f64| ((k[0] * t + k[1]) * t + k[2]) * t + k[3];
        let roots = solve_cubic(k[0], k[1], k[2], k[3], 1e-12);
        const N: usize = 2000;
        for i in 0..N {
            let (t0, t1) = (i as f64 / N as f64, (i + 1) as f64 / N as f64);
            if f(t0) * f(t1) < 0.0 {
                let hit = roots.as_slice().iter().any(|&x| x >= t0 - 1e-6 && x <= t1 + 1e-6);
                prop_assert!(hit, "no root in [{t0}, {t1}]: {:?}", roots.as_slice());
            }
        }
    }
}

#[test]
fn the_linear_term_includes_p() {
    // METHOD.md's correction: the t coefficient is 2 c2.(c0 - P) + |c1|^2, so moving P changes it.
    let seg = Segment::from_bezier(
        DVec3::ZERO,
        DVec3::new(1.0, 2.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
    );
    let a = seg.stationary_cubic(DVec3::ZERO);
    let b = seg.stationary_cubic(DVec3::new(0.0, 1.0, 0.0));
    assert_ne!(a[2], b[2]);
    // And it is the derivative of the squared distance, checked by finite differences.
    let p = DVec3::new(0.3, 0.7, -0.2);
    let k = seg.stationary_cubic(p);
    for i in 0..=10 {
        let t = i as f64 / 10.0;
        let h = 1e-6;
        let dd = ((seg.at(t + h) - p).length_squared() - (seg.at(t - h) - p).length_squared())
            / (2.0 * h);
        let cubic = ((k[0] * t + k[1]) * t + k[2]) * t + k[3];
        assert!(
            (dd - 2.0 * cubic).abs() < 1e-6,
            "t={t}: {dd} vs {}",
            2.0 * cubic
        );
    }
}
