//! Playback of a scene's animation in the viewer: the current frame, play / pause / step / scrub / loop, and
//! exports running beside the UI.
//!
//! Playback state is the view, not the document: it is never an undo step and never saved. The keyed values
//! and pulses it plays are the document's, edited in the panel's Animation section.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use egui::{Key, Modifiers, Ui};

use crate::export::{self, Target};
use crate::gpu::HeadlessRenderer;
use crate::scene::Scene;

/// Where playback is.
#[derive(Clone, Debug, PartialEq)]
pub struct Playback {
    /// The frame shown, in `0..frames`.
    pub frame: u32,
    pub playing: bool,
    /// Start again at frame 0 after the last frame (else stop there).
    pub looping: bool,
    /// Time played but not yet a whole frame, in frames.
    carry: f64,
}

impl Default for Playback {
    fn default() -> Self {
        Self {
            frame: 0,
            playing: false,
            looping: true,
            carry: 0.0,
        }
    }
}

impl Playback {
    /// Moves on by `dt` seconds of playback at `frame_rate` over `frames` frames.
    pub fn advance(&mut self, dt: f64, frame_rate: f64, frames: u32) {
        if !self.playing || frames == 0 {
            return;
        }
        self.carry += dt.max(0.0) * frame_rate;
        let whole = self.carry.floor();
        self.carry -= whole;
        let next = self.frame as u64 + whole as u64;
        if next < frames as u64 {
            self.frame = next as u32;
        } else if self.looping {
            self.frame = (next % frames as u64) as u32;
        } else {
            self.frame = frames - 1;
            self.playing = false;
            self.carry = 0.0;
        }
    }

    /// One frame forward (`delta` 1) or back (-1): around the ends when looping, else stopping at them.
    pub fn step(&mut self, delta: i64, frames: u32) {
        let frames = frames.max(1) as i64;
        let next = self.frame as i64 + delta;
        self.frame = if self.looping {
            next.rem_euclid(frames)
        } else {
            next.clamp(0, frames - 1)
        } as u32;
        self.carry = 0.0;
    }

    /// Goes to `frame` (clamped to the animation).
    pub fn seek(&mut self, frame: u32, frames: u32) {
        self.frame = frame.min(frames.max(1) - 1);
        self.carry = 0.0;
    }
}

/// What an export running beside the UI has done.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExportStatus {
    pub done: u32,
    pub total: u32,
    /// Set when it ended: the files written, or why it failed.
    pub result: Option<Result<Vec<PathBuf>, String>>,
}

/// An export on its own thread and GPU device, so that the viewer stays responsive.
pub struct ExportJob {
    pub status: Arc<Mutex<ExportStatus>>,
    pub description: String,
    /// Raised to stop it after the frame it is on.
    cancel: Arc<AtomicBool>,
}

impl ExportJob {
    /// Starts exporting `frames` of `scene` to `target` at `size` pixels, transparent or not, its objects held
    /// out or not, its field of view fitted to the glow (`export::fit`) or not.
    pub fn start(
        scene: Scene,
        target: Target,
        frames: Range<u32>,
        size: (u32, u32),
        (transparent, holdout, fit): (bool, bool, bool),
        description: String,
    ) -> Self {
        let status = Arc::new(Mutex::new(ExportStatus {
            done: 0,
            total: frames.len() as u32,
            result: None,
        }));
        let shared = status.clone();
        let cancel = Arc::new(AtomicBool::new(false));
        let stop = cancel.clone();
        std::thread::spawn(move || {
            let progress = shared.clone();
            let result = (|| -> Result<Vec<PathBuf>, String> {
                let mut gpu = HeadlessRenderer::new().map_err(|e| e.to_string())?;
                gpu.set_holdout(holdout);
                // An EXR keeps the opaque blend's values above 1.
                gpu.set_unclamped(target.is_exr());
                // W follows the export's pixel density unless the scene fixes it.
                let limit = gpu.ctx.device.limits().max_texture_dimension_2d;
                let mut scene = scene;
                if fit {
                    scene.camera.fov_y_degrees =
                        export::fit::fit_field_of_view(&scene, frames.clone(), size)
                            .map_err(|e| format!("fit: {e}"))?;
                }
                scene.billboard.resolution = gpu
                    .scene_at(&scene, frames.start as f64)
                    .resolution_for(size, limit);
                // Many frames of one structure: its specialised pipelines pay for their compile.
                if frames.len() > 4 {
                    gpu.set_specialise(crate::gpu::Specialise::Blocking);
                }
                export::export_frames(
                    &scene,
                    &target,
                    frames,
                    size,
                    crate::output::Alpha::of(transparent, false),
                    |frame| -> Result<Vec<[f64; 4]>, ExportFailure> {
                        let at = gpu.scene_at(&scene, frame as f64);
                        let frame = gpu.render(&at, size.0, size.1, transparent)?;
                        Ok(frame.pixels.iter().map(|p| p.map(|c| c as f64)).collect())
                    },
                    |done, _| {
                        if let Ok(mut s) = progress.lock() {
                            s.done = done;
                        }
                        if stop.load(Ordering::Relaxed) {
                            std::ops::ControlFlow::Break(())
                        } else {
                            std::ops::ControlFlow::Continue(())
                        }
                    },
                )
                .map_err(|e| e.0)
            })();
            if let Ok(mut s) = shared.lock() {
                s.result = Some(result);
            }
        });
        Self {
            status,
            description,
            cancel,
        }
    }

    /// Stops the export after the frame it is on; the files it wrote are removed.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// True once `cancel` was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    pub fn status(&self) -> ExportStatus {
        self.status.lock().map(|s| s.clone()).unwrap_or_default()
    }
}

/// Any failure of a viewer export, as its message.
struct ExportFailure(String);

impl From<export::ExportError> for ExportFailure {
    fn from(e: export::ExportError) -> Self {
        Self(e.to_string())
    }
}

impl From<crate::gpu::GpuError> for ExportFailure {
    fn from(e: crate::gpu::GpuError) -> Self {
        Self(e.to_string())
    }
}

/// The keys of playback, unless a text field has the keyboard: Space plays or pauses, the arrow keys step.
pub fn shortcuts(ctx: &egui::Context, playback: &mut Playback, frames: u32) {
    if ctx.egui_wants_keyboard_input() {
        return;
    }
    if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Space)) {
        playback.playing = !playback.playing;
    }
    if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::ArrowRight)) {
        playback.playing = false;
        playback.step(1, frames);
    }
    if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::ArrowLeft)) {
        playback.playing = false;
        playback.step(-1, frames);
    }
}

/// The transport bar: play / pause, step back and forward, the scrubber with a tick at every frame that holds a
/// key (`keys`), loop, and the frame number. The scrubber takes the bar's width left after the buttons and the
/// frame number, so that each frame is a few pixels of it.
pub fn bar(ui: &mut Ui, playback: &mut Playback, frames: u32, frame_rate: f64, keys: &[f64]) {
    ui.horizontal(|ui| {
        let last = frames.max(1) - 1;
        if ui.button("First").on_hover_text("First frame").clicked() {
            playback.seek(0, frames);
        }
        if ui
            .button("< Step")
            .on_hover_text("Step back (Left arrow key)")
            .clicked()
        {
            playback.playing = false;
            playback.step(-1, frames);
        }
        let label = if playback.playing { "Pause" } else { "Play" };
        if ui.button(label).on_hover_text("Space").clicked() {
            if !playback.playing && !playback.looping && playback.frame == last {
                playback.seek(0, frames);
            }
            playback.playing = !playback.playing;
        }
        if ui
            .button("Step >")
            .on_hover_text("Step forward (Right arrow key)")
            .clicked()
        {
            playback.playing = false;
            playback.step(1, frames);
        }
        ui.checkbox(&mut playback.looping, "loop");
        let readout = format!(
            "{:>w$} / {last}  {:6.2} s",
            playback.frame,
            playback.frame as f64 / frame_rate,
            w = last.to_string().len()
        );
        // What follows the rail: its value field, its label, the readout.
        let font = egui::TextStyle::Monospace.resolve(ui.style());
        let readout_width = ui.fonts_mut(|f| {
            f.layout_no_wrap(readout.clone(), font, egui::Color32::WHITE)
                .size()
                .x
        });
        let after = readout_width + 140.0;
        let rail = (ui.available_width() - after).max(MIN_SCRUBBER);
        ui.spacing_mut().slider_width = rail;
        let start = ui.cursor().left();
        let mut frame = playback.frame;
        let scrub = ui.add(
            egui::Slider::new(&mut frame, 0..=last)
                .text("frame")
                .clamping(egui::SliderClamping::Always),
        );
        let height = ui.spacing().interact_size.y;
        let span = tick_span(start, rail, height);
        let stroke = egui::Stroke::new(2.0, super::widgets::KEY_COLOR);
        for x in key_ticks(span, keys, last) {
            ui.painter().line_segment(
                [
                    egui::pos2(x, scrub.rect.bottom() - 4.0),
                    egui::pos2(x, scrub.rect.bottom()),
                ],
                stroke,
            );
        }
        // A quick click (pressed and released within a frame) moves no egui slider: it seeks here.
        if scrub.clicked()
            && !scrub.changed()
            && let Some(p) = scrub.interact_pointer_pos()
            && p.x >= start
            && p.x <= start + rail
        {
            frame = frame_at(span, p.x, last);
        }
        if frame != playback.frame {
            playback.seek(frame, frames);
        }
        if scrub.drag_started() {
            playback.playing = false;
        }
        ui.monospace(readout);
    });
}

/// The frame of `0..=last` whose tick lies nearest to `x` along the handle's `span`.
pub fn frame_at(span: egui::Rangef, x: f32, last: u32) -> u32 {
    let share = ((x - span.min) / span.span().max(1e-6)).clamp(0.0, 1.0);
    (share * last as f32).round() as u32
}

/// The scrubber is never narrower than this, points.
pub const MIN_SCRUBBER: f32 = 160.0;

/// Where the scrubber's handle runs for a rail `width` wide from `left`, `height` tall: egui's slider keeps its
/// round handle (radius `height / 2.5`) inside the rail.
pub fn tick_span(left: f32, width: f32, height: f32) -> egui::Rangef {
    let r = height / 2.5;
    egui::Rangef::new(left + r, left + width - r)
}

/// The x of each key's tick along the handle's `span`, for frames `0..=last` (keys outside left out).
pub fn key_ticks(span: egui::Rangef, keys: &[f64], last: u32) -> Vec<f32> {
    keys.iter()
        .filter(|&&k| k >= 0.0 && k <= last as f64)
        .map(|&k| {
            let share = if last == 0 { 0.0 } else { k / last as f64 };
            span.min + span.span() * share as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::Playback;

    #[test]
    fn playback_advances_by_time_loops_and_stops() {
        let mut p = Playback {
            playing: true,
            ..Playback::default()
        };
        // 0.1 s at 30 frames/s is 3 frames; fractions carry over.
        p.advance(0.1, 30.0, 92);
        assert_eq!(p.frame, 3);
        p.advance(0.02, 30.0, 92);
        p.advance(0.02, 30.0, 92);
        assert_eq!(p.frame, 4);
        p.seek(90, 92);
        p.advance(0.1, 30.0, 92);
        assert_eq!(p.frame, 1, "93 wraps to 1 when looping");
        p.looping = false;
        p.seek(90, 92);
        p.advance(0.1, 30.0, 92);
        assert_eq!((p.frame, p.playing), (91, false), "stops on the last frame");
        p.step(1, 92);
        assert_eq!(p.frame, 91);
        p.looping = true;
        p.step(1, 92);
        assert_eq!(p.frame, 0);
        p.step(-1, 92);
        assert_eq!(p.frame, 91);
        let mut paused = Playback::default();
        paused.advance(5.0, 30.0, 92);
        assert_eq!(paused.frame, 0, "paused playback does not move");
    }

    #[test]
    fn key_ticks_sit_where_the_handle_shows_their_frame() {
        let span = super::tick_span(100.0, 500.0, 20.0);
        assert_eq!((span.min, span.max), (108.0, 592.0));
        let x = super::key_ticks(span, &[0.0, 45.5, 91.0, 120.0], 91);
        assert_eq!(x, vec![108.0, 350.0, 592.0]);
    }
}
