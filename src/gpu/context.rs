//! The GPU context: instance, adapter, device and queue, chosen the same way for the viewer and the command
//! line, with every wgpu validation error captured and turned into a `GpuError`.

use std::sync::{Arc, Mutex};

/// Why GPU work could not be done.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No driver for any backend tried: one line that says what to install, for Vulkan and for GL.
    #[error(
        "no GPU driver found (tried {backends}): install Mesa's, for Vulkan `apt-get install mesa-vulkan-drivers libvulkan1` or for GL `apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri` (Debian's packages), or render on the CPU: energywave render --backend cpu"
    )]
    NoAdapter { backends: String },
    #[error("WGPU_ADAPTER_NAME={wanted:?} matches no adapter; available: {available}")]
    NoMatchingAdapter { wanted: String, available: String },
    #[error("the adapter {adapter} refused to create a device: {source}")]
    RequestDevice {
        adapter: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    #[error(
        "billboard resolution {resolution} exceeds this GPU's texture limit of {limit} texels per side"
    )]
    ResolutionTooLarge { resolution: u32, limit: u32 },
    #[error(
        "frame size {width}x{height} exceeds this GPU's texture limit of {limit} pixels per side"
    )]
    FrameTooLarge { width: u32, height: u32, limit: u32 },
    #[error("{name}={value:?} is not valid: {reason}")]
    BadEnvironment {
        name: &'static str,
        value: String,
        reason: String,
    },
    #[error("wgpu validation error: {0}")]
    Validation(String),
    #[error("GPU readback failed: {0}")]
    Readback(String),
}

impl GpuError {
    /// No adapter on any of `backends` (those this build has: Vulkan and GL on Linux).
    pub fn no_adapter(backends: wgpu::Backends) -> Self {
        let backends = backends & wgpu::Instance::enabled_backend_features();
        let names = [
            (wgpu::Backends::VULKAN, "Vulkan"),
            (wgpu::Backends::GL, "GL"),
            (wgpu::Backends::METAL, "Metal"),
            (wgpu::Backends::DX12, "DirectX 12"),
            (wgpu::Backends::BROWSER_WEBGPU, "WebGPU"),
        ];
        let tried: Vec<&str> = (names.iter())
            .filter(|(b, _)| backends.contains(*b))
            .map(|(_, name)| *name)
            .collect();
        GpuError::NoAdapter {
            backends: match tried.is_empty() {
                true => "no backend".into(),
                false => tried.join(", "),
            },
        }
    }

    /// True when the user's request is at fault (a size beyond the device's limits), not the machine.
    pub fn is_input_error(&self) -> bool {
        matches!(
            self,
            GpuError::ResolutionTooLarge { .. }
                | GpuError::FrameTooLarge { .. }
                | GpuError::BadEnvironment { .. }
        )
    }
}

/// Runs `f` inside validation and out-of-memory error scopes of `device`; an error it causes becomes a
/// `GpuError::Validation`.
pub fn checked<T>(device: &wgpu::Device, f: impl FnOnce() -> T) -> Result<T, GpuError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        Some(e) => Err(GpuError::Validation(e.to_string())),
        None => Ok(value),
    }
}

/// A pass's bind group layout over `entries` and its pipeline layout of that one group, labelled
/// `energywave.<name>.*`: what every pass builds before its pipeline.
pub fn pass_layouts(
    device: &wgpu::Device,
    name: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(&format!("energywave.{name}.bind_group_layout")),
        entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(&format!("energywave.{name}.pipeline_layout")),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    (layout, pipeline_layout)
}

/// What sets one render pass's pipeline apart from the others': the pipeline's module holds `vs_main` and the
/// fragment entry point; one color target, no depth, no multisampling.
pub struct RenderPipelineSpec<'a> {
    /// Labels it `energywave.<name>.pipeline`.
    pub name: &'a str,
    pub module: &'a wgpu::ShaderModule,
    pub layout: &'a wgpu::PipelineLayout,
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub topology: wgpu::PrimitiveTopology,
    pub fragment_entry: &'a str,
    /// Values of the fragment stage's pipeline-overridable constants.
    pub constants: &'a [(&'a str, f64)],
    /// The color targets, by location (the objects write their depth to a second one).
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// The depth test, where the pass has a depth attachment (the objects).
    pub depth: Option<wgpu::DepthStencilState>,
}

/// A render pass's pipeline (the billboard, the grid, the blit): what every one of them builds alike.
pub fn render_pipeline(device: &wgpu::Device, spec: RenderPipelineSpec) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&format!("energywave.{}.pipeline", spec.name)),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: spec.vertex_buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: spec.topology,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: spec.depth,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fragment_entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: spec.constants,
                ..Default::default()
            },
            targets: spec.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A compute pipeline over one bind group of `entries`, from the WGSL `source` and its entry point `entry`
/// (labelled `energywave.<name>.*`): the small passes' shared setup.
pub fn compute_pass(
    device: &wgpu::Device,
    name: &str,
    source: &str,
    entry: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> (wgpu::ComputePipeline, wgpu::BindGroupLayout) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&format!("energywave.{name}.shader")),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let (layout, pipeline_layout) = pass_layouts(device, name, entries);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(&format!("energywave.{name}.{entry}")),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    (pipeline, layout)
}

/// A storage buffer of clips (`objects::clip`, one f32 a texel) and what it holds: written through the queue only
/// when the clips change, grown when they outgrow it.
pub struct ClipBuffer {
    label: &'static str,
    buffer: wgpu::Buffer,
    uploaded: Option<Arc<Vec<f32>>>,
}

impl ClipBuffer {
    pub fn new(device: &wgpu::Device, label: &'static str) -> Self {
        Self::of_size(device, label, 4)
    }

    fn of_size(device: &wgpu::Device, label: &'static str, size: u64) -> Self {
        Self {
            label,
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            uploaded: None,
        }
    }

    /// Holds `clips` (written through the queue where they changed).
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, clips: &Arc<Vec<f32>>) {
        if self.uploaded.as_ref() == Some(clips) {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(clips);
        if bytes.len() as u64 > self.buffer.size() {
            *self = Self::of_size(device, self.label, bytes.len() as u64);
        }
        queue.write_buffer(&self.buffer, 0, bytes);
        self.uploaded = Some(clips.clone());
    }

    /// The whole buffer, to bind.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }
}

/// A bind group layout entry for a compute pass: a read-only storage buffer.
pub fn storage_buffer_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    read_only_storage(binding, wgpu::ShaderStages::COMPUTE)
}

/// A bind group layout entry for a fragment shader: a read-only storage buffer.
pub fn fragment_storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    read_only_storage(binding, wgpu::ShaderStages::FRAGMENT)
}

fn read_only_storage(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A bind group layout entry for a fragment shader: the objects' depth copy (`formats::DEPTH_VALUE_FORMAT`),
/// read with `textureLoad`.
pub fn depth_value_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A bind group layout entry for a fragment shader: a 2D float texture it filters (with `filtering_sampler_entry`).
pub fn filtered_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A bind group layout entry for a fragment shader: a filtering sampler.
pub fn filtering_sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

/// A bind group layout entry for a compute pass: a field texture (`field_texture`) read with `textureLoad`.
pub fn loaded_field_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

/// A bind group layout entry for a compute pass: a field texture (`field_texture`) as storage.
pub fn field_storage_entry(
    binding: u32,
    access: wgpu::StorageTextureAccess,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access,
            format: wgpu::TextureFormat::R32Float,
            view_dimension: wgpu::TextureViewDimension::D2Array,
        },
        count: None,
    }
}

/// Layers of a field texture: B, then the tint `sum B_i (Ce_i - Ce)` in red, green and blue
/// (`reference::BrightnessTexture`). r32float layers rather than one rgba32float texture: WebGPU lets a shader
/// read and write a storage texture of r32float only, and the field pass adds its dispatches into the texture.
/// A scene whose sources all have its color has no tint: its field textures hold B alone, one layer
/// (`field_pass::layers_of`), as much memory and work as before there were colors.
pub const FIELD_LAYERS: u32 = 4;

/// The layers a field texture of `layers` is made with on `device`. GL makes a texture of one layer a plain 2D
/// texture (wgpu's GL backend picks the texture's target from its layer count), which a shader's
/// `texture_2d_array` then silently reads as zeros; there a texture of B alone gets a second layer, never written
/// nor read. Every other backend makes what is asked.
pub fn field_texture_layers(device: &wgpu::Device, layers: u32) -> u32 {
    match device.adapter_info().backend {
        wgpu::Backend::Gl => layers.max(2),
        _ => layers,
    }
}

/// A `w` x `w` field texture of `layers` r32float layers (1, B alone, or `FIELD_LAYERS`; on GL at least 2,
/// `field_texture_layers`), for storage, sampling and copies both ways, and its view of every layer (a texture
/// array, whatever the count).
pub fn field_texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    layers: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: w,
            depth_or_array_layers: field_texture_layers(device, layers),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (texture, view)
}

/// A uniform buffer for one `T`, written with `Queue::write_buffer`.
pub fn uniform_buffer<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A 2D texture of one mip level and one sample.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// Bytes of GPU memory a field texture of `layers` r32float layers takes at resolution `w`: the field pass's
/// and the mean of its jittered frames.
pub fn field_texture_bytes(w: u32, layers: u32) -> u64 {
    w as u64 * w as u64 * 4 * layers as u64
}

/// Device, queue and the adapter they came from.
pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    uncaptured: Arc<Mutex<Vec<String>>>,
}

/// Preference order of adapters: a real GPU first, then a virtual one, then a software rasteriser.
fn device_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// Among equal device types, Vulkan (lavapipe for the software case) before the GL fallback.
fn backend_rank(b: wgpu::Backend) -> u8 {
    match b {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 0,
        wgpu::Backend::Gl => 1,
        _ => 2,
    }
}

/// `ENERGYWAVE_MAX_TEXTURE_SIZE`: a smaller texture limit than the adapter's, to check that a scene fits a
/// GPU with smaller limits than the one at hand.
pub const TEXTURE_SIZE_CAP_VAR: &str = "ENERGYWAVE_MAX_TEXTURE_SIZE";

fn texture_size_cap() -> Result<Option<u32>, GpuError> {
    let Ok(value) = std::env::var(TEXTURE_SIZE_CAP_VAR) else {
        return Ok(None);
    };
    match value.trim().parse::<u32>() {
        Ok(cap) if cap >= 64 => Ok(Some(cap)),
        _ => Err(GpuError::BadEnvironment {
            name: TEXTURE_SIZE_CAP_VAR,
            value,
            reason: "give a whole number of texels per side, at least 64 (for example 8192)".into(),
        }),
    }
}

/// A one-line description of an adapter: name, backend, kind, driver.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    let mut s = format!("{} ({:?}, {:?}", info.name, info.backend, info.device_type);
    if !info.driver.is_empty() {
        s.push_str(&format!(", {} {}", info.driver, info.driver_info));
    }
    s.push(')');
    s
}

/// The GPU a pass works on.
#[derive(Clone, Copy)]
pub struct Gpu<'g> {
    pub device: &'g wgpu::Device,
    pub queue: &'g wgpu::Queue,
}

impl GpuContext {
    /// Its device and queue, as the passes take them.
    pub fn gpu(&self) -> Gpu<'_> {
        Gpu {
            device: &self.device,
            queue: &self.queue,
        }
    }

    /// A context on the best adapter found: `WGPU_BACKEND` limits the backends tried, `WGPU_ADAPTER_NAME`
    /// (a case-insensitive part of the name) picks one, else a real GPU before a software one.
    pub fn new() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        pollster::block_on(Self::with_instance(instance, None))
    }

    /// A context on `instance`, with an adapter able to present to `surface` when one is given.
    pub async fn with_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
        let mut adapters: Vec<wgpu::Adapter> = instance
            .enumerate_adapters(backends)
            .await
            .into_iter()
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .collect();
        if adapters.is_empty() {
            return Err(GpuError::no_adapter(backends));
        }
        if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
            let available = adapters
                .iter()
                .map(|a| describe(&a.get_info()))
                .collect::<Vec<_>>()
                .join("; ");
            let w = wanted.to_lowercase();
            adapters.retain(|a| a.get_info().name.to_lowercase().contains(&w));
            if adapters.is_empty() {
                return Err(GpuError::NoMatchingAdapter { wanted, available });
            }
        }
        adapters.sort_by_key(|a| {
            let info = a.get_info();
            (device_rank(info.device_type), backend_rank(info.backend))
        });
        let adapter = adapters.swap_remove(0);
        // The adapter's own limits: the defaults some front ends ask for (WebGL2's) disable compute.
        let mut required_limits = adapter.limits();
        if let Some(cap) = texture_size_cap()? {
            required_limits.max_texture_dimension_2d =
                required_limits.max_texture_dimension_2d.min(cap);
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("energywave.device"),
                required_limits,
                required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::RequestDevice {
                adapter: describe(&adapter.get_info()),
                source,
            })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            uncaptured,
        })
    }

    /// The chosen adapter, in one line.
    pub fn adapter_summary(&self) -> String {
        describe(&self.adapter.get_info())
    }

    /// Runs `f` inside a validation error scope; any wgpu validation or out-of-memory error it causes, or
    /// one raised outside a scope since the last check, becomes an error.
    pub fn checked<T>(&self, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        let value = checked(&self.device, f)?;
        self.check_uncaptured()?;
        Ok(value)
    }

    /// Fails with the first validation error raised outside an error scope since the last call.
    pub fn check_uncaptured(&self) -> Result<(), GpuError> {
        let mut errors = self
            .uncaptured
            .lock()
            .map_err(|_| GpuError::Validation("error log poisoned".into()))?;
        if errors.is_empty() {
            Ok(())
        } else {
            let all = errors.join("\n");
            errors.clear();
            Err(GpuError::Validation(all))
        }
    }

    /// Copies a whole 2D texture of `bytes_per_texel` back to the CPU, rows from the top, without padding.
    pub fn read_texture(
        &self,
        texture: &wgpu::Texture,
        bytes_per_texel: u32,
    ) -> Result<Vec<u8>, GpuError> {
        read_texture(&self.device, &self.queue, texture, bytes_per_texel)
    }
}

/// Copies a whole 2D texture of `bytes_per_texel` back to the CPU, rows from the top, without padding
/// (waits for the GPU); of a field texture, its first layer, B.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>, GpuError> {
    read_texture_layer(device, queue, texture, bytes_per_texel, 0)
}

/// `read_texture` of one layer of a texture array.
pub fn read_texture_layer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
    layer: u32,
) -> Result<Vec<u8>, GpuError> {
    let (width, height) = (texture.width(), texture.height());
    let unpadded = width * bytes_per_texel;
    let padded =
        unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("energywave.readback"),
        size: padded as u64 * height as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("energywave.readback.encoder"),
    });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let bytes = map_read(device, &buffer)?;
    let mut out = Vec::with_capacity((unpadded * height) as usize);
    for row in bytes.chunks(padded as usize) {
        out.extend_from_slice(&row[..unpadded as usize]);
    }
    Ok(out)
}

/// Waits for the GPU, then copies a whole `MAP_READ` buffer to the CPU and unmaps it.
pub fn map_read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let error = |e: &dyn std::fmt::Display| GpuError::Readback(e.to_string());
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| error(&e))?;
    rx.recv().map_err(|e| error(&e))?.map_err(|e| error(&e))?;
    let bytes = buffer
        .slice(..)
        .get_mapped_range()
        .map_err(|e| error(&e))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// A render pass that draws over what `view` holds (loaded, stored), one color attachment, no depth.
pub(super) fn over<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
