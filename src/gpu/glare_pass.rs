//! The glare pass (`shaders/glare.wgsl`): a fog glow added to a field texture before the billboard blends it,
//! the excess over a threshold blurred by a separable Gaussian whose weights come from the f64 twin
//! (`scene::Glare::kernel`).

use super::context::GpuError;
use super::context::{
    compute_pass, field_storage_entry, field_texture, field_texture_layers, loaded_field_entry,
    storage_buffer_entry,
};
use super::pass::{Brightness, FramePass, Recording, Stage};
use super::shaders;
use crate::scene::{Glare, MAX_GLARE_RADIUS};

/// Rust mirror of `GlareParams` in `shaders/glare.wgsl`.
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GlareParams {
        pub threshold: f32, // 0
        pub strength: f32,  // 4
        pub radius: u32,    // 8
        pub undimmed: u32,  // 12: the layer of B undimmed by translucent objects, 0 for none
    }
    const _: () = assert!(size_of::<GlareParams>() == 16);
}

use gpu_data::GlareParams;

/// The two passes (rows, then columns), their parameters and the textures they write: the rows' blur, and the
/// field with the glare added.
pub struct GlarePass {
    rows: wgpu::ComputePipeline,
    rows_layout: wgpu::BindGroupLayout,
    columns: wgpu::ComputePipeline,
    columns_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    weights: wgpu::Buffer,
    /// The rows' blur and the output, with their views, for one size and layer count.
    targets: Option<[(wgpu::Texture, wgpu::TextureView); 2]>,
    /// What the output holds the glare of: the field's view, the glare, its side and layers.
    last: Option<(wgpu::TextureView, Glare, u32, u32)>,
    /// What the next `record` dispatches: the rows' and columns' bind groups, the workgroups a side, the
    /// layers.
    pending: Option<([wgpu::BindGroup; 2], u32, u32)>,
}

impl GlarePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let write = wgpu::StorageTextureAccess::WriteOnly;
        let (rows, rows_layout) = compute_pass(
            device,
            "glare",
            shaders::GLARE_PASS,
            "glare_rows",
            &[
                storage_buffer_entry(0),
                storage_buffer_entry(1),
                loaded_field_entry(2),
                field_storage_entry(4, write),
            ],
        );
        let (columns, columns_layout) = compute_pass(
            device,
            "glare",
            shaders::GLARE_PASS,
            "glare_columns",
            &[
                storage_buffer_entry(0),
                storage_buffer_entry(1),
                loaded_field_entry(2),
                loaded_field_entry(3),
                field_storage_entry(4, write),
            ],
        );
        let buffer = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Self {
            rows,
            rows_layout,
            columns,
            columns_layout,
            params: buffer("energywave.glare.params", size_of::<GlareParams>() as u64),
            weights: buffer(
                "energywave.glare.weights",
                (2 * MAX_GLARE_RADIUS as u64 + 1) * 4,
            ),
            targets: None,
            last: None,
            pending: None,
        }
    }

    /// Prepares the glare over `field` (its brightness) and returns the view of the field with the glare
    /// added. Unless `field.fresh` (its texels changed since the last call), the glare of the same field and
    /// settings is the one already there, and nothing is recorded: a viewer at rest spends nothing on it.
    fn prepare_glare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        field: &Brightness,
        glare: &Glare,
    ) -> wgpu::TextureView {
        // With B undimmed by translucent objects in a layer past the others (`through_pass`), glared as B is.
        let undimmed = if field.undimmed { field.layers } else { 0 };
        let (resolution, layers) = (field.resolution, field.layers + field.undimmed as u32);
        self.pending = None;
        let key = (field.view.clone(), *glare, resolution, layers);
        if !field.fresh && self.last.as_ref() == Some(&key) {
            return self.targets.as_ref().expect("rendered before")[1].1.clone();
        }
        self.last = Some(key);
        let stale = self.targets.as_ref().is_none_or(|[(t, _), _]| {
            t.width() != resolution
                || t.depth_or_array_layers() != field_texture_layers(device, layers)
        });
        if stale {
            self.targets = Some([
                field_texture(device, "energywave.glare.rows", resolution, layers),
                field_texture(device, "energywave.glare.output", resolution, layers),
            ]);
        }
        let weights: Vec<f32> = glare.kernel(resolution).iter().map(|&w| w as f32).collect();
        let params = GlareParams {
            threshold: glare.threshold as f32,
            strength: glare.strength as f32,
            radius: (weights.len() / 2) as u32,
            undimmed,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        queue.write_buffer(&self.weights, 0, bytemuck::cast_slice(&weights));
        let [(_, rows_view), (_, output_view)] = self.targets.as_ref().expect("made above");
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let tex = wgpu::BindingResource::TextureView;
        let rows_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.glare.rows.bind_group"),
            layout: &self.rows_layout,
            entries: &[
                entry(0, self.params.as_entire_binding()),
                entry(1, self.weights.as_entire_binding()),
                entry(2, tex(&field.view)),
                entry(4, tex(rows_view)),
            ],
        });
        let columns_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.glare.columns.bind_group"),
            layout: &self.columns_layout,
            entries: &[
                entry(0, self.params.as_entire_binding()),
                entry(1, self.weights.as_entire_binding()),
                entry(2, tex(&field.view)),
                entry(3, tex(rows_view)),
                entry(4, tex(output_view)),
            ],
        });
        self.pending = Some(([rows_group, columns_group], resolution.div_ceil(8), layers));
        output_view.clone()
    }
}

impl FramePass for GlarePass {
    fn stages(&self) -> &'static [Stage] {
        &[Stage::Glare]
    }

    /// Where the scene has a glare, it adds to the field before the blend.
    fn prepare(&mut self, _: Stage, r: &mut Recording<'_>) -> Result<(), GpuError> {
        self.pending = None;
        if let Some(glare) = &r.frame.setup.scene.glare {
            let (device, queue) = (r.gpu.device, r.gpu.queue);
            r.brightness.view = self.prepare_glare(device, queue, &r.brightness, glare);
        }
        Ok(())
    }

    fn record(&mut self, _: Stage, _: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        let Some((groups, size, layers)) = self.pending.take() else {
            return;
        };
        for (pipeline, group) in [(&self.rows, &groups[0]), (&self.columns, &groups[1])] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("energywave.glare.pass"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(size, size, layers);
        }
    }
}
