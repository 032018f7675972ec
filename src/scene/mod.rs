//! Scenes: the camera, the billboard, the integration settings, the colors and the sources, loaded from and
//! saved to TOML files (format in `docs/scene-format.md`).
//!
//! Loading validates every field before anything reaches a renderer; an invalid file is refused whole with
//! every problem found, each named by file, line, column and field.

mod animation_file;
mod checker;
mod error;
mod file;
pub mod format;
mod keyed;
mod life_file;
pub mod limits;
mod live;
mod objects_file;
mod particles_file;
mod translucent_file;
mod validate;

pub use life_file::MAX_RATE;
pub use live::Simulations;
pub use objects_file::DEFAULT_ALBEDO;
pub use particles_file::{DEFAULTS as PARTICLE_DEFAULTS, MIN_SLICE_WIDTH};

use std::path::{Path, PathBuf};

use glam::DVec3;

pub use error::{Problem, SceneError};
use file::{Locator, SceneFile};
use validate::{deserialize, validate};

use crate::animation::Animation;
use crate::field::{Curve, Look, Sources, WForm};
use crate::geometry::{self, Billboard, Camera};
use crate::integrate::{Decay, Integration};
use crate::objects::Object;
use crate::particles::ParticleSet;

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
    /// Smoke, dust and sparks around the glow, lit by it (`crate::particles`).
    pub particles: Vec<ParticleSet>,
    /// The particles' slices' width, in radii of the smallest particle (the paper's R/2: 0.5).
    pub slice_width: f64,
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
    /// The scene to be written into the folder `to` when it was read from (or, unsaved, is read against) the
    /// folder `from`: every mesh's and PLY file's relative path rewritten to name the same file from `to` (Save As
    /// into another folder), relative where the two folders share a root, else absolute. Absolute paths stay.
    pub fn rebased(&self, from: &Path, to: &Path) -> Scene {
        let mut scene = self.clone();
        let rebase = |written: &mut PathBuf| {
            if written.is_relative() {
                *written = rebase_path(written, from, to);
            }
        };
        for o in &mut scene.objects {
            if let crate::objects::Shape::Mesh(m) = &mut o.shape {
                rebase(&mut m.path);
            }
        }
        for set in &mut scene.particles {
            if let crate::particles::Origin::File { path, .. } = &mut set.origin {
                rebase(path);
            }
        }
        scene
    }

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
            particles: particles_file::write(&self.particles),
            slices: particles_file::write_slices(self.slice_width),
            animation: None,
        };
        animation_file::write(self, &mut file);
        toml::to_string_pretty(&file).expect("a scene always serialises to TOML")
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

    /// True when some source's color differs from the scene's (a `frame::Term::tint` is not zero), or varies
    /// along it.
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
            self.colors.cutoff > 0.0,
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

/// A shipped scene of `assets/scenes/`, for the crate's unit tests.
#[cfg(test)]
pub(crate) fn shipped(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name);
    Scene::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap()
}

/// `written`, a path relative to the folder `from`, as a path relative to the folder `to` naming the same file
/// (lexically: `.` and `..` resolved without the file system, so that a file not yet there is named alike); absolute
/// where the two share no root (another drive).
pub fn rebase_path(written: &Path, from: &Path, to: &Path) -> PathBuf {
    use std::path::Component;
    fn absolute(p: &Path) -> Vec<Component<'_>> {
        let mut out: Vec<Component<'_>> = Vec::new();
        for c in p.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    if matches!(out.last(), Some(Component::Normal(_))) {
                        out.pop();
                    }
                }
                c => out.push(c),
            }
        }
        out
    }
    let here = std::env::current_dir().unwrap_or_default();
    let full_path = here.join(from).join(written);
    let to_path = here.join(to);
    let (full, to) = (absolute(&full_path), absolute(&to_path));
    let shared = full.iter().zip(&to).take_while(|(a, b)| a == b).count();
    // Both are absolute (joined onto the working folder), so a shared first component is a shared root.
    if shared == 0 {
        return full.iter().collect();
    }
    let mut out = PathBuf::new();
    for _ in shared..to.len() {
        out.push("..");
    }
    for c in &full[shared..] {
        out.push(c);
    }
    out
}

#[cfg(test)]
mod rebase_tests {
    use super::*;

    #[test]
    fn a_relative_path_names_the_same_file_from_the_new_folder() {
        let p = |s: &str| PathBuf::from(s);
        assert_eq!(
            rebase_path(&p("mesh.glb"), &p("/a/b"), &p("/a/b")),
            p("mesh.glb")
        );
        assert_eq!(
            rebase_path(&p("mesh.glb"), &p("/a/b"), &p("/a/c")),
            p("../b/mesh.glb")
        );
        assert_eq!(
            rebase_path(&p("../m/mesh.glb"), &p("/a/b"), &p("/a/b/c/d")),
            p("../../../m/mesh.glb")
        );
        assert_eq!(
            rebase_path(&p("./x/../mesh.glb"), &p("/a/b"), &p("/")),
            p("a/b/mesh.glb")
        );
        assert_eq!(
            rebase_path(&p("mesh.glb"), &p("/a/b"), &p("/a/b/./new/..")),
            p("mesh.glb")
        );
    }
}
