//! The side panel: every parameter of the scene, edited live. Values a user cannot sensibly enter are
//! prevented here (odd division counts, R <= 0, zero directions, ...), so the GPU never sees them.

use egui::{Color32, DragValue, Slider, Stroke, Ui};
use glam::DVec3;

use super::app::ViewerApp;
use crate::animation::{
    Animation, CurvePulse, MAX_FRAMES, Parameter, Pulse, SourceKind, Track, Value,
};
use crate::export::Target;
use crate::field::{Curve, Line, Point, Torus, wseries};
use crate::scene::MAX_DIVISIONS;

/// Largest Simpson division count the panel offers (the file format allows more, for batch renders).
const PANEL_MAX_DIVISIONS: u32 = 4096;
/// Largest billboard resolution the panel offers: beyond it a frame takes seconds even on a real GPU (the file
/// format and the command line allow more, for batch renders).
pub const PANEL_MAX_RESOLUTION: u32 = 4096;
const _: () = assert!(PANEL_MAX_DIVISIONS <= MAX_DIVISIONS);

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
fn labelled(ui: &mut Ui, label: &str, widget: impl egui::Widget) -> egui::Response {
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
    animation_section(ui, app);
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
    let scene = &mut app.doc.scene;
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            let i = &mut scene.integration;
            egui::Grid::new("energywave.integration")
                .num_columns(2)
                .show(ui, |ui| {
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
                    labelled(
                        ui,
                        "\u{3bd} (ray reach)",
                        DragValue::new(&mut i.nu).range(1.01..=50.0).speed(0.01),
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
fn wseries_plot(ui: &mut Ui, weights: &[f64]) {
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

/// What an export from the viewer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportKind {
    /// One PNG per frame, numbered.
    Sequence,
    Gif,
    /// A flipbook grid PNG with its layout as JSON beside it.
    Sheet,
}

/// The Animation section's fields that are not the document's: the parameter path being typed and the
/// export's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationForm {
    /// A parameter path to key, as the scene file names it.
    pub new_track: String,
    /// Where to export; empty means beside the scene file.
    pub export_path: String,
    pub export_kind: ExportKind,
    pub transparent: bool,
    /// Width and height of exported frames, pixels.
    pub size: [u32; 2],
}

impl Default for AnimationForm {
    fn default() -> Self {
        Self {
            new_track: String::new(),
            export_path: String::new(),
            export_kind: ExportKind::Sequence,
            transparent: false,
            size: [256, 256],
        }
    }
}

impl AnimationForm {
    /// The export's path: the typed one, or beside the scene (`name_####.png`, `name.gif`,
    /// `name_sheet.png`; the working directory for the embedded default scene).
    pub fn export_target_path(&self, scene_path: Option<&std::path::Path>) -> std::path::PathBuf {
        if !self.export_path.trim().is_empty() {
            return self.export_path.trim().into();
        }
        let stem = scene_path
            .and_then(|p| p.file_stem())
            .map_or("energywave".to_owned(), |s| {
                s.to_string_lossy().into_owned()
            });
        let name = match self.export_kind {
            ExportKind::Sequence => format!("{stem}_####.png"),
            ExportKind::Gif => format!("{stem}.gif"),
            ExportKind::Sheet => format!("{stem}_sheet.png"),
        };
        match scene_path.and_then(|p| p.parent()) {
            Some(dir) if !dir.as_os_str().is_empty() => dir.join(name),
            _ => name.into(),
        }
    }
}

/// A number editor for a keyed value (a vector as three), named by the label `name`.
fn value_editor(ui: &mut Ui, value: &mut Value, color: bool, name: egui::Id) {
    match value {
        Value::Number(x) => {
            ui.add(DragValue::new(x).speed(0.02).max_decimals(4))
                .labelled_by(name);
        }
        Value::Vector(v) => {
            for c in v.iter_mut() {
                let mut d = DragValue::new(c).speed(0.02).max_decimals(4);
                if color {
                    d = d.range(0.0..=1.0).speed(0.005);
                }
                ui.add(d).labelled_by(name);
            }
        }
    }
}

/// Time: the timeline's settings, pulses along curves, keyed parameters, and the export.
fn animation_section(ui: &mut Ui, app: &mut ViewerApp) {
    let frame = app.playback.frame;
    egui::CollapsingHeader::new("Animation")
        .default_open(true)
        .show(ui, |ui| {
            let scene = &mut app.doc.scene;
            let Some(animation) = &scene.animation else {
                ui.label("A still scene.");
                if ui
                    .button("Animate")
                    .on_hover_text(
                        "Add a timeline: then pulses along curves and keys on any parameter",
                    )
                    .clicked()
                {
                    scene.animation = Some(Animation::default());
                }
                return;
            };
            let current = scene.at_frame(frame as f64);
            let mut animation = animation.clone();
            egui::Grid::new("energywave.timeline_settings")
                .num_columns(2)
                .show(ui, |ui| {
                    labelled(
                        ui,
                        "frame rate (1/s)",
                        DragValue::new(&mut animation.frame_rate)
                            .range(0.01..=10000.0)
                            .speed(0.1),
                    );
                    ui.end_row();
                    labelled(
                        ui,
                        "length (frames)",
                        DragValue::new(&mut animation.frames).range(1..=MAX_FRAMES),
                    );
                    ui.end_row();
                });
            let mut remove_animation = false;
            ui.horizontal(|ui| {
                if ui
                    .small_button("natural length")
                    .on_hover_text("Until the last pulse has passed and the last key")
                    .clicked()
                {
                    animation.frames =
                        Animation::natural_length(&animation.pulses, &animation.tracks);
                }
                if ui
                    .small_button("make still")
                    .on_hover_text("Remove the animation (pulses and keys too)")
                    .clicked()
                {
                    remove_animation = true;
                }
            });

            ui.strong("Travelling pulses");
            if scene.sources.curves.is_empty() {
                ui.label("(add a curve to run a pulse along it)");
            }
            for (i, curve) in scene.sources.curves.iter().enumerate() {
                let index = animation.pulses.iter().position(|p| p.curve == i);
                let mut on = index.is_some();
                if ui
                    .checkbox(&mut on, format!("Curve {}: pulse", i + 1))
                    .on_hover_text(
                        "The curve's W series runs the thesis's travelling pulse (eq. 5.1)",
                    )
                    .changed()
                {
                    match index {
                        Some(k) => {
                            animation.pulses.remove(k);
                        }
                        None => animation.pulses.push(CurvePulse {
                            curve: i,
                            pulse: Pulse::thesis(if curve.weights.is_empty() {
                                Pulse::THESIS_COUNT
                            } else {
                                curve.weights.len()
                            }),
                        }),
                    }
                }
                let Some(p) = animation.pulses.iter_mut().find(|p| p.curve == i) else {
                    continue;
                };
                let p = &mut p.pulse;
                egui::Grid::new(("energywave.pulse", i))
                    .num_columns(2)
                    .show(ui, |ui| {
                        labelled(ui, "weights", DragValue::new(&mut p.count).range(1..=1024));
                        ui.end_row();
                        labelled(
                            ui,
                            "speed",
                            DragValue::new(&mut p.speed)
                                .range(0.001..=1000.0)
                                .speed(0.01),
                        );
                        ui.end_row();
                        labelled(
                            ui,
                            "width (frames)",
                            DragValue::new(&mut p.width).range(0.001..=1e6).speed(0.1),
                        );
                        ui.end_row();
                        labelled(
                            ui,
                            "delay per weight",
                            DragValue::new(&mut p.delay).range(-1e6..=1e6).speed(0.1),
                        );
                        ui.end_row();
                        labelled(ui, "start frame", DragValue::new(&mut p.start).speed(0.5));
                        ui.end_row();
                        let mut periodic = p.period.is_some();
                        let name = ui.checkbox(&mut periodic, "repeat every").id;
                        let mut period = p.period.unwrap_or(p.natural_length().max(1.0));
                        ui.add_enabled(
                            periodic,
                            DragValue::new(&mut period)
                                .range(0.001..=1e7)
                                .suffix(" frames"),
                        )
                        .labelled_by(name);
                        p.period = periodic.then_some(period);
                        ui.end_row();
                    });
                if ui.small_button("thesis's values").clicked() {
                    *p = Pulse::thesis(p.count);
                }
                ui.label(format!("W at frame {frame}"));
                wseries_plot(ui, &p.weights(frame as f64));
            }

            ui.strong("Keyed parameters");
            let mut delete_track = None;
            for (t, track) in animation.tracks.iter_mut().enumerate() {
                let color = matches!(
                    track.parameter,
                    Parameter::EnergyColor | Parameter::BackgroundColor
                );
                egui::CollapsingHeader::new(track.parameter.to_string())
                    .id_salt(("energywave.track", t))
                    .default_open(true)
                    .show(ui, |ui| {
                        let mut remove_key = None;
                        let n = track.keys.len();
                        for k in 0..n {
                            // Frames stay in order: each key between its neighbours.
                            let lo = if k > 0 {
                                track.keys[k - 1].frame + 1.0
                            } else {
                                0.0
                            };
                            let hi = if k + 1 < n {
                                track.keys[k + 1].frame - 1.0
                            } else {
                                MAX_FRAMES as f64
                            };
                            let key = &mut track.keys[k];
                            let range = lo.min(key.frame)..=hi.max(key.frame);
                            ui.horizontal(|ui| {
                                let name = ui.label(format!("key {}", k + 1)).id;
                                ui.add(
                                    DragValue::new(&mut key.frame)
                                        .range(range)
                                        .speed(0.2)
                                        .prefix("frame "),
                                )
                                .labelled_by(name);
                                value_editor(ui, &mut key.value, color, name);
                                if ui.small_button("remove").clicked() {
                                    remove_key = Some(k);
                                }
                            });
                        }
                        if let Some(k) = remove_key {
                            track.keys.remove(k);
                        }
                        ui.horizontal(|ui| {
                            if ui
                                .small_button(format!("key at frame {frame}"))
                                .on_hover_text("Set a key here to the value shown now")
                                .clicked()
                                && let Some(v) = track
                                    .value_at(frame as f64)
                                    .or_else(|| track.parameter.get(&current))
                            {
                                track.set_key(frame as f64, v);
                            }
                            if ui.small_button("delete track").clicked() {
                                delete_track = Some(t);
                            }
                        });
                    });
            }
            if let Some(t) = delete_track {
                animation.tracks.remove(t);
            }
            animation.tracks.retain(|t| !t.keys.is_empty());
            ui.horizontal(|ui| {
                ui.add(
                    egui::TextEdit::singleline(&mut app.animation_form.new_track)
                        .hint_text("curves[0].coefficient")
                        .desired_width(170.0),
                );
                if ui
                    .button(format!("key at frame {frame}"))
                    .on_hover_text(crate::animation::PARAMETER_FORMS)
                    .clicked()
                {
                    let path = app.animation_form.new_track.trim().to_owned();
                    match Parameter::parse(&path) {
                        Ok(parameter) => match parameter.get(&current) {
                            Some(value) => {
                                match animation
                                    .tracks
                                    .iter_mut()
                                    .find(|t| t.parameter == parameter)
                                {
                                    Some(track) => track.set_key(frame as f64, value),
                                    None => animation.tracks.push(Track {
                                        parameter,
                                        keys: vec![crate::animation::Key {
                                            frame: frame as f64,
                                            value,
                                        }],
                                    }),
                                }
                                app.animation_form.new_track.clear();
                            }
                            None => {
                                app.notice = Some((
                                    format!(
                                        "{path}: the scene has no such source, point or weight"
                                    ),
                                    true,
                                ))
                            }
                        },
                        Err(e) => app.notice = Some((e, true)),
                    }
                }
            });

            animation.retain_valid(scene);
            scene.animation = (!remove_animation).then_some(animation);
        });
    export_section(ui, app);
}

/// Export of the animation to files, on a thread of its own.
fn export_section(ui: &mut Ui, app: &mut ViewerApp) {
    let Some(animation) = &app.doc.scene.animation else {
        return;
    };
    let frames = animation.frames;
    egui::CollapsingHeader::new("Export")
        .default_open(false)
        .show(ui, |ui| {
            let form = &mut app.animation_form;
            ui.horizontal(|ui| {
                ui.selectable_value(&mut form.export_kind, ExportKind::Sequence, "PNG sequence");
                ui.selectable_value(&mut form.export_kind, ExportKind::Gif, "GIF");
                ui.selectable_value(&mut form.export_kind, ExportKind::Sheet, "sprite sheet");
            });
            let default_path = AnimationForm {
                export_path: String::new(),
                ..form.clone()
            }
            .export_target_path(app.doc.path());
            ui.add(
                egui::TextEdit::singleline(&mut form.export_path)
                    .hint_text(default_path.display().to_string())
                    .desired_width(f32::INFINITY),
            );
            ui.horizontal(|ui| {
                let name = ui.label("size").id;
                ui.add(
                    DragValue::new(&mut form.size[0])
                        .range(1..=4096)
                        .suffix(" px"),
                )
                .labelled_by(name);
                ui.label("\u{d7}");
                ui.add(
                    DragValue::new(&mut form.size[1])
                        .range(1..=4096)
                        .suffix(" px"),
                )
                .labelled_by(name);
                ui.add_enabled(
                    form.export_kind != ExportKind::Gif,
                    egui::Checkbox::new(&mut form.transparent, "transparent"),
                )
                .on_hover_text("alpha = min(B, 1), to composite over anything (not in a GIF)");
            });
            if let Some(job) = &app.export_job {
                let status = job.status();
                ui.add(
                    egui::ProgressBar::new(status.done as f32 / status.total.max(1) as f32).text(
                        format!(
                            "{}: {}/{} frames",
                            job.description, status.done, status.total
                        ),
                    ),
                );
                return;
            }
            if ui
                .button(format!("Export {frames} frames"))
                .on_hover_text("Renders every frame of the animation on a second GPU device")
                .clicked()
            {
                let path = form.export_target_path(app.doc.path());
                let sheet = form.export_kind == ExportKind::Sheet;
                let transparent = form.transparent && form.export_kind != ExportKind::Gif;
                let checked = Target::for_output(&path, sheet, None).and_then(|target| {
                    let expected = match form.export_kind {
                        ExportKind::Sequence => matches!(target, Target::Sequence { .. }),
                        ExportKind::Gif => matches!(target, Target::Gif { .. }),
                        ExportKind::Sheet => matches!(target, Target::Sheet { .. }),
                    };
                    if !expected {
                        return Err(crate::export::ExportError::Target {
                            path: path.clone(),
                            why: "does not fit the kind chosen: a sequence needs a run of # \
                                  (name_####.png), a GIF ends in .gif, a sheet in .png"
                                .into(),
                        });
                    }
                    if let Target::Sheet { path, columns } = &target {
                        crate::export::sheet_grid(
                            path,
                            form.size[0],
                            form.size[1],
                            0..frames,
                            *columns,
                            30.0,
                        )?;
                    }
                    Ok(target)
                });
                match checked {
                    Ok(target) => {
                        let description = path.display().to_string();
                        app.export_job = Some(super::timeline::ExportJob::start(
                            app.doc.scene.clone(),
                            target,
                            0..frames,
                            (form.size[0], form.size[1]),
                            transparent,
                            description,
                        ));
                    }
                    Err(e) => app.notice = Some((e.to_string(), true)),
                }
            }
        });
}
