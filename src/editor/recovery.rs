//! Unsaved work survives a crash: after every change the material is written atomically to the
//! recovery file, which the next start offers back (R) when no `--material` is given.

use std::path::{Path, PathBuf};

use crate::brdf::Material;
use crate::error::{Error, Result};

/// Where unsaved work goes: `BRDF_SHOP_RECOVERY`, else `$XDG_STATE_HOME/brdf-shop/recovery.brdf.json`,
/// else `~/.local/state/brdf-shop/recovery.brdf.json` (a relative `XDG_STATE_HOME` or `HOME` is
/// ignored, [`crate::fsio::user_dir`]); `None` when neither names a folder.
pub fn recovery_path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("BRDF_SHOP_RECOVERY").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    Some(crate::fsio::user_dir("XDG_STATE_HOME", ".local/state")?.join("brdf-shop/recovery.brdf.json"))
}

/// The material in the recovery file at `path`: `Ok(None)` when there is none, an error (what is
/// wrong, without the path) when something is there that is not a readable material. Read through
/// [`crate::fsio::read_regular_limited`], so a FIFO or a link planted at the path is never opened.
pub fn load_recovery(path: &Path) -> std::result::Result<Option<Material>, String> {
    let bytes = match crate::fsio::read_regular_limited(path, crate::brdf::file::MAX_JSON_BYTES) {
        Ok(b) => b,
        Err(crate::fsio::Unreadable::Missing) => return Ok(None),
        Err(e) => return Err(e.to_string()),
    };
    let text = String::from_utf8(bytes).map_err(|_| "not UTF-8 text".to_string())?;
    Material::from_json(&text, &crate::fsio::show(path)).map(Some).map_err(|e| e.to_string())
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
    let e = match recovery_path() {
        Some(path) => save_recovery(m, &path).err()?,
        None => Error::input("BRDF_SHOP_RECOVERY", "no state folder: XDG_STATE_HOME and HOME are unset or relative"),
    };
    let msg = format!("unsaved work is NOT protected: the recovery file cannot be written ({e})");
    if !*warned {
        eprintln!("brdf-shop: warning: {}", crate::fsio::escape_controls(&msg));
        *warned = true;
    }
    Some(format!("warning: {msg}"))
}
