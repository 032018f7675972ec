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
    pad0: u32,
}

@group(0) @binding(0) var<uniform> params: FieldParams;
@group(0) @binding(1) var<storage, read> points: array<PointSource>;
@group(0) @binding(2) var<storage, read> lines: array<LineSource>;
@group(0) @binding(3) var<storage, read> tori: array<TorusSource>;
@group(0) @binding(4) var<storage, read> curves: array<CurveSource>;
@group(0) @binding(5) var<storage, read> segments: array<CurveSegment>;
@group(0) @binding(6) var<storage, read> weights: array<f32>;
@group(0) @binding(7) var brightness: texture_storage_2d<r32float, write>;

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

// A curve chain's term: b Sw(t*) / max(eps, L), t* = (j + t) / k of the nearest point over all segments.
fn curve_field(c: CurveSource, p: vec3<f32>) -> f32 {
    var best = vec2<f32>(0.0, F32_MAX);
    for (var j = 0u; j < c.segment_count; j++) {
        let n = nearest_on_segment(segments[c.first_segment + j], p);
        if n.y < best.y {
            best = vec2<f32>((f32(j) + n.x) / f32(c.segment_count), n.y);
        }
    }
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

@compute @workgroup_size(8, 8)
fn integrate(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.resolution;
    if id.x >= w || id.y >= w {
        return;
    }
    // Texel center on the billboard (4.2), column from the left, row from the top.
    let u = (f32(id.x) + 0.5) / f32(w) - 0.5;
    let v = 0.5 - (f32(id.y) + 0.5) / f32(w);
    let s_point = params.center + params.right * (params.size * u) + params.up * (params.size * v);
    let e_point = params.eye + params.nu * (s_point - params.eye);
    // Simpson's rule over k = 0..=n (3.33, corrected to end at s = 1).
    let n = params.divisions;
    let nf = f32(n);
    var sum = integrand(s_point, e_point, 0.0) + integrand(s_point, e_point, 1.0);
    for (var k = 1u; k < n; k++) {
        let weight = select(2.0, 4.0, (k & 1u) == 1u);
        sum += weight * integrand(s_point, e_point, f32(k) / nf);
    }
    textureStore(brightness, vec2<i32>(id.xy), vec4<f32>(sum / (3.0 * nf), 0.0, 0.0, 1.0));
}
