//! Emitters: a particle set made from a shape, deterministic in its seed. Positions are drawn uniformly inside
//! a sphere or a box, or in a tube of radius `spread` around a curve source's chain (uniform in arc length) or a
//! torus source's ring; radii and densities uniformly in their ranges. A noise above 0 clumps them: a candidate
//! position is kept with probability `1 - noise + noise v(x)`, v a smooth value noise in 0..1 whose cells are a
//! quarter of the emitter's extent.

use glam::DVec3;

use super::Particle;
use super::curl::Turbulence;
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

    pub(crate) fn draw(&self, rng: &mut SplitMix) -> f64 {
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
    /// What makes it live: particles born over time, moving, aging (`super::live`); none for a still set of
    /// `count` particles.
    pub life: Option<Box<Life>>,
}

/// Particles thrown at once, at a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Burst {
    /// The frame they are born at (>= 0).
    pub frame: f64,
    pub count: u32,
}

/// The direction a particle is thrown in, before its cone's spread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Direction {
    /// Away from the shape: a ball's or a box's center, a chain's or a ring's line.
    Normal,
    /// Along a chain or a torus's ring.
    Tangent,
    /// Away from the emitter's center: a ring's radius, in its plane.
    Outward,
    /// One direction for all (unit).
    Fixed(DVec3),
}

impl Direction {
    /// The name in scene files (a fixed direction is written as its vector).
    pub fn name(&self) -> Option<&'static str> {
        match self {
            Direction::Normal => Some("normal"),
            Direction::Tangent => Some("tangent"),
            Direction::Outward => Some("outward"),
            Direction::Fixed(_) => None,
        }
    }
}

/// A value over a particle's life: linear between keys `[age share, value]` (ages in 0..=1, increasing), held
/// before the first and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct LifeCurve {
    pub keys: Vec<(f64, f64)>,
}

impl LifeCurve {
    pub fn constant(x: f64) -> LifeCurve {
        LifeCurve {
            keys: vec![(0.0, x)],
        }
    }

    /// The default fade of a particle's density: in over the first tenth of its life, out over the last quarter,
    /// so that nothing pops into or out of existence.
    pub fn fade() -> LifeCurve {
        LifeCurve {
            keys: vec![(0.0, 0.0), (0.1, 1.0), (0.75, 1.0), (1.0, 0.0)],
        }
    }

    pub fn at(&self, age: f64) -> f64 {
        sample(&self.keys, age, |a, b, s| a + (b - a) * s).unwrap_or(1.0)
    }
}

/// Colors over a particle's life: `[age share, color]` keys, linear between them. Empty: the emitter's color.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ColorCurve {
    pub keys: Vec<(f64, [f64; 3])>,
}

impl ColorCurve {
    pub fn at(&self, age: f64) -> Option<[f64; 3]> {
        sample(&self.keys, age, |a, b, s| {
            std::array::from_fn(|c| a[c] + (b[c] - a[c]) * s)
        })
    }
}

/// Piecewise-linear keys at `x`, held outside them; `None` without keys.
fn sample<T: Copy>(keys: &[(f64, T)], x: f64, lerp: impl Fn(T, T, f64) -> T) -> Option<T> {
    let first = keys.first()?;
    let last = keys.last()?;
    if x <= first.0 {
        return Some(first.1);
    }
    if x >= last.0 {
        return Some(last.1);
    }
    let i = keys.partition_point(|k| k.0 <= x);
    let (a, b) = (keys[i - 1], keys[i]);
    Some(lerp(a.1, b.1, (x - a.0) / (b.0 - a.0)))
}

/// What makes an emitter live (`[particles.life]` in scene files).
#[derive(Clone, Debug, PartialEq)]
pub struct Life {
    /// Particles a second (>= 0).
    pub rate: f64,
    pub bursts: Vec<Burst>,
    /// Seconds a particle lives (> 0).
    pub lifetime: Span,
    /// Scene units a second a particle is thrown at (>= 0).
    pub speed: Span,
    pub direction: Direction,
    /// Half the angle of the cone around the direction, degrees in 0..=180 (uniform over its solid angle).
    pub cone: f64,
    /// Scene units per second squared: gravity, wind.
    pub acceleration: DVec3,
    /// Per second (>= 0): the velocity relaxes toward `acceleration / drag` at this rate.
    pub drag: f64,
    pub turbulence: Option<Turbulence>,
    /// The share of the emitter's own velocity (a moving center, a keyed control point) a particle keeps (>= 0).
    pub inherit: f64,
    /// A curve emitter emits where its W series is lit (a travelling pulse), as much as it is lit: a draw at
    /// chain parameter t is kept with probability min(1, W(t)), so that `rate` is a fully lit chain's.
    pub along_pulse: bool,
    /// The particle's radius over its life, a factor (>= 0).
    pub size: LifeCurve,
    /// Its density over its life, a factor (>= 0).
    pub opacity: LifeCurve,
    pub colors: ColorCurve,
    /// Its emission over its life, a factor (>= 0) of the set's (`particles::Emission`).
    pub emission: LifeCurve,
    /// Its emission's color over its life (each channel in 0..=1), times the set's emission color: white to red
    /// for a spark that cools. None: white throughout.
    pub emission_colors: ColorCurve,
    /// Motion blur: the share of a frame the shutter is open, centred on the frame, in 0..=1 (0.5 is a
    /// 180-degree shutter; 0 draws each particle where it is at the frame). A particle is drawn as copies along
    /// its path over it (`live::State::particles`).
    pub shutter: f64,
}

impl Default for Life {
    fn default() -> Self {
        Life {
            rate: 100.0,
            bursts: Vec::new(),
            lifetime: Span { min: 1.0, max: 2.0 },
            speed: Span::one(0.5),
            direction: Direction::Normal,
            cone: 30.0,
            acceleration: DVec3::ZERO,
            drag: 0.0,
            turbulence: None,
            inherit: 0.0,
            along_pulse: false,
            size: LifeCurve::constant(1.0),
            opacity: LifeCurve::fade(),
            colors: ColorCurve::default(),
            emission: LifeCurve::constant(1.0),
            emission_colors: ColorCurve::default(),
            shutter: 0.0,
        }
    }
}

impl Life {
    /// The most particles it can hold at once at `rate`: every burst plus a rate's worth of the longest life.
    pub fn most_alive(&self, rate: f64) -> f64 {
        rate * self.lifetime.max + self.bursts.iter().map(|b| b.count as f64).sum::<f64>()
    }
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
                emission: [1.0; 3],
            });
        }
        out
    }
}

/// A shape resolved against the scene's sources, ready to draw points from.
pub(crate) enum Placement {
    Ball(DVec3, f64),
    Box(DVec3, DVec3),
    /// A polyline along the chain with its cumulative lengths and each point's chain parameter, and the tube's
    /// radius.
    Tube {
        points: Vec<DVec3>,
        lengths: Vec<f64>,
        params: Vec<f64>,
        spread: f64,
    },
    Ring {
        center: DVec3,
        axes: (DVec3, DVec3),
        radius: f64,
        spread: f64,
    },
}

/// Where in its shape a particle is drawn, apart from where the shape is: a share along a chain or a ring and an
/// offset in the unit ball (or the unit cube around 0 for a box). The same draw placed in the shape at two
/// instants gives a moving emitter's velocity there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Draw {
    along: f64,
    offset: DVec3,
}

/// A point placed in a shape, with the directions a live emitter throws particles along.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spot {
    pub position: DVec3,
    /// Away from the shape: from a ball's or a box's center, from a chain's or a ring's line.
    pub normal: DVec3,
    /// Along a chain or a ring (a ball or a box has none: its normal).
    pub tangent: DVec3,
    /// Away from the emitter's center: a ring's radius in its plane; the normal for the other shapes.
    pub outward: DVec3,
}

/// Polyline points a chain segment is measured by for the draw by arc length.
const STEPS_PER_SEGMENT: usize = 64;

impl Placement {
    pub(crate) fn of(shape: &EmitterShape, sources: &Sources) -> Option<Placement> {
        Some(match *shape {
            EmitterShape::Sphere { center, radius } => Placement::Ball(center, radius),
            EmitterShape::Box { center, size } => Placement::Box(center, size),
            EmitterShape::Curve { curve, spread } => {
                let c = sources.curves.get(curve)?;
                let k = curve::segments(&c.control_points).count().max(1) as f64;
                let mut points = Vec::new();
                let mut params = Vec::new();
                for (j, s) in curve::segments(&c.control_points).enumerate() {
                    let first = usize::from(!points.is_empty());
                    for i in first..=STEPS_PER_SEGMENT {
                        let t = i as f64 / STEPS_PER_SEGMENT as f64;
                        points.push(s.at(t));
                        params.push((j as f64 + t) / k);
                    }
                }
                let mut lengths = vec![0.0];
                for w in points.windows(2) {
                    lengths.push(lengths.last().unwrap() + (w[1] - w[0]).length());
                }
                Placement::Tube {
                    points,
                    lengths,
                    params,
                    spread,
                }
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
            Placement::Tube {
                lengths, spread, ..
            } => lengths.last().unwrap().max(2.0 * spread),
            Placement::Ring { radius, spread, .. } => 2.0 * (radius + spread),
        };
        if e > 0.0 { e } else { 1.0 }
    }

    /// A draw for this kind of shape.
    pub(crate) fn sample(&self, rng: &mut SplitMix) -> Draw {
        match self {
            Placement::Ball(..) => Draw {
                along: 0.0,
                offset: rng.in_ball(),
            },
            Placement::Box(..) => Draw {
                along: 0.0,
                offset: DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5),
            },
            Placement::Tube { .. } | Placement::Ring { .. } => {
                let along = rng.unit();
                Draw {
                    along,
                    offset: rng.in_ball(),
                }
            }
        }
    }

    /// A tube's polyline piece holding the draw's share of the length, and where in it.
    fn piece(lengths: &[f64], along: f64) -> (usize, f64) {
        let total = *lengths.last().unwrap();
        let s = along * total;
        let i = lengths
            .partition_point(|&l| l <= s)
            .clamp(1, lengths.len() - 1);
        let piece = lengths[i] - lengths[i - 1];
        let f = if piece > 0.0 {
            (s - lengths[i - 1]) / piece
        } else {
            0.0
        };
        (i, f)
    }

    /// The chain parameter a draw sits at, for a tube (where a curve's W series is read).
    pub(crate) fn chain_parameter(&self, d: &Draw) -> Option<f64> {
        let Placement::Tube {
            lengths, params, ..
        } = self
        else {
            return None;
        };
        let (i, f) = Placement::piece(lengths, d.along);
        Some(params[i - 1] + (params[i] - params[i - 1]) * f)
    }

    /// The draw placed in the shape.
    pub(crate) fn place(&self, d: &Draw) -> Spot {
        let away = |v: DVec3, fallback: DVec3| v.try_normalize().unwrap_or(fallback);
        // A ball's or a box's point: every direction away from its center.
        let radial = |position: DVec3| {
            let normal = away(d.offset, DVec3::Y);
            Spot {
                position,
                normal,
                tangent: normal,
                outward: normal,
            }
        };
        match self {
            Placement::Ball(center, r) => radial(center + r * d.offset),
            Placement::Box(center, size) => radial(center + size * d.offset),
            Placement::Tube {
                points,
                lengths,
                spread,
                ..
            } => {
                let (i, f) = Placement::piece(lengths, d.along);
                let tangent = away(points[i] - points[i - 1], DVec3::X);
                let across = d.offset - tangent * d.offset.dot(tangent);
                let normal = away(across, tangent.any_orthonormal_vector());
                Spot {
                    position: points[i - 1].lerp(points[i], f) + spread * d.offset,
                    normal,
                    tangent,
                    outward: normal,
                }
            }
            Placement::Ring {
                center,
                axes: (u, v),
                radius,
                spread,
            } => {
                let angle = std::f64::consts::TAU * d.along;
                let outward = angle.cos() * u + angle.sin() * v;
                Spot {
                    position: center + radius * outward + spread * d.offset,
                    normal: away(d.offset, outward),
                    tangent: -angle.sin() * u + angle.cos() * v,
                    outward,
                }
            }
        }
    }

    fn draw(&self, rng: &mut SplitMix) -> DVec3 {
        let d = self.sample(rng);
        self.place(&d).position
    }
}

/// SplitMix64 (Steele, Lea and Flood 2014): a small generator whose stream is fixed by its seed on every
/// platform, which a scene's emitters need (a file renders the same wherever it is opened).
#[derive(Clone, Debug)]
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 bits.
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in the unit ball (by rejection).
    pub(crate) fn in_ball(&mut self) -> DVec3 {
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
            life: None,
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
