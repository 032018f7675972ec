//! Video: the frames piped as raw RGBA into the `ffmpeg` executable, which encodes H.264 in MP4 or VP9 in WebM
//! (with alpha there, for `--transparent`). The file is encoded beside its destination and renamed there when
//! ffmpeg has finished, so that a failed or stopped export leaves nothing half-written.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

use super::ExportError;

/// The containers written, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// H.264 (yuv420p) in MP4: what every player and editor reads; no alpha.
    Mp4,
    /// VP9 in WebM: browsers and engines; with alpha (yuva420p) when transparent.
    Webm,
}

impl Container {
    /// The container of `path`'s extension, if it is a video one.
    pub fn of(path: &Path) -> Option<Container> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("mp4") => Some(Container::Mp4),
            Some("webm") => Some(Container::Webm),
            _ => None,
        }
    }

    fn format(self) -> &'static str {
        match self {
            Container::Mp4 => "mp4",
            Container::Webm => "webm",
        }
    }
}

/// The ffmpeg executable: `ENERGYWAVE_FFMPEG` if set, else `ffmpeg` on PATH.
fn executable() -> PathBuf {
    std::env::var_os("ENERGYWAVE_FFMPEG").map_or("ffmpeg".into(), PathBuf::from)
}

/// Checks that ffmpeg runs, before anything is rendered; says how to install it where it does not.
pub fn check_ffmpeg(path: &Path) -> Result<(), ExportError> {
    let ran = Command::new(executable())
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    match ran {
        Ok(s) if s.success() => Ok(()),
        _ => Err(ExportError::Target {
            path: path.to_owned(),
            why: format!(
                "writing video needs the ffmpeg executable, and {} does not run: install it (Debian and \
                 Ubuntu: apt-get install ffmpeg; macOS: brew install ffmpeg; Windows: winget install ffmpeg), \
                 or set ENERGYWAVE_FFMPEG to its path; or export a PNG sequence (name_####.png)",
                executable().display()
            ),
        }),
    }
}

/// An encoding under way.
pub struct VideoWriter {
    path: PathBuf,
    partial: PathBuf,
    child: Child,
    stdin: Option<ChildStdin>,
    alpha: bool,
}

impl VideoWriter {
    /// Starts ffmpeg on frames of `width` x `height` at `frame_rate`, into a file beside `path`.
    pub fn start(
        path: &Path,
        container: Container,
        width: u32,
        height: u32,
        frame_rate: f64,
        alpha: bool,
    ) -> Result<Self, ExportError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let partial = path.with_file_name(format!(".{name}.{}.partial", std::process::id()));
        let mut command = Command::new(executable());
        command.args(["-hide_banner", "-loglevel", "error", "-y"]);
        command.args(["-f", "rawvideo", "-pix_fmt", "rgba"]);
        command.args(["-s", &format!("{width}x{height}")]);
        command.args(["-r", &format!("{frame_rate}")]);
        command.args(["-i", "-"]);
        // 4:2:0 wants even sides: odd ones get a column or row of padding.
        command.args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"]);
        match container {
            Container::Mp4 => command.args([
                "-c:v",
                "libx264",
                "-pix_fmt",
                "yuv420p",
                "-crf",
                "16",
                "-movflags",
                "+faststart",
            ]),
            Container::Webm => command.args([
                "-c:v",
                "libvpx-vp9",
                "-pix_fmt",
                if alpha { "yuva420p" } else { "yuv420p" },
                "-crf",
                "24",
                "-b:v",
                "0",
            ]),
        };
        // No random identifiers (WebM's segment UID) nor version strings: the same frames make the same file,
        // whether one export or `assemble` of a farm's chunks wrote it.
        command.args(["-fflags", "+bitexact"]);
        command.args(["-f", container.format()]).arg(&partial);
        let mut child = command
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| ExportError::Target {
                path: path.to_owned(),
                why: format!("ffmpeg did not start: {e}"),
            })?;
        let stdin = child.stdin.take();
        Ok(Self {
            path: path.to_owned(),
            partial,
            child,
            stdin,
            alpha,
        })
    }

    /// Sends one frame: RGBA display values, premultiplied where transparent (as the transparent export makes
    /// them), rows from the top.
    pub fn push(&mut self, pixels: &[[f64; 4]]) -> Result<(), ExportError> {
        // Video alpha is straight.
        let alpha = match self.alpha {
            true => crate::output::Alpha::Straight,
            false => crate::output::Alpha::Opaque,
        };
        self.push_rgba8(&crate::output::encode_rgba8(pixels, alpha))
    }

    /// Sends one frame as 8-bit RGBA, straight alpha (255 where opaque), rows from the top: what a PNG frame
    /// of the same export holds.
    pub fn push_rgba8(&mut self, rgba: &[u8]) -> Result<(), ExportError> {
        let stdin = self.stdin.as_mut().expect("open until finish");
        if stdin.write_all(rgba).is_err() {
            // ffmpeg stopped: its message says why.
            return Err(self.failure());
        }
        Ok(())
    }

    /// Ends the stream, waits for ffmpeg and moves the file into place.
    pub fn finish(mut self) -> Result<PathBuf, ExportError> {
        drop(self.stdin.take());
        let failed = match self.child.wait() {
            Ok(s) => !s.success(),
            Err(_) => true,
        };
        if failed {
            return Err(self.failure());
        }
        std::fs::rename(&self.partial, &self.path).map_err(|e| {
            let _ = std::fs::remove_file(&self.partial);
            ExportError::Target {
                path: self.path.clone(),
                why: format!("the encoded video could not be moved into place: {e}"),
            }
        })?;
        Ok(self.path.clone())
    }

    /// Stops ffmpeg and removes what it wrote.
    pub fn abandon(mut self) {
        drop(self.stdin.take());
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.partial);
    }

    /// ffmpeg's complaint, once it has stopped; the partial file removed.
    fn failure(&mut self) -> ExportError {
        drop(self.stdin.take());
        let _ = self.child.kill();
        let mut message = String::new();
        if let Some(mut err) = self.child.stderr.take() {
            let _ = std::io::Read::read_to_string(&mut err, &mut message);
        }
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.partial);
        ExportError::Target {
            path: self.path.clone(),
            why: format!("ffmpeg failed: {}", message.trim()),
        }
    }
}
