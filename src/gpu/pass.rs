//! The one interface every pass of a frame after its field has: it prepares from the frame's data (uploads,
//! textures, bind groups), then records into the frame's encoder, at the stages it takes part in. The frame
//! (`frame::SceneRenderer::compose`) runs one ordered list of them, the viewer's overlays placed in it by their
//! stage; a new pass implements `FramePass` and names its stage.

pub use super::context::Gpu;
use super::context::GpuError;
use super::targets::FrameTargets;
use crate::frame::Frame;

/// Where a pass stands in a frame, in the order the frame records them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// The glow seen through translucent objects, blended over the field (`through_pass`).
    SeeThrough,
    /// The glare added to the field (`glare_pass`).
    Glare,
    /// What lies behind the billboard cleared: the scene's background color, or transparent.
    Background,
    /// Drawn over the background, under everything else: the viewer's grid.
    Behind,
    /// The objects with their depth, which the smoke and the billboard read (`object_pass`).
    Objects,
    /// The smoke's back image (what the glow covers), over the background and the objects (`particle_pass`).
    SmokeBehind,
    /// The billboard blended over a copy of what lies behind it (`billboard_pass`).
    Billboard,
    /// The smoke's front image, over the glow (`particle_pass`).
    SmokeInFront,
}

/// The brightness a frame shows: the field's texture, then the blend seen through translucent objects, then
/// the glare's, as each pass replaces it.
#[derive(Clone, Debug)]
pub struct Brightness {
    pub view: wgpu::TextureView,
    /// Its side in texels: W, or a coarse field's while the viewer's view moves.
    pub resolution: u32,
    /// Its layers (`field_pass::layers_of`).
    pub layers: u32,
    /// Whether its texels changed since the last frame (the glare reuses its last where not).
    pub fresh: bool,
    /// Whether a layer past `layers` holds B without the translucent objects' dimming (`through_pass`): what the
    /// glow's edge fades by, so that a glow dimmed by an object is not also cut off at its edge.
    pub undimmed: bool,
}

/// How the frame is drawn, besides its scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Look {
    /// Over a transparent background, alpha = min(B, 1).
    pub transparent: bool,
    /// The objects hide the glow but are not drawn.
    pub holdout: bool,
    /// The opaque blends are not clamped above 1 (an HDR export).
    pub unclamped: bool,
    /// The viewer's preview of the glare's threshold: the glow at or below it dimmed.
    pub threshold_preview: Option<f64>,
}

/// What a frame's passes read and leave for the passes after them.
pub struct Recording<'r> {
    pub gpu: Gpu<'r>,
    pub frame: &'r Frame<'r, 'r>,
    pub targets: &'r FrameTargets,
    pub look: Look,
    pub brightness: Brightness,
    /// The camera's view-projection matrix for the frame's aspect, with the billboard's depth range.
    pub view_proj: [[f32; 4]; 4],
    /// Whether the objects were drawn (their depth is there to read).
    pub objects: bool,
}

/// A pass of a frame (see the module's documentation).
pub trait FramePass {
    /// The stages it takes part in.
    fn stages(&self) -> &'static [Stage];

    /// Prepares its part of the frame at `stage` from the frame's data: uploads, textures, bind groups; it may
    /// change what the passes after it read (`Recording::brightness`, `Recording::objects`).
    fn prepare(&mut self, stage: Stage, r: &mut Recording<'_>) -> Result<(), GpuError>;

    /// Records what it prepared at `stage` into `encoder`.
    fn record(&mut self, stage: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder);
}

/// Runs `passes` as one ordered list: each stage's passes in the order given (the frame's own first, then the
/// overlays), every pass prepared before any records.
pub fn run(
    passes: &mut [&mut dyn FramePass],
    r: &mut Recording<'_>,
    encoder: &mut wgpu::CommandEncoder,
) -> Result<(), GpuError> {
    let mut order: Vec<(Stage, usize)> = (passes.iter().enumerate())
        .flat_map(|(i, p)| p.stages().iter().map(move |&s| (s, i)))
        .collect();
    order.sort_by_key(|&(stage, _)| stage);
    for &(stage, i) in &order {
        passes[i].prepare(stage, r)?;
    }
    for &(stage, i) in &order {
        passes[i].record(stage, r, encoder);
    }
    Ok(())
}
