//! Rendering a sequence on a render farm the studio already runs: the sequence split into chunks of frames,
//! each chunk an `energywave render --frames A-B` that any machine may run, in any order, as often as the
//! scheduler likes (frame N comes out the same from every chunk, each file written whole or not at all), then one
//! `energywave assemble` that joins the frames into a GIF, a sheet or a video once every chunk is done.
//!
//! `slurm` writes (and submits) the job scripts for Slurm: a job array of the chunks and an assembly job that
//! depends on it. Open Job Description's template and the recipes for other managers are in `docs/farm/`.

pub mod slurm;

use std::ops::Range;
use std::path::{Path, PathBuf};

/// A sequence to render in chunks, and what to join its frames into.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The `energywave` executable the machines run.
    pub executable: PathBuf,
    /// The scene file, as the machines see it (absolute).
    pub scene: PathBuf,
    /// The frames' names, a run of # for the number (absolute).
    pub pattern: PathBuf,
    /// The frames rendered.
    pub frames: Range<u32>,
    /// Frames per chunk.
    pub chunk: u32,
    /// More flags for every chunk's `render` (size, transparency, integrator...).
    pub render_args: Vec<String>,
    /// Where the frames are joined, if anywhere: a .gif, a video, or a sheet (.png).
    pub assemble: Option<PathBuf>,
}

impl Plan {
    /// How many chunks the frames make.
    pub fn chunk_count(&self) -> u32 {
        (self.frames.len() as u32).div_ceil(self.chunk.max(1))
    }

    /// The frames of chunk `k` (0-based).
    pub fn chunk_frames(&self, k: u32) -> Range<u32> {
        let start = self.frames.start + k * self.chunk;
        start..(start + self.chunk).min(self.frames.end)
    }

    /// The command line that renders frames `first` to `last` (both included; shell words such as `"$first"`
    /// in a script), every word but those two quoted for a POSIX shell.
    pub fn render_command(&self, first: &str, last: &str) -> String {
        let mut words = vec![
            quote(&self.executable.to_string_lossy()),
            "render".into(),
            quote(&self.scene.to_string_lossy()),
            "--frames".into(),
            format!("\"{first}-{last}\""),
            "--output".into(),
            quote(&self.pattern.to_string_lossy()),
        ];
        words.extend(self.render_args.iter().map(|a| quote(a)));
        words.join(" ")
    }

    /// The command line that joins the frames, if they are joined.
    pub fn assemble_command(&self) -> Option<String> {
        let out = self.assemble.as_ref()?;
        let mut words = vec![
            quote(&self.executable.to_string_lossy()),
            "assemble".into(),
            quote(&self.scene.to_string_lossy()),
            "--input".into(),
            quote(&self.pattern.to_string_lossy()),
            "--frames".into(),
            format!("{}-{}", self.frames.start, self.frames.end - 1),
            "--output".into(),
            quote(&out.to_string_lossy()),
        ];
        if is_sheet(out) {
            words.push("--sheet".into());
        }
        if self.render_args.iter().any(|a| a == "--premultiplied") {
            words.push("--premultiplied".into());
        }
        Some(words.join(" "))
    }
}

/// A joined output named `.png` is a sprite sheet.
pub fn is_sheet(path: &Path) -> bool {
    (path.extension().and_then(|e| e.to_str())).is_some_and(|e| e.eq_ignore_ascii_case("png"))
}

/// `word` quoted for a POSIX shell: as it is when it holds only characters no shell reads specially, else in
/// single quotes (a single quote inside written `'\''`).
pub fn quote(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        return word.to_owned();
    }
    format!("'{}'", word.replace('\'', r"'\''"))
}

/// `path` made absolute against the current directory (without resolving links), as a machine of the farm,
/// started elsewhere, needs it.
pub fn absolute(path: &Path) -> std::io::Result<PathBuf> {
    std::path::absolute(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Plan {
        Plan {
            executable: "/opt/energywave/bin/energywave".into(),
            scene: "/shows/a b/beam's.toml".into(),
            pattern: "/renders/beam_####.png".into(),
            frames: 3..26,
            chunk: 10,
            render_args: vec!["--size".into(), "1920x1080".into(), "--transparent".into()],
            assemble: Some("/renders/beam.png".into()),
        }
    }

    #[test]
    fn chunks_cover_the_frames_once() {
        let p = plan();
        assert_eq!(p.chunk_count(), 3);
        let chunks: Vec<_> = (0..p.chunk_count()).map(|k| p.chunk_frames(k)).collect();
        assert_eq!(chunks, vec![3..13, 13..23, 23..26]);
        let one = Plan {
            chunk: 100,
            ..plan()
        };
        assert_eq!(one.chunk_count(), 1);
        assert_eq!(one.chunk_frames(0), 3..26);
    }

    #[test]
    fn words_are_quoted_for_the_shell() {
        assert_eq!(quote("--size"), "--size");
        assert_eq!(quote("/a/b_####.png"), "'/a/b_####.png'");
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), r"'it'\''s'");
        assert_eq!(quote(""), "''");
        assert_eq!(quote("$HOME"), "'$HOME'");
        let p = plan();
        assert_eq!(
            p.render_command("$first", "$last"),
            "/opt/energywave/bin/energywave render '/shows/a b/beam'\\''s.toml' --frames \"$first-$last\" \
             --output '/renders/beam_####.png' --size 1920x1080 --transparent"
        );
        assert_eq!(
            p.assemble_command().unwrap(),
            "/opt/energywave/bin/energywave assemble '/shows/a b/beam'\\''s.toml' --input \
             '/renders/beam_####.png' --frames 3-25 --output /renders/beam.png --sheet"
        );
    }
}
