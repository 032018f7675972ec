//! The running mean of jittered field frames (`shaders/average.wgsl`): while the view is still, the viewer
//! renders the jittered integrator again with new offsets and shows the mean of the frames so far, whose
//! noise falls as 1/sqrt(k) towards the converged picture (the jittered estimate is unbiased).

use super::context::{
    compute_pass, field_storage_entry, field_texture, loaded_field_entry, uniform_buffer,
};
use super::shaders;

/// Rust mirror of `AverageParams` in `shaders/average.wgsl` (keep in sync; `tests/gpu_layout.rs` checks it).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct AverageParams {
        pub weight: f32, // 0: 1 / k for the k-th frame
        pub pad0: f32,   // 4
        pub pad1: f32,   // 8
        pub pad2: f32,   // 12
    }
    const _: () = assert!(size_of::<AverageParams>() == 16);
}

use gpu_data::AverageParams;

/// The pipeline, the mean texture (a field texture, W x W) and its bind group over one field texture.
pub struct FrameAverage {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// The field texture bound, the mean texture, its view and the bind group over both.
    mean: Option<Bound>,
    /// The layers averaged (`field_pass::layers_of`).
    layers: u32,
}

struct Bound {
    frame: wgpu::Texture,
    mean: wgpu::Texture,
    view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
}

impl FrameAverage {
    pub fn new(device: &wgpu::Device) -> Self {
        let (pipeline, layout) = compute_pass(
            device,
            "average",
            shaders::AVERAGE_PASS,
            "average_frames",
            &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<AverageParams>() as u64),
                    },
                    count: None,
                },
                loaded_field_entry(1),
                field_storage_entry(2, wgpu::StorageTextureAccess::ReadWrite),
            ],
        );
        let params = uniform_buffer::<AverageParams>(device, "energywave.average.params");
        Self {
            pipeline,
            layout,
            params,
            mean: None,
            layers: 1,
        }
    }

    /// Makes the mean texture match `frame` (W x W) and sets the weight of the next `encode` to that of frame
    /// `k` (1-based): 1 / k, so the first frame overwrites the mean.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &wgpu::Texture,
        frame_view: &wgpu::TextureView,
        k: u32,
        layers: u32,
    ) {
        // Rebound when the field pass replaced its texture (a new resolution); otherwise only the weight changes.
        if self.mean.as_ref().is_none_or(|b| &b.frame != frame) {
            let (texture, view) = field_texture(
                device,
                "energywave.average.mean",
                frame.width(),
                frame.depth_or_array_layers(),
            );
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("energywave.average.bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(frame_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            self.mean = Some(Bound {
                frame: frame.clone(),
                mean: texture,
                view,
                bind_group,
            });
        }
        let params = AverageParams {
            weight: 1.0 / k.max(1) as f32,
            ..AverageParams::default()
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.layers = layers;
    }

    /// Records the dispatch that folds the field texture into the mean (after the field pass's dispatches).
    pub fn encode(&self, pass: &mut wgpu::ComputePass<'_>) {
        if let Some(b) = &self.mean {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &b.bind_group, &[]);
            // One layer a z: the tint's only where the scene has one.
            let (w, h) = (b.mean.width(), b.mean.height());
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), self.layers);
        }
    }

    /// The mean texture and its view (after the first `prepare`).
    pub fn mean(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        self.mean.as_ref().map(|b| (&b.mean, &b.view))
    }

    /// GPU memory held: the mean texture and the uniform, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        let texture = (self.mean.as_ref()).map_or(0, |b| {
            super::context::field_texture_bytes(b.mean.width(), b.mean.depth_or_array_layers())
        });
        texture + self.params.size()
    }
}
