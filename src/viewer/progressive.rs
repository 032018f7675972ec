//! Progressive refinement: how much field the viewport integrates in a frame. While the field's inputs change
//! from frame to frame (orbiting, dragging a handle, editing a value), the viewport integrates the whole field
//! refined in image space at a looser tolerance (`frame::Refine::Coarse`): a coarse grid, its side chosen from
//! the measured cost to hold the frame budget, refined where the picture's detail is, down to single texels at
//! the cores, within `MOVING_TOLERANCE` of the picture (loosened while even the smallest grid overruns the
//! budget). Once the view holds still it integrates the field at the scene's tolerance, a level of the
//! refinement at a time (or bands of rows where it integrates every texel), and shows it when whole: exactly
//! the picture a still render gives. Screenshots and exports never see the moving field.
//!
//! The costs come from the frames themselves: the time from one frame's start to the next is the idle cost of
//! a frame (UI, grid, billboard) plus the field work recorded in it: the full field's cost is linear in its
//! texels, the moving one's that per texel of its coarse grid plus the rest (the refinement's texels, measured
//! together).

use std::time::Instant;

/// The looser tolerance of the adaptive integrator on the moving field (the refinement's dominates it).
pub const PREVIEW_TOLERANCE: f64 = 1e-3;

/// How far the moving field may lie from the still one, on B: a step of an 8-bit picture. Its refinement's
/// detail threshold is `frame::refine::SHARE` of it, as the still field's is of the scene's tolerance.
pub const MOVING_TOLERANCE: f64 = 1.0 / 255.0;

/// The most the moving field's side is divided by where it overruns the frame budget (the field refined all the
/// same at that side, and drawn filtered over the billboard).
pub const MOST_DIVISOR: u32 = 4;

/// Fewest texels a side of the moving field's coarse grid.
pub const MIN_PREVIEW: u32 = 16;

/// A moving frame may cost this many times an idle one (the slack the field gets while the view moves).
pub const MOVING_FACTOR: f64 = 1.3;

/// Field work a refining frame may spend at least, by the estimates, in milliseconds; where an idle frame costs
/// more, as much as an idle frame (`FrameBudget::refine_budget`). The full picture of a scene that takes 300 ms
/// arrives in about half a second of frames that stay responsive (on lavapipe the frames come out at 40 to
/// 55 ms: a frame's share of the GPU's work is measured late, so the estimates run low).
pub const REFINE_MS: f64 = 25.0;

/// The cost of a texel assumed until one is measured, in milliseconds: a CPU rasterizer's on the default scene
/// (lavapipe on two cores: 4 to 5 us), so that a first gesture on a slow adapter is not a frame of a whole field.
const ASSUMED_TEXEL_MS: f64 = 4e-3;

/// The largest field side a still frame integrates whole; larger ones are refined in bands.
const MAX_WHOLE: u32 = 128;

/// Frames further apart than this did not run back to back (the viewer was idle): they measure nothing, unless
/// the first did field work, which may take that long (a moving field on a slow machine), up to `LONGEST_MS`.
const STALE_MS: f64 = 400.0;
const LONGEST_MS: f64 = 3000.0;

/// The weight of a new measurement in the running estimates.
const SMOOTHING: f64 = 0.3;

/// What a frame integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Work {
    /// No field work; the frame composed anew (an idle frame's cost).
    Nothing,
    /// No field work and nothing composed: the last frame shown again. It measures nothing (a moving frame
    /// composes, so the budget's idle frame is a composed one).
    Shown,
    /// A moving field whose coarse grid holds this many texels.
    Preview { texels: u64 },
    /// Texels of the full field (a whole field, or bands of it).
    Full { texels: u64 },
}

/// What the viewport should integrate this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Plan {
    /// The whole field at full quality in this frame (it fits the budget, or nothing is known yet).
    Full,
    /// The moving field: W / `divisor` texels a side, refined from a coarse grid of `resolution` texels a side
    /// within `MOVING_TOLERANCE` of the picture.
    Preview { resolution: u32, divisor: u32 },
    /// The next bands of the full field (levels of its refinement; rows, `band_rows` each, where every texel is
    /// integrated), `bands` of them this frame.
    Refine { band_rows: u32, bands: u32 },
}

/// How the moving field's coarse grid and the refining bands are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pacing {
    /// From the measured cost of the frames, to hold the frame budget (the viewer's screen).
    #[default]
    Measured,
    /// The same every frame whatever the machine's load: a moving field at the full W from a coarse grid of
    /// `preview` texels a side while the view moves (the full field where it is no larger), and bands of
    /// `band_rows` rows (a refined field's levels) while it refines. Tests drive the viewer so, since a loaded
    /// machine measures other costs and would choose other fields.
    Fixed { preview: u32, band_rows: u32 },
}

/// The running estimates of what frames cost.
#[derive(Clone, Debug)]
pub struct FrameBudget {
    /// Milliseconds a frame takes without field work, and whether that was measured (else a 60 Hz frame).
    idle_ms: f64,
    idle_measured: bool,
    /// Milliseconds per texel of the full field.
    full_ms: Option<f64>,
    /// The milliseconds of a moving field beyond its coarse grid's share (its refinement, its dispatches).
    preview_overhead_ms: f64,
    /// The coarse grid's side in use (kept while it still fits, so the picture does not shimmer).
    resolution: Option<u32>,
    /// What the moving field's side is W divided by: 1, more while the smallest grid overruns.
    moving_divisor: u32,
    last: Option<(Instant, Work)>,
}

impl Default for FrameBudget {
    fn default() -> Self {
        Self {
            // A 60 Hz frame until measured.
            idle_ms: 1000.0 / 60.0,
            idle_measured: false,
            full_ms: None,
            preview_overhead_ms: 0.0,
            resolution: None,
            moving_divisor: 1,
            last: None,
        }
    }
}

fn blend(old: Option<f64>, new: f64) -> f64 {
    old.map_or(new, |o| o + SMOOTHING * (new - o))
}

impl FrameBudget {
    /// Starts a frame at `now`: the time since the last frame's start measures what that frame did.
    pub fn frame_started(&mut self, now: Instant) {
        let Some((then, work)) = self.last.take() else {
            return;
        };
        let ms = now.duration_since(then).as_secs_f64() * 1e3;
        let field_work = matches!(work, Work::Preview { .. } | Work::Full { .. });
        if ms > LONGEST_MS || (ms > STALE_MS && !field_work) {
            return;
        }
        // The field's share: at least a tenth of the frame, so a noisy idle estimate never makes it free.
        let field = (ms - self.idle_ms).max(0.1 * ms);
        match work {
            Work::Nothing => {
                self.idle_ms = blend(self.idle_measured.then_some(self.idle_ms), ms);
                self.idle_measured = true;
            }
            Work::Shown => {}
            Work::Preview { texels } => {
                // Without a measured idle frame the fixed part cannot be told from it.
                if self.idle_measured {
                    let per_texel = self.full_ms.unwrap_or(0.0);
                    let overhead = (field - per_texel * texels as f64).max(0.0);
                    self.preview_overhead_ms = blend(Some(self.preview_overhead_ms), overhead);
                }
                // The budget is kept by the moving field's side: its refinement, not its coarse grid, is
                // what it costs.
                let budget = self.moving_budget();
                if field > 1.5 * budget {
                    self.moving_divisor = (2 * self.moving_divisor).min(MOST_DIVISOR);
                } else if field < 0.4 * budget {
                    self.moving_divisor = (self.moving_divisor / 2).max(1);
                }
            }
            Work::Full { texels } => {
                self.full_ms = Some(blend(self.full_ms, field / texels.max(1) as f64));
            }
        }
    }

    /// Records what the frame started last did.
    pub fn frame_did(&mut self, now: Instant, work: Work) {
        self.last = Some((now, work));
    }

    /// The frame recorded last showed the frame before it again (`Work::Shown`), whatever its plan said.
    pub fn frame_shown_again(&mut self) {
        if let Some((_, work)) = &mut self.last {
            *work = Work::Shown;
        }
    }

    /// Field work a refining frame may spend, in milliseconds: as much as an idle frame costs, and at least
    /// `REFINE_MS`. Every refining frame pays an idle frame's cost (the UI, the composition) besides its bands, so
    /// bands of a fixed size would make the wait for the full picture grow with the UI's cost (33 frames of 8
    /// rows, 4.3 to 5.8 s, where idle frames took 90 ms on a loaded machine); at an idle frame's worth, the field
    /// takes at least half of that wait, and a refining frame costs at most about twice an idle one.
    fn refine_budget(&self) -> f64 {
        REFINE_MS.max(self.idle_ms)
    }

    /// The field's share of a moving frame, in milliseconds.
    fn moving_budget(&self) -> f64 {
        (self.idle_ms * (MOVING_FACTOR - 1.0)).max(2.0)
    }

    /// `plan` as `pacing` says: from the measured costs, or fixed.
    pub fn plan_paced(&mut self, pacing: Pacing, moved: bool, w: u32) -> Plan {
        match pacing {
            Pacing::Measured => self.plan(moved, w),
            Pacing::Fixed { preview, .. } if moved && preview < w => Plan::Preview {
                resolution: preview.max(1),
                divisor: 1,
            },
            Pacing::Fixed { .. } if moved => Plan::Full,
            Pacing::Fixed { band_rows, .. } => Plan::Refine {
                band_rows: band_rows.clamp(1, w.max(1)).div_ceil(8) * 8,
                bands: 1,
            },
        }
    }

    /// What to integrate in a frame whose field inputs changed since the last frame (`moved`) or not, for a
    /// full field of `w` texels a side whose texture does not show the inputs yet.
    pub fn plan(&mut self, moved: bool, w: u32) -> Plan {
        let texels = w as f64 * w as f64;
        if moved {
            // Small fields and fast machines: the whole field at once.
            let per_texel = self.full_ms.unwrap_or(ASSUMED_TEXEL_MS);
            if per_texel * texels <= self.moving_budget() || w <= MIN_PREVIEW {
                return Plan::Full;
            }
            // What the texels may spend once the fixed part is paid (a quarter of the budget at least).
            let budget = self.moving_budget();
            let texel_budget = (budget - self.preview_overhead_ms).max(0.25 * budget);
            let ideal = (texel_budget / per_texel.max(1e-9)).sqrt();
            // Multiples of 8 (the shader's workgroups), kept while within 20 % of the ideal.
            let kept = self
                .resolution
                .filter(|&r| (r as f64 - ideal).abs() <= 0.2 * ideal);
            let r = kept.unwrap_or_else(|| ((ideal / 8.0).round() as u32 * 8).max(MIN_PREVIEW));
            let r = r.clamp(MIN_PREVIEW, w);
            self.resolution = Some(r);
            if r >= w {
                return Plan::Full;
            }
            return Plan::Preview {
                resolution: r,
                divisor: self.moving_divisor,
            };
        }
        match self.full_ms {
            // Within one refining frame's budget, and small enough that an estimate off by a few times still
            // makes no long frame: all of it now.
            Some(c) if c * texels <= self.refine_budget() && w <= MAX_WHOLE => Plan::Full,
            // A quarter of the rows at most, so that a low estimate (frames measure the GPU's work only once it
            // is waited for) costs a few short frames, never one long one. Unmeasured: a CPU rasterizer's cost.
            c => {
                let c = c.unwrap_or(ASSUMED_TEXEL_MS);
                let rows = (self.refine_budget() / (c * w as f64)).floor() as u32;
                let rows = rows.clamp(8, (w / 4).max(8));
                Plan::Refine {
                    band_rows: rows.div_ceil(8) * 8,
                    bands: 1,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Feeds `frames` frames of `ms` milliseconds each that did `work`.
    fn run(b: &mut FrameBudget, start: &mut Instant, frames: u32, ms: f64, work: Work) {
        for _ in 0..frames {
            b.frame_started(*start);
            b.frame_did(*start, work);
            *start += Duration::from_secs_f64(ms / 1e3);
        }
        b.frame_started(*start);
    }

    /// Where the moving field overruns the moving budget, its side halves (down to W / `MOST_DIVISOR`); once the
    /// frames fit well again it doubles back to W.
    #[test]
    fn the_moving_side_keeps_the_budget_where_the_grid_cannot() {
        let mut b = FrameBudget::default();
        let mut t = Instant::now();
        // Idle frames of 20 ms; 64^2 texels at 300 ms: the smallest grid is chosen.
        run(&mut b, &mut t, 5, 20.0, Work::Nothing);
        run(&mut b, &mut t, 5, 300.0, Work::Full { texels: 4096 });
        let divisor = |b: &mut FrameBudget| match b.plan(true, 256) {
            Plan::Preview {
                resolution,
                divisor,
            } => {
                assert_eq!(resolution, MIN_PREVIEW);
                divisor
            }
            plan => panic!("{plan:?}"),
        };
        assert_eq!(divisor(&mut b), 1);
        // Moving frames of 50 ms (30 of field against a budget of 6): half the side each frame, down to the most.
        let texels = (MIN_PREVIEW * MIN_PREVIEW) as u64;
        run(&mut b, &mut t, 1, 50.0, Work::Preview { texels });
        assert_eq!(divisor(&mut b), 2);
        run(&mut b, &mut t, 5, 50.0, Work::Preview { texels });
        assert_eq!(divisor(&mut b), MOST_DIVISOR);
        // Frames that fit well: the whole side again.
        run(&mut b, &mut t, 5, 21.0, Work::Preview { texels });
        assert_eq!(divisor(&mut b), 1);
    }

    #[test]
    fn a_slow_field_is_previewed_at_the_resolution_that_holds_the_budget() {
        let mut b = FrameBudget::default();
        let mut t = Instant::now();
        // Idle frames of 20 ms; full frames of 256^2 texels at 300 ms (280 of them the field).
        run(&mut b, &mut t, 5, 20.0, Work::Nothing);
        run(&mut b, &mut t, 5, 300.0, Work::Full { texels: 65536 });
        let Plan::Preview { resolution, .. } = b.plan(true, 256) else {
            panic!("a 280 ms field is previewed while moving");
        };
        // A coarse texel costs what a full one does: 6 ms of field at 4.3 us a texel.
        let field_ms = resolution as f64 * resolution as f64 * 280.0 / 65536.0;
        assert!(
            (4.0..8.5).contains(&field_ms) && resolution % 8 == 0,
            "{resolution}: {field_ms} ms"
        );
        // Measured previews at that cost keep the resolution (no shimmer from frame to frame).
        let texels = resolution as u64 * resolution as u64;
        run(
            &mut b,
            &mut t,
            10,
            20.0 + field_ms,
            Work::Preview { texels },
        );
        assert_eq!(
            b.plan(true, 256),
            Plan::Preview {
                resolution,
                divisor: 1
            }
        );
        // A fixed 3 ms on top of every moving field (its refinement) leaves the coarse grid less.
        run(
            &mut b,
            &mut t,
            20,
            23.0 + field_ms,
            Work::Preview { texels },
        );
        let Plan::Preview {
            resolution: smaller,
            ..
        } = b.plan(true, 256)
        else {
            panic!("still previewed");
        };
        let field_ms = smaller as f64 * smaller as f64 * 280.0 / 65536.0;
        assert!(
            smaller < resolution && field_ms + 3.0 <= 8.5,
            "{smaller}: {field_ms} ms + 3 ms"
        );
        // Still again: the full field in bands of about REFINE_MS.
        let Plan::Refine { band_rows, bands } = b.plan(false, 256) else {
            panic!("a 280 ms field is refined in bands");
        };
        let band_ms = band_rows as f64 * 256.0 * 280.0 / 65536.0;
        assert!(
            bands == 1 && band_ms <= 1.25 * REFINE_MS,
            "{band_rows} rows: {band_ms} ms"
        );
    }

    #[test]
    fn refining_bands_take_as_long_as_an_idle_frame_where_it_is_slow() {
        let mut b = FrameBudget::default();
        let mut t = Instant::now();
        // Idle frames of 90 ms (a slow UI); full frames of 256^2 texels at 1590 ms (1500 of them the field).
        run(&mut b, &mut t, 5, 90.0, Work::Nothing);
        // Measured in bands of 32 rows (187.5 ms of field), frames closer than STALE_MS.
        run(&mut b, &mut t, 5, 277.5, Work::Full { texels: 8192 });
        let Plan::Refine { band_rows, bands } = b.plan(false, 256) else {
            panic!("a 1500 ms field is refined in bands");
        };
        let band_ms = band_rows as f64 * 256.0 * 1500.0 / 65536.0;
        assert_eq!(bands, 1);
        assert!(
            (0.6 * 90.0..=1.25 * 90.0).contains(&band_ms),
            "{band_rows} rows: {band_ms} ms of field beside 90 ms idle frames"
        );
        // Fast idle frames (12 ms) and a 300 ms field: REFINE_MS, as before.
        let mut b = FrameBudget::default();
        run(&mut b, &mut t, 5, 12.0, Work::Nothing);
        run(&mut b, &mut t, 5, 49.5, Work::Full { texels: 8192 });
        let Plan::Refine { band_rows, .. } = b.plan(false, 256) else {
            panic!("in bands");
        };
        let band_ms = band_rows as f64 * 256.0 * 300.0 / 65536.0;
        assert!(
            band_ms <= 1.25 * REFINE_MS,
            "{band_rows} rows: {band_ms} ms"
        );
    }

    #[test]
    fn a_cheap_field_is_integrated_whole_every_frame() {
        let mut b = FrameBudget::default();
        let mut t = Instant::now();
        // Nothing measured yet: coarse, and in bands, as if on a CPU rasterizer, until a full field is timed.
        assert!(matches!(b.plan(true, 256), Plan::Preview { .. }));
        assert!(matches!(b.plan(false, 256), Plan::Refine { .. }));
        assert_eq!(b.plan(true, 32), Plan::Full, "1024 texels fit any frame");
        run(&mut b, &mut t, 5, 16.7, Work::Nothing);
        run(&mut b, &mut t, 5, 18.0, Work::Full { texels: 65536 });
        assert_eq!(b.plan(true, 256), Plan::Full);
        // Still: a field up to 128 a side whole, a larger one in no fewer than four bands.
        assert_eq!(b.plan(false, 128), Plan::Full);
        assert_eq!(
            b.plan(false, 256),
            Plan::Refine {
                band_rows: 64,
                bands: 1
            }
        );
    }

    #[test]
    fn frames_far_apart_measure_nothing() {
        let mut b = FrameBudget::default();
        let mut t = Instant::now();
        run(&mut b, &mut t, 3, 20.0, Work::Nothing);
        let idle = b.idle_ms;
        // An idle viewer redraws every quarter second or less often: those gaps are not frame costs.
        run(&mut b, &mut t, 3, 900.0, Work::Nothing);
        assert_eq!(b.idle_ms, idle);
    }
}
