//! Unsaved work survives a crash: after every change the material is written atomically to the
//! recovery file, which the next start offers back (R) when no `--material` is given.

use std::path::{Path, PathBuf};

use crate::brdf::Material;
use crate::error::{Error, Result};

/// Where unsaved work goes: `BRDF_SHOP_RECOVERY`, else `$XDG_STATE_HOME/brdf-shop/recovery.brdf.json`,
/// else `~/.local/state/brdf-shop/recovery.brdf.json`.
pub fn recovery_path() -> PathBuf {
    if let Ok(p) = std::env::var("BRDF_SHOP_RECOVERY") {
        return PathBuf::from(p);
    }
    let base = std::env::var("XDG_STATE_HOME")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(std::env::var("HOME").unwrap_or_else(|_| ".".into())).join(".local/state"));
    base.join("brdf-shop/recovery.brdf.json")
}

/// Writes the material atomically to the recovery file, creating its folder.
pub fn save_recovery(m: &Material, path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    m.save(path)
}

/// [`save_recovery`] that never ends the session: a recovery file that cannot be written is a
/// warning on stderr (once per session, `warned`) and, returned, a status line for the window; the
/// work goes on and `--out` is still written at the end.
pub fn keep_recovery(m: &Material, warned: &mut bool) -> Option<String> {
    let path = recovery_path();
    let e = save_recovery(m, &path).err()?;
    let msg = format!("unsaved work is NOT protected: the recovery file cannot be written ({e})");
    if !*warned {
        eprintln!("brdf-shop: warning: {}", crate::fsio::escape_controls(&msg));
        *warned = true;
    }
    Some(format!("warning: {msg}"))
}
