// The papers' integrator (METHOD.md section 3): Simpson's rule over n + 1 evenly spaced samples of the ray, or
// with jitter the randomly shifted rectangle rule. Entry point `integrate`. CPU twin: src/reference/simpson.rs.
#import shared/brightest.wgsl


// A curve chain's term at p, b Sw(t) / max(eps, |p - C(t)|) at the point it reads (curve_point: the nearest point t*,
// or the brightest), and that times its color series at t (zero without one).
fn curve_field(c: CurveSource, held: HeldChain, p: vec3<f32>, eps: f32) -> vec4<f32> {
    let best = curve_point(c, held, p);
    let f = c.coefficient * wseries(c, held.weights, best.x) * falloff(best.y, eps);
    return vec4<f32>(f, f * color_series(c, best.x));
}

// The PCG hash (Jarzynski and Olano 2020). Twin of reference::simpson::pcg_hash.
fn pcg_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The texel's jitter offset in [0, 1). Twin of reference::simpson::jitter_offset.
fn jitter_offset(id: vec2<u32>) -> f32 {
    let index = id.y * params.resolution + id.x;
    let h = pcg_hash(index ^ pcg_hash(params.seed + 0x9e3779b9u));
    return f32(h >> 8u) / 16777216.0;
}

// One dispatch's samples of a texel's ray: k = first .. last of s_k = (k + shift) / n, weighted 1 4 2 4 ... 4 1
// (Simpson's rule, shift 0) or all alike (the shifted rectangle rule); the weights' common factor is applied
// once, at the end.
struct Samples {
    s_point: vec3<f32>,
    e_point: vec3<f32>,
    first: u32,
    last: u32,
    n: u32,
    shift: f32,
    simpson: bool,
    squared: bool,  // the rms decay: each sample's weighed energy squared (Integration::power)
}

// Sample k's position on the ray and its weight times zeta(s), zeta(s) = alpha / (s + beta)^2 (squared for the rms
// decay).
fn sample_at(r: Samples, k: u32) -> vec4<f32> {
    let s = (f32(k) + r.shift) / f32(r.n);
    var weight = 1.0;
    if r.simpson && k != 0u && k != r.n {
        weight = select(2.0, 4.0, (k & 1u) == 1u);
    }
    let zeta = zeta_at(s);
    return vec4<f32>(mix(r.s_point, r.e_point, s), weight * select(zeta, zeta * zeta, r.squared));
}

// v, squared for the rms decay.
fn raised(r: Samples, v: f32) -> f32 {
    return select(v, v * v, r.squared);
}

// Each kind's part of the sum over the samples, source by source (thesis 3.28 summed in the other order): a
// source is read once a texel and its values stay in registers for the samples.
fn point_samples(r: Samples, src: PointSource) -> f32 {
    var sum = 0.0;
    for (var k = r.first; k < r.last; k++) {
        let x = sample_at(r, k);
        sum += x.w * raised(r, falloff(length(x.xyz - src.position), EPSILON));
    }
    return raised(r, src.coefficient) * sum;
}

fn line_samples(r: Samples, src: LineSource) -> f32 {
    var sum = 0.0;
    for (var k = r.first; k < r.last; k++) {
        let x = sample_at(r, k);
        sum += x.w * raised(r, falloff(line_distance(x.xyz, src.point, src.direction), EPSILON));
    }
    return raised(r, src.coefficient) * sum;
}

fn torus_samples(r: Samples, src: TorusSource) -> f32 {
    var sum = 0.0;
    for (var k = r.first; k < r.last; k++) {
        let x = sample_at(r, k);
        sum += x.w * raised(r, falloff(torus_distance(x.xyz, src.center, src.axis, src.major_radius), EPSILON));
    }
    return raised(r, src.coefficient) * sum;
}

// B's part and the color series' (zero without one); for the rms decay their squares' (the series weighed by the
// term's square).
fn curve_samples(r: Samples, c: CurveSource) -> vec4<f32> {
    var sum = vec4<f32>(0.0);
    let held = held_chain(c);
    for (var k = r.first; k < r.last; k++) {
        let x = sample_at(r, k);
        let g = curve_field(c, held, x.xyz, EPSILON);
        sum += x.w * select(g, g.x * g, r.squared);
    }
    return sum;
}

// Term t's sums (points, lines, tori, curves): B's part, and its color series' (curves).
fn term_samples(r: Samples, t: u32) -> vec4<f32> {
    let first_line = point_count();
    let first_torus = first_line + line_count();
    let first_curve = first_torus + torus_count();
    if t < first_line {
        return vec4<f32>(point_samples(r, points[t]), 0.0, 0.0, 0.0);
    }
    if t < first_torus {
        return vec4<f32>(line_samples(r, lines[t - first_line]), 0.0, 0.0, 0.0);
    }
    // Every term is before the curves where a pipeline is specialised to a scene without them: saying so drops the
    // curves' code from it, which lavapipe pays for at every invocation even where none runs (benches/README.md).
    if t < first_curve || CURVE_COUNT == 0u {
        return vec4<f32>(torus_samples(r, tori[t - first_torus]), 0.0, 0.0, 0.0);
    }
    return curve_samples(r, curves[t - first_curve]);
}

// Term t's coefficient (points, lines, tori, curves).
fn term_coefficient(t: u32) -> f32 {
    let first_line = point_count();
    let first_torus = first_line + line_count();
    let first_curve = first_torus + torus_count();
    if t < first_line {
        return points[t].coefficient;
    }
    if t < first_torus {
        return lines[t - first_line].coefficient;
    }
    if t < first_curve {
        return tori[t - first_torus].coefficient;
    }
    return curves[t - first_curve].coefficient;
}

// The scratch texture: a term's sums between the dispatches of simpson with the rms decay (gpu::field_pass's
// scratch; one texel where no term takes more than one dispatch).
@group(0) @binding(12) var scratch: texture_storage_2d_array<r32float, read_write>;

// Simpson's rule (or the shifted rectangle rule) with the rms decay, one term a dispatch or several: its sums of
// squares over the dispatch's samples, added to those kept from its earlier dispatches, then kept again, or
// finished into the field: B_t = sign(c_t) sqrt(sum scale / stretch), and its color series' mean weighed alike.
fn integrate_rms(texel: Texel, r_in: Samples, scale: f32) {
    var r = r_in;
    r.squared = true;
    var sums = term_samples(r, chunk.term);
    let at = vec2<i32>(texel.id);
    if (chunk.stage & 1u) != 0u {
        sums += vec4<f32>(
            textureLoad(scratch, at, 0).x,
            textureLoad(scratch, at, 1).x,
            textureLoad(scratch, at, 2).x,
            textureLoad(scratch, at, 3).x,
        );
    }
    if (chunk.stage & 2u) == 0u {
        textureStore(scratch, at, 0, vec4<f32>(sums.x, 0.0, 0.0, 1.0));
        textureStore(scratch, at, 1, vec4<f32>(sums.y, 0.0, 0.0, 1.0));
        textureStore(scratch, at, 2, vec4<f32>(sums.z, 0.0, 0.0, 1.0));
        textureStore(scratch, at, 3, vec4<f32>(sums.w, 0.0, 0.0, 1.0));
        return;
    }
    let b = signed_root(sums.x * scale, term_coefficient(chunk.term));
    var glow = glow_of(chunk.term, b);
    if sums.x > 0.0 {
        glow += vec4<f32>(0.0, b * sums.yzw / sums.x);
    }
    store(texel.id, glow);
}

// The papers' integrator: Simpson's rule over k = 0..=n (3.33, corrected to end at s = 1), or with jitter the
// randomly shifted rectangle rule (1 / n) sum f((k + xi) / n), unbiased, its error noise instead of bands. The
// sum over the sources of psi is taken outside the sum over the samples.
@compute @workgroup_size(8, 8)
fn integrate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let texel = begin_texel(gid);
    if !texel.inside {
        return;
    }
    let n = params.divisions;
    let jitter = jittered();
    var r = Samples(texel.start, texel.end, chunk.first, 0u, n, 0.0, !jitter, false);
    var scale = 1.0 / (3.0 * f32(n));
    if jitter {
        r.shift = jitter_offset(texel.id);
        r.last = min(chunk.first + chunk.count, n);
        scale = 1.0 / f32(n);
    } else {
        r.last = min(chunk.first + chunk.count, n + 1u);
    }
    if params.decay == 1u {
        integrate_rms(texel, r, scale);
        return;
    }
    // B and the tint: each term's sum, and that sum times the term's tint (glow_of).
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < point_count(); i++) {
        sum += glow_of(i, point_samples(r, points[i]));
    }
    let first_line = point_count();
    for (var i = 0u; i < line_count(); i++) {
        sum += glow_of(first_line + i, line_samples(r, lines[i]));
    }
    let first_torus = first_line + line_count();
    for (var i = 0u; i < torus_count(); i++) {
        sum += glow_of(first_torus + i, torus_samples(r, tori[i]));
    }
    let first_curve = first_torus + torus_count();
    for (var i = 0u; i < curve_count(); i++) {
        let g = curve_samples(r, curves[i]);
        sum += glow_of(first_curve + i, g.x) + vec4<f32>(0.0, g.yzw);
    }
    store(texel.id, sum * scale);
}
