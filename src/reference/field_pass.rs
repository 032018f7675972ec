//! What every field pass shares, the f64 twin of `shaders/field_pass.wgsl`: each texel's ray S -> E, B along it
//! by the scene's integrator (`simpson`, or the two families of `adaptive`), and the billboard's whole brightness
//! texture, on every core.

use glam::DVec3;
use rayon::prelude::*;

use super::simpson::jitter_offset;
use super::{adaptive_curves, adaptive_smooth, simpson};
use crate::field::Sources;
use crate::geometry::{Billboard, Reach, ray_end};
use crate::integrate::{Integration, Integrator};
use crate::scene::Scene;

/// The brightness B of the segment from `s` to `e` (3.30): the integral over [0, 1] of
/// `psi((1 - t) S + t E) zeta(t)`, by the scene's integrator. `xi` is the texel's jitter offset (used by the
/// jittered `simpson` integrator only).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3, xi: f64) -> f64 {
    match settings.integrator {
        Integrator::Simpson => simpson::brightness(sources, settings, s, e, xi),
        Integrator::Adaptive => adaptive(sources, settings, s, e),
    }
}

/// B by the adaptive integrator: its two families, as its two GPU passes add into the texture.
pub fn adaptive(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    adaptive_smooth::brightness(sources, settings, s, e)
        + adaptive_curves::brightness(sources, settings, s, e)
}

/// The billboard's brightness texture: `resolution` x `resolution` values of B, row-major, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct BrightnessTexture {
    pub resolution: u32,
    pub values: Vec<f64>,
}

/// Integrates B for every texel of `billboard` (METHOD.md section 3).
pub fn render_brightness(scene: &Scene, billboard: &Billboard) -> BrightnessTexture {
    let w = scene.billboard.resolution;
    let reach = scene.ray_reach(billboard);
    let mut values = vec![0.0; (w as usize) * (w as usize)];
    values
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                *out = texel_brightness_on(scene, billboard, reach, i as u32, j as u32);
            }
        });
    BrightnessTexture {
        resolution: w,
        values,
    }
}

/// B of a single texel, for tests that probe one ray.
pub fn texel_brightness(scene: &Scene, billboard: &Billboard, i: u32, j: u32) -> f64 {
    texel_brightness_on(scene, billboard, scene.ray_reach(billboard), i, j)
}

/// B of texel `(i, j)` with the frame's `reach` already known.
fn texel_brightness_on(scene: &Scene, billboard: &Billboard, reach: Reach, i: u32, j: u32) -> f64 {
    let w = scene.billboard.resolution;
    let s: DVec3 = billboard.texel_center(i, j, w);
    let e = ray_end(s, scene.camera.eye, reach.nu);
    let xi = scene
        .integration
        .jitter
        .map_or(0.5, |seed| jitter_offset(seed, i, j, w));
    let settings = scene.integration.on_ray(reach.stretch);
    brightness(&scene.sources, &settings, s, e, xi)
}
