//! Preview frames: while the user paints, orbits or moves the light, the views that change are
//! rendered at a fraction of their size — the largest of [`LEVELS`] at which the frame is predicted
//! to fit the frame budget — and magnified by the compose pass; the first frame in which nothing
//! changes renders them at full size (a settle frame), and refinement follows. The prediction comes
//! from the frames just finished: each gives its wall time and the GPU time of the passes whose
//! pixels scale, `wall = fixed + per_pixel_share · scale²`.
//!
//! Refinement frames keep to the same budget by the samples they add (at most `REFINE_STEP`):
//! `wall = fixed + per_sample · samples`, from the refinement frames just finished; the first adds
//! one sample. A stroke that starts while the view refines waits for the frames in flight, so on a
//! slow device a 16-sample frame at window size would be a stall of seconds.

use std::collections::VecDeque;

/// The linear scales a preview may take (1: full size). A few fixed steps, so the preview's targets
/// are remade only when the step changes, not every frame.
pub const LEVELS: [f64; 7] = [1.0, 0.875, 0.75, 0.625, 0.5, 0.375, 0.25];

/// The default frame budget (ms): 20 frames a second while the user interacts.
pub const DEFAULT_BUDGET_MS: f64 = 50.0;

/// How many recent frames the prediction takes the median of.
const WINDOW: usize = 5;

/// A larger scale is taken only when predicted within this share of the budget (so the scale does
/// not flip between two steps on the budget's edge).
const GROW_MARGIN: f64 = 0.8;

/// Chooses the scale of interaction frames.
#[derive(Clone, Debug)]
pub struct Preview {
    /// Milliseconds a frame may take; 0 turns previews off (every frame full size).
    budget_ms: f64,
    level: usize,
    /// Recent frames: (wall ms outside the scaled passes, the scaled passes' GPU ms at scale 1).
    seen: VecDeque<(f64, f64)>,
    /// Recent refinement frames: (wall ms outside the sampling pass, its GPU ms a sample).
    refined: VecDeque<(f64, f64)>,
}

impl Preview {
    pub fn new(budget_ms: f64) -> Preview {
        Preview { budget_ms, level: 0, seen: VecDeque::new(), refined: VecDeque::new() }
    }

    /// The linear scale of the next interaction frame's views.
    pub fn scale(&self) -> f64 {
        LEVELS[self.level]
    }

    /// A view of `size` at `scale` (each side at least 1 pixel).
    pub fn size(size: (u32, u32), scale: f64) -> (u32, u32) {
        let side = |s: u32| ((s as f64 * scale).round() as u32).clamp(1, s.max(1));
        (side(size.0), side(size.1))
    }

    /// A finished frame whose views were rendered at `scale`: its wall time and the GPU time of its
    /// passes that scale with the views' pixels (ms). Chooses the next interaction frame's scale.
    pub fn observe(&mut self, scale: f64, wall_ms: f64, scaled_ms: f64) {
        if self.budget_ms <= 0.0 || !(scale > 0.0) || !usable(wall_ms) || !usable(scaled_ms) {
            return;
        }
        remember(&mut self.seen, ((wall_ms - scaled_ms).max(0.0), scaled_ms / (scale * scale)));
        let (fixed, full) = medians(&self.seen);
        let predicted = |level: usize| fixed + full * LEVELS[level] * LEVELS[level];
        let fits =
            |level: usize| predicted(level) <= self.budget_ms * if level < self.level { GROW_MARGIN } else { 1.0 };
        self.level = (0..LEVELS.len()).find(|&l| fits(l)).unwrap_or(LEVELS.len() - 1);
    }

    /// A finished refinement frame: its wall time, its sampling pass's GPU time and the samples it
    /// added. Sets what [`Preview::refine_step`] answers.
    pub fn observe_refinement(&mut self, wall_ms: f64, sampling_ms: f64, samples: u32) {
        if self.budget_ms <= 0.0 || samples == 0 || !usable(wall_ms) || !usable(sampling_ms) {
            return;
        }
        remember(&mut self.refined, ((wall_ms - sampling_ms).max(0.0), sampling_ms / samples as f64));
    }

    /// The samples the next refinement frame adds, at most `most` (≥ 1): as many as the budget
    /// holds by the refinement frames just finished, at least one; one before any was timed; `most`
    /// without a budget.
    pub fn refine_step(&self, most: u32) -> u32 {
        let most = most.max(1);
        if self.budget_ms <= 0.0 {
            return most;
        }
        if self.refined.is_empty() {
            return 1;
        }
        let (fixed, per_sample) = medians(&self.refined);
        let fit = if per_sample > 0.0 { ((self.budget_ms - fixed) / per_sample).floor() } else { most as f64 };
        if fit.is_nan() {
            return 1;
        }
        fit.clamp(1.0, most as f64) as u32
    }
}

/// A time a model can learn from: a finite number of milliseconds, not negative.
fn usable(ms: f64) -> bool {
    ms.is_finite() && ms >= 0.0
}

/// Adds an observation, keeping the last [`WINDOW`].
fn remember(seen: &mut VecDeque<(f64, f64)>, observation: (f64, f64)) {
    seen.push_back(observation);
    while seen.len() > WINDOW {
        seen.pop_front();
    }
}

/// The medians of both members of recent observations.
fn medians(seen: &VecDeque<(f64, f64)>) -> (f64, f64) {
    let a: Vec<f64> = seen.iter().map(|s| s.0).collect();
    let b: Vec<f64> = seen.iter().map(|s| s.1).collect();
    (crate::measure::stats(&a).0, crate::measure::stats(&b).0)
}

/// What a frame does with the mesh view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshStep {
    /// It changed: render it at the preview's scale.
    Preview,
    /// It shows a preview and nothing changed: render it at full size.
    Settle,
    /// It is settled and not fully refined: add samples.
    Refine,
    /// Show what it shows.
    Keep,
}

/// What a frame does with the canvas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CanvasStep {
    Preview,
    Settle,
    Keep,
}

/// What changed and what is shown, for [`steps`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Situation {
    pub mesh_changed: bool,
    pub canvas_changed: bool,
    /// The views show previews.
    pub mesh_previewed: bool,
    pub canvas_previewed: bool,
    /// A mouse button is held (a stroke, an orbit or a light being dragged): a pause in the drag is
    /// not the end of it, so previews are not settled and refinement does not start over them.
    pub holding: bool,
    /// The mesh view should refine (idle, refinement on, not done).
    pub refine: bool,
}

/// What a frame does with each view: a change previews the view; a previewed view settles at full
/// size once nothing changes and no button is held; a settled mesh view refines.
pub fn steps(s: Situation) -> (MeshStep, CanvasStep) {
    let mesh = if s.mesh_changed {
        MeshStep::Preview
    } else if s.mesh_previewed {
        if s.holding {
            MeshStep::Keep
        } else {
            MeshStep::Settle
        }
    } else if s.refine {
        MeshStep::Refine
    } else {
        MeshStep::Keep
    };
    let canvas = if s.canvas_changed {
        CanvasStep::Preview
    } else if s.canvas_previewed && !s.holding {
        CanvasStep::Settle
    } else {
        CanvasStep::Keep
    };
    (mesh, canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_over_budget_shrinks_the_preview_until_it_fits() {
        let mut p = Preview::new(50.0);
        assert_eq!(p.scale(), 1.0);
        // 200 ms of scaled passes and 20 ms besides: 20 + 200 s² ≤ 50 first at s = 0.375 (48.1 ms).
        p.observe(1.0, 220.0, 200.0);
        assert_eq!(p.scale(), 0.375);
        // Frames at that scale that cost what the model says keep it.
        for _ in 0..10 {
            p.observe(0.375, 20.0 + 200.0 * 0.375 * 0.375, 200.0 * 0.375 * 0.375);
            assert_eq!(p.scale(), 0.375);
        }
    }

    #[test]
    fn a_fast_device_stays_at_full_size_and_a_slow_one_at_the_smallest_step() {
        let mut fast = Preview::new(50.0);
        fast.observe(1.0, 2.0, 1.5);
        assert_eq!(fast.scale(), 1.0);
        let mut slow = Preview::new(50.0);
        // Even the smallest step (20 + 2000/16 = 145 ms) misses the budget: take it anyway.
        slow.observe(1.0, 2020.0, 2000.0);
        assert_eq!(slow.scale(), 0.25);
    }

    #[test]
    fn the_scale_grows_back_only_with_room_to_spare() {
        let mut p = Preview::new(50.0);
        p.observe(1.0, 220.0, 200.0);
        assert_eq!(p.scale(), 0.375);
        // The scaled passes become 4× cheaper (a simpler material): 20 + 50 s² ≤ 50 at s = 0.75
        // (48.1 ms), which is within the budget but not within 80 % of it; 0.625 (39.5) is.
        for _ in 0..WINDOW {
            p.observe(0.375, 20.0 + 50.0 * 0.375 * 0.375, 50.0 * 0.375 * 0.375);
        }
        assert_eq!(p.scale(), 0.625);
    }

    #[test]
    fn a_zero_budget_or_a_meaningless_time_changes_nothing() {
        let mut off = Preview::new(0.0);
        off.observe(1.0, 5000.0, 4900.0);
        assert_eq!(off.scale(), 1.0);
        let mut p = Preview::new(50.0);
        for (s, wall, scaled) in
            [(1.0, f64::NAN, 1.0), (1.0, 10.0, -1.0), (0.0, 300.0, 200.0), (1.0, f64::INFINITY, 1.0)]
        {
            p.observe(s, wall, scaled);
        }
        assert_eq!(p.scale(), 1.0);
        assert!(p.seen.is_empty());
    }

    #[test]
    fn refinement_frames_add_what_the_budget_holds() {
        let mut p = Preview::new(50.0);
        // Nothing timed yet: one sample.
        assert_eq!(p.refine_step(16), 1);
        // 110 ms a sample and 20 besides (lavapipe at 1280×720): still one, the least a frame adds.
        p.observe_refinement(130.0, 110.0, 1);
        assert_eq!(p.refine_step(16), 1);
        // 3 ms a sample and 20 besides: (50 − 20) / 3 = 10 samples.
        let mut q = Preview::new(50.0);
        q.observe_refinement(26.0, 6.0, 2);
        assert_eq!(q.refine_step(16), 10);
        // A fast device: as many as a frame may add, and never more than asked.
        let mut fast = Preview::new(50.0);
        fast.observe_refinement(2.0, 0.5, 16);
        assert_eq!((fast.refine_step(16), fast.refine_step(4)), (16, 4));
        // Without a budget: always the most.
        let off = Preview::new(0.0);
        assert_eq!(off.refine_step(16), 16);
        // Meaningless times are not taken; a sampling pass that read 0 ms is a fast device.
        let mut z = Preview::new(50.0);
        z.observe_refinement(f64::NAN, 1.0, 1);
        z.observe_refinement(10.0, 1.0, 0);
        assert_eq!(z.refine_step(16), 1);
        z.observe_refinement(10.0, 0.0, 16);
        assert_eq!(z.refine_step(16), 16);
    }

    #[test]
    fn previews_settle_once_nothing_changes_and_no_button_is_held() {
        let base = Situation { refine: true, ..Situation::default() };
        // A change previews; the frame after settles; then refinement.
        let change = Situation { mesh_changed: true, canvas_changed: true, ..base };
        assert_eq!(steps(change), (MeshStep::Preview, CanvasStep::Preview));
        let idle = Situation { mesh_previewed: true, canvas_previewed: true, ..base };
        assert_eq!(steps(idle), (MeshStep::Settle, CanvasStep::Settle));
        assert_eq!(steps(base), (MeshStep::Refine, CanvasStep::Keep));
        // A pause in a drag keeps the previews and does not refine over them.
        assert_eq!(steps(Situation { holding: true, ..idle }), (MeshStep::Keep, CanvasStep::Keep));
        // A held button over a settled view (a stroke is applied on release) lets it refine.
        assert_eq!(steps(Situation { holding: true, ..base }), (MeshStep::Refine, CanvasStep::Keep));
        // A light drag: the canvas changes and previews while the mesh view settles or refines.
        let light = Situation { canvas_changed: true, mesh_previewed: true, ..base };
        assert_eq!(steps(light), (MeshStep::Settle, CanvasStep::Preview));
        assert_eq!(steps(Situation { holding: true, ..light }), (MeshStep::Keep, CanvasStep::Preview));
        // Without refinement a settled view stays.
        assert_eq!(steps(Situation { refine: false, ..base }), (MeshStep::Keep, CanvasStep::Keep));
    }

    #[test]
    fn preview_sizes_keep_at_least_a_pixel() {
        assert_eq!(Preview::size((500, 720), 0.25), (125, 180));
        assert_eq!(Preview::size((1, 3), 0.25), (1, 1));
        assert_eq!(Preview::size((480, 480), 1.0), (480, 480));
    }
}
