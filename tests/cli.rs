//! The `energywave` command line: exit statuses, messages, outputs, and pictures checked against the camera
//! math and the CPU reference.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use energywave::frame::FrameSetup;
use energywave::reference;
use energywave::scene::Scene;
use glam::DVec3;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_energywave"));
    c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
    c
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn tmpdir(name: &str) -> PathBuf {
    common::tmpdir("cli", name)
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn bad_input_exits_2_with_a_message_naming_it() {
    let dir = tmpdir("bad");
    let bad = dir.join("typo.toml");
    std::fs::write(
        &bad,
        "[camera]\nfov_y = 40\n\n[[tori]]\nmajor_radius = 1\ncoefficent = 5\n",
    )
    .unwrap();
    let out = dir.join("out.png");
    let o = run(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("typo.toml:6:") && e.contains("coefficent"),
        "{e}"
    );
    assert!(!out.exists(), "nothing is written for a bad scene");

    for (args, phrase) in [
        (
            vec!["render", "-o", "x.png", "--size", "12by3"],
            "not a frame size",
        ),
        (
            vec!["render", "-o", "x.png", "--size", "0x10"],
            "not a frame size",
        ),
        (
            vec!["render", "-o", "x.png", "--backend", "quantum"],
            "invalid value 'quantum'",
        ),
        (
            vec!["render", "-o", "x.png", "--divisions", "7"],
            "even division count",
        ),
        (
            vec!["render", "-o", "/nonexistent-dir/x.png"],
            "does not exist",
        ),
        (
            vec!["render", "-o", "x.jpeg2000"],
            "or .gif, .mp4 or .webm for an animation",
        ),
        (
            vec!["render", "-o", "x.png", "--brightness"],
            "give an .exr output",
        ),
        (
            vec!["render", "/nonexistent/scene.toml", "-o", "x.png"],
            "/nonexistent/scene.toml",
        ),
    ] {
        let o = bin().args(&args).current_dir(&dir).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(phrase), "{args:?}: {}", stderr(&o));
    }
    assert!(!dir.join("x.png").exists());
}

#[test]
fn an_existing_output_survives_a_failed_render() {
    let dir = tmpdir("keep");
    let out = dir.join("frame.png");
    std::fs::write(&out, b"previous image").unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[integration]\ndivisions = 3\n").unwrap();
    let o = run(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&out).unwrap(), b"previous image");
    // No temporary files are left behind either.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
}

#[test]
fn view_without_a_display_points_to_render() {
    let o = run(&["view"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("no display") && stderr(&o).contains("energywave render"),
        "{}",
        stderr(&o)
    );
    // A bad scene is still an input error.
    let o = run(&["view", "/nonexistent.toml"]);
    assert_eq!(o.status.code(), Some(2));
}

/// Without a driver (Vulkan's loader pointed at no driver, no other backend tried): one line that names the
/// packages for Vulkan and for GL and the CPU renderer, exit status 1, nothing written, no backtrace.
#[test]
fn render_without_a_driver_says_what_to_install() {
    let dir = tmpdir("no-driver");
    let out = dir.join("frame.png");
    let o = bin()
        .args(["render", "-o", out.to_str().unwrap(), "--size", "16x16"])
        .env("WGPU_BACKEND", "vulkan")
        .env("VK_ICD_FILENAMES", dir.join("none.json"))
        .env("VK_DRIVER_FILES", dir.join("none.json"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let line = (err.lines())
        .find(|l| l.starts_with("energywave: "))
        .unwrap_or_else(|| panic!("no message: {err}"));
    for wanted in [
        "no GPU driver found (tried Vulkan)",
        "mesa-vulkan-drivers libvulkan1",
        "libegl1 libegl-mesa0 libgl1-mesa-dri",
        "--backend cpu",
    ] {
        assert!(line.contains(wanted), "{wanted:?} not in {line:?}");
    }
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn render_writes_the_composed_frame() {
    let dir = tmpdir("frame");
    let out = dir.join("torus.png");
    let path = scene("torus_r0.9_t5.1.toml");
    let o = run(&[
        "render",
        "--backend",
        "cpu",
        &path,
        "-o",
        out.to_str().unwrap(),
        "--size",
        "96x64",
        "--resolution",
        "48",
        "--divisions",
        "64",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (96, 64));
    // The same frame from the library's reference, pixel for pixel (the CLI adds nothing of its own).
    let mut s = Scene::load(Path::new(&path)).unwrap();
    s.billboard.resolution = 48;
    s.integration.divisions = 64;
    let bb = s.place_billboard(96.0 / 64.0);
    let tex = reference::render_brightness(&FrameSetup::new(&s, bb));
    let frame = reference::compose_frame(&FrameSetup::new(&s, bb), &tex, 96, 64, false);
    for (px, want) in img.pixels().zip(&frame) {
        for c in 0..3 {
            assert!((px[c] as f64 - want[c] * 255.0).abs() <= 0.5 + 1e-9);
        }
    }
    // The picture is not flat: the ring blows out to white, the hole is darker than the ring, and the
    // frame's corners are darker still (a bright core fading into the background).
    let at = |p: DVec3| {
        let (x, y) = s.camera.project(p, 96, 64).unwrap();
        img.get_pixel(x as u32, y as u32).0
    };
    let ring = at(DVec3::new(0.9, 0.0, 0.0));
    let hole = at(DVec3::ZERO);
    let corner = img.get_pixel(0, 0).0;
    assert!(ring.iter().all(|&c| c >= 250), "ring {ring:?}");
    assert!(hole[0] < ring[0] - 40, "hole {hole:?} vs ring {ring:?}");
    assert!(
        corner[2] < hole[2] && corner[0] < 60,
        "corner {corner:?} hole {hole:?}"
    );
}

#[test]
fn brightness_writes_b_itself_as_float_exr() {
    let dir = tmpdir("exr");
    let out = dir.join("b.exr");
    let path = scene("bezier_b5.0.toml");
    let o = run(&[
        "render",
        "--backend",
        "cpu",
        &path,
        "-o",
        out.to_str().unwrap(),
        "--brightness",
        "--resolution",
        "24",
        "--divisions",
        "32",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap().to_rgb32f();
    assert_eq!(img.dimensions(), (24, 24));
    let mut s = Scene::load(Path::new(&path)).unwrap();
    s.billboard.resolution = 24;
    s.integration.divisions = 32;
    // --size defaults to a square frame.
    let bb = s.place_billboard(1.0);
    let mut above_one = 0;
    for j in 0..24 {
        for i in 0..24 {
            let want = reference::texel_brightness(&FrameSetup::new(&s, bb), i, j);
            let got = img.get_pixel(i, j).0;
            assert!(
                got.iter()
                    .all(|&g| ((g as f64) - want).abs() <= 1e-6 * want.max(1.0)),
                "({i},{j}) {got:?} vs {want}"
            );
            above_one += (want > 1.0) as usize;
        }
    }
    assert!(above_one > 0, "B is written unclamped");
}

#[test]
fn render_defaults_to_the_embedded_scene() {
    let dir = tmpdir("default");
    let out = dir.join("d.png");
    let o = run(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--size",
        "32x32",
        "--resolution",
        "16",
        "--divisions",
        "16",
        "-v",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("<embedded default scene>"),
        "{}",
        stderr(&o)
    );
    assert_eq!(image::open(&out).unwrap().to_rgb8().dimensions(), (32, 32));
}

#[test]
fn the_gpu_is_the_default_backend_and_names_its_adapter() {
    let dir = tmpdir("gpu");
    let out = dir.join("g.png");
    let o = run(&[
        "render",
        &scene("torus_r0.9_t5.1.toml"),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "40x30",
        "--resolution",
        "24",
        "-v",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("adapter: ") && stderr(&o).contains("backend Gpu"),
        "{}",
        stderr(&o)
    );
    assert_eq!(image::open(&out).unwrap().to_rgb8().dimensions(), (40, 30));
    // Transparent export carries alpha.
    let out = dir.join("t.png");
    let o = run(&[
        "render",
        &scene("torus_r0.9_t5.1.toml"),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "40x30",
        "--resolution",
        "24",
        "--transparent",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap();
    assert!(img.color().has_alpha());
    let alphas: Vec<u8> = img.to_rgba8().pixels().map(|p| p.0[3]).collect();
    assert!(
        alphas.contains(&255) && alphas.iter().any(|&a| a < 200),
        "alpha is graded"
    );
}

#[test]
fn no_adapter_is_a_clear_error_with_status_1() {
    let dir = tmpdir("noadapter");
    let out = dir.join("x.png");
    let o = bin()
        .args(["render", "-o", out.to_str().unwrap(), "--size", "8x8"])
        .env("WGPU_ADAPTER_NAME", "no such adapter anywhere")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("matches no adapter"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn bench_checks_its_json_path_before_running() {
    let o = run(&["bench", "--quick", "--json", "/nonexistent-dir/report.json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("/nonexistent-dir/report.json"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bench_refuses_an_equal_error_size_out_of_range_naming_the_flag() {
    let o = run(&[
        "bench",
        "--only",
        "equal-error",
        "--equal-error-sizes",
        "256,8",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--equal-error-sizes") && stderr(&o).contains("'8'"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn sizes_beyond_the_gpu_limit_are_refused_before_rendering_naming_their_origin() {
    let dir = tmpdir("limit");
    let big = dir.join("big.toml");
    let text = std::fs::read_to_string(scene("torus_r0.9_t5.1.toml")).unwrap();
    let text = format!("[billboard]\nresolution = 128\n{text}");
    std::fs::write(&big, text).unwrap();
    let out = dir.join("out.png");
    // A GPU whose textures hold at most 64 texels per side.
    let capped = |args: &[&str]| {
        bin()
            .env("ENERGYWAVE_MAX_TEXTURE_SIZE", "64")
            .args(args)
            .output()
            .unwrap()
    };
    let (b, o) = (big.to_str().unwrap(), out.to_str().unwrap());
    for (args, phrases) in [
        (
            vec!["render", b, "-o", o, "--size", "48x48"],
            vec![
                "big.toml: [billboard] resolution = 128",
                "at most 64 texels",
            ],
        ),
        (
            vec![
                "render",
                b,
                "-o",
                o,
                "--size",
                "48x48",
                "--resolution",
                "100",
            ],
            vec!["--resolution 100", "at most 64 texels"],
        ),
        (
            vec![
                "render",
                b,
                "-o",
                o,
                "--size",
                "96x48",
                "--resolution",
                "32",
            ],
            vec!["--size 96x48", "at most 64 pixels"],
        ),
    ] {
        let r = capped(&args);
        let e = stderr(&r);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {e}");
        for p in phrases {
            assert!(e.contains(p), "{args:?}: {e:?} lacks {p:?}");
        }
        assert!(!out.exists(), "{args:?}: nothing is written");
    }
    // Within the limit, the same GPU renders.
    let r = capped(&[
        "render",
        b,
        "-o",
        o,
        "--size",
        "48x48",
        "--resolution",
        "32",
        "--divisions",
        "16",
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert_eq!(image::open(&out).unwrap().width(), 48);
    // A scene that leaves W to the export gets what the GPU holds, not the viewer's 256.
    let preset = scene("torus_r0.9_t5.1.toml");
    let r = capped(&[
        "render",
        &preset,
        "-o",
        o,
        "--size",
        "48x48",
        "--divisions",
        "16",
        "-v",
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(
        stderr(&r).contains("billboard 64x64 texels"),
        "{}",
        stderr(&r)
    );

    let r = bin()
        .env("ENERGYWAVE_MAX_TEXTURE_SIZE", "lots")
        .args(["render", "-o", dir.join("x.png").to_str().unwrap()])
        .output()
        .unwrap();
    let e = stderr(&r);
    assert_eq!(r.status.code(), Some(2), "{e}");
    assert!(e.contains("ENERGYWAVE_MAX_TEXTURE_SIZE=\"lots\""), "{e}");
}

#[test]
fn holdout_leaves_the_objects_out_and_their_glow_hidden_on_both_backends() {
    // A bright point behind a sphere that stands before the billboard: the sphere's middle pixel is opaque in a
    // transparent render (the object drawn), transparent under --holdout (the object left out, the glow it hides
    // still hidden), and the glow beside it shows in both; --holdout without --transparent is refused.
    let dir = tmpdir("holdout");
    let file = dir.join("sphere.toml");
    std::fs::write(
        &file,
        "[camera]\neye = [0.0, 0.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 30.0\n\
         [billboard]\nresolution = 48\n\
         [[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.5\n\
         [[objects]]\nshape = \"sphere\"\ncenter = [0.0, 0.0, 4.0]\nradius = 0.5\ncolor = [0.9, 0.6, 0.3]\n",
    )
    .unwrap();
    let (w, h) = (64u32, 48u32);
    let size = format!("{w}x{h}");
    let sphere = file.to_str().unwrap();
    for backend in ["gpu", "cpu"] {
        let render = |name: &str, extra: &[&str]| {
            let out = dir.join(format!("{backend}-{name}.png"));
            let mut args = vec![
                "render",
                sphere,
                "--backend",
                backend,
                "--size",
                &size,
                "-o",
            ];
            let path = out.to_str().unwrap().to_owned();
            args.push(&path);
            args.extend_from_slice(extra);
            let o = run(&args);
            assert!(o.status.success(), "{backend} {name}: {}", stderr(&o));
            image::open(&out).unwrap().to_rgba8()
        };
        let drawn = render("transparent", &["--transparent"]);
        let held = render("holdout", &["--transparent", "--holdout"]);
        let middle = (w / 2, h / 2);
        // A little off the sphere's edge, where the point's glow is.
        let beside = (w / 2 + w / 5, h / 2);
        assert_eq!(
            drawn.get_pixel(middle.0, middle.1)[3],
            255,
            "{backend}: the sphere drawn"
        );
        assert_eq!(
            held.get_pixel(middle.0, middle.1).0,
            [0, 0, 0, 0],
            "{backend}: held out"
        );
        for image in [&drawn, &held] {
            let a = image.get_pixel(beside.0, beside.1)[3];
            assert!(a > 40, "{backend}: the glow beside the sphere, alpha {a}");
        }
        assert_eq!(
            drawn.get_pixel(beside.0, beside.1),
            held.get_pixel(beside.0, beside.1)
        );
    }
    let o = run(&[
        "render",
        sphere,
        "--holdout",
        "-o",
        dir.join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--transparent"), "{}", stderr(&o));
    assert!(!dir.join("x.png").exists());
}

#[test]
fn a_fitted_transparent_sheet_ends_in_alpha_zero_round_every_cell() {
    let dir = tmpdir("fit");
    // The travelling pulse with an edge (its preset keeps the papers' endless glow).
    let text = std::fs::read_to_string(scene("pulse_travelling.toml"))
        .unwrap()
        .replace("cutoff = 0.0", "cutoff = 0.2");
    let file = dir.join("pulse.toml");
    std::fs::write(&file, text).unwrap();
    let sheet = dir.join("sheet.png");
    let (f, s) = (file.to_str().unwrap(), sheet.to_str().unwrap());
    let common = [
        "render",
        f,
        "-o",
        s,
        "--sheet",
        "--columns",
        "3",
        "--frames",
        "20..26",
        "--size",
        "64x48",
        "--transparent",
        "--resolution",
        "96",
    ];
    let o = run(&[&common[..], &["--fit"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&sheet).unwrap().to_rgba8();
    assert_eq!((img.width(), img.height()), (3 * 64, 2 * 48));
    let mut lit = 0;
    for cell in 0..6 {
        let (x0, y0) = ((cell % 3) * 64, (cell / 3) * 48);
        for y in 0..48 {
            for x in 0..64 {
                let a = img.get_pixel(x0 + x, y0 + y)[3];
                lit += (a > 0) as u32;
                if x == 0 || y == 0 || x == 63 || y == 47 {
                    assert_eq!(a, 0, "cell {cell} at ({x}, {y})");
                }
            }
        }
    }
    assert!(
        lit > 6 * 64 * 48 / 10,
        "the pulse glows in the cells: {lit}"
    );
    // The papers' preset has no edge to fit: refused, naming the file and the setting.
    let o = run(&[
        "render",
        &scene("pulse_travelling.toml"),
        "-o",
        s,
        "--sheet",
        "--fit",
        "--transparent",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("pulse_travelling.toml: --fit") && stderr(&o).contains("cutoff"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_opaque_exr_keeps_the_blend_above_one_on_both_backends_and_a_png_clamps_it() {
    let dir = tmpdir("hdr");
    let preset = scene("rings_and_beam.toml");
    let size = ["--size", "64x48", "--resolution", "64"];
    let mut frames = Vec::new();
    for backend in ["gpu", "cpu"] {
        let exr = dir.join(format!("{backend}.exr"));
        let png = dir.join(format!("{backend}.png"));
        for out in [&exr, &png] {
            let o = run(&[
                &[
                    "render",
                    &preset,
                    "-o",
                    out.to_str().unwrap(),
                    "--backend",
                    backend,
                ][..],
                &size,
            ]
            .concat());
            assert!(o.status.success(), "{}", stderr(&o));
        }
        let hdr = image::open(&exr).unwrap().to_rgba32f();
        let ldr = image::open(&png).unwrap().to_rgba8();
        let top = hdr
            .pixels()
            .flat_map(|p| p.0[..3].to_vec())
            .fold(0.0, f32::max);
        assert!(
            top > 1.2,
            "{backend}: the white-hot cores keep their values above 1: {top}"
        );
        for (h, l) in hdr.pixels().zip(ldr.pixels()) {
            assert_eq!(h.0[3], 1.0);
            for c in 0..3 {
                assert!(h.0[c] >= 0.0);
                let want = (h.0[c].clamp(0.0, 1.0) * 255.0).round();
                assert!(
                    (l.0[c] as f32 - want).abs() <= 1.0,
                    "{backend}: {h:?} {l:?}"
                );
            }
        }
        frames.push(hdr);
    }
    // The GPU against its f64 twin, above 1 too.
    let worst = frames[0]
        .pixels()
        .zip(frames[1].pixels())
        .flat_map(|(g, c)| (0..3).map(move |k| (g.0[k] - c.0[k]).abs() / c.0[k].abs().max(1.0)))
        .fold(0.0, f32::max);
    assert!(worst < 4.0 / 255.0, "{worst}");
    // The header says what was written.
    let bytes = std::fs::read(dir.join("gpu.exr")).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    assert!(
        text.contains("values above 1 kept"),
        "the header names the values"
    );
}

/// `--every-texel` integrates every texel (each is the twin's integral along its own ray); without it the field
/// is refined in image space: some texels predicted, all within half the tolerance of those integrated.
#[test]
fn every_texel_is_the_reference_and_the_refined_render_lies_within_half_the_tolerance() {
    let dir = tmpdir("every_texel");
    let w = 128u32;
    let render = |name: &str, every: bool| {
        let out = dir.join(name);
        let resolution = w.to_string();
        let mut args = vec![
            "render",
            "--backend",
            "cpu",
            "-o",
            out.to_str().unwrap(),
            "--brightness",
            "--resolution",
            &resolution,
        ];
        if every {
            args.push("--every-texel");
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        image::open(&out).unwrap().to_rgb32f()
    };
    let (every, refined) = (render("every.exr", true), render("refined.exr", false));
    let mut s = Scene::default_scene();
    s.billboard.resolution = w;
    let bb = s.place_billboard(1.0);
    let setup = FrameSetup::new(&s, bb);
    for j in (0..w).step_by(9) {
        for i in (0..w).step_by(9) {
            let want = reference::texel_brightness(&setup, i, j);
            let got = every.get_pixel(i, j).0[0] as f64;
            assert!(
                (got - want).abs() <= 1e-6 * want.max(1.0),
                "({i},{j}) {got} vs {want}"
            );
        }
    }
    let tolerance = s.integration.tolerance;
    let mut predicted = 0;
    for (a, b) in every.pixels().zip(refined.pixels()) {
        let d = (a.0[0] as f64 - b.0[0] as f64).abs();
        assert!(
            d <= 0.5 * tolerance,
            "{d:e} off, over half of {tolerance:e}"
        );
        // A texel predicted differs from its integral in the last bits at least (most by far less than 1e-6).
        predicted += (d > 0.0) as usize;
    }
    let share = predicted as f64 / (w * w) as f64;
    // At W = 128 the refinement integrates about 73 % of the default scene's texels.
    assert!(
        share > 0.1,
        "the default render refines: {share:.3} of the texels predicted"
    );
}
