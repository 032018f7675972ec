//! One frame of a scene on the GPU: the field pass, then the frame's passes as one ordered list
//! (`pass::FramePass`): the glow seen through translucent objects, the glare, what lies behind the billboard
//! (the background, the viewer's grid, the objects, the smoke behind), the billboard blended over it, the smoke
//! in front. Headless rendering and the viewer's viewport both draw through `SceneRenderer::compose`; the
//! viewer integrates its field progressively and adds its grid to the same list.

use std::sync::Arc;

use super::billboard_pass::{BillboardRenderer, view_projection};
use super::context::{GpuError, checked, read_texture};
use super::field_pass::{FieldInputs, FieldRenderer};
use super::formats::FRAME_FORMAT;
use super::glare_pass::GlarePass;
use super::object_pass::ObjectPass;
use super::particle_pass::ParticlePass;
use super::pass::{Brightness, FramePass, Gpu, Look, Recording, Stage, run};
pub use super::targets::FrameTargets;
use super::through_pass::ThroughPass;
use crate::frame::{Frame, FrameCache, FrameSetup, Resolver};
use crate::scene::Scene;

/// The frame's passes, long-lived, and the cache of what its frames resolved; the scene comes in per frame.
pub struct SceneRenderer {
    field: FieldRenderer,
    /// The glow seen through translucent objects.
    through: ThroughPass,
    glare: GlarePass,
    background: BackgroundPass,
    objects: ObjectPass,
    particles: ParticlePass,
    billboard: BillboardRenderer,
    /// Where what the frames resolved is kept (`frame::FrameCache`), and how the slow parts are resolved.
    cache: Arc<FrameCache>,
    resolver: Resolver,
    look: Look,
    /// Which texels of the field its frames integrate, where not as the scene's tolerance says
    /// (`set_refine`).
    refine: Option<crate::frame::Refine>,
}

impl SceneRenderer {
    /// The passes on `device`, with a frame cache of their own (filling translucent tables on `device` where it
    /// is a real GPU).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        Self::with_cache(device, Arc::new(frame_cache(device, queue)))
    }

    /// The passes on `device`, their frames resolved through `cache` (the viewer shares its own with the
    /// simulation of its live particles).
    pub fn with_cache(device: &wgpu::Device, cache: Arc<FrameCache>) -> Self {
        let field = FieldRenderer::new(device);
        Self {
            through: ThroughPass::new(device, &field.shaders()),
            field,
            glare: GlarePass::new(device),
            background: BackgroundPass,
            objects: ObjectPass::new(device),
            particles: ParticlePass::new(device),
            billboard: BillboardRenderer::new(device, FRAME_FORMAT),
            cache,
            resolver: Resolver::new(),
            look: Look::default(),
            refine: None,
        }
    }

    /// Which texels of the field the frames from `setup` integrate: `None` (the default) as the scene's
    /// tolerance says (`frame::Refine::of`), `Refine::EveryTexel` for a reference render.
    pub fn set_refine(&mut self, refine: Option<crate::frame::Refine>) {
        self.refine = refine;
    }

    /// The cache its frames are resolved through.
    pub fn cache(&self) -> &Arc<FrameCache> {
        &self.cache
    }

    /// The frame of `scene` in a picture of `aspect` (width / height), resolved through this renderer's cache.
    pub fn setup<'a>(&self, scene: &'a Scene, aspect: f64) -> FrameSetup<'a> {
        let mut setup = FrameSetup::placed_in(scene, aspect, &self.cache);
        if let Some(refine) = self.refine {
            setup.refine = refine;
        }
        setup
    }

    /// Works out what takes long, the objects' light (with their translucent tables) and the particles' light,
    /// on threads of their own from now on (the viewer): a frame waits for it up to `wait`
    /// (`frame::resolve::WAIT` in the viewer: a small scene's is ready within it), then draws stand-ins (the
    /// objects unshadowed, the particles it drew before) until it is ready; `preparing` says what is.
    pub fn prepare_in_background(&mut self, wait: std::time::Duration) {
        self.resolver.in_background(wait);
    }

    /// What is being worked out on the background threads, for the status line; `None` when the frames show
    /// everything as it is.
    pub fn preparing(&self) -> Option<String> {
        self.resolver.preparing()
    }

    /// Waits until what is being worked out is ready (a screenshot shows the scene as it is).
    pub fn wait_prepared(&self) {
        self.resolver.wait();
    }

    /// Dims the glow whose B is at or below `threshold` (the glare's, while the viewer's panel edits it), so that
    /// what glares stands out; `None` draws the frame as it is.
    pub fn set_threshold_preview(&mut self, threshold: Option<f64>) {
        self.look.threshold_preview = threshold;
    }

    /// Whether an opaque frame keeps the blend's values above 1 (for an HDR export) or clamps them, as the
    /// display does. A transparent frame is unclamped either way.
    pub fn set_unclamped(&mut self, unclamped: bool) {
        self.look.unclamped = unclamped;
    }

    /// Whether the objects are left out of the picture while still hiding the glow (`holdout`).
    pub fn set_holdout(&mut self, holdout: bool) {
        self.look.holdout = holdout;
    }

    /// The particle pass, for inspection (the smoke's image and its plan).
    pub fn particles(&self) -> &ParticlePass {
        &self.particles
    }

    /// The particle pass, to have it splat the smoke again (`ParticlePass::splat_again`).
    pub fn particles_mut(&mut self) -> &mut ParticlePass {
        &mut self.particles
    }

    /// Records the field of `setup` and the glow seen through its translucent objects over it; whether it has
    /// any (then `through_texture` holds the blend, else the field's texture holds the glow).
    pub fn see_through(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
    ) -> Result<bool, GpuError> {
        let brightness = self.integrate(gpu, encoder, setup)?;
        let seen = self.through.prepare_blend(gpu, setup, &brightness)?;
        checked(gpu.device, || self.through.record_blend(encoder))?;
        Ok(seen.is_some())
    }

    /// The last blend of the glow seen through translucent objects.
    pub fn through_texture(&self) -> Option<&wgpu::Texture> {
        self.through.output()
    }

    /// The field pass, for inspection (dispatch count, texture) and for the brightness alone.
    pub fn field(&self) -> &FieldRenderer {
        &self.field
    }

    pub fn field_mut(&mut self) -> &mut FieldRenderer {
        &mut self.field
    }

    /// Records the field of `setup` (when something it depends on changed) and returns its brightness.
    fn integrate(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
    ) -> Result<Brightness, GpuError> {
        (self.field).prepare(gpu.device, gpu.queue, &FieldInputs::of(setup))?;
        checked(gpu.device, || self.field.encode(encoder))?;
        Ok(Brightness {
            view: self.field.view().expect("prepared above").clone(),
            resolution: setup.resolution,
            layers: crate::gpu::field_pass::layers_of(setup.scene),
            fresh: true,
            undimmed: false,
        })
    }

    /// Records one frame (`setup`, its billboard placed for `target`'s aspect) into `target.targets.color`:
    /// the field pass when something it depends on changed, then the frame's passes (`compose`).
    pub fn record(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
        target: Target<'_>,
    ) -> Result<(), GpuError> {
        let brightness = self.integrate(gpu, encoder, setup)?;
        self.compose(gpu, encoder, setup, target, brightness, &mut [])
    }

    /// Records the rest of a frame over a brightness already integrated (its view, side, layers, and whether its
    /// texels changed since the last frame): the frame's data resolved (`frame::Resolver`), then its passes as
    /// one ordered list, `overlays` (the viewer's grid) placed in it by their stages.
    pub fn compose(
        &mut self,
        gpu: Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
        target: Target<'_>,
        brightness: Brightness,
        overlays: &mut [&mut dyn FramePass],
    ) -> Result<(), GpuError> {
        let frame = self.resolver.resolve(setup);
        let mut r = self.recording(gpu, &frame, target.targets, brightness, target.transparent);
        let mut passes: Vec<&mut dyn FramePass> = vec![
            &mut self.through,
            &mut self.glare,
            &mut self.background,
            &mut self.objects,
            &mut self.particles,
            &mut self.billboard,
        ];
        passes.extend(overlays.iter_mut().map(|p| &mut **p as &mut dyn FramePass));
        checked(gpu.device, || run(&mut passes, &mut r, encoder))?
    }

    /// What the passes of `frame` start from.
    fn recording<'r>(
        &self,
        gpu: Gpu<'r>,
        frame: &'r Frame<'r, 'r>,
        targets: &'r FrameTargets,
        brightness: Brightness,
        transparent: bool,
    ) -> Recording<'r> {
        let setup = frame.setup;
        let [w, h] = targets.size;
        let view_proj = view_projection(&setup.scene.camera, &setup.billboard, w as f64 / h as f64);
        Recording {
            gpu,
            frame,
            targets,
            look: Look {
                transparent,
                ..self.look
            },
            brightness,
            view_proj: view_proj.as_mat4().to_cols_array_2d(),
            objects: false,
        }
    }
}

/// A frame cache for renderers on `device`: its translucent tables filled on `device` where it is a real GPU
/// (`tau_table`), from any thread but on GL, where every call holds the one context.
pub fn frame_cache(device: &wgpu::Device, queue: &wgpu::Queue) -> FrameCache {
    let mut cache = FrameCache::new();
    if super::tau_table::fills_tables(&device.adapter_info()) {
        let (d, q) = (device.clone(), queue.clone());
        let any_thread = device.adapter_info().backend != wgpu::Backend::Gl;
        cache.set_table_fill(
            Box::new(move |voxels| super::tau_table::table_on(&d, &q, voxels).ok()),
            any_thread,
        );
    }
    cache
}

/// Where a frame is drawn: its targets, and whether over a transparent background.
#[derive(Clone, Copy)]
pub struct Target<'t> {
    pub targets: &'t FrameTargets,
    pub transparent: bool,
}

/// What lies behind the billboard cleared: the scene's background color, or transparent.
struct BackgroundPass;

impl FramePass for BackgroundPass {
    fn stages(&self) -> &'static [Stage] {
        &[Stage::Background]
    }

    fn prepare(&mut self, _: Stage, _: &mut Recording<'_>) -> Result<(), GpuError> {
        Ok(())
    }

    fn record(&mut self, _: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        let [red, g, b] = r.frame.setup.scene.colors.background;
        let clear = match r.look.transparent {
            true => wgpu::Color::TRANSPARENT,
            false => wgpu::Color {
                r: red,
                g,
                b,
                a: 1.0,
            },
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("energywave.frame.background"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &r.targets.background_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
    }
}

/// Reads a frame's color back: RGBA, rows from the top (waits for the GPU).
pub fn read_frame(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    targets: &FrameTargets,
) -> Result<Vec<[f32; 4]>, GpuError> {
    let bytes = read_texture(device, queue, &targets.color, 8)?;
    let halves: Vec<f32> = bytes
        .chunks_exact(2)
        .map(|c| f16_to_f32(u16::from_le_bytes([c[0], c[1]])))
        .collect();
    Ok(halves
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect())
}

/// IEEE 754 half to single precision.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exponent = ((h >> 10) & 0x1f) as u32;
    let mantissa = (h & 0x3ff) as u32;
    let bits = match (exponent, mantissa) {
        (0, 0) => sign,
        // Subnormal: value = mantissa * 2^-24.
        (0, m) => {
            let v = m as f32 * 2f32.powi(-24);
            return if sign != 0 { -v } else { v };
        }
        (0x1f, 0) => sign | 0x7f80_0000,
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 127 - 15) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x3555), 0.333_251_95);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x8001), -(2f32.powi(-24)));
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert!(f16_to_f32(0x7e00).is_nan());
        // Every half in [0, 1] decodes into [0, 1], in increasing order.
        let mut last = -1.0;
        for h in 0u16..=0x3c00 {
            let f = f16_to_f32(h);
            assert!((0.0..=1.0).contains(&f) && f > last);
            last = f;
        }
    }
}
