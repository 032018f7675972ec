//! Particles that live: an emitter that makes particles over time (a rate and bursts), each with a lifetime,
//! thrown with a velocity, moved by a constant acceleration, a drag and a turbulence (curl noise), its size,
//! density, color and emission following curves over its life (docs/METHOD.md section 9, "Particles that live").
//!
//! The simulation is a pure function of the scene and the frame: the state at frame N is the state at frame 0
//! stepped N times by [`advance`], each step the same `SUBSTEPS` substeps on one global time grid, each particle
//! drawn from its own generator (seeded by the set's seed and the particle's number). A state reached by
//! playing, by jumping from a kept state, or from scratch in another process is the same to the bit
//! (`scene::live` keeps states to start from).
//!
//! What an emitter reads of its scene (its sources, its own keyed settings) it reads at each substep's ends:
//! a particle born between them is placed where its draw lies in the shape at its birth, interpolated between
//! the two (a moving emitter leaves a continuous trail), and inherits the shape's velocity there.
//!
//! Motion over a step of length `dt` with acceleration `a` and drag `k` is exact (the velocity relaxes to
//! `a / k`): `v' = a/k + (v - a/k) e^(-k dt)`, `x' = x + a/k dt + (v - a/k) (1 - e^(-k dt)) / k` (ballistic
//! for `k = 0`); the turbulence adds its velocity field to the particle's motion, advected by the midpoint
//! rule.

use glam::DVec3;

use super::Particle;
use super::curl::Turbulence;
pub use super::emit::{Burst, ColorCurve, Direction, Life, LifeCurve};
use super::emit::{Emitter, Placement, SplitMix, Spot};
use crate::field::{Sources, wseries};

/// Substeps a frame: the time grid every state is stepped on.
pub const SUBSTEPS: u32 = 2;

/// The most particles one live set holds at once: births beyond it are skipped (the same ones on every run).
pub const MAX_ALIVE: usize = super::ply::MAX_PARTICLES;

/// A live particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveParticle {
    pub position: DVec3,
    pub velocity: DVec3,
    /// Seconds.
    pub born: f64,
    /// Seconds.
    pub lifetime: f64,
    pub radius: f64,
    pub density: f64,
    pub color: [f64; 3],
    /// Its number among the set's births, from 0.
    pub id: u64,
}

/// A live set at one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    pub frame: u32,
    /// Births owed to the rate so far (its integral over time): particle m is born when it passes m.
    owed: f64,
    next_id: u64,
    pub particles: Vec<LiveParticle>,
}

/// What a live set reads of its scene at one instant: its sources and its own emitter, as keyed then.
pub struct World {
    pub sources: Sources,
    pub emitter: Emitter,
}

/// The scene at a frame (fractional), as far as a live set reads it.
pub trait Timeline {
    fn world(&self, frame: f64) -> World;
    fn frame_rate(&self) -> f64;
}

/// A resolved instant: the world and its emitter's placement.
struct Instant {
    world: World,
    placement: Option<Placement>,
}

impl Instant {
    fn at(timeline: &dyn Timeline, frame: f64) -> Instant {
        let world = timeline.world(frame);
        let placement = Placement::of(&world.emitter.shape, &world.sources);
        Instant { world, placement }
    }

    fn life(&self) -> &Life {
        self.world.emitter.life.as_deref().expect("a live emitter")
    }
}

/// The generator of particle `id` of a set seeded `seed`: its own stream, whatever else is born.
fn particle_rng(seed: u64, id: u64) -> SplitMix {
    let mut mix = SplitMix(seed ^ 0x243f_6a88_85a3_08d3);
    mix.0 ^= id.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    mix.next();
    SplitMix(mix.next())
}

/// A unit vector in the cone of half-angle `cone` degrees around unit `axis`, uniform over its solid angle.
fn in_cone(axis: DVec3, cone: f64, rng: &mut SplitMix) -> DVec3 {
    let cos_max = cone.to_radians().cos();
    let cos = 1.0 - rng.unit() * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * rng.unit();
    let (u, v) = axis.any_orthonormal_pair();
    axis * cos + (u * phi.cos() + v * phi.sin()) * sin
}

/// The state at frame 0: the bursts at or before it, born at time 0.
pub fn start(timeline: &dyn Timeline) -> State {
    let now = Instant::at(timeline, 0.0);
    let mut state = State {
        frame: 0,
        owed: 0.0,
        next_id: 0,
        particles: Vec::new(),
    };
    let count: u64 = (now.life().bursts.iter())
        .filter(|b| b.frame <= 0.0)
        .map(|b| b.count as u64)
        .sum();
    let h = substep_length(timeline);
    for _ in 0..count {
        if let Some(p) = state.birth(&now, &now, 0.0, 1.0, h) {
            state.particles.push(p);
        }
    }
    state
}

fn substep_length(timeline: &dyn Timeline) -> f64 {
    1.0 / (timeline.frame_rate() * SUBSTEPS as f64)
}

/// The state one frame later.
pub fn advance(state: &State, timeline: &dyn Timeline) -> State {
    let mut next = state.clone();
    let h = substep_length(timeline);
    let mut before = Instant::at(timeline, state.frame as f64);
    for k in 0..SUBSTEPS {
        let j = state.frame as u64 * SUBSTEPS as u64 + k as u64;
        let end_frame = (j + 1) as f64 / SUBSTEPS as f64;
        let after = Instant::at(timeline, end_frame);
        next.substep(&before, &after, j, h, timeline);
        before = after;
    }
    next.frame = state.frame + 1;
    next
}

impl State {
    /// Substep `j`, from time `j h` to `(j + 1) h`: the particles move and age, the ones born in it join, the
    /// ones whose life ends in it go.
    fn substep(
        &mut self,
        before: &Instant,
        after: &Instant,
        j: u64,
        h: f64,
        timeline: &dyn Timeline,
    ) {
        let (t0, t1) = (j as f64 * h, (j + 1) as f64 * h);
        let life = after.life();
        let seed = after.world.emitter.seed;
        let motion = Motion::of(life, seed);
        move_all(&mut self.particles, &motion, t0, h);
        self.particles.retain(|p| p.born + p.lifetime > t1);
        // Births owed to the rate (trapezoidal in the keyed rate), at the times the owed count passes each whole
        // number; then the bursts of frames in (t0, t1].
        let owed = self.owed + 0.5 * (before.life().rate + life.rate) * h;
        let mut births: Vec<f64> = Vec::new();
        // A whole number passed to within rounding counts as passed, so that a steady rate makes its count on
        // the frame it is due however its per-substep share rounds.
        if owed > self.owed {
            let first = (self.owed + 1e-9).floor() as u64 + 1;
            let last = (owed + 1e-9).floor() as u64;
            // Births past the room the set has left are skipped, their numbers used all the same (a rate keyed
            // beyond reason costs no memory).
            let room = MAX_ALIVE.saturating_sub(self.particles.len()) as u64;
            let listed = last.saturating_sub(first - 1).min(room);
            for m in first..first + listed {
                births.push(t0 + h * ((m as f64 - self.owed) / (owed - self.owed)).clamp(0.0, 1.0));
            }
            self.next_id += last.saturating_sub(first - 1) - listed;
        }
        self.owed = owed;
        // A burst's substep by its frame, exact for whole frames.
        let fps = timeline.frame_rate();
        let s = SUBSTEPS as f64;
        for b in &life.bursts {
            if b.frame * s > j as f64 && b.frame * s <= (j + 1) as f64 {
                let t = (b.frame / fps).clamp(t0, t1);
                births.extend(std::iter::repeat_n(t, b.count as usize));
            }
        }
        for t in births {
            let share = ((t - t0) / h).clamp(0.0, 1.0);
            if let Some(mut p) = self.birth(before, after, t, share, h) {
                let rest = t1 - t;
                if rest > 0.0 {
                    motion.step(&mut p, t, rest);
                }
                if p.born + p.lifetime > t1 {
                    self.particles.push(p);
                }
            }
        }
    }

    /// Particle `next_id` born at time `t`, `share` of the way from `before` to `after` (`h` apart). None (its number used all the same) where the set is full, the shape names
    /// nothing, or a pulse it must follow is not lit where it was drawn.
    fn birth(
        &mut self,
        before: &Instant,
        after: &Instant,
        t: f64,
        share: f64,
        h: f64,
    ) -> Option<LiveParticle> {
        let id = self.next_id;
        self.next_id += 1;
        if self.particles.len() >= MAX_ALIVE {
            return None;
        }
        let emitter = &after.world.emitter;
        let life = after.life();
        let (Some(p0), Some(p1)) = (&before.placement, &after.placement) else {
            return None;
        };
        let mut rng = particle_rng(emitter.seed, id);
        let draw = p1.sample(&mut rng);
        if life.along_pulse {
            // Born where the chain is lit, as often as it is: kept with probability min(1, W(t)) at its draw's
            // chain parameter, so that the rate is a fully lit chain's.
            let weights = match emitter.shape {
                super::emit::EmitterShape::Curve { curve, .. } => {
                    after.world.sources.curves.get(curve).map(|c| &c.weights)
                }
                _ => None,
            };
            let w = match (weights, p1.chain_parameter(&draw)) {
                (Some(w), Some(t)) => wseries::evaluate(w, t).clamp(0.0, 1.0),
                _ => 1.0,
            };
            if rng.unit() >= w {
                return None;
            }
        }
        let (a, b): (Spot, Spot) = (p0.place(&draw), p1.place(&draw));
        let position = a.position.lerp(b.position, share);
        let carried = (b.position - a.position) / h;
        let axis = match life.direction {
            Direction::Normal => b.normal,
            Direction::Tangent => b.tangent,
            Direction::Outward => b.outward,
            Direction::Fixed(d) => d,
        };
        let lifetime = life.lifetime.draw(&mut rng).max(1e-9);
        let radius = emitter.radius.draw(&mut rng);
        let density = emitter.density.draw(&mut rng);
        let speed = life.speed.draw(&mut rng);
        let direction = in_cone(axis, life.cone, &mut rng);
        Some(LiveParticle {
            position,
            velocity: direction * speed + carried * life.inherit,
            born: t,
            lifetime,
            radius,
            density,
            color: emitter.color,
            id,
        })
    }

    /// How many particles the set has made by this state's frame (alive or not, and the ones a pulse did not
    /// let be born).
    pub fn born(&self) -> u64 {
        self.next_id
    }

    /// The particles as the renderers draw them at this state's frame: radius, density and color at each one's
    /// age by its curves (the ones of no size or density left out). With a `shutter` (`Life::shutter`; the
    /// simulation's timeline reads none), each one is drawn as copies along its path over it, as many as
    /// `blur_copies` gives with at most `room` copies more than particles in all.
    pub fn particles(&self, timeline: &dyn Timeline, shutter: f64, room: usize) -> Vec<Particle> {
        let now = timeline.world(self.frame as f64);
        let Some(life) = now.emitter.life.as_deref() else {
            return Vec::new();
        };
        let t = self.frame as f64 / timeline.frame_rate();
        let drawn = |p: &LiveParticle, position: DVec3, age: f64, share: f64| {
            let radius = p.radius * life.size.at(age);
            let density = p.density * life.opacity.at(age) * share;
            (radius > 1e-9 && density > 0.0).then(|| Particle {
                position,
                radius,
                density,
                color: life.colors.at(age).unwrap_or(p.color),
                emission: (life.emission_colors.at(age).unwrap_or([1.0; 3]))
                    .map(|c| c * life.emission.at(age)),
            })
        };
        let open = shutter / timeline.frame_rate();
        if !(open > 0.0) {
            return (self.particles.iter())
                .filter_map(|p| {
                    let age = ((t - p.born) / p.lifetime).clamp(0.0, 1.0);
                    drawn(p, p.position, age, 1.0)
                })
                .collect();
        }
        let motion = Motion::of(life, now.emitter.seed);
        let drifts: Vec<DVec3> = (self.particles.iter())
            .map(|p| motion.drift(p.position, t))
            .collect();
        let copies = blur_copies(&self.particles, &drifts, life, &motion, t, open, room);
        // A copy outside the particle's life (born or gone while the shutter is open) is not drawn: its share of
        // the shutter shows nothing there.
        let mut out = Vec::new();
        for ((p, k), &drift) in self.particles.iter().zip(copies).zip(&drifts) {
            for i in 0..k {
                let tau = open * ((i as f64 + 0.5) / k as f64 - 0.5);
                let age = (t + tau - p.born) / p.lifetime;
                let position = motion.path(p, drift, tau, open);
                if (0.0..=1.0).contains(&age) && position.is_finite() {
                    out.extend(drawn(p, position, age, 1.0 / k as f64));
                }
            }
        }
        out
    }
}

/// The most copies a particle is drawn as over the shutter.
pub const MAX_COPIES: u32 = 32;

/// The farthest apart, in radii, two copies of a particle along its path over the shutter lie. The optical depth
/// the copies give a ray across the streak then ripples along it by at most 1.1 % of the shutter's average (4.7 %
/// at half a radius, 0.36 % at an eighth: the kernel's cut at the ball's edge makes the sum converge slowly).
pub const COPY_SPACING: f64 = 0.25;

/// The chords a particle's path over the shutter is measured along (`blur_copies`).
const PATH_CHORDS: u32 = 8;

/// How many copies each of `particles` is drawn as over a shutter `open` seconds long centred on time `t`: its
/// path's length over it (`PATH_CHORDS` times the longest of as many chords) in `COPY_SPACING` of its smallest
/// radius there (the size curve is linear between its keys: its least at the shutter's ends or a key within it),
/// at least 1 and at most `MAX_COPIES`; fewer for all, evenly, where they would add more than `room` copies to
/// the particles. `drifts`: the turbulence's velocity at each particle (`Motion::drift`).
fn blur_copies(
    particles: &[LiveParticle],
    drifts: &[DVec3],
    life: &Life,
    motion: &Motion,
    t: f64,
    open: f64,
    room: usize,
) -> Vec<u32> {
    let wanted: Vec<u32> = (particles.iter().zip(drifts))
        .map(|(p, &drift)| {
            let age = |tau: f64| ((t + tau - p.born) / p.lifetime).clamp(0.0, 1.0);
            let (first, last) = (age(-0.5 * open), age(0.5 * open));
            let keys = (life.size.keys.iter()).map(|k| k.0);
            let smallest = ([first, last].into_iter())
                .chain(keys.filter(|a| (first..=last).contains(a)))
                .map(|a| p.radius * life.size.at(a))
                .filter(|&r| r > 1e-9)
                .fold(f64::INFINITY, f64::min);
            let at = |i: u32| {
                let tau = open * (i as f64 / PATH_CHORDS as f64 - 0.5);
                motion.path(p, drift, tau, open)
            };
            // The longest chord sets the spacing: a path slowed by a drag or bent by gravity is not walked
            // evenly in time, and the copies are even in time.
            let longest = (0..PATH_CHORDS)
                .map(|i| (at(i + 1) - at(i)).length())
                .fold(0.0, f64::max);
            let length = longest * PATH_CHORDS as f64;
            let k = (length / (COPY_SPACING * smallest)).ceil();
            if k.is_finite() {
                k.clamp(1.0, MAX_COPIES as f64) as u32
            } else {
                1
            }
        })
        .collect();
    let extra: u64 = wanted.iter().map(|&k| k as u64 - 1).sum();
    if extra <= room as u64 {
        return wanted;
    }
    let scale = room as f64 / extra as f64;
    (wanted.into_iter())
        .map(|k| 1 + ((k - 1) as f64 * scale).floor() as u32)
        .collect()
}

/// What moves the particles over one substep.
struct Motion {
    acceleration: DVec3,
    drag: f64,
    turbulence: Option<Turbulence>,
    seed: u64,
}

impl Motion {
    fn of(life: &Life, seed: u64) -> Motion {
        Motion {
            acceleration: life.acceleration,
            drag: life.drag,
            turbulence: life.turbulence,
            seed: seed ^ 0x7f4a_7c15_9e37_79b9,
        }
    }

    /// The turbulence's velocity at `x` at time `t` (none without one).
    fn drift(&self, x: DVec3, t: f64) -> DVec3 {
        (self.turbulence.as_ref()).map_or(DVec3::ZERO, |u| u.velocity(x, t, self.seed))
    }

    /// Where `p` is `tau` after now (of either sign, within a shutter `open` seconds long) by its own velocity,
    /// the acceleration and the drag exactly, and `drift`, the turbulence's velocity where it is now
    /// (`Motion::drift`: the path the shutter stretches it along). Backwards a drag is taken at most `2 / open`: the exact form
    /// multiplies the velocity's departure from `acceleration / drag` by `e^(drag |tau|)`, and for a particle
    /// at its terminal velocity that departure is rounding, which a strong drag would carry anywhere.
    fn path(&self, p: &LiveParticle, drift: DVec3, tau: f64, open: f64) -> DVec3 {
        let drag = if tau < 0.0 {
            self.drag.min(2.0 / open)
        } else {
            self.drag
        };
        let (x, _) = ballistic(p.position, p.velocity, self.acceleration, drag, tau);
        x + drift * tau
    }

    /// `p` moved from time `t` by `dt`.
    fn step(&self, p: &mut LiveParticle, t: f64, dt: f64) {
        let (x, v) = ballistic(p.position, p.velocity, self.acceleration, self.drag, dt);
        p.position = x;
        p.velocity = v;
        if let Some(turbulence) = &self.turbulence {
            p.position = advect(turbulence, self.seed, p.position, t, dt);
        }
    }
}

/// `x` carried by the turbulence from time `t` for `dt`, by the midpoint rule (the simulation's own step; `seed`
/// is the set's turbulence seed).
pub fn advect(turbulence: &Turbulence, seed: u64, x: DVec3, t: f64, dt: f64) -> DVec3 {
    let u0 = turbulence.velocity(x, t, seed);
    let mid = x + u0 * (0.5 * dt);
    x + turbulence.velocity(mid, t + 0.5 * dt, seed) * dt
}

/// Position and velocity after `dt` under constant acceleration `a` and linear drag `k`, exact.
pub fn ballistic(x: DVec3, v: DVec3, a: DVec3, k: f64, dt: f64) -> (DVec3, DVec3) {
    if k <= 0.0 {
        return (x + v * dt + a * (0.5 * dt * dt), v + a * dt);
    }
    let terminal = a / k;
    let decay = (-k * dt).exp();
    // (1 - e^(-k dt)) / k without cancellation for a small k dt.
    let gone = -(-k * dt).exp_m1() / k;
    (
        x + terminal * dt + (v - terminal) * gone,
        terminal + (v - terminal) * decay,
    )
}

/// Every particle moved by one substep from `t` (on every core where there are many: each particle alone, so the
/// result does not depend on how they are split).
fn move_all(particles: &mut [LiveParticle], motion: &Motion, t: f64, h: f64) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    if particles.len() < 4096 || threads < 2 {
        for p in particles.iter_mut() {
            motion.step(p, t, h);
        }
        return;
    }
    let chunk = particles.len().div_ceil(threads);
    std::thread::scope(|scope| {
        for part in particles.chunks_mut(chunk) {
            scope.spawn(move || {
                for p in part {
                    motion.step(p, t, h);
                }
            });
        }
    });
}
