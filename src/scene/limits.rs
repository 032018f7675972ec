//! The ranges a scene's integration and billboard settings must lie in, with the rule that says so: one
//! definition that the scene loader (`scene::validate`), the command line's overrides and the viewer's panel
//! all use, so that their limits and messages cannot drift apart.

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
        assert!(resolution(0).is_err() && resolution(MAX_RESOLUTION + 1).is_err());
    }
}
