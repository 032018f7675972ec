//! The panel's Animation section: the timeline's settings, travelling pulses along curves, keyed
//! parameters, and the export of every frame (run beside the UI by `timeline::ExportJob`).

use egui::{DragValue, Ui};

use super::action::{Action, Edit};
use super::timeline::ExportJob;
use super::widgets::{labelled, wseries_plot};
use crate::animation::{Animation, CurvePulse, MAX_FRAMES, Parameter, Pulse, Track, Value};
use crate::export::Target;
use crate::scene::Scene;

/// What an export from the viewer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportKind {
    /// One PNG per frame, numbered.
    Sequence,
    Gif,
    /// A flipbook grid PNG with its layout as JSON beside it.
    Sheet,
    /// MP4 (H.264) or WebM (VP9, with alpha) through ffmpeg.
    Video,
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
    /// With `transparent`: the objects left out, still hiding the glow (a holdout).
    pub holdout: bool,
    /// The field of view set, for the export alone, so that every frame holds the whole glow down to its edge
    /// (`export::fit`, as `render --fit`).
    pub fit: bool,
    /// Width and height of exported frames, pixels.
    pub size: [u32; 2],
    /// A sheet's padding and power-of-two sides (its columns are as square as they get).
    pub sheet: crate::export::SheetOptions,
}

impl Default for AnimationForm {
    fn default() -> Self {
        Self {
            new_track: String::new(),
            export_path: String::new(),
            export_kind: ExportKind::Sequence,
            transparent: false,
            holdout: false,
            fit: false,
            size: [256, 256],
            sheet: crate::export::SheetOptions::default(),
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
            ExportKind::Video if self.transparent => format!("{stem}.webm"),
            ExportKind::Video => format!("{stem}.mp4"),
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

/// Time: the timeline's settings, pulses along curves, keyed parameters, and the export. `shown` is the
/// scene at `frame`, `form` the section's own fields, `export` the export running if any, `scene_path` the
/// document's file.
pub fn show(
    ui: &mut Ui,
    shown: &Scene,
    frame: u32,
    form: &mut AnimationForm,
    export: Option<&ExportJob>,
    scene_path: Option<&std::path::Path>,
) -> Vec<Action> {
    let mut out = Vec::new();
    egui::CollapsingHeader::new("Animation")
        .default_open(true)
        .show(ui, |ui| {
            let Some(original) = &shown.animation else {
                ui.label("A still scene.");
                if ui
                    .button("Animate")
                    .on_hover_text(
                        "Add a timeline: then pulses along curves and keys on any parameter",
                    )
                    .clicked()
                {
                    out.push(Action::Edit(Edit::Animation(Some(Animation::default()))));
                }
                return;
            };
            let current = shown;
            let mut animation = original.clone();
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
                // A live particle set lives in time: the scene keeps its timeline while it has one.
                let live = shown.particles.iter().any(|p| p.life().is_some());
                if ui
                    .add_enabled(!live, egui::Button::new("make still").small())
                    .on_hover_text("Remove the animation (pulses and keys too)")
                    .on_disabled_hover_text(
                        "A live particle set lives in time: make it still (its live switch) or delete it first",
                    )
                    .clicked()
                {
                    remove_animation = true;
                }
            });

            ui.strong("Travelling pulses");
            if shown.sources.curves.is_empty() {
                ui.label("(add a curve to run a pulse along it)");
            }
            for (i, curve) in shown.sources.curves.iter().enumerate() {
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
                                    .or_else(|| track.parameter.get(current))
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
                    egui::TextEdit::singleline(&mut form.new_track)
                        .hint_text("curves[0].coefficient")
                        .desired_width(170.0),
                );
                if ui
                    .button(format!("key at frame {frame}"))
                    .on_hover_text(crate::animation::PARAMETER_FORMS)
                    .clicked()
                {
                    let path = form.new_track.trim().to_owned();
                    match Parameter::parse(&path) {
                        Ok(parameter) => match parameter.get(current) {
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
                                form.new_track.clear();
                            }
                            None => out.push(Action::error(format!(
                                "{path}: the scene has no such source, point or weight"
                            ))),
                        },
                        Err(e) => out.push(Action::error(e)),
                    }
                }
            });

            if remove_animation {
                out.push(Action::Edit(Edit::Animation(None)));
            } else if animation != *original {
                out.push(Action::Edit(Edit::Animation(Some(animation))));
            }
        });
    export_section(ui, shown, form, export, scene_path, &mut out);
    out
}

/// Export of the animation to files, on a thread of its own.
fn export_section(
    ui: &mut Ui,
    shown: &Scene,
    form: &mut AnimationForm,
    export: Option<&ExportJob>,
    scene_path: Option<&std::path::Path>,
    out: &mut Vec<Action>,
) {
    let Some(animation) = &shown.animation else {
        return;
    };
    let frames = animation.frames;
    egui::CollapsingHeader::new("Export")
        .default_open(false)
        .show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut form.export_kind, ExportKind::Sequence, "PNG sequence");
                ui.selectable_value(&mut form.export_kind, ExportKind::Gif, "GIF");
                ui.selectable_value(&mut form.export_kind, ExportKind::Sheet, "sprite sheet");
                ui.selectable_value(&mut form.export_kind, ExportKind::Video, "video")
                    .on_hover_text("MP4 (H.264), or WebM (VP9) with alpha when transparent; needs ffmpeg");
            });
            let default_path = AnimationForm {
                export_path: String::new(),
                ..form.clone()
            }
            .export_target_path(scene_path);
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
            });
            // Beside the size they overflowed the panel: a row of their own.
            ui.horizontal(|ui| {
                ui.add_enabled(
                    form.export_kind != ExportKind::Gif,
                    egui::Checkbox::new(&mut form.transparent, "transparent"),
                )
                .on_hover_text(
                    "alpha = min(B, 1), to composite over anything (not in a GIF; in a video, WebM only)",
                );
                if !shown.objects.is_empty() {
                    ui.add_enabled(
                        form.transparent && form.export_kind != ExportKind::Gif,
                        egui::Checkbox::new(&mut form.holdout, "holdout"),
                    )
                    .on_hover_text(
                        "The objects left out but still hiding the glow: the glow alone, to layer over a render \
                         of the same scene made elsewhere",
                    );
                }
                ui.add_enabled(
                    shown.colors.cutoff > 0.0,
                    egui::Checkbox::new(&mut form.fit, "fit"),
                )
                .on_hover_text(
                    "The field of view set for the export so that every frame holds the whole glow, down to \
                     its edge, and ends in alpha 0 all round (the eye and target kept; needs an edge cutoff)",
                );
            });
            if form.export_kind == ExportKind::Sheet {
                ui.horizontal(|ui| {
                    labelled(
                        ui,
                        "padding",
                        DragValue::new(&mut form.sheet.padding)
                            .range(0..=64)
                            .suffix(" px"),
                    )
                    .on_hover_text("Transparent pixels between cells, so that mipmaps do not bleed");
                    ui.checkbox(&mut form.sheet.power_of_two, "power of two")
                        .on_hover_text("Round the sheet's sides up to powers of two");
                });
            }
            if let Some(job) = export {
                let status = job.status();
                ui.add(
                    egui::ProgressBar::new(status.done as f32 / status.total.max(1) as f32).text(
                        format!(
                            "{}: {}/{} frames",
                            job.description, status.done, status.total
                        ),
                    ),
                );
                if job.is_cancelled() {
                    ui.label("Cancelling\u{2026}");
                } else if ui
                    .button("Cancel")
                    .on_hover_text("Stop the export; the frames it wrote are removed")
                    .clicked()
                {
                    out.push(Action::CancelExport);
                }
                return;
            }
            if ui
                .button(format!("Export {frames} frames"))
                .on_hover_text("Renders every frame of the animation on a second GPU device")
                .clicked()
            {
                let path = form.export_target_path(scene_path);
                let sheet = form.export_kind == ExportKind::Sheet;
                let transparent = form.transparent && form.export_kind != ExportKind::Gif;
                let mut warning = None;
                let checked =
                    Target::for_output(&path, sheet.then_some(form.sheet))
                        .and_then(|target| {
                            let expected = match form.export_kind {
                                ExportKind::Sequence => matches!(target, Target::Sequence { .. }),
                                ExportKind::Gif => matches!(target, Target::Gif { .. }),
                                ExportKind::Sheet => matches!(target, Target::Sheet { .. }),
                                ExportKind::Video => matches!(target, Target::Video { .. }),
                            };
                            if let Target::Video { container, .. } = &target
                                && transparent
                                && *container == crate::export::video::Container::Mp4
                            {
                                return Err(crate::export::ExportError::Target {
                                    path: path.clone(),
                                    why: "H.264 in MP4 has no alpha: name the file .webm for a \
                                          transparent video"
                                        .into(),
                                });
                            }
                            if !expected {
                                return Err(crate::export::ExportError::Target {
                                    path: path.clone(),
                                    why:
                                        "does not fit the kind chosen: a sequence needs a run of # \
                                  (name_####.png), a GIF ends in .gif, a sheet in .png, a video in \
                                  .mp4 or .webm"
                                            .into(),
                                });
                            }
                            if let Target::Sheet { path, options } = &target {
                                let layout = crate::export::sheet_grid(
                                    path,
                                    form.size[0],
                                    form.size[1],
                                    0..frames,
                                    options,
                                    30.0,
                                )?;
                                warning = crate::export::sheet::mobile_warning(&layout);
                            }
                            Ok(target)
                        });
                match checked {
                    Ok(target) => {
                        out.push(Action::Export {
                            target,
                            frames: 0..frames,
                            size: (form.size[0], form.size[1]),
                            transparent,
                            holdout: transparent && form.holdout,
                            fit: form.fit && shown.colors.cutoff > 0.0,
                            description: path.display().to_string(),
                        });
                        if let Some(w) = warning {
                            out.push(Action::Notify {
                                text: w,
                                is_error: false,
                            });
                        }
                    }
                    Err(e) => out.push(Action::error(e.to_string())),
                }
            }
        });
}
