//! The side panel: every parameter of the scene, edited live. Values a user cannot sensibly enter are
//! prevented here (odd division counts, R <= 0, zero directions, ...), so the GPU never sees them.

use egui::{Color32, DragValue, Slider, Stroke, Ui};
use glam::DVec3;

use super::app::ViewerApp;
use crate::animation::SourceKind;
use crate::field::{Curve, Line, Point, Torus, wseries};
use crate::integrate::Integrator;
use crate::scene::limits;

/// Largest Simpson division count the panel offers (the file format allows more, for batch renders).
const PANEL_MAX_DIVISIONS: u32 = 4096;
/// Largest billboard resolution the panel offers: beyond it a frame takes seconds even on a real GPU (the file
/// format and the command line allow more, for batch renders).
pub const PANEL_MAX_RESOLUTION: u32 = 4096;
/// The tolerances the panel's drag value offers.
const PANEL_TOLERANCE: std::ops::RangeInclusive<f64> = 1e-7..=0.05;
// Whatever the panel offers, the scene loader accepts (`scene::limits`): an edited scene always saves and loads.
const _: () = assert!(PANEL_MAX_DIVISIONS <= limits::MAX_DIVISIONS);
const _: () = assert!(PANEL_MAX_RESOLUTION <= limits::MAX_RESOLUTION);
const _: () = assert!(
    *PANEL_TOLERANCE.start() > limits::MIN_TOLERANCE
        && *PANEL_TOLERANCE.end() < limits::MAX_TOLERANCE
);

/// Three drag values for a vector; returns true when it changed.
fn vec3(ui: &mut Ui, label: &str, v: &mut DVec3, speed: f64) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
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
    changed
}

/// A direction editor: the vector is normalised, and a zero vector is refused (the old one is kept).
fn direction(ui: &mut Ui, label: &str, v: &mut DVec3) {
    let mut edited = *v;
    if vec3(ui, label, &mut edited, 0.01) {
        if edited.length() > 1e-6 {
            *v = edited.normalize();
        } else {
            ui.colored_label(
                Color32::from_rgb(255, 110, 90),
                "a direction cannot be zero",
            );
        }
    }
}

fn color(ui: &mut Ui, label: &str, c: &mut [f64; 3]) {
    ui.horizontal(|ui| {
        let mut rgb = c.map(|x| x as f32);
        if ui.color_edit_button_rgb(&mut rgb).changed() {
            *c = rgb.map(|x| (x as f64).clamp(0.0, 1.0));
        }
        ui.label(label);
    });
}

/// A label and a value widget, the widget named by the label for accessibility (screen readers, UI tests).
pub(super) fn labelled(ui: &mut Ui, label: &str, widget: impl egui::Widget) -> egui::Response {
    let l = ui.label(label);
    ui.add(widget).labelled_by(l.id)
}

fn coefficient(ui: &mut Ui, c: &mut f64) {
    ui.horizontal(|ui| {
        labelled(
            ui,
            "coefficient",
            DragValue::new(c)
                .speed(0.05)
                .range(-1e4..=1e4)
                .max_decimals(3),
        );
    });
}

/// The panel.
pub fn show(ui: &mut Ui, app: &mut ViewerApp) {
    file_section(ui, app);
    ui.separator();
    view_section(ui, app);
    ui.separator();
    render_section(ui, app);
    ui.separator();
    sources_section(ui, app);
    ui.separator();
    super::animation_panel::show(ui, app);
}

fn file_section(ui: &mut Ui, app: &mut ViewerApp) {
    ui.heading(app.title());
    ui.horizontal(|ui| {
        ui.label("File");
        ui.add(
            egui::TextEdit::singleline(&mut app.path_input)
                .hint_text("scene.toml")
                .desired_width(f32::INFINITY),
        );
    });
    ui.horizontal(|ui| {
        if ui
            .button("Open")
            .on_hover_text("Open the file named above")
            .clicked()
        {
            app.open();
        }
        if ui.button("Save").on_hover_text("Ctrl+S").clicked() {
            app.save();
        }
        if ui
            .button("Save As")
            .on_hover_text("Save to the file named above")
            .clicked()
        {
            app.save_as();
        }
        ui.separator();
        let undo = ui
            .add_enabled(app.history.can_undo(), egui::Button::new("Undo"))
            .on_hover_text("Ctrl+Z");
        if undo.clicked() {
            app.undo();
        }
        let redo = ui
            .add_enabled(app.history.can_redo(), egui::Button::new("Redo"))
            .on_hover_text("Ctrl+Shift+Z");
        if redo.clicked() {
            app.redo();
        }
    });
    if let Some(error) = &app.doc.disk_error {
        ui.colored_label(
            Color32::from_rgb(255, 110, 90),
            format!("Not reloaded, keeping the last good scene:\n{error}"),
        );
    }
    if app.doc.pending_reload.is_some() {
        ui.horizontal(|ui| {
            ui.colored_label(Color32::from_rgb(255, 200, 90), "Changed on disk.");
            if ui.button("Reload (drop my edits)").clicked() {
                app.doc.accept_reload();
            }
            if ui.button("Keep mine").clicked() {
                app.doc.pending_reload = None;
            }
        });
    }
    ui.horizontal(|ui| {
        if ui
            .button("Screenshot")
            .on_hover_text("F12: the viewport, as PNG beside the scene")
            .clicked()
        {
            app.screenshot();
        }
        egui::ComboBox::new("energywave.screenshot_scale", "scale")
            .selected_text(format!("{}\u{d7}", app.screenshot_scale))
            .width(50.0)
            .show_ui(ui, |ui| {
                for s in [1, 2, 4] {
                    ui.selectable_value(&mut app.screenshot_scale, s, format!("{s}\u{d7}"));
                }
            });
    });
}

fn view_section(ui: &mut Ui, app: &mut ViewerApp) {
    egui::CollapsingHeader::new("View").default_open(false).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.checkbox(&mut app.show_grid, "grid");
            ui.checkbox(&mut app.show_handles, "handles");
            ui.checkbox(&mut app.progressive, "fast preview").on_hover_text(
                "While the view moves, integrate a coarser field that holds the frame rate, and refine \
                 it to the full one once still; off: the full field every frame",
            );
            if ui.button("Frame").on_hover_text("F: frame the effect").clicked() {
                app.frame_effect();
            }
            if ui.button("Reset view").clicked() {
                app.reset_view();
            }
        });
        let cam = &mut app.doc.scene.camera;
        let mut eye = cam.eye;
        let mut target = cam.target;
        let changed = vec3(ui, "eye", &mut eye, 0.05) | vec3(ui, "target", &mut target, 0.05);
        // The eye must not sit on the target.
        if changed && (eye - target).length() > 1e-6 {
            cam.eye = eye;
            cam.target = target;
        }
        let mut up = cam.up;
        direction(ui, "up", &mut up);
        if up.cross((cam.target - cam.eye).normalize()).length() > 1e-6 {
            cam.up = up;
        }
        ui.add(Slider::new(&mut cam.fov_y_degrees, 1.0..=150.0).text("field of view (\u{b0})"));
        ui.label("Drag: orbit \u{b7} right/middle drag: pan \u{b7} wheel: zoom \u{b7} drag a handle: move it");
    });
}

fn render_section(ui: &mut Ui, app: &mut ViewerApp) {
    let max_resolution = app.max_resolution;
    let average_frames = &mut app.average_frames;
    let scene = &mut app.doc.scene;
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            let i = &mut scene.integration;
            egui::Grid::new("energywave.integration")
                .num_columns(2)
                .show(ui, |ui| {
                    ui.label("integrator");
                    ui.horizontal(|ui| {
                        for integrator in [Integrator::Adaptive, Integrator::Simpson] {
                            ui.selectable_value(&mut i.integrator, integrator, integrator.name())
                                .on_hover_text(match integrator {
                                    Integrator::Adaptive => "Samples where the field needs them, to a tolerance (fast, no banding)",
                                    Integrator::Simpson => "The papers' n evenly spaced samples (bands at a low n)",
                                });
                        }
                    });
                    ui.end_row();
                    match i.integrator {
                        Integrator::Adaptive => {
                            i.jitter = None;
                            labelled(
                                ui,
                                "tolerance",
                                DragValue::new(&mut i.tolerance)
                                    .range(PANEL_TOLERANCE)
                                    .speed(1e-5)
                                    .max_decimals(7),
                            );
                            ui.end_row();
                        }
                        Integrator::Simpson => {
                            let mut n = i.divisions;
                            labelled(
                                ui,
                                "divisions n",
                                DragValue::new(&mut n)
                                    .range(2..=PANEL_MAX_DIVISIONS)
                                    .speed(2),
                            );
                            // Simpson's rule needs an even count.
                            i.divisions = (n + n % 2).clamp(2, PANEL_MAX_DIVISIONS);
                            ui.end_row();
                            let mut jitter = i.jitter.is_some();
                            ui.label("");
                            ui.checkbox(&mut jitter, "jitter (noise instead of bands)");
                            ui.end_row();
                            i.jitter = match (jitter, i.jitter) {
                                (true, Some(seed)) => Some(seed),
                                (true, None) => Some(0),
                                (false, _) => None,
                            };
                            if jitter {
                                labelled(
                                    ui,
                                    "average frames",
                                    DragValue::new(average_frames).range(1..=1024),
                                )
                                .on_hover_text(
                                    "While the view is still, average this many jittered frames \
                                     (the noise falls as 1/\u{221a}frames); 1: none",
                                );
                                ui.end_row();
                            }
                        }
                    }
                    let step = 0.005 * i.decay_length;
                    labelled(
                        ui,
                        "decay length",
                        DragValue::new(&mut i.decay_length)
                            .range(1e-3..=1e6)
                            .speed(step),
                    )
                    .on_hover_text(
                        "The depth past the billboard, in scene units, over which \u{3b6} falls from \
                         \u{3b1}/\u{3b2}\u{b2} to \u{3b1}/(1+\u{3b2})\u{b2}. Fixed in space: the look \
                         holds as the camera moves",
                    );
                    ui.end_row();
                    labelled(
                        ui,
                        "\u{3b1}",
                        DragValue::new(&mut i.alpha)
                            .range(0.001..=1000.0)
                            .speed(0.01),
                    );
                    ui.end_row();
                    labelled(
                        ui,
                        "\u{3b2}",
                        DragValue::new(&mut i.beta)
                            .range(0.001..=1000.0)
                            .speed(0.01),
                    );
                    ui.end_row();
                    labelled(
                        ui,
                        "\u{3b5} (clamp)",
                        DragValue::new(&mut i.epsilon)
                            .range(1e-6..=10.0)
                            .speed(0.001)
                            .max_decimals(6),
                    );
                    ui.end_row();
                    let b = &mut scene.billboard;
                    let top = max_resolution.clamp(8, PANEL_MAX_RESOLUTION);
                    labelled(
                        ui,
                        "resolution W",
                        DragValue::new(&mut b.resolution).range(8..=top).speed(4),
                    );
                    ui.end_row();
                });
            let b = &mut scene.billboard;
            let mut fixed = b.center.is_some();
            if ui
                .checkbox(&mut fixed, "fixed billboard (else placed automatically)")
                .changed()
            {
                if fixed {
                    let aspect =
                        app.viewport_px[0].max(1) as f64 / app.viewport_px[1].max(1) as f64;
                    let placed = crate::geometry::place_billboard(
                        &scene.camera,
                        &scene.sources,
                        None,
                        None,
                        aspect,
                    );
                    b.center = Some(placed.center);
                    b.size = Some(placed.size);
                } else {
                    b.center = None;
                    b.size = None;
                }
            }
            if let (Some(center), Some(size)) = (&mut b.center, &mut b.size) {
                let mut c = *center;
                // The billboard must not contain the eye.
                if vec3(ui, "center", &mut c, 0.05) && (c - scene.camera.eye).length() > 1e-6 {
                    *center = c;
                }
                ui.horizontal(|ui| {
                    labelled(
                        ui,
                        "size l",
                        DragValue::new(size).range(1e-3..=1e5).speed(0.05),
                    );
                });
            }
            color(ui, "energy Ce", &mut scene.colors.energy);
            color(ui, "background Cb", &mut scene.colors.background);
        });
}

fn sources_section(ui: &mut Ui, app: &mut ViewerApp) {
    let scene = &mut app.doc.scene;
    let target = scene.camera.target;
    ui.horizontal(|ui| {
        ui.strong("Sources");
        if ui.button("+ point").clicked() {
            scene.sources.points.push(Point {
                position: target,
                coefficient: 2.0,
            });
        }
        if ui.button("+ line").clicked() {
            scene.sources.lines.push(Line {
                point: target,
                direction: DVec3::X,
                coefficient: 0.5,
            });
        }
        if ui.button("+ torus").clicked() {
            scene.sources.tori.push(Torus {
                center: target,
                axis: DVec3::Y,
                major_radius: 1.0,
                coefficient: 3.0,
            });
        }
        if ui.button("+ curve").clicked() {
            scene.sources.curves.push(Curve {
                control_points: vec![
                    target - DVec3::X * 2.0,
                    target + DVec3::Y * 1.5,
                    target + DVec3::X * 2.0,
                ],
                coefficient: 4.0,
                weights: vec![],
            });
        }
    });
    let s = &mut scene.sources;
    let mut edits = Vec::new();
    edits.push((
        SourceKind::Points,
        list(ui, "Point", &mut s.points, |ui, p| {
            vec3(ui, "position", &mut p.position, 0.02);
            coefficient(ui, &mut p.coefficient);
        }),
    ));
    edits.push((
        SourceKind::Lines,
        list(ui, "Line", &mut s.lines, |ui, l| {
            vec3(ui, "point", &mut l.point, 0.02);
            direction(ui, "direction", &mut l.direction);
            coefficient(ui, &mut l.coefficient);
        }),
    ));
    let tori = list(ui, "Torus", &mut s.tori, |ui, t| {
        vec3(ui, "center", &mut t.center, 0.02);
        direction(ui, "axis", &mut t.axis);
        ui.horizontal(|ui| {
            labelled(
                ui,
                "radius R",
                DragValue::new(&mut t.major_radius)
                    .range(1e-3..=1e4)
                    .speed(0.01),
            );
        });
        coefficient(ui, &mut t.coefficient);
    });
    edits.push((SourceKind::Tori, tori));
    edits.push((
        SourceKind::Curves,
        list(ui, "Curve", &mut s.curves, curve_editor),
    ));
    // Pulses and keys follow their sources when a source is deleted or duplicated.
    if let Some(animation) = &mut scene.animation {
        for (kind, edit) in edits {
            match edit {
                Some(ListEdit::Deleted(i)) => animation.source_removed(kind, i),
                Some(ListEdit::Duplicated(i)) => animation.source_inserted(kind, i + 1),
                None => {}
            }
        }
    }
}

/// A source deleted or duplicated in a list.
enum ListEdit {
    Deleted(usize),
    Duplicated(usize),
}

/// A list of sources of one kind, each with its editor and Duplicate / Delete; says which was deleted or
/// duplicated.
fn list<T: Clone>(
    ui: &mut Ui,
    kind: &str,
    items: &mut Vec<T>,
    mut edit: impl FnMut(&mut Ui, &mut T),
) -> Option<ListEdit> {
    let mut duplicate = None;
    let mut delete = None;
    for (i, item) in items.iter_mut().enumerate() {
        egui::CollapsingHeader::new(format!("{kind} {}", i + 1))
            .id_salt((kind, i))
            .default_open(true)
            .show(ui, |ui| {
                edit(ui, item);
                ui.horizontal(|ui| {
                    if ui.small_button("Duplicate").clicked() {
                        duplicate = Some(i);
                    }
                    if ui.small_button("Delete").clicked() {
                        delete = Some(i);
                    }
                });
            });
    }
    if let Some(i) = duplicate {
        let copy = items[i].clone();
        items.insert(i + 1, copy);
        return Some(ListEdit::Duplicated(i));
    }
    if let Some(i) = delete {
        items.remove(i);
        return Some(ListEdit::Deleted(i));
    }
    None
}

fn curve_editor(ui: &mut Ui, c: &mut Curve) {
    coefficient(ui, &mut c.coefficient);
    let segments = (c.control_points.len() - 1) / 2;
    ui.label(format!(
        "{segments} segment(s), {} control points",
        c.control_points.len()
    ));
    for (k, p) in c.control_points.iter_mut().enumerate() {
        vec3(ui, &format!("B{k}"), p, 0.02);
    }
    ui.horizontal(|ui| {
        if ui
            .small_button("+ segment")
            .on_hover_text("Continue the chain smoothly")
            .clicked()
        {
            let n = c.control_points.len();
            let (end, before) = (c.control_points[n - 1], c.control_points[n - 2]);
            let tangent = end - before;
            // The new middle point on the end tangent keeps the joint smooth.
            c.control_points.push(end + tangent);
            c.control_points
                .push(end + tangent * 2.0 + tangent.any_orthonormal_vector() * tangent.length());
        }
        if ui
            .add_enabled(segments > 1, egui::Button::new("- segment").small())
            .clicked()
        {
            c.control_points.truncate(c.control_points.len() - 2);
        }
    });
    ui.label("Local intensity W");
    let mut remove = None;
    for (k, w) in c.weights.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.add(Slider::new(w, 0.0..=2.0).text(format!("w{k}")));
            if ui
                .small_button("remove")
                .on_hover_text(format!("Remove w{k}"))
                .clicked()
            {
                remove = Some(k);
            }
        });
    }
    if let Some(k) = remove {
        c.weights.remove(k);
    }
    ui.horizontal(|ui| {
        if ui.small_button("+ weight").clicked() {
            let last = c.weights.last().copied().unwrap_or(1.0);
            if c.weights.is_empty() {
                c.weights.push(1.0);
            }
            c.weights.push(last);
        }
        if !c.weights.is_empty()
            && ui
                .small_button("uniform")
                .on_hover_text("All weights 1 (no W series)")
                .clicked()
        {
            c.weights.clear();
        }
    });
    wseries_plot(ui, &c.weights);
}

/// A plot of Sw(t) over [0, 1] with the weights at their nominal parameters i / (n - 1).
pub(super) fn wseries_plot(ui: &mut Ui, weights: &[f64]) {
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
