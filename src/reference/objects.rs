//! The object pass's f64 twin (`shaders/objects.wgsl`): the objects' lit triangles (`objects::lit`) ray-cast
//! from the eye, the vertex colors interpolated at the hit as the rasterizer interpolates them (perspective-
//! correct interpolation is the barycentric weights of the point the pixel's ray meets).

use glam::DVec3;

use crate::objects::mesh::{MeshData, triangle_barycentric};
use crate::objects::{Lit, lit};
use crate::scene::Scene;

/// The lit triangles of a scene, with a hierarchy for the pixels' rays.
pub struct ObjectImage {
    lit: Lit,
    mesh: MeshData,
}

impl ObjectImage {
    /// None where the scene has no objects.
    pub fn of(scene: &Scene) -> Option<ObjectImage> {
        if scene.objects.is_empty() {
            return None;
        }
        let lit = lit(scene);
        let p = &lit.surface.positions;
        let triangles = (lit.surface.indices.chunks_exact(3))
            .map(|t| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]])
            .collect();
        Some(ObjectImage {
            mesh: MeshData::new(triangles),
            lit,
        })
    }

    /// Where (in units of `dir`) the ray from `eye` along `dir` first meets a triangle, and its lit color there.
    pub fn hit(&self, eye: DVec3, dir: DVec3) -> Option<(f64, [f64; 3])> {
        let (t, k) = self.mesh.hit_triangle(eye, dir, 0.0, f64::INFINITY)?;
        let corners = &self.lit.surface.indices[3 * k..3 * k + 3];
        let (_, w) = triangle_barycentric(&self.mesh.triangles[k], eye, dir)?;
        let c = |i: usize| self.lit.colors[corners[i] as usize];
        Some((
            t,
            std::array::from_fn(|ch| w[0] * c(0)[ch] + w[1] * c(1)[ch] + w[2] * c(2)[ch]),
        ))
    }
}
