//! Rendering on a farm: a sequence in chunks (`render --frames A-B`) that any machine renders in any order and
//! as often as it likes, each frame the same byte for byte as in one whole export, live particles included; a
//! chunk stopped by its scheduler leaves nothing; `assemble` joins the chunks' frames into the very GIF, video
//! and sprite sheet one export makes, and names the frames that are missing; `farm slurm` writes job scripts
//! that render their chunk and try again only when trying again can help. (The scripts under a real Slurm, and
//! Open Job Description's template under openjd, are in tests/farm_slurm.rs and tests/farm_openjd.rs.)

mod common;

use std::path::{Path, PathBuf};

use common::{SMALL_FRAMES as SMALL, names, sparks as scene};
use std::process::{Command, Output};

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_energywave"));
    c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
    c
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

/// `render` of the sparks at the small size with `args`.
fn render(args: &[&str]) -> Output {
    let s = scene();
    let mut all = vec!["render", s.as_str()];
    all.extend(SMALL);
    all.extend(args);
    run(&all)
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn refused(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn pattern(dir: &Path) -> String {
    dir.join("f_####.png").display().to_string()
}

fn frame(dir: &Path, n: u32) -> PathBuf {
    dir.join(format!("f_{n:04}.png"))
}

#[test]
fn chunks_in_any_order_make_the_frames_of_one_export_byte_for_byte() {
    let whole = common::tmpdir("farm", "whole");
    let chunks = common::tmpdir("farm", "chunks");
    ok(&render(&["--frames", "0..9", "-o", &pattern(&whole)]));
    // The last chunk first, in the farm managers' inclusive form and in ours.
    for range in ["6-8", "0..3", "3..=5"] {
        ok(&render(&["--frames", range, "-o", &pattern(&chunks)]));
    }
    assert_eq!(names(&chunks), names(&whole));
    assert_eq!(names(&whole).len(), 9);
    for n in 0..9 {
        assert!(
            bytes(&frame(&whole, n)) == bytes(&frame(&chunks, n)),
            "frame {n} differs between the whole export and its chunk"
        );
    }
    // The frames move: a still would prove nothing.
    assert_ne!(bytes(&frame(&whole, 0)), bytes(&frame(&whole, 8)));
    // A chunk run again (the scheduler retried it) writes its own frames and no other: a frame of another chunk
    // changed since is left as it is.
    let elsewhere = b"not touched by chunk 3-5".to_vec();
    std::fs::write(frame(&chunks, 2), &elsewhere).unwrap();
    std::fs::write(frame(&chunks, 6), &elsewhere).unwrap();
    ok(&render(&["--frames", "3-5", "-o", &pattern(&chunks)]));
    assert_eq!(bytes(&frame(&chunks, 2)), elsewhere);
    assert_eq!(bytes(&frame(&chunks, 6)), elsewhere);
    for n in 3..6 {
        assert!(
            bytes(&frame(&whole, n)) == bytes(&frame(&chunks, n)),
            "frame {n} again"
        );
    }
    // One frame alone, as a chunk of one and as a single image.
    let one = common::tmpdir("farm", "one");
    ok(&render(&["--frames", "7", "-o", &pattern(&one)]));
    assert_eq!(names(&one), vec!["f_0007.png"]);
    assert!(bytes(&frame(&one, 7)) == bytes(&frame(&whole, 7)));
    let still = one.join("still.png");
    ok(&render(&[
        "--frames",
        "7",
        "-o",
        &still.display().to_string(),
    ]));
    assert!(bytes(&still) == bytes(&frame(&whole, 7)));
    for d in [whole, chunks, one] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_chunk_stopped_or_failing_halfway_leaves_no_file() {
    let dir = common::tmpdir("farm", "stopped");
    // A scheduler's time limit or cancel: SIGTERM while the chunk renders. It stops after its frame, removes
    // what it wrote and says to try again (status 1).
    // The signal must land while the chunk still renders: once a frame is whole the chunk is stopped (SIGSTOP, at
    // once), and only then sent SIGTERM and let go on (SIGCONT), so that it cannot finish first however fast the
    // GPU; should every frame be done before it was stopped, the chunk is run again over more frames.
    let s = scene();
    let out = pattern(&dir);
    let signal = |name: &str, child: &std::process::Child| {
        // The shell's own kill: no procps needed.
        let ok = Command::new("sh")
            .args(["-c", &format!("kill -{name} {}", child.id())])
            .status()
            .unwrap();
        assert!(ok.success(), "kill -{name}");
    };
    let mut child = None;
    for last in [60, 119] {
        let range = format!("0-{last}");
        let mut args = vec!["render", s.as_str(), "--frames", range.as_str(), "-o", &out];
        args.extend(SMALL);
        let mut c = bin()
            .args(&args)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        // Until a frame is whole in the chunk's staging folder.
        loop {
            let staged: usize = (std::fs::read_dir(&dir).unwrap().flatten())
                .filter(|e| e.path().is_dir())
                .map(|e| std::fs::read_dir(e.path()).map_or(0, |d| d.count()))
                .sum();
            if staged >= 2 || c.try_wait().unwrap().is_some() {
                break;
            }
            assert!(
                start.elapsed().as_secs() < 120,
                "no frame rendered in 2 minutes"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        signal("STOP", &c);
        if c.try_wait().unwrap().is_none() {
            child = Some(c);
            break;
        }
        // It finished every frame first: clear its frames away and run a longer chunk.
        for name in names(&dir) {
            let _ = std::fs::remove_file(dir.join(name));
        }
    }
    let mut child = child.expect("a chunk still rendering when stopped");
    signal("TERM", &child);
    signal("CONT", &child);
    let status = child.wait().unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(err.contains("nothing written"), "{err}");
    assert_eq!(names(&dir), Vec::<String>::new(), "{err}");
    // A chunk failing at its end (a folder stands where its last frame goes): none of its frames is written,
    // status 1.
    std::fs::create_dir(frame(&dir, 2)).unwrap();
    let o = render(&["--frames", "0-2", "-o", &pattern(&dir)]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(names(&dir), vec!["f_0002.png"]);
    let _ = std::fs::remove_dir_all(dir);
}

/// `assemble` of the sparks' frames `dir/f_####.png` with `args`.
fn assemble(dir: &Path, args: &[&str]) -> Output {
    let (s, p) = (scene(), pattern(dir));
    let mut all = vec!["assemble", s.as_str(), "--input", p.as_str()];
    all.extend(args);
    run(&all)
}

#[test]
fn assembled_chunks_are_the_files_one_export_makes() {
    let dir = common::tmpdir("farm", "assemble");
    let opaque = dir.join("opaque");
    let clear = dir.join("transparent");
    std::fs::create_dir_all(&opaque).unwrap();
    std::fs::create_dir_all(&clear).unwrap();
    for range in ["4-6", "0-3"] {
        ok(&render(&["--frames", range, "-o", &pattern(&opaque)]));
        ok(&render(&[
            "--frames",
            range,
            "-o",
            &pattern(&clear),
            "--transparent",
        ]));
    }
    let out = |name: &str| dir.join(name).display().to_string();
    let frames = ["--frames", "0..7"];
    // A GIF and an H.264 video from opaque frames, a VP9 video with alpha and a sheet from transparent ones.
    let cases: [(&str, &[&str], &Path); 4] = [
        ("gif", &[], &opaque),
        ("mp4", &[], &opaque),
        ("webm", &["--transparent"], &clear),
        (
            "png",
            &["--transparent", "--sheet", "--columns", "3"],
            &clear,
        ),
    ];
    for (ext, flags, frames_dir) in cases {
        let (one, joined) = (out(&format!("one.{ext}")), out(&format!("joined.{ext}")));
        let mut args = vec!["-o", one.as_str()];
        args.extend(frames);
        args.extend(flags);
        ok(&render(&args));
        let sheet_flags: Vec<&str> = (flags.iter().copied())
            .filter(|f| *f != "--transparent")
            .collect();
        let mut args = vec!["-o", joined.as_str()];
        args.extend(frames);
        args.extend(&sheet_flags);
        ok(&assemble(frames_dir, &args));
        assert!(
            bytes(Path::new(&one)) == bytes(Path::new(&joined)),
            "{ext}: the joined file differs from the one export's"
        );
        if ext == "png" {
            // The same layout, its frames named after each sheet.
            let json =
                |p: &str| String::from_utf8(bytes(&Path::new(p).with_extension("json"))).unwrap();
            let named = (json(&one).replace("\"one_", "\"joined_"))
                .replace("\"one.png\"", "\"joined.png\"");
            assert_eq!(named, json(&joined), "the sheet's layout");
        }
    }
    // Premultiplied frames make a premultiplied sheet, said in its layout.
    let pre = dir.join("premultiplied");
    std::fs::create_dir_all(&pre).unwrap();
    let flags = ["--transparent", "--premultiplied"];
    let mut args = vec!["--frames", "0-6", "-o"];
    let p = pattern(&pre);
    args.push(&p);
    args.extend(flags);
    ok(&render(&args));
    let (one, joined) = (out("pre_one.png"), out("pre_joined.png"));
    ok(&render(&[
        "--frames",
        "0..7",
        "-o",
        &one,
        "--sheet",
        "--transparent",
        "--premultiplied",
    ]));
    ok(&assemble(
        &pre,
        &[
            "--frames",
            "0..7",
            "-o",
            &joined,
            "--sheet",
            "--premultiplied",
        ],
    ));
    assert!(bytes(Path::new(&one)) == bytes(Path::new(&joined)));
    let layout = String::from_utf8(bytes(&Path::new(&joined).with_extension("json"))).unwrap();
    assert!(layout.contains("\"premultipliedAlpha\": true"), "{layout}");

    // What cannot be joined is refused, naming why, and nothing is written.
    let before = names(&dir);
    // Past the rendered frames: the scene has 120; the default asks for all of them.
    let err = refused(&assemble(&clear, &["-o", &out("x.webm")]));
    assert!(
        err.contains("113 of the 120 frames are missing: 7-119"),
        "{err}"
    );
    let cases: [(&[&str], &str); 4] = [
        (&["-o", "GIF"], "a GIF has no partial transparency"),
        (&["-o", "MP4"], "H.264 in MP4 has no alpha"),
        (&["-o", "SEQ"], "assemble writes one file"),
        (&["-o", "SHEET", "--sheet", "--premultiplied"], "straight"),
    ];
    for (args, why) in cases {
        let args: Vec<String> = (args.iter())
            .map(|a| match *a {
                "GIF" => out("x.gif"),
                "MP4" => out("x.mp4"),
                "SEQ" => out("x_####.png"),
                "SHEET" => out("x.png"),
                a => a.to_owned(),
            })
            .collect();
        let mut all: Vec<&str> = vec!["--frames", "0..7"];
        all.extend(args.iter().map(|s| s.as_str()));
        let from = if args.contains(&"--premultiplied".to_owned()) {
            &opaque
        } else {
            &clear
        };
        let err = refused(&assemble(from, &all));
        let why = if why == "straight" {
            "no alpha (RGB)"
        } else {
            why
        };
        assert!(err.contains(why), "{args:?}: {err}");
    }
    std::fs::remove_file(frame(&opaque, 2)).unwrap();
    std::fs::remove_file(frame(&opaque, 3)).unwrap();
    std::fs::remove_file(frame(&opaque, 5)).unwrap();
    let err = refused(&assemble(
        &opaque,
        &["--frames", "0..7", "-o", &out("x.gif")],
    ));
    assert!(
        err.contains("3 of the 7 frames are missing: 2-3, 5"),
        "{err}"
    );
    // A frame of another size (another chunk's flags).
    std::fs::copy(out("one.png"), frame(&clear, 4)).unwrap();
    let err = refused(&assemble(
        &clear,
        &["--frames", "0..7", "-o", &out("x.webm")],
    ));
    assert!(
        err.contains("f_0004.png") && err.contains("one size"),
        "{err}"
    );
    assert_eq!(names(&dir), before, "nothing written");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn slurm_job_scripts_render_their_chunk_and_try_again_only_when_it_can_help() {
    let dir = common::tmpdir("farm", "slurm");
    let jobs = dir.join("jobs");
    let (s, p, gif, j) = (
        scene(),
        pattern(&dir),
        dir.join("sparks.gif").display().to_string(),
        jobs.display().to_string(),
    );
    let mut args = vec![
        "farm",
        "slurm",
        &s,
        "-o",
        &p,
        "--frames",
        "0..5",
        "--chunk-size",
        "2",
        "--assemble",
        &gif,
        "--job-dir",
        &j,
        "--",
    ];
    args.extend(SMALL);
    ok(&run(&args));
    assert_eq!(
        names(&jobs),
        vec!["assemble.sbatch", "logs", "render.sbatch", "submit.sh"]
    );
    let script = String::from_utf8(bytes(&jobs.join("render.sbatch"))).unwrap();
    assert!(script.contains("#SBATCH --array=0-2\n"), "{script}");
    // Array task 2 renders chunk 2: frame 4 alone (0-1, 2-3, 4).
    let task = |k: u32| {
        Command::new("bash")
            .arg(jobs.join("render.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", k.to_string())
            .output()
            .unwrap()
    };
    ok(&task(2));
    assert_eq!(names(&dir), vec!["f_0004.png", "jobs"]);
    ok(&task(0));
    ok(&task(1));
    ok(&Command::new("bash")
        .arg(jobs.join("assemble.sbatch"))
        .output()
        .unwrap());
    assert_eq!(
        names(&dir),
        vec![
            "f_0000.png",
            "f_0001.png",
            "f_0002.png",
            "f_0003.png",
            "f_0004.png",
            "jobs",
            "sparks.gif"
        ]
    );
    let one = dir.join("one.gif").display().to_string();
    ok(&render(&["--frames", "0..5", "-o", &one]));
    assert!(bytes(Path::new(&one)) == bytes(Path::new(&gif)));

    // A chunk that fails with status 1 is tried again, up to --tries; one that fails with 2 (bad input) is not.
    for (status, tries) in [(1, 3), (2, 1)] {
        let log = dir.join(format!("calls-{status}"));
        let fake = dir.join(format!("fails-{status}.sh"));
        std::fs::write(
            &fake,
            format!(
                "#!/bin/sh\necho \"$@\" >> '{}'\nexit {status}\n",
                log.display()
            ),
        )
        .unwrap();
        ok(&Command::new("chmod").arg("+x").arg(&fake).output().unwrap());
        let fake = fake.display().to_string();
        let jobs = dir.join(format!("jobs-{status}")).display().to_string();
        ok(&run(&[
            "farm",
            "slurm",
            &s,
            "-o",
            &p,
            "--frames",
            "0..5",
            "--chunk-size",
            "2",
            "--tries",
            "3",
            "--executable",
            &fake,
            "--job-dir",
            &jobs,
        ]));
        let o = Command::new("bash")
            .arg(Path::new(&jobs).join("render.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", "1")
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(status));
        let calls = String::from_utf8(bytes(&log)).unwrap();
        assert_eq!(calls.lines().count(), tries, "{calls}");
        assert!(
            calls
                .lines()
                .all(|l| l.contains("render") && l.contains("--frames 2-3")),
            "{calls}"
        );
    }

    // Bad requests are refused before any job is written.
    let before = names(&dir);
    let cases: [(&[&str], &str); 5] = [
        (&["--", "--sise", "9x9"], "--sise"),
        (
            &["--", "--frames", "0-3"],
            "the farm sets each chunk's output and frames",
        ),
        (&["--frames", "100-130"], "the scene has 120 frames"),
        (
            &["--assemble", "GIF", "--", "--transparent"],
            "no partial transparency",
        ),
        (&["--output", "NOHASH"], "a run of #"),
    ];
    for (extra, why) in cases {
        let extra: Vec<String> = (extra.iter())
            .map(|a| match *a {
                "GIF" => dir.join("x.gif").display().to_string(),
                "NOHASH" => dir.join("x.png").display().to_string(),
                a => a.to_owned(),
            })
            .collect();
        let j = dir.join("refused").display().to_string();
        let mut args = vec!["farm", "slurm", &s, "--job-dir", &j];
        if !extra.iter().any(|a| a == "--output") {
            args.extend(["-o", &p]);
        }
        args.extend(extra.iter().map(|a| a.as_str()));
        let err = refused(&run(&args));
        assert!(err.contains(why), "{extra:?}: {err}");
    }
    assert_eq!(names(&dir), before, "no job written");
    let _ = std::fs::remove_dir_all(dir);
}
