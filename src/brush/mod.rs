//! The painting side of BRDF-Shop (paper §3): the spherical canvas, the five brushes that map strokes
//! to lobes, undo/redo, and the strokes file with its replay.
//!
//! Plain Rust: nothing here may import `ash` or the renderer. The editor feeds mouse strokes through
//! [`strokes::apply`], the same path `brdf-shop paint` replays files through.

pub mod brushes;
pub mod canvas;
pub mod history;
pub mod strokes;

pub use brushes::{ModifyRule, Settings};
pub use canvas::Canvas;
pub use history::History;
pub use strokes::{BrushKind, Stroke, Strokes};
