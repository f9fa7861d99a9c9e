//! Starting and ending the editor: the options checked and the scene loaded before any window
//! opens (every refusal comes first), the event loop run, and at the end the outputs written and
//! the summary line of a `--quit` run.

use std::collections::VecDeque;
use std::path::Path;

use winit::event_loop::{EventLoop, EventLoopProxy};
use winit::keyboard::ModifiersState;

use super::lighting::EnvSummary;
use super::recovery::recovery_path;
use super::{backdrop, export, preview, stats, App, Options};
use super::{check_frame_budget, check_size, MAX_WINDOW_SIDE};
use crate::brdf::Material;
use crate::brush::Strokes;
use crate::error::{Error, Result};
use crate::scene::{Environment, Mesh};

/// Runs the editor until the window closes (or, with `quit`, until the replay is done).
pub fn run(opts: Options) -> Result<()> {
    check_options(&opts)?;
    let loaded = Loaded::load(&opts)?;
    let event_loop = EventLoop::new().map_err(|e| {
        Error::NoDevice(format!("cannot reach a display ({e}); set DISPLAY or WAYLAND_DISPLAY, or run under xvfb-run"))
    })?;
    let mut app = App::new(opts, loaded, event_loop.create_proxy());
    app.announce_recovery();
    event_loop.run_app(&mut app).map_err(|e| Error::NoDevice(format!("the window's event loop failed: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    app.finish()?;
    if app.opts.quit && !app.frame_ms.is_empty() {
        app.print_summary();
    }
    drop(app.gpu.take());
    Ok(())
}

/// Refuses, before the window opens, the options the editor cannot run with: a window or
/// `--resize` size out of range, a frame budget that is not a time, and outputs that are the same
/// file however spelled. The exports take part in the same-file check; whether an export's folder takes a file
/// is found when it is written (a status line: the editor goes on).
fn check_options(opts: &Options) -> Result<()> {
    check_size(opts.size)?;
    if let Some(ms) = opts.frame_budget_ms {
        check_frame_budget(ms)?;
    }
    for &(w, h) in &opts.resize {
        check_size((w, h)).map_err(|_| {
            Error::input("--resize", format!("{w}x{h}: each side must be within 1 and {MAX_WINDOW_SIDE} pixels"))
        })?;
    }
    let outputs: Vec<(&str, &Path)> =
        [("--out", &opts.out), ("--screenshot", &opts.screenshot), ("--frame-stats", &opts.frame_stats)]
            .into_iter()
            .filter_map(|(flag, p)| p.as_deref().map(|p| (flag, p)))
            .collect();
    crate::fsio::check_outputs(&outputs)?;
    let exports: Vec<(String, &Path)> =
        opts.export.iter().map(|(f, p)| (format!("--export {}", f.name()), p.as_path())).collect();
    let all: Vec<(&str, &Path)> =
        outputs.iter().copied().chain(exports.iter().map(|(flag, p)| (flag.as_str(), *p))).collect();
    crate::fsio::check_distinct(&all)
}

/// What the editor starts with, loaded before the window opens.
struct Loaded {
    env: Environment,
    mesh: Mesh,
    replay: Option<Strokes>,
    /// The material the history starts from.
    start: Material,
    /// The view settings kept from the last run (the defaults when there are none).
    session: backdrop::Session,
}

impl Loaded {
    /// Loads the environment (`--env`, or the embedded map), the mesh (`--mesh`, or the torus), the
    /// strokes to replay and the starting material (`--material`; a replay starts from scratch,
    /// otherwise the default material). A session file that does not read is a warning: the
    /// defaults are used.
    fn load(opts: &Options) -> Result<Loaded> {
        let env = match &opts.env {
            Some(p) => Environment::load(p)?,
            None => crate::measure::embedded_environment()?,
        };
        let mesh = Mesh::resolve(opts.mesh.as_deref().unwrap_or("torus"))?;
        let replay = opts.replay.as_deref().map(Strokes::load).transpose()?;
        let start = match (&opts.material, &replay) {
            (Some(p), _) => Material::load(p)?,
            (None, Some(_)) => Material::scratch(),
            (None, None) => crate::brush::strokes::default_material()?,
        };
        let session = match backdrop::session_path().map(|p| (backdrop::Session::load(&p), p)) {
            Some((Ok(s), _)) => s,
            Some((Err(why), p)) => {
                eprintln!("brdf-shop: warning: the session file {} is ignored: {why}", crate::fsio::show(&p));
                backdrop::Session::default()
            }
            None => backdrop::Session::default(),
        };
        Ok(Loaded { env, mesh, replay, start, session })
    }
}

impl App {
    /// The editor before its window opens (`init` opens it when the event loop starts).
    fn new(opts: Options, loaded: Loaded, proxy: EventLoopProxy<()>) -> App {
        let Loaded { env, mesh, replay, start, session } = loaded;
        let budget = opts.frame_budget_ms.unwrap_or(preview::DEFAULT_BUDGET_MS);
        let export_dialog = export::Dialog::new(opts.out.as_deref().or(opts.material.as_deref()));
        App {
            proxy,
            opts,
            env_summary: EnvSummary::of(&env),
            env_backdrop: backdrop::auto_brightness(&env),
            session,
            session_warned: false,
            env_turn_pending: false,
            env,
            mesh,
            scene_generation: 0,
            start,
            replay,
            pending: VecDeque::new(),
            window_script: VecDeque::new(),
            window_wait: None,
            egui_repaint: None,
            skipped_minimised: 0,
            restore_redraw: false,
            gpu: None,
            state: None,
            modifiers: ModifiersState::empty(),
            shown: false,
            captured: None,
            error: None,
            done: false,
            mesh_key: None,
            mesh_waiting: false,
            tables_pending: None,
            table_waits: Vec::new(),
            canvas_key: None,
            curves: None,
            frame_ms: Vec::new(),
            in_flight: Vec::new(),
            preview: preview::Preview::new(budget),
            mesh_previewed: false,
            canvas_previewed: false,
            frame_stats: Vec::new(),
            recovery_warned: false,
            egui_ctx: egui::Context::default(),
            egui_state: None,
            spp: 8,
            report: None,
            timings: Vec::new(),
            panel_dragging: false,
            dialog: None,
            export_dialog,
        }
    }

    /// Says on stderr, before the window opens, that the last run left unsaved work (R restores
    /// it), or why the recovery file is ignored.
    fn announce_recovery(&self) {
        let recovery = recovery_path().map(|p| crate::fsio::show(&p)).unwrap_or_default();
        match self.recovered_material() {
            Ok(Some(_)) => eprintln!(
                "brdf-shop: unsaved work from the last session is in {recovery}; press R in the window to restore it"
            ),
            Ok(None) => {}
            Err(why) => eprintln!("brdf-shop: warning: the recovery file {recovery} is ignored: {why}"),
        }
    }

    /// Waits for the frames in flight and files their times, then writes what the options ask for:
    /// the material (`--out`), the last captured frame (`--screenshot`) and the frame statistics
    /// (`--frame-stats`).
    fn finish(&mut self) -> Result<()> {
        if let Some(g) = self.gpu.as_mut() {
            g.renderer.finish_frames()?;
            let finished = g.renderer.take_finished();
            self.file_finished(finished);
        }
        let Some(state) = self.state.as_ref() else { return Ok(()) };
        if let Some(p) = &self.opts.out {
            state.material().save(p)?;
        }
        if let (Some(p), Some(frame)) = (&self.opts.screenshot, &self.captured) {
            let l = state.layout;
            crate::imageio::write_rgba8_png(p, l.width, l.height, frame)?;
        }
        if let Some(p) = &self.opts.frame_stats {
            let device = self.gpu.as_ref().map_or(String::new(), |g| g.renderer.device_name().to_string());
            let size = (state.layout.width, state.layout.height);
            let refined = self.gpu.as_ref().map_or(0, |g| g.renderer.refined_samples());
            let views = stats::views_json(state, (self.env_summary.exposure, self.env_backdrop), self.spp, refined);
            let json = stats::frame_stats_json(
                &device,
                size,
                &self.frame_stats,
                &self.table_waits,
                self.skipped_minimised,
                views,
            );
            crate::fsio::write_atomic(p, json.as_bytes())?;
        }
        Ok(())
    }

    /// The summary line of a `--quit` run on stderr: the frames drawn, the window's size, the median
    /// (min, max) frame time and the samples per pixel the mesh view reached.
    fn print_summary(&self) {
        let (median, min, max) = crate::measure::stats(&self.frame_ms);
        let l = self.state.as_ref().map(|s| s.layout);
        let refined = self.gpu.as_ref().map_or(0, |g| g.renderer.refined_samples());
        eprintln!(
            "{} frames at {}x{}: median {median:.1} ms (min {min:.1}, max {max:.1}); mesh view at {} spp",
            self.frame_ms.len(),
            l.map_or(0, |l| l.width),
            l.map_or(0, |l| l.height),
            if refined == 0 { format!("key {}", self.spp) } else { format!("mis {refined}") }
        );
    }
}
