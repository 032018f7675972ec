//! energywave: design and render "energy wave" effects by the method of Watanabe, Abe and Konno (2016).
//!
//! - [`background`]: work resolved off the caller's thread, the newest request first (the viewer's preparation);
//! - [`field`]: the energy field psi and its sources, in f64 (the reference the GPU is checked against);
//! - [`integrate`]: how a scene integrates along a texel's ray: the integrator, its settings, the decay zeta;
//! - [`geometry`]: the camera, the billboard and its rays;
//! - [`noise`]: value noise with its gradient (the turbulence of live particles, the density of translucent objects);
//! - [`objects`]: spheres, boxes, planes and glTF meshes that hide the glow and are lit by it;
//! - [`particles`]: particle sets (smoke, dust, sparks): the particle, its kernel and the kernel's integrals;
//! - [`animation`]: time in scenes: the travelling pulse (thesis eq. 5.1) and keyframes;
//! - [`scene`]: TOML scene files, validated field by field;
//! - [`frame`]: a frame's data (billboard, reach, terms; clips, the objects' and particles' light, live states),
//!   resolved once before any pass records, through the one cache its renderer owns;
//! - [`reference`]: the f64 CPU renderer, one module for each GPU pass it twins, named alike;
//! - [`gpu`]: the same on the GPU: the field pass, then a frame's passes as one ordered list, headless or in the
//!   viewer;
//! - [`output`]: PNG and EXR files, written atomically;
//! - [`export`]: frame sequences, GIFs and sprite sheets of an animation, with a progress bar, and `assemble`,
//!   which joins frames rendered apart;
//! - [`farm`]: a sequence in chunks as jobs of a render farm's scheduler (Slurm);
//! - [`engine`]: the effect as a shader a game engine runs (GLSL, HLSL, MSL by naga);
//! - [`viewer`]: the interactive viewer (winit, egui, the same GPU passes);
//! - [`bench`]: the papers' speed grid and other benchmarks;
//! - [`cli`]: the `energywave` command line.
//!
//! Each module uses only those listed before it, and within a module its files call one another without a
//! circle (tests/module_graph.rs checks both): a new module goes after what it uses.

pub mod animation;
pub mod background;
pub mod bench;
pub mod cli;
pub mod engine;
pub mod export;
pub mod farm;
pub mod field;
pub mod frame;
pub mod geometry;
pub mod gpu;
pub mod integrate;
pub mod noise;
pub mod objects;
pub mod output;
pub mod particles;
pub mod reference;
pub mod scene;
pub mod viewer;
