//! The editor's state and what each input does to it, without any window or GPU: the material with
//! its undo history, the brush and the stroke being painted, the canvas light, the orbit camera and
//! the window's [`Layout`]. The window code turns winit events into [`Input`]s; `--replay`
//! synthesises the same [`Input`]s from a strokes file, so both go through [`State::handle`].

use std::path::PathBuf;

use glam::DVec3;

use crate::brdf::Material;
use crate::brush::canvas::{normal_at, Canvas};
use crate::brush::history::History;
use crate::brush::strokes::{apply, BrushKind, Stroke};
use crate::brush::Settings;
use crate::export::Format;
use crate::layout::Layout;
use crate::scene::Camera;

use super::backdrop::{Backdrop, BLUR_RANGE};

/// A user action, from the window or synthesised.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    CursorMoved(f64, f64),
    /// Left (`right == false`) or right button.
    Button {
        pressed: bool,
        right: bool,
    },
    Scroll(f64),
    Brush(BrushKind),
    /// Pick the lobe strokes act on (the lobe list); `None`: the one under the brush.
    SelectLobe(Option<usize>),
    Undo,
    Redo,
    ToggleSplit,
    ResetLight,
    FrameView,
    Save,
    /// Save the material to this path (the *Save as…* dialog).
    SaveAs(PathBuf),
    /// Export the material in this format to this path (the *Export…* dialog, `--export`).
    Export(Format, PathBuf),
    Resized(u32, u32),
    /// A file dropped on the window or picked in the *Open…* dialog: environment, mesh or material.
    Dropped(PathBuf),
    /// Linear or log scale of the BRDF graph (G).
    ToggleLogGraph,
    /// Exposure of both views ×1.25 (`true`, + or =) or ÷1.25 (−).
    Exposure(bool),
    /// Bring back the last session's unsaved material, when one was found (R).
    Restore,
    /// Whether Shift is held (a left drag on the mesh view then turns the environment).
    Modifiers {
        shift: bool,
    },
    /// Turn the environment about the up axis by this many degrees (a Shift-drag, `--env-rotation`).
    TurnEnv(f64),
    /// The backdrop: the map or black (B), blurred more or less (`]`, `[`), brighter or darker
    /// (`.`, `,`), or set whole (the panel).
    ToggleBackdrop,
    BackdropBlur(bool),
    BackdropBrightness(bool),
    SetBackdrop(Backdrop),
}

/// What the window must do after an input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Effect {
    pub redraw: bool,
    pub material_changed: bool,
    pub save: bool,
    /// Save to this path instead of `--out`.
    pub save_as: Option<PathBuf>,
    pub load: Option<PathBuf>,
    /// Export the material (format, path).
    pub export: Option<(Format, PathBuf)>,
    /// A stroke that could not be applied, for the status line.
    pub message: Option<String>,
    /// The environment was turned: the renderer takes the turned map.
    pub env_turned: bool,
    /// The session's view settings (the turn, the backdrop) changed: they are saved.
    pub session_changed: bool,
}

/// The orbit camera's starting elevation: the torus seen from a little above, as in the paper.
pub const DEFAULT_PITCH: f64 = 0.45;

/// The room the orbit camera leaves around the mesh at zoom 1: the unit sphere (every mesh is
/// scaled into it) grown by this factor just fits the mesh view's narrower extent
/// ([`crate::scene::camera::fit_distance`]), at every window size and aspect.
pub const FRAME_MARGIN: f64 = 1.25;

/// The closest and furthest the orbit camera comes to the mesh's centre (a zoom keeps within them).
pub const DISTANCE_RANGE: (f64, f64) = (1.2, 50.0);

enum Drag {
    None,
    Stroke(Stroke),
    Orbit {
        last: (f64, f64),
    },
    /// Shift-drag on the mesh view: the environment turns with the cursor.
    TurnEnv {
        last: f64,
    },
    Light,
}

/// Degrees the environment turns per pixel of a Shift-drag: a drag across a 720-pixel view turns
/// it about once around.
pub const TURN_DEG_PER_PIXEL: f64 = 0.5;

pub struct State {
    pub history: History,
    pub settings: Settings,
    pub brush: BrushKind,
    pub lobe: Option<usize>,
    pub layout: Layout,
    /// Orbit camera: yaw and pitch in radians, distance to the target ([`State::refit`]: the
    /// framing distance of the mesh view times `zoom`).
    pub yaw: f64,
    pub pitch: f64,
    pub distance: f64,
    /// The wheel's zoom: 1 frames the mesh ([`FRAME_MARGIN`]); above 1 the camera is further out.
    pub zoom: f64,
    pub fov_deg: f64,
    /// The light the canvas starts with (the environment's brightest direction seen by the camera).
    pub default_light: DVec3,
    /// The user moved the canvas light (right button); until reset, it stays where they put it
    /// instead of following the environment's brightest direction as the camera orbits.
    pub light_moved: bool,
    cursor: (f64, f64),
    drag: Drag,
    pub status: String,
    /// The BRDF graph's scale.
    pub log_graph: bool,
    /// The user's exposure factor on both views (the mesh view's auto exposure times this).
    pub exposure: f64,
    /// The last session's unsaved material, offered back until restored (R) or replaced.
    pub recovered: Option<Material>,
    /// The environment's turn about the up axis (degrees, in [0, 360)).
    pub env_rotation: f64,
    /// What the mesh view shows behind the object.
    pub backdrop: Backdrop,
    shift: bool,
}

impl State {
    /// A mouse button is held over a view (a stroke, an orbit or the canvas light being dragged).
    pub fn dragging(&self) -> bool {
        !matches!(self.drag, Drag::None)
    }

    pub fn new(material: Material, settings: Settings, layout: Layout) -> State {
        let default_light = settings.canvas.light;
        let mut state = State {
            history: History::new(material),
            settings,
            brush: BrushKind::Create,
            lobe: None,
            layout,
            yaw: 0.0,
            pitch: DEFAULT_PITCH,
            distance: 0.0,
            zoom: 1.0,
            fov_deg: 30.0,
            default_light,
            light_moved: false,
            cursor: (0.0, 0.0),
            drag: Drag::None,
            status: String::new(),
            log_graph: false,
            exposure: 1.0,
            recovered: None,
            env_rotation: 0.0,
            backdrop: Backdrop::default(),
            shift: false,
        };
        state.refit();
        state
    }

    /// Sets the orbit distance from the mesh view's aspect and the zoom: the mesh fits both extents
    /// of the view at zoom 1, whatever the window's size.
    pub fn refit(&mut self) {
        let aspect = self.layout.mesh_w as f64 / self.layout.height.max(1) as f64;
        let framed = crate::scene::camera::fit_distance(self.fov_deg, aspect, 1.0, FRAME_MARGIN);
        let (near, far) = DISTANCE_RANGE;
        self.zoom = self.zoom.clamp(near / framed, far / framed);
        self.distance = framed * self.zoom;
    }

    pub fn material(&self) -> &Material {
        self.history.current()
    }

    /// The mesh camera of the orbit.
    pub fn camera(&self) -> Camera {
        let (cy, sy) = (self.yaw.cos(), self.yaw.sin());
        let (cp, sp) = (self.pitch.cos(), self.pitch.sin());
        let eye = DVec3::new(sy * cp, sp, cy * cp) * self.distance;
        Camera { eye, target: DVec3::ZERO, up: DVec3::Y, fov_deg: self.fov_deg }
    }

    /// What `input` does to the state, and what the window must do after it.
    pub fn handle(&mut self, input: Input) -> Effect {
        let mut fx = Effect::default();
        match input {
            Input::CursorMoved(..) | Input::Button { .. } | Input::Scroll(_) => return self.handle_pointer(input),
            Input::Brush(b) => {
                self.brush = b;
                self.status = format!("brush: {}", b.name());
                fx.redraw = true;
            }
            Input::SelectLobe(k) => self.lobe = k,
            Input::Undo => {
                fx.material_changed = self.history.undo();
                fx.redraw = fx.material_changed;
            }
            Input::Redo => {
                fx.material_changed = self.history.redo();
                fx.redraw = fx.material_changed;
            }
            Input::ToggleSplit => {
                self.settings.split_lobes = !self.settings.split_lobes;
                self.status = format!("split lobes {}", if self.settings.split_lobes { "on" } else { "off" });
                fx.redraw = true;
            }
            Input::ResetLight => {
                self.settings.canvas.light = self.default_light;
                self.light_moved = false;
                fx.redraw = true;
            }
            Input::FrameView => {
                (self.yaw, self.pitch, self.zoom) = (0.0, DEFAULT_PITCH, 1.0);
                self.refit();
                fx.redraw = true;
            }
            Input::Save => fx.save = true,
            Input::Resized(w, h) => {
                self.layout = Layout::new(w.max(1), h.max(1));
                self.refit();
                fx.redraw = true;
            }
            Input::SaveAs(p) => fx.save_as = Some(p),
            Input::Export(f, p) => fx.export = Some((f, p)),
            Input::Dropped(p) => fx.load = Some(p),
            Input::ToggleLogGraph => {
                self.log_graph = !self.log_graph;
                fx.redraw = true;
            }
            Input::Exposure(up) => {
                self.exposure = if up { self.exposure * 1.25 } else { self.exposure / 1.25 }.clamp(1e-4, 1e4);
                fx.redraw = true;
            }
            Input::Modifiers { .. }
            | Input::TurnEnv(_)
            | Input::ToggleBackdrop
            | Input::BackdropBlur(_)
            | Input::BackdropBrightness(_)
            | Input::SetBackdrop(_) => return self.handle_view(input),
            Input::Restore => {
                if let Some(m) = self.recovered.take() {
                    self.history.push(m);
                    self.status = "restored the last session's material".into();
                    fx.material_changed = true;
                    fx.redraw = true;
                }
            }
        }
        fx
    }

    /// The pointer's inputs: a move carries on the drag in progress, a press over a view starts one
    /// (on the canvas a stroke with the left button, the light with the right; on the mesh view an
    /// orbit, or with Shift the environment's turn), a release ends it, the wheel zooms the mesh view.
    fn handle_pointer(&mut self, input: Input) -> Effect {
        let mut fx = Effect::default();
        match input {
            Input::CursorMoved(x, y) => return self.cursor_moved(x, y),
            Input::Button { pressed: true, right: false } => {
                let (x, y) = self.cursor;
                if self.layout.in_canvas(x, y) {
                    let (cu, cv) = self.layout.canvas_coords(x, y);
                    self.drag = Drag::Stroke(Stroke { brush: self.brush, points: vec![[cu, cv]], lobe: self.lobe });
                } else if self.layout.in_mesh(x, y) && self.shift {
                    self.drag = Drag::TurnEnv { last: x };
                } else if self.layout.in_mesh(x, y) {
                    self.drag = Drag::Orbit { last: (x, y) };
                }
            }
            Input::Button { pressed: true, right: true } => {
                let (x, y) = self.cursor;
                if self.layout.in_canvas(x, y) {
                    self.drag = Drag::Light;
                    fx.redraw |= self.set_light_at(x, y);
                }
            }
            Input::Button { pressed: false, .. } => return self.release(),
            Input::Scroll(d) if self.layout.in_mesh(self.cursor.0, self.cursor.1) => {
                self.zoom *= 1.0 - 0.1 * d;
                self.refit();
                fx.redraw = true;
            }
            // A scroll outside the mesh view does nothing.
            _ => {}
        }
        fx
    }

    /// The cursor moved to `(x, y)`: the stroke takes the point, the orbit turns the camera, a
    /// Shift-drag turns the environment, a dragged light follows.
    fn cursor_moved(&mut self, x: f64, y: f64) -> Effect {
        let mut fx = Effect::default();
        self.cursor = (x, y);
        match &mut self.drag {
            Drag::Stroke(st) => {
                let (cu, cv) = self.layout.canvas_coords(x, y);
                st.points.push([cu, cv]);
            }
            Drag::Orbit { last } => {
                let (dx, dy) = (x - last.0, y - last.1);
                *last = (x, y);
                self.yaw -= dx * 0.01;
                self.pitch = (self.pitch + dy * 0.01).clamp(-1.5, 1.5);
                fx.redraw = true;
            }
            Drag::TurnEnv { last } => {
                let dx = x - *last;
                *last = x;
                return self.turn_env(dx * TURN_DEG_PER_PIXEL);
            }
            Drag::Light => {
                fx.redraw |= self.set_light_at(x, y);
            }
            Drag::None => {}
        }
        fx
    }

    /// A button was released: the drag ends, and a stroke is applied to the material (a history
    /// step), or why it cannot be becomes the status line.
    fn release(&mut self) -> Effect {
        let mut fx = Effect::default();
        if let Drag::Stroke(st) = std::mem::replace(&mut self.drag, Drag::None) {
            match apply(self.material(), &self.settings, &st) {
                Ok(m) => {
                    self.history.push(m);
                    self.status = format!("{} applied", st.brush.name());
                    fx.material_changed = true;
                    fx.redraw = true;
                }
                Err(e) => {
                    self.status = format!("{}: {e}", st.brush.name());
                    fx.message = Some(self.status.clone());
                    fx.redraw = true;
                }
            }
        }
        fx
    }

    /// The inputs that change the session's view settings: the environment's turn and the backdrop.
    fn handle_view(&mut self, input: Input) -> Effect {
        let b = self.backdrop;
        let backdrop = match input {
            Input::Modifiers { shift } => {
                self.shift = shift;
                return Effect::default();
            }
            Input::TurnEnv(deg) => return self.turn_env(deg),
            Input::ToggleBackdrop => Backdrop { shown: !b.shown, ..b },
            Input::BackdropBlur(more) => Backdrop { blur: b.blur + if more { 0.5 } else { -0.5 }, ..b },
            Input::BackdropBrightness(up) => Backdrop { brightness: b.brightness * if up { 1.25 } else { 0.8 }, ..b },
            Input::SetBackdrop(new) => new,
            _ => return Effect::default(),
        };
        self.backdrop = backdrop.clamped();
        let shown = if self.backdrop.shown { "the map" } else { "black" };
        self.status = format!(
            "backdrop: {shown}, brightness ×{:.2}, blur {:.1} (of {}–{})",
            self.backdrop.brightness, self.backdrop.blur, BLUR_RANGE.0, BLUR_RANGE.1
        );
        Effect { redraw: true, session_changed: self.backdrop != b, ..Effect::default() }
    }

    /// Turns the environment by `deg` degrees about the up axis.
    fn turn_env(&mut self, deg: f64) -> Effect {
        if !deg.is_finite() || deg == 0.0 {
            return Effect::default();
        }
        self.env_rotation = (self.env_rotation + deg).rem_euclid(360.0);
        self.status = format!("environment turned to {:.1}°", self.env_rotation);
        Effect { redraw: true, env_turned: true, session_changed: true, ..Effect::default() }
    }

    /// Points the canvas light at the sphere normal under `(x, y)`; false off the sphere.
    fn set_light_at(&mut self, x: f64, y: f64) -> bool {
        let (cu, cv) = self.layout.canvas_coords(x, y);
        match normal_at(cu, cv).and_then(|n| Canvas::new(n, self.settings.canvas.intensity)) {
            Some(c) => {
                self.settings.canvas = c;
                self.light_moved = true;
                true
            }
            None => false,
        }
    }
}

/// The inputs that paint `stroke` through the window: pick its brush (and lobe), move to its first
/// point, press, move through the others, release.
pub fn stroke_inputs(layout: &Layout, stroke: &Stroke) -> Vec<Input> {
    let mut out = vec![Input::Brush(stroke.brush), Input::SelectLobe(stroke.lobe)];
    for (i, p) in stroke.points.iter().enumerate() {
        let (x, y) = layout.canvas_point(p[0], p[1]);
        out.push(Input::CursorMoved(x, y));
        if i == 0 {
            out.push(Input::Button { pressed: true, right: false });
        }
    }
    out.push(Input::Button { pressed: false, right: false });
    out
}
