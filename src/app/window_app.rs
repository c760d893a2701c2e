//! The winit application: opens the window, the wgpu surface and a device that can present to it,
//! wires egui (egui-winit for input, egui-wgpu for drawing), and on every redraw runs the viewer's
//! frame and draws the image and the panel. Also the automation flags: after N frames, write a
//! screenshot of the whole window and exit.

use std::path::PathBuf;
use std::sync::Arc;

use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use super::display::ImageDisplay;
use super::options::ViewerOptions;
use super::screenshot::{timestamped_path, Capture};
use super::surface::WindowSurface;
use super::viewer::Viewer;
use crate::gpu::{instance_flags, GpuContext};
use crate::trace::save_png;
use crate::{Error, Result};

/// Background of the window where no image is drawn (yet).
const CLEAR: wgpu::Color = wgpu::Color {
    r: 0.02,
    g: 0.02,
    b: 0.025,
    a: 1.0,
};

/// Opens the viewer window and runs until it is closed (or the automation flags end it).
pub fn run(options: ViewerOptions) -> Result<()> {
    let event_loop = EventLoop::new()
        .map_err(|e| Error::Gpu(format!("cannot connect to a display for the viewer: {e}")))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut descriptor = wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
        event_loop.owned_display_handle(),
    ));
    descriptor.flags = instance_flags();
    let instance = wgpu::Instance::new(descriptor);
    let mut app = App {
        options,
        instance: Some(instance),
        running: None,
        outcome: Ok(()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Gpu(format!("viewer event loop failed: {e}")))?;
    app.outcome
}

struct App {
    options: ViewerOptions,
    /// Taken when the device is opened on the first `resumed`.
    instance: Option<wgpu::Instance>,
    running: Option<Running>,
    /// What `run` returns: set by a fatal error or a failed automated screenshot.
    outcome: Result<()>,
}

/// Everything that exists while the window is open.
struct Running {
    window: Arc<Window>,
    surface: WindowSurface,
    ctx: GpuContext,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    display: ImageDisplay,
    viewer: Viewer,
    frames: u64,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(instance) = self.instance.take() else {
            return;
        };
        match Running::open(event_loop, instance, &self.options) {
            Ok(running) => {
                running.window.request_redraw();
                self.running = Some(running);
            }
            Err(e) => {
                self.outcome = Err(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(running) = self.running.as_mut() else {
            return;
        };
        // egui sees every event; it tells us nothing we need (we repaint continuously).
        let _ = running.egui_state.on_window_event(&running.window, &event);
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => event_loop.exit(),
            WindowEvent::Resized(size) => running.surface.resize((size.width, size.height)),
            WindowEvent::RedrawRequested => match running.redraw(&self.options) {
                Ok(FrameEnd::Continue) => running.window.request_redraw(),
                Ok(FrameEnd::Exit) => event_loop.exit(),
                Err(e) => {
                    self.outcome = Err(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(running) = &self.running {
            log::info!("{}", running.viewer.summary());
        }
    }
}

/// Whether the automation flags ended the run with this frame.
enum FrameEnd {
    Continue,
    Exit,
}

impl Running {
    fn open(
        event_loop: &ActiveEventLoop,
        instance: wgpu::Instance,
        options: &ViewerOptions,
    ) -> Result<Self> {
        let (width, height) = options.window_size;
        let attributes = Window::default_attributes()
            .with_title("treelet")
            .with_inner_size(winit::dpi::PhysicalSize::new(width, height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| Error::Gpu(format!("cannot open the viewer window: {e}")))?,
        );
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| Error::Gpu(format!("cannot create a surface for the window: {e}")))?;
        let ctx = GpuContext::with_instance(instance, &options.gpu, Some(&surface))?;
        let size = window.inner_size();
        let surface = WindowSurface::new(&ctx, surface, (size.width, size.height))?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            surface.format(),
            egui_wgpu::RendererOptions::default(),
        );
        let display = ImageDisplay::new(&ctx, surface.format());
        let viewer = Viewer::new(&ctx, options)?;
        Ok(Self {
            window,
            surface,
            ctx,
            egui_ctx,
            egui_state,
            egui_renderer,
            display,
            viewer,
            frames: 0,
        })
    }

    /// One frame: UI, the viewer's animate → build → trace, then drawing and presenting.
    fn redraw(&mut self, options: &ViewerOptions) -> Result<FrameEnd> {
        let target = self.surface.size();
        let raw_input = self.egui_state.take_egui_input(&self.window);
        let mut actions = Default::default();
        let output = self.egui_ctx.run_ui(raw_input, |ui| {
            actions = self.viewer.run_ui(ui, &self.ctx.info, target);
        });
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let button_screenshot = actions.screenshot;
        self.viewer.update(&self.ctx, actions);

        let last_frame = options
            .exit_after_frames
            .is_some_and(|n| self.frames + 1 >= n);
        let capture_to: Option<(PathBuf, bool)> = match &options.screenshot {
            Some(path) if last_frame => Some((path.clone(), true)),
            _ if button_screenshot => Some((timestamped_path(unix_seconds()), false)),
            _ => None,
        };

        let device = &self.ctx.device;
        let queue = &self.ctx.queue;
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(device, queue, *id, delta);
            }
        }
        let paint_jobs = self
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        let Some(frame) = self.surface.acquire(&self.ctx) else {
            for id in &output.textures_delta.free {
                self.egui_renderer.free_texture(id);
            }
            return Ok(FrameEnd::Continue);
        };
        let size = (frame.texture.width(), frame.texture.height());
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: output.pixels_per_point,
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("viewer frame"),
        });
        self.display.prepare(&self.ctx, self.viewer.image());
        let callback_buffers =
            self.egui_renderer
                .update_buffers(device, queue, &mut encoder, &paint_jobs, &screen);
        let view = frame.texture.create_view(&Default::default());
        self.draw(&mut encoder, &view, &paint_jobs, &screen);
        let capture = match capture_to {
            Some((path, automated)) => match Capture::new(&self.ctx, self.surface.format(), size) {
                Ok(capture) => {
                    self.draw(&mut encoder, &capture.view(), &paint_jobs, &screen);
                    capture.record_copy(&mut encoder);
                    Some((capture, path, automated))
                }
                Err(e) if automated => return Err(e),
                Err(e) => {
                    self.viewer.screenshot_done(Err(e));
                    None
                }
            },
            None => None,
        };
        queue.submit(callback_buffers.into_iter().chain([encoder.finish()]));
        queue.present(frame);
        for id in &output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        self.frames += 1;

        if let Some((capture, path, automated)) = capture {
            let saved = capture
                .read(&self.ctx)
                .and_then(|image| save_png(&image, &path))
                .map(|()| format!("saved {}", path.display()));
            match saved {
                Ok(message) => {
                    log::info!("{message} ({}x{})", size.0, size.1);
                    self.viewer.screenshot_done(Ok(message));
                }
                Err(e) if automated => return Err(e),
                Err(e) => self.viewer.screenshot_done(Err(e)),
            }
        }
        Ok(if last_frame {
            FrameEnd::Exit
        } else {
            FrameEnd::Continue
        })
    }

    /// Draws the image and the panel into `view`.
    fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        paint_jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(CLEAR),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime();
        self.display.draw(&mut pass);
        self.egui_renderer.render(&mut pass, paint_jobs, screen);
    }
}

fn unix_seconds() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
