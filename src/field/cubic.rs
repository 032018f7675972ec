//! Real roots of cubic polynomials by Cardano's formula (METHOD.md section 1, thesis appendix A).
//!
//! The published texts omit the `- a/3` shift that undoes the depressing substitution and give a wrong
//! argument for the complex cube root; both are corrected here. The three-real-root case uses the
//! trigonometric form, which never needs to pick "the real ones" among nine complex sums.
//! `shaders/` mirrors this file in f32.

/// Up to three real roots, in no particular order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Roots {
    values: [f64; 3],
    len: usize,
}

impl Roots {
    fn push(&mut self, x: f64) {
        if x.is_finite() && self.len < 3 {
            self.values[self.len] = x;
            self.len += 1;
        }
    }

    /// The roots found.
    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }

    /// Number of roots found.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the polynomial has no real root (or is identically zero).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Real roots of the monic cubic `x^3 + a x^2 + b x + c = 0` by Cardano's formula.
///
/// `p = -a^2/9 + b/3`, `q = a^3/27 - a b/6 + c/2`, `r = p^3 + q^2`; for `r >= 0` one real root
/// `cbrt(-q + sqrt r) + cbrt(-q - sqrt r) - a/3` (evaluated without cancellation), else three real roots
/// `2 sqrt(-p) cos((theta + 2 pi k)/3) - a/3` with `theta = atan2(sqrt(-r), -q)`.
pub fn solve_monic_cubic(a: f64, b: f64, c: f64) -> Roots {
    let mut roots = Roots::default();
    let shift = a / 3.0;
    let p = -a * a / 9.0 + b / 3.0;
    let q = a * a * a / 27.0 - a * b / 6.0 + c / 2.0;
    let r = p * p * p + q * q;
    if r >= 0.0 {
        // y = u + v with u^3 = -q -/+ sqrt(r) and u v = -p. The textbook sum cbrt(-q + sqrt r) + cbrt(-q - sqrt r)
        // cancels catastrophically in one of its terms when |q| ~ sqrt(r); take u on the side without
        // cancellation and v = -p / u instead.
        let t = -q - q.signum() * r.sqrt();
        let u = t.cbrt();
        let v = if u != 0.0 { -p / u } else { 0.0 };
        roots.push(u + v - shift);
    } else {
        // r < 0 implies p < 0.
        let m = 2.0 * (-p).sqrt();
        let theta = (-r).sqrt().atan2(-q);
        for k in 0..3 {
            let angle = (theta + 2.0 * std::f64::consts::PI * k as f64) / 3.0;
            roots.push(m * angle.cos() - shift);
        }
    }
    roots
}

/// Real roots of `c3 x^3 + c2 x^2 + c1 x + c0 = 0`, falling back to the quadratic or linear equation when
/// the leading coefficients vanish. `tiny` is the magnitude below which a coefficient counts as zero
/// relative to the largest one (the caller knows the scale of its problem).
pub fn solve_cubic(c3: f64, c2: f64, c1: f64, c0: f64, tiny: f64) -> Roots {
    let scale = c3.abs().max(c2.abs()).max(c1.abs()).max(c0.abs());
    if scale == 0.0 {
        return Roots::default();
    }
    if c3.abs() > tiny * scale {
        return solve_monic_cubic(c2 / c3, c1 / c3, c0 / c3);
    }
    let mut roots = Roots::default();
    if c2.abs() > tiny * scale {
        // Quadratic, in the cancellation-free form.
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc >= 0.0 {
            let s = disc.sqrt();
            let t = -0.5 * (c1 + c1.signum() * s + if c1 == 0.0 { s } else { 0.0 });
            if t != 0.0 {
                roots.push(t / c2);
                roots.push(c0 / t);
            } else {
                roots.push(0.0);
            }
        }
    } else if c1.abs() > tiny * scale {
        roots.push(-c0 / c1);
    }
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(c: [f64; 4], x: f64) -> f64 {
        ((c[0] * x + c[1]) * x + c[2]) * x + c[3]
    }

    #[test]
    fn known_roots_are_found() {
        // (x - 1)(x - 2)(x - 3) = x^3 - 6x^2 + 11x - 6
        let mut r = solve_monic_cubic(-6.0, 11.0, -6.0).as_slice().to_vec();
        r.sort_by(f64::total_cmp);
        for (got, want) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{r:?}");
        }
        // x^3 - 1: one real root.
        let r = solve_monic_cubic(0.0, 0.0, -1.0);
        assert_eq!(r.len(), 1);
        assert!((r.as_slice()[0] - 1.0).abs() < 1e-14);
    }

    #[test]
    fn the_a_over_3_shift_is_applied() {
        // (x - 5)^3 has its triple root at 5, which only comes out with the -a/3 shift.
        let r = solve_monic_cubic(-15.0, 75.0, -125.0);
        assert!(r.as_slice().iter().all(|x| (x - 5.0).abs() < 1e-9), "{r:?}");
    }

    #[test]
    fn a_root_at_zero_is_found_without_cancellation() {
        // x (x^2 + a x + b) with complex roots of the quadratic: the real root is exactly 0. The textbook sum of
        // cube roots gave -3.5e-11 here.
        let (a, b) = (6.0460503642365815, 12.199098019634668);
        let r = solve_monic_cubic(a, b, 0.0);
        assert_eq!(r.len(), 1);
        assert!(r.as_slice()[0].abs() < 1e-15, "{r:?}");
    }

    #[test]
    fn degenerate_leading_coefficients_fall_back() {
        let r = solve_cubic(0.0, 1.0, -3.0, 2.0, 1e-12);
        let mut v = r.as_slice().to_vec();
        v.sort_by(f64::total_cmp);
        assert_eq!(v.len(), 2);
        assert!((v[0] - 1.0).abs() < 1e-14 && (v[1] - 2.0).abs() < 1e-14);
        let r = solve_cubic(0.0, 0.0, 2.0, -1.0, 1e-12);
        assert_eq!(r.as_slice(), &[0.5]);
        assert!(solve_cubic(0.0, 0.0, 0.0, 0.0, 1e-12).is_empty());
        let c = [1e-20, 1.0, -3.0, 2.0];
        for &x in solve_cubic(c[0], c[1], c[2], c[3], 1e-12).as_slice() {
            assert!(eval(c, x).abs() < 1e-12);
        }
    }
}
