//! Sprite sheets: the frames of an animation in a grid (row-major from the top-left), one PNG, with a JSON
//! file beside it saying where each frame is, for game engines' flipbook and sprite-animation importers.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{ExportError, MAX_SHEET_SIDE};

/// Where a sheet's frames are.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SheetLayout {
    /// The sheet's file name (the JSON lies beside it).
    pub image: String,
    pub frame_width: u32,
    pub frame_height: u32,
    pub columns: u32,
    pub rows: u32,
    pub frame_count: u32,
    /// The animation frame in the first cell.
    pub first_frame: u32,
    pub frame_rate: f64,
    /// How cells are filled.
    pub order: &'static str,
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

impl SheetLayout {
    pub fn width(&self) -> u32 {
        self.columns * self.frame_width
    }

    pub fn height(&self) -> u32 {
        self.rows * self.frame_height
    }

    /// Top-left pixel of the `k`-th cell.
    pub fn cell(&self, k: u32) -> (u32, u32) {
        (
            (k % self.columns) * self.frame_width,
            (k / self.columns) * self.frame_height,
        )
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a layout serialises") + "\n"
    }
}

/// The JSON layout's path: the sheet's, with `.json` for `.png`.
pub fn layout_path(sheet: &Path) -> PathBuf {
    sheet.with_extension("json")
}

/// The grid for `frames` of `width` x `height`: `columns` wide, or as square as it gets
/// (ceil(sqrt(count)) columns). Refused when the sheet would exceed `MAX_SHEET_SIDE` on a side.
pub fn sheet_grid(
    path: &Path,
    width: u32,
    height: u32,
    frames: Range<u32>,
    columns: Option<u32>,
    frame_rate: f64,
) -> Result<SheetLayout, ExportError> {
    let count = frames.end.saturating_sub(frames.start).max(1);
    let columns = columns
        .unwrap_or_else(|| (count as f64).sqrt().ceil() as u32)
        .clamp(1, count);
    let rows = count.div_ceil(columns);
    let (sw, sh) = (columns as u64 * width as u64, rows as u64 * height as u64);
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
        frame_count: count,
        first_frame: frames.start,
        frame_rate,
        order: "row-major from the top-left",
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
        let g = |n: u32, cols: Option<u32>| {
            let l = sheet_grid(Path::new("s.png"), 10, 20, 5..5 + n, cols, 30.0).unwrap();
            (l.columns, l.rows, l.width(), l.height())
        };
        assert_eq!(g(16, None), (4, 4, 40, 80));
        assert_eq!(g(17, None), (5, 4, 50, 80));
        assert_eq!(g(3, None), (2, 2, 20, 40));
        assert_eq!(g(1, None), (1, 1, 10, 20));
        assert_eq!(g(10, Some(10)), (10, 1, 100, 20));
        assert_eq!(g(10, Some(3)), (3, 4, 30, 80));
        let l = sheet_grid(Path::new("s.png"), 10, 20, 5..12, Some(3), 30.0).unwrap();
        assert_eq!(
            l.frames[4],
            SheetCell {
                frame: 9,
                x: 10,
                y: 20
            }
        );
        assert!(sheet_grid(Path::new("s.png"), 4096, 4096, 0..25, None, 30.0).is_err());
    }
}
