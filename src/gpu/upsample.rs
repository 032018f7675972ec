//! The smooth upsampling of a low-resolution brightness texture to W x W (`shaders/upsample.wgsl`): the viewer
//! integrates a coarse field while the view moves and shows it through the same billboard pass as the full
//! one, upsampled by Catmull-Rom (no blocks, no creases between texels). Where the scene has objects, each
//! upsampled texel reads only the coarse texels whose rays end about where its own does (their clips), so that
//! an object's silhouette cuts the preview's glow as sharply as the full field's.

use std::sync::Arc;

use super::context::{
    ClipBuffer, field_storage_entry, field_texture, field_texture_layers, loaded_field_entry,
    pass_layouts, storage_buffer_entry,
};
use super::shaders;

/// The pipelines (without objects, with them), and the W x W output over one source texture.
pub struct Upsample {
    pipelines: [wgpu::ComputePipeline; 2],
    layout: wgpu::BindGroupLayout,
    bound: Option<Bound>,
    /// The coarse texture's clips and the output's, as uploaded last.
    clips: [ClipBuffer; 2],
}

struct Bound {
    source: wgpu::Texture,
    output: wgpu::Texture,
    view: wgpu::TextureView,
}

/// The clips of an upsampling's two textures, where the scene has objects (`FrameSetup::clips_at`).
pub struct UpsampleClips {
    /// The coarse texture's.
    pub source: Arc<Vec<f32>>,
    /// The output's.
    pub output: Arc<Vec<f32>>,
}

impl Upsample {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.upsample.shader"),
            source: wgpu::ShaderSource::Wgsl(shaders::UPSAMPLE_PASS.into()),
        });
        let (layout, pipeline_layout) = pass_layouts(
            device,
            "upsample",
            &[
                loaded_field_entry(0),
                field_storage_entry(1, wgpu::StorageTextureAccess::WriteOnly),
                storage_buffer_entry(2),
                storage_buffer_entry(3),
            ],
        );
        // A pipeline without objects and one with them (the shader's OBJECTS): the clips' loads compiled out
        // where there are none.
        let pipelines = [0.0, 1.0].map(|objects| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("energywave.upsample.upsample"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("upsample"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("OBJECTS", objects)],
                    ..Default::default()
                },
                cache: None,
            })
        });
        Self {
            pipelines,
            layout,
            bound: None,
            clips: [
                ClipBuffer::new(device, "energywave.upsample.clips"),
                ClipBuffer::new(device, "energywave.upsample.clips"),
            ],
        }
    }

    /// Records the upsampling of `source` (its view `source_view`) into the W x W output, `w` = `resolution`:
    /// its first `layers` layers (`field_pass::layers_of`), guided by both textures' `clips` where the scene
    /// has objects.
    pub fn encode(
        &mut self,
        gpu: super::pass::Gpu<'_>,
        encoder: &mut wgpu::CommandEncoder,
        (source, source_view): (&wgpu::Texture, &wgpu::TextureView),
        (resolution, layers): (u32, u32),
        clips: Option<UpsampleClips>,
    ) {
        let (device, queue) = (gpu.device, gpu.queue);
        let stale = self.bound.as_ref().is_none_or(|b| {
            &b.source != source
                || b.output.width() != resolution
                || b.output.depth_or_array_layers() != field_texture_layers(device, layers)
        });
        if stale {
            let (output, view) =
                field_texture(device, "energywave.upsample.output", resolution, layers);
            self.bound = Some(Bound {
                source: source.clone(),
                output,
                view,
            });
        }
        let objects = clips.is_some();
        if let Some(clips) = &clips {
            self.clips[0].upload(device, queue, &clips.source);
            self.clips[1].upload(device, queue, &clips.output);
        }
        let b = self.bound.as_ref().expect("bound above");
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
                    resource: wgpu::BindingResource::TextureView(&b.view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.clips[0].binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: self.clips[1].binding(),
                },
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.upsample.pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipelines[objects as usize]);
        pass.set_bind_group(0, &bind_group, &[]);
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
