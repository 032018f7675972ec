//! Camera navigation as artists expect it from Blender or Effekseer: orbit around the target, pan in the view
//! plane, zoom toward the cursor, frame the effect. Pure functions on `geometry::Camera`.

use glam::{DQuat, DVec3};

use crate::field::Sources;
use crate::geometry::Camera;

/// Closest the view direction may come to the world up axis, in radians (avoids the pole's flip).
const POLE_MARGIN: f64 = 0.02;
/// Closest the eye may come to the target, relative to the scene's scale.
const MIN_DISTANCE: f64 = 1e-4;

/// Orbits the eye around the target: `yaw` around the world up axis, `pitch` up and down (radians),
/// keeping the distance, and stopping short of the poles.
pub fn orbit(camera: &mut Camera, yaw: f64, pitch: f64) {
    let up = camera.up.normalize();
    let offset = camera.eye - camera.target;
    let offset = DQuat::from_axis_angle(up, -yaw) * offset;
    // Elevation angle from the up axis; clamp the pitch so it stays inside (margin, pi - margin).
    let polar = offset.normalize().dot(up).clamp(-1.0, 1.0).acos();
    let new_polar = (polar - pitch).clamp(POLE_MARGIN, std::f64::consts::PI - POLE_MARGIN);
    let right = up.cross(offset);
    let offset = if right.length_squared() > 0.0 {
        DQuat::from_axis_angle(right.normalize(), new_polar - polar) * offset
    } else {
        offset
    };
    camera.eye = camera.target + offset;
}

/// Pans by a drag of `(dx, dy)` pixels in a viewport `height` pixels tall: the point under the cursor at the
/// target's depth follows the cursor.
pub fn pan(camera: &mut Camera, dx: f64, dy: f64, height: f64) {
    let f = camera.frame();
    let distance = (camera.target - camera.eye).length();
    let per_pixel = 2.0 * distance * camera.tan_half_fov() / height.max(1.0);
    let shift = (-dx * f.right + dy * f.up) * per_pixel;
    camera.eye += shift;
    camera.target += shift;
}

/// Zooms by `factor` (below 1 comes closer) toward the point at the target's depth along the unit ray `toward`
/// (the cursor's), which stays under the cursor; without a ray, toward the target.
pub fn zoom(camera: &mut Camera, factor: f64, toward: Option<DVec3>) {
    let forward = camera.frame().forward;
    let distance = (camera.target - camera.eye).length();
    let factor = factor.max(MIN_DISTANCE / distance.max(MIN_DISTANCE));
    let pivot = match toward {
        Some(dir) if dir.dot(forward) > 1e-6 => camera.eye + dir * (distance / dir.dot(forward)),
        _ => camera.target,
    };
    // A homothety centered on the pivot keeps the pivot's ray, hence its place on screen.
    camera.eye = pivot + (camera.eye - pivot) * factor;
    camera.target = pivot + (camera.target - pivot) * factor;
}

/// The wheel's zoom: `zoom` while the target is farther than `floor`; closer, zooming in dollies the eye and the
/// target together along the cursor's ray (or the view), by the step `zoom` would take at `floor`, so the
/// wheel passes through the target and on, as Blender does, instead of slowing to a stop at it.
pub fn zoom_or_dolly(camera: &mut Camera, factor: f64, toward: Option<DVec3>, floor: f64) {
    let distance = (camera.target - camera.eye).length();
    if factor >= 1.0 || distance * factor >= floor {
        zoom(camera, factor, toward);
        return;
    }
    let forward = camera.frame().forward;
    let dir = toward
        .filter(|d| d.dot(forward) > 1e-6)
        .map_or(forward, |d| d.normalize());
    let step = distance.max(floor) * (1.0 - factor);
    camera.eye += dir * step;
    camera.target += dir * step;
}

/// The distance under which the wheel dollies (`zoom_or_dolly`): a twentieth of the sources' extent.
pub fn dolly_floor(sources: &Sources) -> f64 {
    sources
        .bounds()
        .map_or(0.05, |(lo, hi)| ((hi - lo).length() * 0.05).max(1e-3))
}

/// Frames the sources: looks at the center of their bounds from the current direction, from the distance at
/// which the bounding sphere (with a margin for the glow) fits the narrower field of view of a frame of
/// `aspect`.
pub fn frame_sources(camera: &mut Camera, sources: &Sources, aspect: f64) {
    let Some((lo, hi)) = sources.bounds() else {
        return;
    };
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(0.25) * 1.3;
    let half_y = camera.fov_y_degrees.to_radians() * 0.5;
    let half_x = (half_y.tan() * aspect).atan();
    let distance = radius / half_y.min(half_x).sin();
    let forward = camera.frame().forward;
    camera.target = center;
    camera.eye = center - forward * distance;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Torus;

    fn camera() -> Camera {
        Camera {
            eye: DVec3::new(1.0, 2.0, 9.0),
            target: DVec3::new(0.5, 0.0, 0.0),
            up: DVec3::Y,
            fov_y_degrees: 40.0,
        }
    }

    #[test]
    fn orbit_keeps_the_distance_and_the_target() {
        let mut c = camera();
        let d = (c.eye - c.target).length();
        orbit(&mut c, 0.7, 0.3);
        assert!(((c.eye - c.target).length() - d).abs() < 1e-12);
        assert_eq!(c.target, camera().target);
        // A pure yaw keeps the height above the target.
        let mut c = camera();
        orbit(&mut c, 1.1, 0.0);
        assert!((c.eye.y - camera().eye.y).abs() < 1e-12);
        // Yawing a full turn comes back.
        orbit(&mut c, std::f64::consts::TAU - 1.1, 0.0);
        assert!((c.eye - camera().eye).length() < 1e-9);
    }

    #[test]
    fn orbit_stops_short_of_the_poles() {
        let mut c = camera();
        orbit(&mut c, 0.0, 10.0);
        let dir = (c.eye - c.target).normalize();
        assert!(dir.dot(DVec3::Y) < 1.0 - 1e-5 && dir.dot(DVec3::Y) > 0.99);
        // The frame stays well defined.
        assert!(c.frame().right.is_finite());
        orbit(&mut c, 0.0, -10.0);
        assert!((c.eye - c.target).normalize().dot(DVec3::Y) < -0.99);
    }

    #[test]
    fn pan_moves_eye_and_target_together_in_the_view_plane() {
        let mut c = camera();
        let before = c.clone();
        pan(&mut c, 100.0, -50.0, 400.0);
        assert!(((c.eye - c.target) - (before.eye - before.target)).length() < 1e-12);
        let shift = c.target - before.target;
        assert!(shift.dot(before.frame().forward).abs() < 1e-12);
        // Dragging right by a quarter of the height moves the target left by a quarter of the view height at
        // the target's depth.
        let view_height = 2.0 * (before.target - before.eye).length() * before.tan_half_fov();
        assert!((shift.dot(before.frame().right) + view_height * 0.25).abs() < 1e-9);
        assert!((shift.dot(before.frame().up) + view_height * 0.125).abs() < 1e-9);
    }

    #[test]
    fn the_wheel_dollies_through_the_target_when_close() {
        let mut c = camera();
        let start = c.clone();
        let forward = c.frame().forward;
        let distance = (c.target - c.eye).length();
        for _ in 0..400 {
            zoom_or_dolly(&mut c, 0.9, None, 0.5);
        }
        // The eye went past where the target was, looking the same way, the target still ahead of it.
        assert!((c.eye - start.eye).dot(forward) > distance, "{:?}", c.eye);
        assert!((c.frame().forward - forward).length() < 1e-9);
        assert!(((c.target - c.eye).length() - 0.5).abs() < 0.06);
        // Far away, the wheel zooms as before.
        let mut far = camera();
        zoom_or_dolly(&mut far, 0.5, None, 0.5);
        let mut zoomed = camera();
        zoom(&mut zoomed, 0.5, None);
        assert_eq!(far, zoomed);
    }

    #[test]
    fn zoom_toward_the_cursor_keeps_the_point_under_it() {
        let mut c = camera();
        let (w, h) = (400, 300);
        let (px, py) = (310.0, 80.0);
        let dir = c.pixel_ray(px, py, w, h);
        let distance = (c.target - c.eye).length();
        let pivot = c.eye + dir * (distance / dir.dot(c.frame().forward));
        zoom(&mut c, 0.5, Some(dir));
        let (x, y) = c.project(pivot, w, h).unwrap();
        assert!((x - px).abs() < 1e-6 && (y - py).abs() < 1e-6, "{x} {y}");
        assert!(((c.target - c.eye).length() - distance * 0.5).abs() < 1e-9);
        // Without a ray, toward the target.
        let mut c = camera();
        zoom(&mut c, 2.0, None);
        assert_eq!(c.target, camera().target);
        assert!(((c.target - c.eye).length() - 2.0 * distance).abs() < 1e-9);
    }

    #[test]
    fn framing_fits_the_effect_in_view() {
        let sources = Sources {
            tori: vec![Torus {
                center: DVec3::new(10.0, 0.0, 0.0),
                axis: DVec3::Z,
                major_radius: 3.0,
                coefficient: 1.0,
                look: Default::default(),
            }],
            ..Sources::default()
        };
        for aspect in [0.5, 1.0, 2.0] {
            let mut c = camera();
            frame_sources(&mut c, &sources, aspect);
            assert!((c.target - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-9);
            let (w, h) = ((300.0 * aspect) as u32, 300);
            for k in 0..16 {
                let a = k as f64 / 16.0 * std::f64::consts::TAU;
                let p = DVec3::new(10.0 + 3.0 * a.cos(), 3.0 * a.sin(), 0.0);
                let (x, y) = c.project(p, w, h).unwrap();
                assert!(
                    x > 0.0 && x < w as f64 && y > 0.0 && y < h as f64,
                    "aspect {aspect}: {x} {y}"
                );
            }
        }
    }
}
