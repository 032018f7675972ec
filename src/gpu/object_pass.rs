//! The scene's objects on the GPU: their triangles, with the albedo and shadow factor `objects::lighting` gave
//! their vertices, drawn with depth into what lies behind the billboard and shaded at every pixel by the sources,
//! which it holds as the field pass does (`shaders/objects.wgsl`). Lit again only when the objects, the sources
//! or their colors change: orbiting draws the same buffers.

use wgpu::util::DeviceExt;

use super::context::GpuError;
use super::context::{
    RenderPipelineSpec, fragment_storage_entry, pass_layouts, render_pipeline, uniform_buffer,
};
use super::field_pass::{SOURCE_BINDINGS, source_bindings, storage_buffer_init};
use super::formats::DEPTH_VALUE_CLEAR;
use super::formats::{DEPTH_FORMAT, DEPTH_VALUE_FORMAT, FRAME_FORMAT};
use super::pass::{FramePass, Recording, Stage};
use super::shaders::object_module_source;
use crate::frame::{Frame, FrameSetup};
use crate::objects::lighting::AMBIENT;
use crate::objects::{Lit, LitKey};
use crate::scene::Scene;
use std::sync::Arc;

/// Rust mirrors of `shaders/objects.wgsl` (keep in sync; `tests/gpu_layout.rs` checks them).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    /// `ObjectParams` in `shaders/objects.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct ObjectParams {
        pub view_proj: [[f32; 4]; 4], // 0
        pub energy: [f32; 3],         // 64
        pub ambient: f32,             // 76
        pub eye: [f32; 3],            // 80: the camera, for a translucent surface's exit Fresnel
        pub pad0: f32,                // 92
    }
    const _: () = assert!(size_of::<ObjectParams>() == 96);

    /// One vertex (attributes 0 to 6 of `vs_main`): world position, normal, albedo and the shadow factors of
    /// the light of positive and of negative sources (`objects::lighting::Shade::shadow`); on a translucent
    /// object, the light it scatters out and its index of refraction (0 on an opaque one).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct ObjectVertex {
        pub position: [f32; 3],    // 0
        pub normal: [f32; 3],      // 12
        pub albedo: [f32; 3],      // 24
        pub shadow: [f32; 3],      // 36
        pub shadow_dark: [f32; 3], // 48
        pub subsurface: [f32; 3],  // 60
        pub eta: f32,              // 72
    }
    const _: () = assert!(size_of::<ObjectVertex>() == 76);
}

use gpu_data::{ObjectParams, ObjectVertex};

/// How many sources of each kind a scene has: what the object pipelines are specialised to. The fragment shader
/// loops over the sources of every kind; the code of a kind the scene lacks is compiled away (the count 0), a
/// kind's loop of up to `UNROLLED` terms is unrolled (its count a constant), and the brightest-point search is
/// compiled in only where some curve reads it. Measured on lavapipe at 1280 x 720 on the floor preset (one
/// ring): the viewer's frame took 253 ms idle with every kind's code in, 123 ms without the code of the kinds
/// absent (112 ms without lighting at all); orbiting took 125 to 130 ms so, 104 to 112 ms with the ring's count
/// a constant too (80 to 87 ms when the objects were lit at their vertices). A new structure compiles its
/// pipelines when first drawn (55 to 90 ms there), then stays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Structure {
    points: u32,
    lines: u32,
    tori: u32,
    curves: u32,
    search: bool,
}

/// The most terms of a kind whose loop is unrolled; past it the count is read from the sources' params.
const UNROLLED: u32 = 8;

impl Structure {
    fn of(scene: &Scene) -> Structure {
        let s = &scene.sources;
        Structure {
            points: s.points.len() as u32,
            lines: s.lines.len() as u32,
            tori: s.tori.len() as u32,
            curves: s.curves.len() as u32,
            search: s.curves.iter().any(|c| c.searches()),
        }
    }

    /// The values of `shaders/shared/field_pass.wgsl`'s overridable constants: each kind's count up to `UNROLLED`
    /// (past it the default, which reads the count from the sources' params), the search.
    fn constants(self) -> Vec<(&'static str, f64)> {
        let counts = [
            ("POINT_COUNT", self.points),
            ("LINE_COUNT", self.lines),
            ("TORUS_COUNT", self.tori),
            ("CURVE_COUNT", self.curves),
        ];
        (counts.into_iter().filter(|&(_, n)| n <= UNROLLED))
            .map(|(name, n)| (name, n as f64))
            .chain([("SEARCH", self.search as u8 as f64)])
            .collect()
    }
}

/// The objects' pipelines and the buffers of the last scene's lit triangles and sources.
pub struct ObjectPass {
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// For each structure met so far, for the opaque triangles and for the translucent ones (`true`), each
    /// built when first drawn: color and depth; depth alone (a holdout). Each writes the depth's copy too (a
    /// translucent surface's with its lowest bit set: `shaders/objects.wgsl`); the opaque ones write it to the
    /// copy's second channel as well, which keeps the nearest opaque surface behind a translucent one.
    pipelines: std::collections::HashMap<(Structure, bool), [wgpu::RenderPipeline; 2]>,
    /// The structure of the scene last prepared.
    structure: Structure,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// The sources (`FieldParams`, then `SOURCE_BINDINGS`) and `params`, bound together.
    bind_group: Option<wgpu::BindGroup>,
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    count: u32,
    /// The indices of the opaque triangles, which come first (drawn before the translucent ones, so that the
    /// depth test leaves the nearest opaque surface in the depth copy's second channel).
    opaque: u32,
    /// The scene's energy color Ce, its intensity applied.
    energy: [f32; 3],
    /// What the buffers were lit from (`None` while they hold a stand-in).
    key: Option<LitKey>,
    /// The light the buffers hold.
    lit: Option<Arc<Lit>>,
}

/// `ObjectParams`' binding, after the field's.
const PARAMS_BINDING: u32 = 14;

impl ObjectPass {
    /// Builds the module and layouts; a pipeline is built when a scene first needs its structure.
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.objects.shader"),
            source: wgpu::ShaderSource::Wgsl(object_module_source().into()),
        });
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: PARAMS_BINDING,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(size_of::<ObjectParams>() as u64),
            },
            count: None,
        }];
        entries.push(fragment_storage_entry(0));
        entries.extend(SOURCE_BINDINGS.map(fragment_storage_entry));
        let (layout, pipeline_layout) = pass_layouts(device, "objects", &entries);
        let params = uniform_buffer::<ObjectParams>(device, "energywave.objects.params");
        Self {
            module,
            pipeline_layout,
            pipelines: Default::default(),
            structure: Structure {
                points: 0,
                lines: 0,
                tori: 0,
                curves: 0,
                search: false,
            },
            layout,
            params,
            bind_group: None,
            vertices: None,
            indices: None,
            count: 0,
            opaque: 0,
            energy: [0.0; 3],
            key: None,
            lit: None,
        }
    }

    /// The pipelines for `structure`'s opaque triangles (the depth to both of the copy's channels) or its
    /// translucent ones (to the first alone): color and depth, depth alone.
    fn build_pipelines(
        &self,
        device: &wgpu::Device,
        structure: Structure,
        translucent: bool,
    ) -> [wgpu::RenderPipeline; 2] {
        let depth_mask = match translucent {
            false => wgpu::ColorWrites::ALL,
            true => wgpu::ColorWrites::RED,
        };
        let constants = structure.constants();
        [wgpu::ColorWrites::ALL, wgpu::ColorWrites::empty()].map(|write_mask| {
            render_pipeline(
                device,
                RenderPipelineSpec {
                    name: "objects",
                    module: &self.module,
                    layout: &self.pipeline_layout,
                    vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<ObjectVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![
                            0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3,
                            4 => Float32x3, 5 => Float32x3, 6 => Float32
                        ],
                    })],
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    fragment_entry: "fs_main",
                    constants: &constants,
                    targets: &[
                        Some(wgpu::ColorTargetState {
                            format: FRAME_FORMAT,
                            blend: None,
                            write_mask,
                        }),
                        Some(wgpu::ColorTargetState {
                            format: DEPTH_VALUE_FORMAT,
                            blend: None,
                            write_mask: depth_mask,
                        }),
                    ],
                    depth: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                },
            )
        })
    }

    /// Uploads the frame's lit objects and its sources where they changed since the last call (the light of
    /// `frame.objects`, resolved by `frame::Resolver`: the same light again uploads nothing; a stand-in that
    /// keeps the light drawn before uploads the sources alone). Returns whether there is anything to draw.
    fn prepare_objects(&mut self, device: &wgpu::Device, frame: &Frame) -> bool {
        let (setup, scene) = (frame.setup, frame.setup.scene);
        let Some(objects) = &frame.objects else {
            self.count = 0;
            self.key = None;
            self.lit = None;
            return false;
        };
        if self.key.is_some() && self.key == objects.key {
            return self.count > 0;
        }
        self.structure = Structure::of(scene);
        match &self.lit {
            // The light drawn already, kept while the new one is worked out: the pixels shaded by the sources
            // of now.
            Some(drawn) if Arc::ptr_eq(drawn, &objects.lit) => self.upload_sources(device, setup),
            _ => self.upload(device, setup, &objects.lit),
        }
        // The pipelines the triangles take (a scene without translucent objects compiles none for them).
        for (translucent, any) in [(false, self.opaque > 0), (true, self.count > self.opaque)] {
            let key = (self.structure, translucent);
            if any && !self.pipelines.contains_key(&key) {
                let built = self.build_pipelines(device, self.structure, translucent);
                self.pipelines.insert(key, built);
            }
        }
        self.lit = Some(objects.lit.clone());
        self.key = objects.key.clone();
        self.count > 0
    }

    /// Uploads `lit` and the scene's sources (the shader shades each pixel by them).
    fn upload(&mut self, device: &wgpu::Device, setup: &FrameSetup, lit: &Lit) {
        let Lit { surface, light } = lit;
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let vertices: Vec<ObjectVertex> = (0..surface.positions.len())
            .map(|k| ObjectVertex {
                position: surface.positions[k].as_vec3().to_array(),
                normal: surface.normals[k].as_vec3().to_array(),
                albedo: f(light.albedo[k]),
                shadow: f(light.shadow[k][0]),
                shadow_dark: f(light.shadow[k][1]),
                subsurface: f(light.subsurface[k]),
                eta: light.eta[k] as f32,
            })
            .collect();
        self.vertices = Some(
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("energywave.objects.vertices"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
        );
        // The opaque triangles first (an object's vertices share its index of refraction, 0 for an opaque one).
        let (opaque, translucent): (Vec<&[u32]>, Vec<&[u32]>) = surface
            .indices
            .chunks_exact(3)
            .partition(|t| light.eta[t[0] as usize] <= 0.0);
        let indices: Vec<u32> = opaque
            .iter()
            .chain(&translucent)
            .flat_map(|t| t.iter().copied())
            .collect();
        self.indices = Some(
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("energywave.objects.indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
        );
        self.count = indices.len() as u32;
        self.opaque = 3 * opaque.len() as u32;
        self.upload_sources(device, setup);
    }

    /// Uploads the scene's sources and colors, which the shader shades each pixel by (and whose structure its
    /// pipeline is specialised to).
    fn upload_sources(&mut self, device: &wgpu::Device, setup: &FrameSetup) {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let (field_params, lists) = source_bindings(setup);
        let field_params = storage_buffer_init(
            device,
            "energywave.objects.field_params",
            bytemuck::bytes_of(&field_params),
        );
        let lists =
            lists.map(|bytes| storage_buffer_init(device, "energywave.objects.sources", &bytes));
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: PARAMS_BINDING,
                resource: self.params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 0,
                resource: field_params.as_entire_binding(),
            },
        ];
        entries.extend((SOURCE_BINDINGS.iter().zip(&lists)).map(|(&binding, b)| {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }));
        self.bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.objects.bind_group"),
            layout: &self.layout,
            entries: &entries,
        }));
        self.energy = f(setup.scene.colors.energy_color());
    }

    /// Draws the prepared triangles into `pass` (which has a `DEPTH_FORMAT` depth attachment, and a
    /// `DEPTH_VALUE_FORMAT` color attachment beside the frame's for the depth the billboard reads) with the
    /// projection `view_proj` (written before the submit that runs the pass): their colors and depth, or their
    /// depth alone where not `color`; `eye` is the camera's place.
    pub fn draw(
        &self,
        queue: &wgpu::Queue,
        pass: &mut wgpu::RenderPass<'_>,
        (view_proj, eye): ([[f32; 4]; 4], [f32; 3]),
        color: bool,
    ) {
        let (Some(vertices), Some(indices), Some(bind_group)) =
            (&self.vertices, &self.indices, &self.bind_group)
        else {
            return;
        };
        if self.count == 0 {
            return;
        }
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&ObjectParams {
                view_proj,
                energy: self.energy,
                ambient: AMBIENT as f32,
                eye,
                pad0: 0.0,
            }),
        );
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        // The opaque triangles, then the translucent ones (which leave the depth copy's second channel as the
        // opaque ones wrote it).
        for (translucent, range) in [(false, 0..self.opaque), (true, self.opaque..self.count)] {
            if let Some(pipelines) = self.pipelines.get(&(self.structure, translucent))
                && !range.is_empty()
            {
                pass.set_pipeline(&pipelines[!color as usize]);
                pass.draw_indexed(range, 0, 0..1);
            }
        }
    }
}

impl FramePass for ObjectPass {
    fn stages(&self) -> &'static [Stage] {
        &[Stage::Objects]
    }

    fn prepare(&mut self, _: Stage, r: &mut Recording<'_>) -> Result<(), GpuError> {
        r.objects = self.prepare_objects(r.gpu.device, r.frame);
        Ok(())
    }

    /// The objects with depth (a holdout: their depth alone), which the billboard reads to hide the glow in
    /// front of them pixel by pixel.
    fn record(&mut self, _: Stage, r: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        if !r.objects {
            return;
        }
        let targets = r.targets;
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
        let eye = r.frame.setup.eye().as_vec3().to_array();
        self.draw(r.gpu.queue, &mut pass, (r.view_proj, eye), !r.look.holdout);
    }
}
