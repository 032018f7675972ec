//! The kinks of a chain's term along the ray: where its nearest point (or, in the continuous W form, its brightest
//! point) jumps from one branch of the chain to another, d (or the term) has a kink and W a step. Samples of
//! either point along the ray, how far one lands from where the last would have moved on, and the bracket both
//! searches narrow round by round (`bracket_kink`). Twin of `shaders/adaptive_curves/kinks.wgsl`.

use glam::DVec3;

use crate::field::{Curve, brightest, curve};
use crate::integrate::adaptive::{END_SNAP, JUMP, KINK_PROBE, KINK_ROUNDS, PARAM_JUMP};

/// A chain's brightest point seen from the ray's point at t (the continuous W form): its chain parameter and that
/// parameter's rate along the ray, the term's value there (without its coefficient) and the value's slope.
#[derive(Clone, Copy, Debug)]
pub(super) struct BrightSample {
    pub(super) t: f64,
    pub(super) param: f64,
    pub(super) rate: f64,
    pub(super) value: f64,
    pub(super) slope: f64,
}

impl BrightSample {
    pub(super) fn at(pieces: &[brightest::Piece], s: DVec3, dir: DVec3, t: f64, eps: f64) -> Self {
        let p = s + dir * t;
        let b = brightest::search(pieces, p, eps);
        let (rate, slope) = b.motion(pieces, p, dir, eps);
        BrightSample {
            t,
            param: b.at.t,
            rate,
            value: b.value,
            slope,
        }
    }

    /// Where its parameter would be at t had it moved on at its rate.
    pub(super) fn predict(&self, t: f64) -> f64 {
        self.param + self.rate * (t - self.t)
    }
}

/// How far the brightest point's parameter lands at `b` from where its rates would have taken it from `a`.
pub(super) fn bright_miss(a: &BrightSample, b: &BrightSample) -> f64 {
    let m = (b.param - a.param - 0.5 * (a.rate + b.rate) * (b.t - a.t)).abs();
    if m.is_finite() { m } else { f64::INFINITY }
}

/// Where the brightest point jumps between `a` and `b`: the estimate is where the two branches' values, each
/// moving on with its slope, meet (`bracket_kink` narrows the bracket). Returns the estimate in the final bracket
/// and the bracket. Twin of the shader's bright_kink.
pub(super) fn find_bright_kink(
    sample: &impl Fn(f64) -> BrightSample,
    a: BrightSample,
    b: BrightSample,
    bracket: f64,
) -> (f64, BrightSample, BrightSample) {
    let estimate = |a: &BrightSample, b: &BrightSample| {
        let t = (b.value - a.value + a.slope * a.t - b.slope * b.t) / (a.slope - b.slope);
        if t.is_finite() && t > a.t && t < b.t {
            t
        } else {
            0.5 * (a.t + b.t)
        }
    };
    let (a, b) = bracket_kink(sample, &estimate, a, b, bracket);
    (estimate(&a, &b), a, b)
}

/// A sample of a branch of the chain along the ray, as the kink searches bracket them.
pub(super) trait Branch: Copy {
    /// Where along the ray the sample lies.
    fn t(&self) -> f64;
    /// How far sample `m` lands from where this sample's branch, moving on, would be at `m`'s t: the smaller of
    /// the two ends' gaps names the branch `m` continues.
    fn gap(&self, m: &Self) -> f64;
}

impl Branch for BrightSample {
    fn t(&self) -> f64 {
        self.t
    }
    fn gap(&self, m: &Self) -> f64 {
        (m.param - self.predict(m.t)).abs()
    }
}

impl Branch for ChainSample {
    fn t(&self) -> f64 {
        self.t
    }
    fn gap(&self, m: &Self) -> f64 {
        m.point.distance(self.predict(m.t))
    }
}

/// The bracket both kink searches narrow: each round probes either side of `estimate`'s guess (or of the middle
/// where the same end has moved twice in a row: a stale end), and gives each probe to the end whose branch it
/// continues (`Branch::gap`), until the bracket is no longer than `bracket` or `KINK_ROUNDS` have run. Returns the
/// final bracket. Twin of the shader's kink rounds.
pub(super) fn bracket_kink<S: Branch>(
    sample: &impl Fn(f64) -> S,
    estimate: &impl Fn(&S, &S) -> f64,
    mut a: S,
    mut b: S,
    bracket: f64,
) -> (S, S) {
    // Which end the last round moved (+1 b, -1 a, 0 both or neither), to catch a stale end.
    let (mut last_moved, mut stale) = (0i32, false);
    for _ in 0..KINK_ROUNDS {
        if b.t() - a.t() <= bracket {
            break;
        }
        let guess = if stale {
            0.5 * (a.t() + b.t())
        } else {
            estimate(&a, &b)
        };
        let tau = KINK_PROBE * (b.t() - a.t());
        let (mut moved_a, mut moved_b) = (false, false);
        for probe in [guess - tau, guess + tau] {
            if probe <= a.t() || probe >= b.t() {
                continue;
            }
            let m = sample(probe);
            if a.gap(&m) <= b.gap(&m) {
                a = m;
                moved_a = true;
            } else {
                b = m;
                moved_b = true;
            }
        }
        let moved = moved_b as i32 - moved_a as i32;
        stale = moved != 0 && moved == last_moved;
        last_moved = moved;
    }
    (a, b)
}

/// A curve chain's nearest point to the ray's point at t: the squared distance, the point and its velocity along
/// the ray (the nearest point moves as the ray's point does).
#[derive(Clone, Copy, Debug)]
pub(super) struct ChainSample {
    pub(super) t: f64,
    /// The chain parameter of the nearest point.
    pub(super) param: f64,
    pub(super) d2: f64,
    pub(super) point: DVec3,
    /// Zero where unknown.
    pub(super) velocity: DVec3,
    /// The rate of the chain parameter along the ray (zero where the velocity is).
    pub(super) rate: f64,
    /// Whether the nearest point is an end or a joint of the chain (within `END_SNAP` of its parameter), where
    /// the rate says little of where the parameter goes next (`miss`).
    pub(super) at_joint: bool,
    /// Whether the velocity is known (it is infinite at a center of curvature).
    pub(super) known: bool,
    /// The first and second derivatives of `d^2` along the ray (the second `-inf` where the velocity is
    /// unknown).
    pub(super) slope: f64,
    pub(super) curvature: f64,
}

impl ChainSample {
    /// The velocity comes from differentiating the stationarity `(C(u) - L(t)) . C'(u) = 0`:
    /// `du/dt = (C' . dir) / (|C'|^2 - (L - C) . C'')`. At an end of the chain (a clamped `u`) the nearest point
    /// stays put; where the denominator vanishes (a center of curvature) the velocity is infinite.
    pub(super) fn at(c: &Curve, s: DVec3, dir: DVec3, t: f64, moving: bool) -> ChainSample {
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
    pub(super) fn width(&self) -> f64 {
        if self.curvature > 0.0 {
            let d2 = (self.d2 - 0.5 * self.slope * self.slope / self.curvature).max(0.0);
            (2.0 * d2 / self.curvature).sqrt()
        } else {
            0.0
        }
    }

    /// A Newton step toward the minimum of `d^2`, kept in `[lo, hi]`; where `d^2` is not convex, to the end
    /// downhill.
    pub(super) fn newton(&self, lo: f64, hi: f64) -> f64 {
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
    pub(super) fn predict(&self, t: f64) -> DVec3 {
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
pub(super) fn miss(a: &ChainSample, b: &ChainSample, eps: f64) -> f64 {
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
pub(super) fn bisector(s: DVec3, dir: DVec3, a: DVec3, b: DVec3, lo: f64, hi: f64) -> f64 {
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
pub(super) fn model_crossing(
    s: DVec3,
    dir: DVec3,
    a: &ChainSample,
    b: &ChainSample,
) -> Option<f64> {
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
/// a step. The estimate is where the branches' models cross (`model_crossing`), else the bisector plane of the two
/// nearest points; `bracket_kink` narrows the bracket around it, a probe belonging to the end whose predicted
/// point is nearer its own, to `bracket` (`kink_bracket`); the kink is the last estimate. Returns it and the final
/// bracket.
pub(super) fn find_kink(
    sample: &impl Fn(f64) -> ChainSample,
    (s, dir): (DVec3, DVec3),
    a: ChainSample,
    b: ChainSample,
    bracket: f64,
) -> (f64, ChainSample, ChainSample) {
    let estimate = |a: &ChainSample, b: &ChainSample| {
        model_crossing(s, dir, a, b).unwrap_or_else(|| bisector(s, dir, a.point, b.point, a.t, b.t))
    };
    let (a, b) = bracket_kink(sample, &estimate, a, b, bracket);
    (estimate(&a, &b), a, b)
}
