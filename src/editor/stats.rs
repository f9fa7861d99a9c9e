//! Frame statistics: per frame, wall ms, GPU ms per pass, the scale its views were rendered at and
//! whether it was an interaction frame (a change: the fast `key` image, previewed smaller when the
//! frame budget asks), a settle frame (the same at full size once nothing changes) or a refinement
//! frame (more `mis` samples); `--frame-stats` writes them as JSON and the panel shows the median
//! frame rate.

/// What a frame rendered of the mesh view: the fast `key` image after a change (an interaction
/// frame), up to `REFINE_STEP` more `mis` samples (a refinement frame), nothing new, or nothing yet
/// because a lobe pipeline it needs was being built in the background (a waiting frame: the
/// canvas and the panel respond, the mesh view shows its last image). A settle frame renders at full
/// size the views that the interaction frames before it previewed smaller (`preview`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameKind {
    Interaction,
    Settle,
    Refinement,
    Unchanged,
    Waiting,
}

/// One frame for `--frame-stats`.
pub struct FrameStat {
    pub wall_ms: f64,
    /// The sum of the timed passes.
    pub gpu_ms: f64,
    /// The whole frame on the GPU, first command to last (the passes, and the clears, copies and
    /// barriers between them).
    pub frame_ms: f64,
    pub kind: FrameKind,
    /// The linear scale the frame's changed views were rendered at (1: full size).
    pub scale: f64,
    /// The samples per pixel of its mesh view (a refinement frame: those it added; 0: none rendered).
    pub spp: u32,
    pub passes: Vec<(String, f64)>,
}

impl FrameStat {
    /// The whole frame less its timed passes (`vk::query::untimed_ms`).
    pub fn untimed_ms(&self) -> f64 {
        crate::vk::query::untimed_ms(self.frame_ms, self.gpu_ms)
    }
}

/// `{"device", "size": [W, H], "frames": [{"kind", "scale", "spp", "wall_ms", "gpu_ms", "frame_ms", "untimed_ms",
/// "passes": [{"name", "ms"}]}], "interaction": {"frames", "median_wall_ms", "median_gpu_ms", "median_frame_ms",
/// "median_untimed_ms", "median_wall_over_gpu", "median_wall_over_frame"},
/// "settle": {…}, "refinement": {…}, "waiting": {…}, "compensation": {"waits", "median_ms", "max_ms"},
/// "skipped_minimised": N, "views": …}` — `compensation` times the waits for an energy-preserving
/// material's compensation tables (from the first frame drawn without one of them to the first
/// with them all: the latency from a stroke to its compensated image); `waiting`
/// frames are those whose mesh view waited for a lobe pipeline built in the background; `skipped_minimised` counts the redraws
/// that drew nothing because the window was minimised; `views` says where the last frame put the mesh view and the
/// canvas and how (camera, exposure, light), so that a headless render can reproduce them. `gpu_ms` is the sum of
/// the timed passes, `frame_ms` the whole frame on the GPU, `untimed_ms` the whole frame less the passes.
pub fn frame_stats_json(
    device: &str,
    size: (u32, u32),
    frames: &[FrameStat],
    table_waits: &[f64],
    skipped_minimised: u64,
    views: serde_json::Value,
) -> String {
    use serde_json::json;
    let kind_name = |k: FrameKind| match k {
        FrameKind::Interaction => "interaction",
        FrameKind::Settle => "settle",
        FrameKind::Refinement => "refinement",
        FrameKind::Unchanged => "unchanged",
        FrameKind::Waiting => "waiting",
    };
    let summary = |k: FrameKind| {
        let wall: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.wall_ms).collect();
        let gpu: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.gpu_ms).collect();
        if wall.is_empty() {
            return json!({ "frames": 0 });
        }
        let whole: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.frame_ms).collect();
        let untimed: Vec<f64> = frames.iter().filter(|f| f.kind == k).map(|f| f.untimed_ms()).collect();
        let ratio = |of: fn(&FrameStat) -> f64| {
            let r: Vec<f64> = frames.iter().filter(|f| f.kind == k && of(f) > 0.0).map(|f| f.wall_ms / of(f)).collect();
            if r.is_empty() {
                0.0
            } else {
                crate::measure::stats(&r).0
            }
        };
        json!({ "frames": wall.len(), "median_wall_ms": crate::measure::stats(&wall).0,
                "median_gpu_ms": crate::measure::stats(&gpu).0,
                "median_frame_ms": crate::measure::stats(&whole).0,
                "median_untimed_ms": crate::measure::stats(&untimed).0,
                "median_wall_over_gpu": ratio(|f| f.gpu_ms),
                "median_wall_over_frame": ratio(|f| f.frame_ms) })
    };
    let compensation = if table_waits.is_empty() {
        json!({ "waits": 0 })
    } else {
        json!({ "waits": table_waits.len(), "median_ms": crate::measure::stats(table_waits).0,
                "max_ms": table_waits.iter().copied().fold(0.0, f64::max) })
    };
    let list: Vec<_> = frames
        .iter()
        .map(|f| {
            json!({ "kind": kind_name(f.kind), "scale": f.scale, "spp": f.spp, "wall_ms": f.wall_ms, "gpu_ms": f.gpu_ms,
                    "frame_ms": f.frame_ms, "untimed_ms": f.untimed_ms(),
                    "passes": f.passes.iter().map(|(n, ms)| json!({ "name": n, "ms": ms })).collect::<Vec<_>>() })
        })
        .collect();
    let doc = json!({ "device": device, "size": [size.0, size.1], "frames": list,
                      "interaction": summary(FrameKind::Interaction),
                      "settle": summary(FrameKind::Settle), "refinement": summary(FrameKind::Refinement),
                      "waiting": summary(FrameKind::Waiting),
                      "compensation": compensation,
                      "skipped_minimised": skipped_minimised, "views": views });
    let mut s = serde_json::to_string_pretty(&doc).expect("plain JSON");
    s.push('\n');
    s
}

/// The mesh view and canvas of the last frame, for `--frame-stats`: where they are and what a
/// headless `render` needs to reproduce them (`env_exposure`: the map's automatic exposure).
pub fn views_json(
    state: &super::state::State,
    (env_exposure, env_backdrop): (f64, f64),
    spp: u32,
    refined: u32,
) -> serde_json::Value {
    use serde_json::json;
    let l = state.layout;
    let c = state.camera();
    let v = |d: glam::DVec3| format!("{},{},{}", d.x, d.y, d.z);
    json!({
        "mesh": { "x": l.mesh_x, "width": l.mesh_w, "height": l.height,
                  "exposure": state.exposure * env_exposure,
                  "camera": format!("eye={} target={} up={} fov={}", v(c.eye), v(c.target), v(c.up), c.fov_deg),
                  "spp": spp, "refined_spp": refined,
                  "env_rotation": state.env_rotation,
                  "backdrop": { "brightness": state.backdrop.scale(env_backdrop), "blur": state.backdrop.blur } },
        "canvas": { "x": l.canvas_x, "side": l.canvas, "exposure": state.exposure,
                    "light": v(state.settings.canvas.light) },
    })
}
