//! The W series, the distance functions, psi and the integration, each against an independent oracle.

use energywave::field::{
    Curve, Line, Point, Sources, Torus, line_distance, torus_distance, wseries,
};
use energywave::integrate::{Integration, Integrator, zeta};
use energywave::reference::brightness;
use energywave::reference::simpson::{simpson, simpson_refined};
use glam::DVec3;
use proptest::prelude::*;

/// Cox-de Boor recursion, straight from the definition, with 0/0 taken as 0.
fn cox_de_boor(knots: &[f64], i: usize, p: usize, t: f64) -> f64 {
    if p == 0 {
        // Half-open spans, except that t = 1 belongs to the last non-empty span.
        let last = knots[knots.len() - 1];
        let inside = knots[i] <= t && t < knots[i + 1];
        let at_end = t == last && knots[i] < knots[i + 1] && knots[i + 1] == last;
        return if inside || at_end { 1.0 } else { 0.0 };
    }
    let frac = |num: f64, den: f64| if den == 0.0 { 0.0 } else { num / den };
    frac(t - knots[i], knots[i + p] - knots[i]) * cox_de_boor(knots, i, p - 1, t)
        + frac(knots[i + p + 1] - t, knots[i + p + 1] - knots[i + 1])
            * cox_de_boor(knots, i + 1, p - 1, t)
}

/// The clamped uniform knot vector of METHOD.md section 2, written out literally.
fn knots(n: usize) -> Vec<f64> {
    let mut u = vec![0.0, 0.0, 0.0];
    for i in 1..=(n - 3) {
        u.push(i as f64 / (n - 2) as f64);
    }
    u.extend([1.0, 1.0, 1.0]);
    assert_eq!(u.len(), n + 3);
    u
}

/// The explicit piecewise form of a uniform clamped quadratic B-spline with n weights: on segment
/// `k` of `m = n - 2` (local x in [0, 1]) the blend of w_k, w_{k+1}, w_{k+2} with the standard
/// uniform quadratic weights, modified at the two clamped ends.
fn piecewise(w: &[f64], t: f64) -> f64 {
    let m = w.len() - 2;
    let k = ((t * m as f64).floor() as usize).min(m - 1);
    let x = t * m as f64 - k as f64;
    let (a, b, c) = (w[k], w[k + 1], w[k + 2]);
    if m == 1 {
        // Bezier: Bernstein polynomials.
        return a * (1.0 - x).powi(2) + 2.0 * b * x * (1.0 - x) + c * x * x;
    }
    let (na, nb, nc) = match k {
        0 => ((1.0 - x).powi(2), 2.0 * x - 1.5 * x * x, 0.5 * x * x),
        k if k == m - 1 => (0.5 * (1.0 - x).powi(2), 0.5 + x - 1.5 * x * x, x * x),
        _ => (0.5 * (1.0 - x).powi(2), 0.5 + x - x * x, 0.5 * x * x),
    };
    a * na + b * nb + c * nc
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn wseries_matches_cox_de_boor(w in prop::collection::vec(0.0..2.0f64, 3..12), t in 0.0..=1.0f64) {
        let u = knots(w.len());
        let oracle: f64 = (0..w.len()).map(|i| w[i] * cox_de_boor(&u, i, 2, t)).sum();
        prop_assert!((wseries::evaluate(&w, t) - oracle).abs() < 1e-12);
        // Partition of unity: the basis sums to 1 everywhere.
        let sum: f64 = (0..w.len()).map(|i| cox_de_boor(&u, i, 2, t)).sum();
        prop_assert!((sum - 1.0).abs() < 1e-12);
        prop_assert!((wseries::basis(w.len(), t).iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn wseries_matches_the_explicit_piecewise_quadratic(w in prop::collection::vec(0.0..2.0f64, 3..12), t in 0.0..=1.0f64) {
        prop_assert!((wseries::evaluate(&w, t) - piecewise(&w, t)).abs() < 1e-12);
    }

    #[test]
    fn line_distance_is_the_cross_product_norm(p in prop::array::uniform3(-9.0..9.0f64), m in prop::array::uniform3(-9.0..9.0f64), d in prop::array::uniform3(-1.0..1.0f64)) {
        let d = DVec3::from_array(d);
        prop_assume!(d.length() > 1e-3);
        let d = d.normalize();
        let (p, m) = (DVec3::from_array(p), DVec3::from_array(m));
        prop_assert!((line_distance(p, m, d) - (p - m).cross(d).length()).abs() < 1e-9);
    }

    #[test]
    fn torus_distance_is_the_nearest_point_on_its_circle(
        p in prop::array::uniform3(-5.0..5.0f64),
        c in prop::array::uniform3(-2.0..2.0f64),
        a in prop::array::uniform3(-1.0..1.0f64),
        r in 0.1..3.0f64,
    ) {
        let axis = DVec3::from_array(a);
        prop_assume!(axis.length() > 1e-3);
        let axis = axis.normalize();
        let (p, c) = (DVec3::from_array(p), DVec3::from_array(c));
        // Oracle: the circle sampled densely, then refined around the best sample.
        let e1 = axis.any_orthonormal_vector();
        let e2 = axis.cross(e1);
        let at = |phi: f64| c + r * (phi.cos() * e1 + phi.sin() * e2);
        let n = 20000;
        let (mut best_phi, mut best) = (0.0, f64::INFINITY);
        for k in 0..n {
            let phi = k as f64 / n as f64 * std::f64::consts::TAU;
            let d = (at(phi) - p).length();
            if d < best { best = d; best_phi = phi; }
        }
        let h = std::f64::consts::TAU / n as f64;
        for k in -1000..=1000 {
            let d = (at(best_phi + k as f64 * h / 1000.0) - p).length();
            best = best.min(d);
        }
        let got = torus_distance(p, c, axis, r);
        prop_assert!(got <= best + 1e-9 && best - got < 1e-6, "{got} vs {best}");
    }
}

#[test]
fn wseries_reference_plot_values() {
    // METHOD.md section 2's reference series: ends equal the end weights; w_i governs t ~ i/(n-1).
    let w = [1.0, 0.6, 0.2, 0.4, 0.8, 0.6, 1.0];
    assert_eq!(wseries::evaluate(&w, 1.0), 1.0);
    assert_eq!(wseries::evaluate(&w, 0.0), 1.0);
    // The dip at w_2 = 0.2 is the minimum of the curve near t = 2/6.
    let min_t = (0..=1000)
        .map(|k| k as f64 / 1000.0)
        .min_by(|a, b| wseries::evaluate(&w, *a).total_cmp(&wseries::evaluate(&w, *b)))
        .unwrap();
    assert!((min_t - 2.0 / 6.0).abs() < 0.1, "minimum at {min_t}");
}

#[test]
fn simpson_is_exact_on_cubics() {
    for n in [2, 4, 10, 200] {
        let f = |s: f64| 3.0 * s * s * s - 2.0 * s * s + 0.5 * s - 7.0;
        let exact = 3.0 / 4.0 - 2.0 / 3.0 + 0.25 - 7.0;
        assert!((simpson(f, n) - exact).abs() < 1e-13, "n = {n}");
    }
    // And not on quartics (so the test above is not vacuous): error of s^4 with n = 2 is 1/120.
    assert!((simpson(|s| s.powi(4), 2) - 0.2 - 1.0 / 120.0).abs() < 1e-14);
}

#[test]
fn refined_simpson_reaches_the_closed_form_where_a_fixed_n_does_not() {
    // A ray passing 1e-3 from a point source: the peak of 1/d is narrower than a step of n = 4096.
    let m = DVec3::new(0.001, 0.0, 0.0);
    let sources = Sources {
        points: vec![Point {
            position: m,
            coefficient: 1.0,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    let (s, e) = (DVec3::new(0.0, 0.0, 5.3), DVec3::new(0.0, 0.0, -4.7));
    let f = |t: f64| sources.psi(s + (e - s) * t, 1e-12);
    let exact = point_integral_closed_form(s, e, m);
    let fixed = simpson(f, 4096);
    let (refined, evaluations) = simpson_refined(f, 4096, 1e-9, 28);
    assert!(
        (fixed - exact).abs() > 1e-2 * exact,
        "n = 4096 alone is off: {fixed} vs {exact}"
    );
    assert!(
        (refined - exact).abs() < 1e-8 * exact,
        "{refined} vs {exact} ({evaluations} evaluations)"
    );
    // Only around the peak: far fewer evaluations than a uniform n that small a step would take.
    assert!(evaluations < 20_000, "{evaluations} evaluations");

    // A step (where a curve's nearest point jumps, W does): first order for a fixed n, refined to the end.
    let c = 0.3;
    let step = |t: f64| if t < c { 1.0 } else { 2.0 };
    let (refined, evaluations) = simpson_refined(step, 4096, 1e-9, 28);
    assert!((simpson(step, 4096) - (2.0 - c)).abs() > 1e-5);
    assert!(
        (refined - (2.0 - c)).abs() < 1e-8 && evaluations < 10_000,
        "{refined} ({evaluations} evaluations)"
    );

    // Where n = 4096 has converged, one check of each pair of intervals, and Simpson's value at n = 8192.
    let far = DVec3::new(0.8, 0.0, 0.0);
    let g = |t: f64| 1.0 / (s + (e - s) * t - far).length();
    let (value, evaluations) = simpson_refined(g, 4096, 1e-9, 28);
    assert_eq!(evaluations, 2 * 4096 + 1);
    assert!((value - simpson(g, 8192)).abs() < 1e-12, "{value}");
}

/// `integral_0^1 ds / sqrt(A s^2 + 2 B s + C) = [asinh((A s + B) / sqrt(A C - B^2)) / sqrt(A)]_0^1`.
fn point_integral_closed_form(s: DVec3, e: DVec3, m: DVec3) -> f64 {
    let d = e - s;
    let a = d.length_squared();
    let b = d.dot(s - m);
    let c = (s - m).length_squared();
    let k = (a * c - b * b).sqrt();
    (((a + b) / k).asinh() - (b / k).asinh()) / a.sqrt()
}

#[test]
fn point_source_integral_matches_the_closed_form() {
    let m = DVec3::new(0.3, -0.2, 0.5);
    let sources = Sources {
        points: vec![Point {
            position: m,
            coefficient: 1.0,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    for (s, e) in [
        (DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.1, 0.0, -5.0)),
        (DVec3::new(-1.0, 2.0, 3.0), DVec3::new(2.0, -1.0, -4.0)),
    ] {
        let exact = point_integral_closed_form(s, e, m);
        let mut errors = Vec::new();
        for n in [200, 400, 800] {
            let got = simpson(|t| sources.psi(s + (e - s) * t, 1e-9), n);
            errors.push((got - exact).abs());
        }
        assert!(errors[2] < 1e-7 * exact, "{errors:?} of {exact}");
        // Fourth-order convergence: doubling n divides the error by about 16.
        assert!(
            errors[0] / errors[1] > 12.0 && errors[1] / errors[2] > 12.0,
            "{errors:?}"
        );
    }
}

#[test]
fn brightness_applies_zeta_and_the_coefficient() {
    // With alpha = beta^2 and a huge beta, zeta is 1 to within 2/beta: the closed form again, times the
    // coefficient.
    let m = DVec3::new(0.0, 0.4, 0.0);
    let sources = Sources {
        points: vec![Point {
            position: m,
            coefficient: 2.5,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    let beta = 1e7;
    let settings = Integration {
        integrator: Integrator::Simpson,
        divisions: 2000,
        alpha: beta * beta,
        beta,
        epsilon: 1e-9,
        ..Integration::default()
    };
    let (s, e) = (DVec3::new(0.0, 0.0, 4.0), DVec3::new(0.0, 0.0, -4.0));
    let exact = 2.5 * point_integral_closed_form(s, e, m);
    let got = brightness(&sources, &settings, s, e, 0.5);
    assert!((got - exact).abs() < 1e-6 * exact, "{got} vs {exact}");
    // zeta itself.
    assert_eq!(zeta(0.0, 1.0, 1.0), 1.0);
    assert_eq!(zeta(1.0, 1.0, 1.0), 0.25);
    assert_eq!(zeta(1.0, 3.0, 0.5), 3.0 / 2.25);
}

#[test]
fn psi_is_the_sum_of_the_sources_and_is_clamped_by_epsilon() {
    let point = Point {
        position: DVec3::ZERO,
        coefficient: 2.0,
        look: Default::default(),
    };
    let line = Line {
        point: DVec3::new(0.0, 1.0, 0.0),
        direction: DVec3::X,
        coefficient: -0.5,
        look: Default::default(),
    };
    let torus = Torus {
        center: DVec3::new(0.0, 0.0, 1.0),
        axis: DVec3::Y,
        major_radius: 1.0,
        coefficient: 3.0,
        look: Default::default(),
    };
    let curve = Curve {
        control_points: vec![
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        ],
        coefficient: 1.5,
        weights: vec![],
        look: Default::default(),
        color_series: Vec::new(),
        w_form: energywave::field::WForm::Nearest,
    };
    let all = Sources {
        points: vec![point.clone()],
        lines: vec![line.clone()],
        tori: vec![torus.clone()],
        curves: vec![curve.clone()],
    };
    let p = DVec3::new(0.3, 0.2, -0.7);
    let eps = 0.01;
    let sum = point.field(p, eps) + line.field(p, eps) + torus.field(p, eps) + curve.field(p, eps);
    assert!((all.psi(p, eps) - sum).abs() < 1e-14);
    // Hand-computed terms.
    assert!((point.field(p, eps) - 2.0 / p.length()).abs() < 1e-14);
    assert!((line.field(p, eps) + 0.5 / (0.8f64 * 0.8 + 0.49).sqrt()).abs() < 1e-14);
    // On a source, the term is coefficient / eps, finite.
    assert_eq!(point.field(DVec3::ZERO, eps), 2.0 / eps);
    assert_eq!(torus.field(DVec3::new(1.0, 0.0, 1.0), eps), 3.0 / eps);
    assert!((curve.field(DVec3::new(0.0, 0.5, 0.0), eps) - 1.5 / eps).abs() < 1e-9);
}

#[test]
fn a_chain_is_one_source_with_one_w_series() {
    // Two segments joined smoothly at the origin; W = [0, 1, 0] peaks at the joint (chain t = 0.5).
    let cps = vec![
        DVec3::new(-2.0, 0.0, 0.0),
        DVec3::new(-1.0, 1.0, 0.0),
        DVec3::ZERO,
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
    ];
    let chain = Curve {
        control_points: cps.clone(),
        coefficient: 1.0,
        weights: vec![0.0, 1.0, 0.0],
        look: Default::default(),
        color_series: Vec::new(),
        w_form: energywave::field::WForm::Nearest,
    };
    // With three weights the W series is the Bernstein blend: Sw(t) = 2 t (1 - t) for W = [0, 1, 0].
    let sw = |t: f64| 2.0 * t * (1.0 - t);
    // Near the joint (chain t = 0.5) the field is that of the nearest point alone, Sw(0.5) / d: no doubled
    // glow from the two segments meeting there, as two separate curves would give.
    let p = DVec3::new(0.0, 0.0, 0.3);
    let eps = 1e-3;
    assert!(
        (chain.field(p, eps) - sw(0.5) / 0.3).abs() < 1e-9,
        "{}",
        chain.field(p, eps)
    );
    let separate = |cps: &[DVec3]| Curve {
        control_points: cps.to_vec(),
        coefficient: 1.0,
        weights: vec![],
        look: Default::default(),
        color_series: Vec::new(),
        w_form: energywave::field::WForm::Nearest,
    };
    let doubled = separate(&cps[..3]).field(p, eps) + separate(&cps[2..]).field(p, eps);
    assert!(
        (doubled - 2.0 / 0.3).abs() < 1e-9,
        "two separate curves do double at the joint"
    );
    // The W series runs over the whole chain: a point nearest the middle of the second segment reads
    // Sw((1 + 0.5) / 2) = Sw(0.75).
    let seg2_mid = 0.25 * cps[2] + 0.5 * cps[3] + 0.25 * cps[4];
    let q = seg2_mid + DVec3::new(0.0, 0.0, 0.5);
    let expected = sw(0.75) / 0.5;
    assert!(
        (chain.field(q, eps) - expected).abs() < 1e-9,
        "{} vs {expected}",
        chain.field(q, eps)
    );
    assert!(chain.field(cps[0] + DVec3::new(-0.5, 0.0, 0.0), eps).abs() < 1e-12);
}

#[test]
fn the_adaptive_integrator_matches_the_closed_form_however_sharp_the_peak() {
    // zeta = alpha / (s + beta)^2 is 1 within 2e-7 for alpha = beta^2, beta = 1e7: the closed form applies.
    let beta = 1e7;
    let settings = Integration {
        integrator: Integrator::Adaptive,
        tolerance: 1e-7,
        alpha: beta * beta,
        beta,
        epsilon: 1e-9,
        ..Integration::default()
    };
    let (s, e) = (DVec3::new(0.0, 0.0, 4.0), DVec3::new(0.0, 0.0, -4.0));
    for miss in [1.0, 0.1, 1e-2, 1e-4] {
        let m = DVec3::new(miss, 0.0, 0.7);
        let sources = Sources {
            points: vec![Point {
                position: m,
                coefficient: 2.5,
                look: Default::default(),
            }],
            ..Sources::default()
        };
        let exact = 2.5 * point_integral_closed_form(s, e, m);
        let got = brightness(&sources, &settings, s, e, 0.5);
        assert!(
            (got - exact).abs() < 1e-5 * exact,
            "miss {miss}: {got} vs {exact}"
        );
        // Where uniform samples fall apart: 201 samples 0.04 apart cannot see a peak 1e-4 wide.
        if miss == 1e-4 {
            let uniform = Integration {
                integrator: Integrator::Simpson,
                divisions: 200,
                ..settings.clone()
            };
            let simpson = brightness(&sources, &uniform, s, e, 0.5);
            assert!(
                (simpson - exact).abs() > 0.1 * exact,
                "{simpson} vs {exact}"
            );
        }
    }
}
