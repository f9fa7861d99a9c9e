//! The editor's GPU side: the window's surface and swapchain, the composed window image and the tool
//! panel's painter. One frame records the views that changed into their persistent targets (the
//! mesh view's refinement accumulates on the GPU), composes the window (`render::compose`), copies
//! it into the acquired swapchain image, draws the panel straight into that image, submits and
//! presents — without waiting for the GPU, which runs up to `FRAMES_IN_FLIGHT` frames behind.
//! Nothing is read back unless a screenshot is asked for.

use std::collections::VecDeque;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::render::compose::{Parts, Placement, WINDOW_FORMAT};
use crate::render::{Progress, Recorded, Renderer, Settings};
use crate::vk::barrier;
use crate::vk::frame::FRAMES_IN_FLIGHT;
use crate::vk::surface::{self, Surface};
use crate::vk::swapchain::{Acquired, Swapchain};
use crate::vk::{Buffer, Context, Image};

/// The passes of a frame that work on the window's pixels, not the views' (their cost does not
/// change with a preview's scale).
pub const WINDOW_PASSES: [&str; 3] = ["compose", "window copy", "panel"];

/// What one frame draws.
pub struct Plan<'a> {
    pub material: &'a Material,
    /// The mesh view to render, and whether it restarts or refines; `None`: it shows what it has.
    pub mesh: Option<(Settings, Progress)>,
    /// The canvas to render; `None`: unchanged.
    pub canvas: Option<Settings>,
    pub placement: Placement,
    /// The tool panel: egui's texture changes, its triangles and its scale.
    pub ui: (&'a egui::TexturesDelta, &'a [egui::ClippedPrimitive], f32),
    /// Read the presented pixels back (`--screenshot`), waiting for the frame.
    pub capture: bool,
}

/// The acquired swapchain image a frame draws into.
struct Target {
    image: vk::Image,
    view: vk::ImageView,
    extent: vk::Extent2D,
}

/// The one colour layer of the window's images (mip 0, layer 0), for copies.
const COLOR_LAYERS: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};

/// What became of a frame.
pub enum Shown {
    /// Presented; the pixels when captured (`RGBA8`, the window's size), and what became of the mesh
    /// view ([`Recorded::Waiting`]: it shows its last image; `Done` also when it was not asked for).
    Presented { pixels: Option<Vec<u8>>, mesh: Recorded },
    /// The swapchain does not fit the window: nothing was drawn; ask for another frame.
    OutOfDate,
}

pub struct Gpu {
    /// The egui painter; dropped first (it owns device objects).
    ui: Option<egui_ash_renderer::Renderer>,
    /// The format the painter was made for (the swapchain's).
    ui_format: vk::Format,
    /// The composed views (`RGBA8`, the window's size), and the placement last composed into it
    /// (a frame rewrites only what changed).
    window_image: Option<Image>,
    composed: Option<Placement>,
    pub swapchain: Option<Swapchain>,
    surface: Option<Surface>,
    /// Host-visible copy of a captured frame.
    capture: Option<Buffer>,
    /// Textures egui freed, with the number of the last frame that may draw them.
    retired: VecDeque<(u64, Vec<egui::TextureId>)>,
    pub renderer: Renderer,
    pub window: Arc<Window>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let _ = self.renderer.finish_frames();
        drop(self.ui.take());
        let ctx = &self.renderer.ctx;
        if let Some(i) = self.window_image.take() {
            i.destroy(ctx);
        }
        if let Some(b) = self.capture.take() {
            b.destroy(ctx);
        }
        if let Some(s) = self.swapchain.take() {
            s.destroy(ctx);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
    }
}

fn painter(ctx: &Context, format: vk::Format) -> Result<egui_ash_renderer::Renderer> {
    egui_ash_renderer::Renderer::with_default_allocator(
        &ctx.instance.raw,
        ctx.device.physical,
        ctx.device.raw.clone(),
        egui_ash_renderer::DynamicRendering { color_attachment_format: format, depth_attachment_format: None },
        egui_ash_renderer::Options {
            srgb_framebuffer: false,
            in_flight_frames: FRAMES_IN_FLIGHT,
            ..Default::default()
        },
    )
    .map_err(|e| Error::NoDevice(format!("the tool panel's painter: {e}")))
}

impl Gpu {
    /// Opens the window's device objects: the renderer (on a device that can present to `window`),
    /// its surface, the swapchain and the panel's painter.
    pub fn new(window: Arc<Window>) -> Result<Gpu> {
        let display = window.display_handle().map_err(|e| Error::NoDevice(format!("no display handle: {e}")))?.as_raw();
        let handle = window.window_handle().map_err(|e| Error::NoDevice(format!("no window handle: {e}")))?.as_raw();
        let ctx = Context::from_env_with(&surface::required_extensions(display)?)?;
        let renderer = Renderer::new(ctx)?;
        let surface = Surface::new(&renderer.ctx, display, handle)?;
        let mut gpu = Gpu {
            ui: None,
            ui_format: vk::Format::UNDEFINED,
            window_image: None,
            composed: None,
            swapchain: None,
            surface: Some(surface),
            capture: None,
            retired: VecDeque::new(),
            renderer,
            window,
        };
        gpu.swapchain_extent()?;
        Ok(gpu)
    }

    /// The swapchain's size, made (or remade) for the window's size first; `None` while minimised.
    pub fn swapchain_extent(&mut self) -> Result<Option<(u32, u32)>> {
        if self.swapchain.is_none() {
            let size = self.window.inner_size();
            let surface = self.surface.as_ref().expect("lives until drop");
            self.swapchain = Swapchain::new(&self.renderer.ctx, surface, (size.width, size.height))?;
            if let Some(sc) = &self.swapchain {
                if sc.format != self.ui_format {
                    self.renderer.finish_frames()?;
                    drop(self.ui.take());
                    self.ui = Some(painter(&self.renderer.ctx, sc.format)?);
                    self.ui_format = sc.format;
                }
            }
        }
        Ok(self.swapchain.as_ref().map(|s| (s.extent.width, s.extent.height)))
    }

    /// The window was resized to `size`: a swapchain of another size is dropped (not every platform
    /// reports it out of date), so the next frame makes one of the window's size.
    pub fn resized(&mut self, size: (u32, u32)) -> Result<()> {
        if self.swapchain.as_ref().is_some_and(|s| (s.extent.width, s.extent.height) != size) {
            self.drop_swapchain()?;
        }
        Ok(())
    }

    /// Drops the swapchain (out of date: the next frame makes one for the window's size).
    fn drop_swapchain(&mut self) -> Result<()> {
        self.renderer.finish_frames()?;
        if let Some(old) = self.swapchain.take() {
            old.destroy(&self.renderer.ctx);
        }
        Ok(())
    }

    /// Draws one frame as `plan` says (see the module): what became of it. The GPU times of
    /// finished frames are the renderer's (`take_finished`).
    pub fn frame(&mut self, plan: &Plan<'_>) -> Result<Shown> {
        let Some((w, h)) = self.swapchain_extent()? else { return Ok(Shown::OutOfDate) };
        if self.window_image.as_ref().is_none_or(|i| (i.width, i.height) != (w, h)) {
            self.renderer.finish_frames()?;
            if let Some(old) = self.window_image.take() {
                old.destroy(&self.renderer.ctx);
            }
            let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
            self.window_image =
                Some(Image::new(&self.renderer.ctx, (w, h), WINDOW_FORMAT, 1, usage, "window.composed")?);
            self.composed = None;
        }
        self.renderer.begin_frame(plan.material)?;
        let number = self.renderer.frame_number();
        // Textures freed before a frame FRAMES_IN_FLIGHT back are not drawn by any frame in flight.
        while self.retired.front().is_some_and(|r| r.0 + (FRAMES_IN_FLIGHT as u64) < number) {
            let (_, ids) = self.retired.pop_front().expect("checked");
            if let Some(ui) = self.ui.as_mut() {
                ui.free_textures(&ids).map_err(|e| Error::NoDevice(format!("the tool panel's textures: {e}")))?;
            }
        }
        let (_, acquired) = self.renderer.frame_commands();
        let sc = self.swapchain.as_ref().expect("made above");
        let index = match sc.acquire(acquired) {
            Ok(Acquired::Image(i)) => i,
            Ok(Acquired::OutOfDate) => {
                self.renderer.abandon_frame()?;
                self.drop_swapchain()?;
                return Ok(Shown::OutOfDate);
            }
            Err(e) => {
                let _ = self.renderer.abandon_frame();
                return Err(e);
            }
        };
        let mesh = match self.record(plan, index) {
            Ok(m) => m,
            Err(e) => {
                // Nothing of this frame reaches the window image: compose it whole next time.
                self.composed = None;
                // The acquire signalled `acquired` and handed out image `index`: consume the one, and
                // release the other with its swapchain (it cannot be presented unrendered).
                let _ = self.renderer.abandon_acquired_frame(acquired);
                let _ = self.drop_swapchain();
                return Err(e);
            }
        };
        let sc = self.swapchain.as_ref().expect("made above");
        let rendered = sc.rendered[index as usize];
        self.renderer.submit_frame(Some((acquired, vk::PipelineStageFlags::ALL_COMMANDS)), Some(rendered))?;
        let presented = sc.present(&self.renderer.ctx, index)?;
        if !plan.ui.0.free.is_empty() {
            self.retired.push_back((number, plan.ui.0.free.clone()));
        }
        let pixels = if plan.capture {
            self.renderer.finish_frames()?;
            let b = self.capture.as_ref().expect("made by record");
            let bgr = matches!(sc.format, vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB);
            let mut px = b.mapped()[..(w * h * 4) as usize].to_vec();
            if bgr {
                for p in px.chunks_exact_mut(4) {
                    p.swap(0, 2);
                }
            }
            Some(px)
        } else {
            None
        };
        self.renderer.ctx.check_validation()?;
        if !presented {
            self.drop_swapchain()?;
        }
        Ok(Shown::Presented { pixels, mesh })
    }

    /// Records the frame's GPU work after the swapchain image `index` was acquired: the views that
    /// changed, the window image composed from them, the panel's textures, the copy into the
    /// swapchain image, the panel on top, and the image's way to presentation (through the capture
    /// buffer when asked). Returns what became of the mesh view (`Done` when it was not asked for).
    fn record(&mut self, plan: &Plan<'_>, index: u32) -> Result<Recorded> {
        let mesh = self.record_views(plan)?;
        self.compose(plan, mesh)?;
        let ctx = &self.renderer.ctx;
        let ui = self.ui.as_mut().expect("made with the swapchain");
        ui.set_textures(ctx.device.queue, ctx.commands.pool, &plan.ui.0.set)
            .map_err(|e| Error::NoDevice(format!("the tool panel's textures: {e}")))?;
        self.make_capture(plan)?;
        let sc = self.swapchain.as_ref().expect("made by frame");
        let target = Target { image: sc.images[index as usize], view: sc.views[index as usize], extent: sc.extent };
        // The window's copy and the tool panel are timed as passes too: on a CPU device they are
        // part of what the frame costs.
        self.record_window_copy(&target)?;
        self.record_panel(plan, &target)?;
        self.record_to_present(plan, &target);
        Ok(mesh)
    }

    /// Records the mesh view and the canvas as the plan asks. Returns what became of the mesh view.
    fn record_views(&mut self, plan: &Plan<'_>) -> Result<Recorded> {
        let mut mesh = Recorded::Done;
        if let Some((settings, progress)) = &plan.mesh {
            mesh = self.renderer.record(plan.material, settings, *progress)?;
        }
        if let Some(settings) = &plan.canvas {
            // A canvas has no lobe pipelines to wait for.
            let _ = self.renderer.record(plan.material, settings, Progress::Fresh)?;
        }
        Ok(mesh)
    }

    /// Composes the window image, rewriting only what changed since the last composition: a view
    /// that was rendered (not a mesh view that waits) or whose brightness or marker changed, and
    /// everything after a new placement of the views.
    fn compose(&mut self, plan: &Plan<'_>, mesh: Recorded) -> Result<()> {
        let window_image = self.window_image.as_ref().expect("made by frame");
        let (now, was) = (&plan.placement, self.composed.as_ref());
        let parts = Parts {
            mesh: (plan.mesh.is_some() && mesh != Recorded::Waiting)
                || was.is_none_or(|p| (p.mesh_scale, p.backdrop_scale) != (now.mesh_scale, now.backdrop_scale)),
            canvas: plan.canvas.is_some()
                || was.is_none_or(|p| (p.canvas_scale, p.marker) != (now.canvas_scale, now.marker)),
            all: was.is_none_or(|p| (p.mesh, p.canvas) != (now.mesh, now.canvas)),
        };
        self.renderer.record_compose(window_image, now, parts)?;
        self.composed = Some(*now);
        Ok(())
    }

    /// Makes the host-visible buffer a captured frame is copied into, when the plan asks for a
    /// capture and there is none of the swapchain's size; a swapchain whose images cannot be read
    /// back is an error.
    fn make_capture(&mut self, plan: &Plan<'_>) -> Result<()> {
        let ctx = &self.renderer.ctx;
        let sc = self.swapchain.as_ref().expect("made by frame");
        let (w, h) = (sc.extent.width, sc.extent.height);
        if plan.capture && self.capture.as_ref().is_none_or(|b| b.size != (w * h * 4) as u64) {
            if !sc.readable {
                return Err(Error::NoDevice("this window's images cannot be read back for a screenshot".into()));
            }
            if let Some(b) = self.capture.take() {
                b.destroy(ctx);
            }
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            self.capture =
                Some(Buffer::new(ctx, (w * h * 4) as u64, usage, MemoryLocation::GpuToCpu, "window.capture")?);
        }
        Ok(())
    }

    /// The timed "window copy" pass: blits the composed window image into the acquired swapchain
    /// image, which it leaves as a colour attachment for the panel.
    fn record_window_copy(&mut self, target: &Target) -> Result<()> {
        let window_raw = self.window_image.as_ref().expect("made by frame").raw;
        let (w, h) = (target.extent.width, target.extent.height);
        let corner = [vk::Offset3D::default(), vk::Offset3D { x: w as i32, y: h as i32, z: 1 }];
        let blit = vk::ImageBlit::default()
            .src_subresource(COLOR_LAYERS)
            .src_offsets(corner)
            .dst_subresource(COLOR_LAYERS)
            .dst_offsets(corner);
        let (image, range) = (target.image, barrier::color());
        self.renderer.time("window copy", |ctx, cmd| {
            barrier::image(
                ctx,
                cmd,
                image,
                range,
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
                (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::NONE),
                barrier::TRANSFER_WRITE,
            );
            // SAFETY: `cmd` is recording; the composed image (GENERAL, its writes ordered before
            // transfer reads by the compose pass) and the acquired swapchain image (TRANSFER_DST) have
            // this size.
            unsafe {
                ctx.raw().cmd_blit_image(
                    cmd,
                    window_raw,
                    vk::ImageLayout::GENERAL,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[blit],
                    vk::Filter::NEAREST,
                )
            };
            barrier::image(
                ctx,
                cmd,
                image,
                range,
                (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
                barrier::TRANSFER_WRITE,
                barrier::COLOR_ATTACHMENT,
            );
            Ok(())
        })
    }

    /// The timed "panel" pass: egui's triangles drawn straight into the swapchain image, over the
    /// copied window.
    fn record_panel(&mut self, plan: &Plan<'_>, target: &Target) -> Result<()> {
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(target.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let extent = target.extent;
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&attachment);
        let ui = self.ui.as_mut().expect("made with the swapchain");
        self.renderer.time("panel", |ctx, cmd| {
            // SAFETY: the swapchain image is a colour attachment in the layout named.
            unsafe { ctx.raw().cmd_begin_rendering(cmd, &info) };
            let drawn = ui
                .cmd_draw(cmd, extent, plan.ui.2, plan.ui.1)
                .map_err(|e| Error::NoDevice(format!("the tool panel: {e}")));
            // SAFETY: rendering began above.
            unsafe { ctx.raw().cmd_end_rendering(cmd) };
            drawn
        })
    }

    /// Moves the swapchain image from the panel's drawing to presentation; when the plan captures
    /// the frame, through a copy into the capture buffer made visible to the host.
    fn record_to_present(&self, plan: &Plan<'_>, target: &Target) {
        let ctx = &self.renderer.ctx;
        let (cmd, _) = self.renderer.frame_commands();
        let (image, range) = (target.image, barrier::color());
        let present = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
        if let (true, Some(buffer)) = (plan.capture, self.capture.as_ref()) {
            barrier::image(
                ctx,
                cmd,
                image,
                range,
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
                barrier::COLOR_ATTACHMENT,
                barrier::TRANSFER_READ,
            );
            let (width, height) = (target.extent.width, target.extent.height);
            let region = vk::BufferImageCopy::default().image_subresource(COLOR_LAYERS).image_extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            });
            // SAFETY: `cmd` is recording; the buffer holds the whole image, which is in TRANSFER_SRC.
            unsafe {
                ctx.raw().cmd_copy_image_to_buffer(
                    cmd,
                    image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer.raw,
                    &[region],
                )
            };
            barrier::to_host(ctx, cmd, buffer.raw);
            barrier::image(
                ctx,
                cmd,
                image,
                range,
                (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::PRESENT_SRC_KHR),
                barrier::TRANSFER_READ,
                present,
            );
        } else {
            barrier::image(
                ctx,
                cmd,
                image,
                range,
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::PRESENT_SRC_KHR),
                barrier::COLOR_ATTACHMENT,
                present,
            );
        }
    }
}
