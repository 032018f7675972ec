//! The baseline our Simpson pass is held against: a plainly written compute kernel specialised to one scene.
//!
//! Everything about the frame is written into the kernel's text as constants: the billboard, the eye, the
//! decay, every source (a chain's segments in power form, so that the compiler folds the coefficients of
//! each segment's stationary cubic that do not depend on the sample), the resolution and Simpson's n. One
//! loop over the samples of a texel's ray, the sources written out inside it, each chain's nearest point by
//! Cardano's formula and two Newton steps, one dispatch, B alone. It computes what our `simpson` pass
//! computes (the papers' Simpson's rule, METHOD.md section 3) for the scenes it takes: no W or color series,
//! no objects, the papers' decay, no jitter; `tests/specialised.rs` holds it to the f64 twin.

use std::collections::HashMap;
use std::fmt::Write;

use glam::DVec3;
use serde::Serialize;

use crate::field::brightest::uniform;
use crate::field::curve::segments;
use crate::frame::FrameSetup;
use crate::gpu::{
    GpuContext, GpuError, compute_pass, field_storage_entry, field_texture, storage_buffer_entry,
};
use crate::integrate::{Decay, Integrator};
use crate::scene::Scene;

/// Why a scene cannot be drawn by the plain kernel: it is written for the papers' own scenes.
pub fn plain_unsupported(scene: &Scene) -> Option<&'static str> {
    let i = &scene.integration;
    if i.integrator != Integrator::Simpson || i.jitter.is_some() {
        return Some("the plain kernel runs Simpson's rule without jitter");
    }
    if i.decay != Decay::Distance {
        return Some("the plain kernel has the papers' decay only");
    }
    if !scene.objects.is_empty() {
        return Some("the plain kernel has no objects");
    }
    let c = &scene.sources.curves;
    if c.iter()
        .any(|c| !uniform(&c.weights) || !c.color_series.is_empty())
    {
        return Some("the plain kernel has no W or color series");
    }
    None
}

fn f(x: f64) -> String {
    format!("{:e}", x as f32)
}

fn v(x: DVec3) -> String {
    format!("vec3<f32>({}, {}, {})", f(x.x), f(x.y), f(x.z))
}

/// What a plain kernel holds as constants of its text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Baked {
    /// Everything: the frame's values and its structure (the resolution, n, the sources and their kinds).
    All,
    /// The structure alone: the frame's values (billboard, eye, decay, every source's numbers) are read from a
    /// storage buffer once an invocation, so that an edit needs no new pipeline, as in our field pass.
    Structure,
}

/// The values a kernel's text names: literals where `Baked::All`, else private variables loaded from the
/// `values` buffer at the start of the entry point.
struct Values {
    baked: Baked,
    data: Vec<[f32; 4]>,
    declarations: String,
    loads: String,
}

impl Values {
    fn named(
        &mut self,
        name: &str,
        x: [f64; 3],
        ty: &str,
        swizzle: &str,
        literal: String,
    ) -> String {
        if self.baked == Baked::All {
            let _ = writeln!(self.declarations, "const {name} = {literal};");
            return name.to_owned();
        }
        let k = self.data.len();
        self.data.push([x[0] as f32, x[1] as f32, x[2] as f32, 0.0]);
        let _ = writeln!(self.declarations, "var<private> {name}: {ty};");
        let _ = writeln!(self.loads, "    {name} = values[{k}]{swizzle};");
        name.to_owned()
    }

    fn vector(&mut self, name: &str, x: DVec3) -> String {
        self.named(name, x.to_array(), "vec3<f32>", ".xyz", v(x))
    }

    fn scalar(&mut self, name: &str, x: f64) -> String {
        self.named(name, [x, 0.0, 0.0], "f32", ".x", f(x))
    }
}

/// The kernel's WGSL for `scene` (see the module's documentation) and the values its buffer holds (none where
/// `Baked::All`), or why it has none.
pub fn plain_kernel_source(
    scene: &Scene,
    baked: Baked,
) -> Result<(String, Vec<[f32; 4]>), &'static str> {
    if let Some(why) = plain_unsupported(scene) {
        return Err(why);
    }
    let setup = FrameSetup::placed(scene, 1.0);
    let b = &setup.billboard;
    let i = &setup.integration;
    let w = setup.resolution;
    let n = i.divisions;
    let mut values = Values {
        baked,
        data: Vec::new(),
        declarations: String::new(),
        loads: String::new(),
    };
    values.vector("CENTER", b.center);
    values.vector("RIGHT", b.right);
    values.vector("UP", b.up);
    values.vector("EYE", setup.eye());
    values.scalar("SIZE", b.size);
    values.scalar("NU", setup.reach.nu);
    values.scalar("ALPHA", i.alpha);
    values.scalar("BETA", i.beta);
    values.scalar("EPS", i.epsilon);
    let mut psi = String::new();
    let sources = &scene.sources;
    for (k, p) in sources.points.iter().enumerate() {
        let _ = writeln!(
            psi,
            "    sum += {} / max(EPS, length(p - {}));",
            values.scalar(&format!("POINT{k}_C"), p.coefficient),
            values.vector(&format!("POINT{k}_X"), p.position)
        );
    }
    for (k, l) in sources.lines.iter().enumerate() {
        let _ = writeln!(
            psi,
            "    {{ let q = p - {}; sum += {} / max(EPS, length(q - {d} * dot(q, {d}))); }}",
            values.vector(&format!("LINE{k}_X"), l.point),
            values.scalar(&format!("LINE{k}_C"), l.coefficient),
            d = values.vector(&format!("LINE{k}_D"), l.direction)
        );
    }
    for (k, t) in sources.tori.iter().enumerate() {
        let _ = writeln!(
            psi,
            "    sum += {} / max(EPS, torus_distance(p - {}, {}, {}));",
            values.scalar(&format!("TORUS{k}_C"), t.coefficient),
            values.vector(&format!("TORUS{k}_X"), t.center),
            values.vector(&format!("TORUS{k}_A"), t.axis),
            values.scalar(&format!("TORUS{k}_R"), t.major_radius)
        );
    }
    for (k, c) in sources.curves.iter().enumerate() {
        let nearest = segments(&c.control_points)
            .enumerate()
            .map(|(j, s)| {
                format!(
                    "segment_distance2(p, {}, {}, {})",
                    values.vector(&format!("CURVE{k}_{j}_C2"), s.c2),
                    values.vector(&format!("CURVE{k}_{j}_C1"), s.c1),
                    values.vector(&format!("CURVE{k}_{j}_C0"), s.c0)
                )
            })
            .reduce(|a, b| format!("min({a}, {b})"))
            .unwrap_or_default();
        let _ = writeln!(
            psi,
            "    sum += {} / max(EPS, sqrt({nearest}));",
            // A uniform W series weighs the chain by its one weight everywhere (its B-spline sums to it).
            values.scalar(
                &format!("CURVE{k}_C"),
                c.coefficient * c.weights.first().copied().unwrap_or(1.0)
            )
        );
    }
    let buffer = match baked {
        Baked::All => "",
        Baked::Structure => "@group(0) @binding(1) var<storage, read> values: array<vec4<f32>>;\n",
    };
    let source = format!(
        r#"// Simpson's rule over the rays of one scene: its structure constant, and {what}.
{declarations}const W = {w}u;
const N = {n}u;

{buffer}@group(0) @binding(0) var field: texture_storage_2d_array<r32float, write>;

fn torus_distance(q: vec3<f32>, axis: vec3<f32>, r: f32) -> f32 {{
    let z = dot(q, axis);
    let rho = sqrt(max(dot(q, q) - z * z, 0.0));
    return sqrt((rho - r) * (rho - r) + z * z);
}}

fn cbrt(x: f32) -> f32 {{
    return sign(x) * pow(abs(x), 1.0 / 3.0);
}}

fn distance2_at(p: vec3<f32>, c2: vec3<f32>, c1: vec3<f32>, c0: vec3<f32>, t: f32) -> f32 {{
    let d = (c2 * t + c1) * t + c0 - p;
    return dot(d, d);
}}

// Two Newton steps on the monic cubic t^3 + a t^2 + b t + c from Cardano's root t: in f32 his formula alone
// leaves the root a little off, which near the curve, where the distance is of the order of eps, is 1.6 % of B
// (measured on the Bezier scene at 256 x 256, n = 256).
fn polish(a: f32, b: f32, c: f32, t0: f32) -> f32 {{
    var t = t0;
    for (var j = 0; j < 2; j++) {{
        let f = ((t + a) * t + b) * t + c;
        let df = (3.0 * t + 2.0 * a) * t + b;
        if df != 0.0 {{
            t -= f / df;
        }}
    }}
    return t;
}}

// The squared distance from p to the segment c2 t^2 + c1 t + c0, t in [0, 1]: its ends, and the real roots of
// C'(t).(C(t) - p) = 0 by Cardano's formula, polished, clamped to [0, 1].
fn segment_distance2(p: vec3<f32>, c2: vec3<f32>, c1: vec3<f32>, c0: vec3<f32>) -> f32 {{
    let d = c0 - p;
    let k3 = 2.0 * dot(c2, c2);
    let a = 3.0 * dot(c1, c2) / k3;
    let b = (2.0 * dot(c2, d) + dot(c1, c1)) / k3;
    let c = dot(c1, d) / k3;
    let q = b / 3.0 - a * a / 9.0;
    let r = a * a * a / 27.0 - a * b / 6.0 + c / 2.0;
    let disc = q * q * q + r * r;
    var best = min(dot(d, d), distance2_at(p, c2, c1, c0, 1.0));
    if disc >= 0.0 {{
        let s = sqrt(disc);
        let t = polish(a, b, c, cbrt(-r + s) + cbrt(-r - s) - a / 3.0);
        best = min(best, distance2_at(p, c2, c1, c0, clamp(t, 0.0, 1.0)));
    }} else {{
        let m = 2.0 * sqrt(-q);
        let theta = acos(clamp(-r / sqrt(-q * q * q), -1.0, 1.0)) / 3.0;
        for (var j = 0; j < 3; j++) {{
            let t = polish(a, b, c, m * cos(theta - 2.0943951 * f32(j)) - a / 3.0);
            best = min(best, distance2_at(p, c2, c1, c0, clamp(t, 0.0, 1.0)));
        }}
    }}
    return best;
}}

fn psi(p: vec3<f32>) -> f32 {{
    var sum = 0.0;
{psi}    return sum;
}}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
{loads}    if id.x >= W || id.y >= W {{
        return;
    }}
    let u = (f32(id.x) + 0.5) / f32(W) - 0.5;
    let v = 0.5 - (f32(id.y) + 0.5) / f32(W);
    let s_point = CENTER + RIGHT * (SIZE * u) + UP * (SIZE * v);
    let e_point = EYE + NU * (s_point - EYE);
    var sum = 0.0;
    for (var k = 0u; k <= N; k++) {{
        let s = f32(k) / f32(N);
        var weight = select(2.0, 4.0, (k & 1u) == 1u);
        if k == 0u || k == N {{
            weight = 1.0;
        }}
        sum += weight * ALPHA / ((s + BETA) * (s + BETA)) * psi(mix(s_point, e_point, s));
    }}
    textureStore(field, vec2<i32>(id.xy), 0, vec4<f32>(sum / (3.0 * f32(N)), 0.0, 0.0, 1.0));
}}
"#,
        what = match baked {
            Baked::All => "its values constant too",
            Baked::Structure => "its values read from a buffer",
        },
        declarations = values.declarations,
        loads = values.loads,
    );
    Ok((source, values.data))
}

/// One compiled plain kernel: its pipeline, bind group, texture and values buffer (`Baked::Structure`).
struct Compiled {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    texture: wgpu::Texture,
    values: Option<wgpu::Buffer>,
}

/// The plain kernels of the scenes timed, compiled once each by their text, and their textures.
#[derive(Default)]
pub struct PlainKernels {
    compiled: HashMap<String, Compiled>,
}

impl PlainKernels {
    pub fn new() -> Self {
        Self::default()
    }

    /// Records the plain kernel of `scene` holding what `baked` says as constants (compiled on first use, its
    /// values uploaded at every call, as our field pass uploads its parameters) into `encoder`, timestamped by
    /// `writes`; returns the texture it writes (B in layer 0).
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        baked: Baked,
        encoder: &mut wgpu::CommandEncoder,
        writes: Option<wgpu::ComputePassTimestampWrites>,
    ) -> Result<wgpu::Texture, GpuError> {
        let (source, data) =
            plain_kernel_source(scene, baked).map_err(|e| GpuError::Validation(e.into()))?;
        if !self.compiled.contains_key(&source) {
            let compiled = ctx.checked(|| compile(&ctx.device, &source, scene, &data))?;
            self.compiled.insert(source.clone(), compiled);
        }
        let c = &self.compiled[&source];
        if let Some(buffer) = &c.values {
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::cast_slice(&data));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.bench.plain.pass"),
            timestamp_writes: writes,
        });
        pass.set_pipeline(&c.pipeline);
        pass.set_bind_group(0, &c.bind_group, &[]);
        let groups = scene.billboard.resolution.div_ceil(8);
        pass.dispatch_workgroups(groups, groups, 1);
        drop(pass);
        Ok(c.texture.clone())
    }

    /// B of `scene` by its plain kernel, read back, rows from the top.
    pub fn brightness(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        baked: Baked,
    ) -> Result<Vec<f32>, GpuError> {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let texture = self.encode(ctx, scene, baked, &mut encoder, None)?;
        ctx.checked(|| ctx.queue.submit([encoder.finish()]))?;
        let bytes = ctx.read_texture(&texture, 4)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }
}

/// The pipeline of a plain kernel's `source`, its texture for `scene` and its values buffer where `data` holds
/// any.
fn compile(device: &wgpu::Device, source: &str, scene: &Scene, data: &[[f32; 4]]) -> Compiled {
    let mut entries = vec![field_storage_entry(
        0,
        wgpu::StorageTextureAccess::WriteOnly,
    )];
    if !data.is_empty() {
        entries.push(storage_buffer_entry(1));
    }
    let (pipeline, layout) = compute_pass(device, "bench.plain", source, "main", &entries);
    let w = scene.billboard.resolution;
    let (texture, view) = field_texture(device, "energywave.bench.plain", w, 1);
    let values = (!data.is_empty()).then(|| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.bench.plain.values"),
            size: std::mem::size_of_val(data) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    });
    let mut bind = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: wgpu::BindingResource::TextureView(&view),
    }];
    if let Some(buffer) = &values {
        bind.push(wgpu::BindGroupEntry {
            binding: 1,
            resource: buffer.as_entire_binding(),
        });
    }
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("energywave.bench.plain.bind_group"),
        layout: &layout,
        entries: &bind,
    });
    Compiled {
        pipeline,
        bind_group,
        texture,
        values,
    }
}
