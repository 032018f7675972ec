//! The panel's editors of animatable values, each with its key button, and where the panel puts what the user
//! asked for.

use egui::{DragValue, Ui};
use glam::DVec3;

use super::super::action::{Action, Edit};
use super::super::widgets::{KEY_COLOR, color, direction, vec3};
use crate::animation::{Animation, Parameter, Value};

/// Where the panel's editors put what the user asked for, with what their key buttons need.
pub(super) struct Edits<'a> {
    pub(super) actions: Vec<Action>,
    /// The scene's animation, if any: which parameters are keyed, and where.
    pub(super) animation: Option<&'a Animation>,
    /// The current frame: where a key goes.
    pub(super) frame: u32,
}

impl Edits<'_> {
    pub(super) fn push(&mut self, action: Action) {
        self.actions.push(action);
    }

    /// The key button beside an animatable field showing `value`, and the I key over the field's `row`: a key at
    /// the current frame with the value shown (the scene becomes animated if it was still). The button marks a
    /// keyed parameter (outlined) and a key at this frame (filled, and a click removes it).
    pub(super) fn key_button(
        &mut self,
        ui: &mut Ui,
        parameter: Parameter,
        value: Value,
        row: egui::Rect,
    ) {
        let frame = self.frame as f64;
        let track = self
            .animation
            .and_then(|a| a.tracks.iter().find(|t| t.parameter == parameter));
        let here = track.is_some_and(|t| t.keys.iter().any(|k| k.frame == frame));
        let side = ui.spacing().interact_size.y * 0.8;
        let (rect, response) = ui.allocate_exact_size(egui::vec2(side, side), egui::Sense::click());
        let name = format!("key {parameter}");
        response
            .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Button, ui.is_enabled(), &name));
        let color = if track.is_some() {
            KEY_COLOR
        } else if response.hovered() {
            ui.visuals().strong_text_color()
        } else {
            ui.visuals().weak_text_color()
        };
        let c = rect.center();
        let r = side * 0.38;
        let diamond = vec![
            c + egui::vec2(0.0, -r),
            c + egui::vec2(r, 0.0),
            c + egui::vec2(0.0, r),
            c + egui::vec2(-r, 0.0),
        ];
        let fill = if here {
            color
        } else {
            egui::Color32::TRANSPARENT
        };
        ui.painter().add(egui::Shape::convex_polygon(
            diamond,
            fill,
            egui::Stroke::new(1.3, color),
        ));
        let at = self.frame;
        let hover = if here {
            format!("{parameter}: remove its key at frame {at}")
        } else {
            format!("{parameter}: key the value shown at frame {at} (or press I over the field)")
        };
        let clicked = response.on_hover_text(hover).clicked();
        let typed = !ui.ctx().egui_wants_keyboard_input()
            && ui.rect_contains_pointer(row)
            && ui.input_mut(|i| i.consume_key(egui::Modifiers::NONE, egui::Key::I));
        if clicked && here {
            self.push(Action::Edit(Edit::Unkey(parameter)));
        } else if clicked || typed {
            self.push(Action::Edit(Edit::Key(parameter, value)));
        }
    }
}

/// A drag value for an animatable number, with its key button: a `Set` when the user changed it.
pub(super) fn number(
    ui: &mut Ui,
    out: &mut Edits<'_>,
    label: &str,
    parameter: Parameter,
    value: f64,
    widget: impl FnOnce(&mut f64) -> DragValue<'_>,
) -> egui::Response {
    let mut x = value;
    let name = ui.label(label);
    // The field and its key button share one cell (of a grid's second column).
    let response = ui
        .horizontal(|ui| {
            let response = ui.add(widget(&mut x)).labelled_by(name.id);
            out.key_button(ui, parameter, Value::Number(value), response.rect);
            response
        })
        .inner;
    if response.changed() && x != value {
        out.push(Action::set_number(parameter, x));
    }
    response
}

/// A vector editor for an animatable position, with its key button on the same row.
pub(super) fn position(
    ui: &mut Ui,
    out: &mut Edits<'_>,
    label: &str,
    parameter: Parameter,
    p: DVec3,
) {
    ui.horizontal(|ui| {
        let mut q = p;
        let (changed, row) = vec3(ui, label, &mut q, 0.02);
        if changed {
            out.push(Action::set_vector(parameter, q));
        }
        out.key_button(ui, parameter, Value::Vector(p.to_array()), row);
    });
}

/// A direction editor for an animatable axis, with its key button on the same row.
pub(super) fn axis(ui: &mut Ui, out: &mut Edits<'_>, label: &str, parameter: Parameter, d: DVec3) {
    ui.horizontal(|ui| {
        let (edited, row) = direction(ui, label, d);
        if let Some(d) = edited {
            out.push(Action::set_vector(parameter, d));
        }
        out.key_button(ui, parameter, Value::Vector(d.to_array()), row);
    });
}

/// A color editor for an animatable color, with its key button on the same row.
pub(super) fn color_field(
    ui: &mut Ui,
    out: &mut Edits<'_>,
    label: &str,
    parameter: Parameter,
    c: [f64; 3],
) {
    ui.horizontal(|ui| {
        let (edited, row) = color(ui, label, c);
        if let Some(c) = edited {
            out.push(Action::set_vector(parameter, DVec3::from_array(c)));
        }
        out.key_button(ui, parameter, Value::Vector(c), row);
    });
}
