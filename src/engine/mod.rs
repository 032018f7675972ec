//! The effect as a shader a game engine runs (thesis 6.2): `shaders/engine/effect.wgsl` composed for one scene's
//! structure (how many sources of each kind, curve segments, W weights, color series, the Simpson n and the decay,
//! as constants) with every value in one uniform block (`effect`: the view and the sources, which the game sets
//! and animates), then written by naga's backends as GLSL 4.50 and GLSL ES 3.00 (one file a stage), HLSL (shader
//! model 5.0) and MSL, beside the block's layout (JSON) and its values for the scene's own camera (binary). The
//! field functions are the field pass's own files (`shaders/shared/`), read with the uniform block standing in
//! for its storage buffers (`engine/globals.wgsl`). Uniforms only: GLSL ES 3.0 has no storage buffers.
//! Engines' recipes: docs/engines/README.md.

use std::path::{Path, PathBuf};

use crate::frame::FrameSetup;
use crate::gpu::field_pass::{FieldParams, frame_bindings};
use crate::integrate::Decay;
use crate::scene::Scene;

/// The file the effect's module imports for its structure, written for each scene (`compose`).
pub const STRUCTURE: &str = "engine/structure.wgsl";

/// The largest uniform block written: what Direct3D 11 (a constant buffer's 4,096 float4), Metal and desktop GL
/// drivers all take.
pub const MAX_BLOCK_BYTES: usize = 65536;
/// The uniform block GLSL ES 3.0 guarantees (GL_MAX_UNIFORM_BLOCK_SIZE at least 16 KiB): past it the ES shader is
/// still written, with a warning.
pub const ES_BLOCK_BYTES: usize = 16384;
/// The most Simpson divisions the shader takes: each fragment loops over n + 1 samples per source.
pub const MAX_DIVISIONS: u32 = 4096;

/// The view part of the block, as `engine/globals.wgsl` declares `View` (224 bytes): the view-projection, the
/// field pass's own parameter block (`shared/field_params.wgsl`, filled as the field pass fills it), and the
/// blend's energy color and edge.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct View {
    pub view_proj: [[f32; 4]; 4], // 0, columns
    pub params: FieldParams,      // 64
    pub energy: [f32; 3],         // 208
    pub cutoff: f32,              // 220
}
const _: () = assert!(size_of::<View>() == 224);

/// One member of the uniform block: its name, where it starts, its length and what one element is.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Member {
    pub name: &'static str,
    pub offset: usize,
    pub bytes: usize,
    /// Elements in use (an empty list keeps one zeroed element: WGSL has no arrays of none).
    pub count: usize,
    pub element: &'static str,
}

/// The shader of one scene, with its uniform block.
#[derive(Clone, Debug)]
pub struct EffectShader {
    /// The composed WGSL module.
    pub wgsl: String,
    /// The block's members, in order.
    pub layout: Vec<Member>,
    /// The block's values for the scene's camera.
    pub uniforms: Vec<u8>,
    /// The view part alone (`layout[0]`), to set again as the camera moves.
    pub view: View,
    /// What a game needs to place the billboard and the rays again as its camera moves.
    pub placement: Placement,
    module: naga::Module,
    info: naga::valid::ModuleInfo,
}

/// The scene's numbers behind the view's values (`geometry::place_billboard`, `geometry::ray_reach`,
/// `Integration::on_ray`), for a game that moves the camera: docs/engines/README.md gives the formulas.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Placement {
    /// The sources' bounds: their center and half diagonal.
    pub bounds_center: [f64; 3],
    pub bounds_radius: f64,
    /// The decay length in world units, and the scene's decay alpha and beta over it.
    pub decay_length: f64,
    pub alpha: f64,
    pub beta: f64,
    /// The scene's own stretch factor (1 unless the integration sets it).
    pub stretch: f64,
}

/// Why a scene makes no engine shader.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    #[error(
        "the scene's values take {bytes} bytes of uniforms, more than the {MAX_BLOCK_BYTES} every engine's \
         backends take: fewer curve segments, W weights or color stops"
    )]
    TooLarge { bytes: usize },
    #[error(
        "integration.divisions = {n}: each fragment would take {n} samples a source; at most {MAX_DIVISIONS} in a \
         game's shader (the papers' 200 is plenty on screen)"
    )]
    TooManyDivisions { n: u32 },
    #[error("naga cannot write the shader as {target}: {message}")]
    Backend {
        target: &'static str,
        message: String,
    },
    #[error("{}: cannot be made a folder for the shader's files: {source}", path.display())]
    Folder {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl EngineError {
    /// True when the scene is at fault (exit status 2).
    pub fn is_input_error(&self) -> bool {
        matches!(
            self,
            EngineError::TooLarge { .. }
                | EngineError::TooManyDivisions { .. }
                | EngineError::Folder { .. }
        )
    }
}

/// The array members after the view: name, element type, element size, elements in use.
fn members(
    p: &FieldParams,
    bytes: &[Vec<u8>; 9],
) -> Vec<(&'static str, &'static str, usize, usize)> {
    // source_bindings' order: points, lines, tori, curves, segments, weights, tints, colors, pieces.
    let len = |k: usize, size: usize| bytes[k].len() / size;
    vec![
        ("points", "PointSource", 16, p.point_count as usize),
        ("lines", "LineSource", 32, p.line_count as usize),
        ("tori", "TorusSource", 32, p.torus_count as usize),
        ("curves", "CurveSource", 48, p.curve_count as usize),
        ("segments", "CurveSegment", 48, len(4, 48)),
        ("pieces", "CurvePiece", 80, len(8, 80)),
        ("tints", "vec4<f32>", 16, len(6, 16)),
        ("colors", "vec4<f32>", 16, len(7, 16)),
        // The W series, four f32 to an element.
        ("weights", "vec4<f32>", 16, len(5, 4).div_ceil(4)),
    ]
}

/// `source` with every `name[...]` read as `with(...)` (`with` ending in `[` keeps the brackets: an index into
/// another array), for the shared files' buffers that the effect reads from its uniform block.
fn rename_index(source: &str, name: &str, with: &str) -> String {
    let pattern = format!("{name}[");
    let mut out = String::with_capacity(source.len());
    let mut rest = source;
    while let Some(at) = rest.find(&pattern) {
        let before = rest[..at].chars().next_back();
        let word_start = !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.');
        if !word_start {
            out.push_str(&rest[..at + pattern.len()]);
            rest = &rest[at + pattern.len()..];
            continue;
        }
        out.push_str(&rest[..at]);
        // The matching bracket.
        let inner = &rest[at + pattern.len()..];
        let mut depth = 1;
        let mut end = inner.len();
        for (k, c) in inner.char_indices() {
            match c {
                '[' => depth += 1,
                ']' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k;
                        break;
                    }
                }
                _ => {}
            }
        }
        let index = rename_index(&inner[..end], name, with);
        match with.strip_suffix('[') {
            Some(array) => out.push_str(&format!("{array}[{index}]")),
            None => out.push_str(&format!("{with}({index})")),
        }
        rest = &inner[(end + 1).min(inner.len())..];
    }
    out.push_str(rest);
    out
}

/// The WGSL module of the effect for a structure: `structure` is engine/structure.wgsl's text.
pub fn compose(structure: &str) -> String {
    use crate::gpu::shaders;
    let lookup = |path: &str| -> Option<String> {
        let text = match path {
            STRUCTURE => return Some(structure.to_owned()),
            // The field pass's bindings: the uniform block instead.
            "shared/field_pass.wgsl" => {
                return Some("#import shared/curve.wgsl\n#import engine/globals.wgsl\n".to_owned());
            }
            // The adaptive integrator's Gauss-Kronrod table, the generated file's last part, is not the effect's
            // (glslang's HLSL reader takes the array constructor naga writes for it for a recursion).
            shaders::CONSTANTS => {
                let all = shaders::file(path)?;
                let cut = all.find("const KRONROD:").unwrap_or(all.len());
                all[..cut].to_owned()
            }
            p => shaders::file(p)?,
        };
        // The curves' buffers, from the uniform block.
        let text = rename_index(&text, "segments", "effect.segments[");
        let text = rename_index(&text, "pieces", "effect.pieces[");
        let text = rename_index(&text, "colors", "effect.colors[");
        Some(rename_index(&text, "weights", "weight_at"))
    };
    shaders::compose_with("engine/effect.wgsl", &lookup)
        .unwrap_or_else(|e| panic!("shaders/engine/effect.wgsl: {e}"))
}

/// engine/structure.wgsl for a scene: its counts and the arrays' lengths.
fn structure(p: &FieldParams, arrays: &[(&str, &str, usize, usize)], rms: bool) -> String {
    let mut s =
        String::from("// The scene's structure (src/engine writes this file for each scene).\n");
    for (name, value) in [
        ("POINTS", p.point_count),
        ("LINES", p.line_count),
        ("TORI", p.torus_count),
        ("CURVES", p.curve_count),
        ("DIVISIONS", p.divisions),
        ("SEARCH", p.search),
    ] {
        s += &format!("const {name}: u32 = {value}u;\n");
    }
    s += &format!("const RMS: bool = {rms};\n");
    for (name, _, _, count) in arrays {
        let slots = match *name {
            "points" => "POINT_SLOTS",
            "lines" => "LINE_SLOTS",
            "tori" => "TORUS_SLOTS",
            "curves" => "CURVE_SLOTS",
            "segments" => "SEGMENT_SLOTS",
            "pieces" => "PIECE_SLOTS",
            "tints" => "TERM_SLOTS",
            "colors" => "COLOR_SLOTS",
            _ => "WEIGHT_SLOTS",
        };
        s += &format!("const {slots}: u32 = {}u;\n", (*count).max(1));
    }
    s
}

impl EffectShader {
    /// The shader of `scene` (its own integration n and decay; always Simpson's rule) and its values for the
    /// scene's camera in a frame of `aspect` (width / height).
    pub fn of(scene: &Scene, aspect: f64) -> Result<EffectShader, EngineError> {
        let n = scene.integration.divisions;
        if n > MAX_DIVISIONS {
            return Err(EngineError::TooManyDivisions { n });
        }
        let setup = FrameSetup::placed(scene, aspect);
        let (params, bytes) = frame_bindings(&setup);
        let arrays = members(&params, &bytes);
        let rms = setup.integration.decay == Decay::Rms;
        let wgsl = compose(&structure(&params, &arrays, rms));
        let energy = scene.colors.energy_color().map(|c| c as f32);
        let view_proj =
            crate::gpu::view_projection(&scene.camera, &setup.billboard, aspect).as_mat4();
        let view = View {
            view_proj: view_proj.to_cols_array_2d(),
            params,
            energy,
            cutoff: scene.colors.cutoff as f32,
        };
        let (lo, hi) = scene
            .sources
            .bounds()
            .unwrap_or((scene.camera.target, scene.camera.target));
        let placement = Placement {
            bounds_center: ((lo + hi) * 0.5).to_array(),
            bounds_radius: (hi - lo).length() * 0.5,
            decay_length: scene.integration.decay_length,
            alpha: scene.integration.alpha,
            beta: scene.integration.beta,
            stretch: scene.integration.stretch,
        };
        let mut uniforms = bytemuck::bytes_of(&view).to_vec();
        let mut layout = vec![Member {
            name: "view",
            offset: 0,
            bytes: uniforms.len(),
            count: 1,
            element: "View",
        }];
        let sources = [0, 1, 2, 3, 4, 8, 6, 7, 5];
        for ((name, element, size, count), k) in arrays.iter().zip(sources) {
            let offset = uniforms.len();
            let mut data = bytes[k].clone();
            data.resize(size * (*count).max(1), 0);
            uniforms.extend(data);
            layout.push(Member {
                name,
                offset,
                bytes: uniforms.len() - offset,
                count: *count,
                element,
            });
        }
        if uniforms.len() > MAX_BLOCK_BYTES {
            return Err(EngineError::TooLarge {
                bytes: uniforms.len(),
            });
        }
        let mut module = naga::front::wgsl::parse_str(&wgsl)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&wgsl)));
        // Only what the entry points use: the field's shared constants include the adaptive integrator's
        // tables, which the backends would write out for nothing (and glslang's HLSL reader takes an array
        // constructor of one of them for a recursion).
        naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&wgsl)));
        Ok(EffectShader {
            wgsl,
            layout,
            uniforms,
            view,
            placement,
            module,
            info,
        })
    }

    /// The shader's stage `entry` (vs_main, fs_glow, fs_brightness) as GLSL 4.50, or with `es` GLSL ES 3.00.
    pub fn glsl(&self, entry: &str, es: bool) -> Result<String, EngineError> {
        use naga::back::glsl;
        let stage = match entry {
            "vs_main" => naga::ShaderStage::Vertex,
            _ => naga::ShaderStage::Fragment,
        };
        let version = match es {
            true => glsl::Version::Embedded {
                version: 300,
                is_webgl: false,
            },
            false => glsl::Version::Desktop(450),
        };
        let mut binding_map = glsl::BindingMap::default();
        binding_map.insert(
            naga::ResourceBinding {
                group: 0,
                binding: 0,
            },
            0,
        );
        let options = glsl::Options {
            version,
            writer_flags: glsl::WriterFlags::empty(),
            binding_map,
            zero_initialize_workgroup_memory: false,
        };
        let pipeline = glsl::PipelineOptions {
            shader_stage: stage,
            entry_point: entry.to_owned(),
            multiview: None,
        };
        let target = if es { "GLSL ES 3.00" } else { "GLSL 4.50" };
        let fail = |e: glsl::Error| EngineError::Backend {
            target,
            message: e.to_string(),
        };
        let mut out = String::new();
        let mut writer = glsl::Writer::new(
            &mut out,
            &self.module,
            &self.info,
            &options,
            &pipeline,
            naga::proc::BoundsCheckPolicies::default(),
        )
        .map_err(fail)?;
        writer.write().map_err(fail)?;
        Ok(out)
    }

    /// Every entry point as HLSL for shader model 5.0 (the uniform block a `cbuffer` at register b0).
    pub fn hlsl(&self) -> Result<String, EngineError> {
        use naga::back::hlsl;
        let options = hlsl::Options {
            shader_model: hlsl::ShaderModel::V5_0,
            ..Default::default()
        };
        let fail = |e: hlsl::Error| EngineError::Backend {
            target: "HLSL",
            message: e.to_string(),
        };
        let mut out = String::new();
        let pipeline = hlsl::PipelineOptions::default();
        let mut writer = hlsl::Writer::new(&mut out, &options, &pipeline);
        writer.write(&self.module, &self.info, None).map_err(fail)?;
        Ok(out)
    }

    /// Every entry point as Metal Shading Language 2.0 (the uniform block at buffer index 0).
    pub fn msl(&self) -> Result<String, EngineError> {
        use naga::back::msl;
        let options = msl::Options {
            lang_version: (2, 0),
            fake_missing_bindings: true,
            ..Default::default()
        };
        let pipeline = msl::PipelineOptions::default();
        let (out, _) =
            msl::write_string(&self.module, &self.info, &options, &pipeline).map_err(|e| {
                EngineError::Backend {
                    target: "MSL",
                    message: e.to_string(),
                }
            })?;
        Ok(out)
    }

    /// The block's layout and where each value is, as JSON (what a game reads to animate the values).
    pub fn layout_json(&self) -> String {
        #[derive(serde::Serialize)]
        struct Layout<'a> {
            block: &'static str,
            binding: &'static str,
            bytes: usize,
            view: Vec<(&'static str, usize)>,
            members: &'a [Member],
            placement: Placement,
        }
        let view = vec![
            ("view_proj", 0),
            ("eye", 64),
            ("nu", 76),
            ("center", 80),
            ("size", 92),
            ("right", 96),
            ("alpha", 108),
            ("up", 112),
            ("beta", 124),
            ("energy", 128),
            ("cutoff", 140),
            ("epsilon", 144),
            ("stretch", 148),
        ];
        let layout = Layout {
            block: "effect (std140 / HLSL packing: every member 16-byte aligned, arrays 16 bytes a step)",
            binding: "group 0, binding 0 (GLSL binding 0, HLSL register b0, MSL buffer 0)",
            bytes: self.uniforms.len(),
            view,
            members: &self.layout,
            placement: self.placement,
        };
        serde_json::to_string_pretty(&layout).expect("plain data")
    }

    /// Writes the shader for engines into `dir` (made if needed), each file whole or not at all: the WGSL, GLSL
    /// 4.50 and ES 3.00 stages, HLSL, MSL, the block's layout and its values. Returns the files written and a
    /// warning where the ES shader's block passes what GLSL ES 3.0 guarantees.
    pub fn write(
        &self,
        dir: &Path,
        name: &str,
    ) -> Result<(Vec<PathBuf>, Option<String>), EngineError> {
        std::fs::create_dir_all(dir).map_err(|source| EngineError::Folder {
            path: dir.to_owned(),
            source,
        })?;
        let mut files: Vec<(String, Vec<u8>)> =
            vec![(format!("{name}.wgsl"), self.wgsl.clone().into())];
        for (entry, ext) in [
            ("vs_main", "vert"),
            ("fs_glow", "frag"),
            ("fs_brightness", "frag"),
        ] {
            let stem = match entry {
                "vs_main" => name.to_owned(),
                e => format!("{name}.{}", e.trim_start_matches("fs_")),
            };
            files.push((format!("{stem}.{ext}"), self.glsl(entry, false)?.into()));
            files.push((format!("{stem}.es.{ext}"), self.glsl(entry, true)?.into()));
        }
        files.push((format!("{name}.hlsl"), self.hlsl()?.into()));
        files.push((format!("{name}.metal"), self.msl()?.into()));
        files.push((format!("{name}.uniforms.json"), self.layout_json().into()));
        files.push((format!("{name}.uniforms.bin"), self.uniforms.clone()));
        // Into a folder beside them first, then moved into place together: a failure leaves the files of an
        // earlier export whole, never a new stage beside an old block.
        let io = |path: &Path, e: crate::output::OutputError| EngineError::Io {
            path: path.to_owned(),
            source: std::io::Error::other(e.to_string()),
        };
        let first = dir.join(&files[0].0);
        let mut staged =
            crate::export::staged::Staged::beside(&first).map_err(|e| io(&first, e))?;
        for (file, bytes) in &files {
            let path = staged.stage(&dir.join(file));
            crate::output::write_atomically(&path, bytes).map_err(|e| io(&path, e))?;
        }
        let written = staged.commit().map_err(|e| io(dir, e))?;
        let warning = (self.uniforms.len() > ES_BLOCK_BYTES).then(|| {
            format!(
                "the uniform block is {} bytes: GLSL ES 3.0 guarantees {ES_BLOCK_BYTES} (WebGL 2 and some phones \
                 take no more)",
                self.uniforms.len()
            )
        });
        Ok((written, warning))
    }
}

#[cfg(test)]
mod tests {
    use super::rename_index;

    #[test]
    fn indexing_a_buffer_reads_the_block() {
        assert_eq!(
            rename_index(
                "a = weights[c.first_weight + i] + weights[min(w + 1u, last)];",
                "weights",
                "weight_at"
            ),
            "a = weight_at(c.first_weight + i) + weight_at(min(w + 1u, last));"
        );
        assert_eq!(
            rename_index(
                "held.weights[2] + my_weights[1] + weights[weights[0]]",
                "weights",
                "weight_at"
            ),
            "held.weights[2] + my_weights[1] + weight_at(weight_at(0))"
        );
        assert_eq!(
            rename_index("colors[k].xyz", "colors", "effect.colors["),
            "effect.colors[k].xyz"
        );
    }
}
