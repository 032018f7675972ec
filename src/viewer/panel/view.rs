//! The View section: grid, handles and fast preview, framing, and the camera's numbers.

use egui::{Slider, Ui};

use super::super::action::{Action, Edit};
use super::super::widgets::{direction, vec3};
use super::context::ViewSettings;
use super::fields::Edits;
use crate::scene::Scene;

pub(super) fn view_section(
    ui: &mut Ui,
    shown: &Scene,
    view: &mut ViewSettings,
    out: &mut Edits<'_>,
) {
    egui::CollapsingHeader::new("View").default_open(false).show(ui, |ui| {
        // Wrapped, so that opening the section never widens the panel.
        ui.horizontal_wrapped(|ui| {
            ui.checkbox(&mut view.show_overlays, "overlays")
                .on_hover_text("The grid, guides and handles at once (Shift+Alt+Z)");
            ui.add_enabled_ui(view.show_overlays, |ui| {
                ui.checkbox(&mut view.show_grid, "grid");
                ui.checkbox(&mut view.show_handles, "handles");
            });
            ui.checkbox(&mut view.progressive, "fast preview").on_hover_text(
                "While the view moves, integrate a coarser field that holds the frame rate, and refine \
                 it to the full one once still; off: the full field every frame",
            );
            if ui.button("Frame").on_hover_text("F: frame the effect").clicked() {
                out.push(Action::FrameEffect);
            }
            if ui.button("Reset view").clicked() {
                out.push(Action::ResetView);
            }
        });
        let mut cam = shown.camera.clone();
        let mut eye = cam.eye;
        let mut target = cam.target;
        let moved = vec3(ui, "eye", &mut eye, 0.05).0 | vec3(ui, "target", &mut target, 0.05).0;
        // The eye must not sit on the target.
        let mut changed = moved && (eye - target).length() > 1e-6;
        if changed {
            cam.eye = eye;
            cam.target = target;
        }
        if let (Some(up), _) = direction(ui, "up", cam.up)
            && up.cross((cam.target - cam.eye).normalize()).length() > 1e-6
        {
            cam.up = up;
            changed = true;
        }
        changed |= ui
            .add(Slider::new(&mut cam.fov_y_degrees, 1.0..=150.0).text("field of view (\u{b0})"))
            .changed();
        if changed {
            out.push(Action::Edit(Edit::Camera(cam)));
        }
        ui.label("Drag: orbit \u{b7} right/middle drag: pan \u{b7} wheel: zoom \u{b7} drag a handle: move it");
    });
}
