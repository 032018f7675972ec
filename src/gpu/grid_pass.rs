//! The viewer's ground grid and axes: a line list drawn behind the glow, in the billboard pass's own frame
//! (`shaders/grid.wgsl`).

use super::context::GpuError;
use super::pass::{FramePass, Recording, Stage};
use wgpu::util::DeviceExt;

use super::context::{RenderPipelineSpec, pass_layouts, render_pipeline, uniform_buffer};
use super::formats::FRAME_FORMAT;
use super::shaders::GRID_PASS as GRID_SHADER;

/// Rust mirrors of `shaders/grid.wgsl` (keep in sync; `tests/gpu_layout.rs` checks them).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    /// `GridParams` in `shaders/grid.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GridParams {
        pub view_proj: [[f32; 4]; 4], // 0
    }
    const _: () = assert!(size_of::<GridParams>() == 64);

    /// One vertex of the grid's line list (vertex attributes 0 and 1 of `vs_main`).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GridVertex {
        pub position: [f32; 3], // 0
        pub color: [f32; 4],    // 12
    }
    const _: () = assert!(size_of::<GridVertex>() == 28);
}

use gpu_data::{GridParams, GridVertex};

/// The grid's pipeline and buffers.
pub struct GridPass {
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    count: u32,
    /// What `vertices` holds now.
    uploaded: Vec<GridVertex>,
}

impl GridPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.grid.shader"),
            source: wgpu::ShaderSource::Wgsl(GRID_SHADER.into()),
        });
        let (layout, pipeline_layout) = pass_layouts(
            device,
            "grid",
            &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(size_of::<GridParams>() as u64),
                },
                count: None,
            }],
        );
        let params = uniform_buffer::<GridParams>(device, "energywave.grid.params");
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.grid.bind_group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            }],
        });
        let pipeline = render_pipeline(
            device,
            RenderPipelineSpec {
                name: "grid",
                module: &module,
                layout: &pipeline_layout,
                vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: size_of::<GridVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
                })],
                topology: wgpu::PrimitiveTopology::LineList,
                fragment_entry: "fs_main",
                constants: &[],
                targets: &[Some(wgpu::ColorTargetState {
                    format: FRAME_FORMAT,
                    // Lines over the background; alpha stays 1 (the billboard copies it).
                    blend: Some(wgpu::BlendState {
                        color: wgpu::BlendComponent {
                            src_factor: wgpu::BlendFactor::SrcAlpha,
                            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                            operation: wgpu::BlendOperation::Add,
                        },
                        alpha: wgpu::BlendComponent {
                            src_factor: wgpu::BlendFactor::Zero,
                            dst_factor: wgpu::BlendFactor::One,
                            operation: wgpu::BlendOperation::Add,
                        },
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                depth: None,
            },
        );
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("energywave.grid.vertices"),
            contents: &[0; size_of::<GridVertex>() * 2],
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        Self {
            pipeline,
            params,
            bind_group,
            vertices,
            count: 0,
            uploaded: Vec::new(),
        }
    }

    /// Uploads the grid's vertices when they changed (none: nothing is drawn).
    pub fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        vertices: Vec<GridVertex>,
    ) {
        self.count = vertices.len() as u32;
        if vertices == self.uploaded {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(&vertices);
        if bytes.len() as u64 > self.vertices.size() {
            self.vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("energywave.grid.vertices"),
                contents: bytes,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            });
        } else if !bytes.is_empty() {
            queue.write_buffer(&self.vertices, 0, bytes);
        }
        self.uploaded = vertices;
    }

    /// Draws the uploaded lines into `pass` with the projection `view_proj` (written before the submit that
    /// runs the pass).
    fn draw(&self, queue: &wgpu::Queue, pass: &mut wgpu::RenderPass<'_>, view_proj: [[f32; 4]; 4]) {
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&GridParams { view_proj }),
        );
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..self.count, 0..1);
    }
}

impl FramePass for GridPass {
    /// Over the background, under the objects and the glow, which blends over it, with the frame's projection.
    fn stages(&self) -> &'static [Stage] {
        &[Stage::Behind]
    }

    fn prepare(&mut self, _: Stage, _: &mut Recording<'_>) -> Result<(), GpuError> {
        Ok(())
    }

    fn record(&mut self, _: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        if self.count == 0 {
            return;
        }
        let mut pass = super::context::over(encoder, "energywave.grid", &r.targets.background_view);
        self.draw(r.gpu.queue, &mut pass, r.view_proj);
    }
}
