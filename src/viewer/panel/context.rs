//! What the panel reads and does not edit, the viewer's own view settings it edits in place, and the ranges it
//! offers.

use super::super::document::Document;
use super::super::history::History;
use crate::animation::SourceKind;
use crate::scene::{Scene, limits};

/// Largest Simpson division count the panel offers (the file format allows more, for batch renders).
pub(super) const PANEL_MAX_DIVISIONS: u32 = 4096;
/// Largest billboard resolution the panel offers: beyond it a frame takes seconds even on a real GPU (the file
/// format and the command line allow more, for batch renders).
pub const PANEL_MAX_RESOLUTION: u32 = 4096;
/// The tolerances the panel's drag value offers.
pub(super) const PANEL_TOLERANCE: std::ops::RangeInclusive<f64> = 1e-7..=0.05;
// Whatever the panel offers, the scene loader accepts (`scene::limits`): an edited scene always saves and loads.
const _: () = assert!(PANEL_MAX_DIVISIONS <= limits::MAX_DIVISIONS);
const _: () = assert!(PANEL_MAX_RESOLUTION <= limits::MAX_RESOLUTION);
const _: () = assert!(
    *PANEL_TOLERANCE.start() > limits::MIN_TOLERANCE
        && *PANEL_TOLERANCE.end() < limits::MAX_TOLERANCE
);

/// Jittered frames the viewport averages while the view is still, unless set otherwise: the noise falls to
/// 1/8 of one frame's.
pub const DEFAULT_AVERAGE_FRAMES: u32 = 64;

/// How the viewer shows the scene: the viewer's own settings, edited by the panel in place (they are not
/// part of the document and have no undo).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSettings {
    /// Everything drawn over the look: the grid, the guides and the handles (Shift+Alt+Z and the viewport's
    /// "Overlays" button, as Blender's); each also has its own switch.
    pub show_overlays: bool,
    pub show_grid: bool,
    pub show_handles: bool,
    /// With jitter: how many frames the viewport averages while the view is still (1: none).
    pub average_frames: u32,
    /// While the view moves, show a coarse field sized to the frame budget and refine it once still
    /// (`progressive`); off: every frame integrates the full field.
    pub progressive: bool,
    /// How the coarse field and the bands are chosen: from the measured frame costs, or fixed (tests).
    pub pacing: crate::viewer::progressive::Pacing,
    /// Screenshot size relative to the viewport: 1, 2 or 4.
    pub screenshot_scale: u32,
    /// While the glare's threshold is hovered or dragged in the panel: the viewport dims the glow that does
    /// not glare (never a screenshot or an export).
    pub preview_glare_threshold: bool,
}

impl Default for ViewSettings {
    fn default() -> Self {
        Self {
            show_overlays: true,
            show_grid: true,
            show_handles: true,
            average_frames: DEFAULT_AVERAGE_FRAMES,
            progressive: true,
            pacing: Default::default(),
            screenshot_scale: 1,
            preview_glare_threshold: false,
        }
    }
}

/// What the panel reads and does not edit.
pub struct Context<'a> {
    /// The document: its title, file and the state of its file on disk.
    pub doc: &'a Document,
    /// The scene as shown: the document's at the current frame of its animation.
    pub shown: &'a Scene,
    pub history: &'a History,
    /// Largest billboard resolution the device allows.
    pub max_resolution: u32,
    /// The viewport's width over its height.
    pub aspect: f64,
    /// The animation's current frame (where a key goes).
    pub frame: u32,
    /// The selected source: its entry is highlighted.
    pub selected: Option<(SourceKind, usize)>,
    /// The selected object: its entry is highlighted.
    pub selected_object: Option<usize>,
    /// Scroll the selected source's entry into view (it was selected in the viewport).
    pub scroll_to_selected: bool,
    /// The files opened and saved lately, newest first.
    pub recent: &'a [std::path::PathBuf],
}
