//! `[particles.life]` in scene files: a live emitter's every setting checked with located errors, and written
//! back whole.

use super::MAX_COORDINATE;
use super::checker::Checker;
use super::file::{DirectionFile, FieldPath, LifeFile, TurbulenceFile, ValueFile};
use crate::particles::curl::Turbulence;
use crate::particles::emit::{EmitterKind, Span};
use crate::particles::live::{Burst, ColorCurve, Direction, Life, LifeCurve};
use crate::particles::ply::MAX_PARTICLES;

/// The most particles a second an emitter makes.
pub const MAX_RATE: f64 = 1e6;

/// A live emitter's settings; `path` is its set's. None where a setting is wrong (each one reported).
pub(super) fn check_life(
    c: &mut Checker<'_, '_>,
    set: &FieldPath,
    f: &LifeFile,
    kind: EmitterKind,
) -> Option<Box<Life>> {
    let path = set.key("life");
    let before = c.problems.len();
    let d = Life::default();
    let rate = f.rate.map_or(d.rate, |x| {
        let p = path.key("rate");
        if c.finite(&p, x) && !(0.0..=MAX_RATE).contains(&x) {
            c.fail(
                &p,
                format!("{x} is out of range: a rate is particles a second, 0 to {MAX_RATE:e}"),
            );
        }
        x
    });
    let mut bursts = Vec::new();
    for (j, [frame, count]) in f.bursts.iter().flatten().copied().enumerate() {
        let p = path.key("bursts").index(j);
        if !(frame.is_finite() && frame >= 0.0) {
            c.fail(&p, format!("frame {frame}: a burst's frame is at least 0"));
        }
        if !(count.fract() == 0.0 && (0.0..=MAX_PARTICLES as f64).contains(&count)) {
            c.fail(
                &p,
                format!("count {count}: a burst's count is a whole number, 0 to {MAX_PARTICLES}"),
            );
            continue;
        }
        bursts.push(Burst {
            frame,
            count: count as u32,
        });
    }
    let lifetime = f.lifetime.as_ref().map_or(d.lifetime, |v| {
        span(c, &path.key("lifetime"), v, true, "a lifetime (seconds)")
    });
    let speed = (f.speed.as_ref()).map_or(d.speed, |v| {
        span(c, &path.key("speed"), v, false, "a speed")
    });
    let direction = match &f.direction {
        None => d.direction,
        Some(DirectionFile::Vector(a)) => Direction::Fixed(c.direction(&path.key("direction"), *a)),
        Some(DirectionFile::Name(name)) => {
            let p = path.key("direction");
            match name.as_str() {
                "normal" => Direction::Normal,
                "outward" => Direction::Outward,
                "tangent" if matches!(kind, EmitterKind::Curve | EmitterKind::Torus) => {
                    Direction::Tangent
                }
                "tangent" => {
                    c.fail(
                        &p,
                        "\"tangent\": only a curve or torus emitter has a tangent (use \"normal\", \"outward\" or [x, y, z])",
                    );
                    Direction::Normal
                }
                other => {
                    c.fail(
                        &p,
                        format!("\"{other}\" is not a direction: \"normal\", \"tangent\", \"outward\" or [x, y, z]"),
                    );
                    Direction::Normal
                }
            }
        }
    };
    let cone = f.cone.map_or(d.cone, |x| {
        let p = path.key("cone");
        if c.finite(&p, x) && !(0.0..=180.0).contains(&x) {
            c.fail(
                &p,
                format!("{x} is out of range: the cone's half-angle is 0 to 180 degrees"),
            );
        }
        x
    });
    let acceleration =
        (f.acceleration).map_or(d.acceleration, |a| c.position(&path.key("acceleration"), a));
    let drag = f.drag.map_or(d.drag, |x| {
        at_least_zero(c, &path.key("drag"), x, "a drag (per second)")
    });
    let inherit = (f.inherit_velocity).map_or(d.inherit, |x| {
        at_least_zero(
            c,
            &path.key("inherit_velocity"),
            x,
            "the share of the emitter's velocity",
        )
    });
    let along_pulse = f.along_pulse.unwrap_or(false);
    if along_pulse && kind != EmitterKind::Curve {
        c.fail(
            &path.key("along_pulse"),
            "only a curve emitter emits along its curve's pulse",
        );
    }
    let size = curve(c, &path.key("size"), f.size.as_deref()).unwrap_or(d.size);
    let opacity = curve(c, &path.key("opacity"), f.opacity.as_deref()).unwrap_or(d.opacity);
    let emission = curve(c, &path.key("emission"), f.emission.as_deref()).unwrap_or(d.emission);
    let emission_colors = colors(
        c,
        &path.key("emission_colors"),
        f.emission_colors.as_deref(),
    );
    let colors = colors(c, &path.key("colors"), f.colors.as_deref());
    let turbulence = f
        .turbulence
        .as_ref()
        .map(|t| turbulence(c, &path.key("turbulence"), t));
    let shutter = f.shutter.map_or(d.shutter, |x| {
        let p = path.key("shutter");
        if c.finite(&p, x) && !(0.0..=1.0).contains(&x) {
            c.fail(
                &p,
                format!(
                    "{x} is out of range: the shutter is the share of a frame it stays open, 0 to 1 (0.5 is a 180-degree shutter)"
                ),
            );
        }
        x
    });
    let life = Life {
        rate,
        bursts,
        lifetime,
        speed,
        direction,
        cone,
        acceleration,
        drag,
        turbulence,
        inherit,
        along_pulse,
        size,
        opacity,
        colors,
        emission,
        emission_colors,
        shutter,
    };
    (c.problems.len() == before).then(|| Box::new(life))
}

fn at_least_zero(c: &mut Checker<'_, '_>, path: &FieldPath, x: f64, what: &str) -> f64 {
    if c.finite(path, x) && !(0.0..=MAX_COORDINATE).contains(&x) {
        c.fail(path, format!("{x} is out of range: {what} is at least 0"));
    }
    x
}

/// Ages of a curve's keys: in 0..1, increasing.
fn ages(c: &mut Checker<'_, '_>, path: &FieldPath, ages: impl Iterator<Item = f64>) -> bool {
    let mut last = f64::NEG_INFINITY;
    for (j, a) in ages.enumerate() {
        if !(a.is_finite() && (0.0..=1.0).contains(&a) && a > last) {
            c.fail(
                &path.index(j),
                format!(
                    "age {a}: a key's age is a share of the life in 0..1, each after the one before"
                ),
            );
            return false;
        }
        last = a;
    }
    true
}

fn curve(
    c: &mut Checker<'_, '_>,
    path: &FieldPath,
    keys: Option<&[[f64; 2]]>,
) -> Option<LifeCurve> {
    let keys = keys?;
    if keys.is_empty() {
        c.fail(
            path,
            "a curve over a life needs at least one key [age, value]",
        );
        return None;
    }
    if !ages(c, path, keys.iter().map(|k| k[0])) {
        return None;
    }
    for (j, k) in keys.iter().enumerate() {
        if !(k[1].is_finite() && (0.0..=MAX_COORDINATE).contains(&k[1])) {
            c.fail(
                &path.index(j),
                format!("value {}: a factor over a life is at least 0", k[1]),
            );
            return None;
        }
    }
    Some(LifeCurve {
        keys: keys.iter().map(|k| (k[0], k[1])).collect(),
    })
}

/// Colors over a life, `[age, r, g, b]` keys: none where the file gives none; a list given needs a key.
fn colors(c: &mut Checker<'_, '_>, path: &FieldPath, keys: Option<&[[f64; 4]]>) -> ColorCurve {
    let Some(keys) = keys else {
        return ColorCurve::default();
    };
    if keys.is_empty() {
        c.fail(
            path,
            "colors over a life need at least one key [age, r, g, b] (leave the list out for none)",
        );
        return ColorCurve::default();
    }
    if !ages(c, path, keys.iter().map(|k| k[0])) {
        return ColorCurve::default();
    }
    ColorCurve {
        keys: (keys.iter().enumerate())
            .map(|(j, k)| (k[0], c.color(&path.index(j), [k[1], k[2], k[3]])))
            .collect(),
    }
}

fn turbulence(c: &mut Checker<'_, '_>, path: &FieldPath, t: &TurbulenceFile) -> Turbulence {
    let scale = t.scale.unwrap_or(1.0);
    let p = path.key("scale");
    if c.finite(&p, scale) && !(scale > 0.0 && scale <= MAX_COORDINATE) {
        c.fail(
            &p,
            format!("{scale}: a turbulence's scale (the size of its eddies) must be positive"),
        );
    }
    Turbulence {
        scale,
        strength: at_least_zero(
            c,
            &path.key("strength"),
            t.strength.unwrap_or(1.0),
            "a turbulence's strength",
        ),
        speed: at_least_zero(
            c,
            &path.key("speed"),
            t.speed.unwrap_or(1.0),
            "a turbulence's speed",
        ),
    }
}

/// A live emitter's settings as the file writes them: every one, so the file says what the set does.
pub(super) fn write_life(life: &Life) -> LifeFile {
    let range = |s: Span| {
        Some(if s.min == s.max {
            ValueFile::Number(s.min)
        } else {
            ValueFile::Vector(vec![s.min, s.max])
        })
    };
    LifeFile {
        rate: Some(life.rate),
        bursts: (!life.bursts.is_empty()).then(|| {
            life.bursts
                .iter()
                .map(|b| [b.frame, b.count as f64])
                .collect()
        }),
        lifetime: range(life.lifetime),
        speed: range(life.speed),
        direction: Some(match (life.direction.name(), life.direction) {
            (Some(name), _) => DirectionFile::Name(name.to_owned()),
            (None, Direction::Fixed(d)) => DirectionFile::Vector(d.to_array()),
            (None, _) => DirectionFile::Name("normal".to_owned()),
        }),
        cone: Some(life.cone),
        acceleration: Some(life.acceleration.to_array()),
        drag: Some(life.drag),
        inherit_velocity: Some(life.inherit),
        along_pulse: life.along_pulse.then_some(true),
        size: Some(life.size.keys.iter().map(|&(a, x)| [a, x]).collect()),
        opacity: Some(life.opacity.keys.iter().map(|&(a, x)| [a, x]).collect()),
        colors: (!life.colors.keys.is_empty()).then(|| {
            (life.colors.keys.iter())
                .map(|&(a, [r, g, b])| [a, r, g, b])
                .collect()
        }),
        emission: (life.emission != LifeCurve::constant(1.0))
            .then(|| life.emission.keys.iter().map(|&(a, x)| [a, x]).collect()),
        emission_colors: (!life.emission_colors.keys.is_empty()).then(|| {
            (life.emission_colors.keys.iter())
                .map(|&(a, [r, g, b])| [a, r, g, b])
                .collect()
        }),
        turbulence: life.turbulence.map(|t| TurbulenceFile {
            scale: Some(t.scale),
            strength: Some(t.strength),
            speed: Some(t.speed),
        }),
        shutter: (life.shutter > 0.0).then_some(life.shutter),
    }
}

/// A range `[min, max]` or one number.
pub(super) fn span(
    c: &mut Checker<'_, '_>,
    path: &FieldPath,
    v: &ValueFile,
    strictly: bool,
    what: &str,
) -> Span {
    let s = match v {
        ValueFile::Number(x) => Span::one(*x),
        ValueFile::Vector(a) if a.len() == 2 => Span {
            min: a[0],
            max: a[1],
        },
        ValueFile::Vector(a) => {
            c.fail(
                path,
                format!(
                    "{} numbers: {what} is one number or a range [min, max]",
                    a.len()
                ),
            );
            return Span::one(1.0);
        }
    };
    let low_ok = if strictly { s.min > 0.0 } else { s.min >= 0.0 };
    if !(s.min.is_finite()
        && s.max.is_finite()
        && low_ok
        && s.max >= s.min
        && s.max <= MAX_COORDINATE)
    {
        c.fail(
            path,
            format!(
                "[{}, {}]: {what} must be {} and the range's first number at most its second",
                s.min,
                s.max,
                if strictly { "positive" } else { "at least 0" }
            ),
        );
        return Span::one(1.0);
    }
    s
}
