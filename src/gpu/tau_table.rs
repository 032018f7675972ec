//! A translucent object's optical-thickness table on the GPU (`shaders/tau_table.wgsl`): one invocation a pair
//! of surface voxels, in bands of rows no larger than the device's storage binding, read back into the same
//! `Table` the CPU twin (`objects::translucent::table::Table::of`) fills.

use super::context::{GpuContext, GpuError, checked, compute_pass, map_read, storage_buffer_entry};
use super::shaders;
use crate::objects::translucent::table::{Table, row_start};
use crate::objects::translucent::voxels::Voxels;

/// Rust mirror of `TauParams` in `shaders/tau_table.wgsl`.
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct TauParams {
        pub origin: [f32; 3], // 0
        pub side: f32,        // 12
        pub dims: [u32; 3],   // 16
        pub n: u32,           // 28
        pub k0: u32,          // 32
        pub rows: u32,        // 36
        pub base: u32,        // 40
        pub pad0: u32,        // 44
    }
    const _: () = assert!(size_of::<TauParams>() == 48);
}

use gpu_data::TauParams;

/// The table of `voxels` on `ctx`'s device.
pub fn tau_table(ctx: &GpuContext, voxels: &Voxels) -> Result<Table, GpuError> {
    let table = table_on(&ctx.device, &ctx.queue, voxels)?;
    ctx.check_uncaptured()?;
    Ok(table)
}

/// Whether `device` is a real GPU, on which the table is filled (a software one, lavapipe or llvmpipe, runs on
/// the CPU's cores: there the CPU twin, on every core in f64, is the faster: 4.7 s against 6.0 s for the
/// poster's cube at 32 voxels a side on two cores, benches/README.md).
pub fn fills_tables(adapter: &wgpu::AdapterInfo) -> bool {
    adapter.device_type != wgpu::DeviceType::Cpu
}

/// The table of `voxels` on `device`.
pub fn table_on(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    voxels: &Voxels,
) -> Result<Table, GpuError> {
    let n = voxels.surface.len();
    let total = n * (n + 1) / 2;
    if n == 0 {
        return Ok(Table { n, tau: Vec::new() });
    }
    let read_write = wgpu::BindGroupLayoutEntry {
        binding: 3,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let (pipeline, layout) = checked(device, || {
        compute_pass(
            device,
            "tau_table",
            shaders::TAU_TABLE_PASS,
            "tau_table",
            &[
                storage_buffer_entry(0),
                storage_buffer_entry(1),
                storage_buffer_entry(2),
                read_write,
            ],
        )
    })?;
    use wgpu::util::DeviceExt;
    let init = |label: &str, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let extinction = init(
        "energywave.tau.extinction",
        bytemuck::cast_slice(&voxels.extinction),
        storage,
    );
    let points: Vec<[f32; 4]> = (voxels.surface.iter())
        .map(|s| {
            let p = s.position.as_vec3();
            [p.x, p.y, p.z, 0.0]
        })
        .collect();
    let points = init(
        "energywave.tau.points",
        bytemuck::cast_slice(&points),
        storage,
    );
    let params = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("energywave.tau.params"),
        size: size_of::<TauParams>() as u64,
        usage: storage,
        mapped_at_creation: false,
    });
    // Bands of whole rows within the device's storage binding (and 64 MiB, so that the read back is in pieces).
    let limit = device
        .limits()
        .max_storage_buffer_binding_size
        .min(64 << 20)
        / 4;
    let mut tau = Vec::with_capacity(total);
    let mut k0 = 0;
    while k0 < n {
        let mut k1 = k0 + 1;
        while k1 < n && (row_start(n, k1 + 1) - row_start(n, k0)) as u64 <= limit {
            k1 += 1;
        }
        let entries = row_start(n, k1) - row_start(n, k0);
        let size = (entries * 4) as u64;
        let band = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.tau.band"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("energywave.tau.staging"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let o = voxels.origin.as_vec3();
        let rows = (k1 - k0) as u32;
        queue.write_buffer(
            &params,
            0,
            bytemuck::bytes_of(&TauParams {
                origin: [o.x, o.y, o.z],
                side: voxels.side as f32,
                dims: voxels.dims.map(|d| d as u32),
                n: n as u32,
                k0: k0 as u32,
                rows,
                base: row_start(n, k0) as u32,
                pad0: 0,
            }),
        );
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.tau.bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: extinction.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: points.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: band.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(
                (n as u32).div_ceil(64),
                rows.min(65535),
                rows.div_ceil(65535),
            );
        }
        encoder.copy_buffer_to_buffer(&band, 0, &staging, 0, size);
        checked(device, || queue.submit([encoder.finish()]))?;
        let bytes = map_read(device, &staging)?;
        tau.extend_from_slice(bytemuck::cast_slice::<u8, f32>(&bytes));
        k0 = k1;
    }
    Ok(Table { n, tau })
}
