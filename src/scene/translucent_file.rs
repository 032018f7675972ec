//! `[objects.translucent]` in scene files: a translucent material checked with located errors (an object with
//! no inside, a mesh that is not closed, a resolution whose table would not fit), and written back as given.

use glam::DVec3;

use super::checker::Checker;
use super::file::{FieldPath, InnerFile, NoiseFile, TranslucentFile, ValueFile};
use crate::objects::translucent::voxels::{VoxelError, resolution_of};
use crate::objects::translucent::{Inner, InnerShape, MAX_RESOLUTION, Noise, Translucent};
use crate::objects::{Object, Shape};

/// The largest extinction a file may give, per unit of length: past it an object is opaque to every digit.
pub const MAX_EXTINCTION: f64 = 1e4;

/// The material of `[objects.translucent]` at `path`, for `object` (its shape already checked): `None` where
/// it is wrong (the problems noted).
pub(super) fn check(
    c: &mut Checker<'_, '_>,
    path: &FieldPath,
    file: &TranslucentFile,
    object: &Object,
) -> Option<Box<Translucent>> {
    let errors = c.problem_count();
    let defaults = Translucent::default();
    let extinction = match file.extinction {
        Some(x) => extinction(c, &path.key("extinction"), x),
        None => defaults.extinction,
    };
    let eta = match file.eta {
        Some(x) => {
            let p = path.key("eta");
            if c.finite(&p, x) && !(x > 0.0 && x <= 10.0) {
                c.fail(&p, format!("{x} is out of range: the relative index of refraction is in (0, 10] (ice 1.31, glass 1.5)"));
            }
            x
        }
        None => defaults.eta,
    };
    let resolution = match file.resolution {
        Some(r) if !(2..=MAX_RESOLUTION as i64).contains(&r) => {
            c.fail(
                &path.key("resolution"),
                format!("{r} is out of range: voxels along the object's longest side, 2 to {MAX_RESOLUTION}"),
            );
            None
        }
        r => r.map(|r| r as u32),
    };
    let inner = file
        .inner
        .as_ref()
        .and_then(|f| inner(c, &path.key("inner"), f));
    let noise = file.noise.as_ref().map(|f| noise(c, &path.key("noise"), f));
    match &object.shape {
        Shape::Plane { .. } => {
            c.fail(
                path,
                "a plane has no inside: only a sphere, a box or a closed mesh can be translucent",
            );
            return None;
        }
        Shape::Mesh(m) => {
            let open = m.data.open_edges();
            if open > 0 {
                c.fail(
                    path,
                    format!(
                        "the mesh {} is not closed ({open} edges do not join two triangles): it has no inside to \
                         fill; close its holes (Blender: Select > All by Trait > Non Manifold, then Fill)",
                        m.path.display()
                    ),
                );
                return None;
            }
        }
        _ => {}
    }
    if c.problem_count() > errors {
        return None;
    }
    let material = Box::new(Translucent {
        extinction,
        eta,
        inner,
        noise,
        resolution,
    });
    let placed = Object {
        translucent: Some(material.clone()),
        ..object.clone()
    };
    match resolution_of(&placed) {
        Ok(_) => Some(material),
        Err(e @ VoxelError::TooLarge { .. }) => {
            c.fail(&path.key("resolution"), e.to_string());
            None
        }
        Err(e) => {
            c.fail(path, e.to_string());
            None
        }
    }
}

fn extinction(c: &mut Checker<'_, '_>, path: &FieldPath, x: f64) -> f64 {
    if c.finite(path, x) && !(0.0..=MAX_EXTINCTION).contains(&x) {
        c.fail(
            path,
            format!("{x} is out of range: an extinction is per unit of length, 0 (clear) to {MAX_EXTINCTION}"),
        );
    }
    x
}

fn inner(c: &mut Checker<'_, '_>, path: &FieldPath, f: &InnerFile) -> Option<Inner> {
    let center = f
        .center
        .map_or(DVec3::ZERO, |a| c.position(&path.key("center"), a));
    let x = match f.extinction {
        Some(x) => extinction(c, &path.key("extinction"), x),
        None => 0.0,
    };
    let shape = match f.shape.as_str() {
        "sphere" => {
            if f.size.is_some() {
                c.fail(
                    &path.key("size"),
                    "an inner sphere has no size (its keys: center, radius, extinction)",
                );
            }
            let Some(radius) = f.radius else {
                c.fail(path, "missing radius");
                return None;
            };
            c.positive(&path.key("radius"), radius, "an inner sphere's radius");
            InnerShape::Sphere { center, radius }
        }
        "box" => {
            if f.radius.is_some() {
                c.fail(
                    &path.key("radius"),
                    "an inner box has no radius (its keys: center, size, extinction)",
                );
            }
            let Some(size) = &f.size else {
                c.fail(
                    &path.key("size"),
                    "an inner box needs its size: [x, y, z] or one number",
                );
                return None;
            };
            let size = c.lengths(&path.key("size"), size, "an inner box's side lengths");
            InnerShape::Box { center, size }
        }
        other => {
            c.fail(
                &path.key("shape"),
                format!("\"{other}\" is not an inner shape: \"sphere\" or \"box\""),
            );
            return None;
        }
    };
    Some(Inner {
        shape,
        extinction: x,
    })
}

fn noise(c: &mut Checker<'_, '_>, path: &FieldPath, f: &NoiseFile) -> Noise {
    let scale = f.scale.unwrap_or(0.25);
    c.positive(&path.key("scale"), scale, "a noise's scale");
    let amount = f.amount.unwrap_or(0.5);
    let p = path.key("amount");
    if c.finite(&p, amount) && !(0.0..=4.0).contains(&amount) {
        c.fail(
            &p,
            format!("{amount} is out of range: a noise's amount is 0 to 4"),
        );
    }
    Noise {
        scale,
        amount,
        seed: f.seed.unwrap_or(1),
    }
}

/// The material as the file writes it.
pub(super) fn write(t: &Translucent) -> TranslucentFile {
    TranslucentFile {
        extinction: Some(t.extinction),
        eta: Some(t.eta),
        resolution: t.resolution.map(i64::from),
        inner: t.inner.as_ref().map(|i| match &i.shape {
            InnerShape::Sphere { center, radius } => InnerFile {
                shape: "sphere".into(),
                center: Some(center.to_array()),
                radius: Some(*radius),
                size: None,
                extinction: Some(i.extinction),
            },
            InnerShape::Box { center, size } => InnerFile {
                shape: "box".into(),
                center: Some(center.to_array()),
                radius: None,
                size: Some(ValueFile::Vector(size.to_array().to_vec())),
                extinction: Some(i.extinction),
            },
        }),
        noise: t.noise.as_ref().map(|n| NoiseFile {
            scale: Some(n.scale),
            amount: Some(n.amount),
            seed: Some(n.seed),
        }),
    }
}
