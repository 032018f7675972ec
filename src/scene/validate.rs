//! The validator: a scene file's tables converted into a scene, every field checked (`checker::Checker`), every
//! problem collected; and the deserializer that finds every unknown key at once.

use std::path::Path;

use glam::DVec3;

use super::checker::Checker;
use super::error::Problem;
use super::file::{self, FieldPath, Locator, SceneFile};
use super::{
    BillboardSettings, Blend, Colors, Glare, MAX_CUTOFF, MAX_GLARE_SIZE, MAX_INTENSITY, PAPERS_NU,
    Scene, limits, objects_file, particles_file,
};
use crate::field::{Curve, Line, Point, Sources, Torus, WForm};
use crate::geometry::{self, Camera};
use crate::integrate::{Decay, Integration, Integrator};

pub(super) fn validate(
    file: &SceneFile,
    locator: &Locator<'_>,
    base: &Path,
    problems: &mut Vec<Problem>,
) -> Scene {
    let mut c = Checker { locator, problems };
    let camera = check_camera(&mut c, file);
    let billboard = check_billboard(&mut c, file, camera.eye);
    let (integration, nu, decay_length) = check_integration(&mut c, file);
    let colors = check_colors(&mut c, file);
    let sources = check_sources(&mut c, file);
    let int_path = FieldPath::default().key("integration");
    let center = billboard.center;
    // Without a decay length, the papers' nu at this file's own camera: the scene renders as they would here,
    // and keeps that look wherever the camera goes.
    let decay_length = decay_length.unwrap_or_else(|| {
        let d = geometry::papers_decay_length(&camera, &sources, center, nu);
        if !(d > 0.0 && d.is_finite()) && c.problems.is_empty() {
            c.fail(
                &int_path,
                format!("the decay length derived from the camera, (nu - 1) times the eye-to-billboard distance, is {d}: set decay_length"),
            );
        }
        d
    });

    let particles = particles_file::check_particles(&mut c, file, base, &sources);
    Scene {
        camera,
        billboard,
        integration: Integration {
            decay_length,
            ..integration
        },
        colors,
        glare: check_glare(&mut c, file),
        sources,
        objects: objects_file::check_objects(&mut c, file, base),
        particles,
        slice_width: particles_file::check_slices(&mut c, file),
        animation: None,
    }
}

/// `[glare]`: the fog glow's threshold, size and strength.
fn check_glare(c: &mut Checker<'_, '_>, file: &SceneFile) -> Option<Glare> {
    let g = file.glare.as_ref()?;
    let path = FieldPath::default().key("glare");
    let d = Glare::default();
    if let Some(kind) = g.kind.as_deref()
        && kind != "fog"
    {
        c.fail(
            &path.key("kind"),
            format!(
                "{kind:?} is not a kind of glare: \"fog\" (a Gaussian fog glow) is the one there is"
            ),
        );
    }
    let threshold = g.threshold.map_or(d.threshold, |x| {
        if c.finite(&path.key("threshold"), x) && x < 0.0 {
            c.fail(
                &path.key("threshold"),
                format!("{x}: the threshold is a brightness B, at least 0"),
            );
        }
        x
    });
    let size = g.size.map_or(d.size, |x| {
        if c.finite(&path.key("size"), x) && !(x > 0.0 && x <= MAX_GLARE_SIZE) {
            c.fail(
                &path.key("size"),
                format!("{x} is out of range: the size is the blur's standard deviation as a fraction of the billboard's side, in (0, {MAX_GLARE_SIZE}]"),
            );
        }
        x
    });
    let strength = g.strength.map_or(d.strength, |x| {
        if c.finite(&path.key("strength"), x) && !(0.0..=MAX_INTENSITY).contains(&x) {
            c.fail(
                &path.key("strength"),
                format!("{x} is out of range: the strength is in 0..={MAX_INTENSITY}"),
            );
        }
        x
    });
    Some(Glare {
        threshold,
        size,
        strength,
    })
}

/// `[camera]`: eye, target, up and the field of view, and how they relate.
fn check_camera(c: &mut Checker<'_, '_>, file: &SceneFile) -> Camera {
    let root = FieldPath::default();
    let defaults_camera = Camera::default();
    let cam_path = root.key("camera");
    let cam = file.camera.as_ref();
    let get = |f: fn(&file::CameraFile) -> Option<[f64; 3]>| cam.and_then(f);
    let problems_before = c.problems.len();
    let eye = get(|c| c.eye).map_or(defaults_camera.eye, |a| c.position(&cam_path.key("eye"), a));
    let target = get(|c| c.target).map_or(defaults_camera.target, |a| {
        c.position(&cam_path.key("target"), a)
    });
    let up = get(|c| c.up).map_or(defaults_camera.up, |a| c.vector(&cam_path.key("up"), a));
    let fov_y = cam
        .and_then(|c| c.fov_y)
        .map_or(defaults_camera.fov_y_degrees, |x| {
            c.in_open_range(
                &cam_path.key("fov_y"),
                x,
                0.0,
                180.0,
                "the vertical field of view is in degrees, between 0 and 180 (exclusive)",
            )
        });
    if c.problems.len() > problems_before {
        // An eye or target already refused: how they relate says nothing more.
    } else if (target - eye).length() <= 1e-9 * (1.0 + eye.length()) {
        c.fail(
            &cam_path.key("target"),
            "the target must differ from the eye (the camera looks from eye toward target)",
        );
    } else if up.length() <= 1e-12 {
        c.fail(&cam_path.key("up"), "must not be the zero vector");
    } else if up.normalize().cross((target - eye).normalize()).length() < 1e-9 {
        c.fail(
            &cam_path.key("up"),
            "must not be parallel to the view direction (target - eye)",
        );
    }
    Camera {
        eye,
        target,
        up,
        fov_y_degrees: fov_y,
    }
}

/// `[billboard]`: a fixed center and size (both or neither), and the resolution.
fn check_billboard(c: &mut Checker<'_, '_>, file: &SceneFile, eye: DVec3) -> BillboardSettings {
    let root = FieldPath::default();
    let bb_path = root.key("billboard");
    let bb = file.billboard.as_ref();
    let center = bb
        .and_then(|b| b.center)
        .map(|a| c.position(&bb_path.key("center"), a));
    let size = bb.and_then(|b| b.size).map(|x| {
        c.in_open_range(
            &bb_path.key("size"),
            x,
            0.0,
            f64::INFINITY,
            "the side length l must be positive",
        )
    });
    if let Some(center) = center {
        if size.is_none() {
            c.fail(
                &bb_path.key("center"),
                "a fixed center needs a size too (or remove center for automatic placement)",
            );
        }
        if (center - eye).length() <= 1e-9 * (1.0 + eye.length()) {
            c.fail(
                &bb_path.key("center"),
                "the billboard's center must not be at the eye",
            );
        }
    }
    let given = bb.and_then(|b| b.resolution);
    let resolution = given.unwrap_or(BillboardSettings::default().resolution);
    // A resolution given fixes W for exports too, unless the file says otherwise.
    let fixed = bb
        .and_then(|b| b.fixed_resolution)
        .unwrap_or(given.is_some());
    if let Err(rule) = limits::resolution(resolution) {
        c.fail(&bb_path.key("resolution"), format!("{resolution}: {rule}"));
    }
    BillboardSettings {
        center,
        size,
        resolution,
        fixed_resolution: fixed,
    }
}

/// `[integration]`: the integrator and its settings; also the papers' nu and the decay length if the file
/// gives it (without one, `validate` derives it from the camera once the sources are known). The returned
/// settings' decay length is that placeholder's to fill.
fn check_integration(c: &mut Checker<'_, '_>, file: &SceneFile) -> (Integration, f64, Option<f64>) {
    let root = FieldPath::default();
    let int_path = root.key("integration");
    let defaults = Integration::default();
    let int = file.integration.as_ref();
    let divisions = int.and_then(|i| i.divisions).unwrap_or(defaults.divisions);
    if let Err(rule) = limits::divisions(divisions) {
        c.fail(&int_path.key("divisions"), format!("{divisions}: {rule}"));
    }
    let integrator = match int.and_then(|i| i.integrator.as_deref()) {
        None => defaults.integrator,
        Some("adaptive") => Integrator::Adaptive,
        Some("simpson") => Integrator::Simpson,
        Some(other) => {
            c.fail(
                &int_path.key("integrator"),
                format!("{other:?} is not an integrator: use \"adaptive\" (samples where the field needs them, the default) or \"simpson\" (the papers' n evenly spaced samples)"),
            );
            defaults.integrator
        }
    };
    let tolerance = int
        .and_then(|i| i.tolerance)
        .map_or(defaults.tolerance, |x| {
            c.in_open_range(
                &int_path.key("tolerance"),
                x,
                limits::MIN_TOLERANCE,
                limits::MAX_TOLERANCE,
                limits::TOLERANCE_RULE,
            )
        });
    let jitter = int.and_then(|i| i.jitter).unwrap_or(false);
    let seed = int.and_then(|i| i.seed);
    if seed.is_some() && !jitter {
        c.fail(
            &int_path.key("seed"),
            "a seed only matters with jitter = true",
        );
    }
    if jitter && integrator == Integrator::Adaptive {
        c.fail(
            &int_path.key("jitter"),
            "jitter shifts the simpson integrator's evenly spaced samples: set integrator = \"simpson\" with it (the adaptive integrator does not band)",
        );
    }
    let jitter = jitter.then(|| seed.unwrap_or(0));
    let nu = int
        .and_then(|i| i.nu)
        .map_or(PAPERS_NU, |x| c.within(&int_path.key("nu"), x, limits::nu));
    let decay_length = int.and_then(|i| i.decay_length).map(|x| {
        if int.is_some_and(|i| i.nu.is_some()) {
            c.fail(
                &int_path.key("decay_length"),
                "give decay_length or nu, not both: nu only derives the decay length, (nu - 1) times the eye-to-billboard distance at this file's camera",
            );
        }
        c.within(&int_path.key("decay_length"), x, limits::decay_length)
    });
    let alpha = int.and_then(|i| i.alpha).map_or(defaults.alpha, |x| {
        c.in_open_range(
            &int_path.key("alpha"),
            x,
            0.0,
            f64::INFINITY,
            "alpha must be positive (the papers use 1)",
        )
    });
    let beta = int.and_then(|i| i.beta).map_or(defaults.beta, |x| {
        c.in_open_range(&int_path.key("beta"), x, 0.0, f64::INFINITY, "beta must be positive, or zeta = alpha / (s + beta)^2 is infinite at s = 0 (the papers use 1)")
    });
    let epsilon = int.and_then(|i| i.epsilon).map_or(defaults.epsilon, |x| {
        c.in_open_range(
            &int_path.key("epsilon"),
            x,
            0.0,
            f64::INFINITY,
            "epsilon must be positive (it bounds 1 / distance on the sources)",
        )
    });
    let decay = match int.and_then(|i| i.decay.as_deref()) {
        None => defaults.decay,
        Some(name) => Decay::ALL.into_iter().find(|d| d.name() == name).unwrap_or_else(|| {
            c.fail(
                &int_path.key("decay"),
                format!("{name:?} is not a decay: use \"distance\" (the papers': each source's energy along the view summed, the default) or \"rms\" (its root mean square: a single intense spot is not outshone by an even spread)"),
            );
            defaults.decay
        }),
    };
    let settings = Integration {
        integrator,
        divisions,
        tolerance,
        jitter,
        decay,
        decay_length: decay_length.unwrap_or(0.0),
        alpha,
        beta,
        epsilon,
        stretch: 1.0,
    };
    (settings, nu, decay_length)
}

/// `[colors]`: each channel in 0..1.
fn check_colors(c: &mut Checker<'_, '_>, file: &SceneFile) -> Colors {
    let root = FieldPath::default();
    let col_path = root.key("colors");
    let default_colors = Colors::default();
    let col = file.colors.as_ref();
    let energy = col
        .and_then(|x| x.energy)
        .map_or(default_colors.energy, |a| {
            c.color(&col_path.key("energy"), a)
        });
    let energy_intensity = col
        .and_then(|x| x.energy_intensity)
        .map_or(default_colors.energy_intensity, |x| {
            c.intensity(&col_path.key("energy_intensity"), x)
        });
    let background = col
        .and_then(|x| x.background)
        .map_or(default_colors.background, |a| {
            c.color(&col_path.key("background"), a)
        });
    let blend = match col.and_then(|x| x.blend.as_deref()) {
        None => default_colors.blend,
        Some("papers") => Blend::Papers,
        Some("over") => Blend::Over,
        Some(other) => {
            c.fail(
                &col_path.key("blend"),
                format!("{other:?} is not a blend: use \"over\" (clamp(B Ce + (1 - min(B, 1)) Cb), the default: what the transparent export composites to) or \"papers\" (clamp((1 - B) Cb + B Ce): the same wherever B <= 1, but where B > 1 it subtracts the background, turning bright backgrounds dark)"),
            );
            default_colors.blend
        }
    };
    let cutoff = col.and_then(|x| x.cutoff).map_or(default_colors.cutoff, |x| {
        let path = col_path.key("cutoff");
        if c.finite(&path, x) && !(0.0..=MAX_CUTOFF).contains(&x) {
            c.fail(
                &path,
                format!("{x} is out of range: the glow's edge is a brightness B in 0..={MAX_CUTOFF} (0: no edge, the papers' glow)"),
            );
        }
        x
    });
    Colors {
        energy,
        energy_intensity,
        background,
        blend,
        cutoff,
    }
}

/// The sources, each kind in its array of tables.
fn check_sources(c: &mut Checker<'_, '_>, file: &SceneFile) -> Sources {
    let root = FieldPath::default();
    let mut sources = Sources::default();
    for (i, p) in file.points.iter().enumerate() {
        let path = root.key("points").index(i);
        let position = c.position(&path.key("position"), p.position);
        c.finite(&path.key("coefficient"), p.coefficient);
        sources.points.push(Point {
            position,
            coefficient: p.coefficient,
            look: c.look(&path, p.color, p.intensity),
        });
    }
    for (i, l) in file.lines.iter().enumerate() {
        let path = root.key("lines").index(i);
        let point = c.position(&path.key("point"), l.point);
        let direction = c.direction(&path.key("direction"), l.direction);
        c.finite(&path.key("coefficient"), l.coefficient);
        sources.lines.push(Line {
            point,
            direction,
            coefficient: l.coefficient,
            look: c.look(&path, l.color, l.intensity),
        });
    }
    for (i, t) in file.tori.iter().enumerate() {
        let path = root.key("tori").index(i);
        let center = c.position(&path.key("center"), t.center);
        let axis = c.direction(&path.key("axis"), t.axis);
        c.in_open_range(
            &path.key("major_radius"),
            t.major_radius,
            0.0,
            f64::INFINITY,
            "the major radius R must be positive",
        );
        c.finite(&path.key("coefficient"), t.coefficient);
        sources.tori.push(Torus {
            center,
            axis,
            major_radius: t.major_radius,
            coefficient: t.coefficient,
            look: c.look(&path, t.color, t.intensity),
        });
    }
    for (i, curve) in file.curves.iter().enumerate() {
        let path = root.key("curves").index(i);
        let n = curve.control_points.len();
        if n < 3 || n % 2 == 0 {
            c.fail(
                &path.key("control_points"),
                format!("{n} control points: a curve needs 3 (one quadratic Bezier segment) or 2k+1 (a chain of k segments sharing end points)"),
            );
        }
        let control_points = (curve.control_points.iter().enumerate())
            .map(|(j, &p)| c.position(&path.key("control_points").index(j), p))
            .collect();
        c.finite(&path.key("coefficient"), curve.coefficient);
        let weights = match &curve.weights {
            None => Vec::new(),
            Some(w) if w.is_empty() => {
                c.fail(
                    &path.key("weights"),
                    "the W series is empty: give at least one weight, or remove the key for all 1",
                );
                Vec::new()
            }
            Some(w) => {
                for (j, &x) in w.iter().enumerate() {
                    c.within(&path.key("weights").index(j), x, limits::weight);
                }
                w.clone()
            }
        };
        let color_series = match &curve.color_series {
            None => Vec::new(),
            Some(series) if series.is_empty() => {
                c.fail(
                    &path.key("color_series"),
                    "the color series is empty: give at least one color, or remove the key for the curve's one color",
                );
                Vec::new()
            }
            Some(series) => {
                if curve.color.is_some() {
                    c.fail(
                        &path.key("color_series"),
                        "give color or color_series, not both: the series is the curve's color along it",
                    );
                }
                (series.iter().enumerate())
                    .map(|(j, &a)| c.color(&path.key("color_series").index(j), a))
                    .collect()
            }
        };
        let w_form = match curve.w_form.as_deref() {
            None => WForm::default(),
            Some(name) => WForm::ALL.into_iter().find(|f| f.name() == name).unwrap_or_else(|| {
                c.fail(
                    &path.key("w_form"),
                    format!("{name:?} is not a form of the W series: use \"continuous\" (the chain's brightest point seen from P, max Sw(t) / max(eps, |P - C(t)|): no seam, the default) or \"nearest\" (the papers' Sw(t*) at the nearest point t*)"),
                );
                WForm::default()
            }),
        };
        sources.curves.push(Curve {
            control_points,
            coefficient: curve.coefficient,
            weights,
            look: c.look(&path, curve.color, curve.intensity),
            color_series,
            w_form,
        });
    }
    sources
}

/// The scene file's tables, or every problem the deserializer finds: a syntax error or wrong type alone, but
/// every unknown key at once (each with the closest known one, where one is close), found by setting each
/// aside in turn and reading the file again.
pub(super) fn deserialize(text: &str, locator: &Locator) -> Result<SceneFile, Vec<Problem>> {
    let mut text = text.to_owned();
    let mut unknown = Vec::new();
    loop {
        let e = match toml::from_str::<SceneFile>(&text) {
            Ok(file) if unknown.is_empty() => return Ok(file),
            Ok(_) => return Err(unknown),
            Err(e) => e,
        };
        let (location, field) = match e.span() {
            Some(span) => (
                Some(locator.line_column(span.start)),
                locator.path_at(span.start),
            ),
            None => (None, String::new()),
        };
        let message = e.message().trim().to_owned();
        let key_line = e.span().and_then(|span| {
            let start = text[..span.start].rfind('\n').map_or(0, |k| k + 1);
            let end = text[span.start..]
                .find('\n')
                .map_or(text.len(), |k| span.start + k);
            let line = &text[start..end];
            // Set aside only a one-line `key = value` (a value over several lines would leave its rest).
            let balanced = line.matches('[').count() == line.matches(']').count();
            (line.contains('=') && balanced).then_some((start, end))
        });
        match (message.strip_prefix("unknown field `"), key_line) {
            (Some(rest), Some((start, end))) if unknown.len() < 64 => {
                unknown.push(Problem {
                    location,
                    field,
                    message: did_you_mean(rest).unwrap_or_else(|| message.clone()),
                });
                let blank = " ".repeat(end - start);
                text.replace_range(start..end, &blank);
            }
            // Another error after unknown keys may come of setting them aside (a misspelt required key is
            // missing): the unknown keys are what to fix first.
            _ if !unknown.is_empty() => return Err(unknown),
            _ => {
                return Err(vec![Problem {
                    location,
                    field,
                    message,
                }]);
            }
        }
    }
}

/// serde's "unknown field `x`, expected one of `a`, `b`" (after its "unknown field `") with the closest known
/// key named, where one is within a third of its length in edits.
fn did_you_mean(rest: &str) -> Option<String> {
    let (name, expected) = rest.split_once('`')?;
    let known: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    let (best, distance) = known
        .iter()
        .map(|k| (*k, edit_distance(name, k)))
        .min_by_key(|(_, d)| *d)?;
    let message = format!("unknown field `{name}`{}", expected.trim_end());
    Some(if distance <= name.len().max(best.len()).div_ceil(3) {
        format!("{message}; did you mean `{best}`?")
    } else {
        message
    })
}

/// The edits (insertions, deletions, substitutions and swaps of neighbours) between two keys: the optimal
/// string alignment distance.
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for j in 0..=b.len() {
        d[0][j] = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = (a[i - 1] != b[j - 1]) as usize;
            d[i][j] = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d[i][j] = d[i][j].min(d[i - 2][j - 2] + 1);
            }
        }
    }
    d[a.len()][b.len()]
}
