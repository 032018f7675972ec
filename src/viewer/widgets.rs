//! The small editors the panels share: vectors, directions, colors, labelled values, the W series' plot.

use egui::{Color32, DragValue, Stroke, Ui};
use glam::DVec3;

use crate::field::wseries;

/// The color of messages about a value refused.
pub const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 90);
/// The color of keys: the key buttons of keyed parameters, the ticks on the scrubber.
pub const KEY_COLOR: Color32 = Color32::from_rgb(255, 185, 60);

/// Three drag values for a vector; returns true when it changed, and the row's rectangle.
pub fn vec3(ui: &mut Ui, label: &str, v: &mut DVec3, speed: f64) -> (bool, egui::Rect) {
    let mut changed = false;
    let row = ui.horizontal(|ui| {
        ui.label(label);
        for (axis, c) in ["x", "y", "z"].iter().zip(v.as_mut()) {
            changed |= ui
                .add(
                    DragValue::new(c)
                        .speed(speed)
                        .prefix(format!("{axis} "))
                        .max_decimals(4),
                )
                .changed();
        }
    });
    (changed, row.response.rect)
}

/// A direction editor: the new direction, normalised, when the user changed it (a zero vector is refused, and
/// said so), and the row's rectangle.
pub fn direction(ui: &mut Ui, label: &str, v: DVec3) -> (Option<DVec3>, egui::Rect) {
    let mut edited = v;
    let (changed, row) = vec3(ui, label, &mut edited, 0.01);
    if !changed {
        return (None, row);
    }
    if edited.length() > 1e-6 {
        (Some(edited.normalize()), row)
    } else {
        ui.colored_label(ERROR_COLOR, "a direction cannot be zero");
        (None, row)
    }
}

/// A color button; the new color when the user changed it, and the row's rectangle. The picker's f32 channels
/// come back as the shortest decimals that give the same f32 (a picked 0.97 is 0.97, not 0.9700000286102295).
pub fn color(ui: &mut Ui, label: &str, c: [f64; 3]) -> (Option<[f64; 3]>, egui::Rect) {
    let row = ui.horizontal(|ui| {
        let mut rgb = c.map(|x| x as f32);
        let changed = ui.color_edit_button_rgb(&mut rgb).changed();
        ui.label(label);
        changed.then(|| rgb.map(|x| shortest_f64(x).clamp(0.0, 1.0)))
    });
    (row.inner, row.response.rect)
}

/// The f64 of the shortest decimal that reads back as `x`.
pub fn shortest_f64(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(x as f64)
}

/// A label and a value widget, the widget named by the label for accessibility (screen readers, UI tests).
pub fn labelled(ui: &mut Ui, label: &str, widget: impl egui::Widget) -> egui::Response {
    let l = ui.label(label);
    ui.add(widget).labelled_by(l.id)
}

/// A plot of Sw(t) over [0, 1] with the weights at their nominal parameters i / (n - 1).
pub fn wseries_plot(ui: &mut Ui, weights: &[f64]) {
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(ui.available_width().min(300.0), 70.0),
        egui::Sense::hover(),
    );
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let top = weights.iter().copied().fold(1.0f64, f64::max) * 1.1;
    let to_screen = |t: f64, w: f64| {
        egui::pos2(
            rect.left() + t as f32 * rect.width(),
            rect.bottom() - (w / top) as f32 * rect.height(),
        )
    };
    let points: Vec<egui::Pos2> = (0..=100)
        .map(|k| {
            let t = k as f64 / 100.0;
            to_screen(t, wseries::evaluate(weights, t))
        })
        .collect();
    painter.add(egui::Shape::line(
        points,
        Stroke::new(1.5, Color32::from_rgb(120, 180, 255)),
    ));
    let n = weights.len();
    for (i, &w) in weights.iter().enumerate() {
        let t = if n > 1 {
            i as f64 / (n - 1) as f64
        } else {
            0.5
        };
        painter.circle_filled(to_screen(t, w), 2.5, Color32::from_rgb(255, 205, 60));
    }
}
