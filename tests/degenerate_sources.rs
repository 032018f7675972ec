//! Points and lines in the degenerate places of their closed form (`reference::adaptive_smooth::falloff_integral`
//! and its WGSL twin), on both integrators, the f64 twin and the GPU, against the converged reference and, where
//! there is one, a closed form of the whole texel: a line through the eye (the decay's pole at the papers' settings,
//! where the closed form's parts grow as 1 / A^(3/2) and cancelled to +-1e15 on about half the texels), seen along
//! the view axis and crossing it; a point at the eye and just beside it; a ray through a point and through a line;
//! a ray along a line; a point and a line in the billboard's plane.

use std::path::Path;

use energywave::frame::FrameSetup;
use energywave::geometry::ray_end;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::Integrator;
use energywave::reference;
use energywave::reference::converged::converged_reference;
use energywave::scene::Scene;
use glam::DVec3;

/// The scene of the report: eye [0, 0, 10], a billboard fixed at [0, 0, 6] across the view, the papers' alpha =
/// beta = 1 and nu = 2 (so the decay's pole lies at the eye), `sources` as TOML, `resolution` texels a side (odd:
/// the middle texel's ray is the view axis itself).
fn scene(sources: &str, resolution: u32) -> Scene {
    let text = format!(
        "[camera]\neye = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 30.0\n\n\
         [billboard]\ncenter = [0.0, 0.0, 6.0]\nsize = 3.0\nresolution = {resolution}\n\n\
         [integration]\nalpha = 1.0\nbeta = 1.0\nnu = 2.0\n\n{sources}"
    );
    Scene::parse(&text, Path::new("degenerate.toml")).expect("a valid scene")
}

/// Every texel of `scene` on both integrators, CPU and GPU, against the converged reference: the adaptive
/// integrator within its tolerance (and f32's rounding of B on the GPU), Simpson at n = 4000 within 2e-4 of B.
/// Returns the converged reference.
fn meets_the_reference(name: &str, scene: &Scene, gpu: &mut HeadlessRenderer) -> Vec<f64> {
    let want = converged_reference(scene, 1).0;
    let bb = scene.place_billboard(1.0);
    for integrator in [Integrator::Adaptive, Integrator::Simpson] {
        let mut scene = scene.clone();
        scene.integration.integrator = integrator;
        scene.integration.divisions = 4000;
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let gpu_b = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let tolerance = scene.integration.tolerance;
        for (k, &r) in want.iter().enumerate() {
            let (cpu_allowed, gpu_allowed) = match integrator {
                Integrator::Adaptive => (tolerance, tolerance + 1e-5 * r.abs()),
                Integrator::Simpson => (1e-5 + 2e-4 * r.abs(), 1e-5 + 2.5e-4 * r.abs()),
            };
            assert!(
                (cpu[k] - r).abs() <= cpu_allowed,
                "{name}, {}, CPU, texel {k}: {} against {r}",
                integrator.name(),
                cpu[k]
            );
            assert!(
                (gpu_b[k] as f64 - r).abs() <= gpu_allowed,
                "{name}, {}, GPU, texel {k}: {} against {r}",
                integrator.name(),
                gpu_b[k]
            );
        }
    }
    assert!(want.iter().all(|b| b.is_finite()) && want.iter().any(|&b| b > 0.05));
    want
}

/// B of a line through the eye along the view axis, for a texel whose point on the billboard is r from the axis,
/// the pole at the eye and the ray running `span` decay lengths past the billboard. Along the ray the line is
/// `(1 + sigma) r` away (sigma in decay lengths, one decay length being the eye's distance from the billboard),
/// `zeta = 1 / (1 + sigma)^2`: `B = c / eps (1 - 1 / (1 + s0))` over the flat top up to `s0 = eps / r - 1`, and
/// `c / (2 r) ((1 + s0)^-2 - (1 + span)^-2)` after it.
fn axis_line(c: f64, r: f64, eps: f64, span: f64) -> f64 {
    if r * (1.0 + span) <= eps {
        // Inside eps all the way (the ray along the line itself at r = 0).
        return c / eps * (1.0 - 1.0 / (1.0 + span));
    }
    let s0 = (eps / r - 1.0).clamp(0.0, span);
    c / eps * (1.0 - 1.0 / (1.0 + s0))
        + c / (2.0 * r) * ((1.0 + s0).powi(-2) - (1.0 + span).powi(-2))
}

#[test]
fn a_line_through_the_eye_along_the_view_axis_is_its_closed_form() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let c = 1.3;
    let scene = scene(
        &format!(
            "[[lines]]\npoint = [0.0, 0.0, 0.0]\ndirection = [0.0, 0.0, 1.0]\ncoefficient = {c}\n"
        ),
        31,
    );
    let want = meets_the_reference("a line through the eye", &scene, &mut gpu);
    // And every texel against the closed form of the whole ray (which the reference also meets).
    let bb = scene.place_billboard(1.0);
    let reach = FrameSetup::new(&scene, bb).reach;
    let decay = scene.integration.decay_length;
    assert!(
        (decay - 4.0).abs() < 1e-12,
        "nu = 2 at the file's camera: one eye distance"
    );
    let eps = scene.integration.epsilon;
    let w = scene.billboard.resolution;
    for j in 0..w {
        for i in 0..w {
            let s = bb.texel_center(i, j, w);
            let r = s.truncate().length();
            let b = axis_line(c, r, eps, reach.stretch);
            let k = (j * w + i) as usize;
            assert!(
                (want[k] - b).abs() <= 1e-6 * b,
                "texel ({i}, {j}), r {r}: reference {} against the closed form {b}",
                want[k]
            );
        }
    }
    // The middle texel's ray runs along the line itself, inside eps all the way.
    let middle = ((w / 2) * w + w / 2) as usize;
    assert!((want[middle] - axis_line(c, 0.0, eps, reach.stretch)).abs() < 1e-6 * want[middle]);
}

#[test]
fn lines_and_points_through_and_beside_the_eye_meet_the_converged_reference() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let cases = [
        (
            "a line through the eye, across the view",
            "[[lines]]\npoint = [0.0, 0.0, 10.0]\ndirection = [1.0, 0.2, -0.6]\ncoefficient = 1.0\n",
        ),
        (
            "a line through the eye and the middle of the effect, negative",
            "[[lines]]\npoint = [0.3, -0.2, 0.0]\ndirection = [-0.03, 0.02, 1.0]\ncoefficient = -0.8\n\
             [[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 2.0\n",
        ),
        (
            "a point at the eye",
            "[[points]]\nposition = [0.0, 0.0, 10.0]\ncoefficient = 1.0\n\
             [[points]]\nposition = [0.2, 0.1, 0.0]\ncoefficient = 0.6\n",
        ),
        (
            "points a hair beside and behind the eye",
            "[[points]]\nposition = [1e-9, 0.0, 10.0]\ncoefficient = 1.0\n\
             [[points]]\nposition = [0.0, 0.0, 10.3]\ncoefficient = 1.0\n\
             [[points]]\nposition = [0.3, -0.4, 9.0]\ncoefficient = 1.0\n",
        ),
    ];
    for (name, sources) in cases {
        meets_the_reference(name, &scene(sources, 15), &mut gpu);
    }
}

#[test]
fn rays_through_along_and_in_the_plane_of_sources_meet_the_converged_reference() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    // The middle texel's ray (odd resolution) is the view axis; the billboard's plane is z = 6.
    let cases = [
        (
            "a ray through a point",
            "[[points]]\nposition = [0.0, 0.0, 1.5]\ncoefficient = 1.0\n",
        ),
        (
            "a ray through a line crossing the view axis",
            "[[lines]]\npoint = [0.0, 0.0, 2.0]\ndirection = [1.0, 0.0, 0.0]\ncoefficient = 1.0\n",
        ),
        (
            "a point and a line in the billboard's plane",
            "[[points]]\nposition = [0.0, 0.0, 6.0]\ncoefficient = 1.0\n\
             [[lines]]\npoint = [0.0, 0.6, 6.0]\ndirection = [1.0, 0.0, 0.0]\ncoefficient = 0.7\n",
        ),
    ];
    for (name, sources) in cases {
        meets_the_reference(name, &scene(sources, 15), &mut gpu);
    }
    // A ray along a line, the line off the pole: the middle ray runs down the view axis, and a line parallel to it
    // 0.2 away keeps that distance all along it (its closest approach is the whole ray).
    let s = scene(
        "[[lines]]\npoint = [0.2, 0.0, 0.0]\ndirection = [0.0, 0.0, 1.0]\ncoefficient = 1.0\n",
        15,
    );
    let bb = s.place_billboard(1.0);
    let reach = FrameSetup::new(&s, bb).reach;
    let middle = bb.texel_center(7, 7, 15);
    let end = ray_end(middle, s.camera.eye, reach.nu);
    assert!(
        (end - middle).normalize().dot(DVec3::NEG_Z) > 1.0 - 1e-12,
        "the middle ray runs along -z"
    );
    let want = meets_the_reference("a ray along a line 0.2 off it", &s, &mut gpu);
    // Along that ray B = c / 0.2 times the decay's integral over the ray.
    let settings = s.integration.on_ray(reach.stretch);
    let (a, b) = (settings.alpha, settings.beta);
    let closed = a * (1.0 / b - 1.0 / (1.0 + b)) / 0.2;
    assert!(
        (want[7 * 15 + 7] - closed).abs() <= 1e-7 * closed,
        "{} against {closed}",
        want[7 * 15 + 7]
    );
}
