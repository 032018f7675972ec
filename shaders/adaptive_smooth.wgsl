// The adaptive integrator's pass for points, lines and tori (entry point integrate_adaptive): Gauss-Kronrod
// pairs in u on each term's pieces. Twin: src/reference/adaptive_smooth.rs.
#import shared/adaptive.wgsl

// A point's, a line's or a torus's distance from p.
fn smooth_distance(ray: Ray, p: vec3<f32>) -> f32 {
    if ray.kind == KIND_POINT {
        return length(p - ray.anchor);
    }
    if ray.kind == KIND_LINE {
        return line_distance(p, ray.anchor, ray.along);
    }
    return torus_distance(p, ray.anchor, ray.along, ray.radius);
}

// The term's ray, with its source's geometry.
fn smooth_ray(kind: u32, index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> Ray {
    var ray = Ray(s_point, e_point - s_point, kind, index, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    if kind == KIND_POINT {
        ray.anchor = points[index].position;
    } else if kind == KIND_LINE {
        let s = lines[index];
        ray.anchor = s.point;
        ray.along = s.direction;
    } else {
        let s = tori[index];
        ray.anchor = s.center;
        ray.along = s.axis;
        ray.radius = s.major_radius;
    }
    return ray;
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

// The closest approach of the ray to a point or a line: (t*, d*^2, a), d^2(t) = d*^2 + a (t - t*)^2. Twin of
// point_approach and line_approach.
fn approach(ray: Ray) -> vec3<f32> {
    if ray.kind == KIND_POINT {
        let a = dot(ray.dir, ray.dir);
        var c = 0.0;
        if a > 0.0 {
            c = dot(ray.anchor - ray.start, ray.dir) / a;
        }
        let closest = ray.start + ray.dir * c - ray.anchor;
        return vec3<f32>(c, dot(closest, closest), a);
    }
    return line_approach(ray, ray.anchor, ray.along);
}

// 1 / (lo + beta) - 1 / (hi + beta), without the difference's cancellation on a short stretch.
fn decay_between(lo: f32, hi: f32) -> f32 {
    return (hi - lo) / ((lo + BETA) * (hi + BETA));
}

// The integral of u / sqrt(Q(u)) from u_b to u_a for a source near the decay's pole, as a series in powers of u:
// sum_n p_n (u_a^(n+2) - u_b^(n+2)) / ((n + 2) sqrt(a)), p_n = rho^n P_n(w_c / rho) by the Legendre recurrence,
// the differences of the powers by D_(m+1) = u_a D_m + u_b^m (u_a - u_b). Twin of pole_series, with
// POLE_SERIES_TERMS_F32 terms.
fn pole_series(w_c: f32, rho2: f32, a: f32, u_a: f32, u_b: f32, length: f32) -> f32 {
    let delta = length * u_a * u_b;
    var d = u_a * delta + u_b * delta;
    var power = u_b * u_b;
    var previous = 0.0;
    var p = 1.0;
    var sum = 0.0;
    for (var k = 0u; k < POLE_SERIES_TERMS_F32; k++) {
        let n = f32(k);
        sum += p * d / (n + 2.0);
        let next = ((2.0 * n + 1.0) * w_c * p - n * rho2 * previous) / (n + 1.0);
        previous = p;
        p = next;
        d = u_a * d + power * delta;
        power *= u_b;
    }
    return sum / sqrt(a);
}

// The part [lo, hi] (where d >= eps) of falloff_integral's integral: alpha (I(u_a) - I(u_b)), (value, 1) or
// (0, 0) where it cancels beyond CLOSED_FORM_CONDITION; by the pole series where the source lies within
// POLE_SERIES_REACH of the decay's pole (twin of falloff_piece and closed_piece). w_c = c + beta, big_a = A.
fn falloff_piece(lo: f32, hi: f32, c: f32, h2: f32, a: f32, w_c: f32, big_a: f32) -> vec2<f32> {
    if hi <= lo {
        return vec2<f32>(0.0, 1.0);
    }
    let rho2 = w_c * w_c + h2 / a;
    // Within POLE_SERIES_REACH of the pole, against the distance from there to the piece (1 / u_a).
    let reach = POLE_SERIES_REACH * (lo + BETA);
    if rho2 <= reach * reach {
        return vec2<f32>(ALPHA * pole_series(w_c, rho2, a, 1.0 / (lo + BETA), 1.0 / (hi + BETA), hi - lo), 1.0);
    }
    let big_b = -a * w_c;
    let k = a * h2;
    let u_a = 1.0 / (lo + BETA);
    let u_b = 1.0 / (hi + BETA);
    let x_a = (a * w_c * (c - lo) + h2) * u_a;
    let x_b = (a * w_c * (c - hi) + h2) * u_b;
    let r_a = sqrt(x_a * x_a + k);
    let r_b = sqrt(x_b * x_b + k);
    let dr = big_a * (hi - lo) * u_a * u_b * (x_a + x_b) / (r_a + r_b);
    var log_ratio = 0.0;
    if x_a < 0.0 && x_b < 0.0 {
        log_ratio = log((r_b - x_b) / (r_a - x_a));
    } else {
        let p_a = select(k / (r_a - x_a), x_a + r_a, x_a >= 0.0);
        let p_b = select(k / (r_b - x_b), x_b + r_b, x_b >= 0.0);
        log_ratio = log(p_a / p_b);
    }
    let bracket = dr - big_b * log_ratio;
    let size = abs(dr) + abs(big_b * log_ratio);
    // Written so that a NaN or an infinity declines too.
    if !(abs(bracket) * CLOSED_FORM_CONDITION >= size) || !(abs(bracket) < F32_MAX) {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(ALPHA * bracket / (big_a * sqrt(big_a)), 1.0);
}

// A point's or a line's term in closed form for d^2(s) = h2 + a (s - c)^2, before the coefficient: (value, 1),
// or (0, 0) where it is not well conditioned and the term is integrated numerically. Twin of
// reference::adaptive_smooth::falloff_integral.
fn falloff_integral(c: f32, h2_in: f32, a: f32) -> vec2<f32> {
    let h2 = max(h2_in, 0.0);
    let eps = EPSILON;
    if a <= 0.0 {
        return vec2<f32>(ALPHA * decay_between(0.0, 1.0) / max(sqrt(h2), eps), 1.0);
    }
    var half = 0.0;
    if h2 < eps * eps {
        half = sqrt((eps * eps - h2) / a);
    }
    let flat_lo = clamp(c - half, 0.0, 1.0);
    let flat_hi = clamp(c + half, 0.0, 1.0);
    var sum = 0.0;
    let w_c = c + BETA;
    let big_a = a * w_c * w_c + h2;
    var first = vec2<f32>(0.0, 1.0);
    var second = vec2<f32>(0.0, 1.0);
    if half > 0.0 {
        sum = ALPHA * decay_between(flat_lo, flat_hi) / eps;
        first = falloff_piece(0.0, flat_lo, c, h2, a, w_c, big_a);
        second = falloff_piece(flat_hi, 1.0, c, h2, a, w_c, big_a);
    } else {
        first = falloff_piece(0.0, 1.0, c, h2, a, w_c, big_a);
    }
    return vec2<f32>(sum + first.x + second.x, first.y * second.y);
}

// The features of a point, a line or a torus along the ray, sorted, each owning its piece. Twin of features.
fn smooth_features(ray: Ray) -> Peaks {
    var out: Peaks;
    out.count = 1u;
    if ray.kind != KIND_TORUS {
        let r = approach(ray);
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

// The term's integrand in s, f = 1 / max(eps, d) zeta(t), at t clamped to the piece (before the coefficient).
fn smooth_f(ray: Ray, p: Peak, t_in: f32) -> f32 {
    let t = clamp(t_in, p.lo, p.hi);
    let d = smooth_distance(ray, ray.start + ray.dir * t);
    return decayed(falloff(d, EPSILON) * zeta_at(t));
}

// The Kronrod and Gauss values on [a, b] in u of a point's, a line's or a torus's term. Twin of kronrod.
fn smooth_kronrod(ray: Ray, p: Peak, a: f32, b: f32) -> vec2<f32> {
    let c = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    var sum = vec2<f32>(0.0);
    for (var i = 0u; i <= 2u * gauss_order(); i++) {
        let node = kronrod_node(i);
        let m = map_node(p, c + r * node.x);
        sum += node.yz * (m.y * smooth_f(ray, p, m.x));
    }
    return r * sum;
}

// A point's, a line's or a torus's term on the panel [a, b] in u, refined where the pair disagrees. Twin of
// integrate_panel.
fn smooth_panel(ray: Ray, p: Peak, a: f32, b: f32, allowance: f32, refinements: ptr<function, u32>) -> f32 {
    let end = 1u << MAX_DEPTH;
    var at = 0u;
    var level = 0u;
    var sum = 0.0;
    while at < end {
        let x = part_bounds(a, b, at, level);
        let kg = smooth_kronrod(ray, p, x.x, x.y);
        if settled(kg, allowance, x.y - x.x) || level == MAX_DEPTH || *refinements == 0u {
            sum += kg.x;
            let next = next_part(at, level);
            at = next.x;
            level = next.y;
        } else {
            *refinements -= 1u;
            level++;
        }
    }
    return sum;
}

// A point's, a line's or a torus's term of B over its pieces. Twin of integrate_term.
fn integrate_smooth_term(kind: u32, index: u32, s_point: vec3<f32>, e_point: vec3<f32>) -> f32 {
    let coefficient = smooth_coefficient(kind, index);
    if coefficient == 0.0 {
        return 0.0;
    }
    let ray = smooth_ray(kind, index, s_point, e_point);
    // A point's and a line's term in closed form (the distance decay's), where it is well conditioned: no samples.
    if kind != KIND_TORUS && params.decay == 0u {
        let r = approach(ray);
        let closed = falloff_integral(r.x, r.y, r.z);
        if closed.y > 0.0 {
            return coefficient * closed.x;
        }
    }
    let found = smooth_features(ray);
    let length = pieces_length(found);
    var allowance = params.term_tolerance / (abs(coefficient) * max(length, 1e-30));
    // The rms decay's allowance comes from an estimate of its integral: the same panels unrefined, a pass before.
    let passes = select(1u, 2u, params.decay == 1u);
    var sum = 0.0;
    for (var sweep = 0u; sweep < passes; sweep++) {
    var refinements = select(COARSE_REFINEMENTS, MAX_REFINEMENTS, gauss_order() > COARSE_ORDER);
    if sweep + 1u < passes {
        refinements = 0u;
    }
    sum = 0.0;
    for (var k = 0u; k < found.count; k++) {
        let p = found.peaks[k];
        let u0 = stable_asinh((p.lo - p.center) / p.width);
        let u1 = stable_asinh((p.hi - p.center) / p.width);
        if u1 <= u0 {
            continue;
        }
        // The piece's cuts (twin of cuts, with no kinks): only the ends of the falloff's flat top, -kf and kf,
        // so [u0, u1] falls into at most three parts: [u0, -kf], [-kf, kf] and [kf, u1], each clamped to it. No
        // array: lavapipe keeps an array written with a variable index in memory (sorting the cuts into one cost
        // about 8 % of the mixed scene's adaptive pass, measured).
        let flat = p.flat > 0.0;
        let kf = select(0.0, stable_asinh(p.flat / p.width), flat);
        for (var j = 0u; j < select(1u, 3u, flat); j++) {
            let a = select(clamp(select(kf, -kf, j == 1u), u0, u1), u0, j == 0u);
            let b = select(clamp(select(kf, -kf, j == 0u), u0, u1), u1, j == 2u || !flat);
            if b <= a {
                continue;
            }
            let panels = u32(clamp(ceil((b - a) / U_PANEL), 1.0, f32(MAX_GAUSS_PANELS)));
            let width = (b - a) / f32(panels);
            for (var i = 0u; i < panels; i++) {
                let pa = a + width * f32(i);
                sum += smooth_panel(ray, p, pa, pa + width, allowance, &refinements);
            }
        }
    }
    if sweep + 1u < passes {
        let scale = coefficient * coefficient;
        allowance = rms_allowance(sum, scale, length);
    }
    }
    return finish(decayed(coefficient) * sum, coefficient);
}

@compute @workgroup_size(8, 8)
fn integrate_adaptive(@builtin(global_invocation_id) gid: vec3<u32>) {
    let texel = begin_texel(gid);
    if !texel.inside {
        return;
    }
    var b = vec4<f32>(0.0);
    // The range holds points, lines and tori only (gpu::field_pass::plan_chunks); its bounds come from the chunk
    // alone, a storage buffer, so no driver specialises the shader for them.
    for (var t = chunk.first; t < chunk.first + chunk.count; t++) {
        var index = t;
        var kind = KIND_POINT;
        if index >= point_count() {
            index -= point_count();
            kind = KIND_LINE;
            if index >= line_count() {
                index -= line_count();
                kind = KIND_TORUS;
            }
        }
        b += glow_of(t, integrate_smooth_term(kind, index, texel.start, texel.end));
    }
    store(texel.id, b);
}
