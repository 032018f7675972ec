//! The texture formats the passes share: what a frame is composed in, and the objects' depth and its copy.

/// Format of composed frames: half floats (renderable on every backend, unlike Rgba32Float on GL), 11 bits of
/// mantissa, ample for colors in [0, 1] headed for 8-bit PNG or a float EXR.
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The depth buffer's format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The format of the copy of the objects' depth the billboard reads, written beside their color by the same
/// draw: the bits of the fragment's depth, exactly what the depth buffer holds; in the second channel the
/// nearest opaque surface's, which lies behind a translucent one where the first channel has that one (the
/// smoke seen through the translucent objects ends there: `shaders/particles.wgsl`). A depth texture cannot be
/// read by `textureLoad` on GL (naga writes no GLSL for it), and GL without `EXT_color_buffer_float`
/// (llvmpipe) cannot render into `rg32float`; every backend renders into `rg32uint` and reads it back.
pub const DEPTH_VALUE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;

/// The clear value of the depth's copy: the bits of the far plane's depth, 1.0 (as the depth buffer is cleared),
/// in both channels.
pub const DEPTH_VALUE_CLEAR: wgpu::Color = wgpu::Color {
    r: 0x3f80_0000 as f64,
    g: 0x3f80_0000 as f64,
    b: 0.0,
    a: 0.0,
};
