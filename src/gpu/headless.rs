//! Headless rendering through the same code the viewer uses (`frame::SceneRenderer`): the brightness texture
//! alone, or the composed frame in an offscreen texture, read back to the CPU.

use super::context::{GpuContext, GpuError};
use super::field_pass::FieldRenderer;
use super::frame::{FrameTargets, SceneRenderer, Target, read_frame};
use crate::frame::{FrameCache, FrameSetup};
use crate::scene::Scene;

/// A composed frame read back from the GPU: RGBA in [0, 1], rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePixels {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// A GPU context with the scene renderer, rendering offscreen.
pub struct HeadlessRenderer {
    pub ctx: GpuContext,
    renderer: SceneRenderer,
    /// The last `brightness` read the glow seen through translucent objects (`tint` reads the same).
    read_through: bool,
}

impl HeadlessRenderer {
    /// A renderer on the adapter `GpuContext::new` chooses.
    pub fn new() -> Result<Self, GpuError> {
        Ok(Self::from_context(GpuContext::new()?))
    }

    /// The last frame's smoke image and its plan (`ParticlePass::read_image`); none without particles.
    pub fn smoke_image(
        &self,
    ) -> Result<Option<crate::gpu::particle_pass::SmokeReadback>, GpuError> {
        (self.renderer.particles()).read_image(&self.ctx.device, &self.ctx.queue)
    }

    /// Has the next frame splat the smoke again where it would lay the last image again (a benchmark's frames of
    /// one view, each timed as a moved view's).
    pub fn splat_again(&mut self) {
        self.renderer.particles_mut().splat_again();
    }

    /// A renderer on an existing context.
    pub fn from_context(ctx: GpuContext) -> Self {
        let renderer = SceneRenderer::new(&ctx.device, &ctx.queue);
        Self {
            ctx,
            renderer,
            read_through: false,
        }
    }

    /// The cache its frames are resolved through (`frame::FrameCache`).
    pub fn cache(&self) -> &std::sync::Arc<FrameCache> {
        self.renderer.cache()
    }

    /// The frame of `scene` in a picture of `aspect` (width / height), resolved through its cache.
    pub fn setup<'a>(&self, scene: &'a Scene, aspect: f64) -> FrameSetup<'a> {
        self.renderer.setup(scene, aspect)
    }

    /// `Scene::at_frame`, the live sets' simulations kept in its cache (a sequence steps each frame from the
    /// last).
    pub fn scene_at(&self, scene: &Scene, frame: f64) -> Scene {
        self.renderer.cache().scene_at(scene, frame)
    }

    /// Which texels of the field its frames integrate (`SceneRenderer::set_refine`).
    pub fn set_refine(&mut self, refine: Option<crate::frame::Refine>) {
        self.renderer.set_refine(refine);
    }

    /// The field pass, for inspection (dispatch count, texture).
    pub fn field(&self) -> &FieldRenderer {
        self.renderer.field()
    }

    /// When the field pass uses pipelines specialised to the scene's structure (`FieldRenderer::set_specialise`).
    pub fn set_specialise(&mut self, mode: crate::gpu::Specialise) {
        self.renderer.field_mut().set_specialise(mode);
    }

    /// Keeps an opaque frame's values above 1 (an HDR export) instead of clamping them as the display does.
    pub fn set_unclamped(&mut self, unclamped: bool) {
        self.renderer.set_unclamped(unclamped);
    }

    /// Leaves the objects out of the frames while they still hide the glow (a holdout).
    pub fn set_holdout(&mut self, holdout: bool) {
        self.renderer.set_holdout(holdout);
    }

    /// Averages up to `frames` jittered renders of an unchanged scene, one more each call
    /// (`FieldRenderer::set_average_frames`); 1, the default, renders each scene once.
    pub fn set_average_frames(&mut self, frames: u32) {
        self.renderer.field_mut().set_average_frames(frames);
    }

    /// B for every texel of the frame's billboard (W x W, rows from the top), rendered again only if the frame's
    /// field inputs changed since the last call.
    pub fn brightness(&mut self, setup: &FrameSetup) -> Result<Vec<f32>, GpuError> {
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.field.encoder"),
        });
        // Where translucent objects stand, the glow behind them seen through them, as a frame shows it.
        let through = self
            .renderer
            .see_through(self.ctx.gpu(), &mut encoder, setup)?;
        self.ctx.checked(|| queue.submit([encoder.finish()]))?;
        let texture = match through {
            true => self.renderer.through_texture().expect("blended above"),
            false => self.renderer.field().texture().expect("prepared above"),
        };
        let bytes = self.ctx.read_texture(texture, 4)?;
        self.read_through = through;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// The tint `sum B_i (Ce_i - Ce)` for every texel (W x W, rows from the top) of the last `brightness`'s
    /// scene and billboard: zero where every source has the scene's color (the pass writes B alone then).
    pub fn tint(&self) -> Result<Vec<[f32; 3]>, GpuError> {
        let field = self.renderer.field();
        let texture = match self.read_through {
            true => self
                .renderer
                .through_texture()
                .expect("brightness renders first"),
            false => field.texture().expect("brightness renders first"),
        };
        if field.layers() == 1 {
            let w = texture.width() as usize;
            return Ok(vec![[0.0; 3]; w * w]);
        }
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let layers: Vec<Vec<f32>> = (1..4)
            .map(|layer| {
                super::context::read_texture_layer(device, queue, texture, 4, layer)
                    .map(|bytes| bytemuck::cast_slice(&bytes).to_vec())
            })
            .collect::<Result<_, _>>()?;
        Ok((0..layers[0].len())
            .map(|k| [layers[0][k], layers[1][k], layers[2][k]])
            .collect())
    }

    /// The scene's camera view, `width` x `height`: the background color, and the billboard blended over it.
    /// With `transparent`, the background is transparent and the billboard carries alpha = min(B, 1).
    pub fn render(
        &mut self,
        scene: &Scene,
        width: u32,
        height: u32,
        transparent: bool,
    ) -> Result<FramePixels, GpuError> {
        let limit = self.ctx.device.limits().max_texture_dimension_2d;
        if width > limit || height > limit {
            return Err(GpuError::FrameTooLarge {
                width,
                height,
                limit,
            });
        }
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let targets = self
            .ctx
            .checked(|| FrameTargets::new(device, [width, height]))?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("energywave.headless.encoder"),
        });
        // Nothing lies behind the billboard here but the background and the objects (the viewer draws more).
        let setup = self.renderer.setup(scene, width as f64 / height as f64);
        let target = Target {
            targets: &targets,
            transparent,
        };
        (self.renderer).record(self.ctx.gpu(), &mut encoder, &setup, target)?;
        self.ctx.checked(|| queue.submit([encoder.finish()]))?;
        Ok(FramePixels {
            width,
            height,
            pixels: read_frame(device, queue, &targets)?,
        })
    }
}
