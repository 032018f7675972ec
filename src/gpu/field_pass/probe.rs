//! The field's terms at single points, evaluated on the GPU by the field passes' own WGSL functions, beside the
//! passes' bindings: for tests that hold the f32 evaluation to the f64 twin and to oracles point by point, where a
//! texel's integral would average a wrong stretch away.

use glam::DVec3;

use super::{FieldInputs, FieldRenderer};
use crate::frame::FrameSetup;
use crate::gpu::context::{GpuContext, GpuError};

/// The entry point: curve `CURVE`'s term (its coefficient times Sw at the point its term reads, over
/// max(eps, distance)) at the points packed four floats each into the clips binding, then the chain parameter and
/// distance of that point, written three texels a point into the field texture.
const PROBE: &str = "#import shared/brightest.wgsl

override CURVE: u32 = 0u;

@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
    load_scalars();
    let side = textureDimensions(field).x;
    if id.x >= arrayLength(&clips) / 4u {
        return;
    }
    let p = vec3<f32>(clips[4u * id.x], clips[4u * id.x + 1u], clips[4u * id.x + 2u]);
    let c = curves[CURVE];
    let held = held_chain(c);
    let best = curve_point(c, held, p);
    let f = c.coefficient * wseries(c, held.weights, best.x) * falloff(best.y, EPSILON);
    let values = vec3<f32>(f, best.x, best.y);
    for (var k = 0u; k < 3u; k++) {
        let o = 3u * id.x + k;
        textureStore(field, vec2<i32>(i32(o % side), i32(o / side)), 0, vec4<f32>(values[k], 0.0, 0.0, 0.0));
    }
}
";

/// A curve's term at points, on the GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveProbe {
    /// The term: coefficient times Sw(t) / max(eps, distance).
    pub term: f32,
    /// The chain parameter of the point the term reads (the nearest, or in the continuous W form the brightest).
    pub t: f32,
    /// Its distance from the point.
    pub distance: f32,
}

/// Curve `curve`'s term of `setup`'s scene at each of `points` (rounded to f32), evaluated by the field passes'
/// own functions (`curve_point`, `wseries`) with the frame's packed sources and eps.
pub fn curve_terms(
    ctx: &GpuContext,
    setup: &FrameSetup,
    curve: usize,
    points: &[DVec3],
) -> Result<Vec<CurveProbe>, GpuError> {
    assert!(curve < setup.scene.sources.curves.len(), "no curve {curve}");
    let side = ((3 * points.len().max(1)) as f64).sqrt().ceil() as u32;
    let mut inputs = FieldInputs::of(setup);
    inputs.0.params.resolution = side;
    inputs.0.refinement = None;
    inputs.0.clips = std::sync::Arc::new(
        points
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32, 0.0])
            .collect(),
    );
    let device = &ctx.device;
    let mut pass = FieldRenderer::new(device);
    pass.prepare(device, &ctx.queue, &inputs)?;
    let source = crate::gpu::shaders::compose_with("probe.wgsl", &|path| match path {
        "probe.wgsl" => Some(PROBE.to_string()),
        other => crate::gpu::shaders::file(other),
    })
    .map_err(|e| GpuError::Validation(e.into()))?;
    let pipeline = ctx.checked(|| {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("energywave.probe"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("energywave.probe"),
            bind_group_layouts: &[Some(pass.pipelines.layout())],
            immediate_size: 0,
        });
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("energywave.probe"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("probe"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &[
                    ("SEARCH", inputs.0.params.search as f64),
                    ("CURVE", curve as f64),
                ],
                ..Default::default()
            },
            cache: None,
        })
    })?;
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut cp = encoder.begin_compute_pass(&Default::default());
        cp.set_pipeline(&pipeline);
        cp.set_bind_group(0, pass.resources.bind_group.as_ref(), &[0]);
        cp.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let texture = &pass.resources.texture.as_ref().expect("made by prepare").0;
    let bytes = ctx.read_texture(texture, 4)?;
    let values: &[f32] = bytemuck::cast_slice(&bytes);
    Ok(values
        .chunks_exact(3)
        .take(points.len())
        .map(|v| CurveProbe {
            term: v[0],
            t: v[1],
            distance: v[2],
        })
        .collect())
}
