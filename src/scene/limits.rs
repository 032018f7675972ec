//! The ranges a scene's values must lie in, with the rule that says so: one definition that the scene loader
//! (`scene::validate`), its animation keys, keyed values, the command line's overrides and the viewer's panel all
//! use, so that their limits and messages cannot drift apart.

/// Largest billboard resolution a scene may ask for (a GPU may allow less; the renderer checks its limit).
pub const MAX_RESOLUTION: u32 = 16384;
/// Largest Simpson division count a scene may ask for.
pub const MAX_DIVISIONS: u32 = 1 << 20;
/// The adaptive integrator's tolerance lies strictly between these.
pub const MIN_TOLERANCE: f64 = 1e-9;
pub const MAX_TOLERANCE: f64 = 0.1;

/// The tolerance's rule, as the messages state it.
pub const TOLERANCE_RULE: &str =
    "the error the adaptive integrator allows on B must lie between 1e-9 and 0.1 (default 1e-4)";

/// `t` if it is a valid tolerance, else the rule it breaks.
pub fn tolerance(t: f64) -> Result<f64, &'static str> {
    if t > MIN_TOLERANCE && t < MAX_TOLERANCE {
        Ok(t)
    } else {
        Err(TOLERANCE_RULE)
    }
}

/// The decay length lies in this range, scene units: positive, and no longer than coordinates reach.
pub const MIN_DECAY_LENGTH: f64 = 1e-9;
pub const MAX_DECAY_LENGTH: f64 = super::MAX_COORDINATE;

/// The decay length's rule, as the messages state it.
pub const DECAY_LENGTH_RULE: &str = "decay_length must be positive: a distance in scene units from 1e-9 to 1e15 (files without it get (nu - 1) times the eye-to-billboard distance)";

/// `x` if it is a valid decay length, else the rule it breaks.
pub fn decay_length(x: f64) -> Result<f64, &'static str> {
    if (MIN_DECAY_LENGTH..=MAX_DECAY_LENGTH).contains(&x) {
        Ok(x)
    } else {
        Err(DECAY_LENGTH_RULE)
    }
}

/// The papers' nu, which only derives a decay length: greater than 1 (`E = V + nu (S - V)` lies behind the
/// billboard).
pub const NU_RULE: &str =
    "nu must be greater than 1 (E = V + nu (S - V) lies behind the billboard; the papers use 2)";

/// `nu` if it is valid, else the rule it breaks.
pub fn nu(nu: f64) -> Result<f64, &'static str> {
    if nu > 1.0 && nu.is_finite() {
        Ok(nu)
    } else {
        Err(NU_RULE)
    }
}

/// A weight of a curve's W series: finite and at least 0 (no upper bound).
pub const WEIGHT_RULE: &str = "weights must be finite and at least 0";

/// `w` if it is a valid weight, else the rule it breaks.
pub fn weight(w: f64) -> Result<f64, &'static str> {
    if w.is_finite() && w >= 0.0 {
        Ok(w)
    } else {
        Err(WEIGHT_RULE)
    }
}

/// The nearest valid weight, for a keyed value between valid keys (only rounding can take it out).
pub fn clamp_weight(w: f64) -> f64 {
    w.max(0.0)
}

/// The nearest valid decay length, for a keyed value between valid keys.
pub fn clamp_decay_length(x: f64) -> f64 {
    x.clamp(MIN_DECAY_LENGTH, MAX_DECAY_LENGTH)
}

/// `n` if it is a valid Simpson division count, else the rule it breaks.
pub fn divisions(n: u32) -> Result<u32, String> {
    if (2..=MAX_DIVISIONS).contains(&n) && n.is_multiple_of(2) {
        Ok(n)
    } else {
        Err(format!(
            "Simpson's rule needs an even division count between 2 and {MAX_DIVISIONS} (the papers use 200)"
        ))
    }
}

/// `w` if it is a valid billboard resolution, else the rule it breaks.
pub fn resolution(w: u32) -> Result<u32, String> {
    if (1..=MAX_RESOLUTION).contains(&w) {
        Ok(w)
    } else {
        Err(format!("must be between 1 and {MAX_RESOLUTION} texels"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_rule_admits_its_range_and_refuses_its_edges() {
        assert!(tolerance(1e-4).is_ok() && tolerance(1e-9).is_err() && tolerance(0.1).is_err());
        assert!(tolerance(f64::NAN).is_err());
        assert!(divisions(2).is_ok() && divisions(MAX_DIVISIONS).is_ok());
        assert!(
            divisions(0).is_err()
                && divisions(201).is_err()
                && divisions(MAX_DIVISIONS + 2).is_err()
        );
        assert!(resolution(1).is_ok() && resolution(MAX_RESOLUTION).is_ok());
        assert!(decay_length(1e-9).is_ok() && decay_length(1e15).is_ok());
        assert!(decay_length(0.0).is_err() && decay_length(2e15).is_err());
        assert!(decay_length(f64::NAN).is_err() && decay_length(f64::INFINITY).is_err());
        assert!(nu(2.0).is_ok() && nu(1.0).is_err() && nu(f64::INFINITY).is_err());
        assert!(weight(0.0).is_ok() && weight(-1e-300).is_err() && weight(f64::NAN).is_err());
        assert_eq!(clamp_weight(-0.5), 0.0);
        assert_eq!(clamp_decay_length(0.0), MIN_DECAY_LENGTH);
        assert!(resolution(0).is_err() && resolution(MAX_RESOLUTION + 1).is_err());
    }
}
