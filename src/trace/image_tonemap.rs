//! Accumulated radiance to display pixels (kernel `image_tonemap`): average, exposure, ACES
//! filmic curve, sRGB encoding, packed RGBA8.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct TonemapParams {
    pub width: u32,
    pub height: u32,
    pub exposure: f32,
    pub _pad: u32,
}

kernel!(pub IMAGE_TONEMAP: TonemapParams = "image_tonemap"::"main", [8, 8, 1], [Read, ReadWrite]);
