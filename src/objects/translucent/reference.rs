//! The translucent model without voxels or table, in f64: the oracle the voxel number map is checked against,
//! and the depth-map estimate of the shadow-map methods it improves on.
//!
//! The reference sums over fine pieces of the surface itself (`voxels::surface_samples`, every point on the
//! surface, its exact normal and area), each piece's irradiance worked out where it is, and the optical
//! thickness along the exact segment (`Medium::optical_thickness`: piece by piece between the surfaces it
//! crosses, a cavity's included). The same single-scattering model as the table's, so that the difference is
//! the voxels' and the table's error alone, which shrinks as the resolution grows.

use std::f64::consts::PI;

use glam::DVec3;
use rayon::prelude::*;

use super::Medium;
use super::light::{Thickness, light_at};
use super::voxels::{SurfaceSample, surface_samples};
use crate::objects::Object;
use crate::objects::lighting::Lights;

/// The optical thickness of exact segments (`Medium::optical_thickness`, `steps` samples a piece where a
/// noise varies the medium).
pub struct Exact<'a> {
    pub medium: &'a Medium<'a>,
    pub steps: usize,
}

impl Thickness for Exact<'_> {
    fn tau(&self, from: DVec3, to: DVec3) -> f64 {
        self.medium.optical_thickness(from, to, self.steps)
    }
}

/// How the optical thickness from an entry point to an exit point is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimate {
    /// Along the exact segment, through cavities and out of concave parts (the model).
    Exact,
    /// What a depth map from the light gives: the distance between the entry and the exit point times the
    /// object's extinction, as though the object were whole and uniform between them (Dachsbacher and
    /// Stamminger's translucent shadow maps, Kosaka et al.): the foil, wrong where a cavity lies between.
    DepthMap,
}

/// A translucent object's surface in fine pieces with the light entering each.
pub struct Reference<'a> {
    medium: Medium<'a>,
    samples: Vec<SurfaceSample>,
    entering: Vec<[f64; 3]>,
    /// Each piece's `Z` (`Estimate::Exact`, then `DepthMap`): 0 where no light enters it.
    spread: [Vec<f64>; 2],
    area: f64,
    lights: &'a Lights,
    objects: &'a [Object],
    steps: usize,
}

impl<'a> Reference<'a> {
    /// `object` (one of `objects`, which cast the shadows) in pieces no longer than `finest`, lit by `lights`.
    pub fn new(object: &'a Object, objects: &'a [Object], lights: &'a Lights, finest: f64) -> Self {
        let medium = Medium::of(object).expect("a translucent object");
        let samples = surface_samples(object, finest);
        let area = samples.iter().map(|s| s.area).sum();
        let steps = 64;
        let exact = Exact {
            medium: &medium,
            steps,
        };
        let lift = 1e-7 * (1.0 + finest);
        let entering: Vec<[f64; 3]> = samples
            .par_iter()
            .map(|s| {
                light_at(
                    &medium,
                    lights,
                    objects,
                    &exact,
                    (s.position, s.normal, lift),
                )
                .0
            })
            .collect();
        let sigma = medium.material().extinction;
        let spread = [Estimate::Exact, Estimate::DepthMap].map(|estimate| {
            (samples.par_iter().zip(&entering))
                .map(|(y, e)| match e.iter().any(|&v| v != 0.0) {
                    false => 0.0,
                    true => samples
                        .iter()
                        .map(|x| {
                            let tau = match estimate {
                                Estimate::Exact => exact.tau(y.position, x.position),
                                Estimate::DepthMap => sigma * (x.position - y.position).length(),
                            };
                            x.area * (-tau).exp()
                        })
                        .sum(),
                })
                .collect()
        });
        Reference {
            medium,
            samples,
            entering,
            spread,
            area,
            lights,
            objects,
            steps,
        }
    }

    /// The pieces of the surface.
    pub fn samples(&self) -> &[SurfaceSample] {
        &self.samples
    }

    /// The surface's area.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// Every piece's entering light `E` (rgb), in the order of `samples`.
    pub fn entering(&self) -> &[[f64; 3]] {
        &self.entering
    }

    /// The radiance leaving the surface point `x` (outward normal `n`) before the exit's Fresnel:
    /// `(1/pi) (sum_j E_j a_j exp(-tau(y_j, x)) / Z_j + D(x))`, tau by `estimate`.
    pub fn leaving(&self, x: DVec3, n: DVec3, estimate: Estimate) -> [f64; 3] {
        let exact = Exact {
            medium: &self.medium,
            steps: self.steps,
        };
        let sigma = self.medium.material().extinction;
        let spread = &self.spread[(estimate == Estimate::DepthMap) as usize];
        let sum = (self.samples.par_iter().zip(&self.entering).zip(spread))
            .filter(|((_, e), _)| e.iter().any(|&v| v != 0.0))
            .map(|((s, e), z)| {
                let tau = match estimate {
                    Estimate::Exact => exact.tau(s.position, x),
                    Estimate::DepthMap => sigma * (x - s.position).length(),
                };
                let r = s.area * (-tau).exp() / z;
                e.map(|v| v * r)
            })
            .reduce(|| [0.0; 3], |a, b| std::array::from_fn(|c| a[c] + b[c]));
        let (_, inside) = light_at(
            &self.medium,
            self.lights,
            self.objects,
            &exact,
            (x, n, 1e-7),
        );
        std::array::from_fn(|c| (sum[c] + inside[c]) / PI)
    }
}
