//! A frame's particles as both renderers read them (docs/METHOD.md section 9): the smoke's own image of `size`
//! pixels over the frame (rays from the eye through its pixel centers), the slices perpendicular to the view, and
//! for the GPU each tile's particles in the order of the first slab they reach. The CPU twin
//! (`reference::particles::smoke_pixel`) takes the same rays and slices.

use glam::DVec3;
use rayon::prelude::*;

use super::{Particle, Ray, Slicing};
use crate::field::Sources;
use crate::geometry::{Billboard, Camera};
use crate::integrate::zeta;

/// The smoke image's tiles: the pixels that share a list of particles (a workgroup on the GPU). Small: a pixel
/// passes over fewer particles that miss it (with the former loop over segments, 50,000 particles of 1 to 2
/// pixels' radius at 256 x 256 on lavapipe took 1.9 s in tiles of 16 or 8, 1.2 s in tiles of 4).
pub const TILE: u32 = 4;

/// The cells the glow is placed on, in pixels: psi is sampled along the rays of their corners only (it
/// varies smoothly across the image; at the tiles' corners it took 43 ms a view on the default beam at 256 x 256,
/// at these 12 ms).
pub const GLOW_CELL: u32 = 16;

/// The most entries (a particle in a tile) a frame's lists take: past it the image is made coarser (a scene of a
/// million particles keeps a bounded plan; 8 M entries are 64 MiB on the GPU, within every adapter's storage
/// binding).
pub const MAX_ENTRIES: usize = 1 << 23;

/// The most slabs a frame takes: past it the slices widen (a tiny particle far from a large one).
pub const MAX_SLABS: u32 = 1 << 14;

/// The most slabs the GPU's pixel keeps open at once along its ray (`shaders/particles.wgsl`'s ring): the slices
/// are at least as wide as keeps every particle within `RING` slabs (a fifteenth of the largest radius; finer
/// slices than that change the picture by less than the convergence test's 1e-4).
pub const RING: u32 = 32;

/// The samples of psi along a ray that place its glow (`GlowPlace`).
pub const GLOW_SAMPLES: u32 = 48;

/// How much finer `GlowPlace` samples the steps where the glow bends sharply.
pub const GLOW_REFINE: u32 = 8;

/// The shares of the glow along a ray whose depths a ray keeps (`GlowDepths`): finer toward both ends, where a
/// source's long falloff leaves a thin share far from its peak that an even spread would carry too far.
pub const GLOW_LEVELS: [f64; GLOW_DEPTHS] = [
    0.0,
    1.0 / 64.0,
    1.0 / 16.0,
    0.125,
    0.25,
    0.375,
    0.5,
    0.625,
    0.75,
    0.875,
    15.0 / 16.0,
    63.0 / 64.0,
    1.0,
];

/// How many depths place the glow along a ray.
pub const GLOW_DEPTHS: usize = 13;

/// The floats a glow cell's corner takes in `SmokeView::glow`: its `GLOW_DEPTHS` depths, the last repeated up to
/// four vec4s (what the GPU pass loads).
pub const GLOW_STRIDE: usize = 16;

/// Where the glow lies along a ray: the depths along the view axis in front of which `GLOW_LEVELS` of it lie,
/// non-decreasing; between two of them the glow is spread evenly (`glow_before`).
pub type GlowDepths = [f64; GLOW_DEPTHS];

/// The share of the glow on a ray that lies in front of depth `d` along the view axis: piecewise linear through
/// `(depths[i], GLOW_LEVELS[i])`, 0 in front of the first depth and 1 past the last (a step where two depths
/// are equal).
pub fn glow_before(depths: &GlowDepths, d: f64) -> f64 {
    (0..GLOW_DEPTHS - 1)
        .map(|i| {
            let (lo, hi) = (depths[i], depths[i + 1]);
            let part = ((d - lo) / (hi - lo).max(1e-30)).clamp(0.0, 1.0);
            (GLOW_LEVELS[i + 1] - GLOW_LEVELS[i]) * part
        })
        .sum()
}

/// The smoke image of a frame: its size, its rays and its slices, and where the glow lies along its rays.
#[derive(Clone, Debug, PartialEq)]
pub struct SmokeView {
    pub camera: Camera,
    pub size: [u32; 2],
    pub slicing: Slicing,
    /// Where the glow lies along the rays of the glow cells' corners (`glow_cells + 1` a row, rows from the top):
    /// `GLOW_STRIDE` floats a corner, its `GlowDepths` in f32 as the GPU reads them (`glow_at`).
    pub glow: Vec<f32>,
}

/// What places the glow along a ray: the sources, their epsilon, the rays' reach from S on the billboard to
/// E = V + nu (S - V), and the decay `zeta(s) = alpha / (s + beta)^2` over it (the frame's
/// `Integration::on_ray`).
pub struct GlowPlace<'a> {
    pub sources: &'a Sources,
    pub epsilon: f64,
    pub billboard: &'a Billboard,
    pub nu: f64,
    pub alpha: f64,
    pub beta: f64,
}

impl GlowPlace<'_> {
    /// Where the glow lies on `ray`, as depths along the view `axis`: what the field pass integrates there,
    /// `|psi zeta|`, sampled at `GLOW_SAMPLES` midpoints from S to E, each sample's weight spread evenly over its
    /// step, and the depths where that weight's running share reaches each of `GLOW_LEVELS`. All at the
    /// billboard's depth where psi is 0 all along (the glow as one layer there).
    pub fn depths(&self, ray: &Ray, axis: DVec3) -> GlowDepths {
        let b = self.billboard;
        let along = ray.direction.dot(axis);
        let t_s = (b.center - ray.origin).dot(b.normal) / ray.direction.dot(b.normal);
        if !(t_s > 0.0 && t_s.is_finite()) {
            return [(b.center - ray.origin).dot(axis); GLOW_DEPTHS];
        }
        let t_e = self.nu * t_s;
        let field = self.sources.field();
        let weight = |s: f64| {
            let t = t_s + s * (t_e - t_s);
            (field.psi(ray.at(t), self.epsilon) * zeta(s, self.alpha, self.beta)).abs()
        };
        let n = GLOW_SAMPLES as usize;
        let coarse: Vec<f64> = (0..n)
            .map(|k| weight((k as f64 + 0.5) / n as f64))
            .collect();
        let whole: f64 = coarse.iter().sum();
        if !(whole > 0.0 && whole.is_finite()) {
            return [along * t_s; GLOW_DEPTHS];
        }
        // Where the weight bends sharply within a step (a source the ray passes nearer than a few steps), that
        // step and its neighbours are sampled again `GLOW_REFINE` times finer: the share a step holds is spread
        // evenly over it, which would spread a sharp peak over a step or two.
        let at = |k: usize| coarse.get(k).copied().unwrap_or(0.0);
        let sharp = |k: usize| {
            let bend = (at(k.wrapping_sub(1)) + at(k + 1) - 2.0 * at(k)).abs();
            coarse[k] * n as f64 > 0.25 * whole && bend > 0.5 * coarse[k]
        };
        let mut fine = vec![false; n];
        for k in (0..n).filter(|&k| sharp(k)) {
            fine[k.saturating_sub(1)..(k + 2).min(n)].fill(true);
        }
        // The steps as (start, length, weight) along the ray in units of s, finer where refined.
        let mut parts: Vec<(f64, f64, f64)> = Vec::with_capacity(n);
        for (k, &w) in coarse.iter().enumerate() {
            let start = k as f64 / n as f64;
            if fine[k] {
                let r = GLOW_REFINE as f64;
                parts.extend((0..GLOW_REFINE).map(|i| {
                    let s0 = start + i as f64 / (r * n as f64);
                    (
                        s0,
                        1.0 / (r * n as f64),
                        weight(s0 + 0.5 / (r * n as f64)) / r,
                    )
                }));
            } else {
                parts.push((start, 1.0 / n as f64, w));
            }
        }
        let whole: f64 = parts.iter().map(|p| p.2).sum();
        if !(whole > 0.0 && whole.is_finite()) {
            return [along * t_s; GLOW_DEPTHS];
        }
        let depth_at = |s: f64| along * (t_s + s * (t_e - t_s));
        // The first and the last part that hold any of it bound the glow; within a part it is spread evenly.
        let first = parts.iter().position(|p| p.2 > 0.0).unwrap_or(0);
        let last = parts.iter().rposition(|p| p.2 > 0.0).unwrap_or(0);
        let mut depths = [0.0; GLOW_DEPTHS];
        depths[0] = depth_at(parts[first].0);
        depths[GLOW_DEPTHS - 1] = depth_at(parts[last].0 + parts[last].1);
        let (mut k, mut below) = (first, 0.0);
        for (depth, &level) in depths
            .iter_mut()
            .zip(&GLOW_LEVELS)
            .skip(1)
            .take(GLOW_DEPTHS - 2)
        {
            let wanted = level * whole;
            while k < last && below + parts[k].2 < wanted {
                below += parts[k].2;
                k += 1;
            }
            let (start, length, w) = parts[k];
            let within = if w > 0.0 {
                ((wanted - below) / w).clamp(0.0, 1.0)
            } else {
                0.0
            };
            *depth = depth_at(start + within * length);
        }
        depths
    }
}

/// The smoke image's size for a frame of `frame` pixels: about the field's texel density (a texel per
/// `resolution`-th of the frame's height), coarser where the smallest particle's radius spans more than
/// `RADIUS_PIXELS` of the image's pixels (`finest`: that radius in frame pixels, `finest_radius`), at most a
/// pixel a frame pixel and at least a quarter of one a side. The smoke's finest detail is its smallest
/// particle: pixels finer than a quarter of its radius cost the square of their density in work for little the
/// filtered image shows (tests/particles.rs, against the smoke worked out on every frame pixel's ray: the rms of
/// the transmittance 8.2e-4 at 9.6 pixels a radius, 1.8e-3 at 4.8; the largest difference, at the rims,
/// 0.029 and 0.054).
pub fn smoke_size(frame: [u32; 2], resolution: u32, finest: f64) -> [u32; 2] {
    let by_field = frame[1] / resolution.max(1);
    let by_detail = (finest / RADIUS_PIXELS).floor().min(4.0) as u32;
    let step = by_field.max(by_detail).clamp(1, 4);
    frame.map(|s| s.div_ceil(step).max(1))
}

/// The fewest smoke image pixels a particle's radius spans (`smoke_size`).
pub const RADIUS_PIXELS: f64 = 4.0;

/// The radius of the smallest of `particles` in a frame `height` pixels tall seen by `camera`, in frame pixels
/// (at its center's depth); those not wholly in front of the eye left out (they span more); infinite for
/// none.
pub fn finest_radius(particles: &[Particle], camera: &Camera, height: u32) -> f64 {
    let (eye, forward) = (camera.eye, camera.frame().forward);
    let scale = 0.5 * height as f64 / camera.tan_half_fov();
    (particles.iter())
        .filter_map(|p| {
            let depth = (p.position - eye).dot(forward);
            (depth > p.radius).then(|| p.radius / depth * scale)
        })
        .fold(f64::INFINITY, f64::min)
}

impl SmokeView {
    /// The smoke of `particles` seen by `camera` in an image of `size` pixels, sliced at `width` radii of the
    /// smallest particle (widened where a particle would span more than `RING` slabs).
    pub fn new(
        particles: &[Particle],
        camera: &Camera,
        size: [u32; 2],
        width: f64,
        glow: &GlowPlace,
    ) -> SmokeView {
        let axis = camera.frame().forward;
        let smallest = particles
            .iter()
            .map(|p| p.radius)
            .fold(f64::INFINITY, f64::min);
        let largest = particles.iter().map(|p| p.radius).fold(0.0, f64::max);
        let width = (width * smallest).max(2.0 * largest / (RING - 2) as f64);
        let slicing = Slicing::covering(particles, camera.eye, axis, width);
        let mut view = SmokeView {
            camera: camera.clone(),
            size,
            slicing,
            glow: Vec::new(),
        };
        view.bound(particles);
        let [gx, gy] = view.glow_cells();
        view.glow = (0..(gx + 1) * (gy + 1))
            .into_par_iter()
            .flat_map_iter(|k| {
                let (i, j) = (k % (gx + 1), k / (gx + 1));
                let at = |c: u32, n: u32| (c * GLOW_CELL).min(n) as f64;
                let ray = Ray {
                    origin: camera.eye,
                    direction: camera.pixel_ray(at(i, size[0]), at(j, size[1]), size[0], size[1]),
                };
                let depths = glow.depths(&ray, axis);
                (0..GLOW_STRIDE).map(move |i| depths[i.min(GLOW_DEPTHS - 1)] as f32)
            })
            .collect();
        view
    }

    /// Bounds the plan: at most `MAX_SLABS` slabs (the twin keeps two numbers a slab along a ray), and at most
    /// `MAX_ENTRIES` entries (a particle's tiles), the image made coarser as much as that takes.
    fn bound(&mut self, particles: &[Particle]) {
        let (axis, eye) = (self.slicing.axis, self.camera.eye);
        let far = (particles.iter())
            .map(|p| (p.position - eye).dot(axis) + p.radius)
            .fold(f64::NEG_INFINITY, f64::max);
        let depth = far - self.slicing.near;
        if self.slicing.count > MAX_SLABS {
            self.slicing = Slicing::covering(particles, eye, axis, depth / MAX_SLABS as f64);
        }
        for _ in 0..8 {
            let entries: f64 = particles
                .par_iter()
                .map(|p| {
                    self.footprint(p)
                        .map_or(0.0, |(x0, x1, y0, y1)| ((x1 - x0) * (y1 - y0)) as f64)
                })
                .sum();
            if entries <= MAX_ENTRIES as f64 {
                return;
            }
            self.size = self.size.map(|s| s.div_ceil(2).max(1));
        }
    }

    /// Where the glow lies along the ray through the center of pixel `(x, y)`: each depth bilinear between the
    /// glow cells' corners' (`glow`), in f32 as the GPU pass works it out.
    pub fn glow_at(&self, x: u32, y: u32) -> GlowDepths {
        let [gx, gy] = self.glow_cells();
        let g = [
            (x as f32 + 0.5) / GLOW_CELL as f32,
            (y as f32 + 0.5) / GLOW_CELL as f32,
        ];
        let i = [(g[0] as u32).min(gx - 1), (g[1] as u32).min(gy - 1)];
        let f = [g[0] - i[0] as f32, g[1] - i[1] as f32];
        std::array::from_fn(|d| {
            let at = |a: u32, b: u32| self.glow[(b * (gx + 1) + a) as usize * GLOW_STRIDE + d];
            let top = at(i[0], i[1]) + (at(i[0] + 1, i[1]) - at(i[0], i[1])) * f[0];
            let bottom = at(i[0], i[1] + 1) + (at(i[0] + 1, i[1] + 1) - at(i[0], i[1] + 1)) * f[0];
            (top + (bottom - top) * f[1]) as f64
        })
    }

    /// The ray through the center of pixel `(x, y)` of the smoke image.
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        let [w, h] = self.size;
        Ray {
            origin: self.camera.eye,
            direction: self.camera.pixel_ray(x as f64 + 0.5, y as f64 + 0.5, w, h),
        }
    }

    /// The cells the glow is placed on (their corners'), `GLOW_CELL` pixels a side.
    pub fn glow_cells(&self) -> [u32; 2] {
        self.size.map(|s| s.div_ceil(GLOW_CELL))
    }

    pub fn tiles(&self) -> [u32; 2] {
        self.size.map(|s| s.div_ceil(TILE))
    }

    /// The first slab particle `p`'s ball reaches and how many slabs past it it may reach (below `RING`), or none
    /// where it lies wholly behind the eye or past the slices.
    pub fn slabs(&self, p: &Particle) -> Option<(u32, u32)> {
        let s = &self.slicing;
        let depth = (p.position - self.camera.eye).dot(s.axis);
        let first = ((depth - p.radius - s.near) / s.width).floor().max(0.0);
        let last = ((depth + p.radius - s.near) / s.width)
            .floor()
            .min(s.count as f64 - 1.0);
        (last >= first).then(|| {
            let first = first as u32;
            (first, (last as u32 - first).min(RING - 1))
        })
    }

    /// Each tile's particles, the GPU's loop (`gpu::particle_pass`): `(first slab | slabs past it << 24,
    /// particle)`, each tile's in the order of their first slab (then of the particles), flattened; and the tiles
    /// that have any, the busiest first, as `[tile, first entry, end entry]`.
    pub fn tile_lists(&self, particles: &[Particle]) -> (Vec<[u32; 2]>, Vec<[u32; 3]>) {
        let [tx, _] = self.tiles();
        let mut keyed: Vec<(u32, [u32; 2])> = particles
            .par_iter()
            .enumerate()
            .flat_map_iter(|(k, p)| {
                let placed = self.slabs(p).zip(self.footprint(p));
                placed
                    .into_iter()
                    .flat_map(move |((first, span), (x0, x1, y0, y1))| {
                        (y0..y1).flat_map(move |y| {
                            (x0..x1).map(move |x| (y * tx + x, [first | span << 24, k as u32]))
                        })
                    })
            })
            .collect();
        keyed.par_sort_unstable_by_key(|&(tile, [slabs, k])| (tile, slabs & 0xff_ffff, k));
        let mut work: Vec<[u32; 3]> = Vec::new();
        for (i, &(tile, _)) in keyed.iter().enumerate() {
            match work.last_mut() {
                Some(w) if w[0] == tile => w[2] = i as u32 + 1,
                _ => work.push([tile, i as u32, i as u32 + 1]),
            }
        }
        work.sort_by_key(|&[tile, start, end]| (std::cmp::Reverse(end - start), tile));
        (keyed.into_iter().map(|(_, e)| e).collect(), work)
    }

    /// The tiles a particle's ball may cover, `(x0, x1, y0, y1)` half-open: the box of its bounding cube's
    /// corners projected, or every tile where a corner lies at or behind the eye; none off the image.
    fn footprint(&self, p: &Particle) -> Option<(u32, u32, u32, u32)> {
        let [w, h] = self.size;
        let [tx, ty] = self.tiles();
        let f = self.camera.frame();
        if (p.position - self.camera.eye).dot(f.forward) + p.radius <= 0.0 {
            return None;
        }
        let (mut lo, mut hi) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for corner in 0..8 {
            let sign = |bit: u32| if corner >> bit & 1 == 1 { 1.0 } else { -1.0 };
            let c = p.position + p.radius * DVec3::new(sign(0), sign(1), sign(2));
            // A corner too near the eye's plane projects without bound: the whole image.
            if (c - self.camera.eye).dot(f.forward) <= 1e-6 * p.radius {
                return Some((0, tx, 0, ty));
            }
            let (x, y) = self.camera.project(c, w, h)?;
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        let tile = |v: f64, n: u32| (v / TILE as f64).floor().clamp(0.0, n as f64) as u32;
        let (x0, x1) = (tile(lo.0, tx), tile(hi.0, tx - 1) + 1);
        let (y0, y1) = (tile(lo.1, ty), tile(hi.1, ty - 1) + 1);
        (hi.0 >= 0.0 && hi.1 >= 0.0 && lo.0 < w as f64 && lo.1 < h as f64 && x0 < x1 && y0 < y1)
            .then_some((x0, x1, y0, y1))
    }
}
