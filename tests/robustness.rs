//! Degenerate but valid geometry gives defined, finite results on the CPU reference and on the GPU, and random
//! valid scenes never produce a non-finite brightness with any integrator, on either, and survive a save and load.

mod common;

use std::sync::{Mutex, MutexGuard, OnceLock};

use energywave::field::{Curve, Line, Point, Sources, Torus};
use energywave::frame::FrameSetup;
use energywave::geometry::Camera;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::Integrator;
use energywave::reference;
use energywave::scene::Scene;
use glam::DVec3;
use proptest::prelude::*;

fn gpu() -> MutexGuard<'static, HeadlessRenderer> {
    static GPU: OnceLock<Mutex<HeadlessRenderer>> = OnceLock::new();
    GPU.get_or_init(|| Mutex::new(HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)")))
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

fn scene(camera: Camera, sources: Sources) -> Scene {
    let mut s = Scene::default_scene();
    s.camera = camera;
    s.sources = sources;
    // Odd: the central texel's ray is the view axis, exactly through the target (and along the line seen
    // end-on, the torus's axis, through the point).
    s.billboard.resolution = 21;
    s.integration.divisions = 32;
    s
}

fn camera(eye: DVec3, target: DVec3) -> Camera {
    Camera {
        eye,
        target,
        up: DVec3::Y,
        fov_y_degrees: 40.0,
    }
}

fn curve(points: &[DVec3]) -> Curve {
    Curve {
        control_points: points.to_vec(),
        coefficient: 2.0,
        weights: vec![],
        look: Default::default(),
        color_series: Vec::new(),
        w_form: energywave::field::WForm::Nearest,
    }
}

/// Renders on both and checks every texel is finite; returns the worst relative difference.
fn finite_on_both(name: &str, scene: &Scene) -> f64 {
    let bb = scene.place_billboard(1.0);
    assert!(
        bb.center.is_finite() && bb.size.is_finite() && bb.size > 0.0,
        "{name}: billboard {bb:?}"
    );
    let cpu = reference::render_brightness(&FrameSetup::new(scene, bb));
    let g = gpu()
        .brightness(&FrameSetup::new(scene, bb))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut worst: f64 = 0.0;
    for (k, (&c, &g)) in cpu.values.iter().zip(&g).enumerate() {
        assert!(c.is_finite(), "{name}: CPU texel {k} is {c}");
        assert!(g.is_finite(), "{name}: GPU texel {k} is {g}");
        worst = worst.max((g as f64 - c).abs() / c.abs().max(0.01));
    }
    // The composed frame too.
    let frame = gpu()
        .render(scene, 24, 18, false)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(
        frame
            .pixels
            .iter()
            .flatten()
            .all(|c| c.is_finite() && (0.0..=1.0).contains(c)),
        "{name}: frame"
    );
    worst
}

#[test]
fn degenerate_geometry_is_finite_on_cpu_and_gpu() {
    let origin = DVec3::ZERO;
    let far = camera(DVec3::new(0.0, 0.0, 12.0), origin);
    let (a, b) = (DVec3::new(-2.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0));
    let cases: Vec<(&str, Scene, f64)> = vec![
        // A point source on the view axis: the central rays pass through it (the epsilon clamp).
        (
            "point on the rays",
            scene(
                far.clone(),
                Sources {
                    points: vec![Point {
                        position: origin,
                        coefficient: 3.0,
                        look: Default::default(),
                    }],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        // The camera on a torus's axis: the central ray goes through the center, along the axis.
        (
            "ray along the torus axis",
            scene(
                far.clone(),
                Sources {
                    tori: vec![Torus {
                        center: origin,
                        axis: DVec3::Z,
                        major_radius: 1.0,
                        coefficient: 3.0,
                        look: Default::default(),
                    }],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        // A torus seen edge-on: rays run along the circle's plane.
        (
            "torus edge-on",
            scene(
                far.clone(),
                Sources {
                    tori: vec![Torus {
                        center: origin,
                        axis: DVec3::Y,
                        major_radius: 1.0,
                        coefficient: 3.0,
                        look: Default::default(),
                    }],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        (
            "straight curve",
            scene(
                far.clone(),
                Sources {
                    curves: vec![curve(&[a, origin, b])],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        (
            "straight curve, uneven",
            scene(
                far.clone(),
                Sources {
                    curves: vec![curve(&[a, a * 0.9, b])],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        (
            "coincident control points",
            scene(
                far.clone(),
                Sources {
                    curves: vec![curve(&[origin, origin, origin])],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        (
            "two coincident control points",
            scene(
                far.clone(),
                Sources {
                    curves: vec![curve(&[a, a, b])],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        // A line seen end-on: every ray is parallel to it, the central one along it.
        (
            "line end-on",
            scene(
                far.clone(),
                Sources {
                    lines: vec![Line {
                        point: origin,
                        direction: DVec3::Z,
                        coefficient: 0.5,
                        look: Default::default(),
                    }],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        // The camera inside the effect.
        (
            "camera inside the effect",
            scene(
                camera(DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.0, 0.0, -1.0)),
                Sources {
                    tori: vec![Torus {
                        center: origin,
                        axis: DVec3::Z,
                        major_radius: 2.0,
                        coefficient: 3.0,
                        look: Default::default(),
                    }],
                    curves: vec![curve(&[a, origin + DVec3::Y, b])],
                    ..Default::default()
                },
            ),
            1e-3,
        ),
        // Sources far outside a fixed billboard.
        (
            "sources far away",
            {
                let mut s = scene(
                    far.clone(),
                    Sources {
                        points: vec![Point {
                            position: DVec3::new(500.0, 300.0, -200.0),
                            coefficient: 5.0,
                            look: Default::default(),
                        }],
                        curves: vec![curve(&[
                            DVec3::splat(-800.0),
                            DVec3::splat(-790.0),
                            DVec3::new(-780.0, -800.0, -800.0),
                        ])],
                        ..Default::default()
                    },
                );
                s.billboard.center = Some(DVec3::new(0.0, 0.0, 8.0));
                s.billboard.size = Some(1.0);
                s
            },
            1e-3,
        ),
    ];
    for (name, s, tolerance) in &cases {
        let worst = finite_on_both(name, s);
        eprintln!("{name}: worst relative GPU/CPU difference {worst:.2e}");
        assert!(
            worst <= *tolerance,
            "{name}: GPU and CPU differ by {worst:.2e}"
        );
    }
}

/// The default scene scaled by `k` (camera, sources, epsilon and the decay length together).
fn scaled(k: f64) -> Scene {
    let mut s = Scene::default_scene();
    s.billboard.resolution = 20;
    s.integration.divisions = 32;
    s.camera.eye *= k;
    s.camera.target *= k;
    s.integration.epsilon *= k;
    s.integration.decay_length *= k;
    for c in &mut s.sources.curves {
        c.control_points.iter_mut().for_each(|p| *p *= k);
        c.coefficient *= k;
    }
    for t in &mut s.sources.tori {
        t.center *= k;
        t.major_radius *= k;
        t.coefficient *= k;
    }
    s
}

#[test]
fn huge_and_tiny_scales_give_the_same_picture() {
    // The method is scale invariant when the coefficients, epsilon and the decay length scale with the scene (B ~ coefficient /
    // distance): 1e-3 and 1e3 world units must give the picture of scale 1, on the CPU and on the GPU.
    let reference_b = {
        let s = scaled(1.0);
        reference::render_brightness(&FrameSetup::placed(&s, 1.0)).values
    };
    for k in [1e-3, 1e3] {
        let s = scaled(k);
        let worst = finite_on_both(&format!("scale {k}"), &s);
        eprintln!("scale {k}: worst relative GPU/CPU difference {worst:.2e}");
        assert!(
            worst <= 1e-3,
            "scale {k}: GPU and CPU differ by {worst:.2e}"
        );
        let cpu = reference::render_brightness(&FrameSetup::placed(&s, 1.0)).values;
        for (x, y) in cpu.iter().zip(&reference_b) {
            assert!(
                (x - y).abs() <= 1e-9 * y.abs().max(1.0),
                "scale {k}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn thousands_of_sources() {
    let mut sources = Sources::default();
    for i in 0..2000 {
        let a = i as f64 * 0.1;
        sources.points.push(Point {
            position: DVec3::new(a.cos() * 3.0, (a * 0.37).sin() * 2.0, a.sin() * 3.0),
            coefficient: 0.01,
            look: Default::default(),
        });
    }
    for i in 0..200 {
        let x = i as f64 * 0.03 - 3.0;
        sources.curves.push(curve(&[
            DVec3::new(x, -1.0, 0.0),
            DVec3::new(x, 0.0, 0.5),
            DVec3::new(x, 1.0, 0.0),
        ]));
    }
    sources.curves.iter_mut().for_each(|c| c.coefficient = 0.01);
    let mut s = scene(camera(DVec3::new(0.0, 2.0, 14.0), DVec3::ZERO), sources);
    s.billboard.resolution = 8;
    s.integration.divisions = 8;
    let worst = finite_on_both("2200 sources", &s);
    assert!(worst <= 1e-3, "{worst:.2e}");
}

fn vec3(r: f64) -> impl Strategy<Value = DVec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn unit() -> impl Strategy<Value = DVec3> {
    vec3(1.0)
        .prop_filter("non-zero", |v| v.length() > 1e-3)
        .prop_map(|v| v.normalize())
}

fn sources() -> impl Strategy<Value = Sources> {
    let point = (vec3(10.0), -10.0..10.0f64).prop_map(|(position, coefficient)| Point {
        position,
        coefficient,
        look: Default::default(),
    });
    let line =
        (vec3(10.0), unit(), -3.0..3.0f64).prop_map(|(point, direction, coefficient)| Line {
            point,
            direction,
            coefficient,
            look: Default::default(),
        });
    let torus = (vec3(10.0), unit(), 0.001..5.0f64, -10.0..10.0f64).prop_map(
        |(center, axis, major_radius, coefficient)| Torus {
            center,
            axis,
            major_radius,
            coefficient,
            look: Default::default(),
        },
    );
    let curve = (
        1usize..4,
        prop::collection::vec(vec3(10.0), 7),
        -10.0..10.0f64,
        prop::collection::vec(0.0..2.0f64, 0..8),
        any::<bool>(),
    )
        .prop_map(|(k, points, coefficient, weights, nearest)| Curve {
            control_points: points[..2 * k + 1].to_vec(),
            coefficient,
            weights,
            look: Default::default(),
            color_series: Vec::new(),
            w_form: if nearest {
                energywave::field::WForm::Nearest
            } else {
                energywave::field::WForm::Continuous
            },
        });
    (
        prop::collection::vec(point, 0..3),
        prop::collection::vec(line, 0..2),
        prop::collection::vec(torus, 0..3),
        prop::collection::vec(curve, 0..3),
    )
        .prop_map(|(points, lines, tori, curves)| Sources {
            points,
            lines,
            tori,
            curves,
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random valid scenes (any sources, any camera, any valid settings) survive a save and load unchanged, and
    /// never give a non-finite B with any integrator (simpson, jittered simpson, adaptive), on the CPU reference
    /// or on the GPU.
    #[test]
    fn random_valid_scenes_give_finite_brightness(
        sources in sources(),
        eye in vec3(30.0),
        target in vec3(5.0),
        fov in 1.0..170.0f64,
        decay_length in 0.05..60.0f64,
        alpha in 0.01..10.0f64,
        beta in 0.01..10.0f64,
        epsilon in 1e-6..1.0f64,
        half_n in 1u32..12,
        tolerance in 1e-8..0.09f64,
        seed in 0u32..1000,
    ) {
        prop_assume!((eye - target).length() > 1e-3);
        prop_assume!(DVec3::Y.cross((target - eye).normalize()).length() > 1e-3);
        let mut s = scene(camera(eye, target), sources);
        s.camera.fov_y_degrees = fov;
        s.billboard.resolution = 6;
        s.integration = energywave::integrate::Integration { divisions: 2 * half_n, decay_length, alpha, beta, epsilon, tolerance, ..Default::default() };
        for (integrator, jitter) in [(Integrator::Simpson, None), (Integrator::Simpson, Some(seed)), (Integrator::Adaptive, None)] {
            s.integration.integrator = integrator;
            s.integration.jitter = jitter;
            let text = s.to_toml();
            let loaded = Scene::parse(&text, std::path::Path::new("random.toml")).map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert_eq!(&loaded, &s, "the scene changed in a save and load:\n{}", text);
            let bb = loaded.place_billboard(1.3);
            prop_assert!(bb.center.is_finite() && bb.size.is_finite() && bb.size > 0.0);
            let b = reference::render_brightness(&FrameSetup::new(&loaded, bb));
            prop_assert!(b.values.iter().all(|x| x.is_finite()), "{:?} CPU: {:?}", integrator, b.values);
            let g = gpu().brightness(&FrameSetup::new(&loaded, bb)).map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert!(g.iter().all(|x| x.is_finite()), "{:?} GPU: {:?}", integrator, g);
        }
    }
}

fn color() -> impl Strategy<Value = [f64; 3]> {
    (0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64).prop_map(|(r, g, b)| [r, g, b])
}

fn look() -> impl Strategy<Value = energywave::field::Look> {
    (prop::option::of(color()), prop::option::of(0.3..2.0f64))
        .prop_map(|(color, intensity)| energywave::field::Look { color, intensity })
}

/// Sources of moderate size around the origin, of either sign, each in a color of its own or the scene's, curves
/// of one to three segments with a W series and a color series or none, in either W form. (Chains of several
/// segments found the nearest point jumping to another segment and back between two samples of the scan, and a
/// jump beside a closest approach hiding it from the scan, in both twins: 5.7e-3 and 1.6e-2 off the converged value
/// here; the scan now finds the closest approaches segment by segment and samples a suspect interval finer.)
fn colored_sources() -> impl Strategy<Value = Sources> {
    let point = (vec3(1.5), -3.0..3.0f64, look()).prop_map(|(position, coefficient, look)| Point {
        position,
        coefficient,
        look,
    });
    let line = (vec3(1.5), unit(), -1.0..1.0f64, look()).prop_map(
        |(point, direction, coefficient, look)| Line {
            point,
            direction,
            coefficient,
            look,
        },
    );
    let torus = (vec3(1.0), unit(), 0.3..2.0f64, -3.0..3.0f64, look()).prop_map(
        |(center, axis, major_radius, coefficient, look)| Torus {
            center,
            axis,
            major_radius,
            coefficient,
            look,
        },
    );
    let curve = (
        1usize..4,
        prop::collection::vec(vec3(2.0), 7),
        -3.0..3.0f64,
        prop::collection::vec(0.1..1.5f64, 0..6),
        prop::collection::vec(color(), 0..4),
        look(),
        any::<bool>(),
    )
        .prop_map(
            |(k, points, coefficient, weights, color_series, look, nearest)| Curve {
                control_points: points[..2 * k + 1].to_vec(),
                coefficient,
                weights,
                // A series is the curve's color: it has no other.
                look: energywave::field::Look {
                    color: look.color.filter(|_| color_series.is_empty()),
                    ..look
                },
                color_series,
                w_form: if nearest {
                    energywave::field::WForm::Nearest
                } else {
                    energywave::field::WForm::Continuous
                },
            },
        );
    (
        prop::collection::vec(point, 0..3),
        prop::collection::vec(line, 0..2),
        prop::collection::vec(torus, 0..2),
        prop::collection::vec(curve, 0..2),
    )
        .prop_map(|(points, lines, tori, curves)| Sources {
            points,
            lines,
            tori,
            curves,
        })
        .prop_filter("a source", |s| !s.is_empty())
}

/// Spheres, boxes and planes (infinite or square) around the effect.
fn objects() -> impl Strategy<Value = Vec<energywave::objects::Object>> {
    use energywave::objects::{Object, Shape};
    let shape = prop_oneof![
        (vec3(3.0), 0.2..1.5f64).prop_map(|(center, radius)| Shape::Sphere { center, radius }),
        (vec3(3.0), vec3(1.0), vec3(90.0)).prop_map(|(center, size, rotation)| Shape::Box {
            center,
            size: size.abs() + DVec3::splat(0.1),
            rotation,
        }),
        (vec3(2.0), unit(), prop::option::of(0.5..6.0f64)).prop_map(|(point, normal, size)| {
            Shape::Plane {
                point,
                normal,
                size,
            }
        }),
    ];
    prop::collection::vec(
        (shape, color()).prop_map(|(shape, color)| Object {
            shape,
            color,
            translucent: None,
        }),
        0..3,
    )
}

proptest! {
    // A fixed seed: the same scenes on every run and machine, so that a failure here is one to reproduce.
    #![proptest_config(ProptestConfig {
        cases: 64,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_2026),
        ..ProptestConfig::default()
    })]

    /// Random scenes with everything a scene may hold at once: sources of both signs with their colors and color
    /// series, objects, both decays, both blends, glare. Each survives a save and load unchanged; on every texel
    /// the adaptive integrator is within its tolerance of the converged reference on the CPU (and f32's rounding
    /// more on the GPU), the GPU within the twins' bound of the CPU with simpson, and the composed frames (the
    /// blend, the objects, the glare) alike on both, opaque and transparent.
    #[test]
    fn random_scenes_with_objects_colors_and_every_setting_agree_with_the_references(
        sources in colored_sources(),
        objects in objects(),
        eye in vec3(12.0).prop_filter("outside the effect", |e| e.length() > 7.0),
        fov in 20.0..60.0f64,
        rms in any::<bool>(),
        over in any::<bool>(),
        glare in prop::option::of((0.2..1.5f64, 0.01..0.08f64, 0.2..2.0f64)),
        energy in color(),
        background in color(),
    ) {
        use energywave::integrate::Decay;
        use energywave::reference::converged::converged_reference;
        use energywave::scene::{Blend, Glare};
        prop_assume!(DVec3::Y.cross(-eye.normalize()).length() > 1e-2);
        let mut s = scene(camera(eye, DVec3::ZERO), sources);
        s.camera.fov_y_degrees = fov;
        s.billboard.resolution = 10;
        s.objects = objects;
        s.integration.decay = if rms { Decay::Rms } else { Decay::Distance };
        s.colors.blend = if over { Blend::Over } else { Blend::Papers };
        s.colors.energy = energy;
        s.colors.background = background;
        s.glare = glare.map(|(threshold, size, strength)| Glare { threshold, size, strength });
        let text = s.to_toml();
        let loaded = Scene::parse(&text, std::path::Path::new("random.toml")).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(&loaded, &s, "the scene changed in a save and load:\n{}", text);
        let bb = s.place_billboard(1.0);
        let mut g = gpu();
        // The adaptive integrator against the converged reference, on both twins.
        s.integration.integrator = Integrator::Adaptive;
        let want = converged_reference(&s, 1).0;
        let cpu = reference::render_brightness(&FrameSetup::new(&s, bb)).values;
        let gpu_b = g.brightness(&FrameSetup::new(&s, bb)).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let tolerance = s.integration.tolerance;
        for (k, &r) in want.iter().enumerate() {
            prop_assert!((cpu[k] - r).abs() <= tolerance, "texel {}: CPU {} against {}\n{}", k, cpu[k], r, text);
            prop_assert!((gpu_b[k] as f64 - r).abs() <= tolerance + 1.5e-4 * r.abs().max(0.01),
                "texel {}: GPU {} against {}\n{}", k, gpu_b[k], r, text);
        }
        // Simpson: the GPU against its twin.
        s.integration.integrator = Integrator::Simpson;
        s.integration.divisions = 64;
        let cpu = reference::render_brightness(&FrameSetup::new(&s, bb));
        let gpu_b = g.brightness(&FrameSetup::new(&s, bb)).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for (k, (&x, &y)) in gpu_b.iter().zip(&cpu.values).enumerate() {
            prop_assert!((x as f64 - y).abs() <= 1.5e-4 * y.abs().max(0.01), "simpson texel {}: GPU {} CPU {}\n{}", k, x, y, text);
        }
        // The composed frames: a pixel off by more than a few 8-bit steps only where the picture itself steps
        // inside it, which the GPU's raster (f32 depths and positions) and the CPU's ray-cast can put on either
        // side of the pixel's center. Two such places, each found apart from the code under test where it can be:
        // an object's outline (`common::outline_pixels`, the objects' own ray tests), and any step of the CPU's
        // own picture within the pixel: its 3 x 3 frame spreading by more than the allowance over the pixel's
        // nine points. That covers the outlines again, a point source's hard shadow, and where the glow's texels
        // stop matching the depth of the object behind a pixel (`sample_near_clip`), which at this W = 10 jumps
        // by whole texels across a tilted plane.
        let (w, h) = (48u32, 36u32);
        let allowance = 4.0 / 255.0;
        let bb = s.place_billboard(w as f64 / h as f64);
        let texture = reference::render_brightness(&FrameSetup::new(&s, bb));
        let outlines = common::outline_pixels(&s, w, h);
        for transparent in [false, true] {
            let want = reference::compose_frame(&FrameSetup::new(&s, bb), &texture, w, h, transparent);
            let fine = reference::compose_frame(&FrameSetup::new(&s, bb), &texture, 3 * w, 3 * h, transparent);
            let steps = |i: usize| {
                let (x, y) = (i % w as usize, i / w as usize);
                let block = (0..9).map(|k| fine[(3 * y + k / 3) * 3 * w as usize + 3 * x + k % 3]);
                (0..4).any(|c| {
                    let (lo, hi) = block.clone().map(|p| p[c].clamp(0.0, 1.0)).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
                    hi - lo > allowance
                })
            };
            let frame = g.render(&s, w, h, transparent).map_err(|e| TestCaseError::fail(e.to_string()))?;
            let off: Vec<usize> = (want.iter().zip(&frame.pixels).enumerate())
                .filter(|(_, (c, p))| (0..4).any(|k| (c[k].clamp(0.0, 1.0) - (p[k] as f64).clamp(0.0, 1.0)).abs() > allowance))
                .map(|(i, _)| i)
                .collect();
            let unexcused: Vec<usize> = off.iter().copied().filter(|&i| !outlines[i] && !steps(i)).collect();
            prop_assert!(unexcused.is_empty(), "transparent {}: {} of {} pixels differ ({} on no outline or step: {:?}, the first CPU {:?} GPU {:?})\n{}",
                transparent, off.len(), want.len(), unexcused.len(), unexcused, unexcused.first().map(|&i| want[i]), unexcused.first().map(|&i| frame.pixels[i]), text);
        }
    }
}
