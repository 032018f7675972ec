//! `energywave shader` from the command line, without a GPU or glslang: the files it writes (their WGSL parses
//! and validates again, the block's bytes are the layout's), what it refuses (exit 2, nothing written), and that
//! a failed write leaves an earlier export whole. The shaders compiled and run against the field pass:
//! tests/engine.rs.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::names;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn the_shader_files_hold_a_valid_module_and_the_block_its_layout_describes() {
    let dir = common::tmpdir("shader", "files");
    let out = dir.display().to_string();
    let o = run(&["shader", &scene("mixed.toml"), "-o", &out, "--name", "beam"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        names(&dir),
        [
            "beam.brightness.es.frag",
            "beam.brightness.frag",
            "beam.es.vert",
            "beam.glow.es.frag",
            "beam.glow.frag",
            "beam.hlsl",
            "beam.metal",
            "beam.uniforms.bin",
            "beam.uniforms.json",
            "beam.vert",
            "beam.wgsl",
        ]
    );
    // The WGSL as written parses and validates on its own.
    let wgsl = std::fs::read_to_string(dir.join("beam.wgsl")).unwrap();
    let module = naga::front::wgsl::parse_str(&wgsl).unwrap();
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap();
    for entry in ["vs_main", "fs_glow", "fs_brightness"] {
        assert!(
            module.entry_points.iter().any(|e| e.name == entry),
            "{entry}"
        );
    }
    // The block: the layout's members tile it, each 16-byte aligned, and the mixed scene's sources are there.
    let layout: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("beam.uniforms.json")).unwrap())
            .unwrap();
    let bytes = std::fs::read(dir.join("beam.uniforms.bin")).unwrap();
    assert_eq!(layout["bytes"].as_u64().unwrap() as usize, bytes.len());
    let mut at = 0;
    for m in layout["members"].as_array().unwrap() {
        let offset = m["offset"].as_u64().unwrap() as usize;
        assert_eq!(offset, at, "{m}");
        assert_eq!(offset % 16, 0, "{m}");
        at += m["bytes"].as_u64().unwrap() as usize;
    }
    assert_eq!(at, bytes.len());
    let s = energywave::scene::Scene::load(Path::new(&scene("mixed.toml"))).unwrap();
    let member = |name: &str| {
        (layout["members"].as_array().unwrap().iter())
            .find(|m| m["name"] == name)
            .unwrap()
            .clone()
    };
    assert_eq!(
        member("points")["count"].as_u64().unwrap() as usize,
        s.sources.points.len()
    );
    assert_eq!(
        member("curves")["count"].as_u64().unwrap() as usize,
        s.sources.curves.len()
    );
    // The first point's position and coefficient, where the layout says.
    if let Some(p) = s.sources.points.first() {
        let o = member("points")["offset"].as_u64().unwrap() as usize;
        let f: &[f32] = bytemuck::cast_slice(&bytes[o..o + 16]);
        for (got, want) in f.iter().zip(p.position.to_array()) {
            assert!((*got as f64 - want).abs() < 1e-6);
        }
        assert!((f[3] as f64 - p.coefficient).abs() < 1e-6);
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_requests_are_refused_and_a_failed_write_leaves_the_earlier_files_whole() {
    let dir = common::tmpdir("shader", "refused");
    let out = dir.join("out").display().to_string();
    assert!(
        run(&["shader", &scene("default.toml"), "-o", &out])
            .status
            .success()
    );
    let earlier: Vec<(String, Vec<u8>)> = names(Path::new(&out))
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(Path::new(&out).join(&n)).unwrap()))
        .collect();
    // A name that is no file name, a folder where a file stands, too many divisions.
    let file = dir.join("a-file");
    std::fs::write(&file, b"not a folder").unwrap();
    let heavy = dir.join("heavy.toml");
    std::fs::write(
        &heavy,
        std::fs::read_to_string(scene("default.toml"))
            .unwrap()
            .replace("divisions = 200", "divisions = 8192"),
    )
    .unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&["--name", "../x"], "letters, digits"),
        (&["-o", file.to_str().unwrap()], "cannot be made a folder"),
        (&["SCENE", heavy.to_str().unwrap()], "at most 4096"),
    ];
    for (args, why) in cases {
        let mut all = vec!["shader".to_owned()];
        let given_scene = args.first() == Some(&"SCENE");
        all.push(if given_scene {
            args[1].to_owned()
        } else {
            scene("mixed.toml")
        });
        if !args.contains(&"-o") {
            all.extend(["-o".to_owned(), out.clone()]);
        }
        if !given_scene {
            all.extend(args.iter().map(|a| a.to_string()));
        }
        let all: Vec<&str> = all.iter().map(|a| a.as_str()).collect();
        let o = run(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(why), "{args:?}: {err}");
    }
    // A write that fails (a folder where one of the files goes) leaves every earlier file as it was.
    std::fs::remove_file(Path::new(&out).join("effect.metal")).unwrap();
    std::fs::create_dir(Path::new(&out).join("effect.metal")).unwrap();
    let o = run(&["shader", &scene("mixed.toml"), "-o", &out]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for (name, bytes) in &earlier {
        if name != "effect.metal" {
            assert_eq!(
                &std::fs::read(Path::new(&out).join(name)).unwrap(),
                bytes,
                "{name}"
            );
        }
    }
    assert_eq!(
        names(Path::new(&out)).len(),
        earlier.len(),
        "nothing left beside them"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn every_shipped_scene_makes_a_shader_in_every_language() {
    use energywave::engine::{EngineError, MAX_BLOCK_BYTES, MAX_DIVISIONS};
    let (mut made, mut refused) = (0, Vec::new());
    for (name, scene) in common::shipped() {
        let effect = match energywave::engine::EffectShader::of(&scene, 16.0 / 9.0) {
            Ok(e) => e,
            Err(e) => {
                // Only a scene past the engine's limits may be refused: the limit it names is the scene's, and
                // it is past it.
                match &e {
                    EngineError::TooManyDivisions { n } => {
                        assert_eq!(*n, scene.integration.divisions, "{name}: {e}");
                        assert!(*n > MAX_DIVISIONS, "{name}: {e}");
                    }
                    EngineError::TooLarge { bytes } => {
                        assert!(*bytes > MAX_BLOCK_BYTES, "{name}: {e}")
                    }
                    _ => panic!("{name}: refused for no limit of the engine's: {e}"),
                }
                refused.push(name);
                continue;
            }
        };
        made += 1;
        for entry in ["vs_main", "fs_glow", "fs_brightness"] {
            for es in [false, true] {
                let glsl = effect
                    .glsl(entry, es)
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                assert!(glsl.starts_with(if es {
                    "#version 300 es"
                } else {
                    "#version 450"
                }));
            }
        }
        assert!(
            effect
                .hlsl()
                .unwrap()
                .contains("cbuffer effect : register(b0)"),
            "{name}"
        );
        assert!(effect.msl().unwrap().contains("fragment"), "{name}");
    }
    // Every shipped scene is within the limits today: a refusal is a change to look at, not to pass over.
    assert!(refused.is_empty(), "refused: {refused:?}");
    assert!(made >= 20, "{made} shaders made");
}
