//! Particle sets: smoke, dust and sparks around the glow (docs/METHOD.md section 9, after paper 002_, Beliaev and
//! Zaytseva, image-aligned sheet-buffer splatting). A particle spreads its material over a ball by the paper's
//! reconstruction kernel; the medium's extinction is the sum of the particles' kernels times their densities.
//! Here the particle model and the kernel in f64, with the kernel's integral along a line in closed form (what a
//! splat's pre-integrated segment holds), and the wave's light in the medium; the renderer that slices them is
//! `reference::particles`.
//!
//! Conventions (docs/METHOD.md section 9, as we read the paper):
//! - `G(r) = 0.446 exp(-2 r^2)` for `r = |x - p| / R < 1`, zero beyond (the paper's eq. 6, truncated at the
//!   particle's ball). 0.446 is the paper's constant, kept as its peak, not a normalisation.
//! - The extinction coefficient, per scene unit, is `sigma(x) = sum_k rho_k G(|x - p_k| / R_k)`: a particle's
//!   density scales its kernel, and a slab's opacity is `1 - exp(-optical depth)`. (The paper writes
//!   `tau = 1 - alpha` with alpha the density, which read literally makes denser particles clearer.)
//! - A particle's color is its material's: the share of light its material scatters, per channel.
//! - A particle may also glow by itself (sparks, embers): its emission `L_e` is the radiance its material gives
//!   off per unit of optical depth, so that the medium emits `sigma(x) L_e` per scene unit, the way a hot medium
//!   emits where it absorbs. A slab of optical depth `tau` then shows `L_e (1 - exp(-tau))` of it, as much as a
//!   thin particle lets through and at most `L_e` through a thick one, dimmed like any light by what lies in
//!   front. Emission lights nothing else: a spark is not a light source for the objects, the smoke or the other
//!   particles.

pub mod curl;
pub mod emit;
pub mod light;
pub mod live;
pub mod ply;
pub mod view;

use std::path::PathBuf;
use std::sync::Arc;

use glam::DVec3;

use crate::field::Sources;
use crate::objects::lighting::{AMBIENT, Lights};

/// The share of the light reaching a particle that its material scatters, where a set gives none (the paper's).
pub const DEFAULT_ALBEDO: f64 = 0.9;

/// The slices' width in radii of the smallest particle, where a scene gives none (the paper's R/2).
pub const DEFAULT_SLICE_WIDTH: f64 = 0.5;

/// A set of particles in a scene: where they come from, and how much of the light they scatter.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleSet {
    pub origin: Origin,
    /// The share of the light reaching a particle that it scatters, in 0..=1 (times its color per channel).
    pub albedo: f64,
    /// The light its particles give off by themselves (none by default).
    pub emission: Emission,
    /// A live set's particles at the frame its scene was taken at (`Scene::at_frame`); none in a scene as
    /// loaded or edited, and for a still set.
    pub live: Option<Arc<Vec<Particle>>>,
}

/// Where a set's particles come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// A PLY point cloud (`ply`): its path as the scene file gives it, the values its vertices lack, and the
    /// particles read, shared by the copies of a scene.
    File {
        path: PathBuf,
        defaults: ply::Defaults,
        particles: Arc<Vec<Particle>>,
    },
    Emitter(emit::Emitter),
}

/// The light a set's particles give off by themselves: a color (display values, each channel in 0..=1) times an
/// intensity (0..=`scene::MAX_INTENSITY`, above 1 brighter than a display color can be). A live set's emission
/// also follows its life's curves (`emit::Life::emission`, `emission_colors`), which multiply it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub color: [f64; 3],
    pub intensity: f64,
}

impl Emission {
    /// None: white at intensity 0.
    pub const NONE: Emission = Emission {
        color: [1.0; 3],
        intensity: 0.0,
    };

    /// Its radiance per unit of optical depth, rgb.
    pub fn radiance(&self) -> [f64; 3] {
        self.color.map(|c| c * self.intensity)
    }
}

impl Default for Emission {
    fn default() -> Self {
        Emission::NONE
    }
}

impl ParticleSet {
    /// The set's particles, each with its color times the set's albedo (the share of light it scatters, per
    /// channel: what the renderers take as its color, with an albedo of 1) and its emission factor times the
    /// set's emission (its radiance).
    pub fn particles(&self, sources: &Sources) -> Vec<Particle> {
        let emission = self.emission.radiance();
        let own = match &self.origin {
            Origin::File { particles, .. } => particles.as_ref().clone(),
            Origin::Emitter(e) if e.life.is_some() => {
                self.live.as_deref().cloned().unwrap_or_default()
            }
            Origin::Emitter(e) => e.emit(sources),
        };
        own.into_iter()
            .map(|p| Particle {
                color: p.color.map(|c| c * self.albedo),
                emission: std::array::from_fn(|c| p.emission[c] * emission[c]),
                ..p
            })
            .collect()
    }
}

impl ParticleSet {
    /// The set's emitter's life, where it is live.
    pub fn life(&self) -> Option<&live::Life> {
        match &self.origin {
            Origin::Emitter(e) => e.life.as_deref(),
            Origin::File { .. } => None,
        }
    }

    /// The set without its particles of a frame (as a document holds it).
    pub fn unframed(&self) -> ParticleSet {
        ParticleSet {
            live: None,
            ..self.clone()
        }
    }
}

/// Every particle of `sets`, as [`ParticleSet::particles`] gives them.
pub fn gather(sets: &[ParticleSet], sources: &Sources) -> Vec<Particle> {
    sets.iter().flat_map(|s| s.particles(sources)).collect()
}

/// The paper's kernel at the particle's center (its eq. 6).
pub const KERNEL_PEAK: f64 = 0.446;

/// The kernel's exponent: `G(r) = KERNEL_PEAK exp(-KERNEL_FALLOFF r^2)`.
pub const KERNEL_FALLOFF: f64 = 2.0;

/// The light through a pixel's smoke below which the rest of its slabs are left out, by both renderers: what lies
/// behind could add at most this share of its radiance (3D Gaussian splatting stops at the same).
pub const TRANSMITTANCE_CUTOFF: f64 = 1e-4;

/// One particle: a ball of material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    pub position: DVec3,
    /// The ball's radius R, scene units, > 0.
    pub radius: f64,
    /// rho: the extinction per scene unit at the center is `rho KERNEL_PEAK`, >= 0.
    pub density: f64,
    /// The material's color, linear, each channel in [0, 1].
    pub color: [f64; 3],
    /// The radiance it gives off by itself per unit of its optical depth, rgb, >= 0 (the module's emission). A
    /// set's own particles carry a factor of the set's emission (1 for a still set; the life's curves at its
    /// age for a live one), `ParticleSet::particles` the radiance itself.
    pub emission: [f64; 3],
}

/// `G(r)`, r in radii from the center: the paper's Gaussian inside the ball, zero outside.
pub fn kernel(r: f64) -> f64 {
    if r < 1.0 {
        KERNEL_PEAK * (-KERNEL_FALLOFF * r * r).exp()
    } else {
        0.0
    }
}

/// The extinction coefficient at `x`, per scene unit: `sum_k rho_k G(|x - p_k| / R_k)`.
pub fn extinction(particles: &[Particle], x: DVec3) -> f64 {
    particles
        .iter()
        .map(|p| p.density * kernel((x - p.position).length() / p.radius))
        .sum()
}

/// The kernel integrated along a line that passes `u` radii from the center, from `s0` to `s1` radii along the
/// line past its closest approach: `integral of G(sqrt(u^2 + s^2)) ds` over `[s0, s1]` within the ball, in radii.
/// In closed form, `G(u) sqrt(pi / 8) (erf(sqrt 2 b) - erf(sqrt 2 a))` over the chord's part `[a, b]`: the
/// footprint of a pre-integrated segment at a texel.
pub fn segment_integral(u: f64, s0: f64, s1: f64) -> f64 {
    if u >= 1.0 || s1 <= s0 {
        return 0.0;
    }
    let half_chord = (1.0 - u * u).sqrt();
    let (a, b) = (s0.max(-half_chord), s1.min(half_chord));
    if b <= a {
        return 0.0;
    }
    let k = KERNEL_FALLOFF.sqrt();
    let gauss = KERNEL_PEAK * (-KERNEL_FALLOFF * u * u).exp();
    gauss
        * (std::f64::consts::PI / (4.0 * KERNEL_FALLOFF)).sqrt()
        * (libm::erf(k * b) - libm::erf(k * a))
}

/// A ray from `origin` along the unit `direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
}

impl Ray {
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.direction * t
    }
}

impl Particle {
    /// Where `ray` meets the particle's ball, `(t_in, t_out)` along it, if it does.
    pub fn chord(&self, ray: &Ray) -> Option<(f64, f64)> {
        let closest = (self.position - ray.origin).dot(ray.direction);
        let miss = (ray.at(closest) - self.position).length_squared();
        let half = (self.radius * self.radius - miss).sqrt();
        (half > 0.0).then_some((closest - half, closest + half))
    }

    /// The optical depth the particle gives the stretch `[t0, t1]` of `ray`: its density times its kernel
    /// integrated along the stretch (exact: `segment_integral` scaled to scene units).
    pub fn optical_depth(&self, ray: &Ray, t0: f64, t1: f64) -> f64 {
        let closest = (self.position - ray.origin).dot(ray.direction);
        let u = (ray.at(closest) - self.position).length() / self.radius;
        self.density
            * self.radius
            * segment_integral(
                u,
                (t0 - closest) / self.radius,
                (t1 - closest) / self.radius,
            )
    }
}

/// The slices: planes perpendicular to the view `axis` (unit, from the eye into the scene), the first one
/// `near` past the ray's origin along it, `count` slabs of `width` between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slicing {
    pub axis: DVec3,
    pub near: f64,
    pub width: f64,
    pub count: u32,
}

impl Slicing {
    /// Slabs of `width` from the nearest particle's front to the farthest one's back, as seen from `eye` along
    /// `axis`; none without particles in front of the eye.
    pub fn covering(particles: &[Particle], eye: DVec3, axis: DVec3, width: f64) -> Slicing {
        let depths = particles.iter().map(|p| (p.position - eye).dot(axis));
        let near = (particles.iter().zip(depths.clone()))
            .map(|(p, d)| d - p.radius)
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        let far = (particles.iter().zip(depths))
            .map(|(p, d)| d + p.radius)
            .fold(f64::NEG_INFINITY, f64::max);
        let count = if far > near {
            ((far - near) / width).ceil() as u32
        } else {
            0
        };
        Slicing {
            axis,
            near,
            width,
            count,
        }
    }

    /// Where `ray` (from the eye the slicing was made for) crosses the front and back planes of slab `j`.
    pub fn slab(&self, ray: &Ray, j: u32) -> (f64, f64) {
        let along = ray.direction.dot(self.axis);
        let front = self.near + j as f64 * self.width;
        (front / along, (front + self.width) / along)
    }

    /// The slabs `ray` crosses between `t0` and `t1` along it.
    pub fn slabs_between(&self, ray: &Ray, t0: f64, t1: f64) -> std::ops::Range<u32> {
        let along = ray.direction.dot(self.axis);
        let index = |t: f64| ((t * along - self.near) / self.width).floor();
        let first = index(t0).max(0.0) as u32;
        let last = (index(t1) + 1.0).clamp(0.0, self.count as f64) as u32;
        first.min(last)..last
    }
}

/// The share of light the medium scatters from a direction into one at angle theta to it, the paper's Rayleigh
/// phase (its eq. 5): `3/4 (1 + cos^2 theta)`. Its mean over the sphere is 1 (the isotropic phase is 1 in this
/// convention), so that an albedo is the share of the light a particle's material scatters in all.
pub fn phase(cos_theta: f64) -> f64 {
    0.75 * (1.0 + cos_theta * cos_theta)
}

/// The optical depth of `particles` along the straight segment from `a` to `b`: each particle's kernel
/// integrated exactly over its part of it.
pub fn optical_depth_between(particles: &[Particle], a: DVec3, b: DVec3) -> f64 {
    let length = (b - a).length();
    let Some(direction) = (b - a).try_normalize() else {
        return 0.0;
    };
    let ray = Ray {
        origin: a,
        direction,
    };
    particles
        .iter()
        .map(|p| p.optical_depth(&ray, 0.0, length))
        .sum()
}

/// The wave's light at `x` in the medium, in-scattered toward `eye` (docs/METHOD.md section 9): every source a
/// light at the point of it its term reads from `x`, of its color and of the strength its term of psi has at
/// `x` (as it lights objects, `objects::lighting`), dimmed by the particles between that point and `x`, times
/// the phase at the angle between its light and the view; plus the ambient share objects get too:
/// `L_in(x) = AMBIENT + sum_i Ce_i psi_i(x) T_i(x) p(theta_i)`, each channel at least 0 (a source of negative
/// coefficient darkens the light, never below none).
pub fn in_scattered(lights: &Lights, particles: &[Particle], x: DVec3, eye: DVec3) -> [f64; 3] {
    let toward_eye = (eye - x).normalize_or_zero();
    let mut light = [AMBIENT; 3];
    for sample in lights.at(x) {
        let along = (x - sample.from).normalize_or_zero();
        let reach = sample.strength
            * (-optical_depth_between(particles, sample.from, x)).exp()
            * phase(along.dot(toward_eye));
        for (l, c) in light.iter_mut().zip(sample.color) {
            *l += c * reach;
        }
    }
    light.map(|l| l.max(0.0))
}
