//! What the mesh view shows behind the object and how the environment is turned: the backdrop's
//! own brightness and blur (independent of the object's exposure), the switch to black, and the
//! environment's turn about the up axis. These belong to the session, not the material: they are
//! kept in `$XDG_STATE_HOME/brdf-shop/session.json` (else `~/.local/state/…`; `BRDF_SHOP_SESSION`
//! names another file) and read back at the next start, through the same regular-file-only path as
//! every file the program keeps ([`crate::fsio::read_regular_limited`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::scene::Environment;

/// The backdrop of the mesh view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Backdrop {
    /// The map behind the object (`false`: black).
    pub shown: bool,
    /// A factor on [`auto_brightness`]: 1 shows the map's median radiance as mid grey.
    pub brightness: f64,
    /// The level of the map's mip chain shown (0 the map itself; `Settings::backdrop_blur`).
    pub blur: f64,
}

impl Default for Backdrop {
    /// The map, its median at mid grey, two levels down the mip chain: the room reads as a room and
    /// does not compete with the object's highlights.
    fn default() -> Backdrop {
        Backdrop { shown: true, brightness: 1.0, blur: 2.0 }
    }
}

/// The backdrop's blur steps (the `[` and `]` keys, the panel's slider) stay within this range.
pub const BLUR_RANGE: (f64, f64) = (0.0, 8.0);

/// The backdrop's brightness factor stays within this range.
pub const BRIGHTNESS_RANGE: (f64, f64) = (1e-3, 1e3);

impl Backdrop {
    /// The backdrop's linear scale on the map's radiance for `env`: 0 when hidden.
    pub fn scale(&self, env_auto: f64) -> f64 {
        if self.shown {
            self.brightness * env_auto
        } else {
            0.0
        }
    }

    /// Within the ranges, finite (a session file's values are not trusted).
    pub fn clamped(self) -> Backdrop {
        let finite = |v: f64, d: f64| if v.is_finite() { v } else { d };
        Backdrop {
            shown: self.shown,
            brightness: finite(self.brightness, 1.0).clamp(BRIGHTNESS_RANGE.0, BRIGHTNESS_RANGE.1),
            blur: finite(self.blur, 0.0).clamp(BLUR_RANGE.0, BLUR_RANGE.1),
        }
    }
}

/// The linear scale that shows `env`'s median radiance (over solid angle, the mean of RGB) as mid
/// grey (0.18): the map's walls and floor rather than its lamps set it, so a studio's room reads at
/// any exposure the object's highlights want.
pub fn auto_brightness(env: &Environment) -> f64 {
    let mut texels: Vec<(f64, f64)> = Vec::with_capacity(env.texels.len());
    for j in 0..env.height {
        let omega = env.texel_solid_angle(j);
        for t in &env.texels[j * env.width..(j + 1) * env.width] {
            texels.push(((t[0] + t[1] + t[2]).max(0.0) as f64 / 3.0, omega));
        }
    }
    texels.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = texels.iter().map(|t| t.1).sum::<f64>() / 2.0;
    let mut seen = 0.0;
    let median = texels.iter().find(|t| {
        seen += t.1;
        seen >= half
    });
    match median {
        Some(&(m, _)) if m > 0.0 => (0.18 / m).clamp(1e-4, 1e4),
        _ => 1.0,
    }
}

/// What a session keeps besides the material.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    /// The environment's turn about the up axis, degrees (`Environment::rotated`).
    pub env_rotation: f64,
    pub backdrop: Backdrop,
}

/// The largest session file read (bytes): a few numbers.
const MAX_SESSION_BYTES: u64 = 64 << 10;

/// Where the session is kept: `BRDF_SHOP_SESSION`, else `brdf-shop/session.json` in the XDG state
/// folder ([`crate::fsio::user_dir`]); `None` when there is none.
pub fn session_path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("BRDF_SHOP_SESSION").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    Some(crate::fsio::user_dir("XDG_STATE_HOME", ".local/state")?.join("brdf-shop/session.json"))
}

impl Session {
    /// The session at `path`: the default where there is none; an error (what is wrong) where
    /// something is there that is not a session (the session then starts from the default).
    pub fn load(path: &Path) -> Result<Session, String> {
        let bytes = match crate::fsio::read_regular_limited(path, MAX_SESSION_BYTES) {
            Ok(b) => b,
            Err(crate::fsio::Unreadable::Missing) => return Ok(Session::default()),
            Err(e) => return Err(e.to_string()),
        };
        let s: Session = serde_json::from_slice(&bytes)
            .map_err(|e| crate::fsio::shorten_words(&format!("not a session file: {e}"), 80))?;
        let env_rotation = if s.env_rotation.is_finite() { s.env_rotation.rem_euclid(360.0) } else { 0.0 };
        Ok(Session { env_rotation, backdrop: s.backdrop.clamped() })
    }

    /// Writes the session atomically to `path`, creating its folder.
    pub fn save(&self, path: &Path) -> crate::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| crate::Error::io(dir, e))?;
        }
        let text = serde_json::to_string_pretty(self).expect("a session serialises");
        crate::fsio::write_atomic(path, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_reads_back_and_untrusted_values_are_clamped() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.json");
        assert_eq!(Session::load(&p), Ok(Session::default()));
        let s = Session { env_rotation: 123.5, backdrop: Backdrop { shown: false, brightness: 2.0, blur: 3.5 } };
        s.save(&p).unwrap();
        assert_eq!(Session::load(&p), Ok(s));
        std::fs::write(&p, r#"{"env_rotation": -90, "backdrop": {"shown": true, "brightness": 1e9, "blur": -4}}"#)
            .unwrap();
        let got = Session::load(&p).unwrap();
        assert_eq!((got.env_rotation, got.backdrop.brightness, got.backdrop.blur), (270.0, 1e3, 0.0));
        std::fs::write(&p, "[1, 2]").unwrap();
        assert!(Session::load(&p).unwrap_err().contains("not a session file"));
    }

    /// A map whose lower half is 10× brighter than its upper half but for a tiny lamp: the median
    /// is the upper half's value or the lower's (the halves hold equal solid angle), never the
    /// lamp's, which dominates the mean.
    #[test]
    fn the_auto_brightness_follows_the_median_not_the_lamps() {
        let (w, h) = (64, 32);
        let mut texels = vec![[0.5f32; 3]; w * h];
        for t in &mut texels[w * h / 2..] {
            *t = [5.0; 3];
        }
        texels[w * h / 2 - 1] = [1e6; 3];
        let env = Environment::from_texels(w, h, texels, "test").unwrap();
        let b = auto_brightness(&env);
        assert!((b - 0.18 / 0.5).abs() < 1e-12 || (b - 0.18 / 5.0).abs() < 1e-12, "{b}");
        assert_eq!(auto_brightness(&Environment::constant([0.0; 3])), 1.0);
    }
}
