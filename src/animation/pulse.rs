//! The travelling pulse: the W series of a curve animated so that a bright lump runs along it (METHOD.md
//! section 5, thesis eq. 5.1).
//!
//! The thesis's formula, for frame t and weight index i:
//!
//! ```text
//! theta_i  = (t - 7 i) pi / 25
//! theta_i' = theta_i if 0 <= theta_i <= 2 pi, else 0
//! w_i      = min(1, max(0, (-cos theta_i' + 0.8) / 1.5))
//! ```
//!
//! Its constants become parameters, with the thesis's values as defaults: `width` (frames one weight stays
//! lit: 2 pi spans 50 frames), `delay` (frames between neighbouring weights: 7), `speed` (a factor on time:
//! 1), `start` (the frame the first weight lights up: 0) and an optional `period` after which the pulse
//! starts again (the thesis's pulse runs once). Generalised:
//!
//! ```text
//! tau      = t - start, taken modulo period when there is one (into [0, period))
//! theta_i  = (speed tau - delay i) 2 pi / width
//! ```
//!
//! and `theta_i'` and `w_i` as above. The defaults give eq. 5.1 exactly.

/// A travelling pulse along one curve: its W series as a function of the frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Pulse {
    /// How many weights the series has (n); the pulse visits them from the curve's start to its end.
    pub count: usize,
    /// A factor on time: 2 runs the pulse twice as fast.
    pub speed: f64,
    /// Frames (at speed 1) one weight stays lit: the cosine's period, 50 in the thesis.
    pub width: f64,
    /// Frames (at speed 1) between one weight lighting up and the next: 7 in the thesis.
    pub delay: f64,
    /// The frame at which the first weight starts to light up.
    pub start: f64,
    /// When set, the pulse starts again every `period` frames.
    pub period: Option<f64>,
}

impl Pulse {
    /// The thesis's constants (eq. 5.1) for a series of `count` weights.
    pub const THESIS_SPEED: f64 = 1.0;
    pub const THESIS_WIDTH: f64 = 50.0;
    pub const THESIS_DELAY: f64 = 7.0;
    /// The W series of the thesis's figure 5.6, whose length the thesis's pulse animates.
    pub const THESIS_COUNT: usize = 7;

    /// The thesis's pulse (eq. 5.1) over `count` weights, running once from frame 0.
    pub fn thesis(count: usize) -> Self {
        Self {
            count,
            speed: Self::THESIS_SPEED,
            width: Self::THESIS_WIDTH,
            delay: Self::THESIS_DELAY,
            start: 0.0,
            period: None,
        }
    }

    /// `w_i` at frame `t`.
    pub fn weight(&self, i: usize, t: f64) -> f64 {
        let mut tau = t - self.start;
        if let Some(period) = self.period {
            tau = tau.rem_euclid(period);
        }
        let theta = (self.speed * tau - self.delay * i as f64) * std::f64::consts::TAU / self.width;
        let theta = if (0.0..=std::f64::consts::TAU).contains(&theta) {
            theta
        } else {
            0.0
        };
        ((-theta.cos() + 0.8) / 1.5).clamp(0.0, 1.0)
    }

    /// The whole W series at frame `t`.
    pub fn weights(&self, t: f64) -> Vec<f64> {
        (0..self.count).map(|i| self.weight(i, t)).collect()
    }

    /// The frame after which the pulse (without a period) has left every weight; with a period,
    /// `start + period`. Weight i is lit while `speed (t - start) - delay i` is in `[0, width]`.
    pub fn natural_length(&self) -> f64 {
        match self.period {
            Some(p) => self.start + p,
            None => {
                let last = self.delay * self.count.saturating_sub(1) as f64;
                self.start + (last.max(0.0) + self.width) / self.speed.abs().max(1e-9)
            }
        }
    }
}
