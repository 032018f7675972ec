//! What an artist sees: every shipped preset from four cameras has no black hole where its glow passes over
//! something bright, the default blend is "over" and the papers' presets keep theirs.

mod common;

use std::path::Path;

use energywave::reference::{self, Backdrop, BrightnessTexture};
use energywave::scene::{Blend, Scene};
use energywave::viewer::navigation::orbit;
use glam::DVec3;

/// The frame's pixels, RGB, at a small size: the glow over the objects and background, and the same frame
/// without the glow (the objects still lit by it).
fn frames(scene: &Scene) -> (Vec<[f64; 4]>, Vec<[f64; 4]>) {
    let (w, h) = (64, 48);
    let bb = scene.place_billboard(w as f64 / h as f64);
    let glow = reference::render_brightness(scene, &bb);
    let n = glow.values.len();
    let none = BrightnessTexture {
        resolution: glow.resolution,
        values: vec![0.0; n],
        tint: vec![[0.0; 3]; n],
    };
    (
        reference::compose_frame_over(scene, &bb, &glow, (w, h), Backdrop::Opaque),
        reference::compose_frame_over(scene, &bb, &none, (w, h), Backdrop::Opaque),
    )
}

/// The pixels where the glow turns something visibly lit (a channel above 0.1) into black (every channel below
/// 0.02): a glow adds light, it never makes a hole.
fn black_holes(scene: &Scene) -> usize {
    let (with, without) = frames(scene);
    with.iter()
        .zip(&without)
        .filter(|(g, b)| {
            b[..3].iter().any(|&c| c > 0.1) && g[..3].iter().all(|&c| c.clamp(0.0, 1.0) < 0.02)
        })
        .count()
}

/// The file's camera, orbited a quarter and a half turn, and from high above a three-quarter turn round.
fn four_cameras(scene: &Scene) -> Vec<Scene> {
    [(0.0, 0.0), (90.0, 0.0), (180.0, 0.0), (270.0, 50.0)]
        .into_iter()
        .map(|(yaw, pitch): (f64, f64)| {
            let mut s = scene.clone();
            orbit(&mut s.camera, yaw.to_radians(), pitch.to_radians());
            s.billboard.resolution = 48;
            s
        })
        .collect()
}

#[test]
fn no_shipped_preset_shows_a_black_hole_from_four_cameras() {
    for (name, scene) in common::shipped() {
        for (k, s) in four_cameras(&scene).iter().enumerate() {
            let holes = black_holes(s);
            assert_eq!(holes, 0, "{name}, camera {k}: {holes} black pixels");
        }
    }
}

#[test]
fn the_floor_preset_edge_on_lights_the_floor_under_the_ring_instead_of_punching_it_black() {
    let mut scene = common::shipped_scene("floor.toml");
    // The ring stands in the xy plane: from +x it is edge-on, its glow lying along the floor it lights most.
    scene.camera.eye = DVec3::new(7.5, 1.7, 0.0);
    scene.billboard.resolution = 48;
    assert_eq!(scene.colors.blend, Blend::Over);
    assert_eq!(black_holes(&scene), 0);
    // The papers' blend, asked for, still subtracts the lit floor: the panel says so.
    scene.colors.blend = Blend::Papers;
    assert!(black_holes(&scene) > 0);
}

#[test]
fn new_scenes_blend_over_and_the_papers_presets_keep_theirs() {
    let bare = Scene::parse(
        "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1.0\n",
        Path::new("bare.toml"),
    )
    .unwrap();
    assert_eq!(bare.colors.blend, Blend::Over);
    assert_eq!(Scene::default_scene().colors.blend, Blend::Over);
    for (name, scene) in common::shipped() {
        let figure = name.starts_with("bezier_")
            || name.starts_with("divisions_")
            || name.starts_with("local_intensity_")
            || name.starts_with("torus_")
            || name == "pulse_travelling";
        let expected = if figure { Blend::Papers } else { Blend::Over };
        assert_eq!(scene.colors.blend, expected, "{name}");
    }
}
