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
//! - curves: the local minima of d^2 on a scan of `SCAN + 1` samples (the two deepest), each refined by Newton
//!   steps on the exact slope and curvature of d^2 along the ray (the nearest point moves perpendicular to the
//!   distance, so the slope is that of the distance to a fixed point, and its velocity follows from the
//!   stationarity condition); and the chain's end points, in closed form, where the ray crosses an end's normal
//!   plane and the end's peak is sharper than the minima's. A ray along a straight beam (a beam pointed at the
//!   camera) sees d flat along it, a minimum with no curvature and so a uniform map, and then d grows as the
//!   distance to the end point: a point source's half peak, as narrow as the ray is near the axis.
//!
//! The features, sorted along the ray, share it into pieces: each stretch of the ray goes to the feature whose map
//! is densest there (`share_ray`), so a narrow peak keeps its shoulders beside a broad feature. Where a source
//! comes closer than eps, the falloff's flat top `1 / eps` has a kink at each end; the piece is cut there too
//! (exactly for points and lines, where d^2 is exactly quadratic).
//!
//! **Kinks of a curve.** A chain's distance along a ray is smooth except where its nearest point jumps (the ray
//! crosses the chain's medial surface: a kink in d, a step in W), stops at or leaves an end of the chain (the
//! end's normal plane: a jump in d's second derivative) or passes a joint (the joint's normal plane, where the
//! curvature changes); W adds the places where the nearest point crosses one of its knots (its curvature steps
//! there). Ends and joints are cut in closed form where the scan shows the nearest point there; knots by one
//! Newton step on the nearest point's parameter (`knot_cuts`); jumps are found from the scan too: the nearest
//! point's velocity predicts where it and its chain parameter should land, a miss of more than `JUMP` times the
//! distance (or `PARAM_JUMP` in the parameter) is a jump, and `find_kink` brackets it where the two branches'
//! models cross. Joints are looked for on each stretch between jumps and inside each jump's bracket: a nearest
//! point can jump onto a segment and then pass a joint within one interval of the scan.
//!
//! **Degenerate curves.** Where a segment's speed vanishes at an end (two coincident control points) the end's
//! or the joint's normal plane is taken normal to the second derivative (`curve::tangent_out_of`), and the
//! nearest point's parameter moves like the square root of the distance along the ray from it: the integrand's
//! slope is unbounded on that side of the cut. Such a cut is singular (`Kinks`), and the part beside it is
//! integrated in `x` with `u = a + (b - a) x^2` (`toward_singular`), which makes it smooth again.
//!
//! **One segment a piece.** Between its cuts a chain's nearest point neither jumps nor passes a joint, so it
//! stays on one segment: a piece's first node searches the whole chain, the others solve only that segment's
//! cubic (`curve::nearest_on_chain_from`, which falls back to the whole chain where the segment's nearest point
//! sits at a joint). A safety net behind the cuts: where the nearest segments just inside a part's two ends
//! differ, a jump was missed, and the part is split where the segment changes (`split_at_switch`) and solved on
//! the whole chain.
//!
//! **Rule and error control.** Each part is integrated in panels of at most `U_PANEL` in u by a Gauss-Kronrod
//! pair (`kronrod_order(tolerance)`: n from 4 to 10, Gauss with n nodes inside Kronrod with 2n + 1). A panel is
//! bisected (`integrate_panel`, without a stack) where the two rules differ by more than its share of the
//! tolerance, which is split evenly between the sources and along each term's u, with `refinement_budget`
//! refinements a term at most. The difference of the two rules bounds the Kronrod value's error where the
//! integrand is smooth on the panel; the cuts above are what make it so.
//!
//! **Files.** This file holds what both families share (the Gauss-Kronrod pairs, panels and their refinement,
//! the features' pieces and cuts), twin of `shaders/shared/adaptive.wgsl`; `adaptive_smooth` integrates points, lines and
//! tori (twin of `adaptive_smooth.wgsl`, entry point `integrate_adaptive`), `adaptive_curves` the curve chains
//! (twin of `adaptive_curves.wgsl`, `integrate_adaptive_curves`). The two passes are dispatched apart
//! (`gpu::field_pass::plan_chunks`) and add into the texture, as `field_pass::adaptive` adds the two families. Differences: along a curve's part the shader visits the nodes in order
//! along the ray and carries each nearest point on from the last node's (its rate du/dt, then two Newton
//! steps on the segment, over at most `TRACK_REACH` of it), solving the cubic in closed form only where a part
//! begins or Newton has not settled; this twin solves every node in closed form. Both find the same nearest
//! point, to f32 rounding there. So with a curve's brightest point (the continuous W form): the shader carries it
//! on its piece by Newton's method on the piece's h where every other piece's bound stays below its value, and
//! this twin searches the whole chain at every node. And in f32 two rules agreeing within 4e-6 of their value count as agreeing
//! (`ROUNDING` here is 1e-13). The tests hold the GPU to this twin.

use crate::integrate::adaptive::{
    CUT_MERGE, KRONROD, KRONROD_ORDERS, KRONROD_START, MAX_DEPTH, MAX_GAUSS_PANELS, MAX_KINKS,
    MAX_PEAKS, MAX_WIDTH, SINGULAR_MERGE, U_PANEL, kronrod_index, refinement_budget,
};
use glam::DVec3;

/// The Kronrod and the Gauss value of `g` on `[a, b]` with the pair of `order`.
fn kronrod(g: &impl Fn(f64) -> f64, a: f64, b: f64, order: u32) -> (f64, f64) {
    let k = kronrod_index(order);
    let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
    let rows = &KRONROD[KRONROD_START[k]..=KRONROD_START[k] + KRONROD_ORDERS[k] as usize];
    let centre = g(c);
    let (mut kronrod, mut gauss) = (rows[0].1 * centre, rows[0].2 * centre);
    for &(x, wk, wg) in &rows[1..] {
        let pair = g(c - r * x) + g(c + r * x);
        kronrod += wk * pair;
        gauss += wg * pair;
    }
    (r * kronrod, r * gauss)
}

/// A part's rules agreeing within this share of its value count as agreeing, whatever the allowance: the f64
/// rounding of a sum of nodes (the f32 twin's is `4e-6`).
pub const ROUNDING: f64 = 1e-13;

/// How much a term's Gauss and Kronrod values may differ per unit of u with the rms decay: B is `sqrt(J / stretch)`
/// of the integral J of the squared term, and an error dJ costs about `dJ / (2 sqrt(stretch J))` of B, so J may err
/// by `tolerance sqrt(stretch J)` (half what B allows), J estimated by the term's panels unrefined, and at least by
/// `tolerance^2 stretch` (`|sqrt(x) - sqrt(y)| <= sqrt(|x - y|)`); shared evenly along its u `length`. `estimate`
/// is J without the factor `scale` (`b^2`) the integrand was taken without.
pub(super) fn rms_allowance(
    (tolerance, stretch): (f64, f64),
    estimate: f64,
    scale: f64,
    length: f64,
) -> f64 {
    let per_b = (tolerance * (stretch * scale * estimate.max(0.0)).sqrt())
        .max(tolerance * tolerance * stretch);
    per_b / (scale * length.max(1e-300))
}

/// `g` on `[a, b]`, refined where its Gauss and Kronrod values differ by more than `allowance` per unit of
/// length: the parts of a dyadic bisection of `[a, b]`, visited in order (without a stack: after a part is
/// accepted the next starts where it ended, as large as its position allows), each accepted with its Kronrod
/// value once within its share of the allowance, at `MAX_DEPTH`, or once the term's `refinements` are spent.
fn integrate_panel(
    g: &impl Fn(f64) -> f64,
    (a, b): (f64, f64),
    order: u32,
    allowance: f64,
    refinements: &mut u32,
) -> f64 {
    let end = 1u32 << MAX_DEPTH;
    let (mut at, mut level, mut sum) = (0u32, 0u32, 0.0);
    while at < end {
        let size = end >> level;
        let x0 = a + (b - a) * (at as f64 / end as f64);
        let x1 = a + (b - a) * ((at + size) as f64 / end as f64);
        let (k, gauss) = kronrod(g, x0, x1, order);
        let settled = (k - gauss).abs() <= (allowance * (x1 - x0)).max(ROUNDING * k.abs());
        if settled || level == MAX_DEPTH || *refinements == 0 {
            sum += k;
            at += size;
            // Up while this part ended its parent.
            while level > 0 && at & ((end >> (level - 1)) - 1) == 0 {
                level -= 1;
            }
        } else {
            *refinements -= 1;
            level += 1;
        }
    }
    sum
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

/// The peak of a term whose squared distance is `d2(s) = d2_min + a (s - s*)^2`.
pub(super) fn peak(center: f64, d2_min: f64, a: f64, eps: f64) -> Peak {
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
pub(super) fn line_approach(
    s: DVec3,
    dir: DVec3,
    point: DVec3,
    direction: DVec3,
) -> (f64, f64, f64) {
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

/// A term's features along the ray, each owning its piece, and the kinks where a curve's nearest point jumps.
pub(super) struct Features {
    pub(super) peaks: [Peak; MAX_PEAKS],
    pub(super) count: usize,
    pub(super) kinks: Kinks,
}

/// The kinks of a chain along the ray (in t), at most `MAX_KINKS` (more are dropped), and which of them are
/// singular: bit `k` of `singular` where the nearest point leaves a point of the chain whose speed vanishes (an
/// end or a joint where two control points coincide), so that its parameter moves like the square root of the
/// distance along the ray from the cut: the integrand's slope is unbounded there, on one side.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Kinks {
    pub(super) at: [f64; MAX_KINKS],
    pub(super) count: usize,
    pub(super) singular: u32,
}

impl Kinks {
    pub(super) fn push(&mut self, t: f64) {
        self.push_cut(t, false);
    }

    pub(super) fn push_cut(&mut self, t: f64, singular: bool) {
        if self.count < MAX_KINKS {
            self.at[self.count] = t;
            self.singular |= (singular as u32) << self.count;
            self.count += 1;
        }
    }
}

/// Sorts features along the ray and gives each its piece: every stretch of the ray goes to the feature whose map
/// is densest there. The map around `s*` places samples `1 / sqrt(h^2 + (s - s*)^2)` apart, so the owner of `s`
/// is the feature with the least `h^2 + (s - s*)^2 = (h^2 + s*^2) - 2 s* s + s^2`: the lower envelope of lines
/// in s. A narrow peak beside a broad feature keeps its whole shoulder and may hide the broad one entirely (whose
/// piece is then empty).
pub(super) fn share_ray(features: &mut [Peak]) {
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
    // Feature i hands over at the first takeover by any later one. One that is nowhere the densest is taken
    // over before the feature before it hands over (the lower envelope's order), so its piece comes out empty.
    let mut bounds = [1.0; MAX_PEAKS];
    let mut lo = 0.0;
    for (i, bound) in bounds.iter_mut().enumerate().take(n.saturating_sub(1)) {
        let to = (i + 1..n).map(|j| meet(i, j)).fold(f64::INFINITY, f64::min);
        *bound = to.clamp(lo, 1.0);
        lo = *bound;
    }
    let mut lo = 0.0;
    for (f, &hi) in features.iter_mut().zip(&bounds) {
        f.lo = lo;
        f.hi = hi;
        f.center = f.center.clamp(lo, hi);
        lo = hi;
    }
}

/// Most cuts of a piece in u: its ends, the flat top's two ends and the kinks.
const MAX_CUTS: usize = 4 + MAX_KINKS;

/// The cuts of a piece in u, sorted, each with whether it is singular (`Kinks`): its ends, for a source closer
/// than eps the ends of the falloff's flat top, and the kinks (in s) inside the piece.
fn cuts(p: &Peak, u0: f64, u1: f64, kinks: &Kinks) -> ([(f64, bool); MAX_CUTS], usize) {
    let mut out = [(u1, false); MAX_CUTS];
    out[0] = (u0, false);
    let mut n = 1;
    let mut add = |u: f64, singular: bool| {
        if u > u0 && u < u1 {
            out[n] = (u, singular);
            n += 1;
        }
    };
    if p.flat > 0.0 {
        let k = (p.flat / p.width).asinh();
        add(-k, false);
        add(k, false);
    }
    let u: [f64; MAX_KINKS] = kinks.at.map(|kink| ((kink - p.center) / p.width).asinh());
    let singular = |k: usize| kinks.singular >> k & 1 == 1;
    for k in 0..kinks.count {
        // An ordinary cut this close to a singular one is dropped: the jump search finds false jumps where a
        // nearest point leaves a point at rest (its speed grows like a square root), and a part starting there
        // would lose the singular end's map.
        let shadowed = !singular(k)
            && (0..kinks.count).any(|m| singular(m) && (u[m] - u[k]).abs() <= SINGULAR_MERGE);
        if !shadowed {
            add(u[k], singular(k));
        }
    }
    out[..n].sort_by(|x, y| x.0.total_cmp(&y.0));
    out[n] = (u1, false);
    // Cuts within CUT_MERGE of the first of a cluster are one: at its first singular cut if any (the piece's
    // start stays put), singular if any is, the piece's end taking the place of a cluster it falls into. A sliver
    // between them would spend the term's refinements, and hide a singular cut behind an ordinary one.
    let (mut kept, mut start) = (1, out[0].0);
    for k in 1..=n {
        let (u, singular) = out[k];
        if u - start > CUT_MERGE {
            out[kept] = out[k];
            (kept, start) = (kept + 1, u);
        } else if k == n {
            if kept == 1 {
                kept = 2;
            }
            out[kept - 1].0 = u;
        } else {
            if singular && !out[kept - 1].1 && kept > 1 {
                out[kept - 1].0 = u;
            }
            out[kept - 1].1 |= singular;
        }
    }
    (out, kept)
}

/// `g` on `[a, b]` with the nodes drawn toward an end where the integrand behaves like the square root of the
/// distance from it (`singular_a`, `singular_b`): `u = a + (b - a) phi(x)` with `phi(x) = x^2` toward a,
/// `1 - (1 - x)^2` toward b, `3 x^2 - 2 x^3` toward both, whose slope vanishes at the singular end, so that
/// `sqrt(u - a)` is smooth in x. The function of x on [a, b] to integrate instead, and whether it is mapped.
fn toward_singular(
    g: &impl Fn(f64) -> f64,
    (a, b): (f64, f64),
    (singular_a, singular_b): (bool, bool),
) -> impl Fn(f64) -> f64 {
    move |v: f64| {
        let x = (v - a) / (b - a);
        let (phi, slope) = match (singular_a, singular_b) {
            (false, false) => (x, 1.0),
            (true, false) => (x * x, 2.0 * x),
            (false, true) => (x * (2.0 - x), 2.0 - 2.0 * x),
            (true, true) => (x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x)),
        };
        g(a + (b - a) * phi) * slope
    }
}

/// A term's integral over the pieces its features own, within `tolerance` on B, for the term's coefficient `c`
/// and its integrand along the ray `f(t)` (W series and zeta included, the coefficient not): each piece is cut at
/// its kinks (`cuts`), each cut stretch split further by `parts` (a chain's nearest segment changing, which also
/// prepares `f` for the part; the smooth sources keep the stretch whole), each part into panels of at most
/// `U_PANEL` in u, and each panel refined where its Gauss and Kronrod values differ (`integrate_panel`), the
/// tolerance shared out along u. A part beside a singular cut is integrated toward it (`toward_singular`).
pub(super) fn integrate_pieces(
    found: &Features,
    (c, f): (f64, &impl Fn(f64) -> f64),
    order: u32,
    (tolerance, rms): (f64, Option<f64>),
    mut parts: impl FnMut(&Peak, (f64, bool), (f64, bool)) -> ([(f64, f64); 2], usize),
) -> f64 {
    let pieces = found.peaks[..found.count].iter().map(|p| {
        let u0 = ((p.lo - p.center) / p.width).asinh();
        let u1 = ((p.hi - p.center) / p.width).asinh();
        (p, u0, u1)
    });
    let length: f64 = pieces.clone().map(|(_, u0, u1)| (u1 - u0).max(0.0)).sum();
    let mut allowance = tolerance / (c.abs() * length.max(1e-300));
    // The rms decay's allowance comes from an estimate of its integral: the same panels unrefined, a pass before.
    let passes = if rms.is_some() { 2 } else { 1 };
    let mut sum = 0.0;
    for pass in 0..passes {
        let mut refinements = if pass + 1 < passes {
            0
        } else {
            refinement_budget(order)
        };
        sum = 0.0;
        for (p, u0, u1) in pieces.clone() {
            if u1 <= u0 {
                continue;
            }
            // The integrand in u: f(s(u)) ds/du.
            let g = |u: f64| {
                let t = (p.center + p.width * u.sinh()).clamp(p.lo, p.hi);
                f(t) * p.width * u.cosh()
            };
            let (cut, n) = cuts(p, u0, u1, &found.kinks);
            for w in cut[..n].windows(2) {
                let ((a, singular_a), (b, singular_b)) = (w[0], w[1]);
                let (split, count) = parts(p, (a, singular_a), (b, singular_b));
                for (k, &(a, b)) in split[..count].iter().enumerate() {
                    if b <= a {
                        continue;
                    }
                    let (singular_a, singular_b) =
                        (singular_a && k == 0, singular_b && k + 1 == count);
                    let panels = ((b - a) / U_PANEL)
                        .ceil()
                        .clamp(1.0, MAX_GAUSS_PANELS as f64)
                        as u32;
                    let width = (b - a) / panels as f64;
                    for i in 0..panels {
                        let pa = a + width * i as f64;
                        let ends = (singular_a && i == 0, singular_b && i + 1 == panels);
                        let mapped = toward_singular(&g, (pa, pa + width), ends);
                        sum += integrate_panel(
                            &mapped,
                            (pa, pa + width),
                            order,
                            allowance,
                            &mut refinements,
                        );
                    }
                }
            }
        }
        if let (Some(stretch), true) = (rms, pass + 1 < passes) {
            allowance = rms_allowance((tolerance, stretch), sum, c.abs(), length);
        }
    }
    c * sum
}

#[cfg(test)]
/// What the families' tests share: the converged reference they are held to.
pub(super) mod testing {
    use glam::DVec3;

    use crate::field::Sources;
    use crate::integrate::{Integration, zeta};
    use crate::reference::simpson::simpson;

    pub fn settings() -> Integration {
        Integration::default()
    }

    /// The converged integral by Simpson with many samples.
    pub fn reference(sources: &Sources, s: DVec3, e: DVec3, n: u32) -> f64 {
        let st = settings();
        let field = sources.field();
        simpson(
            |t| field.psi(s + (e - s) * t, st.epsilon) * zeta(t, st.alpha, st.beta),
            n,
        )
    }

    /// Every ray's B by `brightness` (a family of the adaptive integrator, on sources of that family) within each
    /// tolerance of Simpson's with 2^18 intervals.
    pub fn assert_within_each_tolerance(
        brightness: impl Fn(&Sources, &Integration, DVec3, DVec3) -> f64,
        sources: &Sources,
        rays: &[(DVec3, DVec3)],
        tolerances: &[f64],
    ) {
        let want: Vec<f64> = rays
            .iter()
            .map(|&(s, e)| reference(sources, s, e, 1 << 18))
            .collect();
        for &tolerance in tolerances {
            let mut st = settings();
            st.tolerance = tolerance;
            for (&(s, e), &want) in rays.iter().zip(&want) {
                let got = brightness(sources, &st, s, e);
                assert!(
                    (got - want).abs() < tolerance,
                    "tolerance {tolerance:e}: {got} vs {want} on {s} -> {e}"
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kronrod_pair_integrates_polynomials_to_its_degree_exactly() {
        // The Kronrod rule of 2n + 1 nodes is exact to degree 3n + 1, its Gauss rule of n nodes to 2n - 1, and
        // the Gauss rule is not exact at degree 2n: the integral of x^k over [-1, 1] is 2 / (k + 1) for even k.
        let moment = |k: u32| {
            if k.is_multiple_of(2) {
                2.0 / (k as f64 + 1.0)
            } else {
                0.0
            }
        };
        for (k, &n) in KRONROD_ORDERS.iter().enumerate() {
            assert_eq!(kronrod_index(n), k);
            for degree in 0..=3 * n + 1 {
                let (kronrod, gauss) = kronrod(&|x: f64| x.powi(degree as i32), -1.0, 1.0, n);
                let want = moment(degree);
                assert!(
                    (kronrod - want).abs() < 1e-14,
                    "K{}, x^{degree}: {kronrod} vs {want}",
                    2 * n + 1
                );
                if degree < 2 * n {
                    assert!(
                        (gauss - want).abs() < 1e-14,
                        "G{n}, x^{degree}: {gauss} vs {want}"
                    );
                }
            }
            let (_, gauss) = kronrod(&|x: f64| x.powi(2 * n as i32), -1.0, 1.0, n);
            assert!(
                (gauss - moment(2 * n)).abs() > 1e-6,
                "G{n} is not exact at degree {}",
                2 * n
            );
        }
    }

    #[test]
    fn share_ray_gives_every_stretch_to_the_densest_map() {
        // Against brute force: for up to MAX_PEAKS random features (some sharing a center, some far off the
        // ray), the pieces tile [0, 1] in order and every point belongs to a feature with the least
        // h^2 + (s - s*)^2 there.
        let mut state = 0x2545_f491_u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for round in 0..4000 {
            let n = 1 + round % MAX_PEAKS;
            let mut found: Vec<Peak> = (0..n)
                .map(|_| {
                    let center = if uniform() < 0.2 {
                        0.5
                    } else {
                        1.6 * uniform() - 0.3
                    };
                    let width = 10f64.powf(-4.0 * uniform());
                    peak(center, width * width, 1.0, 0.0)
                })
                .collect();
            let original = found.clone();
            share_ray(&mut found);
            assert_eq!(found[0].lo, 0.0);
            assert_eq!(found[n - 1].hi, 1.0);
            for pair in found.windows(2) {
                assert!(pair[0].center <= pair[1].center && pair[0].hi == pair[1].lo);
            }
            for k in 0..=200 {
                let x = k as f64 / 200.0;
                let density = |p: &Peak| p.width * p.width + (x - p.center).powi(2);
                let best = original.iter().map(density).fold(f64::INFINITY, f64::min);
                let owner = found
                    .iter()
                    .position(|p| p.lo <= x && x <= p.hi && p.lo < p.hi);
                let owner =
                    owner.map(|i| original.iter().find(|p| p.width == found[i].width).unwrap());
                let got = density(owner.expect("every point has an owner"));
                assert!(
                    got <= best * (1.0 + 1e-9) + 1e-15,
                    "round {round}, s = {x}: owner {got}, best {best}: {found:?}"
                );
            }
        }
    }
}
