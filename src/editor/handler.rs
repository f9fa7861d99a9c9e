//! The winit side: window events become [`Input`]s (every key included) handled by
//! `State::handle` through `App::handle`; replayed inputs and the scripted window changes are fed
//! between frames; idle windows refine the mesh view and otherwise sleep (no redraw is requested).

use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{Key, ModifiersState};
use winit::window::WindowId;

use super::state::Input;
use super::{App, WindowStep, WindowWait, MINIMISED_HOLD, MINIMISED_POLL, MINIMISE_WAIT, REFINE_MAX};
use crate::brush::BrushKind;

/// The input a key press means, if any.
pub fn key_input(key: &Key, mods: ModifiersState) -> Option<Input> {
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
        ("g", false) => Input::ToggleLogGraph,
        ("+" | "=", false) => Input::Exposure(true),
        ("-", false) => Input::Exposure(false),
        ("r", false) => Input::Restore,
        ("b", false) => Input::ToggleBackdrop,
        ("]", false) => Input::BackdropBlur(true),
        ("[", false) => Input::BackdropBlur(false),
        (".", false) => Input::BackdropBrightness(true),
        (",", false) => Input::BackdropBrightness(false),
        _ => return None,
    })
}

impl ApplicationHandler for App {
    /// A report finished on the worker thread: show it.
    fn user_event(&mut self, _el: &ActiveEventLoop, _event: ()) {
        self.request_redraw();
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
            // (Not for the redraw itself: that would redraw forever.)
            if r.repaint && !matches!(event, WindowEvent::RedrawRequested) {
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
            WindowEvent::Resized(s) => {
                if let Some(g) = self.gpu.as_mut() {
                    if let Err(e) = g.resized((s.width, s.height)) {
                        self.fail(el, e);
                        return;
                    }
                }
                Input::Resized(s.width, s.height)
            }
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                Input::Modifiers { shift: self.modifiers.shift_key() }
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
                match key_input(&event.logical_key, self.modifiers) {
                    Some(i) => i,
                    None => return,
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
        // Replayed inputs go through the same handler, one stroke per turn of the loop; a script
        // (strokes, drops, window changes) goes on once the mesh view shows the last step, not while
        // it waits for a lobe pipeline built in the background (the build's end wakes the loop).
        if !self.pending.is_empty() && !self.mesh_waiting {
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
            self.request_redraw();
            return;
        }
        el.set_control_flow(ControlFlow::Wait);
        if !self.mesh_waiting && self.window_script_turn(el) {
            return;
        }
        // A minimised window draws nothing and does not refine (nor quit: a `--screenshot` waits
        // for the window to come back). It looks every quarter second whether it was restored, and
        // then redraws: the expose that comes with the restore may arrive before the window manager
        // has cleared the hidden state, and that redraw was skipped.
        if self.shown && self.minimised() {
            self.restore_redraw = true;
            el.set_control_flow(ControlFlow::wait_duration(MINIMISED_POLL));
            return;
        }
        if std::mem::take(&mut self.restore_redraw) {
            self.request_redraw();
        }
        // A repaint the tool panel asked for (an animation, a blinking cursor), when it is due.
        if let Some(at) = self.egui_repaint {
            if at <= Instant::now() {
                self.egui_repaint = None;
                self.request_redraw();
            } else {
                el.set_control_flow(ControlFlow::WaitUntil(at));
            }
        }
        // A mesh view waiting for a lobe pipeline, or views drawn while a compensation table was
        // baking, are drawn again when the build or the bake wakes the loop (`user_event`); until
        // then they neither refine nor quit.
        if self.mesh_waiting || self.tables_pending.is_some() {
            return;
        }
        // Idle: first render the previewed views at full size (a light dragged on a refined view
        // previews the canvas alone, and nothing else would ask for that frame) — once no button is
        // held: a pause in a drag waits for the next event (`preview::steps`).
        if self.shown && (self.mesh_previewed || self.canvas_previewed) {
            if !self.state.as_ref().is_some_and(|s| s.dragging()) {
                self.request_redraw();
            }
            return;
        }
        // Then refine the mesh view (not while replaying for a screenshot, which shows the fast
        // image); once refined, nothing is requested and the loop sleeps until the next event.
        let refined = self.gpu.as_ref().map_or(0, |g| g.renderer.refined_samples());
        if (!self.opts.quit || self.opts.converge) && self.shown && refined < REFINE_MAX {
            self.request_redraw();
            return;
        }
        if self.opts.quit && self.shown {
            // One frame after the last input (captured for `--screenshot`), then out.
            self.done = true;
            if let Err(e) = self.draw() {
                self.fail(el, e);
                return;
            }
            el.exit();
        }
    }
}

impl App {
    /// The scripted window changes (`--resize`, `--minimise`), one per turn after a frame was
    /// shown. A minimise or restore is the window manager's to do in its own time: the script
    /// looks again every 20 ms until it is done (or `MINIMISE_WAIT` has passed: one stderr line,
    /// the session goes on); a minimised window stays so for `MINIMISED_HOLD` and is asked to
    /// redraw, which must draw nothing. Returns whether this turn was the script's.
    fn window_script_turn(&mut self, el: &ActiveEventLoop) -> bool {
        let poll = ControlFlow::wait_duration(Duration::from_millis(20));
        match self.window_wait {
            Some(WindowWait::Manager { minimised, since }) => {
                if self.minimised() == minimised {
                    self.request_redraw();
                    self.window_wait = minimised.then(|| WindowWait::Hold(Instant::now() + MINIMISED_HOLD));
                } else if since.elapsed() < MINIMISE_WAIT {
                    el.set_control_flow(poll);
                } else {
                    self.window_wait = None;
                    self.request_redraw();
                    eprintln!(
                        "brdf-shop: --minimise: the window was not {} within {} s (is a window manager running?)",
                        if minimised { "minimised" } else { "restored" },
                        MINIMISE_WAIT.as_secs()
                    );
                }
                return true;
            }
            Some(WindowWait::Hold(until)) if Instant::now() < until => {
                el.set_control_flow(ControlFlow::WaitUntil(until));
                return true;
            }
            Some(WindowWait::Hold(_)) => self.window_wait = None,
            None => {}
        }
        if !self.shown {
            return false;
        }
        let (Some(step), Some(g)) = (self.window_script.front().copied(), self.gpu.as_ref()) else { return false };
        self.window_script.pop_front();
        match step {
            WindowStep::Resize(w, h) => {
                let _ = g.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                self.request_redraw();
            }
            WindowStep::Minimise(minimised) => {
                g.window.set_minimized(minimised);
                self.window_wait = Some(WindowWait::Manager { minimised, since: Instant::now() });
                el.set_control_flow(poll);
            }
        }
        true
    }
}
