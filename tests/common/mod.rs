//! What several test files share: the shipped scenes, and the viewer under egui_kittest (`viewer`).
// Each test file compiles this module on its own and uses part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use energywave::scene::Scene;

pub mod engine;
pub mod viewer;

/// A small deterministic generator (the tests need no crate for it).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    pub fn vec(&mut self, scale: f64) -> glam::DVec3 {
        glam::DVec3::new(
            self.range(-scale, scale),
            self.range(-scale, scale),
            self.range(-scale, scale),
        )
    }
}

/// Where `f` is least on `[lo, hi]`, by `steps` steps of golden-section search (for an `f` with one minimum
/// there: the middle of the last bracket, about 0.618^steps of the width from it).
pub fn golden_section_min(f: impl Fn(f64) -> f64, (lo, hi): (f64, f64), steps: u32) -> f64 {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (lo, hi);
    for _ in 0..steps {
        let a = hi - ratio * (hi - lo);
        let b = lo + ratio * (hi - lo);
        if f(a) < f(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    0.5 * (lo + hi)
}

/// A fresh empty folder in the temporary directory for `name`, unique to this process (`prefix` names the
/// test file).
pub fn tmpdir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("energywave-{prefix}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Degenerate but valid Bezier chains, where a segment's speed vanishes: a name, the control points.
pub fn degenerate_chains() -> Vec<(&'static str, Vec<[f64; 3]>)> {
    let (a, c) = ([-2.0, -1.0, 0.0], [2.0, 1.0, 0.5]);
    vec![
        ("first two points coincide", vec![a, a, c]),
        ("last two points coincide", vec![a, c, c]),
        (
            "a segment starting at rest at a joint",
            vec![[-3.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0; 3], [0.0; 3], c],
        ),
        (
            "a segment of zero length inside the chain",
            vec![
                [-3.0, -1.0, 0.0],
                [-1.0, 1.0, 0.0],
                [0.0; 3],
                [0.0; 3],
                [0.0; 3],
                [1.0, -1.0, 0.0],
                c,
            ],
        ),
    ]
}

/// `assets/scenes`.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes")
}

/// Every shipped scene with its file stem, in name order.
pub fn shipped() -> Vec<(String, Scene)> {
    let mut v: Vec<(String, Scene)> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            (
                p.file_stem().unwrap().to_string_lossy().into_owned(),
                Scene::load(&p).unwrap(),
            )
        })
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// The shipped scene `name` (a file name in `assets/scenes`).
pub fn shipped_scene(name: &str) -> Scene {
    Scene::load(&scenes_dir().join(name)).unwrap()
}

/// Runs `energywave render scene -o out` and checks that it refused the scene: exit status 2 and nothing
/// written. Returns what it said on standard error.
pub fn render_refused(scene: &Path, out: &Path) -> String {
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr).into_owned();
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(!out.exists(), "{} written", out.display());
    err
}

/// How many pixels of a GPU frame differ from the CPU twin's by more than 4 8-bit steps in some channel (each
/// clamped to 0..1, as the display shows it): those whose center lies on an object's edge, where a rasterised
/// triangle and a ray cast may disagree.
pub fn pixels_off(cpu: &[[f64; 4]], gpu: &[[f32; 4]]) -> usize {
    (cpu.iter().zip(gpu))
        .filter(|(c, p)| {
            (0..4)
                .any(|k| (c[k].clamp(0.0, 1.0) - (p[k] as f64).clamp(0.0, 1.0)).abs() > 4.0 / 255.0)
        })
        .count()
}

/// Every entry of `dir` (hidden ones included), by name, sorted.
pub fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The farm tests' scene: sparks thrown by a travelling pulse, live particles simulated from frame 0, so frame
/// N depends on every frame before it.
pub fn sparks() -> String {
    scenes_dir().join("pulse_sparks.toml").display().to_string()
}

/// The farm tests' small, quick frames: `render` flags.
pub const SMALL_FRAMES: [&str; 8] = [
    "--size",
    "64x48",
    "--resolution",
    "40",
    "--integrator",
    "simpson",
    "--divisions",
    "40",
];

/// A transparent glow composited "over" a plate (`got`) against the viewer's own blend on that background
/// (`want`): the largest difference of a channel, and how many pixels were compared: those where the glow's B
/// is at most 1 (its alpha below 0.999), where "over" is the viewer's blend (B > 1 cannot be alpha).
pub fn over_error(
    got: &image::Rgba32FImage,
    want: &image::Rgb32FImage,
    glow: &image::Rgba32FImage,
) -> (f32, usize) {
    let (mut worst, mut compared) = (0.0f32, 0);
    for (x, y, p) in got.enumerate_pixels() {
        if glow.get_pixel(x, y)[3] >= 0.999 {
            continue;
        }
        let w = want.get_pixel(x, y);
        for c in 0..3 {
            worst = worst.max((p[c] - w[c]).abs());
        }
        compared += 1;
    }
    (worst, compared)
}

/// Which pixels of a `w` x `h` frame of `scene` lie within a pixel of an outline of one of its objects: where the
/// set of objects the eye's ray passes through (every one, not only the first: outlines seen through a translucent
/// object count) changes between the pixel's center and its neighbours' centers.
pub fn outline_pixels(scene: &energywave::scene::Scene, w: u32, h: u32) -> Vec<bool> {
    let eye = scene.camera.eye;
    let crossed = |x: f64, y: f64| -> u64 {
        let dir = scene.camera.pixel_ray(x, y, w, h);
        (scene.objects.iter().enumerate())
            .filter(|(_, o)| o.hit(eye, dir, 0.0, f64::INFINITY).is_some())
            .fold(0u64, |m, (i, _)| m | 1 << i)
    };
    let centers: Vec<u64> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| crossed(x as f64 + 0.5, y as f64 + 0.5))
        .collect();
    (0..h as i64)
        .flat_map(|y| (0..w as i64).map(move |x| (x, y)))
        .map(|(x, y)| {
            let here = centers[(y * w as i64 + x) as usize];
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx >= 0
                        && ny >= 0
                        && nx < w as i64
                        && ny < h as i64
                        && centers[(ny * w as i64 + nx) as usize] != here
                })
            })
        })
        .collect()
}

/// A uniform translucent sphere (no cavity, no noise, 8 voxels a side): a glass ball.
#[allow(dead_code)]
pub fn glass_sphere(
    center: glam::DVec3,
    radius: f64,
    extinction: f64,
    eta: f64,
) -> energywave::objects::Object {
    energywave::objects::Object {
        shape: energywave::objects::Shape::Sphere { center, radius },
        color: [1.0; 3],
        translucent: Some(Box::new(energywave::objects::translucent::Translucent {
            extinction,
            eta,
            inner: None,
            noise: None,
            resolution: Some(8),
        })),
    }
}
