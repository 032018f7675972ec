//! A soak test through the viewer's own code path (its UI, viewport and field passes, offscreen): thousands
//! of frames with random edits, undo and redo, and navigation. No GPU error, no non-finite value, and memory
//! stays flat.

use energywave::field::{Curve, Point, Torus};
use energywave::integrate::Integrator;
use energywave::scene::Scene;
use energywave::viewer::Document;
use energywave::viewer::offscreen::OffscreenViewer;
use glam::DVec3;

/// A small deterministic generator (xorshift64*), so a failure can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Resident memory of this process, bytes.
fn rss() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse::<u64>().ok())
        .unwrap_or(0)
        * 4096
}

const FRAMES: usize = 2000;

#[test]
fn thousands_of_frames_of_random_edits() {
    let mut scene = Scene::default_scene();
    scene.billboard.resolution = 24;
    // Mostly the cheap uniform integrator; case 7 switches to the adaptive one now and then.
    scene.integration.integrator = Integrator::Simpson;
    scene.integration.divisions = 16;
    let mut v = OffscreenViewer::new(Document::new(scene, None), 640, 400)
        .expect("a GPU adapter (lavapipe in CI)");
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut baseline, mut late) = (0, 0);
    for frame in 0..FRAMES {
        let s = v.app.scene_mut();
        match rng.below(12) {
            0 => s.sources.points.push(Point {
                position: DVec3::new(
                    rng.range(-3.0, 3.0),
                    rng.range(-3.0, 3.0),
                    rng.range(-3.0, 3.0),
                ),
                coefficient: rng.range(-2.0, 4.0),
                look: Default::default(),
            }),
            1 if !s.sources.points.is_empty() => {
                let i = rng.below(s.sources.points.len());
                s.sources.points.remove(i);
            }
            2 => s.sources.tori.push(Torus {
                center: DVec3::new(rng.range(-2.0, 2.0), 0.0, 0.0),
                axis: DVec3::new(rng.range(-1.0, 1.0), 1.0, rng.range(-1.0, 1.0)).normalize(),
                major_radius: rng.range(0.01, 3.0),
                coefficient: rng.range(0.0, 5.0),
                look: Default::default(),
            }),
            3 if s.sources.tori.len() > 1 => {
                s.sources.tori.pop();
            }
            4 => {
                let k = 1 + rng.below(3);
                let points = (0..=2 * k)
                    .map(|j| {
                        DVec3::new(
                            j as f64 - k as f64,
                            rng.range(-2.0, 2.0),
                            rng.range(-1.0, 1.0),
                        )
                    })
                    .collect();
                let weights = (0..rng.below(6)).map(|_| rng.range(0.0, 2.0)).collect();
                s.sources.curves.push(Curve {
                    control_points: points,
                    coefficient: rng.range(0.0, 6.0),
                    weights,
                    look: Default::default(),
                    color_series: Vec::new(),
                    w_form: energywave::field::WForm::default(),
                });
            }
            5 if s.sources.curves.len() > 1 => {
                s.sources.curves.remove(0);
            }
            6 => {
                if let Some(c) = s.sources.curves.first_mut() {
                    let j = rng.below(c.control_points.len());
                    c.control_points[j] += DVec3::new(
                        rng.range(-0.5, 0.5),
                        rng.range(-0.5, 0.5),
                        rng.range(-0.5, 0.5),
                    );
                }
            }
            7 => {
                s.integration.integrator = if rng.below(4) == 0 {
                    Integrator::Adaptive
                } else {
                    Integrator::Simpson
                };
                s.integration.tolerance = rng.range(1e-4, 1e-2);
                s.integration.divisions = 2 * (1 + rng.below(24)) as u32;
                s.billboard.resolution = 8 + rng.below(32) as u32;
                s.integration.epsilon = rng.range(1e-4, 0.1);
                s.integration.decay_length = rng.range(0.5, 40.0);
            }
            8 => s.colors.energy = [rng.unit(), rng.unit(), rng.unit()],
            9 => energywave::viewer::navigation::orbit(
                &mut s.camera,
                rng.range(-0.5, 0.5),
                rng.range(-0.3, 0.3),
            ),
            10 => energywave::viewer::navigation::zoom(&mut s.camera, rng.range(0.7, 1.4), None),
            _ => {
                if rng.unit() < 0.5 {
                    v.app.undo();
                } else {
                    v.app.redo();
                }
            }
        }
        v.frame().unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        // The field itself, every frame: the picture's clamp would hide a NaN or an infinity in B.
        let field = v
            .field_values()
            .unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        assert!(
            field.iter().all(|b| b.is_finite()),
            "frame {frame}: a non-finite value in the field texture"
        );
        // The most memory held in the second quarter against the most in the second half: the viewer keeps the
        // compiled pipelines of a few structures (gpu::field_pass KEPT_STRUCTURES) and compiles on a thread of
        // its own, so resident memory steps up and down as compiles come and go; a leak keeps climbing (4.4 GB
        // over these frames, when the compiled pipelines were kept without a bound).
        if frame >= FRAMES / 2 {
            late = late.max(rss());
        } else if frame >= FRAMES / 4 {
            baseline = baseline.max(rss());
        }
        if frame % 250 == 0 {
            let pixels = v
                .viewport_image()
                .unwrap_or_else(|e| panic!("frame {frame}: {e}"));
            assert!(
                pixels.iter().flatten().all(|c| c.is_finite()),
                "frame {frame}: a non-finite pixel"
            );
        }
    }
    let growth = late.saturating_sub(baseline);
    eprintln!(
        "{FRAMES} frames; the second half's peak of resident memory is {} KiB over the second quarter's",
        growth / 1024
    );
    // Measured over five runs: 20 to 87 MiB, in steps of 20 to 80 MiB as structures compile, and once 174 MiB in
    // a full suite's run (18 and 69 MiB run alone after it, the same build): the compiles' timing on two loaded
    // cores moves the peaks. The leak this guards against grew by gigabytes.
    assert!(growth < 320 << 20, "memory grew by {} MiB", growth >> 20);
    assert!(
        v.field_renders() > FRAMES as u64 / 3,
        "the field was integrated again as edits came"
    );
}
