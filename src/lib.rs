//! energywave: design and render "energy wave" effects by the method of Watanabe, Abe and Konno (2016).
//!
//! - [`field`]: the energy field psi and its sources, in f64 (the reference the GPU is checked against);
//! - [`integrate`]: the decay zeta and Simpson's rule along a texel's ray;
//! - [`geometry`]: the camera, the billboard and its rays;
//! - [`compose`]: the blend `clamp((1 - B) Cb + B Ce)` and texture sampling;
//! - [`reference`]: the multithreaded CPU renderer built from the above;
//! - [`gpu`]: the same on the GPU: WGSL compute and render passes, headless or in the viewer;
//! - [`scene`]: TOML scene files, validated field by field;
//! - [`animation`]: time in scenes: the travelling pulse (thesis eq. 5.1) and keyframes;
//! - [`export`]: frame sequences, GIFs and sprite sheets of an animation, with a progress bar;
//! - [`viewer`]: the interactive viewer (winit, egui, the same GPU passes);
//! - [`output`]: PNG and EXR files, written atomically;
//! - [`bench`]: the papers' speed grid and other benchmarks;
//! - [`cli`]: the `energywave` command line.

pub mod adaptive;
pub mod animation;
pub mod bench;
pub mod cli;
pub mod compose;
pub mod export;
pub mod field;
pub mod geometry;
pub mod gpu;
pub mod integrate;
pub mod output;
pub mod reference;
pub mod scene;
pub mod viewer;
