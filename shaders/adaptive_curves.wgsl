// The adaptive integrator's pass for curve chains (entry point integrate_adaptive_curves): the chain's
// features from a scan along the ray, cuts at its kinks, jumps, knots and joints, then Gauss-Kronrod pairs in u
// between the cuts with the nearest point carried node to node. Twin: src/reference/adaptive_curves/mod.rs.
#import adaptive_curves/scan.wgsl

// No segment known yet (nearest_on_chain_from).
const NO_SEGMENT: u32 = 0xffffffffu;

// Twin of curve::nearest_on_chain_from: the nearest point of the chain to p where it lies on segment *segment
// (NO_SEGMENT where not known) or has moved on from it through a joint: that segment's nearest point unless it
// sits at one of the segment's joints, and then the whole chain's, leaving *segment on its segment. (param, d).
fn nearest_on_chain_from(c: CurveSource, p: vec3<f32>, segment: ptr<function, u32>) -> vec2<f32> {
    var lo = 0u;
    var hi = c.segment_count;
    if *segment < c.segment_count {
        lo = *segment;
        hi = lo + 1u;
    }
    var best = vec2<f32>(0.0, F32_MAX);
    var best_j = lo;
    // Two passes at most: the piece's segment, then (at a joint) the whole chain. One call site of the solver.
    loop {
        for (var j = lo; j < hi; j++) {
            let n = nearest_on_segment(chain_segment(c, HELD, j), p);
            if n.y < best.y {
                best = n;
                best_j = j;
            }
        }
        let at_joint = (best.x == 0.0 && best_j > 0u) || (best.x == 1.0 && best_j + 1u < c.segment_count);
        if hi - lo == c.segment_count || !at_joint {
            break;
        }
        lo = 0u;
        hi = c.segment_count;
        best = vec2<f32>(0.0, F32_MAX);
        best_j = 0u;
    }
    *segment = best_j;
    return vec2<f32>((f32(best_j) + best.x) / f32(c.segment_count), best.y);
}

// A node's nearest point is carried from the last node's by TRACK_NEWTON Newton steps (generated: the field
// pass's iteration budget counts them).
// A node keeps Newton's nearest point where the last step moved it less than this along its segment.
const TRACK_SETTLED: f32 = 1e-4;
// The longest way along its segment (in u) a nearest point is carried from the last node.
const TRACK_REACH: f32 = 0.05;

// The nearest point carried along a piece of a curve's ray, node to node in order along it: its segment
// (NO_SEGMENT before the piece's first node), its parameter u on that segment, and du/dt there.
struct Track {
    segment: u32,
    u: f32,       // < 0 where only the segment is known (at a part's start: solved on it in closed form)
    rate: f32,
    t: f32,
    whole: bool,  // solve every node on the whole chain (a part whose ends lie on different segments)
    home: u32,    // the segment of the part's two ends, where they agree (else NO_SEGMENT), which the part's first
                  // node and a refinement's start are solved on (twin of split_at_switch's segment)
}

// The rate du/dt of a nearest point at u on segment s: from the stationarity (C(u) - L(t)) . C'(u) = 0, C'(u) . dir
// over its u derivative; 0 at the segment's ends or where the derivative is not positive.
fn track_rate(s: CurveSegment, u: f32, off: vec3<f32>, dir: vec3<f32>) -> f32 {
    let d1 = 2.0 * s.c2 * u + s.c1;
    let dg = dot(d1, d1) + 2.0 * dot(off, s.c2);
    return select(0.0, dot(d1, dir) / dg, u > 0.0 && u < 1.0 && dg > 0.0);
}

// Whether segment s's stationary cubic at p has a single real root, clear of a double one: its one stationary
// point is then the segment's nearest point, and Newton's point is it. Near the segment's evolute (three roots,
// or nearly) the carried point may be a local minimum that another stationary point of the same segment has
// overtaken: a jump within the segment that the scan did not see, which the closed form does not miss.
fn single_stationary(s: CurveSegment, p: vec3<f32>) -> bool {
    return one_real_root(stationary_cubic(s, p), SINGLE_MARGIN);
}

// How far from a double root single_stationary asks the cubic to be, relative to its discriminant's terms.
const SINGLE_MARGIN: f32 = 1e-2;

// The nearest point of the chain to the ray's point at t, (param, d), carried from the track's last node: the
// track's segment, its u predicted by du/dt and then TRACK_NEWTON Newton steps on the stationarity. Between a
// piece's cuts the nearest point neither jumps nor passes a joint, so this follows it. Where Newton has not
// settled, the segment's stationarity is not a minimum, or the piece has just begun, it is solved in closed
// form (nearest_on_chain_from); so too where the point reaches a joint, which the cuts at joint planes already
// exclude (a safety net against a missed cut). Leaves the track at this node.
fn track_nearest(c: CurveSource, ray: Ray, t: f32, track: ptr<function, Track>) -> vec2<f32> {
    let p = ray.start + ray.dir * t;
    let k = c.segment_count;
    let j = (*track).segment;
    // Carried only over a short way along the segment: where the nearest point races (near a center of
    // curvature) a long prediction can lead Newton to another stationary point.
    let reach = abs((*track).rate * (t - (*track).t));
    if (*track).whole {
        var segment = NO_SEGMENT;
        return nearest_on_chain_from(c, p, &segment);
    }
    if j < k && (*track).u >= 0.0 && reach <= TRACK_REACH {
        let s = chain_segment(c, HELD, j);
        var u = clamp((*track).u + (*track).rate * (t - (*track).t), 0.0, 1.0);
        var step = 0.0;
        var convex = true;
        for (var i = 0u; i < TRACK_NEWTON; i++) {
            let d1 = 2.0 * s.c2 * u + s.c1;
            let off = segment_at(s, u) - p;
            let dg = dot(d1, d1) + 2.0 * dot(off, s.c2);
            convex = convex && dg > 0.0;
            let next = select(u, clamp(u - dot(off, d1) / dg, 0.0, 1.0), dg > 0.0);
            step = next - u;
            u = next;
        }
        let at_joint = (u == 0.0 && j > 0u) || (u == 1.0 && j + 1u < k);
        if convex && abs(step) <= TRACK_SETTLED && !at_joint && single_stationary(s, p) {
            let off = segment_at(s, u) - p;
            *track = Track(j, u, track_rate(s, u, off, ray.dir), t, false, (*track).home);
            return vec2<f32>((f32(j) + u) / f32(k), length(off));
        }
    }
    var segment = j;
    let n = nearest_on_chain_from(c, p, &segment);
    let s = chain_segment(c, HELD, segment);
    let u = clamp(n.x * f32(k) - f32(segment), 0.0, 1.0);
    *track = Track(segment, u, track_rate(s, u, segment_at(s, u) - p, ray.dir), t, false, (*track).home);
    return n;
}

// The brightest point of a chain (the continuous W form) at the ray's point t, carried from the track's last node
// (whose segment, u and rate here name its piece, x and dx/dt): between a part's cuts it stays on one piece and
// moves smoothly (the cuts are where it jumps or passes a piece's end), so TRACK_NEWTON Newton steps on the piece's
// h from where its rate takes it find it, and it stands where every other piece's bound is below its value. Else
// (a part's first node, a step that has not settled, a point at a piece's end or on the flat top, or a part solved
// whole) the whole chain is searched (curve_search, one call site). The f64 twin searches every node; both find the
// same point, to f32 rounding.
fn bright_track(c: CurveSource, ray: Ray, t: f32, track: ptr<function, Track>) -> Bright {
    let p = ray.start + ray.dir * t;
    let k = (*track).segment;
    if k != NO_SEGMENT && !(*track).whole && abs((*track).rate * (t - (*track).t)) <= TRACK_REACH {
        let q = chain_piece(c, HELD, k);
        let h = stationary_quartic(q, p);
        var x = clamp((*track).u + (*track).rate * (t - (*track).t), 0.0, 1.0);
        var step = 1.0;
        var falls = true;
        for (var i = 0u; i < TRACK_NEWTON; i++) {
            let f = quartic_at(h, x);
            falls = f.y < 0.0;
            let next = select(x, clamp(x - f.x / f.y, 0.0, 1.0), falls);
            step = next - x;
            x = next;
        }
        let d = length(piece_at(q, x) - p);
        let value = piece_weight(q, x) / max(EPSILON, d);
        var stands = falls && abs(step) <= TRACK_SETTLED && x > 0.0 && x < 1.0 && d > EPSILON;
        // It must be the largest of its own piece too: h has no other root there (no sign change but one in its
        // Bernstein coefficients on the whole piece; a brighter stretch within eps would have one), and neither
        // end is brighter. A piece whose W series falls from the chain's start toward a dark knot kept a local
        // maximum against its brighter end (pulse_sparks at frame 60: 7.1e-4 of B low, with no other piece to bound it).
        let ends = vec2<f32>(
            piece_weight(q, 0.0) / max(EPSILON, length(q.c0 - p)),
            piece_weight(q, 1.0) / max(EPSILON, length(piece_at(q, 1.0) - p)),
        );
        stands = stands && sign_changes(bernstein_on(h, 0.0, 1.0)) <= 1u && max(ends.x, ends.y) <= value;
        for (var i = 0u; i < c.piece_count; i++) {
            let j = c.first_piece + i;
            let o = chain_piece(c, HELD, j);
            let bound = o.weight_max / max(EPSILON, length(p - o.center) - o.radius);
            stands = stands && (j == k || bound <= value);
        }
        if stands {
            *track = Track(k, x, piece_rate(q, x, p, ray.dir), t, false, NO_SEGMENT);
            return Bright(value, mix(q.t0, q.t1, x), d, x, k);
        }
    }
    let b = curve_search(c, HELD, p);
    let whole = (*track).whole;
    *track = Track(NO_SEGMENT, 0.0, 0.0, t, whole, NO_SEGMENT);
    if b.x > 0.0 && b.x < 1.0 && b.distance > EPSILON {
        *track = Track(b.piece, b.x, piece_rate(chain_piece(c, HELD, b.piece), b.x, p, ray.dir), t, whole, NO_SEGMENT);
    }
    return b;
}

// The Kronrod and Gauss values on [a, b] in u of a curve's term: f = w / max(eps, d) zeta(t) (before the
// coefficient) at each node, t clamped to the piece. The nodes go in order along the ray, so that each carries
// the nearest point on from the last (track_nearest). Twin of kronrod.
// The Kronrod and Gauss values (kg) and, of the term times the curve's color series (zero without one), the
// Kronrod value (colored): its nodes are B's, and B's pair decides the refinement.
struct CurveRule {
    kg: vec2<f32>,
    colored: vec3<f32>,
}

fn curve_kronrod(ray: Ray, p: Peak, a: f32, b: f32, panel: vec2<f32>, singular: vec2<bool>, track: ptr<function, Track>) -> CurveRule {
    let c = CHAIN;
    let mid = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    var sum = vec2<f32>(0.0);
    var colored = vec3<f32>(0.0);
    for (var i = 0u; i <= 2u * gauss_order(); i++) {
        let node = kronrod_node(i);
        let toward = toward_singular(mid + r * node.x, panel, singular);
        let m = map_node(p, toward.x);
        // The continuous W form searches the whole chain at every node (twin of integrate_weighted).
        var n: vec2<f32>;
        if reads_brightest(c) {
            let b = bright_track(c, ray, m.x, track);
            n = vec2<f32>(b.t, b.distance);
        } else {
            n = track_nearest(c, ray, m.x, track);
        }
        let w = wseries(c, HELD.weights, n.x);
        var f = toward.y * m.y * w * falloff(n.y, EPSILON) * zeta_at(m.x);
        if params.decay == 1u {
            // The rms decay's square of the weighed energy (the map's derivatives stay to the first power).
            let v = w * falloff(n.y, EPSILON) * zeta_at(m.x);
            f = toward.y * m.y * v * v;
        }
        sum += node.yz * f;
        colored += node.y * f * color_series(c, n.x);
    }
    return CurveRule(r * sum, r * colored);
}

// Twin of toward_singular: u at v on the panel [a, b] with the nodes drawn toward its singular ends, and du/dv.
fn toward_singular(v: f32, panel: vec2<f32>, singular: vec2<bool>) -> vec2<f32> {
    let x = (v - panel.x) / (panel.y - panel.x);
    var phi = vec2<f32>(x, 1.0);
    if singular.x && singular.y {
        phi = vec2<f32>(x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x));
    } else if singular.x {
        phi = vec2<f32>(x * x, 2.0 * x);
    } else if singular.y {
        phi = vec2<f32>(x * (2.0 - x), 2.0 - 2.0 * x);
    }
    return vec2<f32>(panel.x + (panel.y - panel.x) * phi.x, phi.y);
}

// A curve's term on the panel [a, b] in u, refined where the pair disagrees. Twin of integrate_panel.
fn curve_panel(ray: Ray, p: Peak, a: f32, b: f32, singular: vec2<bool>, allowance: f32, refinements: ptr<function, u32>, track: ptr<function, Track>) -> vec4<f32> {
    let end = 1u << MAX_DEPTH;
    var at = 0u;
    var level = 0u;
    var sum = vec4<f32>(0.0);
    while at < end {
        let x = part_bounds(a, b, at, level);
        let rule = curve_kronrod(ray, p, x.x, x.y, vec2<f32>(a, b), singular, track);
        let kg = rule.kg;
        if settled(kg, allowance, x.y - x.x) || level == MAX_DEPTH || *refinements == 0u {
            sum += vec4<f32>(kg.x, rule.colored);
            let next = next_part(at, level);
            at = next.x;
            level = next.y;
        } else {
            // Back to the part's start: the nearest point is solved afresh there rather than carried back over
            // the whole part, where Newton could settle on another stationary point.
            (*track).segment = (*track).home;
            (*track).u = -1.0;
            *refinements -= 1u;
            level++;
        }
    }
    return sum;
}

// Twin of curve::nearest_segment_index: the segment of the chain's nearest point to the ray's point at u of
// p's map, NO_SEGMENT where that point is a joint.
fn nearest_segment_index(c: CurveSource, ray: Ray, p: Peak, u: f32) -> u32 {
    var segment = NO_SEGMENT;
    let n = nearest_on_chain_from(c, ray.start + ray.dir * map_node(p, u).x, &segment);
    let local = n.x * f32(c.segment_count) - f32(segment);
    // The chain parameter's f32 rounding: a joint's local parameter comes back within a few ulps of 0 or 1.
    let at_joint = (local <= 1e-5 && segment > 0u) || (local >= 1.0 - 1e-5 && segment + 1u < c.segment_count);
    return select(segment, NO_SEGMENT, at_joint);
}

// A curve's term of B over its pieces, each cut at its kinks, and that term times its color series (zero
// without one). Twin of integrate_term and, for the series, of integrate_weighted.
fn integrate_curve_term(index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> vec4<f32> {
    CHAIN = curves[index];
    let c = CHAIN;
    let coefficient = c.coefficient;
    if coefficient == 0.0 {
        return vec4<f32>(0.0);
    }
    HELD = held_chain(c);
    let ray = Ray(s_point, e_point - s_point, 3u, index, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    // A chain with a segment at rest at an end (or of zero length) is solved on the whole chain at every node:
    // the tracking of the nearest point along one segment loses it there.
    var degenerate = false;
    for (var j = 0u; j < c.segment_count; j++) {
        let s = chain_segment(c, HELD, j);
        degenerate = degenerate || starts_at_rest(s) || ends_at_rest(s);
    }
    let features = curve_features(ray);
    let length = pieces_length(features.found);
    var allowance = params.term_tolerance / (abs(coefficient) * max(length, 1e-30));
    // The rms decay's allowance comes from an estimate of its integral: the same panels unrefined, a pass before.
    let passes = select(1u, 2u, params.decay == 1u);
    var sum = vec4<f32>(0.0);
    for (var sweep = 0u; sweep < passes; sweep++) {
    var refinements = select(COARSE_REFINEMENTS, MAX_REFINEMENTS, gauss_order() > COARSE_ORDER);
    if sweep + 1u < passes {
        refinements = 0u;
    }
    sum = vec4<f32>(0.0);
    for (var k = 0u; k < features.found.count; k++) {
        let p = features.found.peaks[k];
        let u0 = stable_asinh((p.lo - p.center) / p.width);
        let u1 = stable_asinh((p.hi - p.center) / p.width);
        if u1 <= u0 {
            continue;
        }
        // The piece cut in order at the kinks inside it and, closer than eps, at the ends of the falloff's flat
        // top, -kf and kf (twin of cuts): each part ends at the least cut past its start, so that no array is
        // written (see integrate_smooth_term).
        let kf = select(F32_MAX, stable_asinh(p.flat / p.width), p.flat > 0.0);
        // Ordinary kinks within SINGULAR_MERGE of a singular one are dropped (twin of cuts): bit m of kept.
        var kept = 0u;
        for (var m = 0u; m < features.kink_count; m++) {
            let um = stable_asinh((features.kinks[m] - p.center) / p.width);
            var shadowed = false;
            for (var q = 0u; q < features.kink_count; q++) {
                let uq = stable_asinh((features.kinks[q] - p.center) / p.width);
                shadowed = shadowed || (((features.kink_singular >> q) & 1u) == 1u && abs(uq - um) <= SINGULAR_MERGE);
            }
            if ((features.kink_singular >> m) & 1u) == 1u || !shadowed {
                kept |= 1u << m;
            }
        }
        // Cuts within CUT_MERGE of the first of a cluster are one: at its first singular cut if any, singular if
        // any is (twin of cuts' merging). start: the cluster's first cut.
        var singular_b = false;
        for (var m = 0u; m < features.kink_count; m++) {
            let u = stable_asinh((features.kinks[m] - p.center) / p.width);
            singular_b = singular_b || (u > u0 && u <= u0 + CUT_MERGE && ((features.kink_singular >> m) & 1u) == 1u);
        }
        var b = u0;
        var start = u0;
        while b < u1 {
            let a = b;
            let singular_a = singular_b;
            var next = u1;
            for (var m = 0u; m < features.kink_count; m++) {
                let u = stable_asinh((features.kinks[m] - p.center) / p.width);
                if u > start + CUT_MERGE && u < u1 && ((kept >> m) & 1u) == 1u {
                    next = min(next, u);
                }
            }
            if -kf > start + CUT_MERGE && -kf < u1 {
                next = min(next, -kf);
            } else if kf > start + CUT_MERGE && kf < u1 {
                next = min(next, kf);
            }
            start = next;
            b = next;
            singular_b = false;
            var first_singular = F32_MAX;
            for (var m = 0u; m < features.kink_count; m++) {
                let u = stable_asinh((features.kinks[m] - p.center) / p.width);
                if u >= next && u <= next + CUT_MERGE && u < u1 && ((features.kink_singular >> m) & 1u) == 1u {
                    singular_b = true;
                    first_singular = min(first_singular, u);
                }
            }
            if singular_b {
                b = first_singular;
            }
            if u1 - next <= CUT_MERGE {
                b = u1;
            }
            // The safety net behind the cuts (twin of split_at_switch): a part whose ends' nearest points lie on
            // different segments holds a missed jump; it is split where the segment changes, found by bisection,
            // and both sides are solved on the whole chain at every node. So is a part that begins or ends at rest,
            // where the nodes crowd toward the cut.
            let inset = SWITCH_INSET * (b - a);
            // (Not for a curve that reads its brightest point: its nearest point's segments say nothing of it.)
            var ends = vec2<u32>(0u);
            if !(reads_brightest(c)) {
                ends = vec2<u32>(nearest_segment_index(c, ray, p, a + inset), nearest_segment_index(c, ray, p, b - inset));
            }
            let switched = ends.x != ends.y;
            var split = b;
            if switched {
                var lo = a + inset;
                var hi = b - inset;
                for (var r = 0u; r < SWITCH_ROUNDS; r++) {
                    let mid = 0.5 * (lo + hi);
                    if nearest_segment_index(c, ray, p, mid) == ends.x {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                split = 0.5 * (lo + hi);
            }
            for (var part = 0u; part < select(1u, 2u, switched); part++) {
                let pa0 = select(a, split, part == 1u);
                let pb0 = select(split, b, part == 1u || !switched);
                let first = part == 0u;
                let last = part == 1u || !switched;
                // In f32 the bisection can end on a part's end, leaving the other part empty.
                if pb0 <= pa0 {
                    continue;
                }
                let panels = u32(clamp(ceil((pb0 - pa0) / U_PANEL), 1.0, f32(MAX_GAUSS_PANELS)));
                let width = (pb0 - pa0) / f32(panels);
                // Where the part's ends agree on a segment (not in the continuous form, whose ends are 0 here), its
                // nodes are solved on it: a whole-chain solve at the first node could land inside a jump and back the
                // scan missed and carry that segment over the whole part.
                let home = select(NO_SEGMENT, ends.x, !switched && !(reads_brightest(c)));
                var track = Track(home, -1.0, 0.0, 0.0, switched || singular_a || singular_b || degenerate, home);
                for (var i = 0u; i < panels; i++) {
                    let pa = pa0 + width * f32(i);
                    let singular = vec2<bool>(singular_a && first && i == 0u, singular_b && last && i + 1u == panels);
                    sum += curve_panel(ray, p, pa, pa + width, singular, allowance, &refinements, &track);
                }
            }
        }
    }
    if sweep + 1u < passes {
        allowance = rms_allowance(sum.x, coefficient * coefficient, length);
    }
    }
    if params.decay == 1u {
        // B_i, and the color series' mean weighed by the term's square (twin of tint_of).
        let b = finish(coefficient * coefficient * sum.x, coefficient);
        return vec4<f32>(b, select(vec3<f32>(0.0), b * sum.yzw / sum.x, sum.x > 0.0));
    }
    return coefficient * sum;
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive_curves(@builtin(global_invocation_id) gid: vec3<u32>) {
    let texel = begin_texel(gid);
    if !texel.inside {
        return;
    }
    let first_curve = point_count() + line_count() + torus_count();
    var b = vec4<f32>(0.0);
    // The range holds curves only (gpu::field_pass::plan_chunks).
    for (var t = chunk.first; t < chunk.first + chunk.count; t++) {
        let term = integrate_curve_term(t - first_curve, texel.start, texel.end);
        b += glow_of(t, term.x) + vec4<f32>(0.0, term.yzw);
    }
    store(texel.id, b);
}
