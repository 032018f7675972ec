//! Glare, the optional fog glow: the GPU pass against its f64 twin (whose blur is checked against the 2D
//! Gaussian by brute force beside it), in every blend and the transparent export; off by default and then no
//! change at all; the scene file's `[glare]`.

use std::path::Path;

use energywave::frame::FrameSetup;
use energywave::gpu::HeadlessRenderer;
use energywave::reference;
use energywave::scene::{Blend, Glare, Scene, SceneError};

mod common;
use common::shipped_scene;

#[test]
fn the_gpu_glare_matches_the_cpu_twin_in_every_blend() {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let (w, h) = (80, 64);
    for (name, threshold) in [("rings_and_beam.toml", 0.3), ("torus_r0.9_t5.1.toml", 1.0)] {
        let mut scene = shipped_scene(name);
        scene.billboard.resolution = 64;
        let bb = scene.place_billboard(w as f64 / h as f64);
        let texture = reference::render_brightness(&FrameSetup::new(&scene, bb));
        let plain = reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, w, h, false);
        scene.glare = Some(Glare {
            threshold,
            size: 0.04,
            strength: 1.5,
        });
        for blend in [Blend::Papers, Blend::Over] {
            scene.colors.blend = blend;
            for transparent in [false, true] {
                let cpu = reference::compose_frame(
                    &FrameSetup::new(&scene, bb),
                    &texture,
                    w,
                    h,
                    transparent,
                );
                let frame = gpu.render(&scene, w, h, transparent).unwrap();
                for (p, q) in frame.pixels.iter().zip(&cpu) {
                    for c in 0..4 {
                        assert!(
                            (p[c] as f64 - q[c]).abs() <= 2.0 / 255.0 * q[c].abs().max(1.0),
                            "{name} {blend:?} transparent {transparent}: {p:?} against the CPU's {q:?}"
                        );
                    }
                }
            }
        }
        // The glare shows: brighter around the cores, never darker.
        scene.colors.blend = Blend::Papers;
        let glared = reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, w, h, false);
        let mut lifted = 0;
        for (p, q) in glared.iter().zip(&plain) {
            assert!((0..3).all(|c| p[c] >= q[c] - 1e-12), "{p:?} {q:?}");
            lifted += (p[0] + p[1] + p[2] > q[0] + q[1] + q[2] + 0.02) as usize;
        }
        assert!(lifted > 50, "{name}: {lifted} pixels lifted");
    }
}

#[test]
fn without_glare_nothing_changes_and_a_glare_below_every_b_does_nothing() {
    let mut scene = shipped_scene("mixed.toml");
    scene.billboard.resolution = 32;
    assert_eq!(scene.glare, None);
    let bb = scene.place_billboard(1.0);
    let texture = reference::render_brightness(&FrameSetup::new(&scene, bb));
    let plain = reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, 40, 40, false);
    let top = texture.values.iter().copied().fold(0.0, f64::max);
    scene.glare = Some(Glare {
        threshold: top,
        ..Glare::default()
    });
    assert_eq!(
        reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, 40, 40, false),
        plain
    );
}

fn invalid(text: &str) -> String {
    match Scene::parse(text, Path::new("bad.toml")) {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        other => panic!("{text:?} was not refused: {other:?}"),
    }
}

#[test]
fn glare_in_scene_files() {
    let point = "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n\n";
    for (body, field, line, phrase) in [
        ("[glare]\nkind = \"streaks\"\n", "glare.kind", 6, "fog"),
        ("[glare]\nsize = 0.5\n", "glare.size", 6, "(0, 0.1]"),
        ("[glare]\nsize = 0.0\n", "glare.size", 6, "(0, 0.1]"),
        (
            "[glare]\nthreshold = -1.0\n",
            "glare.threshold",
            6,
            "at least 0",
        ),
        ("[glare]\nstrength = 1e6\n", "glare.strength", 6, "0..=1000"),
        (
            "[glare]\nstrenght = 1.0\n",
            "glare.strenght",
            6,
            "unknown field",
        ),
    ] {
        let msg = invalid(&format!("{point}{body}"));
        assert!(
            msg.contains(field)
                && msg.contains(&format!("bad.toml:{line}:"))
                && msg.contains(phrase),
            "{body:?}: {msg}"
        );
    }
    // An empty table is the default glare; the scene writes it back in full and reads it again.
    let scene = Scene::parse(&format!("{point}[glare]\n"), Path::new("ok.toml")).unwrap();
    assert_eq!(scene.glare, Some(Glare::default()));
    let text = scene.to_toml();
    assert!(
        text.contains("[glare]") && text.contains("kind = \"fog\""),
        "{text}"
    );
    assert_eq!(Scene::parse(&text, Path::new("saved.toml")).unwrap(), scene);
    let fresh = energywave::scene::format::fresh_text(&scene, Path::new("saved.toml"));
    assert_eq!(
        Scene::parse(&fresh, Path::new("saved.toml")).unwrap(),
        scene
    );
}

#[test]
fn the_viewers_glare_is_never_a_stale_one() {
    // The viewer reuses its last glare while the field it shows is unchanged. Whatever changed the field (an edit
    // of a coefficient, the bands of a refinement finishing after an orbit), the viewport it presents then is a
    // fresh render of the scene with glare.
    use energywave::gpu::HeadlessRenderer;
    use energywave::viewer::offscreen::OffscreenViewer;
    use energywave::viewer::progressive::Pacing;
    use energywave::viewer::{Document, navigation};
    let mut scene = shipped_scene("rings_and_beam.toml");
    scene.billboard.resolution = 64;
    scene.integration.integrator = energywave::integrate::Integrator::Simpson;
    scene.integration.divisions = 48;
    scene.glare = Some(Glare {
        threshold: 0.3,
        size: 0.04,
        strength: 1.5,
    });
    let mut v = OffscreenViewer::new(Document::new(scene, None), 800, 480).unwrap();
    // The viewport alone: no grid behind the glow, no handles over it.
    v.app.view_mut().show_grid = false;
    v.app.view_mut().show_handles = false;
    v.app.view_mut().pacing = Pacing::Fixed {
        preview: 16,
        band_rows: 16,
    };
    let mut fresh = HeadlessRenderer::new().unwrap();
    let mut settle_and_check = |v: &mut OffscreenViewer, what: &str| {
        for _ in 0..40 {
            v.frame().unwrap();
            if v.app.report().settled() {
                break;
            }
        }
        assert!(v.app.report().settled(), "{what}: the picture is whole");
        let [vw, vh] = v.app.viewport_px();
        let want = fresh.render(&v.app.frame_scene(), vw, vh, false).unwrap();
        let shown = common::viewer::shown_viewport(v, 800);
        // Less the Overlays button in the viewport's top-right corner (egui's, over the picture).
        let button = |k: usize| k % vw as usize >= vw as usize - 100 && k / (vw as usize) < 32;
        let worst = (shown.iter().zip(&want.pixels).enumerate())
            .filter(|(k, _)| !button(*k))
            .map(|(_, (p, q))| {
                (0..3)
                    .map(|c| (p[c] - q[c].clamp(0.0, 1.0)).abs())
                    .fold(0.0, f32::max)
            })
            .fold(0.0, f32::max);
        assert!(
            worst <= 1.5 / 255.0,
            "{what}: off a fresh render by {worst}"
        );
        shown
    };
    let first = settle_and_check(&mut v, "at first");
    // A coefficient edited: the field, and so the glare, changes.
    v.app.scene_mut().sources.tori[0].coefficient *= 1.8;
    let edited = settle_and_check(&mut v, "after an edit");
    assert_ne!(first, edited, "the edit shows");
    // An orbit: coarse fields while moving, then bands, the last of which completes the field.
    for _ in 0..3 {
        navigation::orbit(&mut v.app.scene_mut().camera, 0.05, 0.0);
        v.frame().unwrap();
        assert_eq!(v.app.report().preview, Some(16));
    }
    settle_and_check(&mut v, "after the bands of an orbit");
}
