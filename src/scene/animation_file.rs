//! The scene file's time: `[animation]` with its `[[animation.tracks]]`, and each curve's `[curves.pulse]`,
//! validated into a `crate::animation::Animation` (every problem reported with its place and field), and
//! written back.

use super::checker::Checker;
use super::file::{self, FieldPath, Locator, SceneFile};
use super::{Scene, limits};
use crate::animation::{
    Animation, CurvePulse, DEFAULT_FRAME_RATE, IntegrationSetting, Key, MAX_FRAMES, Parameter,
    Pulse, ShapeField, Track, Value,
};
use crate::scene::Problem;

/// Most weights a pulse may animate.
pub const MAX_PULSE_COUNT: i64 = 1024;

/// The scene's animation, or `None` when the file has neither `[animation]` nor a pulse nor a track.
/// `scene` is the validated still scene (tracks must name something in it).
pub(super) fn validate(
    file: &SceneFile,
    scene: &Scene,
    locator: &Locator<'_>,
    problems: &mut Vec<Problem>,
) -> Option<Animation> {
    let mut c = Checker { locator, problems };
    let root = FieldPath::default();

    let mut pulses = Vec::new();
    for (i, curve) in file.curves.iter().enumerate() {
        let Some(p) = &curve.pulse else { continue };
        let path = root.key("curves").index(i).key("pulse");
        let default_count = curve
            .weights
            .as_ref()
            .map_or(Pulse::THESIS_COUNT, |w| w.len().max(1));
        let count = match p.count {
            None => default_count,
            Some(n) if (1..=MAX_PULSE_COUNT).contains(&n) => n as usize,
            Some(n) => {
                c.fail(
                    &path.key("count"),
                    format!("{n}: a pulse animates between 1 and {MAX_PULSE_COUNT} weights (the thesis uses 7)"),
                );
                default_count
            }
        };
        let mut positive = |key: &'static str, x: Option<f64>, default: f64, what: &str| {
            x.map_or(default, |x| {
                c.in_open_range(&path.key(key), x, 0.0, f64::INFINITY, what)
            })
        };
        let speed = positive(
            "speed",
            p.speed,
            Pulse::THESIS_SPEED,
            "the speed is a factor on time and must be positive (1 is the thesis's)",
        );
        let width = positive(
            "width",
            p.width,
            Pulse::THESIS_WIDTH,
            "the width is in frames and must be positive (50 is the thesis's)",
        );
        let period = p.period.map(|x| {
            positive(
                "period",
                Some(x),
                1.0,
                "the period is in frames and must be positive (remove it for a pulse that runs once)",
            )
        });
        let delay = p.delay.map_or(Pulse::THESIS_DELAY, |x| {
            c.finite(&path.key("delay"), x);
            x
        });
        let start = p.start.map_or(0.0, |x| {
            c.finite(&path.key("start"), x);
            x
        });
        pulses.push(CurvePulse {
            curve: i,
            pulse: Pulse {
                count,
                speed,
                width,
                delay,
                start,
                period,
            },
        });
    }

    let anim = file.animation.as_ref();
    let anim_path = root.key("animation");
    let mut tracks: Vec<Track> = Vec::new();
    for (i, t) in anim.map_or(&[][..], |a| &a.tracks).iter().enumerate() {
        let path = anim_path.key("tracks").index(i);
        // The papers' nu, keyed: each key becomes the decay length it gives at this file's camera.
        let legacy_nu = t.parameter.trim() == "integration.nu";
        if legacy_nu
            && file
                .integration
                .as_ref()
                .is_some_and(|i| i.decay_length.is_some())
        {
            c.fail(
                &path.key("parameter"),
                "integration.nu only derives the decay length, and this file gives one: key integration.decay_length",
            );
            continue;
        }
        let parameter = match Parameter::parse(if legacy_nu {
            "integration.decay_length"
        } else {
            &t.parameter
        }) {
            Ok(p) => p,
            Err(e) => {
                c.fail(&path.key("parameter"), e);
                continue;
            }
        };
        let Some(base) = parameter.get(scene) else {
            let why = match parameter {
                Parameter::Weight(..) => {
                    "the curve, or that weight of its W series, does not exist (key weights only of a curve with `weights`)"
                }
                Parameter::ObjectShape(_, field) => &*format!(
                    "names an object the scene does not have, or one that is not {} (the shapes with a {})",
                    field.shapes(),
                    field.key()
                ),
                Parameter::ObjectPosition(_) | Parameter::ObjectColor(_) => {
                    "names an object the scene does not have"
                }
                Parameter::Translucent(..) => {
                    "names an object the scene does not have, or one that is not translucent (give it an [objects.translucent])"
                }
                Parameter::Particles(_, field) => &*format!(
                    "names a particle set the scene does not have, or one without a {} (the sets with one: {})",
                    field.key(),
                    field.sets()
                ),
                _ => "names a source or control point the scene does not have",
            };
            c.fail(&path.key("parameter"), format!("{}: {why}", t.parameter));
            continue;
        };
        if let Parameter::Weight(curve, _) = parameter
            && pulses.iter().any(|p| p.curve == curve)
        {
            c.fail(
                &path.key("parameter"),
                format!(
                    "{}: the curve's W series is its pulse; remove the pulse or this track",
                    t.parameter
                ),
            );
        }
        if tracks.iter().any(|other| other.parameter == parameter) {
            c.fail(
                &path.key("parameter"),
                format!(
                    "{}: keyed twice; put all its keys in one track",
                    t.parameter
                ),
            );
        }
        if t.keys.is_empty() {
            c.fail(&path.key("keys"), "a track needs at least one key");
        }
        let mut keys = Vec::new();
        for (k, key) in t.keys.iter().enumerate() {
            let key_path = path.key("keys").index(k);
            c.finite(&key_path.key("frame"), key.frame);
            if let Some(prev) = keys.last().map(|k: &Key| k.frame)
                && key.frame.is_finite()
                && key.frame <= prev
            {
                c.fail(
                    &key_path.key("frame"),
                    format!("{}: keys must be in increasing frame order (the key before is at frame {prev})", key.frame),
                );
            }
            let value_path = key_path.key("value");
            let value = match (&key.value, base) {
                (file::ValueFile::Number(nu), Value::Number(_)) if legacy_nu => {
                    c.within(&value_path, *nu, limits::nu);
                    Value::Number(crate::geometry::papers_decay_length(
                        &scene.camera,
                        &scene.sources,
                        scene.billboard.center,
                        *nu,
                    ))
                }
                (file::ValueFile::Number(x), Value::Number(_)) => Value::Number(*x),
                (file::ValueFile::Vector(v), Value::Vector(_)) if v.len() == 3 => {
                    Value::Vector([v[0], v[1], v[2]])
                }
                (_, Value::Number(_)) => {
                    c.fail(&value_path, format!("{} is a number", t.parameter));
                    continue;
                }
                (_, Value::Vector(_)) => {
                    c.fail(
                        &value_path,
                        format!("{} is a vector of three numbers [x, y, z]", t.parameter),
                    );
                    continue;
                }
            };
            if !value.is_finite() {
                c.fail(&value_path, "every number of a value must be finite");
            } else {
                check_value(&mut c, &value_path, &parameter, value);
            }
            keys.push(Key {
                frame: key.frame,
                value,
            });
        }
        tracks.push(Track { parameter, keys });
    }

    if anim.is_none() && pulses.is_empty() && tracks.is_empty() {
        return None;
    }
    let frame_rate = anim
        .and_then(|a| a.frame_rate)
        .map_or(DEFAULT_FRAME_RATE, |x| {
            c.in_open_range(
                &anim_path.key("frame_rate"),
                x,
                0.0,
                f64::INFINITY,
                "frames per second must be positive",
            )
        });
    let frames = match anim.and_then(|a| a.frames) {
        None => Animation::natural_length(&pulses, &tracks),
        Some(n) if (1..=MAX_FRAMES as i64).contains(&n) => n as u32,
        Some(n) => {
            c.fail(
                &anim_path.key("frames"),
                format!("{n}: the length in frames must be between 1 and {MAX_FRAMES}"),
            );
            1
        }
    };
    Some(Animation {
        frame_rate,
        frames,
        pulses,
        tracks,
    })
}

/// What the still scene requires of a value holds for a key too.
fn check_value(c: &mut Checker<'_, '_>, path: &FieldPath, parameter: &Parameter, value: Value) {
    match (parameter, value) {
        (
            Parameter::EnergyColor
            | Parameter::BackgroundColor
            | Parameter::SourceColor(..)
            | Parameter::SeriesColor(..)
            | Parameter::ObjectColor(..)
            | Parameter::Particles(_, crate::animation::ParticleField::Color)
            | Parameter::Particles(_, crate::animation::ParticleField::Emission),
            Value::Vector(v),
        ) => {
            c.color(path, v);
        }
        (
            Parameter::Particles(_, crate::animation::ParticleField::EmissionIntensity),
            Value::Number(x),
        ) => {
            c.intensity(path, x);
        }
        (Parameter::Particles(_, field), Value::Number(x)) => {
            use crate::animation::ParticleField as F;
            let (ok, what) = match field {
                F::Radius => (x > 0.0, "positive"),
                F::Rate => (
                    (0.0..=crate::scene::MAX_RATE).contains(&x),
                    "0 to 1e6 particles a second",
                ),
                F::Albedo => ((0.0..=1.0).contains(&x), "in 0..1"),
                _ => (x >= 0.0, "at least 0"),
            };
            if c.finite(path, x) && !ok {
                c.fail(
                    path,
                    format!(
                        "{x} is out of range: particles[i].{} must be {what}",
                        field.key()
                    ),
                );
            }
        }
        (Parameter::EnergyIntensity | Parameter::Intensity(..), Value::Number(x)) => {
            c.intensity(path, x);
        }
        (Parameter::Translucent(_, field), Value::Number(x)) => {
            use crate::animation::TranslucentField as F;
            let (ok, what) = match field {
                F::Extinction => (
                    (0.0..=super::translucent_file::MAX_EXTINCTION).contains(&x),
                    "0 (clear) to 1e4 per unit of length",
                ),
                F::Eta => (x > 0.0 && x <= 10.0, "in (0, 10]"),
            };
            if c.finite(path, x) && !ok {
                c.fail(
                    path,
                    format!(
                        "{x} is out of range: objects[i].translucent.{} must be {what}",
                        field.key()
                    ),
                );
            }
        }
        (Parameter::Cutoff, Value::Number(x)) if !(0.0..=crate::scene::MAX_CUTOFF).contains(&x) => {
            c.fail(
                path,
                format!(
                    "{x} is out of range: the glow's edge is a brightness B in 0..={}",
                    crate::scene::MAX_CUTOFF
                ),
            );
        }
        (Parameter::Direction(..), Value::Vector(v))
            if glam::DVec3::from_array(v).length() <= 1e-12 =>
        {
            c.fail(path, "a direction must not be the zero vector");
        }
        (Parameter::ObjectShape(_, ShapeField::Radius), Value::Number(x)) if x <= 0.0 => {
            c.fail(path, format!("{x}: a sphere's radius must be positive"));
        }
        (Parameter::ObjectShape(_, ShapeField::Size), Value::Vector(v))
            if v.iter().any(|&x| x <= 0.0) =>
        {
            c.fail(path, "a box's side lengths must be positive");
        }
        (Parameter::ObjectShape(_, ShapeField::Scale), Value::Vector(v)) if v.contains(&0.0) => {
            c.fail(path, "a mesh's scale must not be 0 along any axis");
        }
        (Parameter::ObjectShape(_, ShapeField::Normal), Value::Vector(v))
            if glam::DVec3::from_array(v).length() <= 1e-12 =>
        {
            c.fail(path, "a plane's normal must not be the zero vector");
        }
        (Parameter::MajorRadius(_), Value::Number(x)) if x <= 0.0 => {
            c.fail(path, format!("{x}: the major radius R must be positive"));
        }
        (Parameter::Integration(IntegrationSetting::DecayLength), Value::Number(x)) => {
            c.within(path, x, limits::decay_length);
        }
        (Parameter::Integration(k), Value::Number(x)) if x <= 0.0 => {
            c.fail(path, format!("{x}: {} must be positive", k.key()));
        }
        (Parameter::Weight(..), Value::Number(x)) => {
            c.within(path, x, limits::weight);
        }
        _ => {}
    }
}

/// Fills in the file's `[animation]` and pulses from `scene` (every setting written out).
pub(super) fn write(scene: &Scene, file: &mut SceneFile) {
    let Some(a) = &scene.animation else { return };
    for p in &a.pulses {
        if let Some(curve) = file.curves.get_mut(p.curve) {
            let pulse = &p.pulse;
            curve.pulse = Some(file::PulseFile {
                count: Some(pulse.count as i64),
                speed: Some(pulse.speed),
                width: Some(pulse.width),
                delay: Some(pulse.delay),
                start: Some(pulse.start),
                period: pulse.period,
            });
        }
    }
    file.animation = Some(file::AnimationFile {
        frame_rate: Some(a.frame_rate),
        frames: Some(a.frames as i64),
        tracks: (a.tracks.iter())
            .map(|t| file::TrackFile {
                parameter: t.parameter.to_string(),
                keys: (t.keys.iter())
                    .map(|k| file::KeyFile {
                        frame: k.frame,
                        value: match k.value {
                            Value::Number(x) => file::ValueFile::Number(x),
                            Value::Vector(v) => file::ValueFile::Vector(v.to_vec()),
                        },
                    })
                    .collect(),
            })
            .collect(),
    });
}
