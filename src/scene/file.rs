//! The TOML scene format: its serde mirror, the validation of every field, and where in the text a field is.
//!
//! Field names are a contract with users' files (documented in `docs/scene-format.md`): keep them; new
//! fields must be optional.

use std::ops::Range;

use serde::{Deserialize, Serialize};
use toml::de::{DeTable, DeValue};

use super::error::Problem;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub billboard: Option<BillboardFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration: Option<IntegrationFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colors: Option<ColorsFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glare: Option<GlareFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<PointFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lines: Vec<LineFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tori: Vec<TorusFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<CurveFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectFile>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<ParticlesFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slices: Option<SlicesFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<AnimationFile>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraFile {
    pub eye: Option<[f64; 3]>,
    pub target: Option<[f64; 3]>,
    pub up: Option<[f64; 3]>,
    pub fov_y: Option<f64>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BillboardFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<f64>,
    pub resolution: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_resolution: Option<bool>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct IntegrationFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integrator: Option<String>,
    pub divisions: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jitter: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay_length: Option<f64>,
    pub alpha: Option<f64>,
    pub beta: Option<f64>,
    pub epsilon: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decay: Option<String>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ColorsFile {
    pub energy: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_intensity: Option<f64>,
    pub background: Option<[f64; 3]>,
    pub blend: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff: Option<f64>,
}

/// `[glare]`: the fog glow (`scene::Glare`).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct GlareFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PointFile {
    pub position: [f64; 3],
    pub coefficient: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LineFile {
    pub point: [f64; 3],
    pub direction: [f64; 3],
    pub coefficient: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TorusFile {
    #[serde(default)]
    pub center: [f64; 3],
    #[serde(default = "default_axis")]
    pub axis: [f64; 3],
    pub major_radius: f64,
    pub coefficient: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f64>,
}

fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CurveFile {
    pub control_points: Vec<[f64; 3]>,
    pub coefficient: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pulse: Option<PulseFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color_series: Option<Vec<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w_form: Option<String>,
}

/// `[[objects]]`: a sphere, box, plane or glTF mesh; which keys it takes depends on its shape (checked in
/// `scene::check_objects`).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObjectFile {
    pub shape: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translation: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translucent: Option<TranslucentFile>,
}

/// `[objects.translucent]`: a translucent material (checked in `scene::translucent_file`).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TranslucentFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extinction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inner: Option<InnerFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseFile>,
}

/// `[objects.translucent.inner]`: a region of another extinction.
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct InnerFile {
    pub shape: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extinction: Option<f64>,
}

/// `[objects.translucent.noise]`: a noise that varies the extinction.
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct NoiseFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amount: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// `[[particles]]`: a particle set, from a PLY file or an emitter; which keys it takes depends on which
/// (checked in `scene::particles_file`).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ParticlesFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emitter: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torus: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spread: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particle_radius: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission_intensity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub life: Option<LifeFile>,
}

/// `[particles.life]`: what makes an emitter live (checked in `scene::life_file`).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LifeFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bursts: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lifetime: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<ValueFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<DirectionFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cone: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inherit_velocity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub along_pulse: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opacity: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colors: Option<Vec<[f64; 4]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission_colors: Option<Vec<[f64; 4]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turbulence: Option<TurbulenceFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shutter: Option<f64>,
}

/// `[particles.life.turbulence]`: curl noise.
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TurbulenceFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
}

/// A live emitter's direction: a name or a vector.
#[derive(Debug, Deserialize, Serialize)]
#[serde(untagged)]
pub(crate) enum DirectionFile {
    Name(String),
    Vector([f64; 3]),
}

/// `[slices]`: how particle sets are sliced.
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SlicesFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
}

/// `[animation]`: the timeline and the keyed parameters.
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AnimationFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_rate: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<i64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tracks: Vec<TrackFile>,
}

/// `[[animation.tracks]]`: one keyed parameter.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TrackFile {
    pub parameter: String,
    pub keys: Vec<KeyFile>,
}

/// One key of a track: `{ frame = 10, value = [0.0, 1.0, 0.0] }`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct KeyFile {
    pub frame: f64,
    pub value: ValueFile,
}

/// A key's value: a number or an array of numbers.
#[derive(Debug, Deserialize, Serialize)]
#[serde(untagged)]
pub(crate) enum ValueFile {
    Number(f64),
    Vector(Vec<f64>),
}

/// `[curves.pulse]`: the curve's W series is the travelling pulse (thesis eq. 5.1).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PulseFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
}

/// One step of a field path: a table key or an array index.
#[derive(Clone, Debug)]
pub(crate) enum Step {
    Key(&'static str),
    Index(usize),
}

/// A field path such as `curves[1].control_points`, with the means to find it in the text.
#[derive(Clone, Debug, Default)]
pub(crate) struct FieldPath(pub Vec<Step>);

impl FieldPath {
    pub fn key(&self, k: &'static str) -> FieldPath {
        let mut v = self.0.clone();
        v.push(Step::Key(k));
        FieldPath(v)
    }

    pub fn index(&self, i: usize) -> FieldPath {
        let mut v = self.0.clone();
        v.push(Step::Index(i));
        FieldPath(v)
    }

    pub fn render(&self) -> String {
        let mut s = String::new();
        for step in &self.0 {
            match step {
                Step::Key(k) => {
                    if !s.is_empty() {
                        s.push('.');
                    }
                    s.push_str(k);
                }
                Step::Index(i) => s.push_str(&format!("[{i}]")),
            }
        }
        s
    }

    /// The byte range of this field's value (or of its deepest existing ancestor) in the document.
    fn span(&self, doc: &toml::Spanned<DeTable<'_>>) -> Option<Range<usize>> {
        let mut current: Option<(&DeValue<'_>, Range<usize>)> = None;
        let mut table: Option<&DeTable<'_>> = Some(doc.get_ref());
        let mut best = None;
        for step in &self.0 {
            let next = match (step, table, current.as_ref()) {
                (Step::Key(k), Some(t), _) => t.get(*k),
                (Step::Index(i), _, Some((v, _))) => v.get(*i),
                _ => None,
            };
            let Some(next) = next else { break };
            best = Some(next.span());
            table = next.get_ref().as_table();
            current = Some((next.get_ref(), next.span()));
        }
        best
    }
}

/// Turns byte offsets into 1-based line and column numbers, and field paths into locations.
pub(crate) struct Locator<'a> {
    text: &'a str,
    doc: Option<toml::Spanned<DeTable<'a>>>,
}

impl<'a> Locator<'a> {
    pub fn new(text: &'a str) -> Self {
        Self {
            text,
            doc: DeTable::parse(text).ok(),
        }
    }

    pub fn line_column(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        (line, column)
    }

    /// A problem at `path`, located in the text where the field (or its nearest ancestor) is.
    pub fn problem(&self, path: &FieldPath, message: impl Into<String>) -> Problem {
        let location = self
            .doc
            .as_ref()
            .and_then(|d| path.span(d))
            .map(|r| self.line_column(r.start));
        Problem {
            location,
            field: path.render(),
            message: message.into(),
        }
    }

    /// The field path an error at byte `offset` belongs to (serde's errors only give a span): the last key,
    /// table-array element or nested array that starts at or before the offset, or an empty string.
    pub fn path_at(&self, offset: usize) -> String {
        fn collect(value: &DeValue<'_>, path: &str, out: &mut Vec<(usize, String)>) {
            match value {
                DeValue::Table(t) => {
                    for (k, v) in t.iter() {
                        let p = if path.is_empty() {
                            k.get_ref().to_string()
                        } else {
                            format!("{path}.{}", k.get_ref())
                        };
                        out.push((k.span().start, p.clone()));
                        collect(v.get_ref(), &p, out);
                    }
                }
                DeValue::Array(a) => {
                    for (i, v) in a.iter().enumerate() {
                        // Elements that are numbers are named by their array's field.
                        if v.get_ref().is_table() || v.get_ref().is_array() {
                            let p = format!("{path}[{i}]");
                            out.push((v.span().start, p.clone()));
                            collect(v.get_ref(), &p, out);
                        }
                    }
                }
                _ => {}
            }
        }
        let Some(doc) = &self.doc else {
            return String::new();
        };
        let mut entries = Vec::new();
        for (k, v) in doc.get_ref().iter() {
            entries.push((k.span().start, k.get_ref().to_string()));
            collect(v.get_ref(), k.get_ref(), &mut entries);
        }
        entries
            .into_iter()
            .filter(|(start, _)| *start <= offset)
            .max_by_key(|(start, _)| *start)
            .map(|(_, p)| p)
            .unwrap_or_default()
    }
}
