//! The textures a frame is composed in.

use super::context::texture_2d;
use super::formats::{DEPTH_FORMAT, DEPTH_VALUE_FORMAT, FRAME_FORMAT};

/// The two textures of a composed frame: what lies behind the billboard, and the result.
pub struct FrameTargets {
    pub size: [u32; 2],
    pub background: wgpu::Texture,
    pub background_view: wgpu::TextureView,
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    /// The objects' depth buffer (the depth test).
    pub depth_view: wgpu::TextureView,
    /// The copy of the objects' depth the billboard reads (`DEPTH_VALUE_FORMAT`).
    pub depth_value_view: wgpu::TextureView,
}

impl FrameTargets {
    pub fn new(device: &wgpu::Device, size: [u32; 2]) -> Self {
        use wgpu::TextureUsages as U;
        let background = texture_2d(
            device,
            "energywave.frame.background",
            size,
            FRAME_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let color = texture_2d(
            device,
            "energywave.frame.color",
            size,
            FRAME_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_DST | U::COPY_SRC,
        );
        let depth = texture_2d(
            device,
            "energywave.frame.depth",
            size,
            DEPTH_FORMAT,
            U::RENDER_ATTACHMENT,
        );
        let depth_value = texture_2d(
            device,
            "energywave.frame.depth_value",
            size,
            DEPTH_VALUE_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
        );
        Self {
            size,
            depth_view: depth.create_view(&Default::default()),
            depth_value_view: depth_value.create_view(&Default::default()),
            background_view: background.create_view(&Default::default()),
            color_view: color.create_view(&Default::default()),
            background,
            color,
        }
    }
}
