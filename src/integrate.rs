//! Integration along a texel's ray: the decay zeta and Simpson's rule (METHOD.md section 3, thesis 3.29-3.33).

use glam::DVec3;

use crate::field::Sources;

/// The integration settings of a scene (the papers use `alpha = beta = 1`, `nu = 2`, `n = 200`).
#[derive(Clone, Debug, PartialEq)]
pub struct Integration {
    /// Simpson's division count n: even, at least 2.
    pub divisions: u32,
    /// How far the segment reaches: `E = V + nu (S - V)`, nu > 1.
    pub nu: f64,
    pub alpha: f64,
    pub beta: f64,
    /// The distance clamp of every source's `1 / max(eps, d)`.
    pub epsilon: f64,
}

impl Default for Integration {
    fn default() -> Self {
        Self {
            divisions: 200,
            nu: 2.0,
            alpha: 1.0,
            beta: 1.0,
            epsilon: 0.01,
        }
    }
}

/// The decay `zeta(s) = alpha / (s + beta)^2` (3.31).
pub fn zeta(s: f64, alpha: f64, beta: f64) -> f64 {
    alpha / ((s + beta) * (s + beta))
}

/// Simpson's rule over [0, 1] with `n` (even) divisions, samples `k = 0..=n` (3.33, corrected to end at
/// s = 1): `(1 / 3n) (f_0 + 4 f_1 + 2 f_2 + ... + 4 f_{n-1} + f_n)`.
pub fn simpson(f: impl Fn(f64) -> f64, n: u32) -> f64 {
    debug_assert!(n >= 2 && n.is_multiple_of(2));
    let nf = n as f64;
    let mut sum = f(0.0) + f(1.0);
    for k in 1..n {
        let weight = if k % 2 == 1 { 4.0 } else { 2.0 };
        sum += weight * f(k as f64 / nf);
    }
    sum / (3.0 * nf)
}

/// The brightness B of the segment from `s` to `e` (3.30): the integral over [0, 1] of
/// `psi((1 - t) S + t E) zeta(t)`, by Simpson's rule.
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    simpson(
        |t| sources.psi(s + (e - s) * t, settings.epsilon) * zeta(t, settings.alpha, settings.beta),
        settings.divisions,
    )
}
