//! The viewer under what a window and a GPU can do to it: minimising to 0 x 0, a surface lost, outdated,
//! timing out or failing validation, and the device lost. Driven through the viewer's own frame code
//! (`presenter`, shared with the window) on a texture standing in for the window's surface. Each case must
//! recover with the scene, its history and the picture intact, and say what happened where it matters.

use energywave::scene::Scene;
use energywave::viewer::Document;
use energywave::viewer::offscreen::{OffscreenViewer, SurfaceFault};
use energywave::viewer::presenter::Outcome;

fn viewer() -> OffscreenViewer {
    let mut scene = Scene::default_scene();
    scene.billboard.resolution = 48;
    scene.integration.divisions = 32;
    let mut v = OffscreenViewer::new(Document::new(scene, None), 640, 400)
        .expect("a GPU adapter (lavapipe in CI)");
    // Two frames: the first lays the UI out, the second draws the viewport at its settled size.
    for _ in 0..2 {
        assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
    }
    v
}

/// Texels of the viewport brighter than the background: the glow is on screen.
fn lit_share(pixels: &[[f32; 4]]) -> f64 {
    let lit = pixels.iter().filter(|p| p[0] + p[1] + p[2] > 0.6).count();
    lit as f64 / pixels.len() as f64
}

fn max_difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

#[test]
fn minimised_window_draws_nothing_and_comes_back_at_the_new_size() {
    let mut v = viewer();
    let scene = v.app.scene().clone();
    let (configures, presented) = (v.surface.configures, v.surface.presented);

    v.resize(0, 0);
    for _ in 0..3 {
        assert_eq!(v.frame().unwrap(), Outcome::Minimised);
    }
    assert_eq!(
        v.surface.configures, configures,
        "a 0 x 0 surface must not be configured"
    );
    assert_eq!(
        v.surface.presented, presented,
        "nothing is drawn while minimised"
    );
    v.resize(0, 300);
    assert_eq!(v.frame().unwrap(), Outcome::Minimised);

    v.resize(800, 500);
    assert_eq!(v.surface.configures, configures + 1);
    assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
    assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
    assert_eq!(v.frame_image().unwrap().len(), 800 * 500 * 4);
    assert_eq!(v.app.scene(), &scene);
    // The viewport grew with the window and shows the glow.
    assert!(v.app.viewport_px()[0] > 400 && v.app.viewport_px()[1] > 400);
    let image = v.viewport_image().unwrap();
    assert!(lit_share(&image) > 0.01, "lit share {}", lit_share(&image));
}

#[test]
fn lost_outdated_and_invalid_surfaces_are_reconfigured_and_the_next_frame_draws() {
    let mut v = viewer();
    let scene = v.app.scene().clone();
    let before = v.viewport_image().unwrap();
    for fault in [
        SurfaceFault::Lost,
        SurfaceFault::Outdated,
        SurfaceFault::Validation,
    ] {
        let (configures, presented) = (v.surface.configures, v.surface.presented);
        v.surface.faults.push_back(fault);
        assert_eq!(v.frame().unwrap(), Outcome::Reconfigured, "{fault:?}");
        assert_eq!(v.surface.configures, configures + 1, "{fault:?}");
        assert_eq!(v.surface.presented, presented, "{fault:?}");
        assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
        assert_eq!(v.surface.presented, presented + 1);
    }
    let notice = v
        .app
        .notice()
        .cloned()
        .expect("the validation error is said");
    assert!(notice.1 && notice.0.contains("validation"), "{notice:?}");

    for fault in [SurfaceFault::Timeout, SurfaceFault::Occluded] {
        let (configures, presented) = (v.surface.configures, v.surface.presented);
        v.surface.faults.push_back(fault);
        assert_eq!(v.frame().unwrap(), Outcome::Skipped, "{fault:?}");
        assert_eq!(v.surface.configures, configures, "{fault:?}");
        assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
        assert_eq!(v.surface.presented, presented + 1);
    }
    assert_eq!(v.app.scene(), &scene);
    let after = v.viewport_image().unwrap();
    assert_eq!(max_difference(&before, &after), 0.0);
}

#[test]
fn a_lost_device_is_recreated_keeping_the_scene_its_history_and_the_picture() {
    let mut v = viewer();
    let original = v.app.scene().clone();
    // An edit, committed to the history at the end of the frame.
    v.app.scene_mut().sources.tori[0].coefficient *= 2.0;
    v.app.scene_mut().colors.energy = [1.0, 0.5, 0.2];
    assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
    let edited = v.app.scene().clone();
    let before = v.viewport_image().unwrap();
    assert!(lit_share(&before) > 0.01);

    v.lose_device();
    // The loss is noticed within a few frames (wgpu reports it once the queue has drained); no frame in
    // between may fail or panic, and the GPU side is recreated exactly once.
    let mut outcomes = Vec::new();
    for _ in 0..4 {
        outcomes.push(
            v.frame()
                .expect("a lost device is recovered from, not an error"),
        );
        if v.recoveries > 0 {
            break;
        }
    }
    assert_eq!(
        outcomes.last(),
        Some(&Outcome::DeviceLost),
        "outcomes {outcomes:?}"
    );
    assert_eq!(v.recoveries, 1);
    let notice = v
        .app
        .notice()
        .cloned()
        .expect("the loss is said in the panel");
    assert!(notice.1 && notice.0.contains("lost"), "{notice:?}");

    for _ in 0..2 {
        assert!(matches!(v.frame().unwrap(), Outcome::Drawn { .. }));
    }
    assert_eq!(v.app.scene(), &edited);
    let after = v.viewport_image().unwrap();
    assert!(
        max_difference(&before, &after) < 1e-6,
        "the recreated device draws the same picture"
    );
    v.app.undo();
    assert_eq!(v.app.scene(), &original, "the history survived the loss");
}

/// Runs frames until the UI stops asking for the next (its animations, such as a scroll bar fading in, end).
fn settle(v: &mut OffscreenViewer) {
    for _ in 0..60 {
        if v.frame().unwrap() == (Outcome::Drawn { repaint_now: false }) {
            return;
        }
    }
    panic!("the viewer still repaints after 60 frames of a still view");
}

#[test]
fn a_still_jittered_view_averages_its_frames_then_rests() {
    let mut v = viewer();
    let mean_abs = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        let sum: f64 = (a.iter().zip(b))
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs() as f64).sum::<f64>())
            .sum();
        sum / (3 * a.len()) as f64
    };
    // What the jittered frames converge to: the adaptive integrator's picture.
    let converged = v.viewport_image().unwrap();
    assert!(lit_share(&converged) > 0.01);

    let i = &mut v.app.scene_mut().integration;
    i.integrator = energywave::integrate::Integrator::Simpson;
    i.divisions = 6;
    i.jitter = Some(3);
    v.app.view_mut().average_frames = 1;
    // Every frame integrates the whole field (the mean is of whole fields): with the coarse preview on, a
    // loaded machine's frame budget may show a preview after the orbit below, and the mean would wait
    // (tests/progressive.rs holds the previews).
    v.app.view_mut().progressive = false;
    settle(&mut v);
    let one = v.viewport_image().unwrap();
    assert_eq!(v.app.report().averaged, None);

    // Averaging: each frame asks for the next until the mean holds them all, then the viewer rests.
    v.app.view_mut().average_frames = 24;
    let renders = v.field_renders();
    for k in 1..=24 {
        let outcome = v.frame().unwrap();
        assert_eq!(v.app.report().averaged, Some((k, 24)));
        assert_eq!(
            outcome,
            Outcome::Drawn {
                repaint_now: k < 24
            },
            "frame {k}"
        );
    }
    assert_eq!(v.field_renders(), renders + 24);
    assert_eq!(v.frame().unwrap(), Outcome::Drawn { repaint_now: false });
    assert_eq!(
        v.field_renders(),
        renders + 24,
        "a full mean is not rendered again"
    );
    let mean = v.viewport_image().unwrap();
    let (e1, e24) = (mean_abs(&one, &converged), mean_abs(&mean, &converged));
    assert!(
        e24 < 0.4 * e1,
        "mean difference from the converged picture: one frame {e1:.2e}, the mean of 24 {e24:.2e}"
    );

    // Orbiting starts a new mean.
    energywave::viewer::navigation::orbit(&mut v.app.scene_mut().camera, 0.3, 0.0);
    assert_eq!(v.frame().unwrap(), Outcome::Drawn { repaint_now: true });
    assert_eq!(v.app.report().averaged, Some((1, 24)));
}
