//! Handles of the sources in the viewport, drawn with egui's painter over the 3D view: points, line anchors and
//! directions, torus circles and centers, curve polylines, control polygons and control points. Every handle
//! can be dragged in the view plane.

use egui::{Color32, Pos2, Rect, Stroke, Vec2};
use glam::DVec3;

use crate::animation::{Parameter, SourceKind};
use crate::field::curve::segments;
use crate::geometry::Camera;
use crate::scene::Scene;

/// A draggable point of a source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleId {
    Point(usize),
    LinePoint(usize),
    TorusCenter(usize),
    Control { curve: usize, index: usize },
}

/// How close (in points) the pointer must be to grab a handle.
pub const GRAB_RADIUS: f32 = 9.0;

/// Every handle with its world position.
pub fn handles(scene: &Scene) -> Vec<(HandleId, DVec3)> {
    let s = &scene.sources;
    let mut v = Vec::new();
    v.extend(
        s.points
            .iter()
            .enumerate()
            .map(|(i, p)| (HandleId::Point(i), p.position)),
    );
    v.extend(
        s.lines
            .iter()
            .enumerate()
            .map(|(i, l)| (HandleId::LinePoint(i), l.point)),
    );
    v.extend(
        s.tori
            .iter()
            .enumerate()
            .map(|(i, t)| (HandleId::TorusCenter(i), t.center)),
    );
    for (c, curve) in s.curves.iter().enumerate() {
        v.extend(
            curve
                .control_points
                .iter()
                .enumerate()
                .map(|(k, &p)| (HandleId::Control { curve: c, index: k }, p)),
        );
    }
    v
}

/// The world position of a handle, if it still exists.
pub fn get(scene: &Scene, id: HandleId) -> Option<DVec3> {
    let s = &scene.sources;
    match id {
        HandleId::Point(i) => s.points.get(i).map(|p| p.position),
        HandleId::LinePoint(i) => s.lines.get(i).map(|l| l.point),
        HandleId::TorusCenter(i) => s.tori.get(i).map(|t| t.center),
        HandleId::Control { curve, index } => s
            .curves
            .get(curve)
            .and_then(|c| c.control_points.get(index))
            .copied(),
    }
}

impl HandleId {
    /// The scene parameter the handle moves: dragging it is an edit of that parameter.
    pub fn parameter(self) -> Parameter {
        match self {
            HandleId::Point(i) => Parameter::Position(SourceKind::Points, i),
            HandleId::LinePoint(i) => Parameter::Position(SourceKind::Lines, i),
            HandleId::TorusCenter(i) => Parameter::Position(SourceKind::Tori, i),
            HandleId::Control { curve, index } => Parameter::ControlPoint(curve, index),
        }
    }
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

/// The handle nearest to `pointer` within `GRAB_RADIUS`, if any.
pub fn pick(scene: &Scene, rect: Rect, pointer: Pos2) -> Option<HandleId> {
    handles(scene)
        .into_iter()
        .filter_map(|(id, p)| to_screen(&scene.camera, rect, p).map(|s| (id, s.distance(pointer))))
        .filter(|(_, d)| *d <= GRAB_RADIUS)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(id, _)| id)
}

/// Where a point `p` goes when dragged by `delta` (egui points) in a viewport `height` points tall: it moves
/// in the plane through it parallel to the image, following the pointer.
pub fn drag_in_view_plane(camera: &Camera, height: f32, p: DVec3, delta: Vec2) -> DVec3 {
    let f = camera.frame();
    let depth = (p - camera.eye).dot(f.forward).max(1e-9);
    let per_point = 2.0 * depth * camera.tan_half_fov() / height.max(1.0) as f64;
    p + (f.right * delta.x as f64 - f.up * delta.y as f64) * per_point
}

const CURVE: Color32 = Color32::from_rgba_premultiplied(230, 230, 240, 150);
const GUIDE: Color32 = Color32::from_rgba_premultiplied(150, 150, 170, 110);
const HANDLE: Color32 = Color32::from_rgb(255, 205, 60);
const ACTIVE: Color32 = Color32::from_rgb(255, 120, 40);

/// Draws every source's guides and handles; `highlight` is the hovered or dragged handle.
pub fn draw(painter: &egui::Painter, rect: Rect, scene: &Scene, highlight: Option<HandleId>) {
    let cam = &scene.camera;
    let screen = |p: DVec3| to_screen(cam, rect, p);
    let polyline = |points: &[DVec3], stroke: Stroke| {
        for w in points.windows(2) {
            if let (Some(a), Some(b)) = (screen(w[0]), screen(w[1])) {
                painter.line_segment([a, b], stroke);
            }
        }
    };
    let view_distance = (cam.target - cam.eye).length();
    for l in &scene.sources.lines {
        let reach = l.direction * view_distance * 0.25;
        polyline(&[l.point - reach, l.point + reach], Stroke::new(1.0, GUIDE));
        // An arrow along the direction.
        if let (Some(a), Some(b)) = (screen(l.point), screen(l.point + reach * 0.5)) {
            painter.arrow(a, b - a, Stroke::new(1.5, CURVE));
        }
    }
    for t in &scene.sources.tori {
        let e1 = t.axis.any_orthonormal_vector();
        let e2 = t.axis.cross(e1);
        let circle: Vec<DVec3> = (0..=64)
            .map(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                t.center + t.major_radius * (a.cos() * e1 + a.sin() * e2)
            })
            .collect();
        polyline(&circle, Stroke::new(1.0, CURVE));
        polyline(
            &[t.center, t.center + t.axis * t.major_radius * 0.5],
            Stroke::new(1.0, GUIDE),
        );
    }
    for c in &scene.sources.curves {
        let samples: Vec<DVec3> = segments(&c.control_points)
            .flat_map(|s| (0..24).map(move |k| s.at(k as f64 / 24.0)))
            .chain(c.control_points.last().copied())
            .collect();
        polyline(&samples, Stroke::new(1.5, CURVE));
        polyline(&c.control_points, Stroke::new(1.0, GUIDE));
    }
    for (id, p) in handles(scene) {
        if let Some(s) = screen(p) {
            let active = highlight == Some(id);
            let radius = if active { 6.0 } else { 4.5 };
            let fill = if active { ACTIVE } else { HANDLE };
            painter.circle(s, radius, fill, Stroke::new(1.0, Color32::BLACK));
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
        // Picking finds it where it is drawn, and an edit of its parameter moves it.
        assert_eq!(pick(&scene, rect, before + Vec2::new(2.0, 1.0)), Some(id));
        let mut edited = scene.clone();
        id.parameter()
            .set(&mut edited, crate::animation::Value::Vector(q.to_array()));
        assert_eq!(get(&edited, id), Some(q));
    }

    #[test]
    fn every_handle_names_the_parameter_it_moves() {
        let scene = Scene::parse(
            include_str!("../../assets/scenes/mixed.toml"),
            std::path::Path::new("mixed.toml"),
        )
        .unwrap();
        let all = handles(&scene);
        for kind in ["Point", "LinePoint", "TorusCenter", "Control"] {
            assert!(
                all.iter()
                    .any(|(id, _)| format!("{id:?}").starts_with(kind)),
                "the scene has a {kind} handle"
            );
        }
        for (id, p) in all {
            assert_eq!(
                id.parameter().get(&scene),
                Some(crate::animation::Value::Vector(p.to_array())),
                "{id:?}"
            );
        }
    }
}
