//! The viewer's files: saving, opening (now or after the unsaved-changes prompt), the file dialog, scenes
//! dropped onto the window, and quitting.

use super::*;

impl ViewerApp {
    /// Saves to the document's file, or to the typed path when it has none.
    pub(super) fn save(&mut self) {
        let result = match self.doc.save() {
            Ok(true) => Ok(()),
            Ok(false) => {
                if self.path_input.trim().is_empty() {
                    self.notify("Type a file name to save to, then Save As", true);
                    return;
                }
                self.doc.save_as(&PathBuf::from(self.path_input.trim()))
            }
            Err(e) => Err(e),
        };
        match result {
            Ok(()) => {
                let path = self.doc.path().map(Path::to_owned).unwrap_or_default();
                self.recent.add(&path);
                self.notify(format!("Saved {}", path.display()), false);
            }
            Err(e) => self.notify(e.to_string(), true),
        }
    }

    /// Where the file dialog starts: the typed path, else the document's file, else the working directory.
    pub(super) fn dialog_start(&self) -> String {
        if !self.path_input.trim().is_empty() {
            return self.path_input.clone();
        }
        self.doc
            .path()
            .map_or(String::new(), |p| p.display().to_string())
    }

    pub(super) fn open_now(&mut self, path: PathBuf) {
        match Document::open(&path) {
            Ok(doc) => {
                self.history.reset(&doc.scene);
                self.home_camera = doc.scene.camera.clone();
                self.doc = doc;
                // Another file: nothing the frames resolved from the old one is wanted again.
                self.cache.invalidate(crate::frame::Changed::ALL);
                // Another file: nothing of the old one stays selected, and its panel reads from the top.
                self.selection = None;
                self.selected_object = None;
                self.scroll_panel_to_top = true;
                self.recent.add(&path);
                self.path_input = path.display().to_string();
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

    /// A scene file dropped onto the window opens (asking first about unsaved changes); while files hover over
    /// the window, it says what a drop does.
    pub(super) fn files_dropped(&mut self, ui: &egui::Ui) {
        let (dropped, hovering) =
            ui.input(|i| (i.raw.dropped_files.clone(), !i.raw.hovered_files.is_empty()));
        if hovering {
            let rect = ui.ctx().content_rect();
            let painter = ui.ctx().layer_painter(egui::LayerId::new(
                egui::Order::Foreground,
                egui::Id::unique("energywave.drop"),
            ));
            painter.rect_filled(rect, 0.0, Color32::from_black_alpha(160));
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "Drop a .toml scene to open it",
                egui::FontId::proportional(22.0),
                Color32::WHITE,
            );
        }
        let Some(file) = dropped.into_iter().next() else {
            return;
        };
        let path = file.path().to_owned();
        if path.as_os_str().is_empty() {
            self.notify("The dropped file has no path to open", true);
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
        {
            self.apply(Action::Open(path));
        } else {
            self.notify(
                format!(
                    "{}: only scene files (.toml) open by dropping them here",
                    path.display()
                ),
                true,
            );
        }
    }

    /// The file dialog, while open: a choice opens or saves (through the same actions as the panel, so the
    /// unsaved-changes prompt covers it).
    pub(super) fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.dialog else {
            return;
        };
        let mode = dialog.mode();
        match dialog.show(ctx) {
            DialogOutcome::Open => {}
            DialogOutcome::Cancelled => self.dialog = None,
            DialogOutcome::Chosen(path) => {
                self.dialog = None;
                self.apply(match mode {
                    DialogMode::Open => Action::Open(path),
                    DialogMode::SaveAs => Action::SaveAs(path),
                    // Written relative to the scene's folder where it lies inside it, so the scene moves with
                    // its meshes.
                    DialogMode::Mesh => {
                        let base =
                            self.doc.path().and_then(|p| p.parent()).map(|d| {
                                std::path::absolute(d).unwrap_or_else(|_| d.to_path_buf())
                            });
                        let relative =
                            base.and_then(|b| path.strip_prefix(b).ok().map(Path::to_path_buf));
                        Action::AddMesh(
                            relative.unwrap_or(path).display().to_string(),
                            self.mesh_at,
                        )
                    }
                });
            }
        }
    }

    /// The prompt about unsaved changes before an open or a quit, while one waits.
    pub(super) fn unsaved_prompt(&mut self, ctx: &egui::Context) {
        #[derive(Clone, Copy)]
        enum Choice {
            Save,
            Discard,
            Cancel,
        }
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
                for (label, c) in [
                    ("Save", Choice::Save),
                    ("Discard", Choice::Discard),
                    ("Cancel", Choice::Cancel),
                ] {
                    if ui.button(label).clicked() {
                        choice = Some(c);
                    }
                }
            });
        });
        let proceed = match choice {
            Some(Choice::Save) => {
                self.save();
                !self.doc.is_dirty()
            }
            Some(Choice::Discard) => true,
            Some(Choice::Cancel) => {
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
