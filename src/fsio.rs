//! Text and file output. `shortest` prints an `f64` so it reads back bit for bit. Atomic file writes: the bytes go to a temporary file beside the target, are flushed to disk, and
//! the temporary file is renamed over the target. A failure at any step leaves the target as it was.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().ok_or_else(|| Error::input(path.display().to_string(), "not a file name"))?;
    let tmp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    Ok(())
}

/// The shortest text that reads back to the same `f64`: plain notation for `1e-5 ≤ |v| < 1e16` (and 0),
/// scientific otherwise. What `brdf-shop eval` prints.
pub fn shortest(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-5..1e16).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}
