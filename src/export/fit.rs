//! Framing an export to its effect: the field of view that holds the whole glow, down to its edge (the
//! scene's cutoff, `scene::edge_fade`), in every frame exported, so that a sprite sheet's cells and a
//! sequence's frames end in alpha 0 all round instead of a hard square.

use std::ops::Range;

use crate::frame::FrameSetup;
use crate::reference::{self, Backdrop};
use crate::scene::Scene;

/// The share of the glow's half extent left free beyond it, on each side.
pub const FIT_MARGIN: f64 = 0.06;

/// Pixels along the probe frame's height: the glow's extent is found to about a pixel of it.
const PROBE_HEIGHT: u32 = 96;

/// The probe's billboard resolution: about a texel a pixel of the probe frame's width.
const PROBE_TEXELS: u32 = 128;

/// The least alpha the fit keeps in frame: what an 8-bit alpha does not round to 0. The faint fade below it
/// (B just above the cutoff) may fall outside, where a float EXR holds it below 0.002.
const VISIBLE_ALPHA: f64 = 0.5 / 255.0;

/// The most frames probed: an animation longer than this is probed at evenly spaced frames (and its last).
const MAX_PROBED: u32 = 32;

/// The widest half field of view tried, as its tangent (about 170 degrees).
const MAX_TAN_HALF: f64 = 11.4;

/// Why an effect cannot be framed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FitError {
    #[error(
        "the glow has no edge (colors.cutoff = 0, the papers' glow), so it reaches every frame's border; set a \
         cutoff (0.2 is the default) to frame the effect"
    )]
    NoEdge,
    #[error(
        "the glow reaches past a field of view of 170 degrees at frame {frame}: the eye is inside it"
    )]
    TooWide { frame: u32 },
}

/// The vertical field of view, in degrees, that frames the glow of every frame in `frames` of `scene` at
/// `width` x `height` with `FIT_MARGIN` to spare, the camera's eye, target and up kept: a ray's brightness
/// depends on its direction alone, not on the field of view, so only how much of it the frame shows changes.
/// Measured with the CPU twin on a small frame of the same aspect, transparent and with the objects held out
/// (they end no glow's edge); a frame without glow asks nothing. The scene's own field of view where no frame
/// has any glow.
pub fn fit_field_of_view(
    scene: &Scene,
    frames: Range<u32>,
    (width, height): (u32, u32),
) -> Result<f64, FitError> {
    if scene.colors.cutoff <= 0.0 {
        return Err(FitError::NoEdge);
    }
    let aspect = width.max(1) as f64 / height.max(1) as f64;
    let (pw, ph) = (
        ((PROBE_HEIGHT as f64 * aspect).round() as u32).max(8),
        PROBE_HEIGHT,
    );
    let mut need: Option<f64> = None;
    let step = frames.len().div_ceil(MAX_PROBED as usize).max(1);
    let last = frames.end.saturating_sub(1).max(frames.start);
    let probed = frames.clone().step_by(step).chain(std::iter::once(last));
    // One cache for the probes: the live sets step from the frame probed before, the objects lit once.
    let cache = std::sync::Arc::new(crate::frame::FrameCache::new());
    for frame in probed {
        let mut at = cache.scene_at(scene, frame as f64);
        at.billboard.resolution = PROBE_TEXELS;
        at.billboard.fixed_resolution = true;
        let mut tan_half = at.camera.tan_half_fov() * 2.0;
        loop {
            at.camera.fov_y_degrees = 2.0 * tan_half.atan().to_degrees();
            let view = FrameSetup::placed_in(&at, pw as f64 / ph as f64, &cache);
            let tex = reference::render_brightness(&view);
            let pixels = reference::compose_frame_over(&view, &tex, (pw, ph), Backdrop::Holdout);
            let (mut reach_x, mut reach_y, mut edge) = (None::<f64>, None::<f64>, false);
            for (k, p) in pixels.iter().enumerate() {
                if p[3] < VISIBLE_ALPHA {
                    continue;
                }
                let (x, y) = ((k as u32 % pw) as f64, (k as u32 / pw) as f64);
                edge |= x == 0.0 || y == 0.0 || x == (pw - 1) as f64 || y == (ph - 1) as f64;
                // The pixel's outer side, in units of the probe's half height.
                let sx = ((x + 0.5 - pw as f64 / 2.0).abs() + 0.5) / (ph as f64 / 2.0);
                let sy = ((y + 0.5 - ph as f64 / 2.0).abs() + 0.5) / (ph as f64 / 2.0);
                reach_x = Some(reach_x.map_or(sx, |r| r.max(sx)));
                reach_y = Some(reach_y.map_or(sy, |r| r.max(sy)));
            }
            if edge {
                if tan_half >= MAX_TAN_HALF {
                    return Err(FitError::TooWide { frame });
                }
                tan_half = (tan_half * 2.0).min(MAX_TAN_HALF);
                continue;
            }
            if let (Some(rx), Some(ry)) = (reach_x, reach_y) {
                // The half height the glow needs, in tangent units: its vertical reach, or its horizontal one
                // over the frame's aspect.
                let t = tan_half * ry.max(rx / aspect) * (1.0 + FIT_MARGIN);
                need = Some(need.map_or(t, |n| n.max(t)));
            }
            break;
        }
    }
    Ok(need.map_or(scene.camera.fov_y_degrees, |t| 2.0 * t.atan().to_degrees()))
}
