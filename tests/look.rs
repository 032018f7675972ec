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

/// The largest difference, over the frame, between the default scene at `size` composed with W texels and
/// with `reference` texels a side (CPU twin).
fn beading(scene: &Scene, (w, h): (u32, u32), texels: u32, reference: u32) -> f64 {
    let frame = |texels: u32| {
        let mut s = scene.clone();
        s.billboard.resolution = texels;
        let bb = s.place_billboard(w as f64 / h as f64);
        let tex = reference::render_brightness(&s, &bb);
        reference::compose_frame_over(&s, &bb, &tex, (w, h), Backdrop::Opaque)
    };
    let (a, b) = (frame(texels), frame(reference));
    a.iter()
        .zip(&b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn an_export_takes_the_texels_its_size_needs_unless_the_scene_fixes_them() {
    let scene = Scene::default_scene();
    assert!(!scene.billboard.fixed_resolution);
    assert_eq!(scene.billboard.resolution, 256);
    // The billboard spans the frame's width: at 1920 x 1080, one texel per two pixels of it.
    let full_hd = scene.resolution_for((1920, 1080), 16384);
    assert!((900..=1000).contains(&full_hd), "{full_hd}");
    assert_eq!(full_hd % 8, 0);
    // Never below the viewer's W, never above the device's limit.
    assert_eq!(scene.resolution_for((64, 36), 16384), 256);
    assert_eq!(scene.resolution_for((1920, 1080), 600), 600);
    assert_eq!(scene.resolution_for((1920, 1080), 200), 200);
    // A scene that names its resolution keeps it.
    let mut fixed = scene.clone();
    fixed.billboard.fixed_resolution = true;
    assert_eq!(fixed.resolution_for((1920, 1080), 16384), 256);
    let saved = fixed.to_toml();
    assert!(saved.contains("resolution = 256"), "{saved}");
    assert!(!scene.to_toml().contains("resolution"));
    // Measured on the middle third of the 1920 x 1080 frame: a third of the field of view at 640 x 360, so that
    // the CPU twin stays quick. Its billboard is a third as wide, so 256 / 3 texels there are the full frame's
    // 256, and its own W the full frame's; a thin core beads at the first and is as smooth as at twice W at
    // the second.
    let mut middle = scene.clone();
    middle.camera.fov_y_degrees = 2.0
        * ((scene.camera.fov_y_degrees / 2.0).to_radians().tan() / 3.0)
            .atan()
            .to_degrees();
    let size = (640, 360);
    let own = middle.resolution_for(size, 16384);
    assert!(
        own * 3 >= full_hd - 8 && own * 3 <= full_hd + 24,
        "{own} {full_hd}"
    );
    let beaded = beading(&middle, size, 256 / 3, 2 * own);
    let smooth = beading(&middle, size, own, 2 * own);
    assert!(
        beaded > 3.0 * smooth && smooth < 12.0 / 255.0,
        "{beaded} {smooth}"
    );
}
