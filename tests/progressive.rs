//! Progressive refinement in the viewer: a coarse field, smoothly upsampled, while the view moves; the full one
//! in bands once it holds still, ending on exactly the texture a still render gives; screenshots at full
//! quality whatever the screen shows.

use energywave::frame::FrameSetup;
use energywave::gpu::{
    FieldInputs, FieldRenderer, GpuContext, HeadlessRenderer, Upsample, field_texture,
};
use energywave::scene::Scene;
use energywave::viewer::document::Document;
use energywave::viewer::navigation;
use energywave::viewer::offscreen::OffscreenViewer;
use energywave::viewer::progressive::Pacing;

mod common;
use common::shipped_scene;

/// Runs `upsample` over `values` (n x n, rows from the top) to `w` x `w` and reads the result back.
fn upsampled(ctx: &GpuContext, values: &[f32], n: u32, w: u32) -> Vec<f32> {
    let (device, queue) = (&ctx.device, &ctx.queue);
    // B in the first layer; the tint layers stay zero.
    let (source, view) = field_texture(device, "test.low", n, 1);
    queue.write_texture(
        source.as_image_copy(),
        bytemuck::cast_slice(values),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * n),
            rows_per_image: Some(n),
        },
        wgpu::Extent3d {
            width: n,
            height: n,
            depth_or_array_layers: 1,
        },
    );
    let mut upsample = Upsample::new(device);
    let mut encoder = device.create_command_encoder(&Default::default());
    upsample.encode(ctx.gpu(), &mut encoder, (&source, &view), (w, 1), None);
    ctx.checked(|| queue.submit([encoder.finish()])).unwrap();
    let (output, _) = upsample.output().unwrap();
    bytemuck::cast_slice(&ctx.read_texture(output, 4).unwrap()).to_vec()
}

/// Catmull-Rom reproduces quadratics exactly wherever its 4 x 4 stencil lies inside the texture, takes the
/// source's values where texel centers coincide, and never goes below 0.
#[test]
fn upsampling_is_exact_on_quadratics_and_interpolates() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let n = 16;
    // A quadratic in texture coordinates (texel centers at (i + 0.5) / n).
    let q = |x: f64, y: f64| 0.3 + 0.8 * x - 0.4 * y + 1.1 * x * x - 0.7 * x * y + 0.5 * y * y;
    let center = |i: u32, size: u32| (i as f64 + 0.5) / size as f64;
    let values: Vec<f32> = (0..n * n)
        .map(|k| q(center(k % n, n), center(k / n, n)) as f32)
        .collect();
    for w in [48, 64, 100] {
        let out = upsampled(&ctx, &values, n, w);
        let mut checked = 0;
        for j in 0..w {
            for i in 0..w {
                // The stencil: source texels floor(x) - 1 ..= floor(x) + 2 along each axis.
                let at = |i: u32| (i as f64 + 0.5) * n as f64 / w as f64 - 0.5;
                let inside = |x: f64| x.floor() >= 1.0 && x.floor() + 2.0 <= (n - 1) as f64;
                if !(inside(at(i)) && inside(at(j))) {
                    continue;
                }
                let want = q(center(i, w), center(j, w));
                let got = out[(j * w + i) as usize] as f64;
                assert!(
                    (got - want).abs() < 2e-6,
                    "{w}: texel ({i}, {j}) {got} vs {want}"
                );
                checked += 1;
            }
        }
        assert!(
            checked > (w * w / 2) as usize,
            "{w}: {checked} texels checked"
        );
    }
    // The same size: the identity.
    assert_eq!(upsampled(&ctx, &values, n, n), values);
    // A single bright texel: the cubic's lobes beside it are clipped at 0.
    let mut spike = vec![0.0f32; (n * n) as usize];
    spike[(8 * n + 8) as usize] = 10.0;
    let out = upsampled(&ctx, &spike, n, 64);
    assert!(out.iter().all(|&b| b >= 0.0));
    assert!(out.iter().any(|&b| b > 5.0));
}

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

/// Orbiting the default scene (256 x 256) with the pacing fixed (a coarse field of 32 texels a side while moving,
/// bands of 64 rows while refining), so that the frames are the same on a loaded machine as on an idle one (the
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
    // Still: four bands of 64 rows, the coarse field shown until the last, then the full one.
    let mut refining = 0;
    while v.app.report().preview.is_some() {
        v.frame().unwrap();
        refining += 1;
        assert!(refining <= 4, "four bands");
    }
    assert_eq!(refining, 4);
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
/// a coarse field of 32 texels a side: near the sphere's silhouette the upsampled preview holds the glow of the
/// side each texel lies on (the coarse texels read are those whose rays end where the texel's own does). It is
/// off the full field there by a few times what the smooth upsampling is elsewhere (measured 0.048 against
/// 0.019, B up to 0.41: beside the edge the glow is carried from the coarse texels a texel away). With the clips
/// ignored, the texels beside the silhouette mix glow integrated up to the sphere with glow integrated past it
/// and miss by nearly the peak B (0.40, 17x the error elsewhere): blocks of the sphere over the glow.
#[test]
fn the_preview_holds_the_glow_on_each_side_of_an_objects_silhouette() {
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
    let shown = v.field_values().unwrap();
    let w = 128;
    assert_eq!(shown.len(), w * w, "upsampled to four texels a coarse one");
    // The full field at the upsampled side, over the same billboard.
    let mut moving = v.app.frame_scene();
    let [px, py] = v.app.viewport_px();
    let bb = moving.place_billboard(px as f64 / py as f64);
    moving.billboard.resolution = w as u32;
    let setup = FrameSetup::new(&moving, bb);
    let full = HeadlessRenderer::new().unwrap().brightness(&setup).unwrap();
    // Texels within a coarse texel (4 texels) of a jump in the clips (the silhouette), and the rest.
    let clips = setup.clips().expect("the scene has objects");
    let at = |i: usize, j: usize| clips[j.min(w - 1) * w + i.min(w - 1)];
    let jump = |i: usize, j: usize| {
        (at(i + 1, j) - at(i, j)).abs() > 0.05 || (at(i, j + 1) - at(i, j)).abs() > 0.05
    };
    let near = |i: usize, j: usize| {
        (i.saturating_sub(4)..=(i + 4).min(w - 1))
            .any(|x| (j.saturating_sub(4)..=(j + 4).min(w - 1)).any(|y| jump(x, y)))
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
    assert!(
        edge_texels > 200,
        "the silhouette is in view: {edge_texels} texels"
    );
    assert!(
        elsewhere > 0.0 && elsewhere < 0.05 * peak,
        "{elsewhere} of {peak}"
    );
    assert!(
        edge <= 3.0 * elsewhere && edge <= 0.15 * peak,
        "beside the silhouette the preview is off by {edge}, elsewhere by {elsewhere}, B up to {peak}"
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
