//! One frame of a scene on the GPU: the field pass, what lies behind the billboard, and the billboard blended
//! over it. Headless rendering and the viewer's viewport both draw through `SceneRenderer::record`; the viewer
//! adds its grid behind the glow through the `behind` hook.

use super::billboard_pass::{BillboardRenderer, BlendMode, billboard_params, view_projection};
use super::context::{GpuError, checked, over, read_texture, texture_2d};
use super::field_pass::{FieldInputs, FieldRenderer};
use super::formats::{DEPTH_FORMAT, DEPTH_VALUE_CLEAR, DEPTH_VALUE_FORMAT, FRAME_FORMAT};
use super::glare_pass::GlarePass;
use super::object_pass::ObjectPass;
use super::particle_pass::ParticlePass;
use crate::frame::FrameSetup;

/// The two textures of a composed frame: what lies behind the billboard, and the result.
pub struct FrameTargets {
    pub size: [u32; 2],
    pub background: wgpu::Texture,
    pub background_view: wgpu::TextureView,
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    /// The objects' depth buffer (the depth test).
    pub depth_view: wgpu::TextureView,
    /// The copy of the objects' depth the billboard reads (`DEPTH_VALUE_FORMAT`).
    pub depth_value_view: wgpu::TextureView,
}

impl FrameTargets {
    pub fn new(device: &wgpu::Device, size: [u32; 2]) -> Self {
        use wgpu::TextureUsages as U;
        let background = texture_2d(
            device,
            "energywave.frame.background",
            size,
            FRAME_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let color = texture_2d(
            device,
            "energywave.frame.color",
            size,
            FRAME_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST | U::COPY_SRC,
        );
        let depth = texture_2d(
            device,
            "energywave.frame.depth",
            size,
            DEPTH_FORMAT,
            U::RENDER_ATTACHMENT,
        );
        let depth_value = texture_2d(
            device,
            "energywave.frame.depth_value",
            size,
            DEPTH_VALUE_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
        );
        Self {
            size,
            depth_view: depth.create_view(&Default::default()),
            depth_value_view: depth_value.create_view(&Default::default()),
            background_view: background.create_view(&Default::default()),
            color_view: color.create_view(&Default::default()),
            background,
            color,
        }
    }
}

/// The field and billboard passes, long-lived; the scene is passed in per frame.
pub struct SceneRenderer {
    field: FieldRenderer,
    billboard: BillboardRenderer,
    glare: GlarePass,
    objects: ObjectPass,
    particles: ParticlePass,
    /// The glow seen through translucent objects.
    through: super::through_pass::ThroughPass,
    /// The objects hide the glow but are not drawn: the glow alone with them as a holdout, to layer over a
    /// render of the same scene made elsewhere.
    holdout: bool,
    /// The opaque blends are not clamped above 1 (an HDR export).
    unclamped: bool,
    /// The viewer's preview of the glare's threshold: the glow at or below it dimmed.
    threshold_preview: Option<f64>,
}

impl SceneRenderer {
    pub fn new(device: &wgpu::Device) -> Self {
        let field = FieldRenderer::new(device);
        Self {
            through: super::through_pass::ThroughPass::new(device, &field.shaders()),
            field,
            billboard: BillboardRenderer::new(device, FRAME_FORMAT),
            glare: GlarePass::new(device),
            objects: ObjectPass::new(device),
            particles: ParticlePass::new(device),
            holdout: false,
            unclamped: false,
            threshold_preview: None,
        }
    }

    /// Works out what takes long, the objects' light (with their translucent tables) and the particles' light,
    /// on threads of their own from now on (the viewer): a frame waits for it up to `wait`
    /// (`object_pass::WAIT` in the viewer: a small scene's is ready within it), then draws stand-ins (the
    /// objects unshadowed, the particles it drew before) until it is ready; `preparing` says what is.
    pub fn prepare_in_background(&mut self, wait: std::time::Duration) {
        self.objects.light_in_background(wait);
        self.particles.light_in_background(wait);
    }

    /// What is being worked out on the background threads, for the status line; `None` when the frames show
    /// everything as it is.
    pub fn preparing(&self) -> Option<String> {
        let parts: Vec<&str> = (self.objects.busy().into_iter())
            .chain(self.particles.busy().then_some("particles' light"))
            .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }

    /// Waits until what is being worked out is ready (a screenshot shows the scene as it is).
    pub fn wait_prepared(&self) {
        self.objects.wait();
        self.particles.wait();
    }

    /// Dims the glow whose B is at or below `threshold` (the glare's, while the viewer's panel edits it), so that
    /// what glares stands out; `None` draws the frame as it is.
    pub fn set_threshold_preview(&mut self, threshold: Option<f64>) {
        self.threshold_preview = threshold;
    }

    /// Whether an opaque frame keeps the blend's values above 1 (for an HDR export) or clamps them, as the
    /// display does. A transparent frame is unclamped either way.
    pub fn set_unclamped(&mut self, unclamped: bool) {
        self.unclamped = unclamped;
    }

    /// Whether the objects are left out of the picture while still hiding the glow (`holdout`).
    pub fn set_holdout(&mut self, holdout: bool) {
        self.holdout = holdout;
    }

    /// The particle pass, for inspection (the smoke's image and its plan).
    pub fn particles(&self) -> &ParticlePass {
        &self.particles
    }

    /// Records the glow of `setup` seen through its translucent objects over `field` (`layers` layers, the
    /// setup's resolution); whether it has any (then `through_texture` holds the blend).
    pub fn see_through(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
        field: &wgpu::TextureView,
        layers: u32,
    ) -> Result<bool, GpuError> {
        let size = (setup.resolution, layers);
        Ok((self.through)
            .encode(device, queue, encoder, setup, field, size)?
            .is_some())
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

    /// Records one frame (`setup`, its billboard placed for `targets`' aspect) into `targets.color`: the field
    /// pass when something it depends on changed, the background (the scene's color, or transparent) with
    /// whatever `behind` draws over it (given the view-projection matrix), then the billboard blended over a copy
    /// of that.
    // The GPU handles, the frame's inputs and its hook are all distinct; a struct would only rename them.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
        targets: &FrameTargets,
        transparent: bool,
        behind: impl FnOnce(&mut wgpu::RenderPass<'_>, [[f32; 4]; 4]),
    ) -> Result<(), GpuError> {
        self.field.prepare(device, queue, &FieldInputs::of(setup))?;
        checked(device, || self.field.encode(encoder))?;
        let brightness = self.field.view().expect("prepared above").clone();
        self.compose(
            device,
            queue,
            encoder,
            setup,
            targets,
            transparent,
            (&brightness, setup.resolution, true),
            behind,
        )
    }

    /// Records the rest of a frame over a brightness texture already integrated (`brightness`: its view, its
    /// side, W or another, and whether its texels changed since the last frame, for the glare to reuse its
    /// last where they did not): the background with whatever `behind` draws over it, then the billboard
    /// blended over a copy of that.
    #[allow(clippy::too_many_arguments)]
    pub fn compose(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        setup: &FrameSetup,
        targets: &FrameTargets,
        transparent: bool,
        (brightness, resolution, fresh): (&wgpu::TextureView, u32, bool),
        behind: impl FnOnce(&mut wgpu::RenderPass<'_>, [[f32; 4]; 4]),
    ) -> Result<(), GpuError> {
        let [w, h] = targets.size;
        let aspect = w as f64 / h as f64;
        let (scene, billboard) = (setup.scene, setup.billboard);
        let layers = crate::gpu::field_pass::layers_of(scene);
        // Where translucent objects stand, the glow behind them seen through them.
        let seen = (self.through)
            .encode(
                device,
                queue,
                encoder,
                setup,
                brightness,
                (resolution, layers),
            )?
            .cloned();
        let brightness = seen.as_ref().unwrap_or(brightness);
        checked(device, || {
            // The glare, where the scene has one, adds to the field before the blend.
            let brightness = match &scene.glare {
                Some(glare) => {
                    let size = (resolution, layers);
                    self.glare
                        .encode(device, queue, encoder, brightness, size, glare, fresh)
                }
                None => brightness,
            };
            let view_proj = view_projection(&scene.camera, &billboard, aspect)
                .as_mat4()
                .to_cols_array_2d();
            let [r, g, b] = scene.colors.background;
            let clear = if transparent {
                wgpu::Color::TRANSPARENT
            } else {
                wgpu::Color { r, g, b, a: 1.0 }
            };
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("energywave.frame.background"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &targets.background_view,
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
                behind(&mut pass, view_proj);
            }
            // The objects with depth (a holdout: their depth alone), which the billboard reads to hide the glow
            // in front of them pixel by pixel.
            let objects = self.objects.prepare(device, queue, setup);
            if objects {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("energywave.frame.objects"),
                    color_attachments: &[
                        Some(wgpu::RenderPassColorAttachment {
                            view: &targets.background_view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Load,
                                store: wgpu::StoreOp::Store,
                            },
                        }),
                        // The depth's copy, cleared to the far plane as the depth buffer is.
                        Some(wgpu::RenderPassColorAttachment {
                            view: &targets.depth_value_view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(DEPTH_VALUE_CLEAR),
                                store: wgpu::StoreOp::Store,
                            },
                        }),
                    ],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &targets.depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                self.objects.draw(
                    queue,
                    &mut pass,
                    (view_proj, setup.eye().as_vec3().to_array()),
                    !self.holdout,
                );
            }
            // The particles' smoke behind the billboard's plane over the background and the objects, its rays
            // ended by the objects; the smoke in front of the plane goes over the glow.
            let smoke = (self.particles).prepare(device, queue, setup, targets.size, resolution);
            if smoke {
                self.particles
                    .encode(device, encoder, &targets.depth_value_view);
                let mut pass = over(
                    encoder,
                    "energywave.frame.particles",
                    &targets.background_view,
                );
                self.particles.draw(&mut pass, false);
            }
            // The billboard blends over a copy of what lies behind it.
            encoder.copy_texture_to_texture(
                targets.background.as_image_copy(),
                targets.color.as_image_copy(),
                targets.background.size(),
            );
            let mut params = billboard_params(
                &scene.camera,
                &billboard,
                resolution,
                scene.colors.energy_color(),
                aspect,
                BlendMode::of(transparent, scene.colors.blend),
                setup.reach.nu,
                scene.colors.cutoff,
            );
            if self.unclamped {
                params.mode |= crate::gpu::billboard_pass::UNCLAMPED;
            }
            if let Some(threshold) = self.threshold_preview.filter(|_| !transparent) {
                params.mode |= crate::gpu::billboard_pass::THRESHOLD_PREVIEW;
                params.energy[3] = threshold as f32;
            }
            // Where objects stand, the billboard reads the clips of the texture it shows (`resolution`), up to the
            // first surface of any object: a translucent one's edge guides the glow blended for it as an opaque
            // one's edge guides the glow it ends.
            let clips = match objects {
                true => setup.surface_clips_at(resolution),
                false => None,
            };
            self.billboard.draw(
                device,
                queue,
                encoder,
                &targets.color_view,
                &targets.background_view,
                brightness,
                (&targets.depth_value_view, clips),
                layers,
                &params,
            );
            if smoke {
                let mut pass = over(
                    encoder,
                    "energywave.frame.particles.front",
                    &targets.color_view,
                );
                self.particles.draw(&mut pass, true);
            }
        })
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
