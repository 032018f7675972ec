//! The field pass's storage buffers and pipelines: the generic ones, and those specialised to a scene's
//! structure, compiled on a thread of their own.

use super::super::context::{field_storage_entry, pass_layouts, storage_buffer_entry};
use super::super::shaders;
use crate::frame::FrameSetup;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use super::gpu_data::*;
use super::pack::*;

/// A storage buffer that grows as needed (never empty: WebGPU refuses zero-sized bindings).
pub(super) struct StorageBuffer {
    pub(super) label: &'static str,
    pub(super) buffer: wgpu::Buffer,
}

impl StorageBuffer {
    pub(super) fn new(device: &wgpu::Device, label: &'static str, bytes: &[u8]) -> Self {
        Self {
            label,
            buffer: storage_buffer_init(device, label, bytes),
        }
    }

    /// Writes `bytes`; returns true when the buffer had to be replaced (the bind group must be rebuilt).
    pub(super) fn write(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        bytes: &[u8],
    ) -> bool {
        if bytes.len() as u64 > self.buffer.size() {
            *self = Self::new(device, self.label, bytes);
            true
        } else {
            if !bytes.is_empty() {
                queue.write_buffer(&self.buffer, 0, bytes);
            }
            false
        }
    }
}

/// The scene's structure a specialised pipeline is compiled for: the values of `shaders/shared/field_pass.wgsl`'s
/// pipeline-overridable constants (source counts per kind, the Gauss-Kronrod order, jitter). Values (positions,
/// coefficients, the camera) stay in storage buffers, so editing them never compiles anything.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Structure {
    /// `FieldParams::integrator`: 0 simpson (whose structure has no Gauss order), 1 adaptive (no jitter).
    pub integrator: u32,
    pub points: u32,
    pub lines: u32,
    pub tori: u32,
    pub curves: u32,
    pub gauss_order: u32,
    pub jitter: u32,
    /// Which curves' terms read their brightest point (`FieldParams::search`: none, some, every one).
    pub search: u32,
}

impl Structure {
    pub(super) fn of(params: &FieldParams) -> Self {
        let simpson = params.integrator == 0;
        Self {
            integrator: params.integrator,
            points: params.point_count,
            lines: params.line_count,
            tori: params.torus_count,
            curves: params.curve_count,
            gauss_order: if simpson { 0 } else { params.gauss_order },
            jitter: if simpson { params.jitter } else { 0 },
            search: params.search,
        }
    }

    /// The entry points this structure's integrator dispatches (indices of `Pipelines`).
    pub(super) fn entries(&self) -> &'static [usize] {
        if self.integrator == 0 { &[0] } else { &[1, 2] }
    }

    /// The structure of a frame's field pass.
    pub fn of_frame(setup: &FrameSetup) -> Self {
        Self::of(&pack(setup).params)
    }

    pub(super) fn constants(&self) -> [(&'static str, f64); 7] {
        [
            ("POINT_COUNT", self.points as f64),
            ("LINE_COUNT", self.lines as f64),
            ("TORUS_COUNT", self.tori as f64),
            ("CURVE_COUNT", self.curves as f64),
            ("GAUSS_ORDER", self.gauss_order as f64),
            ("JITTER", self.jitter as f64),
            ("SEARCH", self.search as f64),
        ]
    }
}

/// When the field pass uses pipelines specialised to the scene's structure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Specialise {
    /// Never: the generic pipelines only (the default: a single still render would spend more on the compile,
    /// about 0.3 s on lavapipe, than it saves).
    #[default]
    Off,
    /// Compile a structure's pipelines on a thread of their own the first time it is drawn, and use the generic
    /// ones until they are ready: no frame waits on a compile.
    Background,
    /// Use a structure's pipelines if they are ready, and compile only when asked (`compile_in_background`):
    /// the viewer compiles while it is idle, so that a compile never takes a core from its frames.
    IfReady,
    /// Compile them before the first dispatch that needs them (renders and exports of many frames).
    Blocking,
}

/// The three passes' modules (simpson, adaptive smooth sources, adaptive curves: `shaders::FIELD_PASSES`),
/// indexed by `Chunk::pipeline`; each holds its one entry point.
pub(super) type Modules = [wgpu::ShaderModule; 3];
/// A structure's specialised pipelines: only its integrator's entry points.
pub(super) type SpecialisedSet = [Option<wgpu::ComputePipeline>; 3];

pub(super) fn build_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let specialised = match constants {
        [] => "",
        [("SEARCH", _)] => ".search",
        _ => ".specialised",
    };
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(&format!("energywave.field.{entry}{specialised}")),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// The pipelines of `structure`'s entry points, specialised to it.
fn build_specialised(shaders: &FieldShaders, structure: Structure) -> SpecialisedSet {
    let constants = structure.constants();
    let mut set: SpecialisedSet = Default::default();
    for &k in structure.entries() {
        set[k] = Some(build_pipeline(
            &shaders.device,
            &shaders.modules[k],
            &shaders.pipeline_layout,
            shaders::FIELD_PASSES[k].0,
            &constants,
        ));
    }
    set
}

/// Where a compile's thread leaves its pipelines and how long they took (milliseconds).
pub(super) type CompileSlot = std::sync::Arc<std::sync::Mutex<Option<(SpecialisedSet, f64)>>>;

/// Most structures whose specialised pipelines are kept (the least recently drawn go first): a compiled
/// structure holds about 20 MB of the driver's memory on lavapipe, and an editing session may pass through
/// many structures.
pub(super) const KEPT_STRUCTURES: usize = 4;

/// The specialised pipelines: those ready (most recently drawn first), and the one compile under way.
#[derive(Default)]
pub(super) struct SpecialisedPipelines {
    pub(super) ready: Vec<(Structure, std::sync::Arc<SpecialisedSet>)>,
    /// One compile at a time, on its own thread: a burst of structure changes compiles only what is still
    /// drawn when the compile before it has finished.
    pub(super) compiling: Option<(Structure, CompileSlot)>,
    /// Milliseconds each structure took to compile, in the order they finished.
    pub(super) compile_ms: Vec<(Structure, f64)>,
}

impl SpecialisedPipelines {
    /// The pipelines of `structure` if ready, marked as the most recently drawn.
    pub(super) fn take(&mut self, structure: &Structure) -> Option<std::sync::Arc<SpecialisedSet>> {
        let k = self.ready.iter().position(|(s, _)| s == structure)?;
        let entry = self.ready.remove(k);
        let p = entry.1.clone();
        self.ready.insert(0, entry);
        Some(p)
    }

    /// The pipelines of `structure` if ready, the order left as it is.
    pub(super) fn peek(&self, structure: &Structure) -> Option<std::sync::Arc<SpecialisedSet>> {
        (self.ready.iter()).find_map(|(s, p)| (s == structure).then(|| p.clone()))
    }

    pub(super) fn keep(
        &mut self,
        structure: Structure,
        set: SpecialisedSet,
        ms: f64,
    ) -> std::sync::Arc<SpecialisedSet> {
        let p = std::sync::Arc::new(set);
        self.ready.insert(0, (structure, p.clone()));
        self.ready.truncate(KEPT_STRUCTURES);
        self.compile_ms.push((structure, ms));
        p
    }

    /// Collects the compile under way if it has finished.
    pub(super) fn collect(&mut self) {
        let done = (self.compiling.as_ref())
            .and_then(|(_, slot)| slot.lock().ok().and_then(|mut slot| slot.take()));
        if let Some((set, ms)) = done {
            let (structure, _) = self.compiling.take().expect("a compile was under way");
            self.keep(structure, set, ms);
        }
    }
}

/// The field passes' bind group layout and pipeline layout.
fn field_layouts(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout) {
    let storage = storage_buffer_entry;
    pass_layouts(
        device,
        "field",
        &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                // Read-only storage, like the chunks (binding 8): lavapipe specialises a shader for the
                // values of the uniforms its loops and branches depend on, a compile (and its memory) for
                // every new scene.
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(size_of::<FieldParams>() as u64),
                },
                count: None,
            },
            storage(1),
            storage(2),
            storage(3),
            storage(4),
            storage(5),
            storage(6),
            field_storage_entry(7, wgpu::StorageTextureAccess::ReadWrite),
            storage(9),
            storage(10),
            storage(11),
            storage(13),
            storage(14),
            field_storage_entry(12, wgpu::StorageTextureAccess::ReadWrite),
            // A read-only storage buffer rather than a uniform one: lavapipe recompiles a shader for the
            // values of uniforms that bound its loops (to unroll them), and a chunk's range bounds the term
            // loop, so every new range meant a new compile (seconds each, minutes for some).
            wgpu::BindGroupLayoutEntry {
                binding: 8,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(size_of::<Chunk>() as u64),
                },
                count: None,
            },
        ],
    )
}

/// The field passes' shader modules, layouts and generic pipelines: made once for a device and shared by every
/// field renderer on it (`FieldRenderer::with_shaders`: the viewer's full, coarse and see-through fields), so
/// that each generic pipeline is compiled once, when a dispatch first needs that entry point.
pub struct FieldShaders {
    device: wgpu::Device,
    modules: Modules,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// The generic pipeline of each entry point (`shaders::FIELD_PASSES`, indexed by `Chunk::pipeline`), by
    /// `FieldParams::search`: without the search for a curve's brightest point (scenes without the continuous W
    /// form compile none of it), with it beside the nearest point, and with it alone.
    generic: [[OnceLock<wgpu::ComputePipeline>; 3]; 3],
    /// Which of them a thread of their own is building (`build_in_background`).
    building: [[AtomicBool; 3]; 3],
    /// The refinement's pass (`shaders/refine.wgsl`).
    pub(super) refine: super::refine::RefineShaders,
}

impl std::fmt::Debug for FieldShaders {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let built = |g: &[OnceLock<wgpu::ComputePipeline>; 3]| {
            g.iter().filter(|p| p.get().is_some()).count()
        };
        f.debug_struct("FieldShaders")
            .field(
                "generic_built",
                &[
                    built(&self.generic[0]),
                    built(&self.generic[1]),
                    built(&self.generic[2]),
                ],
            )
            .finish()
    }
}

impl FieldShaders {
    /// The passes' modules and layouts on `device`; no pipeline yet.
    pub fn new(device: &wgpu::Device) -> Arc<Self> {
        let modules: Modules = std::array::from_fn(|k| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&format!("energywave.field.{}", shaders::FIELD_PASSES[k].0)),
                source: wgpu::ShaderSource::Wgsl(shaders::field_module_source(k).into()),
            })
        });
        let (layout, pipeline_layout) = field_layouts(device);
        Arc::new(Self {
            device: device.clone(),
            modules,
            layout,
            pipeline_layout,
            generic: Default::default(),
            building: Default::default(),
            refine: super::refine::RefineShaders::new(device),
        })
    }

    /// Whether the generic pipelines of `entries` (with the search or without) are built.
    fn built(&self, search: u32, entries: &[usize]) -> bool {
        (entries.iter()).all(|&k| self.generic[search as usize][k].get().is_some())
    }

    /// Starts building the generic pipelines of `entries` that are not built on a thread of their own (one
    /// thread for them all, unless one is building them already). Returns false on GL, where every call holds
    /// the one context: nothing is started there, they are built when first dispatched.
    fn build_in_background(self: &Arc<Self>, search: u32, entries: &[usize]) -> bool {
        if self.device.adapter_info().backend == wgpu::Backend::Gl {
            return false;
        }
        let building = &self.building[search as usize];
        let start: Vec<usize> = (entries.iter().copied())
            .filter(|&k| self.generic[search as usize][k].get().is_none())
            .filter(|&k| !building[k].swap(true, Ordering::SeqCst))
            .collect();
        if start.is_empty() {
            return true;
        }
        let (shaders, started) = (self.clone(), start.clone());
        let spawned = std::thread::Builder::new()
            .name("energywave field compile".into())
            .spawn(move || {
                shaders.build_generic(search, &started);
            });
        if spawned.is_err() {
            // Built at the first dispatch instead: only the flags this call raised are lowered.
            start
                .iter()
                .for_each(|&k| building[k].store(false, Ordering::SeqCst));
            return false;
        }
        true
    }

    /// The generic pipelines of `entries` (with the brightest-point search or without), each compiled now if it
    /// is not yet; where several are missing they compile side by side, one thread each (not on GL, where every
    /// call holds the one context).
    fn build_generic(
        &self,
        search: u32,
        entries: &[usize],
    ) -> &[OnceLock<wgpu::ComputePipeline>; 3] {
        let generic = &self.generic[search as usize];
        let missing: Vec<usize> = (entries.iter().copied())
            .filter(|&k| generic[k].get().is_none())
            .collect();
        let with_search = [("SEARCH", search as f64)];
        let constants: &[(&str, f64)] = if search > 0 { &with_search } else { &[] };
        let build = |k: usize| {
            generic[k].get_or_init(|| {
                build_pipeline(
                    &self.device,
                    &self.modules[k],
                    &self.pipeline_layout,
                    shaders::FIELD_PASSES[k].0,
                    constants,
                )
            });
        };
        let gl = self.device.adapter_info().backend == wgpu::Backend::Gl;
        match missing.split_first() {
            Some((&first, rest)) if !rest.is_empty() && !gl => std::thread::scope(|scope| {
                for &k in rest {
                    scope.spawn(move || build(k));
                }
                build(first);
            }),
            _ => missing.iter().for_each(|&k| build(k)),
        }
        generic
    }
}

/// The field pass's pipelines as one renderer uses them: the device's shared shaders and generic pipelines,
/// and the pipelines specialised to the structures this renderer met.
pub(super) struct FieldPipelines {
    pub(super) shaders: Arc<FieldShaders>,
    pub(super) specialise: Specialise,
    pub(super) specialised: SpecialisedPipelines,
}

/// The pipelines one dispatch draws with: each entry point's specialised pipeline where it is ready, else the
/// generic one.
pub(super) struct DispatchPipelines<'a> {
    specialised: Option<std::sync::Arc<SpecialisedSet>>,
    generic: &'a [OnceLock<wgpu::ComputePipeline>; 3],
}

impl DispatchPipelines<'_> {
    /// The pipeline of entry point `k` (`Chunk::pipeline`).
    pub(super) fn get(&self, k: usize) -> &wgpu::ComputePipeline {
        (self.specialised.as_ref())
            .and_then(|set| set[k].as_ref())
            .or_else(|| self.generic[k].get())
            .expect("the generic pipelines are built where the specialised are not ready")
    }
}

impl FieldPipelines {
    /// A renderer's pipelines over `shaders`; nothing specialised yet.
    pub(super) fn new(shaders: Arc<FieldShaders>) -> Self {
        Self {
            shaders,
            specialise: Specialise::default(),
            specialised: SpecialisedPipelines::default(),
        }
    }

    pub(super) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.shaders.layout
    }

    /// The entry points that dispatch `chunks` and have no specialised pipeline ready (`specialised`).
    fn generic_entries(specialised: Option<&SpecialisedSet>, chunks: &[Chunk]) -> Vec<usize> {
        let ready = |k: usize| specialised.is_some_and(|set| set[k].is_some());
        let mut entries: Vec<usize> = (chunks.iter())
            .map(|c| c.pipeline as usize)
            .filter(|&k| !ready(k))
            .collect();
        entries.sort_unstable();
        entries.dedup();
        entries
    }

    /// Whether a dispatch of `chunks` with `params` would find its pipelines built (no compile first).
    pub(super) fn ready_for(&self, params: &FieldParams, chunks: &[Chunk]) -> bool {
        let specialised = (self.specialise != Specialise::Off)
            .then(|| self.specialised.peek(&Structure::of(params)))
            .flatten();
        let entries = Self::generic_entries(specialised.as_deref(), chunks);
        self.shaders.built(params.search, &entries)
    }

    /// Starts building on a thread of its own what a dispatch of `chunks` with `params` would compile first;
    /// whether it will be ready without a compile on this thread (false on GL).
    pub(super) fn build_in_background(&self, params: &FieldParams, chunks: &[Chunk]) -> bool {
        let entries = Self::generic_entries(None, chunks);
        self.shaders.build_in_background(params.search, &entries)
    }

    /// The pipelines that dispatch `chunks` of inputs with these `params`: the specialised ones where
    /// `specialise` allows and they are ready, the generic ones (built now, those of the entry points the chunks
    /// use, if they are not yet) for the rest.
    pub(super) fn for_dispatch(
        &mut self,
        params: &FieldParams,
        chunks: &[Chunk],
    ) -> DispatchPipelines<'_> {
        let specialised = self.specialised_for(Structure::of(params));
        let entries = Self::generic_entries(specialised.as_deref(), chunks);
        let generic = self.shaders.build_generic(params.search, &entries);
        DispatchPipelines {
            specialised,
            generic,
        }
    }

    /// The pipelines specialised to `structure` if they are ready: compiled now (`Blocking`), or their compile
    /// started on a thread of its own if it is not under way yet (`Background`, which returns `None` until it
    /// has finished).
    fn specialised_for(&mut self, structure: Structure) -> Option<std::sync::Arc<SpecialisedSet>> {
        if self.specialise == Specialise::Off {
            return None;
        }
        self.specialised.collect();
        if let Some(p) = self.specialised.take(&structure) {
            return Some(p);
        }
        match self.specialise {
            Specialise::Off => None,
            Specialise::IfReady => None,
            Specialise::Blocking => {
                let start = std::time::Instant::now();
                let set = build_specialised(&self.shaders, structure);
                Some(
                    self.specialised
                        .keep(structure, set, start.elapsed().as_secs_f64() * 1e3),
                )
            }
            Specialise::Background => {
                self.start_compile(structure);
                None
            }
        }
    }

    /// Starts compiling `structure`'s pipelines on a thread of its own, unless a compile is under way (one at
    /// a time: a burst of structure changes compiles what is drawn when the compile before it has finished).
    /// Never on GL: there every call holds the one GL context, so a compile on another thread (seconds on
    /// llvmpipe) holds up every frame, and wgpu gives up on the context after 6 s with a panic; the generic
    /// pipelines draw there instead.
    pub(super) fn start_compile(&mut self, structure: Structure) {
        if self.specialised.compiling.is_some()
            || self.shaders.device.adapter_info().backend == wgpu::Backend::Gl
        {
            return;
        }
        let slot = CompileSlot::default();
        let shaders = self.shaders.clone();
        let out = slot.clone();
        let spawned = std::thread::Builder::new()
            .name("energywave field compile".into())
            .spawn(move || {
                let start = std::time::Instant::now();
                let p = build_specialised(&shaders, structure);
                if let Ok(mut slot) = out.lock() {
                    *slot = Some((p, start.elapsed().as_secs_f64() * 1e3));
                }
            });
        if spawned.is_ok() {
            self.specialised.compiling = Some((structure, slot));
        }
    }
}
