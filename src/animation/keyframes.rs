//! Keyframes: any numeric parameter of a scene (a coefficient, a control point, a color, ...) animated by
//! linear interpolation between keys, held before the first key and after the last.
//!
//! A parameter is named by its path in the scene file, as `curves[0].control_points[2]` or
//! `colors.energy`; [`Parameter`] is that path parsed. Reading and writing the value it names in a scene is
//! `crate::scene`'s (`scene::keyed`): time knows nothing of what it animates.

use std::fmt;

/// A keyed value: a number, or a vector (positions, directions, colors).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Number(f64),
    Vector([f64; 3]),
}

impl Value {
    /// `a + (b - a) s`, component by component; `None` if the two are not of the same kind.
    pub fn lerp(a: Value, b: Value, s: f64) -> Option<Value> {
        let mix = |x: f64, y: f64| x + (y - x) * s;
        match (a, b) {
            (Value::Number(x), Value::Number(y)) => Some(Value::Number(mix(x, y))),
            (Value::Vector(x), Value::Vector(y)) => {
                Some(Value::Vector(std::array::from_fn(|c| mix(x[c], y[c]))))
            }
            _ => None,
        }
    }

    /// Every component finite.
    pub fn is_finite(&self) -> bool {
        match self {
            Value::Number(x) => x.is_finite(),
            Value::Vector(v) => v.iter().all(|x| x.is_finite()),
        }
    }
}

/// One key: the value a parameter has at `frame`.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    pub frame: f64,
    pub value: Value,
}

/// The keys of one parameter, in strictly increasing frame order (the scene loader enforces it).
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub parameter: Parameter,
    pub keys: Vec<Key>,
}

impl Track {
    /// The value at `frame`: linear between the two keys around it, the first key's before it, the last's
    /// after. `None` without keys.
    pub fn value_at(&self, frame: f64) -> Option<Value> {
        let first = self.keys.first()?;
        let last = self.keys.last()?;
        if frame <= first.frame {
            return Some(first.value);
        }
        if frame >= last.frame {
            return Some(last.value);
        }
        // The first key after `frame`; the one before it exists since frame > first.frame.
        let next = self.keys.partition_point(|k| k.frame <= frame);
        let (a, b) = (&self.keys[next - 1], &self.keys[next]);
        let s = (frame - a.frame) / (b.frame - a.frame);
        Value::lerp(a.value, b.value, s)
    }

    /// Sets the key at `frame` (replacing one at the same frame), keeping the keys in order.
    pub fn set_key(&mut self, frame: f64, value: Value) {
        match self.keys.iter().position(|k| k.frame >= frame) {
            Some(i) if self.keys[i].frame == frame => self.keys[i].value = value,
            Some(i) => self.keys.insert(i, Key { frame, value }),
            None => self.keys.push(Key { frame, value }),
        }
    }
}

/// The kinds of source, as the file names their arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    Points,
    Lines,
    Tori,
    Curves,
}

impl SourceKind {
    pub fn key(self) -> &'static str {
        match self {
            SourceKind::Points => "points",
            SourceKind::Lines => "lines",
            SourceKind::Tori => "tori",
            SourceKind::Curves => "curves",
        }
    }
}

/// A parameter that can be keyed: a path into the scene, as the scene file names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// `colors.energy`
    EnergyColor,
    /// `colors.background`
    BackgroundColor,
    /// `colors.energy_intensity`
    EnergyIntensity,
    /// `colors.cutoff`: the glow's edge
    Cutoff,
    /// `points[i].color`, ... (any kind): the source's own energy color
    SourceColor(SourceKind, usize),
    /// `points[i].intensity`, ... (any kind): the source's own intensity
    Intensity(SourceKind, usize),
    /// `curves[i].color_series[j]`
    SeriesColor(usize, usize),
    /// `points[i].position`, `lines[i].point`, `tori[i].center`
    Position(SourceKind, usize),
    /// `lines[i].direction`, `tori[i].axis` (normalised after interpolation)
    Direction(SourceKind, usize),
    /// `points[i].coefficient`, ... (any kind)
    Coefficient(SourceKind, usize),
    /// `tori[i].major_radius`
    MajorRadius(usize),
    /// `curves[i].control_points[j]`
    ControlPoint(usize, usize),
    /// `curves[i].weights[j]`
    Weight(usize, usize),
    /// `integration.decay_length`, `integration.alpha`, `integration.beta`, `integration.epsilon`
    Integration(IntegrationSetting),
    /// `objects[i].position`: a sphere's or a box's center, a plane's point, a mesh's translation (the file's
    /// own names, `center`, `point` and `translation`, are read too)
    ObjectPosition(usize),
    /// `objects[i].color`: an object's albedo
    ObjectColor(usize),
    /// `objects[i].rotation`, `.radius`, `.size`, `.scale`, `.normal`: the rest of an object's transform, where
    /// its shape has it
    ObjectShape(usize, ShapeField),
    /// `objects[i].translucent.extinction`, `.eta`: a translucent object's material
    Translucent(usize, TranslucentField),
    /// `particles[i].rate`, `.center`, ...: a particle set's emitter setting, where its emitter has it
    Particles(usize, ParticleField),
}

/// The settings of a particle set that can be keyed: each belongs to some sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParticleField {
    /// A live emitter's particles a second.
    Rate,
    /// A sphere's or a box's center.
    Center,
    /// A sphere emitter's radius.
    Radius,
    /// A curve or torus emitter's spread around its source.
    Spread,
    /// An emitter's particles' color (at their birth, for a live one).
    Color,
    /// Any set's albedo.
    Albedo,
    /// Any set's emission color.
    Emission,
    /// Any set's emission intensity.
    EmissionIntensity,
    /// A live emitter's acceleration (gravity, wind).
    Acceleration,
    /// A live emitter's drag.
    Drag,
    /// A live emitter's turbulence's strength.
    Turbulence,
}

impl ParticleField {
    pub const ALL: [ParticleField; 11] = [
        ParticleField::Rate,
        ParticleField::Center,
        ParticleField::Radius,
        ParticleField::Spread,
        ParticleField::Color,
        ParticleField::Albedo,
        ParticleField::Emission,
        ParticleField::EmissionIntensity,
        ParticleField::Acceleration,
        ParticleField::Drag,
        ParticleField::Turbulence,
    ];

    /// Its name in a scene file.
    pub fn key(self) -> &'static str {
        match self {
            ParticleField::Rate => "rate",
            ParticleField::Center => "center",
            ParticleField::Radius => "radius",
            ParticleField::Spread => "spread",
            ParticleField::Color => "color",
            ParticleField::Albedo => "albedo",
            ParticleField::Emission => "emission",
            ParticleField::EmissionIntensity => "emission_intensity",
            ParticleField::Acceleration => "acceleration",
            ParticleField::Drag => "drag",
            ParticleField::Turbulence => "turbulence",
        }
    }

    /// The sets that have it, for messages.
    pub fn sets(self) -> &'static str {
        match self {
            ParticleField::Rate | ParticleField::Acceleration | ParticleField::Drag => {
                "a live emitter ([particles.life])"
            }
            ParticleField::Turbulence => "a live emitter with a turbulence",
            ParticleField::Center => "a sphere or box emitter",
            ParticleField::Radius => "a sphere emitter",
            ParticleField::Spread => "a curve or torus emitter",
            ParticleField::Color => "an emitter",
            ParticleField::Albedo | ParticleField::Emission | ParticleField::EmissionIntensity => {
                "any set"
            }
        }
    }

    /// Whether its value is a vector.
    pub fn is_vector(self) -> bool {
        matches!(
            self,
            ParticleField::Center
                | ParticleField::Color
                | ParticleField::Emission
                | ParticleField::Acceleration
        )
    }
}

/// The fields of an object's shape that can be keyed besides its position: each belongs to some shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeField {
    /// A box's or a mesh's rotation, degrees about x, then y, then z.
    Rotation,
    /// A sphere's radius.
    Radius,
    /// A box's side lengths.
    Size,
    /// A mesh's scale along x, y and z.
    Scale,
    /// A plane's normal (normalised after interpolation).
    Normal,
}

impl ShapeField {
    pub const ALL: [ShapeField; 5] = [
        ShapeField::Rotation,
        ShapeField::Radius,
        ShapeField::Size,
        ShapeField::Scale,
        ShapeField::Normal,
    ];

    /// Its name in a scene file.
    pub fn key(self) -> &'static str {
        match self {
            ShapeField::Rotation => "rotation",
            ShapeField::Radius => "radius",
            ShapeField::Size => "size",
            ShapeField::Scale => "scale",
            ShapeField::Normal => "normal",
        }
    }

    /// The shapes that have it, for messages.
    pub fn shapes(self) -> &'static str {
        match self {
            ShapeField::Rotation => "a box or a mesh",
            ShapeField::Radius => "a sphere",
            ShapeField::Size => "a box",
            ShapeField::Scale => "a mesh",
            ShapeField::Normal => "a plane",
        }
    }
}

/// The settings of a translucent object's material that can be keyed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TranslucentField {
    /// Its extinction coefficient.
    Extinction,
    /// Its relative index of refraction.
    Eta,
}

impl TranslucentField {
    pub const ALL: [TranslucentField; 2] = [TranslucentField::Extinction, TranslucentField::Eta];

    /// Its name in a scene file.
    pub fn key(self) -> &'static str {
        match self {
            TranslucentField::Extinction => "extinction",
            TranslucentField::Eta => "eta",
        }
    }
}

/// The integration settings that can be keyed (the division count is an integer and cannot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegrationSetting {
    DecayLength,
    Alpha,
    Beta,
    Epsilon,
}

impl IntegrationSetting {
    pub fn key(self) -> &'static str {
        match self {
            IntegrationSetting::DecayLength => "decay_length",
            IntegrationSetting::Alpha => "alpha",
            IntegrationSetting::Beta => "beta",
            IntegrationSetting::Epsilon => "epsilon",
        }
    }
}

/// The parameter paths a track may name, for messages.
pub const PARAMETER_FORMS: &str = "colors.energy, colors.energy_intensity, colors.background, points[i].position, \
points[i].coefficient, lines[i].point, lines[i].direction, lines[i].coefficient, tori[i].center, tori[i].axis, \
tori[i].major_radius, tori[i].coefficient, curves[i].control_points[j], curves[i].coefficient, curves[i].weights[j], \
points[i].color and points[i].intensity (any kind of source), curves[i].color_series[j], \
integration.decay_length, integration.alpha, integration.beta, integration.epsilon, colors.cutoff, \
objects[i].position (a sphere's or box's center, a plane's point, a mesh's translation), objects[i].color, \
objects[i].rotation (a box or a mesh), objects[i].radius (a sphere), objects[i].size (a box), \
objects[i].scale (a mesh), objects[i].normal (a plane), objects[i].translucent.extinction, \
objects[i].translucent.eta (a translucent object), particles[i].rate, particles[i].center, \
particles[i].radius, particles[i].spread, particles[i].color, particles[i].albedo, particles[i].emission, \
particles[i].emission_intensity, particles[i].acceleration, particles[i].drag, particles[i].turbulence";

/// Splits `name[3]` into `("name", Some(3))`, `name` into `("name", None)`.
fn indexed(part: &str) -> Option<(&str, Option<usize>)> {
    match part.split_once('[') {
        None => Some((part, None)),
        Some((name, rest)) => {
            let index = rest.strip_suffix(']')?.trim().parse().ok()?;
            Some((name, Some(index)))
        }
    }
}

impl Parameter {
    /// Parses a path such as `curves[0].control_points[1]`; the error says which forms exist.
    pub fn parse(path: &str) -> Result<Parameter, String> {
        let err = || {
            format!("{path:?} is not a parameter that can be keyed; use one of: {PARAMETER_FORMS}")
        };
        let parts: Vec<&str> = path.trim().split('.').collect();
        let parts: Option<Vec<(&str, Option<usize>)>> = parts.iter().map(|p| indexed(p)).collect();
        let parts = parts.ok_or_else(err)?;
        use SourceKind::*;
        let kind = |name: &str| match name {
            "points" => Some(Points),
            "lines" => Some(Lines),
            "tori" => Some(Tori),
            "curves" => Some(Curves),
            _ => None,
        };
        let p = match parts.as_slice() {
            [("colors", None), ("energy", None)] => Parameter::EnergyColor,
            [("colors", None), ("background", None)] => Parameter::BackgroundColor,
            [("colors", None), ("energy_intensity", None)] => Parameter::EnergyIntensity,
            [("colors", None), ("cutoff", None)] => Parameter::Cutoff,
            [
                ("objects", Some(i)),
                ("position" | "center" | "point" | "translation", None),
            ] => Parameter::ObjectPosition(*i),
            [("objects", Some(i)), ("color", None)] => Parameter::ObjectColor(*i),
            [("objects", Some(i)), ("translucent", None), (name, None)] => Parameter::Translucent(
                *i,
                (TranslucentField::ALL.into_iter())
                    .find(|f| f.key() == *name)
                    .ok_or_else(err)?,
            ),
            [("objects", Some(i)), (name, None)] => Parameter::ObjectShape(
                *i,
                (ShapeField::ALL.into_iter())
                    .find(|f| f.key() == *name)
                    .ok_or_else(err)?,
            ),
            [("particles", Some(i)), (name, None)] => Parameter::Particles(
                *i,
                (ParticleField::ALL.into_iter())
                    .find(|f| f.key() == *name)
                    .ok_or_else(err)?,
            ),
            [("integration", None), (name, None)] => Parameter::Integration(
                [
                    IntegrationSetting::DecayLength,
                    IntegrationSetting::Alpha,
                    IntegrationSetting::Beta,
                    IntegrationSetting::Epsilon,
                ]
                .into_iter()
                .find(|k| k.key() == *name)
                .ok_or_else(err)?,
            ),
            [(k, Some(i)), (field, sub)] => match (kind(k).ok_or_else(err)?, *field, sub) {
                (Points, "position", None) | (Lines, "point", None) | (Tori, "center", None) => {
                    Parameter::Position(kind(k).ok_or_else(err)?, *i)
                }
                (Lines, "direction", None) | (Tori, "axis", None) => {
                    Parameter::Direction(kind(k).ok_or_else(err)?, *i)
                }
                (kind, "coefficient", None) => Parameter::Coefficient(kind, *i),
                (kind, "color", None) => Parameter::SourceColor(kind, *i),
                (kind, "intensity", None) => Parameter::Intensity(kind, *i),
                (Tori, "major_radius", None) => Parameter::MajorRadius(*i),
                (Curves, "control_points", Some(j)) => Parameter::ControlPoint(*i, *j),
                (Curves, "weights", Some(j)) => Parameter::Weight(*i, *j),
                (Curves, "color_series", Some(j)) => Parameter::SeriesColor(*i, *j),
                _ => return Err(err()),
            },
            _ => return Err(err()),
        };
        Ok(p)
    }

    /// True when the value is a vector (three numbers), false for a number.
    pub fn is_vector(&self) -> bool {
        matches!(
            self,
            Parameter::EnergyColor
                | Parameter::BackgroundColor
                | Parameter::SourceColor(..)
                | Parameter::SeriesColor(..)
                | Parameter::Position(..)
                | Parameter::Direction(..)
                | Parameter::ControlPoint(..)
                | Parameter::ObjectPosition(..)
                | Parameter::ObjectColor(..)
        ) || matches!(self, Parameter::ObjectShape(_, f) if *f != ShapeField::Radius)
            || matches!(self, Parameter::Particles(_, f) if f.is_vector())
    }

    /// The source this parameter belongs to, if any.
    pub fn source(&self) -> Option<(SourceKind, usize)> {
        match *self {
            Parameter::EnergyColor
            | Parameter::BackgroundColor
            | Parameter::EnergyIntensity
            | Parameter::Cutoff
            | Parameter::ObjectPosition(_)
            | Parameter::ObjectColor(_)
            | Parameter::ObjectShape(..)
            | Parameter::Translucent(..)
            | Parameter::Particles(..)
            | Parameter::Integration(_) => None,
            Parameter::Position(k, i)
            | Parameter::Direction(k, i)
            | Parameter::Coefficient(k, i)
            | Parameter::SourceColor(k, i)
            | Parameter::Intensity(k, i) => Some((k, i)),
            Parameter::MajorRadius(i) => Some((SourceKind::Tori, i)),
            Parameter::ControlPoint(i, _)
            | Parameter::Weight(i, _)
            | Parameter::SeriesColor(i, _) => Some((SourceKind::Curves, i)),
        }
    }

    /// The same parameter on source `index` instead (sources renumbered after a deletion).
    pub fn with_source_index(&self, index: usize) -> Parameter {
        match *self {
            Parameter::Position(k, _) => Parameter::Position(k, index),
            Parameter::Direction(k, _) => Parameter::Direction(k, index),
            Parameter::Coefficient(k, _) => Parameter::Coefficient(k, index),
            Parameter::SourceColor(k, _) => Parameter::SourceColor(k, index),
            Parameter::Intensity(k, _) => Parameter::Intensity(k, index),
            Parameter::MajorRadius(_) => Parameter::MajorRadius(index),
            Parameter::ControlPoint(_, j) => Parameter::ControlPoint(index, j),
            Parameter::Weight(_, j) => Parameter::Weight(index, j),
            Parameter::SeriesColor(_, j) => Parameter::SeriesColor(index, j),
            other => other,
        }
    }
}

impl fmt::Display for Parameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Parameter::EnergyColor => write!(f, "colors.energy"),
            Parameter::BackgroundColor => write!(f, "colors.background"),
            Parameter::EnergyIntensity => write!(f, "colors.energy_intensity"),
            Parameter::Cutoff => write!(f, "colors.cutoff"),
            Parameter::ObjectPosition(i) => write!(f, "objects[{i}].position"),
            Parameter::ObjectColor(i) => write!(f, "objects[{i}].color"),
            Parameter::ObjectShape(i, field) => write!(f, "objects[{i}].{}", field.key()),
            Parameter::Translucent(i, field) => {
                write!(f, "objects[{i}].translucent.{}", field.key())
            }
            Parameter::Particles(i, field) => write!(f, "particles[{i}].{}", field.key()),
            Parameter::SourceColor(k, i) => write!(f, "{}[{i}].color", k.key()),
            Parameter::Intensity(k, i) => write!(f, "{}[{i}].intensity", k.key()),
            Parameter::Position(k, i) => {
                let field = match k {
                    SourceKind::Lines => "point",
                    SourceKind::Tori => "center",
                    _ => "position",
                };
                write!(f, "{}[{i}].{field}", k.key())
            }
            Parameter::Direction(k, i) => {
                let field = if *k == SourceKind::Tori {
                    "axis"
                } else {
                    "direction"
                };
                write!(f, "{}[{i}].{field}", k.key())
            }
            Parameter::Coefficient(k, i) => write!(f, "{}[{i}].coefficient", k.key()),
            Parameter::MajorRadius(i) => write!(f, "tori[{i}].major_radius"),
            Parameter::ControlPoint(i, j) => write!(f, "curves[{i}].control_points[{j}]"),
            Parameter::Weight(i, j) => write!(f, "curves[{i}].weights[{j}]"),
            Parameter::SeriesColor(i, j) => write!(f, "curves[{i}].color_series[{j}]"),
            Parameter::Integration(k) => write!(f, "integration.{}", k.key()),
        }
    }
}
