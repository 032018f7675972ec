//! The Sources section: every source's editors, adding, duplicating and deleting, and selection.

use egui::{DragValue, Slider, Ui};

use super::super::action::{Action, Edit};
use super::super::widgets::wseries_plot;
use super::context::Context;
use super::fields::{Edits, axis, color_field, number, position};
use crate::animation::{Parameter, SourceKind, Value};
use crate::field::{Curve, Look, WForm, brightest};
use crate::scene::{Colors, MAX_INTENSITY};
use glam::DVec3;

pub(super) fn sources_section(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
    let shown = cx.shown;
    let target = shown.camera.target;
    ui.horizontal(|ui| {
        ui.strong("Sources");
        for (label, kind) in [
            ("+ point", SourceKind::Points),
            ("+ line", SourceKind::Lines),
            ("+ torus", SourceKind::Tori),
            ("+ curve", SourceKind::Curves),
        ] {
            if ui.button(label).clicked() {
                out.push(Action::Edit(Edit::AddSource(kind, target)));
            }
        }
    });
    let s = &shown.sources;
    list(
        ui,
        cx,
        out,
        "Point",
        SourceKind::Points,
        &s.points,
        |ui, out, i, p| {
            position(
                ui,
                out,
                "position",
                Parameter::Position(SourceKind::Points, i),
                p.position,
            );
            coefficient(ui, out, SourceKind::Points, i, p.coefficient);
            look_editor(
                ui,
                out,
                &shown.colors,
                (SourceKind::Points, i),
                &p.look,
                false,
            );
        },
    );
    list(
        ui,
        cx,
        out,
        "Line",
        SourceKind::Lines,
        &s.lines,
        |ui, out, i, l| {
            position(
                ui,
                out,
                "point",
                Parameter::Position(SourceKind::Lines, i),
                l.point,
            );
            axis(
                ui,
                out,
                "direction",
                Parameter::Direction(SourceKind::Lines, i),
                l.direction,
            );
            coefficient(ui, out, SourceKind::Lines, i, l.coefficient);
            look_editor(
                ui,
                out,
                &shown.colors,
                (SourceKind::Lines, i),
                &l.look,
                false,
            );
        },
    );
    list(
        ui,
        cx,
        out,
        "Torus",
        SourceKind::Tori,
        &s.tori,
        |ui, out, i, t| {
            position(
                ui,
                out,
                "center",
                Parameter::Position(SourceKind::Tori, i),
                t.center,
            );
            axis(
                ui,
                out,
                "axis",
                Parameter::Direction(SourceKind::Tori, i),
                t.axis,
            );
            ui.horizontal(|ui| {
                number(
                    ui,
                    out,
                    "radius R",
                    Parameter::MajorRadius(i),
                    t.major_radius,
                    |x| DragValue::new(x).range(1e-3..=1e4).speed(0.01),
                );
            });
            coefficient(ui, out, SourceKind::Tori, i, t.coefficient);
            look_editor(
                ui,
                out,
                &shown.colors,
                (SourceKind::Tori, i),
                &t.look,
                false,
            );
        },
    );
    let pulsed = |i: usize| {
        shown
            .animation
            .as_ref()
            .is_some_and(|a| a.pulses.iter().any(|p| p.curve == i))
    };
    list(
        ui,
        cx,
        out,
        "Curve",
        SourceKind::Curves,
        &s.curves,
        |ui, out, i, c| {
            curve_editor(ui, out, i, c, pulsed(i));
            let series = !c.color_series.is_empty();
            look_editor(
                ui,
                out,
                &shown.colors,
                (SourceKind::Curves, i),
                &c.look,
                series,
            );
            color_series_editor(ui, out, &shown.colors, i, c);
        },
    );
}

pub(super) fn coefficient(ui: &mut Ui, out: &mut Edits<'_>, kind: SourceKind, i: usize, c: f64) {
    ui.horizontal(|ui| {
        number(
            ui,
            out,
            "coefficient",
            Parameter::Coefficient(kind, i),
            c,
            |x| {
                DragValue::new(x)
                    .speed(0.05)
                    .range(-1e4..=1e4)
                    .max_decimals(3)
            },
        );
    });
}

/// A source's color: the scene's, or its own color and intensity (each keyable); a curve's color series
/// (`series`) stands for its one color.
pub(super) fn look_editor(
    ui: &mut Ui,
    out: &mut Edits<'_>,
    colors: &Colors,
    (kind, i): (SourceKind, usize),
    look: &Look,
    series: bool,
) {
    let own = look.color.is_some() || look.intensity.is_some() || series;
    let mut checked = own;
    let swatch = colors.color_of(look);
    ui.horizontal(|ui| {
        let toggle = ui
            .checkbox(&mut checked, "own color")
            .on_hover_text("A color and intensity of its own, instead of the scene's energy Ce");
        if !own {
            color_swatch(ui, swatch);
        }
        if toggle.changed() {
            out.push(if checked {
                Action::set_vector(
                    Parameter::SourceColor(kind, i),
                    DVec3::from_array(look.color.unwrap_or(colors.energy)),
                )
            } else {
                Action::Edit(Edit::InheritLook(kind, i))
            });
        }
    });
    if !own {
        return;
    }
    if !series {
        color_field(
            ui,
            out,
            "color",
            Parameter::SourceColor(kind, i),
            look.color.unwrap_or(colors.energy),
        );
    }
    ui.horizontal(|ui| {
        number(
            ui,
            out,
            "intensity",
            Parameter::Intensity(kind, i),
            colors.intensity_of(look),
            |x| {
                DragValue::new(x)
                    .speed(0.02)
                    .range(0.0..=MAX_INTENSITY)
                    .max_decimals(3)
            },
        )
        .on_hover_text("Multiplies the color: above 1 the glow is brighter than a display color (HDR, kept in EXR)");
    });
}

/// Curve `i`'s color series: a color editor (keyable) per control color with its removal, one more, and the
/// gradient it makes along the chain.
fn color_series_editor(ui: &mut Ui, out: &mut Edits<'_>, colors: &Colors, i: usize, c: &Curve) {
    if c.color_series.is_empty() {
        if ui
            .small_button("+ color series")
            .on_hover_text("A color along the chain, from its first end to its last (a white core to a colored tip)")
            .clicked()
        {
            out.push(Action::Edit(Edit::AddSeriesColor(i)));
        }
        return;
    }
    ui.label("Color along the curve");
    for (j, &color) in c.color_series.iter().enumerate() {
        ui.horizontal(|ui| {
            color_field(
                ui,
                out,
                &format!("c{j}"),
                Parameter::SeriesColor(i, j),
                color,
            );
            if ui
                .small_button(format!("remove c{j}"))
                .on_hover_text(format!("Remove c{j} from the color series"))
                .clicked()
            {
                out.push(Action::Edit(Edit::RemoveSeriesColor(i, j)));
            }
        });
    }
    if ui.small_button("+ color").clicked() {
        out.push(Action::Edit(Edit::AddSeriesColor(i)));
    }
    gradient_strip(ui, |t| colors.color_along(c, t));
}

/// The colors `color(t)` for t from 0 to 1 as a strip (intensities above 1 shown clamped).
fn gradient_strip(ui: &mut Ui, color: impl Fn(f64) -> [f64; 3]) {
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(ui.available_width().min(300.0), 14.0),
        egui::Sense::hover(),
    );
    let steps = 64;
    let painter = ui.painter_at(rect);
    for k in 0..steps {
        let t = (k as f64 + 0.5) / steps as f64;
        let [r, g, b] = color(t).map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
        let x0 = rect.left() + rect.width() * k as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (k + 1) as f32 / steps as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range()),
            0.0,
            egui::Color32::from_rgb(r, g, b),
        );
    }
}

/// A small square of a color (an intensity above 1 shown clamped).
fn color_swatch(ui: &mut Ui, c: [f64; 3]) {
    let side = ui.spacing().interact_size.y * 0.8;
    let (rect, _) = ui.allocate_exact_size(egui::vec2(side, side), egui::Sense::hover());
    let [r, g, b] = c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
    ui.painter()
        .rect_filled(rect, 2.0, egui::Color32::from_rgb(r, g, b));
}

/// A list of sources of one kind, each with its editor and Duplicate / Delete. A source's name selects it (its
/// handles ringed in the viewport); the selected source's entry is highlighted, and scrolled to when it was
/// selected in the viewport.
pub(super) fn list<T>(
    ui: &mut Ui,
    cx: &Context,
    out: &mut Edits<'_>,
    label: &str,
    kind: SourceKind,
    items: &[T],
    mut editor: impl FnMut(&mut Ui, &mut Edits<'_>, usize, &T),
) {
    for (i, item) in items.iter().enumerate() {
        let selected = cx.selected == Some((kind, i));
        let entry = Entry {
            id: ui.make_persistent_id((label, i)),
            title: format!("{label} {}", i + 1),
            hover: "Select: its handles are ringed in the viewport",
            selected,
            scroll: selected && cx.scroll_to_selected,
            select: Action::Select((!selected).then_some((kind, i))),
            duplicate: Edit::DuplicateSource(kind, i),
            delete: Edit::DeleteSource(kind, i),
        };
        entry.show(ui, out, |ui, out| editor(ui, out, i, item));
    }
}

/// One entry of a list in the panel (a source, an object): framed and highlighted when selected, its name a
/// selectable label that selects it (or clears the selection), its editors, then Duplicate and Delete.
pub(super) struct Entry {
    pub(super) id: egui::Id,
    pub(super) title: String,
    pub(super) hover: &'static str,
    pub(super) selected: bool,
    /// Scroll the entry into view (it was selected in the viewport).
    pub(super) scroll: bool,
    /// What a click on its name asks for.
    pub(super) select: Action,
    pub(super) duplicate: Edit,
    pub(super) delete: Edit,
}

impl Entry {
    pub(super) fn show(
        self,
        ui: &mut Ui,
        out: &mut Edits<'_>,
        body: impl FnOnce(&mut Ui, &mut Edits<'_>),
    ) {
        let frame = if self.selected {
            egui::Frame::NONE
                .fill(ui.visuals().selection.bg_fill.gamma_multiply(0.25))
                .stroke(ui.visuals().selection.stroke)
                .corner_radius(3.0)
        } else {
            egui::Frame::NONE
        };
        let Entry {
            id,
            title,
            hover,
            selected,
            scroll,
            select,
            duplicate,
            delete,
        } = self;
        frame.show(ui, |ui| {
            let state = egui::collapsing_header::CollapsingState::load_with_default_open(
                ui.ctx(),
                id,
                true,
            );
            let (_, header, _) = state
                .show_header(ui, |ui| {
                    let name = ui.selectable_label(selected, title).on_hover_text(hover);
                    if name.clicked() {
                        out.push(select);
                    }
                    name
                })
                .body(|ui| {
                    body(ui, out);
                    ui.horizontal(|ui| {
                        if ui.small_button("Duplicate").clicked() {
                            out.push(Action::Edit(duplicate));
                        }
                        if ui.small_button("Delete").clicked() {
                            out.push(Action::Edit(delete));
                        }
                    });
                });
            if scroll {
                header.inner.scroll_to_me(Some(egui::Align::TOP));
            }
        });
    }
}

/// Curve `i`: its coefficient, control points, segments and W series (`pulsed`: the W series is the
/// animation's travelling pulse, shown and not edited here).
pub(super) fn curve_editor(ui: &mut Ui, out: &mut Edits<'_>, i: usize, c: &Curve, pulsed: bool) {
    coefficient(ui, out, SourceKind::Curves, i, c.coefficient);
    let segments = (c.control_points.len() - 1) / 2;
    ui.label(format!(
        "{segments} segment(s), {} control points",
        c.control_points.len()
    ));
    for (k, &p) in c.control_points.iter().enumerate() {
        position(ui, out, &format!("B{k}"), Parameter::ControlPoint(i, k), p);
    }
    ui.horizontal(|ui| {
        if ui
            .small_button("+ segment")
            .on_hover_text("Continue the chain smoothly")
            .clicked()
        {
            out.push(Action::Edit(Edit::AddSegment(i)));
        }
        if ui
            .add_enabled(segments > 1, egui::Button::new("- segment").small())
            .clicked()
        {
            out.push(Action::Edit(Edit::RemoveSegment(i)));
        }
    });
    ui.label("Local intensity W");
    if pulsed {
        ui.label("Driven by its travelling pulse (Animation section)");
        wseries_plot(ui, &c.weights);
        return;
    }
    for (k, &w) in c.weights.iter().enumerate() {
        ui.horizontal(|ui| {
            let mut x = w;
            let slider = ui.add(Slider::new(&mut x, 0.0..=2.0).text(format!("w{k}")));
            if slider.changed() && x != w {
                out.push(Action::set_number(Parameter::Weight(i, k), x));
            }
            out.key_button(ui, Parameter::Weight(i, k), Value::Number(w), slider.rect);
            if ui
                .small_button("remove")
                .on_hover_text(format!("Remove w{k}"))
                .clicked()
            {
                out.push(Action::Edit(Edit::RemoveWeight(i, k)));
            }
        });
    }
    ui.horizontal(|ui| {
        if ui.small_button("+ weight").clicked() {
            out.push(Action::Edit(Edit::AddWeight(i)));
        }
        if !c.weights.is_empty()
            && ui
                .small_button("uniform")
                .on_hover_text("All weights 1 (no W series)")
                .clicked()
        {
            out.push(Action::Edit(Edit::UniformWeights(i)));
        }
    });
    wseries_plot(ui, &c.weights);
    w_form_editor(ui, out, i, c);
}

/// How a curve's W series weighs its term, offered where the series varies (elsewhere both forms are one term).
fn w_form_editor(ui: &mut Ui, out: &mut Edits<'_>, i: usize, c: &Curve) {
    if brightest::uniform(&c.weights) {
        return;
    }
    let mut continuous = c.w_form == WForm::Continuous;
    let toggle = ui
        .checkbox(&mut continuous, "continuous (no seam)")
        .on_hover_text(
            "W at the chain's brightest point seen from each place, max Sw(t) / d: no edge where the nearest point \
             jumps between parts of the chain. Off: the papers' W at the nearest point",
        );
    if toggle.changed() {
        let form = if continuous {
            WForm::Continuous
        } else {
            WForm::Nearest
        };
        out.push(Action::Edit(Edit::WForm(i, form)));
    }
}
