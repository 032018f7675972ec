//! Sprite sheets: the frames of an animation in a grid (row-major from the top-left), one PNG, with a JSON
//! file beside it saying where each frame is, for game engines' flipbook and sprite-animation importers.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{ExportError, MAX_SHEET_SIDE};

/// How a sheet is laid out, beside its frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SheetOptions {
    /// Columns of the grid (default: as square as it gets).
    pub columns: Option<u32>,
    /// Transparent pixels between neighbouring cells, so that a mipmap's filter does not bleed one frame into
    /// the next.
    pub padding: u32,
    /// Round the sheet's width and height up to powers of two (the cells stay where they are; the rest is
    /// transparent), for engines and older GPUs that want them.
    pub power_of_two: bool,
}

/// Where a sheet's frames are.
#[derive(Clone, Debug, PartialEq)]
pub struct SheetLayout {
    /// The sheet's file name (the JSON lies beside it).
    pub image: String,
    pub frame_width: u32,
    pub frame_height: u32,
    pub columns: u32,
    pub rows: u32,
    pub padding: u32,
    /// The sheet's size (a power of two a side with `SheetOptions::power_of_two`).
    pub sheet_width: u32,
    pub sheet_height: u32,
    pub frame_count: u32,
    /// The animation frame in the first cell.
    pub first_frame: u32,
    pub frame_rate: f64,
    /// Color multiplied by alpha (for premultiplied blend modes).
    pub premultiplied: bool,
    /// Each frame's cell: the animation frame, and the cell's top-left pixel.
    pub frames: Vec<SheetCell>,
}

/// One frame's place in a sheet.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SheetCell {
    pub frame: u32,
    pub x: u32,
    pub y: u32,
}

/// A rectangle of the TexturePacker layout.
#[derive(Serialize)]
struct Rect {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
}

#[derive(Serialize)]
struct Size {
    w: u32,
    h: u32,
}

/// A frame of the TexturePacker "hash" layout.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PackedFrame {
    frame: Rect,
    rotated: bool,
    trimmed: bool,
    sprite_source_size: Rect,
    source_size: Size,
    /// Milliseconds the frame shows (Aseprite's and Phaser's key for it).
    duration: f64,
}

/// The sheet's file as a whole: TexturePacker's `frames` and `meta`, with our own grid in `meta` beside it.
#[derive(Serialize)]
struct PackedSheet {
    frames: serde_json::Map<String, serde_json::Value>,
    meta: Meta,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Meta {
    app: &'static str,
    version: &'static str,
    image: String,
    format: &'static str,
    size: Size,
    scale: &'static str,
    premultiplied_alpha: bool,
    /// The grid: what the frames' rectangles follow.
    #[serde(rename = "energywave")]
    grid: Grid,
}

#[derive(Serialize)]
struct Grid {
    frame_width: u32,
    frame_height: u32,
    columns: u32,
    rows: u32,
    padding: u32,
    frame_count: u32,
    first_frame: u32,
    frame_rate: f64,
    order: &'static str,
    frames: Vec<SheetCell>,
}

impl SheetLayout {
    pub fn width(&self) -> u32 {
        self.sheet_width
    }

    pub fn height(&self) -> u32 {
        self.sheet_height
    }

    /// Top-left pixel of the `k`-th cell.
    pub fn cell(&self, k: u32) -> (u32, u32) {
        (
            (k % self.columns) * (self.frame_width + self.padding),
            (k / self.columns) * (self.frame_height + self.padding),
        )
    }

    /// The name of animation frame `frame` in the layout: the sheet's stem and the frame number.
    pub fn frame_name(&self, frame: u32) -> String {
        let stem = Path::new(&self.image)
            .file_stem()
            .map_or("frame".into(), |s| s.to_string_lossy().into_owned());
        format!("{stem}_{frame:04}")
    }

    /// The layout as JSON in TexturePacker's "hash" form (`frames` by name with `frame`, `sourceSize` and
    /// `spriteSourceSize`; `meta` with `image`, `size`, `format` and `scale`), which Phaser's, Godot's and Unity's
    /// importers read; the grid itself under `meta.energywave`.
    pub fn to_json(&self) -> String {
        let (w, h) = (self.frame_width, self.frame_height);
        let duration = 1000.0 / self.frame_rate;
        let frames = self
            .frames
            .iter()
            .map(|c| {
                let packed = PackedFrame {
                    frame: Rect {
                        x: c.x,
                        y: c.y,
                        w,
                        h,
                    },
                    rotated: false,
                    trimmed: false,
                    sprite_source_size: Rect { x: 0, y: 0, w, h },
                    source_size: Size { w, h },
                    duration,
                };
                (
                    self.frame_name(c.frame),
                    serde_json::to_value(packed).expect("a frame serialises"),
                )
            })
            .collect();
        let sheet = PackedSheet {
            frames,
            meta: Meta {
                app: "energywave",
                version: env!("CARGO_PKG_VERSION"),
                image: self.image.clone(),
                format: "RGBA8888",
                size: Size {
                    w: self.sheet_width,
                    h: self.sheet_height,
                },
                scale: "1",
                premultiplied_alpha: self.premultiplied,
                grid: Grid {
                    frame_width: w,
                    frame_height: h,
                    columns: self.columns,
                    rows: self.rows,
                    padding: self.padding,
                    frame_count: self.frame_count,
                    first_frame: self.first_frame,
                    frame_rate: self.frame_rate,
                    order: "row-major from the top-left",
                    frames: self.frames.clone(),
                },
            },
        };
        serde_json::to_string_pretty(&sheet).expect("a layout serialises") + "\n"
    }
}

/// Mobile GPUs commonly load textures of at most this many pixels a side.
pub const MOBILE_TEXTURE_SIDE: u32 = 4096;

/// A warning when the sheet is larger than `MOBILE_TEXTURE_SIDE` on a side, saying how to make it fit.
pub fn mobile_warning(layout: &SheetLayout) -> Option<String> {
    let (w, h) = (layout.width(), layout.height());
    (w > MOBILE_TEXTURE_SIDE || h > MOBILE_TEXTURE_SIDE).then(|| {
        format!(
            "the sheet is {w}x{h}, over {MOBILE_TEXTURE_SIDE} pixels a side, which many mobile GPUs cannot load: \
             a smaller --size or fewer --frames fit"
        )
    })
}

/// The JSON layout's path: the sheet's, with `.json` for `.png`.
pub fn layout_path(sheet: &Path) -> PathBuf {
    sheet.with_extension("json")
}

/// The grid for `frames` of `width` x `height`: `options.columns` wide, or as square as it gets
/// (ceil(sqrt(count)) columns), `options.padding` between cells, rounded up to powers of two if asked.
/// Refused when the sheet would exceed `MAX_SHEET_SIDE` on a side.
pub fn sheet_grid(
    path: &Path,
    width: u32,
    height: u32,
    frames: Range<u32>,
    options: &SheetOptions,
    frame_rate: f64,
) -> Result<SheetLayout, ExportError> {
    let count = frames.end.saturating_sub(frames.start).max(1);
    let columns = options
        .columns
        .unwrap_or_else(|| (count as f64).sqrt().ceil() as u32)
        .clamp(1, count);
    let rows = count.div_ceil(columns);
    let pad = options.padding as u64;
    let side = |n: u32, cell: u32| {
        let s = n as u64 * cell as u64 + (n as u64 - 1) * pad;
        if options.power_of_two {
            s.next_power_of_two()
        } else {
            s
        }
    };
    let (sw, sh) = (side(columns, width), side(rows, height));
    if sw > MAX_SHEET_SIDE || sh > MAX_SHEET_SIDE {
        return Err(ExportError::Target {
            path: path.to_owned(),
            why: format!(
                "{count} frames of {width}x{height} in {columns} columns and {rows} rows make a {sw}x{sh} sheet, \
                 over {MAX_SHEET_SIDE} pixels a side: use a smaller --size, fewer --frames, or other --columns"
            ),
        });
    }
    let mut layout = SheetLayout {
        image: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        frame_width: width,
        frame_height: height,
        columns,
        rows,
        padding: options.padding,
        sheet_width: sw as u32,
        sheet_height: sh as u32,
        frame_count: count,
        first_frame: frames.start,
        frame_rate,
        premultiplied: false,
        frames: Vec::new(),
    };
    layout.frames = (0..count)
        .map(|k| {
            let (x, y) = layout.cell(k);
            SheetCell {
                frame: frames.start + k,
                x,
                y,
            }
        })
        .collect();
    Ok(layout)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_are_as_square_as_they_get() {
        let g = |n: u32, columns: Option<u32>| {
            let options = SheetOptions {
                columns,
                ..Default::default()
            };
            let l = sheet_grid(Path::new("s.png"), 10, 20, 5..5 + n, &options, 30.0).unwrap();
            (l.columns, l.rows, l.width(), l.height())
        };
        assert_eq!(g(16, None), (4, 4, 40, 80));
        assert_eq!(g(17, None), (5, 4, 50, 80));
        assert_eq!(g(3, None), (2, 2, 20, 40));
        assert_eq!(g(1, None), (1, 1, 10, 20));
        assert_eq!(g(10, Some(10)), (10, 1, 100, 20));
        assert_eq!(g(10, Some(3)), (3, 4, 30, 80));
        let three = SheetOptions {
            columns: Some(3),
            ..Default::default()
        };
        let l = sheet_grid(Path::new("s.png"), 10, 20, 5..12, &three, 30.0).unwrap();
        assert_eq!(
            l.frames[4],
            SheetCell {
                frame: 9,
                x: 10,
                y: 20
            }
        );
        let square = SheetOptions::default();
        assert!(sheet_grid(Path::new("s.png"), 4096, 4096, 0..25, &square, 30.0).is_err());
    }

    #[test]
    fn padding_and_powers_of_two() {
        let options = SheetOptions {
            columns: Some(3),
            padding: 2,
            power_of_two: false,
        };
        let l = sheet_grid(Path::new("s.png"), 10, 20, 0..7, &options, 30.0).unwrap();
        // Three columns of 10 with 2 between: 34; three rows of 20: 64.
        assert_eq!((l.width(), l.height()), (34, 64));
        assert_eq!(l.cell(4), (12, 22));
        let l = sheet_grid(
            Path::new("s.png"),
            10,
            20,
            0..7,
            &SheetOptions {
                power_of_two: true,
                ..options
            },
            30.0,
        )
        .unwrap();
        assert_eq!((l.width(), l.height()), (64, 64));
        assert_eq!(l.cell(4), (12, 22));
    }

    #[test]
    fn the_json_is_texturepackers_hash_layout() {
        let l = sheet_grid(
            Path::new("out/beam.png"),
            10,
            20,
            5..8,
            &SheetOptions {
                padding: 1,
                ..Default::default()
            },
            25.0,
        )
        .unwrap();
        let v: serde_json::Value = serde_json::from_str(&l.to_json()).unwrap();
        let f = &v["frames"]["beam_0007"];
        assert_eq!(
            f["frame"],
            serde_json::json!({"x": 0, "y": 21, "w": 10, "h": 20})
        );
        assert_eq!(f["sourceSize"], serde_json::json!({"w": 10, "h": 20}));
        assert_eq!(
            f["spriteSourceSize"],
            serde_json::json!({"x": 0, "y": 0, "w": 10, "h": 20})
        );
        assert_eq!(f["rotated"], false);
        assert_eq!(f["duration"], 40.0);
        assert_eq!(v["meta"]["image"], "beam.png");
        assert_eq!(v["meta"]["size"], serde_json::json!({"w": 21, "h": 41}));
        assert_eq!(v["meta"]["format"], "RGBA8888");
        assert_eq!(v["meta"]["scale"], "1");
        assert_eq!(v["frames"].as_object().unwrap().len(), 3);
    }
}
