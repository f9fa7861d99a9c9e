//! One editor frame: what must be re-rendered (the mesh view restarts on any change of what it
//! shows, previewed smaller when the frame budget asks, settles at full size and then refines while
//! nothing changes, or stays; the canvas only when the material or its light changed, or to
//! settle), the tool panel, and the GPU frame that composes and presents it.

use super::lighting::light_from;
use super::preview::{self, CanvasStep, MeshStep, Preview};
use super::state::Input;
use super::stats::FrameKind;
use super::view::{Plan, Shown};
use super::{export, graph, panel, report, App, FRAME_RATE_WINDOW, REFINE_MAX, REFINE_STEP};
use crate::error::Result;
use crate::render::compose::Placement;
use crate::render::{Estimator, Progress, Recorded, View};

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
}

impl App {
    /// What this frame renders: the mesh view restarts (any change of what it shows), refines
    /// (nothing changed, refinement on and not done) or stays; the canvas re-renders only when the
    /// material or its light changed. Views that change are previewed smaller when the frame budget
    /// asks (`preview`) and settled at full size in the first frame without a change.
    /// Returns what the frame drew, `None` when nothing was presented.
    pub(super) fn draw_frame(&mut self) -> Result<Option<Drawn>> {
        let (Some(gpu), Some(state)) = (self.gpu.as_mut(), self.state.as_mut()) else { return Ok(None) };
        let Some((w, h)) = gpu.swapchain_extent()? else { return Ok(None) }; // minimised
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
        let generation = state.history.generation();
        let light = state.settings.canvas.light;
        let mesh_settings = crate::render::Settings {
            width: l.mesh_w,
            height: l.height,
            spp: self.spp,
            estimator: Estimator::Key,
            view: View::Mesh,
            camera: state.camera(),
            light,
            intensity: state.settings.canvas.intensity,
            backdrop_blur: state.backdrop.blur,
        };
        let mesh_key = MeshKey {
            material: generation,
            scene: self.scene_generation,
            orbit: [state.yaw, state.pitch, state.distance, state.fov_deg],
            size: (l.mesh_w, l.height),
            spp: self.spp,
            blur: state.backdrop.blur.to_bits(),
        };
        let canvas_key = CanvasKey {
            material: generation,
            light: [light.x, light.y, light.z, state.settings.canvas.intensity],
            side: l.canvas,
        };
        let refining = !self.opts.quit || self.opts.converge;
        let refined = gpu.renderer.refined_samples();
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
            refine: refining && refined < REFINE_MAX,
        });
        let (mesh, kind) = match mesh_step {
            MeshStep::Preview => {
                let (width, height) = mesh_size;
                let preview = crate::render::Settings { width, height, ..mesh_settings.clone() };
                (Some((preview, Progress::Fresh)), FrameKind::Interaction)
            }
            MeshStep::Settle => (Some((mesh_settings.clone(), Progress::Fresh)), FrameKind::Settle),
            MeshStep::Refine => {
                // As many samples as the budget holds (`preview`), up to the step and the end.
                let spp = self.preview.refine_step(REFINE_STEP.min(REFINE_MAX - refined));
                let mis = crate::render::Settings { estimator: Estimator::Mis, spp, ..mesh_settings.clone() };
                (Some((mis, Progress::Refine)), FrameKind::Refinement)
            }
            MeshStep::Keep => (None, FrameKind::Unchanged),
        };
        let canvas = (canvas_step != CanvasStep::Keep).then(|| {
            let side = if canvas_step == CanvasStep::Preview { canvas_side } else { l.canvas };
            crate::render::Settings { width: side, height: side, view: View::Canvas, ..mesh_settings.clone() }
        });
        // What the mesh view shows (the panel's line); a frame that only settles the canvas is a
        // settle frame too (one that only previews it is not a frame of the mesh view's: unchanged).
        let mesh_kind = kind;
        let canvas_settles = canvas_step == CanvasStep::Settle;
        let kind = if kind == FrameKind::Unchanged && canvas_settles { FrameKind::Settle } else { kind };
        let mesh_previewed = mesh_changed && mesh_size != (l.mesh_w, l.height);
        let canvas_previewed = canvas_changed && canvas_side != l.canvas;
        // The scales the views were rendered at: the preview model learns only from frames whose
        // views all had one scale, and refinement's from frames that rendered no canvas.
        let mesh_scale = if mesh_changed { scale } else { 1.0 };
        let canvas_scale = if canvas_changed { scale } else { 1.0 };
        let one_scale = canvas.is_none() || mesh.is_none() || mesh_scale == canvas_scale;
        let m = state.material().clone();
        if self.curves.as_ref().is_none_or(|c| c.0 != canvas_key) {
            self.curves = Some((canvas_key.clone(), graph::Curves::new(&m, light)));
        }
        let placement = Placement {
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
        };
        // The tool panel and the graph: egui on this frame's input; what the user did is applied after.
        let proxy = self.proxy.clone();
        let worker = self.report.get_or_insert_with(|| {
            report::ReportWorker::new(move || {
                // After the loop has closed nobody needs the report: the error is the answer.
                let _ = proxy.send_event(());
            })
        });
        worker.request(&m);
        let report = worker.latest(&m);
        let mesh_spp = mesh.as_ref().map_or(0, |m| m.0.spp);
        let shown_refined = if mesh_kind == FrameKind::Refinement {
            refined + mesh_spp
        } else if matches!(mesh_kind, FrameKind::Interaction | FrameKind::Settle) {
            0
        } else {
            refined
        };
        let quality = if self.mesh_waiting && kind == FrameKind::Interaction {
            "mesh view: building the new lobe's shader…".to_string()
        } else if mesh_previewed {
            format!("mesh view: key {} spp, preview at {:.0} %", self.spp, scale * 100.0)
        } else if shown_refined == 0 {
            format!("mesh view: key {} spp", self.spp)
        } else {
            format!("mesh view: mis {shown_refined} spp")
        };
        let mut spp = self.spp;
        let (mut exposure, mut log_graph, mut backdrop) = (state.exposure, state.log_graph, state.backdrop);
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
        let curves = &self.curves.as_ref().expect("made above").1;
        let dialog = &mut self.dialog;
        let export_dialog = &mut self.export_dialog;
        let output = self.egui_ctx.run(raw_input, |ctx| {
            actions = panel::show(ctx, &m, &info, &mut spp, &mut exposure, &mut backdrop, &mut log_graph);
            panel::dialog(ctx, dialog, &mut actions);
            export_dialog.open |= std::mem::take(&mut actions.open_export);
            actions.export = export::show(ctx, export_dialog);
            let ppp = ctx.pixels_per_point();
            let rect = egui::Rect::from_min_max(
                egui::pos2(l.canvas_x as f32 / ppp, l.graph_y.min(l.height) as f32 / ppp),
                egui::pos2(l.width as f32 / ppp, l.height as f32 / ppp),
            );
            graph::paint(ctx, curves, rect, log_graph);
        });
        egui_state.handle_platform_output(&gpu.window, output.platform_output);
        // A repaint the panel asks for (egui's delay; `Duration::MAX` means none).
        let delay = output.viewport_output.get(&egui::ViewportId::ROOT).map(|v| v.repaint_delay);
        self.egui_repaint = delay.and_then(|d| std::time::Instant::now().checked_add(d));
        let primitives = self.egui_ctx.tessellate(output.shapes, output.pixels_per_point);
        self.spp = spp.max(1);
        if backdrop != state.backdrop {
            // Through the input path, so the session keeps it as it keeps the keys' changes.
            self.pending.push_back(Input::SetBackdrop(backdrop));
        }
        (state.exposure, state.log_graph) = (exposure, log_graph);
        gpu.window.set_title(&format!("brdf-shop — {} — {quality} — {}", state.brush.name(), state.status));
        let capture = self.opts.screenshot.is_some() && self.done;
        let plan = Plan {
            material: &m,
            mesh,
            canvas,
            placement,
            ui: (&output.textures_delta, &primitives, output.pixels_per_point),
            capture,
        };
        let mesh_planned = plan.mesh.is_some();
        let canvas_planned = plan.canvas.is_some();
        let shown = gpu.frame(&plan)?;
        let presented = match shown {
            Shown::Presented { pixels, mesh } => {
                // A mesh view that waited for its pipelines is rendered again when they are built.
                let mesh_waiting = mesh == Recorded::Waiting;
                self.mesh_waiting = mesh_waiting;
                if !mesh_waiting {
                    self.mesh_key = Some(mesh_key);
                    if mesh_planned {
                        self.mesh_previewed = mesh_previewed;
                    }
                }
                if canvas_planned {
                    self.canvas_previewed = canvas_previewed;
                }
                self.canvas_key = Some(canvas_key);
                if pixels.is_some() {
                    self.captured = pixels;
                }
                self.shown = true;
                true
            }
            Shown::OutOfDate => {
                gpu.window.request_redraw();
                false
            }
        };
        self.apply_panel(actions)?;
        let kind = match kind {
            _ if presented && self.mesh_waiting => FrameKind::Waiting,
            k => k,
        };
        // The frames that rendered the mesh view's `key` image at one scale time the preview's model.
        let waited = presented && self.mesh_waiting;
        let sample = mesh_planned && !waited && one_scale && matches!(kind, FrameKind::Interaction | FrameKind::Settle);
        let scale = if mesh_planned { mesh_scale } else { canvas_scale };
        let refine_sample = kind == FrameKind::Refinement && !canvas_planned;
        let spp = if waited { 0 } else { mesh_spp };
        Ok(presented.then_some(Drawn { kind, scale, sample, refine_sample, spp }))
    }
}
