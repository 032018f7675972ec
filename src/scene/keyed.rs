//! Where time meets the scene: the value a keyed parameter names in a scene, read and written; an animation
//! applied to a scene at one frame; a scene's frames. `crate::animation` holds the timeline, keys and pulses
//! and knows nothing of the scene; this module imports it, not the other way round.

use glam::DVec3;

use crate::animation::{
    Animation, IntegrationSetting, Parameter, ParticleField, SourceKind, Value,
};
use crate::field::Look;
use crate::particles::{Origin, ParticleSet};
use crate::scene::{MAX_INTENSITY, Scene, limits};

impl Parameter {
    /// The parameter's current value in `scene`; `None` when the path names nothing there (a source or a
    /// control point that does not exist, a weight of a curve without a W series).
    pub fn get(&self, scene: &Scene) -> Option<Value> {
        let s = &scene.sources;
        let v = |p: DVec3| Value::Vector(p.to_array());
        Some(match *self {
            Parameter::EnergyColor => Value::Vector(scene.colors.energy),
            Parameter::BackgroundColor => Value::Vector(scene.colors.background),
            Parameter::EnergyIntensity => Value::Number(scene.colors.energy_intensity),
            Parameter::Cutoff => Value::Number(scene.colors.cutoff),
            // A source without a color of its own shows the scene's: keying it gives it one.
            Parameter::SourceColor(kind, i) => {
                Value::Vector(scene.look(kind, i)?.color.unwrap_or(scene.colors.energy))
            }
            Parameter::Intensity(kind, i) => {
                Value::Number(scene.colors.intensity_of(scene.look(kind, i)?))
            }
            Parameter::Position(SourceKind::Points, i) => v(s.points.get(i)?.position),
            Parameter::Position(SourceKind::Lines, i) => v(s.lines.get(i)?.point),
            Parameter::Position(SourceKind::Tori, i) => v(s.tori.get(i)?.center),
            Parameter::Position(SourceKind::Curves, _) => return None,
            Parameter::Direction(SourceKind::Lines, i) => v(s.lines.get(i)?.direction),
            Parameter::Direction(SourceKind::Tori, i) => v(s.tori.get(i)?.axis),
            Parameter::Direction(..) => return None,
            Parameter::Coefficient(SourceKind::Points, i) => {
                Value::Number(s.points.get(i)?.coefficient)
            }
            Parameter::Coefficient(SourceKind::Lines, i) => {
                Value::Number(s.lines.get(i)?.coefficient)
            }
            Parameter::Coefficient(SourceKind::Tori, i) => {
                Value::Number(s.tori.get(i)?.coefficient)
            }
            Parameter::Coefficient(SourceKind::Curves, i) => {
                Value::Number(s.curves.get(i)?.coefficient)
            }
            Parameter::MajorRadius(i) => Value::Number(s.tori.get(i)?.major_radius),
            Parameter::ControlPoint(i, j) => v(*s.curves.get(i)?.control_points.get(j)?),
            Parameter::Weight(i, j) => Value::Number(*s.curves.get(i)?.weights.get(j)?),
            Parameter::SeriesColor(i, j) => Value::Vector(*s.curves.get(i)?.color_series.get(j)?),
            Parameter::ObjectPosition(i) => v(scene.objects.get(i)?.center()),
            Parameter::ObjectColor(i) => Value::Vector(scene.objects.get(i)?.color),
            Parameter::ObjectShape(i, field) => {
                use crate::animation::keyframes::ShapeField as F;
                use crate::objects::Shape;
                match (&scene.objects.get(i)?.shape, field) {
                    (Shape::Box { rotation, .. }, F::Rotation) => v(*rotation),
                    (Shape::Mesh(m), F::Rotation) => v(m.rotation),
                    (Shape::Sphere { radius, .. }, F::Radius) => Value::Number(*radius),
                    (Shape::Box { size, .. }, F::Size) => v(*size),
                    (Shape::Mesh(m), F::Scale) => v(m.scale),
                    (Shape::Plane { normal, .. }, F::Normal) => v(*normal),
                    _ => return None,
                }
            }
            Parameter::Translucent(i, field) => {
                let t = scene.objects.get(i)?.translucent.as_ref()?;
                Value::Number(match field {
                    crate::animation::TranslucentField::Extinction => t.extinction,
                    crate::animation::TranslucentField::Eta => t.eta,
                })
            }
            Parameter::Particles(i, field) => particle_field(scene.particles.get(i)?, field)?,
            Parameter::Integration(k) => Value::Number(match k {
                IntegrationSetting::DecayLength => scene.integration.decay_length,
                IntegrationSetting::Alpha => scene.integration.alpha,
                IntegrationSetting::Beta => scene.integration.beta,
                IntegrationSetting::Epsilon => scene.integration.epsilon,
            }),
        })
    }

    /// Writes `value` into `scene`; does nothing when the path names nothing there or the value is of the
    /// wrong kind. Directions are normalised (a zero vector leaves the direction as it was), colors clamped
    /// to 0..1 and intensities to 0..=MAX_INTENSITY, radii and weights kept positive, as the scene loader would
    /// require.
    pub fn set(&self, scene: &mut Scene, value: Value) {
        let s = &mut scene.sources;
        match (self, value) {
            (Parameter::EnergyColor, Value::Vector(c)) => {
                scene.colors.energy = c.map(|x| x.clamp(0.0, 1.0))
            }
            (Parameter::BackgroundColor, Value::Vector(c)) => {
                scene.colors.background = c.map(|x| x.clamp(0.0, 1.0))
            }
            (Parameter::EnergyIntensity, Value::Number(x)) => {
                scene.colors.energy_intensity = x.clamp(0.0, MAX_INTENSITY)
            }
            (Parameter::Cutoff, Value::Number(x)) => {
                scene.colors.cutoff = x.clamp(0.0, crate::scene::MAX_CUTOFF)
            }
            (Parameter::SourceColor(kind, i), Value::Vector(c)) => {
                if let Some(look) = scene.look_mut(*kind, *i) {
                    look.color = Some(c.map(|x| x.clamp(0.0, 1.0)));
                }
            }
            (Parameter::Intensity(kind, i), Value::Number(x)) => {
                if let Some(look) = scene.look_mut(*kind, *i) {
                    look.intensity = Some(x.clamp(0.0, MAX_INTENSITY));
                }
            }
            (Parameter::Position(kind, i), Value::Vector(p)) => {
                let p = DVec3::from_array(p);
                let slot = match kind {
                    SourceKind::Points => s.points.get_mut(*i).map(|x| &mut x.position),
                    SourceKind::Lines => s.lines.get_mut(*i).map(|x| &mut x.point),
                    SourceKind::Tori => s.tori.get_mut(*i).map(|x| &mut x.center),
                    SourceKind::Curves => None,
                };
                if let Some(slot) = slot {
                    *slot = p;
                }
            }
            (Parameter::Direction(kind, i), Value::Vector(d)) => {
                let d = DVec3::from_array(d);
                let slot = match kind {
                    SourceKind::Lines => s.lines.get_mut(*i).map(|x| &mut x.direction),
                    SourceKind::Tori => s.tori.get_mut(*i).map(|x| &mut x.axis),
                    _ => None,
                };
                if let Some(slot) = slot
                    && d.length() > 1e-12
                {
                    *slot = d.normalize();
                }
            }
            (Parameter::Coefficient(kind, i), Value::Number(x)) => {
                let slot = match kind {
                    SourceKind::Points => s.points.get_mut(*i).map(|x| &mut x.coefficient),
                    SourceKind::Lines => s.lines.get_mut(*i).map(|x| &mut x.coefficient),
                    SourceKind::Tori => s.tori.get_mut(*i).map(|x| &mut x.coefficient),
                    SourceKind::Curves => s.curves.get_mut(*i).map(|x| &mut x.coefficient),
                };
                if let Some(slot) = slot {
                    *slot = x;
                }
            }
            (Parameter::MajorRadius(i), Value::Number(x)) => {
                if let Some(t) = s.tori.get_mut(*i) {
                    t.major_radius = x.max(1e-9);
                }
            }
            (Parameter::ControlPoint(i, j), Value::Vector(p)) => {
                if let Some(slot) = s
                    .curves
                    .get_mut(*i)
                    .and_then(|c| c.control_points.get_mut(*j))
                {
                    *slot = DVec3::from_array(p);
                }
            }
            (Parameter::ObjectPosition(i), Value::Vector(p)) => {
                if let Some(o) = scene.objects.get_mut(*i) {
                    *o = o.moved_to(DVec3::from_array(p));
                }
            }
            (Parameter::ObjectColor(i), Value::Vector(c)) => {
                if let Some(o) = scene.objects.get_mut(*i) {
                    o.color = c.map(|x| x.clamp(0.0, 1.0));
                }
            }
            (Parameter::Translucent(i, field), Value::Number(x)) => {
                // Kept valid between keys and from outside: an extinction at least 0, an index above 0.
                if let Some(t) = scene
                    .objects
                    .get_mut(*i)
                    .and_then(|o| o.translucent.as_mut())
                {
                    match field {
                        crate::animation::TranslucentField::Extinction => t.extinction = x.max(0.0),
                        crate::animation::TranslucentField::Eta => t.eta = x.max(1e-3),
                    }
                }
            }
            (Parameter::ObjectShape(i, field), value) => {
                use crate::animation::keyframes::ShapeField as F;
                use crate::objects::Shape;
                let Some(o) = scene.objects.get_mut(*i) else {
                    return;
                };
                // What the file requires holds between valid keys too; only a value set from outside may break
                // it, and is kept valid (a size or scale at least 1e-9 across, a normal of unit length).
                let tiny = |x: f64| match x.abs() < 1e-9 {
                    true => 1e-9_f64.copysign(x),
                    false => x,
                };
                match (&mut o.shape, field, value) {
                    (Shape::Box { rotation, .. }, F::Rotation, Value::Vector(r)) => {
                        *rotation = DVec3::from_array(r)
                    }
                    (Shape::Mesh(m), F::Rotation, Value::Vector(r)) => {
                        m.rotation = DVec3::from_array(r)
                    }
                    (Shape::Sphere { radius, .. }, F::Radius, Value::Number(x)) => {
                        *radius = x.max(1e-9)
                    }
                    (Shape::Box { size, .. }, F::Size, Value::Vector(s)) => {
                        *size = DVec3::from_array(s.map(|x| x.max(1e-9)))
                    }
                    (Shape::Mesh(m), F::Scale, Value::Vector(s)) => {
                        m.scale = DVec3::from_array(s.map(tiny))
                    }
                    (Shape::Plane { normal, .. }, F::Normal, Value::Vector(n)) => {
                        *normal = DVec3::from_array(n).normalize_or(*normal)
                    }
                    _ => {}
                }
            }
            (Parameter::Particles(i, field), value) => {
                if let Some(set) = scene.particles.get_mut(*i) {
                    set_particle_field(set, *field, value);
                }
            }
            (Parameter::Integration(k), Value::Number(x)) => {
                let i = &mut scene.integration;
                let slot = match k {
                    IntegrationSetting::DecayLength => &mut i.decay_length,
                    IntegrationSetting::Alpha => &mut i.alpha,
                    IntegrationSetting::Beta => &mut i.beta,
                    IntegrationSetting::Epsilon => &mut i.epsilon,
                };
                // Every keyable setting is positive. Interpolating between valid keys stays valid; this only
                // guards against rounding.
                *slot = match k {
                    IntegrationSetting::DecayLength => limits::clamp_decay_length(x),
                    _ => x.max(1e-9),
                };
            }
            (Parameter::SeriesColor(i, j), Value::Vector(c)) => {
                if let Some(slot) = (s.curves.get_mut(*i)).and_then(|x| x.color_series.get_mut(*j))
                {
                    *slot = c.map(|x| x.clamp(0.0, 1.0));
                }
            }
            (Parameter::Weight(i, j), Value::Number(x)) => {
                if let Some(slot) = s.curves.get_mut(*i).and_then(|c| c.weights.get_mut(*j)) {
                    *slot = limits::clamp_weight(x);
                }
            }
            _ => {}
        }
    }
}

/// A keyable setting of a particle set, where the set has it.
fn particle_field(set: &ParticleSet, field: ParticleField) -> Option<Value> {
    use crate::particles::emit::EmitterShape as S;
    match field {
        ParticleField::Albedo => return Some(Value::Number(set.albedo)),
        ParticleField::Emission => return Some(Value::Vector(set.emission.color)),
        ParticleField::EmissionIntensity => return Some(Value::Number(set.emission.intensity)),
        _ => {}
    }
    let Origin::Emitter(e) = &set.origin else {
        return None;
    };
    let life = e.life.as_deref();
    Some(match (field, &e.shape) {
        (ParticleField::Rate, _) => Value::Number(life?.rate),
        (ParticleField::Center, S::Sphere { center, .. } | S::Box { center, .. }) => {
            Value::Vector(center.to_array())
        }
        (ParticleField::Radius, S::Sphere { radius, .. }) => Value::Number(*radius),
        (ParticleField::Spread, S::Curve { spread, .. } | S::Torus { spread, .. }) => {
            Value::Number(*spread)
        }
        (ParticleField::Color, _) => Value::Vector(e.color),
        (ParticleField::Acceleration, _) => Value::Vector(life?.acceleration.to_array()),
        (ParticleField::Drag, _) => Value::Number(life?.drag),
        (ParticleField::Turbulence, _) => Value::Number(life?.turbulence?.strength),
        _ => return None,
    })
}

/// Writes a keyable setting of a particle set, kept valid as the loader requires it (rates, drags, spreads and
/// strengths at least 0, a radius positive, colors and the albedo in 0..1, an emission's intensity in
/// 0..=MAX_INTENSITY).
fn set_particle_field(set: &mut ParticleSet, field: ParticleField, value: Value) {
    use crate::particles::emit::EmitterShape as S;
    match (field, value) {
        (ParticleField::Albedo, Value::Number(x)) => set.albedo = x.clamp(0.0, 1.0),
        (ParticleField::Emission, Value::Vector(c)) => {
            set.emission.color = c.map(|x| {
                if x.is_finite() {
                    x.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
        }
        (ParticleField::EmissionIntensity, Value::Number(x)) => {
            set.emission.intensity = match x.is_finite() {
                true => x.clamp(0.0, crate::scene::MAX_INTENSITY),
                false => 0.0,
            }
        }
        _ => {
            let Origin::Emitter(e) = &mut set.origin else {
                return;
            };
            let finite = |x: f64| if x.is_finite() { x.max(0.0) } else { 0.0 };
            match (field, value, &mut e.shape) {
                (
                    ParticleField::Center,
                    Value::Vector(c),
                    S::Sphere { center, .. } | S::Box { center, .. },
                ) => *center = DVec3::from_array(c),
                (ParticleField::Radius, Value::Number(x), S::Sphere { radius, .. }) => {
                    *radius = x.max(1e-9)
                }
                (
                    ParticleField::Spread,
                    Value::Number(x),
                    S::Curve { spread, .. } | S::Torus { spread, .. },
                ) => *spread = finite(x),
                (ParticleField::Color, Value::Vector(c), _) => {
                    e.color = c.map(|x| x.clamp(0.0, 1.0))
                }
                (_, value, _) => {
                    let Some(life) = e.life.as_deref_mut() else {
                        return;
                    };
                    match (field, value) {
                        (ParticleField::Rate, Value::Number(x)) => {
                            life.rate = finite(x).min(crate::scene::MAX_RATE)
                        }
                        (ParticleField::Acceleration, Value::Vector(a)) => {
                            life.acceleration = DVec3::from_array(a)
                        }
                        (ParticleField::Drag, Value::Number(x)) => life.drag = finite(x),
                        (ParticleField::Turbulence, Value::Number(x)) => {
                            if let Some(t) = &mut life.turbulence {
                                t.strength = finite(x);
                            }
                        }
                        _ => {}
                    }
                }
            }
        }
    }
}

impl Scene {
    /// The look of source `i` of `kind`.
    pub fn look(&self, kind: SourceKind, i: usize) -> Option<&Look> {
        let s = &self.sources;
        match kind {
            SourceKind::Points => s.points.get(i).map(|x| &x.look),
            SourceKind::Lines => s.lines.get(i).map(|x| &x.look),
            SourceKind::Tori => s.tori.get(i).map(|x| &x.look),
            SourceKind::Curves => s.curves.get(i).map(|x| &x.look),
        }
    }

    /// The look of source `i` of `kind`, to change.
    pub fn look_mut(&mut self, kind: SourceKind, i: usize) -> Option<&mut Look> {
        let s = &mut self.sources;
        match kind {
            SourceKind::Points => s.points.get_mut(i).map(|x| &mut x.look),
            SourceKind::Lines => s.lines.get_mut(i).map(|x| &mut x.look),
            SourceKind::Tori => s.tori.get_mut(i).map(|x| &mut x.look),
            SourceKind::Curves => s.curves.get_mut(i).map(|x| &mut x.look),
        }
    }
}

impl Animation {
    /// `scene` (whose base values are the unkeyed ones) as it is at `frame`: every track's value set, then
    /// every pulse's W series. Frames may be fractional (keys interpolate, pulses are continuous in time).
    pub fn apply(&self, scene: &mut Scene, frame: f64) {
        for track in &self.tracks {
            if let Some(value) = track.value_at(frame) {
                track.parameter.set(scene, value);
            }
        }
        for p in &self.pulses {
            if let Some(curve) = scene.sources.curves.get_mut(p.curve) {
                curve.weights = p.pulse.weights(frame);
            }
        }
    }

    /// Drops what no longer names anything in `scene` (a control point or weight removed in the viewer),
    /// so that the scene still saves as a valid file.
    pub fn retain_valid(&mut self, scene: &Scene) {
        let curves = scene.sources.curves.len();
        self.pulses.retain(|p| p.curve < curves);
        self.tracks.retain(|t| {
            t.parameter.get(scene).is_some()
                && !matches!(t.parameter, Parameter::Weight(i, _) if self.pulses.iter().any(|p| p.curve == i))
        });
    }
}

impl Scene {
    /// True when the scene has an animation (a timeline; it may still hold nothing that moves).
    pub fn is_animated(&self) -> bool {
        self.animation.is_some()
    }

    /// How many frames the scene has: its animation's length, or 1 for a still scene.
    pub fn frame_count(&self) -> u32 {
        self.animation.as_ref().map_or(1, |a| a.frames)
    }

    /// The scene as it is at `frame`: keyed parameters and pulses applied, live particle sets simulated up to
    /// it from their start (`scene::live`; a fractional frame takes the whole frame before it); a clone of the
    /// scene if still. A renderer of many frames keeps the states reached: `at_frame_in`.
    pub fn at_frame(&self, frame: f64) -> Scene {
        self.at_frame_in(frame, &super::Simulations::new(), &Default::default())
            .expect("never cancelled")
    }

    /// `at_frame`, the live sets simulated from the states `simulations` keeps (a renderer's frame cache:
    /// playback steps one frame from the last), stopped once `cancel` is raised (then `None`): the viewer
    /// simulates on a thread of its own, and an edit or another frame asked for cancels what is under way.
    pub fn at_frame_in(
        &self,
        frame: f64,
        simulations: &super::Simulations,
        cancel: &crate::background::Cancel,
    ) -> Option<Scene> {
        let mut s = self.clone();
        if let Some(a) = &self.animation {
            a.apply(&mut s, frame);
        }
        let whole = if frame.is_finite() {
            frame.floor().clamp(0.0, u32::MAX as f64)
        } else {
            0.0
        };
        for (i, particles) in simulations.particles_at(self, whole as u32, cancel)? {
            s.particles[i].live = Some(particles);
        }
        Some(s)
    }

    /// `at_frame` with each live set's particles as `live` gives them (by the set's index), not simulated:
    /// the viewer's frame while the simulation of that frame runs on a thread of its own.
    pub fn at_frame_with(
        &self,
        frame: f64,
        live: impl Fn(usize) -> Option<std::sync::Arc<Vec<crate::particles::Particle>>>,
    ) -> Scene {
        let mut s = self.clone();
        if let Some(a) = &self.animation {
            a.apply(&mut s, frame);
        }
        for (i, set) in s.particles.iter_mut().enumerate() {
            if set.life().is_some() {
                set.live = live(i);
            }
        }
        s
    }
}
