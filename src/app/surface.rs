//! The window's swap chain: format choice (a non-sRGB 8-bit format when offered, which is what
//! egui-wgpu prefers; sRGB formats work too), no-vsync presentation (the path tracer converges
//! faster and the fps shown is the real throughput), resizing and frame acquisition.

use crate::gpu::GpuContext;
use crate::{Error, Result};

pub struct WindowSurface {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The surface must be configured again before the next frame.
    stale: bool,
}

impl WindowSurface {
    pub fn new(
        ctx: &GpuContext,
        surface: wgpu::Surface<'static>,
        size: (u32, u32),
    ) -> Result<Self> {
        let caps = surface.get_capabilities(&ctx.adapter);
        let preferred = [
            wgpu::TextureFormat::Bgra8Unorm,
            wgpu::TextureFormat::Rgba8Unorm,
        ];
        let format = preferred
            .into_iter()
            .find(|f| caps.formats.contains(f))
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "the window surface cannot be presented from {}",
                    ctx.info.name
                ))
            })?;
        let alpha_mode = if caps.alpha_modes.contains(&wgpu::CompositeAlphaMode::Opaque) {
            wgpu::CompositeAlphaMode::Opaque
        } else {
            wgpu::CompositeAlphaMode::Auto
        };
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.0.max(1),
            height: size.1.max(1),
            present_mode: wgpu::PresentMode::AutoNoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode,
            view_formats: vec![],
        };
        surface.configure(&ctx.device, &config);
        log::info!(
            "viewer surface: {format:?}, {}x{}",
            config.width,
            config.height
        );
        Ok(Self {
            surface,
            config,
            stale: false,
        })
    }

    pub fn format(&self) -> wgpu::TextureFormat {
        self.config.format
    }

    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Follows the window's new inner size (ignored while it is zero, e.g. minimized).
    pub fn resize(&mut self, size: (u32, u32)) {
        if size.0 > 0 && size.1 > 0 && size != self.size() {
            self.config.width = size.0;
            self.config.height = size.1;
            self.stale = true;
        }
    }

    /// The texture to draw the next frame into, or `None` when this frame must be skipped.
    pub fn acquire(&mut self, ctx: &GpuContext) -> Option<wgpu::SurfaceTexture> {
        if self.stale {
            self.surface.configure(&ctx.device, &self.config);
            self.stale = false;
        }
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(texture) => Some(texture),
            wgpu::CurrentSurfaceTexture::Suboptimal(texture) => {
                self.stale = true;
                Some(texture)
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => None,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.stale = true;
                None
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                log::warn!("surface texture acquisition failed validation; skipping a frame");
                None
            }
        }
    }
}
