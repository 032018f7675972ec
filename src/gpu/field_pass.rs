//! The field pass: uploads the scene's sources and settings and dispatches the field passes (`shaders/simpson.wgsl`,
//! `adaptive_smooth.wgsl`, `adaptive_curves.wgsl`, each assembled by `gpu::shaders`), which
//! integrates B for every texel into an r32float storage texture (W x W x 4 bytes: O(W^2), no W x W x n
//! buffer). The texture is re-rendered only when something it depends on changed.

use wgpu::util::DeviceExt;

use super::context::{
    FIELD_LAYERS, GpuError, checked, field_storage_entry, field_texture, field_texture_bytes,
    field_texture_layers, pass_layouts, storage_buffer_entry,
};
use super::frame_average::FrameAverage;
use super::shaders;
use crate::field::curve::segments;
use crate::geometry::Billboard;
use crate::integrate::{Decay, Integrator};
use crate::objects::clip::shared_clip_fractions;
use crate::scene::Scene;

/// Rust mirrors of the WGSL structs of `shaders/field_pass.wgsl` and `shaders/field_common.wgsl` (keep in
/// sync; `tests/gpu_layout.rs` checks them against naga's layout).
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    /// `FieldParams` in `shaders/field_pass.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct FieldParams {
        pub center: [f32; 3],    // 0
        pub size: f32,           // 12
        pub right: [f32; 3],     // 16
        pub resolution: u32,     // 28
        pub up: [f32; 3],        // 32
        pub divisions: u32,      // 44
        pub eye: [f32; 3],       // 48
        pub nu: f32,             // 60
        pub alpha: f32,          // 64
        pub beta: f32,           // 68
        pub epsilon: f32,        // 72
        pub point_count: u32,    // 76
        pub line_count: u32,     // 80
        pub torus_count: u32,    // 84
        pub curve_count: u32,    // 88
        pub integrator: u32,     // 92: 0 simpson, 1 adaptive
        pub term_tolerance: f32, // 96
        pub jitter: u32,         // 100
        pub seed: u32,           // 104
        pub gauss_order: u32, // 108: adaptive: n of the Gauss-Kronrod pair (integrate::adaptive::kronrod_order)
        pub layers: u32, // 112: the field texture's layers written: 1 (B) or FIELD_LAYERS (and the tint)
        pub search: u32, // 116: 1 where some curve's term reads its brightest point (the SEARCH constant)
        pub decay: u32,  // 120: 0 distance, 1 rms (integrate::Decay)
        pub stretch: f32, // 124: the rays' span in decay lengths, the rms decay's unit
        pub clipped: u32, // 128: 1 where the scene has objects: each texel's ray ends at its clip (binding 13)
        pub pad0: u32,
        pub pad1: u32,
        pub pad2: u32,
    }
    const _: () = assert!(size_of::<FieldParams>() == 144);

    /// `Chunk` in `shaders/field_pass.wgsl`: one dispatch's range of samples or terms.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct Chunk {
        pub first: u32,      // 0
        pub count: u32,      // 4
        pub accumulate: u32, // 8
        pub pipeline: u32, // 12: which of `FieldRenderer`'s pipelines runs it (read on the CPU only)
        pub row_offset: u32, // 16: the first texel row of its band
        pub term: u32,     // 20: simpson with the rms decay: the one term it integrates
        pub stage: u32, // 24: that term's sums: bit 0, add the scratch's; bit 1, finish (else keep)
    }
    const _: () = assert!(size_of::<Chunk>() == 28);

    /// `PointSource` in `shaders/field_common.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct PointSource {
        pub position: [f32; 3], // 0
        pub coefficient: f32,   // 12
    }
    const _: () = assert!(size_of::<PointSource>() == 16);

    /// `LineSource` in `shaders/field_common.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct LineSource {
        pub point: [f32; 3],     // 0
        pub coefficient: f32,    // 12
        pub direction: [f32; 3], // 16
        pub pad0: f32,           // 28
    }
    const _: () = assert!(size_of::<LineSource>() == 32);

    /// `TorusSource` in `shaders/field_common.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct TorusSource {
        pub center: [f32; 3],  // 0
        pub major_radius: f32, // 12
        pub axis: [f32; 3],    // 16
        pub coefficient: f32,  // 28
    }
    const _: () = assert!(size_of::<TorusSource>() == 32);

    /// `CurveSource` in `shaders/field_common.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct CurveSource {
        pub first_segment: u32, // 0
        pub segment_count: u32, // 4
        pub first_weight: u32,  // 8
        pub weight_count: u32,  // 12
        pub coefficient: f32,   // 16
        pub first_color: u32,   // 20
        pub color_count: u32,   // 24: 0, no color series
        pub first_piece: u32,   // 28
        pub piece_count: u32,   // 32: 0, the term reads the nearest point
        pub pad0: u32,          // 36
        pub pad1: u32,          // 40
        pub pad2: u32,          // 44
    }
    const _: () = assert!(size_of::<CurveSource>() == 48);

    /// `CurvePiece` in `shaders/field_common.wgsl` (twin of `field::brightest::Piece`).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct CurvePiece {
        pub c2: [f32; 3],     // 0
        pub s2: f32,          // 12
        pub c1: [f32; 3],     // 16
        pub s1: f32,          // 28
        pub c0: [f32; 3],     // 32
        pub s0: f32,          // 44
        pub center: [f32; 3], // 48
        pub radius: f32,      // 60
        pub t0: f32,          // 64
        pub t1: f32,          // 68
        pub weight_max: f32,  // 72
        pub pad0: f32,        // 76
    }
    const _: () = assert!(size_of::<CurvePiece>() == 80);

    /// `CurveSegment` in `shaders/field_common.wgsl`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct CurveSegment {
        pub c2: [f32; 3], // 0
        pub pad0: f32,    // 12
        pub c1: [f32; 3], // 16
        pub pad1: f32,    // 28
        pub c0: [f32; 3], // 32
        pub pad2: f32,    // 44
    }
    const _: () = assert!(size_of::<CurveSegment>() == 48);
}

use gpu_data::*;

/// What the field texture of a scene and billboard depends on (equal inputs give equal textures): compare the
/// inputs of two frames to tell whether the field changed between them.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldInputs(Packed);

impl FieldInputs {
    pub fn of(scene: &Scene, billboard: &Billboard) -> Self {
        FieldInputs(pack(scene, billboard))
    }
}

/// Everything the field pass reads, packed for upload; equal packs give equal textures.
#[derive(Clone, Debug, Default, PartialEq)]
struct Packed {
    params: FieldParams,
    points: Vec<PointSource>,
    lines: Vec<LineSource>,
    tori: Vec<TorusSource>,
    curves: Vec<CurveSource>,
    segments: Vec<CurveSegment>,
    weights: Vec<f32>,
    /// Each term's `Ce_i - Ce` (`Scene::tints`) in rgb, points first, then lines, tori and curves.
    tints: Vec<[f32; 4]>,
    /// The curves' color series, their intensity applied, in rgb (`CurveSource::first_color`).
    colors: Vec<[f32; 4]>,
    /// The pieces of the curves whose term reads their brightest point (`CurveSource::first_piece`).
    pieces: Vec<CurvePiece>,
    /// The share of each texel's ray before the first surface of the scene's objects (`objects::clip`), or
    /// nothing without objects.
    clips: std::sync::Arc<Vec<f32>>,
    /// The dispatches that together integrate the texture.
    chunks: Vec<Chunk>,
}

/// Loop iterations one invocation may spend: Mesa's llvmpipe and lavapipe stop all loops of an invocation after
/// 65535 iterations in all (silently); this leaves room for the estimate's slack.
const ITERATION_BUDGET: u64 = 30_000;
/// Rules the adaptive integrator applies to one term at most: `MAX_GAUSS_PANELS` panels on each of `cuts` parts
/// of its pieces, and two more for each of its `MAX_REFINEMENTS` refinements; each rule evaluates the term at the
/// `2n + 1` nodes of the Kronrod rule, at most 21.
const fn rules(cuts: u64) -> u64 {
    use crate::integrate::adaptive::{MAX_GAUSS_PANELS, MAX_REFINEMENTS};
    cuts * MAX_GAUSS_PANELS as u64 + 2 * MAX_REFINEMENTS as u64
}
/// Loop iterations of one rule of the pair of `order`: its `2n + 1` nodes, the rule's own loop, and the
/// bisection's walk up after it.
const fn rule_iterations(order: u32) -> u64 {
    2 * order as u64 + 2 + crate::integrate::adaptive::MAX_DEPTH as u64
}
/// Evaluations of a curve's distance the adaptive integrator spends on its term at most (each a loop over its
/// segments): the scan, the samples at its ends, the kink search's probes, the Newton steps of its closest
/// approaches, a sample for each knot cut, and the rules on every cut (at most `MAX_PEAKS` pieces, two closest
/// approaches and two ends, each cut at its flat top's ends, and the kinks).
const fn curve_evaluations(order: u32) -> u64 {
    use crate::integrate::adaptive::{
        BRIGHT_SCAN, CUT_BISECTIONS, KINK_ROUNDS, MAX_KINKS, MAX_PEAKS, PEAK_NEWTON, SCAN,
    };
    let cuts = 3 * MAX_PEAKS as u64 + MAX_KINKS as u64;
    (SCAN as u64 + 1)
        // The continuous W form's scan, and the bisections that place its cuts (loop iterations, counted alike).
        + (BRIGHT_SCAN as u64 + 1)
        + MAX_KINKS as u64 * CUT_BISECTIONS as u64
        + 2
        + 2 * KINK_ROUNDS as u64 * MAX_KINKS as u64
        + 2 * PEAK_NEWTON as u64
        + MAX_KINKS as u64
        + rules(cuts) * rule_iterations(order)
}
/// Loop iterations of a point's, a line's or a torus's term at most: the pole series on the closed form's two
/// pieces (where it then declines), Newton on the ring, then three pieces of three cuts, each of its rules a loop
/// over its nodes, and the bisection's walk up after each.
const fn smooth_iterations(order: u32) -> u64 {
    2 * crate::integrate::adaptive::POLE_SERIES_TERMS_F32 as u64
        + 20
        + rules(3 * 3) * rule_iterations(order)
}

/// Loop iterations of one evaluation of a source's distance (a curve loops over its segments and roots), or of its
/// brightest point (`pieces` > 0: over its pieces twice, the parts each walk visits and the Newton steps on the two
/// maxima a piece has at most and on the flat top's two ends, and the adaptive pass's check of every piece's bound
/// where it carries the point on).
fn curve_iterations(segments: u32, pieces: u32) -> u64 {
    use crate::field::brightest::{ROOT_NEWTON, ROOT_VISITS};
    if pieces > 0 {
        2 + pieces as u64 * (4 + ROOT_VISITS as u64 + 4 * ROOT_NEWTON as u64)
    } else {
        1 + 12 * segments as u64
    }
}

/// Newton steps a Gauss node of a curve's piece takes from the last node's nearest point before it falls back, if
/// it must, to solving the cubic.
const TRACK_NEWTON: u64 = shaders::TRACK_NEWTON as u64;

/// Loop iterations of a curve's term in the adaptive integrator at most, `iterations` those of one evaluation of
/// its distance: each evaluation may take Newton's steps from the last node (`track_nearest` in the shader), then
/// solve the piece's segment alone, then the whole chain (`nearest_on_chain_from`), in an outer loop of its own.
fn adaptive_curve_iterations(order: u32, iterations: u64) -> u64 {
    curve_evaluations(order) * (TRACK_NEWTON + iterations + curve_iterations(1, 0) + 1)
}

/// `Chunk::stage`: the dispatch adds the sums the scratch texture keeps to its own (`KEPT`), and finishes the
/// term into the field (`FINISH`; else it keeps its sums in the scratch texture).
const KEPT: u32 = 1;
const FINISH: u32 = 2;
/// `FieldParams::decay` of the rms decay.
const RMS: u32 = 1;

/// The pipelines: simpson's, the adaptive integrator's for points, lines and tori, and for curves.
const SIMPSON: u32 = 0;
const ADAPTIVE_SMOOTH: u32 = 1;
const ADAPTIVE_CURVES: u32 = 2;

/// Splits the integration into dispatches that each stay within `ITERATION_BUDGET` loop iterations a texel.
fn plan_chunks(p: &Packed) -> Vec<Chunk> {
    let chunk = |first: u32, count: u32, k: usize, pipeline: u32| Chunk {
        first,
        count,
        accumulate: (k > 0) as u32,
        pipeline,
        stage: FINISH,
        ..Chunk::default()
    };
    let smooth = p.params.point_count + p.params.line_count + p.params.torus_count;
    let curves: Vec<u64> = p
        .curves
        .iter()
        .map(|c| curve_iterations(c.segment_count, c.piece_count))
        .collect();
    if p.params.integrator == 0 && p.params.decay == RMS && smooth + p.params.curve_count > 0 {
        // Simpson with the rms decay: term by term, each term's samples in as few dispatches as the budget allows,
        // the first ones keeping their sums in the scratch texture, the last finishing the term (the root of its
        // sum of squares) into the field.
        let samples = p.params.divisions + 1;
        let mut chunks = Vec::new();
        let mut finished = 0;
        for t in 0..smooth + p.params.curve_count {
            let per_sample = 4 + if t < smooth {
                1
            } else {
                curves[(t - smooth) as usize]
            };
            let per_chunk = (ITERATION_BUDGET / per_sample).clamp(1, samples as u64) as u32;
            let parts = samples.div_ceil(per_chunk);
            for j in 0..parts {
                let last = j + 1 == parts;
                chunks.push(Chunk {
                    first: j * per_chunk,
                    count: per_chunk,
                    accumulate: (last && finished > 0) as u32,
                    pipeline: SIMPSON,
                    row_offset: 0,
                    term: t,
                    stage: if j > 0 { KEPT } else { 0 } | if last { FINISH } else { 0 },
                });
                finished += last as u32;
            }
        }
        return chunks;
    }
    if p.params.integrator == 0 {
        // Simpson: ranges of samples, each sample costing a walk over every source.
        let per_sample = 4 + smooth as u64 + curves.iter().sum::<u64>();
        let samples = p.params.divisions + 1;
        let per_chunk = (ITERATION_BUDGET / per_sample).clamp(1, samples as u64) as u32;
        return (0..samples.div_ceil(per_chunk))
            .map(|k| chunk(k * per_chunk, per_chunk, k as usize, SIMPSON))
            .collect();
    }
    // Adaptive: ranges of terms, the points, lines and tori first, then the curves, each on its pipeline.
    let costs = (0..smooth)
        .map(|_| (smooth_iterations(p.params.gauss_order), ADAPTIVE_SMOOTH))
        .chain(curves.iter().map(|&c| {
            (
                adaptive_curve_iterations(p.params.gauss_order, c),
                ADAPTIVE_CURVES,
            )
        }));
    let mut chunks = Vec::new();
    let (mut first, mut cost, mut pipeline) = (0u32, 0u64, ADAPTIVE_SMOOTH);
    for (t, (c, kind)) in costs.enumerate() {
        let t = t as u32;
        if t > first && (cost + c > ITERATION_BUDGET || kind != pipeline) {
            chunks.push(chunk(first, t - first, chunks.len(), pipeline));
            (first, cost) = (t, 0);
        }
        pipeline = kind;
        cost += c;
    }
    let total = smooth + p.params.curve_count;
    if total > first || chunks.is_empty() {
        chunks.push(chunk(first, total - first, chunks.len(), pipeline));
    }
    chunks
}

/// The layers of the field texture that `scene` needs: B alone where every source has the scene's color (the
/// tint is zero: the passes neither write nor read it), else B and the tint.
pub fn layers_of(scene: &Scene) -> u32 {
    if scene.tinted() { FIELD_LAYERS } else { 1 }
}

fn v3(v: glam::DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

fn pack(scene: &Scene, billboard: &Billboard) -> Packed {
    let s = &scene.sources;
    let reach = scene.ray_reach(billboard);
    let i = &scene.integration.on_ray(reach.stretch);
    let mut packed = pack_sources(scene);
    packed.params = FieldParams {
        center: v3(billboard.center),
        size: billboard.size as f32,
        right: v3(billboard.right),
        resolution: scene.billboard.resolution,
        up: v3(billboard.up),
        divisions: i.divisions,
        eye: v3(scene.camera.eye),
        nu: reach.nu as f32,
        alpha: i.alpha as f32,
        beta: i.beta as f32,
        epsilon: i.epsilon as f32,
        integrator: match i.integrator {
            Integrator::Simpson => 0,
            Integrator::Adaptive => 1,
        },
        term_tolerance: (i.tolerance / s.len().max(1) as f64) as f32,
        jitter: i.jitter.is_some() as u32,
        seed: i.jitter.unwrap_or(0),
        gauss_order: crate::integrate::adaptive::kronrod_order(i.tolerance),
        decay: match i.decay {
            Decay::Distance => 0,
            Decay::Rms => RMS,
        },
        stretch: i.stretch as f32,
        ..packed.params
    };
    let eye = scene.camera.eye;
    let w = scene.billboard.resolution;
    if let Some(clips) = shared_clip_fractions(&scene.objects, eye, billboard, reach, w) {
        packed.clips = clips;
        packed.params.clipped = 1;
    }
    packed.chunks = plan_chunks(&packed);
    packed
}

/// The sources as the field's shaders read them, with their counts, the layers and the search flag in params
/// (the scene's own epsilon there; nothing of the billboard, the rays or the integrator).
fn pack_sources(scene: &Scene) -> Packed {
    let s = &scene.sources;
    let tints = scene.tints();
    let tinted = tints.iter().flatten().any(|&x| x != 0.0);
    let mut packed = Packed {
        params: FieldParams {
            epsilon: scene.integration.epsilon as f32,
            point_count: s.points.len() as u32,
            line_count: s.lines.len() as u32,
            torus_count: s.tori.len() as u32,
            curve_count: s.curves.len() as u32,
            layers: if tinted { FIELD_LAYERS } else { 1 },
            ..FieldParams::default()
        },
        points: (s.points.iter())
            .map(|p| PointSource {
                position: v3(p.position),
                coefficient: p.coefficient as f32,
            })
            .collect(),
        lines: (s.lines.iter())
            .map(|l| LineSource {
                point: v3(l.point),
                coefficient: l.coefficient as f32,
                direction: v3(l.direction),
                pad0: 0.0,
            })
            .collect(),
        tori: (s.tori.iter())
            .map(|t| TorusSource {
                center: v3(t.center),
                major_radius: t.major_radius as f32,
                axis: v3(t.axis),
                coefficient: t.coefficient as f32,
            })
            .collect(),
        tints: (tints.iter())
            .map(|t| [t[0] as f32, t[1] as f32, t[2] as f32, 0.0])
            .collect(),
        ..Packed::default()
    };
    for c in &s.curves {
        let first_segment = packed.segments.len() as u32;
        let first_weight = packed.weights.len() as u32;
        // Power-form coefficients are computed in f64, then rounded once.
        packed
            .segments
            .extend(segments(&c.control_points).map(|seg| CurveSegment {
                c2: v3(seg.c2),
                c1: v3(seg.c1),
                c0: v3(seg.c0),
                ..CurveSegment::default()
            }));
        packed.weights.extend(c.weights.iter().map(|&w| w as f32));
        let first_color = packed.colors.len() as u32;
        let intensity = c.look.intensity.unwrap_or(scene.colors.energy_intensity);
        packed.colors.extend(
            (c.color_series.iter())
                .map(|x| x.map(|v| (v * intensity) as f32))
                .map(|[r, g, b]| [r, g, b, 0.0]),
        );
        let first_piece = packed.pieces.len() as u32;
        packed.pieces.extend(c.pieces().iter().map(|q| CurvePiece {
            c2: v3(q.segment.c2),
            s2: q.weight[0] as f32,
            c1: v3(q.segment.c1),
            s1: q.weight[1] as f32,
            c0: v3(q.segment.c0),
            s0: q.weight[2] as f32,
            center: v3(q.center),
            // Rounded outward, so that the ball still holds the piece's f32 points.
            radius: (q.radius * (1.0 + 1e-5) + 1e-6 * q.center.length()) as f32,
            t0: q.t0 as f32,
            t1: q.t1 as f32,
            weight_max: (q.weight_max * (1.0 + 1e-6)) as f32,
            pad0: 0.0,
        }));
        packed.curves.push(CurveSource {
            first_segment,
            segment_count: packed.segments.len() as u32 - first_segment,
            first_weight,
            weight_count: c.weights.len() as u32,
            first_color,
            color_count: c.color_series.len() as u32,
            first_piece,
            piece_count: packed.pieces.len() as u32 - first_piece,
            coefficient: c.coefficient as f32,
            ..CurveSource::default()
        });
    }
    packed.params.search = packed.curves.iter().any(|c| c.piece_count > 0) as u32;
    packed
}

/// The bindings of `shaders/field_pass.wgsl` that hold the sources, beside params at 0: points, lines, tori,
/// curves, segments, weights, tints, color series and pieces (`source_bindings`).
pub(crate) const SOURCE_BINDINGS: [u32; 9] = [1, 2, 3, 4, 5, 6, 9, 10, 11];

/// What a pass that evaluates the field's terms at points of its own reads (`gpu::object_pass`): params with the
/// source counts, `scene.integration.epsilon` and the search flag, and the contents of `SOURCE_BINDINGS`.
pub(crate) fn source_bindings(scene: &Scene) -> (FieldParams, [Vec<u8>; 9]) {
    let p = pack_sources(scene);
    let bytes = [
        bytemuck::cast_slice(&p.points).to_vec(),
        bytemuck::cast_slice(&p.lines).to_vec(),
        bytemuck::cast_slice(&p.tori).to_vec(),
        bytemuck::cast_slice(&p.curves).to_vec(),
        bytemuck::cast_slice(&p.segments).to_vec(),
        bytemuck::cast_slice(&p.weights).to_vec(),
        bytemuck::cast_slice(&p.tints).to_vec(),
        bytemuck::cast_slice(&p.colors).to_vec(),
        bytemuck::cast_slice(&p.pieces).to_vec(),
    ];
    (p.params, bytes)
}

/// A storage buffer holding `bytes` (never empty: WebGPU refuses zero-sized bindings, so an empty list still
/// binds one zeroed element of the largest struct, CurvePiece's 80 bytes).
pub(crate) fn storage_buffer_init(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
) -> wgpu::Buffer {
    let zeros = [0u8; 80];
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: if bytes.is_empty() { &zeros } else { bytes },
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// A storage buffer for `count` chunks, `stride` bytes apart.
fn chunk_buffer(device: &wgpu::Device, stride: u64, count: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("energywave.field.chunks"),
        size: stride * count.max(1) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A storage buffer that grows as needed (never empty: WebGPU refuses zero-sized bindings).
struct StorageBuffer {
    label: &'static str,
    buffer: wgpu::Buffer,
}

impl StorageBuffer {
    fn new(device: &wgpu::Device, label: &'static str, bytes: &[u8]) -> Self {
        Self {
            label,
            buffer: storage_buffer_init(device, label, bytes),
        }
    }

    /// Writes `bytes`; returns true when the buffer had to be replaced (the bind group must be rebuilt).
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8]) -> bool {
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

/// The scene's structure a specialised pipeline is compiled for: the values of `shaders/field_pass.wgsl`'s
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
    /// Whether some curve's term reads its brightest point (`FieldParams::search`).
    pub search: u32,
}

impl Structure {
    fn of(params: &FieldParams) -> Self {
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
    fn entries(&self) -> &'static [usize] {
        if self.integrator == 0 { &[0] } else { &[1, 2] }
    }

    /// The structure of `scene` seen through `billboard`.
    pub fn of_scene(scene: &Scene, billboard: &Billboard) -> Self {
        Self::of(&pack(scene, billboard).params)
    }

    fn constants(&self) -> [(&'static str, f64); 7] {
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
type Modules = [wgpu::ShaderModule; 3];
type Pipelines = [wgpu::ComputePipeline; 3];
/// A structure's specialised pipelines: only its integrator's entry points.
type SpecialisedSet = [Option<wgpu::ComputePipeline>; 3];

fn build_pipeline(
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

/// The generic pipelines of every entry point: without the search for the brightest point of a curve (`search`
/// false: scenes without the continuous W form compile none of it), or with it.
fn build_pipelines(
    device: &wgpu::Device,
    modules: &Modules,
    layout: &wgpu::PipelineLayout,
    search: bool,
) -> Pipelines {
    let constants: &[(&str, f64)] = if search { &[("SEARCH", 1.0)] } else { &[] };
    std::array::from_fn(|k| {
        build_pipeline(
            device,
            &modules[k],
            layout,
            shaders::FIELD_PASSES[k].0,
            constants,
        )
    })
}

/// The pipelines of `structure`'s entry points, specialised to it.
fn build_specialised(
    device: &wgpu::Device,
    modules: &Modules,
    layout: &wgpu::PipelineLayout,
    structure: Structure,
) -> SpecialisedSet {
    let constants = structure.constants();
    let mut set: SpecialisedSet = Default::default();
    for &k in structure.entries() {
        set[k] = Some(build_pipeline(
            device,
            &modules[k],
            layout,
            shaders::FIELD_PASSES[k].0,
            &constants,
        ));
    }
    set
}

/// Where a compile's thread leaves its pipelines and how long they took (milliseconds).
type CompileSlot = std::sync::Arc<std::sync::Mutex<Option<(SpecialisedSet, f64)>>>;

/// Most structures whose specialised pipelines are kept (the least recently drawn go first): a compiled
/// structure holds about 20 MB of the driver's memory on lavapipe, and an editing session may pass through
/// many structures.
const KEPT_STRUCTURES: usize = 4;

/// The specialised pipelines: those ready (most recently drawn first), and the one compile under way.
#[derive(Default)]
struct SpecialisedPipelines {
    ready: Vec<(Structure, std::sync::Arc<SpecialisedSet>)>,
    /// One compile at a time, on its own thread: a burst of structure changes compiles only what is still
    /// drawn when the compile before it has finished.
    compiling: Option<(Structure, CompileSlot)>,
    /// Milliseconds each structure took to compile, in the order they finished.
    compile_ms: Vec<(Structure, f64)>,
}

impl SpecialisedPipelines {
    /// The pipelines of `structure` if ready, marked as the most recently drawn.
    fn take(&mut self, structure: &Structure) -> Option<std::sync::Arc<SpecialisedSet>> {
        let k = self.ready.iter().position(|(s, _)| s == structure)?;
        let entry = self.ready.remove(k);
        let p = entry.1.clone();
        self.ready.insert(0, entry);
        Some(p)
    }

    fn keep(
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
    fn collect(&mut self) {
        let done = (self.compiling.as_ref())
            .and_then(|(_, slot)| slot.lock().ok().and_then(|mut slot| slot.take()));
        if let Some((set, ms)) = done {
            let (structure, _) = self.compiling.take().expect("a compile was under way");
            self.keep(structure, set, ms);
        }
    }
}

/// The field pass: its pipelines (one per integrator) and the GPU copies of one scene's data.
pub struct FieldRenderer {
    /// The generic pipelines of the three passes (`shaders::FIELD_PASSES`), indexed by `Chunk::pipeline`: without
    /// the search for a curve's brightest point, and with it, each built when a scene first needs it.
    generic: [Option<Pipelines>; 2],
    modules: Modules,
    pipeline_layout: wgpu::PipelineLayout,
    specialise: Specialise,
    specialised: SpecialisedPipelines,
    device: wgpu::Device,
    layout: wgpu::BindGroupLayout,
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
    uploaded: Option<Packed>,
    /// Rows per band of the next upload's dispatches (0: the whole texture in one band).
    band_rows: u32,
    /// The uploaded texture's bands: how many, their height, and the next one to dispatch (all dispatched:
    /// nothing pending).
    bands: u32,
    band_height: u32,
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
        let modules: Modules = std::array::from_fn(|k| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(&format!("energywave.field.{}", shaders::FIELD_PASSES[k].0)),
                source: wgpu::ShaderSource::Wgsl(shaders::field_module_source(k).into()),
            })
        });
        let storage = storage_buffer_entry;
        let (layout, pipeline_layout) = pass_layouts(
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
        );
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
            generic: [None, None],
            modules,
            pipeline_layout,
            specialise: Specialise::default(),
            specialised: SpecialisedPipelines::default(),
            device: device.clone(),
            layout,
            params,
            chunks: chunk_buffer(device, chunk_stride, 1),
            chunk_stride,
            buffers,
            texture: None,
            scratch: field_texture(device, "energywave.field.scratch", 1, FIELD_LAYERS),
            bind_group: None,
            uploaded: None,
            band_rows: 0,
            bands: 0,
            band_height: 0,
            next_band: 0,
            dispatches: 0,
            average: FrameAverage::new(device),
            average_frames: 1,
            averaged: 0,
        }
    }

    /// While the scene stays the same, averages up to `frames` renders of the jittered integrator, frame k
    /// (0-based) drawing its offsets with the seed `seed + k`; 1 (the default) renders each scene once. Applies
    /// to jittered scenes only: the others are deterministic, and rendered once.
    pub fn set_average_frames(&mut self, frames: u32) {
        self.average_frames = frames.max(1);
    }

    /// Whether the uploaded scene is averaged over frames.
    fn averaging(&self) -> bool {
        self.average_frames > 1 && self.uploaded.as_ref().is_some_and(|p| p.params.jitter != 0)
    }

    /// While averaging: the frames the picture holds and the most it will hold.
    pub fn averaged_frames(&self) -> Option<(u32, u32)> {
        self.averaging()
            .then_some((self.averaged, self.average_frames.max(self.averaged)))
    }

    /// The weight of the next frame of the mean, and the offsets' seed (frame `averaged`).
    fn prepare_average_frame(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        let (Some(packed), Some((texture, view))) = (&self.uploaded, &self.texture) else {
            return;
        };
        let mut params = packed.params;
        params.seed = params.seed.wrapping_add(self.averaged);
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.average.prepare(
            device,
            queue,
            texture,
            view,
            self.averaged + 1,
            params.layers,
        );
    }

    /// Uploads what the texture depends on. Returns true when it changed (the next `encode` re-renders).
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        billboard: &Billboard,
    ) -> Result<bool, GpuError> {
        let w = scene.billboard.resolution;
        let limit = device.limits().max_texture_dimension_2d;
        if w > limit {
            return Err(GpuError::ResolutionTooLarge {
                resolution: w,
                limit,
            });
        }
        let packed = pack(scene, billboard);
        if self.uploaded.as_ref() == Some(&packed) {
            if !self.averaging() || self.averaged >= self.average_frames {
                return Ok(false);
            }
            // The next frame of the average: new offsets, nothing else changes.
            checked(device, || self.prepare_average_frame(device, queue))?;
            self.next_band = 0;
            return Ok(true);
        }
        checked(device, || {
            let mut rebind = self.bind_group.is_none();
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
            for (buffer, bytes) in self.buffers.iter_mut().zip(data) {
                rebind |= buffer.write(device, queue, bytes);
            }
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&packed.params));
            // Every band dispatches every chunk over its rows: entry `band * chunks + k`.
            self.band_height = match self.band_rows {
                0 => w,
                rows => rows.min(w),
            };
            self.bands = w.div_ceil(self.band_height);
            let entries = packed.chunks.len() * self.bands as usize;
            let needed = entries as u64 * self.chunk_stride;
            if self.chunks.size() < needed {
                self.chunks = chunk_buffer(device, self.chunk_stride, entries);
                rebind = true;
            }
            let mut bytes = vec![0u8; needed as usize];
            for band in 0..self.bands {
                for (k, c) in packed.chunks.iter().enumerate() {
                    let entry = Chunk {
                        row_offset: band * self.band_height,
                        ..*c
                    };
                    let at = (band as usize * packed.chunks.len() + k) * self.chunk_stride as usize;
                    bytes[at..at + size_of::<Chunk>()].copy_from_slice(bytemuck::bytes_of(&entry));
                }
            }
            queue.write_buffer(&self.chunks, 0, &bytes);
            let layers = packed.params.layers;
            let stale = |t: &wgpu::Texture| {
                t.width() != w || t.depth_or_array_layers() != field_texture_layers(device, layers)
            };
            if self.texture.as_ref().is_none_or(|(t, _)| stale(t)) {
                self.texture = Some(field_texture(device, "energywave.field.storage", w, layers));
                rebind = true;
            }
            let kept = packed.chunks.iter().any(|c| c.stage != FINISH);
            let side = if kept { w } else { 1 };
            if self.scratch.0.width() != side {
                self.scratch =
                    field_texture(device, "energywave.field.scratch", side, FIELD_LAYERS);
                rebind = true;
            }
            if rebind {
                self.bind_group = Some(self.make_bind_group(device));
            }
        })?;
        self.uploaded = Some(packed);
        self.averaged = 0;
        if self.averaging() {
            checked(device, || self.prepare_average_frame(device, queue))?;
        }
        self.next_band = 0;
        Ok(true)
    }

    fn make_bind_group(&self, device: &wgpu::Device) -> wgpu::BindGroup {
        let view = &self
            .texture
            .as_ref()
            .expect("texture created before binding")
            .1;
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.params.as_entire_binding(),
        }];
        // Bindings 1 to 6, then the tints at 9, the color series at 10, the pieces at 11 and the clips at 13.
        for (i, b) in self.buffers.iter().enumerate() {
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
            binding: 7,
            resource: wgpu::BindingResource::TextureView(view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 12,
            resource: wgpu::BindingResource::TextureView(&self.scratch.1),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 8,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &self.chunks,
                offset: 0,
                size: wgpu::BufferSize::new(size_of::<Chunk>() as u64),
            }),
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.field.bind_group"),
            layout: &self.layout,
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
        let (Some(bind_group), Some(packed)) = (&self.bind_group, &self.uploaded) else {
            return false;
        };
        if !self.pending() {
            return true;
        }
        let w = packed.params.resolution;
        let specialised = Self::specialised_for(
            &mut self.specialised,
            self.specialise,
            &self.device,
            &self.modules,
            &self.pipeline_layout,
            Structure::of(&packed.params),
        );
        // The generic pipelines where the specialised ones are not ready, built the first time they are needed.
        let search = packed.params.search != 0;
        let ready = |k: u32| (specialised.as_ref()).is_some_and(|set| set[k as usize].is_some());
        if !packed.chunks.iter().all(|c| ready(c.pipeline)) {
            let (device, modules, layout) = (&self.device, &self.modules, &self.pipeline_layout);
            self.generic[search as usize]
                .get_or_insert_with(|| build_pipelines(device, modules, layout, search));
        }
        let generic = &self.generic[search as usize];
        let pipeline = |k: usize| {
            (specialised.as_ref())
                .and_then(|set| set[k].as_ref())
                .or_else(|| generic.as_ref().map(|g| &g[k]))
                .expect("the generic pipelines are built where the specialised are not ready")
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.field.pass"),
            timestamp_writes: timestamps,
        });
        let last = self.next_band.saturating_add(bands).min(self.bands);
        for band in self.next_band..last {
            let rows = self.band_height.min(w - band * self.band_height);
            for (k, c) in packed.chunks.iter().enumerate() {
                let entry = band as usize * packed.chunks.len() + k;
                pass.set_pipeline(pipeline(c.pipeline as usize));
                pass.set_bind_group(0, bind_group, &[(entry as u64 * self.chunk_stride) as u32]);
                pass.dispatch_workgroups(w.div_ceil(8), rows.div_ceil(8), 1);
            }
        }
        self.next_band = last;
        if self.pending() {
            return false;
        }
        if self.averaging() {
            self.average.encode(&mut pass);
            self.averaged += 1;
        }
        self.dispatches += 1;
        true
    }

    /// The pipelines specialised to `structure` if they are ready: compiled now (`Blocking`), or their compile
    /// started on a thread of its own if it is not under way yet (`Background`, which returns `None` until it
    /// has finished).
    fn specialised_for(
        cache: &mut SpecialisedPipelines,
        mode: Specialise,
        device: &wgpu::Device,
        modules: &Modules,
        layout: &wgpu::PipelineLayout,
        structure: Structure,
    ) -> Option<std::sync::Arc<SpecialisedSet>> {
        if mode == Specialise::Off {
            return None;
        }
        cache.collect();
        if let Some(p) = cache.take(&structure) {
            return Some(p);
        }
        match mode {
            Specialise::Off => None,
            Specialise::IfReady => None,
            Specialise::Blocking => {
                let start = std::time::Instant::now();
                let set = build_specialised(device, modules, layout, structure);
                Some(cache.keep(structure, set, start.elapsed().as_secs_f64() * 1e3))
            }
            Specialise::Background => {
                Self::start_compile(cache, device, modules, layout, structure);
                None
            }
        }
    }

    /// Starts compiling `structure`'s pipelines on a thread of its own, unless a compile is under way (one at
    /// a time: a burst of structure changes compiles what is drawn when the compile before it has finished).
    /// Never on GL: there every call holds the one GL context, so a compile on another thread (seconds on
    /// llvmpipe) holds up every frame, and wgpu gives up on the context after 6 s with a panic; the generic
    /// pipelines draw there instead.
    fn start_compile(
        cache: &mut SpecialisedPipelines,
        device: &wgpu::Device,
        modules: &Modules,
        layout: &wgpu::PipelineLayout,
        structure: Structure,
    ) {
        if cache.compiling.is_some() || device.adapter_info().backend == wgpu::Backend::Gl {
            return;
        }
        let slot = CompileSlot::default();
        let (device, modules, layout) = (device.clone(), modules.clone(), layout.clone());
        let out = slot.clone();
        let spawned = std::thread::Builder::new()
            .name("energywave field compile".into())
            .spawn(move || {
                let start = std::time::Instant::now();
                let p = build_specialised(&device, &modules, &layout, structure);
                if let Ok(mut slot) = out.lock() {
                    *slot = Some((p, start.elapsed().as_secs_f64() * 1e3));
                }
            });
        if spawned.is_ok() {
            cache.compiling = Some((structure, slot));
        }
    }

    /// Starts compiling the uploaded scene's specialised pipelines on a thread of their own, if they are not
    /// ready and no compile is under way (`Specialise::IfReady`: the viewer calls this once its picture is
    /// whole). Returns whether a compile is under way.
    pub fn compile_in_background(&mut self) -> bool {
        self.specialised.collect();
        if let Some(p) = &self.uploaded {
            let structure = Structure::of(&p.params);
            if !self.specialised_ready(&structure) {
                Self::start_compile(
                    &mut self.specialised,
                    &self.device,
                    &self.modules,
                    &self.pipeline_layout,
                    structure,
                );
            }
        }
        self.compiling()
    }

    /// When to use pipelines specialised to the scene's structure (`Specialise::Off` by default).
    pub fn set_specialise(&mut self, mode: Specialise) {
        self.specialise = mode;
    }

    /// Whether the pipelines specialised to `structure` are ready (they draw the next dispatch of it).
    pub fn specialised_ready(&self, structure: &Structure) -> bool {
        self.specialised.ready.iter().any(|(s, _)| s == structure)
    }

    /// Whether a specialised compile is under way on its thread.
    pub fn compiling(&self) -> bool {
        self.specialised.compiling.is_some()
    }

    /// How long each structure's pipelines took to compile, in milliseconds, in the order they finished.
    pub fn compile_times(&self) -> &[(Structure, f64)] {
        &self.specialised.compile_ms
    }

    /// Whether bands of the uploaded scene are still to be dispatched.
    pub fn pending(&self) -> bool {
        self.uploaded.is_some() && self.next_band < self.bands
    }

    /// The height of the bands of the next upload, in rows (rounded up to the shader's 8 x 8 workgroups; 0:
    /// the whole texture at once, the default). The viewer refines its picture a few bands a frame.
    pub fn set_band_rows(&mut self, rows: u32) {
        self.band_rows = rows.div_ceil(8) * 8;
    }

    /// How many bands the uploaded texture is dispatched in, and how many rows each holds.
    pub fn band_layout(&self) -> (u32, u32) {
        (self.bands, self.band_height)
    }

    /// Whether the texture shows `inputs` completely (uploaded, and every band dispatched).
    pub fn shows(&self, inputs: &FieldInputs) -> bool {
        self.uploaded.as_ref() == Some(&inputs.0) && !self.pending()
    }

    /// Whether `inputs` are the uploaded scene's (complete or not).
    pub fn holds(&self, inputs: &FieldInputs) -> bool {
        self.uploaded.as_ref() == Some(&inputs.0)
    }

    /// GPU memory the field pass holds now: the texture, the uniform and the storage buffers, in bytes.
    pub fn gpu_bytes(&self) -> u64 {
        let texture = self.texture.as_ref().map_or(0, |(t, _)| {
            field_texture_bytes(t.width(), t.depth_or_array_layers())
        });
        let scratch = &self.scratch.0;
        texture
            + field_texture_bytes(scratch.width(), scratch.depth_or_array_layers())
            + self.params.size()
            + self.buffers.iter().map(|b| b.buffer.size()).sum::<u64>()
            + self.average.gpu_bytes()
    }

    /// The brightness texture and its view (after the first `prepare`): the mean of the frames so far while
    /// averaging, else the last frame.
    fn shown(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        if self.averaging() && self.averaged > 0 {
            self.average.mean()
        } else {
            self.texture.as_ref().map(|(t, v)| (t, v))
        }
    }

    /// The layers of the field texture the last `prepare` wrote (`layers_of` its scene): 1, B alone, or
    /// `FIELD_LAYERS`, B and the tint.
    pub fn layers(&self) -> u32 {
        self.uploaded.as_ref().map_or(1, |p| p.params.layers)
    }

    /// The field texture (after the first `prepare`).
    pub fn texture(&self) -> Option<&wgpu::Texture> {
        self.shown().map(|(t, _)| t)
    }

    /// A view of the brightness texture (after the first `prepare`).
    pub fn view(&self) -> Option<&wgpu::TextureView> {
        self.shown().map(|(_, v)| v)
    }

    /// How many times the texture has been rendered.
    pub fn dispatch_count(&self) -> u64 {
        self.dispatches
    }

    /// Forgets the uploaded scene, so the next `prepare` re-renders.
    pub fn invalidate(&mut self) {
        self.uploaded = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Curve, Point, Torus};
    use glam::DVec3;

    /// The value the field module declares for `const NAME: TYPE = VALUE;`, as f64.
    fn shader_constant(name: &str) -> f64 {
        let source = crate::gpu::shaders::field_module_source(2);
        let start = format!("const {name}: ");
        let line = source
            .lines()
            .find(|l| l.trim_start().starts_with(&start))
            .unwrap_or_else(|| panic!("the field module declares {name}"));
        let value = line
            .split('=')
            .nth(1)
            .expect("a value")
            .trim()
            .trim_end_matches(';');
        value
            .trim_end_matches('u')
            .parse()
            .unwrap_or_else(|e| panic!("{name} = {value}: {e}"))
    }

    #[test]
    fn the_constants_shared_with_the_twin_are_generated_from_it_and_declared_once() {
        // Mirrored by hand they drifted apart once (8 panels on the CPU against 4 on the GPU, unnoticed): now the
        // module's declarations are written from the twin's definitions, and no WGSL file declares them again.
        use crate::gpu::shaders;
        use crate::integrate::adaptive as a;
        let shared: &[(&str, f64)] = &[
            ("SCAN", a::SCAN as f64),
            ("JUMP", a::JUMP),
            ("PARAM_JUMP", a::PARAM_JUMP),
            ("END_SNAP", a::END_SNAP),
            ("KINK_ROUNDS", a::KINK_ROUNDS as f64),
            ("KINK_BRACKET", a::KINK_BRACKET),
            ("FINE_KINK_BRACKET", a::FINE_KINK_BRACKET),
            ("KINK_PROBE", a::KINK_PROBE),
            ("MAX_KINKS", a::MAX_KINKS as f64),
            ("U_PANEL", a::U_PANEL),
            ("MAX_GAUSS_PANELS", a::MAX_GAUSS_PANELS as f64),
            ("MAX_DEPTH", a::MAX_DEPTH as f64),
            ("MAX_REFINEMENTS", a::MAX_REFINEMENTS as f64),
            ("COARSE_ORDER", a::COARSE_ORDER as f64),
            ("COARSE_REFINEMENTS", a::COARSE_REFINEMENTS as f64),
            ("MAX_PEAKS", a::MAX_PEAKS as f64),
            ("PEAK_NEWTON", a::PEAK_NEWTON as f64),
            ("PEAK_SETTLED", a::PEAK_SETTLED),
            ("CUT_MERGE", a::CUT_MERGE),
            ("SINGULAR_MERGE", a::SINGULAR_MERGE),
            ("SWITCH_ROUNDS", a::SWITCH_ROUNDS as f64),
            ("SWITCH_INSET", a::SWITCH_INSET),
            ("MAX_WIDTH", a::MAX_WIDTH),
            ("MIN_AXIS_WIDTH", a::MIN_AXIS_WIDTH),
            ("RING_NEWTON", a::RING_NEWTON as f64),
            ("RING_STEP", a::RING_STEP),
            ("DEGENERATE", crate::field::curve::DEGENERATE),
            ("CLOSED_FORM_CONDITION", a::CLOSED_FORM_CONDITION),
            ("TRACK_NEWTON", TRACK_NEWTON as f64),
            ("KRONROD_ROWS", a::KRONROD.len() as f64),
        ];
        let module = shaders::field_module_source(2);
        for &(name, want) in shared {
            let got = shader_constant(name);
            assert!(
                (got - want).abs() <= 1e-7 * want.abs(),
                "{name}: the shader declares {got}, the f64 twin {want}"
            );
            let declaration = format!("const {name}: ");
            assert_eq!(
                module.matches(&declaration).count(),
                1,
                "{name} declared once"
            );
            for (file, text) in [
                ("field_common.wgsl", shaders::FIELD_COMMON),
                ("field_pass.wgsl", shaders::FIELD_PASS),
                ("simpson.wgsl", shaders::SIMPSON_PASS),
                ("adaptive.wgsl", shaders::ADAPTIVE_COMMON),
                ("adaptive_smooth.wgsl", shaders::ADAPTIVE_SMOOTH_PASS),
                ("adaptive_curves.wgsl", shaders::ADAPTIVE_CURVES_PASS),
            ] {
                assert!(
                    !text.contains(&declaration),
                    "{file} declares {name} by hand"
                );
            }
        }
        // The Gauss-Kronrod table, row by row, and where each pair starts.
        let rows: Vec<&str> = module
            .lines()
            .skip_while(|l| !l.starts_with("const KRONROD: "))
            .skip(1)
            .take_while(|l| l.trim_start().starts_with("vec3<f32>("))
            .collect();
        assert_eq!(rows.len(), a::KRONROD.len());
        for (row, (x, k, g)) in rows.iter().zip(a::KRONROD) {
            let values: Vec<f32> = row
                .trim()
                .trim_start_matches("vec3<f32>(")
                .trim_end_matches("),")
                .split(", ")
                .map(|v| v.parse().expect("a number"))
                .collect();
            assert_eq!(values, [x as f32, k as f32, g as f32], "{row}");
        }
        for (k, n) in a::KRONROD_ORDERS
            .iter()
            .enumerate()
            .take(a::KRONROD_ORDERS.len() - 1)
        {
            let case = format!("case {n}u: {{ return {}u; }}", a::KRONROD_START[k]);
            assert!(module.contains(&case), "kronrod_start: {case}");
        }
    }

    /// A scene of `points` points, one torus and curves of the given segment counts.
    fn scene(points: usize, curves: &[usize], integrator: Integrator) -> Packed {
        let mut s = Scene::default_scene();
        s.sources.points = (0..points)
            .map(|i| Point {
                position: DVec3::new(i as f64, 0.0, 0.0),
                coefficient: 1.0,
                look: Default::default(),
            })
            .collect();
        s.sources.lines.clear();
        s.sources.tori = vec![Torus {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            major_radius: 1.0,
            coefficient: 1.0,
            look: Default::default(),
        }];
        s.sources.curves = curves
            .iter()
            .map(|&k| Curve {
                control_points: (0..=2 * k)
                    .map(|i| DVec3::new(i as f64, 1.0, 0.0))
                    .collect(),
                coefficient: 1.0,
                weights: vec![1.0],
                look: Default::default(),
                color_series: Vec::new(),
                w_form: crate::field::WForm::Nearest,
            })
            .collect();
        s.integration.integrator = integrator;
        pack(&s, &s.place_billboard(1.0))
    }

    /// Every term exactly once, in order; the first dispatch writes and the others add.
    fn check_cover(p: &Packed, terms: u32) {
        let mut next = 0;
        for (k, c) in p.chunks.iter().enumerate() {
            assert_eq!(c.first, next, "chunk {k} starts where the last ended");
            assert!(c.count > 0 || terms == 0);
            assert_eq!(c.accumulate, (k > 0) as u32);
            next += c.count;
        }
        assert_eq!(next, terms);
    }

    #[test]
    fn adaptive_dispatches_run_points_lines_and_tori_apart_from_curves_within_the_budget() {
        let p = scene(2, &[1, 2, 40], Integrator::Adaptive);
        check_cover(&p, 6);
        for c in &p.chunks {
            let last = c.first + c.count;
            // Points and the torus (terms 0..3) on the smooth terms' pipeline, curves on their own.
            let want = if last <= 3 {
                ADAPTIVE_SMOOTH
            } else {
                assert!(c.first >= 3, "a dispatch mixes the two families: {c:?}");
                ADAPTIVE_CURVES
            };
            assert_eq!(c.pipeline, want, "{c:?}");
            // A dispatch of several curves stays within the budget.
            if c.pipeline == ADAPTIVE_CURVES && c.count > 1 {
                let cost: u64 = (c.first..last)
                    .map(|t| p.curves[(t - 3) as usize].segment_count)
                    .map(|k| {
                        adaptive_curve_iterations(p.params.gauss_order, curve_iterations(k, 0))
                    })
                    .sum();
                assert!(cost <= ITERATION_BUDGET, "{c:?} costs {cost}");
            }
        }
        // The 40-segment chain costs more than the budget alone: it has a dispatch of its own.
        assert!(p.chunks.iter().any(|c| c.first == 5 && c.count == 1));
        assert!(p.chunks.len() >= 3);
    }

    #[test]
    fn simpson_dispatches_are_ranges_of_samples_on_its_pipeline() {
        let p = scene(1, &[2], Integrator::Simpson);
        check_cover(&p, p.params.divisions + 1);
        assert!(p.chunks.iter().all(|c| c.pipeline == SIMPSON));
    }

    #[test]
    fn a_scene_without_sources_still_writes_the_texture() {
        let mut p = scene(0, &[], Integrator::Adaptive);
        p.params.torus_count = 0;
        p.tori.clear();
        let chunks = plan_chunks(&p);
        assert_eq!(chunks.len(), 1);
        assert_eq!((chunks[0].count, chunks[0].accumulate), (0, 0));
    }
}
