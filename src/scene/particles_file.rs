//! `[[particles]]` and `[slices]` in scene files: each set's keys checked with located errors, PLY files read,
//! and the sets written back as they were given.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use super::MAX_COORDINATE;
use super::checker::Checker;
use super::file::{FieldPath, ParticlesFile, SceneFile, SlicesFile, ValueFile};
use super::life_file::{self, span};
use crate::field::Sources;
use crate::particles::emit::{Emitter, EmitterKind, EmitterShape, Span};
use crate::particles::ply::{self, Defaults, MAX_PARTICLES};
use crate::particles::{DEFAULT_ALBEDO, DEFAULT_SLICE_WIDTH, Emission, Origin, ParticleSet};

/// A particle's radius, density and color where a set gives none.
pub const DEFAULTS: Defaults = Defaults {
    radius: 0.1,
    density: 4.0,
    color: [0.8, 0.8, 0.8],
};

const _: () = assert!(ply::MAX_COORDINATE == MAX_COORDINATE);

/// The most slices per particle radius (`[slices] width` at least its inverse).
pub const MIN_SLICE_WIDTH: f64 = 0.05;

/// Which keys an emitter of each shape takes besides the common ones.
fn shape_keys(kind: EmitterKind) -> &'static [&'static str] {
    match kind {
        EmitterKind::Sphere => &["center", "radius"],
        EmitterKind::Box => &["center", "size"],
        EmitterKind::Curve => &["curve", "spread"],
        EmitterKind::Torus => &["torus", "spread"],
    }
}

/// The keys every emitter takes.
const EMITTER_KEYS: [&str; 11] = [
    "life",
    "count",
    "particle_radius",
    "density",
    "color",
    "seed",
    "noise",
    "albedo",
    "emission",
    "emission_intensity",
    "emitter",
];

/// The keys a set from a file takes.
const FILE_KEYS: [&str; 7] = [
    "file",
    "particle_radius",
    "density",
    "color",
    "albedo",
    "emission",
    "emission_intensity",
];

/// The particle sets of the file; `base` is the scene file's folder, against which a PLY file's relative path
/// is read; `sources` are the scene's, which curve and torus emitters follow.
pub(super) fn check_particles(
    c: &mut Checker<'_, '_>,
    file: &SceneFile,
    base: &Path,
    sources: &Sources,
) -> Vec<ParticleSet> {
    let root = FieldPath::default().key("particles");
    let mut out = Vec::new();
    let mut total = 0usize;
    for (i, f) in file.particles.iter().enumerate() {
        let path = root.index(i);
        let given: [(&'static str, bool); 18] = [
            ("life", f.life.is_some()),
            ("file", f.file.is_some()),
            ("emitter", f.emitter.is_some()),
            ("center", f.center.is_some()),
            ("radius", f.radius.is_some()),
            ("size", f.size.is_some()),
            ("curve", f.curve.is_some()),
            ("torus", f.torus.is_some()),
            ("spread", f.spread.is_some()),
            ("count", f.count.is_some()),
            ("particle_radius", f.particle_radius.is_some()),
            ("density", f.density.is_some()),
            ("color", f.color.is_some()),
            ("seed", f.seed.is_some()),
            ("noise", f.noise.is_some()),
            ("albedo", f.albedo.is_some()),
            ("emission", f.emission.is_some()),
            ("emission_intensity", f.emission_intensity.is_some()),
        ];
        let albedo = f.albedo.map_or(DEFAULT_ALBEDO, |x| {
            let p = path.key("albedo");
            if c.finite(&p, x) && !(0.0..=1.0).contains(&x) {
                c.fail(
                    &p,
                    format!("{x} is out of range: an albedo is a share of the light, in 0..1"),
                );
            }
            x
        });
        let color = f
            .color
            .map_or(DEFAULTS.color, |a| c.color(&path.key("color"), a));
        // A color given alone glows at intensity 1, an intensity alone white, and so does a life whose emission
        // follows curves (they would show nothing at intensity 0).
        let life_glows =
            (f.life.as_ref()).is_some_and(|l| l.emission.is_some() || l.emission_colors.is_some());
        let emission = Emission {
            color: (f.emission).map_or(Emission::NONE.color, |a| c.color(&path.key("emission"), a)),
            intensity: match (f.emission, f.emission_intensity) {
                (_, Some(x)) => c.intensity(&path.key("emission_intensity"), x),
                (Some(_), None) => 1.0,
                (None, None) if life_glows => 1.0,
                (None, None) => Emission::NONE.intensity,
            },
        };
        let origin = match (&f.file, &f.emitter) {
            (Some(_), Some(_)) => {
                c.fail(&path, "a particle set has a file or an emitter, not both");
                continue;
            }
            (None, None) => {
                c.fail(
                    &path,
                    "a particle set needs a file (a PLY point cloud) or an emitter (\"sphere\", \"box\", \"curve\", \"torus\")",
                );
                continue;
            }
            (Some(written), None) => {
                unexpected(c, &path, &given, &FILE_KEYS, "a set from a file");
                let radius = match &f.particle_radius {
                    None => DEFAULTS.radius,
                    Some(v) => one_number(c, &path.key("particle_radius"), v, "radius"),
                };
                c.positive(&path.key("particle_radius"), radius, "a particle's radius");
                let density = match &f.density {
                    None => DEFAULTS.density,
                    Some(v) => one_number(c, &path.key("density"), v, "density"),
                };
                at_least_zero(c, &path.key("density"), density, "a particle's density");
                let defaults = Defaults {
                    radius,
                    density,
                    color,
                };
                let written = PathBuf::from(written);
                let full = if written.is_absolute() {
                    written.clone()
                } else {
                    base.join(&written)
                };
                match ply::read(&full, defaults) {
                    Ok(particles) => Origin::File {
                        path: written,
                        defaults,
                        particles: Arc::new(particles),
                    },
                    Err(e) => {
                        c.fail(&path.key("file"), format!("{}: {e}", full.display()));
                        continue;
                    }
                }
            }
            (None, Some(name)) => {
                let Some(kind) = EmitterKind::ALL.into_iter().find(|k| k.name() == name) else {
                    c.fail(
                        &path.key("emitter"),
                        format!("\"{name}\" is not an emitter: one of \"sphere\", \"box\", \"curve\", \"torus\""),
                    );
                    continue;
                };
                let allowed: Vec<&str> = EMITTER_KEYS
                    .iter()
                    .chain(shape_keys(kind))
                    .copied()
                    .collect();
                unexpected(
                    c,
                    &path,
                    &given,
                    &allowed,
                    &format!("a {} emitter", kind.name()),
                );
                let Some(shape) = shape(c, &path, f, kind, sources) else {
                    continue;
                };
                let life = match &f.life {
                    None => None,
                    Some(l) => {
                        if file.animation.is_none() {
                            c.fail(
                                &path.key("life"),
                                "a live set lives in time: the scene needs its [animation] (a frame rate and a length)",
                            );
                        }
                        if f.noise.is_some() {
                            c.fail(
                                &path.key("noise"),
                                "noise clumps a still set; a live set's particles move: give it a turbulence ([particles.life.turbulence])",
                            );
                        }
                        if f.count.is_some() {
                            c.fail(
                                &path.key("count"),
                                "a live emitter makes its particles by its life's rate and bursts: count is for a still set",
                            );
                        }
                        let Some(life) = life_file::check_life(c, &path, l, kind) else {
                            continue;
                        };
                        Some(life)
                    }
                };
                let count = match f.count {
                    None if life.is_some() => 0,
                    None => {
                        c.fail(
                            &path,
                            "an emitter needs its count: how many particles it makes",
                        );
                        continue;
                    }
                    Some(n) if !(0..=MAX_PARTICLES as i64).contains(&n) => {
                        c.fail(
                            &path.key("count"),
                            format!(
                                "{n} is out of range: a scene takes 0 to {MAX_PARTICLES} particles"
                            ),
                        );
                        continue;
                    }
                    Some(n) => n as u32,
                };
                let radius = match &f.particle_radius {
                    None => Span::one(DEFAULTS.radius),
                    Some(v) => span(
                        c,
                        &path.key("particle_radius"),
                        v,
                        true,
                        "a particle's radius",
                    ),
                };
                let density = match &f.density {
                    None => Span::one(DEFAULTS.density),
                    Some(v) => span(c, &path.key("density"), v, false, "a particle's density"),
                };
                let seed = match f.seed {
                    None => 0,
                    Some(s) if s < 0 => {
                        c.fail(
                            &path.key("seed"),
                            format!("{s}: a seed is a whole number, at least 0"),
                        );
                        0
                    }
                    Some(s) => s as u64,
                };
                let noise = f.noise.map_or(0.0, |x| {
                    let p = path.key("noise");
                    if c.finite(&p, x) && !(0.0..=1.0).contains(&x) {
                        c.fail(
                            &p,
                            format!("{x} is out of range: the noise is in 0..1 (0: no clumping)"),
                        );
                    }
                    x
                });
                Origin::Emitter(Emitter {
                    shape,
                    count,
                    radius,
                    density,
                    color,
                    seed,
                    noise,
                    life,
                })
            }
        };
        let set = ParticleSet {
            origin,
            albedo,
            emission,
            live: None,
        };
        total += match &set.origin {
            Origin::File { particles, .. } => particles.len(),
            Origin::Emitter(e) => match &e.life {
                // The most a live set holds at once at its own rate (a keyed rate is bounded the same way as it
                // is simulated: births past the limit are skipped).
                Some(life) => life.most_alive(life.rate).min(MAX_PARTICLES as f64 + 1.0) as usize,
                None => e.count as usize,
            },
        };
        out.push(set);
    }
    if total > MAX_PARTICLES {
        c.fail(
            &root,
            format!("{total} particles in all: a scene takes at most {MAX_PARTICLES}"),
        );
    }
    out
}

/// `[slices] width`: in radii of the smallest particle.
pub(super) fn check_slices(c: &mut Checker<'_, '_>, file: &SceneFile) -> f64 {
    let Some(width) = file.slices.as_ref().and_then(|s| s.width) else {
        return DEFAULT_SLICE_WIDTH;
    };
    let p = FieldPath::default().key("slices").key("width");
    if c.finite(&p, width) && !(MIN_SLICE_WIDTH..=2.0).contains(&width) {
        c.fail(
            &p,
            format!("{width} is out of range: the slices' width is in radii of the smallest particle, {MIN_SLICE_WIDTH}..2 (the paper's is 0.5)"),
        );
    }
    width
}

/// The keys given that a set of this kind does not take.
fn unexpected(
    c: &mut Checker<'_, '_>,
    path: &FieldPath,
    given: &[(&'static str, bool)],
    allowed: &[&str],
    what: &str,
) {
    for &(key, present) in given {
        if present && !allowed.contains(&key) {
            c.fail(
                &path.key(key),
                format!("{what} has no {key} (its keys: {})", allowed.join(", ")),
            );
        }
    }
}

fn shape(
    c: &mut Checker<'_, '_>,
    path: &FieldPath,
    f: &ParticlesFile,
    kind: EmitterKind,
    sources: &Sources,
) -> Option<EmitterShape> {
    let center = f
        .center
        .map_or(DVec3::ZERO, |a| c.position(&path.key("center"), a));
    let spread = f.spread.unwrap_or(0.2);
    if matches!(kind, EmitterKind::Curve | EmitterKind::Torus) {
        at_least_zero(
            c,
            &path.key("spread"),
            spread,
            "the spread around the source",
        );
    }
    let index = |c: &mut Checker<'_, '_>, key: &'static str, given: Option<i64>, have: usize| {
        let n = given.unwrap_or(0);
        if n < 0 || n as usize >= have {
            let p = if given.is_some() {
                path.key(key)
            } else {
                path.clone()
            };
            c.fail(
                &p,
                format!(
                    "{key} {n}: the scene has {have} {key} source{} ([[{}]], counted from 0)",
                    if have == 1 { "" } else { "s" },
                    if key == "curve" { "curves" } else { "tori" },
                ),
            );
            return None;
        }
        Some(n as usize)
    };
    Some(match kind {
        EmitterKind::Sphere => {
            let radius = f.radius.unwrap_or(1.0);
            c.positive(&path.key("radius"), radius, "the emitter's radius");
            EmitterShape::Sphere { center, radius }
        }
        EmitterKind::Box => {
            let size = match &f.size {
                None => DVec3::ONE,
                Some(ValueFile::Number(x)) => DVec3::splat(*x),
                Some(ValueFile::Vector(a)) if a.len() == 3 => DVec3::new(a[0], a[1], a[2]),
                Some(ValueFile::Vector(a)) => {
                    c.fail(
                        &path.key("size"),
                        format!(
                            "{} numbers: a box's size is [x, y, z] or one number",
                            a.len()
                        ),
                    );
                    DVec3::ONE
                }
            };
            if !size.is_finite() || size.min_element() <= 0.0 || size.max_element() > MAX_COORDINATE
            {
                c.fail(
                    &path.key("size"),
                    format!(
                        "{:?}: a box's side lengths must be positive",
                        size.to_array()
                    ),
                );
            }
            EmitterShape::Box { center, size }
        }
        EmitterKind::Curve => EmitterShape::Curve {
            curve: index(c, "curve", f.curve, sources.curves.len())?,
            spread,
        },
        EmitterKind::Torus => EmitterShape::Torus {
            torus: index(c, "torus", f.torus, sources.tori.len())?,
            spread,
        },
    })
}

/// One number where a file gives a set's default.
fn one_number(c: &mut Checker<'_, '_>, path: &FieldPath, v: &ValueFile, what: &str) -> f64 {
    match v {
        ValueFile::Number(x) => *x,
        ValueFile::Vector(_) => {
            c.fail(
                path,
                format!("one number: the {what} of the file's particles that give none"),
            );
            1.0
        }
    }
}

fn at_least_zero(c: &mut Checker<'_, '_>, path: &FieldPath, x: f64, what: &str) {
    if c.finite(path, x) && !(0.0..=MAX_COORDINATE).contains(&x) {
        c.fail(
            path,
            format!("{x} is out of range: {what} must be at least 0"),
        );
    }
}

/// The sets as the file writes them.
pub(super) fn write(sets: &[ParticleSet]) -> Vec<ParticlesFile> {
    let range = |s: Span| {
        Some(if s.min == s.max {
            ValueFile::Number(s.min)
        } else {
            ValueFile::Vector(vec![s.min, s.max])
        })
    };
    sets.iter()
        .map(|set| {
            let glows = set.emission != Emission::NONE;
            let mut f = ParticlesFile {
                albedo: Some(set.albedo),
                emission: glows.then_some(set.emission.color),
                emission_intensity: glows.then_some(set.emission.intensity),
                ..ParticlesFile::default()
            };
            match &set.origin {
                Origin::File { path, defaults, .. } => {
                    f.file = Some(path.to_string_lossy().into_owned());
                    f.particle_radius = Some(ValueFile::Number(defaults.radius));
                    f.density = Some(ValueFile::Number(defaults.density));
                    f.color = Some(defaults.color);
                }
                Origin::Emitter(e) => {
                    f.emitter = Some(e.shape.kind().name().to_owned());
                    match e.shape {
                        EmitterShape::Sphere { center, radius } => {
                            f.center = Some(center.to_array());
                            f.radius = Some(radius);
                        }
                        EmitterShape::Box { center, size } => {
                            f.center = Some(center.to_array());
                            f.size = Some(ValueFile::Vector(size.to_array().to_vec()));
                        }
                        EmitterShape::Curve { curve, spread } => {
                            f.curve = Some(curve as i64);
                            f.spread = Some(spread);
                        }
                        EmitterShape::Torus { torus, spread } => {
                            f.torus = Some(torus as i64);
                            f.spread = Some(spread);
                        }
                    }
                    match &e.life {
                        Some(life) => f.life = Some(life_file::write_life(life)),
                        None => f.count = Some(e.count as i64),
                    }
                    f.particle_radius = range(e.radius);
                    f.density = range(e.density);
                    f.color = Some(e.color);
                    f.seed = Some(e.seed as i64);
                    f.noise = e.life.is_none().then_some(e.noise);
                }
            }
            f
        })
        .collect()
}

/// `[slices]` as the file writes it: only where it differs from the default.
pub(super) fn write_slices(width: f64) -> Option<SlicesFile> {
    (width != DEFAULT_SLICE_WIDTH).then_some(SlicesFile { width: Some(width) })
}
