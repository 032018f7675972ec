//! The timing harness: medians and spreads, and the field pass timed on one context (GPU timestamps where the
//! adapter has them, wall time always), scenes interleaved frame by frame.

use super::*;

/// Median and spread of a set of durations, in milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct Timing {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub samples: usize,
}

impl Timing {
    pub(super) fn of(mut ms: Vec<f64>) -> Self {
        ms.sort_by(f64::total_cmp);
        let n = ms.len();
        let median = if n % 2 == 1 {
            ms[n / 2]
        } else {
            0.5 * (ms[n / 2 - 1] + ms[n / 2])
        };
        Self {
            median_ms: median,
            min_ms: ms[0],
            max_ms: ms[n - 1],
            samples: n,
        }
    }

    pub fn fps(&self) -> f64 {
        1e3 / self.median_ms
    }
}

/// The field pass of one frame, timed both ways.
#[derive(Clone, Debug, Serialize)]
pub struct PassTiming {
    /// GPU time of the compute pass from timestamp queries, when the adapter has them.
    pub gpu: Option<Timing>,
    /// Wall time from upload to the end of the GPU's work (submit and wait).
    pub wall: Timing,
}

impl PassTiming {
    /// The figure to report: GPU time where there is one, else wall time.
    pub fn best(&self) -> &Timing {
        self.gpu.as_ref().unwrap_or(&self.wall)
    }
}

/// The timestamp queries' set, resolve buffer and read buffer, where the adapter has them.
pub(super) type Queries = Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>;

/// What draws a frame's field in a timing.
#[derive(Clone, Copy, Debug)]
pub(super) enum Pass {
    /// Our field pass, its pipelines chosen by `Specialise`.
    Field(Specialise),
    /// The plain kernel specialised to the scene (`plain`), holding what `Baked` says as constants.
    Plain(Baked),
    /// The field pass specialised to the scene, refined in image space as the scene's tolerance says
    /// (`frame::refine`); `Field` integrates every texel, the work the papers timed.
    Refined,
}

/// Times the field pass on one context: timestamp queries if available, else wall time only.
pub(super) struct FieldBench {
    pub(super) ctx: GpuContext,
    pub(super) field: FieldRenderer,
    pub(super) plain: PlainKernels,
    pub(super) queries: Queries,
    /// The frames' data kept across the timed frames (the objects' clips are not timed again each frame).
    cache: std::sync::Arc<crate::frame::FrameCache>,
    /// Which texels the next frames integrate: every one (the papers' work, what every section but the
    /// refinement's times), or as the scene's tolerance says.
    pub(super) refine: Option<crate::frame::Refine>,
}

impl FieldBench {
    pub(super) fn new() -> Result<Self, GpuError> {
        let ctx = GpuContext::new()?;
        let field = FieldRenderer::new(&ctx.device);
        let queries = ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| {
                let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("energywave.bench.timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("energywave.bench.resolve"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("energywave.bench.read"),
                    size: 16,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                });
                (set, resolve, read)
            });
        Ok(Self {
            ctx,
            field,
            plain: PlainKernels::new(),
            queries,
            cache: Default::default(),
            refine: Some(crate::frame::Refine::EveryTexel),
        })
    }

    /// Integrates the field of `scene` once (forced, even if unchanged): (GPU ms, wall ms).
    pub(super) fn frame(&mut self, scene: &Scene) -> Result<(Option<f64>, f64), GpuError> {
        let start = Instant::now();
        self.field.invalidate();
        let mut setup = FrameSetup::placed_in(scene, 1.0, &self.cache);
        if let Some(refine) = self.refine {
            setup.refine = refine;
        }
        let inputs = FieldInputs::of(&setup);
        self.field
            .prepare(&self.ctx.device, &self.ctx.queue, &inputs)?;
        let Self {
            ctx,
            field,
            queries,
            ..
        } = self;
        timed(ctx, queries, start, |_, encoder, writes| {
            field.encode_timed(encoder, writes);
            Ok(())
        })
    }

    /// `scene`'s field by the plain kernel specialised to it (`plain`), timed as `frame` times ours.
    pub(super) fn plain_frame(
        &mut self,
        scene: &Scene,
        baked: Baked,
    ) -> Result<(Option<f64>, f64), GpuError> {
        let start = Instant::now();
        let Self {
            ctx,
            plain,
            queries,
            ..
        } = self;
        timed(ctx, queries, start, |ctx, encoder, writes| {
            plain.encode(ctx, scene, baked, encoder, writes).map(|_| ())
        })
    }

    /// The brightness texture of `scene`, integrated on the GPU and read back.
    pub(super) fn brightness(&mut self, scene: &Scene) -> Result<Vec<f32>, GpuError> {
        self.frame(scene)?;
        let texture = self.field.texture().expect("integrated above");
        let bytes = self.ctx.read_texture(texture, 4)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }

    /// `frame` or `plain_frame`, as `pass` says.
    fn frame_as(&mut self, pass: Pass, scene: &Scene) -> Result<(Option<f64>, f64), GpuError> {
        match pass {
            Pass::Field(specialise) => {
                self.field.set_specialise(specialise);
                self.refine = Some(crate::frame::Refine::EveryTexel);
                self.frame(scene)
            }
            Pass::Refined => {
                self.field.set_specialise(Specialise::Blocking);
                self.refine = None;
                let timing = self.frame(scene);
                self.refine = Some(crate::frame::Refine::EveryTexel);
                timing
            }
            Pass::Plain(baked) => self.plain_frame(scene, baked),
        }
    }

    /// Times `scenes` interleaved frame by frame (so that drift of a shared, noisy machine hits them alike):
    /// at least `warmup` untimed rounds and `WARMUP_SECONDS`, then `frames` timed ones. `next(k, i)` gives scene
    /// `k` for round `i`.
    pub(super) fn interleaved(
        &mut self,
        count: usize,
        warmup: usize,
        frames: usize,
        next: impl FnMut(usize, usize) -> Scene,
    ) -> Result<Vec<PassTiming>, GpuError> {
        self.interleaved_as(
            count,
            warmup,
            frames,
            |_| Pass::Field(Specialise::Blocking),
            next,
        )
    }

    /// `interleaved`, scene `k` drawn by the pass `mode(k)` chooses (compiled in the warm-up).
    pub(super) fn interleaved_as(
        &mut self,
        count: usize,
        warmup: usize,
        frames: usize,
        mode: impl Fn(usize) -> Pass,
        mut next: impl FnMut(usize, usize) -> Scene,
    ) -> Result<Vec<PassTiming>, GpuError> {
        let mut gpu = vec![Vec::new(); count];
        let mut wall = vec![Vec::new(); count];
        let start = Instant::now();
        let mut round = 0;
        while round < warmup || warming(start, round) {
            for k in 0..count {
                self.frame_as(mode(k), &next(k, round))?;
            }
            round += 1;
        }
        for round in round..round + frames {
            for k in 0..count {
                let (g, w) = self.frame_as(mode(k), &next(k, round))?;
                wall[k].push(w);
                if let Some(g) = g {
                    gpu[k].push(g);
                }
            }
        }
        Ok((0..count)
            .map(|k| PassTiming {
                gpu: (!gpu[k].is_empty()).then(|| Timing::of(gpu[k].clone())),
                wall: Timing::of(wall[k].clone()),
            })
            .collect())
    }
}

/// Least time spent warming up before anything is timed. A real GPU idles at a fraction of its clock and only
/// reaches full speed after a moment of steady work: an H200 timed after two warm-up frames that followed a
/// few seconds of CPU work (the equal-error reference) ran at its idle clock, 345 of 1980 MHz, about 5.7 times
/// slower than in the grid section just before. On lavapipe the warm-up frames alone take longer than this.
pub const WARMUP_SECONDS: f64 = 0.5;
/// Most warm-up rounds, whatever the time: a pass of a few microseconds reaches `WARMUP_SECONDS` in well under this.
pub(super) const MAX_WARMUP_ROUNDS: usize = 100_000;

/// Whether warm-up that began at `start` and has run `rounds` rounds should go on.
pub(super) fn warming(start: Instant, rounds: usize) -> bool {
    rounds < MAX_WARMUP_ROUNDS && start.elapsed().as_secs_f64() < WARMUP_SECONDS
}

/// Records the compute pass `encode` records, timestamped where the adapter can, submits it and waits:
/// (GPU ms, wall ms since `start`).
fn timed(
    ctx: &GpuContext,
    queries: &Queries,
    start: Instant,
    encode: impl FnOnce(
        &GpuContext,
        &mut wgpu::CommandEncoder,
        Option<wgpu::ComputePassTimestampWrites>,
    ) -> Result<(), GpuError>,
) -> Result<(Option<f64>, f64), GpuError> {
    let (device, queue) = (&ctx.device, &ctx.queue);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("energywave.bench.encoder"),
    });
    let writes = queries
        .as_ref()
        .map(|(set, _, _)| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        });
    encode(ctx, &mut encoder, writes)?;
    if let Some((set, resolve, read)) = &queries {
        encoder.resolve_query_set(set, 0..2, resolve, 0);
        encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
    }
    ctx.checked(|| queue.submit([encoder.finish()]))?;
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let wall = start.elapsed().as_secs_f64() * 1e3;
    let gpu = match &queries {
        Some((_, _, read)) => {
            let ticks: [u64; 2] = bytemuck::pod_read_unaligned(&map_read(device, read)?[..16]);
            let period = queue.get_timestamp_period() as f64;
            Some(ticks[1].saturating_sub(ticks[0]) as f64 * period * 1e-6)
        }
        None => None,
    };
    Ok((gpu, wall))
}
