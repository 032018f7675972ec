// A curve's W series and color series: quadratic B-splines over the chain parameter on the clamped uniform knot
// vector (METHOD.md section 2), the weights and colors read from the field pass's bindings. Twin:
// src/field/wseries.rs.
#import shared/field_pass.wgsl

// Knot u_i of the clamped uniform quadratic knot vector for n >= 3 weights. Twin of wseries::knot.
fn wseries_knot(n: u32, i: u32) -> f32 {
    if i <= 2u {
        return 0.0;
    }
    if i >= n {
        return 1.0;
    }
    return f32(i - 2u) / f32(n - 2u);
}

// Knot span index (2..=n-1) holding t, for n >= 3 weights; t = 1 belongs to the last span.
fn wseries_span(n: u32, t: f32) -> u32 {
    let segments = n - 2u;
    let k = clamp(i32(floor(t * f32(segments))), 0, i32(segments) - 1);
    return u32(k) + 2u;
}

// The three non-zero quadratic basis functions N_{span-2}, N_{span-1}, N_span at t (NURBS Book A2.2).
// Twin of wseries::basis.
fn wseries_basis(n: u32, t: f32) -> vec3<f32> {
    let span = wseries_span(n, t);
    let left1 = t - wseries_knot(n, span);
    let right1 = wseries_knot(n, span + 1u) - t;
    let left2 = t - wseries_knot(n, span - 1u);
    let right2 = wseries_knot(n, span + 2u) - t;
    // Degree 1: N_{span-1,1}, N_{span,1}.
    var d = right1 + left1;
    var temp = select(1.0 / d, 0.0, d == 0.0);
    let a0 = right1 * temp;
    let a1 = left1 * temp;
    // Degree 2.
    d = right1 + left2;
    temp = select(a0 / d, 0.0, d == 0.0);
    let b0 = right1 * temp;
    var saved = left2 * temp;
    d = right2 + left1;
    temp = select(a1 / d, 0.0, d == 0.0);
    let b1 = saved + right2 * temp;
    let b2 = left1 * temp;
    return vec3<f32>(b0, b1, b2);
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

// A curve's color series at t (twin of Colors::color_along): the quadratic B-spline of its colors, as wseries
// of its weights; zero without a series.
fn color_series(c: CurveSource, t_in: f32) -> vec3<f32> {
    let t = clamp(t_in, 0.0, 1.0);
    let n = c.color_count;
    let k = c.first_color;
    if n == 0u {
        return vec3<f32>(0.0);
    }
    if n == 1u {
        return colors[k].xyz;
    }
    if n == 2u {
        return mix(colors[k].xyz, colors[k + 1u].xyz, t);
    }
    let b = wseries_basis(n, t);
    let first = k + wseries_span(n, t) - 2u;
    return b.x * colors[first].xyz + b.y * colors[first + 1u].xyz + b.z * colors[first + 2u].xyz;
}
