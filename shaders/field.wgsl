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
    pad0: u32,
}

@group(0) @binding(0) var<uniform> params: FieldParams;
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
    pad0: u32,
}

@group(0) @binding(8) var<uniform> chunk: Chunk;

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

// ---- The adaptive integrator (twin of src/adaptive.rs): source by source, s = s* + h sinh(u) around the ray's
// closest approach to the source, adaptive Simpson in u.

const KIND_POINT: u32 = 0u;
const KIND_LINE: u32 = 1u;
const KIND_TORUS: u32 = 2u;
const KIND_CURVE: u32 = 3u;
const SCAN: u32 = 12u;
const PANELS: u32 = 8u;
const DEPTH: u32 = 12u;
const SPLITS: u32 = 200u;
const RELATIVE_FLOOR: f32 = 4e-6;
const MAX_WIDTH: f32 = 4.0;

// One source's (distance, W series weight) at p.
fn term_distance(kind: u32, index: u32, p: vec3<f32>) -> vec2<f32> {
    if kind == KIND_POINT {
        return vec2<f32>(length(p - points[index].position), 1.0);
    }
    if kind == KIND_LINE {
        let s = lines[index];
        return vec2<f32>(line_distance(p, s.point, s.direction), 1.0);
    }
    if kind == KIND_TORUS {
        let s = tori[index];
        return vec2<f32>(torus_distance(p, s.center, s.axis, s.major_radius), 1.0);
    }
    let c = curves[index];
    let n = curve_nearest(c, p);
    return vec2<f32>(n.y, wseries(c, n.x));
}

fn term_coefficient(kind: u32, index: u32) -> f32 {
    if kind == KIND_POINT {
        return points[index].coefficient;
    }
    if kind == KIND_LINE {
        return lines[index].coefficient;
    }
    if kind == KIND_TORUS {
        return tori[index].coefficient;
    }
    return curves[index].coefficient;
}

// The interval [lo, hi] a peak owns, its center s* and width h, in s.
struct Peak {
    lo: f32,
    hi: f32,
    center: f32,
    width: f32,
}

struct Peaks {
    peaks: array<Peak, 2>,
    count: u32,
}

// A source along the ray S + s dir, fixed for one term's integration.
struct Ray {
    start: vec3<f32>,
    dir: vec3<f32>,
    kind: u32,
    index: u32,
}

fn make_peak(lo: f32, hi: f32, center: f32, d2_min: f32, a: f32) -> Peak {
    let eps = params.epsilon;
    let d2 = max(d2_min, eps * eps);
    var width = MAX_WIDTH;
    if a > 0.0 {
        width = min(sqrt(d2 / a), MAX_WIDTH);
    }
    return Peak(lo, hi, clamp(center, lo, hi), max(width, 1e-6));
}

fn term_d2(ray: Ray, t: f32) -> f32 {
    let d = term_distance(ray.kind, ray.index, ray.start + ray.dir * t).x;
    return d * d;
}

// Two parabolic steps from a bracketed minimum at c: (vertex, value there, curvature a). Twin of refine.
fn refine(ray: Ray, c0: f32, h0: f32, g0: f32, g1: f32, g2: f32) -> vec3<f32> {
    var c = c0;
    var h = h0;
    var g = vec3<f32>(g0, g1, g2);
    var a = 0.0;
    for (var round = 0u; round < 2u; round++) {
        let second = g.x - 2.0 * g.y + g.z;
        a = second / (2.0 * h * h);
        var offset = 0.0;
        if second > 0.0 {
            offset = clamp(0.5 * h * (g.x - g.z) / second, -h, h);
        }
        c += offset;
        if round == 1u {
            break;
        }
        h *= 0.25;
        g = vec3<f32>(term_d2(ray, c - h), term_d2(ray, c), term_d2(ray, c + h));
    }
    let value = term_d2(ray, c);
    return vec3<f32>(c, max(min(value, g.y), 0.0), max(a, 0.0));
}

// The peaks of a term along the ray (at most two). Twin of peaks / scanned_peaks.
fn find_peaks(ray: Ray) -> Peaks {
    var out: Peaks;
    out.peaks[1] = Peak(0.0, 1.0, 0.0, MAX_WIDTH);
    out.count = 1u;
    if ray.kind == KIND_POINT || ray.kind == KIND_LINE {
        var q = ray.start - points[ray.index].position;
        var d = ray.dir;
        if ray.kind == KIND_LINE {
            let l = lines[ray.index];
            let q0 = ray.start - l.point;
            q = q0 - l.direction * dot(q0, l.direction);
            d = ray.dir - l.direction * dot(ray.dir, l.direction);
        }
        let a = dot(d, d);
        var c = 0.0;
        if a > 0.0 {
            c = -dot(q, d) / a;
        }
        let closest = q + d * c;
        out.peaks[0] = make_peak(0.0, 1.0, c, dot(closest, closest), a);
        return out;
    }
    let step = 1.0 / f32(SCAN);
    var g: array<f32, 13>;
    for (var i = 0u; i <= SCAN; i++) {
        g[i] = term_d2(ray, f32(i) * step);
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
    var minima = array<u32, 2>(best0, best1);
    var split = 1.0;
    if best1 != 0xffffffffu {
        out.count = 2u;
        if best1 < best0 {
            minima = array<u32, 2>(best1, best0);
        }
        var m = minima[0];
        for (var i = minima[0]; i <= minima[1]; i++) {
            if g[i] > g[m] {
                m = i;
            }
        }
        split = f32(m) * step;
    }
    for (var slot = 0u; slot < out.count; slot++) {
        let i = minima[slot];
        var lo = 0.0;
        var hi = 1.0;
        if out.count == 2u {
            if slot == 0u {
                hi = split;
            } else {
                lo = split;
            }
        }
        let center = f32(i) * step;
        var g0 = 0.0;
        var g2 = 0.0;
        if i > 0u { g0 = g[i - 1u]; } else { g0 = term_d2(ray, center - step); }
        if i < SCAN { g2 = g[i + 1u]; } else { g2 = term_d2(ray, center + step); }
        let r = refine(ray, center, step, g0, g[i], g2);
        out.peaks[slot] = make_peak(lo, hi, r.x, r.y, r.z);
    }
    return out;
}

// asinh without the cancellation of log(x + sqrt(x^2 + 1)) for x << 0 (some drivers evaluate it so: at
// x = -1000 in f32 that loses a tenth of the result).
fn stable_asinh(x: f32) -> f32 {
    let a = abs(x);
    return sign(x) * log(a + sqrt(a * a + 1.0));
}

// The term's integrand in u: f(s(u)) ds/du, f = w / max(eps, d) zeta(s).
fn g_u(ray: Ray, p: Peak, u: f32) -> f32 {
    let t = clamp(p.center + p.width * sinh(u), p.lo, p.hi);
    let dw = term_distance(ray.kind, ray.index, ray.start + ray.dir * t);
    let zeta = params.alpha / ((t + params.beta) * (t + params.beta));
    return dw.y * falloff(dw.x, params.epsilon) * zeta * p.width * cosh(u);
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
        let flm = g_u(ray, p, 0.5 * (a + m));
        let frm = g_u(ray, p, 0.5 * (m + b));
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

// One source's term of B over its peaks. Twin of integrate_term.
fn integrate_term(kind: u32, index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> f32 {
    let c = term_coefficient(kind, index);
    if c == 0.0 {
        return 0.0;
    }
    let ray = Ray(s_point, e_point - s_point, kind, index);
    let found = find_peaks(ray);
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
        let width = (u1 - u0) / f32(PANELS);
        for (var i = 0u; i < PANELS; i++) {
            let a = u0 + width * f32(i);
            let b = a + width;
            let f = vec3<f32>(g_u(ray, p, a), g_u(ray, p, 0.5 * (a + b)), g_u(ray, p, b));
            sum += adaptive_simpson(ray, p, a, b, f, tol / f32(PANELS), &splits);
        }
    }
    return c * sum;
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    let seg = texel_segment(id.xy);
    var b = 0.0;
    let last = chunk.first + chunk.count;
    for (var t = chunk.first; t < last; t++) {
        var index = t;
        var kind = KIND_POINT;
        if index >= params.point_count {
            index -= params.point_count;
            kind = KIND_LINE;
            if index >= params.line_count {
                index -= params.line_count;
                kind = KIND_TORUS;
                if index >= params.torus_count {
                    index -= params.torus_count;
                    kind = KIND_CURVE;
                    if index >= params.curve_count {
                        break;
                    }
                }
            }
        }
        b += integrate_term(kind, index, seg[0], seg[1]);
    }
    store(id.xy, b);
}
