//! Curl noise (Bridson, Hourihan and Nordenstam 2007): a turbulent velocity field that is divergence free by
//! construction, so that smoke advected by it curls and never gathers into sinks or thins out of sources.
//!
//! The field is the curl of a vector potential whose three components are smooth value noises (a hashed value
//! at each integer lattice point, blended by the quintic fade `6t^5 - 15t^4 + 10t^3`, so that the potential is
//! C2 and its mixed second derivatives commute: `div curl = 0` holds point by point, not only on average). The
//! potential's gradients are analytic. It evolves in time by blending the potentials of consecutive integer
//! time slices (each its own lattice) with the same fade: every blend of curls is a curl, so the field stays
//! divergence free at every instant.

use glam::DVec3;

use crate::noise::noise_with_gradient;

/// Seeds of a potential's three components at time slice `slice`.
fn slice_seeds(seed: u64, slice: i64) -> [u64; 3] {
    let base = seed ^ (slice as u64).wrapping_mul(0xd6e8_feb8_6659_fd93);
    [
        base,
        base ^ 0x5851_f42d_4c95_7f2d,
        base ^ 0x1405_7b7e_f767_814f,
    ]
}

/// The curl of the potential of one time slice at `p` (lattice units).
fn slice_curl(p: DVec3, seed: u64, slice: i64) -> DVec3 {
    let [a, b, c] = slice_seeds(seed, slice);
    let (_, gx) = noise_with_gradient(p, a);
    let (_, gy) = noise_with_gradient(p, b);
    let (_, gz) = noise_with_gradient(p, c);
    // curl (Px, Py, Pz) = (dPz/dy - dPy/dz, dPx/dz - dPz/dx, dPy/dx - dPx/dy)
    DVec3::new(gz.y - gy.z, gx.z - gz.x, gy.x - gx.y)
}

/// A turbulent field: `strength` scene units per second (its root-mean-square speed), lattice cells `scale`
/// scene units across, changing `speed` times a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turbulence {
    /// The size of its eddies, scene units (> 0).
    pub scale: f64,
    /// Its root-mean-square speed, scene units per second (>= 0).
    pub strength: f64,
    /// How fast it changes: time slices per second (>= 0; 0: a still field).
    pub speed: f64,
}

/// The root-mean-square speed of the raw curl of the noise potential (measured over 20,000 points: 1.87; its
/// peaks reach about 2.8 times it): the factor that makes `strength` the field's RMS speed.
const RMS: f64 = 1.87;

impl Turbulence {
    /// The velocity at `x` (scene units) and time `t` (seconds): divergence free in `x` at every `t`.
    pub fn velocity(&self, x: DVec3, t: f64, seed: u64) -> DVec3 {
        let p = x / self.scale;
        let time = self.speed * t;
        let slice = time.floor();
        let f = time - slice;
        let s = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
        let slice = slice as i64;
        let now = slice_curl(p, seed, slice);
        let curl = if s > 0.0 {
            now * (1.0 - s) + slice_curl(p, seed, slice + 1) * s
        } else {
            now
        };
        curl * (self.strength / RMS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_gradient_matches_differences() {
        let h = 1e-6;
        for i in 0..200 {
            let p = DVec3::new(
                i as f64 * 0.137 - 7.0,
                i as f64 * 0.071 + 0.3,
                -(i as f64) * 0.093,
            );
            let (_, g) = noise_with_gradient(p, 11);
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                let d = (noise_with_gradient(p + axis * h, 11).0
                    - noise_with_gradient(p - axis * h, 11).0)
                    / (2.0 * h);
                assert!((d - g.dot(axis)).abs() < 1e-6, "{p} {d} {}", g.dot(axis));
            }
        }
    }

    #[test]
    fn values_stay_in_range_and_differ_by_seed() {
        let mut seen = [f64::INFINITY, f64::NEG_INFINITY];
        for i in 0..5000 {
            let p = DVec3::new(i as f64 * 0.31, i as f64 * 0.17, i as f64 * 0.07);
            let (v, _) = noise_with_gradient(p, 3);
            assert!((-1.0..=1.0).contains(&v));
            seen = [seen[0].min(v), seen[1].max(v)];
        }
        assert!(seen[0] < -0.5 && seen[1] > 0.5, "{seen:?}");
        let p = DVec3::new(0.4, 0.6, 0.2);
        assert_ne!(noise_with_gradient(p, 1).0, noise_with_gradient(p, 2).0);
    }
}
