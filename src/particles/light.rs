//! The wave's light on each particle (docs/METHOD.md section 9), worked out once per edit in f64 and independent of
//! the camera: every source lights a particle from the point of it its term reads at the particle's center,
//! with its color and its term's strength there (`objects::lighting::Lights`), dimmed by the optical depth of the
//! particles between that point and the center (the particle's own half included: its mean shadow) and by the
//! objects (an opaque one stops it, a translucent one lets through its Fresnel transmittance at each surface and
//! `exp(-tau)` between; a long source's shadow is soft, as on the objects: `Lights::passing`), and scattered
//! toward the eye by the paper's phase `3/4 (1 + cos^2 theta)`.
//!
//! Since the phase is a quadratic form in the view direction `v`, the light a particle scatters toward any `v` is
//! `A + v^T M v` per channel, with `A = 3/4 sum_i c_i s_i T_i` and `M = 3/4 sum_i c_i s_i T_i l_i l_i^T` (l_i the
//! unit direction the light travels): orbiting the camera never lights the particles again. The ambient share
//! objects get is added, and the sum is clamped at 0 per channel (a source of negative coefficient darkens the
//! light, never below none), as `particles::in_scattered` does point by point.

use std::collections::HashMap;

use glam::{DVec3, IVec3};
use rayon::prelude::*;

use super::Particle;
use crate::objects::Object;
use crate::objects::lighting::{AMBIENT, Lights};

/// The light a particle scatters, as a function of the direction `v` toward the eye: per channel
/// `max(0, AMBIENT + iso[c] + v^T M_c v)`, `M_c` symmetric, kept as its six entries `xx, yy, zz, xy, xz, yz`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParticleLight {
    pub iso: [f64; 3],
    pub m: [[f64; 6]; 3],
}

impl ParticleLight {
    /// The light scattered toward the unit `v`.
    pub fn toward(&self, v: DVec3) -> [f64; 3] {
        std::array::from_fn(|c| {
            let m = self.m[c];
            let q = m[0] * v.x * v.x
                + m[1] * v.y * v.y
                + m[2] * v.z * v.z
                + 2.0 * (m[3] * v.x * v.y + m[4] * v.x * v.z + m[5] * v.y * v.z);
            (AMBIENT + self.iso[c] + q).max(0.0)
        })
    }
}

/// Every particle's light from `lights`, through `particles` themselves.
pub fn light_particles(lights: &Lights, particles: &[Particle]) -> Vec<ParticleLight> {
    light_particles_among(lights, &[], particles)
}

/// Every particle's light from `lights`, through `particles` themselves and past `objects`: an opaque object
/// stops a source's light, a translucent one dims it by the light it lets through (`Lights::passing`: a long
/// source's shadow soft, as on the objects).
pub fn light_particles_among(
    lights: &Lights,
    objects: &[Object],
    particles: &[Particle],
) -> Vec<ParticleLight> {
    let grid = Grid::new(particles);
    particles
        .par_iter()
        .map_init(
            || (vec![0u64; particles.len()], 0u64),
            |(seen, stamp), p| {
                light_one(lights, p, |k, from| {
                    let passing = lights.passing(objects, p.position, k, from);
                    if passing <= 0.0 {
                        return 0.0;
                    }
                    *stamp += 1;
                    passing * (-grid.optical_depth(particles, from, p.position, seen, *stamp)).exp()
                })
            },
        )
        .collect()
}

/// Every particle's light from `lights` as if nothing stood between: `light_particles` without the particles'
/// shadows, a small part of its cost. What the viewer draws for the moment it works out the shadowed light.
pub fn light_particles_unshadowed(lights: &Lights, particles: &[Particle]) -> Vec<ParticleLight> {
    (particles.par_iter())
        .map(|p| light_one(lights, p, |_, _| 1.0))
        .collect()
}

/// The light of `p` from `lights`, each sample (term `k`, from its place) times the share `through` lets reach
/// the particle.
fn light_one(
    lights: &Lights,
    p: &Particle,
    mut through: impl FnMut(usize, DVec3) -> f64,
) -> ParticleLight {
    let mut out = ParticleLight::default();
    for (k, sample) in lights.at(p.position).enumerate() {
        let reach = 0.75 * sample.strength * through(k, sample.from);
        let l = (p.position - sample.from).normalize_or_zero();
        let outer = [
            l.x * l.x,
            l.y * l.y,
            l.z * l.z,
            l.x * l.y,
            l.x * l.z,
            l.y * l.z,
        ];
        for c in 0..3 {
            let k = sample.color[c] * reach;
            out.iso[c] += k;
            for (m, o) in out.m[c].iter_mut().zip(outer) {
                *m += k * o;
            }
        }
    }
    out
}

/// The particles binned by the cells of a uniform grid their balls overlap, for the shadow rays.
struct Grid {
    cell: f64,
    /// The box around every particle's ball.
    bounds: (DVec3, DVec3),
    cells: HashMap<IVec3, Vec<u32>>,
}

impl Grid {
    fn new(particles: &[Particle]) -> Grid {
        let largest = particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        let cell = (2.0 * largest).max(1e-9);
        let mut cells: HashMap<IVec3, Vec<u32>> = HashMap::new();
        for (k, p) in particles.iter().enumerate() {
            let lo = ((p.position - p.radius) / cell).floor().as_ivec3();
            let hi = ((p.position + p.radius) / cell).floor().as_ivec3();
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        cells.entry(IVec3::new(x, y, z)).or_default().push(k as u32);
                    }
                }
            }
        }
        let bounds = particles
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.position - p.radius), hi.max(p.position + p.radius))
            });
        Grid {
            cell,
            bounds,
            cells,
        }
    }

    /// The optical depth of the particles along the segment `a -> b`, each particle's exact integral over its
    /// part of it counted once (`seen` marks the particles counted for this `stamp`).
    fn optical_depth(
        &self,
        particles: &[Particle],
        a: DVec3,
        b: DVec3,
        seen: &mut [u64],
        stamp: u64,
    ) -> f64 {
        let length = (b - a).length();
        let Some(direction) = (b - a).try_normalize() else {
            return 0.0;
        };
        let ray = super::Ray {
            origin: a,
            direction,
        };
        let mut depth = 0.0;
        let mut visit = |cell: IVec3, depth: &mut f64| {
            if let Some(list) = self.cells.get(&cell) {
                for &k in list {
                    if seen[k as usize] != stamp {
                        seen[k as usize] = stamp;
                        *depth += particles[k as usize].optical_depth(&ray, 0.0, length);
                    }
                }
            }
        };
        // The part of the segment within the particles' box (slab test), then the cells it crosses there, by
        // Amanatides and Woo's traversal.
        let (lo, hi) = self.bounds;
        let (mut t0, mut t1) = (0.0f64, length);
        for axis in 0..3 {
            let (o, v) = (a[axis], direction[axis]);
            if v == 0.0 {
                if o < lo[axis] || o > hi[axis] {
                    return 0.0;
                }
                continue;
            }
            let (p, q) = ((lo[axis] - o) / v, (hi[axis] - o) / v);
            t0 = t0.max(p.min(q));
            t1 = t1.min(p.max(q));
        }
        if t0 > t1 {
            return 0.0;
        }
        let start = ray.at(t0) / self.cell;
        let end = ray.at(t1) / self.cell;
        let mut cell = start.floor().as_ivec3();
        let last = end.floor().as_ivec3();
        let d = end - start;
        let step = IVec3::new(sign(d.x), sign(d.y), sign(d.z));
        let next_boundary = |s: f64, c: i32, st: i32| {
            if st > 0 {
                (c + 1) as f64 - s
            } else {
                s - c as f64
            }
        };
        let inv = |x: f64| {
            if x != 0.0 {
                1.0 / x.abs()
            } else {
                f64::INFINITY
            }
        };
        let t_delta = DVec3::new(inv(d.x), inv(d.y), inv(d.z));
        let mut t_max = DVec3::new(
            next_boundary(start.x, cell.x, step.x) * t_delta.x,
            next_boundary(start.y, cell.y, step.y) * t_delta.y,
            next_boundary(start.z, cell.z, step.z) * t_delta.z,
        );
        let crossings = (last - cell).abs();
        let budget = (crossings.x + crossings.y + crossings.z) as usize + 1;
        for _ in 0..budget {
            visit(cell, &mut depth);
            if cell == last {
                break;
            }
            if t_max.x <= t_max.y && t_max.x <= t_max.z {
                cell.x += step.x;
                t_max.x += t_delta.x;
            } else if t_max.y <= t_max.z {
                cell.y += step.y;
                t_max.y += t_delta.y;
            } else {
                cell.z += step.z;
                t_max.z += t_delta.z;
            }
        }
        depth
    }
}

fn sign(x: f64) -> i32 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// A scene's particles (their colors times their sets' albedo) and the light each scatters.
#[derive(Debug, PartialEq)]
pub struct LitParticles {
    pub particles: Vec<Particle>,
    pub lights: Vec<ParticleLight>,
}

/// The particles of `sets` lit by `sources` past `objects` (`light_particles_among`), none without particles. A renderer keeps
/// them in its frame cache (`frame::FrameCache::lit_particles`): orbiting, or a frame's renderers and its twin,
/// never light them again.
pub fn lit_particles(
    sets: &[super::ParticleSet],
    (sources, objects): (&crate::field::Sources, &[Object]),
    palette: crate::field::Palette,
    epsilon: f64,
) -> Option<LitParticles> {
    if sets.is_empty() {
        return None;
    }
    let particles = super::gather(sets, sources);
    if particles.is_empty() {
        return None;
    }
    let lights =
        light_particles_among(&Lights::new(sources, palette, epsilon), objects, &particles);
    Some(LitParticles { particles, lights })
}

impl LitParticles {
    /// The bytes it holds, for a cache's memory bound.
    pub fn bytes(&self) -> usize {
        size_of_val(&self.particles[..]) + size_of_val(&self.lights[..])
    }
}
