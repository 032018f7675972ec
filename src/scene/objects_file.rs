//! `[[objects]]` in scene files: each shape's keys checked with located errors, meshes read from their glTF
//! files, and the objects written back as they were given.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use super::checker::Checker;
use super::file::{FieldPath, ObjectFile, SceneFile, ValueFile};
use crate::objects::{MeshData, MeshObject, Object, Shape, ShapeKind};

/// The kinds a file may name, in the order the messages list them.
const KINDS: [ShapeKind; 4] = [
    ShapeKind::Sphere,
    ShapeKind::Box,
    ShapeKind::Plane,
    ShapeKind::Mesh,
];

/// Which keys each shape takes besides `shape` and `color`.
fn keys_of(kind: ShapeKind) -> &'static [&'static str] {
    match kind {
        ShapeKind::Sphere => &["center", "radius"],
        ShapeKind::Box => &["center", "size", "rotation"],
        ShapeKind::Plane => &["point", "normal", "size"],
        ShapeKind::Mesh => &["path", "translation", "rotation", "scale"],
    }
}

/// The objects of the file; `base` is the scene file's folder, against which a mesh's relative path is read.
pub(super) fn check_objects(c: &mut Checker<'_, '_>, file: &SceneFile, base: &Path) -> Vec<Object> {
    let root = FieldPath::default().key("objects");
    let mut out = Vec::new();
    for (i, o) in file.objects.iter().enumerate() {
        let path = root.index(i);
        let Some(kind) = KINDS.into_iter().find(|k| k.name() == o.shape) else {
            c.fail(
                &path.key("shape"),
                format!(
                    "\"{}\" is not a shape: one of \"sphere\", \"box\", \"plane\", \"mesh\"",
                    o.shape
                ),
            );
            continue;
        };
        let given: [(&'static str, bool); 10] = [
            ("center", o.center.is_some()),
            ("radius", o.radius.is_some()),
            ("size", o.size.is_some()),
            ("rotation", o.rotation.is_some()),
            ("point", o.point.is_some()),
            ("normal", o.normal.is_some()),
            ("path", o.path.is_some()),
            ("translation", o.translation.is_some()),
            ("scale", o.scale.is_some()),
            ("color", o.color.is_some()),
        ];
        let allowed = keys_of(kind);
        for (key, present) in given {
            if present && key != "color" && !allowed.contains(&key) {
                c.fail(
                    &path.key(key),
                    format!(
                        "a {} has no {key} (its keys: {}, color)",
                        kind.name(),
                        allowed.join(", ")
                    ),
                );
            }
        }
        let given_color = o.color.map(|a| c.color(&path.key("color"), a));
        let shape = match kind {
            ShapeKind::Sphere => {
                let center = o
                    .center
                    .map_or(DVec3::ZERO, |a| c.position(&path.key("center"), a));
                let radius = required(c, &path, "radius", o.radius);
                c.positive(&path.key("radius"), radius, "a sphere's radius");
                Shape::Sphere { center, radius }
            }
            ShapeKind::Box => {
                let center = o
                    .center
                    .map_or(DVec3::ZERO, |a| c.position(&path.key("center"), a));
                let size = match &o.size {
                    None => {
                        c.fail(&path, "a box needs its size: [x, y, z], its side lengths");
                        DVec3::ONE
                    }
                    Some(v) => c.lengths(&path.key("size"), v, "a box's side lengths"),
                };
                let rotation = o
                    .rotation
                    .map_or(DVec3::ZERO, |a| angles(c, &path.key("rotation"), a));
                Shape::Box {
                    center,
                    size,
                    rotation,
                }
            }
            ShapeKind::Plane => {
                let point = o
                    .point
                    .map_or(DVec3::ZERO, |a| c.position(&path.key("point"), a));
                let normal = match o.normal {
                    Some(a) => c.direction(&path.key("normal"), a),
                    None => DVec3::Y,
                };
                let size = match &o.size {
                    None => None,
                    Some(ValueFile::Number(x)) => {
                        c.positive(&path.key("size"), *x, "a finite plane's side length");
                        Some(*x)
                    }
                    Some(ValueFile::Vector(_)) => {
                        c.fail(&path.key("size"), "a plane's size is one number: the side of its square (leave it out for an infinite plane)");
                        None
                    }
                };
                Shape::Plane {
                    point,
                    normal,
                    size,
                }
            }
            ShapeKind::Mesh => {
                let translation = o
                    .translation
                    .map_or(DVec3::ZERO, |a| c.position(&path.key("translation"), a));
                let rotation = o
                    .rotation
                    .map_or(DVec3::ZERO, |a| angles(c, &path.key("rotation"), a));
                let scale = match &o.scale {
                    None => DVec3::ONE,
                    Some(v) => c.lengths(&path.key("scale"), v, "a mesh's scale"),
                };
                let Some(file_path) = &o.path else {
                    c.fail(
                        &path,
                        "a mesh needs its path: a glTF 2.0 file (.gltf or .glb)",
                    );
                    continue;
                };
                let written = PathBuf::from(file_path);
                let full = if written.is_absolute() {
                    written.clone()
                } else {
                    base.join(&written)
                };
                match MeshData::load(&full) {
                    Ok(data) => Shape::Mesh(MeshObject {
                        path: written,
                        translation,
                        rotation,
                        scale,
                        data: Arc::new(data),
                    }),
                    Err(e) => {
                        c.fail(&path.key("path"), format!("{}: {e}", full.display()));
                        continue;
                    }
                }
            }
        };
        // A mesh whose file gives its materials' base colors takes them as they are (a mesh made in Blender
        // looks as it did there); `color` tints them.
        let color = given_color.unwrap_or(match &shape {
            Shape::Mesh(m) if !m.data.base_colors.is_empty() => [1.0; 3],
            _ => DEFAULT_ALBEDO,
        });
        let mut object = Object {
            shape,
            color,
            translucent: None,
        };
        if let Some(t) = &o.translucent {
            object.translucent =
                super::translucent_file::check(c, &path.key("translucent"), t, &object);
        }
        out.push(object);
    }
    out
}

/// An object's albedo where the file gives none: a light grey, lit to white by a source of coefficient 1 at
/// distance 1 seen head on.
pub const DEFAULT_ALBEDO: [f64; 3] = [0.8, 0.8, 0.8];

fn required(c: &mut Checker<'_, '_>, path: &FieldPath, key: &'static str, x: Option<f64>) -> f64 {
    match x {
        Some(x) => x,
        None => {
            c.fail(path, format!("missing {key}"));
            1.0
        }
    }
}

/// Rotation angles in degrees, finite.
fn angles(c: &mut Checker<'_, '_>, path: &FieldPath, a: [f64; 3]) -> DVec3 {
    let v = c.vector(path, a);
    if v.abs().max_element() > 1e6 {
        c.fail(
            path,
            format!("{a:?}: rotation angles are in degrees, within +-1e6"),
        );
        return DVec3::ZERO;
    }
    v
}

/// The objects as the file writes them: every key of each shape, the mesh's path as it was given.
pub(super) fn write(objects: &[Object]) -> Vec<ObjectFile> {
    let v = |p: DVec3| Some(p.to_array());
    let vector = |p: DVec3| Some(ValueFile::Vector(p.to_array().to_vec()));
    objects
        .iter()
        .map(|o| {
            let mut f = ObjectFile {
                shape: o.kind().name().to_owned(),
                color: Some(o.color),
                translucent: o.translucent.as_deref().map(super::translucent_file::write),
                ..ObjectFile::default()
            };
            match &o.shape {
                Shape::Sphere { center, radius } => {
                    f.center = v(*center);
                    f.radius = Some(*radius);
                }
                Shape::Box {
                    center,
                    size,
                    rotation,
                } => {
                    f.center = v(*center);
                    f.size = vector(*size);
                    f.rotation = v(*rotation);
                }
                Shape::Plane {
                    point,
                    normal,
                    size,
                } => {
                    f.point = v(*point);
                    f.normal = v(*normal);
                    f.size = size.map(ValueFile::Number);
                }
                Shape::Mesh(m) => {
                    f.path = Some(m.path.to_string_lossy().into_owned());
                    f.translation = v(m.translation);
                    f.rotation = v(m.rotation);
                    f.scale = vector(m.scale);
                }
            }
            f
        })
        .collect()
}
