//! Time in scenes: a timeline (frame rate, length), travelling pulses along curves (the thesis's eq. 5.1)
//! and keyframed parameters. A scene without an animation is still; `Animation::apply` (in `crate::scene`,
//! with everything else that reads or writes a scene) gives the scene as it is at one frame, which every
//! renderer then draws as a still.
//!
//! - [`pulse`]: the W series of a curve as a function of the frame (METHOD.md section 5);
//! - [`keyframes`]: linear keys on any numeric parameter, named by its path in the scene file.

pub mod keyframes;
pub mod pulse;

pub use keyframes::{
    IntegrationSetting, Key, PARAMETER_FORMS, Parameter, ParticleField, ShapeField, SourceKind,
    Track, TranslucentField, Value,
};
pub use pulse::Pulse;

/// Frame rate of a scene that animates without saying how fast.
pub const DEFAULT_FRAME_RATE: f64 = 30.0;
/// Longest animation a scene may ask for, in frames.
pub const MAX_FRAMES: u32 = 1_000_000;

/// A curve's travelling pulse.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePulse {
    /// Index of the curve in `Sources::curves`.
    pub curve: usize,
    pub pulse: Pulse,
}

/// A scene's animation: its timeline and what moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Frames per second, for playback and GIFs.
    pub frame_rate: f64,
    /// Length in frames: frames are numbered `0..frames`.
    pub frames: u32,
    /// Curves whose W series is a travelling pulse.
    pub pulses: Vec<CurvePulse>,
    /// Keyed parameters.
    pub tracks: Vec<Track>,
}

impl Default for Animation {
    fn default() -> Self {
        Self {
            frame_rate: DEFAULT_FRAME_RATE,
            frames: 100,
            pulses: Vec::new(),
            tracks: Vec::new(),
        }
    }
}

impl Animation {
    /// The length an animation without a stated length gets: until the last pulse has passed (or one
    /// period) and the last key, at least one frame.
    pub fn natural_length(pulses: &[CurvePulse], tracks: &[Track]) -> u32 {
        let pulse_end = pulses
            .iter()
            .map(|p| p.pulse.natural_length())
            .fold(0.0f64, f64::max);
        let key_end = tracks
            .iter()
            .filter_map(|t| t.keys.last())
            .map(|k| k.frame + 1.0)
            .fold(0.0f64, f64::max);
        pulse_end.max(key_end).ceil().clamp(1.0, MAX_FRAMES as f64) as u32
    }

    /// The pulse of curve `curve`, if it has one.
    pub fn pulse(&self, curve: usize) -> Option<&Pulse> {
        self.pulses
            .iter()
            .find(|p| p.curve == curve)
            .map(|p| &p.pulse)
    }

    /// The track of `parameter`, if it is keyed.
    pub fn track(&self, parameter: &Parameter) -> Option<&Track> {
        self.tracks.iter().find(|t| &t.parameter == parameter)
    }

    /// Source `index` of `kind` was removed: its pulse and tracks go, later sources' move down one.
    pub fn source_removed(&mut self, kind: SourceKind, index: usize) {
        if kind == SourceKind::Curves {
            self.pulses.retain(|p| p.curve != index);
            for p in &mut self.pulses {
                if p.curve > index {
                    p.curve -= 1;
                }
            }
        }
        self.tracks
            .retain(|t| t.parameter.source() != Some((kind, index)));
        for t in &mut self.tracks {
            if let Some((k, i)) = t.parameter.source()
                && k == kind
                && i > index
            {
                t.parameter = t.parameter.with_source_index(i - 1);
            }
        }
    }

    /// Particle set `index` was removed: its tracks go, later sets' move down one.
    pub fn particles_removed(&mut self, index: usize) {
        self.tracks
            .retain(|t| !matches!(t.parameter, Parameter::Particles(i, _) if i == index));
        for t in &mut self.tracks {
            if let Parameter::Particles(i, f) = t.parameter
                && i > index
            {
                t.parameter = Parameter::Particles(i - 1, f);
            }
        }
    }

    /// A particle set was inserted at `index`: later sets' tracks move up one.
    pub fn particles_inserted(&mut self, index: usize) {
        for t in &mut self.tracks {
            if let Parameter::Particles(i, f) = t.parameter
                && i >= index
            {
                t.parameter = Parameter::Particles(i + 1, f);
            }
        }
    }

    /// A source of `kind` was inserted at `index`: later sources' pulses and tracks move up one.
    pub fn source_inserted(&mut self, kind: SourceKind, index: usize) {
        if kind == SourceKind::Curves {
            for p in &mut self.pulses {
                if p.curve >= index {
                    p.curve += 1;
                }
            }
        }
        for t in &mut self.tracks {
            if let Some((k, i)) = t.parameter.source()
                && k == kind
                && i >= index
            {
                t.parameter = t.parameter.with_source_index(i + 1);
            }
        }
    }
}
