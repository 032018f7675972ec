//! Joining frames rendered apart (a render farm's chunks, several machines) into the one file an export of them
//! all makes: a GIF, a sprite sheet with its layout, or a video.
//!
//! The frames are the 8-bit PNGs of a sequence export (`name_####.png`); what a GIF, a sheet or a video holds is
//! those very bytes (`FrameSink::push_rgba8`), so the file joined here is the file a single `render` of the same
//! frames writes, byte for byte. Every frame is checked (there, readable, one size, one alpha) before anything is
//! written, and a missing chunk is named by its frame numbers.

use std::ops::{ControlFlow, Range};
use std::path::{Path, PathBuf};

use super::{ExportError, FrameSink, Target, frame_path, hash_runs};
use crate::output::Alpha;

/// The frames of a sequence to join: `pattern`'s run of `#` numbers them.
#[derive(Clone, Debug)]
pub struct Frames {
    pub pattern: PathBuf,
    pub range: Range<u32>,
    /// The frames' color is premultiplied by their alpha (rendered with `--premultiplied`).
    pub premultiplied: bool,
}

/// What the frames hold, read off the first of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Found {
    pub width: u32,
    pub height: u32,
    pub alpha: Alpha,
}

impl Frames {
    /// Checks the pattern, that every frame is there (naming the missing ones, as ranges a farm manager's chunks
    /// are given in), and reads the first frame's size and alpha.
    pub fn check(&self) -> Result<Found, ExportError> {
        let fail = |why: String| ExportError::Target {
            path: self.pattern.clone(),
            why,
        };
        let name = (self.pattern.file_name()).map_or(String::new(), |n| n.to_string_lossy().into());
        if hash_runs(&name) != 1 {
            return Err(fail(
                "the frames' name needs one run of #, the frame number, as in name_####.png".into(),
            ));
        }
        let ext = (self.pattern.extension().and_then(|e| e.to_str()))
            .unwrap_or("")
            .to_ascii_lowercase();
        if ext != "png" {
            return Err(fail(format!(
                "the frames are joined from 8-bit PNGs (name_####.png); {} frames go to a compositor as they are",
                match ext.as_str() {
                    "" => "these".to_owned(),
                    e => format!(".{e}"),
                }
            )));
        }
        let missing: Vec<u32> = (self.range.clone())
            .filter(|&f| !frame_path(&self.pattern, f).is_file())
            .collect();
        if !missing.is_empty() {
            return Err(ExportError::Missing {
                pattern: self.pattern.clone(),
                count: missing.len() as u32,
                of: self.range.len() as u32,
                frames: ranges(&missing),
            });
        }
        let first = frame_path(&self.pattern, self.range.start);
        let (width, height, has_alpha) = read_header(&first)?;
        let alpha = match (has_alpha, self.premultiplied) {
            (false, false) => Alpha::Opaque,
            (false, true) => {
                return Err(ExportError::Target {
                    path: first,
                    why: "--premultiplied: this frame has no alpha (RGB): it was rendered opaque"
                        .into(),
                });
            }
            (true, false) => Alpha::Straight,
            (true, true) => Alpha::Premultiplied,
        };
        Ok(Found {
            width,
            height,
            alpha,
        })
    }
}

/// Frame numbers as a farm manager writes its ranges: `3, 7-9, 12`.
pub fn ranges(frames: &[u32]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut k = 0;
    while k < frames.len() {
        let mut j = k;
        while j + 1 < frames.len() && frames[j + 1] == frames[j] + 1 {
            j += 1;
        }
        out.push(match j > k {
            true => format!("{}-{}", frames[k], frames[j]),
            false => frames[k].to_string(),
        });
        k = j + 1;
    }
    out.join(", ")
}

/// A PNG's size and whether it has alpha, from its header; anything but 8-bit RGB or RGBA is refused.
fn read_header(path: &Path) -> Result<(u32, u32, bool), ExportError> {
    let fail = |why: String| ExportError::Target {
        path: path.to_owned(),
        why,
    };
    let reader = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| fail(format!("cannot be read: {e}")))?;
    if reader.format() != Some(image::ImageFormat::Png) {
        return Err(fail("is not a PNG".into()));
    }
    let decoder = reader
        .into_decoder()
        .map_err(|e| fail(format!("is not a readable PNG: {e}")))?;
    use image::ImageDecoder;
    let (w, h) = decoder.dimensions();
    match decoder.color_type() {
        image::ColorType::Rgb8 => Ok((w, h, false)),
        image::ColorType::Rgba8 => Ok((w, h, true)),
        other => Err(fail(format!(
            "is {other:?}; energywave's frames are 8-bit RGB (opaque) or RGBA (--transparent)"
        ))),
    }
}

/// One frame's pixels as 8-bit RGBA (alpha 255 where the PNG has none), checked against the first frame.
fn read_frame(path: &Path, found: &Found) -> Result<Vec<u8>, ExportError> {
    let fail = |why: String| ExportError::Target {
        path: path.to_owned(),
        why,
    };
    let (w, h, has_alpha) = read_header(path)?;
    if (w, h) != (found.width, found.height) {
        return Err(fail(format!(
            "is {w}x{h}, the first frame {}x{}: every frame of an export has one size",
            found.width, found.height
        )));
    }
    if has_alpha != (found.alpha != Alpha::Opaque) {
        return Err(fail(format!(
            "is {}, the first frame {}: were the chunks rendered with different flags?",
            if has_alpha { "RGBA" } else { "RGB" },
            if has_alpha { "RGB" } else { "RGBA" },
        )));
    }
    let img = image::open(path).map_err(|e| fail(format!("cannot be decoded: {e}")))?;
    Ok(img.to_rgba8().into_raw())
}

/// Joins `frames` into `target` (a GIF, a sheet or a video) at `frame_rate`; `on_frame(done, frame)` after each.
/// Returns the files written; on a failure nothing is written and what was there stays whole.
pub fn assemble(
    frames: &Frames,
    target: &Target,
    frame_rate: f64,
    mut on_frame: impl FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<Vec<PathBuf>, ExportError> {
    let found = frames.check()?;
    let fail = |path: &Path, why: &str| ExportError::Target {
        path: path.to_owned(),
        why: why.to_owned(),
    };
    match target {
        Target::Single { path, .. } | Target::Sequence { pattern: path, .. } => {
            return Err(fail(
                path,
                "assemble writes one file of every frame: a .gif, an .mp4 or .webm video, or a sprite sheet \
                 (.png with --sheet)",
            ));
        }
        Target::Gif { path } if found.alpha != Alpha::Opaque => {
            return Err(fail(
                path,
                "the frames are transparent, and a GIF has no partial transparency: join them into a --sheet or \
                 a .webm",
            ));
        }
        Target::Video { path, container } => {
            if found.alpha != Alpha::Opaque && *container == super::video::Container::Mp4 {
                return Err(fail(
                    path,
                    "the frames are transparent, and H.264 in MP4 has no alpha: join them into a .webm (VP9 with \
                     alpha)",
                ));
            }
            if found.alpha == Alpha::Premultiplied {
                return Err(fail(
                    path,
                    "a video's alpha is straight: render the frames without --premultiplied",
                ));
            }
        }
        _ => {}
    }
    let (w, h) = (found.width, found.height);
    let range = frames.range.clone();
    let mut sink = FrameSink::new(target, w, h, range.clone(), frame_rate, found.alpha)?;
    for (done, frame) in range.enumerate() {
        let pushed = read_frame(&frame_path(&frames.pattern, frame), &found)
            .and_then(|rgba| sink.push_rgba8(frame, &rgba));
        if let Err(e) = pushed {
            sink.abandon();
            return Err(e);
        }
        if on_frame(done as u32 + 1, frame).is_break() {
            sink.abandon();
            return Err(ExportError::Cancelled);
        }
    }
    sink.finish()
}

#[cfg(test)]
mod tests {
    use super::ranges;

    #[test]
    fn missing_frames_read_as_ranges() {
        assert_eq!(ranges(&[3, 7, 8, 9, 12]), "3, 7-9, 12");
        assert_eq!(ranges(&[0]), "0");
        assert_eq!(ranges(&[4, 5]), "4-5");
        assert_eq!(ranges(&[]), "");
    }
}
