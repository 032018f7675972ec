//! Camera and billboard geometry: where the billboard sits, the ray of each texel (METHOD.md section 3,
//! thesis 4.1-4.3) and the camera rays of the composed frame.

use glam::DVec3;

use crate::field::Sources;

/// A perspective camera looking from `eye` at `target`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    /// World "up" hint; need not be orthogonal to the view direction, must not be parallel to it.
    pub up: DVec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_degrees: f64,
}

/// An orthonormal camera frame: `right`, `up`, and `forward` (from the eye toward the target).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
}

impl Camera {
    /// The camera's orthonormal frame (right-handed: `right = forward x up`).
    pub fn frame(&self) -> Frame {
        let forward = (self.target - self.eye).normalize();
        let right = perpendicular_right(self.up, -forward);
        Frame {
            right,
            up: right.cross(forward),
            forward,
        }
    }

    /// `tan(fov_y / 2)`.
    /// The camera with its eye and target rounded to a millionth of the distance between them (to its power
    /// of ten), its up to six decimals and its field of view to four: what navigation leaves after a drag,
    /// so that a saved file reads `eye = [3.617305, 2.4, 6.8]` and not sixteen digits of float noise.
    pub fn tidied(&self) -> Camera {
        let distance = (self.target - self.eye).length();
        let scale = if distance > 0.0 && distance.is_finite() {
            distance.log10().floor() as i32
        } else {
            0
        };
        let round = |x: f64, decimals: i32| -> f64 {
            let decimals = decimals.clamp(0, 15) as usize;
            format!("{x:.decimals$}").parse().unwrap_or(x)
        };
        let point = |p: DVec3| p.to_array().map(|x| round(x, 6 - scale)).into();
        let up = self.up.to_array().map(|x| round(x, 6)).into();
        let tidy = Camera {
            eye: point(self.eye),
            target: point(self.target),
            up,
            fov_y_degrees: round(self.fov_y_degrees, 4),
        };
        // Rounding never makes a camera invalid: where it would (the eye on the target), keep it as it was.
        if (tidy.target - tidy.eye).length() > 0.0
            && tidy.up.cross(tidy.target - tidy.eye).length() > 0.0
        {
            tidy
        } else {
            self.clone()
        }
    }

    pub fn tan_half_fov(&self) -> f64 {
        (self.fov_y_degrees.to_radians() * 0.5).tan()
    }

    /// World-space direction (unit) of the ray through pixel `(x, y)` (continuous pixel coordinates, y down)
    /// of a `width` x `height` frame.
    pub fn pixel_ray(&self, x: f64, y: f64, width: u32, height: u32) -> DVec3 {
        let f = self.frame();
        let t = self.tan_half_fov();
        let aspect = width as f64 / height as f64;
        let ndc_x = 2.0 * x / width as f64 - 1.0;
        let ndc_y = 1.0 - 2.0 * y / height as f64;
        (f.forward + f.right * (ndc_x * t * aspect) + f.up * (ndc_y * t)).normalize()
    }

    /// Projects a world point to continuous pixel coordinates (y down), or `None` behind the eye.
    pub fn project(&self, p: DVec3, width: u32, height: u32) -> Option<(f64, f64)> {
        let f = self.frame();
        let d = p - self.eye;
        let depth = d.dot(f.forward);
        if depth <= 0.0 {
            return None;
        }
        let t = self.tan_half_fov();
        let aspect = width as f64 / height as f64;
        let ndc_x = d.dot(f.right) / (depth * t * aspect);
        let ndc_y = d.dot(f.up) / (depth * t);
        Some((
            (ndc_x + 1.0) * 0.5 * width as f64,
            (1.0 - ndc_y) * 0.5 * height as f64,
        ))
    }
}

/// `normalize(cross(up, n))`, falling back to a deterministic perpendicular of `n` when `up` is (nearly)
/// parallel to `n`, so that a degenerate hint never produces NaN.
fn perpendicular_right(up: DVec3, n: DVec3) -> DVec3 {
    let r = up.cross(n);
    if r.length_squared() > 1e-20 * up.length_squared().max(1e-300) {
        return r.normalize();
    }
    n.any_orthonormal_vector()
}

/// The square billboard: center `C`, side `l`, and its axes facing the eye (METHOD.md section 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Billboard {
    pub center: DVec3,
    pub size: f64,
    pub right: DVec3,
    pub up: DVec3,
    /// `normalize(V - C)`: toward the eye.
    pub normal: DVec3,
    /// The band along each edge over which the glow fades to nothing, as a share of the side (`edge_window`): 0
    /// where the billboard's edges lie outside the frame, up to `EDGE_BAND` where they lie inside it, so that a
    /// glow reaching past the billboard is not cut off square there.
    pub edge: f64,
}

/// The widest band of `Billboard::edge`: a 25th of the side along each edge. A glow this fade reaches is one the
/// effect's reach did not cover (a strong source's, above its cutoff there): the band turns the cut into a short
/// ramp without dimming the glow inside (a fifth of the side dimmed a point's glow beside an object from alpha 40
/// to 6).
pub const EDGE_BAND: f64 = 0.04;

/// The glow's window at texture coordinates `(u, v)` in [0, 1] of a billboard whose fading band is `edge`: 1
/// inside, falling smoothly (smoothstep) to 0 at the edges across the band; 1 everywhere for no band. The one
/// formula of both renderers (`shaders/billboard.wgsl`).
pub fn edge_window(u: f64, v: f64, edge: f64) -> f64 {
    if edge <= 0.0 {
        return 1.0;
    }
    let ramp = |x: f64| {
        let t = (x.min(1.0 - x) / edge).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    ramp(u) * ramp(v)
}

impl Billboard {
    /// A billboard at `center` with side `size` facing `eye`: `n = normalize(V - C)`,
    /// `right = normalize(cross(camera_up, n))`, `up = cross(n, right)`.
    pub fn facing(center: DVec3, size: f64, eye: DVec3, camera_up: DVec3) -> Self {
        let normal = (eye - center).normalize();
        let right = perpendicular_right(camera_up, normal);
        Self {
            center,
            size,
            right,
            up: normal.cross(right),
            normal,
            edge: 0.0,
        }
    }

    /// World position of the center of texel `(i, j)` (column from the left, row from the top) of a `w` x `w`
    /// texture (4.2 at texel centers): `C + l((i + 0.5)/W - 0.5) right + l(0.5 - (j + 0.5)/W) up`.
    pub fn texel_center(&self, i: u32, j: u32, w: u32) -> DVec3 {
        let u = (i as f64 + 0.5) / w as f64 - 0.5;
        let v = 0.5 - (j as f64 + 0.5) / w as f64;
        self.center + self.right * (self.size * u) + self.up * (self.size * v)
    }

    /// Where a ray from `origin` along `dir` meets the billboard, as texture coordinates `(u, v)` in [0, 1]
    /// (u from the left, v from the top), or `None` if it misses the square or the plane is behind.
    pub fn hit(&self, origin: DVec3, dir: DVec3) -> Option<(f64, f64)> {
        let denom = dir.dot(self.normal);
        if denom.abs() < 1e-300 {
            return None;
        }
        let t = (self.center - origin).dot(self.normal) / denom;
        if t <= 0.0 {
            return None;
        }
        let h = origin + dir * t - self.center;
        let u = h.dot(self.right) / self.size + 0.5;
        let v = 0.5 - h.dot(self.up) / self.size;
        ((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)).then_some((u, v))
    }
}

/// The far end of a texel's integration segment: `E = V + nu (S - V)` (4.3, corrected).
pub fn ray_end(s: DVec3, eye: DVec3, nu: f64) -> DVec3 {
    eye + nu * (s - eye)
}

/// How far the glow is assumed to reach beyond the sources' bounding sphere, in radii, when the automatic
/// billboard is sized to the effect rather than to the whole view.
const GLOW_REACH: f64 = 3.0;

/// The effect as the camera sees it: the center of the sources' bounding box, and the radius of its sphere
/// padded by 5 % of the eye's distance to that center (the padding keeps the automatic billboard off the
/// sources themselves, where their glow peaks). Without sources: the camera's target and the padding alone.
fn effect_sphere(camera: &Camera, sources: &Sources) -> (DVec3, f64) {
    let (c, radius) = match sources.bounds() {
        Some((lo, hi)) => ((lo + hi) * 0.5, (hi - lo).length() * 0.5),
        None => (camera.target, 0.0),
    };
    (c, radius + 0.05 * (c - camera.eye).length())
}

/// Places the billboard for `camera` and a frame of `aspect` (width / height).
///
/// `center` and `size` fix it where the scene gives them. Otherwise (automatic placement) the billboard is
/// perpendicular to the view axis, just in front of the sources' bounding sphere (METHOD.md section 3: the
/// plane must lie between the eye and the effect), and large enough to cover the whole frame, or only the
/// effect and its glow when that is smaller and `glow_ends` (the scene's glow has an edge, `colors.cutoff` above
/// 0, which the effect's reach holds): a glow without one reaches past any reach (a lone point's, at 1.2 scene
/// units, still 30/255 on black), and its billboard covers the frame. A camera inside the sphere gets a plane
/// close to the eye.
pub fn place_billboard(
    camera: &Camera,
    sources: &Sources,
    center: Option<DVec3>,
    size: Option<f64>,
    aspect: f64,
    glow_ends: bool,
) -> Billboard {
    let frame = camera.frame();
    let view_distance = (camera.target - camera.eye).length();
    let (c, extent) = effect_sphere(camera, sources);
    let to_c = c - camera.eye;
    let depth = to_c.dot(frame.forward);
    let lateral = (to_c - frame.forward * depth).length();
    let min_plane = 1e-3 * view_distance;
    let plane = (depth - extent).max(0.05 * extent).max(min_plane);

    let center = center.unwrap_or(camera.eye + frame.forward * plane);
    let half_view = (center - camera.eye).length() * camera.tan_half_fov() * aspect.max(1.0);
    let size = size.unwrap_or_else(|| {
        let plane = (center - camera.eye).length();
        let half_effect = if depth > extent && glow_ends {
            plane * (lateral + GLOW_REACH * extent) / depth
        } else {
            f64::INFINITY
        };
        2.0 * half_view.min(half_effect)
    });
    let mut billboard = Billboard::facing(center, size, camera.eye, camera.up);
    // How far the edges lie inside the frame, in bands: the fade grows from none (edges at the frame's, which hide
    // them) to the whole band as they come one band inside, continuously as the camera moves.
    let inside = (half_view - 0.5 * size) / (EDGE_BAND * size);
    let t = inside.clamp(0.0, 1.0);
    billboard.edge = if t.is_finite() {
        EDGE_BAND * t * t * (3.0 - 2.0 * t)
    } else {
        0.0
    };
    billboard
}

/// The most decay lengths a ray may span (a bound against overflow; real scenes stay near 1).
const MAX_STRETCH: f64 = 1e6;

/// How far one frame's rays reach and how their decay is scaled, for a decay measured in scene units.
///
/// The decay runs on `sigma`, the depth past the billboard plane (along its normal) in units of the scene's
/// decay length D: `zeta = alpha / (sigma + beta)^2`, the same function of a point in space whatever the
/// camera. Every ray runs from its texel S to `sigma_end = max(1, far / D)`, `far` the depth of the far side
/// of the sources' padded sphere (`effect_sphere`), so that it always reaches past every source. In the
/// method's normalised `s = sigma / sigma_end` (METHOD.md section 3) this is `E = V + nu (S - V)` with
/// `nu = 1 + sigma_end D / p` (p the eye-to-plane distance) and the decay `(alpha / sigma_end) /
/// (s + beta / sigma_end)^2`: the integrators run unchanged on `Integration::on_ray(stretch)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// `E = V + nu (S - V)` for every texel of the frame.
    pub nu: f64,
    /// `sigma_end`: how many decay lengths the rays span, at least 1.
    pub stretch: f64,
}

/// The reach of every texel's ray through `billboard` seen from `camera` (see `Reach`).
pub fn ray_reach(
    camera: &Camera,
    sources: &Sources,
    billboard: &Billboard,
    decay_length: f64,
) -> Reach {
    let inward = -billboard.normal;
    let plane = (billboard.center - camera.eye).dot(inward);
    let (c, extent) = effect_sphere(camera, sources);
    let far = (c - camera.eye).dot(inward) + extent - plane;
    let stretch = (far / decay_length).clamp(1.0, MAX_STRETCH);
    let stretch = if stretch.is_finite() { stretch } else { 1.0 };
    Reach {
        nu: 1.0 + stretch * decay_length / plane,
        stretch,
    }
}

/// The papers' decay length for a scene seen from `camera`: `E = V + nu (S - V)` puts the end of the ray
/// `(nu - 1) p` behind a billboard `p` away from the eye, so the decay length that renders the scene exactly
/// as the papers do at this camera is `(nu - 1) p`. Scene files without a decay length get it from their
/// own camera this way.
pub fn papers_decay_length(
    camera: &Camera,
    sources: &Sources,
    billboard_center: Option<DVec3>,
    nu: f64,
) -> f64 {
    let b = place_billboard(camera, sources, billboard_center, Some(1.0), 1.0, true);
    (nu - 1.0) * (b.center - camera.eye).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: DVec3::new(0.0, 0.0, 10.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 40.0,
        }
    }

    #[test]
    fn billboard_axes_are_orthonormal_and_face_the_eye() {
        let b = Billboard::facing(
            DVec3::new(1.0, 2.0, 3.0),
            2.0,
            DVec3::new(-4.0, 5.0, 9.0),
            DVec3::Y,
        );
        assert!((b.right.length() - 1.0).abs() < 1e-12);
        assert!((b.up.length() - 1.0).abs() < 1e-12);
        assert!(b.right.dot(b.up).abs() < 1e-12 && b.right.dot(b.normal).abs() < 1e-12);
        assert!(
            b.normal
                .dot((DVec3::new(-4.0, 5.0, 9.0) - b.center).normalize())
                > 1.0 - 1e-12
        );
        // Degenerate up hint: still finite and orthonormal.
        let b = Billboard::facing(DVec3::ZERO, 1.0, DVec3::Y * 3.0, DVec3::Y);
        assert!(b.right.is_finite() && (b.right.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn texel_centers_span_the_square() {
        let b = Billboard::facing(DVec3::ZERO, 4.0, DVec3::Z * 10.0, DVec3::Y);
        // Top-left texel of a 2x2 texture sits at (-1, 1) in the billboard's axes.
        let p = b.texel_center(0, 0, 2);
        assert!((p - DVec3::new(-1.0, 1.0, 0.0)).length() < 1e-12, "{p}");
        let p = b.texel_center(1, 1, 2);
        assert!((p - DVec3::new(1.0, -1.0, 0.0)).length() < 1e-12, "{p}");
    }

    #[test]
    fn ray_end_is_nu_times_the_eye_distance() {
        let eye = DVec3::new(1.0, 1.0, 1.0);
        let s = DVec3::new(2.0, 3.0, 4.0);
        let e = ray_end(s, eye, 2.0);
        assert!((e - (2.0 * s - eye)).length() < 1e-12);
        assert!(((ray_end(s, eye, 3.0) - eye).length() - 3.0 * (s - eye).length()).abs() < 1e-12);
    }

    #[test]
    fn projection_inverts_pixel_rays() {
        let c = camera();
        let dir = c.pixel_ray(123.5, 45.25, 320, 200);
        let (x, y) = c.project(c.eye + dir * 7.0, 320, 200).unwrap();
        assert!((x - 123.5).abs() < 1e-9 && (y - 45.25).abs() < 1e-9);
    }

    fn ring() -> Sources {
        Sources {
            tori: vec![crate::field::Torus {
                center: DVec3::ZERO,
                axis: DVec3::new(0.0, 1.0, 1.0).normalize(),
                major_radius: 1.0,
                coefficient: 1.0,
                look: Default::default(),
            }],
            ..Sources::default()
        }
    }

    #[test]
    fn automatic_billboard_is_in_front_of_the_sources_and_holds_a_small_effect() {
        let c = camera();
        let b = place_billboard(&c, &ring(), None, None, 1.5, true);
        // In front of every source (the ring reaches z = 1/sqrt(2)), between the eye and the effect.
        assert!(b.center.z > 1.0 && b.center.z < 10.0, "{b:?}");
        // The ring and a glow margin around it lie well inside the square.
        for k in 0..32 {
            let a = k as f64 / 32.0 * std::f64::consts::TAU;
            let p = DVec3::new(a.cos(), a.sin() * 0.5f64.sqrt(), -a.sin() * 0.5f64.sqrt()) * 2.0;
            let (u, v) = b
                .hit(c.eye, (p - c.eye).normalize())
                .expect("the glow lies on the billboard");
            assert!(
                (0.1..0.9).contains(&u) && (0.1..0.9).contains(&v),
                "{u} {v}"
            );
        }
    }

    #[test]
    fn automatic_billboard_covers_the_frame_when_the_effect_fills_it() {
        let c = Camera {
            eye: DVec3::new(0.0, 0.0, 3.0),
            ..camera()
        };
        let b = place_billboard(&c, &ring(), None, None, 1.5, true);
        for (x, y) in [
            (0.0, 0.0),
            (300.0, 0.0),
            (0.0, 200.0),
            (300.0, 200.0),
            (150.0, 100.0),
        ] {
            assert!(
                b.hit(c.eye, c.pixel_ray(x, y, 300, 200)).is_some(),
                "corner {x} {y} misses {b:?}"
            );
        }
        // A camera inside the effect still gets a billboard in front of it.
        let inside = Camera {
            eye: DVec3::new(0.2, 0.0, 0.1),
            ..camera()
        };
        let b = place_billboard(&inside, &ring(), None, None, 1.0, true);
        assert!(b.size.is_finite() && b.size > 0.0);
        assert!(
            b.hit(inside.eye, inside.pixel_ray(50.0, 50.0, 100, 100))
                .is_some()
        );
    }
}
