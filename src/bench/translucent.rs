//! Translucent objects: what the voxel number map's precomputation and a frame with one in view cost. For the
//! poster's cube with its cavity and a 50,000-triangle mesh (a sphere), at 32, 64 and 128 voxels a side: the
//! surface voxels, the table's size, the time to voxelise and fill the table (refused, as a file asking for it
//! is, where the table would pass `MAX_TABLE_BYTES`), and the time to light it again (what an edit of the
//! sources costs). Then whole frames of `translucent_cavity.toml` at 1280 x 720: still, orbiting (every frame a
//! new camera: the table kept, the glow integrated twice, in front of the object and behind it), and the same
//! scene with the cube opaque, interleaved frame by frame.

use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use super::Timing;
use crate::gpu::{GpuError, HeadlessRenderer};
use crate::objects::lighting::Lights;
use crate::objects::mesh::MeshData;
use crate::objects::translucent::light::{Prepared, irradiance, leaving, spread};
use crate::objects::translucent::table::Table;
use crate::objects::translucent::voxels::{Voxels, table_bytes};
use crate::objects::translucent::{MAX_TABLE_BYTES, Medium};
use crate::objects::{MeshObject, Object, Shape};
use crate::scene::Scene;

/// One object at one resolution.
#[derive(Clone, Debug, Serialize)]
pub struct TranslucentRow {
    pub case: String,
    pub resolution: u32,
    pub surface_voxels: usize,
    /// The table's bytes, in MB (10^6).
    pub table_mb: f64,
    /// Voxelising and filling the table, in ms; none where it is refused.
    pub precompute_ms: Option<f64>,
    /// Lighting the surface voxels and summing over the table, in ms.
    pub relight_ms: Option<f64>,
    /// The table alone on the CPU (every core) and on the GPU (`gpu::tau_table`), in ms.
    pub table_cpu_ms: Option<f64>,
    pub table_gpu_ms: Option<f64>,
}

/// Whole frames at 1280 x 720.
#[derive(Clone, Debug, Serialize)]
pub struct TranslucentFrames {
    /// The preset, its camera still (the table and the fields kept: the frame composed again).
    pub still: Timing,
    /// The preset orbited a degree a frame.
    pub orbit: Timing,
    /// The same orbit with the cube opaque.
    pub opaque_orbit: Timing,
}

/// A UV sphere of radius 0.7 with `slices` x `stacks` quads, closed (its poles fans).
fn sphere_mesh(slices: usize, stacks: usize) -> MeshData {
    use std::f64::consts::{PI, TAU};
    let at = |i: usize, j: usize| {
        let (phi, theta) = (
            TAU * (i % slices) as f64 / slices as f64,
            PI * j as f64 / stacks as f64,
        );
        if j == 0 {
            return DVec3::new(0.0, 0.7, 0.0);
        }
        if j == stacks {
            return DVec3::new(0.0, -0.7, 0.0);
        }
        DVec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        ) * 0.7
    };
    let mut triangles = Vec::new();
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if j > 0 {
                triangles.push([a, b, c]);
            }
            if j + 1 < stacks {
                triangles.push([a, c, d]);
            }
        }
    }
    MeshData::new(triangles)
}

fn translucent(mut object: Object, resolution: u32) -> Object {
    let t = object.translucent.get_or_insert_with(Default::default);
    t.resolution = Some(resolution);
    object
}

/// The precomputation rows, and the frames.
pub fn translucent_rows(
    warmup: usize,
    frames: usize,
    quick: bool,
) -> Result<(Vec<TranslucentRow>, TranslucentFrames), GpuError> {
    let preset = Scene::parse(
        include_str!("../../assets/scenes/translucent_cavity.toml"),
        std::path::Path::new("translucent_cavity.toml"),
    )
    .expect("the shipped preset is valid");
    let cube = preset.objects[0].clone();
    let mesh = Object {
        shape: Shape::Mesh(MeshObject {
            path: "sphere.glb".into(),
            translation: DVec3::ZERO,
            rotation: DVec3::ZERO,
            scale: DVec3::ONE,
            data: Arc::new(sphere_mesh(160, 157)),
        }),
        color: [1.0; 3],
        translucent: cube.translucent.clone(),
    };
    let triangles = match &mesh.shape {
        Shape::Mesh(m) => m.data.triangles.len(),
        _ => 0,
    };
    let lights = Lights::new(
        &preset.sources,
        preset.colors.palette(),
        preset.integration.epsilon,
    );
    let gpu_ctx = HeadlessRenderer::new()?;
    let mut rows = Vec::new();
    for (name, object) in [
        ("cube with a cavity".to_owned(), cube.clone()),
        (format!("mesh, {triangles} triangles"), mesh),
    ] {
        for resolution in [32u32, 64, 128] {
            let object = translucent(object.clone(), resolution);
            let surface = Voxels::surface_count(&object, resolution).expect("a closed object");
            let bytes = table_bytes(surface);
            let mut row = TranslucentRow {
                case: name.clone(),
                resolution,
                surface_voxels: surface,
                table_mb: bytes as f64 / 1e6,
                precompute_ms: None,
                relight_ms: None,
                table_cpu_ms: None,
                table_gpu_ms: None,
            };
            if bytes <= MAX_TABLE_BYTES && !(quick && resolution > 32) {
                let t = Instant::now();
                let voxels = Voxels::of(&object, resolution).expect("a closed object");
                let v = t.elapsed().as_secs_f64() * 1e3;
                let t = Instant::now();
                let table = Table::of(&voxels);
                let c = t.elapsed().as_secs_f64() * 1e3;
                let t = Instant::now();
                let spread = spread(&voxels, &table);
                row.precompute_ms = Some(v + c + t.elapsed().as_secs_f64() * 1e3);
                row.table_cpu_ms = Some(c);
                let t = Instant::now();
                std::hint::black_box(crate::gpu::tau_table::tau_table(&gpu_ctx.ctx, &voxels)?);
                row.table_gpu_ms = Some(t.elapsed().as_secs_f64() * 1e3);
                let prepared = Prepared {
                    voxels,
                    table,
                    spread,
                    seconds: 0.0,
                };
                let medium = Medium::of(&object).expect("translucent");
                let objects = [object.clone()];
                let t = Instant::now();
                let light = irradiance(&medium, &prepared.voxels, &lights, &objects);
                std::hint::black_box(leaving(&prepared, &light));
                row.relight_ms = Some(t.elapsed().as_secs_f64() * 1e3);
            }
            rows.push(row);
        }
    }
    // Whole frames.
    let (w, h) = (1280, 720);
    let (mut gpu, mut gpu_opaque) = (HeadlessRenderer::new()?, HeadlessRenderer::new()?);
    let mut opaque = preset.clone();
    opaque.objects[0].translucent = None;
    let orbit = |s: &Scene, k: usize| {
        let mut s = s.clone();
        let a = (k as f64).to_radians();
        let e = s.camera.eye - s.camera.target;
        s.camera.eye = s.camera.target
            + DVec3::new(
                e.x * a.cos() - e.z * a.sin(),
                e.y,
                e.x * a.sin() + e.z * a.cos(),
            );
        s
    };
    let (mut still, mut moving, mut opaque_moving) = (Vec::new(), Vec::new(), Vec::new());
    gpu.render(&preset, w, h, false)?;
    for k in 0..warmup + frames {
        let t = Instant::now();
        gpu.render(&preset, w, h, false)?;
        let s = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        gpu.render(&orbit(&preset, k + 1), w, h, false)?;
        let m = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        gpu_opaque.render(&orbit(&opaque, k + 1), w, h, false)?;
        let o = t.elapsed().as_secs_f64() * 1e3;
        if k >= warmup {
            still.push(s);
            moving.push(m);
            opaque_moving.push(o);
        }
    }
    Ok((
        rows,
        TranslucentFrames {
            still: Timing::of(still),
            orbit: Timing::of(moving),
            opaque_orbit: Timing::of(opaque_moving),
        },
    ))
}
