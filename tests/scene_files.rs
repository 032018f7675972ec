//! Scene files: every shipped scene loads, saving round-trips, and each kind of malformed file gets its own
//! clear error naming the file, the place and the field.

use std::path::{Path, PathBuf};

use energywave::scene::{Scene, SceneError};

/// The decay length the papers' `nu` gives `scene` at its own camera.
fn papers_decay_length(scene: &Scene, nu: f64) -> f64 {
    energywave::geometry::papers_decay_length(
        &scene.camera,
        &scene.sources,
        scene.billboard.center,
        nu,
    )
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes")
}

fn shipped() -> Vec<PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_shipped_scene_loads() {
    let all = shipped();
    assert!(
        all.len() >= 12,
        "expected the presets of METHOD.md section 6, found {all:?}"
    );
    for path in &all {
        let scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            !scene.sources.is_empty(),
            "{} has no sources",
            path.display()
        );
    }
    // The embedded default scene is the shipped default.toml.
    let default = Scene::default_scene();
    assert_eq!(
        default,
        Scene::load(&scenes_dir().join("default.toml")).unwrap()
    );
}

#[test]
fn presets_hold_the_papers_settings() {
    let load = |name: &str| Scene::load(&scenes_dir().join(name)).unwrap();
    let t = load("torus_r0.9_t5.1.toml");
    assert_eq!(
        (
            t.sources.tori[0].major_radius,
            t.sources.tori[0].coefficient
        ),
        (0.9, 5.1)
    );
    let t = load("torus_r3.0_t7.4.toml");
    assert_eq!(
        (
            t.sources.tori[0].major_radius,
            t.sources.tori[0].coefficient
        ),
        (3.0, 7.4)
    );
    for (name, b) in [
        ("bezier_b5.0.toml", 5.0),
        ("bezier_b7.5.toml", 7.5),
        ("local_intensity_uniform_b8.0.toml", 8.0),
    ] {
        let s = load(name);
        assert_eq!(
            s.sources.curves.len(),
            1,
            "{name}: two joined segments are one chain"
        );
        assert_eq!(s.sources.curves[0].control_points.len(), 5);
        assert_eq!(s.sources.curves[0].coefficient, b);
    }
    let w = load("local_intensity_w_b8.0.toml");
    assert_eq!(
        w.sources.curves[0].weights,
        vec![1.0, 0.2, 0.6, 1.0, 0.5, 0.8, 1.0]
    );
    for name in ["bezier_b5.0.toml", "bezier_b5.0_moved.toml"] {
        // Smoothly connected: the control points around the joint are collinear with it.
        let cp = &load(name).sources.curves[0].control_points;
        let (a, b) = (cp[1] - cp[2], cp[3] - cp[2]);
        assert!(
            a.cross(b).length() < 1e-12 && a.dot(b) < 0.0,
            "{name}: joint not smooth"
        );
    }
    let m = load("mixed.toml").sources;
    assert!(
        !m.points.is_empty() && !m.lines.is_empty() && !m.tori.is_empty() && !m.curves.is_empty()
    );
    for name in [
        "divisions_torus_t8.0.toml",
        "divisions_torus_t4.0.toml",
        "divisions_curve_b8.0.toml",
        "divisions_curve_b4.0.toml",
    ] {
        let s = load(name);
        assert_eq!((s.integration.alpha, s.integration.beta), (1.0, 1.0));
        assert_eq!(s.integration.decay_length, papers_decay_length(&s, 2.0));
    }
}

#[test]
fn saving_round_trips() {
    for path in shipped() {
        let scene = Scene::load(&path).unwrap();
        let text = scene.to_toml();
        // Saved beside the original: a PLY file's relative path reads the same file.
        let again = Scene::parse(&text, &path.with_file_name("saved.toml"))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(scene, again, "{}", path.display());
    }
}

#[test]
fn defaults_fill_every_section_but_the_sources() {
    let s = Scene::parse(
        "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n",
        Path::new("p.toml"),
    )
    .unwrap();
    assert_eq!(s.integration.divisions, 200);
    assert_eq!((s.integration.alpha, s.integration.beta), (1.0, 1.0));
    // The papers' nu = 2 at the file's own camera (the default eye, a billboard in front of the point).
    assert_eq!(s.integration.decay_length, papers_decay_length(&s, 2.0));
    let eye_to_plane = (s.place_billboard(1.0).center - s.camera.eye).length();
    assert!((s.integration.decay_length - eye_to_plane).abs() < 1e-12);
    assert_eq!(s.billboard.resolution, 256);
    assert!(s.billboard.center.is_none() && s.billboard.size.is_none());
    // Directions are normalised on load.
    let s = Scene::parse(
        "[[lines]]\npoint = [0, 0, 0]\ndirection = [0, 3, 4]\ncoefficient = 1\n",
        Path::new("l.toml"),
    )
    .unwrap();
    assert_eq!(s.sources.lines[0].direction.to_array(), [0.0, 0.6, 0.8]);
}

/// Parses `text` expecting an `Invalid` error; returns the full message.
fn invalid(text: &str) -> (SceneError, String) {
    let err = Scene::parse(text, Path::new("bad.toml")).expect_err("must be refused");
    let msg = err.to_string();
    assert!(
        msg.starts_with("bad.toml"),
        "the message names the file: {msg}"
    );
    (err, msg)
}

const POINT: &str = "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n";

/// Each malformed case: (text, the field named, the line named, a phrase of the explanation).
#[test]
fn each_malformed_kind_gets_its_own_error() {
    let cases: &[(&str, &str, usize, &str)] = &[
        ("[camera\neye = [0, 0, 5]\n", "", 1, "unclosed table"),
        (
            "[camera]\neye = \"far away\"\n",
            "camera.eye",
            2,
            "invalid type",
        ),
        (
            "[camera]\neye = [0, 0]\n",
            "camera.eye",
            2,
            "array of length 3",
        ),
        // Finite, but so far out that distances overflow: named as that, at the eye, and nothing else (the
        // target, 1e308 away, is not "the same as the eye").
        (
            "[camera]\neye = [1e308, 1e308, 1e308]\n[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n",
            "camera.eye",
            2,
            "too far out",
        ),
        (
            "[[curves]]\ncontrol_points = [[0, 0, 0], [1, 2e16, 0], [2, 0, 0]]\ncoefficient = 1\n",
            "curves[0].control_points[1]",
            2,
            "limited to",
        ),
        (
            "[camera]\nfov = 40\n",
            "camera.fov",
            2,
            "unknown field `fov`",
        ),
        (
            "[camera]\nfov_y = 40\n[[points]]\nposition = [1, 2, 3]\n",
            "points[0]",
            3,
            "missing field `coefficient`",
        ),
        ("[camera]\neye = [0, nan, 5]\n", "camera.eye", 2, "finite"),
        ("[camera]\nfov_y = inf\n", "camera.fov_y", 2, "finite"),
        (
            "[camera]\nfov_y = 180\n",
            "camera.fov_y",
            2,
            "between 0 and 180",
        ),
        (
            "[camera]\neye = [1, 2, 3]\ntarget = [1, 2, 3]\n",
            "camera.target",
            3,
            "must differ from the eye",
        ),
        (
            "[camera]\neye = [0, 5, 0]\nup = [0, 1, 0]\n",
            "camera.up",
            3,
            "parallel",
        ),
        (
            "[integration]\ndivisions = 201\n",
            "integration.divisions",
            2,
            "even",
        ),
        (
            "[integration]\ndivisions = 0\n",
            "integration.divisions",
            2,
            "even",
        ),
        (
            "[integration]\nnu = 1.0\n",
            "integration.nu",
            2,
            "greater than 1",
        ),
        (
            "[integration]\ndecay_length = 0\n",
            "integration.decay_length",
            2,
            "must be positive",
        ),
        (
            "[integration]\nnu = 2.0\ndecay_length = 4.0\n",
            "integration.decay_length",
            3,
            "not both",
        ),
        (
            "[integration]\nbeta = 0\n",
            "integration.beta",
            2,
            "positive",
        ),
        (
            "[integration]\nepsilon = -1\n",
            "integration.epsilon",
            2,
            "positive",
        ),
        (
            "[billboard]\nresolution = 0\n",
            "billboard.resolution",
            2,
            "between 1 and",
        ),
        (
            "[billboard]\nresolution = 100000\n",
            "billboard.resolution",
            2,
            "between 1 and",
        ),
        (
            "[billboard]\nresolution = -4\n",
            "billboard.resolution",
            2,
            "invalid value",
        ),
        (
            "[billboard]\ncenter = [0, 0, 8]\nsize = 2\n",
            "billboard.center",
            2,
            "not be at the eye",
        ),
        (
            "[billboard]\ncenter = [0, 0, 2]\n",
            "billboard.center",
            2,
            "needs a size",
        ),
        ("[billboard]\nsize = 0\n", "billboard.size", 2, "positive"),
        (
            "[colors]\nenergy = [1.5, 0, 0]\n",
            "colors.energy",
            2,
            "0..1",
        ),
        (
            "[colors]\nblend = \"add\"\n",
            "colors.blend",
            2,
            "is not a blend",
        ),
        (
            "[[tori]]\nmajor_radius = -1\ncoefficient = 1\n",
            "tori[0].major_radius",
            2,
            "positive",
        ),
        (
            "[[tori]]\nmajor_radius = 0\ncoefficient = 1\n",
            "tori[0].major_radius",
            2,
            "positive",
        ),
        (
            "[[tori]]\naxis = [0, 0, 0]\nmajor_radius = 1\ncoefficient = 1\n",
            "tori[0].axis",
            2,
            "zero vector",
        ),
        (
            "[[lines]]\npoint = [0, 0, 0]\ndirection = [0, 0, 0]\ncoefficient = 1\n",
            "lines[0].direction",
            3,
            "zero vector",
        ),
        (
            "[[curves]]\ncontrol_points = [[0, 0, 0], [1, 1, 0]]\ncoefficient = 1\n",
            "curves[0].control_points",
            2,
            "3 (one quadratic",
        ),
        (
            "[[curves]]\ncontrol_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0], [3, 1, 0]]\ncoefficient = 1\n",
            "curves[0].control_points",
            2,
            "2k+1",
        ),
        (
            "[[curves]]\ncontrol_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0]]\ncoefficient = 1\nweights = []\n",
            "curves[0].weights",
            4,
            "empty",
        ),
        (
            "[[curves]]\ncontrol_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0]]\ncoefficient = 1\nweights = [1, -0.5]\n",
            "curves[0].weights[1]",
            4,
            "at least 0",
        ),
    ];
    for &(text, field, line, phrase) in cases {
        let text = format!("{text}{}", if text.contains("[[") { "" } else { POINT });
        let (err, msg) = invalid(&text);
        let problems = err.problems();
        assert!(!problems.is_empty(), "{text}: {msg}");
        let p = &problems[0];
        assert_eq!(p.field, field, "field of {text:?}: {msg}");
        assert_eq!(
            p.location.map(|l| l.0),
            Some(line),
            "line of {text:?}: {msg}"
        );
        assert!(
            msg.contains(phrase),
            "{text:?} gave {msg:?}, expected it to say {phrase:?}"
        );
        if !field.is_empty() {
            assert!(msg.contains(&format!("bad.toml:{line}:")), "{msg}");
        }
    }
    // An eye too far out is that one problem, not also a target "equal to the eye".
    let (err, msg) = invalid(
        "[camera]\neye = [1e308, 1e308, 1e308]\n[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n",
    );
    assert_eq!(err.problems().len(), 1, "{msg}");
}

#[test]
fn every_problem_is_reported_at_once() {
    let (err, _) = invalid(
        "[integration]\ndivisions = 3\nnu = 0.5\n[[tori]]\nmajor_radius = -1\ncoefficient = 1\n",
    );
    let fields: Vec<_> = err.problems().iter().map(|p| p.field.as_str()).collect();
    assert_eq!(
        fields,
        [
            "integration.divisions",
            "integration.nu",
            "tori[0].major_radius"
        ]
    );
}

#[test]
fn unreadable_inputs_are_named() {
    let dir = std::env::temp_dir().join(format!("energywave-scene-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let empty = dir.join("empty.toml");
    std::fs::write(&empty, "# only a comment\n\n").unwrap();
    assert!(matches!(Scene::load(&empty), Err(SceneError::Empty { .. })));
    let binary = dir.join("binary.toml");
    std::fs::write(&binary, [0x89, b'P', b'N', b'G', 0xff, 0x00, 0x12]).unwrap();
    let e = Scene::load(&binary).unwrap_err();
    assert!(
        matches!(e, SceneError::NotText { .. }) && e.to_string().contains("binary.toml"),
        "{e}"
    );
    let e = Scene::load(&dir).unwrap_err();
    assert!(matches!(e, SceneError::Directory { .. }), "{e}");
    let e = Scene::load(&dir.join("missing.toml")).unwrap_err();
    assert!(
        matches!(e, SceneError::Read { .. }) && e.to_string().contains("missing.toml"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_unknown_key_is_reported_at_once_with_the_key_it_is_closest_to() {
    let text = "[camera]\nfov = 30\nyee = [0, 0, 1]\n[colors]\nbackground = [0, 0, 0]\nzzz = 1\n[[points]]\nposition = [0, 0, 0]\ncoeficient = 1.0\n";
    let (err, msg) = invalid(text);
    let problems = err.problems();
    let found: Vec<(&str, Option<(usize, usize)>)> = problems
        .iter()
        .map(|p| (p.field.as_str(), p.location))
        .collect();
    assert_eq!(
        found,
        [
            ("camera.fov", Some((2, 1))),
            ("camera.yee", Some((3, 1))),
            ("colors.zzz", Some((6, 1))),
            ("points[0].coeficient", Some((9, 1))),
        ],
        "{msg}"
    );
    assert!(msg.contains("did you mean `fov_y`?"), "{msg}");
    assert!(msg.contains("did you mean `eye`?"), "{msg}");
    assert!(msg.contains("did you mean `coefficient`?"), "{msg}");
    // Nothing close to `zzz`: no guess; and the misspelt coefficient is not reported missing as well.
    assert!(!msg.contains("zzz`, expected one of `energy`, `energy_intensity`, `background`, `blend`, `cutoff`; did"), "{msg}");
    assert!(!msg.contains("missing field"), "{msg}");
}
