//! The viewer's file dialog, drawn with egui: a folder's subfolders and scene files, a name field, and Open or
//! Save. (egui-file-dialog, the kept crate for this, needs egui 0.36 at its latest release; this one is small
//! and shares the viewer's look, keyboard and accessibility, so the UI tests drive it like any panel.)

use std::path::{Path, PathBuf};

/// What the dialog is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DialogMode {
    /// Pick an existing scene file.
    Open,
    /// Pick where to save (a new name or an existing file, replaced after asking).
    SaveAs,
    /// Pick a glTF file (`.gltf`, `.glb`) to add as a mesh object.
    Mesh,
}

impl DialogMode {
    /// Whether the dialog lists a file of this name.
    fn lists(self, name: &str) -> bool {
        let ext = Path::new(name)
            .extension()
            .map(|x| x.to_string_lossy().to_ascii_lowercase());
        match self {
            DialogMode::Open | DialogMode::SaveAs => ext.as_deref() == Some("toml"),
            DialogMode::Mesh => matches!(ext.as_deref(), Some("gltf" | "glb")),
        }
    }
}

/// What the user did with the dialog this frame.
#[derive(Clone, Debug, PartialEq)]
pub enum DialogOutcome {
    /// Still choosing.
    Open,
    Cancelled,
    /// The file chosen.
    Chosen(PathBuf),
}

/// One line of the listing.
#[derive(Clone, Debug, PartialEq)]
struct Entry {
    name: String,
    is_dir: bool,
}

/// A file dialog over one folder at a time.
#[derive(Clone, Debug)]
pub struct FileDialog {
    mode: DialogMode,
    dir: PathBuf,
    /// The file name typed or clicked.
    name: String,
    entries: Vec<Entry>,
    /// Why the folder could not be listed, or the name not used.
    problem: Option<String>,
    /// Saving over this existing file waits for a second click.
    confirm_replace: Option<PathBuf>,
}

impl FileDialog {
    /// A dialog in `dir` (the current directory if it is not a folder) with `name` filled in.
    pub fn new(mode: DialogMode, dir: &Path, name: &str) -> Self {
        let dir = if dir.is_dir() {
            dir.to_owned()
        } else {
            std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."))
        };
        let mut d = Self {
            mode,
            dir: std::path::absolute(&dir).unwrap_or(dir),
            name: name.to_owned(),
            entries: Vec::new(),
            problem: None,
            confirm_replace: None,
        };
        d.list();
        d
    }

    /// A dialog beside `current` (a file or folder path, possibly typed), or in the working directory.
    pub fn beside(mode: DialogMode, current: &str) -> Self {
        let p = PathBuf::from(current.trim());
        if p.is_dir() {
            return Self::new(mode, &p, "");
        }
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_owned);
        let name = p
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        Self::new(mode, &dir, &name)
    }

    pub fn mode(&self) -> DialogMode {
        self.mode
    }

    /// The folder shown.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Reads the folder: subfolders first, then the files of the mode (scene files, `.toml`, or glTF), each in
    /// name order; hidden ones left out.
    fn list(&mut self) {
        self.entries.clear();
        self.confirm_replace = None;
        match std::fs::read_dir(&self.dir) {
            Ok(read) => {
                self.problem = None;
                for e in read.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    let is_dir = e.path().is_dir();
                    if !name.starts_with('.') && (is_dir || self.mode.lists(&name)) {
                        self.entries.push(Entry { name, is_dir });
                    }
                }
                self.entries.sort_by(|a, b| {
                    b.is_dir
                        .cmp(&a.is_dir)
                        .then_with(|| a.name.to_lowercase().cmp(&b.name.to_lowercase()))
                });
            }
            Err(e) => self.problem = Some(format!("{}: {e}", self.dir.display())),
        }
    }

    fn go(&mut self, dir: PathBuf) {
        self.dir = dir;
        self.list();
    }

    /// The file the name says: in the folder, with `.toml` added when saving a name without an extension.
    fn target(&self) -> Option<PathBuf> {
        let name = self.name.trim();
        if name.is_empty() {
            return None;
        }
        let mut p = self.dir.join(name);
        if self.mode == DialogMode::SaveAs && p.extension().is_none() {
            p.set_extension("toml");
        }
        Some(p)
    }

    /// Tries to finish with the name as it is.
    fn accept(&mut self) -> DialogOutcome {
        let Some(p) = self.target() else {
            self.problem = Some("Type or pick a file name".into());
            return DialogOutcome::Open;
        };
        if p.is_dir() {
            self.name.clear();
            self.go(p);
            return DialogOutcome::Open;
        }
        match self.mode {
            DialogMode::Open | DialogMode::Mesh if !p.is_file() => {
                self.problem = Some(format!("{} does not exist", p.display()));
                DialogOutcome::Open
            }
            DialogMode::SaveAs if p.exists() && self.confirm_replace.as_ref() != Some(&p) => {
                self.confirm_replace = Some(p);
                DialogOutcome::Open
            }
            _ => DialogOutcome::Chosen(p),
        }
    }

    /// The dialog for this frame.
    pub fn show(&mut self, ctx: &egui::Context) -> DialogOutcome {
        let title = match self.mode {
            DialogMode::Open => "Open a scene",
            DialogMode::SaveAs => "Save the scene as",
            DialogMode::Mesh => "Add a glTF mesh",
        };
        let action = match self.mode {
            DialogMode::Open => "Open",
            DialogMode::SaveAs => "Save",
            DialogMode::Mesh => "Add",
        };
        let mut outcome = DialogOutcome::Open;
        let modal = egui::Modal::new(egui::Id::unique("energywave.file_dialog")).show(ctx, |ui| {
            ui.set_width(460.0);
            ui.heading(title);
            ui.horizontal(|ui| {
                let parent = self.dir.parent().map(Path::to_owned);
                if ui
                    .add_enabled(parent.is_some(), egui::Button::new("Up"))
                    .on_hover_text("The folder above")
                    .clicked()
                    && let Some(p) = parent
                {
                    self.go(p);
                }
                ui.add(egui::Label::new(self.dir.display().to_string()).truncate());
            });
            egui::ScrollArea::vertical()
                .max_height(260.0)
                .auto_shrink([false, false])
                .show(ui, |ui| {
                    if self.entries.is_empty() && self.problem.is_none() {
                        ui.weak("(no folders or scene files here)");
                    }
                    let mut enter = None;
                    for e in &self.entries {
                        let label = if e.is_dir {
                            format!("{}/", e.name)
                        } else {
                            e.name.clone()
                        };
                        let r = ui.selectable_label(!e.is_dir && e.name == self.name, label);
                        if r.double_clicked() || (e.is_dir && r.clicked()) {
                            enter = Some(e.clone());
                        } else if r.clicked() {
                            self.name = e.name.clone();
                            self.confirm_replace = None;
                        }
                    }
                    match enter {
                        Some(e) if e.is_dir => {
                            let dir = self.dir.join(&e.name);
                            self.go(dir);
                        }
                        Some(e) => {
                            self.name = e.name;
                            outcome = self.accept();
                        }
                        None => {}
                    }
                });
            ui.horizontal(|ui| {
                let l = ui.label("name");
                let field = ui
                    .add(
                        egui::TextEdit::singleline(&mut self.name)
                            .hint_text(match self.mode {
                                DialogMode::Mesh => "model.glb",
                                _ => "scene.toml",
                            })
                            .desired_width(f32::INFINITY),
                    )
                    .labelled_by(l.id);
                if field.changed() {
                    self.confirm_replace = None;
                }
                if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                    outcome = self.accept();
                }
            });
            if let Some(p) = &self.confirm_replace {
                ui.colored_label(
                    egui::Color32::from_rgb(255, 200, 90),
                    format!(
                        "{} exists: Save again to replace it",
                        p.file_name().unwrap_or_default().to_string_lossy()
                    ),
                );
            }
            if let Some(problem) = &self.problem {
                ui.colored_label(super::widgets::ERROR_COLOR, problem);
            }
            ui.horizontal(|ui| {
                if ui.button(action).clicked() {
                    outcome = self.accept();
                }
                if ui.button("Cancel").clicked() {
                    outcome = DialogOutcome::Cancelled;
                }
            });
        });
        if modal.should_close() && outcome == DialogOutcome::Open {
            outcome = DialogOutcome::Cancelled;
        }
        outcome
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_has_folders_then_scenes_and_a_save_adds_the_extension() {
        let dir = std::env::temp_dir().join(format!("energywave-dialog-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("b_folder")).unwrap();
        std::fs::create_dir_all(dir.join(".hidden")).unwrap();
        for f in ["z.toml", "a.TOML", "notes.txt", "ring.glb", "Tree.GLTF"] {
            std::fs::write(dir.join(f), "").unwrap();
        }
        let d = FileDialog::new(DialogMode::Open, &dir, "");
        let names: Vec<&str> = d.entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["b_folder", "a.TOML", "z.toml"]);
        // "+ mesh" lists glTF files only, and picks an existing one.
        let mut m = FileDialog::new(DialogMode::Mesh, &dir, "");
        let names: Vec<&str> = m.entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["b_folder", "ring.glb", "Tree.GLTF"]);
        m.name = "ring.glb".into();
        assert_eq!(m.accept(), DialogOutcome::Chosen(dir.join("ring.glb")));
        m.name = "missing.glb".into();
        assert_eq!(m.accept(), DialogOutcome::Open);
        let mut s = FileDialog::new(DialogMode::SaveAs, &dir, "ring");
        assert_eq!(s.accept(), DialogOutcome::Chosen(dir.join("ring.toml")));
        // An existing file is replaced on the second try only.
        s.name = "z.toml".into();
        assert_eq!(s.accept(), DialogOutcome::Open);
        assert_eq!(s.accept(), DialogOutcome::Chosen(dir.join("z.toml")));
        // Opening a name that is not there says so.
        let mut o = FileDialog::new(DialogMode::Open, &dir, "missing.toml");
        assert_eq!(o.accept(), DialogOutcome::Open);
        assert!(o.problem.as_ref().unwrap().contains("does not exist"));
        // A folder's name enters it.
        o.name = "b_folder".into();
        assert_eq!(o.accept(), DialogOutcome::Open);
        assert_eq!(o.dir(), dir.join("b_folder"));
        let beside = FileDialog::beside(
            DialogMode::SaveAs,
            &dir.join("z.toml").display().to_string(),
        );
        assert_eq!(
            (beside.dir(), beside.name.as_str()),
            (dir.as_path(), "z.toml")
        );
    }
}
