//! The rms decay (`integration.decay = "rms"`): each source's B_i is the root of the integral of its squared
//! weighed energy along the view with the sign of its coefficient, `sign(c_i) sqrt(integral of (psi_i zeta)^2
//! dsigma)`. Held to a closed form on a point source of either sign (derived here, apart from the integrators) by
//! both integrators on the CPU and the GPU, sources of both signs with their colors and a color series to a
//! direct quadrature of the definition, to the converged reference on the shipped scenes, and shown to keep an
//! even spread from outshining a spot; the scene key, the command line and the panel.

mod common;

use std::path::Path;
use std::sync::{Mutex, MutexGuard, OnceLock};

use energywave::field::{Line, Point, Sources};
use energywave::frame::FrameSetup;
use energywave::geometry::ray_end;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::{Decay, Integration, Integrator};
use energywave::reference;
use energywave::reference::converged::converged_reference;
use energywave::scene::Scene;
use glam::DVec3;

fn gpu() -> MutexGuard<'static, HeadlessRenderer> {
    static GPU: OnceLock<Mutex<HeadlessRenderer>> = OnceLock::new();
    GPU.get_or_init(|| Mutex::new(HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)")))
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// `integral of u^4 / (q0 + q1 u + q2 u^2) du` from `u0` to `u1`, Q > 0 without real roots (the ray misses the
/// point): long division to `A u^2 + B u + C` and the remainder `D u + E`, whose integral over Q is a logarithm and
/// an arctangent.
fn quartic_over_quadratic(q: [f64; 3], (u0, u1): (f64, f64)) -> f64 {
    let [q0, q1, q2] = q;
    // u^4 = Q (A u^2 + B u + C) + D u + E.
    let a = 1.0 / q2;
    let b = -q1 * a / q2;
    let c = -(q1 * b + q0 * a) / q2;
    let d = -(q1 * c + q0 * b);
    let e = -q0 * c;
    let disc = 4.0 * q2 * q0 - q1 * q1;
    assert!(disc > 0.0, "the ray passes through the point");
    let root = disc.sqrt();
    let poly = |u: f64| a * u * u * u / 3.0 + b * u * u / 2.0 + c * u;
    let log = |u: f64| (d / (2.0 * q2)) * (q0 + q1 * u + q2 * u * u).ln();
    let atan =
        |u: f64| (e - d * q1 / (2.0 * q2)) * 2.0 / root * ((2.0 * q2 * u + q1) / root).atan();
    let f = |u: f64| poly(u) + log(u) + atan(u);
    f(u1) - f(u0)
}

/// A point source's B with the rms decay on the ray S -> E, in closed form: with u = 1 / (s + beta) (settings on
/// the ray, so alpha, beta and the stretch as `Integration::on_ray` gives them), `ds = -du / u^2`, zeta = alpha u^2
/// and d^2 = Q(u) / u^2, the squared term is `b^2 alpha^2 u^4 / Q(u) du` where the point is eps or farther, and
/// `b^2 alpha^2 u^2 / eps^2 du` where it is nearer (the stretch between the roots of Q(u) = eps^2 u^2). The root
/// has the sign of b: the term b S(P) zeta is b's sign all along the ray, and a negative source subtracts.
fn closed_rms(point: DVec3, coefficient: f64, (s, e): (DVec3, DVec3), st: &Integration) -> f64 {
    let dir = e - s;
    let (a, b, c) = (
        dir.length_squared(),
        2.0 * (s - point).dot(dir),
        (s - point).length_squared(),
    );
    let beta = st.beta;
    let q = [a, b - 2.0 * a * beta, a * beta * beta - b * beta + c];
    let (u0, u1) = (1.0 / (1.0 + beta), 1.0 / beta);
    // Q(u) - eps^2 u^2 < 0 between its roots: the stretch closer than eps.
    let eps2 = st.epsilon * st.epsilon;
    let (k2, k1, k0) = (q[2] - eps2, q[1], q[0]);
    let disc = k1 * k1 - 4.0 * k2 * k0;
    let mut cuts = vec![u0, u1];
    if disc > 0.0 {
        for r in [
            (-k1 - disc.sqrt()) / (2.0 * k2),
            (-k1 + disc.sqrt()) / (2.0 * k2),
        ] {
            if r > u0 && r < u1 {
                cuts.push(r);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    let mut integral = 0.0;
    for w in cuts.windows(2) {
        let mid = 0.5 * (w[0] + w[1]);
        let near = q[0] + q[1] * mid + q[2] * mid * mid < eps2 * mid * mid;
        integral += if near {
            (w[1].powi(3) - w[0].powi(3)) / (3.0 * eps2)
        } else {
            quartic_over_quadratic(q, (w[0], w[1]))
        };
    }
    let i = coefficient * coefficient * st.alpha * st.alpha * integral;
    (i / st.stretch).sqrt() * coefficient.signum()
}

/// A scene of one point source seen from `eye`, with the rms decay.
fn point_scene(position: DVec3, coefficient: f64, eye: DVec3, integrator: Integrator) -> Scene {
    let mut scene = Scene::default_scene();
    scene.animation = None;
    scene.sources = Sources {
        points: vec![Point {
            position,
            coefficient,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    scene.camera.eye = eye;
    scene.camera.target = DVec3::ZERO;
    scene.billboard.resolution = 24;
    scene.integration.integrator = integrator;
    scene.integration.decay = Decay::Rms;
    scene.integration.divisions = 4000;
    scene
}

/// Every texel's ray of `scene` with the settings on it.
fn rays(scene: &Scene) -> Vec<((DVec3, DVec3), Integration)> {
    let bb = scene.place_billboard(1.0);
    let reach = FrameSetup::new(scene, bb).reach;
    let w = scene.billboard.resolution;
    (0..w * w)
        .map(|k| {
            let s = bb.texel_center(k % w, k / w, w);
            (
                (s, ray_end(s, scene.camera.eye, reach.nu)),
                scene.integration.on_ray(reach.stretch),
            )
        })
        .collect()
}

#[test]
fn the_closed_form_is_the_integral_it_states() {
    // Independent of the integrators: the closed form against Simpson refined to convergence on the squared term.
    use energywave::integrate::zeta;
    use energywave::reference::simpson::simpson_refined;
    let scene = point_scene(
        DVec3::new(0.3, -0.2, 0.1),
        1.7,
        DVec3::new(1.0, 2.0, 9.0),
        Integrator::Adaptive,
    );
    let mut near = 0;
    for ((s, e), st) in rays(&scene).into_iter().step_by(7) {
        let p = scene.sources.points[0].position;
        let f = |t: f64| {
            let d = (s + (e - s) * t - p).length().max(st.epsilon);
            (1.7 * zeta(t, st.alpha, st.beta) / d).powi(2)
        };
        let (i, _) = simpson_refined(f, 4096, 1e-14, 30);
        let want = (i / st.stretch).sqrt();
        let got = closed_rms(p, 1.7, (s, e), &st);
        assert!((got - want).abs() <= 1e-9 * want, "{got} against {want}");
        near += usize::from(want > 1.0);
    }
    assert!(near > 0, "some rays pass near the point");
    // And a ray through the flat top: the point 0.003 from the ray, eps = 0.01.
    let (s, e) = (DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.0, 0.0, -5.0));
    let st = Integration {
        decay: Decay::Rms,
        ..Integration::default()
    }
    .on_ray(3.0);
    let x = DVec3::new(0.003, 0.0, 0.0);
    let f = |t: f64| {
        let d = (s + (e - s) * t - x).length().max(st.epsilon);
        (zeta(t, st.alpha, st.beta) / d).powi(2)
    };
    let (i, _) = simpson_refined(f, 4096, 1e-14, 30);
    let want = (i / st.stretch).sqrt();
    let got = closed_rms(x, 1.0, (s, e), &st);
    assert!(
        (got - want).abs() <= 1e-9 * want,
        "through the point: {got} against {want}"
    );
}

#[test]
fn both_integrators_meet_the_closed_form_on_a_point_source_on_the_cpu_and_the_gpu() {
    let position = DVec3::new(0.3, -0.2, 0.1);
    let mut g = gpu();
    for integrator in [Integrator::Adaptive, Integrator::Simpson] {
        for (eye, coefficient) in [
            (DVec3::new(1.0, 2.0, 9.0), 1.7),
            (DVec3::new(-4.0, 0.5, 1.5), 1.7),
            (DVec3::new(1.0, 2.0, 9.0), -1.7),
        ] {
            let scene = point_scene(position, coefficient, eye, integrator);
            let bb = scene.place_billboard(1.0);
            let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
            let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
            // The adaptive integrator within its tolerance (and f32's rounding on the GPU); Simpson with n = 4000
            // within 2e-4 of B where the peak is resolved.
            let (tolerance, relative) = match integrator {
                Integrator::Adaptive => (scene.integration.tolerance, 4e-6),
                Integrator::Simpson => (0.0, 2e-4),
            };
            let mut worst: f64 = 0.0;
            for (k, (ray, st)) in rays(&scene).into_iter().enumerate() {
                let want = closed_rms(position, coefficient, ray, &st);
                for (twin, got) in [("CPU", cpu[k]), ("GPU", gpu_b[k] as f64)] {
                    let error = (got - want).abs();
                    worst = worst.max(error / want.abs());
                    assert!(
                        error <= tolerance + relative * want.abs(),
                        "{}, {twin}, eye {eye}, texel {k}: {got} against the closed form {want}",
                        integrator.name()
                    );
                }
            }
            eprintln!(
                "{}, eye {eye}, coefficient {coefficient}: worst relative error {worst:.2e}",
                integrator.name()
            );
        }
    }
}

/// A point, a line, a torus and a chain with a W series and a color series, three of them negative, each in a
/// color of its own or the scene's: every term's sign and color at once.
fn signed_scene(integrator: Integrator) -> Scene {
    use energywave::field::{Curve, Look, Torus, WForm};
    let mut scene = point_scene(
        DVec3::new(0.4, -0.3, 0.2),
        2.0,
        DVec3::new(1.0, 2.0, 9.0),
        integrator,
    );
    scene.billboard.resolution = 12;
    // Simpson's error at the squared term's flat top falls as 1 / n^2: 1e-3 of B at n = 4000 on the point's core.
    scene.integration.divisions = 16000;
    let s = &mut scene.sources;
    s.points[0].look = Look {
        color: Some([1.0, 0.2, 0.1]),
        intensity: None,
    };
    s.lines.push(Line {
        point: DVec3::new(0.0, 0.5, 0.0),
        direction: DVec3::new(1.0, 0.3, 0.0).normalize(),
        coefficient: -0.8,
        look: Look {
            color: Some([0.1, 0.3, 1.0]),
            intensity: Some(1.5),
        },
    });
    s.tori.push(Torus {
        center: DVec3::new(0.0, 0.0, -0.5),
        axis: DVec3::Z,
        major_radius: 1.2,
        coefficient: -1.5,
        look: Look::default(),
    });
    s.curves.push(Curve {
        control_points: vec![
            DVec3::new(-2.0, -1.0, 0.0),
            DVec3::new(0.0, 1.5, 0.3),
            DVec3::new(2.0, -0.5, 0.0),
        ],
        coefficient: -1.2,
        weights: vec![0.3, 1.0, 0.5],
        look: Look::default(),
        color_series: vec![[1.0, 1.0, 1.0], [0.9, 0.3, 0.1], [0.2, 0.45, 1.0]],
        w_form: WForm::Nearest,
    });
    scene
}

/// B and the colored sum G of `scene` on one ray by the definition, each term's integral of its square refined to
/// convergence apart from the integrators: `B_i = sign(c_i) sqrt(J_i / stretch)`, `G = sum B_i Ce_i`, a color
/// series weighed by the term's square (`B_i` times the mean of the series under `(w psi zeta)^2`).
fn rms_by_definition(scene: &Scene, (s, e): (DVec3, DVec3), st: &Integration) -> (f64, [f64; 3]) {
    use energywave::field::{curve, wseries};
    use energywave::integrate::zeta;
    use energywave::reference::simpson::simpson_refined;
    let eps = st.epsilon;
    let at = |t: f64| s + (e - s) * t;
    let shape = |d: f64, t: f64| zeta(t, st.alpha, st.beta) / d.max(eps);
    // Refined to 1e-11 of the integral's size (an absolute tolerance below f64's rounding of a large integral
    // would refine without end).
    let converged = |f: &dyn Fn(f64) -> f64| {
        let rough = simpson_refined(f, 2000, f64::INFINITY, 0).0;
        simpson_refined(f, 2000, 1e-11 * rough.abs(), 30).0
    };
    let src = &scene.sources;
    let mut terms: Vec<(f64, f64, [f64; 3])> = Vec::new();
    for p in &src.points {
        let j = converged(&|t| (p.coefficient * shape((at(t) - p.position).length(), t)).powi(2));
        terms.push((p.coefficient, j, scene.colors.color_of(&p.look)));
    }
    for l in &src.lines {
        let d = |x: DVec3| (x - l.point).cross(l.direction).length();
        let j = converged(&|t| (l.coefficient * shape(d(at(t)), t)).powi(2));
        terms.push((l.coefficient, j, scene.colors.color_of(&l.look)));
    }
    for r in &src.tori {
        let d = |x: DVec3| {
            let q = x - r.center;
            let z = q.dot(r.axis);
            let rho = (q - r.axis * z).length();
            ((rho - r.major_radius).powi(2) + z * z).sqrt()
        };
        let j = converged(&|t| (r.coefficient * shape(d(at(t)), t)).powi(2));
        terms.push((r.coefficient, j, scene.colors.color_of(&r.look)));
    }
    let mut series_glow = [0.0; 3];
    let mut b = 0.0;
    for c in &src.curves {
        let weighed = |x: DVec3, t: f64| {
            let n = curve::nearest_on_chain(&c.control_points, x);
            (
                n.t,
                (c.coefficient * wseries::evaluate(&c.weights, n.t) * shape(n.distance, t)).powi(2),
            )
        };
        let j = converged(&|t| weighed(at(t), t).1);
        let bi = (j / st.stretch).sqrt().copysign(c.coefficient);
        b += bi;
        for (ch, out) in series_glow.iter_mut().enumerate() {
            let jc = converged(&|t| {
                let (u, f) = weighed(at(t), t);
                f * scene.colors.color_along(c, u)[ch]
            });
            *out += bi * jc / j;
        }
    }
    let mut glow = series_glow;
    for (c, j, color) in terms {
        let bi = (j / st.stretch).sqrt().copysign(c);
        b += bi;
        (0..3).for_each(|ch| glow[ch] += bi * color[ch]);
    }
    (b, glow)
}

#[test]
fn negative_sources_subtract_under_rms_as_the_definition_says_with_their_colors() {
    // Against a direct quadrature of the definition, which keeps the sign: B and the tint G - B Ce on every texel,
    // both integrators, CPU and GPU. Squaring the coefficient without giving the sign back turns the three negative
    // sources into light, far outside every allowance here.
    let mut g = gpu();
    for integrator in [Integrator::Adaptive, Integrator::Simpson] {
        let scene = signed_scene(integrator);
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb));
        let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let gpu_tint = g.tint().unwrap();
        let ce = scene.colors.energy_color();
        let tolerance = scene.integration.tolerance;
        let (mut negative, mut worst) = (0, 0.0f64);
        for (k, (ray, st)) in rays(&scene).into_iter().enumerate() {
            let (b, glow) = rms_by_definition(&scene, ray, &st);
            negative += usize::from(b < -0.05);
            // The adaptive integrator within its tolerance on each term (and on the tint, each term's share times
            // its color, at most 1.5 here), f32's rounding on the GPU; Simpson at n = 16000 to 2e-4 of the terms.
            let allowed = |x: f64, twin: &str| match integrator {
                Integrator::Adaptive => {
                    2.0 * tolerance + if twin == "GPU" { 1e-5 * x.abs() } else { 0.0 }
                }
                Integrator::Simpson => 1e-4 + 2e-4 * x.abs(),
            };
            for (twin, got_b, got_tint) in [
                ("CPU", cpu.values[k], cpu.tint[k]),
                ("GPU", gpu_b[k] as f64, gpu_tint[k].map(f64::from)),
            ] {
                worst = worst.max((got_b - b).abs());
                assert!(
                    (got_b - b).abs() <= allowed(b, twin),
                    "{}, {twin}, texel {k}: B {got_b} against {b}",
                    integrator.name()
                );
                for ch in 0..3 {
                    let want = glow[ch] - b * ce[ch];
                    assert!(
                        (got_tint[ch] - want).abs() <= 2.0 * allowed(want, twin),
                        "{}, {twin}, texel {k}, channel {ch}: tint {} against {want}",
                        integrator.name(),
                        got_tint[ch]
                    );
                }
            }
        }
        assert!(
            negative > 10,
            "the negative sources dominate some texels: {negative}"
        );
        eprintln!("{}: worst error on B {worst:.2e}", integrator.name());
    }
}

#[test]
fn the_adaptive_integrator_meets_its_tolerance_with_the_rms_decay_on_every_shipped_scene() {
    // Against the converged reference (each term's integral of squares refined to convergence, then its root), on
    // the CPU and the GPU: every kind of source, the continuous W form and color series included.
    let mut g = gpu();
    for (name, mut scene) in common::shipped() {
        scene.billboard.resolution = 20;
        scene.integration.integrator = Integrator::Adaptive;
        scene.integration.jitter = None;
        scene.integration.decay = Decay::Rms;
        let want = converged_reference(&scene, 1).0;
        let bb = scene.place_billboard(1.0);
        let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
        let tolerance = scene.integration.tolerance;
        for (k, &r) in want.iter().enumerate() {
            assert!(
                (cpu[k] - r).abs() <= tolerance,
                "{name}, texel {k}: CPU {} against {r}",
                cpu[k]
            );
            assert!(
                (gpu_b[k] as f64 - r).abs() <= tolerance + 4e-6 * r.abs(),
                "{name}, texel {k}: GPU {} against {r}",
                gpu_b[k]
            );
        }
        assert!(want.iter().any(|&b| b > 0.05), "{name} shows something");
    }
}

#[test]
fn simpson_with_the_rms_decay_splits_a_long_term_over_dispatches_and_sums_the_terms() {
    // A high n puts a curve's samples over several dispatches, its sums kept between them in the scratch texture;
    // the GPU against the f64 twin, which integrates each term whole, and the whole against the terms rendered alone.
    let mut scene = common::shipped_scene("mixed.toml");
    scene.billboard.resolution = 12;
    scene.integration.integrator = Integrator::Simpson;
    scene.integration.divisions = 6000;
    scene.integration.decay = Decay::Rms;
    let bb = scene.place_billboard(1.0);
    let mut g = gpu();
    let gpu_b = g.brightness(&FrameSetup::new(&scene, bb)).unwrap();
    let cpu = reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
    for (k, (&x, &y)) in gpu_b.iter().zip(&cpu).enumerate() {
        assert!(
            (x as f64 - y).abs() <= 1.5e-4 * y.abs().max(0.01),
            "texel {k}: GPU {x} CPU {y}"
        );
    }
    // The sum of each source alone (the others at coefficient 0: the same rays).
    let n = scene.sources.len();
    let mut alone_sum = vec![0.0; cpu.len()];
    for k in 0..n {
        let mut s = scene.clone();
        let mut i = 0;
        let mut keep = |c: &mut f64| {
            if i != k {
                *c = 0.0;
            }
            i += 1;
        };
        s.sources
            .points
            .iter_mut()
            .for_each(|x| keep(&mut x.coefficient));
        s.sources
            .lines
            .iter_mut()
            .for_each(|x| keep(&mut x.coefficient));
        s.sources
            .tori
            .iter_mut()
            .for_each(|x| keep(&mut x.coefficient));
        s.sources
            .curves
            .iter_mut()
            .for_each(|x| keep(&mut x.coefficient));
        let one = g.brightness(&FrameSetup::new(&s, bb)).unwrap();
        alone_sum
            .iter_mut()
            .zip(&one)
            .for_each(|(a, &b)| *a += b as f64);
    }
    for (k, (&x, &y)) in gpu_b.iter().zip(&alone_sum).enumerate() {
        assert!(
            (x as f64 - y).abs() <= 1e-5 * y.abs().max(0.01),
            "texel {k}: {x} against the sum {y}"
        );
    }
}

#[test]
fn an_even_spread_does_not_outshine_a_spot_of_the_same_energy() {
    // The thesis's complaint (5.6): a ray along an even spread of moderate energy (a line parallel to the ray) and a
    // ray past a single intense spot (a point), set up so that the papers' distance decay gives them the same B.
    // The rms decay makes the spot the brighter, by the factor Cauchy-Schwarz predicts for equal energy; and a
    // spread must carry far more energy than the spot to outshine it.
    let settings = Integration::default().on_ray(2.0);
    let rms = Integration {
        decay: Decay::Rms,
        ..settings.clone()
    };
    let (s, e) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -20.0));
    let spot = |c: f64| Sources {
        points: vec![Point {
            position: DVec3::new(0.05, 0.0, -6.0),
            coefficient: c,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    let spread = |c: f64| Sources {
        lines: vec![Line {
            point: DVec3::new(0.6, 0.0, 0.0),
            direction: DVec3::Z,
            coefficient: c,
            look: Default::default(),
        }],
        ..Sources::default()
    };
    let b = |sources: &Sources, st: &Integration| reference::brightness(sources, st, s, e, 0.5);
    // The spread's coefficient that gives the papers' B of the spot.
    let c = b(&spot(1.0), &settings) / b(&spread(1.0), &settings);
    let (papers_spot, papers_spread) = (b(&spot(1.0), &settings), b(&spread(c), &settings));
    assert!((papers_spot - papers_spread).abs() < 1e-9 * papers_spot);
    let (rms_spot, rms_spread) = (b(&spot(1.0), &rms), b(&spread(c), &rms));
    eprintln!(
        "papers: spot {papers_spot:.4}, spread {papers_spread:.4}; rms: spot {rms_spot:.4}, spread {rms_spread:.4}"
    );
    assert!(
        rms_spot > 2.0 * rms_spread,
        "the spot outshines the spread: {rms_spot} against {rms_spread}"
    );
    // Twice the spread's energy is not enough to catch up (with the papers' decay it would be twice as bright).
    assert!(b(&spread(2.0 * c), &rms) < rms_spot);
    // Each term keeps its scale: twice the coefficient, twice the brightness.
    assert!((b(&spot(2.0), &rms) - 2.0 * rms_spot).abs() <= 3.0 * rms.tolerance);
}

fn invalid(text: &str) -> String {
    match Scene::parse(text, Path::new("bad.toml")) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted: {text}"),
    }
}

#[test]
fn the_decay_in_scene_files_and_on_the_command_line() {
    let point = "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n";
    let parse =
        |extra: &str| Scene::parse(&format!("{extra}{point}"), Path::new("s.toml")).unwrap();
    assert_eq!(parse("").integration.decay, Decay::Distance);
    assert_eq!(
        parse("[integration]\ndecay = \"rms\"\n").integration.decay,
        Decay::Rms
    );
    assert_eq!(
        parse("[integration]\ndecay = \"distance\"\n")
            .integration
            .decay,
        Decay::Distance
    );
    let msg = invalid(&format!("[integration]\ndecay = \"square\"\n{point}"));
    assert!(
        msg.contains("bad.toml:2:") && msg.contains("integration.decay"),
        "{msg}"
    );
    assert!(
        msg.contains("\"distance\"") && msg.contains("\"rms\""),
        "{msg}"
    );
    for (extra, written) in [("[integration]\ndecay = \"rms\"\n", true), ("", false)] {
        let scene = parse(extra);
        let text = scene.to_toml();
        assert_eq!(text.contains("decay = \"rms\""), written, "{text}");
        assert_eq!(Scene::parse(&text, Path::new("saved.toml")).unwrap(), scene);
    }
    // The command line: --decay and --w-form, and a clear refusal of an unknown value (exit status 2).
    let dir = std::env::temp_dir().join(format!("energywave-decay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = |name: &str| dir.join(name);
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_energywave"))
            .args(args)
            .env("XDG_RUNTIME_DIR", &dir)
            .output()
            .unwrap()
    };
    let scene = common::scenes_dir().join("default.toml");
    let scene = scene.to_str().unwrap();
    let bad = run(&[
        "render",
        scene,
        "--decay",
        "square",
        "-o",
        out("bad.png").to_str().unwrap(),
    ]);
    assert_eq!(bad.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(
        stderr.contains("square") && stderr.contains("rms"),
        "{stderr}"
    );
    assert!(!out("bad.png").exists());
    let bad = run(&[
        "render",
        scene,
        "--w-form",
        "closest",
        "-o",
        out("bad.png").to_str().unwrap(),
    ]);
    assert_eq!(bad.status.code(), Some(2));
    for (name, args) in [
        ("distance.exr", vec!["--brightness"]),
        ("rms.exr", vec!["--brightness", "--decay", "rms"]),
        ("nearest.exr", vec!["--brightness", "--w-form", "nearest"]),
    ] {
        let path = out(name);
        let mut all = vec![
            "render",
            scene,
            "--backend",
            "cpu",
            "--resolution",
            "16",
            "--size",
            "16x16",
            "-o",
        ];
        all.push(path.to_str().unwrap());
        all.extend(args);
        let done = run(&all);
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
    }
    let read = |name: &str| -> Vec<f32> {
        image::open(out(name))
            .unwrap()
            .to_rgba32f()
            .pixels()
            .map(|p| p.0[0])
            .collect()
    };
    // The CPU backend's brightness, against the twin with the same override.
    let mut want = Scene::load(Path::new(scene)).unwrap();
    want.billboard.resolution = 16;
    want.integration.decay = Decay::Rms;
    let bb = want.place_billboard(1.0);
    let b = reference::render_brightness(&FrameSetup::new(&want, bb)).values;
    let rms = read("rms.exr");
    assert!(
        b.iter()
            .zip(&rms)
            .all(|(&x, &y)| (x - y as f64).abs() <= 1e-5 * x.abs().max(1.0))
    );
    assert_ne!(read("distance.exr"), rms);
    assert_ne!(read("distance.exr"), read("nearest.exr"));
    std::fs::remove_dir_all(&dir).ok();
}
