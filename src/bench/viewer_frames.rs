//! Whole viewer frames, drawn offscreen through the viewer's own UI and viewport code. The bench does not import
//! the viewer: whoever runs it hands in the viewer as a [`TimedViewer`] (the command line hands in
//! `viewer::offscreen::OffscreenViewer`).

use super::*;

/// The size of the viewer's frames timed.
pub const VIEWER_SIZE: [u32; 2] = [1280, 720];

/// A viewer drawn offscreen, frame by frame, as the bench times it.
pub trait TimedViewer {
    /// One whole frame: UI, viewport, and the field when it changed; waits for the GPU.
    fn frame(&mut self) -> Result<(), GpuError>;
    /// True while the picture is not whole yet (the moving field shown while the full one refines, frames
    /// averaging).
    fn wants_frame(&self) -> bool;
    /// The side of the field shown at the last frame while the picture was not whole (the moving field, refined to
    /// 1/255, at W or less where the frame budget made it smaller); None once it is whole.
    fn preview(&self) -> Option<u32>;
    /// The scene, changed between frames as a user's gesture would.
    fn scene_mut(&mut self) -> &mut Scene;
    /// Shows the animation's next frame, as playback at the animation's rate does; returns that rate (frames a
    /// second), or none where the scene has no animation.
    fn step_animation(&mut self) -> Option<f64>;
    /// Turns the camera about its target by `yaw` radians, as an orbit drag does.
    fn orbit(&mut self, yaw: f64);
    /// Progressive refinement on (the viewer's default) or off (the whole field every frame).
    fn set_progressive(&mut self, on: bool);
    /// The viewport's pixels as the last frame drew them: RGBA, 8 bits a channel, rows from the top.
    fn viewport(&self) -> Result<Vec<u8>, GpuError>;
}

/// How far a moving frame's viewport lies from the settled one's (both RGBA8 of one size): the largest
/// difference of a color channel, in 1/255, and the share of pixels with a channel off by more than 16/255.
pub fn frame_difference(moving: &[u8], settled: &[u8]) -> (u8, f64) {
    let (mut largest, mut over) = (0u8, 0usize);
    let pixels = moving.len().min(settled.len()) / 4;
    for (a, b) in moving.chunks_exact(4).zip(settled.chunks_exact(4)) {
        let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
        largest = largest.max(d);
        over += usize::from(d > 16);
    }
    (largest, over as f64 / pixels.max(1) as f64)
}

/// Opens the viewer to time, at `VIEWER_SIZE` on the scene `BenchOptions::viewer_scene` names.
pub type OpenViewer<'a> = &'a mut dyn FnMut() -> Result<Box<dyn TimedViewer>, GpuError>;

pub(super) fn viewer_frames(
    options: &BenchOptions,
    open: OpenViewer,
    progress: &mut impl FnMut(&str),
) -> Result<ViewerFrameRow, GpuError> {
    let [width, height] = VIEWER_SIZE;
    progress(&format!(
        "viewer: {width} x {height}, {} scene",
        options.viewer_scene
    ));
    let mut viewer = open()?;
    let viewer = viewer.as_mut();
    let timed = |viewer: &mut dyn TimedViewer| -> Result<f64, GpuError> {
        let t = Instant::now();
        viewer.frame()?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    };
    // Until the picture is whole and nothing asks for another frame.
    let settle = |viewer: &mut dyn TimedViewer| -> Result<(f64, u32, f64), GpuError> {
        let (start, mut frames, mut longest) = (Instant::now(), 0, 0.0f64);
        while viewer.wants_frame() && frames < 1000 {
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
    settle(viewer)?;
    let frames = options.frames().max(3);
    let mut idle = Vec::new();
    for _ in 0..frames {
        idle.push(timed(viewer)?);
    }
    // A gesture: several frames in a row, each moving the view, timed once the frame budget has adapted.
    let gesture = |viewer: &mut dyn TimedViewer,
                   step: &dyn Fn(&mut dyn TimedViewer)|
     -> Result<(Vec<f64>, u32), GpuError> {
        let (mut ms, mut resolution) = (Vec::new(), 0);
        for k in 0..frames + 4 {
            step(viewer);
            let t = timed(viewer)?;
            if k >= 4 {
                ms.push(t);
                resolution = (viewer.preview()).unwrap_or(viewer.scene_mut().billboard.resolution);
            }
        }
        Ok((ms, resolution))
    };
    let orbit = |v: &mut dyn TimedViewer| v.orbit(0.01);
    let (orbiting, orbiting_resolution) = gesture(viewer, &orbit)?;
    let moving = viewer.viewport()?;
    let (refine_ms, refine_frames, refine_longest_frame_ms) = settle(viewer)?;
    let (moving_largest_difference, moving_share_over_16) =
        frame_difference(&moving, &viewer.viewport()?);
    // A curve's control point, else a ring's center, else a point (a source moved: objects are lit again).
    let drag = |v: &mut dyn TimedViewer| {
        let s = &mut v.scene_mut().sources;
        let moved = (s.curves.first_mut())
            .and_then(|c| c.control_points.get_mut(1))
            .or(s.tori.first_mut().map(|t| &mut t.center))
            .or(s.points.first_mut().map(|p| &mut p.position));
        if let Some(p) = moved {
            p.y += 0.01;
        }
    };
    let (dragging, dragging_resolution) = gesture(viewer, &drag)?;
    settle(viewer)?;
    viewer.scene_mut().sources.points.push(crate::field::Point {
        position: glam::DVec3::new(0.5, 1.0, 0.0),
        coefficient: 1.0,
        look: Default::default(),
    });
    let first = timed(viewer)?;
    let (_, added_frames, added_longest) = settle(viewer)?;
    viewer.scene_mut().sources.points.pop();
    settle(viewer)?;
    viewer.set_progressive(false);
    let (orbiting_full_field, _) = gesture(viewer, &orbit)?;
    viewer.set_progressive(true);
    // An animation playing, each frame the next of it: as the viewer draws it, and with the whole field.
    let playing = match viewer.step_animation() {
        Some(frame_rate) => {
            settle(viewer)?;
            let step = |v: &mut dyn TimedViewer| {
                v.step_animation();
            };
            let (frame, side) = gesture(viewer, &step)?;
            viewer.set_progressive(false);
            let (full_field, _) = gesture(viewer, &step)?;
            viewer.set_progressive(true);
            Some(PlayingRow {
                frame_rate,
                frame: Timing::of(frame),
                side,
                full_field: Timing::of(full_field),
            })
        }
        None => None,
    };
    Ok(ViewerFrameRow {
        width,
        height,
        scene: options.viewer_scene.clone(),
        idle: Timing::of(idle),
        orbiting: Timing::of(orbiting),
        orbiting_resolution,
        orbiting_full_field: Timing::of(orbiting_full_field),
        dragging: Timing::of(dragging),
        dragging_resolution,
        refine_ms,
        refine_frames,
        refine_longest_frame_ms,
        moving_largest_difference,
        moving_share_over_16,
        add_source_longest_frame_ms: first.max(added_longest),
        add_source_frames: added_frames + 1,
        playing,
    })
}
