// Real roots of a cubic, Cardano's formula in f32. Twin: src/field/cubic.rs.
#import shared/field.wgsl

// Up to three real roots; unused slots hold a value outside any range a caller accepts.
struct Roots {
    values: vec3<f32>,
    count: u32,
}

fn real_cbrt(x: f32) -> f32 {
    return sign(x) * pow(abs(x), 1.0 / 3.0);
}

// (p, q) of x^3 + a x^2 + b x + c = 0 shifted by a / 3 to y^3 + 3 p y + 2 q = 0: three real roots where
// p^3 + q^2 < 0, one where it is > 0.
fn depressed_cubic(a: f32, b: f32, c: f32) -> vec2<f32> {
    return vec2<f32>(-a * a / 9.0 + b / 3.0, a * a * a / 27.0 - a * b / 6.0 + c / 2.0);
}

// Whether k3 x^3 + k2 x^2 + k1 x + k0 has one real root, its discriminant clear of zero by `margin` of its
// terms' size (a cubic that degenerates to a line has one). The GPU's alone: the f64 twin solves every cubic.
fn one_real_root(k: vec4<f32>, margin: f32) -> bool {
    let scale = max(max(abs(k.x), abs(k.y)), max(abs(k.z), abs(k.w)));
    if abs(k.x) <= 1e-6 * scale {
        return true;
    }
    let pq = depressed_cubic(k.y / k.x, k.z / k.x, k.w / k.x);
    let cube = pq.x * pq.x * pq.x;
    return cube + pq.y * pq.y > margin * (abs(cube) + pq.y * pq.y);
}

// Cardano's formula for x^3 + a x^2 + b x + c = 0, trigonometric form for three real roots, with the - a/3
// shift (METHOD.md section 1, corrected). Twin of field::cubic::solve_monic_cubic.
fn solve_monic_cubic(a: f32, b: f32, c: f32) -> Roots {
    let shift = a / 3.0;
    let pq = depressed_cubic(a, b, c);
    let p = pq.x;
    let q = pq.y;
    let r = p * p * p + q * q;
    if r >= 0.0 {
        // u on the side of -q -/+ sqrt(r) without cancellation, v = -p / u (u v = -p).
        let t = -q - select(-1.0, 1.0, q >= 0.0) * sqrt(r);
        let u = real_cbrt(t);
        let v = select(-p / u, 0.0, u == 0.0);
        return Roots(vec3<f32>(u + v - shift, F32_MAX, F32_MAX), 1u);
    }
    let m = 2.0 * sqrt(-p);
    let theta = atan2(sqrt(-r), -q);
    return Roots(
        vec3<f32>(
            m * cos(theta / 3.0) - shift,
            m * cos((theta + 2.0 * PI) / 3.0) - shift,
            m * cos((theta + 4.0 * PI) / 3.0) - shift,
        ),
        3u,
    );
}

// Real roots of k3 x^3 + k2 x^2 + k1 x + k0, falling back to lower degrees when the leading coefficients
// vanish relative to the largest (tiny = 1e-6 in f32). Twin of field::cubic::solve_cubic.
fn solve_cubic(k3: f32, k2: f32, k1: f32, k0: f32) -> Roots {
    let tiny = 1e-6;
    let scale = max(max(abs(k3), abs(k2)), max(abs(k1), abs(k0)));
    if scale == 0.0 {
        return Roots(vec3<f32>(F32_MAX), 0u);
    }
    if abs(k3) > tiny * scale {
        return solve_monic_cubic(k2 / k3, k1 / k3, k0 / k3);
    }
    if abs(k2) > tiny * scale {
        let disc = k1 * k1 - 4.0 * k2 * k0;
        if disc < 0.0 {
            return Roots(vec3<f32>(F32_MAX), 0u);
        }
        let s = sqrt(disc);
        var t = -0.5 * (k1 + s);
        if k1 < 0.0 {
            t = -0.5 * (k1 - s);
        }
        if t == 0.0 {
            return Roots(vec3<f32>(0.0, F32_MAX, F32_MAX), 1u);
        }
        return Roots(vec3<f32>(t / k2, k0 / t, F32_MAX), 2u);
    }
    if abs(k1) > tiny * scale {
        return Roots(vec3<f32>(-k0 / k1, F32_MAX, F32_MAX), 1u);
    }
    return Roots(vec3<f32>(F32_MAX), 0u);
}

