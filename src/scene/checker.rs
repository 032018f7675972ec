//! Collects the problems of a scene file while it is converted into a scene: each value checked against its
//! range, named by file, line, column and field.

use glam::DVec3;

use super::error::Problem;
use super::file::{FieldPath, Locator, ValueFile};
use super::{MAX_COORDINATE, MAX_INTENSITY};
use crate::field::Look;

/// Collects problems while converting the file into a scene.
pub(super) struct Checker<'a, 'b> {
    pub(super) locator: &'a Locator<'b>,
    pub(super) problems: &'a mut Vec<Problem>,
}

impl Checker<'_, '_> {
    pub(super) fn fail(&mut self, path: &FieldPath, message: impl Into<String>) {
        self.problems.push(self.locator.problem(path, message));
    }

    /// `x` a positive length, at most `MAX_COORDINATE`; `what` names it in the message.
    pub(super) fn positive(&mut self, path: &FieldPath, x: f64, what: &str) {
        if self.finite(path, x) && !(x > 0.0 && x <= MAX_COORDINATE) {
            self.fail(
                path,
                format!("{x} is out of range: {what} must be positive"),
            );
        }
    }

    /// A vector of three positive lengths, or one length for all three (`what` names it).
    pub(super) fn lengths(&mut self, path: &FieldPath, v: &ValueFile, what: &str) -> DVec3 {
        let v = match v {
            ValueFile::Number(x) => DVec3::splat(*x),
            ValueFile::Vector(a) if a.len() == 3 => DVec3::new(a[0], a[1], a[2]),
            ValueFile::Vector(a) => {
                self.fail(
                    path,
                    format!(
                        "{} numbers: {what} is [x, y, z] or one number for all three",
                        a.len()
                    ),
                );
                return DVec3::ONE;
            }
        };
        if !v.is_finite() || v.min_element() <= 0.0 || v.max_element() > MAX_COORDINATE {
            self.fail(
                path,
                format!("{:?}: {what} must be positive numbers", v.to_array()),
            );
            return DVec3::ONE;
        }
        v
    }

    /// How many problems were noted so far.
    pub(super) fn problem_count(&self) -> usize {
        self.problems.len()
    }

    pub(super) fn finite(&mut self, path: &FieldPath, x: f64) -> bool {
        if x.is_finite() {
            true
        } else {
            self.fail(path, format!("{x} is not a finite number"));
            false
        }
    }

    pub(super) fn vector(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        if a.iter().all(|x| x.is_finite()) {
            DVec3::from_array(a)
        } else {
            self.fail(
                path,
                format!("{a:?} has a component that is not a finite number"),
            );
            DVec3::ZERO
        }
    }

    /// A point in world space: finite, and within `MAX_COORDINATE` of the origin in every coordinate, beyond which
    /// the distances between points overflow (the GPU squares them in 32-bit floats).
    pub(super) fn position(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        let v = self.vector(path, a);
        if a.iter().any(|x| x.abs() > MAX_COORDINATE) && v.is_finite() {
            self.fail(
                path,
                format!(
                    "{a:?} is too far out: coordinates are limited to +-{MAX_COORDINATE:e} world units, beyond which distances overflow"
                ),
            );
            return DVec3::ZERO;
        }
        v
    }

    /// A non-zero vector, normalised.
    pub(super) fn direction(&mut self, path: &FieldPath, a: [f64; 3]) -> DVec3 {
        let d = self.vector(path, a);
        let len = d.length();
        if d.is_finite() && len > 1e-12 && (d / len).is_finite() {
            // A vector that is already unit up to rounding is kept bit for bit, so that saving and loading
            // again is lossless.
            if (len - 1.0).abs() <= 1e-14 {
                d
            } else {
                d / len
            }
        } else {
            if d.is_finite() {
                self.fail(path, "must not be the zero vector (it gives the direction; its length does not matter)");
            }
            DVec3::Z
        }
    }

    /// A finite number strictly inside `(lo, hi)` (or above `lo` when `hi` is infinite).
    pub(super) fn in_open_range(
        &mut self,
        path: &FieldPath,
        x: f64,
        lo: f64,
        hi: f64,
        what: &str,
    ) -> f64 {
        if self.finite(path, x) && !(x > lo && x < hi) {
            self.fail(path, format!("{x} is out of range: {what}"));
        }
        x
    }

    /// `x` checked by one of `limits`' rules: a problem naming the value and the rule where it breaks it.
    pub(super) fn within<E: std::fmt::Display>(
        &mut self,
        path: &FieldPath,
        x: f64,
        rule: impl Fn(f64) -> Result<f64, E>,
    ) -> f64 {
        if let Err(why) = rule(x) {
            self.fail(path, format!("{x} is out of range: {why}"));
        }
        x
    }

    /// A color's intensity multiplier: finite, in 0..=MAX_INTENSITY.
    pub(super) fn intensity(&mut self, path: &FieldPath, x: f64) -> f64 {
        if self.finite(path, x) && !(0.0..=MAX_INTENSITY).contains(&x) {
            self.fail(
                path,
                format!("{x} is out of range: an intensity multiplies its color and is in 0..={MAX_INTENSITY} (1 leaves the color as it is, above 1 is HDR)"),
            );
        }
        x
    }

    /// A source's own color and intensity (`color`, `intensity` at `path`), each optional.
    pub(super) fn look(
        &mut self,
        path: &FieldPath,
        color: Option<[f64; 3]>,
        intensity: Option<f64>,
    ) -> Look {
        Look {
            color: color.map(|a| self.color(&path.key("color"), a)),
            intensity: intensity.map(|x| self.intensity(&path.key("intensity"), x)),
        }
    }

    pub(super) fn color(&mut self, path: &FieldPath, a: [f64; 3]) -> [f64; 3] {
        if a.iter().any(|c| !(0.0..=1.0).contains(c)) {
            self.fail(path, format!("{a:?}: each channel must be in 0..1"));
        }
        a
    }
}
