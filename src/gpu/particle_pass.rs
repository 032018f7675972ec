//! Particle sets on the GPU (`shaders/particles.wgsl`, docs/METHOD.md section 9): the smoke's image by sheet-buffer
//! splatting, a compute pass over the pixels of the tiles that have particles, then laid over the frame's
//! background and objects before the glow, filtered. The particles and their light come from the frame
//! (`Frame::particles`, lit once per edit); the slices and each tile's particles from its camera
//! (`particles::view::SmokeView`), worked out again only when the view or the particles change. CPU twin:
//! `reference::particles::smoke_pixel`.

use std::sync::Arc;

use wgpu::util::DeviceExt;

use super::context::GpuError;
use super::context::{
    RenderPipelineSpec, compute_pass, filtered_texture_entry, filtering_sampler_entry,
    fragment_storage_entry, over, pass_layouts, render_pipeline, storage_buffer_entry,
};
use super::formats::FRAME_FORMAT;
use super::pass::{FramePass, Gpu, Recording, Stage};
use crate::frame::{Frame, FrameSetup};
use crate::objects::Lit;
use crate::objects::lighting::AMBIENT;
use crate::particles::light::LitParticles;
use crate::particles::view::{RING, SmokeView, TILE};

/// Rust mirrors of `shaders/particles.wgsl` (keep in sync; `tests/gpu_layout.rs` checks them).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    /// `SmokeParams` in `shaders/particles.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SmokeParams {
        pub eye: [f32; 3],
        pub tan_half: f32,
        pub forward: [f32; 3],
        pub aspect: f32,
        pub right: [f32; 3],
        pub near: f32,
        pub up: [f32; 3],
        pub width: f32,
        pub size: [u32; 2],
        pub tiles_x: u32,
        pub chunk: u32,
        pub frame: [u32; 2],
        pub objects: u32,
        pub pad0: u32,
        pub depth_near: f32,
        pub depth_far: f32,
        pub pad1: f32,
        pub pad2: f32,
        pub bb_center: [f32; 3],
        pub bb_size: f32,
        pub bb_right: [f32; 3],
        pub glass_w: u32,
        pub bb_up: [f32; 3],
        pub glass_offset: u32,
        pub bb_normal: [f32; 3],
        pub pad4: f32,
    }
    const _: () = assert!(size_of::<SmokeParams>() == 176);

    /// `SmokeParticle` in `shaders/particles.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SmokeParticle {
        pub position: [f32; 3],
        pub radius: f32,
        pub color: [f32; 3],
        pub density: f32,
        pub diag_r: [f32; 4],
        pub off_r: [f32; 4],
        pub diag_g: [f32; 4],
        pub off_g: [f32; 4],
        pub diag_b: [f32; 4],
        pub off_b: [f32; 4],
    }
    const _: () = assert!(size_of::<SmokeParticle>() == 128);

    /// `SmokeChunk` in `shaders/particles.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SmokeChunk {
        pub index: u32,
        pub last: u32,
        pub pad0: u32,
        pub pad1: u32,
    }
}

use gpu_data::{SmokeChunk, SmokeParams, SmokeParticle};

/// The most particles a tile takes in one dispatch: lavapipe stops an invocation's loops after 65535 iterations
/// in all, and a particle costs a pixel at most 2 `RING` + 1 (its slabs, and the slabs it closes).
pub const CHUNK: u32 = 960;
const _: () = assert!(CHUNK * (2 * RING + 1) + RING < 65535);

/// A pixel's state between dispatches, in vec4s (`STATE` in the shader): the smoke so far, what the glow covers of
/// it and loses of the glow (`reference::particles::SmokeLayers`), the marks, the open slabs, the light through
/// the slabs past a translucent surface.
const STATE: u64 = 4 + RING as u64;

/// The format of the images the draw passes filter: their light and coverage.
const IMAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The splatting and compositing pipelines, and the last frame's buffers.
pub struct ParticlePass {
    splat: wgpu::ComputePipeline,
    splat_layout: wgpu::BindGroupLayout,
    /// The front image over the glow, the back image under it.
    draw: [wgpu::RenderPipeline; 2],
    draw_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// One `SmokeChunk` every `chunk_stride` bytes, bound at a dynamic offset.
    chunks: wgpu::Buffer,
    chunk_stride: u64,
    /// Bilinear between the smoke image's pixel centers, clamped at its edges.
    sampler: wgpu::Sampler,
    prepared: Option<Prepared>,
    /// Whether the frame being recorded has smoke.
    smoke: bool,
    /// What the smoke image in the prepared textures was splatted for: the plan (cleared where it is made anew)
    /// and the objects whose depth ended its rays (their light's `Arc`, new whenever they change). A frame for
    /// the same splats nothing and lays the same image over the frame again (the viewer's still frames: the
    /// field's bands refining, the UI).
    splatted: Option<Option<Arc<Lit>>>,
    /// Whether the frame being recorded splats.
    pending: bool,
}

/// A smoke image read back: per pixel, rows from the top, the front and the back image's (radiance,
/// transmittance); with the plan it was made by.
pub type SmokeReadback = (Vec<[[f32; 4]; 2]>, SmokeView);

/// What a frame's plan depends on besides its particles: the view, the image's size, the slices' width, and
/// what places the glow along the rays.
#[derive(Clone, Debug, PartialEq)]
struct ViewKey {
    camera: crate::geometry::Camera,
    frame: [u32; 2],
    resolution: u32,
    slice_width: f64,
    billboard: crate::geometry::Billboard,
    nu: f64,
    decay: (f64, f64),
}

impl ViewKey {
    fn of(setup: &FrameSetup, frame: [u32; 2], resolution: u32) -> ViewKey {
        ViewKey {
            camera: setup.scene.camera.clone(),
            frame,
            resolution,
            slice_width: setup.scene.slice_width,
            billboard: setup.billboard,
            nu: setup.reach.nu,
            decay: (setup.integration.alpha, setup.integration.beta),
        }
    }
}

/// What the frame last prepared holds.
struct Prepared {
    lit: Arc<LitParticles>,
    key: ViewKey,
    view: SmokeView,
    particles: wgpu::Buffer,
    balls: wgpu::Buffer,
    entries: wgpu::Buffer,
    work: wgpu::Buffer,
    /// Where the glow lies along the glow cells' corners' rays, then the field texels' crossings of the
    /// translucent objects (`glass`), a vec4 each.
    glow: wgpu::Buffer,
    /// The crossings (`FrameSetup::crossings_at` at the plan's resolution), none without translucent objects.
    glass: Option<Arc<Vec<f32>>>,
    state: wgpu::Buffer,
    /// The front and back images, two a pixel, in f32 (read back by `read_image`).
    image: wgpu::Buffer,
    /// The same as the draw passes filter them: front, back.
    textures: [wgpu::Texture; 2],
    /// The tiles with particles, the busiest first (`SmokeView::tile_lists`).
    tiles: Vec<u32>,
    /// How many tiles each dispatch takes: those with more particles than the dispatches before took.
    groups: Vec<u32>,
    /// The frame's pixels the smoke may cover: (x, y, width, height), the tiles' box and a pixel of the image
    /// around it.
    scissor: [u32; 4],
    draw_group: wgpu::BindGroup,
}

impl ParticlePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let source = super::shaders::compose("particles.wgsl");
        let uniform = |binding, visibility, dynamic| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: None,
            },
            count: None,
        };
        let compute = wgpu::ShaderStages::COMPUTE;
        let written = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: compute,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: IMAGE_FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        };
        let read_write = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: compute,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let splat_entries = [
            // A storage buffer, not a uniform: lavapipe compiles a shader anew for every value of a uniform that
            // bounds a loop, and the slabs a pixel's loop crosses follow the view's (3 s a moved view).
            storage_buffer_entry(0),
            storage_buffer_entry(1),
            storage_buffer_entry(2),
            storage_buffer_entry(3),
            storage_buffer_entry(8),
            storage_buffer_entry(9),
            read_write(4),
            read_write(10),
            written(11),
            written(12),
            wgpu::BindGroupLayoutEntry {
                binding: 5,
                visibility: compute,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            uniform(6, compute, true),
        ];
        let (splat, splat_layout) =
            compute_pass(device, "particles.splat", &source, "splat", &splat_entries);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.particles.draw.shader"),
            source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
        });
        let (draw_layout, pipeline_layout) = pass_layouts(
            device,
            "particles.draw",
            &[
                fragment_storage_entry(0),
                filtered_texture_entry(13),
                filtered_texture_entry(14),
                filtering_sampler_entry(15),
            ],
        );
        let draw = ["fs_front", "fs_back"].map(|fragment_entry| {
            render_pipeline(
                device,
                RenderPipelineSpec {
                    name: "particles.draw",
                    module: &module,
                    layout: &pipeline_layout,
                    vertex_buffers: &[],
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    fragment_entry,
                    constants: &[],
                    targets: &[Some(wgpu::ColorTargetState {
                        format: FRAME_FORMAT,
                        blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    depth: None,
                },
            )
        });
        let chunk_stride = (device.limits().min_uniform_buffer_offset_alignment as u64)
            .max(size_of::<SmokeChunk>() as u64);
        Self {
            splat,
            splat_layout,
            draw,
            draw_layout,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("energywave.particles.params"),
                size: size_of::<SmokeParams>() as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            chunks: chunk_buffer(device, chunk_stride, 1),
            chunk_stride,
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("energywave.particles.sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            prepared: None,
            smoke: false,
            splatted: None,
            pending: false,
        }
    }

    /// Uploads the frame's particles (`Frame::particles`) and plans its segments for a frame of `frame` pixels
    /// over a field of `resolution` texels a side (`FrameSetup::smoke_view`), where the particles, the view or
    /// the size changed; `objects`: whether the objects' depth was drawn this frame. Returns whether there is
    /// smoke to draw.
    fn prepare_smoke(
        &mut self,
        gpu: Gpu<'_>,
        data: &Frame,
        (frame, resolution): ([u32; 2], u32),
        objects: bool,
    ) -> bool {
        let (device, queue, setup) = (gpu.device, gpu.queue, data.setup);
        let Some(lit) = data.particles.clone() else {
            self.prepared = None;
            self.splatted = None;
            return false;
        };
        let key = ViewKey::of(setup, frame, resolution);
        // The smoke past a translucent surface is dimmed by the light its field texel keeps through the objects.
        let glass = setup.crossings_at(resolution);
        let same_glass = |p: &Prepared| match (&p.glass, &glass) {
            (None, None) => true,
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        if let Some(p) = &self.prepared
            && Arc::ptr_eq(&p.lit, &lit)
            && p.key == key
            && same_glass(p)
        {
            self.write_params(queue, setup, frame, objects);
            return true;
        }
        let view = setup.smoke_view(&lit.particles, frame, resolution);
        let size = view.size;
        let (entries, work) = view.tile_lists(&lit.particles);
        // Dispatch i takes the tiles with more than i CHUNK particles: the first ones, the busiest first.
        let busiest = work.first().map_or(0, |w| w[2] - w[1]);
        let groups: Vec<u32> = (0..busiest.div_ceil(CHUNK).max(1))
            .map(|i| work.partition_point(|w| w[2] - w[1] > i * CHUNK) as u32)
            .collect();
        if self.chunks.size() < groups.len() as u64 * self.chunk_stride {
            self.chunks = chunk_buffer(device, self.chunk_stride, groups.len() as u32);
        }
        for i in 0..groups.len() {
            let c = SmokeChunk {
                index: i as u32,
                last: (i + 1 == groups.len()) as u32,
                ..Default::default()
            };
            queue.write_buffer(
                &self.chunks,
                i as u64 * self.chunk_stride,
                bytemuck::bytes_of(&c),
            );
        }
        let same_particles = self
            .prepared
            .as_ref()
            .is_some_and(|p| Arc::ptr_eq(&p.lit, &lit));
        let (particles, balls, textures) = match self.prepared.take() {
            Some(p) if same_particles && p.view.size == size => (p.particles, p.balls, p.textures),
            p => {
                let (particles, balls) = match p {
                    Some(p) if same_particles => (p.particles, p.balls),
                    _ => {
                        let balls: Vec<[f32; 4]> = (lit.particles.iter())
                            .map(|p| {
                                let c = p.position.as_vec3();
                                [c.x, c.y, c.z, p.radius as f32]
                            })
                            .collect();
                        (
                            storage(
                                device,
                                "particles",
                                bytemuck::cast_slice(&gpu_particles(&lit)),
                            ),
                            storage(device, "balls", bytemuck::cast_slice(&balls)),
                        )
                    }
                };
                let textures = ["front", "back"].map(|name| {
                    device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(&format!("energywave.particles.{name}")),
                        size: wgpu::Extent3d {
                            width: size[0],
                            height: size[1],
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: IMAGE_FORMAT,
                        usage: wgpu::TextureUsages::STORAGE_BINDING
                            | wgpu::TextureUsages::TEXTURE_BINDING
                            | wgpu::TextureUsages::RENDER_ATTACHMENT,
                        view_formats: &[],
                    })
                });
                (particles, balls, textures)
            }
        };
        let tiles: Vec<u32> = work.iter().map(|w| w[0]).collect();
        let work: Vec<[u32; 4]> = work.iter().map(|&[t, a, b]| [t, a, b, 0]).collect();
        let entries = storage(device, "entries", bytemuck::cast_slice(&entries));
        let work = storage(device, "work", bytemuck::cast_slice(&work));
        let mut glow = view.glow.clone();
        if let Some(x) = &glass {
            glow.extend(x.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 0.0]));
        }
        let glow = storage(device, "glow", bytemuck::cast_slice(&glow));
        // The tiles a second dispatch takes carry their pixels' state.
        let carried = groups.get(1).copied().unwrap_or(0).max(1) as u64;
        let state = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.particles.state"),
            size: 16 * STATE * (TILE * TILE) as u64 * carried,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let image = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.particles.image"),
            size: 32 * (size[0] as u64 * size[1] as u64),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let scissor = scissor(&view, &tiles, frame);
        let views = textures
            .each_ref()
            .map(|t| t.create_view(&Default::default()));
        let draw_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.particles.draw.bind_group"),
            layout: &self.draw_layout,
            entries: &[
                entry(0, self.params.as_entire_binding()),
                entry(13, wgpu::BindingResource::TextureView(&views[0])),
                entry(14, wgpu::BindingResource::TextureView(&views[1])),
                entry(15, wgpu::BindingResource::Sampler(&self.sampler)),
            ],
        });
        self.splatted = None;
        self.prepared = Some(Prepared {
            lit,
            key,
            view,
            particles,
            balls,
            entries,
            work,
            glow,
            glass,
            state,
            image,
            textures,
            tiles,
            groups,
            scissor,
            draw_group,
        });
        self.write_params(queue, setup, frame, objects);
        true
    }

    /// `objects`: whether the objects' depth was drawn this frame (it ends the rays).
    fn write_params(
        &self,
        queue: &wgpu::Queue,
        setup: &FrameSetup,
        frame: [u32; 2],
        objects: bool,
    ) {
        let Some(p) = &self.prepared else {
            return;
        };
        let camera = &setup.scene.camera;
        let f = camera.frame();
        let v = |x: glam::DVec3| x.as_vec3().to_array();
        let (depth_near, depth_far) = super::billboard_pass::depth_range(camera, &setup.billboard);
        let b = &setup.billboard;
        let glass_w = p
            .glass
            .as_ref()
            .map_or(0, |x| ((x.len() / 3) as f64).sqrt().round() as u32);
        let params = SmokeParams {
            eye: v(camera.eye),
            tan_half: camera.tan_half_fov() as f32,
            forward: v(f.forward),
            aspect: frame[0] as f32 / frame[1] as f32,
            right: v(f.right),
            near: p.view.slicing.near as f32,
            up: v(f.up),
            width: p.view.slicing.width as f32,
            size: p.view.size,
            tiles_x: p.view.tiles()[0],
            chunk: CHUNK,
            frame,
            objects: objects as u32,
            depth_near: depth_near as f32,
            depth_far: depth_far as f32,
            bb_center: v(b.center),
            bb_size: b.size as f32,
            bb_right: v(b.right),
            glass_w,
            bb_up: v(b.up),
            glass_offset: (p.view.glow.len() / 4) as u32,
            bb_normal: v(b.normal),
            ..Default::default()
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }

    /// Records the splatting: the smoke's image of the prepared frame, its rays ended by the objects' depth
    /// (`depth_value`, read where the scene has objects).
    fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        depth_value: &wgpu::TextureView,
    ) {
        let Some(p) = &self.prepared else {
            return;
        };
        // The images start as none: the tiles without particles are not dispatched.
        let views = p
            .textures
            .each_ref()
            .map(|t| t.create_view(&Default::default()));
        let cleared = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("energywave.particles.clear"),
            color_attachments: &[cleared(&views[0]), cleared(&views[1])],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        }));
        if p.tiles.is_empty() {
            return;
        }
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.particles.splat.bind_group"),
            layout: &self.splat_layout,
            entries: &[
                entry(0, self.params.as_entire_binding()),
                entry(1, p.particles.as_entire_binding()),
                entry(2, p.entries.as_entire_binding()),
                entry(3, p.work.as_entire_binding()),
                entry(10, p.image.as_entire_binding()),
                entry(11, wgpu::BindingResource::TextureView(&views[0])),
                entry(12, wgpu::BindingResource::TextureView(&views[1])),
                entry(8, p.glow.as_entire_binding()),
                entry(9, p.balls.as_entire_binding()),
                entry(4, p.state.as_entire_binding()),
                entry(5, wgpu::BindingResource::TextureView(depth_value)),
                entry(
                    6,
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.chunks,
                        offset: 0,
                        size: wgpu::BufferSize::new(size_of::<SmokeChunk>() as u64),
                    }),
                ),
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.particles.splat"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.splat);
        for (i, &groups) in p.groups.iter().enumerate() {
            pass.set_bind_group(0, &group, &[(i as u64 * self.chunk_stride) as u32]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
    }

    /// Lays the smoke's front image (over the glow) or its back image (under it) over what `pass` draws
    /// into (premultiplied: its light, plus what lies behind times its transmittance).
    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, front: bool) {
        if let Some(p) = &self.prepared
            && !p.tiles.is_empty()
        {
            let [x, y, w, h] = p.scissor;
            pass.set_scissor_rect(x, y, w, h);
            pass.set_pipeline(&self.draw[!front as usize]);
            pass.set_bind_group(0, &p.draw_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }

    /// Has the next frame splat the smoke again even where nothing it depends on changed (a benchmark's frame
    /// of the same view, timed as a moved view's).
    pub fn splat_again(&mut self) {
        self.splatted = None;
    }

    /// The last frame's smoke image read back (waits for the GPU): per pixel, rows from the top, the front and
    /// the back image's (radiance, transmittance); with the plan it was made by.
    pub fn read_image(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<SmokeReadback>, super::context::GpuError> {
        let Some(p) = &self.prepared else {
            return Ok(None);
        };
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.particles.readback"),
            size: p.image.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&p.image, 0, &staging, 0, p.image.size());
        queue.submit([encoder.finish()]);
        let bytes = super::context::map_read(device, &staging)?;
        let floats: &[f32] = bytemuck::cast_slice(&bytes);
        let mut pixels: Vec<[[f32; 4]; 2]> = floats
            .chunks_exact(8)
            .map(|c| [[c[0], c[1], c[2], c[3]], [c[4], c[5], c[6], c[7]]])
            .collect();
        // The pixels of the tiles not dispatched hold no smoke.
        let none = [[0.0, 0.0, 0.0, 1.0]; 2];
        let mut dispatched = vec![false; p.view.tiles().iter().product::<u32>() as usize];
        for &t in &p.tiles {
            dispatched[t as usize] = true;
        }
        let [w, _] = p.view.size;
        let tiles_x = p.view.tiles()[0];
        for (k, pixel) in pixels.iter_mut().enumerate() {
            let (x, y) = (k as u32 % w, k as u32 / w);
            if !dispatched[((y / TILE) * tiles_x + x / TILE) as usize] {
                *pixel = none;
            }
        }
        Ok(Some((pixels, p.view.clone())))
    }
}

impl FramePass for ParticlePass {
    /// The smoke's back image (what the glow covers of it) over the background and the objects, its rays ended
    /// by the objects; its front image over the glow.
    fn stages(&self) -> &'static [Stage] {
        &[Stage::SmokeBehind, Stage::SmokeInFront]
    }

    fn prepare(&mut self, stage: Stage, r: &mut Recording<'_>) -> Result<(), GpuError> {
        if stage == Stage::SmokeBehind {
            let (size, resolution) = (r.targets.size, r.brightness.resolution);
            self.smoke = self.prepare_smoke(r.gpu, r.frame, (size, resolution), r.objects);
            let objects = r.frame.objects.as_ref().map(|o| o.lit.clone());
            let same = |seen: &Option<Arc<Lit>>| match (seen, &objects) {
                (None, None) => true,
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                _ => false,
            };
            if !self.splatted.as_ref().is_some_and(same) {
                self.splatted = None;
            }
            self.pending = self.smoke && self.splatted.is_none();
            if self.pending {
                self.splatted = Some(objects);
            }
        }
        Ok(())
    }

    fn record(&mut self, stage: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        if !self.smoke {
            return;
        }
        let targets = r.targets;
        match stage {
            Stage::SmokeBehind => {
                if self.pending {
                    self.encode(r.gpu.device, encoder, &targets.depth_value_view);
                }
                let mut pass = over(
                    encoder,
                    "energywave.frame.particles",
                    &targets.background_view,
                );
                self.draw(&mut pass, false);
            }
            _ => {
                let mut pass = over(
                    encoder,
                    "energywave.frame.particles.front",
                    &targets.color_view,
                );
                self.draw(&mut pass, true);
            }
        }
    }
}

/// The frame's pixels that the smoke of `tiles` may cover, as a scissor rectangle: their box in the smoke image
/// and a pixel of it around (the filter reaches that far), in frame pixels.
fn scissor(view: &SmokeView, tiles: &[u32], frame: [u32; 2]) -> [u32; 4] {
    let tiles_x = view.tiles()[0];
    let (mut lo, mut hi) = ([u32::MAX; 2], [0u32; 2]);
    for &t in tiles {
        let at = [t % tiles_x, t / tiles_x];
        for k in 0..2 {
            lo[k] = lo[k].min(at[k] * TILE);
            hi[k] = hi[k].max((at[k] + 1) * TILE);
        }
    }
    if tiles.is_empty() {
        return [0, 0, 0, 0];
    }
    // Smoke pixel i covers frame pixels [i, i + 1) frame / size.
    let to_frame = |v: u32, k: usize, up: bool| {
        let x = v as u64 * frame[k] as u64;
        let n = view.size[k] as u64;
        (if up { x.div_ceil(n) } else { x / n }).min(frame[k] as u64) as u32
    };
    let x0 = to_frame(lo[0].saturating_sub(1), 0, false);
    let y0 = to_frame(lo[1].saturating_sub(1), 1, false);
    let x1 = to_frame(hi[0] + 1, 0, true);
    let y1 = to_frame(hi[1] + 1, 1, true);
    [x0, y0, x1 - x0, y1 - y0]
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

fn storage(device: &wgpu::Device, name: &str, bytes: &[u8]) -> wgpu::Buffer {
    // An empty list still binds: a buffer of one word.
    let bytes = if bytes.is_empty() {
        &[0u8; 8][..]
    } else {
        bytes
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(&format!("energywave.particles.{name}")),
        contents: bytes,
        usage: wgpu::BufferUsages::STORAGE,
    })
}

fn chunk_buffer(device: &wgpu::Device, stride: u64, count: u32) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("energywave.particles.chunks"),
        size: stride * count.max(1) as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The particles as the shader reads them, each channel's isotropic part (the ambient share in it) in its
/// diagonal's w, its emission in its off-diagonal's w.
fn gpu_particles(lit: &LitParticles) -> Vec<SmokeParticle> {
    let f = |x: f64| x as f32;
    (lit.particles.iter().zip(&lit.lights))
        .map(|(p, l)| {
            // The diagonal, and the isotropic part with the ambient share in w.
            let diag = |c: usize| {
                [
                    f(l.m[c][0]),
                    f(l.m[c][1]),
                    f(l.m[c][2]),
                    f(AMBIENT + l.iso[c]),
                ]
            };
            let off = |c: usize| [f(l.m[c][3]), f(l.m[c][4]), f(l.m[c][5]), f(p.emission[c])];
            SmokeParticle {
                position: p.position.as_vec3().to_array(),
                radius: f(p.radius),
                color: p.color.map(f),
                density: f(p.density),
                diag_r: diag(0),
                off_r: off(0),
                diag_g: diag(1),
                off_g: off(1),
                diag_b: diag(2),
                off_b: off(2),
            }
        })
        .collect()
}
