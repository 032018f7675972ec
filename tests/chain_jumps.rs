//! Chains of several segments whose nearest point jumps between segments close beside a closest approach, or
//! jumps to another segment and back between two samples of the adaptive integrator's scan: random chains in
//! random views (a fixed generator, so the same scenes on every machine), those of 300 that were off the converged
//! value by 3e-2 to 0.61 of B in both twins before the closest approaches were found segment by segment and a
//! suspect interval sampled finer (README, "Error control"). Every texel on the CPU twin and on the GPU (Vulkan,
//! and GL through test.sh) within the tolerance of the converged reference (f32's rounding of B more on the GPU).

use energywave::field::{Curve, Sources, WForm};
use energywave::frame::{FrameSetup, Refine};
use energywave::geometry::Camera;
use energywave::gpu::HeadlessRenderer;
use energywave::reference;
use energywave::reference::converged::converged_reference;
use energywave::scene::Scene;
use glam::DVec3;

/// A linear congruential generator: the views below are its draws, in order.
struct Draws(u64);

impl Draws {
    fn unit(&mut self) -> f64 {
        self.0 = (self.0)
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }

    fn within(&mut self, r: f64) -> DVec3 {
        DVec3::new(
            (2.0 * self.unit() - 1.0) * r,
            (2.0 * self.unit() - 1.0) * r,
            (2.0 * self.unit() - 1.0) * r,
        )
    }

    /// A chain of `segments` with control points in a cube of side 4, a W series of 0 to 5 weights, either W
    /// form, seen at W = 10 from 7 to 12 units away.
    fn view(&mut self, segments: usize) -> Scene {
        let points: Vec<DVec3> = (0..2 * segments + 1).map(|_| self.within(2.0)).collect();
        let count = (self.unit() * 6.0) as usize;
        let weights: Vec<f64> = (0..count).map(|_| 0.1 + 1.4 * self.unit()).collect();
        let nearest = self.unit() < 0.5;
        let mut eye = self.within(12.0);
        while eye.length() < 7.0 {
            eye = self.within(12.0);
        }
        let mut s = Scene::default_scene();
        s.camera = Camera {
            eye,
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_degrees: 40.0,
        };
        s.sources = Sources {
            curves: vec![Curve {
                control_points: points,
                coefficient: 2.0,
                weights,
                look: Default::default(),
                color_series: vec![],
                w_form: if nearest {
                    WForm::Nearest
                } else {
                    WForm::Continuous
                },
            }],
            ..Default::default()
        };
        s.billboard.resolution = 10;
        s
    }
}

/// The views (by their index among the generator's draws) each chain length put furthest off before.
const WORST: [(usize, &[usize]); 2] = [(2, &[34, 75, 126, 147]), (3, &[3, 33, 66])];

#[test]
fn chains_whose_nearest_point_jumps_beside_a_closest_approach_or_and_back_are_integrated_within_the_tolerance()
 {
    let mut gpu = HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)");
    let mut checked = 0;
    for (segments, views) in WORST {
        let mut draws = Draws(0x5eed);
        let last = *views.iter().max().unwrap();
        for v in 0..=last {
            let s = draws.view(segments);
            if !views.contains(&v) {
                continue;
            }
            let want = converged_reference(&s, 1).0;
            let mut setup = FrameSetup::new(&s, s.place_billboard(1.0));
            setup.refine = Refine::EveryTexel;
            let cpu = reference::render_brightness(&setup).values;
            let on_gpu = gpu.brightness(&setup).expect("the GPU renders");
            let tolerance = s.integration.tolerance;
            for (k, &r) in want.iter().enumerate() {
                assert!(
                    (cpu[k] - r).abs() <= tolerance,
                    "{segments} segments, view {v}, texel {k}: CPU {} against {r}",
                    cpu[k]
                );
                assert!(
                    (on_gpu[k] as f64 - r).abs() <= tolerance + 4e-6 * r.abs(),
                    "{segments} segments, view {v}, texel {k}: GPU {} against {r}",
                    on_gpu[k]
                );
            }
            // A chain seen at all: the views were chosen for their bright cores.
            assert!(want.iter().any(|&b| b > 1.0), "view {v}: {want:?}");
            checked += 1;
        }
    }
    assert_eq!(checked, 7);
}
