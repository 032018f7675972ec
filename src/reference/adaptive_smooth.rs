//! The adaptive integrator's smooth sources: points, lines and tori, the f64 twin of
//! `shaders/adaptive_smooth.wgsl` (entry point `integrate_adaptive`). A point's or a line's term is taken in
//! closed form where that is well conditioned (`falloff_integral`); otherwise, and for every torus, by
//! Gauss-Kronrod pairs on the pieces around its closest approaches (`super::adaptive`, whose module text
//! describes the method).

use glam::DVec3;

use super::adaptive::{Features, Kinks, Peak, integrate_pieces, line_approach, peak, share_ray};
use crate::field::{Line, Point, Sources, Torus, falloff, line_distance, torus_distance};
use crate::integrate::adaptive::{
    CLOSED_FORM_CONDITION, MAX_PEAKS, MAX_WIDTH, MIN_AXIS_WIDTH, POLE_SERIES_REACH,
    POLE_SERIES_TERMS, RING_NEWTON, RING_STEP, kronrod_order,
};
use crate::integrate::{Decay, Integration, zeta};

/// One smooth source's term along a ray.
#[derive(Clone, Copy)]
enum Smooth<'a> {
    Point(&'a Point),
    Line(&'a Line),
    Torus(&'a Torus),
}

impl Smooth<'_> {
    fn distance(&self, p: DVec3) -> f64 {
        match self {
            Smooth::Point(s) => (p - s.position).length(),
            Smooth::Line(s) => line_distance(p, s.point, s.direction),
            Smooth::Torus(s) => torus_distance(p, s.center, s.axis, s.major_radius),
        }
    }

    fn coefficient(&self) -> f64 {
        match self {
            Smooth::Point(s) => s.coefficient,
            Smooth::Line(s) => s.coefficient,
            Smooth::Torus(s) => s.coefficient,
        }
    }
}

/// A torus's ring seen along the ray `s + t dir`: `rho^2 = A t^2 + B t + C` (rho, the distance from the axis) and
/// `z = z0 + z1 t` (the height over the ring's plane), so `d^2 = (rho - R)^2 + z^2` and its derivatives are
/// closed forms. `d^2` is smooth on either side of the ray's closest approach to the axis (where rho has its
/// kink); on each side its minimum, the ring's closest approach, is found by Newton's method, with no sampling.
struct Ring {
    a: f64,
    b: f64,
    c: f64,
    z0: f64,
    z1: f64,
    r: f64,
}

impl Ring {
    fn new(torus: &Torus, s: DVec3, dir: DVec3) -> Ring {
        let q = s - torus.center;
        let (z0, z1) = (q.dot(torus.axis), dir.dot(torus.axis));
        Ring {
            a: dir.length_squared() - z1 * z1,
            b: 2.0 * (q.dot(dir) - z0 * z1),
            c: q.length_squared() - z0 * z0,
            z0,
            z1,
            r: torus.major_radius,
        }
    }

    /// Half the first and second derivatives of `d^2` at t, and `d^2`.
    fn at(&self, t: f64) -> (f64, f64, f64) {
        let rho = (self.a * t * t + self.b * t + self.c).max(1e-30).sqrt();
        let drho = (2.0 * self.a * t + self.b) / (2.0 * rho);
        let ddrho = (self.a - drho * drho) / rho;
        let z = self.z0 + self.z1 * t;
        let first = (rho - self.r) * drho + z * self.z1;
        let second = drho * drho + (rho - self.r) * ddrho + self.z1 * self.z1;
        (first, second, (rho - self.r) * (rho - self.r) + z * z)
    }

    /// Where to start Newton on `[lo, hi]`: where the ray crosses the ring's cylinder (`rho = R`) there, else
    /// where it crosses the ring's plane, else the side's middle.
    fn start(&self, lo: f64, hi: f64, left: bool) -> f64 {
        let disc = self.b * self.b - 4.0 * self.a * (self.c - self.r * self.r);
        if self.a > 0.0 && disc >= 0.0 {
            let root = disc.sqrt();
            let t = if left {
                (-self.b - root) / (2.0 * self.a)
            } else {
                (-self.b + root) / (2.0 * self.a)
            };
            if t >= lo && t <= hi {
                return t;
            }
        }
        if self.z1 != 0.0 {
            let t = -self.z0 / self.z1;
            if t >= lo && t <= hi {
                return t;
            }
        }
        0.5 * (lo + hi)
    }

    /// The closest approach on `[lo, hi]` from `t0`: `(t*, d*^2, a)` with `d^2(t) ~ d*^2 + a (t - t*)^2`. Newton's
    /// steps are at most `RING_STEP`; where `d^2` is concave, half that step downhill instead.
    fn approach(&self, t0: f64, lo: f64, hi: f64) -> (f64, f64, f64) {
        let mut t = t0.clamp(lo, hi);
        for _ in 0..RING_NEWTON {
            let (first, second, _) = self.at(t);
            let delta = if second > 0.0 {
                (first / second).clamp(-RING_STEP, RING_STEP)
            } else {
                0.5 * RING_STEP * first.signum()
            };
            t = (t - delta).clamp(lo, hi);
        }
        let (_, second, d2) = self.at(t);
        (t, d2, second.max(0.0))
    }
}

/// The closest approach of the ray `s + t dir` to the point `p`: `(t*, d*^2, a)` with `d^2(t) = d*^2 + a (t - t*)^2`.
fn point_approach(s: DVec3, dir: DVec3, p: DVec3) -> (f64, f64, f64) {
    let a = dir.length_squared();
    let c = if a > 0.0 { (p - s).dot(dir) / a } else { 0.0 };
    (c, (s + dir * c - p).length_squared(), a)
}

/// The term of a point or a line in closed form: the integral over s in [0, 1] of `zeta(s) / max(eps, d(s))`
/// for a squared distance along the ray `d(s)^2 = h2 + a (s - c)^2` (closest approach `c`, its squared distance
/// `h2`), with no samples at all. Where `d < eps` (around `c` when `h2 < eps^2`) the integrand is
/// `alpha / (eps (s + beta)^2)`. Elsewhere, with `w = s + beta`, `u = 1 / w` turns `ds / (w^2 d)` into
/// `-u du / sqrt(Q(u))` for the quadratic `Q(u) = A u^2 + 2 B u + a`, `A = d(-beta)^2 = a (c + beta)^2 + h2`,
/// `B = -a (c + beta)`, whose antiderivative is `I(u) = (r - B ln(X + r)) / A^(3/2)` with `X = A u + B` and
/// `r = sqrt(X^2 + a h2)` (docs/METHOD.md, "Points and lines in closed form"). The differences of `r` and of
/// the logarithm are taken without cancellation. Where the source lies close to the decay's pole at `s = -beta`
/// (within `POLE_SERIES_REACH` of the piece, `pole_series`) A nearly vanishes and the closed form's two parts
/// cancel however they are written; the piece is summed as a series about the pole instead. `None` where, even
/// so, the closed form's two parts cancel to more than `1 / condition` of their size: the caller integrates
/// numerically there.
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
    let piece = |lo, hi| falloff_piece((c, h2, a), beta, (lo, hi), condition).map(|v| alpha * v);
    if half > 0.0 {
        sum += piece(0.0, flat_lo)? + piece(flat_hi, 1.0)?;
    } else {
        sum += piece(0.0, 1.0)?;
    }
    Some(sum)
}

/// `falloff_integral`'s part of the ray `[lo, hi]` where `d >= eps`, before alpha: the integral of
/// `ds / ((s + beta)^2 d(s))`, `d(s)^2 = h2 + a (s - c)^2`, in u = 1 / (s + beta) the integral of `u / sqrt(Q(u))`
/// from `u_b = 1 / (hi + beta)` to `u_a = 1 / (lo + beta)`: by the pole series where the source lies within
/// `POLE_SERIES_REACH` of the decay's pole, else by the closed form, `None` where its parts cancel beyond
/// `condition`.
pub fn falloff_piece(
    (c, h2, a): (f64, f64, f64),
    beta: f64,
    (lo, hi): (f64, f64),
    condition: f64,
) -> Option<f64> {
    if hi <= lo {
        return Some(0.0);
    }
    let w_c = c + beta;
    // The source's squared distance from the pole over a, in the units of w = s + beta.
    let rho2 = w_c * w_c + h2 / a;
    let u_a = 1.0 / (lo + beta);
    if rho2 * u_a * u_a <= POLE_SERIES_REACH * POLE_SERIES_REACH {
        return Some(pole_series(w_c, rho2, a, (u_a, 1.0 / (hi + beta)), hi - lo));
    }
    closed_piece((c, h2, a), beta, (lo, hi), condition)
}

/// `falloff_piece` by the closed form `I(u_a) - I(u_b)`, `I(u) = (r - B ln(X + r)) / A^(3/2)`, its differences
/// taken without cancellation; `None` where its two parts cancel beyond `condition` (or it is not finite).
pub fn closed_piece(
    (c, h2, a): (f64, f64, f64),
    beta: f64,
    (lo, hi): (f64, f64),
    condition: f64,
) -> Option<f64> {
    let w_c = c + beta;
    let big_a = a * w_c * w_c + h2;
    let big_b = -a * w_c;
    let k = a * h2;
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
    Some(bracket / (big_a * big_a.sqrt()))
}

/// The integral of `u / sqrt(Q(u))` from `u_b` to `u_a` (`falloff_integral`'s piece before alpha, `length` its
/// length in s) for a source near the decay's pole, as a series in powers of u: `Q(u) = a (1 - 2 w_c u + rho2 u^2)`
/// with `rho2 = w_c^2 + h2 / a`, so that `1 / sqrt(Q) = sum_n p_n u^n / sqrt(a)`, `p_n = rho^n P_n(w_c / rho)` (the
/// Legendre polynomials' generating function, rho the source's distance from the pole over sqrt(a)), and the
/// integral is `sum_n p_n (u_a^(n+2) - u_b^(n+2)) / ((n + 2) sqrt(a))`. `|p_n| <= rho^n`, so the terms fall as
/// `(rho u_a)^n` (within `POLE_SERIES_REACH`); `p_n` comes from the Legendre recurrence, which needs no division by
/// rho (the source exactly at the pole is the series' first term), and the differences of the powers from
/// `D_(m+1) = u_a D_m + u_b^m (u_a - u_b)`, `u_a - u_b = length u_a u_b`, without cancellation on a short piece.
pub fn pole_series(w_c: f64, rho2: f64, a: f64, (u_a, u_b): (f64, f64), length: f64) -> f64 {
    let delta = length * u_a * u_b;
    // D_2 = u_a^2 - u_b^2, and u_b^2 for the next.
    let mut d = u_a * delta + u_b * delta;
    let mut power = u_b * u_b;
    let (mut previous, mut p) = (0.0, 1.0);
    let mut sum = 0.0;
    for n in 0..POLE_SERIES_TERMS {
        let n = n as f64;
        sum += p * d / (n + 2.0);
        let next = ((2.0 * n + 1.0) * w_c * p - n * rho2 * previous) / (n + 1.0);
        (previous, p) = (p, next);
        d = u_a * d + power * delta;
        power *= u_b;
    }
    sum / a.sqrt()
}

/// The features of a term along `s -> e` (at most `MAX_PEAKS`), sorted along the ray, each owning its piece.
fn features(term: Smooth, s: DVec3, e: DVec3, eps: f64) -> Features {
    let dir = e - s;
    let mut out = [peak(0.0, 0.0, 0.0, eps); MAX_PEAKS];
    let count = match term {
        Smooth::Point(p) => {
            let (c, d2, a) = point_approach(s, dir, p.position);
            out[0] = peak(c, d2, a, eps);
            1
        }
        Smooth::Line(l) => {
            let (c, d2, a) = line_approach(s, dir, l.point, l.direction);
            out[0] = peak(c, d2, a, eps);
            1
        }
        Smooth::Torus(t) => {
            // One closest approach on each side of the axis, and the axis itself.
            let ring = Ring::new(t, s, dir);
            let (c, r2, a) = line_approach(s, dir, t.center, t.axis);
            let crosses = a > 0.0 && c > 0.0 && c < 1.0;
            let sides: &[(f64, f64, bool)] = if crosses {
                &[(0.0, c, true), (c, 1.0, false)]
            } else {
                &[(0.0, 1.0, c >= 1.0)]
            };
            for (k, &(lo, hi, left)) in sides.iter().enumerate() {
                let (tc, d2, curvature) = ring.approach(ring.start(lo, hi, left), lo, hi);
                out[k] = peak(tc, d2, curvature, eps);
            }
            let mut count = sides.len();
            if crosses {
                let width = (r2 / a).sqrt().clamp(MIN_AXIS_WIDTH, MAX_WIDTH);
                out[count] = Peak {
                    lo: 0.0,
                    hi: 1.0,
                    center: c,
                    width,
                    flat: 0.0,
                };
                count += 1;
            }
            count
        }
    };
    share_ray(&mut out[..count]);
    Features {
        peaks: out,
        count,
        kinks: Kinks::default(),
    }
}

/// One term's integral along `s -> e` within `tolerance` on B: in closed form for a point or a line where it is
/// well conditioned, else on the pieces of its features (`integrate_pieces`).
fn integrate_term(term: Smooth, s: DVec3, e: DVec3, settings: &Integration, tolerance: f64) -> f64 {
    let c = term.coefficient();
    if c == 0.0 {
        return 0.0;
    }
    let (eps, alpha, beta) = (settings.epsilon, settings.alpha, settings.beta);
    let approach = match term {
        Smooth::Point(p) => Some(point_approach(s, e - s, p.position)),
        Smooth::Line(l) => Some(line_approach(s, e - s, l.point, l.direction)),
        Smooth::Torus(_) => None,
    };
    // The closed form is the distance decay's (the rms decay's square has its own, which only the tests take).
    if let Some((center, d2, a)) = approach
        && settings.decay == Decay::Distance
        && let Some(v) = falloff_integral(center, d2, a, eps, alpha, beta, CLOSED_FORM_CONDITION)
    {
        return c * v;
    }
    let order = kronrod_order(settings.tolerance);
    let found = features(term, s, e, eps);
    let dir = e - s;
    let power = settings.power();
    let f = |t: f64| (falloff(term.distance(s + dir * t), eps) * zeta(t, alpha, beta)).powi(power);
    let rms = (settings.decay == Decay::Rms).then_some(settings.stretch);
    // No kinks and no segments: every cut stretch is one part.
    let integral = integrate_pieces(
        &found,
        (c.powi(power), &f),
        order,
        (tolerance, rms),
        |_, (a, _), (b, _)| ([(a, b); 2], 1),
    );
    settings.finish(integral, c)
}

/// The points', lines' and tori's part of the brightness B of the segment `s -> e`, each term within an equal
/// share of the tolerance among all the scene's sources (the curves' are `adaptive_curves::brightness`).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    let share = settings.term_tolerance(sources.len());
    terms(sources)
        .map(|t| integrate_term(t, s, e, settings, share))
        .sum()
}

/// The adaptive integrator's points, lines and tori: `adaptive_smooth.wgsl`'s twin.
pub struct AdaptiveSmooth;

impl super::TermIntegrator for AdaptiveSmooth {
    /// The part of B of term `k` alone (points, then lines, then tori), as `brightness` integrates it.
    fn term_brightness(
        &self,
        sources: &Sources,
        k: usize,
        settings: &Integration,
        ray: super::TexelRay,
    ) -> f64 {
        let share = settings.term_tolerance(sources.len());
        terms(sources).nth(k).map_or(0.0, |t| {
            integrate_term(t, ray.start, ray.end, settings, share)
        })
    }
}

fn terms(sources: &Sources) -> impl Iterator<Item = Smooth<'_>> {
    (sources.points.iter().map(Smooth::Point))
        .chain(sources.lines.iter().map(Smooth::Line))
        .chain(sources.tori.iter().map(Smooth::Torus))
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::testing::{assert_within_each_tolerance, reference, settings};
    use super::*;
    use crate::reference::simpson::simpson_refined;

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
        converged(|t: f64| zeta(t, alpha, beta) / (s + (e - s) * t - x).length().max(eps))
    }

    /// The integral of `f` over [0, 1] by Simpson's rule refined to 1e-14 of its size (an absolute tolerance
    /// below f64's rounding of a large integral would refine without end).
    fn converged(f: impl Fn(f64) -> f64) -> f64 {
        let rough = simpson_refined(&f, 1 << 12, f64::INFINITY, 0).0;
        simpson_refined(&f, 1 << 12, 1e-14 * rough.abs(), 30).0
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
        // A source on the decay's pole (s = -beta, the eye at the papers' settings): A vanishes, and the pole
        // series takes the term.
        let pole = s + (e - s) * -beta;
        let got = closed(s, e, pole, eps, alpha, beta).expect("the series");
        let want = brute(s, e, pole, eps, alpha, beta);
        assert!((got - want).abs() <= 1e-12 * want, "{got} against {want}");
    }

    #[test]
    fn sources_at_and_near_the_decay_s_pole_meet_brute_force() {
        // The closed form's parts grow as 1 / A^(3/2) near the pole, A the squared distance of source and pole:
        // a source there (a line through the eye, at the papers' settings) gave +-1e15 on about half the rays,
        // rounding's noise in A passing the cancellation test. Points and lines from exactly on the pole out to
        // where the closed form takes over again, in every direction from it, with the accepting condition the
        // integrators use (CLOSED_FORM_CONDITION), against brute force.
        let (s, e) = (DVec3::new(0.2, -0.1, 6.0), DVec3::new(0.5, 0.3, -2.0));
        let mut series = 0;
        for beta in [1.0, 0.25, 0.05] {
            let pole = s + (e - s) * -beta;
            let reach = (e - s).length() * beta;
            for offset in [
                0.0, 1e-16, 1e-12, 1e-8, 1e-4, 1e-2, 0.1, 0.25, 0.29, 0.31, 0.5, 2.0,
            ] {
                for direction in [
                    e - s,
                    s - e,
                    DVec3::new(1.0, 0.0, 0.0),
                    DVec3::new(0.3, -0.8, 0.2),
                ] {
                    let x = pole + direction.normalize() * offset * reach;
                    let d = e - s;
                    let a = d.length_squared();
                    let c = (x - s).dot(d) / a;
                    let h2 = (s + d * c - x).length_squared();
                    let (eps, alpha) = (0.01, 1.3);
                    let got = falloff_integral(c, h2, a, eps, alpha, beta, CLOSED_FORM_CONDITION);
                    let want = brute(s, e, x, eps, alpha, beta);
                    let got = got.unwrap_or_else(|| {
                        panic!("beta {beta}, offset {offset}, {direction}: declined")
                    });
                    assert!(
                        (got - want).abs() <= 1e-11 * want,
                        "beta {beta}, offset {offset}, {direction}: {got} against {want}"
                    );
                    series += usize::from(offset < POLE_SERIES_REACH);
                    // A line through that point, across the ray, along it (the ray's line inside the source's
                    // where the point is on it: a = 0 up to rounding) and nearly along it.
                    let ray = (e - s).normalize();
                    let tilted =
                        |angle: f64| (ray + ray.any_orthonormal_vector() * angle).normalize();
                    for along in [DVec3::Y, ray, tilted(1e-6), tilted(1e-3)] {
                        let (c, h2, a) = line_approach(s, d, x, along);
                        let got =
                            falloff_integral(c, h2, a, eps, alpha, beta, CLOSED_FORM_CONDITION);
                        // The distance by the cross product, which keeps its digits along the line (the
                        // difference of squares in `line_distance` loses them there, and the refinement chases
                        // its noise).
                        let want = converged(|t: f64| {
                            zeta(t, alpha, beta) / (s + d * t - x).cross(along).length().max(eps)
                        });
                        let got = got.unwrap_or_else(|| {
                            panic!("line, beta {beta}, offset {offset}, {direction}: declined")
                        });
                        assert!(
                            (got - want).abs() <= 1e-10 * want,
                            "line along {along}, beta {beta}, offset {offset}, {direction}: {got} against {want}"
                        );
                    }
                }
            }
        }
        assert!(series > 50);
    }

    #[test]
    fn the_pole_series_is_the_closed_form_where_both_hold() {
        // Where both are well conditioned (a source between 0.15 and 0.3 of the way to the piece, where the closed
        // form cancels less than 25x in f64), the two agree: an independent check of the series' every term.
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..300 {
            let (a, beta) = (0.2 + 3.0 * rng.unit(), 0.05 + rng.unit());
            let (lo, hi) = (0.7 * rng.unit(), 0.7 + 0.3 * rng.unit());
            let z = 0.15 + 0.15 * rng.unit();
            let angle = std::f64::consts::PI * rng.unit();
            let rho = z * (lo + beta);
            let w_c = rho * angle.cos();
            let h2 = a * (rho * angle.sin()).powi(2);
            let (u_a, u_b) = (1.0 / (lo + beta), 1.0 / (hi + beta));
            let series = pole_series(w_c, w_c * w_c + h2 / a, a, (u_a, u_b), hi - lo);
            let closed =
                closed_piece((w_c - beta, h2, a), beta, (lo, hi), 1e6).expect("well conditioned");
            assert!(
                (series - closed).abs() <= 1e-12 * closed,
                "z {z}: series {series} against the closed form {closed}"
            );
        }
    }

    #[test]
    fn a_point_on_the_ray_is_integrated_to_high_accuracy() {
        // The peak is 1 / max(eps, |s - 0.37| L), a sharp spike that uniform Simpson needs thousands of samples
        // for; the map flattens it.
        let sources = Sources {
            points: vec![Point {
                position: DVec3::new(0.0, 0.0, -3.7),
                coefficient: 1.0,
                look: Default::default(),
            }],
            ..Default::default()
        };
        let (s, e) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -10.0));
        for h in [0.0, 1e-3, 0.01, 0.1, 1.0] {
            let mut src = sources.clone();
            src.points[0].position.x = h;
            let want = reference(&src, s, e, 1 << 20);
            let got = brightness(&src, &settings(), s, e);
            assert!((got - want).abs() < 2e-3 * want, "h {h}: {got} vs {want}");
        }
    }

    #[test]
    fn a_ring_seen_edge_on_has_two_peaks_and_both_are_integrated() {
        let sources = Sources {
            tori: vec![Torus {
                center: DVec3::new(0.0, 0.0, -5.0),
                axis: DVec3::Y,
                major_radius: 1.0,
                coefficient: 1.0,
                look: Default::default(),
            }],
            ..Default::default()
        };
        let (s, e) = (DVec3::new(0.02, 0.001, 0.0), DVec3::new(0.02, 0.001, -10.0));
        // Two ring passes and, between them, the axis.
        let found = features(Smooth::Torus(&sources.tori[0]), s, e, 0.01);
        let (p, count) = (found.peaks, found.count);
        assert_eq!(count, 3);
        assert!((p[0].center - 0.4).abs() < 2e-3 && (p[2].center - 0.6).abs() < 2e-3);
        assert!((p[1].center - 0.5).abs() < 1e-9);
        let want = reference(&sources, s, e, 1 << 20);
        let got = brightness(&sources, &settings(), s, e);
        assert!((got - want).abs() < 2e-3 * want, "{got} vs {want}");
    }

    #[test]
    fn a_point_closer_than_eps_is_integrated_to_the_tolerance() {
        // The falloff's flat top 1 / eps has a kink at each end; the piece is cut there.
        let mut st = settings();
        st.tolerance = 1e-9;
        let (s, e) = (DVec3::ZERO, DVec3::new(0.0, 0.0, -10.0));
        for h in [0.0, 0.003, 0.0099, 0.0101, 0.05] {
            let sources = Sources {
                points: vec![Point {
                    position: DVec3::new(h, 0.0, -3.7),
                    coefficient: 1.0,
                    look: Default::default(),
                }],
                ..Default::default()
            };
            let want = reference(&sources, s, e, 1 << 22);
            let got = brightness(&sources, &st, s, e);
            assert!((got - want).abs() < 1e-8 * want, "h {h}: {got} vs {want}");
        }
    }

    #[test]
    fn a_torus_is_integrated_within_the_tolerance_on_rays_through_ring_and_axis() {
        // Rays from above a tilted ring, through its hole (crossing the axis, where the distance has a kink),
        // across the tube and beside it; at each tolerance every ray's error stays under it.
        let sources = Sources {
            tori: vec![Torus {
                center: DVec3::new(0.2, -0.1, -5.0),
                axis: DVec3::new(0.3, 1.0, 0.2).normalize(),
                major_radius: 0.9,
                coefficient: 2.0,
                look: Default::default(),
            }],
            ..Default::default()
        };
        let eye = DVec3::new(0.0, 6.0, 2.0);
        let rays: Vec<(DVec3, DVec3)> = (0..9)
            .flat_map(|i| (0..9).map(move |j| (i, j)))
            .map(|(i, j)| {
                let target = DVec3::new(-1.6 + 0.4 * i as f64, 0.0, -6.6 + 0.4 * j as f64);
                (eye, eye + (target - eye) * 2.0)
            })
            .collect();
        assert_within_each_tolerance(brightness, &sources, &rays, &[1e-3, 1e-4, 1e-5, 1e-6]);
    }
}
