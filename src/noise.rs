//! Value noise: a hashed value at each integer lattice point in [-1, 1], blended by the quintic fade
//! `6t^5 - 15t^4 + 10t^3` (C2, so that its mixed second derivatives commute), with its analytic gradient. The
//! curl noise of live particles (`particles::curl`) takes the curl of three of them; a translucent object's
//! extinction is varied by one (`objects::translucent::Noise`).

use glam::DVec3;

/// A value noise on the integer lattice with its gradient: `(value, d/dx, d/dy, d/dz)`, the value in [-1, 1].
pub fn noise_with_gradient(p: DVec3, seed: u64) -> (f64, DVec3) {
    let base = p.floor();
    let f = p - base;
    let (ix, iy, iz) = (base.x as i64, base.y as i64, base.z as i64);
    let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let slope = |t: f64| 30.0 * t * t * (t * (t - 2.0) + 1.0);
    let (u, v, w) = (fade(f.x), fade(f.y), fade(f.z));
    let (du, dv, dw) = (slope(f.x), slope(f.y), slope(f.z));
    let c = |dx: i64, dy: i64, dz: i64| lattice(ix + dx, iy + dy, iz + dz, seed);
    let (c000, c100, c010, c110) = (c(0, 0, 0), c(1, 0, 0), c(0, 1, 0), c(1, 1, 0));
    let (c001, c101, c011, c111) = (c(0, 0, 1), c(1, 0, 1), c(0, 1, 1), c(1, 1, 1));
    // The trilinear blend of the corners written out as a polynomial in the faded coordinates.
    let k0 = c000;
    let k1 = c100 - c000;
    let k2 = c010 - c000;
    let k3 = c001 - c000;
    let k4 = c000 - c100 - c010 + c110;
    let k5 = c000 - c010 - c001 + c011;
    let k6 = c000 - c100 - c001 + c101;
    let k7 = -c000 + c100 + c010 - c110 + c001 - c101 - c011 + c111;
    let value =
        k0 + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
    let gradient = DVec3::new(
        du * (k1 + k4 * v + k6 * w + k7 * v * w),
        dv * (k2 + k5 * w + k4 * u + k7 * w * u),
        dw * (k3 + k6 * u + k5 * v + k7 * u * v),
    );
    (value, gradient)
}

/// The hashed value at a lattice point, in [-1, 1]: the same on every machine (integer arithmetic only).
fn lattice(x: i64, y: i64, z: i64, seed: u64) -> f64 {
    let mut h = seed
        ^ (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (y as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ (z as u64).wrapping_mul(0x1656_67b1_9e37_79f9);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
