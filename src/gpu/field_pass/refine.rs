//! The field refined in image space on the GPU (`shaders/refine.wgsl`; the plan is `frame::refine`'s): per level,
//! the texels are predicted and those to integrate listed, and the field pass dispatched indirectly over the list,
//! so that a texel kept as predicted costs nothing. The pipelines are the device's (`RefineShaders`, shared by
//! every field renderer on it); the buffers are each renderer's (`Refiner`).

use std::sync::{Arc, OnceLock};

use bytemuck::{Pod, Zeroable};

use super::super::context::{field_storage_entry, pass_layouts};
use super::super::shaders;
use crate::frame::refine::Levels;

/// `Level` in `shaders/refine.wgsl`: one level's settings.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Level {
    pub resolution: u32,   // 0
    pub layers: u32,       // 4
    pub level: u32,        // 8
    pub coarsest: u32,     // 12
    pub tolerance: f32,    // 16
    pub slot: u32,         // 20: the level's indirect arguments, in u32s
    pub measured_top: u32, // 24: 1 where the coarsest level's own detail decides the level below it
    pub pad1: u32,
}
const _: () = assert!(size_of::<Level>() == 32);

/// What a refined field's upload holds beside the sources: the detail threshold and the forced texels
/// (`frame::refine::forced_mask`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Refinement {
    pub(crate) tolerance: f32,
    pub(crate) levels: Levels,
    pub(crate) forced: Arc<Vec<u32>>,
}

/// The refine module's entry points, in the order `RefineShaders` keeps their pipelines.
const ENTRIES: [&str; 4] = ["begin", "mark", "arguments", "measure"];
const BEGIN: usize = 0;
const MARK: usize = 1;
const ARGUMENTS: usize = 2;
const MEASURE: usize = 3;

/// The parts a level's list is cut into (`PARTS` in refine.wgsl): the viewer integrates a fine level's over
/// several frames.
pub(super) const PARTS: u32 = 4;

/// u32s of the indirect arguments a level holds: x, y, z and the count of texels, for each part and the whole.
pub(super) const SLOT: u32 = 4 * (PARTS + 1);

/// u32s of the list's header (the count, its pad, the parts and the whole).
const LIST_HEADER: u64 = 4 + 4 * (PARTS as u64 + 1);

/// The refine pass's module, layouts and pipelines on a device (built when a refined field first records).
pub struct RefineShaders {
    device: wgpu::Device,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// `measure`'s, without the indirect arguments (binding 5): it is dispatched by them, and a buffer
    /// dispatched by may not be bound for writing in the same dispatch.
    measure_layout: wgpu::BindGroupLayout,
    measure_pipeline_layout: wgpu::PipelineLayout,
    module: OnceLock<wgpu::ShaderModule>,
    pipelines: [OnceLock<wgpu::ComputePipeline>; 4],
}

impl RefineShaders {
    pub fn new(device: &wgpu::Device) -> Self {
        let buffer = |binding, read_only, dynamic| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: dynamic,
                min_binding_size: None,
            },
            count: None,
        };
        let entries = [
            buffer(0, true, true),
            field_storage_entry(1, wgpu::StorageTextureAccess::ReadWrite),
            buffer(2, false, false),
            buffer(3, true, false),
            buffer(4, false, false),
            buffer(5, false, false),
        ];
        let (layout, pipeline_layout) = pass_layouts(device, "refine", &entries);
        let (measure_layout, measure_pipeline_layout) =
            pass_layouts(device, "refine.measure", &entries[..5]);
        Self {
            device: device.clone(),
            layout,
            pipeline_layout,
            measure_layout,
            measure_pipeline_layout,
            module: OnceLock::new(),
            pipelines: Default::default(),
        }
    }

    fn pipeline(&self, k: usize) -> &wgpu::ComputePipeline {
        self.pipelines[k].get_or_init(|| {
            let module = self.module.get_or_init(|| {
                (self.device).create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("energywave.refine"),
                    source: wgpu::ShaderSource::Wgsl(shaders::compose("refine.wgsl").into()),
                })
            });
            (self.device).create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&format!("energywave.refine.{}", ENTRIES[k])),
                layout: Some(match k {
                    MEASURE => &self.measure_pipeline_layout,
                    _ => &self.pipeline_layout,
                }),
                module,
                entry_point: Some(ENTRIES[k]),
                compilation_options: Default::default(),
                cache: None,
            })
        })
    }
}

/// One field renderer's refinement buffers: the levels' settings, the detail, the forced texels, the list (which
/// the field pass reads too) and the indirect arguments.
pub(super) struct Refiner {
    levels: wgpu::Buffer,
    level_stride: u64,
    detail: wgpu::Buffer,
    forced: wgpu::Buffer,
    pub(super) list: wgpu::Buffer,
    arguments: wgpu::Buffer,
    /// The bind groups of `begin`, `mark` and `arguments`, and of `measure`.
    group: Option<[wgpu::BindGroup; 2]>,
    /// The uploaded refinement's levels.
    uploaded: Option<Levels>,
}

fn buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    })
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_DST);

impl Refiner {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        let level_stride = (device.limits().min_storage_buffer_offset_alignment as u64)
            .max(size_of::<Level>() as u64);
        Self {
            levels: buffer(device, "energywave.refine.levels", level_stride, STORAGE),
            level_stride,
            detail: buffer(device, "energywave.refine.detail", 16, STORAGE),
            forced: buffer(device, "energywave.refine.forced", 16, STORAGE),
            // The header and a texel, rounded to the struct's 16-byte alignment: the field pass binds it whether
            // it refines or not.
            list: buffer(
                device,
                "energywave.refine.list",
                (LIST_HEADER + 4) * 4,
                STORAGE,
            ),
            arguments: buffer(
                device,
                "energywave.refine.arguments",
                16,
                STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC,
            ),
            group: None,
            uploaded: None,
        }
    }

    /// Uploads a list of texels made on the CPU (`x | y << 16`) as one part (part 0, and the whole), dispatched
    /// directly with `per_row` invocations a row (`texel_of` in shaders/shared/field_pass.wgsl); returns true
    /// where the list buffer was replaced (the field pass's bind group must be made again).
    pub(super) fn list_texels(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texels: &[u32],
        per_row: u32,
    ) -> bool {
        let n = texels.len() as u64;
        let size = ((LIST_HEADER + n.max(1)) * 4).next_multiple_of(16);
        let grown = grow(device, &mut self.list, "list", size, STORAGE);
        if grown {
            self.group = None;
        }
        let mut words = vec![0u32; LIST_HEADER as usize];
        words[0] = n as u32;
        let part = [0, n as u32, per_row, 0];
        words[4..8].copy_from_slice(&part);
        let whole = 4 + 4 * PARTS as usize;
        words[whole..whole + 4].copy_from_slice(&part);
        words.extend_from_slice(texels);
        queue.write_buffer(&self.list, 0, bytemuck::cast_slice(&words));
        grown
    }

    /// Uploads a refinement of a `layers`-layer texture; returns true where the list buffer was replaced (the
    /// field pass's bind group, which reads it, must be made again). The bind group of this pass is made again
    /// by `bind`.
    pub(super) fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        refinement: &Refinement,
        layers: u32,
    ) -> bool {
        let levels = refinement.levels;
        let w = levels.resolution as u64;
        let count = levels.coarsest as u64 + 1;
        let arguments = STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC;
        let grown = [
            grow(
                device,
                &mut self.levels,
                "levels",
                count * self.level_stride,
                STORAGE,
            ),
            grow(device, &mut self.detail, "detail", w * w * 4, STORAGE),
            grow(
                device,
                &mut self.forced,
                "forced",
                refinement.forced.len() as u64 * 4,
                STORAGE,
            ),
            grow(
                device,
                &mut self.arguments,
                "arguments",
                count * SLOT as u64 * 4,
                arguments,
            ),
        ];
        let size = ((LIST_HEADER + w * w) * 4).next_multiple_of(16);
        let list = grow(device, &mut self.list, "list", size, STORAGE);
        if list || grown.iter().any(|&g| g) {
            self.group = None;
        }
        let mut bytes = vec![0u8; (count * self.level_stride) as usize];
        for l in 0..=levels.coarsest {
            let level = Level {
                resolution: levels.resolution,
                layers,
                level: l,
                coarsest: levels.coarsest,
                tolerance: refinement.tolerance,
                slot: l * SLOT,
                measured_top: levels.measured_top as u32,
                ..Default::default()
            };
            let at = (l as u64 * self.level_stride) as usize;
            bytes[at..at + size_of::<Level>()].copy_from_slice(bytemuck::bytes_of(&level));
        }
        queue.write_buffer(&self.levels, 0, &bytes);
        queue.write_buffer(&self.forced, 0, bytemuck::cast_slice(&refinement.forced));
        // The counts of a level not recorded yet read as zero.
        queue.write_buffer(
            &self.arguments,
            0,
            &vec![0u8; (count * SLOT as u64 * 4) as usize],
        );
        self.uploaded = Some(levels);
        list
    }

    /// The bind group over the field texture `view`, made again where a buffer or the texture changed.
    pub(super) fn bind(
        &mut self,
        device: &wgpu::Device,
        shaders: &RefineShaders,
        view: &wgpu::TextureView,
    ) {
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let entries = [
            entry(
                0,
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &self.levels,
                    offset: 0,
                    size: wgpu::BufferSize::new(size_of::<Level>() as u64),
                }),
            ),
            entry(1, wgpu::BindingResource::TextureView(view)),
            entry(2, self.detail.as_entire_binding()),
            entry(3, self.forced.as_entire_binding()),
            entry(4, self.list.as_entire_binding()),
            entry(5, self.arguments.as_entire_binding()),
        ];
        let group = |layout, entries: &[wgpu::BindGroupEntry]| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("energywave.refine.bind_group"),
                layout,
                entries,
            })
        };
        self.group = Some([
            group(&shaders.layout, &entries),
            group(&shaders.measure_layout, &entries[..5]),
        ]);
    }

    pub(super) fn bound(&self) -> bool {
        self.group.is_some()
    }

    /// Records parts `parts` of level `l` (all: `0..PARTS`): with the first, its texels predicted and listed;
    /// each part's `integrate` (the field pass's dispatches, given the part, the indirect arguments' buffer and
    /// offset); with the last, the detail measured where a finer level reads it.
    pub(super) fn record_level(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        shaders: &RefineShaders,
        (l, parts): (u32, std::ops::Range<u32>),
        mut integrate: impl FnMut(&mut wgpu::ComputePass<'_>, u32, &wgpu::Buffer, u64),
    ) {
        let (Some([group, measure]), Some(levels)) = (&self.group, &self.uploaded) else {
            return;
        };
        let offset = (l as u64 * self.level_stride) as u32;
        let run = |pass: &mut wgpu::ComputePass<'_>, k: usize| {
            pass.set_pipeline(shaders.pipeline(k));
            let group = if k == MEASURE { measure } else { group };
            pass.set_bind_group(0, group, &[offset]);
        };
        if parts.start == 0 {
            run(pass, BEGIN);
            pass.dispatch_workgroups(1, 1, 1);
            run(pass, MARK);
            let side = levels.resolution.div_ceil(1 << l).div_ceil(8);
            pass.dispatch_workgroups(side, side, 1);
            run(pass, ARGUMENTS);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let at = |part: u32| ((l * SLOT + 4 * part) * 4) as u64;
        for part in parts.clone() {
            integrate(pass, part, &self.arguments, at(part));
        }
        if parts.end == PARTS && l > 0 && (l < levels.coarsest || levels.measured_top) {
            run(pass, MEASURE);
            pass.dispatch_workgroups_indirect(&self.arguments, at(PARTS));
        }
    }

    /// The arguments' buffer, whose slot of each level recorded holds the count of texels it integrated (the
    /// whole list's, u32 3 of the level's last four).
    pub(super) fn arguments(&self) -> &wgpu::Buffer {
        &self.arguments
    }

    pub(super) fn gpu_bytes(&self) -> u64 {
        [
            &self.levels,
            &self.detail,
            &self.forced,
            &self.list,
            &self.arguments,
        ]
        .iter()
        .map(|b| b.size())
        .sum()
    }
}

/// Makes `b` again with `size` bytes where it holds fewer; returns whether it did.
fn grow(
    device: &wgpu::Device,
    b: &mut wgpu::Buffer,
    name: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> bool {
    if b.size() >= size {
        return false;
    }
    *b = buffer(device, &format!("energywave.refine.{name}"), size, usage);
    true
}
