//! Exports of an animation from the command line: PNG sequences (numbering, padding, ranges), GIFs and
//! sprite sheets decoded back, transparent frames composited over a checkerboard against the blend computed
//! by hand, and bad requests refused with exit status 2 before anything is rendered.
//!
//! Frames are small (48 x 40 pixels, a 40-texel billboard, n = 40) so that the whole file runs in seconds on
//! a software GPU.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use image::AnimationDecoder;

fn preset() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes/pulse_travelling.toml")
        .display()
        .to_string()
}

fn tmpdir(name: &str) -> PathBuf {
    common::tmpdir("export", name)
}

/// `render` of `scene` at test size with `args`.
fn render(scene: &str, args: &[&str]) -> Output {
    let size: &[&str] = if args.contains(&"--size") {
        &[]
    } else {
        &["--size", "48x40"]
    };
    Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args(["render", scene, "--resolution", "40", "--divisions", "40"])
        .args(size)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

/// `render` of `scene` with `args` alone (no test size, resolution or divisions).
fn render_as_given(scene: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args(["render", scene])
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn a_sequence_gets_numbered_padded_files_that_match_single_renders() {
    let dir = tmpdir("seq");
    let pattern = dir.join("beam_####.png");
    let o = render(
        &preset(),
        &["--frames", "20..23", "-o", pattern.to_str().unwrap()],
    );
    ok(&o);
    assert_eq!(
        files(&dir),
        ["beam_0020.png", "beam_0021.png", "beam_0022.png"]
    );
    // The progress bar, one line per frame when stderr is not a terminal.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("3/3 frames (frame 22)"), "{err}");
    let frames: Vec<_> = (20..23)
        .map(|f| rgba(&dir.join(format!("beam_{f:04}.png"))))
        .collect();
    for f in &frames {
        assert_eq!(f.dimensions(), (48, 40));
    }
    // The pulse moves: consecutive frames differ.
    assert_ne!(frames[0], frames[1]);
    assert_ne!(frames[1], frames[2]);
    // An inclusive range, another machine's share of the same export, continues the numbering; and one
    // frame rendered alone is the same picture as in the sequence.
    let single = dir.join("single.png");
    ok(&render(
        &preset(),
        &["--frames", "21", "-o", single.to_str().unwrap()],
    ));
    assert_eq!(rgba(&single), frames[1]);
    let more = tmpdir("seq-more");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "89..=91",
            "-o",
            more.join("beam_##.png").to_str().unwrap(),
        ],
    ));
    assert_eq!(files(&more), ["beam_89.png", "beam_90.png", "beam_91.png"]);
    // The brightness B of each frame, W x W floats, as an EXR sequence.
    let exr = tmpdir("seq-exr");
    ok(&render(
        &preset(),
        &[
            "--brightness",
            "--frames",
            "0..2",
            "-o",
            exr.join("b_#.exr").to_str().unwrap(),
        ],
    ));
    assert_eq!(files(&exr), ["b_0.exr", "b_1.exr"]);
    let b = image::open(exr.join("b_1.exr")).unwrap().to_rgb32f();
    assert_eq!(b.dimensions(), (40, 40));
}

#[test]
fn a_gif_and_a_sprite_sheet_decode_to_the_frames() {
    let dir = tmpdir("gif");
    let gif = dir.join("pulse.gif");
    ok(&render(
        &preset(),
        &["--frames", "10..16", "-o", gif.to_str().unwrap()],
    ));
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    let frames = decoder.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 6);
    let mut total = 0.0;
    for f in &frames {
        assert_eq!(f.buffer().dimensions(), (48, 40));
        // 30 frames/s; GIF delays are whole hundredths of a second.
        let (num, den) = f.delay().numer_denom_ms();
        let ms = num as f64 / den as f64;
        assert!((30.0..=40.0).contains(&ms), "delay {ms} ms");
        total += ms;
    }
    // 3 and 4 hundredths in turn: six frames at 30 frames/s last 0.2 s, not 0.18.
    assert_eq!(total, 200.0);
    assert_ne!(frames[0].buffer(), frames[5].buffer(), "the pulse moves");

    // The sheet: 5 frames in 3 columns, 2 rows, row-major; its cells are the sequence's frames.
    let sheet = dir.join("sheet.png");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "20..25",
            "--sheet",
            "--columns",
            "3",
            "-o",
            sheet.to_str().unwrap(),
        ],
    ));
    let img = rgba(&sheet);
    assert_eq!(img.dimensions(), (3 * 48, 2 * 40));
    let layout: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sheet.json")).unwrap()).unwrap();
    let grid = &layout["meta"]["energywave"];
    assert_eq!(grid["columns"], 3);
    assert_eq!(grid["rows"], 2);
    assert_eq!(grid["frame_count"], 5);
    assert_eq!(
        grid["frames"][4],
        serde_json::json!({ "frame": 24, "x": 48, "y": 40 })
    );
    let seq = tmpdir("gif-seq");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "20..25",
            "-o",
            seq.join("f_####.png").to_str().unwrap(),
        ],
    ));
    // Decoded with the TexturePacker layout alone, as an engine's importer does: each frame's rectangle is the
    // sequence's frame.
    assert_eq!(layout["meta"]["image"], "sheet.png");
    assert_eq!(
        layout["meta"]["size"],
        serde_json::json!({"w": 3 * 48, "h": 2 * 40})
    );
    let frames_json = layout["frames"].as_object().unwrap();
    assert_eq!(frames_json.len(), 5);
    for k in 0..5u32 {
        let f = &frames_json[&format!("sheet_{:04}", 20 + k)];
        let r = &f["frame"];
        let (x, y, w, h) = (
            r["x"].as_u64().unwrap() as u32,
            r["y"].as_u64().unwrap() as u32,
            r["w"].as_u64().unwrap() as u32,
            r["h"].as_u64().unwrap() as u32,
        );
        assert_eq!(f["sourceSize"], serde_json::json!({"w": w, "h": h}));
        let cell = image::imageops::crop_imm(&img, x, y, w, h).to_image();
        let frame = rgba(&seq.join(format!("f_{:04}.png", 20 + k)));
        assert_eq!(cell, frame, "frame {}", 20 + k);
    }
    // The unused sixth cell is black.
    assert!(
        image::imageops::crop_imm(&img, 96, 40, 48, 40)
            .to_image()
            .pixels()
            .all(|p| p.0[..3] == [0, 0, 0])
    );
    let gif_frame = frames[0].buffer();
    let png = tmpdir("gif-one").join("ten.png");
    ok(&render(
        &preset(),
        &["--frames", "10", "-o", png.to_str().unwrap()],
    ));
    let truth = rgba(&png);
    let mean: f64 = gif_frame
        .pixels()
        .zip(truth.pixels())
        .map(|(a, b)| {
            (0..3)
                .map(|c| (a.0[c] as f64 - b.0[c] as f64).abs())
                .sum::<f64>()
        })
        .sum::<f64>()
        / (48.0 * 40.0 * 3.0);
    assert!(
        mean < 6.0,
        "the GIF's palette is close to the frame (mean error {mean})"
    );
}

/// The preset with its background color replaced, as a scene file in `dir`.
fn with_background(dir: &Path, name: &str, cb: [f64; 3]) -> String {
    let text = std::fs::read_to_string(preset()).unwrap().replace(
        "background = [0.0, 0.0, 0.02]",
        &format!("background = [{}, {}, {}]", cb[0], cb[1], cb[2]),
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn transparent_frames_composite_over_a_checkerboard_like_the_blend() {
    let dir = tmpdir("alpha");
    let frame = "30";
    let t = dir.join("t.png");
    ok(&render(
        &preset(),
        &[
            "--frames",
            frame,
            "--transparent",
            "-o",
            t.to_str().unwrap(),
        ],
    ));
    let t = rgba(&t);
    // The checkerboard's two colors, and black.
    let light = [0.9, 0.8, 0.2];
    let dark = [0.1, 0.3, 0.6];
    let opaque = |name: &str, cb: [f64; 3]| {
        let scene = with_background(&dir, &format!("{name}.toml"), cb);
        let out = dir.join(format!("{name}.png"));
        ok(&render(
            &scene,
            &["--frames", frame, "-o", out.to_str().unwrap()],
        ));
        rgba(&out)
    };
    let (o_light, o_dark, o_black) = (
        opaque("light", light),
        opaque("dark", dark),
        opaque("black", [0.0; 3]),
    );
    let energy = [0.3, 0.55, 1.0];
    let (mut partial, mut blown) = (0, 0);
    for (x, y, p) in t.enumerate_pixels() {
        let [r, g, b, a] = p.0.map(|c| c as f64 / 255.0);
        // "Over", by hand: straight color times alpha plus the background times (1 - alpha).
        let over = |k: [f64; 3]| {
            [
                r * a + k[0] * (1.0 - a),
                g * a + k[1] * (1.0 - a),
                b * a + k[2] * (1.0 - a),
            ]
        };
        let close = |got: [f64; 3], want: &image::Rgba<u8>, what: &str| {
            for c in 0..3 {
                let w = want.0[c] as f64 / 255.0;
                assert!(
                    (got[c] - w).abs() <= 2.5 / 255.0,
                    "({x}, {y}) {what}: composite {got:?} vs blend {:?} (alpha {a})",
                    want.0
                );
            }
        };
        // Over black, everywhere, blown-out pixels included.
        close(over([0.0; 3]), o_black.get_pixel(x, y), "over black");
        if p.0[3] < 255 {
            // B < 1 here: over the checkerboard, the viewer's blend with that square's color as Cb.
            let on_light = (x / 8 + y / 8) % 2 == 0;
            let (k, o) = if on_light {
                (light, &o_light)
            } else {
                (dark, &o_dark)
            };
            close(over(k), o.get_pixel(x, y), "over the checkerboard");
            // And by hand: (1 - B) Cb + B Ce with B = alpha.
            let by_hand: [f64; 3] = std::array::from_fn(|c| (1.0 - a) * k[c] + a * energy[c]);
            for (got, want) in over(k).iter().zip(by_hand) {
                assert!((got - want).abs() <= 2.5 / 255.0, "({x}, {y}) by hand");
            }
            if p.0[3] > 0 {
                partial += 1;
            }
        } else if p.0[..3] != [77, 140, 255] {
            // Alpha 1 and a color brighter than Ce: B > 1, blown toward white.
            blown += 1;
        }
    }
    assert!(
        partial > 200,
        "the glow's soft edge is covered ({partial} pixels)"
    );
    assert!(
        blown > 20,
        "blown-out pixels (B > 1) are covered ({blown} pixels)"
    );
}

#[test]
fn bad_requests_exit_2_before_rendering_and_write_nothing() {
    let dir = tmpdir("bad");
    let still = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes/torus_r0.9_t5.1.toml")
        .display()
        .to_string();
    let p = |name: &str| dir.join(name).display().to_string();
    let cases: Vec<(String, Vec<String>, &str)> = vec![
        (
            preset(),
            vec![
                "--frames".into(),
                "0..500".into(),
                "-o".into(),
                p("a_####.png"),
            ],
            "the scene has 92 frames",
        ),
        (
            preset(),
            vec![
                "--frames".into(),
                "5..2".into(),
                "-o".into(),
                p("a_####.png"),
            ],
            "empty",
        ),
        (
            preset(),
            vec!["--frames".into(), "0..3".into(), "-o".into(), p("one.png")],
            "one image",
        ),
        (
            preset(),
            vec!["--transparent".into(), "-o".into(), p("a.gif")],
            "GIF",
        ),
        (
            preset(),
            vec!["-o".into(), p("a_##_#.png")],
            "more than one run of #",
        ),
        (preset(), vec!["-o".into(), p("a_###.gif")], "remove the #"),
        (
            preset(),
            vec!["--sheet".into(), "-o".into(), p("s_##.png")],
            "sprite sheet",
        ),
        (
            preset(),
            vec![
                "--sheet".into(),
                "--size".into(),
                "4096x4096".into(),
                "-o".into(),
                p("s.png"),
            ],
            "over 16384 pixels",
        ),
        (
            still.clone(),
            vec!["--frames".into(), "1..3".into(), "-o".into(), p("t_##.png")],
            "has 1 frame",
        ),
        (
            preset(),
            vec!["-o".into(), p("missing/a_####.png")],
            "does not exist",
        ),
        (
            preset(),
            vec![
                "--frames".into(),
                "ten".into(),
                "-o".into(),
                p("a_####.png"),
            ],
            "not a frame range",
        ),
        (
            preset(),
            vec!["-o".into(), p("a_####.jpg")],
            "unknown image extension",
        ),
    ];
    for (scene, args, phrase) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = render(scene, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(phrase),
            "{args:?}: expected {phrase:?} in: {err}"
        );
        assert!(files(&dir).is_empty(), "{args:?} wrote {:?}", files(&dir));
    }
    // A still scene exports as a one-frame sequence.
    ok(&render(&still, &["-o", &p("still_####.png")]));
    assert_eq!(files(&dir), ["still_0000.png"]);
}

/// `oiiotool` (OpenImageIO, Debian `openimageio-tools`) with `args`; panics with its message when it fails.
fn oiiotool(args: &[&str]) {
    let o = Command::new("oiiotool")
        .args(args)
        .output()
        .expect("oiiotool runs (Debian: apt-get install openimageio-tools)");
    assert!(
        o.status.success(),
        "oiiotool {args:?}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn a_padded_power_of_two_premultiplied_sheet_decodes_from_its_json() {
    let dir = tmpdir("sheet-pad");
    let sheet = dir.join("beam.png");
    let o = render(
        &preset(),
        &[
            "--frames",
            "30..37",
            "--sheet",
            "--padding",
            "3",
            "--power-of-two",
            "--transparent",
            "--premultiplied",
            "-o",
            sheet.to_str().unwrap(),
        ],
    );
    ok(&o);
    let img = image::open(&sheet).unwrap().to_rgba8();
    // Seven frames of 48 x 40: 3 columns, 3 rows, 3 between: 150 x 126, rounded up to 256 x 128.
    assert_eq!(img.dimensions(), (256, 128));
    let layout: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("beam.json")).unwrap()).unwrap();
    assert_eq!(
        layout["meta"]["size"],
        serde_json::json!({"w": 256, "h": 128})
    );
    assert_eq!(layout["meta"]["premultipliedAlpha"], true);
    // Each cell is the premultiplied single frame; the padding between cells is transparent.
    let seq = tmpdir("sheet-pad-seq");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "30..37",
            "--transparent",
            "--premultiplied",
            "-o",
            seq.join("f_##.png").to_str().unwrap(),
        ],
    ));
    for (name, f) in layout["frames"].as_object().unwrap() {
        let r = &f["frame"];
        let at = |k: &str| r[k].as_u64().unwrap() as u32;
        let frame: u32 = name.trim_start_matches("beam_").parse().unwrap();
        let cell = image::imageops::crop_imm(&img, at("x"), at("y"), at("w"), at("h")).to_image();
        assert_eq!(cell, rgba(&seq.join(format!("f_{frame}.png"))), "{name}");
        // Premultiplied: no channel above its alpha.
        assert!(cell.pixels().all(|p| p.0[..3].iter().all(|&c| c <= p.0[3])));
    }
    for x in 48..51 {
        assert!(
            (0..40).all(|y| img.get_pixel(x, y).0[3] == 0),
            "padding column {x}"
        );
    }
    // Past what mobile GPUs load, the command line says so.
    let big = render(
        &preset(),
        &[
            "--frames",
            "0..4",
            "--sheet",
            "--size",
            "2100x64",
            "-o",
            dir.join("big.png").to_str().unwrap(),
        ],
    );
    ok(&big);
    assert!(
        String::from_utf8_lossy(&big.stderr).contains("over 4096 pixels a side"),
        "{}",
        String::from_utf8_lossy(&big.stderr)
    );
}

#[test]
fn a_compositor_puts_the_transparent_exr_and_png_over_a_plate_as_the_viewer_blends() {
    let dir = tmpdir("over");
    let scene_text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml"),
    )
    .unwrap();
    let scene = dir.join("glow.toml");
    std::fs::write(&scene, &scene_text).unwrap();
    let s = scene.to_str().unwrap();
    let size = ["--size", "96x64"];
    let exr = dir.join("glow.exr");
    let png = dir.join("glow.png");
    for out in [&exr, &png] {
        ok(&render(
            s,
            &[&size[..], &["--transparent", "-o", out.to_str().unwrap()]].concat(),
        ));
    }
    let glow = image::open(&exr).unwrap().to_rgba32f();
    let straight = image::open(&png).unwrap().to_rgba8();
    let mut compared = 0;
    for (k, background) in [[0.9, 0.4, 0.1], [0.1, 0.6, 0.2], [0.5, 0.5, 0.5]]
        .iter()
        .enumerate()
    {
        let [r, g, b] = background;
        // What the viewer shows on that background.
        let on = dir.join(format!("on{k}.toml"));
        std::fs::write(
            &on,
            scene_text.replace(
                "background = [0.0, 0.0, 0.02]",
                &format!("background = [{r}, {g}, {b}]"),
            ),
        )
        .unwrap();
        let want_path = dir.join(format!("want{k}.exr"));
        ok(&render(
            on.to_str().unwrap(),
            &[&size[..], &["-o", want_path.to_str().unwrap()]].concat(),
        ));
        let want = image::open(&want_path).unwrap().to_rgb32f();
        // A plate of that color, and the compositor's "over".
        let plate = dir.join(format!("plate{k}.exr"));
        let plate_str = plate.to_str().unwrap().to_owned();
        oiiotool(&[
            "--pattern",
            &format!("constant:color={r},{g},{b},1"),
            "96x64",
            "4",
            "-o",
            &plate_str,
        ]);
        for (input, tolerance) in [(&exr, 2.0 / 255.0), (&png, 2.0 / 255.0)] {
            let out = dir.join(format!("over{k}.exr"));
            oiiotool(&[
                input.to_str().unwrap(),
                &plate_str,
                "--over",
                "-o",
                out.to_str().unwrap(),
            ]);
            let got = image::open(&out).unwrap().to_rgba32f();
            let (worst, pixels) = common::over_error(&got, &want, &glow);
            compared += pixels;
            assert!(
                worst <= tolerance,
                "{} over {background:?}: off by {worst} from the viewer's blend",
                input.display()
            );
        }
    }
    assert!(
        compared > 3 * 2 * 96 * 64 / 2,
        "most pixels have B <= 1: {compared}"
    );
    // The PNG holds straight color, the EXR associated color: the same glow.
    let (p, e) = (straight.get_pixel(48, 32), glow.get_pixel(48, 32));
    if e[3] > 0.05 && e[3] < 0.999 {
        for c in 0..3 {
            assert!((p[c] as f32 / 255.0 * e[3] - e[c]).abs() < 2.0 / 255.0);
        }
    }
}

#[test]
fn a_transparent_exr_keeps_hdr_and_says_its_color_space() {
    let dir = tmpdir("exr-hdr");
    let exr = dir.join("glow.exr");
    ok(&render(
        &preset(),
        &["--transparent", "-o", exr.to_str().unwrap()],
    ));
    let glow = image::open(&exr).unwrap().to_rgba32f();
    let brightest = glow.pixels().map(|p| p[2]).fold(0.0f32, f32::max);
    assert!(brightest > 1.0, "B > 1 keeps B Ce unclamped: {brightest}");
    assert!(
        glow.pixels()
            .all(|p| p[3] <= 1.0 && p.0.iter().take(3).all(|&c| c <= p[3].max(1e-6) * 100.0))
    );
    let o = Command::new("oiiotool")
        .args(["--info", "-v", exr.to_str().unwrap()])
        .output()
        .expect("oiiotool runs");
    let info = String::from_utf8_lossy(&o.stdout);
    assert!(
        info.contains("chromaticities: 0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329"),
        "{info}"
    );
    assert!(
        info.contains("energywave:values: \"display-referred"),
        "{info}"
    );
}

/// ffprobe's `key=value` lines about the video stream of `path`.
fn probe(path: &Path) -> String {
    let o = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_read_frames,width,height,codec_name,r_frame_rate:stream_tags=alpha_mode",
            "-of",
            "default=nw=1",
        ])
        .arg(path)
        .output()
        .expect("ffprobe runs (Debian: apt-get install ffmpeg)");
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_video_decodes_back_to_its_frames() {
    let dir = tmpdir("video");
    let mp4 = dir.join("pulse.mp4");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "0..12",
            "--size",
            "96x64",
            "-o",
            mp4.to_str().unwrap(),
        ],
    ));
    let info = probe(&mp4);
    for line in [
        "codec_name=h264",
        "width=96",
        "height=64",
        "r_frame_rate=30/1",
        "nb_read_frames=12",
    ] {
        assert!(info.lines().any(|l| l == line), "{line} in\n{info}");
    }
    // Frame 5 decoded is the frame rendered alone, but for the codec's loss.
    let decoded = dir.join("five.png");
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(&mp4)
        .args(["-vf", "select=eq(n\\,5)", "-frames:v", "1"])
        .arg(&decoded)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let single = dir.join("single.png");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "5",
            "--size",
            "96x64",
            "-o",
            single.to_str().unwrap(),
        ],
    ));
    let (a, b) = (rgba(&decoded), rgba(&single));
    let mean: f64 = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p[c] as f64 - q[c] as f64).abs())
                .sum::<f64>()
                / 3.0
        })
        .sum::<f64>()
        / (96.0 * 64.0);
    assert!(mean < 4.0, "mean difference {mean} of 255");
    // WebM carries the transparent export's alpha.
    let webm = dir.join("pulse.webm");
    ok(&render(
        &preset(),
        &[
            "--frames",
            "0..12",
            "--size",
            "96x64",
            "--transparent",
            "-o",
            webm.to_str().unwrap(),
        ],
    ));
    let info = probe(&webm);
    for line in [
        "codec_name=vp9",
        "width=96",
        "height=64",
        "nb_read_frames=12",
        "TAG:alpha_mode=1",
    ] {
        assert!(info.lines().any(|l| l == line), "{line} in\n{info}");
    }
    assert_eq!(
        files(&dir).iter().filter(|f| f.contains("partial")).count(),
        0
    );
}

#[test]
fn without_ffmpeg_a_video_is_refused_with_the_install_command() {
    let dir = tmpdir("no-ffmpeg");
    let mp4 = dir.join("pulse.mp4");
    let o = Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args([
            "render",
            &preset(),
            "--size",
            "32x32",
            "-o",
            mp4.to_str().unwrap(),
        ])
        .env("ENERGYWAVE_FFMPEG", dir.join("no-such-ffmpeg"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("pulse.mp4") && err.contains("apt-get install ffmpeg"),
        "{err}"
    );
    assert!(files(&dir).is_empty(), "nothing written");
    // H.264 has no alpha.
    let o = render(&preset(), &["--transparent", "-o", mp4.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains(".webm"));
}

/// Runs `f` while as many threads as the machine has cores spin beside it, so that a writer's own threads are
/// scheduled differently from an idle run.
fn with_cores_busy<T>(f: impl FnOnce() -> T) -> T {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
    let spinners: Vec<_> = (0..cores)
        .map(|_| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                let mut x = 0u64;
                while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                    x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                }
                x
            })
        })
        .collect();
    let out = f();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    spinners.into_iter().for_each(|t| drop(t.join()));
    out
}

#[test]
fn two_renders_of_a_frame_are_the_same_bytes_in_every_format() {
    // A render farm checksums frames: the same frame rendered twice must give the same file, whatever the writer's
    // threads did. The EXR of the brightness went through the image crate's writer, whose chunks come in the order
    // its threads finish them; every EXR now goes in increasing line order. Each format rendered at a larger size
    // (many chunks), once idle and once with every core busy.
    let dir = tmpdir("reproducible");
    let scene = preset();
    let cases: &[(&str, &[&str])] = &[
        ("frame.png", &[]),
        ("frame.exr", &[]),
        ("transparent.png", &["--transparent"]),
        ("premultiplied.png", &["--transparent", "--premultiplied"]),
        ("transparent.exr", &["--transparent"]),
        ("holdout.exr", &["--transparent", "--holdout"]),
        ("brightness.exr", &["--brightness"]),
        ("anim.gif", &["--frames", "20..23"]),
        ("sheet.png", &["--frames", "20..23", "--sheet"]),
        ("clip.mp4", &["--frames", "20..26"]),
        ("clip.webm", &["--frames", "20..26"]),
    ];
    for (name, args) in cases {
        let mut bytes = Vec::new();
        for busy in [false, true] {
            let out = dir.join(format!("{}-{busy}", busy as u8)).join(name);
            std::fs::create_dir_all(out.parent().unwrap()).unwrap();
            let out_s = out.display().to_string();
            let mut all = vec!["--size", "320x240", "--resolution", "160", "-o", &out_s];
            all.extend_from_slice(args);
            if !args.contains(&"--frames") {
                all.extend_from_slice(&["--frames", "20"]);
            }
            let run = || render_as_given(&scene, &all);
            let o = if busy { with_cores_busy(run) } else { run() };
            ok(&o);
            let mut files = vec![std::fs::read(&out).unwrap()];
            if args.contains(&"--sheet") {
                files.push(std::fs::read(out.with_extension("json")).unwrap());
            }
            bytes.push(files);
        }
        assert!(
            bytes[0].iter().all(|f| f.len() > 100),
            "{name}: a file was written"
        );
        assert!(
            bytes[0] == bytes[1],
            "{name}: two renders of the same frame differ ({} against {} bytes)",
            bytes[0][0].len(),
            bytes[1][0].len()
        );
    }
}

#[test]
fn a_brightness_sequence_is_staged_and_moved_in_whole() {
    // As every other sequence: interrupted or failed on the way, it leaves an earlier sequence of the same names
    // as it was; done, the frames are in place and nothing of the staging is left.
    let dir = tmpdir("brightness-sequence");
    let pattern = dir.join("b_####.exr").display().to_string();
    ok(&render(
        &preset(),
        &["--brightness", "--frames", "3..6", "-o", &pattern],
    ));
    assert_eq!(files(&dir), ["b_0003.exr", "b_0004.exr", "b_0005.exr"]);
    let before: Vec<Vec<u8>> = (3..6)
        .map(|f| std::fs::read(dir.join(format!("b_{f:04}.exr"))).unwrap())
        .collect();
    // A second export over it that fails on its third frame (its folder made unwritable there is not portable;
    // a frame named as a folder is): the first two frames it rendered must not have replaced the old ones.
    std::fs::remove_file(dir.join("b_0005.exr")).unwrap();
    std::fs::create_dir(dir.join("b_0005.exr")).unwrap();
    std::fs::write(dir.join("b_0005.exr").join("keep"), b"a folder in the way").unwrap();
    // (Another billboard resolution, so that the frames it renders differ from the ones in place.)
    let o = render_as_given(
        &preset(),
        &[
            "--brightness",
            "--resolution",
            "24",
            "--frames",
            "3..6",
            "-o",
            &pattern,
        ],
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "a frame's place taken by a folder fails the export: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    for (k, f) in (3..5).enumerate() {
        assert_eq!(
            std::fs::read(dir.join(format!("b_{f:04}.exr"))).unwrap(),
            before[k],
            "frame {f} kept"
        );
    }
    assert!(
        files(&dir).iter().all(|n| !n.contains("partial")),
        "no staging left behind: {:?}",
        files(&dir)
    );
}
