//! The object pass's f64 twin (`shaders/objects.wgsl`): the objects' lit triangles (`objects::lit`) ray-cast
//! from the eye and shaded at the hit as the fragment shader shades a pixel: the vertices' albedo, shadow
//! factor and normal interpolated as the rasterizer interpolates them (perspective-correct interpolation is the
//! barycentric weights of the point the pixel's ray meets), the direct light evaluated at the hit itself
//! (`objects::lighting::shaded`).

use glam::DVec3;

use crate::frame::FrameSetup;
use crate::objects::Lit;
use crate::objects::lighting::{Lights, shaded, shaded_translucent};
use crate::objects::mesh::{MeshData, triangle_barycentric};

/// The lit triangles of a scene, with a hierarchy for the pixels' rays and the sources that light them.
pub struct ObjectImage {
    lit: std::sync::Arc<Lit>,
    mesh: MeshData,
    /// The opaque objects' triangles alone, where some object is translucent: what ends the glow.
    opaque: Option<MeshData>,
    lights: Lights,
}

impl ObjectImage {
    /// The objects of `setup`'s frame, lit as it resolves them (`FrameSetup::objects`, the GPU's light to the
    /// bit); none where the scene has no objects.
    pub fn of(setup: &FrameSetup) -> Option<ObjectImage> {
        let scene = setup.scene;
        let lit = setup.objects()?;
        let p = &lit.surface.positions;
        let triangles: Vec<[DVec3; 3]> = (lit.surface.indices.chunks_exact(3))
            .map(|t| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]])
            .collect();
        let translucent = |t: &[u32]| {
            let o = lit.surface.object[t[0] as usize] as usize;
            scene.objects[o].translucent.is_some()
        };
        let opaque = scene
            .objects
            .iter()
            .any(|o| o.translucent.is_some())
            .then(|| {
                let kept = (lit.surface.indices.chunks_exact(3).zip(&triangles))
                    .filter(|(t, _)| !translucent(t))
                    .map(|(_, tri)| *tri)
                    .collect();
                MeshData::new(kept)
            });
        Some(ObjectImage {
            mesh: MeshData::new(triangles),
            opaque,
            lit,
            lights: Lights::new(
                &scene.sources,
                scene.colors.palette(),
                scene.integration.epsilon,
            ),
        })
    }

    /// Where (in units of `dir`) the ray from `eye` along `dir` first meets an opaque object's triangle: where
    /// its glow ends (the translucent objects let it through).
    pub fn hit_opaque(&self, eye: DVec3, dir: DVec3) -> Option<f64> {
        match &self.opaque {
            Some(mesh) => mesh.hit(eye, dir, 0.0, f64::INFINITY),
            None => self.mesh.hit(eye, dir, 0.0, f64::INFINITY),
        }
    }

    /// Where (in units of `dir`) the ray from `eye` along `dir` first meets a triangle, and its lit color there.
    pub fn hit(&self, eye: DVec3, dir: DVec3) -> Option<(f64, [f64; 3])> {
        self.hit_surface(eye, dir).map(|(t, color, _)| (t, color))
    }

    /// `hit`, and whether the surface met is a translucent object's.
    pub fn hit_surface(&self, eye: DVec3, dir: DVec3) -> Option<(f64, [f64; 3], bool)> {
        let (t, k) = self.mesh.hit_triangle(eye, dir, 0.0, f64::INFINITY)?;
        let corners = &self.lit.surface.indices[3 * k..3 * k + 3];
        let (_, w) = triangle_barycentric(&self.mesh.triangles[k], eye, dir)?;
        let mix = |value: &dyn Fn(usize) -> [f64; 3]| -> [f64; 3] {
            let v = |i: usize| value(corners[i] as usize);
            std::array::from_fn(|c| w[0] * v(0)[c] + w[1] * v(1)[c] + w[2] * v(2)[c])
        };
        let normals = &self.lit.surface.normals;
        let n = (0..3)
            .map(|i| normals[corners[i] as usize] * w[i])
            .sum::<DVec3>()
            .normalize_or_zero();
        let light = &self.lit.light;
        let eta = light.eta[corners[0] as usize];
        if eta > 0.0 {
            // A translucent object: its scattered light through the exit's Fresnel toward the eye.
            let cos_view = match n != DVec3::ZERO {
                true => n.dot(-dir.normalize()).abs(),
                false => 1.0,
            };
            let subsurface = mix(&|k| light.subsurface[k]);
            let color = shaded_translucent(mix(&|k| light.albedo[k]), subsurface, eta, cos_view);
            return Some((t, color, true));
        }
        let direct = self.lights.direct(eye + dir * t, n);
        let shadow = [0, 1].map(|s| mix(&|k| light.shadow[k][s]));
        Some((t, shaded(mix(&|k| light.albedo[k]), shadow, direct), false))
    }
}
