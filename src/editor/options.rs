//! What `brdf-shop edit` was asked to do, and the window-size checks made before a window opens.

use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::export::Format;

/// What `brdf-shop edit` was asked to do.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub env: Option<PathBuf>,
    pub mesh: Option<String>,
    pub material: Option<PathBuf>,
    pub replay: Option<PathBuf>,
    /// Scripted drops: after the replay, these files are dropped onto the window in order.
    pub drop: Vec<PathBuf>,
    /// Scripted exports (`--export FORMAT=PATH`): after the replay and the drops, each is made as the
    /// *Export…* button makes it, its status line on stderr.
    pub export: Vec<(Format, PathBuf)>,
    /// Write per-frame statistics (wall ms, GPU ms per pass, interaction or refinement) here on exit.
    pub frame_stats: Option<PathBuf>,
    pub screenshot: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub quit: bool,
    /// With `quit`: refine the mesh view to REFINE_MAX samples before leaving.
    pub converge: bool,
    /// Scripted window changes after the replay and the drops: each size in turn, then (with
    /// `minimise`) minimise and restore — each takes effect before the next.
    pub resize: Vec<(u32, u32)>,
    pub minimise: bool,
    pub size: (u32, u32),
    /// Milliseconds an interaction frame may take: views that change are previewed smaller to fit
    /// (`preview`); `Some(0.0)` renders every frame at full size; `None` is
    /// [`super::preview::DEFAULT_BUDGET_MS`].
    pub frame_budget_ms: Option<f64>,
}

/// Refuses (naming `--frame-budget`) a budget that is not a finite number of milliseconds ≥ 0.
pub fn check_frame_budget(ms: f64) -> Result<()> {
    if !(ms.is_finite() && ms >= 0.0) {
        return Err(Error::input(
            "--frame-budget",
            format!("{ms}: expected milliseconds, 0 or more (0 renders every frame at full size)"),
        ));
    }
    Ok(())
}

/// The longest side of the editor's window (pixels), checked before a window is made: an 8K
/// display is 7680 wide, X11 cannot make a window of 65536 (winit panics on it), and the frame is
/// composed on the GPU at 4 bytes a pixel plus the views' targets, so 8192² stays near 2 GB.
pub const MAX_WINDOW_SIDE: u32 = 8192;

/// Each side of a requested window size, limited to the display's.
pub fn clamp_to_display(size: (u32, u32), display: (u32, u32)) -> (u32, u32) {
    (size.0.min(display.0).max(1), size.1.min(display.1).max(1))
}

/// Refuses (naming `--size`) a window size of a zero side or a side over [`MAX_WINDOW_SIDE`].
pub fn check_size(size: (u32, u32)) -> Result<()> {
    let (w, h) = size;
    if w == 0 || h == 0 || w > MAX_WINDOW_SIDE || h > MAX_WINDOW_SIDE {
        return Err(Error::input(
            "--size",
            format!("{w}x{h}: each side of the window must be within 1 and {MAX_WINDOW_SIDE} pixels"),
        ));
    }
    Ok(())
}

/// Parses an `--export FORMAT=PATH` value; an unknown format (or no `=`) is refused naming the known
/// formats, before any window opens.
pub fn parse_export(text: &str) -> Result<(Format, PathBuf)> {
    let known: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
    let refuse = |what: String| {
        Error::input("--export", format!("{what} (expected FORMAT=PATH, FORMAT one of {})", known.join(", ")))
    };
    let Some((name, path)) = text.split_once('=') else {
        return Err(refuse(format!("\"{}\" has no '='", crate::fsio::quote(text))));
    };
    let format = Format::ALL
        .into_iter()
        .find(|f| f.name() == name)
        .ok_or_else(|| refuse(format!("unknown format \"{}\"", crate::fsio::quote(name))))?;
    if path.is_empty() {
        return Err(refuse(format!("\"{}\" names no file", crate::fsio::quote(text))));
    }
    Ok((format, PathBuf::from(path)))
}
