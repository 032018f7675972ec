//! The glow seen through translucent objects (`shaders/through.wgsl`): the frame's field ends its texels' rays
//! at the first opaque surface; this pass integrates the glow in front of the translucent ones and up to the
//! last translucent surface crossed (fields of the same frame, `FrameSetup::front` and `FrameSetup::exit`, only
//! on the texels whose rays cross one) and blends the three by the shares of the glow inside and behind that
//! reach the eye, `front + inside (exit - front) + behind (behind_field - exit)`. Its fields are kept while
//! their inputs do not change, as every field pass's is.

use super::context::{
    ClipBuffer, GpuError, compute_pass, field_storage_entry, field_texture, field_texture_layers,
    loaded_field_entry, storage_buffer_entry,
};
use super::field_pass::{FieldInputs, FieldRenderer};
use super::pass::{Brightness, FramePass, Gpu, Recording, Stage};
use super::shaders;
use crate::frame::FrameSetup;

/// Rust mirror of `ThroughParams` in `shaders/through.wgsl`.
pub mod gpu_data {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct ThroughParams {
        pub resolution: u32, // 0
        pub layers: u32,     // 4
        pub pad1: u32,       // 8
        pub pad2: u32,       // 12
    }
    const _: () = assert!(size_of::<ThroughParams>() == 16);
}

use gpu_data::ThroughParams;

/// The front and exit fields, the blend's pipeline and its output.
pub struct ThroughPass {
    front: FieldRenderer,
    exit: FieldRenderer,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    shares: ClipBuffer,
    output: Option<(wgpu::Texture, wgpu::TextureView)>,
    pending: Option<Pending>,
}

impl ThroughPass {
    /// The pass, its two fields drawn with `shaders` (the frame's own field's: no pipeline compiled twice).
    pub fn new(device: &wgpu::Device, shaders: &std::sync::Arc<super::FieldShaders>) -> Self {
        let (pipeline, layout) = compute_pass(
            device,
            "through",
            shaders::THROUGH_PASS,
            "see_through",
            &[
                storage_buffer_entry(0),
                storage_buffer_entry(1),
                loaded_field_entry(2),
                loaded_field_entry(3),
                field_storage_entry(4, wgpu::StorageTextureAccess::WriteOnly),
                loaded_field_entry(5),
            ],
        );
        Self {
            front: FieldRenderer::with_shaders(device, shaders.clone()),
            exit: FieldRenderer::with_shaders(device, shaders.clone()),
            pipeline,
            layout,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("energywave.through.params"),
                size: size_of::<ThroughParams>() as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            shares: ClipBuffer::new(device, "energywave.through.shares"),
            output: None,
            pending: None,
        }
    }

    /// The last blend's texture.
    pub fn output(&self) -> Option<&wgpu::Texture> {
        self.output.as_ref().map(|(t, _)| t)
    }

    /// The front field, for inspection.
    pub fn front(&self) -> &FieldRenderer {
        &self.front
    }

    /// Prepares the glow of `setup` seen through its translucent objects over `behind` (its field): the front
    /// and exit fields where their inputs changed, the blend's output and bind group; returns the view of the
    /// blend, `None` where the scene has no translucent objects (the field is the frame's as it is).
    /// `record_blend` records it.
    pub fn prepare_blend(
        &mut self,
        gpu: Gpu<'_>,
        setup: &FrameSetup,
        behind: &Brightness,
    ) -> Result<Option<wgpu::TextureView>, GpuError> {
        let (device, queue) = (gpu.device, gpu.queue);
        let (resolution, layers) = (behind.resolution, behind.layers);
        self.pending = None;
        let Some(shares) = setup.crossings_at(resolution) else {
            return Ok(None);
        };
        let mut views = Vec::new();
        let mut fields = [false; 2];
        let mut failed = None;
        for (k, (field, mut at)) in [
            (&mut self.front, setup.front()),
            (&mut self.exit, setup.exit()),
        ]
        .into_iter()
        .enumerate()
        {
            at.resolution = resolution;
            let inputs = FieldInputs::of(&at);
            if !field.shows(&inputs) {
                if let Err(e) = field.prepare(device, queue, &inputs) {
                    failed = Some(e);
                    break;
                }
                fields[k] = true;
            }
            views.push(field.view().expect("prepared above").clone());
        }
        if let Some(e) = failed {
            // The front field, prepared but not recorded now, is integrated again by the next frame.
            if fields[0] {
                self.front.invalidate();
            }
            return Err(e);
        }
        // One layer more than the field's: B behind them undimmed, which the glow's edge fades by.
        let stale = self.output.as_ref().is_none_or(|(t, _)| {
            t.width() != resolution
                || t.depth_or_array_layers() != field_texture_layers(device, layers + 1)
        });
        if stale {
            self.output = Some(field_texture(
                device,
                "energywave.through.output",
                resolution,
                layers + 1,
            ));
        }
        self.shares.upload(device, queue, &shares);
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&ThroughParams {
                resolution,
                layers,
                ..Default::default()
            }),
        );
        let (_, output) = self.output.as_ref().expect("made above");
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let tex = wgpu::BindingResource::TextureView;
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("energywave.through.bind_group"),
            layout: &self.layout,
            entries: &[
                entry(0, self.params.as_entire_binding()),
                entry(1, self.shares.binding()),
                entry(2, tex(&views[0])),
                entry(3, tex(&behind.view)),
                entry(4, tex(output)),
                entry(5, tex(&views[1])),
            ],
        });
        self.pending = Some(Pending {
            fields,
            group,
            groups: resolution.div_ceil(8),
            layers: layers + 1,
        });
        Ok(Some(output.clone()))
    }

    /// Records what `prepare_blend` prepared: the fields that changed, then the blend.
    pub fn record_blend(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Some(p) = self.pending.take() else {
            return;
        };
        for (field, changed) in [&mut self.front, &mut self.exit].into_iter().zip(p.fields) {
            if changed {
                field.encode(encoder);
            }
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("energywave.through.pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &p.group, &[]);
        pass.dispatch_workgroups(p.groups, p.groups, p.layers);
    }
}

/// What the next `record_blend` records.
struct Pending {
    /// Whether the front and the exit field changed (and are integrated before the blend).
    fields: [bool; 2],
    group: wgpu::BindGroup,
    groups: u32,
    layers: u32,
}

impl FramePass for ThroughPass {
    fn stages(&self) -> &'static [Stage] {
        &[Stage::SeeThrough]
    }

    fn prepare(&mut self, _: Stage, r: &mut Recording<'_>) -> Result<(), GpuError> {
        if let Some(view) = self.prepare_blend(r.gpu, r.frame.setup, &r.brightness)? {
            r.brightness.view = view;
            r.brightness.undimmed = true;
        }
        Ok(())
    }

    fn record(&mut self, _: Stage, _: &Recording<'_>, encoder: &mut wgpu::CommandEncoder) {
        self.record_blend(encoder);
    }
}
