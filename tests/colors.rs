//! A color per source and HDR intensities: the colored sum `sum B_i Ce_i` the field pass integrates beside B,
//! against each source rendered alone and summed (the independent oracle: B is linear in the sources); the GPU
//! against the CPU twin; scenes in the scene's one color exactly as before; intensities above 1 unclamped in
//! the transparent export; the scene file's keys, errors and round trip.

use std::path::Path;
use std::sync::{Mutex, MutexGuard, OnceLock};

use energywave::frame::FrameSetup;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::Integrator;
use energywave::reference;
use energywave::scene::{Blend, Scene, SceneError};

mod common;
use common::shipped_scene;

fn gpu() -> MutexGuard<'static, HeadlessRenderer> {
    static GPU: OnceLock<Mutex<HeadlessRenderer>> = OnceLock::new();
    GPU.get_or_init(|| Mutex::new(HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)")))
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// The shipped red rings around a blue beam, at `w` texels a side, by `integrator`.
fn rings(w: u32, integrator: Integrator) -> Scene {
    let mut scene = shipped_scene("rings_and_beam.toml");
    scene.billboard.resolution = w;
    scene.integration.integrator = integrator;
    scene.integration.divisions = 400;
    scene
}

/// `scene` with every source but term `k` (points, lines, tori, curves) at coefficient 0: the same rays
/// (their reach depends on where the sources are, not on how bright) and the same share of the tolerance.
fn alone(scene: &Scene, k: usize) -> Scene {
    let mut s = scene.clone();
    let mut i = 0;
    let mut keep = |c: &mut f64| {
        if i != k {
            *c = 0.0;
        }
        i += 1;
    };
    let src = &mut s.sources;
    src.points.iter_mut().for_each(|x| keep(&mut x.coefficient));
    src.lines.iter_mut().for_each(|x| keep(&mut x.coefficient));
    src.tori.iter_mut().for_each(|x| keep(&mut x.coefficient));
    src.curves.iter_mut().for_each(|x| keep(&mut x.coefficient));
    s
}

#[test]
fn the_colored_sum_is_each_source_rendered_alone_and_summed() {
    for integrator in [Integrator::Simpson, Integrator::Adaptive] {
        let scene = rings(20, integrator);
        let bb = scene.place_billboard(1.0);
        let whole = reference::render_brightness(&FrameSetup::new(&scene, bb));
        let looks: Vec<_> = scene.sources.looks().copied().collect();
        assert_eq!(looks.len(), 3);
        let ce = scene.colors.energy_color();
        let mut b_sum = vec![0.0; whole.values.len()];
        let mut g_sum = vec![[0.0; 3]; whole.values.len()];
        for (k, look) in looks.iter().enumerate() {
            let one = reference::render_brightness(&FrameSetup::new(&alone(&scene, k), bb));
            // Alone, a source in one color has the tint B_k (Ce_k - Ce); the beam's color varies along it
            // (its series is checked against a direct evaluation below).
            let series = scene.series_curve(k).is_some();
            let color = scene.colors.color_of(look);
            for (t, (&b, tint)) in one.values.iter().zip(&one.tint).enumerate() {
                b_sum[t] += b;
                for c in 0..3 {
                    g_sum[t][c] += b * ce[c] + tint[c];
                    if !series {
                        assert!(
                            (tint[c] - b * (color[c] - ce[c])).abs() <= 1e-12 * b.abs().max(1.0)
                        );
                    }
                }
            }
        }
        // B and the colored sum G = B Ce + tint against the sum of the sources alone. Simpson is linear in the
        // integrand: the same to rounding. The adaptive integrator picks its nodes term by term, each within
        // its share of the tolerance, which alone keeps.
        let tolerance = match integrator {
            Integrator::Simpson => 1e-12,
            Integrator::Adaptive => scene.integration.tolerance * 1e-6,
        };
        let mut lit = 0;
        for t in 0..whole.values.len() {
            let b = whole.values[t];
            assert!(
                (b - b_sum[t]).abs() <= tolerance * b.max(1.0),
                "{integrator:?} texel {t}"
            );
            for c in 0..3 {
                let g = b * ce[c] + whole.tint[t][c];
                assert!(
                    (g - g_sum[t][c]).abs() <= tolerance * b.max(1.0) * 2.0,
                    "{integrator:?} texel {t} channel {c}: {g} against {}",
                    g_sum[t][c]
                );
            }
            lit += whole.tint[t].iter().any(|&x| x.abs() > 0.05) as usize;
        }
        assert!(lit > 40, "the rings tint the texture: {lit} texels");
    }
}

#[test]
fn sources_in_the_scene_color_render_as_the_scene_did_to_the_bit() {
    let mut scene = shipped_scene("mixed.toml");
    scene.billboard.resolution = 24;
    let bb = scene.place_billboard(1.0);
    let plain = reference::render_brightness(&FrameSetup::new(&scene, bb));
    assert!(plain.tint.iter().all(|t| *t == [0.0; 3]));
    let frame = reference::compose_frame(&FrameSetup::new(&scene, bb), &plain, 40, 40, false);
    // Every source given the scene's color and intensity explicitly: nothing changes.
    let mut explicit = scene.clone();
    let (energy, intensity) = (scene.colors.energy, scene.colors.energy_intensity);
    for look in looks_mut(&mut explicit) {
        look.color = Some(energy);
        look.intensity = Some(intensity);
    }
    assert!(!explicit.tinted());
    let texture = reference::render_brightness(&FrameSetup::new(&explicit, bb));
    assert_eq!(texture, plain);
    assert_eq!(
        reference::compose_frame(&FrameSetup::new(&explicit, bb), &texture, 40, 40, false),
        frame
    );
    let mut g = gpu();
    let explicit_frame = g.render(&explicit, 40, 40, false).unwrap().pixels;
    assert_eq!(
        explicit_frame,
        g.render(&scene, 40, 40, false).unwrap().pixels
    );
    drop(g);
    // Every source in one other color is the scene in that color.
    let orange = [1.0, 0.5, 0.1];
    let mut recolored = scene.clone();
    for look in looks_mut(&mut recolored) {
        look.color = Some(orange);
    }
    let mut orange_scene = scene.clone();
    orange_scene.colors.energy = orange;
    let a = reference::compose_frame(
        &FrameSetup::new(&recolored, bb),
        &reference::render_brightness(&FrameSetup::new(&recolored, bb)),
        40,
        40,
        false,
    );
    let b = reference::compose_frame(&FrameSetup::new(&orange_scene, bb), &plain, 40, 40, false);
    for (p, q) in a.iter().zip(&b) {
        assert!((0..4).all(|c| (p[c] - q[c]).abs() < 1e-12), "{p:?} {q:?}");
    }
}

fn looks_mut(scene: &mut Scene) -> Vec<&mut energywave::field::Look> {
    let s = &mut scene.sources;
    (s.points.iter_mut().map(|x| &mut x.look))
        .chain(s.lines.iter_mut().map(|x| &mut x.look))
        .chain(s.tori.iter_mut().map(|x| &mut x.look))
        .chain(s.curves.iter_mut().map(|x| &mut x.look))
        .collect()
}

#[test]
fn the_gpu_tint_matches_the_cpu_twin() {
    for integrator in [Integrator::Simpson, Integrator::Adaptive] {
        let scene = rings(40, integrator);
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb));
        let mut g = gpu();
        let b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let tint = g.tint().unwrap();
        let largest = (FrameSetup::new(&scene, bb).terms.iter())
            .flat_map(|t| t.tint)
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let mut worst: f64 = 0.0;
        for t in 0..b.len() {
            let scale = cpu.values[t].abs().max(0.01);
            let rel = (b[t] as f64 - cpu.values[t]).abs() / scale;
            assert!(
                rel <= 1.5e-4,
                "{integrator:?} texel {t}: B {} against {}",
                b[t],
                cpu.values[t]
            );
            for (c, (&g, &want)) in tint[t].iter().zip(&cpu.tint[t]).enumerate() {
                let rel = (g as f64 - want).abs() / (scale * largest);
                assert!(
                    rel <= 1.5e-4,
                    "{integrator:?} texel {t} channel {c}: tint {g} against {want}"
                );
                worst = worst.max(rel);
            }
        }
        eprintln!("{integrator:?}: worst tint error {worst:.2e} of B times the largest tint");
    }
}

#[test]
fn colored_frames_match_the_cpu_in_every_blend_and_the_transparent_export() {
    let (w, h) = (72, 56);
    for blend in [Blend::Papers, Blend::Over] {
        let mut scene = rings(48, Integrator::Adaptive);
        scene.colors.blend = blend;
        let bb = scene.place_billboard(w as f64 / h as f64);
        let texture = reference::render_brightness(&FrameSetup::new(&scene, bb));
        for transparent in [false, true] {
            let cpu =
                reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, w, h, transparent);
            let frame = gpu().render(&scene, w, h, transparent).unwrap();
            let mut red = 0;
            for (p, q) in frame.pixels.iter().zip(&cpu) {
                for c in 0..4 {
                    let scale = q[c].abs().max(1.0);
                    assert!(
                        (p[c] as f64 - q[c]).abs() <= 2.0 / 255.0 * scale,
                        "{blend:?} transparent {transparent}: {p:?} against the CPU's {q:?}"
                    );
                }
                red += (q[0] > 0.4 && q[0] > 2.0 * q[2]) as usize;
            }
            // Both colors show: red rings and a blue beam.
            let blue = cpu.iter().filter(|q| q[2] > 0.3 && q[2] > q[0]).count();
            assert!(red > 30 && blue > 10, "red {red}, blue {blue}");
        }
    }
}

#[test]
fn intensities_above_one_stay_unclamped_in_the_transparent_export() {
    let mut scene = shipped_scene("mixed.toml");
    scene.billboard.resolution = 32;
    let bb = scene.place_billboard(1.0);
    let texture = reference::render_brightness(&FrameSetup::new(&scene, bb));
    let base = reference::compose_frame(&FrameSetup::new(&scene, bb), &texture, 32, 32, true);
    // The point four times as intense as its color; the scene twice.
    scene.sources.points[0].look.intensity = Some(4.0);
    scene.colors.energy_intensity = 2.0;
    let hot = reference::render_brightness(&FrameSetup::new(&scene, bb));
    // B does not change: intensity is color, not energy.
    assert_eq!(hot.values, texture.values);
    let frame = reference::compose_frame(&FrameSetup::new(&scene, bb), &hot, 32, 32, true);
    let brightest = frame.iter().map(|p| p[2]).fold(0.0, f64::max);
    assert!(brightest > 2.0, "HDR values survive unclamped: {brightest}");
    // Where the point contributes nothing the glow is twice the base; everywhere it is at least that.
    for (p, q) in frame.iter().zip(&base) {
        for c in 0..3 {
            assert!(p[c] >= 2.0 * q[c] - 1e-9);
        }
        assert_eq!(p[3], q[3]);
    }
    let gpu_frame = gpu().render(&scene, 32, 32, true).unwrap();
    for (p, q) in gpu_frame.pixels.iter().zip(&frame) {
        for c in 0..3 {
            assert!(
                (p[c] as f64 - q[c]).abs() <= 4e-3 * q[c].max(1.0),
                "{p:?} {q:?}"
            );
        }
    }
    // The opaque frame shows the clamp.
    let opaque = gpu().render(&scene, 32, 32, false).unwrap();
    assert!(opaque.pixels.iter().all(|p| p.iter().all(|&c| c <= 1.0)));
    // One texel of the tint by hand: the point's B_0 times (4 Ce_0 - 2 Ce), Ce_0 = Ce.
    let t = 16 * 32 + 16;
    let b0 = reference::render_brightness(&FrameSetup::new(&alone(&scene, 0), bb)).values[t];
    let ce = scene.colors.energy;
    for (tint, ce) in hot.tint[t].iter().zip(ce) {
        assert!((tint - b0 * (4.0 - 2.0) * ce).abs() < 1e-9);
    }
}

/// The quadratic B-spline of `values` on the clamped uniform knot vector at `t`, by the Cox-de Boor recursion
/// (independent of `wseries`' triangular scheme).
fn cox_de_boor(values: &[f64], t: f64) -> f64 {
    let n = values.len();
    match n {
        1 => return values[0],
        2 => return values[0] + (values[1] - values[0]) * t,
        _ => {}
    }
    let segments = (n - 2) as f64;
    let knot = |i: usize| ((i as f64 - 2.0) / segments).clamp(0.0, 1.0);
    fn basis(i: usize, p: usize, t: f64, knot: &dyn Fn(usize) -> f64) -> f64 {
        if p == 0 {
            let (a, b) = (knot(i), knot(i + 1));
            // The last non-empty span holds t = 1.
            return if (a <= t && t < b) || (t >= 1.0 && b >= 1.0 && a < 1.0) {
                1.0
            } else {
                0.0
            };
        }
        let mut v = 0.0;
        let d1 = knot(i + p) - knot(i);
        if d1 > 0.0 {
            v += (t - knot(i)) / d1 * basis(i, p - 1, t, knot);
        }
        let d2 = knot(i + p + 1) - knot(i + 1);
        if d2 > 0.0 {
            v += (knot(i + p + 1) - t) / d2 * basis(i + 1, p - 1, t, knot);
        }
        v
    }
    (0..n).map(|i| values[i] * basis(i, 2, t, &knot)).sum()
}

#[test]
fn a_curve_s_color_series_is_its_b_spline_along_the_nearest_point() {
    use energywave::field::{curve, falloff, wseries};
    use energywave::geometry::ray_end;
    use energywave::integrate::zeta;
    use energywave::reference::simpson::simpson_refined;
    // The series itself, against Cox-de Boor, at many t and for every length.
    for series in [
        vec![[0.2, 0.4, 0.9]],
        vec![[1.0, 1.0, 1.0], [0.1, 0.3, 1.0]],
        vec![[1.0, 1.0, 1.0], [0.6, 0.8, 1.0], [0.2, 0.45, 1.0]],
        vec![
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.5, 0.5, 0.5],
        ],
    ] {
        for k in 0..=50 {
            let t = k as f64 / 50.0;
            let got = wseries::evaluate_colors(&series, t);
            for (c, g) in got.iter().enumerate() {
                let channel: Vec<f64> = series.iter().map(|x| x[c]).collect();
                assert!(
                    (g - cox_de_boor(&channel, t)).abs() < 1e-12,
                    "{series:?} at {t}"
                );
            }
        }
    }
    // The beam alone, with an intensity: its tint on a few texel rays against the integral, converged, of its
    // term times (I Cs(t*) - Ce), Cs by Cox-de Boor at the nearest point's t*.
    for integrator in [Integrator::Simpson, Integrator::Adaptive] {
        let mut scene = rings(16, integrator);
        let beam = 2;
        assert!(scene.series_curve(beam).is_some());
        scene.sources.curves[0].look.intensity = Some(1.7);
        let scene = alone(&scene, beam);
        let bb = scene.place_billboard(1.0);
        let texture = reference::render_brightness(&FrameSetup::new(&scene, bb));
        let (ce, curve) = (scene.colors.energy_color(), &scene.sources.curves[0]);
        let reach = FrameSetup::new(&scene, bb).reach;
        let settings = scene.integration.on_ray(reach.stretch);
        for (i, j) in [(8, 8), (3, 8), (12, 7), (8, 2), (15, 15)] {
            let s = bb.texel_center(i, j, 16);
            let e = ray_end(s, scene.camera.eye, reach.nu);
            for c in 0..3 {
                let channel: Vec<f64> = curve.color_series.iter().map(|x| x[c]).collect();
                let f = |t: f64| {
                    let n = curve::nearest_on_chain(&curve.control_points, s + (e - s) * t);
                    curve.coefficient
                        * (1.7 * cox_de_boor(&channel, n.t) - ce[c])
                        * falloff(n.distance, settings.epsilon)
                        * zeta(t, settings.alpha, settings.beta)
                };
                let (want, _) = simpson_refined(f, 2000, 1e-11, 30);
                let got = texture.tint[(j * 16 + i) as usize][c];
                let allowed = match integrator {
                    Integrator::Simpson => 1e-3 * want.abs().max(0.01),
                    Integrator::Adaptive => 2.0 * scene.integration.tolerance,
                };
                assert!(
                    (got - want).abs() <= allowed,
                    "{integrator:?} texel ({i}, {j}) channel {c}: {got} against {want}"
                );
            }
        }
    }
}

#[test]
fn a_series_of_one_color_is_that_color() {
    let mut scene = rings(16, Integrator::Adaptive);
    let bb = scene.place_billboard(1.0);
    scene.sources.curves[0].color_series = vec![[0.9, 0.2, 0.6]];
    let series = reference::render_brightness(&FrameSetup::new(&scene, bb));
    scene.sources.curves[0].color_series.clear();
    scene.sources.curves[0].look.color = Some([0.9, 0.2, 0.6]);
    let one = reference::render_brightness(&FrameSetup::new(&scene, bb));
    assert_eq!(series.values, one.values);
    for (a, b) in series.tint.iter().zip(&one.tint) {
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 1e-6 * b[c].abs().max(1.0),
                "{a:?} {b:?}"
            );
        }
    }
}

fn invalid(text: &str) -> String {
    match Scene::parse(text, Path::new("bad.toml")) {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        other => panic!("{text:?} was not refused: {other:?}"),
    }
}

#[test]
fn colors_and_intensities_in_scene_files() {
    let msg = invalid(
        "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\ncolor = [1.2, 0.0, 0.0]\n",
    );
    assert!(
        msg.contains("bad.toml:4:") && msg.contains("points[0].color"),
        "{msg}"
    );
    assert!(msg.contains("0..1"), "{msg}");
    let msg = invalid(
        "[[tori]]\nmajor_radius = 1.0\ncoefficient = 1.0\n\n[[tori]]\nmajor_radius = 1.0\ncoefficient = 1.0\nintensity = -1.0\n",
    );
    assert!(
        msg.contains("bad.toml:8:") && msg.contains("tori[1].intensity"),
        "{msg}"
    );
    let msg = invalid(
        "[colors]\nenergy_intensity = 1e9\n\n[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n",
    );
    assert!(
        msg.contains("colors.energy_intensity") && msg.contains("0..=1000"),
        "{msg}"
    );
    let msg = invalid(
        "[[curves]]\ncontrol_points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0]]\ncoefficient = 1.0\ncolour = [1.0, 0.0, 0.0]\n",
    );
    assert!(msg.contains("colour"), "{msg}");
    let curve = "[[curves]]\ncontrol_points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0]]\ncoefficient = 1.0\n";
    let msg = invalid(&format!("{curve}color_series = []\n"));
    assert!(
        msg.contains("bad.toml:4:")
            && msg.contains("curves[0].color_series")
            && msg.contains("empty"),
        "{msg}"
    );
    let msg = invalid(&format!(
        "{curve}color_series = [[1.0, 1.0, 1.0], [0.0, -0.5, 1.0]]\n"
    ));
    assert!(
        msg.contains("curves[0].color_series[1]") && msg.contains("0..1"),
        "{msg}"
    );
    let msg = invalid(&format!(
        "{curve}color = [1.0, 0.0, 0.0]\ncolor_series = [[1.0, 1.0, 1.0]]\n"
    ));
    assert!(msg.contains("not both"), "{msg}");

    // Written back and read again: the same scene, each source's own color and intensity kept, and the keys
    // of sources without their own left out.
    let scene = shipped_scene("rings_and_beam.toml");
    let text = scene.to_toml();
    assert_eq!(Scene::parse(&text, Path::new("saved.toml")).unwrap(), scene);
    assert_eq!(text.matches("color = ").count(), 2, "{text}");
    assert_eq!(text.matches("color_series = ").count(), 1, "{text}");
    assert_eq!(text.matches("intensity = ").count(), 1, "{text}");
    // One edit, one line changed in the file's own text.
    let path = common::scenes_dir().join("rings_and_beam.toml");
    let original = std::fs::read_to_string(&path).unwrap();
    let mut edited = scene.clone();
    edited.sources.tori[1].look.color = Some([0.2, 1.0, 0.4]);
    let saved = energywave::scene::format::update_text(&original, &scene, &edited, &path);
    let changed: Vec<_> = original
        .lines()
        .zip(saved.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(
        changed,
        [("color = [1.0, 0.55, 0.1]", "color = [0.2, 1.0, 0.4]")]
    );
    assert_eq!(original.lines().count(), saved.lines().count());
}

#[test]
fn color_series_on_degenerate_chains_meet_the_converged_integral_on_the_cpu_and_the_gpu() {
    use energywave::field::{Curve, Sources, curve, falloff};
    use energywave::geometry::ray_end;
    use energywave::integrate::zeta;
    use energywave::reference::simpson::simpson_refined;
    use glam::DVec3;
    let chains = common::degenerate_chains();
    let series = vec![[1.0, 1.0, 1.0], [0.9, 0.3, 0.1], [0.2, 0.45, 1.0]];
    let mut g = gpu();
    for (name, points) in chains {
        let mut scene = Scene::default_scene();
        scene.billboard.resolution = 16;
        scene.animation = None;
        scene.sources = Sources {
            curves: vec![Curve {
                control_points: points.iter().map(|&p| DVec3::from(p)).collect(),
                coefficient: 3.0,
                weights: vec![0.2, 1.0, 0.4, 0.9, 0.3],
                look: Default::default(),
                color_series: series.clone(),
                w_form: energywave::field::WForm::Nearest,
            }],
            ..Sources::default()
        };
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb));
        g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let gpu_tint = g.tint().unwrap();
        // Each within the tolerance of the converged value (|Cs - Ce| <= 1 here), so within twice of each other:
        // the adaptive integrator's promise, which on these chains is not a relative one.
        let tolerance = scene.integration.tolerance;
        for (t, (gt, ct)) in gpu_tint.iter().zip(&cpu.tint).enumerate() {
            for (ch, (&g, &c)) in gt.iter().zip(ct).enumerate() {
                let g = g as f64;
                assert!(
                    (g - c).abs() <= 2.0 * tolerance,
                    "{name}: texel {t} channel {ch}: GPU {g} CPU {c}"
                );
            }
        }
        let (ce, curve) = (scene.colors.energy_color(), &scene.sources.curves[0]);
        let reach = FrameSetup::new(&scene, bb).reach;
        let settings = scene.integration.on_ray(reach.stretch);
        for (i, j) in [(8, 8), (4, 9), (11, 6), (2, 13)] {
            let s = bb.texel_center(i, j, 16);
            let e = ray_end(s, scene.camera.eye, reach.nu);
            for ch in 0..3 {
                let channel: Vec<f64> = series.iter().map(|x| x[ch]).collect();
                let f = |t: f64| {
                    let n = curve::nearest_on_chain(&curve.control_points, s + (e - s) * t);
                    curve.coefficient
                        * cox_de_boor(&curve.weights, n.t)
                        * (cox_de_boor(&channel, n.t) - ce[ch])
                        * falloff(n.distance, settings.epsilon)
                        * zeta(t, settings.alpha, settings.beta)
                };
                let (want, _) = simpson_refined(f, 2000, 1e-11, 30);
                let k = (j * 16 + i) as usize;
                for (twin, got) in [("CPU", cpu.tint[k][ch]), ("GPU", gpu_tint[k][ch] as f64)] {
                    assert!(
                        (got - want).abs() <= 2.0 * tolerance,
                        "{name}: {twin} texel ({i}, {j}) channel {ch}: {got} against {want}"
                    );
                }
            }
        }
    }
}
