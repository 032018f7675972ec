//! The adaptive integrator: B integrated source by source, each term's samples placed where its integrand
//! changes: around the ray's closest approaches to the source, by the change of variables `s = s* + h sinh(u)`,
//! with the ray split between them.
//!
//! The integral is linear in the sources, `B = sum_i integral_0^1 f_i(L(s)) zeta(s) ds` with
//! `f_i = c_i w_i / max(eps, d_i)`. Near its closest approach at `s*` a source's distance along the ray is
//! `d(s)^2 ~ d*^2 + a (s - s*)^2` (exactly so for a point and a line), so `1 / d` is a peak of width
//! `h = d* / sqrt(a)` in s. Substituting `s = s* + h sinh(u)`, `ds = h cosh(u) du` cancels the peak: the integrand
//! in u is smooth and nearly flat however sharp the peak. The u interval `[asinh((lo - s*) / h),
//! asinh((hi - s*) / h)]` maps exactly onto `[lo, hi]`, so the rule integrates the true integrand whatever `s*`
//! and `h` are: a poor guess costs accuracy, never bias.
//!
//! **Features.** A term's integrand needs samples where it bends sharply; each such place is a feature
//! (center and width in s):
//! - points and lines: the closest approach, in closed form (d^2 is quadratic in s);
//! - tori: the distance to the ring is `sqrt((rho - R)^2 + z^2)` with `rho` the distance from the axis. Along a
//!   ray `rho^2` is quadratic and z linear, so `d^2` and its derivatives are closed forms (`Ring`). rho is a
//!   hyperbola, `sqrt(rho*^2 + a (s - s*)^2)`, with a kink where the ray crosses the axis: that is a feature of
//!   width `rho* / sqrt(a)`, and on either side of it Newton's method finds the ring's closest approach (a ray
//!   can pass close to a ring twice, once on each side), with no sampling;
//! - curves: the local minima of d^2 on a scan of `SCAN + 1` samples (the two deepest), each refined by one
//!   parabolic step.
//!
//! The features, sorted along the ray, share it into pieces: each stretch of the ray goes to the feature whose map
//! is densest there (`share_ray`), so a narrow peak keeps its shoulders beside a broad feature. Where a point, a
//! line or a torus comes closer than eps, the falloff's flat top `1 / eps` has a kink at each end; the piece is
//! cut there too (exactly for points and lines, where d^2 is exactly quadratic).
//!
//! **Rules.** Points, lines and tori: in u each cut of a piece is smooth (analytic), and Gauss-Legendre with
//! `gauss_order(tolerance)` nodes (6 to 16) on each `U_PANEL` of u converges geometrically; the order grows as
//! the tolerance shrinks (measured: on the papers' torus, 10 nodes are within 2e-7 of the converged f64 value in
//! every texel, with about 19 evaluations of the torus a ray against Simpson's 201). Curves: the nearest point
//! of a chain jumps where the ray crosses the chain's medial surface, a kink in d (and a step in W) that no fixed
//! rule converges over, so a curve's pieces are integrated by adaptive Simpson, `PANELS` panels each bisected
//! (at most `DEPTH` times) while its halves disagree with it by more than the tolerance allows. The tolerance is
//! shared between the curves and every other source in proportion to their coefficients.
//!
//! `shaders/field.wgsl` is the f32 twin of this file: `integrate_adaptive` for points, lines and tori and
//! `integrate_adaptive_curves` for curves, dispatched apart (`gpu::field_pass::plan_chunks`).

use glam::DVec3;

use crate::field::{Sources, curve, falloff, line_distance, torus_distance, wseries};
use crate::integrate::{Integration, zeta};

/// Intervals of the scan that locates a torus's or a curve's closest approaches.
pub const SCAN: u32 = 6;
/// Simpson panels in u per piece of a curve before any refinement.
pub const PANELS: u32 = 6;
/// Deepest bisection of a panel.
pub const DEPTH: u32 = 12;
/// Most bisections for one term, all its panels together: bounds a term's work (and its loop iterations on the
/// GPU, which some drivers cap).
pub const SPLITS: u32 = 200;
/// The smallest error asked of a panel, relative to its value.
pub const RELATIVE_FLOOR: f64 = 4e-6;
/// The longest stretch of u one Gauss-Legendre rule covers.
pub const U_PANEL: f64 = 4.0;
/// Most Gauss-Legendre panels on one cut of a piece.
pub const MAX_GAUSS_PANELS: u32 = 4;

/// Gauss-Legendre rules on [-1, 1] for 6, 8, 10, 12 and 16 nodes: the positive nodes with their weights, the
/// rule of `n` nodes starting at `GAUSS_START[k]` (`GAUSS_ORDERS[k] = n`). The WGSL twin holds the same table.
pub const GAUSS_ORDERS: [u32; 5] = [6, 8, 10, 12, 16];
pub const GAUSS_START: [usize; 5] = [0, 3, 7, 12, 18];
pub const GAUSS: [(f64, f64); 26] = [
    (0.23861918608319693, 0.46791393457269126), // 6
    (0.66120938646626459, 0.36076157304813861), // 6
    (0.93246951420315205, 0.17132449237917050), // 6
    (0.18343464249564978, 0.36268378337836199), // 8
    (0.52553240991632899, 0.31370664587788738), // 8
    (0.79666647741362684, 0.22238103445337445), // 8
    (0.96028985649753629, 0.10122853629037679), // 8
    (0.14887433898163122, 0.29552422471475293), // 10
    (0.43339539412924716, 0.26926671930999624), // 10
    (0.67940956829902444, 0.21908636251598218), // 10
    (0.86506336668898454, 0.14945134915058053), // 10
    (0.97390652851717174, 0.06667134430868371), // 10
    (0.12523340851146894, 0.24914704581340288), // 12
    (0.36783149899818018, 0.23349253653835458), // 12
    (0.58731795428661748, 0.20316742672306584), // 12
    (0.76990267419430469, 0.16007832854334633), // 12
    (0.90411725637047480, 0.10693932599531818), // 12
    (0.98156063424671924, 0.04717533638650846), // 12
    (0.09501250983763744, 0.18945061045506847), // 16
    (0.28160355077925892, 0.18260341504492361), // 16
    (0.45801677765722737, 0.16915651939500242), // 16
    (0.61787624440264377, 0.14959598881657682), // 16
    (0.75540440835500300, 0.12462897125553395), // 16
    (0.86563120238783176, 0.09515851168249290), // 16
    (0.94457502307323260, 0.06225352393864778), // 16
    (0.98940093499164994, 0.02715245941175185), // 16
];

/// The Gauss-Legendre order for the scene's tolerance on B: more nodes for a finer tolerance. B is scale free
/// (coefficient over distance), and so is this choice. Measured on the shipped scenes and on rays through a
/// ring, its hole and its axis, each order's largest error stays under its tolerance: 6 nodes 1e-4, 8 nodes 5e-6,
/// 10 nodes 2e-6, 12 and 16 nodes 1e-6 and below (`tests` below, and `energywave bench`).
pub fn gauss_order(tolerance: f64) -> u32 {
    match tolerance {
        t if t >= 1e-3 => 6,
        t if t >= 1e-4 => 8,
        t if t >= 1e-5 => 10,
        t if t >= 1e-6 => 12,
        _ => 16,
    }
}

/// Index of `order` in `GAUSS_ORDERS` (the last for anything else).
pub fn gauss_index(order: u32) -> usize {
    GAUSS_ORDERS
        .iter()
        .position(|&n| n == order)
        .unwrap_or(GAUSS_ORDERS.len() - 1)
}

/// `n`-node Gauss-Legendre on `[a, b]`.
fn gauss_legendre(g: &impl Fn(f64) -> f64, a: f64, b: f64, order: u32) -> f64 {
    let k = gauss_index(order);
    let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
    let pairs = &GAUSS[GAUSS_START[k]..GAUSS_START[k] + GAUSS_ORDERS[k] as usize / 2];
    r * pairs
        .iter()
        .map(|&(x, w)| w * (g(c - r * x) + g(c + r * x)))
        .sum::<f64>()
}

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

/// A feature of one term along the ray and the piece of the ray it owns: the interval `[lo, hi]`, its center
/// `s*` and width `h` (all in s), and `flat`, the half-length of the stretch around `s*` where the source is
/// closer than eps (0 where it is not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub lo: f64,
    pub hi: f64,
    pub center: f64,
    pub width: f64,
    pub flat: f64,
}

/// Widest feature considered: beyond it the map is as good as uniform.
const MAX_WIDTH: f64 = 4.0;
/// Narrowest axis feature: a ray through the axis itself has a true kink there, which a map this narrow
/// resolves as well as any.
const MIN_AXIS_WIDTH: f64 = 1e-4;

/// The peak of a term whose squared distance is `d2(s) = d2_min + a (s - s*)^2`.
fn peak(center: f64, d2_min: f64, a: f64, eps: f64) -> Peak {
    let d2 = d2_min.max(eps * eps);
    let width = if a > 0.0 {
        (d2 / a).sqrt().min(MAX_WIDTH)
    } else {
        MAX_WIDTH
    };
    let flat = if a > 0.0 && d2_min < eps * eps {
        ((eps * eps - d2_min) / a).sqrt()
    } else {
        0.0
    };
    Peak {
        lo: 0.0,
        hi: 1.0,
        center,
        width: width.max(1e-6),
        flat,
    }
}

/// The closest approach of the ray `s + t dir` to the line through `point` along the unit `direction`:
/// `(t*, d*^2, a)` with `d^2(t) = d*^2 + a (t - t*)^2`.
fn line_approach(s: DVec3, dir: DVec3, point: DVec3, direction: DVec3) -> (f64, f64, f64) {
    let q = s - point;
    let q_perp = q - direction * q.dot(direction);
    let d_perp = dir - direction * dir.dot(direction);
    let a = d_perp.length_squared();
    let c = if a > 0.0 {
        -q_perp.dot(d_perp) / a
    } else {
        0.0
    };
    (c, (q_perp + d_perp * c).length_squared(), a)
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
    fn new(torus: &crate::field::Torus, s: DVec3, dir: DVec3) -> Ring {
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

/// Newton steps that find a ring's closest approach, and the longest of them (in t).
const RING_NEWTON: u32 = 6;
const RING_STEP: f64 = 0.125;

/// The features of a term along `s -> e` (at most three), sorted along the ray, each owning its piece.
fn features(term: Term, s: DVec3, e: DVec3, scan: u32, eps: f64) -> ([Peak; 3], usize) {
    let dir = e - s;
    let mut out = [peak(0.0, 0.0, 0.0, eps); 3];
    let count = match term {
        Term::Point(p) => {
            let a = dir.length_squared();
            let c = if a > 0.0 {
                (p.position - s).dot(dir) / a
            } else {
                0.0
            };
            let d2 = (s + dir * c - p.position).length_squared();
            out[0] = peak(c, d2, a, eps);
            1
        }
        Term::Line(l) => {
            let (c, d2, a) = line_approach(s, dir, l.point, l.direction);
            out[0] = peak(c, d2, a, eps);
            1
        }
        Term::Torus(t) => {
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
        Term::Curve(_) => {
            let d2 = |t: f64| {
                let d = term.distance(s + dir * t).0;
                d * d
            };
            let (found, count) = scanned_peaks(d2, scan, eps);
            out[..count].copy_from_slice(&found[..count]);
            count
        }
    };
    share_ray(&mut out[..count]);
    (out, count)
}

/// Sorts features along the ray and gives each its piece: every stretch of the ray goes to the feature whose map
/// is densest there. The map around `s*` places samples `1 / sqrt(h^2 + (s - s*)^2)` apart, so the owner of `s`
/// is the feature with the least `h^2 + (s - s*)^2 = (h^2 + s*^2) - 2 s* s + s^2`: the lower envelope of lines
/// in s. A narrow peak beside a broad feature keeps its whole shoulder and may hide the broad one entirely (whose
/// piece is then empty). At most three features.
fn share_ray(features: &mut [Peak]) {
    features.sort_by(|x, y| x.center.total_cmp(&y.center));
    let n = features.len();
    // Where feature j (further along) takes over from i.
    let meet = |i: usize, j: usize| -> f64 {
        let (x, y) = (features[i], features[j]);
        let gap = y.center - x.center;
        if gap > 0.0 {
            0.5 * (x.center + y.center) + (y.width - x.width) * (y.width + x.width) / (2.0 * gap)
        } else if y.width <= x.width {
            f64::NEG_INFINITY
        } else {
            f64::INFINITY
        }
    };
    let bounds: [f64; 2] = match n {
        2 => [meet(0, 1), 1.0],
        3 => {
            let (b01, b12) = (meet(0, 1), meet(1, 2));
            if b01 < b12 {
                [b01, b12]
            } else {
                // The middle one is nowhere the densest.
                let b02 = meet(0, 2);
                [b02, b02]
            }
        }
        _ => [1.0, 1.0],
    };
    let mut lo = 0.0;
    for (i, f) in features.iter_mut().enumerate() {
        let hi = if i + 1 < n {
            bounds[i].clamp(lo, 1.0)
        } else {
            1.0
        };
        f.lo = lo;
        f.hi = hi;
        f.center = f.center.clamp(lo, hi);
        lo = hi;
    }
}

/// Local minima of `d2` on a scan of `scan` intervals, at most the two deepest, each refined by one parabolic
/// step through its neighbours.
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
    let mut out = [peak(0.0, 0.0, 0.0, eps); 2];
    for (slot, &i) in best.iter().take(count).enumerate() {
        let center = i as f64 * step;
        let g0 = if i > 0 { g[i - 1] } else { d2(center - step) };
        let g2 = if i < k { g[i + 1] } else { d2(center + step) };
        let (c, value, a) = refine(&d2, center, step, g0, g[i], g2);
        out[slot] = peak(c, value, a, eps);
    }
    (out, count)
}

/// One parabolic step from a bracketed minimum at `c` (samples `g0, g1, g2` at `c - h, c, c + h`): the vertex,
/// the value there and the curvature `a` of `d2 ~ value + a (s - vertex)^2`.
fn refine(d2: &impl Fn(f64) -> f64, c: f64, h: f64, g0: f64, g1: f64, g2: f64) -> (f64, f64, f64) {
    let second = g0 - 2.0 * g1 + g2;
    let a = second / (2.0 * h * h);
    let offset = if second > 0.0 {
        (0.5 * h * (g0 - g2) / second).clamp(-h, h)
    } else {
        0.0
    };
    let c = c + offset;
    let value = d2(c);
    (c, value.min(g1).max(0.0), a.max(0.0))
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

/// The cuts of a piece in u: its ends and, for a source closer than eps, the ends of the falloff's flat top.
fn cuts(p: &Peak, u0: f64, u1: f64) -> ([f64; 4], usize) {
    let mut out = [u0, u1, u1, u1];
    let mut n = 2;
    if p.flat > 0.0 {
        let k = (p.flat / p.width).asinh();
        n = 1;
        for u in [-k, k] {
            if u > u0 && u < u1 {
                out[n] = u;
                n += 1;
            }
        }
        out[n] = u1;
        n += 1;
    }
    (out, n)
}

/// One term's integral over its pieces, to `tol` before the coefficient.
fn integrate_term(term: Term, s: DVec3, e: DVec3, settings: &Integration, tol: f64) -> f64 {
    let c = term.coefficient();
    if c == 0.0 {
        return 0.0;
    }
    let (pieces, count) = features(term, s, e, SCAN, settings.epsilon);
    let dir = e - s;
    let f = |t: f64| {
        let (d, w) = term.distance(s + dir * t);
        w * falloff(d, settings.epsilon) * zeta(t, settings.alpha, settings.beta)
    };
    let curve = matches!(term, Term::Curve(_));
    let order = gauss_order(settings.tolerance);
    // Shared between the pieces.
    let tol = tol / count as f64;
    let mut sum = 0.0;
    let mut splits = SPLITS;
    for p in &pieces[..count] {
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
        if curve {
            // Neighbouring panels share their end value.
            let width = (u1 - u0) / PANELS as f64;
            let mut fa = g(u0);
            for i in 0..PANELS {
                let a = u0 + width * i as f64;
                let b = a + width;
                let (fm, fb) = (g(0.5 * (a + b)), g(b));
                sum += adaptive_simpson(
                    &g,
                    a,
                    b,
                    [fa, fm, fb],
                    tol / PANELS as f64,
                    DEPTH,
                    &mut splits,
                );
                fa = fb;
            }
            continue;
        }
        let (cut, n) = cuts(p, u0, u1);
        for w in cut[..n].windows(2) {
            let (a, b) = (w[0], w[1]);
            let panels = ((b - a) / U_PANEL)
                .ceil()
                .clamp(1.0, MAX_GAUSS_PANELS as f64) as u32;
            let width = (b - a) / panels as f64;
            for i in 0..panels {
                let pa = a + width * i as f64;
                sum += gauss_legendre(&g, pa, pa + width, order);
            }
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
        // Two ring passes and, between them, the axis.
        let (p, count) = features(Term::Torus(&sources.tori[0]), s, e, SCAN, 0.01);
        assert_eq!(count, 3);
        assert!((p[0].center - 0.4).abs() < 2e-3 && (p[2].center - 0.6).abs() < 2e-3);
        assert!((p[1].center - 0.5).abs() < 1e-9);
        let want = reference(&sources, s, e, 1 << 20);
        let got = brightness(&sources, &settings(), s, e);
        assert!((got - want).abs() < 2e-3 * want, "{got} vs {want}");
    }

    #[test]
    fn every_gauss_rule_integrates_polynomials_of_degree_2n_minus_1_exactly() {
        for (k, &n) in GAUSS_ORDERS.iter().enumerate() {
            assert_eq!(gauss_index(n), k);
            for degree in 0..2 * n {
                let got = gauss_legendre(&|x: f64| x.powi(degree as i32), -1.0, 1.0, n);
                // The integral of x^k over [-1, 1]: 2 / (k + 1) for even k, 0 for odd.
                let want = if degree % 2 == 0 {
                    2.0 / (degree as f64 + 1.0)
                } else {
                    0.0
                };
                assert!(
                    (got - want).abs() < 1e-14,
                    "{n} nodes, x^{degree}: {got} vs {want}"
                );
            }
        }
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
        let want: Vec<f64> = rays
            .iter()
            .map(|&(s, e)| reference(&sources, s, e, 1 << 18))
            .collect();
        for tolerance in [1e-3, 1e-4, 1e-5, 1e-6] {
            let mut st = settings();
            st.tolerance = tolerance;
            for (&(s, e), &want) in rays.iter().zip(&want) {
                let got = brightness(&sources, &st, s, e);
                assert!(
                    (got - want).abs() < tolerance,
                    "tolerance {tolerance:e}: {got} vs {want} on {s} -> {e}"
                );
            }
        }
    }
}
