//! The whole effect at every camera. Each texel's ray must reach past the far side of every source wherever
//! the eye is (close up, from inside the sources' bounds, orbiting), and the decay is fixed in scene units
//! (`integration.decay_length`), so that moving the camera keeps the look instead of shortening the rays.
//!
//! The checks are independent of how `geometry::ray_reach` finds the end: the sources' farthest depths come
//! from their own geometry (a Bezier curve lies in its control points' hull, a torus's circle reaches
//! `R sqrt(1 - (a.n)^2)` along n), and B is judged against `reference::converged`, which integrates
//! the decay in scene units (depth past the billboard over the decay length) rather than the integrators'
//! rescaled s.

use std::path::Path;

use energywave::frame::FrameSetup;
use energywave::geometry::ray_end;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::Integrator;
use energywave::reference;
use energywave::reference::converged::converged_reference;
use energywave::scene::Scene;
use energywave::viewer::navigation;
use glam::DVec3;

mod common;
use common::shipped_scene;

/// `scene` with its eye moved toward the target, to `fraction` of its distance.
fn closer(scene: &Scene, fraction: f64) -> Scene {
    let mut s = scene.clone();
    s.camera.eye = s.camera.target + (s.camera.eye - s.camera.target) * fraction;
    s
}

/// The default scene seen from inside its sources' bounding box, between the ring and the beam.
fn inside() -> Scene {
    let mut s = Scene::default_scene();
    s.camera.eye = DVec3::new(0.16, 0.36, 1.12);
    let (lo, hi) = s.sources.bounds().unwrap();
    assert!(
        s.camera.eye.cmpgt(lo).all() && s.camera.eye.cmplt(hi).all(),
        "{lo} {hi}"
    );
    s
}

/// The largest depth along `inward` (from `eye`) that any bounded source reaches.
fn deepest_source(scene: &Scene, eye: DVec3, inward: DVec3) -> f64 {
    let src = &scene.sources;
    let depth = |p: DVec3| (p - eye).dot(inward);
    let points = src.points.iter().map(|p| depth(p.position));
    let tori = src.tori.iter().map(|t| {
        depth(t.center) + t.major_radius * (1.0 - t.axis.dot(inward).powi(2)).max(0.0).sqrt()
    });
    let curves = src
        .curves
        .iter()
        .flat_map(|c| c.control_points.iter().map(|&p| depth(p)));
    points.chain(tori).chain(curves).fold(f64::MIN, f64::max)
}

#[test]
fn every_ray_reaches_past_every_source_close_up_inside_and_orbiting() {
    let default = Scene::default_scene();
    let beam = shipped_scene("beam_end_on.toml");
    let mut cameras = vec![
        ("default", default.clone()),
        ("default at half distance", closer(&default, 0.5)),
        ("default at a quarter", closer(&default, 0.25)),
        ("default from inside", inside()),
        ("end-on beam", beam.clone()),
    ];
    for degrees in [30.0, 60.0, 90.0, 150.0] {
        let mut s = beam.clone();
        navigation::orbit(&mut s.camera, f64::to_radians(degrees), 0.0);
        cameras.push(("end-on beam orbited", s.clone()));
        cameras.push(("end-on beam orbited, close", closer(&s, 0.4)));
    }
    for (name, scene) in &cameras {
        let bb = scene.place_billboard(1.0);
        let reach = FrameSetup::new(scene, bb).reach;
        let eye = scene.camera.eye;
        let inward = -bb.normal;
        let deepest = deepest_source(scene, eye, inward);
        let w = 16;
        for j in 0..w {
            for i in 0..w {
                let e = ray_end(bb.texel_center(i, j, w), eye, reach.nu);
                assert!(
                    (e - eye).dot(inward) > deepest,
                    "{name}: texel ({i}, {j})'s ray ends at depth {} before the deepest source at {deepest}",
                    (e - eye).dot(inward)
                );
            }
        }
    }
}

/// The default scene at half and a quarter of its eye distance and from inside its bounds, with the
/// adaptive integrator on the CPU and the GPU: within the tolerance of the converged full ray.
#[test]
fn the_default_scene_close_up_and_from_inside_is_within_tolerance_of_the_converged_reference() {
    let default = Scene::default_scene();
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    for (name, mut scene) in [
        ("half distance", closer(&default, 0.5)),
        ("quarter distance", closer(&default, 0.25)),
        ("inside", inside()),
    ] {
        let w = 24;
        scene.billboard.resolution = w;
        scene.integration.integrator = Integrator::Adaptive;
        let want = converged_reference(&scene, 1).0;
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let gpu_b = gpu.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let tolerance = scene.integration.tolerance;
        for (k, &r) in want.iter().enumerate() {
            let (i, j) = (k as u32 % w, k as u32 / w);
            assert!(
                (cpu[k] - r).abs() <= tolerance,
                "{name}, texel ({i}, {j}): CPU {} against the converged {r}",
                cpu[k]
            );
            // f32's rounding of B on the GPU comes on top, as on the shipped scenes.
            assert!(
                (gpu_b[k] as f64 - r).abs() <= tolerance + 4e-6 * r.abs(),
                "{name}, texel ({i}, {j}): GPU {} against the converged {r}",
                gpu_b[k]
            );
        }
        // Not flat: the sources stand out of their haze.
        let (lo, hi) = want
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &b| (lo.min(b), hi.max(b)));
        assert!(hi > 1.5 * lo && hi > 1.0, "{name}: B spans only {lo}..{hi}");
    }
}

/// Moving the eye along its view axis keeps the ray through the target on the same line, so its B may move
/// only as far as the billboard's standoff from the effect does (5 % of the eye distance): a few percent,
/// where rays that shrank with the camera lost most of the effect at half the distance.
#[test]
fn zooming_in_keeps_the_look_on_the_view_axis() {
    let default = Scene::default_scene();
    let axis = |fraction: f64| {
        let mut s = closer(&default, fraction);
        s.billboard.resolution = 25;
        s.integration.tolerance = 1e-7;
        let bb = s.place_billboard(1.0);
        // The middle texel of an odd billboard sits on the view axis.
        let mid = bb.texel_center(12, 12, 25);
        let to_target = (s.camera.target - s.camera.eye).normalize();
        assert!((mid - s.camera.eye).normalize().dot(to_target) > 1.0 - 1e-12);
        reference::texel_brightness(&FrameSetup::new(&s, bb), 12, 12)
    };
    let far = axis(1.0);
    assert!(far > 1.0, "the view axis crosses the effect: B = {far}");
    for fraction in [0.75, 0.5, 0.4] {
        let near = axis(fraction);
        assert!(
            (near / far - 1.0).abs() < 0.05,
            "at {fraction} of the distance B = {near}, at the file's camera {far}"
        );
    }
}

/// A file's decay length is fixed when it is read: moving the camera afterwards, or saving the moved view and
/// reading it again, keeps it, so the effect looks the same after a save as before.
#[test]
fn the_decay_length_stays_with_the_scene_when_the_camera_moves() {
    let mut scene = Scene::default_scene();
    let length = scene.integration.decay_length;
    navigation::orbit(&mut scene.camera, 0.7, 0.2);
    navigation::zoom(&mut scene.camera, 0.4, None);
    let again = Scene::parse(&scene.to_toml(), Path::new("moved.toml")).unwrap();
    assert_eq!(again.integration.decay_length, length);
    assert_eq!(again.camera, scene.camera);
}
