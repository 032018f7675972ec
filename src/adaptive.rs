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
//! `shaders/adaptive.wgsl` with `adaptive_smooth.wgsl` and `adaptive_curves.wgsl` is the f32 twin of this file:
//! `integrate_adaptive` for points, lines and tori and `integrate_adaptive_curves` for curves, dispatched apart
//! (`gpu::field_pass::plan_chunks`). Differences: along a curve's part the shader visits the nodes in order
//! along the ray and carries each nearest point on from the last node's (its rate du/dt, then two Newton
//! steps on the segment, over at most `TRACK_REACH` of it), solving the cubic in closed form only where a part
//! begins or Newton has not settled; this twin solves every node in closed form. Both find the same nearest
//! point, to f32 rounding there. And in f32 two rules agreeing within 4e-6 of their value count as agreeing
//! (`ROUNDING` here is 1e-13). The tests hold the GPU to this twin.

use std::cell::Cell;

use glam::DVec3;

use crate::field::{Sources, curve, falloff, line_distance, torus_distance, wseries};
use crate::integrate::{Integration, falloff_integral, zeta};

/// Intervals of the scan along a curve's ray, which finds its closest approaches and kinks.
pub const SCAN: u32 = 6;
/// A chain's nearest point jumps between two samples where it lands farther than this many times the distance
/// from where a smooth motion would have taken it.
pub const JUMP: f64 = 0.1;
/// Or where its chain parameter lands farther than this from where its rate would have taken it (`miss`).
pub const PARAM_JUMP: f64 = 0.05;
/// Most rounds of the kink search, each one or two probes. (Two are not enough: a kink misplaced by 5e-3 where W
/// steps across it costs 5e-4 on a ray of the mixed scene.)
pub const KINK_ROUNDS: u32 = 12;
/// The kink search stops when its bracket is this short (in t, the ray being 1 long).
pub const KINK_BRACKET: f64 = 1e-3;

/// How short the kink search's bracket gets with the pair of `order`: `KINK_BRACKET` at the default tolerance
/// and coarser, 1e-5 for a finer one (a W step misplaced by 1e-3 costs about 3e-5 on the seven-weight preset).
pub fn kink_bracket(order: u32) -> f64 {
    if order <= 5 { KINK_BRACKET } else { 1e-5 }
}
/// How far either side of its estimate a round of the kink search probes, relative to the bracket.
pub const KINK_PROBE: f64 = 0.05;
/// Most kinks cut on one curve's ray.
pub const MAX_KINKS: usize = 8;
/// The longest stretch of u one panel (one Gauss-Kronrod pair before refinement) covers.
pub const U_PANEL: f64 = 4.0;
/// Most panels on one cut of a piece. This and the other settings here the WGSL twin uses are declared in it
/// from these definitions (`gpu::shaders::shared_constants`).
pub const MAX_GAUSS_PANELS: u32 = 8;

/// Gauss-Kronrod pairs on [-1, 1]: the Gauss-Legendre rule of `n` nodes and the Kronrod rule of `2n + 1` nodes
/// that contains it, for `n` in `KRONROD_ORDERS`. Rule `k` is `n + 1` rows from `KRONROD_START[k]`: each a node
/// `x >= 0` (the first is 0) with its Kronrod weight and its Gauss weight (0 where `x` is a Kronrod node only). The
/// difference of the two rules on an interval bounds the error of the Kronrod value there, which the integrator
/// refines until it is within its share of the tolerance (`integrate_panel`). Computed to 60 digits (the
/// Stieltjes polynomial's roots, then the weights from the moments) and printed to 17; `tests` below check that
/// the Kronrod rule of `n` is exact to degree `3n + 1` and the Gauss rule to `2n - 1`. The WGSL twin's table is
/// written from this one (`gpu::shaders::shared_constants`).
pub const KRONROD_ORDERS: [u32; 7] = [3, 4, 5, 6, 7, 8, 10];
pub const KRONROD_START: [usize; 7] = [0, 4, 9, 15, 22, 30, 39];
#[allow(clippy::excessive_precision)]
pub const KRONROD: [(f64, f64, f64); 50] = [
    (0.0, 0.45091653865847414, 0.88888888888888889), // 3
    (0.43424374934680256, 0.40139741477596222, 0.0), // 3
    (
        0.77459666924148338,
        0.26848808986833344,
        0.55555555555555556,
    ), // 3
    (0.96049126870802028, 0.10465622602646727, 0.0), // 3
    (0.0, 0.34644298189013636, 0.0),                 // 4
    (
        0.33998104358485626,
        0.32694918960145163,
        0.65214515486254614,
    ), // 4
    (0.64028621749630998, 0.26679834045228445, 0.0), // 4
    (
        0.86113631159405258,
        0.17005360533572273,
        0.34785484513745386,
    ), // 4
    (0.97656025073757311, 0.062977373665473015, 0.0), // 4
    (0.0, 0.28298741785749121, 0.56888888888888889), // 5
    (0.27963041316178319, 0.27284980191255892, 0.0), // 5
    (
        0.53846931010568309,
        0.24104033922864759,
        0.47862867049936647,
    ), // 5
    (0.75416672657084922, 0.18680079655649266, 0.0), // 5
    (
        0.90617984593866399,
        0.11523331662247339,
        0.23692688505618909,
    ), // 5
    (0.98408536009484246, 0.042582036751081833, 0.0), // 5
    (0.0, 0.24107258017346476, 0.0),                 // 6
    (
        0.23861918608319691,
        0.23377086411699441,
        0.46791393457269105,
    ), // 6
    (0.46311821247530461, 0.21320965227196228, 0.0), // 6
    (
        0.66120938646626451,
        0.18107199432313762,
        0.36076157304813861,
    ), // 6
    (0.82137334086502794, 0.13732060463444692, 0.0), // 6
    (
        0.93246951420315203,
        0.083694440446906626,
        0.17132449237917035,
    ), // 6
    (0.98870320261267886, 0.030396154119819769, 0.0), // 6
    (0.0, 0.20948214108472783, 0.41795918367346939), // 7
    (0.20778495500789847, 0.20443294007529889, 0.0), // 7
    (
        0.40584515137739717,
        0.19035057806478541,
        0.38183005050511894,
    ), // 7
    (0.58608723546769113, 0.1690047266392679, 0.0),  // 7
    (
        0.74153118559939444,
        0.14065325971552592,
        0.27970539148927667,
    ), // 7
    (0.86486442335976907, 0.10479001032225018, 0.0), // 7
    (
        0.94910791234275852,
        0.063092092629978553,
        0.12948496616886969,
    ), // 7
    (0.99145537112081264, 0.022935322010529225, 0.0), // 7
    (0.0, 0.18444640574469164, 0.0),                 // 8
    (0.1834346424956498, 0.18140002506803464, 0.36268378337836198), // 8
    (0.36070109792813196, 0.17207060855521131, 0.0), // 8
    (0.52553240991632899, 0.1566526061681884, 0.31370664587788729), // 8
    (0.67235407094515868, 0.13626310925517222, 0.0), // 8
    (
        0.79666647741362674,
        0.11164637082683961,
        0.22238103445337447,
    ), // 8
    (0.89412090684745642, 0.082482298931358331, 0.0), // 8
    (
        0.96028985649753623,
        0.049439395002139309,
        0.10122853629037626,
    ), // 8
    (0.99337987588171616, 0.017822383320710355, 0.0), // 8
    (0.0, 0.14944555400291691, 0.0),                 // 10
    (
        0.14887433898163121,
        0.14773910490133849,
        0.29552422471475287,
    ), // 10
    (0.2943928627014602, 0.14277593857706008, 0.0),  // 10
    (
        0.43339539412924719,
        0.13470921731147333,
        0.26926671930999636,
    ), // 10
    (0.56275713466860468, 0.12349197626206585, 0.0), // 10
    (
        0.67940956829902441,
        0.10938715880229764,
        0.21908636251598204,
    ), // 10
    (0.7808177265864169, 0.093125454583697606, 0.0), // 10
    (
        0.86506336668898451,
        0.075039674810919953,
        0.14945134915058059,
    ), // 10
    (0.93015749135570823, 0.054755896574351996, 0.0), // 10
    (
        0.97390652851717172,
        0.032558162307964727,
        0.066671344308688138,
    ), // 10
    (0.99565716302580808, 0.011694638867371874, 0.0), // 10
];

/// The Gauss-Kronrod pair for the scene's tolerance on B: a higher order for a finer tolerance, so that smooth
/// pieces pass the error test without refinement. B is scale free (coefficient over distance), and so is this
/// choice.
pub fn kronrod_order(tolerance: f64) -> u32 {
    match tolerance {
        t if t >= 1e-3 => 4,
        t if t >= 1e-4 => 5,
        t if t >= 1e-5 => 6,
        t if t >= 1e-6 => 7,
        t if t >= 1e-7 => 8,
        _ => 10,
    }
}

/// Index of `order` in `KRONROD_ORDERS` (the last for anything else).
pub fn kronrod_index(order: u32) -> usize {
    KRONROD_ORDERS
        .iter()
        .position(|&n| n == order)
        .unwrap_or(KRONROD_ORDERS.len() - 1)
}

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

/// Levels of bisection of a panel at most: its smallest part is `2^-MAX_DEPTH` of it.
pub const MAX_DEPTH: u32 = 10;
/// Parts a term may refine beyond its panels at most (each refinement spends two more rules).
pub const MAX_REFINEMENTS: u32 = 24;

/// The refinements a term may spend with the pair of `order`: 8 at the default tolerance and coarser (lavapipe
/// stops a shader invocation after 65535 loop iterations, and a term's parts solved on the whole chain cost the
/// most), `MAX_REFINEMENTS` for a finer one.
pub fn refinement_budget(order: u32) -> u32 {
    if order <= 5 { 8 } else { MAX_REFINEMENTS }
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

    /// `distance` at a point of one piece of the ray, where a chain's nearest point stays on one segment or
    /// moves on from it through a joint: only that segment is solved (`curve::nearest_on_chain_from`).
    fn distance_on_piece(&self, p: DVec3, segment: &mut Option<usize>) -> (f64, f64) {
        match self {
            Term::Curve(s) => {
                let n = curve::nearest_on_chain_from(&s.control_points, p, segment);
                (n.distance, wseries::evaluate(&s.weights, n.t))
            }
            _ => self.distance(p),
        }
    }

    /// The segment of a chain's nearest point to `p` (`None` at a joint, and for the other kinds).
    fn segment_at(&self, p: DVec3) -> Option<usize> {
        match self {
            Term::Curve(s) => curve::nearest_segment_index(&s.control_points, p),
            _ => None,
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
pub const MAX_WIDTH: f64 = 4.0;
/// Narrowest axis feature: a ray through the axis itself has a true kink there, which a map this narrow
/// resolves as well as any.
pub const MIN_AXIS_WIDTH: f64 = 1e-4;

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
pub const RING_NEWTON: u32 = 6;
pub const RING_STEP: f64 = 0.125;

/// Most features of one term: a torus's two ring passes and its axis, or a chain's two closest approaches and its
/// two ends.
pub const MAX_PEAKS: usize = 4;

/// A term's features along the ray, each owning its piece, and the kinks where a curve's nearest point jumps.
struct Features {
    peaks: [Peak; MAX_PEAKS],
    count: usize,
    kinks: Kinks,
}

/// The features of a term along `s -> e` (at most `MAX_PEAKS`), sorted along the ray, each owning its piece.
/// The closest approach of the ray `s + t dir` to the point `p`: `(t*, d*^2, a)` with `d^2(t) = d*^2 + a (t - t*)^2`.
fn point_approach(s: DVec3, dir: DVec3, p: DVec3) -> (f64, f64, f64) {
    let a = dir.length_squared();
    let c = if a > 0.0 { (p - s).dot(dir) / a } else { 0.0 };
    (c, (s + dir * c - p).length_squared(), a)
}

/// Most cancellation the closed form of a point's or a line's term may suffer before the integrator takes it
/// numerically instead (`integrate::falloff_integral`'s `condition`): in f32 (the shader, which uses the same
/// bound) a term's error stays within about 2e-5 of it, measured over 200 000 random rays; the terms declined
/// are those of a source close to the decay's pole at s = -beta.
pub const CLOSED_FORM_CONDITION: f64 = 16.0;

fn features(term: Term, s: DVec3, e: DVec3, scan: u32, eps: f64, bracket: f64) -> Features {
    let dir = e - s;
    let mut out = [peak(0.0, 0.0, 0.0, eps); MAX_PEAKS];
    let mut kinks = Kinks::default();
    let count = match term {
        Term::Point(p) => {
            let (c, d2, a) = point_approach(s, dir, p.position);
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
        Term::Curve(c) => {
            let (found, count) = chain_features(c, s, dir, (scan, eps, bracket), &mut kinks);
            out[..count].copy_from_slice(&found[..count]);
            count
        }
    };
    share_ray(&mut out[..count]);
    Features {
        peaks: out,
        count,
        kinks,
    }
}

/// A chain's closest approaches along the ray `s + t dir` and its kinks (appended to `kinks`), in one pass over
/// the scan's `scan` intervals:
/// - the closest approaches: the two deepest local minima of d^2 on the scan, refined by Newton (`chain_peaks`);
/// - the chain's ends: where the ray crosses the normal plane at an end, the nearest point starts (or stops)
///   moving along the chain, so d turns from the distance to the end point to the distance to the curve, smoothly
///   but with a jump in its second derivative. Where a scan sample beside the crossing is at that end, the
///   crossing is cut and sampled, and its interval split there: the side at the end with the point at rest, the
///   other with it moving off. On the side at rest d is exactly the distance to the end point, a point source's
///   peak, which is also a feature where it is sharper than the closest approaches (`with_ends`): a ray along a
///   straight beam sees d flat along it (no curvature, a uniform map) and then a narrow fall past each end;
/// - the jumps of the nearest point in each (part of an) interval (`search_jumps`).
fn chain_features(
    c: &crate::field::Curve,
    s: DVec3,
    dir: DVec3,
    (scan, eps, bracket): (u32, f64, f64),
    kinks: &mut Kinks,
) -> ([Peak; MAX_PEAKS], usize) {
    let sample = |t: f64| ChainSample::at(c, s, dir, t, false);
    let k = scan.max(2);
    let step = 1.0 / k as f64;
    let cp = &c.control_points;
    let last = cp.len() - 1;
    let segments = (cp.len() - 1) / 2;
    let mut ends = [
        (cp[0], curve::tangent_out_of(cp, 0), 0.0),
        (cp[last], curve::tangent_into(cp, segments), 1.0),
    ]
    .map(|(end, (tangent, rest), at_end)| {
        ((end - s).dot(tangent) / dir.dot(tangent), at_end, rest)
    });
    if ends[1].0 < ends[0].0 {
        ends.swap(0, 1);
    }
    let mut end_peaks = [peak(0.0, 0.0, 0.0, eps); 2];
    let mut end_count = 0;
    let mut minima = Minima::default();
    let mut before = sample(0.0);
    let mut g_before_before = f64::INFINITY;
    for i in 1..=k {
        let after = sample(i as f64 * step);
        minima.offer(before, g_before_before, after.d2);
        // The interval (before, after), split at the ends' normal planes inside it. `calm` starts the stretch
        // since the last jump, which the joints' cuts look at.
        let mut left = before;
        let mut calm = before;
        for &(t, at_end, rest) in &ends {
            // Half open, so that a crossing on a sample is cut once.
            let inside = t > before.t && t <= after.t;
            if !inside || (!at(&before, at_end) && !at(&after, at_end)) {
                continue;
            }
            let moving = ChainSample::at(c, s, dir, t, true);
            let at_rest = ChainSample {
                velocity: DVec3::ZERO,
                rate: 0.0,
                curvature: 2.0 * dir.length_squared(),
                ..moving
            };
            let (x, y) = if at(&left, at_end) {
                (at_rest, moving)
            } else {
                (moving, at_rest)
            };
            kinks.push_cut(t, rest);
            let end = if at_end == 0.0 { cp[0] } else { cp[last] };
            let a = dir.length_squared();
            let center = (end - s).dot(dir) / a;
            end_peaks[end_count] = peak(center, (s + dir * center - end).length_squared(), a, eps);
            end_count += 1;
            // A ray through the end closer than eps: the falloff's flat top ends where the end point is eps away.
            if moving.d2 < eps * eps {
                let q = s - moving.point;
                let (a, b, c) = (
                    dir.length_squared(),
                    dir.dot(q),
                    q.length_squared() - eps * eps,
                );
                let root = (b * b - a * c).max(0.0).sqrt();
                for t in [(-b - root) / a, (-b + root) / a] {
                    if t > 0.0 && t < 1.0 {
                        kinks.push(t);
                    }
                }
            }
            if let Some((a1, b1)) = search_jumps(&sample, (s, dir), left, x, (eps, bracket), kinks)
            {
                joint_cuts(cp, (s, dir), [&calm, &a1, &b1], kinks);
                knot_cuts(&sample, c.weights.len(), &calm, &a1, kinks);
                calm = b1;
            }
            left = y;
        }
        if let Some((a1, b1)) = search_jumps(&sample, (s, dir), left, after, (eps, bracket), kinks)
        {
            joint_cuts(cp, (s, dir), [&calm, &a1, &b1], kinks);
            knot_cuts(&sample, c.weights.len(), &calm, &a1, kinks);
            calm = b1;
        }
        joint_cuts(cp, (s, dir), [&calm, &after, &after], kinks);
        knot_cuts(&sample, c.weights.len(), &calm, &after, kinks);
        g_before_before = before.d2;
        before = after;
    }
    minima.offer(before, g_before_before, f64::INFINITY);
    let (peaks, count) = chain_peaks(&sample, &minima, step, eps);
    with_ends(peaks, count, &end_peaks[..end_count])
}

/// The closest approaches and, after them, each end's peak whose map at its center is more than twice as dense as
/// every feature's before it (where an end is the closest approach, Newton has found it already).
fn with_ends(found: [Peak; 2], count: usize, ends: &[Peak]) -> ([Peak; MAX_PEAKS], usize) {
    let mut out = [found[0]; MAX_PEAKS];
    out[..count].copy_from_slice(&found[..count]);
    let mut n = count;
    for end in ends {
        let sharper = out[..n].iter().all(|p| {
            let gap = end.center - p.center;
            4.0 * end.width * end.width < p.width * p.width + gap * gap
        });
        if sharper && n < MAX_PEAKS {
            out[n] = *end;
            n += 1;
        }
    }
    (out, n)
}

/// Whether a sample's nearest point is at the chain's end `at_end` (0 or 1). Where the chain's speed vanishes at
/// that end (two coincident control points), the stationary cubic has a double root there and the solver's
/// parameter is off by up to the square root of the rounding: within `END_SNAP` counts.
fn at(x: &ChainSample, at_end: f64) -> bool {
    (x.param - at_end).abs() <= END_SNAP
}

/// How close to an end of the chain (in its parameter) a nearest point counts as at it (`at`).
pub const END_SNAP: f64 = 1e-4;

/// The cuts where a chain's nearest point crosses a knot of the W series between samples `x` and `y` with no
/// jump between them: there Sw is continuous with its slope but its curvature steps (a quadratic B-spline), so
/// the integrand is smooth on either side only, and a rule across it converges slowly and misjudges its own
/// error. Each crossing is placed by the parameter's linear interpolation, then one Newton step on a sample
/// there (its parameter and rate).
fn knot_cuts(
    sample: &impl Fn(f64) -> ChainSample,
    weights: usize,
    x: &ChainSample,
    y: &ChainSample,
    kinks: &mut Kinks,
) {
    if weights < 4 || x.param == y.param || y.t <= x.t {
        return;
    }
    let spans = (weights - 2) as f64;
    for i in 1..weights - 2 {
        let knot = i as f64 / spans;
        if (x.param - knot) * (y.param - knot) > 0.0 {
            continue;
        }
        let guess = x.t + (y.t - x.t) * (knot - x.param) / (y.param - x.param);
        let m = sample(guess.clamp(x.t, y.t));
        let t = if m.rate != 0.0 {
            m.t + (knot - m.param) / m.rate
        } else {
            m.t
        };
        kinks.push(if t.is_finite() {
            t.clamp(x.t, y.t)
        } else {
            m.t
        });
    }
}

/// The cuts at a chain's joints between samples in order along the ray: from the start of a stretch with no
/// jump to a jump's bracket `[a, b]`, then inside the bracket (where the nearest point may have passed a joint
/// as well as jumped). Where its nearest point passes a joint, the chain's curvature changes (it is smooth only
/// to first order there), and d's second derivative jumps, where the ray crosses the joint's normal plane (two
/// planes at a corner, with the joint nearest between them). Cut there where two neighbouring samples lie on
/// either side of the joint. Between the cuts the nearest point stays on one segment
/// (`curve::nearest_on_chain_from`).
fn joint_cuts(
    cp: &[DVec3],
    (s, dir): (DVec3, DVec3),
    samples: [&ChainSample; 3],
    kinks: &mut Kinks,
) {
    let segments = (cp.len() - 1) / 2;
    for (x, y) in [(samples[0], samples[1]), (samples[1], samples[2])] {
        for j in 1..segments {
            let pj = j as f64 / segments as f64;
            if (x.param - pj) * (y.param - pj) > 0.0 {
                continue;
            }
            let joint = cp[2 * j];
            let ((t_in, in_rest), (t_out, out_rest)) =
                (curve::tangent_into(cp, j), curve::tangent_out_of(cp, j));
            let corner = t_in.cross(t_out).length_squared()
                > 1e-12 * t_in.length_squared() * t_out.length_squared();
            // At a corner each plane is singular where its own side starts at rest; at a smooth joint the one
            // plane is where either side does.
            let planes = [(t_out, out_rest || (!corner && in_rest)), (t_in, in_rest)];
            for &(tangent, rest) in &planes[..1 + corner as usize] {
                let t = (joint - s).dot(tangent) / dir.dot(tangent);
                if t > x.t && t <= y.t {
                    kinks.push_cut(t, rest);
                }
            }
        }
    }
}

/// The kinks of a chain along the ray (in t), at most `MAX_KINKS` (more are dropped), and which of them are
/// singular: bit `k` of `singular` where the nearest point leaves a point of the chain whose speed vanishes (an
/// end or a joint where two control points coincide), so that its parameter moves like the square root of the
/// distance along the ray from the cut: the integrand's slope is unbounded there, on one side.
#[derive(Clone, Copy, Debug, Default)]
struct Kinks {
    at: [f64; MAX_KINKS],
    count: usize,
    singular: u32,
}

impl Kinks {
    fn push(&mut self, t: f64) {
        self.push_cut(t, false);
    }

    fn push_cut(&mut self, t: f64, singular: bool) {
        if self.count < MAX_KINKS {
            self.at[self.count] = t;
            self.singular |= (singular as u32) << self.count;
            self.count += 1;
        }
    }
}

/// The jumps of a chain's nearest point between samples `a` and `b`: where it lands far from its smooth motion
/// (`miss`), the kink is found (`find_kink`); if the bracket left around it still jumps, the rest of the interval
/// on either side is searched once more (an interval may hold two jumps). Returns the bracket left around the
/// first kink, if any.
fn search_jumps(
    sample: &impl Fn(f64) -> ChainSample,
    ray: (DVec3, DVec3),
    a: ChainSample,
    b: ChainSample,
    (eps, bracket): (f64, f64),
    kinks: &mut Kinks,
) -> Option<(ChainSample, ChainSample)> {
    if miss(&a, &b, eps) <= JUMP {
        return None;
    }
    let (kink, a1, b1) = find_kink(sample, ray, a, b, bracket);
    kinks.push(kink);
    if miss(&a1, &b1, eps) > JUMP {
        for (x, y) in [(a, a1), (b1, b)] {
            if miss(&x, &y, eps) > JUMP {
                kinks.push(find_kink(sample, ray, x, y, bracket).0);
            }
        }
    }
    Some((a1, b1))
}

/// A curve chain's nearest point to the ray's point at t: the squared distance, the point and its velocity along
/// the ray (the nearest point moves as the ray's point does).
#[derive(Clone, Copy, Debug)]
struct ChainSample {
    t: f64,
    /// The chain parameter of the nearest point.
    param: f64,
    d2: f64,
    point: DVec3,
    /// Zero where unknown.
    velocity: DVec3,
    /// The rate of the chain parameter along the ray (zero where the velocity is).
    rate: f64,
    /// Whether the nearest point is an end or a joint of the chain (within `END_SNAP` of its parameter), where
    /// the rate says little of where the parameter goes next (`miss`).
    at_joint: bool,
    /// Whether the velocity is known (it is infinite at a center of curvature).
    known: bool,
    /// The first and second derivatives of `d^2` along the ray (the second `-inf` where the velocity is
    /// unknown).
    slope: f64,
    curvature: f64,
}

impl ChainSample {
    /// The velocity comes from differentiating the stationarity `(C(u) - L(t)) . C'(u) = 0`:
    /// `du/dt = (C' . dir) / (|C'|^2 - (L - C) . C'')`. At an end of the chain (a clamped `u`) the nearest point
    /// stays put; where the denominator vanishes (a center of curvature) the velocity is infinite.
    fn at(c: &crate::field::Curve, s: DVec3, dir: DVec3, t: f64, moving: bool) -> ChainSample {
        let p = s + dir * t;
        let n = curve::nearest_on_chain(&c.control_points, p);
        let (point, d1, d2, clamped) = curve::chain_frame(&c.control_points, n.t);
        let denominator = d1.length_squared() - (p - point).dot(d2);
        let segments = ((c.control_points.len() - 1) / 2) as f64;
        let (rate, known) = if clamped && !moving {
            (0.0, true)
        } else if denominator > 0.0 {
            (d1.dot(dir) / denominator, true)
        } else {
            (0.0, false)
        };
        let velocity = d1 * rate;
        let x = n.t * segments;
        let at_joint = (x - x.round()).abs() <= END_SNAP * segments;
        // The nearest point moves along the chain, perpendicular to p - point: d^2's slope is that of the
        // distance to a fixed point, 2 (p - point) . dir; its curvature 2 dir . (dir - velocity).
        ChainSample {
            t,
            param: n.t,
            d2: n.distance * n.distance,
            point,
            velocity,
            rate: rate / segments,
            at_joint,
            known,
            slope: 2.0 * (p - point).dot(dir),
            curvature: if known {
                2.0 * dir.dot(dir - velocity)
            } else {
                f64::NEG_INFINITY
            },
        }
    }

    /// The width `d / sqrt(a)` of the peak d^2 ~ d*^2 + a (t - t*)^2 seen from here (0 where d^2 is not convex).
    fn width(&self) -> f64 {
        if self.curvature > 0.0 {
            let d2 = (self.d2 - 0.5 * self.slope * self.slope / self.curvature).max(0.0);
            (2.0 * d2 / self.curvature).sqrt()
        } else {
            0.0
        }
    }

    /// A Newton step toward the minimum of `d^2`, kept in `[lo, hi]`; where `d^2` is not convex, to the end
    /// downhill.
    fn newton(&self, lo: f64, hi: f64) -> f64 {
        let t = if self.curvature > 0.0 {
            self.t - self.slope / self.curvature
        } else if self.slope > 0.0 {
            lo
        } else {
            hi
        };
        if t.is_finite() {
            t.clamp(lo, hi)
        } else {
            self.t
        }
    }

    /// Where the nearest point would be at `t` if it moved on smoothly from here.
    fn predict(&self, t: f64) -> DVec3 {
        self.point + self.velocity * (t - self.t)
    }
}

/// How far the nearest point of a chain lands between two samples from where it would be had it moved smoothly
/// (the trapezoid rule on its velocity), relative to the distance (at least eps: closer, the falloff is flat and
/// a jump there is only W's), or its chain parameter from where its rate would have taken it, relative to
/// `PARAM_JUMP`: over `JUMP`, it jumped (or its velocity is unknown, infinite). The parameter catches a jump
/// between points close together but far apart along the chain (W steps there, and a piece's nearest point
/// must stay on one segment): across a joint where a segment of zero length or one with a vanishing speed sits,
/// the point barely moves while its parameter does.
fn miss(a: &ChainSample, b: &ChainSample, eps: f64) -> f64 {
    if b.t <= a.t {
        return 0.0;
    }
    if !(a.known && b.known) {
        return f64::MAX;
    }
    let moved = b.point - a.point;
    let smooth = (a.velocity + b.velocity) * (0.5 * (b.t - a.t));
    let miss = (moved - smooth).length() / a.d2.min(b.d2).sqrt().max(eps).max(1e-30);
    let param = if a.at_joint || b.at_joint {
        0.0
    } else {
        (b.param - a.param - 0.5 * (a.rate + b.rate) * (b.t - a.t)).abs() / PARAM_JUMP
    };
    let miss = miss.max(JUMP * param);
    if miss.is_finite() { miss } else { f64::MAX }
}

/// Where along the ray `s + t dir` the points `a` and `b` are equally far: the ray's crossing of their bisector
/// plane (the middle of `[lo, hi]` where the ray runs parallel to it), clamped to `[lo, hi]`.
fn bisector(s: DVec3, dir: DVec3, a: DVec3, b: DVec3, lo: f64, hi: f64) -> f64 {
    let n = b - a;
    let along = dir.dot(n);
    let t = if along != 0.0 {
        (0.5 * (a + b) - s).dot(n) / along
    } else {
        0.5 * (lo + hi)
    };
    if t.is_finite() {
        t.clamp(lo, hi)
    } else {
        0.5 * (lo + hi)
    }
}

/// Where the two branches' models are equally far from the ray's point: each branch modelled by its nearest
/// point at a bracket end moving on with its velocity there, `P(t) = point + velocity (t - t0)`, so the difference
/// of the squared distances is a quadratic in t. `None` where it does not change sign on the bracket.
fn model_crossing(s: DVec3, dir: DVec3, a: &ChainSample, b: &ChainSample) -> Option<f64> {
    // L(t) - P(t) = r + q t.
    let rq = |x: &ChainSample| {
        let v = x.velocity;
        (s - x.point + v * x.t, dir - v)
    };
    let ((ra, qa), (rb, qb)) = (rq(a), rq(b));
    let c2 = qa.length_squared() - qb.length_squared();
    let c1 = 2.0 * (ra.dot(qa) - rb.dot(qb));
    let c0 = ra.length_squared() - rb.length_squared();
    let f = |t: f64| (c2 * t + c1) * t + c0;
    let (fa, fb) = (f(a.t), f(b.t));
    // No sign change, or a NaN: no crossing to find.
    if fa * fb > 0.0 || (fa * fb).is_nan() {
        return None;
    }
    let inside = |t: f64| t >= a.t && t <= b.t;
    let disc = (c1 * c1 - 4.0 * c2 * c0).max(0.0);
    let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
    [q / c2, c0 / q]
        .into_iter()
        .find(|&t| t.is_finite() && inside(t))
        .or_else(|| Some(a.t + (b.t - a.t) * fa / (fa - fb)).filter(|t| inside(*t)))
}

/// The kink between two samples of a chain whose nearest point jumps between them (`miss`): where the ray crosses
/// the chain's medial surface, d is the smaller of two smooth distances (to either branch) and has a kink, and W
/// a step. Each round estimates it where the branches' models cross (`model_crossing`, else the bisector plane
/// of the two nearest points, else the middle where one end has not moved for two rounds) and probes either side
/// of the estimate; a probe belongs to the end whose predicted point is nearer its own. The rounds stop when the
/// bracket is shorter than `bracket` (`kink_bracket`); the kink is the last estimate. Returns it and the final bracket.
fn find_kink(
    sample: &impl Fn(f64) -> ChainSample,
    (s, dir): (DVec3, DVec3),
    mut a: ChainSample,
    mut b: ChainSample,
    bracket: f64,
) -> (f64, ChainSample, ChainSample) {
    // Which end the last round moved (+1 b, -1 a, 0 both), to catch a stale end.
    let mut last_moved = 0i32;
    let mut stale = false;
    for _ in 0..KINK_ROUNDS {
        if b.t - a.t <= bracket {
            break;
        }
        let guess = if stale {
            0.5 * (a.t + b.t)
        } else {
            model_crossing(s, dir, &a, &b)
                .unwrap_or_else(|| bisector(s, dir, a.point, b.point, a.t, b.t))
        };
        let tau = KINK_PROBE * (b.t - a.t);
        let (mut moved_a, mut moved_b) = (false, false);
        for probe in [guess - tau, guess + tau] {
            if probe <= a.t || probe >= b.t {
                continue;
            }
            let m = sample(probe);
            if m.point.distance(a.predict(probe)) <= m.point.distance(b.predict(probe)) {
                a = m;
                moved_a = true;
            } else {
                b = m;
                moved_b = true;
            }
        }
        let moved = match (moved_a, moved_b) {
            (true, false) => -1,
            (false, true) => 1,
            _ => 0,
        };
        stale = moved != 0 && moved == last_moved;
        last_moved = moved;
    }
    let kink = model_crossing(s, dir, &a, &b)
        .unwrap_or_else(|| bisector(s, dir, a.point, b.point, a.t, b.t));
    (kink, a, b)
}

/// Sorts features along the ray and gives each its piece: every stretch of the ray goes to the feature whose map
/// is densest there. The map around `s*` places samples `1 / sqrt(h^2 + (s - s*)^2)` apart, so the owner of `s`
/// is the feature with the least `h^2 + (s - s*)^2 = (h^2 + s*^2) - 2 s* s + s^2`: the lower envelope of lines
/// in s. A narrow peak beside a broad feature keeps its whole shoulder and may hide the broad one entirely (whose
/// piece is then empty).
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

/// Newton steps that refine a chain's closest approach from the scan, at most.
pub const PEAK_NEWTON: u32 = 2;
/// Newton stops once its step is this small against the peak's width (a broad peak needs no refinement: the map
/// is exact whatever its center, and a center off by a fraction of the width costs little accuracy).
pub const PEAK_SETTLED: f64 = 0.25;

/// The two deepest local minima of d^2 on a scan, offered in order (ties to the left).
#[derive(Clone, Copy, Debug, Default)]
struct Minima {
    best: [Option<ChainSample>; 2],
}

impl Minima {
    /// Offers sample `x` with d^2 `g_left` and `g_right` at its neighbours (infinite beyond the ray).
    fn offer(&mut self, x: ChainSample, g_left: f64, g_right: f64) {
        if !(x.d2 < g_left && x.d2 <= g_right) {
            return;
        }
        match self.best {
            [None, _] => self.best[0] = Some(x),
            [Some(b0), _] if x.d2 < b0.d2 => self.best = [Some(x), Some(b0)],
            [_, None] => self.best[1] = Some(x),
            [_, Some(b1)] if x.d2 < b1.d2 => self.best[1] = Some(x),
            _ => {}
        }
    }
}

/// The closest approaches of a chain along the ray: its scan's local minima of d^2, each refined by
/// `PEAK_NEWTON` Newton steps on the exact slope and curvature of d^2, within its scan neighbours (`step` away).
fn chain_peaks(
    sample: &impl Fn(f64) -> ChainSample,
    minima: &Minima,
    step: f64,
    eps: f64,
) -> ([Peak; 2], usize) {
    let mut out = [peak(0.0, 0.0, 0.0, eps); 2];
    let mut count = 0;
    for x in minima.best.iter().flatten() {
        let (lo, hi) = ((x.t - step).max(0.0), (x.t + step).min(1.0));
        let mut x = *x;
        for _ in 0..PEAK_NEWTON {
            let next = x.newton(lo, hi);
            if (next - x.t).abs() <= PEAK_SETTLED * x.width() {
                break;
            }
            x = sample(next);
        }
        let (center, d2) = if x.curvature > 0.0 {
            (
                x.newton(lo, hi),
                x.d2 - 0.5 * x.slope * x.slope / x.curvature,
            )
        } else {
            (x.t, x.d2)
        };
        out[count] = peak(center, d2.max(0.0), 0.5 * x.curvature.max(0.0), eps);
        count += 1;
    }
    if count == 0 {
        // A flat scan (constant distance): one uniform piece.
        count = 1;
    }
    (out, count)
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

/// Cuts of a piece closer than this in u are merged (`cuts`).
pub const CUT_MERGE: f64 = 1e-6;
/// Ordinary cuts closer than this in u to a singular one are dropped (`cuts`).
pub const SINGULAR_MERGE: f64 = 1e-3;

/// Bisection rounds that find where a part's nearest segment changes (`split_at_switch`).
pub const SWITCH_ROUNDS: u32 = 24;
/// How far inside a part (a share of its length) `split_at_switch` looks at its ends' segments.
pub const SWITCH_INSET: f64 = 1e-3;

/// The part `[a, b]` (in u) split where the chain's nearest segment changes, `segment(u)` (`None` at a joint),
/// where the segments just inside its ends differ (a joint at one end and a segment at the other counts): a
/// jump the kink search missed, or a joint it passes without its plane's cut. Found by bisection to
/// `2^-SWITCH_ROUNDS` of the part, so that the step a jump puts in the integrand is a cut. One part where the
/// ends agree.
fn split_at_switch(
    segment: impl Fn(f64) -> Option<usize>,
    (a, b): (f64, f64),
) -> ([(f64, f64); 2], usize) {
    // Looked at just inside the part: at a cut that is a jump, the nearest point may be on either branch.
    let inset = SWITCH_INSET * (b - a);
    match (segment(a + inset), segment(b - inset)) {
        (x, y) if x != y => {
            let (mut lo, mut hi) = (a + inset, b - inset);
            for _ in 0..SWITCH_ROUNDS {
                let mid = 0.5 * (lo + hi);
                if segment(mid) == x {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let m = 0.5 * (lo + hi);
            ([(a, m), (m, b)], 2)
        }
        _ => ([(a, b); 2], 1),
    }
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

/// One term's integral over its pieces, within `tolerance` on B: each piece is cut at its kinks, each cut into
/// panels of at most `U_PANEL` in u, and each panel refined where its Gauss and Kronrod values differ
/// (`integrate_panel`), the tolerance shared out along u.
fn integrate_term(term: Term, s: DVec3, e: DVec3, settings: &Integration, tolerance: f64) -> f64 {
    let c = term.coefficient();
    if c == 0.0 {
        return 0.0;
    }
    // A point's and a line's term in closed form, where it is well conditioned: no samples at all.
    let approach = match term {
        Term::Point(p) => Some(point_approach(s, e - s, p.position)),
        Term::Line(l) => Some(line_approach(s, e - s, l.point, l.direction)),
        _ => None,
    };
    if let Some((center, d2, a)) = approach {
        let (eps, alpha, beta) = (settings.epsilon, settings.alpha, settings.beta);
        if let Some(v) = falloff_integral(center, d2, a, eps, alpha, beta, CLOSED_FORM_CONDITION) {
            return c * v;
        }
    }
    let order = kronrod_order(settings.tolerance);
    let found = features(term, s, e, SCAN, settings.epsilon, kink_bracket(order));
    let dir = e - s;
    // A chain's nearest point stays on one segment between cuts, or passes a joint continuously: each cut
    // piece starts with a whole-chain search, at its first node, and then solves that segment only.
    // A safety net behind the cuts: where the nearest points at a part's two ends lie on different segments, a
    // jump was missed (the kink search can lose a branch that starts at rest), and the part is split where the
    // segment changes and solved on the whole chain at every node (`split_at_switch`).
    let segment = Cell::new(None);
    let tracking = Cell::new(true);
    // So is every part of a chain with a segment at rest at an end (`curve::is_degenerate`): the shader's
    // tracking loses the nearest point there.
    let degenerate = matches!(term, Term::Curve(c) if curve::is_degenerate(&c.control_points));
    let f = |t: f64| {
        let (d, w) = if tracking.get() {
            let mut on = segment.get();
            let found = term.distance_on_piece(s + dir * t, &mut on);
            segment.set(on);
            found
        } else {
            term.distance(s + dir * t)
        };
        w * falloff(d, settings.epsilon) * zeta(t, settings.alpha, settings.beta)
    };
    let pieces = found.peaks[..found.count].iter().map(|p| {
        let u0 = ((p.lo - p.center) / p.width).asinh();
        let u1 = ((p.hi - p.center) / p.width).asinh();
        (p, u0, u1)
    });
    let length: f64 = pieces.clone().map(|(_, u0, u1)| (u1 - u0).max(0.0)).sum();
    let allowance = tolerance / (c.abs() * length.max(1e-300));
    let mut refinements = refinement_budget(order);
    let mut sum = 0.0;
    for (p, u0, u1) in pieces {
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
            segment.set(None);
            let at = |u: f64| s + dir * (p.center + p.width * f64::sinh(u)).clamp(p.lo, p.hi);
            let (parts, count) = split_at_switch(|u| term.segment_at(at(u)), (a, b));
            // A part that begins or ends at rest is solved on the whole chain too: its nodes crowd toward the
            // cut, which the shader's tracking of the nearest point does not follow reliably.
            tracking.set(count == 1 && !singular_a && !singular_b && !degenerate);
            for (k, &(a, b)) in parts[..count].iter().enumerate() {
                if b <= a {
                    continue;
                }
                let (singular_a, singular_b) = (singular_a && k == 0, singular_b && k + 1 == count);
                let panels = ((b - a) / U_PANEL)
                    .ceil()
                    .clamp(1.0, MAX_GAUSS_PANELS as f64) as u32;
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
    c * sum
}

/// The brightness B of the segment from `s` to `e` by the adaptive integrator: every term within an equal share
/// of the tolerance.
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    let share = settings.tolerance / sources.len().max(1) as f64;
    let terms = sources
        .points
        .iter()
        .map(Term::Point)
        .chain(sources.lines.iter().map(Term::Line))
        .chain(sources.tori.iter().map(Term::Torus))
        .chain(sources.curves.iter().map(Term::Curve));
    terms
        .map(|t| integrate_term(t, s, e, settings, share))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Curve, Point, Torus};
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

    /// Every ray's B by the adaptive integrator within each tolerance of Simpson's with 2^18 intervals.
    fn assert_within_each_tolerance(
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
        let found = features(
            Term::Torus(&sources.tori[0]),
            s,
            e,
            SCAN,
            0.01,
            KINK_BRACKET,
        );
        let (p, count) = (found.peaks, found.count);
        assert_eq!(count, 3);
        assert!((p[0].center - 0.4).abs() < 2e-3 && (p[2].center - 0.6).abs() < 2e-3);
        assert!((p[1].center - 0.5).abs() < 1e-9);
        let want = reference(&sources, s, e, 1 << 20);
        let got = brightness(&sources, &settings(), s, e);
        assert!((got - want).abs() < 2e-3 * want, "{got} vs {want}");
    }

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
        assert_within_each_tolerance(&sources, &rays, &[1e-3, 1e-4, 1e-5, 1e-6]);
    }

    /// An arch, one segment from (-1, 0, 0) over (0, 2, 0) to (1, 0, 0), symmetric about x = 0.
    fn arch() -> Curve {
        Curve {
            control_points: vec![
                DVec3::new(-1.0, 0.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
            ],
            coefficient: 1.0,
            weights: vec![],
        }
    }

    #[test]
    fn a_chain_s_kinks_are_found_where_the_nearest_point_jumps_and_at_its_ends() {
        // Under the arch, on x = 0 the two halves are equally near: a ray along x crosses that medial plane at
        // t = 0.5 (a kink, found to second order in its bracket), and the normal planes at the arch's ends, where
        // the nearest point stops at the end: (p - end) . tangent = 0 with tangents (1, 2, 0) at (-1, 0, 0) and
        // (1, -2, 0) at (1, 0, 0). The ray passes under the arch's center of curvature, where the nearest point
        // races along the arch: the search may cut there too (a cut costs work, never accuracy).
        let c = arch();
        let (y, z) = (0.3, 0.2);
        let (s, e) = (DVec3::new(-3.0, y, z), DVec3::new(3.0, y, z));
        let found = features(Term::Curve(&c), s, e, SCAN, 0.01, KINK_BRACKET);
        let kinks = &found.kinks.at[..found.kinks.count];
        let near = |t: f64, within: f64| kinks.iter().any(|&k| (k - t).abs() < within);
        assert!(near(0.5, 1e-5), "the medial crossing: {kinks:?}");
        // The ends' normal planes: x + 2 y = -1 and x - 2 y = 1, at x = -1 - 2 y and 1 + 2 y.
        for x in [-1.0 - 2.0 * y, 1.0 + 2.0 * y] {
            assert!(
                near((x + 3.0) / 6.0, 1e-12),
                "the end plane at x = {x}: {kinks:?}"
            );
        }
        // Far above the arch the nearest point moves smoothly: no kink but the ends'.
        let (s, e) = (DVec3::new(-3.0, 3.0, z), DVec3::new(3.0, 3.0, z));
        let found = features(Term::Curve(&c), s, e, SCAN, 0.01, KINK_BRACKET);
        assert!(
            found.kinks.count <= 2,
            "{:?}",
            &found.kinks.at[..found.kinks.count]
        );
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

    #[test]
    fn a_beam_seen_end_on_is_integrated_within_the_tolerance() {
        // A straight chain along the view direction, rays along it and nearly so, inside eps and outside. Along
        // the beam the distance is flat (the nearest point moves with the ray); past each end it is the distance
        // to the end point, so the integrand falls off the plateau as a point source's half peak, as narrow as
        // the ray is near the axis. The scan's minimum sits on the flat stretch, where d^2 has no curvature and
        // its map is uniform: only the ends' own maps resolve the fall.
        let sources = Sources {
            curves: vec![Curve {
                control_points: vec![
                    DVec3::new(0.0, 0.0, -3.0),
                    DVec3::new(0.0, 0.0, -3.8),
                    DVec3::new(0.0, 0.0, -5.0),
                ],
                coefficient: 0.4,
                weights: vec![],
            }],
            ..Default::default()
        };
        let mut rays = Vec::new();
        for x in [0.0, 0.004, 0.0099, 0.02, 0.1, 0.5] {
            let s = DVec3::new(x, 0.3 * x, 0.0);
            rays.push((s, s + DVec3::new(0.0, 0.0, -10.0)));
        }
        // Tilted through the beam's middle, by 1e-3 and 1e-2 radians.
        for tilt in [1e-3, 1e-2] {
            let s = DVec3::new(4.0 * tilt, 0.0, 0.0);
            rays.push((s, s + DVec3::new(-tilt, 0.0, -1.0) * 10.0));
        }
        assert_within_each_tolerance(&sources, &rays, &[1e-3, 1e-4, 1e-5]);
    }

    #[test]
    fn a_chain_is_integrated_within_the_tolerance_across_its_kinks_and_steps() {
        // The mixed scene's chain: two segments with a W series, so where the nearest point jumps W steps too.
        // Rays from an eye through a grid around it: over the segments, through the medial surfaces, past the
        // ends, one passing closer than eps. Against Simpson with 2^18 intervals (its own error here is under
        // 1e-6: W's steps converge at first order).
        let sources = Sources {
            curves: vec![Curve {
                control_points: vec![
                    DVec3::new(-3.0, 2.0, 0.0),
                    DVec3::new(-1.0, -1.0, 1.0),
                    DVec3::new(1.0, 0.0, 0.0),
                    DVec3::new(3.0, 1.0, -1.0),
                    DVec3::new(3.5, 3.0, 0.0),
                ],
                coefficient: 3.0,
                weights: vec![0.3, 1.0, 0.5, 1.0],
            }],
            ..Default::default()
        };
        let eye = DVec3::new(0.5, 1.0, 9.0);
        let mut rays: Vec<(DVec3, DVec3)> = (0..7)
            .flat_map(|i| (0..5).map(move |j| (i, j)))
            .map(|(i, j)| {
                let target = DVec3::new(-3.6 + 1.2 * i as f64, -1.5 + 1.0 * j as f64, 0.0);
                (eye, eye + (target - eye) * 2.0)
            })
            .collect();
        // Through the chain's joint, 0.004 off it.
        let joint = DVec3::new(1.0, 0.004, 0.0);
        rays.push((eye, eye + (joint - eye) * 2.0));
        // From the mixed scene's view: the nearest point jumps off the chain's end and then passes the joint
        // continuously, within one interval of the scan (the joint's cut is found after the jump).
        rays.push((
            DVec3::new(1.2128, 3.1659, 4.3950),
            DVec3::new(-1.5744, 1.3317, -6.2100),
        ));
        assert_within_each_tolerance(&sources, &rays, &[1e-3, 1e-4, 1e-5]);
    }
}
