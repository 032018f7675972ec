//! Particles that live (`particles::live`, `[particles.life]`): every frame the same however it is reached
//! (played, scrubbed back, jumped to, rendered alone in another process), emission counts and lifetimes against
//! the rate, bursts and lifetime ranges, motion against closed forms (ballistic flight, exponential drag, a
//! moving emitter's velocity inherited), the turbulence divergence free and volume preserving where its foil
//! (a gradient field) is not, the curves over a life, keyed emitter settings, and every bad input refused with
//! its place named and exit status 2.

mod common;

use std::path::Path;
use std::process::Command;

use energywave::particles::Particle;
use energywave::particles::curl::Turbulence;
use energywave::particles::live::advect;
use energywave::scene::{Scene, Simulations};
use glam::DVec3;

thread_local! {
    /// The states this test thread's simulations reached, kept as a renderer's frame cache keeps them: a test
    /// that reads several frames of one set steps from the last.
    static SIMULATIONS: Simulations = Simulations::new();
}

/// The state of live set `index` of `scene` at `frame` (`Simulations::state_at`).
fn live_state_at(
    scene: &Scene,
    index: usize,
    frame: u32,
) -> std::sync::Arc<energywave::particles::live::State> {
    SIMULATIONS.with(|s| s.state_at(scene, index, frame))
}

fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse(text, Path::new("live.toml")).map_err(|e| e.to_string())
}

fn particles(scene: &Scene, frame: u32) -> Vec<Particle> {
    let at = SIMULATIONS.with(|s| scene.at_frame_in(frame as f64, s, &Default::default()));
    let at = at.expect("never cancelled");
    at.particles[0].particles(&at.sources)
}

/// A scene with one live set: a box emitter at the origin with `life` (TOML lines of `[particles.life]`) and
/// `extra` lines after the set's own keys.
fn live_scene(emitter: &str, life: &str, animation: &str) -> Scene {
    let text = format!(
        "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n\n\
         [[particles]]\n{emitter}\n\n[particles.life]\n{life}\n\n[animation]\nframe_rate = 30.0\nframes = 200\n{animation}\n"
    );
    parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn every_frame_is_the_same_however_it_is_reached() {
    let scene = common::shipped_scene("pulse_sparks.toml");
    let frames = scene.frame_count();
    assert_eq!(frames, 120);
    let played: Vec<Vec<Particle>> = (0..frames).map(|f| particles(&scene, f)).collect();
    assert!(played[60].len() > 50, "{}", played[60].len());
    // Scrubbed backwards, and jumped about, from the kept states.
    for f in (0..frames).rev().step_by(7) {
        assert_eq!(particles(&scene, f), played[f as usize], "scrubbed to {f}");
    }
    for f in [97, 3, 119, 41, 0, 88] {
        assert_eq!(particles(&scene, f), played[f as usize], "jumped to {f}");
    }
    // From scratch: a key on a setting no particle reads makes another simulation, which keeps nothing of the
    // first one's states.
    let mut fresh = scene.clone();
    if let Some(a) = &mut fresh.animation {
        a.tracks.push(energywave::animation::Track {
            parameter: energywave::animation::Parameter::Cutoff,
            keys: vec![energywave::animation::Key {
                frame: 0.0,
                value: energywave::animation::Value::Number(scene.colors.cutoff),
            }],
        });
    }
    for f in [119, 60, 5] {
        assert_eq!(
            particles(&fresh, f),
            played[f as usize],
            "from scratch at {f}"
        );
    }
    // A renderer's frame cache keeps the states its frames reached (`FrameCache::scene_at`); `Scene::at_frame`
    // keeps none and simulates from the start: the same particles either way.
    let cache = energywave::frame::FrameCache::new();
    for f in [30, 31, 29, 90] {
        let at = cache.scene_at(&scene, f as f64);
        assert_eq!(
            at.particles[0].particles(&at.sources),
            played[f as usize],
            "cached at {f}"
        );
        assert!(cache.bytes() > 0);
    }
    let alone = scene.at_frame(90.0);
    assert_eq!(alone.particles[0].particles(&alone.sources), played[90]);
    // An edit of the particle sets drops their kept states.
    cache.invalidate(energywave::frame::Changed {
        particles: true,
        ..Default::default()
    });
    assert_eq!(cache.bytes(), 0);
}

#[test]
fn a_frame_rendered_alone_in_another_process_matches_the_sequence() {
    let dir = common::tmpdir("live_particles", "alone");
    let scene = common::scenes_dir().join("pulse_sparks.toml");
    // The same scene without its sparks: what the glow alone shows.
    let text = std::fs::read_to_string(&scene).unwrap();
    let glow_only = dir.join("glow_only.toml");
    let cut = text.find("[[particles]]").expect("the preset has sparks");
    let animation = &text[text.find("[animation]").expect("and an animation")..];
    std::fs::write(&glow_only, format!("{}\n{animation}", &text[..cut])).unwrap();
    let bin = env!("CARGO_BIN_EXE_energywave");
    let render = |scene: &std::path::Path, args: &[&str]| {
        let out = Command::new(bin)
            .arg("render")
            .arg(scene)
            .args(["--size", "96x72"])
            .args(args)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let run = |args: &[&str]| render(&scene, args);
    for backend in ["cpu", "gpu"] {
        let seq = dir.join(format!("{backend}_####.png"));
        run(&[
            "--backend",
            backend,
            "--frames",
            "40..44",
            "-o",
            seq.to_str().unwrap(),
        ]);
        let alone = dir.join(format!("{backend}_alone.png"));
        run(&[
            "--backend",
            backend,
            "--frames",
            "43",
            "-o",
            alone.to_str().unwrap(),
        ]);
        let a = image::open(dir.join(format!("{backend}_0043.png")))
            .unwrap()
            .to_rgba8();
        let b = image::open(&alone).unwrap().to_rgba8();
        // The same particles: the same picture, to the bit on the CPU (and on the GPU here, whose passes are
        // deterministic; within a step of 8 bits allowed).
        let largest = (a.as_raw().iter().zip(b.as_raw()))
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        let allowed = if backend == "cpu" { 0 } else { 1 };
        assert!(
            largest <= allowed,
            "{backend}: frame 43 differs by {largest} between the sequence and alone"
        );
        // Not a blank frame, nor the glow alone: against the frame without the sparks, the sparks light pixels
        // of their own.
        let bare = dir.join(format!("{backend}_glow_only.png"));
        render(
            &glow_only,
            &[
                "--backend",
                backend,
                "--frames",
                "43",
                "-o",
                bare.to_str().unwrap(),
            ],
        );
        let bare = image::open(&bare).unwrap().to_rgba8();
        let lit = a.pixels().filter(|p| p.0[0] > 40).count();
        assert!(lit > 100, "{backend}: {lit}");
        let sparks = (a.pixels().zip(bare.pixels()))
            .filter(|(x, y)| x.0[0].abs_diff(y.0[0]) > 20)
            .count();
        assert!(
            sparks > 20,
            "{backend}: the sparks change {sparks} pixels of the glow's frame"
        );
    }
}

const STILL_BOX: &str =
    "emitter = \"box\"\ncenter = [0.0, 0.0, 0.0]\nsize = 1.0\nparticle_radius = 0.1";

#[test]
fn births_follow_the_rate_and_bursts_exactly() {
    let scene = live_scene(
        STILL_BOX,
        "rate = 45.0\nbursts = [[10.0, 50.0], [10.0, 7.0], [33.0, 5.0]]\nlifetime = 100.0\nspeed = 0.0",
        "",
    );
    for frame in [0u32, 1, 9, 10, 11, 32, 33, 34, 120] {
        let state = live_state_at(&scene, 0, frame);
        let from_rate = (45.0 * frame as f64 / 30.0 + 1e-9).floor() as u64;
        let from_bursts = if frame >= 33 {
            62
        } else if frame >= 10 {
            57
        } else {
            0
        };
        assert_eq!(state.born(), from_rate + from_bursts, "frame {frame}");
        assert_eq!(state.particles.len() as u64, state.born());
    }
    // A keyed rate: none before frame 30, then 60 a second: its integral.
    let keyed = live_scene(
        STILL_BOX,
        "rate = 0.0\nlifetime = 100.0",
        "[[animation.tracks]]\nparameter = \"particles[0].rate\"\nkeys = [[30, 0.0], [31, 60.0]]\n",
    );
    assert_eq!(live_state_at(&keyed, 0, 30).born(), 0);
    // Half a frame's worth over the ramp (30..31), then 2 a frame.
    assert_eq!(live_state_at(&keyed, 0, 41).born(), 21);
}

#[test]
fn lifetimes_follow_their_range() {
    // Alive at 3 s of a steady 300 a second, lives uniform in [0.5, 1.5] s: 300 E[L] = 300 on average. Over 60
    // seeds the mean's error is about 1; one frame's emission is 10: the bound of 4 fails on a frame's slip.
    let mut total = 0.0;
    let seeds = 60;
    for seed in 0..seeds {
        let scene = live_scene(
            &format!("{STILL_BOX}\nseed = {seed}"),
            "rate = 300.0\nlifetime = [0.5, 1.5]\nspeed = 0.0",
            "",
        );
        let state = live_state_at(&scene, 0, 90);
        let t = 3.0;
        for p in &state.particles {
            assert!(p.born + p.lifetime > t && p.born <= t);
            assert!((0.5..=1.5).contains(&p.lifetime));
        }
        total += state.particles.len() as f64;
    }
    let mean = total / seeds as f64;
    assert!((mean - 300.0).abs() < 4.0, "{mean}");
}

/// One particle, thrown from the origin (a sphere of radius 1e-9) at `speed` along +x, under `extra` motion.
fn one_particle(life: &str) -> Scene {
    live_scene(
        "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1e-15\nparticle_radius = 0.1",
        &format!(
            "rate = 0.0\nbursts = [[0.0, 1.0]]\nlifetime = 100.0\nspeed = 2.0\ndirection = [1.0, 0.0, 0.0]\ncone = 0.0\n{life}"
        ),
        "",
    )
}

#[test]
fn flight_matches_closed_forms() {
    let g = DVec3::new(0.0, -9.81, 0.0);
    let v0 = DVec3::new(2.0, 0.0, 0.0);
    let ballistic = one_particle("acceleration = [0.0, -9.81, 0.0]");
    let drag = one_particle("drag = 1.5");
    let both = one_particle("drag = 0.7\nacceleration = [0.0, -9.81, 0.0]");
    for frame in [1u32, 7, 30, 95] {
        let t = frame as f64 / 30.0;
        let p = live_state_at(&ballistic, 0, frame).particles[0];
        let expected = v0 * t + 0.5 * g * t * t;
        assert!(
            (p.position - expected).length() < 1e-9 * (1.0 + expected.length()),
            "{frame}"
        );
        assert!((p.velocity - (v0 + g * t)).length() < 1e-9 * (1.0 + t * 9.81));
        let p = live_state_at(&drag, 0, frame).particles[0];
        let k: f64 = 1.5;
        let expected = v0 * (1.0 - (-k * t).exp()) / k;
        assert!((p.position - expected).length() < 1e-12, "{frame}");
        assert!((p.velocity - v0 * (-k * t).exp()).length() < 1e-12);
        let p = live_state_at(&both, 0, frame).particles[0];
        let k: f64 = 0.7;
        let terminal = g / k;
        let expected = terminal * t + (v0 - terminal) * (1.0 - (-k * t).exp()) / k;
        assert!(
            (p.position - expected).length() < 1e-9 * (1.0 + expected.length()),
            "{frame}"
        );
    }
}

#[test]
fn a_moving_emitter_leaves_a_trail_and_gives_its_velocity() {
    // The center moves at 3 units a second along x; particles thrown at no speed keep all of its velocity.
    let scene = live_scene(
        "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1e-15\nparticle_radius = 0.1",
        "rate = 60.0\nlifetime = 100.0\nspeed = 0.0\ninherit_velocity = 1.0",
        "[[animation.tracks]]\nparameter = \"particles[0].center\"\nkeys = [[0, [0.0, 0.0, 0.0]], [300, [30.0, 0.0, 0.0]]]\n",
    );
    let state = live_state_at(&scene, 0, 30);
    assert_eq!(state.particles.len(), 60);
    for p in &state.particles {
        assert!((p.velocity - DVec3::new(3.0, 0.0, 0.0)).length() < 1e-9);
        // Born where the center was at its birth, then moved with it: at the center now.
        assert!(
            (p.position - DVec3::new(3.0, 0.0, 0.0)).length() < 1e-9,
            "{:?}",
            p.position
        );
    }
    // Without inheriting, each stays where it was born: evenly spread along the center's path, two a frame.
    let still = live_scene(
        "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1e-15\nparticle_radius = 0.1",
        "rate = 60.0\nlifetime = 100.0\nspeed = 0.0",
        "[[animation.tracks]]\nparameter = \"particles[0].center\"\nkeys = [[0, [0.0, 0.0, 0.0]], [300, [30.0, 0.0, 0.0]]]\n",
    );
    let state = live_state_at(&still, 0, 30);
    for p in &state.particles {
        assert!((p.position.x - 3.0 * p.born).abs() < 1e-9);
    }
    let mut xs: Vec<f64> = state.particles.iter().map(|p| p.position.x).collect();
    xs.sort_by(f64::total_cmp);
    for w in xs.windows(2) {
        assert!((w[1] - w[0] - 0.05).abs() < 1e-9, "{w:?}");
    }
}

#[test]
fn the_turbulence_is_divergence_free() {
    let t = Turbulence {
        scale: 0.7,
        strength: 1.3,
        speed: 0.9,
    };
    let h = 1e-5;
    let mut rng = common::Lcg(5);
    let mut largest = 0.0f64;
    let mut typical = 0.0f64;
    for _ in 0..300 {
        let x = rng.vec(4.0);
        let time = rng.range(0.0, 5.0);
        let mut div = 0.0;
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            let d =
                (t.velocity(x + axis * h, time, 9) - t.velocity(x - axis * h, time, 9)) / (2.0 * h);
            div += d.dot(axis);
            typical = typical.max(d.length());
        }
        largest = largest.max(div.abs());
    }
    // Central differences err by about h^2 |u'''|: far below the gradients' own size (about 1 / scale).
    assert!(typical > 0.5, "{typical}");
    assert!(largest < 1e-6 * typical, "{largest} of {typical}");
}

/// The volume a closed triangle mesh encloses (the divergence theorem).
fn volume(vertices: &[DVec3], triangles: &[[usize; 3]]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| vertices[a].dot(vertices[b].cross(vertices[c])) / 6.0)
        .sum()
}

/// An icosphere of radius `r` around `center`, subdivided `levels` times.
fn icosphere(center: DVec3, r: f64, levels: u32) -> (Vec<DVec3>, Vec<[usize; 3]>) {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let mut f: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::new();
        let mut middle = |a: usize, b: usize, v: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a] + v[b]) / 2.0).normalize());
                v.len() - 1
            })
        };
        for [a, b, c] in f {
            let (ab, bc, ca) = (
                middle(a, b, &mut v),
                middle(b, c, &mut v),
                middle(c, a, &mut v),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v.into_iter().map(|x| center + x * r).collect(), f)
}

#[test]
fn advection_by_the_turbulence_keeps_volume() {
    const STEPS: usize = 60;
    // A ball of smoke (radius 0.25) carried for one second in the simulation's own steps (30 frames a second,
    // two substeps a frame) keeps its volume (incompressible flow) to about 1e-3 (the steps' and the mesh's
    // error), while it is deformed by more than its radius; the foil, a field that draws it in at the same
    // order of speed, changes it by hundreds of times more.
    let t = Turbulence {
        scale: 0.5,
        strength: 0.5,
        speed: 1.0,
    };
    let (start, triangles) = icosphere(DVec3::new(0.3, -0.2, 0.1), 0.25, 4);
    let v0 = volume(&start, &triangles);
    let h = 1.0 / 60.0;
    let mut moved = start.clone();
    for j in 0..STEPS {
        for x in &mut moved {
            *x = advect(&t, 17, *x, j as f64 * h, h);
        }
    }
    let v1 = volume(&moved, &triangles);
    let deformed = (moved.iter().zip(&start))
        .map(|(a, b)| (*a - *b - (moved[0] - start[0])).length())
        .fold(0.0, f64::max);
    assert!(deformed > 0.1, "{deformed}");
    let change = (v1 - v0).abs() / v0;
    assert!(change < 2e-3, "{change}");
    // The foil: carried along -grad of |x - c|^2 scaled by the same strength (compressing), volume shrinks.
    let mut foil = start.clone();
    let c = DVec3::new(0.3, -0.2, 0.1);
    for _ in 0..STEPS {
        for x in &mut foil {
            *x -= (*x - c) * (0.5 * h);
        }
    }
    let foil_change = (volume(&foil, &triangles) - v0).abs() / v0;
    assert!(foil_change > 100.0 * change, "{foil_change} {change}");
}

#[test]
fn size_density_and_color_follow_their_curves() {
    let scene = live_scene(
        "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.5\nparticle_radius = 0.2\ndensity = 8.0\ncolor = [0.2, 0.4, 0.6]",
        "rate = 0.0\nbursts = [[0.0, 20.0]]\nlifetime = 4.0\nspeed = 0.0\n\
         size = [[0.0, 0.5], [0.5, 2.0]]\nopacity = [[0.0, 0.0], [0.25, 1.0], [1.0, 0.5]]\n\
         colors = [[0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0]]",
        "",
    );
    for frame in [0u32, 12, 30, 60, 90, 119] {
        let age = frame as f64 / 30.0 / 4.0;
        let size = if age < 0.5 { 0.5 + 3.0 * age } else { 2.0 };
        let opacity = if age < 0.25 {
            age / 0.25
        } else {
            1.0 - 0.5 * (age - 0.25) / 0.75
        };
        let drawn = particles(&scene, frame);
        if opacity == 0.0 {
            assert!(drawn.is_empty(), "nothing of no density is drawn");
            continue;
        }
        assert_eq!(drawn.len(), 20, "{frame}");
        for p in drawn {
            assert!(
                (p.radius - 0.2 * size).abs() < 1e-12,
                "{frame} {}",
                p.radius
            );
            // The set's albedo (0.9 by default) times the color over the life.
            assert!((p.density - 8.0 * opacity).abs() < 1e-12);
            let c = [1.0 - age, 0.0, age].map(|x| x * 0.9);
            assert!(
                (0..3).all(|i| (p.color[i] - c[i]).abs() < 1e-12),
                "{:?} {c:?}",
                p.color
            );
        }
    }
    // Dead after four seconds.
    assert!(particles(&scene, 121).is_empty());
}

/// A spark's own light over its life: the set's emission (color times intensity) times the life's emission
/// factor and emission color at the particle's age, not times the albedo (emission is not scattered light).
#[test]
fn emission_follows_its_curves() {
    let scene = live_scene(
        "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.5\nparticle_radius = 0.2\ndensity = 8.0\n\
         emission = [1.0, 0.5, 0.5]\nemission_intensity = 4.0",
        "rate = 0.0\nbursts = [[0.0, 20.0]]\nlifetime = 4.0\nspeed = 0.0\nopacity = [[0.0, 1.0]]\n\
         emission = [[0.0, 1.0], [1.0, 0.25]]\n\
         emission_colors = [[0.0, 1.0, 1.0, 1.0], [0.5, 1.0, 0.5, 0.0], [1.0, 0.6, 0.0, 0.0]]",
        "",
    );
    for frame in [0u32, 12, 30, 60, 90, 119] {
        let age = frame as f64 / 30.0 / 4.0;
        let factor = 1.0 - 0.75 * age;
        let tint = if age < 0.5 {
            [1.0, 1.0 - age, 1.0 - 2.0 * age]
        } else {
            [1.0 - 0.8 * (age - 0.5), 0.5 - (age - 0.5), 0.0]
        };
        let drawn = particles(&scene, frame);
        assert_eq!(drawn.len(), 20, "{frame}");
        for p in drawn {
            let want: Vec<f64> = (0..3)
                .map(|c| [1.0, 0.5, 0.5][c] * 4.0 * factor * tint[c])
                .collect();
            assert!(
                (0..3).all(|c| (p.emission[c] - want[c]).abs() < 1e-12),
                "frame {frame}: {:?} against {want:?}",
                p.emission
            );
        }
    }
    // A set that gives no emission glows with none.
    let plain = common::shipped_scene("ring_smoke.toml");
    assert!(
        (plain.at_frame(20.0).particles.iter())
            .flat_map(|s| s.particles(&plain.sources))
            .all(|p| p.emission == [0.0; 3])
    );
}

/// Motion blur: a spark thrown at 31 units a second under gravity, seen with a half-frame shutter, is drawn as
/// copies on its exact path over the shutter (the closed form of `flight_matches_closed_forms`), no more than
/// a quarter of a radius apart, that share its density; the optical depth they give rays across and along the streak is
/// the particle's averaged over the shutter, against that average by a quadrature 400 times finer; a spark born
/// while the shutter is open shows from its birth on.
#[test]
fn motion_blur_draws_a_particle_along_its_path_over_the_shutter() {
    use energywave::particles::live::{COPY_SPACING, MAX_COPIES};
    use energywave::particles::optical_depth_between;
    let g = DVec3::new(0.0, -9.81, 0.0);
    let v0 = DVec3::new(31.0, 0.0, 0.0);
    let spark = |shutter: f64| {
        live_scene(
            "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1e-15\nparticle_radius = 0.1",
            &format!(
                "rate = 0.0\nbursts = [[0.0, 1.0]]\nlifetime = 100.0\nspeed = 31.0\ndirection = [1.0, 0.0, 0.0]\n\
                 cone = 0.0\nacceleration = [0.0, -9.81, 0.0]\nopacity = [[0.0, 1.0]]\nshutter = {shutter}"
            ),
            "",
        )
    };
    let (sharp, blurred) = (spark(0.0), spark(0.5));
    let at = |t: f64| v0 * t + 0.5 * g * t * t;
    let frame = 12u32;
    let t = frame as f64 / 30.0;
    let open = 0.5 / 30.0;
    let one = particles(&sharp, frame);
    assert_eq!(one.len(), 1);
    let copies = particles(&blurred, frame);
    // Half a frame at about 31 units a second: 0.52 units, in copies a quarter of a radius (0.025) apart.
    let length = (at(t + 0.5 * open) - at(t - 0.5 * open)).length();
    let k = (length / (COPY_SPACING * 0.1)).ceil() as usize;
    assert!(k > 5 && k < MAX_COPIES as usize, "{k}");
    assert_eq!(copies.len(), k);
    let mass: f64 = copies.iter().map(|p| p.density).sum();
    assert!((mass - one[0].density).abs() < 1e-12 * one[0].density);
    for (i, p) in copies.iter().enumerate() {
        let tau = open * ((i as f64 + 0.5) / k as f64 - 0.5);
        let want = at(t + tau);
        assert!(
            (p.position - want).length() < 1e-9,
            "copy {i}: {:?} against {want:?}",
            p.position
        );
        assert_eq!(
            (p.radius, p.color, p.emission),
            (one[0].radius, one[0].color, one[0].emission)
        );
    }
    for w in copies.windows(2) {
        assert!((w[1].position - w[0].position).length() <= COPY_SPACING * 0.1 + 1e-12);
    }
    // The optical depth along rays across the streak (at its middle, near an end, past it) and along it, against
    // the particle's own averaged over the shutter at 4,000 instants.
    let averaged = |a: DVec3, b: DVec3| {
        let n = 4000;
        (0..n)
            .map(|i| {
                let tau = open * ((i as f64 + 0.5) / n as f64 - 0.5);
                let moved = Particle {
                    position: at(t + tau),
                    ..one[0]
                };
                optical_depth_between(&[moved], a, b)
            })
            .sum::<f64>()
            / n as f64
    };
    let middle = at(t);
    let end = at(t + 0.5 * open);
    let rays = [
        (middle - DVec3::Z, middle + DVec3::Z),
        (
            middle + DVec3::new(0.0, 0.04, -1.0),
            middle + DVec3::new(0.0, 0.04, 1.0),
        ),
        (
            end - DVec3::new(0.03, 0.0, 1.0),
            end + DVec3::new(-0.03, 0.0, 1.0),
        ),
        (
            end + DVec3::new(0.08, 0.0, -1.0),
            end + DVec3::new(0.08, 0.0, 1.0),
        ),
        (
            middle - 0.5 * v0.normalize() - 0.002 * g,
            middle + 0.5 * v0.normalize() - 0.002 * g,
        ),
    ];
    // Each within 1.5 % of the larger of its own average and the streak's across its middle (its tails, past the
    // ends, hold little: an error there is measured against what the streak shows).
    let across = averaged(rays[0].0, rays[0].1);
    let mut worst: f64 = 0.0;
    for (a, b) in rays {
        let want = averaged(a, b);
        let got = optical_depth_between(&copies, a, b);
        let unblurred = optical_depth_between(&one, a, b);
        assert!(want > 1e-3, "{want}");
        worst = worst.max((got - want).abs() / want.max(across));
        assert!(
            (got - want).abs() < 1.5e-2 * want.max(across),
            "{a:?}: copies {got}, the shutter's average {want} (the sharp particle's {unblurred})"
        );
    }
    eprintln!(
        "blurred spark: the copies' optical depth within {worst:.1e} of the shutter's average (of the streak's)"
    );
    // Past the sharp particle's ball, the streak's end still holds some of it.
    let past = (
        end + DVec3::new(0.08, 0.0, -1.0),
        end + DVec3::new(0.08, 0.0, 1.0),
    );
    assert_eq!(optical_depth_between(&one, past.0, past.1), 0.0);
    // Born at frame 0's instant: the shutter's half before its birth shows nothing. Its path over the shutter is
    // 31 / 60 units long, 21 copies: the 11 from its birth on are drawn, each with a share of 1 / 21.
    let born = particles(&blurred, 0);
    assert_eq!(born.len(), 11);
    assert!(born.iter().all(|p| p.position.x > -1e-12));
    let mass: f64 = born.iter().map(|p| p.density).sum();
    let sharp_mass = particles(&sharp, 0)[0].density;
    assert!((mass - sharp_mass * 11.0 / 21.0).abs() < 1e-12 * sharp_mass);
    // The shutter only draws the particles: a shutter edited keeps the states the simulation reached.
    let reached = live_state_at(&blurred, 0, 30);
    assert!(std::sync::Arc::ptr_eq(
        &reached,
        &live_state_at(&spark(0.8), 0, 30)
    ));
}

/// Motion blur with drag and gravity, a size curve and a life that ends while the shutter is open: each copy at
/// the closed form of its instant (backwards too), of the size its own age gives, none past the end, no two
/// farther apart than a quarter of the smallest radius on the path (to 1 %: the copies are even in time, the
/// path's longest eighth sets their number).
#[test]
fn motion_blur_follows_the_drag_the_curves_and_the_end_of_a_life() {
    use energywave::particles::live::COPY_SPACING;
    let spark = |shutter: f64| {
        live_scene(
            "emitter = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1e-15\nparticle_radius = 0.1",
            &format!(
                "rate = 0.0\nbursts = [[0.0, 1.0]]\nlifetime = 0.47\nspeed = 31.0\ndirection = [1.0, 0.0, 0.0]\n\
                 cone = 0.0\nacceleration = [0.0, -9.81, 0.0]\ndrag = 1.5\nopacity = [[0.0, 1.0]]\n\
                 size = [[0.0, 1.0], [1.0, 0.5]]\nshutter = {shutter}"
            ),
            "",
        )
    };
    let (k, g, v0) = (1.5, DVec3::new(0.0, -9.81, 0.0), DVec3::new(31.0, 0.0, 0.0));
    let terminal = g / k;
    let at = |t: f64| terminal * t + (v0 - terminal) * (1.0 - (-k * t).exp()) / k;
    // Frame 14 is t = 0.4667 s; the shutter, open a half frame, covers 0.4583 to 0.4750 s; the life ends at 0.47.
    let (frame, open) = (14u32, 0.5 / 30.0);
    let t = frame as f64 / 30.0;
    let sharp = particles(&spark(0.0), frame);
    assert_eq!(sharp.len(), 1);
    let copies = particles(&spark(0.5), frame);
    let n = (sharp[0].density / copies[0].density).round() as usize;
    assert!(n > 10, "{n} copies");
    let shown: Vec<usize> = (0..n)
        .filter(|&i| t + open * ((i as f64 + 0.5) / n as f64 - 0.5) <= 0.47)
        .collect();
    assert!(shown.len() < n, "the shutter passes the life's end");
    assert_eq!(copies.len(), shown.len());
    for (p, &i) in copies.iter().zip(&shown) {
        let when = t + open * ((i as f64 + 0.5) / n as f64 - 0.5);
        let want = at(when);
        assert!(
            (p.position - want).length() < 1e-9 * (1.0 + want.length()),
            "copy {i}: {:?} against {want:?}",
            p.position
        );
        let age = when / 0.47;
        assert!(
            (p.radius - 0.1 * (1.0 - 0.5 * age)).abs() < 1e-12,
            "copy {i}: radius {}",
            p.radius
        );
        assert!((p.density * n as f64 - sharp[0].density).abs() < 1e-9 * sharp[0].density);
    }
    // The smallest radius on the path is at the life's end, half the drawn one.
    for w in copies.windows(2) {
        let d = (w[1].position - w[0].position).length();
        assert!(d <= COPY_SPACING * 0.05 * 1.01, "{d} apart, {n} copies");
    }
}

#[test]
fn saved_and_loaded_again_a_live_set_is_the_same() {
    for name in [
        "pulse_sparks.toml",
        "ring_smoke.toml",
        "beam_dust.toml",
        "beam_sparks.toml",
    ] {
        let scene = common::shipped_scene(name);
        let again = parse(&scene.to_toml()).unwrap();
        assert_eq!(again.particles, scene.particles, "{name}");
        assert_eq!(again.animation, scene.animation, "{name}");
    }
}

#[test]
fn bad_input_is_refused_with_its_place() {
    let base = |emitter: &str, life: &str, animation: bool| {
        format!(
            "[[curves]]\ncontrol_points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0]]\ncoefficient = 1.0\n\n\
             [[particles]]\n{emitter}\n\n[particles.life]\n{life}\n{}",
            if animation {
                "\n[animation]\nframes = 10\n"
            } else {
                ""
            }
        )
    };
    let sphere = "emitter = \"sphere\"";
    let cases: [(String, &str); 22] = [
        (base(sphere, "rate = -1.0", true), "particles[0].life.rate"),
        (
            base(sphere, "shutter = 1.5", true),
            "particles[0].life.shutter",
        ),
        (
            base(sphere, "shutter = -0.25", true),
            "particles[0].life.shutter",
        ),
        (
            base(sphere, "lifetime = [-1.0, 2.0]", true),
            "particles[0].life.lifetime",
        ),
        (
            base(sphere, "lifetime = 0.0", true),
            "particles[0].life.lifetime",
        ),
        (base(sphere, "drag = -0.5", true), "particles[0].life.drag"),
        (
            base(sphere, "[particles.life.turbulence]\nscale = 0.0", true),
            "particles[0].life.turbulence.scale",
        ),
        (
            base("emitter = \"curve\"\ncurve = 3", "rate = 1.0", true),
            "particles[0].curve",
        ),
        (
            base("emitter = \"sphere\"\ncount = 10", "rate = 1.0", true),
            "particles[0].count",
        ),
        (base(sphere, "rate = 1.0", false), "particles[0].life"),
        (
            base(sphere, "direction = \"tangent\"", true),
            "particles[0].life.direction",
        ),
        (
            base(sphere, "along_pulse = true", true),
            "particles[0].life.along_pulse",
        ),
        (
            base(sphere, "bursts = [[2.0, 1.5]]", true),
            "particles[0].life.bursts[0]",
        ),
        (
            base(sphere, "size = [[0.5, 1.0], [0.2, 1.0]]", true),
            "particles[0].life.size[1]",
        ),
        (
            base(sphere, "rate = 1e6\nlifetime = 10.0", true),
            "particles in all",
        ),
        (
            base(sphere, "emission = [[0.0, 1.0], [1.0, -0.5]]", true),
            "particles[0].life.emission[1]",
        ),
        (
            base(sphere, "emission_colors = []", true),
            "particles[0].life.emission_colors",
        ),
        (
            base(sphere, "emission_colors = [[0.0, 1.0, 2.0, 0.0]]", true),
            "particles[0].life.emission_colors[0]",
        ),
        (
            base(
                "emitter = \"sphere\"\nemission_intensity = -1.0",
                "rate = 1.0",
                true,
            ),
            "particles[0].emission_intensity",
        ),
        (
            base(sphere, "rate = 1.0", true)
                + "[[animation.tracks]]\nparameter = \"particles[0].emission_intensity\"\nkeys = [[0, 2e3]]\n",
            "animation.tracks[0].keys",
        ),
        (
            base(sphere, "rate = 1.0", true)
                + "[[animation.tracks]]\nparameter = \"particles[0].rate\"\nkeys = [[0, -3.0]]\n",
            "animation.tracks[0].keys",
        ),
        (
            base(sphere, "rate = 1.0", true)
                + "[[animation.tracks]]\nparameter = \"particles[0].rate\"\nkeys = [[0, 1e12]]\n",
            "animation.tracks[0].keys",
        ),
    ];
    for (text, field) in &cases {
        let err = parse(text).expect_err(text);
        assert!(err.contains(field), "{field} not named in: {err}\n{text}");
    }
    // The command line: exit 2, the file named, nothing written.
    let dir = common::tmpdir("live_particles", "bad");
    let path = dir.join("bad.toml");
    std::fs::write(&path, &cases[0].0).unwrap();
    let out_file = dir.join("out.png");
    let out = Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args([
            "render",
            path.to_str().unwrap(),
            "-o",
            out_file.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.toml") && stderr.contains("life.rate"),
        "{stderr}"
    );
    assert!(!out_file.exists());
}

#[test]
fn the_pulse_throws_sparks_where_it_is() {
    // Births follow the lit part of the chain: at frame 8 the pulse's peak is near the curve's start (x < 0), at
    // frame 45 near its end (x > 0).
    let scene = common::shipped_scene("pulse_sparks.toml");
    let mean_x = |frame: u32| {
        let state = live_state_at(&scene, 0, frame);
        let young: Vec<f64> = (state.particles.iter())
            .filter(|p| frame as f64 / 30.0 - p.born < 0.2)
            .map(|p| p.position.x)
            .collect();
        assert!(young.len() > 10, "{frame}: {}", young.len());
        young.iter().sum::<f64>() / young.len() as f64
    };
    let (early, late) = (mean_x(8), mean_x(45));
    assert!(early < -1.0 && late > 1.0, "{early} {late}");
}

#[test]
fn particles_are_thrown_along_the_shape() {
    // A torus's ring (radius 2 about +y at the origin, no spread): "outward" along the ring's radius in its plane,
    // "tangent" along the ring; a curve's chain: "tangent" along it, "normal" across it. Cone 0, speed 1.
    let scene = |emitter: &str, direction: &str| {
        let text = format!(
            "[[tori]]\ncenter = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\nmajor_radius = 2.0\ncoefficient = 1.0\n\n\
             [[curves]]\ncontrol_points = [[-2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]\ncoefficient = 1.0\n\n\
             [[particles]]\n{emitter}\nspread = 0.0\nparticle_radius = 0.1\n\n[particles.life]\nrate = 0.0\n\
             bursts = [[0.0, 200.0]]\nlifetime = 10.0\nspeed = 1.0\ncone = 0.0\ndirection = \"{direction}\"\n\n\
             [animation]\nframes = 10\n"
        );
        let state = live_state_at(&parse(&text).unwrap(), 0, 0);
        // The burst's 200, every one of them checked below.
        assert_eq!(state.particles.len(), 200, "{emitter} {direction}");
        state
    };
    for p in &scene("emitter = \"torus\"\ntorus = 0", "outward").particles {
        let radial = DVec3::new(p.position.x, 0.0, p.position.z) / 2.0;
        assert!((p.position.length() - 2.0).abs() < 1e-9);
        assert!(
            (p.velocity - radial).length() < 1e-9,
            "{:?} {radial:?}",
            p.velocity
        );
    }
    for p in &scene("emitter = \"torus\"\ntorus = 0", "tangent").particles {
        assert!(p.velocity.dot(p.position).abs() < 1e-9 && p.velocity.y.abs() < 1e-9);
        assert!((p.velocity.length() - 1.0).abs() < 1e-9);
    }
    for p in &scene("emitter = \"curve\"\ncurve = 0", "tangent").particles {
        assert!((p.velocity.x.abs() - 1.0).abs() < 1e-9, "{:?}", p.velocity);
    }
    for p in &scene("emitter = \"curve\"\ncurve = 0", "normal").particles {
        assert!(p.velocity.x.abs() < 1e-9 && (p.velocity.length() - 1.0).abs() < 1e-9);
    }
}
