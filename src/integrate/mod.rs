//! How a scene integrates B along a texel's ray: the integrator and its settings (the scene file's
//! `[integration]`), and the decay zeta every integrator weighs the field with (METHOD.md section 3, thesis 3.31).
//! The integrators themselves are the GPU's field passes (`gpu::field_pass`) and their f64 twins
//! (`crate::reference`), which share the adaptive integrator's settings in [`adaptive`].

pub mod adaptive;

/// How B is integrated along a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// The papers' method: n + 1 evenly spaced samples of psi, Simpson's rule (or, with jitter, the randomly
    /// shifted rectangle rule).
    Simpson,
    /// Source by source, samples packed around the ray's closest approach, to a tolerance
    /// (`reference::adaptive`).
    #[default]
    Adaptive,
}

impl Integrator {
    /// The name used in scene files, on the command line and in the viewer.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Simpson => "simpson",
            Integrator::Adaptive => "adaptive",
        }
    }
}

/// How a term's energy along the view adds up to its part of B (scene key `integration.decay`).
///
/// With the papers' distance decay, B_i is the integral of the term weighed by zeta along the ray: the sum of its
/// energy along the view, so a moderate energy spread evenly along a long stretch (a beam seen end on, a ring
/// seen edge on) outshines a single intense spot, and the look changes as the camera orbits (thesis 5.6). The
/// rms decay takes the root of the mean square instead, `B_i = sign(c_i) sqrt(integral of (psi_i zeta)^2 dsigma)`
/// over the ray in decay lengths (the sign of the term's coefficient, as every term is its coefficient times a
/// positive shape: a negative source subtracts as under the distance decay): for a given total energy it is least where the energy is spread evenly (Cauchy-Schwarz:
/// `(integral f)^2 <= L integral f^2` over a stretch L, with equality for an even f) and grows as the energy
/// concentrates, so an even spread outshines a spot only where it carries sqrt(L / w) times the spot's total
/// energy (a stretch L against a spot w wide) rather than merely more. It keeps each term's scale (twice the
/// coefficient, twice the brightness) and B stays a sum over the sources, so colors and the blends work as
/// before.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Decay {
    /// The papers': `B_i = integral of psi_i zeta`.
    #[default]
    Distance,
    /// `B_i = sign(c_i) sqrt(integral of (psi_i zeta)^2 dsigma)`, sigma the depth in decay lengths.
    Rms,
}

impl Decay {
    /// The name used in scene files, on the command line and in the viewer.
    pub fn name(self) -> &'static str {
        match self {
            Decay::Distance => "distance",
            Decay::Rms => "rms",
        }
    }

    /// Every decay, in the order the viewer lists them.
    pub const ALL: [Decay; 2] = [Decay::Distance, Decay::Rms];
}

/// The integration settings of a scene (the papers use `alpha = beta = 1`, `nu = 2`, `n = 200`; their nu sets
/// the decay length `(nu - 1) p` for a billboard `p` from the eye, `geometry::papers_decay_length`).
#[derive(Clone, Debug, PartialEq)]
pub struct Integration {
    pub integrator: Integrator,
    /// Simpson's division count n: even, at least 2 (the `simpson` integrator).
    pub divisions: u32,
    /// Absolute error allowed on B (the `adaptive` integrator), shared between the sources.
    pub tolerance: f64,
    /// Random sample placement for the `simpson` integrator, with this seed: each texel's n samples are
    /// shifted by a random fraction of a step, which turns banding into fine noise and is unbiased.
    pub jitter: Option<u32>,
    /// The depth past the billboard, in scene units, over which the decay `zeta = alpha / (sigma + beta)^2`
    /// runs from sigma = 0 to 1; rays reach at least this far and past the far side of the effect
    /// (`geometry::ray_reach`). Fixed in space, so the look holds as the camera moves.
    pub decay_length: f64,
    pub alpha: f64,
    pub beta: f64,
    /// The distance clamp of every source's `1 / max(eps, d)`.
    pub epsilon: f64,
    /// How each term's energy along the view adds up to its part of B.
    pub decay: Decay,
    /// The span of the ray in decay lengths once `on_ray` has mapped the settings onto one (1 in a scene's own
    /// settings): the length the rms decay measures in.
    pub stretch: f64,
}

/// The decay length of settings built in code (scene files derive theirs from their camera): the papers'
/// nu = 2 at a billboard 10 units from the eye.
pub const DEFAULT_DECAY_LENGTH: f64 = 10.0;

/// The adaptive integrator's default tolerance: well under the 1/255 step of an 8-bit image.
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

impl Default for Integration {
    fn default() -> Self {
        Self {
            integrator: Integrator::default(),
            divisions: 200,
            tolerance: DEFAULT_TOLERANCE,
            jitter: None,
            decay_length: DEFAULT_DECAY_LENGTH,
            alpha: 1.0,
            beta: 1.0,
            epsilon: 0.01,
            decay: Decay::default(),
            stretch: 1.0,
        }
    }
}

impl Integration {
    /// The settings the integrators see on a ray that spans `stretch` decay lengths, integrated over the
    /// method's s in [0, 1] (`geometry::Reach`): `alpha / (sigma + beta)^2` with `sigma = stretch s` and
    /// `d sigma = stretch ds` is `(alpha / stretch) / (s + beta / stretch)^2`.
    pub fn on_ray(&self, stretch: f64) -> Integration {
        Integration {
            alpha: self.alpha / stretch,
            beta: self.beta / stretch,
            stretch: self.stretch * stretch,
            ..self.clone()
        }
    }

    /// Each term's share of the tolerance, of a scene of `terms` sources: the integrators hold every term to
    /// it, so that B, their sum, is within the tolerance.
    pub fn term_tolerance(&self, terms: usize) -> f64 {
        self.tolerance / terms.max(1) as f64
    }

    /// The power the decay raises each term's weighed energy `psi_i zeta` to before integrating it.
    pub fn power(&self) -> i32 {
        match self.decay {
            Decay::Distance => 1,
            Decay::Rms => 2,
        }
    }

    /// A term's part of B from the integral over s in [0, 1] of its weighed energy to the decay's power (`power`),
    /// for a term of `coefficient`: the integral itself (distance), or `sign(c) sqrt(integral / stretch)` (rms:
    /// `dsigma = stretch ds` and `zeta_sigma = zeta_s / stretch`). The square drops the term's sign, which the
    /// root gives back: a negative source subtracts energy under either decay.
    pub fn finish(&self, integral: f64, coefficient: f64) -> f64 {
        match self.decay {
            Decay::Distance => integral,
            Decay::Rms => (integral.max(0.0) / self.stretch)
                .sqrt()
                .copysign(coefficient),
        }
    }
}

/// The decay `zeta(s) = alpha / (s + beta)^2` (3.31).
pub fn zeta(s: f64, alpha: f64, beta: f64) -> f64 {
    alpha / ((s + beta) * (s + beta))
}
