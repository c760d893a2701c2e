//! Shows the path tracer's tonemapped pixel buffer in the window: a render pipeline
//! (`shaders/image_display.wgsl`) drawing one fullscreen triangle into the image rectangle, reading
//! the packed RGBA8 storage buffer directly (no texture upload, no CPU round trip).

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind_entry, shader_source, uniform_buffer, GpuContext};

/// The render shader (vertex and fragment), the one WGSL file that is no compute kernel.
pub const DISPLAY_SHADER: &str = include_str!("../../shaders/image_display.wgsl");

/// A rectangle of the render target in physical pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelRect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl PixelRect {
    /// `rect` (egui points) in physical pixels, clipped to a `target` of the given size.
    pub fn from_points(rect: egui::Rect, pixels_per_point: f32, target: (u32, u32)) -> Self {
        let to_px = |v: f32, max: u32| ((v * pixels_per_point).round().max(0.0) as u32).min(max);
        let x = to_px(rect.min.x, target.0);
        let y = to_px(rect.min.y, target.1);
        Self {
            x,
            y,
            width: to_px(rect.max.x, target.0).saturating_sub(x),
            height: to_px(rect.max.y, target.1).saturating_sub(y),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.width == 0 || self.height == 0
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DisplayParams {
    origin: [u32; 2],
    size: [u32; 2],
    decode_srgb: u32,
    _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<DisplayParams>() == 32);

pub struct ImageDisplay {
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    decode_srgb: bool,
    /// Bind group and rectangle of the image prepared for this frame.
    prepared: Option<(wgpu::BindGroup, PixelRect)>,
}

impl ImageDisplay {
    /// A display pipeline writing to render targets of `format`.
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("image_display.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source(DISPLAY_SHADER, &[]).into()),
            });
        let pipeline = ctx
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("image_display"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
        Self {
            pipeline,
            params: uniform_buffer(ctx, "display params", &DisplayParams::zeroed()),
            decode_srgb: format.is_srgb(),
            prepared: None,
        }
    }

    /// Sets up drawing `pixels` (an image of `rect`'s size) into `rect`; `None` draws nothing.
    pub fn prepare(&mut self, ctx: &GpuContext, image: Option<(&wgpu::Buffer, PixelRect)>) {
        self.prepared = image
            .filter(|(_, rect)| !rect.is_empty())
            .map(|(pixels, rect)| {
                let params = DisplayParams {
                    origin: [rect.x, rect.y],
                    size: [rect.width, rect.height],
                    decode_srgb: u32::from(self.decode_srgb),
                    _pad: [0; 3],
                };
                ctx.queue
                    .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
                let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("image_display"),
                    layout: &self.pipeline.get_bind_group_layout(0),
                    entries: &[bind_entry(0, &self.params), bind_entry(1, pixels)],
                });
                (bind_group, rect)
            });
    }

    /// Records the draw of the prepared image into `pass`.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        let Some((bind_group, rect)) = &self.prepared else {
            return;
        };
        pass.set_viewport(
            rect.x as f32,
            rect.y as f32,
            rect.width as f32,
            rect.height as f32,
            0.0,
            1.0,
        );
        pass.set_scissor_rect(rect.x, rect.y, rect.width, rect.height);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rects_convert_to_pixels_and_clip() {
        let rect = egui::Rect::from_min_max(egui::pos2(300.0, 0.0), egui::pos2(640.0, 400.0));
        let px = PixelRect::from_points(rect, 2.0, (1000, 700));
        assert_eq!(
            px,
            PixelRect {
                x: 600,
                y: 0,
                width: 400,
                height: 700
            }
        );
        assert!(PixelRect::from_points(rect, 1.0, (200, 700)).is_empty());
    }
}
