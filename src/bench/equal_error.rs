//! The equal-error study: the adaptive integrator against simpson at n = 200, both against the converged f64
//! reference.

use super::*;
use crate::reference::converged::{REFERENCE_DIVISIONS, converged_reference};

/// The equal-error reference is computed on at most this many texels per side (a subset of larger textures).
pub(super) const REFERENCE_SIZE: u32 = 256;

/// The adaptive tolerances tried, cheapest first, for the equal-error comparison.
pub(super) const TOLERANCES: [f64; 11] = [
    5e-2, 2e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6,
];

/// The second comparison's target: the largest |B - B_ref| both integrators are held to.
pub(super) const TARGET_ERROR: f64 = 1e-4;

/// Simpson's division counts tried for `TARGET_ERROR`, cheapest first.
pub(super) const TARGET_DIVISIONS: [u32; 5] = [200, 400, 800, 1600, 3200];

/// The error of a brightness texture against the converged reference: the largest on B itself (the tolerance's
/// promise, B > 1 included: exports keep it), and the share of texels whose picture changes, on B clamped to
/// [0, 1] as the blend shows it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RenderError {
    /// Largest |B - B_ref|, unclamped.
    pub max_abs: f64,
    /// Share of texels off by more than 1/255 on B clamped to [0, 1].
    pub share_over_1_255: f64,
}

impl RenderError {
    /// The error of `values` (every `stride`-th texel of a W x W texture, rows and columns) against
    /// `reference` (those texels only).
    pub fn of(values: &[f32], w: u32, stride: u32, reference: &[f64]) -> Self {
        let mut max_abs: f64 = 0.0;
        let mut over = 0usize;
        let texels = (0..w).step_by(stride as usize).flat_map(|j| {
            (0..w)
                .step_by(stride as usize)
                .map(move |i| (j * w + i) as usize)
        });
        for (k, r) in texels.zip(reference) {
            let b = values[k] as f64;
            max_abs = max_abs.max((b - r).abs());
            let shown = b.clamp(0.0, 1.0) - r.clamp(0.0, 1.0);
            over += (shown.abs() > 1.0 / 255.0) as usize;
        }
        Self {
            max_abs,
            share_over_1_255: over as f64 / reference.len().max(1) as f64,
        }
    }

    /// True when no figure of `self` is larger than `other`'s.
    pub fn no_larger_than(&self, other: &RenderError) -> bool {
        self.max_abs <= other.max_abs && self.share_over_1_255 <= other.share_over_1_255
    }
}

/// The papers' integrator at n = 200 against the adaptive one at the cheapest tolerance whose error is no
/// larger, both against the converged reference.
#[derive(Clone, Debug, Serialize)]
pub struct EqualErrorRow {
    pub scene: String,
    pub resolution: u32,
    /// Every how many texels (in each direction) the error is computed.
    pub error_stride: u32,
    pub reference: String,
    pub simpson_divisions: u32,
    /// Which field pass times both integrators: the fastest the project has, specialised to the structure.
    pub pipelines: String,
    pub simpson: PassTiming,
    pub simpson_error: RenderError,
    pub adaptive_tolerance: f64,
    pub adaptive: PassTiming,
    pub adaptive_error: RenderError,
    /// Whether some tried tolerance reached the error of `simpson` (else the finest tried is shown).
    pub equal_error: bool,
    /// Median time of `simpson` over median time of `adaptive` (GPU timestamps where available).
    pub speedup: f64,
    /// Every tolerance tried, with its error.
    pub tried: Vec<(f64, RenderError)>,
    /// Both integrators at the largest error `TARGET_ERROR` on B.
    pub at_target: AtTargetRow,
}

/// Simpson at the fewest divisions of `TARGET_DIVISIONS` whose largest error on B is at most `TARGET_ERROR`,
/// against the adaptive integrator at the loosest tolerance that reaches it; where one never does, its finest
/// tried stands in, marked.
#[derive(Clone, Debug, Serialize)]
pub struct AtTargetRow {
    pub target_max_abs: f64,
    pub simpson_divisions: u32,
    pub simpson_reached: bool,
    pub simpson: PassTiming,
    pub simpson_error: RenderError,
    pub adaptive_tolerance: f64,
    pub adaptive_reached: bool,
    pub adaptive: PassTiming,
    pub adaptive_error: RenderError,
    /// Median time of `simpson` over median time of `adaptive`.
    pub speedup: f64,
    /// Every division count tried, with its error.
    pub tried_divisions: Vec<(u32, RenderError)>,
}

/// The equal-error comparison: on the torus, Bezier and mixed scenes at 256 and 512 (256 only with --quick),
/// the errors of simpson (n = 200) and of the adaptive integrator at each tolerance against the converged
/// reference, then the two timed interleaved at the cheapest tolerance whose error is no larger.
pub(super) fn equal_error(
    bench: &mut FieldBench,
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<EqualErrorRow>, GpuError> {
    let scenes = [
        ("torus", load(TORUS_SCENE, "torus_r0.9_t5.1.toml")),
        ("bezier", load(BEZIER_SCENE, "bezier_b5.0.toml")),
        ("mixed", load(MIXED_SCENE, "mixed.toml")),
    ];
    let resolutions: &[u32] = match (&options.equal_error_sizes, options.quick) {
        (Some(sizes), _) => sizes,
        (None, true) => &[256],
        (None, false) => &[256, 512],
    };
    let mut rows = Vec::new();
    for &resolution in resolutions {
        for (name, base) in &scenes {
            // The f64 reference is the slow part: above 256, every (W / 256)-th texel in each direction, so
            // that it costs the same at every size.
            let stride = (resolution / REFERENCE_SIZE).max(1);
            let mut simpson = base.clone();
            simpson.billboard.resolution = resolution;
            simpson.integration.integrator = Integrator::Simpson;
            simpson.integration.jitter = None;
            simpson.integration.divisions = 200;
            progress(&format!(
                "equal error: {name}, {resolution} x {resolution}: f64 reference (n = {REFERENCE_DIVISIONS} and more)"
            ));
            let (reference, reference_stats) = converged_reference(&simpson, stride);
            let simpson_error =
                RenderError::of(&bench.brightness(&simpson)?, resolution, stride, &reference);
            let mut adaptive = simpson.clone();
            adaptive.integration.integrator = Integrator::Adaptive;
            let mut tried = Vec::new();
            let mut chosen = None;
            for &tolerance in &TOLERANCES {
                adaptive.integration.tolerance = tolerance;
                let error = RenderError::of(
                    &bench.brightness(&adaptive)?,
                    resolution,
                    stride,
                    &reference,
                );
                tried.push((tolerance, error));
                if error.no_larger_than(&simpson_error) {
                    chosen = Some(tolerance);
                    break;
                }
            }
            let equal = chosen.is_some();
            let tolerance = chosen.unwrap_or(TOLERANCES[TOLERANCES.len() - 1]);
            adaptive.integration.tolerance = tolerance;
            let adaptive_error = tried.last().expect("a tolerance was tried").1;
            progress(&format!(
                "equal error: {name}, {resolution} x {resolution}: timing simpson n = 200 against adaptive tolerance {tolerance:e}"
            ));
            let (ts, ta) = timed_pair(bench, options, &simpson, &adaptive)?;
            let speedup = ts.best().median_ms / ta.best().median_ms;
            // Both at a fixed error: the cheapest simpson and the loosest tolerance reaching TARGET_ERROR.
            progress(&format!(
                "equal error: {name}, {resolution} x {resolution}: both at a largest error of {TARGET_ERROR:e}"
            ));
            let reaches = |e: &RenderError| e.max_abs <= TARGET_ERROR;
            let mut target_simpson = simpson.clone();
            let mut tried_divisions = Vec::new();
            for n in TARGET_DIVISIONS {
                target_simpson.integration.divisions = n;
                let values = bench.brightness(&target_simpson)?;
                let error = RenderError::of(&values, resolution, stride, &reference);
                tried_divisions.push((n, error));
                if reaches(&error) {
                    break;
                }
            }
            let (divisions, simpson_at) = *tried_divisions.last().expect("a count was tried");
            let mut target_adaptive = adaptive.clone();
            let mut adaptive_at = None;
            for &(tolerance, error) in &tried {
                if reaches(&error) {
                    adaptive_at = Some((tolerance, error));
                    break;
                }
            }
            let untried = TOLERANCES
                .iter()
                .filter(|&&t| t < tried.last().expect("tried").0);
            if adaptive_at.is_none() {
                for &tolerance in untried {
                    target_adaptive.integration.tolerance = tolerance;
                    let values = bench.brightness(&target_adaptive)?;
                    let error = RenderError::of(&values, resolution, stride, &reference);
                    adaptive_at = Some((tolerance, error));
                    if reaches(&error) {
                        break;
                    }
                }
            }
            let (target_tolerance, adaptive_target_error) =
                adaptive_at.unwrap_or(*tried.last().expect("tried"));
            target_adaptive.integration.tolerance = target_tolerance;
            let (ts_at, ta_at) = timed_pair(bench, options, &target_simpson, &target_adaptive)?;
            let at_target = AtTargetRow {
                target_max_abs: TARGET_ERROR,
                simpson_divisions: divisions,
                simpson_reached: reaches(&simpson_at),
                speedup: ts_at.best().median_ms / ta_at.best().median_ms,
                simpson: ts_at,
                simpson_error: simpson_at,
                adaptive_tolerance: target_tolerance,
                adaptive_reached: reaches(&adaptive_target_error),
                adaptive: ta_at,
                adaptive_error: adaptive_target_error,
                tried_divisions,
            };
            rows.push(EqualErrorRow {
                scene: name.to_string(),
                resolution,
                error_stride: stride,
                reference: reference_stats.to_string(),
                simpson_divisions: 200,
                pipelines: "specialised to the scene's structure (gpu::Specialise::Blocking)"
                    .into(),
                simpson: ts,
                simpson_error,
                adaptive_tolerance: tolerance,
                adaptive: ta,
                adaptive_error,
                equal_error: equal,
                speedup,
                tried,
                at_target,
            });
        }
    }
    Ok(rows)
}

/// `simpson` and `adaptive` timed interleaved on the specialised pipelines.
fn timed_pair(
    bench: &mut FieldBench,
    options: &BenchOptions,
    simpson: &Scene,
    adaptive: &Scene,
) -> Result<(PassTiming, PassTiming), GpuError> {
    let t = bench.interleaved(2, options.warmup(), options.frames(), |k, _| {
        if k == 0 {
            simpson.clone()
        } else {
            adaptive.clone()
        }
    })?;
    let mut t = t.into_iter();
    Ok((t.next().expect("two"), t.next().expect("two")))
}
