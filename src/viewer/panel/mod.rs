//! The side panel: every parameter of the scene, edited live. It reads the scene as shown (at the current
//! frame of its animation) and returns what the user asked for as actions; `ViewerApp::apply` carries them
//! out. Values a user cannot sensibly enter are prevented here (odd division counts, R <= 0, zero
//! directions, ...), so the GPU never sees them.
//!
//! One file a section: `file` (the document, files, screenshots), `view` (the camera), `render` (integration,
//! billboard, colors), `sources`, `objects`, `particles`; `fields` holds the editors with their key buttons, `context` what the panel
//! reads and its own settings.

mod context;
mod fields;
mod file;
mod objects;
mod particles;
mod render;
mod sources;
mod view;

pub use context::{Context, DEFAULT_AVERAGE_FRAMES, PANEL_MAX_RESOLUTION, ViewSettings};

use egui::Ui;

use super::action::Action;
use fields::Edits;

/// The panel's file, view, rendering and sources sections (the Animation section is `animation_panel`).
/// `path` is the file name typed in the file section.
pub fn show(ui: &mut Ui, cx: &Context, path: &mut String, view: &mut ViewSettings) -> Vec<Action> {
    let mut out = Edits {
        actions: Vec::new(),
        animation: cx.shown.animation.as_ref(),
        frame: cx.frame,
    };
    file::file_section(ui, cx, path, view, &mut out);
    ui.separator();
    view::view_section(ui, cx.shown, view, &mut out);
    ui.separator();
    render::render_section(ui, cx, view, &mut out);
    ui.separator();
    sources::sources_section(ui, cx, &mut out);
    ui.separator();
    objects::objects_section(ui, cx, &mut out);
    ui.separator();
    particles::particles_section(ui, cx, &mut out);
    out.actions
}
