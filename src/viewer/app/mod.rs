//! The viewer's state and its whole user interface, independent of the window: the window loop and the UI tests
//! both call `ViewerApp::ui`. State here is plain parameters; GPU resources live in `viewport::ViewportGpu`.
//!
//! The panels and the viewport read the scene as shown (the document's at the current frame) and return what
//! the user asked for as [`Action`]s; `ViewerApp::apply` carries each out, here and nowhere else. The
//! viewport's gestures and selection are in `gestures`, files (saving, opening, the dialog, drops) in `files`,
//! the status line and messages in `status`.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Instant, SystemTime};

use egui::{Color32, Key, KeyboardShortcut, Modifiers, PointerButton, Sense};
use glam::DVec3;

use super::action::{Action, Edit};
use super::animation_panel::{self, AnimationForm};
use super::document::{DiskChange, Document};
use super::file_dialog::{DialogMode, DialogOutcome, FileDialog};
use super::handles::{self, HandleId};
use super::history::History;
use super::navigation;
use super::panel::{self, ViewSettings};
use super::recent::RecentFiles;
use super::timeline::{self, ExportJob, Playback};
use super::viewport::{ViewportCallback, ViewportReport, ViewportView};
use crate::animation::SourceKind;
use crate::background::{Latest, Poll};
use crate::geometry::Camera;
use crate::integrate::Integrator;
use crate::scene::Scene;

mod access;
mod files;
mod gestures;
mod status;

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

/// How long a message that is not an error stays in the status bar, seconds. Any message also clears at the
/// user's next action; an error about the file on disk clears once the file is fine again.
pub const NOTICE_SECONDS: f64 = 5.0;

/// A message in the status bar.
#[derive(Clone, Debug)]
struct Notice {
    /// The text and whether it is an error.
    message: (String, bool),
    /// When it was given (the UI's clock).
    at: f64,
    /// About the file on disk: cleared once the file loads and no reload waits.
    from_disk: bool,
}

/// The viewer's state.
/// How long a frame waits for its live particle sets' simulation before it shows the particles last simulated.
const LIVE_WAIT: std::time::Duration = std::time::Duration::from_millis(30);

pub struct ViewerApp {
    doc: Document,
    history: History,
    /// How the scene is shown (grid, handles, averaging, fast preview, screenshot scale).
    view: ViewSettings,
    /// The path typed in the file section.
    path_input: String,
    /// Name of the GPU adapter, for the status line.
    adapter: String,
    /// Largest billboard resolution the device allows.
    max_resolution: u32,
    /// The viewport's size in physical pixels at the last frame.
    viewport_px: [u32; 2],
    /// The viewport's rectangle (egui points) at the last frame.
    viewport_rect: egui::Rect,
    /// The camera as loaded, for "Reset view".
    home_camera: Camera,
    pending: Option<Pending>,
    /// The last message for the user.
    notice: Option<Notice>,
    /// The UI's clock at this frame (egui's time, seconds).
    now: f64,
    report: Arc<Mutex<ViewportReport>>,
    /// The frame cache shared with the viewport: the live sets are simulated in it.
    cache: Arc<crate::frame::FrameCache>,
    gesture: Option<Gesture>,
    hovered: Option<HandleId>,
    /// The selected source: ringed in the viewport, highlighted in the panel.
    selection: Option<(SourceKind, usize)>,
    /// The selected object, if any (a source or an object is selected, not both).
    selected_object: Option<usize>,
    /// The handle the last click picked, and where: a second click there goes on to the next handle under it.
    picked: Option<(HandleId, egui::Pos2)>,
    /// The panel scrolls to the selected source's entry at its next frame (a selection made in the viewport).
    scroll_to_selection: bool,
    /// The panel scrolls back to its top on the next frame (another file was opened).
    scroll_panel_to_top: bool,
    /// Where a mesh chosen in the file dialog goes (the target when "+ mesh" was clicked).
    mesh_at: DVec3,
    /// The file dialog, while it is open.
    dialog: Option<FileDialog>,
    /// The files opened and saved lately.
    recent: RecentFiles,
    frame_times: VecDeque<f64>,
    last_frame: Option<Instant>,
    requests: Vec<Request>,
    /// The animation's current frame and transport (not a document edit).
    playback: Playback,
    /// The Animation section's own fields (the parameter being typed, the export settings).
    animation_form: AnimationForm,
    /// An export running beside the UI.
    export_job: Option<ExportJob>,
    /// The live particle sets simulated up to the frame shown, on a thread of their own (a scrub far into a
    /// dense set steps the simulation for seconds): the scene at a frame, by the document's scene and the frame.
    live: Latest<(Scene, u32), Scene>,
    /// The live sets' particles last simulated, each set's by its index: what a frame shows while the
    /// simulation of its own runs.
    live_shown: Mutex<Vec<Option<Arc<Vec<crate::particles::Particle>>>>>,
    /// How long a frame waits for the simulation (`LIVE_WAIT`).
    live_wait: std::time::Duration,
}

const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);
const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
const OPEN: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);
/// Blender's overlays toggle.
const OVERLAYS: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::SHIFT.plus(Modifiers::ALT), Key::Z);
const SAVE_AS: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::S);

impl ViewerApp {
    /// The viewer on `doc`; `report` and `cache` (the frame cache its live particles are simulated in) are
    /// shared with the viewport's GPU side.
    pub fn new(
        doc: Document,
        adapter: String,
        max_resolution: u32,
        report: Arc<Mutex<ViewportReport>>,
        cache: Arc<crate::frame::FrameCache>,
    ) -> Self {
        Self {
            cache,
            history: History::new(&doc.scene),
            home_camera: doc.scene.camera.clone(),
            path_input: doc
                .path()
                .map_or(String::new(), |p| p.display().to_string()),
            doc,
            view: ViewSettings::default(),
            adapter,
            max_resolution,
            viewport_px: [0, 0],
            viewport_rect: egui::Rect::NOTHING,
            pending: None,
            notice: None,
            now: 0.0,
            report,
            gesture: None,
            hovered: None,
            selection: None,
            selected_object: None,
            picked: None,
            scroll_to_selection: false,
            scroll_panel_to_top: false,
            mesh_at: DVec3::ZERO,
            dialog: None,
            recent: RecentFiles::default(),
            frame_times: VecDeque::new(),
            last_frame: None,
            requests: Vec::new(),
            playback: Playback::default(),
            animation_form: AnimationForm::default(),
            export_job: None,
            live: Latest::new("energywave live particles"),
            live_shown: Mutex::new(Vec::new()),
            live_wait: LIVE_WAIT,
        }
    }

    /// The scene as shown: the document's scene at the current frame of its animation. Its live particle sets
    /// are simulated on a thread of their own: a frame waits for them a moment (`LIVE_WAIT`: a frame of
    /// playback, or a short scrub, is ready within it), then shows the particles last simulated until they are
    /// ready; another frame or an edit cancels the simulation under way.
    pub fn frame_scene(&self) -> Scene {
        let scene = &self.doc.scene;
        if !scene.is_animated() {
            return scene.clone();
        }
        let frame = self.playback.frame;
        if !scene.particles.iter().any(|p| p.life().is_some()) {
            return scene.at_frame(frame as f64);
        }
        let key = (scene.clone(), frame);
        let job = || {
            let (scene, frame) = key.clone();
            let cache = self.cache.clone();
            move |cancel: &crate::background::Cancel| {
                scene.at_frame_in(frame as f64, cache.simulations(), cancel)
            }
        };
        match self.live.request_within(&key, self.live_wait, job) {
            Poll::Ready(shown) => {
                if let Ok(mut kept) = self.live_shown.lock() {
                    *kept = shown.particles.iter().map(|p| p.live.clone()).collect();
                }
                (*shown).clone()
            }
            Poll::Pending => {
                let kept = self
                    .live_shown
                    .lock()
                    .map(|k| k.clone())
                    .unwrap_or_default();
                scene.at_frame_with(frame as f64, |i| kept.get(i).cloned().flatten())
            }
        }
    }

    /// How long a frame waits for its live sets' simulation before it shows older particles (`LIVE_WAIT` by
    /// default; a test that checks the particles of a frame waits as long as it takes).
    pub fn set_preparation_wait(&mut self, wait: std::time::Duration) {
        self.live_wait = wait;
    }

    /// What the app itself is preparing on a thread of its own (the live sets' simulation), for the status line.
    pub fn preparing(&self) -> Option<&'static str> {
        self.live.busy().then_some("particle simulation")
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
                Some(Err(_)) if job.is_cancelled() => {
                    self.notify("Export cancelled: nothing written", false);
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
        let mut keys: Vec<f64> = (animation.tracks.iter())
            .flat_map(|t| t.keys.iter().map(|k| k.frame))
            .collect();
        keys.sort_by(f64::total_cmp);
        keys.dedup();
        egui::Panel::bottom("energywave.timeline").show(ui, |ui| {
            timeline::bar(ui, &mut self.playback, frames, frame_rate, &keys)
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
        cache: Arc<crate::frame::FrameCache>,
    ) {
        self.adapter = adapter;
        self.max_resolution = max_resolution;
        self.report = report;
        self.cache = cache;
    }

    /// Carries out what the user asked for: every action of the panels, the viewport, the shortcuts and the
    /// prompts comes through here.
    pub fn apply(&mut self, action: Action) {
        // A message is about what came before: the next action clears it.
        if !matches!(action, Action::Notify { .. }) {
            self.notice = None;
        }
        match action {
            Action::Open(path) => {
                if self.doc.is_dirty() {
                    self.pending = Some(Pending::Open(path));
                } else {
                    self.open_now(path);
                }
            }
            Action::Save => self.save(),
            Action::SaveAs(path) => match self.doc.save_as(&path) {
                Ok(()) => {
                    self.recent.add(&path);
                    self.path_input = path.display().to_string();
                    self.notify(format!("Saved {}", path.display()), false);
                }
                Err(e) => self.notify(e.to_string(), true),
            },
            Action::OpenDialog => {
                self.dialog = Some(FileDialog::beside(DialogMode::Open, &self.dialog_start()))
            }
            Action::SaveAsDialog => {
                self.dialog = Some(FileDialog::beside(DialogMode::SaveAs, &self.dialog_start()))
            }
            Action::Undo => {
                if self.history.undo(&mut self.doc.scene) {
                    self.notify("Undone", false);
                }
            }
            Action::Redo => {
                if self.history.redo(&mut self.doc.scene) {
                    self.notify("Redone", false);
                }
            }
            Action::AcceptReload => {
                let before = self.doc.scene.clone();
                self.doc.accept_reload();
                // The file changed on disk: what the frames resolved from what it no longer holds goes.
                (self.cache).invalidate(crate::frame::Changed::between(&before, &self.doc.scene));
            }
            Action::KeepMine => self.doc.pending_reload = None,
            Action::Screenshot => {
                let path = self.doc.screenshot_path(SystemTime::now());
                self.requests.push(Request::Screenshot {
                    path,
                    scale: self.view.screenshot_scale,
                });
            }
            Action::ToggleOverlays => self.view.show_overlays = !self.view.show_overlays,
            Action::FrameEffect => {
                let aspect = self.aspect();
                let scene = &mut self.doc.scene;
                navigation::frame_sources(&mut scene.camera, &scene.sources, aspect);
            }
            Action::ResetView => self.doc.scene.camera = self.home_camera.clone(),
            Action::Export {
                target,
                frames,
                size,
                transparent,
                holdout,
                fit,
                description,
            } => {
                if self.export_job.is_none() {
                    self.export_job = Some(ExportJob::start(
                        self.doc.scene.clone(),
                        target,
                        frames,
                        size,
                        (transparent, holdout, fit),
                        description,
                    ));
                }
            }
            Action::CancelExport => {
                if let Some(job) = &self.export_job {
                    job.cancel();
                }
            }
            Action::Notify { text, is_error } => self.notify(text, is_error),
            Action::Select(selection) => {
                self.selection = selection;
                if selection.is_some() {
                    self.selected_object = None;
                }
                self.picked = None;
            }
            Action::SelectObject(selected) => {
                self.selected_object = selected;
                if selected.is_some() {
                    self.selection = None;
                }
                self.picked = None;
            }
            Action::AddMesh(path, at) => self.add_mesh(&path, at),
            Action::AddMeshDialog(at) => {
                let start = (self.doc.path().and_then(|p| p.parent()))
                    .map_or_else(|| ".".to_owned(), |d| d.display().to_string());
                self.mesh_at = at;
                self.dialog = Some(FileDialog::new(DialogMode::Mesh, Path::new(&start), ""));
            }
            Action::Edit(edit) => {
                self.follow_renumbering(&edit);
                let added = match edit {
                    Edit::AddSource(kind, _) => Some(Some(kind)),
                    Edit::AddObject(..) | Edit::InsertObject(..) => Some(None),
                    _ => None,
                };
                edit.apply(&mut self.doc.scene, self.playback.frame as f64);
                // What was just added is selected (its handle ringed, its entry highlighted); the panel stays
                // where it is, by the button just clicked.
                match added {
                    Some(Some(kind)) => self.select_last_source(kind),
                    Some(None) => self.select_last_object(),
                    None => {}
                }
            }
        }
    }

    /// Selects the last source of `kind` (the one just added).
    fn select_last_source(&mut self, kind: SourceKind) {
        let s = &self.doc.scene.sources;
        let count = match kind {
            SourceKind::Points => s.points.len(),
            SourceKind::Lines => s.lines.len(),
            SourceKind::Tori => s.tori.len(),
            SourceKind::Curves => s.curves.len(),
        };
        if count > 0 {
            self.selection = Some((kind, count - 1));
            self.selected_object = None;
        }
    }

    /// Selects the last object (the one just added).
    fn select_last_object(&mut self) {
        if let Some(last) = self.doc.scene.objects.len().checked_sub(1) {
            self.selected_object = Some(last);
            self.selection = None;
        }
    }

    /// Reads the glTF file at `path` (relative to the scene file's folder, or absolute) and adds it as a mesh
    /// object at `at`; a file that does not read is reported and adds nothing.
    fn add_mesh(&mut self, path: &str, at: DVec3) {
        let written = std::path::PathBuf::from(path.trim());
        let base = (self.doc.path().and_then(|p| p.parent()))
            .map(|p| p.to_path_buf())
            .unwrap_or_default();
        let full = if written.is_absolute() {
            written.clone()
        } else {
            base.join(&written)
        };
        match crate::objects::MeshData::load(&full) {
            Ok(data) => {
                let object = crate::objects::Object {
                    shape: crate::objects::Shape::Mesh(crate::objects::MeshObject {
                        path: written,
                        translation: at,
                        rotation: DVec3::ZERO,
                        scale: DVec3::ONE,
                        data: std::sync::Arc::new(data),
                    }),
                    color: crate::scene::DEFAULT_ALBEDO,
                    translucent: None,
                };
                self.apply(Action::Edit(Edit::InsertObject(object)));
            }
            Err(e) => self.notify(format!("{}: {e}", full.display()), true),
        }
    }

    fn apply_all(&mut self, actions: Vec<Action>) {
        for action in actions {
            self.apply(action);
        }
    }

    pub fn undo(&mut self) {
        self.apply(Action::Undo);
    }

    pub fn redo(&mut self) {
        self.apply(Action::Redo);
    }

    /// The viewport's width over its height.
    fn aspect(&self) -> f64 {
        self.viewport_px[0].max(1) as f64 / self.viewport_px[1].max(1) as f64
    }

    /// The whole interface for one frame.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        self.now = ui.input(|i| i.time);
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
            Some(DiskChange::Invalid(e)) => self.notify_disk(
                format!(
                    "The file changed on disk but does not load; keeping the last good scene.\n{e}"
                ),
                true,
            ),
            Some(DiskChange::Conflict) => {
                self.notify_disk("The file changed on disk; you have unsaved changes", true)
            }
            None => {}
        }
        let actions = self.shortcuts(ui.ctx());
        self.apply_all(actions);
        self.expire_notice(ui.ctx());
        self.check_selection();

        egui::Panel::bottom("energywave.status").show(ui, |ui| self.status_bar(ui));
        self.animation_ui(ui);
        let shown = self.frame_scene();
        let actions = egui::Panel::left("energywave.panel")
            .resizable(true)
            .default_size(340.0)
            .show(ui, |ui| {
                let mut area = egui::ScrollArea::vertical();
                if std::mem::take(&mut self.scroll_panel_to_top) {
                    area = area.vertical_scroll_offset(0.0);
                }
                area.show(ui, |ui| {
                    let cx = panel::Context {
                        doc: &self.doc,
                        shown: &shown,
                        history: &self.history,
                        max_resolution: self.max_resolution,
                        aspect: self.aspect(),
                        frame: self.playback.frame,
                        selected: self.selection,
                        selected_object: self.selected_object,
                        scroll_to_selected: std::mem::take(&mut self.scroll_to_selection),
                        recent: self.recent.files(),
                    };
                    let mut actions = panel::show(ui, &cx, &mut self.path_input, &mut self.view);
                    ui.separator();
                    actions.extend(animation_panel::show(
                        ui,
                        &shown,
                        self.playback.frame,
                        &mut self.animation_form,
                        self.export_job.as_ref(),
                        self.doc.path(),
                    ));
                    actions
                })
                .inner
            })
            .inner;
        self.apply_all(actions);
        let actions = egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.viewport(ui))
            .inner;
        self.apply_all(actions);
        self.files_dropped(ui);
        self.file_dialog_ui(ui.ctx());
        self.unsaved_prompt(ui.ctx());

        // An edit is committed when it settles: no button held (a drag is one step).
        if !ui.ctx().input(|i| i.pointer.any_down()) {
            self.history.commit(&self.doc.scene);
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) -> Vec<Action> {
        let mut out = Vec::new();
        if ctx.input_mut(|i| i.consume_shortcut(&SAVE_AS)) {
            out.push(Action::SaveAsDialog);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&SAVE)) {
            out.push(Action::Save);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&OPEN)) {
            out.push(Action::OpenDialog);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&REDO) || i.consume_shortcut(&REDO_Y)) {
            out.push(Action::Redo);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&UNDO)) {
            out.push(Action::Undo);
        }
        if ctx.input_mut(|i| i.consume_shortcut(&OVERLAYS)) {
            out.push(Action::ToggleOverlays);
        }
        if ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F12)) {
            out.push(Action::Screenshot);
        }
        if !ctx.egui_wants_keyboard_input()
            && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F))
        {
            out.push(Action::FrameEffect);
        }
        out
    }
}
