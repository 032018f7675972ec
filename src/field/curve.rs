//! Quadratic Bezier curves and chains of them: the nearest point by Cardano's formula (METHOD.md section 1,
//! thesis 3.8-3.23).
//!
//! A chain of `k` segments has `2k + 1` control points; segment `j` uses points `2j, 2j+1, 2j+2`, so
//! consecutive segments share their end point. The chain is one source: its distance is the nearest point
//! over all segments, and its parameter for the W series is `(j + t) / k`.

use glam::DVec3;

use super::cubic;

/// One quadratic segment in power form, `C(t) = c2 t^2 + c1 t + c0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub c2: DVec3,
    pub c1: DVec3,
    pub c0: DVec3,
}

/// The nearest point of a curve to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Parameter of the nearest point: local `t` for a segment, `(j + t) / k` for a chain.
    pub t: f64,
    /// Distance from the query point.
    pub distance: f64,
}

impl Segment {
    /// From Bezier control points: `c2 = b0 - 2 b1 + b2`, `c1 = 2 (b1 - b0)`, `c0 = b0` (thesis 3.9-3.10).
    pub fn from_bezier(b0: DVec3, b1: DVec3, b2: DVec3) -> Self {
        Self {
            c2: b0 - 2.0 * b1 + b2,
            c1: 2.0 * (b1 - b0),
            c0: b0,
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        (self.c2 * t + self.c1) * t + self.c0
    }

    /// Coefficients `[k3, k2, k1, k0]` of `C'(t) . (C(t) - P) = 0`, the stationarity condition of the squared
    /// distance, with the corrected linear term `2 c2.(c0 - P) + |c1|^2` (METHOD.md section 1).
    pub fn stationary_cubic(&self, p: DVec3) -> [f64; 4] {
        let d = self.c0 - p;
        [
            2.0 * self.c2.length_squared(),
            3.0 * self.c1.dot(self.c2),
            2.0 * self.c2.dot(d) + self.c1.length_squared(),
            self.c1.dot(d),
        ]
    }

    /// Nearest point of this segment (t in [0, 1]) to `p`.
    ///
    /// Candidates: both end points and the real roots in [0, 1] of the stationary cubic, each polished by
    /// two Newton steps on the cubic (Cardano loses digits near double roots) and clamped to [0, 1].
    /// A (nearly) straight segment has a vanishing cubic term; `cubic::solve_cubic` then solves the
    /// lower-degree equation.
    pub fn nearest(&self, p: DVec3) -> Nearest {
        // A segment at rest at its end (its last two control points coincide) is solved from that end: there the
        // stationary cubic has a double root, found only to the square root of the rounding; from the other side
        // it is a simple root. The shader's twin needs this in f32; this one does it alike.
        if self.ends_at_rest() && !self.starts_at_rest() {
            let reversed = Segment {
                c2: self.c2,
                c1: -(2.0 * self.c2 + self.c1),
                c0: self.c2 + self.c1 + self.c0,
            };
            let n = reversed.nearest_from_start(p);
            return Nearest {
                t: 1.0 - n.t,
                distance: n.distance,
            };
        }
        self.nearest_from_start(p)
    }

    /// `nearest`, solved as the segment stands.
    fn nearest_from_start(&self, p: DVec3) -> Nearest {
        let k = self.stationary_cubic(p);
        let mut best = Nearest {
            t: 0.0,
            distance: (self.c0 - p).length(),
        };
        let mut consider = |t: f64| {
            let distance = (self.at(t) - p).length();
            if distance < best.distance {
                best = Nearest { t, distance };
            }
        };
        consider(1.0);
        for &root in cubic::solve_cubic(k[0], k[1], k[2], k[3], 1e-12).as_slice() {
            // Roots far outside [0, 1] cannot polish into it; the end points already cover them.
            if !(-0.5..=1.5).contains(&root) {
                continue;
            }
            consider(root.clamp(0.0, 1.0));
            consider(polish(k, root).clamp(0.0, 1.0));
        }
        // At rest at its start the segment is straight, c0 + c2 t^2, and its nearest t^2 a projection (the cubic's
        // roots crowd around 0 near the resting end; the shader's twin cannot part them in f32).
        let c22 = self.c2.length_squared();
        if self.starts_at_rest() && c22 > 0.0 {
            consider((-self.c2.dot(self.c0 - p) / c22).clamp(0.0, 1.0).sqrt());
        }
        best
    }
}

impl Segment {
    /// The direction in which the segment leaves its start: `C'(0) = c1`, or where that vanishes (the first two
    /// control points coincide, and `C(t) ~ c0 + c2 t^2`) the second derivative's direction, `c2`. Zero only for a
    /// segment of zero length.
    pub fn start_tangent(&self) -> DVec3 {
        if self.starts_at_rest() {
            self.c2
        } else {
            self.c1
        }
    }

    /// The direction in which the segment arrives at its end: `C'(1) = 2 c2 + c1`, or where that vanishes (the
    /// last two control points coincide) `-c2`.
    pub fn end_tangent(&self) -> DVec3 {
        if self.ends_at_rest() {
            -self.c2
        } else {
            2.0 * self.c2 + self.c1
        }
    }
}

/// A first derivative this much smaller (squared) than the second counts as zero: the segment's speed vanishes
/// there, and its direction is the second derivative's. The same in f32 and in f64, so that both twins cut alike.
pub const DEGENERATE: f64 = 1e-10;

impl Segment {
    /// Whether the segment's speed vanishes at its start (its first two control points coincide): there the
    /// nearest point's parameter moves like the square root of the distance it has left the start by.
    pub fn starts_at_rest(&self) -> bool {
        self.c1.length_squared() <= DEGENERATE * self.c2.length_squared()
    }

    /// Whether the segment's speed vanishes at its end (its last two control points coincide).
    pub fn ends_at_rest(&self) -> bool {
        let d1 = 2.0 * self.c2 + self.c1;
        d1.length_squared() <= DEGENERATE * self.c2.length_squared()
    }
}

/// Whether a chain has a segment at rest at an end (two coincident control points), a segment of zero length
/// included: there the nearest point's parameter moves like a square root, which the adaptive integrator's
/// tracking along one segment does not follow, so such a chain is solved on the whole chain at every node.
pub fn is_degenerate(control_points: &[DVec3]) -> bool {
    (0..segment_count(control_points)).any(|j| {
        let s = segment(control_points, j);
        s.starts_at_rest() || s.ends_at_rest()
    })
}

/// Segment `j` of a chain.
fn segment(control_points: &[DVec3], j: usize) -> Segment {
    let b = &control_points[2 * j..2 * j + 3];
    Segment::from_bezier(b[0], b[1], b[2])
}

/// The tangent with which a chain arrives at its joint `j` (the start of segment `j`; `j = k` for its end)
/// from segment `j - 1`, or from `j - 2` where `j - 1` has zero length (zero where neither has a direction),
/// and whether that segment arrives at rest.
pub fn tangent_into(control_points: &[DVec3], j: usize) -> (DVec3, bool) {
    let mut s = segment(control_points, j - 1);
    if s.end_tangent() == DVec3::ZERO && j >= 2 {
        s = segment(control_points, j - 2);
    }
    (s.end_tangent(), s.ends_at_rest())
}

/// The tangent with which a chain leaves its joint `j` (or its start, `j = 0`) on segment `j`, or on `j + 1`
/// where `j` has zero length (zero where neither has a direction), and whether that segment leaves at rest.
pub fn tangent_out_of(control_points: &[DVec3], j: usize) -> (DVec3, bool) {
    let mut s = segment(control_points, j);
    if s.start_tangent() == DVec3::ZERO && j + 1 < segment_count(control_points) {
        s = segment(control_points, j + 1);
    }
    (s.start_tangent(), s.starts_at_rest())
}

/// Two Newton steps on the cubic `k`, keeping the start when a step misbehaves.
fn polish(k: [f64; 4], mut t: f64) -> f64 {
    for _ in 0..2 {
        let f = ((k[0] * t + k[1]) * t + k[2]) * t + k[3];
        let df = (3.0 * k[0] * t + 2.0 * k[1]) * t + k[2];
        if df == 0.0 {
            break;
        }
        let next = t - f / df;
        if !next.is_finite() {
            break;
        }
        t = next;
    }
    t
}

/// The segments of a chain of `2k + 1` control points (`k >= 1`).
pub fn segments(control_points: &[DVec3]) -> impl Iterator<Item = Segment> + '_ {
    control_points
        .windows(3)
        .step_by(2)
        .map(|w| Segment::from_bezier(w[0], w[1], w[2]))
}

/// Nearest point of a whole chain to `p`, with the chain parameter `(j + t) / k`.
/// Panics in debug builds on fewer than 3 or an even number of control points (the scene validator refuses
/// those before they reach the field).
pub fn nearest_on_chain(control_points: &[DVec3], p: DVec3) -> Nearest {
    let (j, n) = nearest_segment(control_points, 0..segment_count(control_points), p);
    chain_nearest(control_points, j, n)
}

/// Nearest point of a chain to `p` where the nearest point is known to lie on segment `*segment`, or to have
/// moved on from it continuously: that segment's nearest point, unless it sits at one of the segment's joints
/// (the nearest point may have passed into the neighbour), and then the whole chain's. `*segment` (None where
/// not known yet) is left on the nearest point's segment.
///
/// The adaptive integrator's pieces of a ray lie between the places where a chain's nearest point jumps or
/// passes a joint, so along one piece one segment in `k` is solved instead of all `k`: the same point as
/// `nearest_on_chain`, at a `k`-th of the cost.
pub fn nearest_on_chain_from(
    control_points: &[DVec3],
    p: DVec3,
    segment: &mut Option<usize>,
) -> Nearest {
    let k = segment_count(control_points);
    if let Some(j) = *segment {
        let (j, n) = nearest_segment(control_points, j..j + 1, p);
        let at_joint = (n.t == 0.0 && j > 0) || (n.t == 1.0 && j + 1 < k);
        if !at_joint {
            return chain_nearest(control_points, j, n);
        }
    }
    let (j, n) = nearest_segment(control_points, 0..k, p);
    *segment = Some(j);
    chain_nearest(control_points, j, n)
}

/// The segment of a chain whose point is nearest to `p`, or `None` where that point is a joint (shared by two
/// segments).
pub fn nearest_segment_index(control_points: &[DVec3], p: DVec3) -> Option<usize> {
    let k = segment_count(control_points);
    let (j, n) = nearest_segment(control_points, 0..k, p);
    let at_joint = (n.t == 0.0 && j > 0) || (n.t == 1.0 && j + 1 < k);
    (!at_joint).then_some(j)
}

/// The number of segments of a chain of `2k + 1` control points.
fn segment_count(control_points: &[DVec3]) -> usize {
    debug_assert!(control_points.len() >= 3 && control_points.len() % 2 == 1);
    (control_points.len() - 1) / 2
}

/// The nearest of the segments `range` to `p` (ties to the first): its index and its own nearest point.
fn nearest_segment(
    control_points: &[DVec3],
    range: std::ops::Range<usize>,
    p: DVec3,
) -> (usize, Nearest) {
    let mut best = (
        range.start,
        Nearest {
            t: 0.0,
            distance: f64::INFINITY,
        },
    );
    for j in range {
        let b = &control_points[2 * j..2 * j + 3];
        let n = Segment::from_bezier(b[0], b[1], b[2]).nearest(p);
        if n.distance < best.1.distance {
            best = (j, n);
        }
    }
    best
}

/// Segment `j`'s nearest point as the chain's: parameter `(j + t) / k`.
fn chain_nearest(control_points: &[DVec3], j: usize, n: Nearest) -> Nearest {
    Nearest {
        t: (j as f64 + n.t) / segment_count(control_points) as f64,
        distance: n.distance,
    }
}

/// A chain at the chain parameter `t = (j + t_j) / k`: the point, its first and second derivatives in the
/// segment's own parameter `t_j`, and whether `t_j` is an end of the segment (0 or 1).
pub fn chain_frame(control_points: &[DVec3], t: f64) -> (DVec3, DVec3, DVec3, bool) {
    let k = (control_points.len() - 1) / 2;
    let x = t.clamp(0.0, 1.0) * k as f64;
    let j = (x.floor() as usize).min(k - 1);
    let b = &control_points[2 * j..2 * j + 3];
    let segment = Segment::from_bezier(b[0], b[1], b[2]);
    let local = x - j as f64;
    (
        segment.at(local),
        2.0 * segment.c2 * local + segment.c1,
        2.0 * segment.c2,
        local <= 0.0 || local >= 1.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_form_matches_bezier() {
        let (b0, b1, b2) = (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(2.0, 0.0, 1.0),
        );
        let s = Segment::from_bezier(b0, b1, b2);
        for i in 0..=10 {
            let t = i as f64 / 10.0;
            let bern = (1.0 - t) * (1.0 - t) * b0 + 2.0 * t * (1.0 - t) * b1 + t * t * b2;
            assert!((s.at(t) - bern).length() < 1e-14);
        }
    }

    #[test]
    fn nearest_on_a_parabola_vertex() {
        // Symmetric arch: the nearest point to a point straight above the apex is the apex, t = 0.5.
        let s = Segment::from_bezier(
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        );
        let n = s.nearest(DVec3::new(0.0, 3.0, 0.0));
        assert!((n.t - 0.5).abs() < 1e-12);
        assert!((n.distance - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_segment_carried_along_a_ray_gives_the_chains_nearest_point() {
        // A chain with a smooth joint and a corner. Along rays in small steps, the segment is carried from one
        // step to the next and forgotten only where the whole-chain search says the nearest point jumped (its
        // parameter moves by more than a step can carry it). Every step must agree with the whole-chain search,
        // also where the nearest point passes a joint continuously.
        let chain = [
            DVec3::new(-3.0, -1.0, -1.0),
            DVec3::new(-1.5, 1.5, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.5, -1.5, 0.0),
            DVec3::new(3.0, 1.0, 1.0),
            DVec3::new(2.0, 2.5, 0.5),
            DVec3::new(0.5, 2.0, 1.5),
        ];
        let mut passes = 0;
        for i in 0..40 {
            for j in 0..8 {
                let a = i as f64 * 0.157;
                let start = DVec3::new(-5.0 * a.cos(), -3.0 + 0.8 * j as f64, 2.0 * a.sin() - 1.0);
                let end = DVec3::new(
                    5.0 * (a + 0.7).cos(),
                    3.0 - 0.7 * j as f64,
                    -1.5 * a.sin() + 0.5,
                );
                let mut segment = None;
                let mut previous = nearest_on_chain(&chain, start);
                for k in 0..=2000 {
                    let p = start + (end - start) * (k as f64 / 2000.0);
                    let want = nearest_on_chain(&chain, p);
                    if (want.t - previous.t).abs() > 0.01 {
                        segment = None;
                    }
                    let before = segment;
                    let got = nearest_on_chain_from(&chain, p, &mut segment);
                    assert!(
                        (got.distance - want.distance).abs() < 1e-12
                            && (got.t - want.t).abs() < 1e-9,
                        "{p}: {got:?} on segment {before:?} vs {want:?}"
                    );
                    passes += usize::from(before.is_some() && before != segment);
                    previous = want;
                }
            }
        }
        // The rays do pass joints, so the fallback to the whole chain was exercised.
        assert!(passes > 20, "{passes} joint passes");
    }
}
