//! Objects as the triangles the GPU draws and the CPU twin ray-casts: positions, normals (the lit side) and
//! indices, in world space.

use glam::DVec3;

use super::{Object, Shape, plane_axes, rotation_matrix};

/// Triangles sharing vertices: what is drawn, and where the shadows are worked out (once a vertex; the light
/// itself is evaluated at every pixel).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    /// The object each vertex belongs to (its index in the scene), for its albedo.
    pub object: Vec<u32>,
    /// What each vertex's albedo is, times its object's color: a glTF mesh's base color there, else 1.
    pub tint: Vec<[f64; 3]>,
    pub indices: Vec<u32>,
}

/// Quads a side of a sphere's longitude and latitude: its outline within 0.1 % of its radius (1 - cos(pi / 64)).
const SPHERE_SLICES: u32 = 64;
const SPHERE_STACKS: u32 = 32;
/// Cells along each edge of a box's face and of a finite plane: the shadows are read at their corners (and
/// where a shadow's edge crosses, finer). The light is shaded at every pixel, so the cells need not follow it:
/// halving the planes' cells and rings (from 96, 96 x 256) lit the floor preset in 43 ms instead of 122 ms
/// with its picture within 10/255 (78 pixels of 960 x 600 off by more than 3/255, along the shadow).
const BOX_CELLS: u32 = 16;
const PLANE_CELLS: u32 = 48;
/// An infinite plane is drawn as a disc of rings around the effect's foot on it, from `INNER` to `OUTER` times
/// the effect's size, spaced geometrically (fine near the effect, where shadows fall, coarse far away).
const PLANE_RINGS: u32 = 48;
const PLANE_SEGMENTS: u32 = 128;
const INNER: f64 = 0.02;
const OUTER: f64 = 500.0;

impl Surface {
    fn vertex(&mut self, p: DVec3, n: DVec3, object: u32) -> u32 {
        self.tinted_vertex(p, n, object, [1.0; 3])
    }

    fn tinted_vertex(&mut self, p: DVec3, n: DVec3, object: u32, tint: [f64; 3]) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        self.object.push(object);
        self.tint.push(tint);
        self.positions.len() as u32 - 1
    }

    /// A grid of `(nu + 1) x (nv + 1)` vertices `at(i, j)` with normals `normal(i, j)`, two triangles a cell,
    /// wound counter-clockwise seen from the normal's side.
    fn grid(
        &mut self,
        (nu, nv): (u32, u32),
        object: u32,
        at: impl Fn(u32, u32) -> DVec3,
        normal: impl Fn(u32, u32) -> DVec3,
    ) {
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                self.vertex(at(i, j), normal(i, j), object);
            }
        }
        let k = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                self.indices.extend([
                    k(i, j),
                    k(i + 1, j),
                    k(i + 1, j + 1),
                    k(i, j),
                    k(i + 1, j + 1),
                    k(i, j + 1),
                ]);
            }
        }
    }

    /// The triangles of every object; `focus` and `extent` place and size an infinite plane's disc (the effect's
    /// center and size).
    pub fn of(objects: &[Object], focus: DVec3, extent: f64) -> Surface {
        let mut s = Surface::default();
        for (k, o) in objects.iter().enumerate() {
            s.add(o, k as u32, focus, extent);
        }
        s
    }

    fn add(&mut self, object: &Object, k: u32, focus: DVec3, extent: f64) {
        use std::f64::consts::{PI, TAU};
        match &object.shape {
            Shape::Sphere { center, radius } => {
                let dir = |i: u32, j: u32| {
                    // The seam's two columns at one place (sin(2 pi) is not 0).
                    let phi = TAU * (i % SPHERE_SLICES) as f64 / SPHERE_SLICES as f64;
                    let theta = PI * j as f64 / SPHERE_STACKS as f64;
                    // From the north pole (+y) down, counter-clockwise seen from outside.
                    DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.cos(),
                        theta.sin() * phi.sin(),
                    )
                };
                self.grid(
                    (SPHERE_SLICES, SPHERE_STACKS),
                    k,
                    |i, j| *center + dir(i, j) * *radius,
                    dir,
                );
            }
            Shape::Box {
                center,
                size,
                rotation,
            } => {
                let r = rotation_matrix(*rotation);
                let half = *size * 0.5;
                // Each face: its normal axis and sign, and the two axes spanning it (u x v along the normal).
                for (axis, sign) in [
                    (0, 1.0),
                    (0, -1.0),
                    (1, 1.0),
                    (1, -1.0),
                    (2, 1.0),
                    (2, -1.0),
                ] {
                    let n = DVec3::AXES[axis] * sign;
                    let u = DVec3::AXES[(axis + 1) % 3] * sign;
                    let v = n.cross(u);
                    let (hu, hv) = (u.abs().dot(half), v.abs().dot(half));
                    let at = |i: u32, j: u32| {
                        let a = (i as f64 / BOX_CELLS as f64 * 2.0 - 1.0) * hu;
                        let b = (j as f64 / BOX_CELLS as f64 * 2.0 - 1.0) * hv;
                        *center + r * (n * n.abs().dot(half) + u * a + v * b)
                    };
                    let world_n = r * n;
                    self.grid((BOX_CELLS, BOX_CELLS), k, at, |_, _| world_n);
                }
            }
            Shape::Plane {
                point,
                normal,
                size,
            } => {
                let (u, v) = plane_axes(*normal);
                match size {
                    Some(size) => {
                        let at = |i: u32, j: u32| {
                            let a = (i as f64 / PLANE_CELLS as f64 - 0.5) * size;
                            let b = (j as f64 / PLANE_CELLS as f64 - 0.5) * size;
                            *point + u * a + v * b
                        };
                        self.grid((PLANE_CELLS, PLANE_CELLS), k, at, |_, _| *normal);
                    }
                    None => {
                        // The effect's foot on the plane, and rings around it.
                        let foot = focus - *normal * normal.dot(focus - *point);
                        let extent = extent.max(1e-3);
                        let radius = |j: u32| {
                            if j == 0 {
                                0.0
                            } else {
                                let x = (j - 1) as f64 / (PLANE_RINGS - 1) as f64;
                                extent * INNER * (OUTER / INNER).powf(x)
                            }
                        };
                        let at = |i: u32, j: u32| {
                            let a = TAU * (i % PLANE_SEGMENTS) as f64 / PLANE_SEGMENTS as f64;
                            foot + (u * a.cos() + v * a.sin()) * radius(j)
                        };
                        // Rings outward: u x v is the normal, so (i, j) runs counter-clockwise seen from it
                        // with the grid's winding reversed; swap to keep the normal's side the front.
                        let base = self.positions.len() as u32;
                        self.grid((PLANE_SEGMENTS, PLANE_RINGS), k, at, |_, _| *normal);
                        flip(&mut self.indices, base);
                    }
                }
            }
            Shape::Mesh(m) => {
                let (_, forward) = m.inverse();
                let normal_matrix = forward.inverse().transpose();
                for (j, t) in m.data.triangles.iter().enumerate() {
                    let p = t.map(|p| forward * p + m.translation);
                    let face =
                        (normal_matrix * (t[1] - t[0]).cross(t[2] - t[0])).normalize_or_zero();
                    // The file's normals where it has them (smooth shading), turned as the mesh is; the
                    // face's where it has none or one is degenerate.
                    let normals = m.data.normals.get(j).copied();
                    let tint = m.data.base_colors.get(j).copied().unwrap_or([1.0; 3]);
                    let i: [u32; 3] = std::array::from_fn(|c| {
                        let n = normals
                            .map(|n| (normal_matrix * n[c]).normalize_or_zero())
                            .filter(|n| *n != DVec3::ZERO)
                            .unwrap_or(face);
                        self.tinted_vertex(p[c], n, k, tint)
                    });
                    self.indices.extend(i);
                }
            }
        }
    }
}

/// Reverses the winding of every triangle whose vertices start at `base`.
fn flip(indices: &mut [u32], base: u32) {
    for t in indices.chunks_exact_mut(3) {
        if t[0] >= base {
            t.swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn objects() -> Vec<Object> {
        let color = [0.5; 3];
        vec![
            Object {
                shape: Shape::Sphere {
                    center: DVec3::new(1.0, 2.0, 3.0),
                    radius: 0.5,
                },
                color,
                translucent: None,
            },
            Object {
                shape: Shape::Box {
                    center: DVec3::ZERO,
                    size: DVec3::new(1.0, 2.0, 3.0),
                    rotation: DVec3::new(10.0, 20.0, 30.0),
                },
                color,
                translucent: None,
            },
            Object {
                shape: Shape::Plane {
                    point: DVec3::new(0.0, -1.0, 0.0),
                    normal: DVec3::Y,
                    size: None,
                },
                color,
                translucent: None,
            },
            Object {
                shape: Shape::Plane {
                    point: DVec3::new(0.0, -1.0, 0.0),
                    normal: DVec3::new(0.0, 0.6, 0.8),
                    size: Some(4.0),
                },
                color,
                translucent: None,
            },
        ]
    }

    #[test]
    fn every_vertex_lies_on_its_shape_and_every_triangle_faces_its_normal() {
        let objects = objects();
        let s = Surface::of(&objects, DVec3::ZERO, 2.0);
        for t in s.indices.chunks_exact(3) {
            let p: [DVec3; 3] = std::array::from_fn(|i| s.positions[t[i] as usize]);
            let face = (p[1] - p[0]).cross(p[2] - p[0]);
            if face.length() < 1e-12 {
                continue; // the sphere's poles
            }
            let n = s.normals[t[0] as usize] + s.normals[t[1] as usize] + s.normals[t[2] as usize];
            assert!(
                face.dot(n) > 0.0,
                "a triangle of object {} faces away",
                s.object[t[0] as usize]
            );
        }
        for (k, p) in s.positions.iter().enumerate() {
            let o = &objects[s.object[k] as usize];
            let n = s.normals[k];
            // A ray from just outside along -n meets the surface at the vertex (a box's or a square's a hair
            // toward its center, off the edges, where rounding may pass either side).
            let inward = match o.kind() {
                crate::objects::ShapeKind::Sphere => DVec3::ZERO,
                _ => {
                    let c = o.center() - *p;
                    let across = c - n * n.dot(c);
                    if across.length() > 1e-9 {
                        across.normalize() * 1e-6
                    } else {
                        DVec3::ZERO
                    }
                }
            };
            let from = *p + inward + n * 1e-3;
            let t = o
                .hit(from, -n, 0.0, 1.0)
                .expect("the vertex is on the surface");
            assert!(
                (t - 1e-3).abs() < 1e-9,
                "object {}: {t} at {p} normal {n} inward {inward}",
                s.object[k]
            );
        }
    }
}
