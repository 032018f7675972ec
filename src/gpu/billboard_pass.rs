//! The billboard pass: draws the billboard as a quad in 3D with `shaders/billboard.wgsl`, blending B over a
//! copy of what lies behind it.

use glam::DMat4;

use super::context::GpuError;
use super::context::{
    ClipBuffer, RenderPipelineSpec, depth_value_entry, fragment_storage_entry, pass_layouts,
    render_pipeline, uniform_buffer,
};
use super::pass::{FramePass, Recording, Stage};
use crate::frame::FrameSetup;
use crate::geometry::{Billboard, Camera};
use crate::scene::Blend;

/// Rust mirror of `BillboardParams` in `shaders/billboard.wgsl` (keep in sync; `tests/gpu_layout.rs` checks
/// it against naga's layout).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct BillboardParams {
        pub view_proj: [[f32; 4]; 4], // 0, column-major
        pub center: [f32; 3],         // 64
        pub size: f32,                // 76
        pub right: [f32; 3],          // 80
        pub resolution: u32,          // 92
        pub up: [f32; 3],             // 96
        pub mode: u32,                // 108: BlendMode
        pub energy: [f32; 4],         // 112
        pub near: f32,                // 128: the projection's depth range (`depth_range`)
        pub far: f32,                 // 132
        pub nu: f32,                  // 136: E = V + nu (S - V) (`geometry::Reach`)
        pub cutoff: f32,              // 140: the glow's edge (`scene::edge_fade`), 0 for none
        pub edge: f32, // 144: the band the glow fades over at the edges (`geometry::edge_window`)
        pub pad0: f32, // 148
        pub pad1: f32, // 152
        pub pad2: f32, // 156
    }
    const _: () = assert!(size_of::<BillboardParams>() == 160);
}

use gpu_data::BillboardParams;

/// The camera's view-projection matrix (right-handed, depth in [0, 1]) for a frame of `aspect`, with near and
/// far planes around the billboard (nothing else is drawn by this pass).
pub fn view_projection(camera: &Camera, billboard: &Billboard, aspect: f64) -> DMat4 {
    let (near, far) = depth_range(camera, billboard);
    let frame = camera.frame();
    let proj = DMat4::perspective_rh(camera.fov_y_degrees.to_radians(), aspect, near, far);
    proj * DMat4::look_at_rh(camera.eye, camera.eye + frame.forward, frame.up)
}

/// The near and far planes of `view_projection`.
pub fn depth_range(camera: &Camera, billboard: &Billboard) -> (f64, f64) {
    let distance = (billboard.center - camera.eye).length().max(1e-9);
    (1e-3 * distance, 1e3 * (distance + billboard.size))
}

/// What the billboard pass writes: the glow blended over the background, or the glow alone for compositing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlendMode {
    /// `clamp((1 - B) Cb + G)` (the papers'), G = sum B_i Ce_i.
    Papers = 0,
    /// Premultiplied G with alpha `min(B, 1)`, unclamped.
    Transparent = 1,
    /// `clamp(G + (1 - min(B, 1)) Cb)`.
    Over = 2,
}

/// Added to an opaque `BlendMode` in the pass's parameters: the blend is not clamped above 1 (below 0 still
/// is), for an HDR export of the opaque frame.
pub const UNCLAMPED: u32 = 4;

/// Added to an opaque `BlendMode`: the viewer's preview of the glare's threshold, the glow at or below it
/// (`energy.w`) dimmed to a quarter, so what glares stands out.
pub const THRESHOLD_PREVIEW: u32 = 8;

impl BlendMode {
    /// The transparent export, or the scene's blend.
    pub fn of(transparent: bool, blend: Blend) -> BlendMode {
        match (transparent, blend) {
            (true, _) => BlendMode::Transparent,
            (false, Blend::Papers) => BlendMode::Papers,
            (false, Blend::Over) => BlendMode::Over,
        }
    }
}

/// The pass's parameters for a frame of `setup` in a picture of `aspect`, showing a brightness of `resolution`
/// texels a side.
pub fn billboard_params(
    setup: &FrameSetup,
    resolution: u32,
    aspect: f64,
    mode: BlendMode,
) -> BillboardParams {
    let (camera, billboard) = (&setup.scene.camera, &setup.billboard);
    let energy = setup.scene.colors.energy_color();
    let (nu, cutoff) = (setup.reach.nu, setup.scene.colors.cutoff);
    let (near, far) = depth_range(camera, billboard);
    BillboardParams {
        near: near as f32,
        far: far as f32,
        nu: nu as f32,
        cutoff: cutoff as f32,
        edge: billboard.edge as f32,
        pad0: 0.0,
        pad1: 0.0,
        pad2: 0.0,
        view_proj: view_projection(camera, billboard, aspect)
            .as_mat4()
            .to_cols_array_2d(),
        center: billboard.center.as_vec3().to_array(),
        size: billboard.size as f32,
        right: billboard.right.as_vec3().to_array(),
        resolution,
        up: billboard.up.as_vec3().to_array(),
        mode: mode as u32,
        energy: [energy[0] as f32, energy[1] as f32, energy[2] as f32, 1.0],
    }
}

/// The pipeline of the billboard pass for one target format.
pub struct BillboardRenderer {
    /// B alone, and B with the tint (`field_pass::layers_of`); each without objects and with them.
    /// By the tint (B alone, with the tint) and the objects (none, some, some translucent: the shader's
    /// OBJECTS and THROUGH).
    pipelines: [[wgpu::RenderPipeline; 3]; 2],
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Each texel's share of its ray before the first surface (`objects::clip`), where the scene has objects.
    clips: ClipBuffer,
    /// What the next `record` draws: its bind group, and its pipeline's indices.
    pending: Option<(wgpu::BindGroup, [usize; 2])>,
}

impl BillboardRenderer {
    /// Builds the pipeline for render targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.billboard.shader"),
            source: wgpu::ShaderSource::Wgsl(super::shaders::BILLBOARD_PASS.into()),
        });
        let texture = |binding, view_dimension| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension,
                multisampled: false,
            },
            count: None,
        };
        let (layout, pipeline_layout) = pass_layouts(
            device,
            "billboard",
            &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<BillboardParams>() as u64),
                    },
                    count: None,
                },
                texture(1, wgpu::TextureViewDimension::D2Array),
                texture(2, wgpu::TextureViewDimension::D2),
                depth_value_entry(3),
                fragment_storage_entry(4),
            ],
        );
        // Two pipelines, B alone and B with the tint (the shader's TINTED): a branch on a uniform around the
        // tint's loads cost lavapipe 14 % of the billboard even where it is never taken (measured, a 4096^2
        // frame).
        let pipelines = [0.0, 1.0].map(|tinted| {
            [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)].map(|(objects, through)| {
                render_pipeline(
                    device,
                    RenderPipelineSpec {
                        name: "billboard",
                        module: &module,
                        layout: &pipeline_layout,
                        vertex_buffers: &[],
                        topology: wgpu::PrimitiveTopology::TriangleStrip,
                        fragment_entry: "fs_main",
                        constants: &[
                            ("TINTED", tinted),
                            ("OBJECTS", objects),
                            ("THROUGH", through),
                        ],
                        targets: &[Some(wgpu::ColorTargetState {
                            format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                        depth: None,
                    },
                )
            })
        });
        let params = uniform_buffer::<BillboardParams>(device, "energywave.billboard.params");
        Self {
            pipelines,
            layout,
            params,
            clips: ClipBuffer::new(device, "energywave.billboard.clips"),
            pending: None,
        }
    }
}

impl FramePass for BillboardRenderer {
    fn stages(&self) -> &'static [Stage] {
        &[Stage::Billboard]
    }

    /// The parameters, and a bind group reading the brightness, a copy of what lies behind the billboard (the
    /// frame's background target, copied into its color target by `record`) and, where objects were drawn,
    /// their depth and the clips of the texture it shows, up to the first surface of any object: a translucent
    /// one's edge guides the glow blended for it as an opaque one's edge guides the glow it ends.
    fn prepare(&mut self, _: Stage, r: &mut Recording<'_>) -> Result<(), GpuError> {
        let (device, queue) = (r.gpu.device, r.gpu.queue);
        let setup = r.frame.setup;
        let [w, h] = r.targets.size;
        let mode = BlendMode::of(r.look.transparent, setup.scene.colors.blend);
        let resolution = r.brightness.resolution;
        let mut params = billboard_params(setup, resolution, w as f64 / h as f64, mode);
        if r.look.unclamped {
            params.mode |= UNCLAMPED;
        }
        if let Some(threshold) = r.look.threshold_preview.filter(|_| !r.look.transparent) {
            params.mode |= THRESHOLD_PREVIEW;
            params.energy[3] = threshold as f32;
        }
        let clips = match r.objects {
            true => setup.surface_clips_at(resolution),
            false => None,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let objects = clips.is_some();
        if let Some(clips) = &clips {
            self.clips.upload(device, queue, clips);
        }
        let tex = wgpu::BindingResource::TextureView;
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.billboard.bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: tex(&r.brightness.view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: tex(&r.targets.background_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: tex(&r.targets.depth_value_view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: self.clips.binding(),
                },
            ],
        });
        let through = objects && r.brightness.undimmed;
        let pipeline = [
            (r.brightness.layers > 1) as usize,
            objects as usize + through as usize,
        ];
        self.pending = Some((bind_group, pipeline));
        Ok(())
    }

    /// Copies what lies behind the billboard, then blends the billboard over it.
    fn record(&mut self, _: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        let Some((bind_group, [layers, objects])) = self.pending.take() else {
            return;
        };
        let targets = r.targets;
        encoder.copy_texture_to_texture(
            targets.background.as_image_copy(),
            targets.color.as_image_copy(),
            targets.background.size(),
        );
        let mut pass =
            super::context::over(encoder, "energywave.billboard.pass", &targets.color_view);
        pass.set_pipeline(&self.pipelines[layers][objects]);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..4, 0..1);
    }
}
