//! The effect as a game engine's shader (`energywave shader`): the GLSL 4.50 and the HLSL naga writes from our WGSL
//! compiled by glslang (Khronos' reference compiler, Debian's `glslang-tools`) to SPIR-V, that SPIR-V run as it
//! is on the GPU (wgpu's passthrough, Vulkan) with the exported uniforms as they are (the scene's camera), each
//! pixel's B against the f64 twin along the pixel's own ray (`common::engine::check_against_twin`), on points,
//! lines, tori, curves with W and color series, the brightest-point W form and the rms decay. The GLSL ES 3.00
//! stages and the GLSL 4.50 vertex stage are checked by glslang for OpenGL (tests/engine_es.rs runs the ES stages
//! on GLES). Needs `--features glslang` (`./test.sh` turns it on); without it the test is listed as ignored, with
//! what it needs.

mod common;

use std::path::Path;
use std::process::Command;

use common::engine::{CLEAR, FRAME};
use energywave::engine::EffectShader;

/// `glslangValidator ARGS`, which must succeed.
fn glslang(args: &[&str]) {
    let o = Command::new("glslangValidator")
        .args(args)
        .output()
        .expect("glslangValidator runs (Debian: apt-get install glslang-tools)");
    assert!(
        o.status.success(),
        "glslangValidator {args:?}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn spirv(path: &Path) -> Vec<u32> {
    let bytes = std::fs::read(path).unwrap();
    bytes
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
        .collect()
}

/// A device that takes SPIR-V as it is.
fn device() -> (wgpu::Device, wgpu::Queue) {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .expect("an adapter");
    assert!(
        adapter
            .features()
            .contains(wgpu::Features::PASSTHROUGH_SHADERS),
        "SPIR-V passthrough on {:?} (run on Vulkan: WGPU_BACKEND=vulkan)",
        adapter.get_info()
    );
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("engine shader test"),
        required_features: wgpu::Features::PASSTHROUGH_SHADERS,
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .expect("a device")
}

/// The SPIR-V stages `vertex` and `fragment` (entry points by name) drawn over `common::engine::FRAME` with
/// `uniforms`, the target cleared to `common::engine::CLEAR`: RGBA, rows from the top.
fn draw(
    (device, queue): &(wgpu::Device, wgpu::Queue),
    vertex: (&[u32], &str),
    fragment: (&[u32], &str),
    uniforms: &[u8],
) -> Vec<[f32; 4]> {
    let (w, h) = FRAME;
    let module = |code: &[u32], entry: &str| unsafe {
        device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
            label: Some(entry),
            entry_points: vec![wgpu::PassthroughShaderEntryPoint {
                name: entry.into(),
                workgroup_size: (1, 1, 1),
            }]
            .into(),
            spirv: Some(code.into()),
            ..Default::default()
        })
    };
    let (vs, fs) = (module(vertex.0, vertex.1), module(fragment.0, fragment.1));
    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let format = wgpu::TextureFormat::Rgba32Float;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: None,
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &vs,
            entry_point: Some(vertex.1),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &fs,
            entry_point: Some(fragment.1),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleStrip,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    use wgpu::util::DeviceExt;
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: uniforms,
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &bgl,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let row = (16 * w).div_ceil(256) * 256;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (row * h) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let view = target.create_view(&Default::default());
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: CLEAR[0] as f64,
                        g: CLEAR[1] as f64,
                        b: CLEAR[2] as f64,
                        a: CLEAR[3] as f64,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..4, 0..1);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let data = slice.get_mapped_range().unwrap();
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h as usize {
        let line: &[f32] =
            bytemuck::cast_slice(&data[y * row as usize..y * row as usize + 16 * w as usize]);
        out.extend(line.chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]));
    }
    out
}

#[test]
#[cfg_attr(
    not(feature = "glslang"),
    ignore = "needs glslangValidator (Debian's glslang-tools) and Vulkan and --features glslang: ./test.sh runs it"
)]
fn the_glsl_and_hlsl_engines_get_give_the_twins_brightness_with_the_exported_camera() {
    let gpu = device();
    let dir = common::tmpdir("engine", "shaders");
    let at = |f: &str| dir.join(f).display().to_string();
    let (width, height) = FRAME;
    for (name, scene) in common::engine::scenes() {
        let effect = EffectShader::of(&scene, width as f64 / height as f64).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let (files, warning) = effect.write(&dir, "effect").unwrap();
        assert!(warning.is_none(), "{name}: {warning:?}");
        assert_eq!(files.len(), 11);
        // OpenGL: the vertex stage and ES 3.00's three stages as glslang reads them for GL.
        glslang(&["-G", &at("effect.vert"), "-o", &at("gl.vert.spv")]);
        for es in [
            "effect.es.vert",
            "effect.glow.es.frag",
            "effect.brightness.es.frag",
        ] {
            glslang(&[&at(es)]);
        }
        // Vulkan SPIR-V from the GLSL 4.50 (its vertex index named as Vulkan's GLSL names it) and from the HLSL.
        let vert = std::fs::read_to_string(at("effect.vert")).unwrap();
        std::fs::write(at("vk.vert"), vert.replace("gl_VertexID", "gl_VertexIndex")).unwrap();
        glslang(&["-V", &at("vk.vert"), "-o", &at("glsl.vert.spv")]);
        glslang(&[
            "-V",
            &at("effect.brightness.frag"),
            "-o",
            &at("glsl.frag.spv"),
        ]);
        glslang(&["-V", &at("effect.glow.frag"), "-o", &at("glsl.glow.spv")]);
        for (entry, stage) in [
            ("vs_main", "vert"),
            ("fs_brightness", "frag"),
            ("fs_glow", "frag"),
        ] {
            let out = at(&format!("hlsl.{entry}.spv"));
            glslang(&[
                "-D",
                "-V",
                "-S",
                stage,
                "-e",
                entry,
                &at("effect.hlsl"),
                "-o",
                &out,
            ]);
        }
        // Both languages' stages with the exported uniforms (`uniforms.bin`: the scene's camera), against the twin.
        let glsl_vertex = spirv(&dir.join("glsl.vert.spv"));
        for (language, vs, fs, glow) in [
            (
                "GLSL",
                (glsl_vertex.clone(), "main"),
                (spirv(&dir.join("glsl.frag.spv")), "main"),
                (spirv(&dir.join("glsl.glow.spv")), "main"),
            ),
            (
                "HLSL",
                (spirv(&dir.join("hlsl.vs_main.spv")), "vs_main"),
                (spirv(&dir.join("hlsl.fs_brightness.spv")), "fs_brightness"),
                (spirv(&dir.join("hlsl.fs_glow.spv")), "fs_glow"),
            ),
        ] {
            let uniforms = std::fs::read(at("effect.uniforms.bin")).unwrap();
            assert_eq!(
                uniforms, effect.uniforms,
                "{name}: the file holds the block"
            );
            let brightness = draw(&gpu, (&vs.0, vs.1), (&fs.0, fs.1), &uniforms);
            let glow = draw(&gpu, (&vs.0, vs.1), (&glow.0, glow.1), &uniforms);
            let (compared, outside, worst, top) = common::engine::check_against_twin(
                &format!("{name}, {language}"),
                &scene,
                &brightness,
                &glow,
            );
            eprintln!(
                "{name}, {language}: {compared} pixels, {outside} outside the billboard, B within {worst:.1e} of \
                 the twin's (relative, at least 0.01), largest B {top:.3}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
