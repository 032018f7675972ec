//! Round trips with Blender (Debian's `blender`, run headless): a glTF scene Blender exports (nested transforms,
//! flat and smooth normals, base colors) loads as Blender has it; transparent PNG and EXR sequences composited over
//! a plate by Blender's compositor (Alpha Over, the sequence read as Blender's image sequence and rendered as an
//! animation) are the viewer's blend over that background, frame by frame; and
//! a Blender camera set from ours (docs/blender/camera.py) sees an object where we draw it. The scripts are those
//! docs/blender/ gives users. Needs `--features blender` (`./test.sh` turns it on);
//! without it each test is listed as ignored, with what it needs.
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use energywave::scene::Scene;
use glam::DVec3;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `blender -b --factory-startup` with `before` (options such as `--python-expr`), then the script of
/// docs/blender/ with `args`; its stdout, after checking that it succeeded.
fn blender(before: &[&str], script: &str, args: &[&str]) -> String {
    let o = Command::new("blender")
        .args(["-b", "--factory-startup", "--python-exit-code", "1"])
        .args(before)
        .arg("--python")
        .arg(root().join("docs/blender").join(script))
        .arg("--")
        .args(args)
        .output()
        .expect("blender runs (Debian: apt-get install blender python3-numpy)");
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "blender {script} {args:?}: exit {:?}\n{out}\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// The JSON a script prints after `tag`.
fn report(out: &str, tag: &str) -> serde_json::Value {
    let line = (out.lines())
        .find_map(|l| l.strip_prefix(tag))
        .unwrap_or_else(|| panic!("no {tag} in:\n{out}"));
    serde_json::from_str(line).unwrap()
}

fn energywave(args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs");
    assert!(
        o.status.success(),
        "energywave {args:?}: exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn vec3(v: &serde_json::Value) -> DVec3 {
    let a: Vec<f64> = (v.as_array().unwrap().iter())
        .map(|x| x.as_f64().unwrap())
        .collect();
    DVec3::new(a[0], a[1], a[2])
}

#[test]
#[cfg_attr(
    not(feature = "blender"),
    ignore = "needs Blender (Debian's blender and python3-numpy) and --features blender: ./test.sh runs it"
)]
fn a_gltf_scene_from_blender_loads_where_blender_has_it_with_its_normals_and_colors() {
    let dir = common::tmpdir("blender", "gltf");
    let glb = dir.join("shot.glb");
    let out = blender(&[], "export_gltf.py", &[glb.to_str().unwrap()]);
    let blend = report(&out, "ENERGYWAVE_BLENDER_JSON ");
    // The file as a scene's object: no color given, so its materials' base colors are the albedo.
    let scene_path = dir.join("shot.toml");
    std::fs::write(
        &scene_path,
        "[[points]]\nposition = [0.0, 3.0, 3.0]\ncoefficient = 1.0\n\n[[objects]]\nshape = \"mesh\"\npath = \"shot.glb\"\n",
    )
    .unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.objects[0].color, [1.0; 3]);
    let energywave::objects::Shape::Mesh(mesh) = &scene.objects[0].shape else {
        panic!("a mesh")
    };
    let data = &mesh.data;
    assert_eq!(
        data.normals.len(),
        data.triangles.len(),
        "the file's normals"
    );
    assert_eq!(data.base_colors.len(), data.triangles.len());
    let meshes: Vec<&serde_json::Value> = (blend["objects"].as_array().unwrap().iter())
        .filter(|o| o["type"] == "MESH")
        .collect();
    assert_eq!(meshes.len(), 2, "the nested cube and the sphere");
    let mut matched = 0;
    let (mut worst_position, mut worst_normal, mut worst_color) = (0.0f64, 0.0f64, 0.0f64);
    for object in &meshes {
        let mesh = &object["mesh"];
        let base = vec3(&mesh["base_color_srgb"]);
        let smooth = mesh["shading"] == "smooth";
        let triangles = mesh["triangles"].as_array().unwrap();
        let normals = mesh["normals"].as_array().unwrap();
        let mut varied = 0;
        for (corners, corner_normals) in triangles.iter().zip(normals) {
            let want: Vec<DVec3> = corners.as_array().unwrap().iter().map(vec3).collect();
            let want_n: Vec<DVec3> = corner_normals
                .as_array()
                .unwrap()
                .iter()
                .map(vec3)
                .collect();
            let center = (want[0] + want[1] + want[2]) / 3.0;
            // The loaded triangle with that center, in world space: the nested transforms applied.
            let (k, got) = (data.triangles.iter().enumerate())
                .min_by(|a, b| {
                    let d = |t: &[DVec3; 3]| ((t[0] + t[1] + t[2]) / 3.0 - center).length();
                    d(a.1).total_cmp(&d(b.1))
                })
                .unwrap();
            for (c, w) in want.iter().enumerate() {
                // The same corner, wherever the file starts the triangle.
                let j = (0..3)
                    .min_by(|&a, &b| (got[a] - *w).length().total_cmp(&(got[b] - *w).length()))
                    .unwrap();
                worst_position = worst_position.max((got[j] - *w).length());
                let n = data.normals[k][j].normalize();
                worst_normal = worst_normal.max((n - want_n[c]).length());
            }
            let color = DVec3::from_array(data.base_colors[k]);
            worst_color = worst_color.max((color - base).abs().max_element());
            varied += usize::from((want_n[0] - want_n[1]).length() > 1e-3);
            matched += 1;
        }
        // Blender's shading, kept: the sphere's corners each their own normal, the cube's its faces'.
        match smooth {
            true => assert!(varied > triangles.len() / 2, "smooth: {varied}"),
            false => assert_eq!(varied, 0, "flat"),
        }
    }
    eprintln!(
        "{matched} triangles: positions within {worst_position:.1e}, normals {worst_normal:.1e}, base colors {worst_color:.1e}"
    );
    assert_eq!(matched, data.triangles.len(), "every triangle, once");
    assert!(worst_position < 1e-5, "positions off by {worst_position}");
    assert!(worst_normal < 1e-5, "normals off by {worst_normal}");
    assert!(worst_color < 1e-5, "base colors off by {worst_color}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
#[cfg_attr(
    not(feature = "blender"),
    ignore = "needs Blender (Debian's blender and python3-numpy) and --features blender: ./test.sh runs it"
)]
fn blender_puts_our_transparent_png_and_exr_frames_over_a_plate_as_the_viewer_blends() {
    let dir = common::tmpdir("blender", "over");
    let text = std::fs::read_to_string(root().join("assets/scenes/pulse_travelling.toml")).unwrap();
    let scene = dir.join("glow.toml");
    std::fs::write(&scene, &text).unwrap();
    let s = scene.to_str().unwrap();
    let small = [
        "--size",
        "96x64",
        "--resolution",
        "48",
        "--integrator",
        "simpson",
    ];
    let frames = ["--frames", "10-11"];
    for pattern in ["glow_####.exr", "glow_####.png"] {
        let out = dir.join(pattern);
        let mut args = vec!["render", s, "--transparent", "-o", out.to_str().unwrap()];
        args.extend(small);
        args.extend(frames);
        energywave(&args);
    }
    let mut compared = 0;
    for (k, background) in [[0.9, 0.4, 0.1], [0.1, 0.6, 0.2]].iter().enumerate() {
        let [r, g, b] = background;
        // What the viewer shows on that background, frame by frame.
        let on = dir.join(format!("on{k}.toml"));
        let replaced = text.replace(
            "background = [0.0, 0.0, 0.02]",
            &format!("background = [{r}, {g}, {b}]"),
        );
        assert_ne!(replaced, text);
        std::fs::write(&on, replaced).unwrap();
        let want_pattern = dir.join(format!("want{k}_####.exr"));
        let mut args = vec![
            "render",
            on.to_str().unwrap(),
            "-o",
            want_pattern.to_str().unwrap(),
        ];
        args.extend(small);
        args.extend(frames);
        energywave(&args);
        // A plate of that color, as a float EXR.
        let plate = dir.join(format!("plate{k}.exr"));
        energywave::output::write_rgba(
            &plate,
            96,
            64,
            &vec![[*r, *g, *b, 1.0]; 96 * 64],
            energywave::output::Alpha::Opaque,
        )
        .unwrap();
        for ext in ["exr", "png"] {
            // The sequence composited as Blender composites one: an image sequence, rendered as an animation.
            let input = dir.join(format!("glow_####.{ext}"));
            let out = dir.join(format!("over{k}_{ext}_####.exr"));
            blender(
                &[],
                "alpha_over.py",
                &[
                    plate.to_str().unwrap(),
                    input.to_str().unwrap(),
                    out.to_str().unwrap(),
                    "--frames",
                    "10-11",
                ],
            );
            for frame in [10, 11] {
                let open = |name: String| image::open(dir.join(name)).unwrap();
                let want = open(format!("want{k}_{frame:04}.exr")).to_rgb32f();
                let glow = open(format!("glow_{frame:04}.exr")).to_rgba32f();
                let got = open(format!("over{k}_{ext}_{frame:04}.exr")).to_rgba32f();
                let (worst, pixels) = common::over_error(&got, &want, &glow);
                compared += pixels;
                eprintln!("frame {frame} ({ext}) over {background:?}: within {worst:.2e}");
                assert!(
                    worst <= 2.0 / 255.0,
                    "frame {frame} ({ext}) over {background:?}: off by {worst} from the viewer's blend"
                );
            }
        }
    }
    assert!(
        compared > 2 * 2 * 2 * 96 * 64 / 2,
        "most pixels have B <= 1: {compared}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
#[cfg_attr(
    not(feature = "blender"),
    ignore = "needs Blender (Debian's blender and python3-numpy) and --features blender: ./test.sh runs it"
)]
fn a_blender_camera_set_from_ours_sees_an_object_where_we_draw_it() {
    let dir = common::tmpdir("blender", "camera");
    let (w, h) = (160u32, 90u32);
    // Blender's factory cube (its vertices at +-1) as our box, a faint point that lights it, and a camera off
    // every axis.
    let scene_path = dir.join("shot.toml");
    std::fs::write(
        &scene_path,
        "[camera]\neye = [3.1, 2.2, 5.3]\ntarget = [0.2, -0.1, 0.3]\nup = [0.0, 1.0, 0.0]\nfov_y = 31.0\n\n\
         [colors]\nbackground = [0.0, 0.0, 0.0]\n\n[[points]]\nposition = [30.0, 30.0, 30.0]\ncoefficient = 0.0001\n\n\
         [[objects]]\nshape = \"box\"\ncenter = [0.0, 0.0, 0.0]\nsize = [2.0, 2.0, 2.0]\n",
    )
    .unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let size = format!("{w}x{h}");
    // Where Blender's camera puts points, against our own projection.
    let points = [
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, -1.0],
        [0.7, -0.4, 2.5],
        [-2.0, 0.3, 0.1],
    ];
    let list: Vec<String> = points
        .iter()
        .map(|p| format!("{},{},{}", p[0], p[1], p[2]))
        .collect();
    let ours = dir.join("ours.png");
    let theirs = dir.join("blender.png");
    let out = blender(
        &[
            "--python-expr",
            "import bpy; s = bpy.context.scene; s.render.engine = 'BLENDER_WORKBENCH'; \
             s.render.film_transparent = True; s.display.shading.light = 'FLAT'",
        ],
        "camera.py",
        &[
            "--scene",
            scene_path.to_str().unwrap(),
            "--size",
            &size,
            "--points",
            &list.join(";"),
            "--render",
            theirs.to_str().unwrap(),
        ],
    );
    let json = report(&out, "ENERGYWAVE_CAMERA_JSON ");
    let pixels = json["pixels"].as_array().unwrap();
    for (p, px) in points.iter().zip(pixels) {
        let (x, y) = scene.camera.project(DVec3::from_array(*p), w, h).unwrap();
        let b = px.as_array().unwrap();
        let (bx, by) = (b[0].as_f64().unwrap(), b[1].as_f64().unwrap());
        assert!(
            (bx - x).abs() < 0.01 && (by - y).abs() < 0.01,
            "{p:?}: Blender ({bx}, {by}), ours ({x}, {y})"
        );
    }
    // The cube drawn by both: the same pixels covered.
    energywave(&[
        "render",
        scene_path.to_str().unwrap(),
        "--size",
        &size,
        "--transparent",
        "-o",
        ours.to_str().unwrap(),
    ]);
    let mask = |path: &Path| -> Vec<bool> {
        let img = image::open(path).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (w, h), "{}", path.display());
        img.pixels().map(|p| p[3] >= 128).collect()
    };
    let (a, b) = (mask(&ours), mask(&theirs));
    let both = a.iter().zip(&b).filter(|(x, y)| **x && **y).count();
    let either = a.iter().zip(&b).filter(|(x, y)| **x || **y).count();
    assert!(
        either > 800,
        "the cube covers a good part of the frame: {either}"
    );
    let centroid = |m: &[bool]| {
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for (k, _) in m.iter().enumerate().filter(|(_, v)| **v) {
            sx += (k as u32 % w) as f64;
            sy += (k as u32 / w) as f64;
            n += 1.0;
        }
        (sx / n, sy / n)
    };
    let (ca, cb) = (centroid(&a), centroid(&b));
    let iou = both as f64 / either as f64;
    eprintln!("the cube: overlap {iou:.4}, centroids {ca:?} (ours) and {cb:?} (Blender)");
    assert!(iou > 0.97, "the cube's pixels overlap by {iou:.3}");
    assert!(
        (ca.0 - cb.0).abs() < 0.35 && (ca.1 - cb.1).abs() < 0.35,
        "centroids {ca:?} (ours) and {cb:?} (Blender)"
    );
    let _ = std::fs::remove_dir_all(dir);
}
