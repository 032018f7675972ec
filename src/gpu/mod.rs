//! The GPU renderer: the field pass (a WGSL compute shader integrating B into a storage texture), then a
//! frame's passes as one ordered list (`pass::FramePass`, run by `frame::SceneRenderer::compose`: the glow seen
//! through translucent objects, the glare, the background, the objects, the smoke, the billboard's blend), and
//! the headless renderer that runs them for the command line and the tests. The viewer draws through the same
//! list, its grid added to it. A new pass implements `FramePass`, names its `Stage` and joins the list in
//! `SceneRenderer::compose`.

mod billboard_pass;
mod blit_pass;
mod context;
pub(crate) mod field_pass;
mod formats;
mod frame;
mod frame_average;
pub mod glare_pass;
pub mod grid_pass;
mod headless;
pub mod object_pass;
pub mod particle_pass;
pub mod pass;
pub mod shaders;
mod targets;
pub mod tau_table;
pub mod through_pass;

pub use billboard_pass::{BillboardRenderer, billboard_params, view_projection};
pub use blit_pass::BlitPass;
pub use context::{
    FIELD_LAYERS, GpuContext, GpuError, checked, compute_pass, describe, field_storage_entry,
    field_texture, field_texture_bytes, field_texture_layers, map_read, read_texture,
    read_texture_layer, storage_buffer_entry, texture_2d, uniform_buffer,
};
pub use field_pass::probe;
pub use field_pass::{FieldInputs, FieldRenderer, FieldShaders, Specialise, Structure, layers_of};
pub use formats::FRAME_FORMAT;
pub use frame::{FrameTargets, SceneRenderer, Target, f16_to_f32, frame_cache, read_frame};
pub use grid_pass::GridPass;
pub use headless::{FramePixels, HeadlessRenderer};
pub use pass::{Brightness, FramePass, Gpu, Look, Stage};

/// The Rust mirrors of the WGSL structs, for the layout tests.
pub mod layout {
    pub use super::billboard_pass::gpu_data::BillboardParams;
    pub use super::field_pass::gpu_data::{
        Chunk, CurvePiece, CurveSegment, CurveSource, FieldParams, LineSource, PointSource,
        TorusSource,
    };
    pub use super::field_pass::refine::Level;
    pub use super::frame_average::gpu_data::AverageParams;
}
