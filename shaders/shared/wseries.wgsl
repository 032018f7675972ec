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

// A W series' first eight weights, read from their buffer once (held_weights) and kept in registers for every
// point the series is evaluated at (see held_chain); those past them are read from the buffer.
struct HeldWeights {
    low: vec4<f32>,
    high: vec4<f32>,
}

fn held_weights(c: CurveSource) -> HeldWeights {
    if c.weight_count == 0u {
        return HeldWeights(vec4<f32>(1.0), vec4<f32>(1.0));
    }
    let w = c.first_weight;
    let last = w + c.weight_count - 1u;
    return HeldWeights(
        vec4<f32>(weights[w], weights[min(w + 1u, last)], weights[min(w + 2u, last)], weights[min(w + 3u, last)]),
        vec4<f32>(
            weights[min(w + 4u, last)],
            weights[min(w + 5u, last)],
            weights[min(w + 6u, last)],
            weights[min(w + 7u, last)],
        ),
    );
}

// Weight i of a curve's series: from the registers, else from the buffer.
fn series_weight(c: CurveSource, held: HeldWeights, i: u32) -> f32 {
    if i < 8u {
        let v = select(held.low, held.high, i >= 4u);
        let j = i & 3u;
        return select(select(v.x, v.y, j == 1u), select(v.z, v.w, j == 3u), j >= 2u);
    }
    return weights[c.first_weight + i];
}

// Sw(t) of a curve's W series (METHOD.md section 2), its first weights held. Twin of wseries::evaluate.
fn wseries(c: CurveSource, held: HeldWeights, t_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    let n = c.weight_count;
    if n == 0u {
        return 1.0;
    }
    if n == 1u {
        return held.low.x;
    }
    if n == 2u {
        return mix(held.low.x, held.low.y, t);
    }
    let b = wseries_basis(n, t);
    let first = wseries_span(n, t) - 2u;
    return b.x * series_weight(c, held, first) + b.y * series_weight(c, held, first + 1u)
        + b.z * series_weight(c, held, first + 2u);
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
