//! The interactive editor (paper §3.1, Fig. 1): one window with the mesh under the environment
//! (left; orbit with the left button, zoom with the wheel, `F` frames it), the spherical canvas (right;
//! paint with the left button, drag the light with the right, `L` resets it) and the BRDF graph
//! (lower right; `G` toggles log scale). Brushes: `C` create, `M` modify, `S` streak, `I` intensify,
//! `D` de-intensify; `P` split lobes on/off; Ctrl+Z / Ctrl+Shift+Z undo/redo; Ctrl+S saves. A
//! dropped (or *Open…*ed) `.exr`/`.hdr`, mesh or `.brdf.json` file is loaded; *Export…* writes the
//! material in any format `brdf-shop export` writes (`export`).
//!
//! The layout: `handler` turns winit events into [`state::Input`]s, which [`state::State`] handles
//! (`--replay` feeds the same inputs from a strokes file); this module owns the session (window,
//! scene, history, scripted steps, dropped files); `frame` decides per frame what must be re-rendered
//! (generation counters of the material, camera, light and environment) and runs the tool panel;
//! `view` renders, composes and presents on the GPU with frames in flight; `start` checks the options,
//! loads the scene, runs the event loop and writes the outputs at the end; `recovery` keeps unsaved
//! work; `stats` records frame times. Where the panel and the views sit is [`crate::layout`].

pub mod backdrop;
pub mod export;
mod frame;
pub mod graph;
pub mod handler;
pub mod lighting;
pub mod options;
pub mod panel;
pub mod preview;
pub mod recovery;
pub mod report;
mod start;
pub mod state;
pub mod stats;
pub mod view;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use winit::event_loop::{ActiveEventLoop, EventLoopProxy};
use winit::keyboard::ModifiersState;
use winit::window::Window;

use crate::brdf::Material;
use crate::brush::{Settings, Strokes};
use crate::error::{Error, Result};
use crate::layout::Layout;
use crate::scene::{Environment, Mesh};

use frame::{CanvasKey, MeshKey};
use recovery::keep_recovery;
pub use recovery::{recovery_path, save_recovery};
pub use start::run;
use state::{Input, State};
use stats::{FrameKind, FrameStat};
use view::Gpu;

use lighting::{light_from, EnvSummary};
pub use options::{check_frame_budget, check_size, clamp_to_display, parse_export, Options, MAX_WINDOW_SIDE};

struct App {
    opts: Options,
    /// The environment as loaded; the renderer has it turned by the session's `env_rotation`.
    env: Environment,
    env_summary: EnvSummary,
    /// `backdrop::auto_brightness` of `env` (a turn does not change it).
    env_backdrop: f64,
    /// The session's view settings as loaded at the start (`backdrop::Session`).
    session: backdrop::Session,
    /// Whether the warning that the session file cannot be written was printed.
    session_warned: bool,
    /// The environment was turned since the last frame: the next frame gives the renderer the
    /// turned map.
    env_turn_pending: bool,
    mesh: Mesh,
    /// Changes when the environment or the mesh is replaced.
    scene_generation: u64,
    start: Material,
    replay: Option<Strokes>,
    pending: VecDeque<Input>,
    /// Scripted window changes still to make (`--resize`, `--minimise`), one per frame.
    window_script: VecDeque<WindowStep>,
    /// What the window script waits for before its next step.
    window_wait: Option<WindowWait>,
    /// When the tool panel asked to be repainted (egui's repaint delay), if it did.
    egui_repaint: Option<std::time::Instant>,
    /// Redraws skipped because the window was minimised (`--frame-stats`).
    skipped_minimised: u64,
    /// The window was seen minimised: redraw once it is not.
    restore_redraw: bool,
    gpu: Option<Gpu>,
    state: Option<State>,
    modifiers: ModifiersState,
    /// At least one frame was presented.
    shown: bool,
    /// The last captured frame (`--screenshot`).
    captured: Option<Vec<u8>>,
    error: Option<Error>,
    done: bool,
    mesh_key: Option<MeshKey>,
    /// The mesh view waits for a lobe pipeline being built in the background (it shows its last
    /// image; the build's end wakes the loop).
    mesh_waiting: bool,
    /// Since when the views drawn lack a compensation table being baked (`None`: they lack none).
    tables_pending: Option<std::time::Instant>,
    /// Each wait for compensation tables, ms, from the first frame drawn without one to the first
    /// with them all (`--frame-stats`).
    table_waits: Vec<f64>,
    canvas_key: Option<CanvasKey>,
    /// The BRDF graph's curves and what they were computed for.
    curves: Option<(CanvasKey, graph::Curves)>,
    /// Wall-clock milliseconds of each frame drawn (record, submit, present).
    frame_ms: Vec<f64>,
    /// Frames submitted whose GPU times are not in yet, with their wall ms.
    in_flight: Vec<(u64, f64, frame::Drawn)>,
    /// The scale of interaction frames (`--frame-budget`).
    preview: preview::Preview,
    /// The mesh view, and the canvas, show a preview (smaller than their places): the next frame
    /// without a change renders them at full size.
    mesh_previewed: bool,
    canvas_previewed: bool,
    /// Every frame's statistics (`--frame-stats`).
    frame_stats: Vec<FrameStat>,
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
    /// The GPU ms of the passes of the last finished frame.
    timings: Vec<(String, f64)>,
    /// A panel widget was being dragged last frame: its edits amend one history step.
    panel_dragging: bool,
    /// The *Open…* / *Save as…* dialog's path field, while it is open.
    dialog: Option<panel::Dialog>,
    /// The *Export…* dialog (its last format and path are kept while it is closed).
    export_dialog: export::Dialog,
}

#[derive(Clone, Copy, Debug)]
enum WindowStep {
    Resize(u32, u32),
    Minimise(bool),
}

/// What the window script waits for.
#[derive(Clone, Copy, Debug)]
enum WindowWait {
    /// The window manager to minimise (`true`) or restore the window; asked at `since`.
    Manager { minimised: bool, since: std::time::Instant },
    /// The minimised window stays so until then.
    Hold(std::time::Instant),
}

/// How long a scripted minimise or restore waits for the window manager to do it.
pub const MINIMISE_WAIT: std::time::Duration = std::time::Duration::from_secs(10);

/// How often a minimised window looks whether it was restored.
pub const MINIMISED_POLL: std::time::Duration = std::time::Duration::from_millis(250);

/// How long a scripted minimise keeps the window minimised.
pub const MINIMISED_HOLD: std::time::Duration = std::time::Duration::from_millis(500);

/// The most samples per pixel a refining frame adds (fewer when the frame budget asks), and where
/// refinement stops.
pub const REFINE_STEP: u32 = 16;
pub const REFINE_MAX: u32 = 1024;

/// How many recent frames the panel's median frame time is taken over.
pub const FRAME_RATE_WINDOW: usize = 30;

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        el.exit();
    }

    fn request_redraw(&self) {
        if let Some(g) = &self.gpu {
            g.window.request_redraw();
        }
    }

    fn init(&mut self, el: &ActiveEventLoop) -> Result<()> {
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
        let mut gpu = Gpu::new(window)?;
        // New lobe pipelines are built off the UI thread; the finished build wakes the loop.
        let proxy = self.proxy.clone();
        gpu.renderer.build_in_background = Some(Arc::new(move || {
            let _ = proxy.send_event(());
        }));
        gpu.renderer.set_mesh(&self.mesh)?;
        self.egui_state = Some(egui_winit::State::new(
            self.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &*gpu.window,
            Some(gpu.window.scale_factor() as f32),
            None,
            Some(gpu.renderer.ctx.device.limits.max_image_dimension2_d as usize),
        ));
        let size = gpu.window.inner_size();
        let (w, h) = gpu.swapchain_extent()?.unwrap_or((size.width, size.height));
        let settings = match &self.replay {
            Some(s) => s.settings("replay")?,
            None => Settings::new(crate::brush::Canvas { light: DVec3::Z, intensity: 1.0 }),
        };
        let mut state = State::new(self.start.clone(), settings, Layout::new(w.max(1), h.max(1)));
        (state.env_rotation, state.backdrop) = (self.session.env_rotation, self.session.backdrop);
        self.gpu = Some(gpu);
        self.set_env(state.env_rotation)?;
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
        self.pending.extend(self.opts.export.iter().cloned().map(|(f, p)| Input::Export(f, p)));
        self.window_script.extend(self.opts.resize.iter().map(|&(w, h)| WindowStep::Resize(w, h)));
        if self.opts.minimise {
            self.window_script.extend([WindowStep::Minimise(true), WindowStep::Minimise(false)]);
        }
        state.recovered = self.recovered_material().ok().flatten();
        if let (Some(_), Some(path)) = (&state.recovered, recovery_path()) {
            state.status =
                format!("unsaved work from the last session found ({}): press R to restore it", path.display());
        }
        self.state = Some(state);
        Ok(())
    }

    /// The recovery file's material when it should be offered back: no `--material`, no replay,
    /// and different from the one the session starts with. An error says why a file at the recovery
    /// path is not offered (it is not a regular file, or not a material).
    fn recovered_material(&self) -> std::result::Result<Option<Material>, String> {
        let Some(recovery) = recovery_path() else { return Ok(None) };
        match (&self.opts.material, &self.replay) {
            (None, None) => Ok(recovery::load_recovery(&recovery)?.filter(|m| *m != self.start)),
            _ => Ok(None),
        }
    }

    fn handle(&mut self, input: Input) -> Result<()> {
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        let fx = state.handle(input);
        // The turned map is made once per frame, however many cursor moves a frame's drag holds.
        self.env_turn_pending |= fx.env_turned;
        if fx.session_changed {
            self.keep_session();
        }
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        if fx.material_changed {
            if let Some(status) = keep_recovery(state.material(), &mut self.recovery_warned) {
                state.status = status;
            }
        }
        let save_to = fx.save_as.clone().or_else(|| {
            fx.save.then(|| {
                self.opts
                    .out
                    .clone()
                    .or_else(|| self.opts.material.clone())
                    .unwrap_or_else(|| PathBuf::from("material.brdf.json"))
            })
        });
        if let Some(path) = save_to {
            // A path that cannot be written is the user's to fix: a status line, the session goes on.
            state.status = match state.material().save(&path) {
                Ok(()) => format!("saved {}", crate::fsio::show(&path)),
                Err(e) if e.is_user_error() => format!("not saved: {e}"),
                Err(e) => return Err(e),
            };
        }
        if let Some((format, path)) = fx.export {
            // As the *Export…* button does: a status line, on stderr too (scripted sessions).
            let material_file = self.opts.out.as_deref().or(self.opts.material.as_deref());
            let line = export::export(state.material(), format, &path, material_file);
            eprintln!("brdf-shop: {}", crate::fsio::escape_controls(&line));
            state.status = line;
        }
        if let Some(p) = fx.load {
            // So is a file that does not load (broken, unknown kind); a device error is not.
            if let Err(e) = self.load_dropped(&p) {
                if !e.is_user_error() {
                    return Err(e);
                }
                let line = format!("not loaded: {e}");
                eprintln!("brdf-shop: {}", crate::fsio::escape_controls(&line));
                if let Some(state) = self.state.as_mut() {
                    state.status = line;
                }
            }
        }
        if fx.redraw {
            self.request_redraw();
        }
        Ok(())
    }

    fn load_dropped(&mut self, p: &Path) -> Result<()> {
        let name = p.to_string_lossy().to_lowercase();
        let Some(camera) = self.state.as_ref().map(|s| s.camera()) else { return Ok(()) };
        if name.ends_with(".exr") || name.ends_with(".hdr") {
            let env = Environment::load(p)?;
            self.env_backdrop = backdrop::auto_brightness(&env);
            self.env = env;
            let rotation = self.state.as_ref().map_or(0.0, |s| s.env_rotation);
            self.set_env(rotation)?;
        }
        let (Some(gpu), Some(state)) = (self.gpu.as_mut(), self.state.as_mut()) else { return Ok(()) };
        if name.ends_with(".exr") || name.ends_with(".hdr") {
            state.default_light = light_from(&self.env_summary, &camera);
            state.settings.canvas.light = state.default_light;
        } else if Mesh::is_mesh_file(p) {
            // The same loader as `--mesh`: OBJ, glTF (.gltf, .glb) or PLY.
            self.mesh = Mesh::load(p)?;
            gpu.renderer.set_mesh(&self.mesh)?;
            self.scene_generation += 1;
        } else if name.ends_with(".json") {
            let m = Material::load(p)?;
            state.history.push(m);
            state.status = format!("loaded {}", crate::fsio::show(p));
        } else {
            state.status = format!("{}: not an environment, mesh or material", crate::fsio::show(p));
        }
        gpu.window.request_redraw();
        Ok(())
    }

    /// Gives the renderer the environment turned by `rotation` degrees about the up axis (the
    /// lighting, the key lights, the SH and the backdrop turn together) and takes its summary.
    fn set_env(&mut self, rotation: f64) -> Result<()> {
        let turned = (rotation != 0.0).then(|| self.env.rotated(rotation));
        let env = turned.as_ref().unwrap_or(&self.env);
        if let Some(gpu) = self.gpu.as_mut() {
            gpu.renderer.set_environment(env)?;
        }
        self.env_summary = EnvSummary::of(env);
        self.scene_generation += 1;
        Ok(())
    }

    /// Keeps the session's view settings (`backdrop::Session`): a file that cannot be written is a
    /// warning once and a status line; the session goes on.
    fn keep_session(&mut self) {
        let Some(state) = self.state.as_mut() else { return };
        let session = backdrop::Session { env_rotation: state.env_rotation, backdrop: state.backdrop };
        let Some(path) = backdrop::session_path() else { return };
        if let Err(e) = session.save(&path) {
            let msg = format!("the view settings are not kept: the session file cannot be written ({e})");
            if !self.session_warned {
                eprintln!("brdf-shop: warning: {}", crate::fsio::escape_controls(&msg));
                self.session_warned = true;
            }
            state.status = format!("warning: {msg}");
        }
    }

    /// Whether the window manager has minimised the window (an X11 window stays its size when
    /// iconified, so the swapchain alone cannot tell).
    fn minimised(&self) -> bool {
        self.gpu.as_ref().is_some_and(|g| g.window.is_minimized() == Some(true))
    }

    /// Draws one frame and records its statistics; a minimised window draws nothing.
    fn draw(&mut self) -> Result<()> {
        if self.minimised() {
            self.skipped_minimised += 1;
            return Ok(());
        }
        let start = std::time::Instant::now();
        if std::mem::take(&mut self.env_turn_pending) {
            let rotation = self.state.as_ref().map_or(0.0, |s| s.env_rotation);
            self.set_env(rotation)?;
        }
        let drawn = self.draw_frame()?;
        let Some(drawn) = drawn else { return Ok(()) };
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        self.frame_ms.push(wall_ms);
        if let Some(g) = self.gpu.as_mut() {
            self.in_flight.push((g.renderer.frame_number(), wall_ms, drawn));
            let finished = g.renderer.take_finished();
            self.file_finished(finished);
        }
        Ok(())
    }

    /// Files the GPU times of finished frames with their wall times.
    fn file_finished(&mut self, finished: Vec<crate::vk::frame::Finished>) {
        for f in finished {
            let Some(k) = self.in_flight.iter().position(|e| e.0 == f.number) else { continue };
            let (_, wall_ms, drawn) = self.in_flight.remove(k);
            let passes: Vec<(String, f64)> = f.timings.iter().map(|t| (t.name.clone(), t.ms)).collect();
            if drawn.refine_sample {
                let sampling = passes.iter().filter(|t| t.0 == "mis").map(|t| t.1).sum();
                self.preview.observe_refinement(wall_ms, sampling, drawn.spp);
            }
            if drawn.sample {
                // Every pass but the window's own works on the views' pixels.
                let scaled = passes.iter().filter(|t| !view::WINDOW_PASSES.contains(&t.0.as_str())).map(|t| t.1).sum();
                self.preview.observe(drawn.scale, wall_ms, scaled);
            }
            if drawn.kind != FrameKind::Unchanged {
                // (+ 0.0: the sum of no passes is -0.0.)
                let gpu_ms = passes.iter().map(|t| t.1).sum::<f64>() + 0.0;
                let (kind, scale, spp, frame_ms) = (drawn.kind, drawn.scale, drawn.spp, f.frame_ms);
                let passes = passes.clone();
                self.frame_stats.push(FrameStat { wall_ms, gpu_ms, frame_ms, kind, scale, spp, passes });
            }
            self.timings = passes;
        }
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
        if let Some(p) = a.open {
            self.handle(Input::Dropped(p))?;
        }
        if let Some(p) = a.save_as {
            self.handle(Input::SaveAs(p))?;
        }
        if let Some((f, p)) = a.export {
            self.handle(Input::Export(f, p))?;
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
            self.request_redraw();
        } else {
            self.panel_dragging = false;
        }
        Ok(())
    }
}
