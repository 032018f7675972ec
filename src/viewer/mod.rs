//! The interactive viewer: an orbit camera around the effect, a panel that edits every parameter live,
//! handles to drag in the viewport, undo and redo, scene files with hot reload, and screenshots.
//!
//! - [`app`]: the state and the whole UI (`ViewerApp::ui`), shared by the window and the UI tests; it applies
//!   every action in one place;
//! - [`action`]: what the panels and the viewport return: the user's requests and the edits of the scene;
//! - [`panel`]: the side panel's editors;
//! - [`animation_panel`]: its Animation section (pulses, keys, export);
//! - [`widgets`]: the small editors both panels use;
//! - [`handles`]: the sources' handles, drawn and dragged with egui's painter;
//! - [`navigation`]: orbit, pan, zoom and framing;
//! - [`history`]: undo and redo;
//! - [`timeline`]: playback of the animation (play, pause, step, scrub, loop) and exports beside the UI;
//! - [`document`]: the scene file, saving, hot reload, screenshot names;
//! - [`file_dialog`]: Open and Save As through a dialog; [`recent`]: the recent files, kept between runs;
//! - [`viewport`]: the 3D viewport on the GPU (grid, field, billboard) as an egui-wgpu paint callback;
//! - [`window`]: the winit window and event loop;
//! - [`presenter`]: one frame of the viewer into a surface, and recovery from surface and device faults;
//! - [`offscreen`]: the same viewer drawn into a texture (benchmarks, stress tests).

pub mod action;
pub mod animation_panel;
pub mod app;
pub mod document;
pub mod file_dialog;
pub mod handles;
pub mod history;
pub mod navigation;
pub mod offscreen;
pub mod panel;
pub mod presenter;
pub mod progressive;
pub mod recent;
pub mod timeline;
pub mod viewport;
pub mod widgets;
pub mod window;

pub use action::{Action, Edit};
pub use app::{Request, ViewerApp};
pub use document::Document;
pub use panel::ViewSettings;
pub use window::{ViewOptions, ViewerError, run};
