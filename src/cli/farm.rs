//! The `farm` commands: a sequence's chunks and its assembly as jobs of a render farm's scheduler.

use std::path::{Path, PathBuf};

use clap::Parser;

use super::{Cli, CliError, SlurmArgs};
use crate::export::{self, Target};
use crate::farm::{self, Plan, slurm};
use crate::output::Format;
use crate::scene::Scene;

/// Everything checked before a job is written: the scene, the frames, the output, the assembly and the render
/// flags (parsed as `render` parses them), so that no chunk of a farm fails on a typo an hour later.
fn plan(args: &SlurmArgs) -> Result<Plan, CliError> {
    let scene = Scene::load(&args.scene)?;
    let pattern_target = Target::for_output(&args.output, None)?;
    let Target::Sequence { format, .. } = pattern_target else {
        return Err(CliError::Usage(format!(
            "{}: a farm renders a sequence, one file a frame: name it with a run of # for the frame number \
             (name_####.png or name_####.exr)",
            args.output.display()
        )));
    };
    let frames = match &args.frames {
        Some(spec) => spec.resolve(scene.frame_count())?,
        None => 0..scene.frame_count(),
    };
    for word in &args.render_args {
        let flag = word.split('=').next().unwrap_or("");
        if ["-o", "--output", "--frames", "--sheet"].contains(&flag) {
            return Err(CliError::Usage(format!(
                "-- {word}: the farm sets each chunk's output and frames; give them to `farm slurm` itself \
                 (--output, --frames, --assemble)"
            )));
        }
    }
    let abs = |p: &Path| {
        farm::absolute(p)
            .map_err(|e| CliError::Usage(format!("{}: cannot be made absolute: {e}", p.display())))
    };
    let (scene_path, pattern) = (abs(&args.scene)?, abs(&args.output)?);
    // The chunks' command line, parsed as `render` will parse it.
    let mut line: Vec<String> = vec!["energywave".into(), "render".into()];
    line.push(scene_path.to_string_lossy().into());
    line.extend(["--frames".into(), format!("{}", frames.start)]);
    line.extend(["--output".into(), pattern.to_string_lossy().into()]);
    line.extend(args.render_args.iter().cloned());
    let parsed = Cli::try_parse_from(&line).map_err(|e| {
        CliError::Usage(format!(
            "the render flags after --: {}",
            e.to_string()
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
        ))
    })?;
    let Some(super::Command::Render(render)) = parsed.command else {
        unreachable!("parsed as the render command");
    };
    let assemble = match &args.assemble {
        Some(out) => {
            let sheet = farm::is_sheet(out);
            let target = Target::for_output(out, sheet.then(export::SheetOptions::default))?;
            if format != Format::Png {
                return Err(CliError::Usage(format!(
                    "--assemble {}: frames are joined from a PNG sequence; {} is EXR (for a compositor, as it is)",
                    out.display(),
                    args.output.display()
                )));
            }
            if render.transparent && matches!(target, Target::Gif { .. }) {
                return Err(CliError::Usage(format!(
                    "--assemble {}: the frames are transparent (--transparent), and a GIF has no partial \
                     transparency: assemble a sheet (.png) or a .webm",
                    out.display()
                )));
            }
            if let Target::Video { container, .. } = &target {
                if render.transparent && *container == export::video::Container::Mp4 {
                    return Err(CliError::Usage(format!(
                        "--assemble {}: the frames are transparent, and H.264 in MP4 has no alpha: assemble a \
                         .webm",
                        out.display()
                    )));
                }
                if render.premultiplied {
                    return Err(CliError::Usage(format!(
                        "--assemble {}: a video's alpha is straight: render without --premultiplied",
                        out.display()
                    )));
                }
            }
            Some(abs(out)?)
        }
        None => None,
    };
    let executable = match &args.executable {
        Some(p) => abs(p)?,
        None => std::env::current_exe()
            .map_err(|e| CliError::Unavailable(format!("this executable's path: {e}")))?,
    };
    Ok(Plan {
        executable,
        scene: scene_path,
        pattern,
        frames,
        chunk: args.chunk_size,
        render_args: args.render_args.clone(),
        assemble,
    })
}

/// The scene file's name without its extension: the jobs' name.
fn stem(path: &Path) -> String {
    let s = (path.file_stem()).map_or("energywave".into(), |s| s.to_string_lossy().into_owned());
    let clean: String = (s.chars())
        .map(
            |c| match c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                true => c,
                false => '_',
            },
        )
        .collect();
    clean
}

pub(super) fn slurm(args: &SlurmArgs) -> Result<(), CliError> {
    let plan = plan(args)?;
    let name = stem(&args.scene);
    let dir: PathBuf = match &args.job_dir {
        // Absolute, as the scripts name their logs and each other from wherever they run.
        Some(d) => farm::absolute(d)
            .map_err(|e| CliError::Usage(format!("--job-dir {}: {e}", d.display())))?,
        None => crate::output::parent_dir(&plan.pattern).join(format!("{name}.slurm")),
    };
    let options = slurm::Options {
        tries: args.tries,
        max_parallel: args.max_parallel,
        sbatch: args.sbatch.clone(),
        name,
    };
    let files = slurm::write(&dir, &plan, &options)?;
    eprintln!(
        "frames {}..={} in {} chunks of {}: {}{}",
        plan.frames.start,
        plan.frames.end - 1,
        plan.chunk_count(),
        plan.chunk,
        files.render.display(),
        files
            .assemble
            .as_ref()
            .map_or(String::new(), |a| format!(", then {}", a.display())),
    );
    if !args.submit {
        eprintln!("queue them with {}", files.submit.display());
        return Ok(());
    }
    let queued = slurm::submit(&files).map_err(|e| CliError::Unavailable(e.to_string()))?;
    println!("render job: {}", queued.render);
    if let Some(a) = &queued.assemble {
        println!("assemble job: {a}");
    }
    Ok(())
}
