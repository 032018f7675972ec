//! The viewer's state and its whole user interface, independent of the window: the window loop and the UI tests
//! both call `ViewerApp::ui`. State here is plain parameters; GPU resources live in `viewport::ViewportGpu`.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Instant, SystemTime};

use egui::{Color32, Key, KeyboardShortcut, Modifiers, PointerButton, Sense};

use super::animation_panel;
use super::document::{DiskChange, Document};
use super::handles::{self, HandleId};
use super::history::History;
use super::navigation;
use super::panel;
use super::timeline::{self, ExportJob, Playback};
use super::viewport::{ViewportCallback, ViewportReport, ViewportView};
use crate::animation::{Parameter, Value};
use crate::geometry::Camera;
use crate::integrate::Integrator;
use crate::scene::Scene;

/// What the UI asks of the window around it.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    /// Save the viewport alone, at `scale` times its size, to `path`.
    Screenshot { path: PathBuf, scale: u32 },
    /// Close the window (unsaved changes have been dealt with).
    Quit,
}

/// An action waiting for the user to decide about unsaved changes.
#[derive(Clone, Debug, PartialEq)]
pub enum Pending {
    Open(PathBuf),
    Quit,
}

/// A drag in the viewport, from where it started: applied from the pointer's total offset each frame, so that
/// slow frames (a software GPU re-integrating the field) lose no movement.
#[derive(Clone, Debug)]
enum Gesture {
    Handle {
        id: HandleId,
        start: glam::DVec3,
        press: egui::Pos2,
    },
    Orbit {
        start: Camera,
        press: egui::Pos2,
    },
    Pan {
        start: Camera,
        press: egui::Pos2,
    },
}

/// Jittered frames the viewport averages while the view is still, unless set otherwise: the noise falls to
/// 1/8 of one frame's.
pub const DEFAULT_AVERAGE_FRAMES: u32 = 64;

/// The viewer's state.
pub struct ViewerApp {
    pub doc: Document,
    pub history: History,
    pub show_grid: bool,
    pub show_handles: bool,
    /// With jitter: how many frames the viewport averages while the view is still (1: none).
    pub average_frames: u32,
    /// While the view moves, show a coarse field sized to the frame budget and refine it once still
    /// (`progressive`); off: every frame integrates the full field.
    pub progressive: bool,
    /// Screenshot size relative to the viewport: 1, 2 or 4.
    pub screenshot_scale: u32,
    /// The path typed in the file section.
    pub path_input: String,
    /// Name of the GPU adapter, for the status line.
    pub adapter: String,
    /// Largest billboard resolution the device allows.
    pub max_resolution: u32,
    /// The viewport's size in physical pixels at the last frame.
    pub viewport_px: [u32; 2],
    /// The viewport's rectangle (egui points) at the last frame.
    pub viewport_rect: egui::Rect,
    /// The camera as loaded, for "Reset view".
    pub home_camera: Camera,
    pub pending: Option<Pending>,
    /// The last message for the user (and whether it is an error).
    pub notice: Option<(String, bool)>,
    report: Arc<Mutex<ViewportReport>>,
    gesture: Option<Gesture>,
    hovered: Option<HandleId>,
    frame_times: VecDeque<f64>,
    last_frame: Option<Instant>,
    requests: Vec<Request>,
    /// The animation's current frame and transport (not a document edit).
    pub playback: Playback,
    /// The Animation section's own fields (the parameter being typed, the export settings).
    pub animation_form: animation_panel::AnimationForm,
    /// An export running beside the UI.
    pub export_job: Option<ExportJob>,
    /// The document's title as it was before this frame's edits (see `show_keyed_values`).
    title: String,
}

/// How many sources, control points and weights a scene has: keyed values are only written back by path
/// when no edit renumbered them.
fn source_shape(scene: &Scene) -> Vec<usize> {
    let s = &scene.sources;
    let mut v = vec![s.points.len(), s.lines.len(), s.tori.len(), s.curves.len()];
    for c in &s.curves {
        v.push(c.control_points.len());
        v.push(c.weights.len());
    }
    v
}

const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);
const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);

impl ViewerApp {
    /// The viewer on `doc`; `report` is shared with the viewport's GPU side.
    pub fn new(
        doc: Document,
        adapter: String,
        max_resolution: u32,
        report: Arc<Mutex<ViewportReport>>,
    ) -> Self {
        Self {
            history: History::new(&doc.scene),
            home_camera: doc.scene.camera.clone(),
            path_input: doc
                .path()
                .map_or(String::new(), |p| p.display().to_string()),
            doc,
            show_grid: true,
            show_handles: true,
            average_frames: DEFAULT_AVERAGE_FRAMES,
            progressive: true,
            screenshot_scale: 1,
            adapter,
            max_resolution,
            viewport_px: [0, 0],
            viewport_rect: egui::Rect::NOTHING,
            pending: None,
            notice: None,
            report,
            gesture: None,
            hovered: None,
            frame_times: VecDeque::new(),
            last_frame: None,
            requests: Vec::new(),
            playback: Playback::default(),
            animation_form: animation_panel::AnimationForm::default(),
            export_job: None,
            title: String::new(),
        }
    }

    /// The document's title for the panel (unsaved changes marked), unaffected by the keyed values shown
    /// during the frame.
    pub fn title(&self) -> String {
        if self.title.is_empty() {
            self.doc.title()
        } else {
            self.title.clone()
        }
    }

    /// Writes each keyed parameter's value at the current frame into the document's scene, so that the
    /// panel and the handles show (and edit) what is on screen. Returns (parameter, base value, value
    /// shown) for `key_edited_values` to undo afterwards.
    fn show_keyed_values(&mut self) -> Vec<(Parameter, Value, Value)> {
        let Some(animation) = &self.doc.scene.animation else {
            return Vec::new();
        };
        let frame = self.playback.frame as f64;
        let mut shown = Vec::new();
        for track in animation.tracks.clone() {
            let p = track.parameter.clone();
            let (Some(base), Some(value)) = (p.get(&self.doc.scene), track.value_at(frame)) else {
                continue;
            };
            p.set(&mut self.doc.scene, value);
            if let Some(injected) = p.get(&self.doc.scene) {
                shown.push((p, base, injected));
            }
        }
        shown
    }

    /// After the panel and the viewport: a keyed value edited there becomes a key at the current frame (an
    /// edit while paused), and the scene's own values come back. Skipped when an edit renumbered sources,
    /// points or weights (the paths may name others now; the shown values then stay as the base values,
    /// which only a still render uses).
    fn key_edited_values(&mut self, shown: Vec<(Parameter, Value, Value)>, shape: Vec<usize>) {
        if shown.is_empty() || source_shape(&self.doc.scene) != shape {
            return;
        }
        let frame = self.playback.frame as f64;
        for (parameter, base, injected) in shown {
            if let (Some(now), Some(animation)) = (
                parameter.get(&self.doc.scene),
                self.doc.scene.animation.as_mut(),
            ) && now != injected
                && let Some(track) = animation
                    .tracks
                    .iter_mut()
                    .find(|t| t.parameter == parameter)
            {
                track.set_key(frame, now);
            }
            parameter.set(&mut self.doc.scene, base);
        }
    }

    /// The scene as shown: the document's scene at the current frame of its animation.
    pub fn frame_scene(&self) -> Scene {
        if self.doc.scene.is_animated() {
            self.doc.scene.at_frame(self.playback.frame as f64)
        } else {
            self.doc.scene.clone()
        }
    }

    /// Playback, the transport bar and any export running: once per frame, before the rest of the UI.
    fn animation_ui(&mut self, ui: &mut egui::Ui) {
        if let Some(job) = &self.export_job {
            let status = job.status();
            match status.result {
                Some(Ok(files)) => {
                    let first = files
                        .first()
                        .map_or(String::new(), |p| p.display().to_string());
                    let more = if files.len() > 1 {
                        format!(" (+{} more)", files.len() - 1)
                    } else {
                        String::new()
                    };
                    self.notify(format!("Exported {first}{more}"), false);
                    self.export_job = None;
                }
                Some(Err(e)) => {
                    self.notify(format!("Export failed: {e}"), true);
                    self.export_job = None;
                }
                None => ui
                    .ctx()
                    .request_repaint_after(std::time::Duration::from_millis(200)),
            }
        }
        let Some(animation) = &self.doc.scene.animation else {
            self.playback.playing = false;
            self.playback.frame = 0;
            return;
        };
        let (frames, frame_rate) = (animation.frames, animation.frame_rate);
        if self.playback.frame >= frames {
            self.playback.seek(self.playback.frame, frames);
        }
        timeline::shortcuts(ui.ctx(), &mut self.playback, frames);
        // Real time, but at most half a second per UI frame, so a slow frame skips ahead but never far.
        let dt = ui.input(|i| i.stable_dt).min(0.5) as f64;
        self.playback.advance(dt, frame_rate, frames);
        egui::Panel::bottom("energywave.timeline").show(ui, |ui| {
            timeline::bar(ui, &mut self.playback, frames, frame_rate)
        });
        if self.playback.playing {
            ui.ctx().request_repaint();
        }
    }

    /// Takes a new GPU (after the device was lost and recreated).
    pub fn set_gpu(
        &mut self,
        adapter: String,
        max_resolution: u32,
        report: Arc<Mutex<ViewportReport>>,
    ) {
        self.adapter = adapter;
        self.max_resolution = max_resolution;
        self.report = report;
    }

    /// The scene being edited.
    pub fn scene(&self) -> &Scene {
        &self.doc.scene
    }

    /// Takes what the UI asked of the window since the last call.
    pub fn take_requests(&mut self) -> Vec<Request> {
        std::mem::take(&mut self.requests)
    }

    /// What the GPU side reported.
    pub fn report(&self) -> ViewportReport {
        self.report.lock().map(|r| r.clone()).unwrap_or_default()
    }

    pub fn notify(&mut self, text: impl Into<String>, is_error: bool) {
        self.notice = Some((text.into(), is_error));
    }

    /// Median frame time in seconds over the last frames.
    pub fn frame_time(&self) -> Option<f64> {
        if self.frame_times.is_empty() {
            return None;
        }
        let mut v: Vec<f64> = self.frame_times.iter().copied().collect();
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    pub fn undo(&mut self) {
        if self.history.undo(&mut self.doc.scene) {
            self.notify("Undone", false);
        }
    }

    pub fn redo(&mut self) {
        if self.history.redo(&mut self.doc.scene) {
            self.notify("Redone", false);
        }
    }

    /// Saves to the document's file, or to the typed path when it has none.
    pub fn save(&mut self) {
        let result = match self.doc.save() {
            Ok(true) => Ok(()),
            Ok(false) => {
                let path = PathBuf::from(self.path_input.trim());
                if self.path_input.trim().is_empty() {
                    self.notify("Type a file name to save to, then Save As", true);
                    return;
                }
                self.doc.save_as(&path)
            }
            Err(e) => Err(e),
        };
        match result {
            Ok(()) => self.notify(
                format!(
                    "Saved {}",
                    self.doc
                        .path()
                        .map_or(String::new(), |p| p.display().to_string())
                ),
                false,
            ),
            Err(e) => self.notify(e.to_string(), true),
        }
    }

    /// Saves to the typed path.
    pub fn save_as(&mut self) {
        let path = PathBuf::from(self.path_input.trim());
        if self.path_input.trim().is_empty() {
            self.notify("Type a file name to save to", true);
            return;
        }
        match self.doc.save_as(&path) {
            Ok(()) => self.notify(format!("Saved {}", path.display()), false),
            Err(e) => self.notify(e.to_string(), true),
        }
    }

    /// Opens the typed path, asking first if there are unsaved changes.
    pub fn open(&mut self) {
        let path = PathBuf::from(self.path_input.trim());
        if self.doc.is_dirty() {
            self.pending = Some(Pending::Open(path));
        } else {
            self.open_now(path);
        }
    }

    fn open_now(&mut self, path: PathBuf) {
        match Document::open(&path) {
            Ok(doc) => {
                self.history.reset(&doc.scene);
                self.home_camera = doc.scene.camera.clone();
                self.doc = doc;
                self.notify(format!("Opened {}", path.display()), false);
            }
            Err(e) => self.notify(e.to_string(), true),
        }
    }

    /// The window was asked to close: quit now, or ask about unsaved changes first.
    pub fn request_quit(&mut self) {
        if self.doc.is_dirty() {
            self.pending = Some(Pending::Quit);
        } else {
            self.requests.push(Request::Quit);
        }
    }

    /// Asks the window for a screenshot of the viewport beside the scene file.
    pub fn screenshot(&mut self) {
        let path = self.doc.screenshot_path(SystemTime::now());
        self.requests.push(Request::Screenshot {
            path,
            scale: self.screenshot_scale,
        });
    }

    pub fn frame_effect(&mut self) {
        let aspect = self.viewport_px[0].max(1) as f64 / self.viewport_px[1].max(1) as f64;
        let scene = &mut self.doc.scene;
        navigation::frame_sources(&mut scene.camera, &scene.sources, aspect);
    }

    pub fn reset_view(&mut self) {
        self.doc.scene.camera = self.home_camera.clone();
    }

    /// The whole interface for one frame.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        if let Some(last) = self.last_frame.replace(now) {
            self.frame_times
                .push_back(now.duration_since(last).as_secs_f64());
            if self.frame_times.len() > 60 {
                self.frame_times.pop_front();
            }
        }
        match self.doc.poll_disk(now) {
            Some(DiskChange::Reloaded) => self.notify("Reloaded: the file changed on disk", false),
            Some(DiskChange::Invalid(e)) => self.notify(
                format!(
                    "The file changed on disk but does not load; keeping the last good scene.\n{e}"
                ),
                true,
            ),
            Some(DiskChange::Conflict) => {
                self.notify("The file changed on disk; you have unsaved changes", true)
            }
            None => {}
        }
        self.shortcuts(ui.ctx());

        egui::Panel::bottom("energywave.status").show(ui, |ui| self.status_bar(ui));
        self.animation_ui(ui);
        self.title = self.doc.title();
        let shape = source_shape(&self.doc.scene);
        let shown = self.show_keyed_values();
        egui::Panel::left("energywave.panel")
            .resizable(true)
            .default_size(340.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| panel::show(ui, self));
            });
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.viewport(ui));
        self.key_edited_values(shown, shape);
        self.modals(ui.ctx());

        // An edit is committed when it settles: no button held (a drag is one step).
        if !ui.ctx().input(|i| i.pointer.any_down()) {
            self.history.commit(&self.doc.scene);
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        if ctx.input_mut(|i| i.consume_shortcut(&SAVE)) {
            self.save();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&REDO) || i.consume_shortcut(&REDO_Y)) {
            self.redo();
        }
        if ctx.input_mut(|i| i.consume_shortcut(&UNDO)) {
            self.undo();
        }
        if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F12)) {
            self.screenshot();
        }
        if !ctx.egui_wants_keyboard_input()
            && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F))
        {
            self.frame_effect();
        }
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            match self.frame_time() {
                Some(t) if t > 0.0 => {
                    ui.monospace(format!("{:6.1} ms  {:5.1} FPS", t * 1e3, 1.0 / t))
                }
                _ => ui.monospace("   -- ms     -- FPS"),
            };
            ui.separator();
            ui.label(&self.adapter);
            ui.separator();
            let w = self.doc.scene.billboard.resolution;
            let i = &self.doc.scene.integration;
            let integrator = match i.integrator {
                Integrator::Adaptive => format!("adaptive, tolerance {:e}", i.tolerance),
                Integrator::Simpson if i.jitter.is_some() => {
                    let averaged = match self.report().averaged {
                        Some((k, most)) => format!(", mean of {k}/{most} frames"),
                        None => String::new(),
                    };
                    format!("simpson, n = {}, jittered{averaged}", i.divisions)
                }
                Integrator::Simpson => format!("simpson, n = {}", i.divisions),
            };
            let moving = match self.report().preview {
                Some(r) if r < w => format!(" (moving: {r}\u{d7}{r})"),
                _ => String::new(),
            };
            ui.label(format!("billboard {w}\u{d7}{w}{moving}, {integrator}"))
                .on_hover_text(
                    "While the view moves, a coarser field sized to hold the frame rate, refined to \
                     the full one within about a second once it holds still (View: fast preview)",
                );
            ui.separator();
            ui.label(self.doc.title());
            if let Some((text, is_error)) = &self.notice {
                ui.separator();
                let first_line = text.lines().next().unwrap_or_default();
                let color = if *is_error {
                    Color32::from_rgb(255, 110, 90)
                } else {
                    ui.visuals().weak_text_color()
                };
                ui.colored_label(color, first_line)
                    .on_hover_text(text.as_str());
            }
        });
    }

    fn viewport(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let ppp = ui.ctx().pixels_per_point();
        self.viewport_rect = rect;
        self.viewport_px = [
            (rect.width() * ppp).round() as u32,
            (rect.height() * ppp).round() as u32,
        ];
        if self.viewport_px[0] == 0 || self.viewport_px[1] == 0 {
            return;
        }
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            rect,
            ViewportCallback(ViewportView {
                scene: self.frame_scene(),
                size: self.viewport_px,
                show_grid: self.show_grid,
                average_frames: self.average_frames,
                progressive: self.progressive,
            }),
        ));

        // Handles first: a press on a handle drags it, anywhere else navigates.
        let pointer = response.hover_pos().or(response.interact_pointer_pos());
        let dragged_handle = match &self.gesture {
            Some(Gesture::Handle { id, .. }) => Some(*id),
            _ => None,
        };
        self.hovered = match (self.show_handles, pointer) {
            (true, Some(p)) if dragged_handle.is_none() => handles::pick(&self.doc.scene, rect, p),
            _ => self.hovered,
        };
        if response.drag_started() {
            // A drag is only recognised once the pointer has moved: start from where the button went down.
            let press = ui
                .input(|i| i.pointer.press_origin())
                .or(response.interact_pointer_pos())
                .unwrap_or(rect.center());
            let camera = self.doc.scene.camera.clone();
            let handle = self
                .show_handles
                .then(|| handles::pick(&self.doc.scene, rect, press))
                .flatten();
            self.gesture = if response.dragged_by(PointerButton::Primary) {
                Some(
                    match handle.and_then(|id| handles::get(&self.doc.scene, id).map(|p| (id, p))) {
                        Some((id, start)) => Gesture::Handle { id, start, press },
                        None => Gesture::Orbit {
                            start: camera,
                            press,
                        },
                    },
                )
            } else {
                Some(Gesture::Pan {
                    start: camera,
                    press,
                })
            };
        }
        let latest = ui.input(|i| i.pointer.latest_pos());
        if let (Some(gesture), Some(now)) = (&self.gesture, latest) {
            match gesture {
                Gesture::Handle { id, start, press } => {
                    let q = handles::drag_in_view_plane(
                        &self.doc.scene.camera,
                        rect.height(),
                        *start,
                        now - *press,
                    );
                    handles::set(&mut self.doc.scene, *id, q);
                }
                Gesture::Orbit { start, press } => {
                    let d = now - *press;
                    let mut camera = start.clone();
                    // About a full turn across a typical viewport's width.
                    navigation::orbit(&mut camera, d.x as f64 * 0.0065, d.y as f64 * 0.0065);
                    self.doc.scene.camera = camera;
                }
                Gesture::Pan { start, press } => {
                    let d = now - *press;
                    let mut camera = start.clone();
                    navigation::pan(&mut camera, d.x as f64, d.y as f64, rect.height() as f64);
                    self.doc.scene.camera = camera;
                }
            }
        }
        if self.gesture.is_some() && !ui.input(|i| i.pointer.any_down()) {
            self.gesture = None;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let toward = pointer.map(|p| handles::screen_ray(&self.doc.scene.camera, rect, p));
                navigation::zoom(
                    &mut self.doc.scene.camera,
                    (-scroll as f64 * 0.003).exp(),
                    toward,
                );
            }
        }

        let painter = ui.painter_at(rect);
        if self.show_handles {
            handles::draw(
                &painter,
                rect,
                &self.doc.scene,
                dragged_handle.or(self.hovered),
            );
        }
        if let Some(error) = self.report().error {
            painter.text(
                rect.left_top() + egui::vec2(8.0, 8.0),
                egui::Align2::LEFT_TOP,
                format!("GPU error: {error}"),
                egui::FontId::proportional(13.0),
                Color32::from_rgb(255, 110, 90),
            );
        }
    }

    fn modals(&mut self, ctx: &egui::Context) {
        let Some(pending) = self.pending.clone() else {
            return;
        };
        let what = match &pending {
            Pending::Open(p) => format!("Open {} and lose your unsaved changes?", p.display()),
            Pending::Quit => "Quit and lose your unsaved changes?".to_owned(),
        };
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("energywave.unsaved")).show(ctx, |ui| {
            ui.heading("Unsaved changes");
            ui.label(format!(
                "{} has unsaved changes.",
                self.doc.title().trim_end_matches(" *")
            ));
            ui.label(what);
            ui.horizontal(|ui| {
                if ui.button("Save").clicked() {
                    choice = Some("save");
                }
                if ui.button("Discard").clicked() {
                    choice = Some("discard");
                }
                if ui.button("Cancel").clicked() {
                    choice = Some("cancel");
                }
            });
        });
        let proceed = match choice {
            Some("save") => {
                self.save();
                !self.doc.is_dirty()
            }
            Some("discard") => true,
            Some(_) => {
                self.pending = None;
                false
            }
            None => false,
        };
        if proceed {
            self.pending = None;
            match pending {
                Pending::Open(path) => self.open_now(path),
                Pending::Quit => self.requests.push(Request::Quit),
            }
        }
    }
}
