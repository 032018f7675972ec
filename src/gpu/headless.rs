//! Headless rendering through the same passes the viewer uses: the brightness texture alone, or the composed
//! frame in an offscreen texture, read back to the CPU.

use super::billboard_pass::{BillboardRenderer, billboard_params};
use super::context::{GpuContext, GpuError};
use super::field_pass::FieldRenderer;
use crate::geometry::Billboard;
use crate::scene::Scene;

/// The offscreen frame format: half floats (renderable on every backend, unlike Rgba32Float on GL), 11 bits
/// of mantissa: ample for colors in [0, 1] headed for 8-bit PNG or a float EXR.
const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

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

/// A composed frame read back from the GPU: RGBA in [0, 1], rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// A GPU context with the field and billboard passes, rendering offscreen.
pub struct HeadlessRenderer {
    pub ctx: GpuContext,
    field: FieldRenderer,
    billboard: BillboardRenderer,
}

impl HeadlessRenderer {
    /// A renderer on the adapter `GpuContext::new` chooses.
    pub fn new() -> Result<Self, GpuError> {
        Ok(Self::from_context(GpuContext::new()?))
    }

    /// A renderer on an existing context.
    pub fn from_context(ctx: GpuContext) -> Self {
        let field = FieldRenderer::new(&ctx.device);
        let billboard = BillboardRenderer::new(&ctx.device, FRAME_FORMAT);
        Self {
            ctx,
            field,
            billboard,
        }
    }

    /// The field pass, for inspection (dispatch count, texture).
    pub fn field(&self) -> &FieldRenderer {
        &self.field
    }

    /// Renders the brightness texture if the scene or billboard changed since the last call.
    fn update_field(&mut self, scene: &Scene, billboard: &Billboard) -> Result<(), GpuError> {
        self.field
            .prepare(&self.ctx.device, &self.ctx.queue, scene, billboard)?;
        self.ctx.check_uncaptured()?;
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("energywave.field.encoder"),
            });
        self.field.encode(&mut encoder);
        self.ctx
            .checked(|| self.ctx.queue.submit([encoder.finish()]))?;
        Ok(())
    }

    /// B for every texel of `billboard` (W x W, rows from the top).
    pub fn brightness(
        &mut self,
        scene: &Scene,
        billboard: &Billboard,
    ) -> Result<Vec<f32>, GpuError> {
        self.update_field(scene, billboard)?;
        let texture = self.field.texture().expect("prepared above");
        let bytes = self.ctx.read_texture(texture, 4)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// The scene's camera view, `width` x `height`: the background color, and the billboard blended over it.
    /// With `transparent`, the background is transparent and the billboard carries alpha = min(B, 1).
    pub fn render(
        &mut self,
        scene: &Scene,
        width: u32,
        height: u32,
        transparent: bool,
    ) -> Result<Frame, GpuError> {
        let limit = self.ctx.device.limits().max_texture_dimension_2d;
        if width > limit || height > limit {
            return Err(GpuError::FrameTooLarge {
                width,
                height,
                limit,
            });
        }
        let aspect = width as f64 / height as f64;
        let billboard = scene.place_billboard(aspect);
        self.update_field(scene, &billboard)?;
        let device = &self.ctx.device;
        let (frame, background) = self.ctx.checked(|| {
            let make = |label, usage| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: FRAME_FORMAT,
                    usage,
                    view_formats: &[],
                })
            };
            (
                make(
                    "energywave.headless.frame",
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                ),
                make(
                    "energywave.headless.background",
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                ),
            )
        })?;
        let frame_view = frame.create_view(&Default::default());
        let background_view = background.create_view(&Default::default());
        let [r, g, b] = scene.colors.background;
        let clear = if transparent {
            wgpu::Color::TRANSPARENT
        } else {
            wgpu::Color { r, g, b, a: 1.0 }
        };
        let params = billboard_params(
            &scene.camera,
            &billboard,
            scene.billboard.resolution,
            scene.colors.energy,
            aspect,
            transparent,
        );
        let brightness = self.field.view().expect("prepared above");
        self.ctx.checked(|| {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("energywave.headless.encoder"),
            });
            // What lies behind the billboard: here the background color alone (the viewer draws more).
            for view in [&background_view, &frame_view] {
                encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("energywave.headless.clear"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
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
            self.billboard.draw(
                device,
                &self.ctx.queue,
                &mut encoder,
                &frame_view,
                &background_view,
                brightness,
                &params,
            );
            self.ctx.queue.submit([encoder.finish()]);
        })?;
        let bytes = self.ctx.read_texture(&frame, 8)?;
        let halves: Vec<f32> = bytes
            .chunks_exact(2)
            .map(|c| f16_to_f32(u16::from_le_bytes([c[0], c[1]])))
            .collect();
        Ok(Frame {
            width,
            height,
            pixels: halves
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        })
    }
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
