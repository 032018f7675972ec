//! Integration along a texel's ray: the settings, the decay zeta, Simpson's rule and the shifted rectangle rule
//! (METHOD.md section 3, thesis 3.29-3.33), and a point's or a line's term in closed form. The dispatch over the
//! integrators is `reference::brightness`.

/// How B is integrated along a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// The papers' method: n + 1 evenly spaced samples of psi, Simpson's rule (or, with jitter, the randomly
    /// shifted rectangle rule).
    Simpson,
    /// Source by source, samples packed around the ray's closest approach, to a tolerance
    /// (`crate::adaptive`).
    #[default]
    Adaptive,
}

impl Integrator {
    /// The name used in scene files, on the command line and in the viewer.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Simpson => "simpson",
            Integrator::Adaptive => "adaptive",
        }
    }
}

/// The integration settings of a scene (the papers use `alpha = beta = 1`, `nu = 2`, `n = 200`; their nu sets
/// the decay length `(nu - 1) p` for a billboard `p` from the eye, `geometry::papers_decay_length`).
#[derive(Clone, Debug, PartialEq)]
pub struct Integration {
    pub integrator: Integrator,
    /// Simpson's division count n: even, at least 2 (the `simpson` integrator).
    pub divisions: u32,
    /// Absolute error allowed on B (the `adaptive` integrator), shared between the sources.
    pub tolerance: f64,
    /// Random sample placement for the `simpson` integrator, with this seed: each texel's n samples are
    /// shifted by a random fraction of a step, which turns banding into fine noise and is unbiased.
    pub jitter: Option<u32>,
    /// The depth past the billboard, in scene units, over which the decay `zeta = alpha / (sigma + beta)^2`
    /// runs from sigma = 0 to 1; rays reach at least this far and past the far side of the effect
    /// (`geometry::ray_reach`). Fixed in space, so the look holds as the camera moves.
    pub decay_length: f64,
    pub alpha: f64,
    pub beta: f64,
    /// The distance clamp of every source's `1 / max(eps, d)`.
    pub epsilon: f64,
}

/// The decay length of settings built in code (scene files derive theirs from their camera): the papers'
/// nu = 2 at a billboard 10 units from the eye.
pub const DEFAULT_DECAY_LENGTH: f64 = 10.0;

/// The adaptive integrator's default tolerance: well under the 1/255 step of an 8-bit image.
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

impl Default for Integration {
    fn default() -> Self {
        Self {
            integrator: Integrator::default(),
            divisions: 200,
            tolerance: DEFAULT_TOLERANCE,
            jitter: None,
            decay_length: DEFAULT_DECAY_LENGTH,
            alpha: 1.0,
            beta: 1.0,
            epsilon: 0.01,
        }
    }
}

impl Integration {
    /// The settings the integrators see on a ray that spans `stretch` decay lengths, integrated over the
    /// method's s in [0, 1] (`geometry::Reach`): `alpha / (sigma + beta)^2` with `sigma = stretch s` and
    /// `d sigma = stretch ds` is `(alpha / stretch) / (s + beta / stretch)^2`.
    pub fn on_ray(&self, stretch: f64) -> Integration {
        Integration {
            alpha: self.alpha / stretch,
            beta: self.beta / stretch,
            ..self.clone()
        }
    }
}

/// The decay `zeta(s) = alpha / (s + beta)^2` (3.31).
pub fn zeta(s: f64, alpha: f64, beta: f64) -> f64 {
    alpha / ((s + beta) * (s + beta))
}

/// The term of a point or a line in closed form: the integral over s in [0, 1] of `zeta(s) / max(eps, d(s))`
/// for a squared distance along the ray `d(s)^2 = h2 + a (s - c)^2` (closest approach `c`, its squared distance
/// `h2`), with no samples at all. Where `d < eps` (around `c` when `h2 < eps^2`) the integrand is
/// `alpha / (eps (s + beta)^2)`. Elsewhere, with `w = s + beta`, `u = 1 / w` turns `ds / (w^2 d)` into
/// `-u du / sqrt(Q(u))` for the quadratic `Q(u) = A u^2 + 2 B u + a`, `A = d(-beta)^2 = a (c + beta)^2 + h2`,
/// `B = -a (c + beta)`, whose antiderivative is `I(u) = (r - B ln(X + r)) / A^(3/2)` with `X = A u + B` and
/// `r = sqrt(X^2 + a h2)` (docs/METHOD.md, "Points and lines in closed form"). The differences of `r` and of
/// the logarithm are taken without cancellation. `None` where the two parts of `I`'s difference cancel to more
/// than `1 / condition` of their size (a source near the decay's pole at `s = -beta`, where A vanishes): the
/// caller integrates numerically there.
pub fn falloff_integral(
    c: f64,
    h2: f64,
    a: f64,
    eps: f64,
    alpha: f64,
    beta: f64,
    condition: f64,
) -> Option<f64> {
    let h2 = h2.max(0.0);
    // 1 / (lo + beta) - 1 / (hi + beta), without the difference's cancellation on a short stretch.
    let decay = |lo: f64, hi: f64| (hi - lo) / ((lo + beta) * (hi + beta));
    if a <= 0.0 {
        // d does not change along the ray (a line parallel to it, or a ray of no length).
        return Some(alpha * decay(0.0, 1.0) / h2.sqrt().max(eps));
    }
    // The stretch where d < eps, clamped to the ray.
    let half = if h2 < eps * eps {
        ((eps * eps - h2) / a).sqrt()
    } else {
        0.0
    };
    let (flat_lo, flat_hi) = ((c - half).clamp(0.0, 1.0), (c + half).clamp(0.0, 1.0));
    let mut sum = if half > 0.0 {
        alpha * decay(flat_lo, flat_hi) / eps
    } else {
        0.0
    };
    let w_c = c + beta;
    let big_a = a * w_c * w_c + h2;
    let big_b = -a * w_c;
    let k = a * h2;
    let piece = |lo: f64, hi: f64| -> Option<f64> {
        if hi <= lo {
            return Some(0.0);
        }
        // u runs from u_b = 1 / (hi + beta) up to u_a = 1 / (lo + beta).
        let (u_a, u_b) = (1.0 / (lo + beta), 1.0 / (hi + beta));
        // X = A u + B = (a (c + beta) (c - s) + h2) / (s + beta), without A u and B's cancellation.
        let x = |s: f64, u: f64| (a * w_c * (c - s) + h2) * u;
        let (x_a, x_b) = (x(lo, u_a), x(hi, u_b));
        let (r_a, r_b) = ((x_a * x_a + k).sqrt(), (x_b * x_b + k).sqrt());
        let dx = big_a * (hi - lo) * u_a * u_b;
        let dr = dx * (x_a + x_b) / (r_a + r_b);
        // ln((X_a + r_a) / (X_b + r_b)), each X + r written as k / (r - X) where X < 0.
        let log = if x_a < 0.0 && x_b < 0.0 {
            ((r_b - x_b) / (r_a - x_a)).ln()
        } else {
            let p = |x: f64, r: f64| if x >= 0.0 { x + r } else { k / (r - x) };
            (p(x_a, r_a) / p(x_b, r_b)).ln()
        };
        let bracket = dr - big_b * log;
        let size = dr.abs() + (big_b * log).abs();
        if !(bracket.is_finite() && bracket.abs() * condition >= size) {
            return None;
        }
        Some(alpha * bracket / (big_a * big_a.sqrt()))
    };
    if half > 0.0 {
        sum += piece(0.0, flat_lo)? + piece(flat_hi, 1.0)?;
    } else {
        sum += piece(0.0, 1.0)?;
    }
    Some(sum)
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A small deterministic generator (xorshift64*).
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn vec(&mut self, scale: f64) -> DVec3 {
            DVec3::new(self.unit() - 0.5, self.unit() - 0.5, self.unit() - 0.5) * 2.0 * scale
        }
    }

    /// A point source's term along the ray from `s` to `e`, in closed form.
    fn closed(s: DVec3, e: DVec3, x: DVec3, eps: f64, alpha: f64, beta: f64) -> Option<f64> {
        let d = e - s;
        let a = d.length_squared();
        let c = if a > 0.0 { (x - s).dot(d) / a } else { 0.0 };
        let h2 = (s + d * c - x).length_squared();
        falloff_integral(c, h2, a, eps, alpha, beta, 1e6)
    }

    /// The same term by brute force: Simpson on the distance itself, refined where it has not converged.
    fn brute(s: DVec3, e: DVec3, x: DVec3, eps: f64, alpha: f64, beta: f64) -> f64 {
        let f = |t: f64| zeta(t, alpha, beta) / (s + (e - s) * t - x).length().max(eps);
        simpson_refined(f, 1 << 12, 1e-13, 30).0
    }

    #[test]
    fn the_closed_form_of_a_point_term_is_the_integral() {
        let mut rng = Rng(0x51_7cc1_b727_220a);
        let mut worst: f64 = 0.0;
        let mut declined = 0;
        for k in 0..400 {
            let s = rng.vec(3.0);
            let e = s + rng.vec(6.0);
            // Far, near, within eps of the ray and on it; before, along and past the segment.
            let along = s + (e - s) * (rng.unit() * 1.6 - 0.3);
            let off = rng.vec(1.0) * [2.0, 0.3, 0.02, 0.004, 0.0][k % 5];
            let x = along + off;
            let eps = [0.01, 0.05, 0.2][k % 3];
            let (alpha, beta) = (0.5 + rng.unit(), [0.05, 0.3, 1.0, 4.0][k % 4]);
            let want = brute(s, e, x, eps, alpha, beta);
            match closed(s, e, x, eps, alpha, beta) {
                Some(got) => worst = worst.max((got - want).abs() / want.abs()),
                None => declined += 1,
            }
        }
        assert!(worst < 1e-9, "relative error {worst:e}");
        assert!(declined <= 4, "{declined} of 400 rays declined");
    }

    #[test]
    fn the_closed_form_covers_the_degenerate_rays() {
        let (eps, alpha, beta) = (0.05, 1.0, 1.0);
        let s = DVec3::new(0.0, 0.0, 0.0);
        let e = DVec3::new(0.0, 0.0, 4.0);
        // Through the source, with the stretch within eps inside the ray, at its start and past its end.
        for z in [2.0, 0.0, 4.0, 4.03, -0.03] {
            let x = DVec3::new(0.0, 0.0, z);
            let got = closed(s, e, x, eps, alpha, beta).expect("well conditioned");
            let want = brute(s, e, x, eps, alpha, beta);
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "z = {z}: {got} against {want}"
            );
        }
        // Exactly eps from the ray, and a ray of no length (d constant).
        let x = DVec3::new(eps, 0.0, 1.0);
        let (got, want) = (
            closed(s, e, x, eps, alpha, beta).unwrap(),
            brute(s, e, x, eps, alpha, beta),
        );
        assert!((got - want).abs() <= 1e-9 * want, "{got} against {want}");
        let x = DVec3::new(0.3, 0.0, 0.0);
        let got = closed(s, s, x, eps, alpha, beta).unwrap();
        assert!((got - alpha * (1.0 / beta - 1.0 / (1.0 + beta)) / 0.3).abs() < 1e-15);
        // A source on the decay's pole (s = -beta): A vanishes, and the closed form declines.
        let x = s + (e - s) * -beta;
        assert_eq!(closed(s, e, x, eps, alpha, beta), None);
    }
}
