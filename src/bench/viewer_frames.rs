//! Whole viewer frames, drawn offscreen through the viewer's own UI and viewport code.

use super::*;
use crate::viewer::Document;
use crate::viewer::offscreen::OffscreenViewer;

pub(super) fn viewer_frames(
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<ViewerFrameRow, GpuError> {
    progress("viewer: 1280 x 720, default scene");
    let mut viewer = OffscreenViewer::new(Document::new(Scene::default_scene(), None), 1280, 720)?;
    let timed = |viewer: &mut OffscreenViewer| -> Result<f64, GpuError> {
        let t = Instant::now();
        viewer.frame()?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    // Until the picture is whole and nothing asks for another frame.
    let settle = |viewer: &mut OffscreenViewer| -> Result<(f64, u32, f64), GpuError> {
        let (start, mut frames, mut longest) = (Instant::now(), 0, 0.0f64);
        while viewer.app.report().wants_frame() && frames < 1000 {
            longest = longest.max(timed(viewer)?);
            frames += 1;
        }
        Ok((start.elapsed().as_secs_f64() * 1e3, frames, longest))
    };
    let start = Instant::now();
    let mut rounds = 0;
    while rounds < options.warmup() || warming(start, rounds) {
        viewer.frame()?;
        rounds += 1;
    }
    settle(&mut viewer)?;
    let frames = options.frames().max(3);
    let mut idle = Vec::new();
    for _ in 0..frames {
        idle.push(timed(&mut viewer)?);
    }
    // A gesture: several frames in a row, each moving the view, timed once the frame budget has adapted.
    let gesture = |viewer: &mut OffscreenViewer,
                   step: &dyn Fn(&mut Scene)|
     -> Result<(Vec<f64>, u32), GpuError> {
        let (mut ms, mut resolution) = (Vec::new(), 0);
        for k in 0..frames + 4 {
            step(&mut viewer.app.doc.scene);
            let t = timed(viewer)?;
            if k >= 4 {
                ms.push(t);
                resolution = (viewer.app.report().preview)
                    .unwrap_or(viewer.app.doc.scene.billboard.resolution);
            }
        }
        Ok((ms, resolution))
    };
    let orbit = |s: &mut Scene| crate::viewer::navigation::orbit(&mut s.camera, 0.01, 0.0);
    let (orbiting, orbiting_resolution) = gesture(&mut viewer, &orbit)?;
    let (refine_ms, refine_frames, refine_longest_frame_ms) = settle(&mut viewer)?;
    let drag = |s: &mut Scene| {
        if let Some(p) = s
            .sources
            .curves
            .first_mut()
            .and_then(|c| c.control_points.get_mut(1))
        {
            p.y += 0.01;
        }
    };
    let (dragging, dragging_resolution) = gesture(&mut viewer, &drag)?;
    settle(&mut viewer)?;
    viewer
        .app
        .doc
        .scene
        .sources
        .points
        .push(crate::field::Point {
            position: glam::DVec3::new(0.5, 1.0, 0.0),
            coefficient: 1.0,
        });
    let first = timed(&mut viewer)?;
    let (_, added_frames, added_longest) = settle(&mut viewer)?;
    viewer.app.doc.scene.sources.points.pop();
    settle(&mut viewer)?;
    viewer.app.progressive = false;
    let (orbiting_full_field, _) = gesture(&mut viewer, &orbit)?;
    viewer.app.progressive = true;
    Ok(ViewerFrameRow {
        width: 1280,
        height: 720,
        scene: "default".into(),
        idle: Timing::of(idle),
        orbiting: Timing::of(orbiting),
        orbiting_resolution,
        orbiting_full_field: Timing::of(orbiting_full_field),
        dragging: Timing::of(dragging),
        dragging_resolution,
        refine_ms,
        refine_frames,
        refine_longest_frame_ms,
        add_source_longest_frame_ms: first.max(added_longest),
        add_source_frames: added_frames + 1,
    })
}
