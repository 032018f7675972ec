//! What the viewer lets its callers and tests read and set: the scene, the document, the view, the selection,
//! the form of the Animation section, the viewport's size and what the GPU side reported.

use super::*;

impl ViewerApp {
    /// The scene being edited (its base values: keyed parameters as the file holds them).
    pub fn scene(&self) -> &Scene {
        &self.doc.scene
    }

    /// The scene, for a change from outside the UI (a script, a test standing in for another tool): the next
    /// frame shows it, and commits it to the history as one edit.
    pub fn scene_mut(&mut self) -> &mut Scene {
        &mut self.doc.scene
    }

    /// The document: its file, whether it has unsaved changes, its title.
    pub fn document(&self) -> &Document {
        &self.doc
    }

    pub fn history(&self) -> &History {
        &self.history
    }

    /// How the scene is shown.
    pub fn view(&self) -> &ViewSettings {
        &self.view
    }

    pub fn view_mut(&mut self) -> &mut ViewSettings {
        &mut self.view
    }

    /// The file name typed in the panel's file section (what Open and Save As use).
    pub fn path_input_mut(&mut self) -> &mut String {
        &mut self.path_input
    }

    /// The Animation section's own fields: the parameter path being typed, the export's settings.
    pub fn animation_form_mut(&mut self) -> &mut AnimationForm {
        &mut self.animation_form
    }

    /// Keeps the recent files in `recent` (the window uses the user's list; a viewer under test keeps its own).
    pub fn set_recent(&mut self, recent: RecentFiles) {
        self.recent = recent;
    }

    /// The files opened and saved lately, newest first.
    pub fn recent_files(&self) -> &[PathBuf] {
        self.recent.files()
    }

    /// The file dialog, while it is open.
    pub fn file_dialog(&self) -> Option<&FileDialog> {
        self.dialog.as_ref()
    }

    /// The selected source, if any.
    pub fn selection(&self) -> Option<(SourceKind, usize)> {
        self.selection
    }

    /// The selected object, if any.
    pub fn selected_object(&self) -> Option<usize> {
        self.selected_object
    }

    /// The animation's current frame and transport.
    pub fn playback(&self) -> &Playback {
        &self.playback
    }

    /// Goes to `frame` of the animation (clamped to it), as the scrubber does.
    pub fn seek(&mut self, frame: u32) {
        let frames = self.doc.scene.frame_count();
        self.playback.seek(frame, frames);
    }

    /// Shows the animation's next frame (around its end), as playback does when the viewer keeps up with the
    /// animation's rate; returns that rate, or none without an animation.
    pub fn step_animation(&mut self) -> Option<f64> {
        let a = self.doc.scene.animation.as_ref()?;
        self.playback.step(1, a.frames);
        Some(a.frame_rate)
    }

    /// True while an export runs beside the UI.
    pub fn is_exporting(&self) -> bool {
        self.export_job.is_some()
    }

    /// The last message for the user, and whether it is an error.
    pub fn notice(&self) -> Option<&(String, bool)> {
        self.notice.as_ref().map(|n| &n.message)
    }

    /// Largest billboard resolution the device allows.
    pub fn max_resolution(&self) -> u32 {
        self.max_resolution
    }

    /// The viewport's size in physical pixels at the last frame.
    pub fn viewport_px(&self) -> [u32; 2] {
        self.viewport_px
    }

    /// The viewport's rectangle (egui points) at the last frame.
    pub fn viewport_rect(&self) -> egui::Rect {
        self.viewport_rect
    }

    /// What the viewport draws this frame: the scene as shown at the viewport's size.
    pub fn viewport_view(&self) -> ViewportView {
        ViewportView {
            scene: self.frame_scene(),
            size: [self.viewport_px[0].max(1), self.viewport_px[1].max(1)],
            show_grid: self.view.show_grid && self.view.show_overlays,
            average_frames: self.view.average_frames,
            progressive: self.view.progressive,
            pacing: self.view.pacing,
            threshold_preview: self
                .view
                .preview_glare_threshold
                .then(|| self.scene().glare.map(|g| g.threshold))
                .flatten(),
        }
    }

    /// What a screenshot at `scale` times the viewport draws: the scene as shown, its field integrated at
    /// `scale` times the billboard's resolution (as far as the device allows), so that a 4x screenshot is 4x
    /// the detail and not an enlargement; whole, not a preview.
    pub fn screenshot_view(&self, scale: u32) -> ViewportView {
        let mut view = self.viewport_view();
        view.size = view.size.map(|x| x * scale);
        view.progressive = false;
        view.threshold_preview = None;
        let w = &mut view.scene.billboard.resolution;
        *w = w
            .saturating_mul(scale)
            .min(self.max_resolution)
            .min(crate::scene::MAX_RESOLUTION);
        view
    }

    /// Takes what the UI asked of the window since the last call.
    pub fn take_requests(&mut self) -> Vec<Request> {
        std::mem::take(&mut self.requests)
    }

    /// What the GPU side reported.
    pub fn report(&self) -> ViewportReport {
        self.report.lock().map(|r| r.clone()).unwrap_or_default()
    }
}
