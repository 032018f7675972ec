//! The Particles section: smoke, dust and sparks around the glow, lit by it. Adding a set by its emitter's shape
//! (a cloud at the view's target, a layer of dust under it, sparks along a curve, dust around a ring), each
//! set's emitter or file settings, Duplicate and Delete, and the slices' width. Every change replaces the set
//! whole (`Edit::SetParticles`), one undo step a settled edit like every other; none is keyable.

use egui::{DragValue, Slider, Ui};
use glam::DVec3;

use super::super::action::{Action, Edit};
use super::super::widgets::{color, labelled, vec3};
use super::context::Context;
use super::fields::Edits;
use crate::particles::emit::{Emitter, EmitterShape, Span};
use crate::particles::ply::MAX_PARTICLES;
use crate::particles::{DEFAULT_ALBEDO, Origin, ParticleSet};
use crate::scene::PARTICLE_DEFAULTS;

/// The section.
pub(super) fn particles_section(ui: &mut Ui, cx: &Context, out: &mut Edits<'_>) {
    let scene = cx.shown;
    let target = scene.camera.target;
    ui.horizontal_wrapped(|ui| {
        ui.strong("Particles");
        let mut add = |ui: &mut Ui, label: &str, hover: &str, shape: EmitterShape| {
            if ui.button(label).on_hover_text(hover).clicked() {
                out.push(Action::Edit(Edit::AddParticles(new_set(shape))));
            }
        };
        add(
            ui,
            "+ smoke",
            "A cloud around the view's target",
            EmitterShape::Sphere {
                center: target,
                radius: 1.5,
            },
        );
        add(
            ui,
            "+ dust",
            "A flat layer of dust under the view's target",
            EmitterShape::Box {
                center: target - DVec3::Y * 1.5,
                size: DVec3::new(6.0, 0.4, 6.0),
            },
        );
        if !scene.sources.curves.is_empty() {
            add(
                ui,
                "+ sparks",
                "Along the first curve",
                EmitterShape::Curve {
                    curve: 0,
                    spread: 0.5,
                },
            );
        }
        if !scene.sources.tori.is_empty() {
            add(
                ui,
                "+ ring dust",
                "Around the first torus's ring",
                EmitterShape::Torus {
                    torus: 0,
                    spread: 0.5,
                },
            );
        }
    });
    if scene.particles.is_empty() {
        ui.weak(
            "None. Particle sets are smoke, dust or sparks: lit by the glow, hiding what lies behind them \
             (a PLY point cloud joins through the scene file: [[particles]] file = \"...\").",
        );
        return;
    }
    ui.horizontal(|ui| {
        let mut w = scene.slice_width;
        let response = labelled(
            ui,
            "slices",
            DragValue::new(&mut w)
                .range(crate::scene::MIN_SLICE_WIDTH..=2.0)
                .speed(0.01)
                .max_decimals(3)
                .suffix(" R"),
        )
        .on_hover_text(
            "The slices' width, in radii of the smallest particle (the paper's: 0.5). Thinner is closer to \
             the exact medium, and slower.",
        );
        if response.changed() && w != scene.slice_width {
            out.push(Action::Edit(Edit::SliceWidth(w)));
        }
    });
    for (i, set) in scene.particles.iter().enumerate() {
        let id = ui.make_persistent_id(("energywave.particles", i));
        egui::collapsing_header::CollapsingState::load_with_default_open(ui.ctx(), id, true)
            .show_header(ui, |ui| ui.label(title(set, i)))
            .body(|ui| {
                let mut edited = set.clone();
                set_editor(ui, scene, &mut edited);
                if edited != *set {
                    out.push(Action::Edit(Edit::SetParticles(i, edited)));
                }
                ui.horizontal(|ui| {
                    if ui.small_button("Duplicate").clicked() {
                        out.push(Action::Edit(Edit::DuplicateParticles(i)));
                    }
                    if ui.small_button("Delete").clicked() {
                        out.push(Action::Edit(Edit::DeleteParticles(i)));
                    }
                });
            });
    }
}

/// A new set of 1000 particles from `shape`: a visible smoke (about 1 of optical depth through a cloud of
/// radius 1.5), in the scene files' default color.
fn new_set(shape: EmitterShape) -> ParticleSet {
    ParticleSet {
        origin: Origin::Emitter(Emitter {
            shape,
            count: 1000,
            radius: Span {
                min: 0.15,
                max: 0.3,
            },
            density: Span {
                min: 1.0,
                max: PARTICLE_DEFAULTS.density,
            },
            color: PARTICLE_DEFAULTS.color,
            seed: 0,
            noise: 0.5,
            life: None,
        }),
        albedo: DEFAULT_ALBEDO,
        live: None,
    }
}

fn title(set: &ParticleSet, i: usize) -> String {
    match &set.origin {
        Origin::File {
            path, particles, ..
        } => {
            format!(
                "{}. {} ({} particles)",
                i + 1,
                path.display(),
                particles.len()
            )
        }
        Origin::Emitter(e) => {
            let shape = match e.shape {
                EmitterShape::Sphere { .. } => "Cloud".to_owned(),
                EmitterShape::Box { .. } => "Box".to_owned(),
                EmitterShape::Curve { curve, .. } => format!("Along curve {}", curve + 1),
                EmitterShape::Torus { torus, .. } => format!("Around torus {}", torus + 1),
            };
            format!("{}. {shape} ({} particles)", i + 1, e.count)
        }
    }
}

/// Every setting of a set, edited in place.
fn set_editor(ui: &mut Ui, scene: &crate::scene::Scene, set: &mut ParticleSet) {
    match &mut set.origin {
        Origin::File { defaults, .. } => {
            ui.weak("From its file; where a vertex gives none:");
            positive(ui, "radius", &mut defaults.radius);
            at_least_zero(ui, "density", &mut defaults.density);
            edit_color(ui, "color", &mut defaults.color);
        }
        Origin::Emitter(e) => {
            match &mut e.shape {
                EmitterShape::Sphere { center, radius } => {
                    vec3(ui, "center", center, 0.02);
                    positive(ui, "radius", radius);
                }
                EmitterShape::Box { center, size } => {
                    vec3(ui, "center", center, 0.02);
                    let mut s = *size;
                    if vec3(ui, "size", &mut s, 0.02).0 && s.min_element() > 0.0 {
                        *size = s;
                    }
                }
                EmitterShape::Curve { curve, spread } => {
                    source_index(ui, "curve", curve, scene.sources.curves.len());
                    at_least_zero(ui, "spread", spread);
                }
                EmitterShape::Torus { torus, spread } => {
                    source_index(ui, "torus", torus, scene.sources.tori.len());
                    at_least_zero(ui, "spread", spread);
                }
            }
            ui.horizontal(|ui| {
                labelled(
                    ui,
                    "count",
                    DragValue::new(&mut e.count)
                        .range(0..=MAX_PARTICLES as u32)
                        .speed(10.0),
                );
            });
            span(ui, "radius", &mut e.radius, true);
            span(ui, "density", &mut e.density, false);
            edit_color(ui, "color", &mut e.color);
            ui.horizontal(|ui| {
                labelled(ui, "seed", DragValue::new(&mut e.seed).speed(1.0));
            });
            ui.horizontal(|ui| {
                labelled(ui, "noise", Slider::new(&mut e.noise, 0.0..=1.0))
                    .on_hover_text("How much the particles clump: 0 spreads them evenly");
            });
        }
    }
    ui.horizontal(|ui| {
        labelled(ui, "albedo", Slider::new(&mut set.albedo, 0.0..=1.0))
            .on_hover_text("The share of the light reaching a particle that it scatters");
    });
}

fn positive(ui: &mut Ui, label: &str, x: &mut f64) {
    ui.horizontal(|ui| {
        labelled(
            ui,
            label,
            DragValue::new(x)
                .range(1e-4..=1e6)
                .speed(0.005)
                .max_decimals(4),
        );
    });
}

fn at_least_zero(ui: &mut Ui, label: &str, x: &mut f64) {
    ui.horizontal(|ui| {
        labelled(
            ui,
            label,
            DragValue::new(x)
                .range(0.0..=1e6)
                .speed(0.01)
                .max_decimals(4),
        );
    });
}

/// A range `[min, max]`: the first never above the second.
fn span(ui: &mut Ui, label: &str, s: &mut Span, strictly_positive: bool) {
    let low = if strictly_positive { 1e-4 } else { 0.0 };
    ui.horizontal(|ui| {
        let drag = |x| {
            DragValue::new(x)
                .range(low..=1e6)
                .speed(0.005)
                .max_decimals(4)
        };
        labelled(ui, label, drag(&mut s.min));
        labelled(ui, "to", drag(&mut s.max));
    });
    if s.max < s.min {
        s.max = s.min;
    }
}

fn edit_color(ui: &mut Ui, label: &str, c: &mut [f64; 3]) {
    ui.horizontal(|ui| {
        if let (Some(edited), _) = color(ui, label, *c) {
            *c = edited;
        }
    });
}

/// Which source of its kind an emitter follows, among the scene's `count`.
fn source_index(ui: &mut Ui, label: &str, index: &mut usize, count: usize) {
    ui.horizontal(|ui| {
        let mut shown = *index + 1;
        labelled(
            ui,
            label,
            DragValue::new(&mut shown)
                .range(1..=count.max(1))
                .speed(0.05),
        );
        *index = shown.saturating_sub(1).min(count.saturating_sub(1));
    });
}
