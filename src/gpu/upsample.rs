//! The smooth upsampling of a low-resolution brightness texture to W x W (`shaders/upsample.wgsl`): the viewer
//! integrates a coarse field while the view moves and shows it through the same billboard pass as the full
//! one, upsampled by Catmull-Rom (no blocks, no creases between texels).

use super::context::{
    compute_pass, field_storage_entry, field_texture, field_texture_layers, loaded_field_entry,
};
use super::shaders;

/// The pipeline, and the W x W output with its bind group over one source texture.
pub struct Upsample {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bound: Option<Bound>,
}

struct Bound {
    source: wgpu::Texture,
    output: wgpu::Texture,
    view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

impl Upsample {
    pub fn new(device: &wgpu::Device) -> Self {
        let (pipeline, layout) = compute_pass(
            device,
            "upsample",
            shaders::UPSAMPLE_PASS,
            "upsample",
            &[
                loaded_field_entry(0),
                field_storage_entry(1, wgpu::StorageTextureAccess::WriteOnly),
            ],
        );
        Self {
            pipeline,
            layout,
            bound: None,
        }
    }

    /// Records the upsampling of `source` (its view `source_view`) into the W x W output, `w` = `resolution`:
    /// its first `layers` layers (`field_pass::layers_of`).
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Texture,
        source_view: &wgpu::TextureView,
        resolution: u32,
        layers: u32,
    ) {
        let stale = self.bound.as_ref().is_none_or(|b| {
            &b.source != source
                || b.output.width() != resolution
                || b.output.depth_or_array_layers() != field_texture_layers(device, layers)
        });
        if stale {
            let (output, view) =
                field_texture(device, "energywave.upsample.output", resolution, layers);
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("energywave.upsample.bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(source_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            self.bound = Some(Bound {
                source: source.clone(),
                output,
                view,
                bind_group,
            });
        }
        let b = self.bound.as_ref().expect("bound above");
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.upsample.pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &b.bind_group, &[]);
        // One layer a z: B, and the tint only where the scene has one.
        pass.dispatch_workgroups(resolution.div_ceil(8), resolution.div_ceil(8), layers);
    }

    /// The upsampled texture and its view (after the first `encode`).
    pub fn output(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        self.bound.as_ref().map(|b| (&b.output, &b.view))
    }

    /// GPU memory held: the output texture, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        self.bound.as_ref().map_or(0, |b| {
            super::context::field_texture_bytes(b.output.width(), b.output.depth_or_array_layers())
        })
    }
}
