//! The effect as a game engine's shader (`energywave shader`): the GLSL 4.50 and the HLSL naga writes from our WGSL
//! compiled by glslang (Khronos' reference compiler, Debian's `glslang-tools`) to SPIR-V, that SPIR-V run as it
//! is on the GPU (wgpu's passthrough, Vulkan), the billboard drawn texel for texel: its B is the field pass's
//! Simpson B within f32, on points, lines, tori, curves with W and color series, the brightest-point W form and
//! the rms decay. The GLSL ES 3.00 stages and the GLSL 4.50 vertex stage are checked by glslang for OpenGL. Needs
//! `--features glslang` (`./test.sh` turns it on); without it the test is listed as ignored, with what it needs.

mod common;

use std::path::Path;
use std::process::Command;

use energywave::engine::EffectShader;
use energywave::frame::FrameSetup;
use energywave::gpu::HeadlessRenderer;
use energywave::integrate::{Decay, Integrator};
use energywave::scene::Scene;

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

/// The billboard's W x W texels drawn by the SPIR-V stages `vertex` and `fragment` (entry points by name), the
/// view set so that the quad covers the target exactly: each fragment's center is a texel's. RGBA: B and the tint.
fn draw(
    (device, queue): &(wgpu::Device, wgpu::Queue),
    vertex: (&[u32], &str),
    fragment: (&[u32], &str),
    uniforms: &[u8],
    w: u32,
) -> Vec<[f32; 4]> {
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
            height: w,
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
        size: (row * w) as u64,
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
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
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
            height: w,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let data = slice.get_mapped_range().unwrap();
    let mut out = Vec::with_capacity((w * w) as usize);
    for y in 0..w as usize {
        let line: &[f32] =
            bytemuck::cast_slice(&data[y * row as usize..y * row as usize + 16 * w as usize]);
        out.extend(line.chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]));
    }
    out
}

/// The uniforms of `effect` with the view set so that the billboard covers the clip square exactly.
fn covering(effect: &EffectShader) -> Vec<u8> {
    let v = effect.view.params;
    let half = v.size / 2.0;
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let rows = [
        [
            v.right[0] / half,
            v.right[1] / half,
            v.right[2] / half,
            -dot(v.center, v.right) / half,
        ],
        [
            v.up[0] / half,
            v.up[1] / half,
            v.up[2] / half,
            -dot(v.center, v.up) / half,
        ],
        [0.0, 0.0, 0.0, 0.5],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let columns: [[f32; 4]; 4] = std::array::from_fn(|c| std::array::from_fn(|r| rows[r][c]));
    let mut view = effect.view;
    view.view_proj = columns;
    let mut bytes = effect.uniforms.clone();
    bytes[..size_of::<energywave::engine::View>()].copy_from_slice(bytemuck::bytes_of(&view));
    bytes
}

/// Scenes that reach every part of the shader, Simpson's rule at the papers' n.
fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for name in [
        "default",
        "mixed",
        "pulse_travelling",
        "rings_and_beam",
        "bezier_b5.0",
    ] {
        let mut scene = common::shipped_scene(&format!("{name}.toml"));
        scene.integration.integrator = Integrator::Simpson;
        scene.billboard.resolution = 48;
        out.push((name.to_owned(), scene));
    }
    // The rms decay, and curves read at their brightest point (the continuous W form).
    let (_, mixed) = out[1].clone();
    let mut rms = mixed;
    rms.integration.decay = Decay::Rms;
    out.push(("mixed, rms".into(), rms));
    let (_, pulse) = out[2].clone();
    let mut bright = pulse.at_frame(30.0);
    (bright.sources.curves.iter_mut())
        .for_each(|c| c.w_form = energywave::field::WForm::Continuous);
    out.push(("pulse_travelling, continuous W".into(), bright));
    out
}

#[test]
#[cfg_attr(
    not(feature = "glslang"),
    ignore = "needs glslangValidator (Debian's glslang-tools) and Vulkan and --features glslang: ./test.sh runs it"
)]
fn the_glsl_and_hlsl_engines_get_give_the_field_pass_brightness_within_f32() {
    let gpu = device();
    let mut ours = HeadlessRenderer::new().unwrap();
    let dir = common::tmpdir("engine", "shaders");
    let at = |f: &str| dir.join(f).display().to_string();
    for (name, scene) in scenes() {
        let effect = EffectShader::of(&scene, 1.0).unwrap();
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
        // Our field pass, Simpson's rule, f32.
        let setup = FrameSetup::placed(&scene, 1.0);
        let w = setup.resolution;
        let want = ours.brightness(&setup).unwrap();
        let top = want.iter().fold(0.0f32, |m, b| m.max(b.abs()));
        assert!(top > 0.05, "{name}: a glow to compare ({top})");
        // And the f64 twin: the engine's f32 error against it is the field pass's own, not more.
        let twin = energywave::reference::render_brightness(&setup).values;
        let off = |b: &[f32]| -> f32 {
            (b.iter().zip(&twin)).fold(0.0f64, |m, (b, t)| m.max((*b as f64 - t).abs())) as f32
                / top
        };
        let pass_off = off(&want);
        let uniforms = covering(&effect);
        for (language, vs, fs) in [
            (
                "GLSL",
                (spirv(&dir.join("glsl.vert.spv")), "main"),
                (spirv(&dir.join("glsl.frag.spv")), "main"),
            ),
            (
                "HLSL",
                (spirv(&dir.join("hlsl.vs_main.spv")), "vs_main"),
                (spirv(&dir.join("hlsl.fs_brightness.spv")), "fs_brightness"),
            ),
        ] {
            let got = draw(&gpu, (&vs.0, vs.1), (&fs.0, fs.1), &uniforms, w);
            let mut worst = 0.0f32;
            for (g, b) in got.iter().zip(&want) {
                worst = worst.max((g[0] - b).abs() / top);
            }
            let b: Vec<f32> = got.iter().map(|g| g[0]).collect();
            let twin_off = off(&b);
            eprintln!(
                "{name}, {language}: B within {worst:.1e} of the field pass's (of the largest B, {w}x{w} texels); \
                 {twin_off:.1e} from the f64 twin, the field pass {pass_off:.1e}"
            );
            assert!(
                worst < 1e-4,
                "{name}, {language}: B off by {worst:e} of the largest ({top})"
            );
            assert!(
                twin_off <= 4.0 * pass_off + 1e-5,
                "{name}, {language}: {twin_off:e} from the twin, the field pass {pass_off:e}"
            );
        }
        // The glow the engine blends: G premultiplied, alpha min(B, 1), against the same B.
        let glow = draw(
            &gpu,
            (&spirv(&dir.join("glsl.vert.spv")), "main"),
            (&spirv(&dir.join("glsl.glow.spv")), "main"),
            &uniforms,
            w,
        );
        // Its color too, not the alpha alone: G = B Ce + the sources' tint, faded at the glow's edge, against our
        // field pass's B and tint and the scene's energy color.
        let tint = ours.tint().expect("the field pass's tint");
        let energy = scene.colors.energy_color();
        for ((g, b), t) in glow.iter().zip(&want).zip(&tint) {
            let fade = energywave::scene::edge_fade(*b as f64, scene.colors.cutoff) as f32;
            assert!(
                (g[3] - (b * fade).clamp(0.0, 1.0)).abs() < 1e-4,
                "{name}: alpha {} for B {b}",
                g[3]
            );
            for k in 0..3 {
                let color = (fade * (b * energy[k] as f32 + t[k])).max(0.0);
                assert!(
                    (g[k] - color).abs() < 1e-4 * color.abs().max(1.0),
                    "{name}: premultiplied color {g:?} for B {b}, tint {t:?}: channel {k} should be {color}"
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
