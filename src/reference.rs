//! The f64 CPU reference renderer: the brightness texture B of the billboard and the composed frame,
//! formula for formula as METHOD.md states them, on every core.
//!
//! It is the oracle the GPU passes are tested against, and `energywave render --backend cpu`.

use glam::DVec3;

use crate::compose::{blend, blend_transparent, sample_bilinear};
use crate::field::Sources;
use crate::geometry::{Billboard, Reach, ray_end};
use crate::integrate::{Integration, Integrator, jitter_offset, shifted_rectangle, simpson, zeta};
use crate::scene::Scene;

/// The brightness B of the segment from `s` to `e` (3.30): the integral over [0, 1] of
/// `psi((1 - t) S + t E) zeta(t)`, by the scene's integrator: the papers' rule (`crate::integrate`) or the
/// adaptive one (`crate::adaptive`). `xi` is the texel's jitter offset (used by the jittered `simpson`
/// integrator only).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3, xi: f64) -> f64 {
    let f = |t: f64| {
        sources.psi(s + (e - s) * t, settings.epsilon) * zeta(t, settings.alpha, settings.beta)
    };
    match (settings.integrator, settings.jitter) {
        (Integrator::Simpson, None) => simpson(f, settings.divisions),
        (Integrator::Simpson, Some(_)) => shifted_rectangle(f, settings.divisions, xi),
        (Integrator::Adaptive, _) => crate::adaptive::brightness(sources, settings, s, e),
    }
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
    for_each_row(&mut values, w as usize, |j, row| {
        for (i, out) in row.iter_mut().enumerate() {
            *out = texel_brightness_on(scene, billboard, reach, i as u32, j as u32);
        }
    });
    BrightnessTexture {
        resolution: w,
        values,
    }
}

/// The frame the camera sees, RGBA, rows from the top: the background color everywhere, and over the
/// billboard the blend of B (sampled bilinearly, as the GPU's pass does) `clamp((1 - B) Cb + B Ce)`, alpha 1.
/// With `transparent`, the background is transparent and the billboard carries straight color with
/// alpha = min(B, 1) (`compose::blend_transparent`).
pub fn compose_frame(
    scene: &Scene,
    billboard: &Billboard,
    texture: &BrightnessTexture,
    width: u32,
    height: u32,
    transparent: bool,
) -> Vec<[f64; 4]> {
    let [r, g, b] = scene.colors.background;
    let clear = if transparent {
        [0.0; 4]
    } else {
        [r, g, b, 1.0]
    };
    let mut pixels = vec![clear; width as usize * height as usize];
    for_each_row(&mut pixels, width as usize, |y, row| {
        for (x, out) in row.iter_mut().enumerate() {
            let dir = scene
                .camera
                .pixel_ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
            if let Some((u, v)) = billboard.hit(scene.camera.eye, dir) {
                let b = sample_bilinear(&texture.values, texture.resolution, u, v);
                *out = if transparent {
                    blend_transparent(b, scene.colors.energy)
                } else {
                    let [r, g, b] = blend(b, scene.colors.energy, scene.colors.background);
                    [r, g, b, 1.0]
                };
            }
        }
    });
    pixels
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

/// Runs `f(row_index, row)` over the rows of `data` (rows of `width` items) on every core.
fn for_each_row<T: Send>(data: &mut [T], width: usize, f: impl Fn(usize, &mut [T]) + Sync) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows: Vec<(usize, &mut [T])> = data.chunks_mut(width.max(1)).enumerate().collect();
    let queue = std::sync::Mutex::new(rows.into_iter());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let next = queue.lock().map(|mut q| q.next()).unwrap_or(None);
                    let Some((j, row)) = next else { break };
                    f(j, row);
                }
            });
        }
    });
}
