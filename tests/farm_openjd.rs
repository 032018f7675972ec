//! Open Job Description: `docs/farm/energywave.openjd.yaml` checked by `openjd check` and run whole by `openjd
//! run` (openjd-cli, the reference runtime of AWS Deadline Cloud's job format): chunks of frames from its
//! CHUNK[INT] task parameter, then the assembly, every frame and the joined GIF those of one local export; a
//! chunk failing on bad input stops the job before the assembly. Needs `--features openjd`
//! (`./test.sh` turns it on); without it the test is listed as ignored, with what it needs.
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn template() -> String {
    root()
        .join("docs/farm/energywave.openjd.yaml")
        .display()
        .to_string()
}

fn openjd(args: &[&str]) -> Output {
    Command::new("openjd")
        .args(args)
        .env_remove("DISPLAY")
        .output()
        .expect("openjd runs (pip install openjd-cli; .ci/run)")
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
#[cfg_attr(
    not(feature = "openjd"),
    ignore = "needs openjd-cli on PATH and --features openjd: ./test.sh runs it"
)]
fn the_template_renders_chunks_and_joins_them_as_one_export_does() {
    ok(&openjd(&["check", &template()]));
    let dir = common::tmpdir("openjd", "sparks");
    let scene = root()
        .join("assets/scenes/pulse_sparks.toml")
        .display()
        .to_string();
    let exe = env!("CARGO_BIN_EXE_energywave");
    let gif = dir.join("sparks.gif").display().to_string();
    let more = "--resolution 40 --integrator simpson --divisions 40";
    let param = |k: &str, v: &str| format!("{k}={v}");
    let run = |last: &str, exe: &str, out: &Path| {
        let params = [
            param("Executable", exe),
            param("SceneFile", &scene),
            param("OutputDir", &out.display().to_string()),
            param("OutputName", "f_####.png"),
            param("FirstFrame", "0"),
            param("LastFrame", last),
            param("ChunkSize", "3"),
            param("Size", "64x48"),
            param("RenderArgs", more),
            param("AssembleOutput", &gif),
        ];
        let mut args = vec!["run".to_owned(), template()];
        for p in params {
            args.extend(["-p".to_owned(), p]);
        }
        let args: Vec<&str> = args.iter().map(|a| a.as_str()).collect();
        openjd(&args)
    };
    let o = run("7", exe, &dir);
    ok(&o);
    let log = String::from_utf8_lossy(&o.stdout).into_owned();
    // Three chunks of the eight frames (shared out evenly), then the assembly.
    for chunk in ["--frames 0-2", "--frames 3-5", "--frames 6-7"] {
        assert!(log.contains(chunk), "{chunk} not run:\n{log}");
    }
    assert!(log.contains("energywave assemble:"), "{log}");
    let local = common::tmpdir("openjd", "local");
    let (pattern, local_gif) = (
        local.join("f_####.png").display().to_string(),
        local.join("sparks.gif").display().to_string(),
    );
    for out in [&pattern, &local_gif] {
        let mut args = vec![
            "render", &scene, "--frames", "0-7", "-o", out, "--size", "64x48",
        ];
        args.extend(more.split(' '));
        ok(&Command::new(exe).args(&args).output().unwrap());
    }
    for n in 0..8 {
        let name = format!("f_{n:04}.png");
        assert!(
            std::fs::read(dir.join(&name)).unwrap() == std::fs::read(local.join(&name)).unwrap(),
            "frame {n}"
        );
    }
    assert!(
        std::fs::read(&gif).unwrap() == std::fs::read(&local_gif).unwrap(),
        "the GIF"
    );

    // Frames past the animation's end (it has 120): energywave refuses the chunk with status 2, the job fails
    // and the assembly never runs.
    let bad = common::tmpdir("openjd", "bad");
    let _ = std::fs::remove_file(&gif);
    let o = run("125", exe, &bad);
    assert!(!o.status.success());
    let log = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        log.contains("energywave exit 2: the input is at fault"),
        "{log}"
    );
    assert!(
        !Path::new(&gif).exists(),
        "no assembly after a failed chunk"
    );
    for d in [dir, local, bad] {
        let _ = std::fs::remove_dir_all(d);
    }
}
