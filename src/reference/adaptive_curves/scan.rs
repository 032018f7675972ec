//! A chain's features from its scan along the ray: its closest approaches (the deepest minima of d^2, refined by
//! Newton), its ends, joints and W's knots, and the jumps between scan samples, each cut where the kink search
//! (`super::kinks`) places it. Twin of `shaders/adaptive_curves/scan.wgsl`.

use glam::DVec3;

use super::super::adaptive::{Kinks, Peak, peak};
use super::kinks::{BrightSample, ChainSample, bright_miss, find_bright_kink, find_kink, miss};
use crate::field::{Curve, brightest, cubic, curve};
use crate::integrate::adaptive::{
    BRIGHT_SCAN, CUT_BISECTIONS, END_SNAP, EXACT_SAMPLES, EXACT_SLACK, JUMP, MAX_KINKS, MAX_PEAKS,
    MINIMA, PARAM_JUMP, PEAK_NEWTON, PEAK_SETTLED, RIVAL_MARGIN, SUB_SCAN, SUSPECT_MISS,
    SWITCH_INSET, SWITCH_ROUNDS,
};

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
pub(super) fn chain_features(
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
    let survey = Survey::of(c, s, dir);
    let fine = k * SUB_SCAN;
    let fine_step = step / SUB_SCAN as f64;
    let mut before = sample(0.0);
    let mut g_before_before = f64::INFINITY;
    // The scan's next sample (`step` on), and whether the interval up to it is sampled `SUB_SCAN` times finer. The
    // shader runs one loop of `fine` rounds, taking a sample only where one is due, in the same order.
    let (mut ahead, mut suspect) = (before, false);
    for i in 1..=fine {
        if (i - 1) % SUB_SCAN == 0 {
            ahead = sample(((i - 1) / SUB_SCAN + 1) as f64 * step);
            let why = survey.suspect(&before, &ahead, (s, dir));
            suspect = why != Suspicion::None;
            // An interval suspected for a rival alone is searched for jumps whole too, as an interval the scan does
            // not suspect is (where no end's normal plane splits it): its finer samples can each see the nearest
            // point move smoothly where the whole interval sees it race, and a cut there keeps the pieces' rules
            // honest (a chain with a segment of zero length lost 3.3e-4 of B without it). Not where it passes a
            // joint: the finer samples' cuts there already fill the kinks (MAX_KINKS).
            let split = ends.iter().any(|&(t, _, _)| t > before.t && t <= ahead.t);
            if why == Suspicion::Rival && nearest_kinks && !split {
                search_jumps(&sample, (s, dir), before, ahead, (eps, bracket), kinks);
            }
        }
        let after = if i % SUB_SCAN == 0 {
            ahead
        } else if suspect {
            sample(i as f64 * fine_step)
        } else {
            continue;
        };
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
    let minima = closest_approaches(&survey, &sample, &minima);
    let (peaks, count) = chain_peaks(&sample, &minima, step, eps);
    with_ends(peaks, count, &end_peaks[..end_count])
}

/// The closest approaches and, after them, each end's peak whose map at its center is more than twice as dense as
/// every feature's before it (where an end is the closest approach, Newton has found it already).
pub(super) fn with_ends(
    found: [Peak; MINIMA],
    count: usize,
    ends: &[Peak],
) -> ([Peak; MAX_PEAKS], usize) {
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
pub(super) fn at(x: &ChainSample, at_end: f64) -> bool {
    (x.param - at_end).abs() <= END_SNAP
}

/// The cuts where a chain's nearest point crosses a knot of the W series between samples `x` and `y` with no
/// jump between them: there Sw is continuous with its slope but its curvature steps (a quadratic B-spline), so
/// the integrand is smooth on either side only, and a rule across it converges slowly and misjudges its own
/// error. Each crossing is placed by the parameter's linear interpolation, then one Newton step on a sample
/// there (its parameter and rate).
pub(super) fn knot_cuts(
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
pub(super) fn joint_cuts(
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
/// on either side is searched once more (an interval may hold two jumps). An interval that misses by less than
/// `JUMP` but more than `SUSPECT_MISS` of it is looked at again at its middle, and the kink searched in the half
/// that jumps. Returns the bracket left around the first kink, if any.
pub(super) fn search_jumps(
    sample: &impl Fn(f64) -> ChainSample,
    ray: (DVec3, DVec3),
    a: ChainSample,
    b: ChainSample,
    (eps, bracket): (f64, f64),
    kinks: &mut Kinks,
) -> Option<(ChainSample, ChainSample)> {
    let whole = miss(&a, &b, eps);
    if whole <= SUSPECT_MISS * JUMP {
        return None;
    }
    let (x, y) = if whole > JUMP {
        (a, b)
    } else {
        let m = sample(0.5 * (a.t + b.t));
        if miss(&a, &m, eps) > JUMP {
            (a, m)
        } else if miss(&m, &b, eps) > JUMP {
            (m, b)
        } else {
            return None;
        }
    };
    let (kink, a1, b1) = find_kink(sample, ray, x, y, bracket);
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
pub(super) fn bright_kinks(
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
pub(super) fn bright_cuts(
    pieces: &[brightest::Piece],
    x: &BrightSample,
    y: &BrightSample,
    kinks: &mut Kinks,
) {
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

/// The chain's closest approaches to the ray, found exactly segment by segment, in place of the scan's local
/// minima of d^2 (`scanned`) inside the ray: a scan samples d^2 only every `step`, and where the nearest point
/// jumps between segments beside a closest approach, the scan's deepest sample can lie on the other segment, and
/// Newton's steps from it miss the approach (a peak of width 1e-2 of the ray, 0.6 of B lost on a chain of two
/// segments; a scan four times finer still lost 0.6 on another).
///
/// The distance from segment `C(u) = c2 u^2 + c1 u + c0` to the ray's line is that of its projection across the
/// ray, `P (C(u) - s)` with `P` the projection onto the plane normal to `dir`, from the origin: its stationary
/// points are the roots of that projected segment's stationary cubic (`Segment::stationary_cubic`). Each local
/// minimum of it in `[0, 1]` (a root where the distance curves up, or an end where it rises into the segment: a
/// corner or an end of the chain) whose foot lies inside the ray is a candidate, the ray's closest approach to
/// that segment; every local minimum of the chain's distance inside the ray is one of them. It is the chain's
/// where no other segment comes nearer there: the chain's nearest point at that `t` is sampled (only for a
/// `EXACT_SAMPLES` deepest candidates, `Survey::of`) and kept where its distance squared is within `EXACT_SLACK` of
/// the candidate's. The scan's minima at the ray's ends (which no candidate inside it stands for) are offered too; where
/// no candidate is kept (a straight segment along the ray has none), the scan's minima stand. Twin of
/// `closest_approaches` in `shaders/adaptive_curves/scan.wgsl`.
pub(super) fn closest_approaches(
    survey: &Survey,
    sample: &impl Fn(f64) -> ChainSample,
    scanned: &Minima,
) -> Minima {
    let mut exact = Minima::default();
    for &(d2, t) in &survey.candidates[..survey.candidate_count] {
        let x = sample(t);
        if x.d2 >= EXACT_SLACK * d2 {
            exact.offer(x, f64::INFINITY, f64::INFINITY);
        }
    }
    if exact.best[0].is_none() {
        return *scanned;
    }
    for x in scanned.best.iter().flatten() {
        if x.t == 0.0 || x.t == 1.0 {
            exact.offer(*x, f64::INFINITY, f64::INFINITY);
        }
    }
    exact
}

/// The local minima of segment `seg`'s distance squared to the line `s + t dir`, as `(d2, t, peak)` (`t` the foot
/// on the line, anywhere along it): the ends where the distance rises into the segment, then the stationary cubic's
/// roots inside where it curves up (see `closest_approaches`). `peak` says whether it is a local minimum of the
/// chain's distance too: an inner joint is one only where the distance falls into it from the neighbour (a corner;
/// at a smooth joint the neighbour's own minimum is the chain's), which `falls_in` says of the segment before and
/// the returned flag (the distance falls into the segment's end) of the next; a chain's ends always are.
pub(super) fn approaches(
    seg: &curve::Segment,
    s: DVec3,
    dir: DVec3,
    (falls_in, last): (bool, bool),
) -> ([Option<(f64, f64, bool)>; 5], bool) {
    let mut out = [None; 5];
    let a = dir.length_squared();
    if a == 0.0 {
        return (out, false);
    }
    let across = |v: DVec3| v - dir * (dir.dot(v) / a);
    let projected = curve::Segment {
        c2: across(seg.c2),
        c1: across(seg.c1),
        c0: across(seg.c0 - s),
    };
    let k = projected.stationary_cubic(DVec3::ZERO);
    // The slope of the distance squared at u, over 2, and its curvature, over 2.
    let slope = |u: f64| ((k[0] * u + k[1]) * u + k[2]) * u + k[3];
    let bend = |u: f64| (3.0 * k[0] * u + 2.0 * k[1]) * u + k[2];
    let mut n = 0;
    let mut take = |u: f64, peak: bool| {
        out[n] = Some((
            projected.at(u).length_squared(),
            dir.dot(seg.at(u) - s) / a,
            peak,
        ));
        n += 1;
    };
    let falls_out = slope(1.0) < 0.0;
    if slope(0.0) > 0.0 {
        take(0.0, falls_in);
    }
    if falls_out {
        take(1.0, last);
    }
    for &u in cubic::solve_cubic(k[0], k[1], k[2], k[3], 1e-12).as_slice() {
        // One Newton step on the cubic: Cardano loses digits near double roots.
        let d = bend(u);
        let u = if d != 0.0 { u - slope(u) / d } else { u };
        if u > 0.0 && u < 1.0 && bend(u) > 0.0 {
            take(u, true);
        }
    }
    (out, falls_out)
}

/// A chain's segments seen from the ray's line, in one pass over them (`approaches`): the two that come nearest
/// the line by their closest approach, which may take the nearest point from the one the scan's samples find it on
/// (`Survey::suspect`), and the deepest closest approaches inside the ray (`closest_approaches`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Survey {
    /// `(d2, segment)`, nearest first; `d2` infinite where the chain has fewer segments.
    nearest: [(f64, usize); 2],
    segments: usize,
    /// `(d2, t)` of the `EXACT_SAMPLES` deepest closest approaches whose foot lies inside the ray, deepest first
    /// (ties in the order found).
    candidates: [(f64, f64); EXACT_SAMPLES as usize],
    candidate_count: usize,
}

impl Survey {
    pub(super) fn of(c: &Curve, s: DVec3, dir: DVec3) -> Self {
        let mut nearest = [(f64::INFINITY, 0); 2];
        let mut candidates = [(f64::INFINITY, 0.0); EXACT_SAMPLES as usize];
        let mut candidate_count = 0;
        let mut segments = 0;
        let count = (c.control_points.len() - 1) / 2;
        let mut falls_in = true;
        for (j, seg) in curve::segments(&c.control_points).enumerate() {
            segments += 1;
            let mut least = f64::INFINITY;
            let (found, falls_out) = approaches(&seg, s, dir, (falls_in, j + 1 == count));
            falls_in = falls_out;
            for (d2, t, peak) in found.into_iter().flatten() {
                least = least.min(d2);
                if !peak || !(t > 0.0 && t < 1.0) {
                    continue;
                }
                // Into its place among the deepest, the last dropped where all are taken.
                let mut x = (d2, t);
                for slot in &mut candidates {
                    if x.0 < slot.0 {
                        std::mem::swap(slot, &mut x);
                    }
                }
                candidate_count = (candidate_count + 1).min(EXACT_SAMPLES as usize);
            }
            if least < nearest[0].0 {
                nearest = [(least, j), nearest[0]];
            } else if least < nearest[1].0 {
                nearest[1] = (least, j);
            }
        }
        Self {
            nearest,
            segments,
            candidates,
            candidate_count,
        }
    }

    /// Whether the nearest point may leave its segment and come back, or pass more than one event, between scan
    /// samples `x` and `y` (the scan then samples the interval `SUB_SCAN` times finer): where either lies on an
    /// inner joint or they lie on different segments (`Suspicion::Events`), and where another segment's closest
    /// approach to the ray comes within the farthest the chain can be from the ray between them
    /// (`reach_between`; `Suspicion::Rival`).
    pub(super) fn suspect(
        &self,
        x: &ChainSample,
        y: &ChainSample,
        (s, dir): (DVec3, DVec3),
    ) -> Suspicion {
        let k = self.segments;
        if k < 2 {
            return Suspicion::None;
        }
        let (jx, jy) = (segment_of(x.param, k), segment_of(y.param, k));
        if inner_joint(x.param, k) || inner_joint(y.param, k) || jx != jy {
            return Suspicion::Events;
        }
        let rival = if self.nearest[0].1 == jx {
            self.nearest[1].0
        } else {
            self.nearest[0].0
        };
        if rival <= RIVAL_MARGIN * reach_between(x, y, (s, dir)) {
            Suspicion::Rival
        } else {
            Suspicion::None
        }
    }
}

/// Why the scan samples an interval finer (`Survey::suspect`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Suspicion {
    None,
    /// The samples lie on different segments or on a joint: the nearest point passes a joint or jumps in between,
    /// maybe more than once.
    Events,
    /// Both lie inside one segment, and another comes near enough the ray to take the nearest point and give it
    /// back in between.
    Rival,
}

/// The segment of chain parameter `param` on a chain of `k` segments.
fn segment_of(param: f64, k: usize) -> usize {
    ((param.clamp(0.0, 1.0) * k as f64).floor() as usize).min(k - 1)
}

/// Whether chain parameter `param` lies on an inner joint (within `END_SNAP` of it).
fn inner_joint(param: f64, k: usize) -> bool {
    let x = param * k as f64;
    let r = x.round();
    r > 0.0 && r < k as f64 && (x - r).abs() <= END_SNAP * k as f64
}

/// The farthest the chain can be from the ray, squared, between samples `x` and `y`: within the nearer of their
/// two nearest points. Each distance squared `|L(t) - n|^2` is convex along the ray and their difference linear,
/// so the least of the two is largest at the ends or where they cross.
pub(super) fn reach_between(x: &ChainSample, y: &ChainSample, (s, dir): (DVec3, DVec3)) -> f64 {
    let f = |n: DVec3, t: f64| (s + dir * t - n).length_squared();
    // f(x.point, t) - f(y.point, t) = |x.point|^2 - |y.point|^2 - 2 (s + dir t) . (x.point - y.point).
    let e = x.point - y.point;
    let slope = -2.0 * dir.dot(e);
    let at_zero = x.point.length_squared() - y.point.length_squared() - 2.0 * s.dot(e);
    let cross = if slope != 0.0 {
        (-at_zero / slope).clamp(x.t, y.t)
    } else {
        x.t
    };
    let cross = if cross.is_finite() { cross } else { x.t };
    x.d2.max(y.d2).max(f(x.point, cross).min(f(y.point, cross)))
}

/// The `MINIMA` deepest local minima of d^2, offered in order (ties to the left), deepest first.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Minima {
    pub(super) best: [Option<ChainSample>; MINIMA],
}

impl Minima {
    /// Offers sample `x` with d^2 `g_left` and `g_right` at its neighbours (infinite beyond the ray).
    pub(super) fn offer(&mut self, x: ChainSample, g_left: f64, g_right: f64) {
        if !(x.d2 < g_left && x.d2 <= g_right) {
            return;
        }
        let mut x = x;
        for slot in &mut self.best {
            match *slot {
                None => {
                    *slot = Some(x);
                    return;
                }
                Some(b) if x.d2 < b.d2 => {
                    *slot = Some(x);
                    x = b;
                }
                Some(_) => {}
            }
        }
    }
}

/// The closest approaches of a chain along the ray: its scan's local minima of d^2, each refined by
/// `PEAK_NEWTON` Newton steps on the exact slope and curvature of d^2, within its scan neighbours (`step` away).
pub(super) fn chain_peaks(
    sample: &impl Fn(f64) -> ChainSample,
    minima: &Minima,
    step: f64,
    eps: f64,
) -> ([Peak; MINIMA], usize) {
    let mut out = [peak(0.0, 0.0, 0.0, eps); MINIMA];
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
/// ends agree, with their segment: the part's nodes are solved on it (the nearest point leaves it only through a
/// joint, which the solve sees, or by a jump and back the scan missed, too narrow to matter; a whole-chain solve at
/// the part's first node could land inside such a jump and carry the wrong segment over the whole part, 0.6 of
/// B lost on a chain of two segments).
pub(super) fn split_at_switch(
    segment: impl Fn(f64) -> Option<usize>,
    (a, b): (f64, f64),
) -> ([(f64, f64); 2], usize, Option<usize>) {
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
            ([(a, m), (m, b)], 2, None)
        }
        (x, _) => ([(a, b); 2], 1, x),
    }
}
