//! Time in scenes: the travelling pulse against the thesis's eq. 5.1 written out here, keyframe
//! interpolation against hand-computed values, the `[animation]` format's errors, and the preset.

use std::f64::consts::PI;
use std::path::Path;

use energywave::animation::{Parameter, Pulse, SourceKind, Value};
use energywave::frame::FrameSetup;
use energywave::scene::Scene;

/// Thesis eq. (5.1), as printed (min and max, not a clamp): frame t, weight index i.
#[allow(clippy::manual_clamp)]
fn eq_5_1(t: f64, i: usize) -> f64 {
    let theta = (t - 7.0 * i as f64) / 25.0 * PI;
    let theta = if (0.0..=2.0 * PI).contains(&theta) {
        theta
    } else {
        0.0
    };
    f64::min(1.0, f64::max(0.0, (-theta.cos() + 0.8) / 1.5))
}

fn preset() -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/pulse_travelling.toml"))
        .unwrap()
}

#[test]
fn the_preset_pulse_is_eq_5_1_at_every_frame() {
    let scene = preset();
    let animation = scene.animation.as_ref().expect("the preset is animated");
    assert_eq!(
        animation.frames, 92,
        "6 * 7 + 50 frames: until the pulse has left w_6"
    );
    assert_eq!(
        scene.sources.curves[0].coefficient, 8.0,
        "the thesis's b = 8.0"
    );
    // The loop starts 46 frames into the thesis's run and repeats every 92 frames: the preset's frame
    // (t - 46) mod 92 is the thesis's frame t, and its frame 0 shows the pulse halfway along the curve.
    let thesis_frame = |t: f64| scene.at_frame((t - 46.0).rem_euclid(92.0));
    for t in [0u32, 1, 7, 12, 25, 38, 50, 63, 75, 91] {
        let w = &thesis_frame(t as f64).sources.curves[0].weights;
        assert_eq!(w.len(), 7);
        for (i, &wi) in w.iter().enumerate() {
            let want = eq_5_1(t as f64, i);
            assert!(
                (wi - want).abs() < 1e-12,
                "frame {t}, w_{i}: {wi} vs eq. 5.1 {want}"
            );
        }
    }
    // Spot values worked by hand: at t = 25, w_0 has theta = pi: (1 + 0.8) / 1.5 > 1, clamped to 1;
    // w_1 has theta = 18 pi / 25; w_4 (theta < 0) is 0.
    let w = thesis_frame(25.0).sources.curves[0].weights.clone();
    assert_eq!(w[0], 1.0);
    assert!((w[1] - (-(18.0 * PI / 25.0).cos() + 0.8) / 1.5).abs() < 1e-12);
    assert_eq!(w[4], 0.0);
    // The pulse travels: the brightest weight moves from the start to the end of the curve.
    let argmax = |t: f64| {
        let w = thesis_frame(t).sources.curves[0].weights.clone();
        (0..w.len()).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap()
    };
    assert!(argmax(25.0) < argmax(50.0) && argmax(50.0) < argmax(67.0));
    // Seamless: frame 92 would be frame 0.
    assert_eq!(
        scene.at_frame(92.0).sources.curves[0].weights,
        scene.at_frame(0.0).sources.curves[0].weights
    );
    // The base scene (a still render) keeps the thesis's initial state, all weights 1.
    assert!(scene.sources.curves[0].weights.is_empty());
}

#[test]
fn the_pulse_parameters_generalise_eq_5_1() {
    // Written out independently: theta_i = (speed tau - delay i) 2 pi / width, tau = (t - start) mod period.
    let general = |p: &Pulse, t: f64, i: usize| {
        let mut tau = t - p.start;
        if let Some(period) = p.period {
            tau -= period * (tau / period).floor();
        }
        let theta = (p.speed * tau - p.delay * i as f64) * 2.0 * PI / p.width;
        let theta = if (0.0..=2.0 * PI).contains(&theta) {
            theta
        } else {
            0.0
        };
        ((0.8 - theta.cos()) / 1.5).clamp(0.0, 1.0)
    };
    let pulse = Pulse {
        count: 9,
        speed: 2.0,
        width: 30.0,
        delay: 4.0,
        start: 5.0,
        period: Some(40.0),
    };
    for t in [0.0, 5.0, 11.5, 20.0, 44.0, 63.0, 100.0, -7.0] {
        for i in 0..9 {
            let (got, want) = (pulse.weight(i, t), general(&pulse, t, i));
            assert!((got - want).abs() < 1e-12, "t {t}, i {i}: {got} vs {want}");
        }
    }
    // The period repeats the pulse exactly.
    assert_eq!(pulse.weights(13.0), pulse.weights(53.0));
    // The thesis's pulse is eq. 5.1.
    let thesis = Pulse::thesis(7);
    for t in 0..100 {
        for i in 0..7 {
            assert!((thesis.weight(i, t as f64) - eq_5_1(t as f64, i)).abs() < 1e-12);
        }
    }
    // A negative delay runs the pulse from the end of the curve to its start (`start` is still the frame
    // w_0 lights up, now the last): w_6 lights up at frame 0 and w_0 at frame 42, and all is over at 92.
    let back = Pulse {
        delay: -7.0,
        start: 42.0,
        ..Pulse::thesis(7)
    };
    assert!(back.weight(6, 10.0) > 0.0 && back.weight(0, 10.0) == 0.0);
    assert!(back.weight(0, 60.0) > 0.0 && back.weight(6, 60.0) == 0.0);
    assert_eq!(back.natural_length(), 92.0);
    assert_eq!(Pulse::thesis(7).natural_length(), 92.0);
}

const KEYED: &str = r#"
[[points]]
position = [0, 0, 0]
coefficient = 1.0

[[curves]]
control_points = [[-1, 0, 0], [0, 1, 0], [1, 0, 0]]
coefficient = 2.0

[animation]
frame_rate = 24
frames = 40

[[animation.tracks]]
parameter = "points[0].coefficient"
keys = [{ frame = 0, value = 1.0 }, { frame = 10, value = 3.0 }, { frame = 30, value = 2.0 }]

[[animation.tracks]]
parameter = "curves[0].control_points[1]"
keys = [{ frame = 4, value = [0, 1, 0] }, { frame = 8, value = [2, 3, -4] }]

[[animation.tracks]]
parameter = "colors.energy"
keys = [{ frame = 0, value = [1, 0, 0] }, { frame = 20, value = [0, 0, 1] }]

[[animation.tracks]]
parameter = "integration.decay_length"
keys = [{ frame = 0, value = 2.0 }, { frame = 40, value = 4.0 }]
"#;

#[test]
fn keys_interpolate_linearly_and_hold_at_the_ends() {
    let scene = Scene::parse(KEYED, Path::new("keyed.toml")).unwrap();
    let a = scene.animation.as_ref().unwrap();
    assert_eq!((a.frame_rate, a.frames), (24.0, 40));
    let coef = |t: f64| scene.at_frame(t).sources.points[0].coefficient;
    // By hand: 1 -> 3 over frames 0..10, 3 -> 2 over 10..30, held outside.
    for (t, want) in [
        (-3.0, 1.0),
        (0.0, 1.0),
        (2.5, 1.5),
        (5.0, 2.0),
        (10.0, 3.0),
        (15.0, 2.75),
        (25.0, 2.25),
        (30.0, 2.0),
        (39.0, 2.0),
    ] {
        assert!(
            (coef(t) - want).abs() < 1e-12,
            "frame {t}: {} vs {want}",
            coef(t)
        );
    }
    let cp = |t: f64| scene.at_frame(t).sources.curves[0].control_points[1].to_array();
    assert_eq!(cp(0.0), [0.0, 1.0, 0.0]);
    assert_eq!(cp(6.0), [1.0, 2.0, -2.0]);
    assert_eq!(cp(7.0), [1.5, 2.5, -3.0]);
    assert_eq!(cp(20.0), [2.0, 3.0, -4.0]);
    assert_eq!(scene.at_frame(5.0).colors.energy, [0.75, 0.0, 0.25]);
    assert_eq!(scene.at_frame(10.0).integration.decay_length, 2.5);
    // Unkeyed values and the base scene are untouched.
    assert_eq!(scene.at_frame(5.0).sources.curves[0].coefficient, 2.0);
    assert_eq!(scene.sources.points[0].coefficient, 1.0);
    // Saving and loading keeps every key.
    let again = Scene::parse(&scene.to_toml(), Path::new("saved.toml")).unwrap();
    assert_eq!(again, scene);
}

#[test]
fn scenes_without_an_animation_stay_still() {
    let scene = Scene::default_scene();
    assert!(!scene.is_animated());
    assert_eq!(scene.frame_count(), 1);
    for t in [0.0, 1.0, 50.0] {
        assert_eq!(scene.at_frame(t), scene);
    }
    assert!(!scene.to_toml().contains("animation"));
    // A pulse alone animates, over its natural length at the default frame rate.
    let s = Scene::parse(
        "[[curves]]\ncontrol_points = [[-1, 0, 0], [0, 1, 0], [1, 0, 0]]\ncoefficient = 2\n[curves.pulse]\n",
        Path::new("p.toml"),
    )
    .unwrap();
    let a = s.animation.as_ref().unwrap();
    assert_eq!(
        (a.frame_rate, a.frames, a.pulses[0].pulse.count),
        (30.0, 92, 7)
    );
}

#[test]
fn pulses_and_keys_follow_their_sources_when_sources_are_removed() {
    let mut scene = Scene::parse(
        &format!(
            "{KEYED}\n[[points]]\nposition = [1, 1, 1]\ncoefficient = 5\n\n[[animation.tracks]]\nparameter = \"points[1].position\"\nkeys = [{{ frame = 0, value = [0, 0, 0] }}]\n"
        ),
        Path::new("k.toml"),
    )
    .unwrap();
    let a = scene.animation.as_mut().unwrap();
    a.source_removed(SourceKind::Points, 0);
    let params: Vec<String> = a.tracks.iter().map(|t| t.parameter.to_string()).collect();
    assert_eq!(
        params,
        [
            "curves[0].control_points[1]",
            "colors.energy",
            "integration.decay_length",
            "points[0].position"
        ]
    );
    a.source_inserted(SourceKind::Curves, 0);
    assert_eq!(a.tracks[0].parameter, Parameter::ControlPoint(1, 1));
    assert_eq!(
        Parameter::parse("tori[3].major_radius"),
        Ok(Parameter::MajorRadius(3))
    );
    let mut t = a.tracks[3].clone();
    t.set_key(5.0, Value::Vector([1.0, 2.0, 3.0]));
    t.set_key(0.0, Value::Vector([9.0, 9.0, 9.0]));
    assert_eq!(t.keys.len(), 2);
    assert_eq!(t.value_at(2.5), Some(Value::Vector([5.0, 5.5, 6.0])));
}

/// Older files key the papers' nu: each key becomes the decay length that nu gives at the file's camera, so
/// the animation plays as it did there, and it is saved in decay lengths.
#[test]
fn a_keyed_nu_becomes_the_decay_length_it_gives_at_the_files_camera() {
    const BASE: &str =
        "[camera]\neye = [1, 2, 9]\n[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n";
    let keyed = Scene::parse(
        &format!(
            "{BASE}[[animation.tracks]]\nparameter = \"integration.nu\"\nkeys = [{{ frame = 0, value = 3.0 }}, {{ frame = 10, value = 5.0 }}]\n"
        ),
        Path::new("keyed.toml"),
    )
    .unwrap();
    let still = |nu: f64| {
        Scene::parse(
            &format!("{BASE}[integration]\nnu = {nu}\n"),
            Path::new("still.toml"),
        )
        .unwrap()
        .integration
        .decay_length
    };
    for (frame, nu) in [(0.0, 3.0), (5.0, 4.0), (10.0, 5.0), (20.0, 5.0)] {
        let got = keyed.at_frame(frame).integration.decay_length;
        assert!(
            (got - still(nu)).abs() < 1e-12 * got,
            "frame {frame}: {got} vs {}",
            still(nu)
        );
    }
    let text = keyed.to_toml();
    assert!(
        text.contains("\"integration.decay_length\"") && !text.contains("nu"),
        "{text}"
    );
    assert_eq!(Scene::parse(&text, Path::new("saved.toml")).unwrap(), keyed);
}

/// Each malformed animation: (text, the field named, its line, a phrase of the explanation).
#[test]
fn malformed_animations_are_refused_with_place_and_field() {
    const CURVE: &str = "[[curves]]\ncontrol_points = [[-1, 0, 0], [0, 1, 0], [1, 0, 0]]\ncoefficient = 2\nweights = [1, 1, 1]\n";
    let track = |param: &str, keys: &str| {
        format!(
            "{CURVE}[animation]\n[[animation.tracks]]\nparameter = \"{param}\"\nkeys = {keys}\n"
        )
    };
    let cases: Vec<(String, &str, usize, &str)> = vec![
        (
            format!("{CURVE}[animation]\nframe_rate = -24\n"),
            "animation.frame_rate",
            6,
            "must be positive",
        ),
        (
            format!("{CURVE}[animation]\nframe_rate = nan\n"),
            "animation.frame_rate",
            6,
            "not a finite number",
        ),
        (
            format!("{CURVE}[animation]\nframes = 0\n"),
            "animation.frames",
            6,
            "between 1 and",
        ),
        (
            format!("{CURVE}[animation]\nfps = 30\n"),
            "animation",
            6,
            "unknown field `fps`",
        ),
        (
            track("points[0].coefficient", "[{ frame = 0, value = 1 }]"),
            "animation.tracks[0].parameter",
            7,
            "does not have",
        ),
        (
            track("curves[0].radius", "[{ frame = 0, value = 1 }]"),
            "animation.tracks[0].parameter",
            7,
            "not a parameter that can be keyed",
        ),
        (
            track(
                "curves[0].coefficient",
                "[{ frame = 5, value = 1 }, { frame = 2, value = 2 }]",
            ),
            "animation.tracks[0].keys[1].frame",
            8,
            "increasing frame order",
        ),
        (
            track(
                "curves[0].coefficient",
                "[{ frame = 0, value = [1, 2, 3] }]",
            ),
            "animation.tracks[0].keys[0].value",
            8,
            "is a number",
        ),
        (
            track("curves[0].control_points[2]", "[{ frame = 0, value = 1 }]"),
            "animation.tracks[0].keys[0].value",
            8,
            "vector of three numbers",
        ),
        (
            track("colors.energy", "[{ frame = 0, value = [2, 0, 0] }]"),
            "animation.tracks[0].keys[0].value",
            8,
            "0..1",
        ),
        (
            track("curves[0].coefficient", "[{ frame = inf, value = 1 }]"),
            "animation.tracks[0].keys[0].frame",
            8,
            "not a finite number",
        ),
        (
            track("curves[0].coefficient", "[]"),
            "animation.tracks[0].keys",
            8,
            "at least one key",
        ),
        (
            track("integration.nu", "[{ frame = 0, value = 1.0 }]"),
            "animation.tracks[0].keys[0].value",
            8,
            "nu must be greater than 1",
        ),
        (
            track("integration.decay_length", "[{ frame = 0, value = 0.0 }]"),
            "animation.tracks[0].keys[0].value",
            8,
            "decay_length must be positive",
        ),
        (
            format!(
                "[integration]\ndecay_length = 5.0\n{}",
                track("integration.nu", "[{ frame = 0, value = 3.0 }]")
            ),
            "animation.tracks[0].parameter",
            9,
            "key integration.decay_length",
        ),
        (
            format!("{CURVE}[curves.pulse]\nwidth = 0\n"),
            "curves[0].pulse.width",
            6,
            "must be positive",
        ),
        (
            format!("{CURVE}[curves.pulse]\ncount = 0\n"),
            "curves[0].pulse.count",
            6,
            "between 1 and",
        ),
        (
            format!("{CURVE}[curves.pulse]\nspeeed = 2\n"),
            "curves[0].pulse",
            6,
            "unknown field `speeed`",
        ),
        (
            format!(
                "{CURVE}[curves.pulse]\n[[animation.tracks]]\nparameter = \"curves[0].weights[1]\"\nkeys = [{{ frame = 0, value = 1 }}]\n"
            ),
            "animation.tracks[0].parameter",
            7,
            "is its pulse",
        ),
    ];
    for (text, field, line, phrase) in &cases {
        let err = Scene::parse(text, Path::new("bad.toml")).expect_err(text);
        let msg = err.to_string();
        assert!(
            msg.contains(&format!("bad.toml:{line}:"))
                && msg.contains(field)
                && msg.contains(phrase),
            "expected line {line}, field {field}, {phrase:?}; got: {msg}\n--- in ---\n{text}"
        );
    }
}

#[test]
fn every_shipped_scene_shows_its_effect_on_its_first_frame() {
    // A still render of an animated scene is its frame 0, and the viewer opens on it: the pulse preset's loop
    // once began with every weight at 0, a black picture.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let mut scene = Scene::load(&path).unwrap().at_frame(0.0);
        scene.billboard.resolution = 16;
        let bb = scene.place_billboard(1.0);
        let b = energywave::reference::render_brightness(&FrameSetup::new(&scene, bb)).values;
        let lit = b.iter().filter(|&&v| v > 0.2).count();
        assert!(
            lit >= 8,
            "{}: frame 0 shows {lit} of 256 texels over B = 0.2",
            path.display()
        );
    }
}
