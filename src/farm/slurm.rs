//! Slurm: the chunks as one job array, the assembly as a job that starts only when every chunk succeeded.
//!
//! `write` puts three files in the job's folder: `render.sbatch` (array task k renders chunk k, and tries again
//! on exit status 1, never on 2: bad input stays bad), `assemble.sbatch`, and `submit.sh`, which submits both with
//! `sbatch` (the second `--dependency=afterok` on the first, `--kill-on-invalid-dep=yes` so that a failed chunk
//! cancels it instead of leaving it pending forever). `submit` does what `submit.sh` does.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{Plan, quote};

/// How the jobs are submitted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// Tries of a chunk that fails with status 1 (a crash, a lost GPU), in its array task, before it gives up.
    pub tries: u32,
    /// At most this many chunks at once (`--array=0-N%M`).
    pub max_parallel: Option<u32>,
    /// More `#SBATCH` options for both jobs (`--partition=gpu`, `--gres=gpu:1`, `--time=1:00:00`...).
    pub sbatch: Vec<String>,
    /// The job names' stem.
    pub name: String,
}

/// The files of a job written into its folder.
#[derive(Clone, Debug, PartialEq)]
pub struct JobFiles {
    pub render: PathBuf,
    pub assemble: Option<PathBuf>,
    pub submit: PathBuf,
    pub logs: PathBuf,
}

/// The job array's script.
pub fn render_script(plan: &Plan, options: &Options, logs: &Path) -> String {
    let last_task = plan.chunk_count().saturating_sub(1);
    let parallel = options
        .max_parallel
        .map_or(String::new(), |m| format!("%{m}"));
    let mut s = String::from("#!/bin/bash\n");
    s += &format!("#SBATCH --job-name={}-render\n", options.name);
    s += &format!("#SBATCH --array=0-{last_task}{parallel}\n");
    s += &format!(
        "#SBATCH --output={}\n",
        logs.join("render-%A_%a.log").display()
    );
    for o in &options.sbatch {
        s += &format!("#SBATCH {o}\n");
    }
    s += &format!(
        "# Frames {}..={} of {} in {} chunks of {} (array task k renders chunk k). Written by energywave farm slurm.\n",
        plan.frames.start,
        plan.frames.end - 1,
        plan.scene.display(),
        plan.chunk_count(),
        plan.chunk,
    );
    s += "set -u\n";
    s += &format!(
        "first=$(( {} + SLURM_ARRAY_TASK_ID * {} ))\n",
        plan.frames.start, plan.chunk
    );
    s += &format!(
        "last=$(( first + {} - 1 )); [ \"$last\" -gt {} ] && last={}\n",
        plan.chunk,
        plan.frames.end - 1,
        plan.frames.end - 1
    );
    s += "# energywave exits 0 when done, 2 on bad input (trying again cannot help), 1 on any other failure.\n";
    s += &format!("for try in $(seq 1 {}); do\n", options.tries.max(1));
    s += &format!("  {}\n", plan.render_command("$first", "$last"));
    s += "  status=$?\n";
    s += "  [ \"$status\" -eq 1 ] || exit \"$status\"\n";
    s += "  echo \"energywave: frames $first-$last failed (try $try)\" >&2\n";
    s += "done\n";
    s += "exit 1\n";
    s
}

/// The assembly job's script, if the frames are joined.
pub fn assemble_script(plan: &Plan, options: &Options, logs: &Path) -> Option<String> {
    let command = plan.assemble_command()?;
    let mut s = String::from("#!/bin/bash\n");
    s += &format!("#SBATCH --job-name={}-assemble\n", options.name);
    s += &format!(
        "#SBATCH --output={}\n",
        logs.join("assemble-%j.log").display()
    );
    for o in &options.sbatch {
        s += &format!("#SBATCH {o}\n");
    }
    s += "# Joins the frames once every chunk of the render array succeeded. Written by energywave farm slurm.\n";
    s += &format!("exec {command}\n");
    Some(s)
}

/// `submit.sh`: both jobs, the assembly after the array.
pub fn submit_script(files: &JobFiles) -> String {
    let mut s = String::from(
        "#!/bin/bash\n# Submits the render array, then the assembly after it.\nset -euo pipefail\n",
    );
    s += &format!(
        "render=$(sbatch --parsable {})\nrender=${{render%%;*}}\necho \"render job: $render\"\n",
        quote(&files.render.to_string_lossy())
    );
    if let Some(assemble) = &files.assemble {
        s += &format!(
            "assemble=$(sbatch --parsable --dependency=afterok:$render --kill-on-invalid-dep=yes {})\n\
             assemble=${{assemble%%;*}}\necho \"assemble job: $assemble\"\n",
            quote(&assemble.to_string_lossy())
        );
    }
    s
}

/// Writes the job's files into `dir` (made if needed), each whole or not at all.
pub fn write(
    dir: &Path,
    plan: &Plan,
    options: &Options,
) -> Result<JobFiles, crate::output::OutputError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| crate::output::OutputError::Io { path, source }
    };
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).map_err(io(&logs))?;
    let files = JobFiles {
        render: dir.join("render.sbatch"),
        assemble: plan.assemble.as_ref().map(|_| dir.join("assemble.sbatch")),
        submit: dir.join("submit.sh"),
        logs: logs.clone(),
    };
    let write = |path: &Path, text: &str| -> Result<(), crate::output::OutputError> {
        crate::output::write_atomically(path, text.as_bytes())?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
                .map_err(io(path))?;
        }
        Ok(())
    };
    write(&files.render, &render_script(plan, options, &logs))?;
    if let (Some(path), Some(text)) = (&files.assemble, assemble_script(plan, options, &logs)) {
        write(path, &text)?;
    }
    write(&files.submit, &submit_script(&files))?;
    Ok(files)
}

/// The jobs `submit` queued.
#[derive(Clone, Debug, PartialEq)]
pub struct Submitted {
    pub render: String,
    pub assemble: Option<String>,
}

/// Why the jobs could not be queued.
#[derive(Debug, thiserror::Error)]
pub enum SubmitError {
    #[error(
        "sbatch does not run ({0}): submit from a machine with Slurm's commands, or run the job's submit.sh there"
    )]
    NoSbatch(std::io::Error),
    #[error("sbatch {script}: {message}")]
    Refused { script: PathBuf, message: String },
}

/// Queues the render array and then the assembly after it, as `submit.sh` does.
pub fn submit(files: &JobFiles) -> Result<Submitted, SubmitError> {
    let render = sbatch(&[], &files.render)?;
    let assemble = match &files.assemble {
        Some(script) => Some(sbatch(
            &[
                format!("--dependency=afterok:{render}"),
                "--kill-on-invalid-dep=yes".into(),
            ],
            script,
        )?),
        None => None,
    };
    Ok(Submitted { render, assemble })
}

/// `sbatch --parsable ARGS SCRIPT`: the job's id.
fn sbatch(args: &[String], script: &Path) -> Result<String, SubmitError> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .arg(script)
        .output()
        .map_err(SubmitError::NoSbatch)?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    // `--parsable` prints "id" or "id;cluster".
    let id = stdout.trim().split(';').next().unwrap_or("").to_owned();
    if !out.status.success() || id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(SubmitError::Refused {
            script: script.to_owned(),
            message: format!(
                "{} {}",
                stdout.trim(),
                String::from_utf8_lossy(&out.stderr).trim()
            )
            .trim()
            .to_owned(),
        });
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_array_renders_each_chunk_and_tries_again_only_on_failure() {
        let plan = Plan {
            executable: "/bin/energywave".into(),
            scene: "/s/beam.toml".into(),
            pattern: "/r/beam_####.png".into(),
            frames: 0..25,
            chunk: 10,
            render_args: vec![],
            assemble: Some("/r/beam.mp4".into()),
        };
        let options = Options {
            tries: 3,
            max_parallel: Some(2),
            sbatch: vec!["--partition=gpu".into()],
            name: "beam".into(),
        };
        let script = render_script(&plan, &options, Path::new("/j/logs"));
        assert!(script.contains("#SBATCH --array=0-2%2\n"), "{script}");
        assert!(script.contains("#SBATCH --partition=gpu\n"));
        assert!(script.contains("first=$(( 0 + SLURM_ARRAY_TASK_ID * 10 ))\n"));
        assert!(script.contains("[ \"$last\" -gt 24 ] && last=24\n"));
        assert!(script.contains("for try in $(seq 1 3); do\n"));
        assert!(script.contains("--frames \"$first-$last\""));
        let assemble = assemble_script(&plan, &options, Path::new("/j/logs")).unwrap();
        assert!(assemble.contains("exec /bin/energywave assemble /s/beam.toml --input '/r/beam_####.png' --frames 0-24 --output /r/beam.mp4\n"), "{assemble}");
    }
}
