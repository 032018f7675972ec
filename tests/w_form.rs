//! The continuous W form of a curve's term (`field::brightest`): the chain's brightest point seen from P,
//! `b max_t Sw(t) / max(eps, |P - C(t)|)`, against a brute-force search of the chain; continuous where the papers'
//! form has its seam; the papers' term wherever W is uniform; both integrators within their promises on it, the GPU
//! against the f64 twin; and the scene key `w_form`.

mod common;

use energywave::field::curve::chain_frame;
use energywave::field::{Curve, Look, Sources, WForm, brightest, wseries};
use energywave::frame::FrameSetup;
use glam::DVec3;

use common::Lcg;

/// The continuous term's value `Sw(t) / max(eps, |p - C(t)|)` at chain parameter t.
fn value_at(cps: &[DVec3], weights: &[f64], p: DVec3, eps: f64, t: f64) -> f64 {
    wseries::evaluate(weights, t) / (chain_frame(cps, t).0 - p).length().max(eps)
}

/// Brute force: the chain sampled at 40000 + 1 parameters, then each of the best few local maxima refined by
/// golden-section search between its neighbours. Independent of the pieces, the quartic and its roots.
fn brute_brightest(cps: &[DVec3], weights: &[f64], p: DVec3, eps: f64) -> f64 {
    const SAMPLES: usize = 40_000;
    let g = |t: f64| value_at(cps, weights, p, eps, t);
    let values: Vec<f64> = (0..=SAMPLES)
        .map(|k| g(k as f64 / SAMPLES as f64))
        .collect();
    let mut maxima: Vec<usize> = (0..=SAMPLES)
        .filter(|&k| {
            (k == 0 || values[k] >= values[k - 1]) && (k == SAMPLES || values[k] >= values[k + 1])
        })
        .collect();
    maxima.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let mut best = values.iter().copied().fold(f64::MIN, f64::max);
    for &k in maxima.iter().take(6) {
        let step = 1.0 / SAMPLES as f64;
        let around = (
            (k as f64 * step - step).max(0.0),
            (k as f64 * step + step).min(1.0),
        );
        best = best.max(g(common::golden_section_min(|t| -g(t), around, 200)));
    }
    best
}

/// A random chain of 1 to 3 segments in a box of side 6, and a W series of 0, 3 to 9 weights: in [0, 1.5], or
/// one time in three a travelling pulse's lit lump with dark (zero) weights around it, where S has a double zero
/// at a knot.
fn random_chain(rng: &mut Lcg) -> (Vec<DVec3>, Vec<f64>) {
    let k = 1 + (rng.unit() * 3.0) as usize;
    let cps: Vec<DVec3> = (0..2 * k + 1).map(|_| rng.vec(3.0)).collect();
    let n = [0, 3, 4, 5, 7, 9][(rng.unit() * 6.0) as usize];
    let weights = if rng.unit() < 1.0 / 3.0 {
        let lump = rng.range(0.0, n as f64);
        (0..n)
            .map(|i| (1.0 - (i as f64 - lump).abs() / 1.5).max(0.0))
            .collect()
    } else {
        (0..n).map(|_| rng.range(0.0, 1.5)).collect()
    };
    (cps, weights)
}

#[test]
fn the_brightest_point_is_the_largest_of_the_term_over_the_whole_chain() {
    let mut rng = Lcg(0x5eed);
    let eps = 0.01;
    let mut checked = 0;
    let mut within_eps = 0;
    for _ in 0..120 {
        let (cps, weights) = random_chain(&mut rng);
        let pieces = brightest::pieces(&cps, &weights);
        for q in 0..12 {
            // Points anywhere, near the chain, and closer than eps to it.
            let p = match q % 3 {
                0 => rng.vec(5.0),
                1 => chain_frame(&cps, rng.unit()).0 + rng.vec(0.2),
                _ => chain_frame(&cps, rng.unit()).0 + rng.vec(0.004),
            };
            let got = brightest::brightest(&pieces, p, eps);
            let (point, ..) = chain_frame(&cps, got.t);
            assert!(
                ((point - p).length() - got.distance).abs() <= 1e-9 * (1.0 + got.distance),
                "the distance reported is the point's"
            );
            let value = value_at(&cps, &weights, p, eps, got.t);
            let want = brute_brightest(&cps, &weights, p, eps);
            assert!(
                (value - want).abs() <= 1e-9 * want.max(1.0),
                "{cps:?} {weights:?} at {p}: search {value} at t = {}, brute force {want}",
                got.t
            );
            within_eps += usize::from(got.distance < eps);
            checked += 1;
        }
    }
    assert_eq!(checked, 1440);
    // The flat top (closer than eps) was reached often enough to be tested.
    assert!(
        within_eps > 100,
        "{within_eps} searches ended closer than eps"
    );
}

/// The papers' preset of figure 12: b = 8, W = [1.0, 0.2, 0.6, 1.0, 0.5, 0.8, 1.0] on two joined segments.
fn figure_12(form: WForm) -> Curve {
    Curve {
        control_points: vec![
            DVec3::new(-3.0, -1.0, -1.0),
            DVec3::new(-1.5, 1.5, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.5, -1.5, 0.0),
            DVec3::new(3.0, 1.0, 1.0),
        ],
        coefficient: 8.0,
        weights: vec![1.0, 0.2, 0.6, 1.0, 0.5, 0.8, 1.0],
        look: Look::default(),
        color_series: Vec::new(),
        w_form: form,
    }
}

#[test]
fn the_continuous_form_has_no_seam_where_the_papers_form_jumps() {
    // Along lines through the chain's medial surfaces, the papers' term jumps (the nearest point leaves one part of
    // the chain for another, and W differs between them); the continuous term moves by no more than its slope
    // allows. Slope bound: the term is the largest of functions of P whose gradients are bounded by
    // b max W / max(eps, d)^2, d the distance to the chain.
    let eps = 0.01;
    let (nearest, continuous) = (figure_12(WForm::Nearest), figure_12(WForm::Continuous));
    let mut rng = Lcg(7);
    let mut seams = 0;
    for _ in 0..60 {
        let a = rng.vec(4.0);
        let b = rng.vec(4.0);
        let steps = 4000;
        let step = (b - a).length() / steps as f64;
        let mut last: Option<(f64, f64)> = None;
        for k in 0..=steps {
            let p = a + (b - a) * (k as f64 / steps as f64);
            let (fn_, fc) = (nearest.field(p, eps), continuous.field(p, eps));
            // Never darker than the papers' term: the nearest point is one of the candidates.
            assert!(fc >= fn_ * (1.0 - 1e-12), "{p}: {fc} < {fn_}");
            let d = energywave::field::curve::nearest_on_chain(&nearest.control_points, p).distance;
            let slope = 8.0 * 1.0 / (d - step).max(eps).powi(2);
            if let Some((ln, lc)) = last {
                assert!(
                    (fc - lc).abs() <= 1.5 * slope * step,
                    "{p}: the continuous term jumps from {lc} to {fc}"
                );
                seams += usize::from((fn_ - ln).abs() > 3.0 * slope * step);
            }
            last = Some((fn_, fc));
        }
    }
    // The lines did cross the papers' seam.
    assert!(seams > 20, "{seams} jumps of the papers' term");
}

#[test]
fn with_a_uniform_w_series_the_continuous_form_is_the_papers_term_to_the_bit() {
    let mut rng = Lcg(11);
    for weights in [vec![], vec![0.7], vec![0.4, 0.4, 0.4, 0.4]] {
        let make = |form| Curve {
            w_form: form,
            weights: weights.clone(),
            ..figure_12(form)
        };
        let (nearest, continuous) = (make(WForm::Nearest), make(WForm::Continuous));
        assert!(!continuous.searches());
        for _ in 0..200 {
            let p = rng.vec(4.0);
            assert_eq!(nearest.field(p, 0.01), continuous.field(p, 0.01));
        }
        // And the search, where it is asked for all the same, finds the same value.
        let pieces = brightest::pieces(&continuous.control_points, &[0.4, 0.4, 0.4, 0.4]);
        for _ in 0..200 {
            let p = rng.vec(4.0);
            let got = brightest::brightest(&pieces, p, 0.01);
            let want = energywave::field::curve::nearest_on_chain(&continuous.control_points, p);
            assert!((got.distance.max(0.01) - want.distance.max(0.01)).abs() < 1e-12);
        }
    }
}

#[test]
fn sources_evaluate_the_continuous_form_alike_prepared_or_not() {
    let sources = Sources {
        curves: vec![figure_12(WForm::Continuous)],
        ..Sources::default()
    };
    let field = sources.field();
    let mut rng = Lcg(3);
    for _ in 0..100 {
        let p = rng.vec(4.0);
        assert_eq!(field.psi(p, 0.01), sources.psi(p, 0.01));
        assert_eq!(field.term(0, p, 0.01), sources.curves[0].field(p, 0.01));
    }
}

use std::sync::{Mutex, MutexGuard, OnceLock};

use energywave::gpu::HeadlessRenderer;
use energywave::integrate::{Integrator, zeta};
use energywave::reference;
use energywave::reference::simpson::simpson_refined;
use energywave::scene::Scene;

fn gpu() -> MutexGuard<'static, HeadlessRenderer> {
    static GPU: OnceLock<Mutex<HeadlessRenderer>> = OnceLock::new();
    GPU.get_or_init(|| Mutex::new(HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)")))
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// The scenes with a curve in the continuous form: the shipped ones that have it by default, the figure-12 preset
/// switched to it, and a beam seen end on (its rays run inside the flat top along the whole beam).
fn continuous_scenes() -> Vec<(String, Scene)> {
    let mut out: Vec<(String, Scene)> = ["default.toml", "mixed.toml", "beam_end_on.toml"]
        .iter()
        .map(|&n| (n.to_owned(), common::shipped_scene(n)))
        .collect();
    // The pulse halfway along the chain, and a quarter of the way (the still file has no W series).
    for frame in [0.0, 23.0] {
        let scene = common::shipped_scene("pulse_travelling.toml").at_frame(frame);
        out.push((format!("pulse_travelling.toml at frame {frame}"), scene));
    }
    // A chain in the continuous form beside one in the papers' form: the passes then hold both ways of reading a
    // chain (FieldParams::search 1), where every other scene here reads all its chains by the search (2).
    let mut both = common::shipped_scene("default.toml");
    let mut papers = both.sources.curves[0].clone();
    papers.weights = vec![0.8, 0.4, 1.0];
    papers.w_form = WForm::Nearest;
    papers.control_points.iter_mut().for_each(|p| p.y += 1.5);
    both.sources.curves.push(papers);
    out.push((
        "default.toml with a chain in the papers' form".to_owned(),
        both,
    ));
    let mut figure = common::shipped_scene("local_intensity_w_b8.0.toml");
    figure.sources.curves[0].w_form = WForm::Continuous;
    out.push(("local_intensity_w_b8.0.toml, continuous".to_owned(), figure));
    for (name, scene) in &out {
        assert!(
            scene.sources.curves.iter().any(Curve::searches),
            "{name} has a curve in the continuous form"
        );
    }
    out
}

#[test]
fn the_gpu_matches_its_f64_twin_on_the_continuous_form_with_both_integrators() {
    // Relative to max(|B|, 0.01), as tests/integrators.rs holds the twins on the papers' form.
    let mut g = gpu();
    for (name, mut scene) in continuous_scenes() {
        scene.animation = None;
        scene.billboard.resolution = 32;
        for integrator in [Integrator::Simpson, Integrator::Adaptive] {
            scene.integration.integrator = integrator;
            scene.integration.jitter = None;
            let bb = scene.place_billboard(1.0);
            let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
            let cpu_b = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
            let worst = (gpu_b.iter().zip(&cpu_b))
                .map(|(&x, &y)| (x as f64 - y).abs() / y.abs().max(0.01))
                .fold(0.0, f64::max);
            eprintln!(
                "{name}, {}: worst GPU against CPU {worst:.2e}",
                integrator.name()
            );
            assert!(
                worst <= 1.5e-4,
                "{name}, {}: {worst:.2e}",
                integrator.name()
            );
            assert!(cpu_b.iter().any(|&b| b > 0.05), "{name} shows something");
        }
    }
}

#[test]
fn the_gpu_meets_a_tight_tolerance_on_the_continuous_form_within_its_loop_budget() {
    // At 1e-6 the adaptive pass refines far more, and every search runs inside lavapipe's budget of 65535 loop
    // iterations per invocation: a walk that overran it once stopped silently and left texels far off. The GPU
    // within the tolerance of its f64 twin (itself within the tolerance of the converged value, tested below)
    // and f32's rounding of the sum.
    let mut g = gpu();
    for (name, mut scene) in continuous_scenes() {
        scene.animation = None;
        scene.billboard.resolution = 24;
        scene.integration.integrator = Integrator::Adaptive;
        scene.integration.jitter = None;
        scene.integration.tolerance = 1e-6;
        let bb = scene.place_billboard(1.0);
        let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let cpu_b = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let worst = (gpu_b.iter().zip(&cpu_b))
            .map(|(&x, &y)| (x as f64 - y).abs() / (2e-6 + 4e-6 * y.abs()))
            .fold(0.0, f64::max);
        eprintln!("{name}: worst GPU against CPU {worst:.2} of the allowance");
        assert!(worst <= 1.0, "{name}: {worst:.2} of the allowance");
    }
}

#[test]
fn the_adaptive_integrator_meets_its_tolerance_on_the_continuous_form() {
    // The f64 twin against Simpson refined to convergence, on every third texel, from a loose to a tight
    // tolerance: the term turns a corner wherever the brightest point jumps, which the cuts at those jumps resolve.
    use energywave::geometry::ray_end;
    for (name, mut scene) in continuous_scenes() {
        scene.animation = None;
        scene.billboard.resolution = 24;
        scene.integration.integrator = Integrator::Adaptive;
        let bb = scene.place_billboard(1.0);
        let reach = FrameSetup::new(&scene, bb).reach;
        for tolerance in [1e-3, 1e-4, 1e-5, 1e-6] {
            scene.integration.tolerance = tolerance;
            let settings = scene.integration.on_ray(reach.stretch);
            let field = scene.sources.field();
            let mut worst: f64 = 0.0;
            for k in (0..24 * 24).step_by(3) {
                let (i, j) = ((k % 24) as u32, (k / 24) as u32);
                let s = bb.texel_center(i, j, 24);
                let e = ray_end(s, scene.camera.eye, reach.nu);
                let got = reference::brightness(&scene.sources, &settings, s, e, 0.5);
                let f = |t: f64| {
                    field.psi(s + (e - s) * t, settings.epsilon)
                        * zeta(t, settings.alpha, settings.beta)
                };
                let (want, _) = simpson_refined(f, 4000, 1e-3 * tolerance, 30);
                worst = worst.max((got - want).abs() / tolerance);
            }
            eprintln!("{name}, tolerance {tolerance:e}: worst error {worst:.3} of the tolerance");
            assert!(
                worst <= 1.0,
                "{name}, tolerance {tolerance:e}: {worst:.3} of the tolerance"
            );
        }
    }
}

#[test]
fn the_gpu_meets_its_tolerance_on_the_papers_form_where_rays_pass_the_segments_centers_of_curvature()
 {
    // Figure 12's preset in its own (the papers') form at 256 x 256: some rays pass inside a segment's evolute,
    // where the segment's stationary cubic has three roots and its nearest point jumps from one to another within
    // the segment, sometimes inside a scan interval that does not show it. The GPU carried the nearest point by
    // Newton from node to node and followed the overtaken local minimum: B 1.3e-3 low at 23 texels (the f64
    // twin solves each node in closed form and did not). Checked against the converged integral (Simpson refined)
    // where the GPU is farthest from its twin.
    use energywave::geometry::ray_end;
    let mut scene = common::shipped_scene("local_intensity_w_b8.0.toml");
    let w = 256;
    scene.billboard.resolution = w;
    scene.integration.integrator = Integrator::Adaptive;
    scene.integration.jitter = None;
    let tolerance = scene.integration.tolerance;
    let bb = scene.place_billboard(1.0);
    let setup = FrameSetup::new(&scene, bb);
    let gpu_b = gpu().brightness(&setup).unwrap();
    let cpu_b = reference::render_brightness(&setup).values;
    let mut order: Vec<usize> = (0..gpu_b.len()).collect();
    order.sort_by(|&a, &b| {
        let off = |k: usize| (gpu_b[k] as f64 - cpu_b[k]).abs();
        off(b).total_cmp(&off(a))
    });
    let settings = scene.integration.on_ray(setup.reach.stretch);
    let field = scene.sources.field();
    for &k in &order[..8] {
        let (i, j) = ((k % w as usize) as u32, (k / w as usize) as u32);
        let s = bb.texel_center(i, j, w);
        let e = ray_end(s, scene.camera.eye, setup.reach.nu);
        let f = |t: f64| {
            field.psi(s + (e - s) * t, settings.epsilon) * zeta(t, settings.alpha, settings.beta)
        };
        let (want, _) = simpson_refined(f, 4000, 1e-3 * tolerance, 30);
        let off = (gpu_b[k] as f64 - want).abs();
        eprintln!(
            "texel ({i}, {j}): B {want:.5}, GPU off by {off:.2e}, twin by {:.2e}",
            (cpu_b[k] - want).abs()
        );
        assert!(
            off <= tolerance,
            "texel ({i}, {j}): B {want}, the GPU off by {off:.2e}"
        );
    }
}

/// The brightest point by brute force (2000 samples, the best three local maxima refined by golden section):
/// its chain parameter and distance.
fn brute_point(cps: &[DVec3], weights: &[f64], p: DVec3, eps: f64) -> (f64, f64) {
    const SAMPLES: usize = 2000;
    let g = |t: f64| value_at(cps, weights, p, eps, t);
    let values: Vec<f64> = (0..=SAMPLES)
        .map(|k| g(k as f64 / SAMPLES as f64))
        .collect();
    let mut maxima: Vec<usize> = (0..=SAMPLES)
        .filter(|&k| {
            (k == 0 || values[k] >= values[k - 1]) && (k == SAMPLES || values[k] >= values[k + 1])
        })
        .collect();
    maxima.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let mut best = (f64::MIN, 0.0);
    for &k in maxima.iter().take(3) {
        let step = 1.0 / SAMPLES as f64;
        let around = (
            (k as f64 * step - step).max(0.0),
            (k as f64 * step + step).min(1.0),
        );
        for t in [
            k as f64 * step,
            common::golden_section_min(|t| -g(t), around, 80),
        ] {
            if g(t) > best.0 {
                best = (g(t), t);
            }
        }
    }
    (best.1, (chain_frame(cps, best.1).0 - p).length())
}

/// Cox-de Boor's recursion for a quadratic B-spline over the clamped uniform knots (METHOD.md section 2), written
/// apart from `wseries`'s triangular scheme; one value is a constant, two a line.
fn cox_de_boor(values: &[f64], t: f64) -> f64 {
    let n = values.len();
    match n {
        1 => return values[0],
        2 => return values[0] + (values[1] - values[0]) * t,
        _ => {}
    }
    let knot = |i: usize| -> f64 {
        if i <= 2 {
            0.0
        } else if i >= n {
            1.0
        } else {
            (i - 2) as f64 / (n - 2) as f64
        }
    };
    fn basis(i: usize, k: usize, t: f64, knot: &dyn Fn(usize) -> f64, n: usize) -> f64 {
        if k == 0 {
            let (a, b) = (knot(i), knot(i + 1));
            // Half-open spans, the last one closed.
            return if (a <= t && t < b) || (t == 1.0 && b == 1.0 && a < b && i == n - 1) {
                1.0
            } else {
                0.0
            };
        }
        let mut out = 0.0;
        let d1 = knot(i + k) - knot(i);
        if d1 > 0.0 {
            out += (t - knot(i)) / d1 * basis(i, k - 1, t, knot, n);
        }
        let d2 = knot(i + k + 1) - knot(i + 1);
        if d2 > 0.0 {
            out += (knot(i + k + 1) - t) / d2 * basis(i + 1, k - 1, t, knot, n);
        }
        out
    }
    (0..n).map(|i| values[i] * basis(i, 2, t, &knot, n)).sum()
}

#[test]
fn a_color_series_in_the_continuous_form_is_the_converged_integral_at_the_brightest_point() {
    // The beam of the rings preset, with a W series and in the continuous form: its tint against the integral of
    // the term times (Cs - Ce), both read at the brightest point found by brute force and Cox-de Boor's series,
    // refined to convergence; on the CPU and the GPU, with both integrators.
    use energywave::geometry::ray_end;
    let mut scene = common::shipped_scene("rings_and_beam.toml");
    scene.animation = None;
    scene.sources.tori.clear();
    let curve = &mut scene.sources.curves[0];
    curve.weights = vec![1.0, 0.25, 0.9, 0.3, 0.8];
    curve.w_form = WForm::Continuous;
    let series = curve.color_series.clone();
    scene.billboard.resolution = 16;
    let mut g = gpu();
    for integrator in [Integrator::Adaptive, Integrator::Simpson] {
        scene.integration.integrator = integrator;
        scene.integration.divisions = 2000;
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb));
        g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let gpu_tint = g.tint().unwrap();
        let (ce, curve) = (scene.colors.energy_color(), &scene.sources.curves[0]);
        let intensity = curve
            .look
            .intensity
            .unwrap_or(scene.colors.energy_intensity);
        let reach = FrameSetup::new(&scene, bb).reach;
        let settings = scene.integration.on_ray(reach.stretch);
        // Simpson with n = 2000 is within this of the converged integral here; the adaptive within its tolerance.
        let tolerance = match integrator {
            Integrator::Adaptive => 2.0 * scene.integration.tolerance,
            Integrator::Simpson => 2e-3,
        };
        for (i, j) in [(8, 8), (5, 9), (11, 6), (3, 12)] {
            let s = bb.texel_center(i, j, 16);
            let e = ray_end(s, scene.camera.eye, reach.nu);
            for ch in 0..3 {
                let channel: Vec<f64> = series.iter().map(|x| x[ch] * intensity).collect();
                let f = |t: f64| {
                    let (tb, d) = brute_point(
                        &curve.control_points,
                        &curve.weights,
                        s + (e - s) * t,
                        settings.epsilon,
                    );
                    curve.coefficient
                        * cox_de_boor(&curve.weights, tb)
                        * (cox_de_boor(&channel, tb) - ce[ch])
                        / d.max(settings.epsilon)
                        * zeta(t, settings.alpha, settings.beta)
                };
                let (want, _) = simpson_refined(f, 400, 1e-9, 24);
                let k = (j * 16 + i) as usize;
                for (twin, got) in [("CPU", cpu.tint[k][ch]), ("GPU", gpu_tint[k][ch] as f64)] {
                    assert!(
                        (got - want).abs() <= tolerance,
                        "{}: {twin} texel ({i}, {j}) channel {ch}: {got} against {want}",
                        integrator.name()
                    );
                }
            }
        }
    }
}

#[test]
fn the_brightest_point_s_motion_is_its_derivative_along_the_ray() {
    // The rate of the brightest point's parameter and the slope of the term's value, which the adaptive integrator's
    // search for jumps predicts with, against central differences away from the jumps.
    let c = figure_12(WForm::Continuous);
    let pieces = brightest::pieces(&c.control_points, &c.weights);
    let mut rng = Lcg(23);
    let mut compared = 0;
    for _ in 0..400 {
        let p = rng.vec(3.0);
        let dir = rng.vec(1.0);
        let h = 1e-6;
        let (b0, bm, bp) = (
            brightest::search(&pieces, p, 0.01),
            brightest::search(&pieces, p - dir * h, 0.01),
            brightest::search(&pieces, p + dir * h, 0.01),
        );
        if (bp.at.t - bm.at.t).abs() > 1e-3 || b0.at.distance < 0.02 {
            continue;
        }
        let (rate, slope) = b0.motion(&pieces, p, dir, 0.01);
        let (num_rate, num_slope) = (
            (bp.at.t - bm.at.t) / (2.0 * h),
            (bp.value - bm.value) / (2.0 * h),
        );
        assert!(
            (rate - num_rate).abs() <= 1e-4 * (1.0 + num_rate.abs()),
            "{p}: rate {rate} vs {num_rate}"
        );
        assert!(
            (slope - num_slope).abs() <= 1e-4 * (1.0 + num_slope.abs()),
            "{p}: slope {slope} vs {num_slope}"
        );
        compared += 1;
    }
    assert!(compared > 300, "{compared}");
}

fn invalid(text: &str) -> String {
    match Scene::parse(text, std::path::Path::new("bad.toml")) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted: {text}"),
    }
}

#[test]
fn the_w_form_in_scene_files() {
    let curve = "[[curves]]\ncontrol_points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0]]\ncoefficient = 1.0\nweights = [1.0, 0.2, 0.8]\n";
    let parse = |extra: &str| {
        Scene::parse(&format!("{curve}{extra}"), std::path::Path::new("s.toml")).unwrap()
    };
    assert_eq!(parse("").sources.curves[0].w_form, WForm::Continuous);
    assert_eq!(
        parse("w_form = \"nearest\"\n").sources.curves[0].w_form,
        WForm::Nearest
    );
    assert_eq!(
        parse("w_form = \"continuous\"\n").sources.curves[0].w_form,
        WForm::Continuous
    );
    let msg = invalid(&format!("{curve}w_form = \"closest\"\n"));
    assert!(
        msg.contains("s.toml:5:") || msg.contains("bad.toml:5:"),
        "the line of the key: {msg}"
    );
    assert!(
        msg.contains("curves[0].w_form")
            && msg.contains("\"continuous\"")
            && msg.contains("\"nearest\""),
        "{msg}"
    );
    // Written back: "nearest" kept, the default left out; each reads back as the scene.
    for (extra, written) in [("w_form = \"nearest\"\n", true), ("", false)] {
        let scene = parse(extra);
        let text = scene.to_toml();
        assert_eq!(text.contains("w_form = \"nearest\""), written, "{text}");
        assert!(!text.contains("continuous"), "{text}");
        assert_eq!(
            Scene::parse(&text, std::path::Path::new("saved.toml")).unwrap(),
            scene
        );
    }
    // The papers' figure keeps the papers' form.
    let figure = common::shipped_scene("local_intensity_w_b8.0.toml");
    assert_eq!(figure.sources.curves[0].w_form, WForm::Nearest);
}

#[test]
fn the_gpu_term_holds_to_the_twin_and_a_brute_force_where_a_pulse_leaves_its_w_series_dark() {
    // A travelling pulse leaves zero weights ahead of its lump and behind it: S has a double zero at the knot where
    // the series goes dark, and h a root at that piece's end, which rounding put on either side of it; the search
    // then missed the maximum beside it (pulse_sparks at frame 0 was 0.16 of B low on Vulkan, and its points near
    // the chain up to 5x low). Point by point, on the GPU's own functions (field_pass::probe), at the shipped
    // scenes whose terms search, at frames across their animations, near the knots and anywhere around the chain:
    // the f64 twin against a brute force that knows nothing of pieces, and the GPU against the twin.
    use energywave::gpu::GpuContext;
    use energywave::gpu::probe::curve_terms;
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = Lcg(0xda4c);
    let mut checked = 0;
    for (name, scene) in common::shipped() {
        let frames = scene.frame_count();
        for frame in [0, frames / 6, frames / 3, frames / 2, 5 * frames / 6] {
            let at = scene.at_frame(frame as f64);
            let setup = FrameSetup::placed(&at, 1.0);
            let eps = setup.integration.epsilon;
            for (i, c) in at.sources.curves.iter().enumerate() {
                if !c.searches() {
                    continue;
                }
                let n = c.weights.len();
                let knots: Vec<f64> = (0..=n - 2).map(|k| k as f64 / (n - 2) as f64).collect();
                let points: Vec<DVec3> = (0..240)
                    .map(|q| {
                        let t = match q % 2 {
                            0 => knots[q / 2 % knots.len()] + rng.range(-0.03, 0.03),
                            _ => rng.unit(),
                        };
                        let scale = [0.02, 0.2, 0.6][q % 3];
                        chain_frame(&c.control_points, t.clamp(0.0, 1.0)).0 + rng.vec(scale)
                    })
                    .map(|p| p.as_vec3().as_dvec3())
                    .collect();
                let gpu = curve_terms(&ctx, &setup, i, &points).expect("probed");
                let pieces = c.pieces();
                for (p, g) in points.iter().zip(&gpu) {
                    let twin = c.term_at(c.point_seen(&pieces, *p, eps), eps);
                    let brute =
                        c.coefficient * brute_brightest(&c.control_points, &c.weights, *p, eps);
                    assert!(
                        (twin - brute).abs() <= 1e-9 * brute.max(1.0),
                        "{name} frame {frame} curve {i} at {p}: the twin's term {twin}, the brute force's {brute}"
                    );
                    // f32 places the point and the chain to about 1e-7 of their size: the distance's error, over
                    // the falloff's distance, is the term's (near an end-on chain at z = 5, within eps: 1.4e-4).
                    let distance = c.point_seen(&pieces, *p, eps).distance;
                    let mut allowed = 1e-5 + 1e-6 * (1.0 + p.length()) / distance.max(eps);
                    if distance <= eps * (1.0 + 1e-9) {
                        // Within eps, on the flat top, the f32 search places the stretch's ends by Newton on
                        // D - eps^2 next to D's minimum, where its slope is all rounding: on the end-on beam at
                        // z = 5 it stopped 5e-4 short in t (6e-4 of the term, over a stretch 0.012 long).
                        allowed = allowed.max(1e-3);
                    }
                    assert!(
                        (g.term as f64 - twin).abs() <= allowed * twin.max(1e-3),
                        "{name} frame {frame} curve {i} at {p}: the GPU's term {} (t {}, distance {}), the twin's {twin} \
                         (t {}, distance {distance})",
                        g.term,
                        g.t,
                        g.distance,
                        c.point_seen(&pieces, *p, eps).t,
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked >= 240 * 5 * 2, "{checked} points checked");
}
