//! The engine shader's GLSL ES 3.00 stages (`energywave shader`'s `NAME.es.vert`, `NAME.brightness.es.frag`,
//! `NAME.glow.es.frag`: what WebGL 2, phones and GLES engines compile) run as they are written, on Mesa's llvmpipe
//! through EGL and OpenGL ES 3 (surfaceless), fed the exported uniform block as it is: the scene's camera, its
//! `view_proj` and billboard as `uniforms.bin` holds them, in a frame of the aspect it was exported for. Each
//! pixel's B against the f64 twin's Simpson along that pixel's own ray (the camera's ray through the pixel's
//! center, met with the billboard's plane, continued to the ray's reach), so that a wrong camera number (a
//! `view_proj` off by a pixel, a billboard placed for another aspect) shows as well as a wrong field; the glow
//! stage's premultiplied color and alpha against the same B. Needs libEGL and Mesa's GLES driver (test.sh installs
//! them for the GL runs).

mod common;

use std::sync::{Mutex, OnceLock};

use common::engine::{CLEAR, FRAME};
use energywave::engine::EffectShader;
use glow::HasContext;
use khronos_egl as egl;

/// A current OpenGL ES 3 context on Mesa's surfaceless EGL platform (no window, no display server).
struct Gles {
    gl: glow::Context,
    egl: egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
}

// Used only under `gles`'s lock, which makes the context current on the thread that holds it.
unsafe impl Send for Gles {}

const EGL_PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;

fn open_gles() -> Gles {
    let egl = unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }
        .expect("libEGL.so.1 (Debian: libegl1 libegl-mesa0)");
    let display = unsafe {
        egl.get_platform_display(
            EGL_PLATFORM_SURFACELESS_MESA,
            egl::DEFAULT_DISPLAY,
            &[egl::ATTRIB_NONE],
        )
    }
    .expect("Mesa's surfaceless EGL platform");
    egl.initialize(display).expect("EGL initialises");
    let config = egl
        .choose_first_config(
            display,
            &[
                egl::RENDERABLE_TYPE,
                egl::OPENGL_ES3_BIT,
                egl::SURFACE_TYPE,
                0,
                egl::NONE,
            ],
        )
        .expect("EGL configs")
        .expect("an OpenGL ES 3 config (Debian: libgles2 libgl1-mesa-dri)");
    egl.bind_api(egl::OPENGL_ES_API).unwrap();
    let context = egl
        .create_context(
            display,
            config,
            None,
            &[
                egl::CONTEXT_MAJOR_VERSION,
                3,
                egl::CONTEXT_MINOR_VERSION,
                0,
                egl::NONE,
            ],
        )
        .expect("an OpenGL ES 3.0 context");
    egl.make_current(display, None, None, Some(context))
        .expect("a surfaceless context made current");
    let gl = unsafe {
        glow::Context::from_loader_function(|name| {
            egl.get_proc_address(name)
                .map_or(std::ptr::null(), |f| f as *const _)
        })
    };
    Gles {
        gl,
        egl,
        display,
        context,
    }
}

/// The one context, current on the calling thread while the guard is held: the tests here take turns on it.
fn gles() -> std::sync::MutexGuard<'static, Gles> {
    static GLES: OnceLock<Mutex<Gles>> = OnceLock::new();
    let guard =
        (GLES.get_or_init(|| Mutex::new(open_gles())).lock()).unwrap_or_else(|e| e.into_inner());
    (guard.egl)
        .make_current(guard.display, None, None, Some(guard.context))
        .expect("the context made current on this thread");
    guard
}

/// `vertex` and `fragment` (GLSL ES 3.00 sources) linked, their uniform blocks (one a stage, named by stage) bound
/// to `uniforms`, four vertices drawn as a triangle strip into a `width` x `height` RGBA32F target cleared to
/// `CLEAR`; RGBA, rows from the top.
fn draw(
    gl: &glow::Context,
    vertex: &str,
    fragment: &str,
    uniforms: &[u8],
    (width, height): (u32, u32),
) -> Vec<[f32; 4]> {
    unsafe {
        let compile = |kind: u32, source: &str| {
            let shader = gl.create_shader(kind).unwrap();
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            assert!(
                gl.get_shader_compile_status(shader),
                "the ES shader compiles: {}",
                gl.get_shader_info_log(shader)
            );
            shader
        };
        let program = gl.create_program().unwrap();
        let (vs, fs) = (
            compile(glow::VERTEX_SHADER, vertex),
            compile(glow::FRAGMENT_SHADER, fragment),
        );
        gl.attach_shader(program, vs);
        gl.attach_shader(program, fs);
        gl.link_program(program);
        assert!(
            gl.get_program_link_status(program),
            "the ES stages link: {}",
            gl.get_program_info_log(program)
        );
        let blocks = gl.get_program_parameter_i32(program, glow::ACTIVE_UNIFORM_BLOCKS) as u32;
        assert!(blocks >= 1, "the stages read the uniform block");
        for index in 0..blocks {
            let size = gl.get_active_uniform_block_parameter_i32(
                program,
                index,
                glow::UNIFORM_BLOCK_DATA_SIZE,
            );
            assert!(
                size as usize <= uniforms.len(),
                "block {index}: {size} bytes, the export has {}",
                uniforms.len()
            );
            gl.uniform_block_binding(program, index, 0);
        }
        let buffer = gl.create_buffer().unwrap();
        gl.bind_buffer(glow::UNIFORM_BUFFER, Some(buffer));
        gl.buffer_data_u8_slice(glow::UNIFORM_BUFFER, uniforms, glow::STATIC_DRAW);
        gl.bind_buffer_base(glow::UNIFORM_BUFFER, 0, Some(buffer));

        let target = gl.create_renderbuffer().unwrap();
        gl.bind_renderbuffer(glow::RENDERBUFFER, Some(target));
        gl.renderbuffer_storage(
            glow::RENDERBUFFER,
            glow::RGBA32F,
            width as i32,
            height as i32,
        );
        let framebuffer = gl.create_framebuffer().unwrap();
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(framebuffer));
        gl.framebuffer_renderbuffer(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::RENDERBUFFER,
            Some(target),
        );
        assert_eq!(
            gl.check_framebuffer_status(glow::FRAMEBUFFER),
            glow::FRAMEBUFFER_COMPLETE,
            "an RGBA32F target (EXT_color_buffer_float)"
        );
        gl.viewport(0, 0, width as i32, height as i32);
        gl.clear_buffer_f32_slice(glow::COLOR, 0, &CLEAR);
        let vao = gl.create_vertex_array().unwrap();
        gl.bind_vertex_array(Some(vao));
        gl.use_program(Some(program));
        gl.draw_arrays(glow::TRIANGLE_STRIP, 0, 4);
        let mut bytes = vec![0u8; (16 * width * height) as usize];
        gl.read_pixels(
            0,
            0,
            width as i32,
            height as i32,
            glow::RGBA,
            glow::FLOAT,
            glow::PixelPackData::Slice(Some(&mut bytes)),
        );
        assert_eq!(gl.get_error(), glow::NO_ERROR);
        gl.delete_vertex_array(vao);
        gl.delete_framebuffer(framebuffer);
        gl.delete_renderbuffer(target);
        gl.delete_buffer(buffer);
        gl.delete_program(program);
        gl.delete_shader(vs);
        gl.delete_shader(fs);
        // GL's rows run from the bottom.
        let floats: &[f32] = bytemuck::cast_slice(&bytes);
        (0..height as usize)
            .rev()
            .flat_map(|y| (0..width as usize).map(move |x| (y, x)))
            .map(|(y, x)| {
                let p = &floats[4 * (y * width as usize + x)..][..4];
                [p[0], p[1], p[2], p[3]]
            })
            .collect()
    }
}

#[test]
fn the_glsl_es_stages_run_with_the_exported_camera_and_give_the_twins_brightness() {
    let guard = gles();
    let gl = &guard.gl;
    let (width, height) = FRAME;
    for (name, scene) in common::engine::scenes() {
        let effect = EffectShader::of(&scene, width as f64 / height as f64).unwrap();
        let vertex = effect.glsl("vs_main", true).unwrap();
        assert!(
            vertex.starts_with("#version 300 es"),
            "{name}: {}",
            &vertex[..40]
        );
        let stage = |entry: &str| {
            let fragment = effect.glsl(entry, true).unwrap();
            draw(gl, &vertex, &fragment, &effect.uniforms, FRAME)
        };
        let (brightness, glow) = (stage("fs_brightness"), stage("fs_glow"));
        let (compared, outside, worst, top) =
            common::engine::check_against_twin(&name, &scene, &brightness, &glow);
        eprintln!(
            "{name}: {compared} pixels, {outside} outside the billboard, B and tint within {worst:.1e} of the twin's \
             (relative, at least 0.01), largest B {top:.3}"
        );
    }
    let version = unsafe { gl.get_parameter_string(glow::VERSION) };
    eprintln!("on {version}");
}
