//! The interactive editor (paper §3.1, Fig. 1): one window with the mesh under the environment
//! (left; orbit with the left button, zoom with the wheel, `F` frames it), the spherical canvas (right;
//! paint with the left button, drag the light with the right, `L` resets it) and the BRDF graph
//! (lower right; `G` toggles log scale). Brushes: `C` create, `M` modify, `S` streak, `I` intensify,
//! `D` de-intensify; `P` split lobes on/off; Ctrl+Z / Ctrl+Shift+Z undo/redo; Ctrl+S saves. A
//! dropped `.exr`/`.hdr`, `.obj` or `.brdf.json` file is loaded.
//!
//! Window events become [`state::Input`]s handled by [`state::State`]; `--replay` feeds the same
//! inputs from a strokes file. Frames are rendered by `render::Renderer`, composed on the CPU and
//! copied into the swapchain. After every change the material is written atomically to the recovery
//! file, which the next start loads when no `--material` is given.

pub mod graph;
pub mod panel;
pub mod report;
pub mod state;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, ModifiersState};
use winit::window::{Window, WindowId};

use crate::brdf::Material;
use crate::brush::{BrushKind, Settings, Strokes};
use crate::error::{Error, Result};
use crate::imageio::srgb8;
use crate::render::{Estimator, Renderer, View};
use crate::scene::{Environment, Mesh};
use crate::vk::surface::{self, Surface};
use crate::vk::swapchain::{Acquired, Swapchain};
use crate::vk::{Buffer, Context};

use state::{Input, Layout, State};

/// What `brdf-shop edit` was asked to do.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub env: Option<PathBuf>,
    pub mesh: Option<String>,
    pub material: Option<PathBuf>,
    pub replay: Option<PathBuf>,
    /// Scripted drops: after the replay, these files are dropped onto the window in order.
    pub drop: Vec<PathBuf>,
    /// Write per-frame statistics (wall ms, GPU ms per pass, interaction or refinement) here on exit.
    pub frame_stats: Option<PathBuf>,
    pub screenshot: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub quit: bool,
    /// With `quit`: refine the mesh view to REFINE_MAX samples before leaving.
    pub converge: bool,
    pub size: (u32, u32),
}

/// The longest side of the editor's window (pixels), checked before a window is made: an 8K
/// display is 7680 wide, X11 cannot make a window of 65536 (winit panics on it), and the frame is
/// composed on the CPU at 4 bytes a pixel plus the GPU's targets, so 8192² stays near 1.5 GB.
pub const MAX_WINDOW_SIDE: u32 = 8192;

/// Each side of a requested window size, limited to the display's.
pub fn clamp_to_display(size: (u32, u32), display: (u32, u32)) -> (u32, u32) {
    (size.0.min(display.0).max(1), size.1.min(display.1).max(1))
}

/// Refuses (naming `--size`) a window size of a zero side or a side over [`MAX_WINDOW_SIDE`].
pub fn check_size(size: (u32, u32)) -> Result<()> {
    let (w, h) = size;
    if w == 0 || h == 0 || w > MAX_WINDOW_SIDE || h > MAX_WINDOW_SIDE {
        return Err(Error::input(
            "--size",
            format!("{w}x{h}: each side of the window must be within 1 and {MAX_WINDOW_SIDE} pixels"),
        ));
    }
    Ok(())
}

/// Where unsaved work goes: `BRDF_SHOP_RECOVERY`, else `$XDG_STATE_HOME/brdf-shop/recovery.brdf.json`,
/// else `~/.local/state/brdf-shop/recovery.brdf.json`.
pub fn recovery_path() -> PathBuf {
    if let Ok(p) = std::env::var("BRDF_SHOP_RECOVERY") {
        return PathBuf::from(p);
    }
    let base = std::env::var("XDG_STATE_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(std::env::var("HOME").unwrap_or_else(|_| ".".into())).join(".local/state"));
    base.join("brdf-shop/recovery.brdf.json")
}

/// Writes the material atomically to the recovery file, creating its folder.
pub fn save_recovery(m: &Material, path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    m.save(path)
}

/// [`save_recovery`] that never ends the session: a recovery file that cannot be written is a
/// warning on stderr (once per session, `warned`) and, returned, a status line for the window; the
/// work goes on and `--out` is still written at the end.
fn keep_recovery(m: &Material, warned: &mut bool) -> Option<String> {
    let path = recovery_path();
    let e = save_recovery(m, &path).err()?;
    let msg = format!("unsaved work is NOT protected: the recovery file cannot be written ({e})");
    if !*warned {
        eprintln!("brdf-shop: warning: {}", crate::fsio::escape_controls(&msg));
        *warned = true;
    }
    Some(format!("warning: {msg}"))
}

struct Gpu {
    /// The egui painter; dropped first (it owns device objects).
    ui: Option<egui_ash_renderer::Renderer>,
    /// The frame as composed on the CPU with the panel drawn over it (`RGBA8`), blitted to the
    /// swapchain and read back for screenshots.
    target: Option<crate::vk::Image>,
    readback: Option<Buffer>,
    swapchain: Option<Swapchain>,
    surface: Option<Surface>,
    staging: Option<Buffer>,
    renderer: Renderer,
    window: Arc<Window>,
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: nothing is in flight (every submission is waited on); the painter goes first.
        let _ = unsafe { self.renderer.ctx.raw().device_wait_idle() };
        drop(self.ui.take());
        if let Some(i) = self.target.take() {
            i.destroy(&self.renderer.ctx);
        }
        if let Some(b) = self.readback.take() {
            b.destroy(&self.renderer.ctx);
        }
        if let Some(s) = self.swapchain.take() {
            s.destroy(&self.renderer.ctx);
        }
        if let Some(b) = self.staging.take() {
            b.destroy(&self.renderer.ctx);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
    }
}

/// What the editor needs of the environment beyond its texels, computed once per map (not per frame).
struct EnvSummary {
    /// `Environment::brightest_direction`, where the canvas light starts.
    brightest: DVec3,
    /// [`auto_exposure`]'s scale of the mesh view.
    exposure: f64,
}

impl EnvSummary {
    fn of(env: &Environment) -> EnvSummary {
        EnvSummary { brightest: env.brightest_direction(), exposure: auto_exposure(env) }
    }
}

struct App {
    opts: Options,
    env: Environment,
    env_summary: EnvSummary,
    mesh: Mesh,
    start: Material,
    replay: Option<Strokes>,
    pending: VecDeque<Input>,
    gpu: Option<Gpu>,
    state: Option<State>,
    modifiers: ModifiersState,
    log_graph: bool,
    exposure: f64,
    last_ms: f64,
    frame: Option<Vec<u8>>,
    error: Option<Error>,
    done: bool,
    /// Progressive refinement: what the accumulated `mis` image shows, its running sum and samples.
    refine_key: String,
    refine_sum: Vec<[f32; 4]>,
    refine_samples: u32,
    /// Wall-clock milliseconds of each frame drawn (render, compose, present).
    frame_ms: Vec<f64>,
    /// Every frame's statistics (`--frame-stats`).
    frame_stats: Vec<FrameStat>,
    /// What the last frame rendered of the mesh view.
    last_kind: FrameKind,
    /// The recovery file's material, offered until restored (R) or replaced by an edit.
    recovered: Option<Material>,
    /// Whether the warning that the recovery file cannot be written was printed.
    recovery_warned: bool,
    egui_ctx: egui::Context,
    egui_state: Option<egui_winit::State>,
    spp: u32,
    /// The energy report of the material shown, measured off the UI thread (made with the window).
    report: Option<report::ReportWorker>,
    /// Wakes the event loop from the report's thread (a window's `request_redraw` from another
    /// thread panics in winit's X11 backend once the loop has closed; a proxy returns an error).
    proxy: EventLoopProxy<()>,
    timings: Vec<(String, f64)>,
    /// A panel widget was being dragged last frame: its edits amend one history step.
    panel_dragging: bool,
}

/// Samples per pixel added by each refining frame, and where refinement stops.
pub const REFINE_STEP: u32 = 16;
pub const REFINE_MAX: u32 = 1024;

/// How many recent frames the panel's median frame time is taken over.
pub const FRAME_RATE_WINDOW: usize = 30;

/// The canvas light the editor starts with: the environment's brightest direction seen from the
/// camera (canvas x = right, y = up, z = towards the viewer).
fn light_from(env: &EnvSummary, state_camera: &crate::scene::Camera) -> DVec3 {
    let d = env.brightest;
    let (right, up, forward) = state_camera.basis();
    DVec3::new(d.dot(right), d.dot(up), -d.dot(forward)).normalize()
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        el.exit();
    }

    fn init(&mut self, el: &ActiveEventLoop) -> Result<()> {
        // A window larger than the display is clamped to it, with a message (checked against
        // MAX_WINDOW_SIDE before the loop started).
        if let Some(m) = el.primary_monitor().or_else(|| el.available_monitors().next()) {
            let (mw, mh) = (m.size().width, m.size().height);
            let (w, h) = self.opts.size;
            if mw > 0 && mh > 0 && (w > mw || h > mh) {
                let fit = clamp_to_display((w, h), (mw, mh));
                eprintln!(
                    "brdf-shop: --size {w}x{h} is larger than the display ({mw}x{mh}): the window is {}x{}",
                    fit.0, fit.1
                );
                self.opts.size = fit;
            }
        }
        let attrs = Window::default_attributes()
            .with_title("brdf-shop")
            .with_inner_size(winit::dpi::PhysicalSize::new(self.opts.size.0, self.opts.size.1));
        let window =
            Arc::new(el.create_window(attrs).map_err(|e| Error::NoDevice(format!("cannot open a window: {e}")))?);
        let display = window.display_handle().map_err(|e| Error::NoDevice(format!("no display handle: {e}")))?.as_raw();
        let handle = window.window_handle().map_err(|e| Error::NoDevice(format!("no window handle: {e}")))?.as_raw();
        let ctx = Context::from_env_with(&surface::required_extensions(display)?)?;
        let mut renderer = Renderer::new(ctx)?;
        renderer.set_environment(&self.env)?;
        renderer.set_mesh(&self.mesh)?;
        let surface = Surface::new(&renderer.ctx, display, handle)?;
        let size = window.inner_size();
        let ui = egui_ash_renderer::Renderer::with_default_allocator(
            &renderer.ctx.instance.raw,
            renderer.ctx.device.physical,
            renderer.ctx.device.raw.clone(),
            egui_ash_renderer::DynamicRendering {
                color_attachment_format: vk::Format::R8G8B8A8_UNORM,
                depth_attachment_format: None,
            },
            egui_ash_renderer::Options { srgb_framebuffer: false, ..Default::default() },
        )
        .map_err(|e| Error::NoDevice(format!("the tool panel's painter: {e}")))?;
        self.egui_state = Some(egui_winit::State::new(
            self.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &*window,
            Some(window.scale_factor() as f32),
            None,
            Some(renderer.ctx.device.limits.max_image_dimension2_d as usize),
        ));
        let mut gpu = Gpu {
            ui: Some(ui),
            target: None,
            readback: None,
            swapchain: None,
            surface: Some(surface),
            staging: None,
            renderer,
            window,
        };
        gpu.swapchain =
            Swapchain::new(&gpu.renderer.ctx, gpu.surface.as_ref().expect("made above"), (size.width, size.height))?;
        let (w, h) = gpu.swapchain.as_ref().map_or((size.width, size.height), |s| (s.extent.width, s.extent.height));
        let settings = match &self.replay {
            Some(s) => s.settings("replay")?,
            None => Settings::new(crate::brush::Canvas { light: DVec3::Z, intensity: 1.0 }),
        };
        let mut state = State::new(self.start.clone(), settings, Layout::new(w.max(1), h.max(1)));
        if self.replay.is_none() {
            // The light as the orbit camera sees the environment's brightest direction.
            state.default_light = light_from(&self.env_summary, &state.camera());
            state.settings.canvas.light = state.default_light;
        }
        if let Some(strokes) = &self.replay {
            for st in &strokes.strokes {
                self.pending.extend(state::stroke_inputs(&state.layout, st));
            }
        }
        self.pending.extend(self.opts.drop.iter().cloned().map(Input::Dropped));
        self.state = Some(state);
        if self.recovered.is_some() {
            if let Some(s) = self.state.as_mut() {
                s.status = format!(
                    "unsaved work from the last session found ({}): press R to restore it",
                    recovery_path().display()
                );
            }
        }
        self.gpu = Some(gpu);
        Ok(())
    }

    fn handle(&mut self, input: Input) -> Result<()> {
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        let fx = state.handle(input);
        if fx.material_changed {
            if let Some(status) = keep_recovery(state.material(), &mut self.recovery_warned) {
                state.status = status;
            }
        }
        if fx.save {
            let path = self
                .opts
                .out
                .clone()
                .or_else(|| self.opts.material.clone())
                .unwrap_or_else(|| PathBuf::from("material.brdf.json"));
            // A path that cannot be written is the user's to fix: a status line, the session goes on.
            state.status = match state.material().save(&path) {
                Ok(()) => format!("saved {}", path.display()),
                Err(e) if e.is_user_error() => format!("not saved: {e}"),
                Err(e) => return Err(e),
            };
        }
        if let Some(p) = fx.load {
            // So is a file that does not load (broken, unknown kind); a device error is not.
            if let Err(e) = self.load_dropped(&p) {
                if !e.is_user_error() {
                    return Err(e);
                }
                let line = format!("not loaded: {e}");
                eprintln!("brdf-shop: {line}");
                if let Some(state) = self.state.as_mut() {
                    state.status = line;
                }
            }
        }
        if fx.redraw {
            if let Some(g) = &self.gpu {
                g.window.request_redraw();
            }
        }
        Ok(())
    }

    fn load_dropped(&mut self, p: &Path) -> Result<()> {
        let name = p.to_string_lossy().to_lowercase();
        let (Some(gpu), Some(state)) = (self.gpu.as_mut(), self.state.as_mut()) else { return Ok(()) };
        if name.ends_with(".exr") || name.ends_with(".hdr") {
            let env = Environment::load(p)?;
            gpu.renderer.set_environment(&env)?;
            let summary = EnvSummary::of(&env);
            state.default_light = light_from(&summary, &state.camera());
            state.settings.canvas.light = state.default_light;
            self.env = env;
            self.env_summary = summary;
        } else if Mesh::is_mesh_file(p) {
            // The same loader as `--mesh`: OBJ, glTF (.gltf, .glb) or PLY.
            self.mesh = Mesh::load(p)?;
            gpu.renderer.set_mesh(&self.mesh)?;
        } else if name.ends_with(".json") {
            let m = Material::load(p)?;
            state.history.push(m);
        } else {
            state.status = format!("{}: not an environment, mesh or material", p.display());
        }
        gpu.window.request_redraw();
        Ok(())
    }

    /// Renders both views, composes the window's pixels and presents them.
    fn draw(&mut self) -> Result<()> {
        let start = std::time::Instant::now();
        self.last_kind = FrameKind::Unchanged;
        let r = self.draw_frame();
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        self.frame_ms.push(wall_ms);
        if r.is_ok() && self.last_kind != FrameKind::Unchanged {
            let gpu_ms = self.timings.iter().map(|t| t.1).sum();
            self.frame_stats.push(FrameStat { wall_ms, gpu_ms, kind: self.last_kind, passes: self.timings.clone() });
        }
        r
    }

    fn draw_frame(&mut self) -> Result<()> {
        let (Some(gpu), Some(state)) = (self.gpu.as_mut(), self.state.as_mut()) else { return Ok(()) };
        let ctx_size = gpu.window.inner_size();
        if gpu.swapchain.is_none() {
            gpu.swapchain = Swapchain::new(
                &gpu.renderer.ctx,
                gpu.surface.as_ref().expect("live"),
                (ctx_size.width, ctx_size.height),
            )?;
        }
        let Some(sc) = gpu.swapchain.as_ref() else { return Ok(()) }; // minimised
        let (w, h) = (sc.extent.width, sc.extent.height);
        if (state.layout.width, state.layout.height) != (w, h) {
            state.handle(Input::Resized(w, h));
        }
        let l = state.layout;
        // The canvas light follows the environment's brightest direction seen from the orbiting
        // camera, unless the user moved it (a replay keeps its strokes file's light).
        if !state.light_moved && self.replay.is_none() {
            state.default_light = light_from(&self.env_summary, &state.camera());
            state.settings.canvas.light = state.default_light;
        }
        let m = state.material().clone();
        let mesh_settings = crate::render::Settings {
            width: l.mesh_w,
            height: l.height,
            spp: self.spp,
            estimator: Estimator::Key,
            view: View::Mesh,
            camera: state.camera(),
            light: state.settings.canvas.light,
            intensity: state.settings.canvas.intensity,
        };
        // Any change shows the fast `key` image and restarts the accumulation; while nothing changes,
        // each frame adds REFINE_STEP samples of `mis` (the true image, not the prefiltered blur).
        let key = format!("{m:?}{:?}{:?}{:?}", mesh_settings.camera, l, self.env.origin);
        let refining = !self.opts.quit || self.opts.converge;
        let mesh_frame = if key != self.refine_key || !refining {
            self.last_kind = FrameKind::Interaction;
            self.refine_key = key;
            self.refine_samples = 0;
            self.refine_sum.clear();
            gpu.renderer.render(&m, &mesh_settings)?
        } else if self.refine_samples < REFINE_MAX {
            self.last_kind = FrameKind::Refinement;
            let mis = crate::render::Settings { estimator: Estimator::Mis, spp: REFINE_STEP, ..mesh_settings.clone() };
            gpu.renderer.mis_offset = self.refine_samples;
            let f = gpu.renderer.render(&m, &mis);
            gpu.renderer.mis_offset = 0;
            let mut f = f?;
            if self.refine_sum.len() != f.image.pixels.len() {
                self.refine_sum = vec![[0.0; 4]; f.image.pixels.len()];
            }
            self.refine_samples += REFINE_STEP;
            let n = (self.refine_samples / REFINE_STEP) as f32;
            for (acc, p) in self.refine_sum.iter_mut().zip(&mut f.image.pixels) {
                for c in 0..4 {
                    acc[c] += p[c];
                    p[c] = acc[c] / n;
                }
            }
            f
        } else {
            let n = (self.refine_samples / REFINE_STEP).max(1) as f32;
            let pixels = self.refine_sum.iter().map(|a| a.map(|v| v / n)).collect();
            crate::render::Frame {
                image: crate::reference::Image { width: l.mesh_w, height: l.height, pixels },
                timings: Vec::new(),
            }
        };
        let canvas_settings =
            crate::render::Settings { width: l.canvas, height: l.canvas, view: View::Canvas, ..mesh_settings.clone() };
        let canvas_frame = gpu.renderer.render(&m, &canvas_settings)?;
        self.last_ms = mesh_frame.timings.iter().chain(&canvas_frame.timings).map(|t| t.ms).sum();
        let (w, h) = (w as usize, h as usize);
        let mut rgba = vec![0u8; w * h * 4];
        for px in rgba.chunks_exact_mut(4) {
            px.copy_from_slice(&[32, 32, 36, 255]);
        }
        let blit = |rgba: &mut [u8], im: &crate::reference::Image, x0: usize, exposure: f64| {
            for y in 0..(im.height as usize).min(h) {
                for x in 0..(im.width as usize).min(w.saturating_sub(x0)) {
                    let p = im.pixels[y * im.width as usize + x];
                    let k = 4 * (y * w + x0 + x);
                    rgba[k..k + 3].copy_from_slice(&[
                        srgb8(p[0] as f64, exposure),
                        srgb8(p[1] as f64, exposure),
                        srgb8(p[2] as f64, exposure),
                    ]);
                }
            }
        };
        blit(&mut rgba, &mesh_frame.image, l.mesh_x as usize, self.exposure * self.env_summary.exposure);
        blit(&mut rgba, &canvas_frame.image, l.canvas_x as usize, self.exposure);
        // The snap marker: the mirror point, where a new lobe needs no rotation (paper §3.3.1).
        if let Some((cu, cv)) = state.settings.canvas.mirror_point() {
            let (mx, my) = l.canvas_point(cu, cv);
            for d in -6i64..=6 {
                for (x, y) in [(mx as i64 + d, my as i64), (mx as i64, my as i64 + d)] {
                    if x >= l.canvas_x as i64 && x < w as i64 && y >= 0 && y < (l.canvas as i64).min(h as i64) {
                        let k = 4 * (y as usize * w + x as usize);
                        rgba[k..k + 3].copy_from_slice(&[255, 210, 60]);
                    }
                }
            }
        }
        let gx = l.canvas_x as usize;
        let gy = (l.graph_y as usize).min(h);
        graph::draw(&mut rgba, w, (gx, gy, w - gx, h - gy), &m, state.settings.canvas.light, self.log_graph);
        let sums = m.energy_sums();
        let quality =
            if self.refine_samples == 0 { "key 8 spp".to_string() } else { format!("mis {} spp", self.refine_samples) };
        gpu.window.set_title(&format!(
            "brdf-shop — {} — {} lobe(s), Σρ = ({:.2}, {:.2}, {:.2}) — {quality}, {:.1} GPU ms — {}",
            state.brush.name(),
            m.lobes.len(),
            sums[0],
            sums[1],
            sums[2],
            self.last_ms,
            state.status
        ));
        self.timings = mesh_frame.timings.iter().chain(&canvas_frame.timings).map(|t| (t.name.clone(), t.ms)).collect();
        // The tool panel: run egui on this frame's input, apply what the user did after drawing.
        let proxy = self.proxy.clone();
        let worker = self.report.get_or_insert_with(|| {
            report::ReportWorker::new(move || {
                // After the loop has closed nobody needs the report: the error is the answer.
                let _ = proxy.send_event(());
            })
        });
        worker.request(&m);
        let report = worker.latest(&m);
        let quality = if self.refine_samples == 0 {
            format!("mesh view: key {} spp", self.spp)
        } else {
            format!("mesh view: mis {} spp", self.refine_samples)
        };
        let (mut spp, mut exposure, mut log_graph) = (self.spp, self.exposure, self.log_graph);
        let egui_state = self.egui_state.as_mut().expect("made in init");
        let raw_input = egui_state.take_egui_input(&gpu.window);
        let info = panel::Info {
            brush: state.brush,
            split: state.settings.split_lobes,
            report: report.map(|r| r.0),
            report_updating: report.is_none_or(|r| !r.1),
            timings: &self.timings,
            quality: &quality,
            frame_ms: (self.frame_ms.len() >= 2).then(|| {
                let recent = &self.frame_ms[self.frame_ms.len().saturating_sub(FRAME_RATE_WINDOW)..];
                (crate::measure::stats(recent).0, recent.len())
            }),
            status: &state.status,
        };
        let mut actions = panel::Actions::default();
        let output = self.egui_ctx.run(raw_input, |ctx| {
            actions = panel::show(ctx, &m, &info, &mut spp, &mut exposure, &mut log_graph);
        });
        egui_state.handle_platform_output(&gpu.window, output.platform_output);
        let primitives = self.egui_ctx.tessellate(output.shapes, output.pixels_per_point);
        (self.spp, self.exposure, self.log_graph) = (spp.max(1), exposure, log_graph);
        let ctx = &gpu.renderer.ctx;
        let ui = gpu.ui.as_mut().expect("made in init");
        ui.set_textures(ctx.device.queue, ctx.commands.pool, &output.textures_delta.set)
            .map_err(|e| Error::NoDevice(format!("the tool panel's textures: {e}")))?;
        // The frame's pixels, the panel over them, then into the swapchain and the readback buffer.
        let size = (w as u32, h as u32);
        if gpu.target.as_ref().is_none_or(|t| (t.width, t.height) != size) {
            if let Some(t) = gpu.target.take() {
                t.destroy(ctx);
            }
            if let Some(b) = gpu.readback.take() {
                b.destroy(ctx);
            }
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST;
            gpu.target = Some(crate::vk::Image::new(ctx, size, vk::Format::R8G8B8A8_UNORM, 1, usage, "window.frame")?);
            gpu.readback = Some(Buffer::new(
                ctx,
                (w * h * 4) as u64,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                "window.readback",
            )?);
        }
        if gpu.staging.as_ref().is_none_or(|b| b.size != rgba.len() as u64) {
            if let Some(b) = gpu.staging.take() {
                b.destroy(ctx);
            }
            gpu.staging = Some(Buffer::new(
                ctx,
                rgba.len() as u64,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
                "window.pixels",
            )?);
        }
        let staging = gpu.staging.as_mut().expect("made above");
        staging.write(&rgba);
        let (target, readback, staging) =
            (gpu.target.as_ref().expect("made above"), gpu.readback.as_ref().expect("made above"), &*staging);
        let extent = vk::Extent2D { width: size.0, height: size.1 };
        let scale = output.pixels_per_point;
        let record = |cmd: vk::CommandBuffer, swap_image: vk::Image| -> Result<()> {
            record_frame(ctx, cmd, (target, staging, readback), ui, (extent, scale, &primitives), swap_image)
        };
        let fresh = match sc.acquire(ctx)? {
            Acquired::Image(i) => sc.present(ctx, i, record)?,
            Acquired::OutOfDate => false,
        };
        ui.free_textures(&output.textures_delta.free)
            .map_err(|e| Error::NoDevice(format!("the tool panel's textures: {e}")))?;
        ctx.check_validation()?;
        if !fresh {
            if let Some(old) = gpu.swapchain.take() {
                old.destroy(ctx);
            }
            gpu.window.request_redraw();
        } else if let Some(b) = &gpu.readback {
            let n = rgba.len();
            rgba.copy_from_slice(&b.mapped()[..n]);
        }
        self.apply_panel(actions)?;
        self.frame = Some(rgba);
        Ok(())
    }

    /// Turns the panel's actions into state changes (material edits become history steps).
    fn apply_panel(&mut self, a: panel::Actions) -> Result<()> {
        if let Some(b) = a.brush {
            self.handle(Input::Brush(b))?;
        }
        for (yes, input) in [
            (a.toggle_split, Input::ToggleSplit),
            (a.undo, Input::Undo),
            (a.redo, Input::Redo),
            (a.save, Input::Save),
            (a.reset_light, Input::ResetLight),
        ] {
            if yes {
                self.handle(input)?;
            }
        }
        if let (Some((m, dragging)), Some(state)) = (a.material, self.state.as_mut()) {
            if self.panel_dragging {
                state.history.amend(m);
            } else {
                state.history.push(m);
            }
            self.panel_dragging = dragging;
            if let Some(status) = keep_recovery(state.material(), &mut self.recovery_warned) {
                state.status = status;
            }
            if let Some(g) = &self.gpu {
                g.window.request_redraw();
            }
        } else {
            self.panel_dragging = false;
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<()> {
        let Some(state) = self.state.as_ref() else { return Ok(()) };
        if let Some(p) = &self.opts.out {
            state.material().save(p)?;
        }
        if let (Some(p), Some(frame)) = (&self.opts.screenshot, &self.frame) {
            let l = state.layout;
            crate::imageio::write_rgba8_png(p, l.width, l.height, frame)?;
        }
        if let Some(p) = &self.opts.frame_stats {
            let device = self.gpu.as_ref().map_or(String::new(), |g| g.renderer.device_name().to_string());
            let json = frame_stats_json(&device, (state.layout.width, state.layout.height), &self.frame_stats);
            crate::fsio::write_atomic(p, json.as_bytes())?;
        }
        Ok(())
    }
}

/// What a frame rendered of the mesh view: the fast `key` image after a change (an interaction
/// frame), `REFINE_STEP` more `mis` samples (a refinement frame), or nothing new.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FrameKind {
    Interaction,
    Refinement,
    Unchanged,
}

/// One frame for `--frame-stats`.
struct FrameStat {
    wall_ms: f64,
    gpu_ms: f64,
    kind: FrameKind,
    passes: Vec<(String, f64)>,
}

/// `{"device", "size": [W, H], "frames": [{"kind", "wall_ms", "gpu_ms", "passes": [{"name", "ms"}]}],
/// "interaction": {"frames", "median_wall_ms", "median_gpu_ms"}, "refinement": {…}}`.
fn frame_stats_json(device: &str, size: (u32, u32), frames: &[FrameStat]) -> String {
    use serde_json::json;
    let kind_name = |k: FrameKind| match k {
        FrameKind::Interaction => "interaction",
        FrameKind::Refinement => "refinement",
        FrameKind::Unchanged => "unchanged",
    };
    let summary = |k: FrameKind| {
        let wall: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.wall_ms).collect();
        let gpu: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.gpu_ms).collect();
        if wall.is_empty() {
            return json!({ "frames": 0 });
        }
        json!({ "frames": wall.len(), "median_wall_ms": crate::measure::stats(&wall).0,
                "median_gpu_ms": crate::measure::stats(&gpu).0 })
    };
    let list: Vec<_> = frames
        .iter()
        .map(|f| {
            json!({ "kind": kind_name(f.kind), "wall_ms": f.wall_ms, "gpu_ms": f.gpu_ms,
                    "passes": f.passes.iter().map(|(n, ms)| json!({ "name": n, "ms": ms })).collect::<Vec<_>>() })
        })
        .collect();
    let doc = json!({ "device": device, "size": [size.0, size.1], "frames": list,
                      "interaction": summary(FrameKind::Interaction), "refinement": summary(FrameKind::Refinement) });
    let mut s = serde_json::to_string_pretty(&doc).expect("plain JSON");
    s.push('\n');
    s
}

/// Scales the mesh view so the environment's mean radiance shows as mid grey.
fn auto_exposure(env: &Environment) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for j in 0..env.height {
        let o = env.texel_solid_angle(j);
        for t in &env.texels[j * env.width..(j + 1) * env.width] {
            s += (t[0] + t[1] + t[2]).max(0.0) as f64 / 3.0 * o;
            w += o;
        }
    }
    if s > 0.0 {
        (0.18 * w / s).clamp(1e-4, 1e4)
    } else {
        1.0
    }
}

/// Records one window frame: CPU pixels → `target`, the panel drawn over them, `target` blitted into
/// the swapchain image (in `TRANSFER_DST_OPTIMAL`) and copied to `readback`.
fn record_frame(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    (target, staging, readback): (&crate::vk::Image, &Buffer, &Buffer),
    ui: &mut egui_ash_renderer::Renderer,
    (extent, scale, primitives): (vk::Extent2D, f32, &[egui::ClippedPrimitive]),
    swap_image: vk::Image,
) -> Result<()> {
    let raw = ctx.raw();
    let none = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
    let copy = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
    let colour = (
        vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
    );
    let read = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_READ);
    let layers = vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    };
    let whole = vk::Extent3D { width: extent.width, height: extent.height, depth: 1 };
    target.barrier(ctx, cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL, none, copy);
    let region = vk::BufferImageCopy::default().image_subresource(layers).image_extent(whole);
    // SAFETY: `cmd` is recording; buffer and image hold a whole frame.
    unsafe {
        raw.cmd_copy_buffer_to_image(cmd, staging.raw, target.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region])
    };
    target.barrier(
        ctx,
        cmd,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        copy,
        colour,
    );
    let attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(target.view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::LOAD)
        .store_op(vk::AttachmentStoreOp::STORE)];
    let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
    let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&attachment);
    // SAFETY: the target is a colour attachment in the layout named.
    unsafe { raw.cmd_begin_rendering(cmd, &info) };
    let drawn =
        ui.cmd_draw(cmd, extent, scale, primitives).map_err(|e| Error::NoDevice(format!("the tool panel: {e}")));
    // SAFETY: rendering began above.
    unsafe { raw.cmd_end_rendering(cmd) };
    drawn?;
    target.barrier(
        ctx,
        cmd,
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        colour,
        read,
    );
    let corner = [vk::Offset3D::default(), vk::Offset3D { x: extent.width as i32, y: extent.height as i32, z: 1 }];
    let blit = vk::ImageBlit::default()
        .src_subresource(layers)
        .src_offsets(corner)
        .dst_subresource(layers)
        .dst_offsets(corner);
    // SAFETY: source in TRANSFER_SRC, destination (the acquired swapchain image) in TRANSFER_DST, same size.
    unsafe {
        raw.cmd_blit_image(
            cmd,
            target.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            swap_image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[blit],
            vk::Filter::NEAREST,
        );
        raw.cmd_copy_image_to_buffer(cmd, target.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, readback.raw, &[region]);
    }
    let b = [vk::BufferMemoryBarrier2::default()
        .buffer(readback.raw)
        .size(vk::WHOLE_SIZE)
        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)];
    // SAFETY: `cmd` is recording.
    unsafe { raw.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&b)) };
    Ok(())
}

fn key_input(key: &Key, mods: ModifiersState) -> Option<Input> {
    let Key::Character(c) = key else { return None };
    let c = c.to_lowercase();
    let ctrl = mods.control_key();
    Some(match (c.as_str(), ctrl) {
        ("z", true) if mods.shift_key() => Input::Redo,
        ("z", true) => Input::Undo,
        ("y", true) => Input::Redo,
        ("s", true) => Input::Save,
        ("c", false) => Input::Brush(BrushKind::Create),
        ("m", false) => Input::Brush(BrushKind::Modify),
        ("s", false) => Input::Brush(BrushKind::Streak),
        ("i", false) => Input::Brush(BrushKind::Intensify),
        ("d", false) => Input::Brush(BrushKind::Deintensify),
        ("p", false) => Input::ToggleSplit,
        ("l", false) => Input::ResetLight,
        ("f", false) => Input::FrameView,
        _ => return None,
    })
}

impl ApplicationHandler for App {
    /// A report finished on the worker thread: show it.
    fn user_event(&mut self, _el: &ActiveEventLoop, _event: ()) {
        if let Some(g) = &self.gpu {
            g.window.request_redraw();
        }
    }

    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gpu.is_none() {
            if let Err(e) = self.init(el) {
                self.fail(el, e);
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        // The tool panel sees every event first; what it takes does not reach the views.
        if let (Some(es), Some(g)) = (self.egui_state.as_mut(), self.gpu.as_ref()) {
            let r = es.on_window_event(&g.window, &event);
            if r.repaint {
                g.window.request_redraw();
            }
            let passes = matches!(
                event,
                WindowEvent::CloseRequested
                    | WindowEvent::RedrawRequested
                    | WindowEvent::Resized(_)
                    | WindowEvent::ModifiersChanged(_)
            );
            if r.consumed && !passes {
                return;
            }
        }
        let input = match event {
            WindowEvent::CloseRequested => {
                self.done = true;
                el.exit();
                return;
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.draw() {
                    self.fail(el, e);
                }
                return;
            }
            WindowEvent::Resized(s) => Input::Resized(s.width, s.height),
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                return;
            }
            WindowEvent::CursorMoved { position, .. } => Input::CursorMoved(position.x, position.y),
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => Input::Button { pressed, right: false },
                    MouseButton::Right => Input::Button { pressed, right: true },
                    _ => return,
                }
            }
            WindowEvent::MouseWheel { delta, .. } => Input::Scroll(match delta {
                MouseScrollDelta::LineDelta(_, y) => y as f64,
                MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
            }),
            WindowEvent::DroppedFile(p) => Input::Dropped(p),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                if let Key::Character(c) = &event.logical_key {
                    if c.as_str() == "r" {
                        if let (Some(m), Some(s)) = (self.recovered.take(), self.state.as_mut()) {
                            s.history.push(m);
                            s.status = "restored the last session's material".into();
                            if let Some(g) = &self.gpu {
                                g.window.request_redraw();
                            }
                        }
                    }
                    match c.as_str() {
                        "g" => self.log_graph = !self.log_graph,
                        "+" | "=" => self.exposure *= 1.25,
                        "-" => self.exposure /= 1.25,
                        _ => {}
                    }
                }
                match key_input(&event.logical_key, self.modifiers) {
                    Some(i) => i,
                    None => {
                        if let Some(g) = &self.gpu {
                            g.window.request_redraw();
                        }
                        return;
                    }
                }
            }
            _ => return,
        };
        if let Err(e) = self.handle(input) {
            self.fail(el, e);
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        if self.state.is_none() {
            return;
        }
        // Replayed inputs go through the same handler, one batch per turn of the loop.
        if !self.pending.is_empty() {
            while let Some(i) = self.pending.pop_front() {
                let release = matches!(i, Input::Button { pressed: false, .. });
                if let Err(e) = self.handle(i) {
                    self.fail(el, e);
                    return;
                }
                if release {
                    break;
                }
            }
            if let Some(g) = &self.gpu {
                g.window.request_redraw();
            }
            return;
        }
        // Idle: refine the mesh view (not while replaying for a screenshot, which shows the fast image).
        if (!self.opts.quit || self.opts.converge) && self.frame.is_some() && self.refine_samples < REFINE_MAX {
            if let Some(g) = &self.gpu {
                g.window.request_redraw();
            }
            return;
        }
        if self.opts.quit && self.frame.is_some() {
            // One frame after the last input, then out.
            if let Err(e) = self.draw() {
                self.fail(el, e);
                return;
            }
            self.done = true;
            el.exit();
        }
    }
}

/// Runs the editor until the window closes (or, with `quit`, until the replay is done).
pub fn run(opts: Options) -> Result<()> {
    check_size(opts.size)?;
    for (flag, path) in [("--out", &opts.out), ("--screenshot", &opts.screenshot)] {
        if let Some(p) = path {
            crate::fsio::check_output(flag, p)?;
        }
    }
    let env = match &opts.env {
        Some(p) => Environment::load(p)?,
        None => crate::measure::embedded_environment()?,
    };
    let mesh = Mesh::resolve(opts.mesh.as_deref().unwrap_or("torus"))?;
    let replay = opts.replay.as_deref().map(Strokes::load).transpose()?;
    let recovery = recovery_path();
    let start = match (&opts.material, &replay) {
        (Some(p), _) => Material::load(p)?,
        (None, Some(_)) => Material::scratch(),
        (None, None) => crate::brush::strokes::default_material()?,
    };
    // Unsaved work of an earlier session that did not end cleanly is offered back (R restores it).
    let recovered = match (&opts.material, &replay) {
        (None, None) if recovery.exists() => Material::load(&recovery).ok().filter(|m| *m != start),
        _ => None,
    };
    if recovered.is_some() {
        eprintln!(
            "brdf-shop: unsaved work from the last session is in {}; press R in the window to restore it",
            recovery.display()
        );
    }
    let event_loop = EventLoop::new().map_err(|e| {
        Error::NoDevice(format!("cannot reach a display ({e}); set DISPLAY or WAYLAND_DISPLAY, or run under xvfb-run"))
    })?;
    let mut app = App {
        proxy: event_loop.create_proxy(),
        opts,
        env_summary: EnvSummary::of(&env),
        env,
        mesh,
        start,
        replay,
        pending: VecDeque::new(),
        gpu: None,
        state: None,
        modifiers: ModifiersState::empty(),
        log_graph: false,
        exposure: 1.0,
        last_ms: 0.0,
        frame: None,
        error: None,
        done: false,
        refine_key: String::new(),
        refine_sum: Vec::new(),
        refine_samples: 0,
        frame_ms: Vec::new(),
        frame_stats: Vec::new(),
        last_kind: FrameKind::Unchanged,
        recovered,
        recovery_warned: false,
        egui_ctx: egui::Context::default(),
        egui_state: None,
        spp: 8,
        report: None,
        timings: Vec::new(),
        panel_dragging: false,
    };
    event_loop.run_app(&mut app).map_err(|e| Error::NoDevice(format!("the window's event loop failed: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    app.finish()?;
    if app.opts.quit && !app.frame_ms.is_empty() {
        let (median, min, max) = crate::measure::stats(&app.frame_ms);
        let l = app.state.as_ref().map(|s| s.layout);
        eprintln!(
            "{} frames at {}x{}: median {median:.1} ms (min {min:.1}, max {max:.1}); mesh view at {} spp",
            app.frame_ms.len(),
            l.map_or(0, |l| l.width),
            l.map_or(0, |l| l.height),
            if app.refine_samples == 0 { "key 8".to_string() } else { format!("mis {}", app.refine_samples) }
        );
    }
    drop(app.gpu.take());
    Ok(())
}
