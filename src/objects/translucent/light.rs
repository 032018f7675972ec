//! The wave's light carried through a translucent object: the irradiance of every surface voxel, the sum over
//! the table, and what the points of the drawn surface read from the voxels near them.
//!
//! Everything here is independent of the camera: the radiance leaving surface voxel l before the exit's
//! Fresnel, `S_l = (1/pi) (sum_k E_k A_k exp(-tau(k, l)) / Z_k + D_l)`, `Z_k = sum_l A_l exp(-tau(k, l))`, `D_l` the light of the sources inside
//! the object (the module's reading), is worked out when the lights or the objects change; a pixel multiplies
//! it by `F_t(eta, w_out)` and the object's tint (`shaders/objects.wgsl`, `lighting::shaded_translucent`).

use std::f64::consts::PI;
use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::Medium;
use super::table::{Table, thickness};
use super::voxels::{NONE, Voxels, resolution_of};
use crate::objects::Object;
use crate::objects::lighting::{Lights, fresnel_transmittance};

/// An object's voxels and table: what depends on its shape, place and material only.
#[derive(Debug)]
pub struct Prepared {
    pub voxels: Voxels,
    pub table: Table,
    /// Each surface voxel's `Z_k = sum_l A_l exp(-tau(k, l))`, over which the light entering it spreads.
    pub spread: Vec<f64>,
    /// Seconds the voxels and the table took.
    pub seconds: f64,
}

/// `object`'s voxels and table (none for an opaque object, or one that cannot be voxelised), the table filled by
/// `fill` where it gives one (a real GPU's, `gpu::tau_table`, through the frame cache's hook), else by the CPU.
/// A renderer keeps them in its frame cache (`frame::FrameCache::translucent`): editing a source or orbiting
/// the camera relights the voxels without voxelising again.
pub fn prepare(object: &Object, fill: &dyn Fn(&Voxels) -> Option<Table>) -> Option<Prepared> {
    object.translucent.as_ref()?;
    let start = std::time::Instant::now();
    let resolution = resolution_of(object).ok()?;
    let voxels = Voxels::of(object, resolution).ok()?;
    let table = fill(&voxels).unwrap_or_else(|| Table::of(&voxels));
    let spread = spread(&voxels, &table);
    Some(Prepared {
        voxels,
        table,
        spread,
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl Prepared {
    /// The bytes it holds (its voxels, table and spread), for a cache's memory bound.
    pub fn bytes(&self) -> usize {
        let v = &self.voxels;
        4 * (v.extinction.len() + v.number.len() + self.table.tau.len())
            + size_of_val(&v.surface[..])
            + 8 * self.spread.len()
    }
}

/// `Z_k = sum_l A_l exp(-tau(k, l))` of every surface voxel k.
pub fn spread(voxels: &Voxels, table: &Table) -> Vec<f64> {
    (0..table.n)
        .into_par_iter()
        .map(|k| {
            (0..table.n)
                .map(|l| voxels.surface[l].area * (-(table.get(k, l) as f64)).exp())
                .sum()
        })
        .collect()
}

/// The light at every surface voxel: what enters from outside (`E_k`), and what the sources inside bring
/// (`D_k`), rgb.
#[derive(Clone, Debug, PartialEq)]
pub struct Irradiance {
    pub entering: Vec<[f64; 3]>,
    pub inside: Vec<[f64; 3]>,
}

/// How the light reaching a surface point is worked out: from the voxels (the method) or exactly (the
/// reference): the optical thickness from an inner source's point to the surface point.
pub trait Thickness: Sync {
    fn tau(&self, from: DVec3, to: DVec3) -> f64;
}

impl Thickness for Voxels {
    fn tau(&self, from: DVec3, to: DVec3) -> f64 {
        thickness(self, from, to)
    }
}

/// The light reaching the surface point `x` (outward normal `n`) of the translucent `medium`: entering
/// (`F_t(eta, w_in) max(0, n . w_in) I V`, summed over the sources outside) and from inside (`I exp(-tau)`
/// over the sources inside). `lift` moves the point off the surface for the shadow rays (the voxels' points lie
/// a little inside a curved surface).
pub fn light_at(
    medium: &Medium<'_>,
    lights: &Lights,
    objects: &[Object],
    thickness: &dyn Thickness,
    (x, n, lift): (DVec3, DVec3, f64),
) -> ([f64; 3], [f64; 3]) {
    let eta = medium.material().eta;
    let mut entering = [0.0; 3];
    let mut inside = [0.0; 3];
    for (k, light) in lights.at(x).enumerate() {
        if light.strength == 0.0 {
            continue;
        }
        if medium.object().contains(light.from) {
            let dim = light.strength * (-thickness.tau(light.from, x)).exp();
            for (sum, color) in inside.iter_mut().zip(light.color) {
                *sum += color * dim;
            }
            continue;
        }
        let to = light.from - x;
        let d = to.length();
        if d == 0.0 {
            continue;
        }
        let cos = n.dot(to / d);
        if cos <= 0.0 {
            continue;
        }
        let seen = lights.visibility(objects, x + n * lift, n, k, light.from);
        let e = light.strength * cos * fresnel_transmittance(eta, cos) * seen;
        for (sum, color) in entering.iter_mut().zip(light.color) {
            *sum += color * e;
        }
    }
    (entering, inside)
}

/// Every surface voxel's light.
pub fn irradiance(
    medium: &Medium<'_>,
    voxels: &Voxels,
    lights: &Lights,
    objects: &[Object],
) -> Irradiance {
    let lift = 0.5 * voxels.side;
    let (entering, inside): (Vec<_>, Vec<_>) = voxels
        .surface
        .par_iter()
        .map(|s| {
            light_at(
                medium,
                lights,
                objects,
                voxels,
                (s.position, s.normal, lift),
            )
        })
        .unzip();
    Irradiance { entering, inside }
}

/// The radiance leaving every surface voxel before the exit's Fresnel: `S_l` (the module's formula).
pub fn leaving(prepared: &Prepared, light: &Irradiance) -> Vec<[f64; 3]> {
    let (voxels, table) = (&prepared.voxels, &prepared.table);
    // Only the voxels some light enters add to the sums.
    let lit: Vec<(usize, [f64; 3])> = (light.entering.iter().enumerate())
        .filter(|(_, e)| e.iter().any(|&x| x != 0.0))
        .map(|(k, e)| {
            let a = voxels.surface[k].area / prepared.spread[k].max(1e-300);
            (k, e.map(|x| x * a))
        })
        .collect();
    (0..voxels.surface.len())
        .into_par_iter()
        .map(|l| {
            let mut sum = [0.0; 3];
            for &(k, e) in &lit {
                let r = (-(table.get(k, l) as f64)).exp();
                for c in 0..3 {
                    sum[c] += e[c] * r;
                }
            }
            std::array::from_fn(|c| (sum[c] + light.inside[l][c]) / PI)
        })
        .collect()
}

/// The radiance leaving the voxels, and what a point of the object's surface reads from them.
#[derive(Clone, Debug)]
pub struct Scattered {
    pub prepared: Arc<Prepared>,
    /// `S_l` of every surface voxel.
    pub leaving: Vec<[f64; 3]>,
}

impl Scattered {
    /// The object's scattered light under `lights`, its shadows cast by `objects`, from its voxels and table
    /// (`prepare`).
    pub fn of(
        object: &Object,
        prepared: Arc<Prepared>,
        lights: &Lights,
        objects: &[Object],
    ) -> Option<Scattered> {
        let medium = Medium::of(object)?;
        let light = irradiance(&medium, &prepared.voxels, lights, objects);
        let leaving = leaving(&prepared, &light);
        Some(Scattered { prepared, leaving })
    }

    /// `S` at the surface point `x` of normal `n`: the surface voxels around it (those within 1.5 voxels, and
    /// facing the same side), weighted by `(1 - d / 1.5 side)^2`; the nearest within 3 voxels where none is.
    pub fn at(&self, x: DVec3, n: DVec3) -> [f64; 3] {
        let v = &self.prepared.voxels;
        let c = v.cell(x);
        for reach in [1i64, 3] {
            let radius = (reach as f64 + 0.5) * v.side;
            let mut sum = [0.0; 3];
            let mut weight = 0.0;
            for dk in -reach..=reach {
                for dj in -reach..=reach {
                    for di in -reach..=reach {
                        let q = [c[0] as i64 + di, c[1] as i64 + dj, c[2] as i64 + dk];
                        if (0..3).any(|a| q[a] < 0 || q[a] >= v.dims[a] as i64) {
                            continue;
                        }
                        let number = v.number[v.index(q[0] as usize, q[1] as usize, q[2] as usize)];
                        if number == NONE {
                            continue;
                        }
                        let s = &v.surface[number as usize];
                        if s.normal.dot(n) <= 0.0 {
                            continue;
                        }
                        let w = (1.0 - (s.position - x).length() / radius).max(0.0).powi(2);
                        weight += w;
                        for (sum, s) in sum.iter_mut().zip(self.leaving[number as usize]) {
                            *sum += w * s;
                        }
                    }
                }
            }
            if weight > 0.0 {
                return sum.map(|s| s / weight);
            }
        }
        [0.0; 3]
    }
}
