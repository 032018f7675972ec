//! The file section: the document's title, its file (typed, or through the dialog), Recent, undo and redo, the
//! file changed on disk, screenshots.

use egui::Ui;

use super::super::action::Action;
use super::super::widgets::ERROR_COLOR;
use super::context::{Context, ViewSettings};
use super::fields::Edits;

pub(super) fn file_section(
    ui: &mut Ui,
    cx: &Context,
    path: &mut String,
    view: &mut ViewSettings,
    out: &mut Edits<'_>,
) {
    ui.heading(cx.doc.title());
    ui.horizontal(|ui| {
        let l = ui.label("File");
        let field = ui
            .add(
                egui::TextEdit::singleline(path)
                    .hint_text("scene.toml")
                    .desired_width(f32::INFINITY),
            )
            .labelled_by(l.id)
            .on_hover_text("A scene file's path; Enter opens it");
        if field.lost_focus()
            && ui.input(|i| i.key_pressed(egui::Key::Enter))
            && !path.trim().is_empty()
        {
            out.push(Action::Open(std::path::PathBuf::from(path.trim())));
        }
    });
    ui.horizontal_wrapped(|ui| {
        if ui
            .button("Open\u{2026}")
            .on_hover_text("Ctrl+O: choose a scene file (or drop one onto the window)")
            .clicked()
        {
            out.push(Action::OpenDialog);
        }
        if ui.button("Save").on_hover_text("Ctrl+S").clicked() {
            out.push(Action::Save);
        }
        if ui
            .button("Save As\u{2026}")
            .on_hover_text("Ctrl+Shift+S: choose where to save")
            .clicked()
        {
            out.push(Action::SaveAsDialog);
        }
        ui.menu_button("Recent", |ui| {
            if cx.recent.is_empty() {
                ui.weak("(none yet)");
            }
            for p in cx.recent {
                let name = p.file_name().map_or(p.display().to_string(), |n| {
                    n.to_string_lossy().into_owned()
                });
                if ui
                    .button(name)
                    .on_hover_text(p.display().to_string())
                    .clicked()
                {
                    out.push(Action::Open(p.clone()));
                    ui.close();
                }
            }
        });
    });
    // Undo and Redo on a row of their own: they never wrap away from the file buttons as the panel's width
    // changes.
    ui.horizontal(|ui| {
        let undo = ui
            .add_enabled(cx.history.can_undo(), egui::Button::new("Undo"))
            .on_hover_text("Ctrl+Z");
        if undo.clicked() {
            out.push(Action::Undo);
        }
        let redo = ui
            .add_enabled(cx.history.can_redo(), egui::Button::new("Redo"))
            .on_hover_text("Ctrl+Shift+Z");
        if redo.clicked() {
            out.push(Action::Redo);
        }
    });
    if let Some(error) = &cx.doc.disk_error {
        ui.add(
            egui::Label::new(
                egui::RichText::new(format!(
                    "Not reloaded, keeping the last good scene:\n{error}"
                ))
                .color(ERROR_COLOR),
            )
            .wrap(),
        );
    }
    if cx.doc.pending_reload.is_some() {
        ui.colored_label(
            egui::Color32::from_rgb(255, 200, 90),
            "The file changed on disk, and you have unsaved edits.",
        );
        // Wrapped, so that the buttons never widen the panel (and push the viewport aside).
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Reload")
                .on_hover_text("Take the file's new content; your edits are dropped")
                .clicked()
            {
                out.push(Action::AcceptReload);
            }
            if ui
                .button("Keep mine")
                .on_hover_text("Keep your edits; saving overwrites the file")
                .clicked()
            {
                out.push(Action::KeepMine);
            }
        });
    }
    let shots = cx.doc.screenshot_dir();
    ui.horizontal(|ui| {
        if ui
            .button("Screenshot")
            .on_hover_text(format!(
                "F12: the viewport as PNG, its field integrated at the scale chosen, into {}",
                shots.display()
            ))
            .clicked()
        {
            out.push(Action::Screenshot);
        }
        egui::ComboBox::new("energywave.screenshot_scale", "scale")
            .selected_text(format!("{}\u{d7}", view.screenshot_scale))
            .width(50.0)
            .show_ui(ui, |ui| {
                for s in [1, 2, 4] {
                    ui.selectable_value(&mut view.screenshot_scale, s, format!("{s}\u{d7}"));
                }
            });
    });
    ui.add(
        egui::Label::new(
            egui::RichText::new(format!("into {}", shots.display()))
                .small()
                .weak(),
        )
        .truncate(),
    )
    .on_hover_text(format!("Screenshots go to {}", shots.display()));
}
