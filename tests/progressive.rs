//! Progressive refinement in the viewer: the whole field refined at a looser tolerance while the view moves; the
//! full one a level of its refinement (or a band of rows) at a time once it holds still, ending on exactly the
//! texture a still render gives; screenshots at full quality whatever the screen shows.

use energywave::frame::FrameSetup;
use energywave::gpu::{FieldInputs, FieldRenderer, GpuContext, HeadlessRenderer};
use energywave::scene::Scene;
use energywave::viewer::document::Document;
use energywave::viewer::navigation;
use energywave::viewer::offscreen::OffscreenViewer;
use energywave::viewer::progressive::Pacing;

mod common;
use common::shipped_scene;

/// Reads the field texture of `field` after it was encoded whole or band by band.
fn integrate(ctx: &GpuContext, scene: &Scene, band_rows: u32) -> (Vec<f32>, u32) {
    let (device, queue) = (&ctx.device, &ctx.queue);
    let mut field = FieldRenderer::new(device);
    field.set_band_rows(band_rows);
    let bb = scene.place_billboard(1.0);
    assert!(
        field
            .prepare(device, queue, &FieldInputs::of(&FrameSetup::new(scene, bb)))
            .unwrap()
    );
    let mut frames = 0;
    loop {
        let mut encoder = device.create_command_encoder(&Default::default());
        let done = field.encode_bands(&mut encoder, 1, None);
        ctx.checked(|| queue.submit([encoder.finish()])).unwrap();
        frames += 1;
        if done {
            break;
        }
        assert!(frames < 1000);
    }
    assert_eq!(field.dispatch_count(), 1, "one render, however many bands");
    let texture = field.texture().unwrap();
    let values = bytemuck::cast_slice(&ctx.read_texture(texture, 4).unwrap()).to_vec();
    (values, frames)
}

#[test]
fn a_field_integrated_in_bands_is_the_field_integrated_at_once() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    for name in ["default.toml", "mixed.toml"] {
        let mut scene = shipped_scene(name);
        scene.billboard.resolution = 44;
        let (whole, frames) = integrate(&ctx, &scene, 0);
        assert_eq!(frames, 1);
        // 8-row bands (the last of 4 rows), and 16-row bands rounded from 13.
        for (rows, bands) in [(8, 6), (13, 3)] {
            let (banded, frames) = integrate(&ctx, &scene, rows);
            assert_eq!(frames, bands, "{name}: {rows} rows");
            assert_eq!(banded, whole, "{name}: {rows}-row bands");
        }
        assert!(whole.iter().any(|&b| b > 0.1), "{name} shows its effect");
    }
}

/// A refined field recorded a level of its refinement at a time, the two finest a quarter of their lists at a
/// time, is the field recorded at once (those are its bands), whatever band height is asked for.
#[test]
fn a_refined_field_integrated_a_level_at_a_time_is_the_field_integrated_at_once() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let mut scene = shipped_scene("floor.toml");
    scene.billboard.resolution = 128;
    let (whole, frames) = integrate(&ctx, &scene, 0);
    assert_eq!(
        frames, 9,
        "the coarsest level, then the two finer ones, each in four parts"
    );
    let (levels, frames) = integrate(&ctx, &scene, 8);
    assert_eq!(frames, 9, "the same, the band height aside");
    assert_eq!(levels, whole);
}

/// Frames until the viewer stops asking for more (the picture whole), at most 200.
fn settle(v: &mut OffscreenViewer) -> u32 {
    for k in 0..200 {
        v.frame().unwrap();
        if v.app.report().settled() {
            return k + 1;
        }
    }
    panic!("the viewer still refines after 200 frames");
}

/// Orbiting the default scene (256 x 256) with the pacing fixed (a moving field from a coarse grid of 32 texels a
/// side; bands of 64 rows while refining, which a refined field takes a level at a time instead), so that the frames are the same on a loaded machine as on an idle one (the
/// measured pacing is `progressive::FrameBudget`'s, held by its unit tests on made-up frame times): every moving
/// frame shows the coarse field, the still view refines in four bands and ends on exactly the texture a still
/// render of the final view gives, and on the picture a viewer that never moved shows.
#[test]
fn the_viewer_previews_while_orbiting_and_ends_on_the_still_picture() {
    let (width, height) = (640, 400);
    let mut v = OffscreenViewer::new(Document::new(Scene::default_scene(), None), width, height)
        .expect("a GPU adapter (lavapipe in CI)");
    v.app.view_mut().pacing = Pacing::Fixed {
        preview: 32,
        band_rows: 64,
    };
    settle(&mut v);
    let w = v.app.scene().billboard.resolution;
    assert_eq!(w, 256);
    let mut previews = Vec::new();
    for _ in 0..8 {
        navigation::orbit(&mut v.app.scene_mut().camera, 0.02, 0.0);
        v.frame().unwrap();
        previews.push(v.app.report().preview);
    }
    assert_eq!(previews, vec![Some(32); 8]);
    let moving = v.app.frame_scene();
    // Still: the four levels of the refinement (W = 256: the coarsest of stride 8, then 4, then 2 and 1 a
    // quarter of their lists a frame), the moving field shown until the last, then the full one.
    let mut refining = 0;
    while v.app.report().preview.is_some() {
        v.frame().unwrap();
        refining += 1;
        assert!(refining <= 10, "two levels, then two in four parts");
    }
    assert_eq!(refining, 10);
    settle(&mut v);
    assert_eq!(v.app.report().preview, None);
    // A screenshot is the full picture, and the one the viewport ends on.
    let shot = v.viewport_image().unwrap();
    let mut again =
        OffscreenViewer::new(Document::new(moving.clone(), None), width, height).unwrap();
    again.app.view_mut().progressive = false;
    settle(&mut again);
    assert_eq!(again.viewport_image().unwrap(), shot);
    // The texture the viewport ends on is the still render's, bit for bit.
    let shown = v.field_values().unwrap();
    let mut headless = HeadlessRenderer::new().unwrap();
    let bb = moving.place_billboard(v.app.viewport_px()[0] as f64 / v.app.viewport_px()[1] as f64);
    assert_eq!(
        shown,
        headless.brightness(&FrameSetup::new(&moving, bb)).unwrap()
    );
}

/// A sphere on a floor, a point source hidden behind it (its glow brightest beside the silhouette), orbited with
/// the moving field (a coarse grid of 32 texels a side, refined within a step of the 8-bit picture): the texels
/// beside the sphere's silhouette are integrated exactly (`frame::refine` forces them), so the glow on each side
/// of it is the full field's, and the rest lies within the moving tolerance of it. Measured on lavapipe: 0
/// beside the silhouette (the scene's tolerance, 1e-3, is the moving integrator's), 2.7e-5 elsewhere, B up to
/// 0.41. Until the moving field was refined it was a coarse one upsampled: off by 0.048 beside the silhouette,
/// 0.019 elsewhere.
#[test]
fn the_moving_field_holds_the_glow_on_each_side_of_an_objects_silhouette() {
    let mut scene = shipped_scene("floor.toml");
    scene.sources.tori.clear();
    scene.sources.points.push(energywave::field::Point {
        position: glam::DVec3::new(-0.12, 0.29, 0.07),
        coefficient: 1.0,
        look: Default::default(),
    });
    let (width, height) = (480, 320);
    let mut v = OffscreenViewer::new(Document::new(scene, None), width, height)
        .expect("a GPU adapter (lavapipe in CI)");
    v.app.view_mut().pacing = Pacing::Fixed {
        preview: 32,
        band_rows: 64,
    };
    settle(&mut v);
    navigation::orbit(&mut v.app.scene_mut().camera, 0.02, 0.0);
    v.frame().unwrap();
    assert_eq!(v.app.report().preview, Some(32));
    let w = v.app.scene().billboard.resolution;
    assert_eq!(
        v.app.report().moving_side,
        Some(w),
        "the moving field at the scene's W"
    );
    let tolerance = energywave::viewer::progressive::MOVING_TOLERANCE;
    let shown = v.field_values().unwrap();
    let moving = v.app.frame_scene();
    let w = moving.billboard.resolution as usize;
    assert_eq!(shown.len(), w * w, "the whole field");
    // The still field of the same view.
    let [px, py] = v.app.viewport_px();
    let bb = moving.place_billboard(px as f64 / py as f64);
    let setup = FrameSetup::new(&moving, bb);
    let full = HeadlessRenderer::new().unwrap().brightness(&setup).unwrap();
    // Texels within two of a jump in the clips (the silhouette), and the rest.
    let clips = setup.clips().expect("the scene has objects");
    let at = |i: usize, j: usize| clips[j.min(w - 1) * w + i.min(w - 1)];
    let jump = |i: usize, j: usize| {
        (at(i + 1, j) - at(i, j)).abs() > 0.05 || (at(i, j + 1) - at(i, j)).abs() > 0.05
    };
    let near = |i: usize, j: usize| {
        (i.saturating_sub(2)..=(i + 2).min(w - 1))
            .any(|x| (j.saturating_sub(2)..=(j + 2).min(w - 1)).any(|y| jump(x, y)))
    };
    let (mut edge, mut elsewhere, mut edge_texels) = (0f32, 0f32, 0);
    for j in 0..w {
        for i in 0..w {
            let e = (shown[j * w + i] - full[j * w + i]).abs();
            if near(i, j) {
                edge = edge.max(e);
                edge_texels += 1;
            } else {
                elsewhere = elsewhere.max(e);
            }
        }
    }
    let peak = full.iter().fold(0f32, |m, &b| m.max(b));
    eprintln!("beside the silhouette {edge:e}, elsewhere {elsewhere:e}, B up to {peak}");
    assert!(
        edge_texels > 200,
        "the silhouette is in view: {edge_texels} texels"
    );
    assert!(peak > 0.2, "the glow is in view: B up to {peak}");
    assert!(
        edge <= 2e-3,
        "beside the silhouette the moving field is off by {edge}"
    );
    assert!(
        elsewhere as f64 <= tolerance,
        "the moving field is off by {elsewhere}, over {tolerance}"
    );
}

/// A still view shows its last frame again rather than composing it anew, and composes anew as soon as
/// something the frame shows changes though the field does not (an object's albedo): the frame is then the one
/// a viewer opened on the edited scene shows, and the field is not integrated again.
#[test]
fn a_still_frame_is_shown_again_until_what_it_shows_changes() {
    let scene = shipped_scene("floor.toml");
    let (width, height) = (480, 320);
    let mut v = OffscreenViewer::new(Document::new(scene.clone(), None), width, height).unwrap();
    settle(&mut v);
    v.frame().unwrap();
    let still = v.viewport_pixels().unwrap();
    let renders = v.field_renders();
    for _ in 0..3 {
        v.frame().unwrap();
        assert_eq!(
            v.viewport_pixels().unwrap(),
            still,
            "a still frame is shown again"
        );
    }
    let albedo = [0.9, 0.2, 0.1];
    v.app.scene_mut().objects[1].color = albedo;
    v.frame().unwrap();
    let edited = v.viewport_pixels().unwrap();
    assert_ne!(edited, still, "the sphere's new albedo is drawn");
    assert_eq!(
        v.field_renders(),
        renders,
        "the field is not integrated again"
    );
    for _ in 0..2 {
        v.frame().unwrap();
        assert_eq!(v.viewport_pixels().unwrap(), edited);
    }
    let mut moved = scene;
    moved.objects[1].color = albedo;
    let mut fresh = OffscreenViewer::new(Document::new(moved, None), width, height).unwrap();
    settle(&mut fresh);
    fresh.frame().unwrap();
    assert_eq!(
        fresh.viewport_pixels().unwrap(),
        edited,
        "the frame a viewer of the edited scene shows"
    );
}
