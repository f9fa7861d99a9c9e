//! One editor frame: what must be re-rendered (the mesh view restarts on any change of what it
//! shows, previewed smaller when the frame budget asks, settles at full size and then refines while
//! nothing changes, or stays; the canvas only when the material or its light changed, or to
//! settle), the tool panel, and the GPU frame that composes and presents it.

use super::lighting::light_from;
use super::preview::{self, CanvasStep, MeshStep, Preview};
use super::state::{Input, State};
use super::stats::FrameKind;
use super::view::{Plan, Shown};
use super::{export, graph, panel, report, App, FRAME_RATE_WINDOW, REFINE_MAX, REFINE_STEP};
use crate::brdf::Material;
use crate::error::Result;
use crate::layout::Layout;
use crate::render::compose::Placement;
use crate::render::{Estimator, Progress, Recorded, Settings, View};

/// What the mesh view was last rendered for: any change restarts it (an interaction frame).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct MeshKey {
    material: u64,
    scene: u64,
    orbit: [f64; 4],
    size: (u32, u32),
    spp: u32,
    /// The backdrop's blur (its mip level's bits): the mesh view reads the map at it.
    blur: u64,
    /// Every compensation table of the material was there (`brdf::compensation::baked`): a view
    /// drawn while one was being baked is drawn again once it is.
    tables: bool,
}

/// What a presented frame drew, for its statistics and the preview's model.
pub(super) struct Drawn {
    pub kind: FrameKind,
    /// The linear scale of the views it changed (1: full size).
    pub scale: f64,
    /// It rendered the mesh view's `key` image (an interaction or a settle frame), every view it
    /// rendered at `scale`: the preview's model learns from it.
    pub sample: bool,
    /// A refinement frame that rendered nothing else: the refinement step's model learns from it.
    pub refine_sample: bool,
    /// The samples per pixel its mesh view took (a refinement frame: those it added; 0: none).
    pub spp: u32,
}

/// What the canvas was last rendered for.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct CanvasKey {
    material: u64,
    light: [f64; 4],
    side: u32,
    tables: bool,
}

/// What a frame renders and what kind of frame it is, decided before anything is recorded
/// ([`App::decide`]).
struct Decision {
    /// The mesh view to render, and whether it restarts or refines; `None`: it keeps its image.
    mesh: Option<(Settings, Progress)>,
    /// The canvas to render; `None`: unchanged.
    canvas: Option<Settings>,
    /// What the views are rendered for: kept once the frame is presented.
    mesh_key: MeshKey,
    canvas_key: CanvasKey,
    /// The frame's kind for its statistics: a frame that only settles the canvas is a settle frame
    /// too (one that only previews it is not a frame of the mesh view's: unchanged).
    kind: FrameKind,
    /// What the mesh view itself does (the panel's line).
    mesh_kind: FrameKind,
    /// The frame budget's scale for the views that change (1 in a frame without a change).
    scale: f64,
    /// The views are rendered smaller than their places: the next frame without a change settles
    /// them at full size.
    mesh_previewed: bool,
    canvas_previewed: bool,
    /// The scales the views were rendered at (1: full size, or not rendered), and whether the views
    /// rendered share one: the preview model learns only from frames whose views all had one scale,
    /// and refinement's from frames that rendered no canvas.
    mesh_scale: f64,
    canvas_scale: f64,
    one_scale: bool,
    /// The refinement samples the mesh view held before this frame.
    refined: u32,
}

impl Decision {
    /// The samples per pixel the mesh view takes this frame (a refinement frame: those it adds).
    fn mesh_spp(&self) -> u32 {
        self.mesh.as_ref().map_or(0, |m| m.0.spp)
    }

    /// The panel's line on what the mesh view shows: the new lobe's shader being built, a preview,
    /// the `key` image or the samples refinement has reached. `key_spp` is the `key` estimator's
    /// samples per pixel; `waiting`: the mesh view waits for a lobe pipeline.
    fn quality(&self, key_spp: u32, waiting: bool) -> String {
        let shown_refined = if self.mesh_kind == FrameKind::Refinement {
            self.refined + self.mesh_spp()
        } else if matches!(self.mesh_kind, FrameKind::Interaction | FrameKind::Settle) {
            0
        } else {
            self.refined
        };
        if waiting && self.kind == FrameKind::Interaction {
            "mesh view: building the new lobe's shader…".to_string()
        } else if self.mesh_previewed {
            format!("mesh view: key {key_spp} spp, preview at {:.0} %", self.scale * 100.0)
        } else if shown_refined == 0 {
            format!("mesh view: key {key_spp} spp")
        } else {
            format!("mesh view: mis {shown_refined} spp")
        }
    }

    /// What the presented frame drew; `waited`: the mesh view waited for its lobe pipelines and
    /// shows its last image (a waiting frame, from which no model learns).
    fn drawn(&self, waited: bool) -> Drawn {
        let kind = if waited { FrameKind::Waiting } else { self.kind };
        let mesh_planned = self.mesh.is_some();
        // The frames that rendered the mesh view's `key` image at one scale time the preview's model.
        let sample =
            mesh_planned && !waited && self.one_scale && matches!(kind, FrameKind::Interaction | FrameKind::Settle);
        let scale = if mesh_planned { self.mesh_scale } else { self.canvas_scale };
        let refine_sample = kind == FrameKind::Refinement && self.canvas.is_none();
        let spp = if waited { 0 } else { self.mesh_spp() };
        Drawn { kind, scale, sample, refine_sample, spp }
    }
}

/// The tool panel's part of a frame: egui's texture changes, triangles and scale for the GPU, the
/// view settings as the panel left them, and what else the user did (applied after the frame).
struct PanelFrame {
    actions: panel::Actions,
    view: panel::ViewSettings,
    textures: egui::TexturesDelta,
    primitives: Vec<egui::ClippedPrimitive>,
    pixels_per_point: f32,
}

/// The BRDF graph's rectangle (egui points): below the canvas, right of the mesh view.
fn graph_rect(l: &Layout, pixels_per_point: f32) -> egui::Rect {
    let ppp = pixels_per_point;
    egui::Rect::from_min_max(
        egui::pos2(l.canvas_x as f32 / ppp, l.graph_y.min(l.height) as f32 / ppp),
        egui::pos2(l.width as f32 / ppp, l.height as f32 / ppp),
    )
}

impl App {
    /// Follows the compensation tables of the frames drawn (the views were drawn without the terms
    /// of lobes whose tables are baking): times each wait, from the first frame drawn without a
    /// table to the first with them all (`--frame-stats`).
    fn note_tables(&mut self, complete: bool) {
        match (self.tables_pending, complete) {
            (None, false) => self.tables_pending = Some(std::time::Instant::now()),
            (Some(since), true) => {
                self.tables_pending = None;
                self.table_waits.push(since.elapsed().as_secs_f64() * 1e3);
            }
            _ => {}
        }
    }

    /// What this frame renders: the mesh view restarts (any change of what it shows), refines
    /// (nothing changed, refinement on and not done) or stays; the canvas re-renders only when the
    /// material or its light changed. Views that change are previewed smaller when the frame budget
    /// asks (`preview`) and settled at full size in the first frame without a change.
    /// Returns what the frame drew, `None` when nothing was presented.
    pub(super) fn draw_frame(&mut self) -> Result<Option<Drawn>> {
        let Some(l) = self.prepare_frame()? else { return Ok(None) };
        let (Some(gpu), Some(state)) = (self.gpu.as_ref(), self.state.as_ref()) else { return Ok(None) };
        let d = self.decide(state, &l, gpu.renderer.refined_samples());
        let (m, light) = (state.material().clone(), state.settings.canvas.light);
        let placement = self.placement(state, &l);
        if self.curves.as_ref().is_none_or(|c| c.0 != d.canvas_key) {
            self.curves = Some((d.canvas_key.clone(), graph::Curves::new(&m, light)));
        }
        let quality = d.quality(self.spp, self.mesh_waiting);
        let panel = self.run_panel(&l, &m, &quality);
        self.apply_view_settings(panel.view, &quality);
        let presented = self.present(&d, &m, placement, &panel)?;
        self.apply_panel(panel.actions)?;
        Ok(presented.then(|| d.drawn(self.mesh_waiting)))
    }

    /// Fits the state's layout to the swapchain (a resize the window did not report yet) and points
    /// the canvas light at the environment's brightest direction seen from the orbiting camera,
    /// unless the user moved it (a replay keeps its strokes file's light). Returns the frame's
    /// layout; `None` when there is nothing to draw into (no window, or a minimised one).
    fn prepare_frame(&mut self) -> Result<Option<Layout>> {
        let (Some(gpu), Some(state)) = (self.gpu.as_mut(), self.state.as_mut()) else { return Ok(None) };
        let Some((w, h)) = gpu.swapchain_extent()? else { return Ok(None) }; // minimised
        if (state.layout.width, state.layout.height) != (w, h) {
            state.handle(Input::Resized(w, h));
        }
        if !state.light_moved && self.replay.is_none() {
            state.default_light = light_from(&self.env_summary, &state.camera());
            state.settings.canvas.light = state.default_light;
        }
        Ok(Some(state.layout))
    }

    /// Decides what this frame renders (see [`Decision`]) from what the views were last rendered
    /// for, the drag in progress and `refined`, the refinement samples the mesh view holds.
    fn decide(&self, state: &State, l: &Layout, refined: u32) -> Decision {
        let full = self.mesh_settings(state, l);
        let (mesh_key, canvas_key) = self.keys(state, l);
        let refining = !self.opts.quit || self.opts.converge;
        let mesh_changed = self.mesh_key.as_ref() != Some(&mesh_key) || (!refining && refined > 0);
        let canvas_changed = self.canvas_key.as_ref() != Some(&canvas_key);
        // A view that changes is previewed at the budget's scale (`preview`); the first frame in
        // which nothing changes renders the previewed views at full size (a settle frame).
        let scale = if mesh_changed || canvas_changed { self.preview.scale() } else { 1.0 };
        let mesh_size = Preview::size((l.mesh_w, l.height), scale);
        let canvas_side = Preview::size((l.canvas, l.canvas), scale).0;
        let (mesh_step, canvas_step) = preview::steps(preview::Situation {
            mesh_changed,
            canvas_changed,
            mesh_previewed: self.mesh_previewed,
            canvas_previewed: self.canvas_previewed,
            holding: state.dragging(),
            // No refinement of an image still waiting for a compensation table.
            refine: refining && refined < REFINE_MAX && self.tables_pending.is_none(),
        });
        let (mesh, mesh_kind) = self.mesh_work(mesh_step, &full, mesh_size, refined);
        let canvas = (canvas_step != CanvasStep::Keep).then(|| {
            let side = if canvas_step == CanvasStep::Preview { canvas_side } else { l.canvas };
            Settings { width: side, height: side, view: View::Canvas, ..full.clone() }
        });
        let canvas_settles = canvas_step == CanvasStep::Settle;
        let kind = if mesh_kind == FrameKind::Unchanged && canvas_settles { FrameKind::Settle } else { mesh_kind };
        let mesh_scale = if mesh_changed { scale } else { 1.0 };
        let canvas_scale = if canvas_changed { scale } else { 1.0 };
        Decision {
            one_scale: canvas.is_none() || mesh.is_none() || mesh_scale == canvas_scale,
            mesh,
            canvas,
            mesh_key,
            canvas_key,
            kind,
            mesh_kind,
            scale,
            mesh_previewed: mesh_changed && mesh_size != (l.mesh_w, l.height),
            canvas_previewed: canvas_changed && canvas_side != l.canvas,
            mesh_scale,
            canvas_scale,
            refined,
        }
    }

    /// The mesh view at full size with the `key` estimator, as the state shows it (the canvas is
    /// rendered with the same settings, its size and view changed).
    fn mesh_settings(&self, state: &State, l: &Layout) -> Settings {
        Settings {
            width: l.mesh_w,
            height: l.height,
            spp: self.spp,
            estimator: Estimator::Key,
            view: View::Mesh,
            camera: state.camera(),
            light: state.settings.canvas.light,
            intensity: state.settings.canvas.intensity,
            backdrop_blur: state.backdrop.blur,
        }
    }

    /// What the mesh view and the canvas would be rendered for this frame: a view whose key differs
    /// from the one it was last rendered for has changed.
    fn keys(&self, state: &State, l: &Layout) -> (MeshKey, CanvasKey) {
        let generation = state.history.generation();
        let light = state.settings.canvas.light;
        let m = state.material();
        let tables = !m.compensated() || m.lobes.iter().all(crate::brdf::compensation::baked);
        let mesh = MeshKey {
            material: generation,
            scene: self.scene_generation,
            orbit: [state.yaw, state.pitch, state.distance, state.fov_deg],
            size: (l.mesh_w, l.height),
            spp: self.spp,
            blur: state.backdrop.blur.to_bits(),
            tables,
        };
        let canvas = CanvasKey {
            material: generation,
            light: [light.x, light.y, light.z, state.settings.canvas.intensity],
            side: l.canvas,
            tables,
        };
        (mesh, canvas)
    }

    /// The mesh view's work for `step`, from its full-size settings `full`: a preview at `size`, the
    /// full-size settle, or a refinement step; with the kind of frame it makes of the mesh view's.
    fn mesh_work(
        &self,
        step: MeshStep,
        full: &Settings,
        size: (u32, u32),
        refined: u32,
    ) -> (Option<(Settings, Progress)>, FrameKind) {
        match step {
            MeshStep::Preview => {
                let (width, height) = size;
                let preview = Settings { width, height, ..full.clone() };
                (Some((preview, Progress::Fresh)), FrameKind::Interaction)
            }
            MeshStep::Settle => (Some((full.clone(), Progress::Fresh)), FrameKind::Settle),
            MeshStep::Refine => {
                // As many samples as the budget holds (`preview`), up to the step and the end.
                let spp = self.preview.refine_step(REFINE_STEP.min(REFINE_MAX - refined));
                let mis = Settings { estimator: Estimator::Mis, spp, ..full.clone() };
                (Some((mis, Progress::Refine)), FrameKind::Refinement)
            }
            MeshStep::Keep => (None, FrameKind::Unchanged),
        }
    }

    /// Where the views go in the window image and how bright each is composed: the mesh view at the
    /// user's exposure times the environment's, the backdrop at its own brightness, the canvas at the
    /// user's exposure with the mirror point marked.
    fn placement(&self, state: &State, l: &Layout) -> Placement {
        Placement {
            mesh: (l.mesh_x, l.mesh_w, l.height),
            canvas: (l.canvas_x, l.canvas),
            mesh_scale: (state.exposure * self.env_summary.exposure) as f32,
            backdrop_scale: state.backdrop.scale(self.env_backdrop) as f32,
            summed: 1,
            canvas_scale: state.exposure as f32,
            marker: state.settings.canvas.mirror_point().map(|(cu, cv)| {
                let (x, y) = l.canvas_point(cu, cv);
                (x as f32, y as f32)
            }),
        }
    }

    /// Runs the tool panel, its dialogs and the BRDF graph (egui) on this frame's input, after asking
    /// the report worker to measure `m` (the panel shows the newest report it has). Only called
    /// once [`App::prepare_frame`] found a window and a state.
    fn run_panel(&mut self, l: &Layout, m: &Material, quality: &str) -> PanelFrame {
        let gpu = self.gpu.as_ref().expect("a frame is drawn with a window");
        let state = self.state.as_ref().expect("made with the window");
        let proxy = self.proxy.clone();
        let worker = self.report.get_or_insert_with(|| {
            report::ReportWorker::new(move || {
                // After the loop has closed nobody needs the report: the error is the answer.
                let _ = proxy.send_event(());
            })
        });
        worker.request(m);
        let report = worker.latest(m);
        let mut view = panel::ViewSettings {
            spp: self.spp,
            exposure: state.exposure,
            backdrop: state.backdrop,
            log_graph: state.log_graph,
        };
        let egui_state = self.egui_state.as_mut().expect("made in init");
        let raw_input = egui_state.take_egui_input(&gpu.window);
        let info = panel::Info {
            brush: state.brush,
            split: state.settings.split_lobes,
            report: report.map(|r| r.0),
            report_updating: report.is_none_or(|r| !r.1),
            timings: &self.timings,
            quality,
            frame_ms: (self.frame_ms.len() >= 2).then(|| {
                let recent = &self.frame_ms[self.frame_ms.len().saturating_sub(FRAME_RATE_WINDOW)..];
                (crate::measure::stats(recent).0, recent.len())
            }),
            status: &state.status,
        };
        let mut actions = panel::Actions::default();
        let curves = &self.curves.as_ref().expect("made before the panel").1;
        let (dialog, export_dialog) = (&mut self.dialog, &mut self.export_dialog);
        let output = self.egui_ctx.run(raw_input, |ctx| {
            actions = panel::show(ctx, m, &info, &mut view);
            panel::dialog(ctx, dialog, &mut actions);
            export_dialog.open |= std::mem::take(&mut actions.open_export);
            actions.export = export::show(ctx, export_dialog);
            graph::paint(ctx, curves, graph_rect(l, ctx.pixels_per_point()), view.log_graph);
        });
        egui_state.handle_platform_output(&gpu.window, output.platform_output);
        // A repaint the panel asks for (egui's delay; `Duration::MAX` means none).
        let delay = output.viewport_output.get(&egui::ViewportId::ROOT).map(|v| v.repaint_delay);
        self.egui_repaint = delay.and_then(|d| std::time::Instant::now().checked_add(d));
        let primitives = self.egui_ctx.tessellate(output.shapes, output.pixels_per_point);
        PanelFrame {
            actions,
            view,
            textures: output.textures_delta,
            primitives,
            pixels_per_point: output.pixels_per_point,
        }
    }

    /// Takes the view settings as the panel left them and titles the window with the brush, the
    /// mesh view's line (`quality`) and the status line.
    fn apply_view_settings(&mut self, view: panel::ViewSettings, quality: &str) {
        let gpu = self.gpu.as_ref().expect("a frame is drawn with a window");
        let state = self.state.as_mut().expect("made with the window");
        self.spp = view.spp.max(1);
        if view.backdrop != state.backdrop {
            // Through the input path, so the session keeps it as it keeps the keys' changes.
            self.pending.push_back(Input::SetBackdrop(view.backdrop));
        }
        (state.exposure, state.log_graph) = (view.exposure, view.log_graph);
        gpu.window.set_title(&format!("brdf-shop — {} — {quality} — {}", state.brush.name(), state.status));
    }

    /// Draws the frame on the GPU as decided, with the panel on top (read back for `--screenshot` in
    /// the last frame), and keeps what the views were rendered for once it is presented;
    /// a mesh view that waited for its pipelines is rendered again when they are built. Returns
    /// whether the frame was presented (a swapchain out of date asks for another frame).
    fn present(&mut self, d: &Decision, m: &Material, placement: Placement, panel: &PanelFrame) -> Result<bool> {
        let plan = Plan {
            material: m,
            mesh: d.mesh.clone(),
            canvas: d.canvas.clone(),
            placement,
            ui: (&panel.textures, &panel.primitives, panel.pixels_per_point),
            capture: self.opts.screenshot.is_some() && self.done,
        };
        let gpu = self.gpu.as_mut().expect("a frame is drawn with a window");
        match gpu.frame(&plan)? {
            Shown::Presented { pixels, mesh } => {
                self.mesh_waiting = mesh == Recorded::Waiting;
                let complete = gpu.renderer.tables_complete();
                self.note_tables(complete);
                // The views were drawn with the tables the frame had, whatever the decision saw.
                if !self.mesh_waiting {
                    self.mesh_key = Some(MeshKey { tables: complete, ..d.mesh_key.clone() });
                    if d.mesh.is_some() {
                        self.mesh_previewed = d.mesh_previewed;
                    }
                }
                if d.canvas.is_some() {
                    self.canvas_previewed = d.canvas_previewed;
                }
                self.canvas_key = Some(CanvasKey { tables: complete, ..d.canvas_key.clone() });
                if pixels.is_some() {
                    self.captured = pixels;
                }
                self.shown = true;
                Ok(true)
            }
            Shown::OutOfDate => {
                gpu.window.request_redraw();
                Ok(false)
            }
        }
    }
}
