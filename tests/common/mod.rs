//! What several test files share: the shipped scenes, and the viewer under egui_kittest (`viewer`).
// Each test file compiles this module on its own and uses part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use energywave::scene::Scene;

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
