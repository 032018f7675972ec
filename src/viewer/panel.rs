//! The side panel: every parameter of the scene, edited live. It reads the scene as shown (at the current
//! frame of its animation) and returns what the user asked for as actions; `ViewerApp::apply` carries them
//! out. Values a user cannot sensibly enter are prevented here (odd division counts, R <= 0, zero
//! directions, ...), so the GPU never sees them.

use egui::{DragValue, Slider, Ui};
use glam::DVec3;

use super::action::{Action, Edit};
use super::document::Document;
use super::history::History;
use super::widgets::{ERROR_COLOR, KEY_COLOR, color, direction, labelled, vec3, wseries_plot};
use crate::animation::{Animation, IntegrationSetting, Parameter, SourceKind, Value};
use crate::field::Curve;
use crate::integrate::Integrator;
use crate::scene::{Blend, Scene, limits};

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

/// Jittered frames the viewport averages while the view is still, unless set otherwise: the noise falls to
/// 1/8 of one frame's.
pub const DEFAULT_AVERAGE_FRAMES: u32 = 64;

/// How the viewer shows the scene: the viewer's own settings, edited by the panel in place (they are not
/// part of the document and have no undo).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSettings {
    pub show_grid: bool,
    pub show_handles: bool,
    /// With jitter: how many frames the viewport averages while the view is still (1: none).
    pub average_frames: u32,
    /// While the view moves, show a coarse field sized to the frame budget and refine it once still
    /// (`progressive`); off: every frame integrates the full field.
    pub progressive: bool,
    /// Screenshot size relative to the viewport: 1, 2 or 4.
    pub screenshot_scale: u32,
}

impl Default for ViewSettings {
    fn default() -> Self {
        Self {
            show_grid: true,
            show_handles: true,
            average_frames: DEFAULT_AVERAGE_FRAMES,
            progressive: true,
            screenshot_scale: 1,
        }
    }
}

/// What the panel reads and does not edit.
pub struct Context<'a> {
    /// The document: its title, file and the state of its file on disk.
    pub doc: &'a Document,
    /// The scene as shown: the document's at the current frame of its animation.
    pub shown: &'a Scene,
    pub history: &'a History,
    /// Largest billboard resolution the device allows.
    pub max_resolution: u32,
    /// The viewport's width over its height.
    pub aspect: f64,
    /// The animation's current frame (where a key goes).
    pub frame: u32,
    /// The selected source: its entry is highlighted.
    pub selected: Option<(SourceKind, usize)>,
    /// Scroll the selected source's entry into view (it was selected in the viewport).
    pub scroll_to_selected: bool,
    /// The files opened and saved lately, newest first.
    pub recent: &'a [std::path::PathBuf],
}

/// The panel's file, view, rendering and sources sections (the Animation section is `animation_panel`).
/// `path` is the file name typed in the file section.
pub fn show(ui: &mut Ui, cx: &Context, path: &mut String, view: &mut ViewSettings) -> Vec<Action> {
    let mut out = Edits {
        actions: Vec::new(),
        animation: cx.shown.animation.as_ref(),
        frame: cx.frame,
    };
    file_section(ui, cx, path, view, &mut out);
    ui.separator();
    view_section(ui, cx.shown, view, &mut out);
    ui.separator();
    render_section(ui, cx, view, &mut out);
    ui.separator();
    sources_section(ui, cx, &mut out);
    out.actions
}

/// Where the panel's editors put what the user asked for, with what their key buttons need.
struct Edits<'a> {
    actions: Vec<Action>,
    /// The scene's animation, if any: which parameters are keyed, and where.
    animation: Option<&'a Animation>,
    /// The current frame: where a key goes.
    frame: u32,
}

impl Edits<'_> {
    fn push(&mut self, action: Action) {
        self.actions.push(action);
    }

    /// The key button beside an animatable field showing `value`, and the I key over the field's `row`: a key at
    /// the current frame with the value shown (the scene becomes animated if it was still). The button marks a
    /// keyed parameter (outlined) and a key at this frame (filled, and a click removes it).
    fn key_button(&mut self, ui: &mut Ui, parameter: Parameter, value: Value, row: egui::Rect) {
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

fn file_section(
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
        ui.separator();
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

fn view_section(ui: &mut Ui, shown: &Scene, view: &mut ViewSettings, out: &mut Edits<'_>) {
    egui::CollapsingHeader::new("View").default_open(false).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.checkbox(&mut view.show_grid, "grid");
            ui.checkbox(&mut view.show_handles, "handles");
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

/// A drag value for an animatable number, with its key button: a `Set` when the user changed it.
fn number(
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
fn position(ui: &mut Ui, out: &mut Edits<'_>, label: &str, parameter: Parameter, p: DVec3) {
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
fn axis(ui: &mut Ui, out: &mut Edits<'_>, label: &str, parameter: Parameter, d: DVec3) {
    ui.horizontal(|ui| {
        let (edited, row) = direction(ui, label, d);
        if let Some(d) = edited {
            out.push(Action::set_vector(parameter, d));
        }
        out.key_button(ui, parameter, Value::Vector(d.to_array()), row);
    });
}

/// A color editor for an animatable color, with its key button on the same row.
fn color_field(ui: &mut Ui, out: &mut Edits<'_>, label: &str, parameter: Parameter, c: [f64; 3]) {
    ui.horizontal(|ui| {
        let (edited, row) = color(ui, label, c);
        if let Some(c) = edited {
            out.push(Action::set_vector(parameter, DVec3::from_array(c)));
        }
        out.key_button(ui, parameter, Value::Vector(c), row);
    });
}

fn render_section(ui: &mut Ui, cx: &Context, view: &mut ViewSettings, out: &mut Edits<'_>) {
    let scene = cx.shown;
    let i = &scene.integration;
    let edit = |out: &mut Edits<'_>, e: Edit| out.push(Action::Edit(e));
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            egui::Grid::new("energywave.integration")
                .num_columns(2)
                .show(ui, |ui| {
                    ui.label("integrator");
                    ui.horizontal(|ui| {
                        for integrator in [Integrator::Adaptive, Integrator::Simpson] {
                            let hint = match integrator {
                                Integrator::Adaptive => "Samples where the field needs them, to a tolerance (fast, no banding)",
                                Integrator::Simpson => "The papers' n evenly spaced samples (bands at a low n)",
                            };
                            if ui
                                .selectable_label(i.integrator == integrator, integrator.name())
                                .on_hover_text(hint)
                                .clicked()
                                && i.integrator != integrator
                            {
                                edit(out, Edit::Integrator(integrator));
                            }
                        }
                    });
                    ui.end_row();
                    match i.integrator {
                        Integrator::Adaptive => {
                            let mut t = i.tolerance;
                            let r = labelled(
                                ui,
                                "tolerance",
                                DragValue::new(&mut t)
                                    .range(PANEL_TOLERANCE)
                                    .speed(1e-5)
                                    .max_decimals(7),
                            );
                            if r.changed() && t != i.tolerance {
                                edit(out, Edit::Tolerance(t));
                            }
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
                            let n = (n + n % 2).clamp(2, PANEL_MAX_DIVISIONS);
                            if n != i.divisions {
                                edit(out, Edit::Divisions(n));
                            }
                            ui.end_row();
                            let mut jitter = i.jitter.is_some();
                            ui.label("");
                            if ui
                                .checkbox(&mut jitter, "jitter (noise instead of bands)")
                                .changed()
                            {
                                edit(out, Edit::Jitter(jitter.then_some(i.jitter.unwrap_or(0))));
                            }
                            ui.end_row();
                            if jitter {
                                labelled(
                                    ui,
                                    "average frames",
                                    DragValue::new(&mut view.average_frames).range(1..=1024),
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
                    let setting = |k| Parameter::Integration(k);
                    number(
                        ui,
                        out,
                        "decay length",
                        setting(IntegrationSetting::DecayLength),
                        i.decay_length,
                        |x| DragValue::new(x).range(1e-3..=1e6).speed(step),
                    )
                    .on_hover_text(
                        "The depth past the billboard, in scene units, over which \u{3b6} falls from \
                         \u{3b1}/\u{3b2}\u{b2} to \u{3b1}/(1+\u{3b2})\u{b2}. Fixed in space: the look \
                         holds as the camera moves",
                    );
                    ui.end_row();
                    number(ui, out, "\u{3b1}", setting(IntegrationSetting::Alpha), i.alpha, |x| {
                        DragValue::new(x).range(0.001..=1000.0).speed(0.01)
                    });
                    ui.end_row();
                    number(ui, out, "\u{3b2}", setting(IntegrationSetting::Beta), i.beta, |x| {
                        DragValue::new(x).range(0.001..=1000.0).speed(0.01)
                    });
                    ui.end_row();
                    number(
                        ui,
                        out,
                        "\u{3b5} (clamp)",
                        setting(IntegrationSetting::Epsilon),
                        i.epsilon,
                        |x| {
                            DragValue::new(x)
                                .range(1e-6..=10.0)
                                .speed(0.001)
                                .max_decimals(6)
                        },
                    );
                    ui.end_row();
                    let top = cx.max_resolution.clamp(8, PANEL_MAX_RESOLUTION);
                    let mut w = scene.billboard.resolution;
                    let r = labelled(
                        ui,
                        "resolution W",
                        DragValue::new(&mut w).range(8..=top).speed(4),
                    );
                    if r.changed() && w != scene.billboard.resolution {
                        edit(out, Edit::Resolution(w));
                    }
                    ui.end_row();
                });
            billboard_editor(ui, cx, out);
            color_field(ui, out, "energy Ce", Parameter::EnergyColor, scene.colors.energy);
            color_field(
                ui,
                out,
                "background Cb",
                Parameter::BackgroundColor,
                scene.colors.background,
            );
            ui.horizontal(|ui| {
                ui.label("blend");
                for (blend, hint) in [
                    (
                        Blend::Papers,
                        "The papers' clamp((1 - B) Cb + B Ce): where B > 1 it subtracts the background",
                    ),
                    (
                        Blend::Over,
                        "clamp(B Ce + (1 - min(B, 1)) Cb): the same wherever B <= 1, white-hot cores over any \
                         background, and what the transparent export composites to",
                    ),
                ] {
                    if ui
                        .selectable_label(scene.colors.blend == blend, blend.name())
                        .on_hover_text(hint)
                        .clicked()
                        && scene.colors.blend != blend
                    {
                        out.push(Action::Edit(Edit::Blend(blend)));
                    }
                }
            });
        });
}

/// Fixed or automatic placement of the billboard; a fixed one's center and size.
fn billboard_editor(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
    let scene = cx.shown;
    let b = &scene.billboard;
    let mut fixed = b.center.is_some();
    if ui
        .checkbox(&mut fixed, "fixed billboard (else placed automatically)")
        .changed()
    {
        let placement = fixed.then(|| {
            // Fixed where it is now.
            let placed = crate::geometry::place_billboard(
                &scene.camera,
                &scene.sources,
                None,
                None,
                cx.aspect,
            );
            (placed.center, placed.size)
        });
        out.push(Action::Edit(Edit::Billboard(placement)));
    }
    if let (Some(center), Some(size)) = (b.center, b.size) {
        let mut c = center;
        // The billboard must not contain the eye.
        if vec3(ui, "center", &mut c, 0.05).0 && (c - scene.camera.eye).length() > 1e-6 {
            out.push(Action::Edit(Edit::Billboard(Some((c, size)))));
        }
        ui.horizontal(|ui| {
            let mut l = size;
            let r = labelled(
                ui,
                "size l",
                DragValue::new(&mut l).range(1e-3..=1e5).speed(0.05),
            );
            if r.changed() && l != size {
                out.push(Action::Edit(Edit::Billboard(Some((center, l)))));
            }
        });
    }
}

fn sources_section(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
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
        |ui, out, i, c| curve_editor(ui, out, i, c, pulsed(i)),
    );
}

fn coefficient(ui: &mut Ui, out: &mut Edits<'_>, kind: SourceKind, i: usize, c: f64) {
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

/// A list of sources of one kind, each with its editor and Duplicate / Delete. A source's name selects it (its
/// handles ringed in the viewport); the selected source's entry is highlighted, and scrolled to when it was
/// selected in the viewport.
fn list<T>(
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
        let id = ui.make_persistent_id((label, i));
        let frame = if selected {
            egui::Frame::NONE
                .fill(ui.visuals().selection.bg_fill.gamma_multiply(0.25))
                .stroke(ui.visuals().selection.stroke)
                .corner_radius(3.0)
        } else {
            egui::Frame::NONE
        };
        frame.show(ui, |ui| {
            let state = egui::collapsing_header::CollapsingState::load_with_default_open(
                ui.ctx(),
                id,
                true,
            );
            let (_, header, _) = state
                .show_header(ui, |ui| {
                    let name = ui
                        .selectable_label(selected, format!("{label} {}", i + 1))
                        .on_hover_text("Select: its handles are ringed in the viewport");
                    if name.clicked() {
                        out.push(Action::Select((!selected).then_some((kind, i))));
                    }
                    name
                })
                .body(|ui| {
                    editor(ui, out, i, item);
                    ui.horizontal(|ui| {
                        if ui.small_button("Duplicate").clicked() {
                            out.push(Action::Edit(Edit::DuplicateSource(kind, i)));
                        }
                        if ui.small_button("Delete").clicked() {
                            out.push(Action::Edit(Edit::DeleteSource(kind, i)));
                        }
                    });
                });
            if selected && cx.scroll_to_selected {
                header.inner.scroll_to_me(Some(egui::Align::TOP));
            }
        });
    }
}

/// Curve `i`: its coefficient, control points, segments and W series (`pulsed`: the W series is the
/// animation's travelling pulse, shown and not edited here).
fn curve_editor(ui: &mut Ui, out: &mut Edits<'_>, i: usize, c: &Curve, pulsed: bool) {
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
}
