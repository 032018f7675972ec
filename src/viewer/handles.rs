//! Handles of the sources in the viewport, drawn with egui's painter over the 3D view: points, line anchors and
//! directions, torus centers, radii and axes, curve polylines, control polygons and control points. Every handle
//! can be dragged in the view plane; the selected source is drawn brighter.

use egui::{Color32, Pos2, Rect, Stroke, Vec2};
use glam::DVec3;

use crate::animation::{Parameter, SourceKind, Value};
use crate::field::curve::segments;
use crate::geometry::Camera;
use crate::scene::Scene;

/// A draggable point of a source: its position, or a point that sets its direction or its radius.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleId {
    Point(usize),
    LinePoint(usize),
    /// The tip of a line's direction arrow.
    LineDirection(usize),
    TorusCenter(usize),
    /// A point of a torus's ring: its distance from the axis is the radius.
    TorusRadius(usize),
    /// The tip of a torus's axis.
    TorusAxis(usize),
    Control {
        curve: usize,
        index: usize,
    },
    /// An object's center (a plane's point, a mesh's translation).
    Object(usize),
}

/// How close (in points) the pointer must be to grab a handle.
pub const GRAB_RADIUS: f32 = 9.0;
/// A line's direction handle sits this share of the camera's distance to its target along the line, where its
/// arrow ends: the same size on screen however far the camera is.
const DIRECTION_REACH: f64 = 0.125;
/// A torus's axis handle sits this share of its radius along the axis.
const AXIS_REACH: f64 = 0.5;

impl HandleId {
    /// The source the handle belongs to (none for an object's).
    pub fn source(self) -> Option<(SourceKind, usize)> {
        Some(match self {
            HandleId::Point(i) => (SourceKind::Points, i),
            HandleId::LinePoint(i) | HandleId::LineDirection(i) => (SourceKind::Lines, i),
            HandleId::TorusCenter(i) | HandleId::TorusRadius(i) | HandleId::TorusAxis(i) => {
                (SourceKind::Tori, i)
            }
            HandleId::Control { curve, .. } => (SourceKind::Curves, curve),
            HandleId::Object(_) => return None,
        })
    }

    /// The object the handle belongs to, if it is an object's.
    pub fn object(self) -> Option<usize> {
        match self {
            HandleId::Object(i) => Some(i),
            _ => None,
        }
    }

    /// True for a handle that moves the source (a position), not its direction or size.
    pub fn is_position(self) -> bool {
        !matches!(
            self,
            HandleId::LineDirection(_) | HandleId::TorusRadius(_) | HandleId::TorusAxis(_)
        )
    }
}

/// The unit vector in a torus's ring plane toward its radius handle.
fn ring_direction(axis: DVec3) -> DVec3 {
    axis.any_orthonormal_vector()
}

/// Every handle with its world position.
pub fn handles(scene: &Scene) -> Vec<(HandleId, DVec3)> {
    let s = &scene.sources;
    let reach = DIRECTION_REACH * (scene.camera.target - scene.camera.eye).length();
    let mut v = Vec::new();
    v.extend(
        s.points
            .iter()
            .enumerate()
            .map(|(i, p)| (HandleId::Point(i), p.position)),
    );
    for (i, l) in s.lines.iter().enumerate() {
        v.push((HandleId::LinePoint(i), l.point));
        v.push((HandleId::LineDirection(i), l.point + l.direction * reach));
    }
    for (i, t) in s.tori.iter().enumerate() {
        v.push((HandleId::TorusCenter(i), t.center));
        v.push((
            HandleId::TorusRadius(i),
            t.center + ring_direction(t.axis) * t.major_radius,
        ));
        v.push((
            HandleId::TorusAxis(i),
            t.center + t.axis * t.major_radius * AXIS_REACH,
        ));
    }
    for (c, curve) in s.curves.iter().enumerate() {
        v.extend(
            curve
                .control_points
                .iter()
                .enumerate()
                .map(|(k, &p)| (HandleId::Control { curve: c, index: k }, p)),
        );
    }
    v.extend((scene.objects.iter().enumerate()).map(|(i, o)| (HandleId::Object(i), o.center())));
    v
}

/// The world position of a handle, if it still exists.
pub fn get(scene: &Scene, id: HandleId) -> Option<DVec3> {
    handles(scene)
        .into_iter()
        .find(|(h, _)| *h == id)
        .map(|(_, p)| p)
}

/// The edit that puts an object's handle at `q`: the object moved there. `None` for a source's handle (`edit`)
/// or an object that no longer exists.
pub fn object_edit(scene: &Scene, id: HandleId, q: DVec3) -> Option<crate::viewer::action::Edit> {
    let i = id.object()?;
    let moved = scene.objects.get(i)?.moved_to(q);
    Some(crate::viewer::action::Edit::SetObject(i, moved))
}

/// The edit that puts handle `id` at `q`: a position moves there; a direction handle turns its line or torus
/// toward `q`; a radius handle sets the ring through `q`'s distance from the axis. `None` where `q` says no
/// direction (on the anchor) or the handle no longer exists.
pub fn edit(scene: &Scene, id: HandleId, q: DVec3) -> Option<(Parameter, Value)> {
    let s = &scene.sources;
    let toward = |from: DVec3| {
        let d = q - from;
        (d.length() > 1e-9).then(|| Value::Vector(d.normalize().to_array()))
    };
    Some(match id {
        HandleId::Point(i) => (
            Parameter::Position(SourceKind::Points, i),
            Value::Vector(q.to_array()),
        ),
        HandleId::LinePoint(i) => (
            Parameter::Position(SourceKind::Lines, i),
            Value::Vector(q.to_array()),
        ),
        HandleId::TorusCenter(i) => (
            Parameter::Position(SourceKind::Tori, i),
            Value::Vector(q.to_array()),
        ),
        HandleId::Control { curve, index } => (
            Parameter::ControlPoint(curve, index),
            Value::Vector(q.to_array()),
        ),
        HandleId::LineDirection(i) => (
            Parameter::Direction(SourceKind::Lines, i),
            toward(s.lines.get(i)?.point)?,
        ),
        HandleId::TorusAxis(i) => (
            Parameter::Direction(SourceKind::Tori, i),
            toward(s.tori.get(i)?.center)?,
        ),
        HandleId::TorusRadius(i) => {
            let t = s.tori.get(i)?;
            let d = q - t.center;
            let in_plane = d - t.axis * d.dot(t.axis);
            (
                Parameter::MajorRadius(i),
                Value::Number(in_plane.length().max(1e-3)),
            )
        }
        HandleId::Object(_) => return None,
    })
}

/// Projects a world point into `rect` (egui points), or `None` behind the eye.
pub fn to_screen(camera: &Camera, rect: Rect, p: DVec3) -> Option<Pos2> {
    let f = camera.frame();
    let d = p - camera.eye;
    let depth = d.dot(f.forward);
    if depth <= 1e-9 {
        return None;
    }
    let t = camera.tan_half_fov();
    let aspect = (rect.width() / rect.height().max(1.0)) as f64;
    let ndc_x = d.dot(f.right) / (depth * t * aspect);
    let ndc_y = d.dot(f.up) / (depth * t);
    Some(Pos2::new(
        rect.min.x + ((ndc_x + 1.0) * 0.5) as f32 * rect.width(),
        rect.min.y + ((1.0 - ndc_y) * 0.5) as f32 * rect.height(),
    ))
}

/// The world direction (unit) of the ray through a screen position in `rect`.
pub fn screen_ray(camera: &Camera, rect: Rect, pos: Pos2) -> DVec3 {
    let f = camera.frame();
    let t = camera.tan_half_fov();
    let aspect = (rect.width() / rect.height().max(1.0)) as f64;
    let ndc_x = ((pos.x - rect.min.x) / rect.width().max(1.0) * 2.0 - 1.0) as f64;
    let ndc_y = (1.0 - (pos.y - rect.min.y) / rect.height().max(1.0) * 2.0) as f64;
    (f.forward + f.right * (ndc_x * t * aspect) + f.up * (ndc_y * t)).normalize()
}

/// The handles within `GRAB_RADIUS` of `pointer`, nearest to the eye first (then nearest the pointer): where
/// handles overlap on screen, the one in front comes first, and a second click goes on to the next.
pub fn pick_all(scene: &Scene, rect: Rect, pointer: Pos2) -> Vec<HandleId> {
    let f = scene.camera.frame();
    let mut near: Vec<(HandleId, f64, f32)> = handles(scene)
        .into_iter()
        .filter_map(|(id, p)| {
            let s = to_screen(&scene.camera, rect, p)?;
            let d = s.distance(pointer);
            (d <= GRAB_RADIUS).then(|| (id, (p - scene.camera.eye).dot(f.forward), d))
        })
        .collect();
    // Depths within a thousandth of the nearer count as equal: then the pointer decides.
    near.sort_by(|a, b| {
        let tie = (a.1 - b.1).abs() <= 1e-3 * a.1.abs().max(b.1.abs());
        if tie {
            a.2.total_cmp(&b.2)
        } else {
            a.1.total_cmp(&b.1)
        }
    });
    near.into_iter().map(|(id, ..)| id).collect()
}

/// The handle in front under `pointer`, if any.
pub fn pick(scene: &Scene, rect: Rect, pointer: Pos2) -> Option<HandleId> {
    pick_all(scene, rect, pointer).into_iter().next()
}

/// Where a point `p` goes when dragged by `delta` (egui points) in a viewport `height` points tall: it moves
/// in the plane through it parallel to the image, following the pointer.
pub fn drag_in_view_plane(camera: &Camera, height: f32, p: DVec3, delta: Vec2) -> DVec3 {
    let f = camera.frame();
    let depth = (p - camera.eye).dot(f.forward).max(1e-9);
    let per_point = 2.0 * depth * camera.tan_half_fov() / height.max(1.0) as f64;
    p + (f.right * delta.x as f64 - f.up * delta.y as f64) * per_point
}

// Guides are thin and translucent (premultiplied colors), so the glow reads through them: a curve's guide lies
// on its core.
const CURVE: Color32 = Color32::from_rgba_premultiplied(60, 60, 64, 64);
const GUIDE: Color32 = Color32::from_rgba_premultiplied(40, 40, 48, 56);
const HANDLE: Color32 = Color32::from_rgb(255, 205, 60);
const ACTIVE: Color32 = Color32::from_rgb(255, 120, 40);
/// The selected source's handles' rings.
const SELECTED: Color32 = Color32::from_rgb(120, 200, 255);
/// Its guides: the same blue, translucent.
const SELECTED_GUIDE: Color32 = Color32::from_rgba_premultiplied(52, 86, 110, 110);

/// Draws every source's guides and handles; `highlight` is the hovered or dragged handle, `selected` the
/// selected source (its guides drawn brighter, its handles ringed).
pub fn draw(
    painter: &egui::Painter,
    rect: Rect,
    scene: &Scene,
    highlight: Option<HandleId>,
    selected: Option<(SourceKind, usize)>,
    selected_object: Option<usize>,
) {
    let cam = &scene.camera;
    let screen = |p: DVec3| to_screen(cam, rect, p);
    let polyline = |points: &[DVec3], stroke: Stroke| {
        for w in points.windows(2) {
            if let (Some(a), Some(b)) = (screen(w[0]), screen(w[1])) {
                painter.line_segment([a, b], stroke);
            }
        }
    };
    let stroke = |kind: SourceKind, i: usize, width: f32, color: Color32| {
        if selected == Some((kind, i)) {
            Stroke::new(width + 0.5, SELECTED_GUIDE)
        } else {
            Stroke::new(width, color)
        }
    };
    let view_distance = (cam.target - cam.eye).length();
    for (i, l) in scene.sources.lines.iter().enumerate() {
        let reach = l.direction * view_distance * 0.25;
        polyline(
            &[l.point - reach, l.point + reach],
            stroke(SourceKind::Lines, i, 1.0, GUIDE),
        );
        // An arrow along the direction, to its handle.
        if let (Some(a), Some(b)) = (screen(l.point), screen(l.point + reach * 0.5)) {
            painter.arrow(a, b - a, stroke(SourceKind::Lines, i, 1.5, CURVE));
        }
    }
    for (i, t) in scene.sources.tori.iter().enumerate() {
        let e1 = ring_direction(t.axis);
        let e2 = t.axis.cross(e1);
        let circle: Vec<DVec3> = (0..=64)
            .map(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                t.center + t.major_radius * (a.cos() * e1 + a.sin() * e2)
            })
            .collect();
        polyline(&circle, stroke(SourceKind::Tori, i, 1.0, CURVE));
        polyline(
            &[t.center, t.center + t.axis * t.major_radius * AXIS_REACH],
            stroke(SourceKind::Tori, i, 1.0, GUIDE),
        );
    }
    for (i, c) in scene.sources.curves.iter().enumerate() {
        let samples: Vec<DVec3> = segments(&c.control_points)
            .flat_map(|s| (0..24).map(move |k| s.at(k as f64 / 24.0)))
            .chain(c.control_points.last().copied())
            .collect();
        polyline(&samples, stroke(SourceKind::Curves, i, 1.0, CURVE));
        polyline(&c.control_points, stroke(SourceKind::Curves, i, 1.0, GUIDE));
    }
    for (id, p) in handles(scene) {
        if let Some(s) = screen(p) {
            let active = highlight == Some(id);
            let radius = if active { 6.0 } else { 4.5 };
            let fill = if active { ACTIVE } else { HANDLE };
            let chosen = match id.object() {
                Some(i) => selected_object == Some(i),
                None => selected.is_some() && selected == id.source(),
            };
            let outline = if chosen {
                Stroke::new(2.0, SELECTED)
            } else {
                Stroke::new(1.0, Color32::BLACK)
            };
            if id.object().is_some() {
                // Objects: diamonds.
                let r = radius * 1.3;
                let diamond = vec![
                    s + Vec2::new(0.0, -r),
                    s + Vec2::new(r, 0.0),
                    s + Vec2::new(0.0, r),
                    s + Vec2::new(-r, 0.0),
                ];
                painter.add(egui::Shape::convex_polygon(diamond, fill, outline));
            } else if id.is_position() {
                painter.circle(s, radius, fill, outline);
            } else {
                // Directions and sizes: squares.
                let r = egui::Rect::from_center_size(s, Vec2::splat(radius * 1.6));
                painter.rect(r, 1.0, fill, outline, egui::StrokeKind::Middle);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_and_rays_agree_with_the_camera() {
        let scene = Scene::default_scene();
        let rect = Rect::from_min_size(Pos2::new(100.0, 20.0), Vec2::new(400.0, 300.0));
        let p = DVec3::new(1.0, 0.5, -0.3);
        let s = to_screen(&scene.camera, rect, p).unwrap();
        // The same point through the camera's own pixel projection, shifted by the rect's origin.
        let (x, y) = scene.camera.project(p, 400, 300).unwrap();
        assert!((s.x - 100.0 - x as f32).abs() < 1e-3 && (s.y - 20.0 - y as f32).abs() < 1e-3);
        let ray = screen_ray(&scene.camera, rect, s);
        assert!(ray.dot((p - scene.camera.eye).normalize()) > 1.0 - 1e-9);
    }

    #[test]
    fn dragging_follows_the_pointer_in_the_view_plane() {
        let scene = Scene::default_scene();
        let rect = Rect::from_min_size(Pos2::ZERO, Vec2::new(640.0, 480.0));
        let id = HandleId::Control { curve: 0, index: 1 };
        let p = get(&scene, id).unwrap();
        let before = to_screen(&scene.camera, rect, p).unwrap();
        let delta = Vec2::new(37.0, -12.0);
        let q = drag_in_view_plane(&scene.camera, rect.height(), p, delta);
        let after = to_screen(&scene.camera, rect, q).unwrap();
        assert!(
            (after - before - delta).length() < 1e-2,
            "{before:?} -> {after:?}"
        );
        // Same depth: it moved in the view plane.
        let f = scene.camera.frame();
        assert!(((q - p).dot(f.forward)).abs() < 1e-9);
        // Picking finds it where it is drawn, and its edit moves it.
        assert_eq!(pick(&scene, rect, before + Vec2::new(2.0, 1.0)), Some(id));
        let mut edited = scene.clone();
        let (parameter, value) = edit(&scene, id, q).unwrap();
        parameter.set(&mut edited, value);
        assert_eq!(get(&edited, id), Some(q));
    }

    #[test]
    fn a_handle_left_where_it_is_edits_nothing_and_moved_it_edits_its_source() {
        let scene = Scene::parse(
            include_str!("../../assets/scenes/mixed.toml"),
            std::path::Path::new("mixed.toml"),
        )
        .unwrap();
        let all = handles(&scene);
        for kind in [
            "Point",
            "LinePoint",
            "LineDirection",
            "TorusCenter",
            "TorusRadius",
            "TorusAxis",
            "Control",
        ] {
            assert!(
                all.iter()
                    .any(|(id, _)| format!("{id:?}").starts_with(kind)),
                "the scene has a {kind} handle"
            );
        }
        let close = |a: &Scene, b: &Scene| {
            let (x, y) = (a.to_toml(), b.to_toml());
            let nums = |t: &str| -> Vec<f64> {
                t.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
                    .filter_map(|w| w.parse().ok())
                    .collect()
            };
            nums(&x)
                .iter()
                .zip(nums(&y))
                .all(|(p, q)| (p - q).abs() < 1e-9)
        };
        for (id, p) in &all {
            // Put back where it is: the scene as it was.
            let (parameter, value) = edit(&scene, *id, *p).unwrap();
            let mut same = scene.clone();
            parameter.set(&mut same, value);
            assert!(close(&same, &scene), "{id:?}");
            // Moved: the handle follows to where it was put (a direction's and a radius's handle onto its
            // guide), and no other source changes.
            let q = *p + DVec3::new(0.3, 0.2, -0.1);
            let (parameter, value) = edit(&scene, *id, q).unwrap();
            let mut moved = scene.clone();
            parameter.set(&mut moved, value);
            let now = get(&moved, *id).unwrap();
            if id.is_position() {
                assert!((now - q).length() < 1e-12, "{id:?}");
            } else {
                assert!((now - *p).length() > 1e-3, "{id:?} moved");
            }
            let (kind, i) = id.source().unwrap();
            let mut others = moved.clone();
            match kind {
                SourceKind::Points => others.sources.points[i] = scene.sources.points[i].clone(),
                SourceKind::Lines => others.sources.lines[i] = scene.sources.lines[i].clone(),
                SourceKind::Tori => others.sources.tori[i] = scene.sources.tori[i].clone(),
                SourceKind::Curves => others.sources.curves[i] = scene.sources.curves[i].clone(),
            }
            assert_eq!(others, scene, "{id:?} changed only its source");
        }
        // A radius handle dragged out along the ring doubles the radius.
        let t = &scene.sources.tori[0];
        let out = t.center + ring_direction(t.axis) * 2.0 * t.major_radius;
        assert_eq!(
            edit(&scene, HandleId::TorusRadius(0), out),
            Some((
                Parameter::MajorRadius(0),
                Value::Number(2.0 * t.major_radius)
            ))
        );
    }

    #[test]
    fn overlapping_handles_are_picked_nearest_the_eye_first() {
        let mut scene = Scene::default_scene();
        let rect = Rect::from_min_size(Pos2::ZERO, Vec2::new(640.0, 480.0));
        // A point straight behind the torus's center, and one straight in front.
        let f = scene.camera.frame();
        let center = scene.sources.tori[0].center;
        for d in [2.0, -2.0] {
            scene.sources.points.push(crate::field::Point {
                position: center + f.forward * d,
                coefficient: 1.0,
                look: Default::default(),
            });
        }
        let at = to_screen(&scene.camera, rect, center).unwrap();
        let picked = pick_all(&scene, rect, at);
        assert_eq!(picked.first(), Some(&HandleId::Point(1)), "{picked:?}");
        assert_eq!(picked.last(), Some(&HandleId::Point(0)), "{picked:?}");
        assert!(picked.contains(&HandleId::TorusCenter(0)));
        assert!(picked.contains(&HandleId::Control { curve: 0, index: 2 }));
    }
}
