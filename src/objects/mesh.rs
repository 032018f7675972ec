//! Triangle meshes from glTF 2.0 files (`.gltf` with its buffers, or `.glb`), through the `gltf` crate, and
//! their ray hits through a bounding-volume hierarchy.

use std::path::Path;

use glam::{DMat4, DVec3};

/// A mesh's triangles in its own space (the file's node transforms applied), with a bounding-volume hierarchy
/// over them for ray hits.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshData {
    pub triangles: Vec<[DVec3; 3]>,
    /// Each triangle's corner normals from the file (node transforms applied), where it has them: smooth
    /// shading. Empty, or one entry a triangle.
    pub normals: Vec<[DVec3; 3]>,
    /// Each triangle's base color (its material's `baseColorFactor`, as display values: sRGB-encoded like every
    /// color of a scene), which the object's color multiplies into its albedo. Empty, or one a triangle.
    pub base_colors: Vec<[f64; 3]>,
    nodes: Vec<Node>,
    /// Triangle indices in the order the leaves list them.
    order: Vec<u32>,
}

/// A node of the hierarchy: its box, and either its two children or a range of `order`.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaves: the first index into `order` and the count; inner nodes: the children's indices and 0.
    first: u32,
    second: u32,
    leaf: bool,
}

/// What reading a glTF file can fail on, for the scene's error message.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("cannot read it as glTF 2.0: {0}")]
    Gltf(#[from] gltf::Error),
    #[error("it has no triangles (a mesh needs at least one triangle primitive)")]
    Empty,
    #[error("it has {0} triangles, more than the {1} a mesh may have")]
    TooLarge(usize, usize),
    #[error("a position is not a finite number")]
    NotFinite,
}

/// The most triangles a mesh may have: its hits and its lighting are computed on the CPU.
pub const MAX_TRIANGLES: usize = 1 << 20;

const LEAF_SIZE: usize = 4;

impl MeshData {
    /// Reads every triangle primitive of the file's default scene (or of its first), node transforms applied.
    pub fn load(path: &Path) -> Result<MeshData, MeshError> {
        let (document, buffers, _images) = gltf::import(path).or_else(|e| match e {
            // Images are of no use here: a file whose textures are missing still gives its geometry.
            gltf::Error::Image(_) | gltf::Error::UnsupportedImageEncoding => {
                let gltf = gltf::Gltf::open(path)?;
                let base = path.parent().unwrap_or(Path::new("."));
                let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())?;
                Ok((gltf.document, buffers, Vec::new()))
            }
            e => Err(e),
        })?;
        let mut triangles = Vec::new();
        let mut normals: Vec<Option<[DVec3; 3]>> = Vec::new();
        let mut base_colors = Vec::new();
        let mut materials = false;
        let scene = document
            .default_scene()
            .or_else(|| document.scenes().next());
        let mut stack: Vec<(gltf::Node<'_>, DMat4)> = match &scene {
            Some(s) => s.nodes().map(|n| (n, DMat4::IDENTITY)).collect(),
            None => Vec::new(),
        };
        while let Some((node, parent)) = stack.pop() {
            let local =
                DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
            let world = parent * local;
            let normal_world = glam::DMat3::from_mat4(world).inverse().transpose();
            if let Some(mesh) = node.mesh() {
                for primitive in mesh.primitives() {
                    if primitive.mode() != gltf::mesh::Mode::Triangles {
                        continue;
                    }
                    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                    let Some(positions) = reader.read_positions() else {
                        continue;
                    };
                    let positions: Vec<DVec3> = positions
                        .map(|p| world.transform_point3(DVec3::from_array(p.map(f64::from))))
                        .collect();
                    let file_normals: Option<Vec<DVec3>> = reader.read_normals().map(|n| {
                        n.map(|v| normal_world * DVec3::from_array(v.map(f64::from)))
                            .collect()
                    });
                    // glTF's base color factor is linear; a scene's colors are display values.
                    let base = primitive
                        .material()
                        .pbr_metallic_roughness()
                        .base_color_factor();
                    let base = [0, 1, 2].map(|c| linear_to_srgb(base[c] as f64));
                    materials |= primitive.material().index().is_some();
                    let indices: Vec<u32> = match reader.read_indices() {
                        Some(i) => i.into_u32().collect(),
                        None => (0..positions.len() as u32).collect(),
                    };
                    for t in indices.chunks_exact(3) {
                        let corner = |k: usize| positions.get(t[k] as usize).copied();
                        if let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) {
                            triangles.push([a, b, c]);
                            normals.push(file_normals.as_ref().and_then(|n| {
                                let at = |k: usize| n.get(t[k] as usize).copied();
                                Some([at(0)?, at(1)?, at(2)?])
                            }));
                            base_colors.push(base);
                        }
                    }
                    if triangles.len() > MAX_TRIANGLES {
                        return Err(MeshError::TooLarge(triangles.len(), MAX_TRIANGLES));
                    }
                }
            }
            stack.extend(node.children().map(|c| (c, world)));
        }
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if triangles.iter().flatten().any(|p| !p.is_finite()) {
            return Err(MeshError::NotFinite);
        }
        let mut data = MeshData::new(triangles);
        // Normals only where every triangle has them (a file mixing primitives with and without gets its faces').
        if normals
            .iter()
            .all(|n| n.is_some_and(|n| n.iter().all(|v| v.is_finite())))
        {
            data.normals = normals.into_iter().flatten().collect();
        }
        // Base colors where the file gives materials (glTF's default material, without one, is white).
        if materials {
            data.base_colors = base_colors;
        }
        Ok(data)
    }

    /// The mesh of `triangles`, with its hierarchy built.
    pub fn new(triangles: Vec<[DVec3; 3]>) -> MeshData {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = Vec::new();
        if !triangles.is_empty() {
            build(&triangles, &mut order, 0, triangles.len(), &mut nodes);
        }
        MeshData {
            triangles,
            normals: Vec::new(),
            base_colors: Vec::new(),
            nodes,
            order,
        }
    }

    /// The smallest t in `(t_min, t_max)` where `o + t d` meets a triangle (either face).
    pub fn hit(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        self.hit_triangle(o, d, t_min, t_max).map(|(t, _)| t)
    }

    /// Whether `p` lies inside the mesh: an odd number of crossings of its surface along a ray (a direction
    /// off every axis and diagonal, so that it seldom grazes an edge; each crossing counted once).
    pub fn contains(&self, p: DVec3) -> bool {
        let d = DVec3::new(0.573_218_4, 0.661_083_9, 0.484_723_1);
        let mut t = 0.0;
        let mut crossings = 0u32;
        while let Some(next) = self.hit(p, d, t, f64::INFINITY) {
            crossings += 1;
            // Past the crossing by a relative step, so that the same triangle is not met again.
            t = next + 1e-9 * (1.0 + next);
            if crossings > 10_000 {
                break;
            }
        }
        crossings % 2 == 1
    }

    /// The edges of the mesh that do not join exactly two triangles (by their ends' places, to 1e-9): none for
    /// a closed surface, which has an inside.
    pub fn open_edges(&self) -> usize {
        let key = |p: DVec3| (p * 1e9).round().to_array().map(|x| x as i64);
        let mut count = std::collections::HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                if a == b {
                    continue;
                }
                *count
                    .entry(if a < b { (a, b) } else { (b, a) })
                    .or_insert(0u32) += 1;
            }
        }
        count.values().filter(|&&n| n != 2).count()
    }

    /// `hit`, with the index of the triangle met (in `triangles`).
    pub fn hit_triangle(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<(f64, usize)> {
        if self.nodes.is_empty() {
            return None;
        }
        let inv = d.recip();
        let mut best = t_max;
        let mut found = None;
        let mut stack = vec![0u32];
        while let Some(k) = stack.pop() {
            let n = &self.nodes[k as usize];
            if !slab(n.lo, n.hi, o, inv, t_min, best) {
                continue;
            }
            if n.leaf {
                for &t in &self.order[n.first as usize..(n.first + n.second) as usize] {
                    if let Some(x) = triangle_hit(&self.triangles[t as usize], o, d)
                        && x > t_min
                        && x < best
                    {
                        best = x;
                        found = Some(t as usize);
                    }
                }
            } else {
                stack.push(n.first);
                stack.push(n.second);
            }
        }
        found.map(|k| (best, k))
    }
}

fn build(
    triangles: &[[DVec3; 3]],
    order: &mut [u32],
    first: usize,
    end: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &t in &order[first..end] {
        for p in triangles[t as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let c = centroid(&triangles[t as usize]);
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        first: first as u32,
        second: (end - first) as u32,
        leaf: true,
    });
    let extent = chi - clo;
    if end - first <= LEAF_SIZE || extent.max_element() == 0.0 {
        return index;
    }
    // Split at the median along the centroids' longest extent.
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = (first + end) / 2;
    order[first..end].select_nth_unstable_by(mid - first, |&a, &b| {
        centroid(&triangles[a as usize])[axis].total_cmp(&centroid(&triangles[b as usize])[axis])
    });
    let left = build(triangles, order, first, mid, nodes);
    let right = build(triangles, order, mid, end, nodes);
    let node = &mut nodes[index as usize];
    node.first = left;
    node.second = right;
    node.leaf = false;
    index
}

fn centroid(t: &[DVec3; 3]) -> DVec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

/// Whether `o + t d` passes through the box for some t in `[t_min, t_max]`, `inv` the reciprocal of d.
fn slab(lo: DVec3, hi: DVec3, o: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> bool {
    let mut near = t_min;
    let mut far = t_max;
    for k in 0..3 {
        let (a, b) = ((lo[k] - o[k]) * inv[k], (hi[k] - o[k]) * inv[k]);
        let (a, b) = if a.is_nan() || b.is_nan() {
            // The ray runs in the slab's plane (0 * inf): inside or out as its origin is.
            if o[k] < lo[k] || o[k] > hi[k] {
                return false;
            }
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (a.min(b), a.max(b))
        };
        near = near.max(a);
        far = far.min(b);
        if near > far {
            return false;
        }
    }
    true
}

/// The ray's parameter where it crosses the triangle (Moller-Trumbore, both faces), or none.
pub fn triangle_hit(t: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
    triangle_barycentric(t, o, d).map(|(t, _)| t)
}

/// The barycentric weights of the corners of `t` at the ray's crossing (Moller-Trumbore), and its parameter.
pub fn triangle_barycentric(t: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<(f64, [f64; 3])> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, [1.0 - u - v, u, v]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hierarchy_finds_what_a_scan_of_every_triangle_finds() {
        // A bumpy grid of triangles, rays from every side.
        let mut tris = Vec::new();
        let h = |x: f64, z: f64| (x * 1.7).sin() * (z * 1.3).cos() * 0.3;
        for i in 0..20 {
            for j in 0..20 {
                let (x, z) = (i as f64 * 0.1, j as f64 * 0.1);
                let p = |x: f64, z: f64| DVec3::new(x, h(x, z), z);
                tris.push([p(x, z), p(x + 0.1, z), p(x, z + 0.1)]);
                tris.push([p(x + 0.1, z), p(x + 0.1, z + 0.1), p(x, z + 0.1)]);
            }
        }
        let mesh = MeshData::new(tris.clone());
        let mut seed = 7u64;
        let mut r = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut hits = 0;
        for _ in 0..500 {
            let o = DVec3::new(r() * 3.0 - 0.5, r() * 2.0 - 1.0, r() * 3.0 - 0.5);
            let d = DVec3::new(r() - 0.5, r() - 0.5, r() - 0.5);
            let scan = (tris.iter())
                .filter_map(|t| triangle_hit(t, o, d))
                .filter(|&t| t > 0.0)
                .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
            assert_eq!(mesh.hit(o, d, 0.0, f64::INFINITY), scan);
            hits += scan.is_some() as usize;
        }
        assert!(hits > 50, "{hits} rays hit");
    }
}

/// The sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
fn linear_to_srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}
