//! The papers' integrator, the f64 twin of `shaders/simpson.wgsl` (entry point `integrate`): `n + 1` evenly spaced
//! samples of psi along the ray by Simpson's rule, or, with jitter, the randomly shifted rectangle rule with the
//! texel's offset (METHOD.md section 3, thesis 3.29-3.33). And Simpson's rule refined where it has not converged,
//! the rule of the converged reference (`converged`).

use glam::DVec3;

use crate::field::{Curve, Sources, falloff};
use crate::integrate::{Decay, Integration, zeta};

/// The brightness B of the segment from `s` to `e` by the papers' rule with the settings' `divisions`:
/// Simpson's, or the shifted rectangle rule with offset `xi` where the settings jitter. With the distance decay the
/// sum over the sources is taken inside the integral; with the rms decay each term is its own integral.
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3, xi: f64) -> f64 {
    let field = sources.field();
    match settings.decay {
        Decay::Distance => along_ray(settings, (s, e), xi, |p| field.psi(p, settings.epsilon)),
        Decay::Rms => (0..sources.len())
            .map(|k| {
                settings.finish(
                    along_ray(settings, (s, e), xi, |p| field.term(k, p, settings.epsilon)),
                    sources.coefficient(k),
                )
            })
            .sum(),
    }
}

/// The papers' rule (and the shifted rectangle rule with jitter): `simpson.wgsl`'s twin.
pub struct Simpson;

impl super::TermIntegrator for Simpson {
    /// The part of B of term `k` of psi alone (`Sources::term`), by the same rule as `brightness`.
    fn term_brightness(
        &self,
        sources: &Sources,
        k: usize,
        settings: &Integration,
        ray: super::TexelRay,
    ) -> f64 {
        let field = sources.field();
        settings.finish(
            along_ray(settings, (ray.start, ray.end), ray.xi, |p| {
                field.term(k, p, settings.epsilon)
            }),
            sources.coefficient(k),
        )
    }
}

/// Curve `c`'s term to the decay's power (`Integration::power`) without its W series, times `weight(t)` at the
/// point the term reads (`Curve::point_seen`: the nearest point, or the brightest in the continuous form), by the
/// same rule as `brightness`: the integral of `(b falloff zeta)^power weight(t)`, with `weight` the W series (to
/// the same power) times whatever the caller weighs it with.
pub fn curve_weighted(
    c: &Curve,
    settings: &Integration,
    (s, e): (DVec3, DVec3),
    xi: f64,
    weight: &dyn Fn(f64) -> f64,
) -> f64 {
    let pieces = c.pieces();
    let power = settings.power();
    let f = |t: f64| {
        let n = c.point_seen(&pieces, s + (e - s) * t, settings.epsilon);
        let x = c.coefficient
            * falloff(n.distance, settings.epsilon)
            * zeta(t, settings.alpha, settings.beta);
        x.powi(power) * weight(n.t)
    };
    by_rule(settings, xi, f)
}

/// The integral over [0, 1] of `(field((1 - t) S + t E) zeta(t))^power` (the decay's power) by the settings' rule:
/// Simpson's, or the shifted rectangle rule with offset `xi` where they jitter.
fn along_ray(
    settings: &Integration,
    (s, e): (DVec3, DVec3),
    xi: f64,
    field: impl Fn(DVec3) -> f64,
) -> f64 {
    let power = settings.power();
    by_rule(settings, xi, |t: f64| {
        (field(s + (e - s) * t) * zeta(t, settings.alpha, settings.beta)).powi(power)
    })
}

/// The integral over [0, 1] of `f` by the settings' rule.
fn by_rule(settings: &Integration, xi: f64, f: impl Fn(f64) -> f64) -> f64 {
    match settings.jitter {
        None => simpson(f, settings.divisions),
        Some(_) => shifted_rectangle(f, settings.divisions, xi),
    }
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

/// Simpson's rule over [0, 1] refined where it has not converged: n = `divisions` evenly spaced samples, each
/// pair of intervals then checked against its halves and split again (adaptive Simpson, with the Richardson
/// term) until the estimated error is at most `tolerance` times the interval's width, or after `max_depth`
/// splits. The error of the whole is then about `tolerance`. Returns B and the evaluations of `f` spent. For a
/// reference: a uniform n leaves a source's near passes (a peak narrower than a few steps) and the steps of the
/// integrand where a curve's nearest point jumps unconverged; refining only there costs little.
pub fn simpson_refined(
    f: impl Fn(f64) -> f64,
    divisions: u32,
    tolerance: f64,
    max_depth: u32,
) -> (f64, u64) {
    debug_assert!(divisions >= 2 && divisions.is_multiple_of(2));
    struct Refine<F> {
        f: F,
        tolerance: f64,
        evaluations: u64,
    }
    impl<F: Fn(f64) -> f64> Refine<F> {
        /// [a, b] with f at its ends and middle, and its Simpson value `whole`.
        #[allow(clippy::too_many_arguments)]
        fn interval(
            &mut self,
            a: f64,
            b: f64,
            fa: f64,
            fm: f64,
            fb: f64,
            whole: f64,
            depth: u32,
        ) -> f64 {
            let m = 0.5 * (a + b);
            let (fl, fr) = ((self.f)(0.5 * (a + m)), (self.f)(0.5 * (m + b)));
            self.evaluations += 2;
            let left = (m - a) / 6.0 * (fa + 4.0 * fl + fm);
            let right = (b - m) / 6.0 * (fm + 4.0 * fr + fb);
            let delta = left + right - whole;
            if depth == 0 || delta.abs() <= 15.0 * self.tolerance * (b - a) {
                return left + right + delta / 15.0;
            }
            self.interval(a, m, fa, fl, fm, left, depth - 1)
                + self.interval(m, b, fm, fr, fb, right, depth - 1)
        }
    }
    let n = divisions as usize;
    let samples: Vec<f64> = (0..=n).map(|k| f(k as f64 / n as f64)).collect();
    let mut r = Refine {
        f,
        tolerance,
        evaluations: samples.len() as u64,
    };
    let h = 1.0 / n as f64;
    let value = (0..n / 2)
        .map(|p| {
            let (a, b) = ((2 * p) as f64 * h, (2 * p + 2) as f64 * h);
            let (fa, fm, fb) = (samples[2 * p], samples[2 * p + 1], samples[2 * p + 2]);
            let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
            r.interval(a, b, fa, fm, fb, whole, max_depth)
        })
        .sum();
    (value, r.evaluations)
}

/// The randomly shifted rectangle rule over [0, 1]: `(1 / n) sum_k f((k + xi) / n)`, `0 <= xi < 1`. Its mean
/// over a uniform `xi` is the integral itself.
pub fn shifted_rectangle(f: impl Fn(f64) -> f64, n: u32, xi: f64) -> f64 {
    let nf = n as f64;
    (0..n).map(|k| f((k as f64 + xi) / nf)).sum::<f64>() / nf
}

/// A texel's random offset in [0, 1) for `seed`: a PCG hash of texel and seed, the same on the GPU.
pub fn jitter_offset(seed: u32, i: u32, j: u32, w: u32) -> f64 {
    let index = j.wrapping_mul(w).wrapping_add(i);
    let h = pcg_hash(index ^ pcg_hash(seed.wrapping_add(0x9e37_79b9)));
    (h >> 8) as f64 / (1u32 << 24) as f64
}

/// The PCG hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", 2020).
pub fn pcg_hash(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}
