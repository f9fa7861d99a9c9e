//! Where the tool panel and the views sit in the editor's window: pure geometry in pixels, shared by
//! the editor (its input handling, its frame and its composition) and `measure::viewer` (which
//! times the editor's frame without a window). No window, GPU or egui here.

/// The tool panel's width (left edge of the window), when the window is wide enough for it.
pub const PANEL_WIDTH: u32 = 280;

/// Where the views sit in the window (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    pub width: u32,
    pub height: u32,
    /// The mesh view: `(mesh_x, 0, mesh_w, height)`, right of the tool panel.
    pub mesh_x: u32,
    pub mesh_w: u32,
    /// The canvas: a square of side `canvas` at `(canvas_x, 0)`.
    pub canvas_x: u32,
    pub canvas: u32,
    /// The BRDF graph: `(canvas_x, graph_y, width − canvas_x, height − graph_y)`.
    pub graph_y: u32,
}

impl Layout {
    pub fn new(width: u32, height: u32) -> Layout {
        // The tool panel is always drawn at the left edge: the views start right of it (in a
        // window narrower than two panels, half the width is left to them).
        let mesh_x = PANEL_WIDTH.min(width / 2);
        // The right column is as wide as the canvas (at most half of what the panel leaves, at
        // most 3/5 of the height: the graphs below it keep the rest); the mesh view takes all the
        // width between the panel and that column, so no strip of the window is left unfilled.
        let canvas = ((width - mesh_x) / 2).min(height * 3 / 5).max(1);
        let mesh_w = (width - mesh_x).saturating_sub(canvas).max(1);
        let canvas_x = mesh_x + mesh_w;
        Layout { width, height, mesh_x, mesh_w, canvas_x, canvas, graph_y: canvas.min(height) }
    }

    /// Canvas coordinates `(cu, cv)` of a window point.
    pub fn canvas_coords(&self, x: f64, y: f64) -> (f64, f64) {
        ((x - self.canvas_x as f64) / self.canvas as f64, y / self.canvas as f64)
    }

    /// The window point of canvas coordinates.
    pub fn canvas_point(&self, cu: f64, cv: f64) -> (f64, f64) {
        (self.canvas_x as f64 + cu * self.canvas as f64, cv * self.canvas as f64)
    }

    pub fn in_canvas(&self, x: f64, y: f64) -> bool {
        let (cu, cv) = self.canvas_coords(x, y);
        (0.0..1.0).contains(&cu) && (0.0..1.0).contains(&cv)
    }

    pub fn in_mesh(&self, x: f64, y: f64) -> bool {
        x >= self.mesh_x as f64 && x < (self.mesh_x + self.mesh_w) as f64 && y >= 0.0 && y < self.height as f64
    }
}
