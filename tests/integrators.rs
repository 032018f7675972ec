//! The integrators against independent oracles: the adaptive one on the GPU against the converged f64
//! reference (Simpson from n = 4096, doubled texel by texel until converged) on every shipped scene; jittered
//! sampling unbiased (its mean over seeds converges to the reference, on the CPU and on the GPU) and identical
//! on both (same hash, same offsets).
//!
//! Error of a render, as the benchmark states it: on B clamped to [0, 1], the largest difference and the share
//! of texels off by more than 1/255; and on B unclamped, against the integrator's tolerance.

use energywave::bench::RenderError;
use energywave::field::{Line, Point, Sources};
use energywave::frame::FrameSetup;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::{Integration, Integrator, zeta};
use energywave::reference;
use energywave::reference::brightness;
use energywave::reference::converged::converged_reference;
use energywave::reference::simpson::jitter_offset;
use energywave::scene::Scene;
use glam::DVec3;

mod common;
use common::shipped;

/// The GPU (f32) against its f64 twin, relative to max(|B|, 0.01): a few times the 3e-5 measured on lavapipe,
/// so that a bug of either twin, or a mistyped constant, shows.
const TWIN_TOLERANCE: f64 = 1.5e-4;

/// Largest difference of the GPU's B from the f64 twin's over every texel of `scene`, relative to
/// max(|B|, 0.01): held to `TWIN_TOLERANCE`.
fn worst_against_twin(gpu: &mut HeadlessRenderer, scene: &Scene) -> f64 {
    let bb = scene.place_billboard(1.0);
    let g = gpu.brightness(&FrameSetup::new(scene, bb)).unwrap();
    let c = reference::render_brightness(&FrameSetup::new(scene, bb)).values;
    g.iter()
        .zip(&c)
        .map(|(&gv, &cv)| (gv as f64 - cv).abs() / cv.abs().max(0.01))
        .fold(0.0, f64::max)
}

/// The shipped preset `name` (file stem).
fn preset(name: &str) -> Scene {
    shipped()
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("the preset {name}"))
        .1
}

/// The converged reference of `scene`'s brightness texture, as the benchmark computes it.
fn converged(scene: &Scene) -> Vec<f64> {
    converged_reference(scene, 1).0
}

#[test]
fn the_adaptive_integrator_on_the_gpu_matches_the_converged_reference_on_every_shipped_scene() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    for (name, mut scene) in shipped() {
        scene.billboard.resolution = 40;
        scene.integration.integrator = Integrator::Adaptive;
        scene.integration.jitter = None;
        let reference = converged(&scene);
        let bb = scene.place_billboard(1.0);
        let adaptive = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let error = RenderError::of(&adaptive, 40, 1, &reference);
        // At the default tolerance (1e-4 on B), nothing visible: no texel off by 1/255.
        assert!(
            error.max_abs <= 1.0 / 255.0 && error.share_over_1_255 == 0.0,
            "{name}: {error:?}"
        );
        // And on B itself, unclamped (B > 1 still shows as color): within the tolerance, plus f32's rounding of
        // B on the GPU.
        let tolerance = scene.integration.tolerance;
        for (k, (&g, &r)) in adaptive.iter().zip(&reference).enumerate() {
            assert!(
                (g as f64 - r).abs() <= tolerance + 4e-6 * r.abs(),
                "{name}, texel ({}, {}): {g} against the converged {r}, tolerance {tolerance:e}",
                k % 40,
                k / 40
            );
        }
        assert!(
            reference.iter().any(|&b| b > 0.05),
            "{name}: the scene shows something"
        );
    }
}

/// A scene of points and lines only (whose terms the adaptive integrator takes in closed form), seen from `eye`.
fn points_and_lines(eye: DVec3) -> Scene {
    let mut scene = Scene::default_scene();
    scene.sources.tori.clear();
    scene.sources.curves.clear();
    scene.sources.points = [
        (DVec3::new(0.0, 0.0, 0.0), 1.5),
        (DVec3::new(1.2, 0.4, -0.8), 0.7),
        (DVec3::new(-1.5, -0.6, 0.5), 2.0),
        (DVec3::new(0.3, 1.1, 1.4), -0.4),
    ]
    .map(|(position, coefficient)| Point {
        position,
        coefficient,
        look: Default::default(),
    })
    .to_vec();
    scene.sources.lines = [
        (DVec3::new(0.0, -1.0, 0.0), DVec3::new(1.0, 0.2, 0.0), 0.8),
        (DVec3::new(0.5, 0.5, 0.5), DVec3::new(0.0, 0.0, 1.0), 0.5),
    ]
    .map(|(point, direction, coefficient)| Line {
        point,
        direction: direction.normalize(),
        coefficient,
        look: Default::default(),
    })
    .to_vec();
    scene.camera.eye = eye;
    scene.camera.target = DVec3::ZERO;
    scene.billboard.resolution = 40;
    scene.integration.integrator = Integrator::Adaptive;
    scene.integration.jitter = None;
    scene
}

#[test]
fn points_and_lines_in_closed_form_match_the_converged_reference_from_every_side() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    // Far, close, end-on along a line, and from among the sources.
    let eyes = [
        DVec3::new(0.0, 2.0, 12.0),
        DVec3::new(6.0, -3.0, 2.0),
        DVec3::new(0.5, 0.5, 7.0),
        DVec3::new(0.2, 0.3, 2.5),
    ];
    for eye in eyes {
        let scene = points_and_lines(eye);
        let reference = converged(&scene);
        let bb = scene.place_billboard(1.0);
        let tolerance = scene.integration.tolerance;
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let on_gpu = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        for (k, ((&g, &c), &r)) in on_gpu.iter().zip(&cpu).zip(&reference).enumerate() {
            let at = (k % 40, k / 40);
            assert!(
                (c - r).abs() <= 1e-9 * r.abs().max(1.0),
                "eye {eye}, texel {at:?}: the f64 twin's {c} against the converged {r}"
            );
            assert!(
                (g as f64 - r).abs() <= tolerance + 4e-6 * r.abs(),
                "eye {eye}, texel {at:?}: the GPU's {g} against the converged {r}"
            );
        }
        assert!(
            worst_against_twin(&mut gpu, &scene) <= TWIN_TOLERANCE,
            "eye {eye}: the GPU against its twin"
        );
    }
}

/// One ray past a point source, with the papers' decay, and its integrand.
fn grazing_ray() -> (Sources, Integration, DVec3, DVec3) {
    let sources = Sources {
        points: vec![Point {
            position: DVec3::new(0.003, 0.0, -3.3),
            coefficient: 1.0,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    let settings = Integration {
        integrator: Integrator::Simpson,
        divisions: 8,
        jitter: Some(0),
        ..Integration::default()
    };
    (sources, settings, DVec3::ZERO, DVec3::new(0.0, 0.0, -10.0))
}

#[test]
fn jittered_sampling_is_unbiased_where_fixed_samples_are_not() {
    let (sources, settings, s, e) = grazing_ray();
    let f = |t: f64| sources.psi(s + (e - s) * t, settings.epsilon) * zeta(t, 1.0, 1.0);
    let exact = energywave::reference::simpson::simpson(f, 1 << 20);
    // Eight evenly spaced samples miss the peak: the fixed rule is off by far more than its noise would be.
    let fixed = brightness(
        &sources,
        &Integration {
            jitter: None,
            ..settings.clone()
        },
        s,
        e,
        0.5,
    );
    // The jittered estimate over many offsets (the hash's, texel by texel, as a render draws them).
    let n = 20_000u32;
    let estimates: Vec<f64> = (0..n)
        .map(|k| {
            brightness(
                &sources,
                &settings,
                s,
                e,
                jitter_offset(7, k % 200, k / 200, 200),
            )
        })
        .collect();
    let mean = estimates.iter().sum::<f64>() / n as f64;
    let var = estimates.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let standard_error = (var / n as f64).sqrt();
    assert!(
        (mean - exact).abs() < 4.0 * standard_error,
        "mean {mean} vs {exact} (standard error {standard_error})"
    );
    assert!(
        (fixed - exact).abs() > 20.0 * standard_error,
        "fixed {fixed} vs {exact}: the bias the jitter removes"
    );
    // The offsets are uniform on [0, 1): their mean and variance are 1/2 and 1/12.
    let xi: Vec<f64> = (0..n).map(|k| jitter_offset(3, k, 0, n)).collect();
    let m = xi.iter().sum::<f64>() / n as f64;
    let v = xi.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64;
    assert!(
        (m - 0.5).abs() < 0.01 && (v - 1.0 / 12.0).abs() < 0.003,
        "{m} {v}"
    );
}

/// The papers' torus, small (24 x 24) and with simpson at n = 8: far from converged, banded without jitter.
fn coarse_torus() -> Scene {
    let mut scene = preset("divisions_torus_t4.0");
    scene.billboard.resolution = 24;
    scene.integration.integrator = Integrator::Simpson;
    scene.integration.divisions = 8;
    scene
}

/// Mean absolute difference of `values` from `reference`, texel by texel.
fn mean_abs_error<T: Copy + Into<f64>>(values: &[T], reference: &[f64]) -> f64 {
    let sum: f64 = (values.iter().zip(reference))
        .map(|(&a, b)| (a.into() - b).abs())
        .sum();
    sum / values.len() as f64
}

#[test]
fn jittered_renders_are_the_same_on_the_gpu_and_converge_to_the_reference() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let mut scene = coarse_torus();
    let w = scene.billboard.resolution;
    let bb = scene.place_billboard(1.0);
    let reference = converged(&scene);

    // The GPU draws the very offsets the CPU does: one seed, texel by texel.
    scene.integration.jitter = Some(11);
    let worst = worst_against_twin(&mut gpu, &scene);
    assert!(
        worst <= TWIN_TOLERANCE,
        "jittered: worst relative difference {worst:.2e}"
    );

    // The mean over seeds approaches the reference; fixed samples at the same n stay biased (bands).
    let seeds = 48;
    let mut sum = vec![0.0f64; (w * w) as usize];
    for seed in 0..seeds {
        scene.integration.jitter = Some(seed);
        for (acc, v) in sum
            .iter_mut()
            .zip(gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap())
        {
            *acc += v as f64;
        }
    }
    let mean: Vec<f64> = sum.iter().map(|s| s / seeds as f64).collect();
    scene.integration.jitter = None;
    let fixed: Vec<f64> = gpu
        .brightness(&FrameSetup::new(&scene, bb))
        .unwrap()
        .iter()
        .map(|&v| v as f64)
        .collect();
    let (jittered_error, fixed_error) = (
        mean_abs_error(&mean, &reference),
        mean_abs_error(&fixed, &reference),
    );
    assert!(
        jittered_error < 0.25 * fixed_error,
        "mean of {seeds} jittered renders: {jittered_error}, fixed samples: {fixed_error}"
    );
}

#[test]
fn averaged_frames_are_the_mean_of_their_seeds_and_their_noise_falls() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let mut scene = coarse_torus();
    let w = scene.billboard.resolution;
    scene.integration.jitter = Some(5);
    let bb = scene.place_billboard(1.0);
    let reference = converged(&scene);

    // The oracle: the f64 twin's renders with seeds 5, 6, ..., averaged on the CPU.
    let frames = 6u32;
    let mut cpu_mean = vec![0.0f64; (w * w) as usize];
    for k in 0..frames {
        let mut s = scene.clone();
        s.integration.jitter = Some(5 + k);
        for (acc, v) in cpu_mean
            .iter_mut()
            .zip(reference::render_brightness(&FrameSetup::new(&s, bb)).values)
        {
            *acc += v / frames as f64;
        }
    }
    gpu.set_average_frames(frames);
    let first = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
    let mut last = first.clone();
    for _ in 1..frames {
        last = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
    }
    let worst = last
        .iter()
        .zip(&cpu_mean)
        .map(|(&g, &c)| (g as f64 - c).abs() / c.abs().max(0.01))
        .fold(0.0, f64::max);
    assert!(
        worst <= TWIN_TOLERANCE,
        "mean of {frames} frames: worst relative difference {worst:.2e}"
    );
    // Full: the scene is not rendered again, and the picture stays.
    let renders = gpu.field().dispatch_count();
    assert_eq!(gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap(), last);
    assert_eq!(gpu.field().dispatch_count(), renders);

    // A change starts a new mean, from the first seed again.
    scene.integration.alpha *= 1.5;
    let changed = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
    gpu.set_average_frames(1);
    assert_eq!(
        gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap(),
        changed
    );
    scene.integration.alpha /= 1.5;

    // Unbiased, so the mean's error is noise, falling as 1/sqrt(frames): 32 frames, about 1/5.7 of one's.
    gpu.set_average_frames(32);
    let mut mean = Vec::new();
    for _ in 0..32 {
        mean = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
    }
    let (one, many) = (
        mean_abs_error(&first, &reference),
        mean_abs_error(&mean, &reference),
    );
    assert!(
        many < 0.35 * one,
        "error of one jittered frame {one:.3e}, of the mean of 32 {many:.3e}"
    );
}

#[test]
fn long_integrals_are_not_cut_short_by_a_drivers_loop_limit() {
    // Mesa's llvmpipe and lavapipe stop all loops of an invocation after 65535 iterations in all, silently:
    // n = 8192 on a two-segment curve is over 200 000. The field pass splits such integrals over dispatches.
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let mut scene = preset("bezier_b5.0");
    scene.billboard.resolution = 12;
    scene.integration.integrator = Integrator::Simpson;
    scene.integration.divisions = 8192;
    let worst = worst_against_twin(&mut gpu, &scene);
    assert!(
        worst <= 1e-3,
        "n = 8192: worst relative difference {worst:.2e}"
    );
}

#[test]
fn the_adaptive_pass_matches_its_f64_twin_on_every_texel_of_the_mixed_scene() {
    // At the scene's own resolution rays pass within 1e-4 of the line: there f32 rounding once kept the
    // refinement splitting until the driver's loop limit cut the texel short (dark dashes along the line).
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let scene = preset("mixed");
    assert_eq!(scene.integration.integrator, Integrator::Adaptive);
    let worst = worst_against_twin(&mut gpu, &scene);
    assert!(
        worst <= TWIN_TOLERANCE,
        "worst relative difference {worst:.2e}"
    );
}

/// The field passes hold a chain's first four segments and pieces in registers and read the rest from their
/// buffers, and its first eight weights: a chain of five segments with a W series of nine weights (eleven pieces
/// in the continuous form), in both W forms and with both integrators, matches the f64 twin on every texel.
#[test]
fn a_chain_longer_than_what_the_passes_hold_matches_its_twin() {
    use energywave::field::WForm;
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let mut scene = Scene::default_scene();
    scene.animation = None;
    scene.billboard.resolution = 32;
    scene.integration.jitter = None;
    let curve = &mut scene.sources.curves[0];
    // A wave of five segments, its joints smooth (each joint the middle of its neighbours).
    curve.control_points = (0..11)
        .map(|k| {
            let x = -3.5 + 0.7 * k as f64;
            let y = if k % 2 == 1 {
                (k as f64 * 0.9).sin() * 1.5
            } else {
                0.0
            };
            DVec3::new(x, y, 0.2 * (k as f64 * 0.5).cos())
        })
        .collect();
    for k in (2..10).step_by(2) {
        let (a, b) = (curve.control_points[k - 1], curve.control_points[k + 1]);
        curve.control_points[k] = 0.5 * (a + b);
    }
    curve.weights = vec![0.4, 1.0, 0.3, 0.9, 0.5, 1.2, 0.2, 0.8, 0.6];
    for form in [WForm::Nearest, WForm::Continuous] {
        for integrator in [Integrator::Simpson, Integrator::Adaptive] {
            scene.sources.curves[0].w_form = form;
            scene.integration.integrator = integrator;
            let worst = worst_against_twin(&mut gpu, &scene);
            eprintln!("{form:?}, {}: {worst:.2e}", integrator.name());
            assert!(
                worst <= TWIN_TOLERANCE,
                "{form:?}, {}: {worst:.2e} against the twin",
                integrator.name()
            );
        }
    }
}
