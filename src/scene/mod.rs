//! Scenes: the camera, the billboard, the integration settings, the colors and the sources, loaded from and
//! saved to TOML files (format in `docs/scene-format.md`).
//!
//! Loading validates every field before anything reaches a renderer; an invalid file is refused whole with
//! every problem found, each named by file, line, column and field.

mod animation_file;
mod error;
mod file;
pub mod format;
mod keyed;
pub mod limits;
mod objects_file;

pub use objects_file::DEFAULT_ALBEDO;

use std::path::{Path, PathBuf};

use glam::DVec3;

pub use error::{Problem, SceneError};
use file::{FieldPath, Locator, SceneFile};

use crate::animation::Animation;
use crate::field::{Curve, Line, Look, Point, Sources, Torus, WForm};
use crate::geometry::{self, Billboard, Camera};
use crate::integrate::{Decay, Integration, Integrator};
use crate::objects::Object;

/// The scene used when none is given, embedded in the binary.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../assets/scenes/default.toml");
/// The name under which the embedded default scene reports errors.
pub const DEFAULT_SCENE_NAME: &str = "<embedded default scene>";

pub use limits::{MAX_DIVISIONS, MAX_RESOLUTION};
/// The largest world coordinate of any point of a scene (`camera.eye`, a source's position, ...): squared
/// distances between such points stay well inside f32 (about 3.4e38).
pub const MAX_COORDINATE: f64 = 1e15;

/// The papers' nu (`E = V + nu (S - V)`), from which a file without a decay length derives one.
pub const PAPERS_NU: f64 = 2.0;

/// The largest intensity multiplier of a color (`colors.energy_intensity`, a source's `intensity`).
pub const MAX_INTENSITY: f64 = 1000.0;

/// Where the billboard goes; `None` fields are placed automatically (`geometry::place_billboard`).
#[derive(Clone, Debug, PartialEq)]
pub struct BillboardSettings {
    pub center: Option<DVec3>,
    pub size: Option<f64>,
    /// W: texels per side of the brightness texture, in the viewer (a screenshot at 2x doubles it) and in every
    /// export where the scene fixes it.
    pub resolution: u32,
    /// Whether the scene fixes W for exports too (`[billboard] resolution` in the file). Otherwise an export
    /// follows its pixel density (`Scene::resolution_for`): a 1920 x 1080 frame gets the texels its size needs.
    pub fixed_resolution: bool,
}

/// The most texels per side an export's billboard takes by itself (`Scene::resolution_for`); a scene or
/// `--resolution` may fix more.
pub const MAX_AUTO_RESOLUTION: u32 = 4096;

/// The energy color Ce and the background color Cb, display values in [0, 1], and how the glow goes over the
/// background.
#[derive(Clone, Debug, PartialEq)]
pub struct Colors {
    pub energy: [f64; 3],
    /// The energy color's intensity multiplier, at least 0 (HDR above 1): `Ce = energy_intensity energy`.
    pub energy_intensity: f64,
    pub background: [f64; 3],
    pub blend: Blend,
    /// The glow's edge: B at or below it is transparent, and the glow fades in smoothly up to twice it, so a
    /// transparent export reaches alpha 0 (the 1/d falloff never does); 0 keeps the papers' unbounded glow.
    /// At least 0 and at most `MAX_CUTOFF`.
    pub cutoff: f64,
}

/// The glow's edge of a file without `cutoff`, and of a new scene.
pub const DEFAULT_CUTOFF: f64 = 0.2;

/// The largest cutoff: B at 1 blows out, so a cutoff at 1 leaves only the fade into the core.
pub const MAX_CUTOFF: f64 = 1.0;

/// The factor a glow of brightness `b` keeps with the edge at `cutoff`: 0 where |b| is at or below `cutoff`, 1
/// from twice it, a smoothstep between, so that `b` times it rises from 0 with slope 0 and joins `b` with slope
/// 1 (no ring at either end); by |b|, so a negative glow (negative coefficients) keeps its sign and has its edge
/// too. 1 everywhere for a cutoff of 0. The one formula of both renderers (shaders/billboard.wgsl).
pub fn edge_fade(b: f64, cutoff: f64) -> f64 {
    if cutoff <= 0.0 {
        return 1.0;
    }
    let x = ((b.abs() - cutoff) / cutoff).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

impl Colors {
    /// The scene's energy color Ce as the blend uses it: the color times its intensity.
    pub fn energy_color(&self) -> [f64; 3] {
        self.energy.map(|c| c * self.energy_intensity)
    }

    /// The scene's energy color and intensity, which the sources' colors are made from.
    pub fn palette(&self) -> crate::field::Palette {
        crate::field::Palette {
            energy: self.energy,
            energy_intensity: self.energy_intensity,
        }
    }

    /// A source's energy color Ce_i (`Palette::color_of`).
    pub fn color_of(&self, look: &Look) -> [f64; 3] {
        self.palette().color_of(look)
    }

    /// The intensity a source's color is multiplied by (`Palette::intensity_of`).
    pub fn intensity_of(&self, look: &Look) -> f64 {
        self.palette().intensity_of(look)
    }

    /// A curve's energy color at chain parameter `t` (`Palette::color_along`).
    pub fn color_along(&self, curve: &Curve, t: f64) -> [f64; 3] {
        self.palette().color_along(curve, t)
    }
}

/// How the glow's brightness B puts Ce over Cb.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Blend {
    /// The papers' `clamp((1 - B) Cb + B Ce)`: where B > 1, `(1 - B) Cb` is negative and subtracts the
    /// background (a light-blue core turns magenta over green, a lit floor under a ring turns black). The papers'
    /// presets name it; over the near-black backgrounds of their figures it is the same as `Over`.
    Papers,
    /// `clamp(B Ce + (1 - min(B, 1)) Cb)` (B below 0 taken as 0): the papers' blend wherever 0 <= B <= 1,
    /// white-hot cores over any background, and exactly what the transparent export composites to, for every B.
    /// The default: a file without `blend`, a new scene.
    #[default]
    Over,
}

impl Blend {
    /// The name in scene files and the panel.
    pub fn name(self) -> &'static str {
        match self {
            Blend::Papers => "papers",
            Blend::Over => "over",
        }
    }
}

/// Glare, an optional post pass (`[glare]`, off without it): a fog glow, the parts of the glow brighter than
/// `threshold` blurred by a Gaussian and added back `strength` times, in the billboard's plane. It adds to B and
/// to the colored sum alike, each texel's excess in its own color, so every blend and the transparent export
/// take it as more glow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glare {
    /// B above which the glow glares, at least 0 (1: only what blows out).
    pub threshold: f64,
    /// The Gaussian's standard deviation as a fraction of the billboard's side, in (0, MAX_GLARE_SIZE].
    pub size: f64,
    /// How much of the blurred excess is added, at least 0.
    pub strength: f64,
}

impl Default for Glare {
    fn default() -> Self {
        // A bloom that shows on every preset, a faint ring's (B near 0.8) as a blinding beam's (the excess is
        // compressed, `reference::glare`); looked at on each shipped preset.
        Self {
            threshold: 0.5,
            size: 0.04,
            strength: 1.0,
        }
    }
}

/// The largest glare size: a tenth of the billboard's side.
pub const MAX_GLARE_SIZE: f64 = 0.1;

/// The most texels the glare's blur reaches to either side (3 standard deviations, at most).
pub const MAX_GLARE_RADIUS: u32 = 128;

impl Glare {
    /// The blur's weights for offsets `-r..=r` (r = ceil(3 sigma), at most `MAX_GLARE_RADIUS`), sigma = size W
    /// texels on a billboard of W, normalised to sum to 1: the one kernel of the GPU pass and its twin.
    pub fn kernel(&self, w: u32) -> Vec<f64> {
        let sigma = (self.size * w as f64).max(1e-6);
        let r = ((3.0 * sigma).ceil() as u32).min(MAX_GLARE_RADIUS) as i64;
        let raw: Vec<f64> = (-r..=r)
            .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp())
            .collect();
        let total: f64 = raw.iter().sum();
        raw.into_iter().map(|x| x / total).collect()
    }
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub camera: Camera,
    pub billboard: BillboardSettings,
    pub integration: Integration,
    pub colors: Colors,
    /// The fog glow over the glow, or none (the papers' look).
    pub glare: Option<Glare>,
    pub sources: Sources,
    /// What stands around the effect: it hides the glow behind it and is lit by it (`crate::objects`).
    pub objects: Vec<Object>,
    /// Time: `None` for a still scene (see `crate::animation`).
    pub animation: Option<Animation>,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: DVec3::new(0.0, 0.0, 8.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 40.0,
        }
    }
}

impl Default for BillboardSettings {
    fn default() -> Self {
        Self {
            center: None,
            size: None,
            resolution: 256,
            fixed_resolution: false,
        }
    }
}

impl Default for Colors {
    fn default() -> Self {
        Self {
            energy: [0.35, 0.65, 1.0],
            energy_intensity: 1.0,
            background: [0.0, 0.0, 0.0],
            blend: Blend::Over,
            cutoff: DEFAULT_CUTOFF,
        }
    }
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let meta = std::fs::metadata(path).map_err(|source| SceneError::Read {
            path: path.to_owned(),
            source,
        })?;
        if meta.is_dir() {
            return Err(SceneError::Directory {
                path: path.to_owned(),
            });
        }
        let bytes = std::fs::read(path).map_err(|source| SceneError::Read {
            path: path.to_owned(),
            source,
        })?;
        Scene::parse_bytes(&bytes, path)
    }

    /// Parses and validates the bytes of a scene file (UTF-8 TOML); `path` only names the origin in errors.
    pub fn parse_bytes(bytes: &[u8], path: &Path) -> Result<Scene, SceneError> {
        let text = std::str::from_utf8(bytes).map_err(|e| SceneError::NotText {
            path: path.to_owned(),
            offset: e.valid_up_to(),
        })?;
        Scene::parse(text, path)
    }

    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        Scene::parse(DEFAULT_SCENE_TOML, Path::new(DEFAULT_SCENE_NAME))
            .expect("the embedded default scene is valid (held by a test)")
    }

    /// Parses and validates scene text; `path` only names the origin in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        if text.contains('\0') {
            return Err(SceneError::NotText {
                path: path.to_owned(),
                offset: text.find('\0').unwrap_or(0),
            });
        }
        let meaningful = text
            .lines()
            .map(str::trim)
            .any(|l| !l.is_empty() && !l.starts_with('#'));
        if !meaningful {
            return Err(SceneError::Empty {
                path: path.to_owned(),
            });
        }
        let locator = Locator::new(text);
        let file = deserialize(text, &locator).map_err(|problems| SceneError::Invalid {
            path: path.to_owned(),
            problems,
        })?;
        let mut problems = Vec::new();
        let base = path.parent().unwrap_or(Path::new(""));
        let mut scene = validate(&file, &locator, base, &mut problems);
        scene.animation = animation_file::validate(&file, &scene, &locator, &mut problems);
        if problems.is_empty() {
            Ok(scene)
        } else {
            Err(SceneError::Invalid {
                path: PathBuf::from(path),
                problems,
            })
        }
    }

    /// The scene as TOML text, every setting written out; `Scene::parse` of it gives this scene back.
    pub fn to_toml(&self) -> String {
        let v = |p: DVec3| p.to_array();
        let mut file = SceneFile {
            camera: Some(file::CameraFile {
                eye: Some(v(self.camera.eye)),
                target: Some(v(self.camera.target)),
                up: Some(v(self.camera.up)),
                fov_y: Some(self.camera.fov_y_degrees),
            }),
            billboard: Some(file::BillboardFile {
                center: self.billboard.center.map(v),
                size: self.billboard.size,
                resolution: Some(self.billboard.resolution),
                fixed_resolution: Some(self.billboard.fixed_resolution),
            }),
            integration: Some(file::IntegrationFile {
                integrator: Some(self.integration.integrator.name().to_owned()),
                divisions: Some(self.integration.divisions),
                tolerance: Some(self.integration.tolerance),
                jitter: Some(self.integration.jitter.is_some()),
                seed: self.integration.jitter,
                nu: None,
                decay_length: Some(self.integration.decay_length),
                alpha: Some(self.integration.alpha),
                beta: Some(self.integration.beta),
                epsilon: Some(self.integration.epsilon),
                decay: (self.integration.decay != Decay::default())
                    .then(|| self.integration.decay.name().to_owned()),
            }),
            colors: Some(file::ColorsFile {
                energy: Some(self.colors.energy),
                energy_intensity: (self.colors.energy_intensity != 1.0)
                    .then_some(self.colors.energy_intensity),
                background: Some(self.colors.background),
                blend: Some(self.colors.blend.name().to_owned()),
                cutoff: Some(self.colors.cutoff),
            }),
            glare: self.glare.map(|g| file::GlareFile {
                kind: Some("fog".to_owned()),
                threshold: Some(g.threshold),
                size: Some(g.size),
                strength: Some(g.strength),
            }),
            points: (self.sources.points.iter())
                .map(|s| file::PointFile {
                    position: v(s.position),
                    coefficient: s.coefficient,
                    color: s.look.color,
                    intensity: s.look.intensity,
                })
                .collect(),
            lines: (self.sources.lines.iter())
                .map(|s| file::LineFile {
                    point: v(s.point),
                    direction: v(s.direction),
                    coefficient: s.coefficient,
                    color: s.look.color,
                    intensity: s.look.intensity,
                })
                .collect(),
            tori: (self.sources.tori.iter())
                .map(|s| file::TorusFile {
                    center: v(s.center),
                    axis: v(s.axis),
                    major_radius: s.major_radius,
                    coefficient: s.coefficient,
                    color: s.look.color,
                    intensity: s.look.intensity,
                })
                .collect(),
            curves: (self.sources.curves.iter())
                .map(|s| file::CurveFile {
                    control_points: s.control_points.iter().map(|&p| v(p)).collect(),
                    coefficient: s.coefficient,
                    weights: (!s.weights.is_empty()).then(|| s.weights.clone()),
                    pulse: None,
                    color: s.look.color,
                    intensity: s.look.intensity,
                    color_series: (!s.color_series.is_empty()).then(|| s.color_series.clone()),
                    w_form: (s.w_form != WForm::default()).then(|| s.w_form.name().to_owned()),
                })
                .collect(),
            objects: objects_file::write(&self.objects),
            animation: None,
        };
        animation_file::write(self, &mut file);
        toml::to_string_pretty(&file).expect("a scene always serialises to TOML")
    }

    /// Each source's color less the scene's, `Ce_i - Ce`, in the order of the field pass's terms (points, lines,
    /// tori, curves): what the field pass integrates beside B, `sum B_i (Ce_i - Ce)`, so that the colored sum is
    /// `B Ce + sum B_i (Ce_i - Ce) = sum B_i Ce_i`. Zero for every source in the scene's color, where the blend is
    /// the papers' own to the bit. A curve with a color series has `-Ce`: its color varies along it, and the
    /// field pass adds the integral of B_i's integrand times the series (`Colors::color_along`) itself.
    pub fn tints(&self) -> Vec<[f64; 3]> {
        let base = self.colors.energy_color();
        let series = |k: usize| self.series_curve(k).is_some();
        (self.sources.looks().enumerate())
            .map(|(k, look)| {
                let c = if series(k) {
                    [0.0; 3]
                } else {
                    self.colors.color_of(look)
                };
                std::array::from_fn(|j| c[j] - base[j])
            })
            .collect()
    }

    /// Term `k` (points, lines, tori, curves) when it is a curve with a color series.
    pub fn series_curve(&self, k: usize) -> Option<&Curve> {
        let s = &self.sources;
        let c = s.curves.get(k.checked_sub(s.first_curve())?)?;
        (!c.color_series.is_empty()).then_some(c)
    }

    /// What lights the scene's objects (`objects::lit`).
    pub fn lit_inputs(&self) -> crate::objects::LitInputs<'_> {
        crate::objects::LitInputs {
            objects: &self.objects,
            sources: &self.sources,
            palette: self.colors.palette(),
            epsilon: self.integration.epsilon,
        }
    }

    /// True when some source's color differs from the scene's (`tints` is not all zero), or varies along it.
    pub fn tinted(&self) -> bool {
        let base = self.colors.energy_color();
        (self.sources.looks()).any(|look| self.colors.color_of(look) != base)
            || self
                .sources
                .curves
                .iter()
                .any(|c| !c.color_series.is_empty())
    }

    /// The billboard for a frame of `aspect` (width / height): the scene's own, or placed automatically.
    pub fn place_billboard(&self, aspect: f64) -> Billboard {
        geometry::place_billboard(
            &self.camera,
            &self.sources,
            self.billboard.center,
            self.billboard.size,
            aspect,
        )
    }

    /// The billboard resolution W for an export of `width` x `height` pixels: the scene's own where it fixes
    /// one; otherwise one texel per two pixels of the billboard's side in that frame, rounded up to a multiple of 8,
    /// never below the scene's W (the viewer's) and at most `limit` (the device's) and `MAX_AUTO_RESOLUTION`,
    /// which win over the scene's W.
    /// So a thin core stays smooth at any size, as a 2x screenshot doubles the viewer's W.
    pub fn resolution_for(&self, (width, height): (u32, u32), limit: u32) -> u32 {
        let own = self.billboard.resolution;
        if self.billboard.fixed_resolution {
            return own;
        }
        let bb = self.place_billboard(width.max(1) as f64 / height.max(1) as f64);
        let forward = (self.camera.target - self.camera.eye).normalize_or_zero();
        let depth = (bb.center - self.camera.eye).dot(forward);
        let top = limit.clamp(1, MAX_AUTO_RESOLUTION);
        let own = own.min(top);
        // The frame's height spans 2 depth tan(fov / 2) at the billboard's depth.
        let per_pixel = 2.0 * depth * self.camera.tan_half_fov() / height.max(1) as f64;
        if !(per_pixel > 0.0) {
            return top;
        }
        // Two pixels a texel: bilinear upsampling keeps a thin core smooth there (at 7.5 it beads), and a
        // texel a pixel costs four times the field for no visible gain (measured on the default scene at
        // 1920 x 1080: largest difference to one texel a pixel 10/255 at 2.5 pixels a texel, 36/255 at 7.5).
        let texels = (bb.size / per_pixel / 2.0).ceil();
        if !texels.is_finite() || texels >= top as f64 {
            return top;
        }
        (texels as u32)
            .div_ceil(8)
            .saturating_mul(8)
            .clamp(own, top)
    }
}

/// Collects problems while converting the file into a scene.
struct Checker<'a, 'b> {
    locator: &'a Locator<'b>,
    problems: &'a mut Vec<Problem>,
}

impl Checker<'_, '_> {
    fn fail(&mut self, path: &FieldPath, message: impl Into<String>) {
        self.problems.push(self.locator.problem(path, message));
    }

    fn finite(&mut self, path: &FieldPath, x: f64) -> bool {
        if x.is_finite() {
            true
        } else {
            self.fail(path, format!("{x} is not a finite number"));
            false
        }
    }

    fn vector(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        if a.iter().all(|x| x.is_finite()) {
            DVec3::from_array(a)
        } else {
            self.fail(
                path,
                format!("{a:?} has a component that is not a finite number"),
            );
            DVec3::ZERO
        }
    }

    /// A point in world space: finite, and within `MAX_COORDINATE` of the origin in every coordinate, beyond which
    /// the distances between points overflow (the GPU squares them in 32-bit floats).
    fn position(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        let v = self.vector(path, a);
        if a.iter().any(|x| x.abs() > MAX_COORDINATE) && v.is_finite() {
            self.fail(
                path,
                format!(
                    "{a:?} is too far out: coordinates are limited to +-{MAX_COORDINATE:e} world units, beyond which distances overflow"
                ),
            );
            return DVec3::ZERO;
        }
        v
    }

    /// A non-zero vector, normalised.
    fn direction(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        let d = self.vector(path, a);
        let len = d.length();
        if d.is_finite() && len > 1e-12 && (d / len).is_finite() {
            // A vector that is already unit up to rounding is kept bit for bit, so that saving and loading
            // again is lossless.
            if (len - 1.0).abs() <= 1e-14 {
                d
            } else {
                d / len
            }
        } else {
            if d.is_finite() {
                self.fail(path, "must not be the zero vector (it gives the direction; its length does not matter)");
            }
            DVec3::Z
        }
    }

    /// A finite number strictly inside `(lo, hi)` (or above `lo` when `hi` is infinite).
    fn in_open_range(&mut self, path: &FieldPath, x: f64, lo: f64, hi: f64, what: &str) -> f64 {
        if self.finite(path, x) && !(x > lo && x < hi) {
            self.fail(path, format!("{x} is out of range: {what}"));
        }
        x
    }

    /// A color's intensity multiplier: finite, in 0..=MAX_INTENSITY.
    fn intensity(&mut self, path: &FieldPath, x: f64) -> f64 {
        if self.finite(path, x) && !(0.0..=MAX_INTENSITY).contains(&x) {
            self.fail(
                path,
                format!("{x} is out of range: an intensity multiplies its color and is in 0..={MAX_INTENSITY} (1 leaves the color as it is, above 1 is HDR)"),
            );
        }
        x
    }

    /// A source's own color and intensity (`color`, `intensity` at `path`), each optional.
    fn look(&mut self, path: &FieldPath, color: Option<[f64; 3]>, intensity: Option<f64>) -> Look {
        Look {
            color: color.map(|a| self.color(&path.key("color"), a)),
            intensity: intensity.map(|x| self.intensity(&path.key("intensity"), x)),
        }
    }

    fn color(&mut self, path: &FieldPath, a: [f64; 3]) -> [f64; 3] {
        if a.iter().any(|c| !(0.0..=1.0).contains(c)) {
            self.fail(path, format!("{a:?}: each channel must be in 0..1"));
        }
        a
    }
}

fn validate(
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
    let nu = int.and_then(|i| i.nu).map_or(PAPERS_NU, |x| {
        c.in_open_range(&int_path.key("nu"), x, 1.0, f64::INFINITY, "nu must be greater than 1 (E = V + nu (S - V) lies behind the billboard; the papers use 2)")
    });
    let decay_length = int.and_then(|i| i.decay_length).map(|x| {
        if int.is_some_and(|i| i.nu.is_some()) {
            c.fail(
                &int_path.key("decay_length"),
                "give decay_length or nu, not both: nu only derives the decay length, (nu - 1) times the eye-to-billboard distance at this file's camera",
            );
        }
        c.in_open_range(
            &int_path.key("decay_length"),
            x,
            0.0,
            MAX_COORDINATE,
            "the decay length is a distance in scene units and must be positive (files without it get (nu - 1) times the eye-to-billboard distance)",
        )
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
                    if !x.is_finite() || x < 0.0 {
                        c.fail(
                            &path.key("weights").index(j),
                            format!("{x}: weights must be finite and at least 0"),
                        );
                    }
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
fn deserialize(text: &str, locator: &Locator) -> Result<SceneFile, Vec<Problem>> {
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
