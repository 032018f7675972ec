// The field pass: for every texel of the billboard's W x W brightness texture, integrate the energy field psi
// along the texel's ray S -> E with Simpson's rule (METHOD.md section 3), accumulating in one pass: memory is
// the texture alone, O(W^2). field_common.wgsl is prepended. Rust side: src/gpu/field_pass.rs (gpu_data holds
// the mirror of FieldParams; keep in sync). CPU twin: src/reference.rs and src/integrate.rs.

struct FieldParams {
    center: vec3<f32>,  // billboard center C
    size: f32,          // side length l
    right: vec3<f32>,
    resolution: u32,    // W
    up: vec3<f32>,
    divisions: u32,     // Simpson's n, even
    eye: vec3<f32>,     // V
    nu: f32,
    alpha: f32,
    beta: f32,
    epsilon: f32,
    point_count: u32,
    line_count: u32,
    torus_count: u32,
    curve_count: u32,
    integrator: u32,    // 0: simpson, 1: adaptive
    tolerance: f32,     // adaptive: error allowed on a term's integral before its coefficient
    jitter: u32,        // simpson: 1 for the randomly shifted rectangle rule
    seed: u32,
    gauss_order: u32,   // adaptive: Gauss-Legendre nodes per panel for points, lines and tori (6, 8, 10, 12, 16)
}

@group(0) @binding(0) var<storage, read> params: FieldParams;
@group(0) @binding(1) var<storage, read> points: array<PointSource>;
@group(0) @binding(2) var<storage, read> lines: array<LineSource>;
@group(0) @binding(3) var<storage, read> tori: array<TorusSource>;
@group(0) @binding(4) var<storage, read> curves: array<CurveSource>;
@group(0) @binding(5) var<storage, read> segments: array<CurveSegment>;
@group(0) @binding(6) var<storage, read> weights: array<f32>;
@group(0) @binding(7) var brightness: texture_storage_2d<r32float, read_write>;

// One dispatch's share of the work: a range of Simpson samples, or of the adaptive integrator's terms (points,
// then lines, tori, curves). A texel's loops must stay under what some drivers allow one invocation (Mesa's
// llvmpipe and lavapipe stop every loop of an invocation after 65535 iterations in all, silently), so long
// integrals are split over several dispatches that add into the texture. Rust side: gpu_data::Chunk.
struct Chunk {
    first: u32,
    count: u32,
    accumulate: u32,  // 0: the first dispatch writes, else adds to what the texel holds
    pipeline: u32,    // the entry point that runs it (read on the CPU only)
}

@group(0) @binding(8) var<storage, read> chunk: Chunk;

fn store(id: vec2<u32>, value: f32) {
    var v = value;
    if chunk.accumulate != 0u {
        v += textureLoad(brightness, vec2<i32>(id)).x;
    }
    textureStore(brightness, vec2<i32>(id), vec4<f32>(v, 0.0, 0.0, 1.0));
}

// Sw(t) of a curve's W series (METHOD.md section 2). Twin of wseries::evaluate.
fn wseries(c: CurveSource, t_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    let n = c.weight_count;
    let w = c.first_weight;
    if n == 0u {
        return 1.0;
    }
    if n == 1u {
        return weights[w];
    }
    if n == 2u {
        return mix(weights[w], weights[w + 1u], t);
    }
    let b = wseries_basis(n, t);
    let first = w + wseries_span(n, t) - 2u;
    return b.x * weights[first] + b.y * weights[first + 1u] + b.z * weights[first + 2u];
}

// The nearest point of a curve chain: (t* = (j + t) / k over all segments, distance).
fn curve_nearest(c: CurveSource, p: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(0.0, F32_MAX);
    for (var j = 0u; j < c.segment_count; j++) {
        let n = nearest_on_segment(segments[c.first_segment + j], p);
        if n.y < best.y {
            best = vec2<f32>((f32(j) + n.x) / f32(c.segment_count), n.y);
        }
    }
    return best;
}

// A curve chain's term: b Sw(t*) / max(eps, L).
fn curve_field(c: CurveSource, p: vec3<f32>) -> f32 {
    let best = curve_nearest(c, p);
    return c.coefficient * wseries(c, best.x) * falloff(best.y, params.epsilon);
}

// psi(P), the sum over every source (thesis 3.28).
fn psi(p: vec3<f32>) -> f32 {
    let eps = params.epsilon;
    var sum = 0.0;
    for (var i = 0u; i < params.point_count; i++) {
        let s = points[i];
        sum += s.coefficient * falloff(length(p - s.position), eps);
    }
    for (var i = 0u; i < params.line_count; i++) {
        let s = lines[i];
        sum += s.coefficient * falloff(line_distance(p, s.point, s.direction), eps);
    }
    for (var i = 0u; i < params.torus_count; i++) {
        let s = tori[i];
        sum += s.coefficient * falloff(torus_distance(p, s.center, s.axis, s.major_radius), eps);
    }
    for (var i = 0u; i < params.curve_count; i++) {
        sum += curve_field(curves[i], p);
    }
    return sum;
}

// The integrand psi(L(s)) zeta(s), zeta(s) = alpha / (s + beta)^2.
fn integrand(s_point: vec3<f32>, e_point: vec3<f32>, s: f32) -> f32 {
    let zeta = params.alpha / ((s + params.beta) * (s + params.beta));
    return psi(mix(s_point, e_point, s)) * zeta;
}

// The texel's segment S -> E (4.2, 4.3): texel center on the billboard, column from the left, row from the top.
fn texel_segment(id: vec2<u32>) -> array<vec3<f32>, 2> {
    let w = params.resolution;
    let u = (f32(id.x) + 0.5) / f32(w) - 0.5;
    let v = 0.5 - (f32(id.y) + 0.5) / f32(w);
    let s_point = params.center + params.right * (params.size * u) + params.up * (params.size * v);
    let e_point = params.eye + params.nu * (s_point - params.eye);
    return array<vec3<f32>, 2>(s_point, e_point);
}

// The PCG hash (Jarzynski and Olano 2020). Twin of integrate::pcg_hash.
fn pcg_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The texel's jitter offset in [0, 1). Twin of integrate::jitter_offset.
fn jitter_offset(id: vec2<u32>) -> f32 {
    let index = id.y * params.resolution + id.x;
    let h = pcg_hash(index ^ pcg_hash(params.seed + 0x9e3779b9u));
    return f32(h >> 8u) / 16777216.0;
}

// The papers' integrator: Simpson's rule over k = 0..=n (3.33, corrected to end at s = 1), or with jitter the
// randomly shifted rectangle rule (1 / n) sum f((k + xi) / n), unbiased, its error noise instead of bands.
@compute @workgroup_size(8, 8)
fn integrate(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    let seg = texel_segment(id.xy);
    let s_point = seg[0];
    let e_point = seg[1];
    let n = params.divisions;
    let nf = f32(n);
    let first = chunk.first;
    var b = 0.0;
    if params.jitter != 0u {
        let xi = jitter_offset(id.xy);
        let last = min(first + chunk.count, n);
        var sum = 0.0;
        for (var k = first; k < last; k++) {
            sum += integrand(s_point, e_point, (f32(k) + xi) / nf);
        }
        b = sum / nf;
    } else {
        // Samples k = first .. first + count of 0..=n, with Simpson's weights 1 4 2 4 ... 4 1.
        let last = min(first + chunk.count, n + 1u);
        var sum = 0.0;
        for (var k = first; k < last; k++) {
            var weight = select(2.0, 4.0, (k & 1u) == 1u);
            if k == 0u || k == n {
                weight = 1.0;
            }
            sum += weight * integrand(s_point, e_point, f32(k) / nf);
        }
        b = sum / (3.0 * nf);
    }
    store(id.xy, b);
}

// ---- The adaptive integrator (twin of src/adaptive.rs): source by source, the ray shared into pieces around
// the term's features (closest approaches, a torus's axis), each mapped by s = s* + h sinh(u). Two entry points:
// integrate_adaptive (points, lines and tori: Gauss-Legendre in u) and integrate_adaptive_curves (adaptive
// Simpson in u). They are dispatched separately and add into the texture: apart, neither carries the other's
// code, which on CPU drivers costs even where it never runs.

const KIND_POINT: u32 = 0u;
const KIND_LINE: u32 = 1u;
const KIND_TORUS: u32 = 2u;
const SCAN: u32 = 6u;
const PANELS: u32 = 6u;
const DEPTH: u32 = 12u;
const SPLITS: u32 = 200u;
const RELATIVE_FLOOR: f32 = 4e-6;
const MAX_WIDTH: f32 = 4.0;
const MIN_AXIS_WIDTH: f32 = 1e-4;
const U_PANEL: f32 = 4.0;
const MAX_GAUSS_PANELS: u32 = 4u;
const RING_NEWTON: u32 = 6u;
const RING_STEP: f32 = 0.125;

// Gauss-Legendre on [-1, 1], 6, 8, 10, 12 and 16 nodes: (positive node, weight), each rule's pairs in turn.
// Twin of adaptive::GAUSS.
const GAUSS: array<vec2<f32>, 26> = array<vec2<f32>, 26>(
    vec2<f32>(0.238619186, 0.467913935),  // 6
    vec2<f32>(0.661209386, 0.360761573),  // 6
    vec2<f32>(0.932469514, 0.171324492),  // 6
    vec2<f32>(0.183434642, 0.362683783),  // 8
    vec2<f32>(0.525532410, 0.313706646),  // 8
    vec2<f32>(0.796666477, 0.222381034),  // 8
    vec2<f32>(0.960289856, 0.101228536),  // 8
    vec2<f32>(0.148874339, 0.295524225),  // 10
    vec2<f32>(0.433395394, 0.269266719),  // 10
    vec2<f32>(0.679409568, 0.219086363),  // 10
    vec2<f32>(0.865063367, 0.149451349),  // 10
    vec2<f32>(0.973906529, 0.066671344),  // 10
    vec2<f32>(0.125233409, 0.249147046),  // 12
    vec2<f32>(0.367831499, 0.233492537),  // 12
    vec2<f32>(0.587317954, 0.203167427),  // 12
    vec2<f32>(0.769902674, 0.160078329),  // 12
    vec2<f32>(0.904117256, 0.106939326),  // 12
    vec2<f32>(0.981560634, 0.047175336),  // 12
    vec2<f32>(0.095012510, 0.189450610),  // 16
    vec2<f32>(0.281603551, 0.182603415),  // 16
    vec2<f32>(0.458016778, 0.169156519),  // 16
    vec2<f32>(0.617876244, 0.149595989),  // 16
    vec2<f32>(0.755404408, 0.124628971),  // 16
    vec2<f32>(0.865631202, 0.095158512),  // 16
    vec2<f32>(0.944575023, 0.062253524),  // 16
    vec2<f32>(0.989400935, 0.027152459),  // 16
);

// A feature and the piece [lo, hi] of the ray it owns: center s* and width h in s, and flat, the half-length of
// the stretch where the source is closer than eps (0 where it is not).
struct Peak {
    lo: f32,
    hi: f32,
    center: f32,
    width: f32,
    flat: f32,
}

struct Peaks {
    peaks: array<Peak, 3>,
    count: u32,
}

// A source along the ray S + s dir, fixed for one term's integration.
struct Ray {
    start: vec3<f32>,
    dir: vec3<f32>,
    kind: u32,
    index: u32,
}

// Twin of adaptive::peak.
fn make_peak(center: f32, d2_min: f32, a: f32) -> Peak {
    let eps = params.epsilon;
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

// Sorts the features along the ray (insertion sort, stable like the CPU's) and gives every stretch of the ray to
// the feature whose map is densest there: the lower envelope of the lines (h^2 + s*^2) - 2 s* s. Twin of
// share_ray.
fn share_ray(found: ptr<function, Peaks>) {
    let n = (*found).count;
    for (var i = 1u; i < n; i++) {
        var j = i;
        while j > 0u && (*found).peaks[j].center < (*found).peaks[j - 1u].center {
            let x = (*found).peaks[j];
            (*found).peaks[j] = (*found).peaks[j - 1u];
            (*found).peaks[j - 1u] = x;
            j -= 1u;
        }
    }
    var bounds = vec2<f32>(1.0, 1.0);
    if n == 2u {
        bounds.x = meet((*found).peaks[0], (*found).peaks[1]);
    } else if n == 3u {
        let b01 = meet((*found).peaks[0], (*found).peaks[1]);
        let b12 = meet((*found).peaks[1], (*found).peaks[2]);
        if b01 < b12 {
            bounds = vec2<f32>(b01, b12);
        } else {
            let b02 = meet((*found).peaks[0], (*found).peaks[2]);
            bounds = vec2<f32>(b02, b02);
        }
    }
    var lo = 0.0;
    for (var i = 0u; i < n; i++) {
        var hi = 1.0;
        if i + 1u < n {
            hi = clamp(bounds[i], lo, 1.0);
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

// The decay zeta(t) along the ray.
fn zeta_at(t: f32) -> f32 {
    return params.alpha / ((t + params.beta) * (t + params.beta));
}

// -- Points, lines and tori: Gauss-Legendre in u.

// A point's, a line's or a torus's distance from p.
fn smooth_distance(kind: u32, index: u32, p: vec3<f32>) -> f32 {
    if kind == KIND_POINT {
        return length(p - points[index].position);
    }
    if kind == KIND_LINE {
        let s = lines[index];
        return line_distance(p, s.point, s.direction);
    }
    let s = tori[index];
    return torus_distance(p, s.center, s.axis, s.major_radius);
}

fn smooth_coefficient(kind: u32, index: u32) -> f32 {
    if kind == KIND_POINT {
        return points[index].coefficient;
    }
    if kind == KIND_LINE {
        return lines[index].coefficient;
    }
    return tori[index].coefficient;
}

// A torus's ring along the ray: rho^2 = a t^2 + b t + c, z = z0 + z1 t, d^2 = (rho - r)^2 + z^2. Twin of Ring.
struct Ring {
    a: f32,
    b: f32,
    c: f32,
    z0: f32,
    z1: f32,
    r: f32,
}

fn make_ring(ray: Ray) -> Ring {
    let t = tori[ray.index];
    let q = ray.start - t.center;
    let z0 = dot(q, t.axis);
    let z1 = dot(ray.dir, t.axis);
    return Ring(dot(ray.dir, ray.dir) - z1 * z1, 2.0 * (dot(q, ray.dir) - z0 * z1), dot(q, q) - z0 * z0, z0, z1,
        t.major_radius);
}

// Half the first and second derivatives of d^2 at t, and d^2. Twin of Ring::at.
fn ring_at(g: Ring, t: f32) -> vec3<f32> {
    let rho = sqrt(max(g.a * t * t + g.b * t + g.c, 1e-30));
    let drho = (2.0 * g.a * t + g.b) / (2.0 * rho);
    let ddrho = (g.a - drho * drho) / rho;
    let z = g.z0 + g.z1 * t;
    let first = (rho - g.r) * drho + z * g.z1;
    let second = drho * drho + (rho - g.r) * ddrho + g.z1 * g.z1;
    return vec3<f32>(first, second, (rho - g.r) * (rho - g.r) + z * z);
}

// Where Newton starts on [lo, hi]. Twin of Ring::start.
fn ring_start(g: Ring, lo: f32, hi: f32, left: bool) -> f32 {
    let disc = g.b * g.b - 4.0 * g.a * (g.c - g.r * g.r);
    if g.a > 0.0 && disc >= 0.0 {
        let root = sqrt(disc);
        var t = (-g.b + root) / (2.0 * g.a);
        if left {
            t = (-g.b - root) / (2.0 * g.a);
        }
        if t >= lo && t <= hi {
            return t;
        }
    }
    if g.z1 != 0.0 {
        let t = -g.z0 / g.z1;
        if t >= lo && t <= hi {
            return t;
        }
    }
    return 0.5 * (lo + hi);
}

// The ring's closest approach on [lo, hi] from t0: (t*, d*^2, a). Twin of Ring::approach.
fn ring_approach(g: Ring, t0: f32, lo: f32, hi: f32) -> vec3<f32> {
    var t = clamp(t0, lo, hi);
    for (var k = 0u; k < RING_NEWTON; k++) {
        let v = ring_at(g, t);
        var delta = 0.5 * RING_STEP * sign(v.x);
        if v.y > 0.0 {
            delta = clamp(v.x / v.y, -RING_STEP, RING_STEP);
        }
        t = clamp(t - delta, lo, hi);
    }
    let v = ring_at(g, t);
    return vec3<f32>(t, v.z, max(v.y, 0.0));
}

// The features of a point, a line or a torus along the ray, sorted, each owning its piece. Twin of features.
fn smooth_features(ray: Ray) -> Peaks {
    var out: Peaks;
    out.count = 1u;
    if ray.kind == KIND_POINT {
        let p = points[ray.index].position;
        let a = dot(ray.dir, ray.dir);
        var c = 0.0;
        if a > 0.0 {
            c = dot(p - ray.start, ray.dir) / a;
        }
        let closest = ray.start + ray.dir * c - p;
        out.peaks[0] = make_peak(c, dot(closest, closest), a);
    } else if ray.kind == KIND_LINE {
        let l = lines[ray.index];
        let r = line_approach(ray, l.point, l.direction);
        out.peaks[0] = make_peak(r.x, r.y, r.z);
    } else {
        // One closest approach on each side of the axis, and the axis itself.
        let t = tori[ray.index];
        let ring = make_ring(ray);
        let axis = line_approach(ray, t.center, t.axis);
        if axis.z > 0.0 && axis.x > 0.0 && axis.x < 1.0 {
            let l = ring_approach(ring, ring_start(ring, 0.0, axis.x, true), 0.0, axis.x);
            let r = ring_approach(ring, ring_start(ring, axis.x, 1.0, false), axis.x, 1.0);
            out.peaks[0] = make_peak(l.x, l.y, l.z);
            out.peaks[1] = make_peak(r.x, r.y, r.z);
            let width = clamp(sqrt(axis.y / axis.z), MIN_AXIS_WIDTH, MAX_WIDTH);
            out.peaks[2] = Peak(0.0, 1.0, axis.x, width, 0.0);
            out.count = 3u;
        } else {
            let r = ring_approach(ring, ring_start(ring, 0.0, 1.0, axis.x >= 1.0), 0.0, 1.0);
            out.peaks[0] = make_peak(r.x, r.y, r.z);
        }
    }
    share_ray(&out);
    return out;
}

// The first pair of the Gauss-Legendre rule of `order` nodes in GAUSS. Twin of adaptive::GAUSS_START.
fn gauss_start(order: u32) -> u32 {
    switch order {
        case 6u: { return 0u; }
        case 8u: { return 3u; }
        case 10u: { return 7u; }
        case 12u: { return 12u; }
        default: { return 18u; }
    }
}

// The term's integrand in s, f = 1 / max(eps, d) zeta(t), at t clamped to the piece (before the coefficient).
fn smooth_f(ray: Ray, p: Peak, t_in: f32) -> f32 {
    let t = clamp(t_in, p.lo, p.hi);
    let d = smooth_distance(ray.kind, ray.index, ray.start + ray.dir * t);
    return falloff(d, params.epsilon) * zeta_at(t);
}

// Gauss-Legendre on [a, b] in u, params.gauss_order nodes. Twin of gauss_legendre. The nodes come in pairs
// c -+ r x, whose exponentials are exp(c) / exp(r x) and exp(c) exp(r x): one exp a pair, no sinh or cosh.
fn gauss_legendre(ray: Ray, p: Peak, a: f32, b: f32) -> f32 {
    let first = gauss_start(params.gauss_order);
    let last = first + select(8u, params.gauss_order / 2u, first < 18u);
    let c = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    let ec = exp(c);
    var sum = 0.0;
    for (var k = first; k < last; k++) {
        let xw = GAUSS[k];
        let ex = exp(r * xw.x);
        let hi = ec * ex;
        let lo = ec / ex;
        // sinh and cosh of c + r x (hi) and c - r x (lo).
        let sh = 0.5 * (hi - 1.0 / hi);
        let ch = 0.5 * (hi + 1.0 / hi);
        let sl = 0.5 * (lo - 1.0 / lo);
        let cl = 0.5 * (lo + 1.0 / lo);
        sum += xw.y * (smooth_f(ray, p, p.center + p.width * sl) * cl + smooth_f(ray, p, p.center + p.width * sh) * ch);
    }
    return r * p.width * sum;
}

// A point's, a line's or a torus's term of B over its pieces. Twin of integrate_term.
fn integrate_smooth_term(kind: u32, index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> f32 {
    let coefficient = smooth_coefficient(kind, index);
    if coefficient == 0.0 {
        return 0.0;
    }
    let ray = Ray(s_point, e_point - s_point, kind, index);
    let found = smooth_features(ray);
    var sum = 0.0;
    for (var k = 0u; k < found.count; k++) {
        let p = found.peaks[k];
        let u0 = stable_asinh((p.lo - p.center) / p.width);
        let u1 = stable_asinh((p.hi - p.center) / p.width);
        if u1 <= u0 {
            continue;
        }
        // The cuts: the piece's ends and, closer than eps, the ends of the falloff's flat top. Twin of cuts.
        var cut = array<f32, 4>(u0, u1, u1, u1);
        var n = 2u;
        if p.flat > 0.0 {
            let kf = stable_asinh(p.flat / p.width);
            n = 1u;
            if -kf > u0 && -kf < u1 {
                cut[n] = -kf;
                n += 1u;
            }
            if kf > u0 && kf < u1 {
                cut[n] = kf;
                n += 1u;
            }
            cut[n] = u1;
            n += 1u;
        }
        for (var j = 0u; j + 1u < n; j++) {
            let a = cut[j];
            let b = cut[j + 1u];
            let panels = u32(clamp(ceil((b - a) / U_PANEL), 1.0, f32(MAX_GAUSS_PANELS)));
            let width = (b - a) / f32(panels);
            for (var i = 0u; i < panels; i++) {
                let pa = a + width * f32(i);
                sum += gauss_legendre(ray, p, pa, pa + width);
            }
        }
    }
    return coefficient * sum;
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    let seg = texel_segment(id.xy);
    var b = 0.0;
    // The range holds points, lines and tori only (gpu::field_pass::plan_chunks); its bounds come from the chunk
    // alone, a storage buffer, so no driver specialises the shader for them.
    for (var t = chunk.first; t < chunk.first + chunk.count; t++) {
        var index = t;
        var kind = KIND_POINT;
        if index >= params.point_count {
            index -= params.point_count;
            kind = KIND_LINE;
            if index >= params.line_count {
                index -= params.line_count;
                kind = KIND_TORUS;
            }
        }
        b += integrate_smooth_term(kind, index, seg[0], seg[1]);
    }
    store(id.xy, b);
}

// -- Curves: adaptive Simpson in u.

// A curve's squared distance at t along the ray.
fn curve_d2(ray: Ray, t: f32) -> f32 {
    let d = curve_nearest(curves[ray.index], ray.start + ray.dir * t).y;
    return d * d;
}

// One parabolic step from a bracketed minimum at c: (vertex, value there, curvature a). Twin of refine.
fn refine(ray: Ray, c0: f32, h: f32, g0: f32, g1: f32, g2: f32) -> vec3<f32> {
    let second = g0 - 2.0 * g1 + g2;
    let a = second / (2.0 * h * h);
    var offset = 0.0;
    if second > 0.0 {
        offset = clamp(0.5 * h * (g0 - g2) / second, -h, h);
    }
    let c = c0 + offset;
    let value = curve_d2(ray, c);
    return vec3<f32>(c, max(min(value, g1), 0.0), max(a, 0.0));
}

// A curve's features: the two deepest local minima of d^2 on a scan, sorted, each owning its piece. Twin of
// features / scanned_peaks.
fn curve_features(ray: Ray) -> Peaks {
    var out: Peaks;
    let step = 1.0 / f32(SCAN);
    var g: array<f32, 7>;  // SCAN + 1
    for (var i = 0u; i <= SCAN; i++) {
        g[i] = curve_d2(ray, f32(i) * step);
    }
    // The two deepest local minima (ties to the left).
    var best0 = 0xffffffffu;
    var best1 = 0xffffffffu;
    for (var i = 0u; i <= SCAN; i++) {
        let left = i == 0u || g[i] < g[i - 1u];
        let right = i == SCAN || g[i] <= g[i + 1u];
        if !(left && right) {
            continue;
        }
        if best0 == 0xffffffffu || g[i] < g[best0] {
            best1 = best0;
            best0 = i;
        } else if best1 == 0xffffffffu || g[i] < g[best1] {
            best1 = i;
        }
    }
    if best0 == 0xffffffffu {
        best0 = 0u;
    }
    let minima = array<u32, 2>(best0, best1);
    out.count = 1u;
    if best1 != 0xffffffffu {
        out.count = 2u;
    }
    for (var slot = 0u; slot < out.count; slot++) {
        let i = minima[slot];
        let center = f32(i) * step;
        var g0 = 0.0;
        var g2 = 0.0;
        if i > 0u { g0 = g[i - 1u]; } else { g0 = curve_d2(ray, center - step); }
        if i < SCAN { g2 = g[i + 1u]; } else { g2 = curve_d2(ray, center + step); }
        let r = refine(ray, center, step, g0, g[i], g2);
        out.peaks[slot] = make_peak(r.x, r.y, r.z);
    }
    share_ray(&out);
    return out;
}

// A curve's integrand in u: f(s(u)) ds/du, f = w / max(eps, d) zeta(s).
fn curve_g(ray: Ray, p: Peak, u: f32) -> f32 {
    // sinh and cosh from one exp.
    let e = exp(u);
    let t = clamp(p.center + p.width * 0.5 * (e - 1.0 / e), p.lo, p.hi);
    let c = curves[ray.index];
    let n = curve_nearest(c, ray.start + ray.dir * t);
    return wseries(c, n.x) * falloff(n.y, params.epsilon) * zeta_at(t) * p.width * 0.5 * (e + 1.0 / e);
}

// Adaptive Simpson on [a, b] in u, iterative with an explicit stack. Twin of adaptive_simpson.
fn adaptive_simpson(ray: Ray, p: Peak, a0: f32, b0: f32, f0: vec3<f32>, tol0: f32, splits: ptr<function, u32>) -> f32 {
    // Depth-first, left half first: at most DEPTH + 1 entries.
    var bounds: array<vec4<f32>, 14>;  // a, b, tol, depth
    var values: array<vec3<f32>, 14>;  // f(a), f(m), f(b)
    bounds[0] = vec4<f32>(a0, b0, tol0, f32(DEPTH));
    values[0] = f0;
    var top = 1u;
    var sum = 0.0;
    while top > 0u {
        top -= 1u;
        let bd = bounds[top];
        let f = values[top];
        let a = bd.x;
        let b = bd.y;
        let m = 0.5 * (a + b);
        let flm = curve_g(ray, p, 0.5 * (a + m));
        let frm = curve_g(ray, p, 0.5 * (m + b));
        let whole = (b - a) / 6.0 * (f.x + 4.0 * f.y + f.z);
        let left = (m - a) / 6.0 * (f.x + 4.0 * flm + f.y);
        let right = (b - m) / 6.0 * (f.y + 4.0 * frm + f.z);
        let delta = left + right - whole;
        let allowed = 15.0 * max(bd.z, RELATIVE_FLOOR * abs(left + right));
        if bd.w < 0.5 || *splits == 0u || abs(delta) <= allowed {
            sum += left + right + delta / 15.0;
        } else {
            *splits -= 1u;
            // Right half below the left, so the left is taken first (the recursion's order).
            bounds[top] = vec4<f32>(m, b, 0.5 * bd.z, bd.w - 1.0);
            values[top] = vec3<f32>(f.y, frm, f.z);
            bounds[top + 1u] = vec4<f32>(a, m, 0.5 * bd.z, bd.w - 1.0);
            values[top + 1u] = vec3<f32>(f.x, flm, f.y);
            top += 2u;
        }
    }
    return sum;
}

// A curve's term of B over its pieces. Twin of integrate_term.
fn integrate_curve_term(index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> f32 {
    let coefficient = curves[index].coefficient;
    if coefficient == 0.0 {
        return 0.0;
    }
    let ray = Ray(s_point, e_point - s_point, 3u, index);
    let found = curve_features(ray);
    let tol = params.tolerance / f32(found.count);
    var sum = 0.0;
    var splits = SPLITS;
    for (var k = 0u; k < found.count; k++) {
        let p = found.peaks[k];
        let u0 = stable_asinh((p.lo - p.center) / p.width);
        let u1 = stable_asinh((p.hi - p.center) / p.width);
        if u1 <= u0 {
            continue;
        }
        // Neighbouring panels share their end value.
        let width = (u1 - u0) / f32(PANELS);
        var fa = curve_g(ray, p, u0);
        for (var i = 0u; i < PANELS; i++) {
            let a = u0 + width * f32(i);
            let b = a + width;
            let fb = curve_g(ray, p, b);
            let f = vec3<f32>(fa, curve_g(ray, p, 0.5 * (a + b)), fb);
            sum += adaptive_simpson(ray, p, a, b, f, tol / f32(PANELS), &splits);
            fa = fb;
        }
    }
    return coefficient * sum;
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive_curves(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    let seg = texel_segment(id.xy);
    let first_curve = params.point_count + params.line_count + params.torus_count;
    var b = 0.0;
    // The range holds curves only (gpu::field_pass::plan_chunks).
    for (var t = chunk.first; t < chunk.first + chunk.count; t++) {
        b += integrate_curve_term(t - first_curve, seg[0], seg[1]);
    }
    store(id.xy, b);
}
