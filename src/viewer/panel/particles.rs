//! The Particles section: smoke, dust and sparks around the glow, lit by it. Adding a set by its emitter's shape
//! (a cloud at the view's target, a layer of dust under it, sparks along a curve, dust around a ring), or a live
//! one (sparks thrown by a curve's pulse, smoke shed by a ring, a fountain at the target); each set's emitter or
//! file settings, its life (rate, bursts, lifetimes, motion, turbulence, curves over the life), Duplicate and
//! Delete, and the slices' width. The keyable settings (`Parameter::Particles`: a rate, a center, a color, an
//! acceleration, ...) have their key buttons and change by `Edit::Set`; every other change replaces the set
//! whole (`Edit::SetParticles`), one undo step a settled edit like every other.

use egui::{DragValue, Slider, Ui};
use glam::DVec3;

use super::super::action::{Action, Edit};
use super::super::widgets::{color, labelled, vec3};
use super::context::Context;
use super::fields::{Edits, color_field, position};
use crate::animation::{Parameter, ParticleField, Value};
use crate::particles::curl::Turbulence;
use crate::particles::emit::{Burst, Direction, Emitter, EmitterShape, Life, LifeCurve, Span};
use crate::particles::ply::MAX_PARTICLES;
use crate::particles::{DEFAULT_ALBEDO, Emission, Origin, ParticleSet};
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
    ui.horizontal_wrapped(|ui| {
        ui.weak("live:");
        let mut add = |ui: &mut Ui, label: &str, hover: &str, set: ParticleSet| {
            if ui.button(label).on_hover_text(hover).clicked() {
                out.push(Action::Edit(Edit::AddParticles(set)));
            }
        };
        add(
            ui,
            "+ fountain",
            "Particles thrown up from the view's target, falling back (the scene gets a timeline if it has none)",
            fountain(target, (scene.camera.eye - target).length() / 8.0),
        );
        if !scene.sources.curves.is_empty() {
            add(
                ui,
                "+ pulse sparks",
                "Sparks thrown off the first curve where its W series is lit (its pulse, if it has one)",
                pulse_sparks(),
            );
            add(
                ui,
                "+ glowing sparks",
                "Sparks thrown off the first curve that glow by themselves, cooling from white to red",
                glowing_sparks(),
            );
        }
        if !scene.sources.tori.is_empty() {
            add(
                ui,
                "+ ring smoke",
                "Smoke shed outward from the first torus's ring, curling in a turbulence",
                ring_smoke(),
            );
        }
    });
    if scene.particles.is_empty() {
        ui.weak(
            "None. Particle sets are smoke, dust or sparks: lit by the glow, hiding what lies behind them, \
             glowing by themselves where they have an emission (a PLY point cloud joins through the scene \
             file: [[particles]] file = \"...\").",
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
                let mut edited = set.unframed();
                set_editor(ui, scene, &mut edited, i, out);
                if edited != set.unframed() {
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
        emission: Emission::NONE,
        live: None,
    }
}

/// A live set from `shape` with `life`: small, dense particles in `color`.
fn live_set(
    shape: EmitterShape,
    radius: Span,
    density: Span,
    color: [f64; 3],
    life: Life,
) -> ParticleSet {
    ParticleSet {
        origin: Origin::Emitter(Emitter {
            shape,
            count: 0,
            radius,
            density,
            color,
            seed: 0,
            noise: 0.0,
            life: Some(Box::new(life)),
        }),
        albedo: DEFAULT_ALBEDO,
        emission: Emission::NONE,
        live: None,
    }
}

/// Particles thrown up from `at` in a cone, falling back under gravity; `scale` times the size of the one made
/// for a view 8 units from its target, so that it fills about as much of any view.
fn fountain(at: DVec3, scale: f64) -> ParticleSet {
    let k = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    live_set(
        EmitterShape::Sphere {
            center: at,
            radius: 0.1 * k,
        },
        Span {
            min: 0.1 * k,
            max: 0.16 * k,
        },
        Span {
            min: 8.0 / k,
            max: 16.0 / k,
        },
        [1.0, 0.9, 0.8],
        Life {
            rate: 200.0,
            lifetime: Span { min: 1.0, max: 1.6 },
            speed: Span {
                min: 2.5 * k,
                max: 3.5 * k,
            },
            direction: Direction::Fixed(DVec3::Y),
            cone: 20.0,
            acceleration: DVec3::new(0.0, -4.0 * k, 0.0),
            drag: 0.3,
            ..Life::default()
        },
    )
}

/// The live set of a shipped preset (its first), for the panel to add: one definition of each.
fn shipped_set(text: &str, name: &str) -> ParticleSet {
    let scene = crate::scene::Scene::parse(text, std::path::Path::new(name))
        .expect("the shipped presets are valid (held by tests)");
    scene.particles[0].unframed()
}

/// Sparks thrown off the first curve where its W series is lit: the shipped `pulse_sparks` preset's.
fn pulse_sparks() -> ParticleSet {
    shipped_set(
        include_str!("../../../assets/scenes/pulse_sparks.toml"),
        "pulse_sparks.toml",
    )
}

/// Sparks thrown off the first curve that glow by themselves, cooling from white to red: the shipped
/// `beam_sparks` preset's.
fn glowing_sparks() -> ParticleSet {
    shipped_set(
        include_str!("../../../assets/scenes/beam_sparks.toml"),
        "beam_sparks.toml",
    )
}

/// Smoke shed outward from the first torus's ring, curling: the shipped `ring_smoke` preset's.
fn ring_smoke() -> ParticleSet {
    shipped_set(
        include_str!("../../../assets/scenes/ring_smoke.toml"),
        "ring_smoke.toml",
    )
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
            match &e.life {
                Some(life) => format!("{}. {shape}, live ({} a second)", i + 1, life.rate),
                None => format!("{}. {shape} ({} particles)", i + 1, e.count),
            }
        }
    }
}

/// Every setting of set `i`, edited in place; the keyable ones by their own editors into `out`.
fn set_editor(
    ui: &mut Ui,
    scene: &crate::scene::Scene,
    set: &mut ParticleSet,
    i: usize,
    out: &mut Edits<'_>,
) {
    let key = |field| Parameter::Particles(i, field);
    let (albedo, emission) = (set.albedo, set.emission);
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
                    position(ui, out, "center", key(ParticleField::Center), *center);
                    keyed_number(ui, out, "radius", key(ParticleField::Radius), *radius, 1e-4);
                }
                EmitterShape::Box { center, size } => {
                    position(ui, out, "center", key(ParticleField::Center), *center);
                    let mut s = *size;
                    if vec3(ui, "size", &mut s, 0.02).0 && s.min_element() > 0.0 {
                        *size = s;
                    }
                }
                EmitterShape::Curve { curve, spread } => {
                    source_index(ui, "curve", curve, scene.sources.curves.len());
                    keyed_number(ui, out, "spread", key(ParticleField::Spread), *spread, 0.0);
                }
                EmitterShape::Torus { torus, spread } => {
                    source_index(ui, "torus", torus, scene.sources.tori.len());
                    keyed_number(ui, out, "spread", key(ParticleField::Spread), *spread, 0.0);
                }
            }
            let mut live = e.life.is_some();
            ui.checkbox(&mut live, "live").on_hover_text(
                "Born over time at a rate and in bursts, each particle moving and aging over its lifetime \
                 (the scene gets a timeline if it has none)",
            );
            match (live, e.life.is_some()) {
                (true, false) => {
                    e.life = Some(Box::default());
                    // Clumping is a still set's; a live one's particles move.
                    e.noise = 0.0;
                }
                (false, true) => {
                    e.life = None;
                    e.count = e.count.max(1000);
                }
                _ => {}
            }
            if e.life.is_none() {
                ui.horizontal(|ui| {
                    labelled(
                        ui,
                        "count",
                        DragValue::new(&mut e.count)
                            .range(0..=MAX_PARTICLES as u32)
                            .speed(10.0),
                    );
                });
            }
            span(ui, "radius", &mut e.radius, true);
            span(ui, "density", &mut e.density, false);
            color_field(ui, out, "color", key(ParticleField::Color), e.color);
            ui.horizontal(|ui| {
                labelled(ui, "seed", DragValue::new(&mut e.seed).speed(1.0));
            });
            if e.life.is_none() {
                ui.horizontal(|ui| {
                    labelled(ui, "noise", Slider::new(&mut e.noise, 0.0..=1.0))
                        .on_hover_text("How much the particles clump: 0 spreads them evenly");
                });
            }
            let curve = matches!(e.shape, EmitterShape::Curve { .. });
            let ring = matches!(e.shape, EmitterShape::Torus { .. });
            if let Some(life) = e.life.as_deref_mut() {
                life_editor(ui, life, curve || ring, curve, i, out);
            }
        }
    }
    keyed_number(ui, out, "albedo", key(ParticleField::Albedo), albedo, 0.0);
    // The light the particles give off by themselves (sparks, embers): it lights nothing else.
    color_field(
        ui,
        out,
        "emission",
        key(ParticleField::Emission),
        emission.color,
    );
    keyed_number(
        ui,
        out,
        "emission intensity",
        key(ParticleField::EmissionIntensity),
        emission.intensity,
        0.0,
    );
}

/// A number with its key button on one row: `Edit::Set` when changed (a key at this frame where it is keyed).
fn keyed_number(
    ui: &mut Ui,
    out: &mut Edits<'_>,
    label: &str,
    parameter: Parameter,
    value: f64,
    low: f64,
) {
    ui.horizontal(|ui| {
        let mut x = value;
        let high = match parameter {
            Parameter::Particles(_, ParticleField::Albedo) => 1.0,
            Parameter::Particles(_, ParticleField::EmissionIntensity) => {
                crate::scene::MAX_INTENSITY
            }
            _ => 1e6,
        };
        let response = labelled(
            ui,
            label,
            DragValue::new(&mut x)
                .range(low..=high)
                .speed(0.01)
                .max_decimals(4),
        );
        if response.changed() && x != value {
            out.push(Action::set_number(parameter, x));
        }
        out.key_button(ui, parameter, Value::Number(value), response.rect);
    });
}

/// A live emitter's settings: birth, motion, turbulence and the curves over a life.
fn life_editor(
    ui: &mut Ui,
    life: &mut Life,
    has_tangent: bool,
    curve: bool,
    i: usize,
    out: &mut Edits<'_>,
) {
    let key = |field| Parameter::Particles(i, field);
    ui.separator();
    keyed_number(ui, out, "rate /s", key(ParticleField::Rate), life.rate, 0.0);
    bursts(ui, &mut life.bursts);
    span(ui, "life (s)", &mut life.lifetime, true);
    span(ui, "speed", &mut life.speed, false);
    ui.horizontal(|ui| {
        ui.label("thrown");
        let names: &[(&str, Direction)] = &[
            ("normal", Direction::Normal),
            ("tangent", Direction::Tangent),
            ("outward", Direction::Outward),
            ("up", Direction::Fixed(DVec3::Y)),
        ];
        for (name, d) in names {
            if *name == "tangent" && !has_tangent {
                continue;
            }
            let chosen = match (life.direction, d) {
                (Direction::Fixed(_), Direction::Fixed(_)) => true,
                (a, b) => a == *b,
            };
            if ui.selectable_label(chosen, *name).clicked() && !chosen {
                life.direction = *d;
            }
        }
    });
    if let Direction::Fixed(d) = life.direction {
        let mut v = d;
        if vec3(ui, "direction", &mut v, 0.01).0 && v.length() > 1e-6 {
            life.direction = Direction::Fixed(v.normalize());
        }
    }
    ui.horizontal(|ui| {
        labelled(
            ui,
            "cone",
            Slider::new(&mut life.cone, 0.0..=180.0).suffix("°"),
        )
        .on_hover_text("Half the angle of the cone around the direction a particle is thrown in");
    });
    position(
        ui,
        out,
        "accel.",
        key(ParticleField::Acceleration),
        life.acceleration,
    );
    keyed_number(ui, out, "drag /s", key(ParticleField::Drag), life.drag, 0.0);
    ui.horizontal(|ui| {
        labelled(ui, "inherit", Slider::new(&mut life.inherit, 0.0..=1.0)).on_hover_text(
            "The share of a moving emitter's own velocity (a keyed center, a moving source) its particles keep",
        );
    });
    if curve {
        ui.checkbox(&mut life.along_pulse, "along the pulse")
            .on_hover_text("Born where the curve's W series is lit, as often as it is lit");
    }
    let mut turbulent = life.turbulence.is_some();
    ui.checkbox(&mut turbulent, "turbulence")
        .on_hover_text("Curl noise: the particles swirl without gathering or thinning");
    match (turbulent, life.turbulence.is_some()) {
        (true, false) => {
            life.turbulence = Some(Turbulence {
                scale: 1.0,
                strength: 0.5,
                speed: 1.0,
            })
        }
        (false, true) => life.turbulence = None,
        _ => {}
    }
    if let Some(t) = &mut life.turbulence {
        ui.horizontal(|ui| {
            let drag = |x| {
                DragValue::new(x)
                    .range(0.01..=1e6)
                    .speed(0.01)
                    .max_decimals(3)
            };
            labelled(ui, "eddies", drag(&mut t.scale));
            labelled(
                ui,
                "changing /s",
                DragValue::new(&mut t.speed).range(0.0..=1e6).speed(0.01),
            );
        });
        keyed_number(
            ui,
            out,
            "strength",
            key(ParticleField::Turbulence),
            t.strength,
            0.0,
        );
    }
    ui.horizontal(|ui| {
        labelled(ui, "shutter", Slider::new(&mut life.shutter, 0.0..=1.0)).on_hover_text(
            "Motion blur: the share of a frame the shutter stays open (0.5 is a 180\u{b0} shutter); each particle \
             is stretched along its path over it. 0: none",
        );
    });
    life_curve(ui, "size over life", &mut life.size);
    life_curve(ui, "density over life", &mut life.opacity);
    color_curve(
        ui,
        "color over life",
        "none: the set's color",
        &mut life.colors,
    );
    life_curve(ui, "emission over life", &mut life.emission);
    color_curve(
        ui,
        "emission color over life",
        "none: the set's emission color",
        &mut life.emission_colors,
    );
}

/// Bursts: a frame and a count each; + adds one at frame 0.
fn bursts(ui: &mut Ui, bursts: &mut Vec<Burst>) {
    let mut gone = None;
    for (j, b) in bursts.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            labelled(
                ui,
                "burst at frame",
                DragValue::new(&mut b.frame).range(0.0..=1e6).speed(0.2),
            );
            labelled(
                ui,
                "count",
                DragValue::new(&mut b.count)
                    .range(0..=MAX_PARTICLES as u32)
                    .speed(2.0),
            );
            if ui
                .small_button("x")
                .on_hover_text("Remove this burst")
                .clicked()
            {
                gone = Some(j);
            }
        });
    }
    if let Some(j) = gone {
        bursts.remove(j);
    }
    if ui.small_button("+ burst").clicked() {
        bursts.push(Burst {
            frame: 0.0,
            count: 100,
        });
    }
}

/// Keys over a life, `(age, value)`, one row each: the age kept between its neighbours', the value by `value`,
/// a remove button (not on the last key when `keep_one`); the index of a key removed.
fn key_rows<T>(
    ui: &mut Ui,
    keys: &mut [(f64, T)],
    keep_one: bool,
    mut value: impl FnMut(&mut Ui, &mut T),
) -> Option<usize> {
    let mut gone = None;
    let n = keys.len();
    for j in 0..n {
        let (low, high) = age_bounds(&keys.iter().map(|k| k.0).collect::<Vec<_>>(), j);
        ui.horizontal(|ui| {
            let (age, v) = &mut keys[j];
            labelled(
                ui,
                "age",
                DragValue::new(age)
                    .range(low..=high)
                    .speed(0.005)
                    .max_decimals(3),
            );
            value(ui, v);
            if (n > 1 || !keep_one)
                && ui
                    .small_button("x")
                    .on_hover_text("Remove this key")
                    .clicked()
            {
                gone = Some(j);
            }
        });
    }
    gone
}

/// A curve over a life: its keys `age, value`, ages kept in order, one key at least.
fn life_curve(ui: &mut Ui, label: &str, curve: &mut LifeCurve) {
    ui.label(label);
    let gone = key_rows(ui, &mut curve.keys, true, |ui, value| {
        labelled(
            ui,
            "x",
            DragValue::new(value)
                .range(0.0..=1e3)
                .speed(0.01)
                .max_decimals(3),
        );
    });
    if let Some(j) = gone {
        curve.keys.remove(j);
    }
    if ui.small_button("+ key").clicked() {
        let ages: Vec<f64> = curve.keys.iter().map(|k| k.0).collect();
        let (at, age) = widest_gap(&ages);
        curve.keys.insert(at, (age, curve.at(age)));
    }
}

/// Colors over a life: none (`none` says what stands for them) or keys `age, color`.
fn color_curve(
    ui: &mut Ui,
    label: &str,
    none: &str,
    curve: &mut crate::particles::emit::ColorCurve,
) {
    ui.label(label);
    let gone = key_rows(ui, &mut curve.keys, false, |ui, c| {
        if let (Some(edited), _) = color(ui, "", *c) {
            *c = edited;
        }
    });
    if let Some(j) = gone {
        curve.keys.remove(j);
    }
    if curve.keys.is_empty() {
        ui.weak(none);
    }
    if ui.small_button("+ color").clicked() {
        let ages: Vec<f64> = curve.keys.iter().map(|k| k.0).collect();
        let (at, age) = widest_gap(&ages);
        let c = curve.at(age).unwrap_or([1.0, 1.0, 1.0]);
        curve.keys.insert(at, (age, c));
    }
}

/// Where a new key goes among keys at `ages` (increasing, in 0..1): its index and the middle of the widest gap
/// (the ends 0 and 1 counted as gaps' ends).
fn widest_gap(ages: &[f64]) -> (usize, f64) {
    let mut bounds = vec![0.0];
    bounds.extend_from_slice(ages);
    bounds.push(1.0);
    let (i, _) = (bounds.windows(2).enumerate())
        .max_by(|a, b| (a.1[1] - a.1[0]).total_cmp(&(b.1[1] - b.1[0])))
        .expect("two bounds at least");
    (i, (bounds[i] + bounds[i + 1]) / 2.0)
}

/// The range key `j`'s age may take between its neighbours (strictly increasing ages, in 0..1).
fn age_bounds(ages: &[f64], j: usize) -> (f64, f64) {
    let tiny = 1e-3;
    let low = if j == 0 { 0.0 } else { ages[j - 1] + tiny };
    let high = ages.get(j + 1).map_or(1.0, |a| a - tiny);
    (low.min(high), high.max(low))
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
