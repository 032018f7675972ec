// The adaptive integrator's shared parts (twin of src/reference/adaptive.rs): source by source, the ray shared into pieces
// around the term's features (closest approaches, a torus's axis), each mapped by s = s* + h sinh(u), and
// integrated by Gauss-Kronrod pairs in u, bisected where the pair disagrees. Two passes build on this file:
// adaptive_smooth.wgsl (points, lines and tori; entry point integrate_adaptive) and adaptive_curves.wgsl
// (integrate_adaptive_curves). They are dispatched separately and add into the texture; each is a module of its
// own, so neither carries the other's code, which on CPU drivers costs even where it never runs.
#import shared/brightest.wgsl

const KIND_POINT: u32 = 0u;
const KIND_LINE: u32 = 1u;
const KIND_TORUS: u32 = 2u;
// The adaptive integrator's settings and the Gauss-Kronrod table (KRONROD, kronrod_start) are generated from
// the twin's (gpu::shaders::shared_constants) and prepended to the module.

// A feature and the piece [lo, hi] of the ray it owns: center s* and width h in s, and flat, the half-length of
// the stretch where the source is closer than eps (0 where it is not).
struct Peak {
    lo: f32,
    hi: f32,
    center: f32,
    width: f32,
    flat: f32,
}

// At most MAX_PEAKS: a torus's two ring passes and its axis, or a chain's two closest approaches and two ends.
struct Peaks {
    peaks: array<Peak, MAX_PEAKS>,
    count: u32,
}

// A source along the ray S + s dir, fixed for one term's integration.
struct Ray {
    start: vec3<f32>,
    dir: vec3<f32>,
    kind: u32,
    index: u32,
    // A point's, a line's or a torus's geometry, read once for the term (see load_scalars): the point, the
    // line's point and direction, the torus's center, axis and major radius.
    anchor: vec3<f32>,
    along: vec3<f32>,
    radius: f32,
}

// Twin of adaptive::peak.
fn make_peak(center: f32, d2_min: f32, a: f32) -> Peak {
    let eps = EPSILON;
    let d2 = max(d2_min, eps * eps);
    var width = MAX_WIDTH;
    var flat = 0.0;
    if a > 0.0 {
        width = min(sqrt(d2 / a), MAX_WIDTH);
        if d2_min < eps * eps {
            flat = sqrt((eps * eps - d2_min) / a);
        }
    }
    return Peak(0.0, 1.0, center, max(width, 1e-6), flat);
}

// The ray's closest approach to a line through m along the unit d: (t*, d*^2, a). Twin of line_approach.
fn line_approach(ray: Ray, m: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let q0 = ray.start - m;
    let q = q0 - d * dot(q0, d);
    let v = ray.dir - d * dot(ray.dir, d);
    let a = dot(v, v);
    var c = 0.0;
    if a > 0.0 {
        c = -dot(q, v) / a;
    }
    let closest = q + v * c;
    return vec3<f32>(c, dot(closest, closest), a);
}

// Where feature y (further along the ray) takes over from x: their maps are equally dense there. Twin of the
// closure in share_ray.
fn meet(x: Peak, y: Peak) -> f32 {
    let gap = y.center - x.center;
    if gap > 0.0 {
        return 0.5 * (x.center + y.center) + (y.width - x.width) * (y.width + x.width) / (2.0 * gap);
    }
    if y.width <= x.width {
        return -1e30;
    }
    return 1e30;
}

// Swaps features j and j + 1 (of the first n) where the second lies before the first along the ray: a step of a
// bubble sort, stable like the CPU's sort.
fn order_pair(found: ptr<function, Peaks>, j: u32, n: u32) {
    if j + 1u < n && (*found).peaks[j + 1u].center < (*found).peaks[j].center {
        let x = (*found).peaks[j];
        (*found).peaks[j] = (*found).peaks[j + 1u];
        (*found).peaks[j + 1u] = x;
    }
}

// Sorts the features along the ray (a bubble sort, stable like the CPU's) and gives every stretch of the ray to
// the feature whose map is densest there: the lower envelope of the lines (h^2 + s*^2) - 2 s* s. Twin of
// share_ray. The sort's three pairs (MAX_PEAKS = 4) have fixed indices: an insertion sort's `peaks[j - 1]` in
// its loop's condition gave a torus wrong features on 0.7 % of its texels on GL, where naga adds no bounds checks
// (Vulkan with wgpu's bounds checks turned off gave the same values; with them, the right ones).
fn share_ray(found: ptr<function, Peaks>) {
    let n = (*found).count;
    for (var round = 1u; round < n; round++) {
        order_pair(found, 0u, n);
        order_pair(found, 1u, n);
        order_pair(found, 2u, n);
    }
    // Feature i hands over at the first takeover by any later one (an empty piece where it is nowhere the
    // densest).
    var lo = 0.0;
    for (var i = 0u; i < n; i++) {
        var hi = 1.0;
        if i + 1u < n {
            var to = 1e30;
            for (var j = i + 1u; j < n; j++) {
                to = min(to, meet((*found).peaks[i], (*found).peaks[j]));
            }
            hi = clamp(to, lo, 1.0);
        }
        (*found).peaks[i].lo = lo;
        (*found).peaks[i].hi = hi;
        (*found).peaks[i].center = clamp((*found).peaks[i].center, lo, hi);
        lo = hi;
    }
}

// asinh without the cancellation of log(x + sqrt(x^2 + 1)) for x << 0 (some drivers evaluate it so: at
// x = -1000 in f32 that loses a tenth of the result).
fn stable_asinh(x: f32) -> f32 {
    let a = abs(x);
    return sign(x) * log(a + sqrt(a * a + 1.0));
}

// KRONROD as a variable: indexing a constant array with a variable makes naga copy the whole array into a
// temporary at every access, which lavapipe pays in full; a private variable is copied once.
var<private> KRONROD_NODES: array<vec3<f32>, KRONROD_ROWS> = KRONROD;

// Node i of the 2n + 1 of the pair on [a, b] in u, in order along the ray (the outermost on the left first):
// (u's offset factor x with its sign, Kronrod weight, Gauss weight).
fn kronrod_node(i: u32) -> vec3<f32> {
    let n = gauss_order();
    let first = kronrod_start(n);
    if i < n {
        let row = KRONROD_NODES[first + n - i];
        return vec3<f32>(-row.x, row.y, row.z);
    }
    return KRONROD_NODES[first + i - n];
}

// s at u by p's map, s* + h sinh(u), clamped to the piece, and ds/du = h cosh(u): one exp.
fn map_node(p: Peak, u: f32) -> vec2<f32> {
    let e = exp(u);
    return vec2<f32>(clamp(p.center + p.width * 0.5 * (e - 1.0 / e), p.lo, p.hi), p.width * 0.5 * (e + 1.0 / e));
}

// The allowance of a term with the rms decay (twin of rms_allowance): B = sqrt(J / stretch) of the integral J of the
// squared term, and an error dJ costs about dJ / (2 sqrt(stretch J)) of B, so J may err by tolerance sqrt(stretch J)
// (half what B allows), J estimated by the term's panels unrefined, and at least by tolerance^2 stretch
// (|sqrt(x) - sqrt(y)| <= sqrt(|x - y|)); shared evenly along its u length. estimate: J without the factor scale
// (b^2) the integrand was taken without.
fn rms_allowance(estimate: f32, scale: f32, length: f32) -> f32 {
    let tolerance = params.term_tolerance;
    let stretch = STRETCH;
    let per_b = max(tolerance * sqrt(stretch * scale * max(estimate, 0.0)), tolerance * tolerance * stretch);
    return per_b / (scale * max(length, 1e-30));
}

// The weighed energy v of a term at a node, squared for the rms decay (Integration::power).
fn decayed(v: f32) -> f32 {
    return select(v, v * v, params.decay == 1u);
}

// A term's part of B from the integral of its weighed energy to the decay's power, for a term of `coefficient`:
// with the rms decay the root takes back the sign the square dropped (twin of Integration::finish).
fn finish(integral: f32, coefficient: f32) -> f32 {
    if params.decay == 1u {
        return signed_root(integral, coefficient);
    }
    return integral;
}

// Whether a part's Kronrod and Gauss values kg are close enough for its share of the allowance (per unit of u),
// or close to f32's rounding of the value, below which f32 cannot tell. Twin of integrate_panel's test.
fn settled(kg: vec2<f32>, allowance: f32, width: f32) -> bool {
    return abs(kg.x - kg.y) <= max(allowance * width, 4e-6 * abs(kg.x));
}

// The part at `at` of size 2^-level (in units of 2^-MAX_DEPTH) of the panel [a, b]: its ends in u. Shared by
// both passes' bisection walks (smooth_panel, curve_panel), which differ only in their rule.
fn part_bounds(a: f32, b: f32, at: u32, level: u32) -> vec2<f32> {
    let end = f32(1u << MAX_DEPTH);
    return vec2<f32>(a + (b - a) * (f32(at) / end), a + (b - a) * (f32(at + ((1u << MAX_DEPTH) >> level)) / end));
}

// The next part of a dyadic bisection after an accepted one (twin of integrate_panel): (at, level) on.
fn next_part(at: u32, level: u32) -> vec2<u32> {
    let end = 1u << MAX_DEPTH;
    let next = at + (end >> level);
    var up = level;
    while up > 0u && (next & ((end >> (up - 1u)) - 1u)) == 0u {
        up -= 1u;
    }
    return vec2<u32>(next, up);
}

// The u length of a term's pieces, over which its tolerance is shared.
fn pieces_length(found: Peaks) -> f32 {
    var length = 0.0;
    for (var k = 0u; k < found.count; k++) {
        let p = found.peaks[k];
        length += max(stable_asinh((p.hi - p.center) / p.width) - stable_asinh((p.lo - p.center) / p.width), 0.0);
    }
    return length;
}
