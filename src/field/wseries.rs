//! The W series: local intensity along a curve as a quadratic B-spline (METHOD.md section 2, thesis
//! 3.24-3.27).
//!
//! `Sw(t) = sum_i w_i N_i^2(t)` over the clamped uniform knot vector
//! `[0, 0, 0, 1/(n-2), ..., (n-3)/(n-2), 1, 1, 1]`. The texts only cover `n >= 3`; here `n = 1` is a
//! constant, `n = 2` the straight line between the two weights, and an empty series means "all 1".
//! Evaluation uses the triangular scheme for the three non-zero basis functions of the knot span (The NURBS
//! Book, A2.2), which is what the shader does too; the tests check it against the Cox-de Boor recursion.

/// Evaluates `Sw(t)` for `t` in `[0, 1]` (values outside are clamped).
pub fn evaluate(weights: &[f64], t: f64) -> f64 {
    evaluate_by(weights.len(), t, |i| weights[i])
}

/// The color series at `t`: the same quadratic B-spline as the W series, of colors (each channel alike); a
/// series of one color is that color. `colors` must not be empty.
pub fn evaluate_colors(colors: &[[f64; 3]], t: f64) -> [f64; 3] {
    std::array::from_fn(|c| evaluate_by(colors.len(), t, |i| colors[i][c]))
}

/// The series of `n` values `value(0..n)` at `t`: 1 without values.
fn evaluate_by(n: usize, t: f64, value: impl Fn(usize) -> f64) -> f64 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    match n {
        0 => 1.0,
        1 => value(0),
        2 => value(0) + (value(1) - value(0)) * t,
        n => {
            let [b0, b1, b2] = basis(n, t);
            let span = span_index(n, t);
            b0 * value(span - 2) + b1 * value(span - 1) + b2 * value(span)
        }
    }
}

/// Index `i` of the knot span `[u_i, u_{i+1})` holding `t`, for `n >= 3` weights: `2..=n-1`.
/// `t = 1` belongs to the last non-empty span, so `Sw(1) = w_{n-1}`.
pub fn span_index(n: usize, t: f64) -> usize {
    let segments = n - 2;
    let k = (t * segments as f64).floor() as isize;
    (k.clamp(0, segments as isize - 1) as usize) + 2
}

/// The three basis functions `N_{span-2}, N_{span-1}, N_span` (degree 2) that are non-zero at `t`, for
/// `n >= 3` weights on the clamped uniform knot vector.
pub fn basis(n: usize, t: f64) -> [f64; 3] {
    let span = span_index(n, t);
    let knot = |i: usize| knot(n, i);
    // NURBS Book A2.2 with p = 2.
    let mut left = [0.0; 3];
    let mut right = [0.0; 3];
    let mut out = [1.0, 0.0, 0.0];
    for j in 1..=2 {
        left[j] = t - knot(span + 1 - j);
        right[j] = knot(span + j) - t;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom == 0.0 { 0.0 } else { out[r] / denom };
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
    out
}

/// Knot `u_i` of the clamped uniform quadratic knot vector for `n >= 3` control weights (`n + 3` knots).
pub fn knot(n: usize, i: usize) -> f64 {
    let segments = (n - 2) as f64;
    match i {
        0..=2 => 0.0,
        i if i >= n => 1.0,
        i => (i - 2) as f64 / segments,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn end_values_are_the_end_weights() {
        let w = [1.0, 0.6, 0.2, 0.4, 0.8, 0.6, 1.0];
        assert!((evaluate(&w, 0.0) - 1.0).abs() < 1e-15);
        assert!((evaluate(&w, 1.0) - 1.0).abs() < 1e-15);
        let w = [0.3, 0.9, 0.5];
        assert!((evaluate(&w, 0.0) - 0.3).abs() < 1e-15);
        assert!((evaluate(&w, 1.0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn short_series_are_defined() {
        assert_eq!(evaluate(&[], 0.3), 1.0);
        assert_eq!(evaluate(&[0.7], 0.3), 0.7);
        assert!((evaluate(&[0.0, 1.0], 0.25) - 0.25).abs() < 1e-15);
    }
}
