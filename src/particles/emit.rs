//! Emitters: a particle set made from a shape, deterministic in its seed. Positions are drawn uniformly inside
//! a sphere or a box, or in a tube of radius `spread` around a curve source's chain (uniform in arc length) or a
//! torus source's ring; radii and densities uniformly in their ranges. A noise above 0 clumps them: a candidate
//! position is kept with probability `1 - noise + noise v(x)`, v a smooth value noise in 0..1 whose cells are a
//! quarter of the emitter's extent.

use glam::DVec3;

use super::Particle;
use crate::field::{Sources, curve};

/// A closed range `[min, max]` a value is drawn from uniformly (`min == max`: that value).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub min: f64,
    pub max: f64,
}

impl Span {
    pub const fn one(x: f64) -> Span {
        Span { min: x, max: x }
    }

    fn draw(&self, rng: &mut SplitMix) -> f64 {
        self.min + (self.max - self.min) * rng.unit()
    }
}

/// Where an emitter puts its particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EmitterShape {
    /// Inside the ball of `radius` around `center`.
    Sphere { center: DVec3, radius: f64 },
    /// Inside the axis-aligned box of side lengths `size` around `center`.
    Box { center: DVec3, size: DVec3 },
    /// Within `spread` of the scene's curve source `curve` (an index into its curves), uniform along the chain.
    Curve { curve: usize, spread: f64 },
    /// Within `spread` of the ring of the scene's torus source `torus` (an index into its tori).
    Torus { torus: usize, spread: f64 },
}

/// The kinds of emitter shape, as scene files and the panel name them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmitterKind {
    Sphere,
    Box,
    Curve,
    Torus,
}

impl EmitterKind {
    pub const ALL: [EmitterKind; 4] = [
        EmitterKind::Sphere,
        EmitterKind::Box,
        EmitterKind::Curve,
        EmitterKind::Torus,
    ];

    pub fn name(self) -> &'static str {
        match self {
            EmitterKind::Sphere => "sphere",
            EmitterKind::Box => "box",
            EmitterKind::Curve => "curve",
            EmitterKind::Torus => "torus",
        }
    }
}

impl EmitterShape {
    pub fn kind(&self) -> EmitterKind {
        match self {
            EmitterShape::Sphere { .. } => EmitterKind::Sphere,
            EmitterShape::Box { .. } => EmitterKind::Box,
            EmitterShape::Curve { .. } => EmitterKind::Curve,
            EmitterShape::Torus { .. } => EmitterKind::Torus,
        }
    }
}

/// A particle set made from a shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Emitter {
    pub shape: EmitterShape,
    pub count: u32,
    /// The particles' radii, > 0.
    pub radius: Span,
    /// The particles' densities, >= 0.
    pub density: Span,
    /// Every particle's color.
    pub color: [f64; 3],
    pub seed: u64,
    /// How much the particles clump, in 0..=1 (0: uniform).
    pub noise: f64,
}

impl Emitter {
    /// The particles: the same for the same emitter and sources, on every machine. Empty where the shape names a
    /// source the scene does not have (the loader refuses such a file; the panel may leave one behind).
    pub fn emit(&self, sources: &Sources) -> Vec<Particle> {
        let Some(place) = Placement::of(&self.shape, sources) else {
            return Vec::new();
        };
        let mut rng = SplitMix(self.seed);
        let cell = place.extent() / 4.0;
        let noise_seed = rng.next();
        let mut out = Vec::with_capacity(self.count as usize);
        // A candidate is kept with probability at least 1 - noise: 64 tries a particle are plenty for any noise
        // (the noise's mean is a half), and bound the work of an unlucky seed.
        let mut tries = 64 * self.count as u64;
        while out.len() < self.count as usize && tries > 0 {
            tries -= 1;
            let position = place.draw(&mut rng);
            let keep = 1.0 - self.noise + self.noise * value_noise(position / cell, noise_seed);
            if rng.unit() >= keep {
                continue;
            }
            out.push(Particle {
                position,
                radius: self.radius.draw(&mut rng),
                density: self.density.draw(&mut rng),
                color: self.color,
            });
        }
        out
    }
}

/// A shape resolved against the scene's sources, ready to draw points from.
enum Placement {
    Ball(DVec3, f64),
    Box(DVec3, DVec3),
    /// A polyline along the chain with its cumulative lengths, and the tube's radius.
    Tube(Vec<DVec3>, Vec<f64>, f64),
    Ring {
        center: DVec3,
        axes: (DVec3, DVec3),
        radius: f64,
        spread: f64,
    },
}

/// Polyline points a chain segment is measured by for the draw by arc length.
const STEPS_PER_SEGMENT: usize = 64;

impl Placement {
    fn of(shape: &EmitterShape, sources: &Sources) -> Option<Placement> {
        Some(match *shape {
            EmitterShape::Sphere { center, radius } => Placement::Ball(center, radius),
            EmitterShape::Box { center, size } => Placement::Box(center, size),
            EmitterShape::Curve { curve, spread } => {
                let c = sources.curves.get(curve)?;
                let mut points = Vec::new();
                for s in curve::segments(&c.control_points) {
                    let first = usize::from(!points.is_empty());
                    points.extend(
                        (first..=STEPS_PER_SEGMENT)
                            .map(|i| s.at(i as f64 / STEPS_PER_SEGMENT as f64)),
                    );
                }
                let mut lengths = vec![0.0];
                for w in points.windows(2) {
                    lengths.push(lengths.last().unwrap() + (w[1] - w[0]).length());
                }
                Placement::Tube(points, lengths, spread)
            }
            EmitterShape::Torus { torus, spread } => {
                let t = sources.tori.get(torus)?;
                Placement::Ring {
                    center: t.center,
                    axes: t.axis.any_orthonormal_pair(),
                    radius: t.major_radius,
                    spread,
                }
            }
        })
    }

    /// The size of the region, for the noise's cells.
    fn extent(&self) -> f64 {
        let e = match self {
            Placement::Ball(_, r) => 2.0 * r,
            Placement::Box(_, size) => size.max_element(),
            Placement::Tube(_, lengths, spread) => lengths.last().unwrap().max(2.0 * spread),
            Placement::Ring { radius, spread, .. } => 2.0 * (radius + spread),
        };
        if e > 0.0 { e } else { 1.0 }
    }

    fn draw(&self, rng: &mut SplitMix) -> DVec3 {
        match self {
            Placement::Ball(center, r) => center + r * rng.in_ball(),
            Placement::Box(center, size) => {
                center + size * DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5)
            }
            Placement::Tube(points, lengths, spread) => {
                let total = *lengths.last().unwrap();
                let s = rng.unit() * total;
                let i = lengths
                    .partition_point(|&l| l <= s)
                    .clamp(1, points.len() - 1);
                let piece = lengths[i] - lengths[i - 1];
                let f = if piece > 0.0 {
                    (s - lengths[i - 1]) / piece
                } else {
                    0.0
                };
                points[i - 1].lerp(points[i], f) + spread * rng.in_ball()
            }
            Placement::Ring {
                center,
                axes: (u, v),
                radius,
                spread,
            } => {
                let angle = std::f64::consts::TAU * rng.unit();
                center + radius * (angle.cos() * u + angle.sin() * v) + spread * rng.in_ball()
            }
        }
    }
}

/// SplitMix64 (Steele, Lea and Flood 2014): a small generator whose stream is fixed by its seed on every
/// platform, which a scene's emitters need (a file renders the same wherever it is opened).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 bits.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in the unit ball (by rejection).
    fn in_ball(&mut self) -> DVec3 {
        loop {
            let p = DVec3::new(self.unit(), self.unit(), self.unit()) * 2.0 - DVec3::ONE;
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }
}

/// Smooth value noise in [0, 1]: a hashed value at each integer lattice point, blended by smoothstep.
fn value_noise(p: DVec3, seed: u64) -> f64 {
    let base = p.floor();
    let f = p - base;
    let s = f * f * (DVec3::splat(3.0) - 2.0 * f);
    let corner = |dx: i64, dy: i64, dz: i64| {
        let key = [base.x as i64 + dx, base.y as i64 + dy, base.z as i64 + dz];
        let mut h = SplitMix(seed);
        for k in key {
            h.0 ^= k as u64;
            h.next();
        }
        h.unit()
    };
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let x0 = [
        lerp(corner(0, 0, 0), corner(1, 0, 0), s.x),
        lerp(corner(0, 1, 0), corner(1, 1, 0), s.x),
        lerp(corner(0, 0, 1), corner(1, 0, 1), s.x),
        lerp(corner(0, 1, 1), corner(1, 1, 1), s.x),
    ];
    lerp(lerp(x0[0], x0[1], s.y), lerp(x0[2], x0[3], s.y), s.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(noise: f64, seed: u64) -> Emitter {
        Emitter {
            shape: EmitterShape::Sphere {
                center: DVec3::new(1.0, 2.0, 3.0),
                radius: 2.0,
            },
            count: 4000,
            radius: Span { min: 0.1, max: 0.3 },
            density: Span { min: 1.0, max: 2.0 },
            color: [0.5, 0.6, 0.7],
            seed,
            noise,
        }
    }

    #[test]
    fn emitters_are_deterministic_and_stay_in_their_shape() {
        let sources = Sources::default();
        let a = sphere(0.0, 7).emit(&sources);
        assert_eq!(a, sphere(0.0, 7).emit(&sources));
        assert_ne!(a, sphere(0.0, 8).emit(&sources));
        assert_eq!(a.len(), 4000);
        for p in &a {
            assert!((p.position - DVec3::new(1.0, 2.0, 3.0)).length() <= 2.0);
            assert!((0.1..=0.3).contains(&p.radius) && (1.0..=2.0).contains(&p.density));
        }
        // Uniform in the ball: the share within half the radius is an eighth (binomial sd 0.005 at 4000).
        let inner = a
            .iter()
            .filter(|p| (p.position - DVec3::new(1.0, 2.0, 3.0)).length() < 1.0)
            .count() as f64
            / 4000.0;
        assert!((inner - 0.125).abs() < 0.02, "{inner}");
    }

    #[test]
    fn noise_clumps() {
        // A box of side 4 over 64 whole cells of the noise (a quarter of the emitter's extent: 1): the particles'
        // counts over them spread out more than a uniform draw's (whose variance is its mean, Poisson).
        let sources = Sources::default();
        let boxed = |noise| Emitter {
            shape: EmitterShape::Box {
                center: DVec3::ZERO,
                size: DVec3::splat(4.0),
            },
            count: 6400,
            noise,
            ..sphere(0.0, 3)
        };
        let spread = |e: Emitter| {
            let mut cells = std::collections::HashMap::<[i64; 3], f64>::new();
            for p in e.emit(&sources) {
                *cells
                    .entry(p.position.floor().as_i64vec3().to_array())
                    .or_default() += 1.0;
            }
            let n = cells.len() as f64;
            let mean = cells.values().sum::<f64>() / n;
            cells.values().map(|c| (c - mean).powi(2)).sum::<f64>() / n / mean
        };
        let (uniform, clumped) = (spread(boxed(0.0)), spread(boxed(1.0)));
        assert!(
            uniform < 2.0 && clumped > 3.0 * uniform,
            "{uniform} {clumped}"
        );
    }

    #[test]
    fn value_noise_is_continuous_and_within_unit() {
        let mut last = value_noise(DVec3::new(0.3, 0.7, -1.2), 5);
        for i in 1..2000 {
            let x = value_noise(DVec3::new(0.3 + i as f64 * 1e-3, 0.7, -1.2), 5);
            assert!((0.0..=1.0).contains(&x) && (x - last).abs() < 1e-2);
            last = x;
        }
    }
}
