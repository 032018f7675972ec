//! The adaptive integrator: B integrated source by source, each term with its samples packed around the ray's
//! closest approach to that source by the change of variables `s = s* + h sinh(u)`.
//!
//! The integral is linear in the sources, `B = sum_i integral_0^1 f_i(L(s)) zeta(s) ds` with
//! `f_i = c_i w_i / max(eps, d_i)`. Near its closest approach at `s*` a source's distance along the ray is
//! `d(s)^2 ~ d*^2 + a (s - s*)^2` (exactly so for a point and a line), so `1 / d` is a peak of width
//! `h = d* / sqrt(a)` in s. Substituting `s = s* + h sinh(u)`, `ds = h cosh(u) du` cancels the peak: the integrand
//! in u is smooth and nearly flat, and a few Simpson samples in u integrate it to a fraction of a percent,
//! however sharp the peak, with no banding. The u interval `[asinh((lo - s*) / h), asinh((hi - s*) / h)]` maps
//! exactly onto `[lo, hi]`, so the rule integrates the true integrand whatever `s*` and `h` are: a poor guess of
//! the peak costs accuracy, never bias.
//!
//! Closest approach: closed form for points and lines (d^2 is quadratic in s); for tori and curves a scan of d^2
//! at `scan + 1` evenly spaced samples finds the local minima (at most two peaks, split at the largest d^2
//! between them: a ray can pass close to a ring twice), each refined by two parabolic steps.
//!
//! The rule in u is adaptive Simpson: `PANELS` panels, each bisected (at most `DEPTH` times) while its halves
//! disagree with it by more than the tolerance allows, so B's error stays near the scene's `tolerance` whatever
//! the shape of the peaks (a ray grazing a curve makes a broad, uneven one). The tolerance is shared between the
//! sources in proportion to their coefficients, so it bounds the whole of B, however many sources there are.
//!
//! `shaders/field.wgsl` (`integrate_adaptive`) is the f32 twin of this file.

use glam::DVec3;

use crate::field::{Sources, curve, falloff, line_distance, torus_distance, wseries};
use crate::integrate::{Integration, zeta};

/// Intervals of the scan that locates a torus's or a curve's closest approaches.
pub const SCAN: u32 = 12;
/// Simpson panels in u per peak before any refinement.
pub const PANELS: u32 = 8;
/// Deepest bisection of a panel.
pub const DEPTH: u32 = 12;
/// Most bisections for one term, all its panels together: bounds a term's work (and its loop iterations on the
/// GPU, which some drivers cap).
pub const SPLITS: u32 = 200;
/// The smallest error asked of a panel, relative to its value.
pub const RELATIVE_FLOOR: f64 = 4e-6;

/// One source's term along a ray: `(d^2, f)` at a point, f with coefficient and W series, before zeta.
#[derive(Clone, Copy)]
enum Term<'a> {
    Point(&'a crate::field::Point),
    Line(&'a crate::field::Line),
    Torus(&'a crate::field::Torus),
    Curve(&'a crate::field::Curve),
}

impl Term<'_> {
    fn distance(&self, p: DVec3) -> (f64, f64) {
        match self {
            Term::Point(s) => ((p - s.position).length(), 1.0),
            Term::Line(s) => (line_distance(p, s.point, s.direction), 1.0),
            Term::Torus(s) => (torus_distance(p, s.center, s.axis, s.major_radius), 1.0),
            Term::Curve(s) => {
                let n = curve::nearest_on_chain(&s.control_points, p);
                (n.distance, wseries::evaluate(&s.weights, n.t))
            }
        }
    }

    fn coefficient(&self) -> f64 {
        match self {
            Term::Point(s) => s.coefficient,
            Term::Line(s) => s.coefficient,
            Term::Torus(s) => s.coefficient,
            Term::Curve(s) => s.coefficient,
        }
    }
}

/// A peak of one term along the ray: the interval it owns, its center `s*` and width `h` (both in s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub lo: f64,
    pub hi: f64,
    pub center: f64,
    pub width: f64,
}

/// Widest peak considered: beyond it the map is as good as uniform.
const MAX_WIDTH: f64 = 4.0;

/// The peak of a term whose squared distance is `d2(s) = d2_min + a (s - s*)^2`, over `[lo, hi]`.
fn peak(lo: f64, hi: f64, center: f64, d2_min: f64, a: f64, eps: f64) -> Peak {
    let d2 = d2_min.max(eps * eps);
    let width = if a > 0.0 {
        (d2 / a).sqrt().min(MAX_WIDTH)
    } else {
        MAX_WIDTH
    };
    Peak {
        lo,
        hi,
        center: center.clamp(lo, hi),
        width: width.max(1e-6),
    }
}

/// The peaks of a term along `s -> e` (at most two).
fn peaks(term: Term, s: DVec3, e: DVec3, scan: u32, eps: f64) -> ([Peak; 2], usize) {
    let dir = e - s;
    let none = Peak {
        lo: 0.0,
        hi: 1.0,
        center: 0.0,
        width: MAX_WIDTH,
    };
    match term {
        Term::Point(p) => {
            let a = dir.length_squared();
            let c = if a > 0.0 {
                (p.position - s).dot(dir) / a
            } else {
                0.0
            };
            let d2 = (s + dir * c - p.position).length_squared();
            ([peak(0.0, 1.0, c, d2, a, eps), none], 1)
        }
        Term::Line(l) => {
            let q = s - l.point;
            let q_perp = q - l.direction * q.dot(l.direction);
            let d_perp = dir - l.direction * dir.dot(l.direction);
            let a = d_perp.length_squared();
            let c = if a > 0.0 {
                -q_perp.dot(d_perp) / a
            } else {
                0.0
            };
            let d2 = (q_perp + d_perp * c).length_squared();
            ([peak(0.0, 1.0, c, d2, a, eps), none], 1)
        }
        Term::Torus(_) | Term::Curve(_) => {
            let d2 = |t: f64| {
                let d = term.distance(s + dir * t).0;
                d * d
            };
            scanned_peaks(d2, scan, eps)
        }
    }
}

/// Local minima of `d2` on a scan of `scan` intervals, at most the two deepest, each refined by two parabolic
/// steps; their intervals meet at the largest scanned value between them.
fn scanned_peaks(d2: impl Fn(f64) -> f64, scan: u32, eps: f64) -> ([Peak; 2], usize) {
    let k = scan.max(2) as usize;
    let step = 1.0 / k as f64;
    let g: Vec<f64> = (0..=k).map(|i| d2(i as f64 * step)).collect();
    // The two deepest local minima (ties to the left).
    let mut best = [usize::MAX; 2];
    for i in 0..=k {
        let left = i == 0 || g[i] < g[i - 1];
        let right = i == k || g[i] <= g[i + 1];
        if !(left && right) {
            continue;
        }
        if best[0] == usize::MAX || g[i] < g[best[0]] {
            best[1] = best[0];
            best[0] = i;
        } else if best[1] == usize::MAX || g[i] < g[best[1]] {
            best[1] = i;
        }
    }
    if best[0] == usize::MAX {
        // A flat scan (constant distance): one uniform interval.
        best[0] = 0;
    }
    let count = if best[1] == usize::MAX { 1 } else { 2 };
    let mut minima = [best[0], best[1]];
    if count == 2 && minima[1] < minima[0] {
        minima.swap(0, 1);
    }
    // Split at the largest value between the two minima.
    let split = if count == 2 {
        let (a, b) = (minima[0], minima[1]);
        let m = (a..=b).max_by(|&x, &y| g[x].total_cmp(&g[y])).unwrap_or(a);
        m as f64 * step
    } else {
        1.0
    };
    let mut out = [Peak {
        lo: 0.0,
        hi: 1.0,
        center: 0.0,
        width: MAX_WIDTH,
    }; 2];
    for (slot, &i) in minima.iter().take(count).enumerate() {
        let (lo, hi) = match (count, slot) {
            (1, _) => (0.0, 1.0),
            (_, 0) => (0.0, split),
            _ => (split, 1.0),
        };
        let center = i as f64 * step;
        let (g0, g1, g2) = (
            if i > 0 { g[i - 1] } else { d2(center - step) },
            g[i],
            if i < k { g[i + 1] } else { d2(center + step) },
        );
        let (c, value, a) = refine(&d2, center, step, g0, g1, g2);
        out[slot] = peak(lo, hi, c, value, a, eps);
    }
    (out, count)
}

/// Two parabolic steps from a bracketed minimum at `c` (samples `g0, g1, g2` at `c - h, c, c + h`): the vertex,
/// the value there and the curvature `a` of `d2 ~ value + a (s - vertex)^2`.
fn refine(d2: &impl Fn(f64) -> f64, c: f64, h: f64, g0: f64, g1: f64, g2: f64) -> (f64, f64, f64) {
    let (mut c, mut h, mut g) = (c, h, [g0, g1, g2]);
    let mut a = 0.0;
    for round in 0..2 {
        let second = g[0] - 2.0 * g[1] + g[2];
        a = second / (2.0 * h * h);
        let offset = if second > 0.0 {
            (0.5 * h * (g[0] - g[2]) / second).clamp(-h, h)
        } else {
            0.0
        };
        c += offset;
        if round == 1 {
            break;
        }
        h *= 0.25;
        g = [d2(c - h), d2(c), d2(c + h)];
    }
    let value = d2(c);
    (c, value.min(g[1]).max(0.0), a.max(0.0))
}

/// Simpson on `[a, b]` from its end and middle values, split in halves (left first) while they disagree with the
/// whole by more than `15 tol` (Richardson), `depth` levels at most and while `splits` lasts. The test never asks
/// for less than `RELATIVE_FLOOR` of the panel's value: below that f32 rounding (on the GPU) would split forever.
fn adaptive_simpson(
    g: &impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    [fa, fm, fb]: [f64; 3],
    tol: f64,
    depth: u32,
    splits: &mut u32,
) -> f64 {
    let m = 0.5 * (a + b);
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (flm, frm) = (g(lm), g(rm));
    let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    let delta = left + right - whole;
    let allowed = 15.0 * tol.max(RELATIVE_FLOOR * (left + right).abs());
    if depth == 0 || *splits == 0 || delta.abs() <= allowed {
        return left + right + delta / 15.0;
    }
    *splits -= 1;
    let l = adaptive_simpson(g, a, m, [fa, flm, fm], 0.5 * tol, depth - 1, splits);
    l + adaptive_simpson(g, m, b, [fm, frm, fb], 0.5 * tol, depth - 1, splits)
}

/// The error allowed on one term's integral before its coefficient: the scene's tolerance on B shared between
/// the sources in proportion to their coefficients, `tolerance / sum |c|`. Twin of `FieldParams::tolerance`.
pub fn term_tolerance(sources: &Sources, tolerance: f64) -> f64 {
    let total: f64 = (sources.points.iter().map(|s| s.coefficient.abs()))
        .chain(sources.lines.iter().map(|s| s.coefficient.abs()))
        .chain(sources.tori.iter().map(|s| s.coefficient.abs()))
        .chain(sources.curves.iter().map(|s| s.coefficient.abs()))
        .sum();
    tolerance / total.max(1e-30)
}

/// One term's integral over its peaks: adaptive Simpson in u, to `tol` before the coefficient.
fn integrate_term(term: Term, s: DVec3, e: DVec3, settings: &Integration, tol: f64) -> f64 {
    let c = term.coefficient();
    if c == 0.0 {
        return 0.0;
    }
    let (peaks, count) = peaks(term, s, e, SCAN, settings.epsilon);
    let dir = e - s;
    let f = |t: f64| {
        let (d, w) = term.distance(s + dir * t);
        w * falloff(d, settings.epsilon) * zeta(t, settings.alpha, settings.beta)
    };
    // Shared between the peaks.
    let tol = tol / count as f64;
    let mut sum = 0.0;
    let mut splits = SPLITS;
    for p in &peaks[..count] {
        let u0 = ((p.lo - p.center) / p.width).asinh();
        let u1 = ((p.hi - p.center) / p.width).asinh();
        if u1 <= u0 {
            continue;
        }
        // The integrand in u: f(s(u)) ds/du.
        let g = |u: f64| {
            let t = (p.center + p.width * u.sinh()).clamp(p.lo, p.hi);
            f(t) * p.width * u.cosh()
        };
        let width = (u1 - u0) / PANELS as f64;
        for i in 0..PANELS {
            let a = u0 + width * i as f64;
            let b = a + width;
            let (fa, fm, fb) = (g(a), g(0.5 * (a + b)), g(b));
            sum += adaptive_simpson(
                &g,
                a,
                b,
                [fa, fm, fb],
                tol / PANELS as f64,
                DEPTH,
                &mut splits,
            );
        }
    }
    c * sum
}

/// The brightness B of the segment from `s` to `e` by the adaptive integrator.
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    let terms = sources
        .points
        .iter()
        .map(Term::Point)
        .chain(sources.lines.iter().map(Term::Line))
        .chain(sources.tori.iter().map(Term::Torus))
        .chain(sources.curves.iter().map(Term::Curve));
    let tol = term_tolerance(sources, settings.tolerance);
    terms.map(|t| integrate_term(t, s, e, settings, tol)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Point, Torus};
    use crate::integrate::simpson;

    fn settings() -> Integration {
        Integration::default()
    }

    /// The converged integral by Simpson with many samples.
    fn reference(sources: &Sources, s: DVec3, e: DVec3, n: u32) -> f64 {
        let st = settings();
        simpson(
            |t| sources.psi(s + (e - s) * t, st.epsilon) * zeta(t, st.alpha, st.beta),
            n,
        )
    }

    #[test]
    fn a_point_on_the_ray_is_integrated_to_high_accuracy() {
        // The peak is 1 / max(eps, |s - 0.37| L), a sharp spike that uniform Simpson needs thousands of samples
        // for; the map flattens it.
        let sources = Sources {
            points: vec![Point {
                position: DVec3::new(0.0, 0.0, -3.7),
                coefficient: 1.0,
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
            }],
            ..Default::default()
        };
        let (s, e) = (DVec3::new(0.02, 0.001, 0.0), DVec3::new(0.02, 0.001, -10.0));
        let (p, count) = peaks(Term::Torus(&sources.tori[0]), s, e, 12, 0.01);
        assert_eq!(count, 2);
        assert!((p[0].center - 0.4).abs() < 2e-3 && (p[1].center - 0.6).abs() < 2e-3);
        let want = reference(&sources, s, e, 1 << 20);
        let got = brightness(&sources, &settings(), s, e);
        assert!((got - want).abs() < 2e-3 * want, "{got} vs {want}");
    }
}
