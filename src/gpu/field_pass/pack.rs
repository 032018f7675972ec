//! What the field pass uploads: the scene's sources and settings packed as the WGSL reads them, and the
//! dispatches planned within what an invocation may loop.

use wgpu::util::DeviceExt;

use super::super::context::FIELD_LAYERS;
use super::super::shaders;
use crate::field::curve::segments;
use crate::frame::{FrameSetup, Term};
use crate::integrate::{Decay, Integrator};
use crate::scene::Scene;

use super::gpu_data::*;
use super::refine::Refinement;
use crate::frame::refine::forced_mask;

/// What the field texture of a scene and billboard depends on (equal inputs give equal textures): compare the
/// inputs of two frames to tell whether the field changed between them.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldInputs(pub(super) Packed);

impl FieldInputs {
    /// The field pass's inputs for a frame: its sources and settings packed as the WGSL reads them.
    pub fn of(setup: &FrameSetup) -> Self {
        FieldInputs(pack(setup))
    }

    /// The side of the texture these inputs integrate, in texels.
    pub fn resolution(&self) -> u32 {
        self.0.params.resolution
    }
}

/// Everything the field pass reads, packed for upload; equal packs give equal textures.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Packed {
    pub(super) params: FieldParams,
    pub(super) points: Vec<PointSource>,
    pub(super) lines: Vec<LineSource>,
    pub(super) tori: Vec<TorusSource>,
    pub(super) curves: Vec<CurveSource>,
    pub(super) segments: Vec<CurveSegment>,
    pub(super) weights: Vec<f32>,
    /// Each term's `Ce_i - Ce` (`frame::Term::tint`) in rgb, points first, then lines, tori and curves.
    pub(super) tints: Vec<[f32; 4]>,
    /// The curves' color series, their intensity applied, in rgb (`CurveSource::first_color`).
    pub(super) colors: Vec<[f32; 4]>,
    /// The pieces of the curves whose term reads their brightest point (`CurveSource::first_piece`).
    pub(super) pieces: Vec<CurvePiece>,
    /// The share of each texel's ray before the first surface of the scene's objects (`objects::clip`), or
    /// nothing without objects.
    pub(super) clips: std::sync::Arc<Vec<f32>>,
    /// The dispatches that together integrate the texture.
    pub(super) chunks: Vec<Chunk>,
    /// Where the texture is refined in image space (`frame::refine`): its tolerance and forced texels.
    pub(super) refinement: Option<Refinement>,
}

/// Loop iterations one invocation may spend: Mesa's llvmpipe and lavapipe stop all loops of an invocation after
/// 65535 iterations in all (silently); this leaves room for the estimate's slack.
pub(super) const ITERATION_BUDGET: u64 = 30_000;
/// Rules the adaptive integrator applies to one term at most: `MAX_GAUSS_PANELS` panels on each of `cuts` parts
/// of its pieces, and two more for each of its `MAX_REFINEMENTS` refinements; each rule evaluates the term at the
/// `2n + 1` nodes of the Kronrod rule, at most 21.
pub(super) const fn rules(cuts: u64) -> u64 {
    use crate::integrate::adaptive::{MAX_GAUSS_PANELS, MAX_REFINEMENTS};
    cuts * MAX_GAUSS_PANELS as u64 + 2 * MAX_REFINEMENTS as u64
}
/// Loop iterations of one rule of the pair of `order`: its `2n + 1` nodes, the rule's own loop, and the
/// bisection's walk up after it.
pub(super) const fn rule_iterations(order: u32) -> u64 {
    2 * order as u64 + 2 + crate::integrate::adaptive::MAX_DEPTH as u64
}
/// Evaluations of a curve's distance the adaptive integrator spends on its term at most (each a loop over its
/// segments): the scan, the samples at its ends, the kink search's probes, the Newton steps of its closest
/// approaches, a sample for each knot cut, and the rules on every cut (at most `MAX_PEAKS` pieces, two closest
/// approaches and two ends, each cut at its flat top's ends, and the kinks).
pub(super) const fn curve_evaluations(order: u32) -> u64 {
    use crate::integrate::adaptive::{
        BRIGHT_SCAN, CUT_BISECTIONS, EXACT_SAMPLES, KINK_ROUNDS, MAX_KINKS, MAX_PEAKS, MINIMA,
        PEAK_NEWTON, SCAN, SUB_SCAN,
    };
    let cuts = 3 * MAX_PEAKS as u64 + MAX_KINKS as u64;
    // The scan, finer where it suspects a rival segment; the closest approaches' checks (the two passes over the
    // segments that find them cost about one evaluation each).
    (SCAN as u64 * SUB_SCAN as u64 + 1)
        + EXACT_SAMPLES as u64
        + 2
        // The continuous W form's scan, and the bisections that place its cuts (loop iterations, counted alike).
        + (BRIGHT_SCAN as u64 + 1)
        + MAX_KINKS as u64 * CUT_BISECTIONS as u64
        + 2
        + 2 * KINK_ROUNDS as u64 * MAX_KINKS as u64
        + MINIMA as u64 * PEAK_NEWTON as u64
        + MAX_KINKS as u64
        + rules(cuts) * rule_iterations(order)
}
/// Loop iterations of a point's, a line's or a torus's term at most: the pole series on the closed form's two
/// pieces (where it then declines), Newton on the ring, then three pieces of three cuts, each of its rules a loop
/// over its nodes, and the bisection's walk up after each.
pub(super) const fn smooth_iterations(order: u32) -> u64 {
    2 * crate::integrate::adaptive::POLE_SERIES_TERMS_F32 as u64
        + 20
        + rules(3 * 3) * rule_iterations(order)
}

/// Loop iterations of one evaluation of a source's distance (a curve loops over its segments and roots), or of its
/// brightest point (`pieces` > 0: over its pieces twice, the parts each walk visits and the Newton steps on the two
/// maxima a piece has at most and on the flat top's two ends, and the adaptive pass's check of every piece's bound
/// where it carries the point on).
pub(super) fn curve_iterations(segments: u32, pieces: u32) -> u64 {
    use crate::field::brightest::{ROOT_NEWTON, ROOT_VISITS};
    if pieces > 0 {
        2 + pieces as u64 * (4 + ROOT_VISITS as u64 + 4 * ROOT_NEWTON as u64)
    } else {
        1 + 12 * segments as u64
    }
}

/// Newton steps a Gauss node of a curve's piece takes from the last node's nearest point before it falls back, if
/// it must, to solving the cubic.
pub(super) const TRACK_NEWTON: u64 = shaders::TRACK_NEWTON as u64;

/// Loop iterations of a curve's term in the adaptive integrator at most, `iterations` those of one evaluation of
/// its distance: each evaluation may take Newton's steps from the last node (`track_nearest` in the shader), then
/// solve the piece's segment alone, then the whole chain (`nearest_on_chain_from`), in an outer loop of its own.
pub(super) fn adaptive_curve_iterations(order: u32, iterations: u64) -> u64 {
    curve_evaluations(order) * (TRACK_NEWTON + iterations + curve_iterations(1, 0) + 1)
}

/// `Chunk::stage`: the dispatch adds the sums the scratch texture keeps to its own (`KEPT`), and finishes the
/// term into the field (`FINISH`; else it keeps its sums in the scratch texture).
pub(super) const KEPT: u32 = 1;
pub(super) const FINISH: u32 = 2;
/// `FieldParams::decay` of the rms decay.
pub(super) const RMS: u32 = 1;

/// The pipelines: simpson's, the adaptive integrator's for points, lines and tori, and for curves.
pub(super) const SIMPSON: u32 = 0;
pub(super) const ADAPTIVE_SMOOTH: u32 = 1;
pub(super) const ADAPTIVE_CURVES: u32 = 2;

/// Splits the integration into dispatches that each stay within `ITERATION_BUDGET` loop iterations a texel.
pub(super) fn plan_chunks(p: &Packed) -> Vec<Chunk> {
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
                    listed: 0,
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

pub(super) fn v3(v: glam::DVec3) -> [f32; 3] {
    v.as_vec3().to_array()
}

pub(super) fn pack(setup: &FrameSetup) -> Packed {
    let (scene, billboard, reach) = (setup.scene, &setup.billboard, setup.reach);
    let i = &setup.integration;
    let mut packed = pack_sources(setup);
    packed.params = FieldParams {
        center: v3(billboard.center),
        size: billboard.size as f32,
        right: v3(billboard.right),
        resolution: setup.resolution,
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
        term_tolerance: setup.term_tolerance as f32,
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
    if let Some(clips) = setup.clips() {
        packed.clips = clips;
        packed.params.clipped = 1;
    }
    packed.chunks = plan_chunks(&packed);
    let refine = setup.refine;
    if let Some((tolerance, levels)) = refine.tolerance().zip(refine.levels(setup.resolution)) {
        let forced = forced_mask(
            &levels,
            packed.params.clipped.eq(&1).then_some(&packed.clips[..]),
        );
        packed.refinement = Some(Refinement {
            tolerance: tolerance as f32,
            levels,
            forced: std::sync::Arc::new(forced),
        });
    }
    packed
}

/// The sources as the field's shaders read them, with their counts, the layers and the search flag in params
/// (the scene's own epsilon there; nothing of the billboard, the rays or the integrator).
pub(super) fn pack_sources(setup: &FrameSetup) -> Packed {
    let (scene, s) = (setup.scene, &setup.scene.sources);
    let tinted = (setup.terms.iter()).any(|t| t.tint.iter().any(|&x| x != 0.0));
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
        tints: (setup.terms.iter())
            .map(|Term { tint: t, .. }| [t[0] as f32, t[1] as f32, t[2] as f32, 0.0])
            .collect(),
        ..Packed::default()
    };
    for (c, term) in s.curves.iter().zip(&setup.terms[setup.first_curve()..]) {
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
        let intensity = term.intensity;
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
            zero_end: q.zero_end.map_or(-1.0, |r| r as f32),
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
    // 2 where every curve's term reads its brightest point: the passes then hold the search alone, without the
    // nearest point's code beside it. lavapipe pays for the code a pass holds whether a lane runs it or not: the
    // default scene's field pass takes a quarter less time (benches/README.md).
    let searching = packed.curves.iter().filter(|c| c.piece_count > 0).count();
    packed.params.search = match searching {
        0 => 0,
        n if n == packed.curves.len() => 2,
        _ => 1,
    };
    packed
}

/// The bindings of `shaders/shared/field_pass.wgsl` that hold the sources, beside params at 0: points, lines, tori,
/// curves, segments, weights, tints, color series and pieces (`source_bindings`).
pub(crate) const SOURCE_BINDINGS: [u32; 9] = [1, 2, 3, 4, 5, 6, 9, 10, 11];

/// What a pass that evaluates the field's terms at points of its own reads (`gpu::object_pass`): params with the
/// source counts, `scene.integration.epsilon` and the search flag, and the contents of `SOURCE_BINDINGS`.
pub(crate) fn source_bindings(setup: &FrameSetup) -> (FieldParams, [Vec<u8>; 9]) {
    let p = pack_sources(setup);
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

/// What the field pass reads for a whole frame (params with the view, the rays and the integrator, and the
/// contents of `SOURCE_BINDINGS`), for the effect shader of game engines (`crate::engine`).
pub(crate) fn frame_bindings(setup: &FrameSetup) -> (FieldParams, [Vec<u8>; 9]) {
    let p = pack(setup);
    let (_, bytes) = source_bindings(setup);
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
pub(super) fn chunk_buffer(device: &wgpu::Device, stride: u64, count: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("energywave.field.chunks"),
        size: stride * count.max(1) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
