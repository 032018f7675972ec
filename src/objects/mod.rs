//! Objects in a scene: spheres, boxes, planes and glTF meshes that hide the glow behind them and are lit by it
//! (thesis 6.2: hidden-surface removal against the rest of the scene, and lighting with shadows).
//!
//! - every texel's integral runs from S only to the first surface its ray meets (`clip`): the exact,
//!   closed-form hit of each shape (a mesh's triangles through a bounding-volume hierarchy, `mesh`);
//! - objects are drawn as triangles (`tessellate`) and lit at every pixel by every source (`lighting`): the
//!   shadows are worked out at the vertices in f64 on the CPU, where they do not depend on the camera (orbiting
//!   never casts them again), and the direct light at every pixel, by the field's own functions;
//! - the GPU draws them with depth behind the billboard (`gpu::object_pass`), the CPU twin ray-casts the same
//!   triangles (`reference::objects`).

pub mod clip;
pub mod lighting;
pub mod mesh;
pub mod tessellate;
pub mod translucent;

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DMat3, DVec3};

pub use mesh::MeshData;

/// An object of the scene: a shape and its albedo.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    /// The albedo, each channel in 0..1: the share of the light that reaches it that the surface sends back.
    /// For a translucent object, the tint of the light it scatters.
    pub color: [f64; 3],
    /// A translucent material (`translucent`): light enters, is carried through the inside and leaves
    /// elsewhere; `None` for an opaque surface.
    pub translucent: Option<Box<translucent::Translucent>>,
}

/// The shapes an object takes.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// A box of side lengths `size` around `center`, turned by `rotation` (`rotation_matrix`).
    Box {
        center: DVec3,
        size: DVec3,
        rotation: DVec3,
    },
    /// The plane through `point` across the unit `normal`: infinite, or a square of side `size` around `point`
    /// (its edges along `plane_axes`).
    Plane {
        point: DVec3,
        normal: DVec3,
        size: Option<f64>,
    },
    Mesh(MeshObject),
}

/// A triangle mesh read from a glTF 2.0 file, placed by `translation`, `rotation` and `scale` (applied in the
/// order scale, rotation, translation, after the transforms of the file's own nodes).
#[derive(Clone, Debug)]
pub struct MeshObject {
    /// The path as the scene file gives it (relative to the scene file's folder, or absolute).
    pub path: PathBuf,
    pub translation: DVec3,
    /// Degrees about x, then y, then z (`rotation_matrix`).
    pub rotation: DVec3,
    pub scale: DVec3,
    /// The file's triangles, shared by the copies of a scene.
    pub data: Arc<MeshData>,
}

/// The kinds of shape, as scene files and the viewer name them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeKind {
    Sphere,
    Box,
    Plane,
    Mesh,
}

impl ShapeKind {
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Box => "box",
            ShapeKind::Plane => "plane",
            ShapeKind::Mesh => "mesh",
        }
    }
}

/// The rotation of `degrees` about x, then y, then z (world axes): `Rz Ry Rx`.
pub fn rotation_matrix(degrees: DVec3) -> DMat3 {
    // Most objects are not rotated: no sines to work out for every ray that meets them.
    if degrees == DVec3::ZERO {
        return DMat3::IDENTITY;
    }
    let r = degrees * (std::f64::consts::PI / 180.0);
    DMat3::from_rotation_z(r.z) * DMat3::from_rotation_y(r.y) * DMat3::from_rotation_x(r.x)
}

/// Two unit axes in a plane across the unit `normal`, with it a right-handed frame: the edges of a finite plane.
/// The first lies in the world's x-z plane where it can (a floor's edges run along x and z).
pub fn plane_axes(normal: DVec3) -> (DVec3, DVec3) {
    let helper = if normal.y.abs() < 0.9 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let u = helper.cross(normal).normalize();
    (u, normal.cross(u))
}

/// Rays that start this close to a surface (in units of the scene's scale) do not hit it again: shadow rays
/// leave from the lit surface itself.
const SELF_HIT: f64 = 1e-9;

impl Object {
    pub fn kind(&self) -> ShapeKind {
        match self.shape {
            Shape::Sphere { .. } => ShapeKind::Sphere,
            Shape::Box { .. } => ShapeKind::Box,
            Shape::Plane { .. } => ShapeKind::Plane,
            Shape::Mesh(_) => ShapeKind::Mesh,
        }
    }

    /// Where the viewer puts the object's handle: its center (a plane's point, a mesh's translation).
    pub fn center(&self) -> DVec3 {
        match &self.shape {
            Shape::Sphere { center, .. } | Shape::Box { center, .. } => *center,
            Shape::Plane { point, .. } => *point,
            Shape::Mesh(m) => m.translation,
        }
    }

    /// Whether `p` lies inside the object (a plane has no inside): a mesh's by the parity of its surface's
    /// crossings along a ray (a closed mesh's; an open one's as far as that holds).
    pub fn contains(&self, p: DVec3) -> bool {
        match &self.shape {
            Shape::Sphere { center, radius } => (p - *center).length_squared() < radius * radius,
            Shape::Box {
                center,
                size,
                rotation,
            } => {
                let q = rotation_matrix(*rotation).transpose() * (p - *center);
                q.abs().cmplt(*size * 0.5).all()
            }
            Shape::Plane { .. } => false,
            Shape::Mesh(m) => {
                let (inverse, _) = m.inverse();
                m.data.contains(inverse * (p - m.translation))
            }
        }
    }

    /// The object's frame: its center and its rotation (a sphere's none), in which a translucent object's inner
    /// region is placed.
    pub fn frame(&self) -> (DVec3, DMat3) {
        match &self.shape {
            Shape::Sphere { center, .. } => (*center, DMat3::IDENTITY),
            Shape::Box {
                center, rotation, ..
            } => (*center, rotation_matrix(*rotation)),
            Shape::Plane { point, .. } => (*point, DMat3::IDENTITY),
            Shape::Mesh(m) => (m.translation, rotation_matrix(m.rotation)),
        }
    }

    /// The object's axis-aligned bounds in the world: none for a plane.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        match &self.shape {
            Shape::Sphere { center, radius } => Some((*center - *radius, *center + *radius)),
            Shape::Box {
                center,
                size,
                rotation,
            } => {
                let r = rotation_matrix(*rotation);
                let half =
                    (r.x_axis.abs() * size.x + r.y_axis.abs() * size.y + r.z_axis.abs() * size.z)
                        * 0.5;
                Some((*center - half, *center + half))
            }
            Shape::Plane { .. } => None,
            Shape::Mesh(m) => {
                let (_, forward) = m.inverse();
                let mut lo = DVec3::INFINITY;
                let mut hi = DVec3::NEG_INFINITY;
                for t in &m.data.triangles {
                    for p in t {
                        let w = forward * *p + m.translation;
                        lo = lo.min(w);
                        hi = hi.max(w);
                    }
                }
                (lo.cmple(hi).all()).then_some((lo, hi))
            }
        }
    }

    /// The object moved so that its center is at `to`.
    pub fn moved_to(&self, to: DVec3) -> Object {
        let mut out = self.clone();
        match &mut out.shape {
            Shape::Sphere { center, .. } | Shape::Box { center, .. } => *center = to,
            Shape::Plane { point, .. } => *point = to,
            Shape::Mesh(m) => m.translation = to,
        }
        out
    }

    /// The smallest `t` in `(t_min, t_max)` where `origin + t dir` meets the object's surface, both faces
    /// counting: from inside a sphere or a box, its far wall. `dir` need not be of unit length; `t` is in its
    /// units.
    pub fn hit(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        let t = match &self.shape {
            Shape::Sphere { center, radius } => sphere_hit(origin - *center, dir, *radius, t_min),
            Shape::Box {
                center,
                size,
                rotation,
            } => {
                let r = rotation_matrix(*rotation).transpose();
                box_hit(r * (origin - *center), r * dir, *size * 0.5, t_min)
            }
            Shape::Plane {
                point,
                normal,
                size,
            } => plane_hit(origin, dir, *point, *normal, *size, t_min),
            Shape::Mesh(m) => {
                let (inverse, _) = m.inverse();
                let o = inverse * (origin - m.translation);
                let d = inverse * dir;
                m.data.hit(o, d, t_min, t_max)
            }
        }?;
        (t > t_min && t < t_max).then_some(t)
    }
}

impl PartialEq for MeshObject {
    /// The same file placed alike; its triangles compared only where they are not shared (every frame compares
    /// the scene with the last one's).
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path
            && self.translation == other.translation
            && self.rotation == other.rotation
            && self.scale == other.scale
            && (Arc::ptr_eq(&self.data, &other.data) || self.data == other.data)
    }
}

impl MeshObject {
    /// The model matrix's linear part `R S` and its inverse: (inverse, forward).
    pub fn inverse(&self) -> (DMat3, DMat3) {
        let forward = rotation_matrix(self.rotation) * DMat3::from_diagonal(self.scale);
        (forward.inverse(), forward)
    }
}

/// The first hit of `origin + t dir` on the sphere of `radius` around the origin past `t_min`: the roots of
/// `|o + t d|^2 = r^2`, the near one where it is past `t_min`, else the far one. The roots in the stable form
/// (q = -(b + sign(b) sqrt(disc)), t = q / a and c / q), so that a ray far from a small sphere keeps its digits.
pub fn sphere_hit(o: DVec3, d: DVec3, radius: f64, t_min: f64) -> Option<f64> {
    let a = d.length_squared();
    let half_b = o.dot(d);
    // The discriminant from the ray's closest approach, not b^2 - ac: its cancellation would lose a grazing hit.
    let closest = o - d * (half_b / a);
    let disc = a * (radius * radius - closest.length_squared());
    if a.is_nan() || a <= 0.0 || disc < 0.0 {
        return None;
    }
    let q = -(half_b + half_b.signum() * disc.sqrt());
    let c = o.length_squared() - radius * radius;
    let (t0, t1) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        let (x, y) = (q / a, c / q);
        (x.min(y), x.max(y))
    };
    [t0, t1].into_iter().find(|&t| t > t_min)
}

/// The first hit past `t_min` of `o + t d` on the axis-aligned box of half sides `half` around the origin
/// (slabs): its entry where that is past `t_min`, else its exit.
pub fn box_hit(o: DVec3, d: DVec3, half: DVec3, t_min: f64) -> Option<f64> {
    let mut near = f64::NEG_INFINITY;
    let mut far = f64::INFINITY;
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k].abs() > half[k] {
                return None;
            }
            continue;
        }
        let a = (-half[k] - o[k]) / d[k];
        let b = (half[k] - o[k]) / d[k];
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    if near > far {
        return None;
    }
    [near, far].into_iter().find(|&t| t > t_min)
}

/// The hit past `t_min` of `o + t d` on the plane through `point` across `normal`, inside the square of side
/// `size` around `point` where it is finite.
pub fn plane_hit(
    o: DVec3,
    d: DVec3,
    point: DVec3,
    normal: DVec3,
    size: Option<f64>,
    t_min: f64,
) -> Option<f64> {
    let denom = normal.dot(d);
    if denom == 0.0 {
        return None;
    }
    let t = normal.dot(point - o) / denom;
    if t.is_nan() || t <= t_min || !t.is_finite() {
        return None;
    }
    if let Some(size) = size {
        let (u, v) = plane_axes(normal);
        let q = o + d * t - point;
        if q.dot(u).abs() > size * 0.5 || q.dot(v).abs() > size * 0.5 {
            return None;
        }
    }
    Some(t)
}

/// The first hit of `origin + t dir` past `t_min` and before `t_max` among `objects`: the object's index and t.
pub fn first_hit(
    objects: &[Object],
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (i, o) in objects.iter().enumerate() {
        let limit = best.map_or(t_max, |b| b.1);
        if let Some(t) = o.hit(origin, dir, t_min, limit) {
            best = Some((i, t));
        }
    }
    best
}

/// Whether some object lies on the segment from `from` to `to` (a shadow ray), its ends excluded: `from` is a
/// point of a lit surface, which its own surface must not shadow.
pub fn blocked(objects: &[Object], from: DVec3, to: DVec3) -> bool {
    let d = to - from;
    let scale = 1.0 + from.abs().max_element().max(to.abs().max_element());
    let skip = SELF_HIT * scale / d.length().max(1e-300);
    objects
        .iter()
        .any(|o| o.hit(from, d, skip, 1.0 - skip).is_some())
}

/// Whether an opaque object among `objects` crosses the segment `from -> to` (`blocked` without the
/// translucent ones, which dim the light that crosses them instead).
pub fn blocked_by_opaque(objects: &[Object], from: DVec3, to: DVec3) -> bool {
    let d = to - from;
    let scale = 1.0 + from.abs().max_element().max(to.abs().max_element());
    let skip = SELF_HIT * scale / d.length().max(1e-300);
    (objects.iter())
        .filter(|o| o.translucent.is_none())
        .any(|o| o.hit(from, d, skip, 1.0 - skip).is_some())
}

/// The share of light from `from` that reaches `to` past `objects`: none where an opaque object crosses the
/// segment, else the light the translucent ones it crosses let through (`translucent::transmittance`: the
/// Fresnel transmittance at each surface, `exp(-tau)` through the medium). The ends' own surfaces are left out,
/// as `blocked` leaves them.
pub fn passes(objects: &[Object], from: DVec3, to: DVec3) -> f64 {
    if blocked_by_opaque(objects, from, to) {
        return 0.0;
    }
    if objects.iter().all(|o| o.translucent.is_none()) {
        return 1.0;
    }
    let d = to - from;
    let scale = 1.0 + from.abs().max_element().max(to.abs().max_element());
    let skip = SELF_HIT * scale / d.length().max(1e-300);
    translucent::transmittance(objects, from + d * skip, to - d * skip)
}

/// The objects' triangles with their vertices' light (albedo, shadow factor and lit color): what the GPU draws
/// and the CPU twin ray-casts, both shading every pixel from them (`lighting::shaded`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lit {
    pub surface: tessellate::Surface,
    pub light: lighting::VertexLights,
}

/// What lights a scene's objects: they, the sources, the colors those take and the field's eps
/// (`scene::Scene::lit_inputs`).
#[derive(Clone, Copy, Debug)]
pub struct LitInputs<'a> {
    pub objects: &'a [Object],
    pub sources: &'a crate::field::Sources,
    pub palette: crate::field::Palette,
    pub epsilon: f64,
}

/// What the objects' look depends on: they are lit again only when one of these changes (not as the camera
/// moves).
#[derive(Clone, Debug, PartialEq)]
pub struct LitKey {
    objects: Vec<Object>,
    sources: crate::field::Sources,
    palette: crate::field::Palette,
    epsilon: f64,
}

impl LitKey {
    pub fn of(inputs: LitInputs<'_>) -> LitKey {
        LitKey {
            objects: inputs.objects.to_vec(),
            sources: inputs.sources.clone(),
            palette: inputs.palette,
            epsilon: inputs.epsilon,
        }
    }

    /// Whether `inputs` differ from these at most in the objects' colors: the same surface, shadows and light
    /// carried through (which the colors do not change), only the albedo new (`Lit::recolored`).
    pub fn matches_but_colors(&self, inputs: LitInputs<'_>) -> bool {
        let uncolored = |o: &Object| Object {
            color: [0.0; 3],
            ..o.clone()
        };
        self.sources == *inputs.sources
            && self.palette == inputs.palette
            && self.epsilon == inputs.epsilon
            && self.objects.len() == inputs.objects.len()
            && (self.objects.iter().zip(inputs.objects)).all(|(a, b)| uncolored(a) == uncolored(b))
    }

    /// Whether `inputs` would light the objects the same, without cloning them.
    pub fn matches(&self, inputs: LitInputs<'_>) -> bool {
        self.objects == inputs.objects
            && self.sources == *inputs.sources
            && self.palette == inputs.palette
            && self.epsilon == inputs.epsilon
    }
}

/// The effect's center and size, where an infinite plane's disc is centered and how fine it starts: the
/// sources' bounding box (the origin and 1 without sources). Independent of the camera.
pub fn focus(sources: &crate::field::Sources) -> (DVec3, f64) {
    match sources.bounds() {
        Some((lo, hi)) => ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(0.1)),
        None => (DVec3::ZERO, 1.0),
    }
}

impl Lit {
    /// This light with the objects' colors of `objects` (the same objects otherwise, `LitKey::matches_but_colors`):
    /// each vertex's albedo its object's new color times its tint, as `lit` makes it, and its lit color scaled
    /// along (exactly, except in a channel whose old albedo was 0, which keeps the ambient part alone). The
    /// shadows and the light scattered through translucent objects do not depend on the colors.
    pub fn recolored(&self, objects: &[Object]) -> Lit {
        let surface = &self.surface;
        let old = &self.light;
        let albedo: Vec<[f64; 3]> = (0..old.albedo.len())
            .map(|k| {
                let color = objects[surface.object[k] as usize].color;
                std::array::from_fn(|c| color[c] * surface.tint[k][c])
            })
            .collect();
        let colors = (0..albedo.len())
            .map(|k| match old.eta[k] > 0.0 {
                true => lighting::shaded_translucent(albedo[k], old.subsurface[k], old.eta[k], 1.0),
                false => std::array::from_fn(|c| match old.albedo[k][c] != 0.0 {
                    true => old.colors[k][c] * albedo[k][c] / old.albedo[k][c],
                    false => albedo[k][c] * lighting::AMBIENT,
                }),
            })
            .collect();
        Lit {
            surface: surface.clone(),
            light: lighting::VertexLights {
                albedo,
                shadow: old.shadow.clone(),
                colors,
                subsurface: old.subsurface.clone(),
                eta: old.eta.clone(),
            },
        }
    }
}

/// The objects tessellated, unshadowed and without their translucent light (`lighting::unshadowed`): the
/// moment's stand-in for `lit`, quick to work out.
pub fn unshadowed(inputs: LitInputs<'_>) -> Lit {
    let (center, extent) = focus(inputs.sources);
    let surface = tessellate::Surface::of(inputs.objects, center, extent);
    let light = lighting::unshadowed(&surface, inputs.objects);
    Lit { surface, light }
}

/// Where the translucent objects' voxels and tables come from: a renderer's frame cache
/// (`frame::FrameCache`), which keeps them and fills the tables on a real GPU where it has one.
pub trait Tables: Sync {
    /// `object`'s voxels and table (`translucent::light::prepare`); none for an opaque object.
    fn translucent(&self, object: &Object) -> Option<std::sync::Arc<translucent::light::Prepared>>;
}

/// The objects tessellated and lit, finer where a shadow's edge crosses them; the translucent ones' voxels and
/// tables from `tables`.
pub fn lit(inputs: LitInputs<'_>, tables: &dyn Tables) -> Lit {
    let (center, extent) = focus(inputs.sources);
    let mut surface = tessellate::Surface::of(inputs.objects, center, extent);
    let lights = lighting::Lights::new(inputs.sources, inputs.palette, inputs.epsilon);
    // The translucent objects' light, carried through them from their surface voxels.
    let scattered: Vec<Option<translucent::light::Scattered>> = (inputs.objects.iter())
        .map(|o| {
            let prepared = tables.translucent(o)?;
            translucent::light::Scattered::of(o, prepared, &lights, inputs.objects)
        })
        .collect();
    let light = lighting::light_surface(&mut surface, inputs.objects, &lights, &|o, x, n| {
        scattered[o].as_ref().map_or([0.0; 3], |s| s.at(x, n))
    });
    Lit { surface, light }
}

impl Lit {
    /// The bytes it holds, for a cache's memory bound.
    pub fn bytes(&self) -> usize {
        let (s, l) = (&self.surface, &self.light);
        size_of_val(&s.positions[..])
            + size_of_val(&s.normals[..])
            + size_of_val(&s.object[..])
            + size_of_val(&s.tint[..])
            + size_of_val(&s.indices[..])
            + size_of_val(&l.albedo[..])
            + size_of_val(&l.shadow[..])
            + size_of_val(&l.colors[..])
            + size_of_val(&l.subsurface[..])
            + size_of_val(&l.eta[..])
    }
}
