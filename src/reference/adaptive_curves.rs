//! The adaptive integrator's curve chains, the f64 twin of `shaders/adaptive_curves.wgsl` (entry point
//! `integrate_adaptive_curves`): the chain's closest approaches and kinks from a scan along the ray (its nearest
//! point's jumps, its ends, joints and W's knots), cuts there, and Gauss-Kronrod pairs on the pieces between them
//! (`super::adaptive`, whose module text describes the method).

use std::cell::Cell;

use glam::DVec3;

use super::adaptive::{Features, Kinks, Peak, integrate_pieces, peak, share_ray};
use crate::field::{Curve, Sources, brightest, curve, falloff, wseries};
use crate::integrate::adaptive::{
    BRIGHT_SCAN, CUT_BISECTIONS, END_SNAP, JUMP, KINK_PROBE, KINK_ROUNDS, MAX_KINKS, MAX_PEAKS,
    PARAM_JUMP, PEAK_NEWTON, PEAK_SETTLED, SCAN, SWITCH_INSET, SWITCH_ROUNDS, kink_bracket,
    kronrod_order,
};
use crate::integrate::{Decay, Integration, zeta};

/// The features of a chain along `s -> e` (at most `MAX_PEAKS`), sorted along the ray, each owning its piece,
/// and its kinks: those of its nearest point, or in the continuous W form (`pieces` not empty) those of its
/// brightest point (`bright_kinks`).
fn features(
    c: &Curve,
    pieces: &[brightest::Piece],
    s: DVec3,
    e: DVec3,
    (scan, eps, bracket): (u32, f64, f64),
) -> Features {
    let dir = e - s;
    let mut out = [peak(0.0, 0.0, 0.0, eps); MAX_PEAKS];
    let mut kinks = Kinks::default();
    let nearest_kinks = pieces.is_empty();
    let (found, count) = chain_features(c, s, dir, (scan, eps, bracket, nearest_kinks), &mut kinks);
    if !nearest_kinks {
        let sample = |t: f64| BrightSample::at(pieces, s, dir, t, eps);
        bright_kinks(&sample, pieces, bracket, &mut kinks);
    }
    out[..count].copy_from_slice(&found[..count]);
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
    c: &Curve,
    s: DVec3,
    dir: DVec3,
    (scan, eps, bracket, nearest_kinks): (u32, f64, f64, bool),
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
            if !nearest_kinks {
                left = y;
                continue;
            }
            if let Some((a1, b1)) = search_jumps(&sample, (s, dir), left, x, (eps, bracket), kinks)
            {
                joint_cuts(cp, (s, dir), [&calm, &a1, &b1], kinks);
                knot_cuts(&sample, c.weights.len(), &calm, &a1, kinks);
                calm = b1;
            }
            left = y;
        }
        if nearest_kinks {
            if let Some((a1, b1)) =
                search_jumps(&sample, (s, dir), left, after, (eps, bracket), kinks)
            {
                joint_cuts(cp, (s, dir), [&calm, &a1, &b1], kinks);
                knot_cuts(&sample, c.weights.len(), &calm, &a1, kinks);
                calm = b1;
            }
            joint_cuts(cp, (s, dir), [&calm, &after, &after], kinks);
            knot_cuts(&sample, c.weights.len(), &calm, &after, kinks);
        }
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

/// The continuous W form's kinks along the ray: where the chain's brightest point jumps from one part of the chain
/// to another, the term (the largest of the parts' values) is continuous but turns a corner, which a
/// Gauss-Kronrod pair across it misjudges. A scan of `BRIGHT_SCAN` intervals finds the jumps: the brightest point's
/// parameter lands far from where its rate would take it (`bright_miss`); each is bracketed by
/// `find_bright_kink`, and the rest of its interval on either side searched once more.
///
/// Between jumps the term is smooth but for where the brightest point crosses a joint or a knot of W (the ends of
/// the pieces: the chain's curvature or S's steps there, and the term's second derivative with them) or comes to
/// rest at an end of the chain: those are cut too (`bright_cuts`).
fn bright_kinks(
    sample: &impl Fn(f64) -> BrightSample,
    pieces: &[brightest::Piece],
    bracket: f64,
    kinks: &mut Kinks,
) {
    // The shader runs this as one loop with one call of its search, in the same order of samples.
    let k = BRIGHT_SCAN;
    let mut before = sample(0.0);
    for i in 1..=k {
        let after = sample(i as f64 / k as f64);
        let mut calm = before;
        // Once the kinks are full, further searches would be dropped: none is made.
        let room = |kinks: &Kinks| kinks.count < MAX_KINKS;
        if bright_miss(&before, &after) > PARAM_JUMP && room(kinks) {
            let (kink, a1, b1) = find_bright_kink(sample, before, after, bracket);
            kinks.push(kink);
            for (x, y) in [(before, a1), (b1, after)] {
                if bright_miss(&x, &y) > PARAM_JUMP && room(kinks) {
                    kinks.push(find_bright_kink(sample, x, y, bracket).0);
                }
            }
            bright_cuts(pieces, &calm, &a1, kinks);
            calm = b1;
        }
        bright_cuts(pieces, &calm, &after, kinks);
        before = after;
    }
}

/// The cuts where the brightest point passes the end of a piece (a joint or a knot of W) between samples `x` and
/// `y` with no jump between them, or comes to rest at (or leaves) an end of the chain. Its parameter between the
/// samples is their cubic Hermite interpolant (values and rates), whose crossing of a piece's end is found by
/// bisection; a rest at an end starts or stops where the moving sample's rate takes it there. No sample is taken
/// (the shader's search has one call site in this scan, see bright_kinks there).
fn bright_cuts(pieces: &[brightest::Piece], x: &BrightSample, y: &BrightSample, kinks: &mut Kinks) {
    if y.t <= x.t || x.param == y.param {
        return;
    }
    let h = y.t - x.t;
    let hermite = |t: f64| {
        let u = (t - x.t) / h;
        let (u2, u3) = (u * u, u * u * u);
        (2.0 * u3 - 3.0 * u2 + 1.0) * x.param
            + (u3 - 2.0 * u2 + u) * h * x.rate
            + (-2.0 * u3 + 3.0 * u2) * y.param
            + (u3 - u2) * h * y.rate
    };
    for k in 0..=pieces.len() {
        let end = k == 0 || k == pieces.len();
        let at = match k {
            0 => 0.0,
            k if k == pieces.len() => 1.0,
            k => pieces[k].t0,
        };
        let t = if end {
            if (x.param == at) == (y.param == at) {
                continue;
            }
            // The moving sample's rate takes it to the end.
            let m = if x.param == at { y } else { x };
            m.t + (at - m.param) / m.rate
        } else {
            if (x.param - at) * (y.param - at) >= 0.0 {
                continue;
            }
            let (mut lo, mut hi) = (x.t, y.t);
            for _ in 0..CUT_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if (hermite(mid) - at) * (x.param - at) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        kinks.push(if t.is_finite() {
            t.clamp(x.t, y.t)
        } else {
            0.5 * (x.t + y.t)
        });
    }
}

/// A chain's brightest point seen from the ray's point at t (the continuous W form): its chain parameter and that
/// parameter's rate along the ray, the term's value there (without its coefficient) and the value's slope.
#[derive(Clone, Copy, Debug)]
struct BrightSample {
    t: f64,
    param: f64,
    rate: f64,
    value: f64,
    slope: f64,
}

impl BrightSample {
    fn at(pieces: &[brightest::Piece], s: DVec3, dir: DVec3, t: f64, eps: f64) -> Self {
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
    fn predict(&self, t: f64) -> f64 {
        self.param + self.rate * (t - self.t)
    }
}

/// How far the brightest point's parameter lands at `b` from where its rates would have taken it from `a`.
fn bright_miss(a: &BrightSample, b: &BrightSample) -> f64 {
    let m = (b.param - a.param - 0.5 * (a.rate + b.rate) * (b.t - a.t)).abs();
    if m.is_finite() { m } else { f64::INFINITY }
}

/// Where the brightest point jumps between `a` and `b`: each round probes either side of the estimate (where the
/// two branches' values, each moving on with its slope, meet), or of the middle where the same side has moved
/// twice in a row, and gives each probe to the end whose branch it continues. Returns the estimate in the final
/// bracket and the bracket. Twin of the shader's bright_kink.
fn find_bright_kink(
    sample: &impl Fn(f64) -> BrightSample,
    mut a: BrightSample,
    mut b: BrightSample,
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
    let (mut last_moved, mut stale) = (0i32, false);
    for _ in 0..KINK_ROUNDS {
        if b.t - a.t <= bracket {
            break;
        }
        let guess = if stale {
            0.5 * (a.t + b.t)
        } else {
            estimate(&a, &b)
        };
        let tau = KINK_PROBE * (b.t - a.t);
        let (mut moved_a, mut moved_b) = (false, false);
        for probe in [guess - tau, guess + tau] {
            if probe <= a.t || probe >= b.t {
                continue;
            }
            let m = sample(probe);
            if (m.param - a.predict(probe)).abs() <= (m.param - b.predict(probe)).abs() {
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
    (estimate(&a, &b), a, b)
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
    fn at(c: &Curve, s: DVec3, dir: DVec3, t: f64, moving: bool) -> ChainSample {
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

/// One chain's part of B along `s -> e` within `tolerance`, on the pieces of its features, cut at its kinks.
fn integrate_term(c: &Curve, s: DVec3, e: DVec3, settings: &Integration, tolerance: f64) -> f64 {
    let power = settings.power();
    let integral = integrate_weighted(c, s, e, settings, tolerance, &|t| {
        wseries::evaluate(&c.weights, t).powi(power)
    });
    settings.finish(integral, c.coefficient)
}

/// A chain's term to the decay's power without its W series, times `weight(t)` at the point the term reads:
/// the integral of `(b falloff zeta)^power weight(t)` along `s -> e` within `tolerance` on B, on the same features
/// and cuts whatever the weight (as `simpson::curve_weighted`).
fn integrate_weighted(
    c: &Curve,
    s: DVec3,
    e: DVec3,
    settings: &Integration,
    tolerance: f64,
    weight: &dyn Fn(f64) -> f64,
) -> f64 {
    if c.coefficient == 0.0 {
        return 0.0;
    }
    let order = kronrod_order(settings.tolerance);
    let pieces = c.pieces();
    let found = features(
        c,
        &pieces,
        s,
        e,
        (SCAN, settings.epsilon, kink_bracket(order)),
    );
    let dir = e - s;
    let cp = &c.control_points;
    // A chain's nearest point stays on one segment between cuts, or passes a joint continuously: each cut
    // piece starts with a whole-chain search, at its first node, and then solves that segment only.
    // A safety net behind the cuts: where the nearest points at a part's two ends lie on different segments, a
    // jump was missed (the kink search can lose a branch that starts at rest), and the part is split where the
    // segment changes and solved on the whole chain at every node (`split_at_switch`).
    let segment = Cell::new(None);
    let tracking = Cell::new(true);
    // So is every part of a chain with a segment at rest at an end (`curve::is_degenerate`): the shader's
    // tracking loses the nearest point there.
    let degenerate = curve::is_degenerate(cp);
    // In the continuous form every node searches the whole chain for its brightest point (the term is continuous,
    // with kinks where that point jumps, cut at by `bright_kinks`).
    let power = settings.power();
    let f = |t: f64| {
        let p = s + dir * t;
        let n = if !pieces.is_empty() {
            brightest::brightest(&pieces, p, settings.epsilon)
        } else if tracking.get() {
            let mut on = segment.get();
            let n = curve::nearest_on_chain_from(cp, p, &mut on);
            segment.set(on);
            n
        } else {
            curve::nearest_on_chain(cp, p)
        };
        (falloff(n.distance, settings.epsilon) * zeta(t, settings.alpha, settings.beta)).powi(power)
            * weight(n.t)
    };
    let rms = (settings.decay == Decay::Rms).then_some(settings.stretch);
    integrate_pieces(
        &found,
        (c.coefficient.powi(power), &f),
        order,
        (tolerance, rms),
        |p, (a, singular_a), (b, singular_b)| {
            segment.set(None);
            let at = |u: f64| s + dir * (p.center + p.width * f64::sinh(u)).clamp(p.lo, p.hi);
            // (Not for a curve that reads its brightest point: its nearest point's segments say nothing of it.)
            let (parts, count) = if pieces.is_empty() {
                split_at_switch(|u| curve::nearest_segment_index(cp, at(u)), (a, b))
            } else {
                ([(a, b); 2], 1)
            };
            // A part that begins or ends at rest is solved on the whole chain too: its nodes crowd toward the
            // cut, which the shader's tracking of the nearest point does not follow reliably.
            tracking.set(count == 1 && !singular_a && !singular_b && !degenerate);
            (parts, count)
        },
    )
}

/// The curves' part of the brightness B of the segment `s -> e`, each chain within an equal share of the
/// tolerance among all the scene's sources (the points', lines' and tori's are `adaptive_smooth::brightness`).
pub fn brightness(sources: &Sources, settings: &Integration, s: DVec3, e: DVec3) -> f64 {
    let share = settings.term_tolerance(sources.len());
    sources
        .curves
        .iter()
        .map(|c| integrate_term(c, s, e, settings, share))
        .sum()
}

/// Curve `k`'s term to the decay's power times `weight(t)` in the place of its W series (`integrate_weighted`),
/// within its share of the tolerance times `scale` (the weight's largest size against the W series').
pub fn term_weighted(
    sources: &Sources,
    k: usize,
    settings: &Integration,
    (s, e): (DVec3, DVec3),
    weight: &dyn Fn(f64) -> f64,
    scale: f64,
) -> f64 {
    let share = settings.term_tolerance(sources.len()) * scale;
    (sources.curves.get(k)).map_or(0.0, |c| {
        integrate_weighted(c, s, e, settings, share, weight)
    })
}

/// The part of B of curve `k` alone, as `brightness` integrates it.
pub fn term_brightness(
    sources: &Sources,
    k: usize,
    settings: &Integration,
    s: DVec3,
    e: DVec3,
) -> f64 {
    let share = settings.term_tolerance(sources.len());
    (sources.curves.get(k)).map_or(0.0, |c| integrate_term(c, s, e, settings, share))
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::testing::assert_within_each_tolerance;
    use super::*;
    use crate::integrate::adaptive::KINK_BRACKET;

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
            look: Default::default(),
            color_series: Vec::new(),
            w_form: crate::field::WForm::Nearest,
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
        let found = features(&c, &[], s, e, (SCAN, 0.01, KINK_BRACKET));
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
        let found = features(&c, &[], s, e, (SCAN, 0.01, KINK_BRACKET));
        assert!(
            found.kinks.count <= 2,
            "{:?}",
            &found.kinks.at[..found.kinks.count]
        );
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
                look: Default::default(),
                color_series: Vec::new(),
                w_form: crate::field::WForm::Nearest,
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
        assert_within_each_tolerance(brightness, &sources, &rays, &[1e-3, 1e-4, 1e-5]);
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
                look: Default::default(),
                color_series: Vec::new(),
                w_form: crate::field::WForm::Nearest,
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
        assert_within_each_tolerance(brightness, &sources, &rays, &[1e-3, 1e-4, 1e-5]);
    }
}
