//! `farm slurm --submit` on a real Slurm cluster (`.ci/slurm-up` starts one on this machine): the chunks run as a
//! job array, the assembly after them, and every frame and the joined GIF are those of one local export; a chunk
//! failing on bad input fails its array task with status 2 and cancels the assembly instead of leaving it pending.
//! Needs `--features slurm` (`./test.sh` turns it on);
//! without it the test is listed as ignored, with what it needs.
mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use common::{SMALL_FRAMES as SMALL, sparks as scene};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_energywave"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs")
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The job id after `what job: ` in `farm slurm --submit`'s output.
fn job(stdout: &str, what: &str) -> String {
    let line = (stdout.lines())
        .find_map(|l| l.strip_prefix(&format!("{what} job: ")))
        .unwrap_or_else(|| panic!("no {what} job in {stdout:?}"));
    line.trim().to_owned()
}

/// Waits until none of `jobs` is queued or running (ten minutes at most).
fn wait(jobs: &[&str]) {
    let start = Instant::now();
    loop {
        let o = Command::new("squeue")
            .args(["-h", "-j", &jobs.join(",")])
            .output()
            .expect("squeue runs (Debian: slurm-client; .ci/slurm-up)");
        if String::from_utf8_lossy(&o.stdout).trim().is_empty() {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "jobs {jobs:?} still queued after 10 minutes"
        );
        std::thread::sleep(Duration::from_millis(300));
    }
}

/// `scontrol show job -o ID`: one line per job (per array task), with JobState= and ExitCode=.
fn states(id: &str) -> Vec<String> {
    let o = Command::new("scontrol")
        .args(["show", "job", "-o", id])
        .output()
        .expect("scontrol runs");
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| {
            let field = |k: &str| {
                (l.split_whitespace())
                    .find_map(|w| w.strip_prefix(k))
                    .unwrap_or("?")
                    .to_owned()
            };
            format!("{} {}", field("JobState="), field("ExitCode="))
        })
        .collect()
}

#[test]
#[cfg_attr(
    not(feature = "slurm"),
    ignore = "needs a one-node Slurm cluster (.ci/slurm-up) and --features slurm: ./test.sh runs it"
)]
fn a_job_array_renders_the_chunks_and_a_dependent_job_joins_them() {
    let dir = common::tmpdir("slurm", "sparks");
    let (s, pattern, gif) = (
        scene(),
        dir.join("f_####.png").display().to_string(),
        dir.join("sparks.gif").display().to_string(),
    );
    let jobs = dir.join("jobs").display().to_string();
    let mut args = vec![
        "farm",
        "slurm",
        &s,
        "-o",
        &pattern,
        "--frames",
        "0..8",
        "--chunk-size",
        "3",
        "--assemble",
        &gif,
        "--job-dir",
        &jobs,
        "--submit",
        "--",
    ];
    args.extend(SMALL);
    let out = ok(&run(&args));
    let (render, assemble) = (job(&out, "render"), job(&out, "assemble"));
    wait(&[&render, &assemble]);
    let logs = || {
        let mut text = String::new();
        for e in std::fs::read_dir(Path::new(&jobs).join("logs"))
            .unwrap()
            .flatten()
        {
            text += &format!(
                "== {}\n{}",
                e.path().display(),
                std::fs::read_to_string(e.path()).unwrap_or_default()
            );
        }
        text
    };
    let tasks = states(&render);
    assert_eq!(tasks.len(), 3, "three chunks: {tasks:?}\n{}", logs());
    assert!(
        tasks.iter().all(|t| t == "COMPLETED 0:0"),
        "{tasks:?}\n{}",
        logs()
    );
    assert_eq!(states(&assemble), vec!["COMPLETED 0:0"], "{}", logs());
    // What the farm made is what one machine makes.
    let local = common::tmpdir("slurm", "local");
    let local_pattern = local.join("f_####.png").display().to_string();
    let local_gif = local.join("sparks.gif").display().to_string();
    for out in [&local_pattern, &local_gif] {
        let mut args = vec!["render", &s, "--frames", "0..8", "-o", out];
        args.extend(SMALL);
        ok(&run(&args));
    }
    for n in 0..8 {
        let name = format!("f_{n:04}.png");
        let (farm, here) = (
            std::fs::read(dir.join(&name)).unwrap(),
            std::fs::read(local.join(&name)).unwrap(),
        );
        assert!(
            farm == here,
            "frame {n}: the farm's differs from the local render"
        );
    }
    assert!(
        std::fs::read(&gif).unwrap() == std::fs::read(&local_gif).unwrap(),
        "the GIF"
    );

    // Chunks failing on bad input (status 2): every array task FAILED with 2, and the assembly cancelled, not left
    // pending for ever.
    let fake = dir.join("bad-input.sh");
    std::fs::write(
        &fake,
        "#!/bin/sh\necho \"energywave: bad input\" >&2\nexit 2\n",
    )
    .unwrap();
    assert!(
        Command::new("chmod")
            .arg("+x")
            .arg(&fake)
            .status()
            .unwrap()
            .success()
    );
    let jobs = dir.join("failing").display().to_string();
    let fake = fake.display().to_string();
    let out = ok(&run(&[
        "farm",
        "slurm",
        &s,
        "-o",
        &pattern,
        "--frames",
        "0..4",
        "--chunk-size",
        "2",
        "--assemble",
        &gif,
        "--job-dir",
        &jobs,
        "--executable",
        &fake,
        "--submit",
    ]));
    let (render, assemble) = (job(&out, "render"), job(&out, "assemble"));
    wait(&[&render, &assemble]);
    let tasks = states(&render);
    assert_eq!(tasks, vec!["FAILED 2:0", "FAILED 2:0"]);
    let cancelled = states(&assemble);
    assert_eq!(cancelled.len(), 1);
    assert!(cancelled[0].starts_with("CANCELLED"), "{cancelled:?}");
    let _ = std::fs::remove_dir_all(dir);
    let _ = std::fs::remove_dir_all(local);
}
