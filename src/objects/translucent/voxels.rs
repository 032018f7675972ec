//! A translucent object voxelised: a grid of cubic voxels over its bounds, the extinction at each voxel's
//! center (zero outside the object and in a cavity), and its surface voxels numbered, the voxel number map.
//!
//! The surface voxels are the voxels the object's surface runs through, found by sampling the surface itself
//! (its triangles split until finer than half a voxel, a sphere's pushed back onto it): each gets the area of
//! the surface inside it `A_k`, the area-weighted mean of its points (where light enters and leaves it) and of
//! its normals. Counting the surface's own area, not voxel faces, keeps `sum A_k` the surface's area at every
//! resolution (a staircase of voxel faces would overcount a slanted face by up to sqrt(3)).

use glam::DVec3;
use rayon::prelude::*;

use super::{MAX_TABLE_BYTES, Medium};
use crate::objects::tessellate::Surface;
use crate::objects::{Object, Shape};

/// A piece of the object's surface: its center, outward unit normal and area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    pub position: DVec3,
    pub normal: DVec3,
    pub area: f64,
}

/// A numbered surface voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceVoxel {
    /// The voxel's index in the grid (`Voxels::index`).
    pub voxel: usize,
    /// The area-weighted mean of the surface's points in it.
    pub position: DVec3,
    /// The area-weighted mean of its outward normals, of unit length.
    pub normal: DVec3,
    /// The surface's area in it.
    pub area: f64,
}

/// The voxel number map of an object.
#[derive(Clone, Debug, PartialEq)]
pub struct Voxels {
    /// The grid's lowest corner.
    pub origin: DVec3,
    /// A voxel's side.
    pub side: f64,
    /// Voxels along x, y and z.
    pub dims: [usize; 3],
    /// `sigma_t` at each voxel's center, x fastest, then y, then z.
    pub extinction: Vec<f32>,
    /// Each voxel's surface number, `NONE` where the surface does not run through it.
    pub number: Vec<u32>,
    /// The surface voxels in the order of their numbers (the grid's order).
    pub surface: Vec<SurfaceVoxel>,
    /// The surface's whole area `A`.
    pub area: f64,
}

/// A voxel the surface does not run through.
pub const NONE: u32 = u32::MAX;

/// Why an object cannot be voxelised.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VoxelError {
    #[error("a {0} has no inside: only a sphere, a box or a closed mesh can be translucent")]
    NoInside(&'static str),
    #[error(
        "{resolution} voxels a side make {surface} surface voxels, a table of {} MiB, over the {} MiB allowed: \
         {fits} voxels a side or fewer fit",
        table_bytes(*surface) >> 20,
        MAX_TABLE_BYTES >> 20
    )]
    TooLarge {
        resolution: u32,
        surface: usize,
        fits: u32,
    },
}

/// The bytes of the table of `n` surface voxels: f32, the upper triangle with its diagonal.
pub fn table_bytes(n: usize) -> u64 {
    let n = n as u64;
    n * (n + 1) / 2 * 4
}

impl Voxels {
    /// The index of voxel (i, j, k).
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// The center of voxel (i, j, k).
    pub fn center(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * self.side
    }

    /// The voxel holding `p`, clamped into the grid.
    pub fn cell(&self, p: DVec3) -> [usize; 3] {
        let q = (p - self.origin) / self.side;
        std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// The grid of `object` at `resolution` voxels along its longest side, or why not.
    pub fn of(object: &Object, resolution: u32) -> Result<Voxels, VoxelError> {
        let medium = Medium::of(object).expect("a translucent object");
        let (lo, hi) = object
            .bounds()
            .ok_or(VoxelError::NoInside(object.kind().name()))?;
        let (origin, side, dims) = grid(lo, hi, resolution);
        let samples = surface_samples(object, side * 0.5);
        // The surface's area and mean point and normal in each voxel it runs through.
        let mut gathered: std::collections::BTreeMap<usize, (f64, DVec3, DVec3)> =
            Default::default();
        let index = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        let cell = |p: DVec3| -> [usize; 3] {
            let q = (p - origin) / side;
            std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(dims[a] - 1))
        };
        let mut area = 0.0;
        for s in &samples {
            let e =
                gathered
                    .entry(index(cell(s.position)))
                    .or_insert((0.0, DVec3::ZERO, DVec3::ZERO));
            e.0 += s.area;
            e.1 += s.position * s.area;
            e.2 += s.normal * s.area;
            area += s.area;
        }
        let count = dims[0] * dims[1] * dims[2];
        let mut number = vec![NONE; count];
        let surface: Vec<SurfaceVoxel> = gathered
            .into_iter()
            .filter(|(_, (a, _, _))| *a > 0.0)
            .map(|(voxel, (a, p, n))| SurfaceVoxel {
                voxel,
                position: p / a,
                normal: n.normalize_or(DVec3::Y),
                area: a,
            })
            .collect();
        for (k, s) in surface.iter().enumerate() {
            number[s.voxel] = k as u32;
        }
        // A voxel the surface runs through is inside (the medium is closed, `Medium::holds`): its extinction
        // read at its center, or where that is outside, at the nearest of its points that is not.
        let extinction: Vec<f32> = (0..count)
            .into_par_iter()
            .map(|v| {
                let (i, j, k) = (
                    v % dims[0],
                    (v / dims[0]) % dims[1],
                    v / (dims[0] * dims[1]),
                );
                let p = origin + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * side;
                if object.contains(p) {
                    return medium.inside(p) as f32;
                }
                if number[v] == NONE {
                    return 0.0;
                }
                let s = &surface[number[v] as usize];
                medium.inside(s.position - s.normal * (1e-9 * (1.0 + side))) as f32
            })
            .collect();
        Ok(Voxels {
            origin,
            side,
            dims,
            extinction,
            number,
            surface,
            area,
        })
    }

    /// The surface voxels `object` would have at `resolution`, without the rest of the grid: what its table's
    /// size is reckoned from.
    pub fn surface_count(object: &Object, resolution: u32) -> Result<usize, VoxelError> {
        let (lo, hi) = object
            .bounds()
            .ok_or(VoxelError::NoInside(object.kind().name()))?;
        let (origin, side, dims) = grid(lo, hi, resolution);
        let mut seen = std::collections::HashSet::new();
        for s in surface_samples(object, side * 0.5) {
            let q = (s.position - origin) / side;
            let c: [usize; 3] =
                std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(dims[a] - 1));
            seen.insert(c);
        }
        Ok(seen.len())
    }
}

/// The resolution an object's material asks for, or the finest up to `DEFAULT_RESOLUTION` whose table fits;
/// an error where the one asked for does not fit (naming the finest that does).
pub fn resolution_of(object: &Object) -> Result<u32, VoxelError> {
    let asked = object.translucent.as_ref().and_then(|t| t.resolution);
    let fits = |r: u32| -> Result<bool, VoxelError> {
        Ok(table_bytes(Voxels::surface_count(object, r)?) <= MAX_TABLE_BYTES)
    };
    match asked {
        Some(r) => {
            if fits(r)? {
                return Ok(r);
            }
            // The table grows as r^4: the finest that fits, from the estimate down.
            let surface = Voxels::surface_count(object, r)?;
            let ratio = (MAX_TABLE_BYTES as f64 / table_bytes(surface) as f64).powf(0.25);
            let mut f = ((r as f64 * ratio).floor() as u32).max(1);
            while f > 1 && !fits(f)? {
                f -= 1;
            }
            Err(VoxelError::TooLarge {
                resolution: r,
                surface,
                fits: f,
            })
        }
        None => {
            let mut r = super::DEFAULT_RESOLUTION;
            while r > 4 && !fits(r)? {
                r -= 2;
            }
            Ok(r)
        }
    }
}

/// The grid over `lo..hi`: cubic voxels, `resolution` of them along the longest side, and more round it so
/// that no surface voxel lies on the grid's edge; the bounds fall a quarter of the way into a voxel, not on the
/// faces between voxels, so that a face of the object along the grid does not scatter its points over two layers
/// of voxels as rounding goes. (origin, side, dims).
fn grid(lo: DVec3, hi: DVec3, resolution: u32) -> (DVec3, f64, [usize; 3]) {
    let extent = (hi - lo).max(DVec3::splat(1e-9));
    let side = extent.max_element() / resolution.max(1) as f64;
    let origin = lo - DVec3::splat(1.25 * side);
    let dims: [usize; 3] = std::array::from_fn(|a| (extent[a] / side + 2.5).ceil() as usize);
    (origin, side, dims)
}

/// The object's surface as pieces no longer than `finest` (its drawn triangles split in four until they are;
/// a sphere's new corners pushed back onto it), each with its outward normal and area.
pub fn surface_samples(object: &Object, finest: f64) -> Vec<SurfaceSample> {
    let surface = Surface::of(std::slice::from_ref(object), DVec3::ZERO, 1.0);
    let sphere = match object.shape {
        Shape::Sphere { center, radius } => Some((center, radius)),
        _ => None,
    };
    let project = |p: DVec3| match sphere {
        Some((c, r)) => c + (p - c).normalize_or(DVec3::Y) * r,
        None => p,
    };
    let triangles: Vec<([DVec3; 3], DVec3)> = surface
        .indices
        .chunks_exact(3)
        .map(|t| {
            let p: [DVec3; 3] = std::array::from_fn(|c| surface.positions[t[c] as usize]);
            let n: DVec3 = t.iter().map(|&i| surface.normals[i as usize]).sum();
            (p, n)
        })
        .collect();
    triangles
        .par_iter()
        .flat_map_iter(|(p, n)| {
            let mut out = Vec::new();
            split(*p, *n, finest, &project, &mut out, 0);
            out
        })
        .collect()
}

fn split(
    p: [DVec3; 3],
    outward: DVec3,
    finest: f64,
    project: &dyn Fn(DVec3) -> DVec3,
    out: &mut Vec<SurfaceSample>,
    depth: u32,
) {
    let longest = (p[0] - p[1])
        .length()
        .max((p[1] - p[2]).length())
        .max((p[2] - p[0]).length());
    if longest <= finest || depth >= 12 {
        let face = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * face.length();
        if area > 0.0 {
            let normal = face.normalize();
            let normal = if normal.dot(outward) < 0.0 {
                -normal
            } else {
                normal
            };
            out.push(SurfaceSample {
                position: project((p[0] + p[1] + p[2]) / 3.0),
                normal,
                area,
            });
        }
        return;
    }
    let m = [
        project((p[0] + p[1]) * 0.5),
        project((p[1] + p[2]) * 0.5),
        project((p[2] + p[0]) * 0.5),
    ];
    for t in [
        [p[0], m[0], m[2]],
        [m[0], p[1], m[1]],
        [m[2], m[1], p[2]],
        [m[0], m[1], m[2]],
    ] {
        split(t, outward, finest, project, out, depth + 1);
    }
}
