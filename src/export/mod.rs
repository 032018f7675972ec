//! Exporting an animation: which frames (`--frames A..B`), where they go (a numbered PNG or EXR sequence, an
//! animated GIF, or a sprite sheet with its layout beside it), and the progress bar.
//!
//! Everything a user can get wrong (the range, the pattern, the extension, the directory) is checked by
//! [`Target::for_output`] and [`FrameSpec::resolve`] before any rendering. Every file is written atomically;
//! a sequence's frames go into a folder beside their destination and move into place only when the last is
//! written (`staged`), and a GIF, a sheet and a video are written once, at the end: an export that is
//! cancelled, fails or is interrupted leaves the destination as it found it (an earlier export of the same
//! names whole).

pub mod assemble;
pub mod fit;
pub mod progress;
pub mod sheet;
pub(crate) mod staged;
pub mod video;

use std::ops::{ControlFlow, Range};
use std::path::{Path, PathBuf};

use crate::output::{self, Alpha, Format, OutputError};
use crate::scene::Scene;

pub use progress::Progress;
pub use sheet::{SheetLayout, SheetOptions, sheet_grid};

/// Widest sprite sheet, in pixels per side (what game engines and image tools load without trouble).
pub const MAX_SHEET_SIDE: u64 = 16384;

/// Why an export cannot go ahead.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("--frames {spec:?}: {why}")]
    Frames { spec: String, why: String },
    #[error("{}: {why}", path.display())]
    Target { path: PathBuf, why: String },
    #[error("{0}")]
    Output(#[from] OutputError),
    /// Frames to join are not there: a chunk did not render (or not yet).
    #[error(
        "{}: {count} of the {of} frames are missing: {frames}; render them (energywave render --frames A-B, \
         for each range) and assemble again",
        pattern.display()
    )]
    Missing {
        pattern: PathBuf,
        count: u32,
        of: u32,
        frames: String,
    },
    /// Stopped before the last frame; nothing it wrote is left, and nothing that was there is changed.
    #[error("cancelled: nothing written")]
    Cancelled,
}

impl ExportError {
    /// True when the request is at fault (exit status 2).
    pub fn is_input_error(&self) -> bool {
        match self {
            // A missing chunk: assembling again does not help until it is rendered.
            ExportError::Frames { .. }
            | ExportError::Target { .. }
            | ExportError::Missing { .. } => true,
            ExportError::Output(e) => e.is_input_error(),
            ExportError::Cancelled => false,
        }
    }
}

/// The frames asked for on the command line, before the scene's length is known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameSpec {
    text: String,
    start: Option<u32>,
    /// Exclusive.
    end: Option<u32>,
}

impl FrameSpec {
    /// Parses `A..B` (frames A to B - 1, so that `0..50` and `50..100` split an export in two), `A..=B`
    /// (A to B), `A..` (A to the end), `..B`, `..`, a single frame `A`, or `A-B` (A to B: the range
    /// expression of render farm managers' chunks: Open Job Description's, Flamenco's, Afanasy's).
    pub fn parse(s: &str) -> Result<FrameSpec, String> {
        let err = || {
            if s.contains(',') {
                return format!(
                    "{s:?} is a list of frames: give one contiguous range (A..B, A..=B or A-B); a farm \
                     manager's chunks must be contiguous (Open Job Description: rangeConstraint: CONTIGUOUS)"
                );
            }
            format!(
                "{s:?} is not a frame range: use A..B (frames A to B-1), A..=B or A-B (A to B), A.., ..B or \
                 one frame number A"
            )
        };
        let num = |t: &str| -> Result<Option<u32>, String> {
            let t = t.trim();
            if t.is_empty() {
                Ok(None)
            } else {
                t.parse::<u32>().map(Some).map_err(|_| err())
            }
        };
        let (start, end) = if let Some((a, b)) = s.split_once("..=") {
            let b = num(b)?.ok_or_else(err)?;
            (num(a)?, Some(b.checked_add(1).ok_or_else(err)?))
        } else if let Some((a, b)) = s.split_once("..") {
            (num(a)?, num(b)?)
        } else if let Some((a, b)) = s.split_once('-') {
            // Both ends given: "-3" and "3-" are no ranges (a frame number is never negative).
            let (a, b) = (num(a)?.ok_or_else(err)?, num(b)?.ok_or_else(err)?);
            (Some(a), Some(b.checked_add(1).ok_or_else(err)?))
        } else {
            let a = num(s)?.ok_or_else(err)?;
            (Some(a), Some(a.checked_add(1).ok_or_else(err)?))
        };
        Ok(FrameSpec {
            text: s.to_owned(),
            start,
            end,
        })
    }

    /// The frames of an animation of `count` frames this asks for; an empty range or one beyond the end is
    /// an error.
    pub fn resolve(&self, count: u32) -> Result<Range<u32>, ExportError> {
        let start = self.start.unwrap_or(0);
        let end = self.end.unwrap_or(count);
        let fail = |why: String| ExportError::Frames {
            spec: self.text.clone(),
            why,
        };
        let scene_has = if count == 1 {
            "the scene has 1 frame, frame 0 (it has no [animation])".to_owned()
        } else {
            format!("the scene has {count} frames, 0 to {}", count - 1)
        };
        if start >= end {
            return Err(fail(format!("frames {start}..{end} is empty; {scene_has}")));
        }
        if end > count {
            return Err(fail(format!("goes to frame {}, but {scene_has}", end - 1)));
        }
        Ok(start..end)
    }
}

/// The frames to render: those of `spec`, else all of them for a multi-frame target, else frame 0.
pub fn frames_to_render(
    spec: Option<&FrameSpec>,
    target: &Target,
    count: u32,
) -> Result<Range<u32>, ExportError> {
    match spec {
        Some(s) => s.resolve(count),
        None if matches!(target, Target::Single { .. }) => Ok(0..1),
        None => Ok(0..count.max(1)),
    }
}

/// Where rendered frames go.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// One image (a single frame).
    Single { path: PathBuf, format: Format },
    /// One file per frame: `pattern`'s run of `#` replaced by the zero-padded frame number.
    Sequence { pattern: PathBuf, format: Format },
    /// An animated GIF, looping.
    Gif { path: PathBuf },
    /// A flipbook grid PNG, with its layout as JSON beside it.
    Sheet {
        path: PathBuf,
        options: SheetOptions,
    },
    /// A video through the ffmpeg executable: MP4 (H.264) or WebM (VP9).
    Video {
        path: PathBuf,
        container: video::Container,
    },
}

impl Target {
    /// Works out the target from the output path and `--sheet` (its layout's options), checking it
    /// (extension, directory, pattern) before anything is rendered.
    pub fn for_output(path: &Path, sheet: Option<SheetOptions>) -> Result<Target, ExportError> {
        let fail = |why: &str| ExportError::Target {
            path: path.to_owned(),
            why: why.to_owned(),
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let hashes = hash_runs(&name);
        if hashes > 1 {
            return Err(fail(
                "the file name has more than one run of #; use one, as in name_####.png",
            ));
        }
        // An animation in one file (a GIF, a video): no sheet, no run of #.
        let one_file = |what: &str| {
            if sheet.is_some() {
                return Err(fail("a sprite sheet is a .png"));
            }
            if hashes > 0 {
                return Err(fail(&format!(
                    "{what} holds every frame in one file: remove the # from its name"
                )));
            }
            Ok(output::check_directory(path)?)
        };
        if ext == "gif" {
            one_file("a GIF")?;
            return Ok(Target::Gif {
                path: path.to_owned(),
            });
        }
        if let Some(container) = video::Container::of(path) {
            one_file("a video")?;
            video::check_ffmpeg(path)?;
            return Ok(Target::Video {
                path: path.to_owned(),
                container,
            });
        }
        let format = output::check_destination(path)?;
        if let Some(options) = sheet {
            if format != Format::Png || hashes > 0 {
                return Err(fail(
                    "a sprite sheet is one .png file (its layout goes beside it as .json)",
                ));
            }
            if options.columns == Some(0) {
                return Err(fail("--columns must be at least 1"));
            }
            let layout = sheet::layout_path(path);
            if layout.is_dir() {
                return Err(ExportError::Target {
                    path: layout,
                    why: "is a directory; the sheet's layout is written there".into(),
                });
            }
            return Ok(Target::Sheet {
                path: path.to_owned(),
                options,
            });
        }
        Ok(if hashes == 1 {
            Target::Sequence {
                pattern: path.to_owned(),
                format,
            }
        } else {
            Target::Single {
                path: path.to_owned(),
                format,
            }
        })
    }

    /// True for the targets that hold several frames.
    /// Whether the frames go to EXR files (which keep values above 1).
    pub fn is_exr(&self) -> bool {
        matches!(
            self,
            Target::Single {
                format: Format::Exr,
                ..
            } | Target::Sequence {
                format: Format::Exr,
                ..
            }
        )
    }

    pub fn is_multi_frame(&self) -> bool {
        !matches!(self, Target::Single { .. })
    }
}

/// How many separate runs of `#` the text has.
fn hash_runs(name: &str) -> usize {
    name.split(|c| c != '#').filter(|s| !s.is_empty()).count()
}

/// The file of `frame` in a sequence: the run of `#` in the pattern's file name replaced by the frame
/// number, zero-padded to the run's length (wider numbers are written in full).
pub fn frame_path(pattern: &Path, frame: u32) -> PathBuf {
    let name = pattern
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (Some(first), Some(last)) = (name.find('#'), name.rfind('#')) else {
        return pattern.to_owned();
    };
    let width = last - first + 1;
    let numbered = format!("{}{frame:0width$}{}", &name[..first], &name[last + 1..]);
    pattern.with_file_name(numbered)
}

/// The delay of GIF frame `k` in hundredths of a second (the format's unit) at `frame_rate`: the frames' ends
/// rounded to the nearest hundredth, so that the delays average the frame rate's (30 frames a second alternate 3
/// and 4 hundredths, 100 in 30 frames) instead of each rounding alike (3 each: 33 frames a second). At least 1.
pub fn gif_delay(k: u32, frame_rate: f64) -> u32 {
    let end = |k: u32| (k as f64 * 100.0 / frame_rate).round() as i64;
    (end(k + 1) - end(k)).max(1) as u32
}

/// A byte buffer the GIF encoder writes into and the sink reads back when the encoder is done.
#[derive(Clone, Default)]
struct SharedBuffer(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl SharedBuffer {
    fn take(&self) -> Vec<u8> {
        std::mem::take(&mut self.0.borrow_mut())
    }
}

impl std::io::Write for SharedBuffer {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Collects rendered frames into a target; [`FrameSink::finish`] writes what is written at the end.
pub struct FrameSink {
    target: Target,
    width: u32,
    height: u32,
    alpha: Alpha,
    frames: Range<u32>,
    frame_rate: f64,
    gif: Option<(image::codecs::gif::GifEncoder<SharedBuffer>, SharedBuffer)>,
    /// Frames in the GIF so far (their delays add up to the frame rate's time).
    gif_frames: u32,
    /// The sheet's layout and its 8-bit RGBA, as its PNG holds it.
    sheet: Option<(SheetLayout, Vec<u8>)>,
    video: Option<video::VideoWriter>,
    /// A sequence's frames, written beside the destination until the last is.
    staged: Option<staged::Staged>,
    written: Vec<PathBuf>,
}

impl FrameSink {
    /// A sink for `frames` of `width` x `height` pixels at `frame_rate`; `alpha` says how the alpha channel of
    /// a transparent export is kept (a GIF keeps none, and the caller refuses a transparent one beforehand).
    pub fn new(
        target: &Target,
        width: u32,
        height: u32,
        frames: Range<u32>,
        frame_rate: f64,
        alpha: Alpha,
    ) -> Result<Self, ExportError> {
        let mut sink = Self {
            target: target.clone(),
            width,
            height,
            alpha,
            frames: frames.clone(),
            frame_rate,
            gif: None,
            gif_frames: 0,
            sheet: None,
            video: None,
            staged: None,
            written: Vec::new(),
        };
        if let Target::Single { path, .. }
        | Target::Sequence { pattern: path, .. }
        | Target::Sheet { path, .. } = target
        {
            sink.staged = Some(staged::Staged::beside(path)?);
        }
        match target {
            Target::Gif { path } => {
                // Speed 10 of NeuQuant's 1..30: a good palette per frame in a fraction of the render time.
                let buffer = SharedBuffer::default();
                let mut enc = image::codecs::gif::GifEncoder::new_with_speed(buffer.clone(), 10);
                enc.set_repeat(image::codecs::gif::Repeat::Infinite)
                    .map_err(|source| OutputError::Encode {
                        path: path.clone(),
                        source,
                    })?;
                sink.gif = Some((enc, buffer));
            }
            Target::Video { path, container } => {
                sink.video = Some(video::VideoWriter::start(
                    path,
                    *container,
                    width,
                    height,
                    frame_rate,
                    alpha != Alpha::Opaque,
                )?);
            }
            Target::Sheet { path, options } => {
                let mut layout =
                    sheet_grid(path, width, height, frames.clone(), options, frame_rate)?;
                layout.premultiplied = alpha == Alpha::Premultiplied;
                let bytes = vec![0; 4 * layout.width() as usize * layout.height() as usize];
                sink.sheet = Some((layout, bytes));
            }
            _ => {}
        }
        Ok(sink)
    }

    /// Adds the rendered `frame` (RGBA display values, premultiplied where transparent, rows from the top).
    pub fn push(&mut self, frame: u32, pixels: &[[f64; 4]]) -> Result<(), ExportError> {
        let (w, h) = (self.width, self.height);
        match &self.target {
            Target::Single { path, .. } => {
                let staged = self.staged.as_mut().expect("made with the target");
                output::write_rgba(&staged.stage(path), w, h, pixels, self.alpha)?;
            }
            Target::Sequence { pattern, .. } => {
                let staged = self.staged.as_mut().expect("made with the target");
                let path = staged.stage(&frame_path(pattern, frame));
                output::write_rgba(&path, w, h, pixels, self.alpha)?;
            }
            Target::Gif { .. } | Target::Video { .. } | Target::Sheet { .. } => {
                let rgba = output::encode_rgba8(pixels, self.encoding());
                self.push_rgba8(frame, &rgba)?;
            }
        }
        Ok(())
    }

    /// How this sink's 8-bit frames hold alpha: none in a GIF, straight in a video (255 where opaque), as the
    /// export says in a PNG.
    pub fn encoding(&self) -> Alpha {
        match (&self.target, self.alpha) {
            (Target::Gif { .. }, _) | (_, Alpha::Opaque) => Alpha::Opaque,
            (Target::Video { .. }, _) => Alpha::Straight,
            (_, alpha) => alpha,
        }
    }

    /// Adds `frame` as 8-bit RGBA (rows from the top) encoded as `encoding` says: what a PNG frame of the same
    /// export holds, so that frames rendered apart and joined here make the very file one export makes.
    pub fn push_rgba8(&mut self, frame: u32, rgba: &[u8]) -> Result<(), ExportError> {
        let (w, h) = (self.width, self.height);
        let has_alpha = self.alpha != Alpha::Opaque;
        match &self.target {
            Target::Single { path, .. } => {
                let staged = self.staged.as_mut().expect("made with the target");
                output::write_png8(&staged.stage(path), w, h, rgba, has_alpha)?;
            }
            Target::Sequence { pattern, .. } => {
                let staged = self.staged.as_mut().expect("made with the target");
                let path = staged.stage(&frame_path(pattern, frame));
                output::write_png8(&path, w, h, rgba, has_alpha)?;
            }
            Target::Gif { path } => {
                let rgba = image::RgbaImage::from_raw(w, h, rgba.to_vec())
                    .expect("the frame's size matches");
                let delay = image::Delay::from_numer_denom_ms(
                    10 * gif_delay(self.gif_frames, self.frame_rate),
                    1,
                );
                self.gif_frames += 1;
                let (enc, _) = self.gif.as_mut().expect("made with the target");
                enc.encode_frame(image::Frame::from_parts(rgba, 0, 0, delay))
                    .map_err(|source| OutputError::Encode {
                        path: path.clone(),
                        source,
                    })?;
            }
            Target::Video { .. } => {
                self.video
                    .as_mut()
                    .expect("made with the target")
                    .push_rgba8(rgba)?;
            }
            Target::Sheet { .. } => {
                let (layout, sheet) = self.sheet.as_mut().expect("made with the target");
                let (x0, y0) = layout.cell(frame - self.frames.start);
                let (row, sheet_row) = (4 * w as usize, 4 * layout.width() as usize);
                for y in 0..h as usize {
                    let at = (y0 as usize + y) * sheet_row + 4 * x0 as usize;
                    sheet[at..at + row].copy_from_slice(&rgba[y * row..(y + 1) * row]);
                }
            }
        }
        Ok(())
    }

    /// Removes what was written so far (an export stopped before its end leaves nothing half done, and the files
    /// of the same names that were there before it as they were).
    pub fn abandon(mut self) {
        if let Some(v) = self.video.take() {
            v.abandon();
        }
        if let Some(s) = self.staged.take() {
            s.discard();
        }
        for path in &self.written {
            let _ = std::fs::remove_file(path);
        }
    }

    /// Writes the GIF or the sheet (and its layout), and moves what was staged into place; returns every file
    /// written.
    pub fn finish(mut self) -> Result<Vec<PathBuf>, ExportError> {
        match &self.target {
            Target::Gif { path } => {
                let (enc, buffer) = self.gif.take().expect("made with the target");
                // The encoder writes the GIF's trailer when dropped.
                drop(enc);
                let bytes = buffer.take();
                output::write_atomically(path, &bytes)?;
                self.written.push(path.clone());
            }
            Target::Video { .. } => {
                let v = self.video.take().expect("made with the target");
                self.written.push(v.finish()?);
            }
            Target::Sheet { path, .. } => {
                let (layout, rgba) = self.sheet.take().expect("made with the target");
                let staged = self.staged.as_mut().expect("made with the target");
                // Cells past the last frame stay transparent (black in an opaque sheet). The sheet and its layout
                // move into place together: never a new sheet beside an old layout.
                let (w, h) = (layout.width(), layout.height());
                let alpha = self.alpha != Alpha::Opaque;
                output::write_png8(&staged.stage(path), w, h, &rgba, alpha)?;
                let json = staged.stage(&sheet::layout_path(path));
                output::write_atomically(&json, layout.to_json().as_bytes())?;
            }
            _ => {}
        }
        if let Some(staged) = self.staged.take() {
            self.written.extend(staged.commit()?);
        }
        Ok(self.written)
    }
}

/// Renders `frames` of `scene`'s animation with `render` (the composed frame of the scene at the frame given,
/// RGBA display values, `size` pixels: its renderer takes the scene at that frame through its frame cache,
/// `frame::FrameCache::scene_at`, so that live sets step from the last frame) into `target`; `on_frame(done, frame)` after each. Returns the files
/// written. `on_frame` may stop the export (`ControlFlow::Break`): what it wrote so far is then removed, the
/// files of the same names from before left whole, and it ends with `ExportError::Cancelled`, as after a failure. The command line and the viewer's export both
/// run this.
pub fn export_frames<E: From<ExportError>>(
    scene: &Scene,
    target: &Target,
    frames: Range<u32>,
    size: (u32, u32),
    alpha: Alpha,
    mut render: impl FnMut(u32) -> Result<Vec<[f64; 4]>, E>,
    mut on_frame: impl FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<Vec<PathBuf>, E> {
    let frame_rate = scene
        .animation
        .as_ref()
        .map_or(crate::animation::DEFAULT_FRAME_RATE, |a| a.frame_rate);
    let mut sink = FrameSink::new(target, size.0, size.1, frames.clone(), frame_rate, alpha)?;
    for (done, frame) in frames.enumerate() {
        let pixels = match render(frame) {
            Ok(p) => p,
            Err(e) => {
                sink.abandon();
                return Err(e);
            }
        };
        if let Err(e) = sink.push(frame, &pixels) {
            sink.abandon();
            return Err(e.into());
        }
        if on_frame(done as u32 + 1, frame).is_break() {
            sink.abandon();
            return Err(ExportError::Cancelled.into());
        }
    }
    Ok(sink.finish()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges() {
        let r = |s: &str, n: u32| FrameSpec::parse(s).unwrap().resolve(n).ok();
        assert_eq!(r("0..10", 100), Some(0..10));
        assert_eq!(r("10..=19", 100), Some(10..20));
        assert_eq!(r("90..", 100), Some(90..100));
        assert_eq!(r("..5", 100), Some(0..5));
        assert_eq!(r("..", 100), Some(0..100));
        assert_eq!(r("7", 100), Some(7..8));
        // A farm manager's chunk: inclusive.
        assert_eq!(r("10-19", 100), Some(10..20));
        assert_eq!(r("99-99", 100), Some(99..100));
        assert_eq!(r("5-4", 100), None);
        assert_eq!(r("90-100", 100), None);
        assert_eq!(r("0..101", 100), None);
        assert_eq!(r("5..5", 100), None);
        assert_eq!(r("1", 1), None);
        for bad in [
            "", "a..b", "-1..3", "3..-1", "1...2", "..=", "1..2..3", "-3", "3-", "1-2-3", "1-5,8",
        ] {
            assert!(FrameSpec::parse(bad).is_err(), "{bad}");
        }
    }

    /// Every file in `dir` with its bytes, by name.
    fn listing(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        let mut out: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let p = e.unwrap().path();
                let bytes = std::fs::read(&p).unwrap();
                (p, bytes)
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn a_cancelled_or_failed_export_leaves_the_folder_as_it_found_it() {
        // A folder holding an earlier export of the same names (frames 0 to 9 of another render), and a file of
        // the user's: a cancelled export, one failing on a frame and one stopped after its only frame leave every
        // byte of it as it was; a whole export replaces the frames and nothing else.
        let dir = std::env::temp_dir().join(format!("energywave-earlier-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut scene = Scene::default_scene();
        scene.animation = Some(crate::animation::Animation {
            frames: 10,
            ..Default::default()
        });
        let target = Target::Sequence {
            pattern: dir.join("f_##.png"),
            format: crate::output::Format::Png,
        };
        let earlier = vec![[0.1, 0.9, 0.2, 1.0]; 8 * 6];
        let rendered = std::cell::Cell::new(0);
        let render = |pixels: &Vec<[f64; 4]>, stop: u32| {
            rendered.set(0);
            export_frames::<ExportError>(
                &scene,
                &target,
                0..10,
                (8, 6),
                Alpha::Opaque,
                |_| {
                    rendered.set(rendered.get() + 1);
                    Ok(pixels.clone())
                },
                |done, _| match done == stop {
                    true => ControlFlow::Break(()),
                    false => ControlFlow::Continue(()),
                },
            )
        };
        assert_eq!(render(&earlier, 0).unwrap().len(), 10);
        std::fs::write(dir.join("notes.txt"), b"the user's").unwrap();
        let before = listing(&dir);
        assert_eq!(before.len(), 11);
        let pixels = vec![[0.5, 0.25, 1.0, 1.0]; 8 * 6];
        for stop in [1, 4, 10] {
            assert!(matches!(render(&pixels, stop), Err(ExportError::Cancelled)));
            assert_eq!(rendered.get(), stop, "no frame rendered after the cancel");
            assert_eq!(listing(&dir), before, "cancelled after {stop} frames");
        }
        rendered.set(0);
        let failing = export_frames::<ExportError>(
            &scene,
            &target,
            0..10,
            (8, 6),
            Alpha::Opaque,
            |_| match rendered.replace(rendered.get() + 1) >= 3 {
                true => Err(ExportError::Target {
                    path: dir.clone(),
                    why: "the device was lost".into(),
                }),
                false => Ok(pixels.clone()),
            },
            |_, _| ControlFlow::Continue(()),
        );
        assert!(failing.is_err());
        assert_eq!(listing(&dir), before, "a failed render");
        // A single image stopped after its frame keeps the image that was there.
        let single = Target::Single {
            path: dir.join("f_03.png"),
            format: crate::output::Format::Png,
        };
        let stopped = export_frames::<ExportError>(
            &scene,
            &single,
            3..4,
            (8, 6),
            Alpha::Opaque,
            |_| Ok(pixels.clone()),
            |_, _| ControlFlow::Break(()),
        );
        assert!(matches!(stopped, Err(ExportError::Cancelled)));
        assert_eq!(listing(&dir), before, "a single image");
        // Whole, it replaces the ten frames and leaves the user's file.
        assert_eq!(render(&pixels, 0).unwrap().len(), 10);
        let after = listing(&dir);
        assert_eq!(after.len(), 11);
        let changed = (before.iter().zip(&after))
            .filter(|(b, a)| b.1 != a.1)
            .count();
        assert_eq!(changed, 10, "every frame new, the notes as they were");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn gif_delays_average_the_frame_rate() {
        let delays: Vec<u32> = (0..30).map(|k| gif_delay(k, 30.0)).collect();
        assert_eq!(delays.iter().sum::<u32>(), 100, "30 frames in a second");
        assert!(delays.iter().all(|&d| d == 3 || d == 4), "{delays:?}");
        assert_eq!(&delays[..3], &[3, 4, 3]);
        assert!((0..24).map(|k| gif_delay(k, 24.0)).sum::<u32>() == 100);
        assert!((0..100).all(|k| gif_delay(k, 25.0) == 4));
        // Faster than the format can hold: one hundredth each, never none.
        assert!((0..10).all(|k| gif_delay(k, 500.0) >= 1));
    }

    #[test]
    fn frame_numbers_are_padded_to_the_run_of_hashes() {
        let p = Path::new("out/beam_####.png");
        assert_eq!(frame_path(p, 7), Path::new("out/beam_0007.png"));
        assert_eq!(frame_path(p, 1234), Path::new("out/beam_1234.png"));
        assert_eq!(frame_path(p, 12345), Path::new("out/beam_12345.png"));
        assert_eq!(frame_path(Path::new("f#.exr"), 3), Path::new("f3.exr"));
        assert_eq!(
            frame_path(Path::new("a#b/x_###_y.png"), 42),
            Path::new("a#b/x_042_y.png")
        );
        assert_eq!(hash_runs("a_##_b_#.png"), 2);
        assert_eq!(hash_runs("a_####.png"), 1);
        assert_eq!(hash_runs("a.png"), 0);
    }
}
