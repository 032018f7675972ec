//! The field pass: uploads the scene's sources and settings and dispatches the field passes (`shaders/simpson.wgsl`,
//! `adaptive_smooth.wgsl`, `adaptive_curves.wgsl`, each assembled by `gpu::shaders`), which
//! integrates B for every texel into an r32float storage texture (W x W x 4 bytes: O(W^2), no W x W x n
//! buffer). The texture is re-rendered only when something it depends on changed.

use super::context::{
    FIELD_LAYERS, GpuError, checked, field_texture, field_texture_bytes, field_texture_layers,
};
use super::frame_average::FrameAverage;

pub mod gpu_data;
pub mod probe;

use gpu_data::*;

mod pack;
mod pipelines;
pub mod refine;

pub(crate) use gpu_data::FieldParams;
use pack::*;
pub use pack::{FieldInputs, layers_of};
pub(crate) use pack::{SOURCE_BINDINGS, frame_bindings, source_bindings, storage_buffer_init};
use pipelines::*;
pub use pipelines::{FieldShaders, Specialise, Structure};
use std::sync::Arc;
/// The field pass: its pipelines, the GPU memory a frame's field is integrated in, and how far the uploaded
/// frame's field has come. All of it outlives a frame; a frame's own data comes in by `prepare` (`FieldInputs`,
/// packed from the frame's `FrameSetup`).
pub struct FieldRenderer {
    pipelines: FieldPipelines,
    resources: Resources,
    progress: Progress,
}

/// The GPU memory a frame's field is integrated in, grown as frames need and kept: the inputs' buffers, the
/// texture, the scratch texture, bound together.
struct Resources {
    params: wgpu::Buffer,
    /// The chunks, one per `chunk_stride` bytes (bound with a dynamic offset).
    chunks: wgpu::Buffer,
    chunk_stride: u64,
    buffers: [StorageBuffer; 10],
    texture: Option<(wgpu::Texture, wgpu::TextureView)>,
    /// Where simpson with the rms decay keeps a term's sums between its dispatches (B's and the color series'
    /// integrals of squares, four layers): as large as the field where a term takes several dispatches, else one
    /// texel, which nothing reads.
    scratch: (wgpu::Texture, wgpu::TextureView),
    bind_group: Option<wgpu::BindGroup>,
    /// The refinement's buffers: its list of texels is the field pass's binding 14.
    refiner: refine::Refiner,
    /// A layer of zeros, where a field lists its texels (`sparse_texels`): copied over the texture first.
    zeros: Option<wgpu::Buffer>,
}

/// How far the uploaded inputs' field has come: its bands, and the jittered frames averaged.
struct Progress {
    uploaded: Option<Packed>,
    /// Rows per band of the next upload's dispatches (0: the whole texture in one band).
    band_rows: u32,
    /// The uploaded texture's bands: how many, their height, and the next one to dispatch (all dispatched:
    /// nothing pending). A refined texture's bands are its levels, coarse to fine, each whole or (the two
    /// finest) a part of its list at a time: `levels`.
    bands: u32,
    levels: Vec<(u32, std::ops::Range<u32>)>,
    band_height: u32,
    /// Where only the texels with something to integrate are dispatched (`sparse_texels`): the workgroups of
    /// the direct dispatch over their list (x, y), and how many they are.
    sparse: Option<[u32; 3]>,
    next_band: u32,
    dispatches: u64,
    /// The mean of the jittered frames rendered since the scene last changed.
    average: FrameAverage,
    /// How many jittered frames to average at most (1: none, each frame stands alone).
    average_frames: u32,
    /// How many frames the mean holds now.
    averaged: u32,
}

impl FieldRenderer {
    /// Builds the passes' modules and layouts; their pipelines are built when a scene first needs them.
    pub fn new(device: &wgpu::Device) -> Self {
        Self::with_shaders(device, FieldShaders::new(device))
    }

    /// A renderer with its own GPU memory over `shaders`, which other renderers on the device share: a generic
    /// pipeline compiled for one draws for all.
    pub fn with_shaders(device: &wgpu::Device, shaders: Arc<FieldShaders>) -> Self {
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.field.params"),
            size: size_of::<FieldParams>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let buffers = [
            "energywave.field.points",
            "energywave.field.lines",
            "energywave.field.tori",
            "energywave.field.curves",
            "energywave.field.segments",
            "energywave.field.weights",
            "energywave.field.tints",
            "energywave.field.colors",
            "energywave.field.pieces",
            "energywave.field.clips",
        ]
        .map(|label| StorageBuffer::new(device, label, &[]));
        let chunk_stride = (device.limits().min_storage_buffer_offset_alignment as u64)
            .max(size_of::<Chunk>() as u64);
        Self {
            pipelines: FieldPipelines::new(shaders),
            resources: Resources {
                params,
                chunks: chunk_buffer(device, chunk_stride, 1),
                chunk_stride,
                buffers,
                texture: None,
                scratch: field_texture(device, "energywave.field.scratch", 1, FIELD_LAYERS),
                bind_group: None,
                refiner: refine::Refiner::new(device),
                zeros: None,
            },
            progress: Progress {
                uploaded: None,
                band_rows: 0,
                bands: 0,
                band_height: 0,
                sparse: None,
                levels: Vec::new(),
                next_band: 0,
                dispatches: 0,
                average: FrameAverage::new(device),
                average_frames: 1,
                averaged: 0,
            },
        }
    }

    /// While the scene stays the same, averages up to `frames` renders of the jittered integrator, frame k
    /// (0-based) drawing its offsets with the seed `seed + k`; 1 (the default) renders each scene once. Applies
    /// to jittered scenes only: the others are deterministic, and rendered once.
    pub fn set_average_frames(&mut self, frames: u32) {
        self.progress.average_frames = frames.max(1);
    }

    /// Whether the uploaded scene is averaged over frames.
    fn averaging(&self) -> bool {
        self.progress.average_frames > 1
            && self
                .progress
                .uploaded
                .as_ref()
                .is_some_and(|p| p.params.jitter != 0)
    }

    /// While averaging: the frames the picture holds and the most it will hold.
    pub fn averaged_frames(&self) -> Option<(u32, u32)> {
        self.averaging().then_some((
            self.progress.averaged,
            self.progress.average_frames.max(self.progress.averaged),
        ))
    }

    /// The weight of the next frame of the mean, and the offsets' seed (frame `averaged`).
    fn prepare_average_frame(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        let (Some(packed), Some((texture, view))) =
            (&self.progress.uploaded, &self.resources.texture)
        else {
            return;
        };
        let mut params = packed.params;
        params.seed = params.seed.wrapping_add(self.progress.averaged);
        queue.write_buffer(&self.resources.params, 0, bytemuck::bytes_of(&params));
        self.progress.average.prepare(
            device,
            queue,
            texture,
            view,
            self.progress.averaged + 1,
            params.layers,
        );
    }

    /// Uploads what the texture depends on: a frame's inputs (`FieldInputs::of`, packed once a frame). Returns
    /// true when they changed (the next `encode` re-renders).
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        inputs: &FieldInputs,
    ) -> Result<bool, GpuError> {
        let w = inputs.resolution();
        let limit = device.limits().max_texture_dimension_2d;
        if w > limit {
            return Err(GpuError::ResolutionTooLarge {
                resolution: w,
                limit,
            });
        }
        let packed = &inputs.0;
        if self.progress.uploaded.as_ref() == Some(packed) {
            if !self.averaging() || self.progress.averaged >= self.progress.average_frames {
                return Ok(false);
            }
            // The next frame of the average: new offsets, nothing else changes.
            checked(device, || self.prepare_average_frame(device, queue))?;
            self.progress.next_band = 0;
            return Ok(true);
        }
        checked(device, || {
            let mut rebind = self.resources.bind_group.is_none();
            let data: [&[u8]; 10] = [
                bytemuck::cast_slice(&packed.points),
                bytemuck::cast_slice(&packed.lines),
                bytemuck::cast_slice(&packed.tori),
                bytemuck::cast_slice(&packed.curves),
                bytemuck::cast_slice(&packed.segments),
                bytemuck::cast_slice(&packed.weights),
                bytemuck::cast_slice(&packed.tints),
                bytemuck::cast_slice(&packed.colors),
                bytemuck::cast_slice(&packed.pieces),
                bytemuck::cast_slice(packed.clips.as_slice()),
            ];
            for (buffer, bytes) in self.resources.buffers.iter_mut().zip(data) {
                rebind |= buffer.write(device, queue, bytes);
            }
            queue.write_buffer(
                &self.resources.params,
                0,
                bytemuck::bytes_of(&packed.params),
            );
            // Where objects hide part of the texels' rays, those left are listed and the hidden ones hold zero
            // (`sparse_texels`): in place of a refinement where a quarter or less are left, in one band.
            let whole = packed.refinement.is_some() || self.progress.band_rows == 0;
            let sparse = (whole && packed.params.clipped == 1)
                .then(|| sparse_texels(&packed.clips, w, packed.refinement.is_some()))
                .flatten();
            let refinement = packed.refinement.as_ref().filter(|_| sparse.is_none());
            // Every band dispatches every chunk over its rows: entry `band * chunks + k`. A refined texture
            // records a level a band, each chunk over the level's list.
            let refined = refinement.is_some();
            self.progress.band_height = match self.progress.band_rows {
                _ if refined || sparse.is_some() => w,
                0 => w,
                rows => rows.min(w),
            };
            self.progress.levels = match refinement {
                Some(r) => (0..=r.levels.coarsest)
                    .rev()
                    .flat_map(|l| match l {
                        0 | 1 => (0..refine::PARTS).map(|p| (l, p..p + 1)).collect(),
                        _ => vec![(l, 0..refine::PARTS)],
                    })
                    .collect(),
                None => Vec::new(),
            };
            self.progress.bands = match refinement {
                Some(_) => self.progress.levels.len() as u32,
                None => w.div_ceil(self.progress.band_height),
            };
            // A band of a refined texture counts as its share of the texels (`band_layout`: the viewer's estimate
            // of a band's work).
            if refined {
                self.progress.band_height = w.div_ceil(self.progress.bands);
            }
            // The list's direct dispatch: rows of a multiple of 8 invocations, about as many rows as columns.
            self.progress.sparse = sparse.as_ref().map(|texels| {
                let groups = ((texels.len() as f64).sqrt() / 8.0).max(1.0) as u32;
                let n = texels.len() as u32;
                [groups, n.div_ceil(8 * groups).div_ceil(8), n]
            });
            if let (Some(texels), Some([groups, ..])) = (&sparse, self.progress.sparse) {
                rebind |= (self.resources.refiner).list_texels(device, queue, texels, 8 * groups);
            }
            // A refined texture's chunks, once for each part of a level's list (`row_offset` names the part).
            let sets = match refined {
                true => refine::PARTS as usize,
                false => self.progress.bands as usize,
            };
            let entries = packed.chunks.len() * sets;
            let needed = entries as u64 * self.resources.chunk_stride;
            if self.resources.chunks.size() < needed {
                self.resources.chunks = chunk_buffer(device, self.resources.chunk_stride, entries);
                rebind = true;
            }
            let mut bytes = vec![0u8; needed as usize];
            for band in 0..sets as u32 {
                for (k, c) in packed.chunks.iter().enumerate() {
                    let entry = Chunk {
                        row_offset: match refined {
                            true => band,
                            false => band * self.progress.band_height,
                        },
                        listed: (refined || sparse.is_some()) as u32,
                        ..*c
                    };
                    let at = (band as usize * packed.chunks.len() + k)
                        * self.resources.chunk_stride as usize;
                    bytes[at..at + size_of::<Chunk>()].copy_from_slice(bytemuck::bytes_of(&entry));
                }
            }
            queue.write_buffer(&self.resources.chunks, 0, &bytes);
            if let Some(r) = refinement {
                rebind |= (self.resources.refiner).prepare(device, queue, r, packed.params.layers);
            }
            let layers = packed.params.layers;
            let stale = |t: &wgpu::Texture| {
                t.width() != w || t.depth_or_array_layers() != field_texture_layers(device, layers)
            };
            if self
                .resources
                .texture
                .as_ref()
                .is_none_or(|(t, _)| stale(t))
            {
                self.resources.texture =
                    Some(field_texture(device, "energywave.field.storage", w, layers));
                rebind = true;
            }
            let kept = packed.chunks.iter().any(|c| c.stage != FINISH);
            let side = if kept { w } else { 1 };
            if self.resources.scratch.0.width() != side {
                self.resources.scratch =
                    field_texture(device, "energywave.field.scratch", side, FIELD_LAYERS);
                rebind = true;
            }
            if sparse.is_some() {
                // A layer of zeros, copied over every layer before the list is integrated (`encode_bands`).
                let bytes = zero_row_bytes(w) as u64 * w as u64;
                if self
                    .resources
                    .zeros
                    .as_ref()
                    .is_none_or(|z| z.size() < bytes)
                {
                    self.resources.zeros = Some(device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("energywave.field.zeros"),
                        size: bytes,
                        usage: wgpu::BufferUsages::COPY_SRC,
                        mapped_at_creation: false,
                    }));
                }
            }
            if rebind {
                self.resources.bind_group = Some(self.make_bind_group(device));
            }
            if rebind || !self.resources.refiner.bound() {
                let (_, view) = self.resources.texture.as_ref().expect("made above");
                let shaders = &self.pipelines.shaders.refine;
                self.resources.refiner.bind(device, shaders, view);
            }
        })?;
        self.progress.uploaded = Some(packed.clone());
        self.progress.averaged = 0;
        if self.averaging() {
            checked(device, || self.prepare_average_frame(device, queue))?;
        }
        self.progress.next_band = 0;
        Ok(true)
    }

    fn make_bind_group(&self, device: &wgpu::Device) -> wgpu::BindGroup {
        let view = &(self.resources.texture)
            .as_ref()
            .expect("texture created before binding")
            .1;
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.resources.params.as_entire_binding(),
        }];
        // Bindings 1 to 6, then the tints at 9, the color series at 10, the pieces at 11 and the clips at 13.
        for (i, b) in self.resources.buffers.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: match i {
                    0..6 => i as u32 + 1,
                    6..9 => i as u32 + 3,
                    _ => 13,
                },
                resource: b.buffer.as_entire_binding(),
            });
        }
        entries.push(wgpu::BindGroupEntry {
            binding: 14,
            resource: self.resources.refiner.list.as_entire_binding(),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 7,
            resource: wgpu::BindingResource::TextureView(view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 12,
            resource: wgpu::BindingResource::TextureView(&self.resources.scratch.1),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 8,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.resources.chunks,
                offset: 0,
                size: wgpu::BufferSize::new(size_of::<Chunk>() as u64),
            }),
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.field.bind_group"),
            layout: self.pipelines.layout(),
            entries: &entries,
        })
    }

    /// Records the dispatch if the last `prepare` changed something; does nothing otherwise.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.encode_timed(encoder, None);
    }

    /// `encode`, writing GPU timestamps at the beginning and end of the pass when `timestamps` is given
    /// (benchmarks). Returns whether a dispatch was recorded.
    pub fn encode_timed(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> bool {
        let recorded = self.pending();
        self.encode_bands(encoder, u32::MAX, timestamps);
        recorded
    }

    /// Records the dispatches of up to `bands` of the pending bands (`set_band_rows`), in order; returns true
    /// when the texture is complete after them (nothing pending). The texture is counted as rendered, and a
    /// jittered frame folded into the mean, with its last band.
    pub fn encode_bands(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        bands: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> bool {
        let (Some(bind_group), Some(packed)) =
            (&self.resources.bind_group, &self.progress.uploaded)
        else {
            return false;
        };
        if !self.pending() {
            return true;
        }
        let w = packed.params.resolution;
        // A listed field's texels left out hold zero, as their integral does (every integrand is zero on them).
        if let (Some(_), Some(zeros), Some((texture, _)), 0) = (
            self.progress.sparse,
            &self.resources.zeros,
            &self.resources.texture,
            self.progress.next_band,
        ) {
            for layer in 0..texture.depth_or_array_layers() {
                encoder.copy_buffer_to_texture(
                    wgpu::TexelCopyBufferInfo {
                        buffer: zeros,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(zero_row_bytes(w)),
                            rows_per_image: Some(w),
                        },
                    },
                    wgpu::TexelCopyTextureInfo {
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer,
                        },
                        ..texture.as_image_copy()
                    },
                    wgpu::Extent3d {
                        width: w,
                        height: w,
                        depth_or_array_layers: 1,
                    },
                );
            }
        }
        let shaders = self.pipelines.shaders.clone();
        let pipelines = self.pipelines.for_dispatch(&packed.params, &packed.chunks);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.field.pass"),
            timestamp_writes: timestamps,
        });
        let last = self
            .progress
            .next_band
            .saturating_add(bands)
            .min(self.progress.bands);
        let stride = self.resources.chunk_stride;
        match packed
            .refinement
            .as_ref()
            .filter(|_| self.progress.sparse.is_none())
        {
            Some(_) => {
                let refiner = &self.resources.refiner;
                let shaders = &shaders.refine;
                let n = packed.chunks.len();
                for band in self.progress.next_band..last {
                    let level = self.progress.levels[band as usize].clone();
                    refiner.record_level(&mut pass, shaders, level, |pass, part, arguments, at| {
                        for (k, c) in packed.chunks.iter().enumerate() {
                            let entry = part as usize * n + k;
                            pass.set_pipeline(pipelines.get(c.pipeline as usize));
                            pass.set_bind_group(0, bind_group, &[(entry as u64 * stride) as u32]);
                            pass.dispatch_workgroups_indirect(arguments, at);
                        }
                    });
                }
            }
            None => {
                for band in self.progress.next_band..last {
                    let rows =
                        (self.progress.band_height).min(w - band * self.progress.band_height);
                    let [x, y, _] =
                        (self.progress.sparse).unwrap_or([w.div_ceil(8), rows.div_ceil(8), 0]);
                    for (k, c) in packed.chunks.iter().enumerate() {
                        let entry = band as usize * packed.chunks.len() + k;
                        pass.set_pipeline(pipelines.get(c.pipeline as usize));
                        pass.set_bind_group(0, bind_group, &[(entry as u64 * stride) as u32]);
                        pass.dispatch_workgroups(x, y, 1);
                    }
                }
            }
        }
        self.progress.next_band = last;
        if self.pending() {
            return false;
        }
        if self.averaging() {
            self.progress.average.encode(&mut pass);
            self.progress.averaged += 1;
        }
        self.progress.dispatches += 1;
        true
    }

    /// Whether a dispatch of `inputs` would find its pipelines built, with nothing to compile first.
    pub fn compiled_for(&self, inputs: &FieldInputs) -> bool {
        (self.pipelines).ready_for(&inputs.0.params, &inputs.0.chunks)
    }

    /// Starts compiling on a thread of its own the pipelines a dispatch of `inputs` would compile first
    /// (`compiled_for` says when they are ready). Returns false where nothing can be compiled off this thread
    /// (GL): a dispatch compiles them there.
    pub fn compile_for_in_background(&self, inputs: &FieldInputs) -> bool {
        (self.pipelines).build_in_background(&inputs.0.params, &inputs.0.chunks)
    }

    /// The shaders and generic pipelines this renderer draws with, to share with other renderers on its device.
    pub fn shaders(&self) -> Arc<FieldShaders> {
        self.pipelines.shaders.clone()
    }

    /// Starts compiling the uploaded scene's specialised pipelines on a thread of their own, if they are not
    /// ready and no compile is under way (`Specialise::IfReady`: the viewer calls this once its picture is
    /// whole). Returns whether a compile is under way.
    pub fn compile_in_background(&mut self) -> bool {
        self.pipelines.specialised.collect();
        if let Some(p) = &self.progress.uploaded {
            let structure = Structure::of(&p.params);
            if !self.specialised_ready(&structure) {
                self.pipelines.start_compile(structure);
            }
        }
        self.compiling()
    }

    /// When to use pipelines specialised to the scene's structure (`Specialise::Off` by default).
    pub fn set_specialise(&mut self, mode: Specialise) {
        self.pipelines.specialise = mode;
    }

    /// Whether the pipelines specialised to `structure` are ready (they draw the next dispatch of it).
    pub fn specialised_ready(&self, structure: &Structure) -> bool {
        self.pipelines
            .specialised
            .ready
            .iter()
            .any(|(s, _)| s == structure)
    }

    /// Whether a specialised compile is under way on its thread.
    pub fn compiling(&self) -> bool {
        self.pipelines.specialised.compiling.is_some()
    }

    /// How long each structure's pipelines took to compile, in milliseconds, in the order they finished.
    pub fn compile_times(&self) -> &[(Structure, f64)] {
        &self.pipelines.specialised.compile_ms
    }

    /// Whether bands of the uploaded scene are still to be dispatched.
    pub fn pending(&self) -> bool {
        self.progress.uploaded.is_some() && self.progress.next_band < self.progress.bands
    }

    /// The height of the bands of the next upload, in rows (rounded up to the shader's 8 x 8 workgroups; 0:
    /// the whole texture at once, the default). The viewer refines its picture a few bands a frame.
    pub fn set_band_rows(&mut self, rows: u32) {
        self.progress.band_rows = rows.div_ceil(8) * 8;
    }

    /// How many bands the uploaded texture is dispatched in, and how many rows each holds.
    pub fn band_layout(&self) -> (u32, u32) {
        (self.progress.bands, self.progress.band_height)
    }

    /// Whether the texture shows `inputs` completely (uploaded, and every band dispatched).
    pub fn shows(&self, inputs: &FieldInputs) -> bool {
        self.progress.uploaded.as_ref() == Some(&inputs.0) && !self.pending()
    }

    /// Whether `inputs` are the uploaded scene's (complete or not).
    pub fn holds(&self, inputs: &FieldInputs) -> bool {
        self.progress.uploaded.as_ref() == Some(&inputs.0)
    }

    /// GPU memory the field pass holds now: the texture, the uniform and the storage buffers, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        let texture = self.resources.texture.as_ref().map_or(0, |(t, _)| {
            field_texture_bytes(t.width(), t.depth_or_array_layers())
        });
        let scratch = &self.resources.scratch.0;
        texture
            + field_texture_bytes(scratch.width(), scratch.depth_or_array_layers())
            + self.resources.params.size()
            + self
                .resources
                .buffers
                .iter()
                .map(|b| b.buffer.size())
                .sum::<u64>()
            + self.progress.average.gpu_bytes()
            + self.resources.refiner.gpu_bytes()
    }

    /// The brightness texture and its view (after the first `prepare`): the mean of the frames so far while
    /// averaging, else the last frame.
    fn shown(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        if self.averaging() && self.progress.averaged > 0 {
            self.progress.average.mean()
        } else {
            self.resources.texture.as_ref().map(|(t, v)| (t, v))
        }
    }

    /// The layers of the field texture the last `prepare` wrote (`layers_of` its scene): 1, B alone, or
    /// `FIELD_LAYERS`, B and the tint.
    pub fn layers(&self) -> u32 {
        self.progress
            .uploaded
            .as_ref()
            .map_or(1, |p| p.params.layers)
    }

    /// The field texture (after the first `prepare`).
    pub fn texture(&self) -> Option<&wgpu::Texture> {
        self.shown().map(|(t, _)| t)
    }

    /// A view of the brightness texture (after the first `prepare`).
    pub fn view(&self) -> Option<&wgpu::TextureView> {
        self.shown().map(|(_, v)| v)
    }

    /// How many texels the uploaded texture integrated exactly, once recorded and submitted (reads the GPU
    /// back: benches and tests), or `None` where it is not refined (every texel is); where its texels were
    /// listed in place of the refinement (`listed_texels`), those.
    pub fn integrated_texels(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Option<u64>, GpuError> {
        let refined = self
            .progress
            .uploaded
            .as_ref()
            .and_then(|p| p.refinement.as_ref());
        let Some(r) = refined else {
            return Ok(None);
        };
        if let Some([.., listed]) = self.progress.sparse {
            return Ok(Some(listed as u64));
        }
        let source = self.resources.refiner.arguments();
        let bytes = 4 * refine::SLOT as u64 * (r.levels.coarsest as u64 + 1);
        let read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.refine.read"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(source, 0, &read, 0, bytes);
        queue.submit([encoder.finish()]);
        let words: Vec<u32> = bytemuck::cast_slice(&super::map_read(device, &read)?).to_vec();
        // Each level's whole list: its slot's last four u32s, the count last.
        let slot = refine::SLOT as usize;
        Ok(Some(
            words.chunks_exact(slot).map(|s| s[slot - 1] as u64).sum(),
        ))
    }

    /// How many texels the uploaded field dispatches where it lists those the objects leave (`sparse_texels`),
    /// or `None` where it dispatches a band of rows, or a refinement's lists, as usual.
    pub fn listed_texels(&self) -> Option<u32> {
        self.progress.sparse.map(|s| s[2])
    }

    /// How many times the texture has been rendered.
    pub fn dispatch_count(&self) -> u64 {
        self.progress.dispatches
    }

    /// Forgets the uploaded scene, so the next `prepare` re-renders.
    pub fn invalidate(&mut self) {
        self.progress.uploaded = None;
    }
}

#[cfg(test)]
mod tests;

/// The texels of a `w` x `w` field whose rays have glow to integrate (their `clips`, the share of the ray
/// before the first surface, above zero), as the field pass's list holds them (`x | y << 16`, rows from the
/// top); none where too few are hidden for the list to pay: an eighth at least, or where the field would be
/// `refined`, three quarters (a refinement integrates its coarsest level whole and passes over every texel of
/// the finer ones). lavapipe and llvmpipe pay for every invocation dispatched, a hidden texel's too (about
/// 16 ms for 256^2 texels where each integrates nothing): the fields behind a translucent object, which
/// integrate only the texels whose rays cross one, cost their share of the texels, and a field behind a large
/// opaque object the texels it leaves.
fn sparse_texels(clips: &[f32], w: u32, refined: bool) -> Option<Vec<u32>> {
    if clips.len() != (w as usize) * (w as usize) {
        return None;
    }
    let seen = clips.iter().filter(|&&c| c > 0.0).count();
    let pays = match refined {
        true => 4 * seen <= clips.len(),
        false => 8 * seen <= 7 * clips.len(),
    };
    pays.then(|| {
        (0..w)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| clips[(y * w + x) as usize] > 0.0)
            .map(|(x, y)| x | y << 16)
            .collect()
    })
}

/// The bytes a row of zeros holds in the copy over a `w`-texel-wide layer (r32float, rows aligned as copies
/// need).
fn zero_row_bytes(w: u32) -> u32 {
    (4 * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}
