//! The viewer's copy of its offscreen frame into the window's (egui's) render pass, converting to the
//! window's format and softening the staircase of the objects' silhouettes (`shaders/blit.wgsl`).

use super::context::{
    RenderPipelineSpec, depth_value_entry, filtered_texture_entry, filtering_sampler_entry,
    pass_layouts, render_pipeline,
};
use super::shaders::BLIT_PASS as BLIT_SHADER;

/// The copy's pipeline for one target format, and what a frame's bind group is made of.
pub struct BlitPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

impl BlitPass {
    /// The pipeline writing `target_format`: with the sRGB encoding done by the target if it is an sRGB
    /// format, else by the shader.
    pub fn new(device: &wgpu::Device, target_format: wgpu::TextureFormat) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.blit.shader"),
            source: wgpu::ShaderSource::Wgsl(BLIT_SHADER.into()),
        });
        let (layout, pipeline_layout) = pass_layouts(
            device,
            "blit",
            &[
                filtered_texture_entry(0),
                filtering_sampler_entry(1),
                depth_value_entry(2),
            ],
        );
        let pipeline = render_pipeline(
            device,
            RenderPipelineSpec {
                name: "blit",
                module: &module,
                layout: &pipeline_layout,
                vertex_buffers: &[],
                topology: wgpu::PrimitiveTopology::TriangleList,
                fragment_entry: if target_format.is_srgb() {
                    "fs_srgb"
                } else {
                    "fs_display"
                },
                constants: &[],
                targets: &[Some(wgpu::ColorTargetState {
                    format: target_format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                depth: None,
            },
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("energywave.blit.sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self {
            pipeline,
            layout,
            sampler,
        }
    }

    /// The bind group that copies `source`, its objects' silhouettes found in `depth` (the frame's copy of the
    /// objects' depth, `DEPTH_VALUE_FORMAT`) and softened.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        source: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.blit.bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(source),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(depth),
                },
            ],
        })
    }

    /// Draws the copy of `bind_group`'s source into `pass` (over its viewport).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, bind_group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
