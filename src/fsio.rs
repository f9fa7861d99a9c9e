//! Text and file input/output. `shortest` prints an `f64` so it reads back bit for bit.
//!
//! Atomic file writes: the bytes go to a temporary file beside the target, are flushed to disk, and
//! the temporary file is renamed over the target. A failure at any step leaves the target as it was.
//! [`write_all_atomic`] does the same for several outputs of one command: every temporary file is
//! written before the first rename, so a failure leaves every target as it was.
//!
//! Output paths are checked before any work ([`check_output`]); input files are read with a stated
//! size limit ([`read_limited`]), checked before anything is allocated. [`quote`] is how every
//! message shows a value the user gave: at most [`QUOTE_CHARS`] characters, control characters
//! escaped.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The most characters of a bad value a message quotes: enough to recognise it, short enough that a
/// 100 MB field still gives one short line.
pub const QUOTE_CHARS: usize = 80;

/// `s` for a message: control characters (and other non-printing ones) escaped as `\n`, `\u{1b}`…,
/// cut to [`QUOTE_CHARS`] characters with `…` and the full length in bytes when longer.
pub fn quote(s: &str) -> String {
    let mut out = String::new();
    for (shown, c) in s.chars().enumerate() {
        if shown == QUOTE_CHARS {
            out.push_str(&format!("… ({} bytes in all)", s.len()));
            return out;
        }
        escape_char(c, &mut out);
    }
    out
}

/// `msg` with control characters escaped and every word (run without a space) longer than `max`
/// characters cut to `max`, with its length in bytes: for messages of other crates that echo a value
/// whole (serde's `unknown field `…``, `invalid type: string "…"`).
pub fn shorten_words(msg: &str, max: usize) -> String {
    let escaped = escape_controls(msg);
    let mut out = String::with_capacity(escaped.len().min(4096));
    for (k, word) in escaped.split(' ').enumerate() {
        if k > 0 {
            out.push(' ');
        }
        if word.chars().count() > max {
            out.extend(word.chars().take(max));
            out.push_str(&format!("…({} bytes)", word.len()));
        } else {
            out.push_str(word);
        }
    }
    out
}

/// Escapes control characters of a whole message (which stays as long as it is).
pub fn escape_controls(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        escape_char(c, &mut out);
    }
    out
}

fn escape_char(c: char, out: &mut String) {
    if c.is_control() || matches!(c, '\u{200b}'..='\u{200f}' | '\u{2028}'..='\u{202e}' | '\u{feff}') {
        out.extend(c.escape_default());
    } else {
        out.push(c);
    }
}

/// A path for a message: [`escape_controls`] of its display form.
pub fn show(path: &Path) -> String {
    escape_controls(&path.display().to_string())
}

/// Reads a whole file of at most `limit` bytes; a longer one is refused (naming the file, its size
/// and the limit) before its contents are read. `what` names the kind of file in the message.
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let too_big = |len: u64| {
        Error::input(show(path), format!("{len} bytes or more is larger than the limit for {what} ({limit} bytes)"))
    };
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::input(show(path), "is a folder, not a file"));
    }
    if meta.len() > limit {
        return Err(too_big(meta.len()));
    }
    // A pipe or a file that grows while read reports a smaller length: read at most one byte more
    // than the limit to tell.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64, what: &str) -> Result<String> {
    let bytes = read_limited(path, limit, what)?;
    String::from_utf8(bytes).map_err(|e| {
        Error::input(
            show(path),
            format!("not UTF-8 text (byte {} is not part of a character)", e.utf8_error().valid_up_to()),
        )
    })
}

/// The folder an output file is written into (`.` for a bare name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks, before any work, that `path` can be written atomically: it has a file name, is not a
/// folder, and its folder exists and accepts a new file (a probe file is created and removed).
/// `flag` names the option in the message.
pub fn check_output(flag: &str, path: &Path) -> Result<()> {
    let name = path.file_name().ok_or_else(|| Error::input(flag, format!("{}: not a file name", show(path))))?;
    if path.is_dir() {
        return Err(Error::input(flag, format!("{}: is a folder, not a file", show(path))));
    }
    let dir = parent_of(path);
    if !dir.is_dir() {
        return Err(Error::input(flag, format!("{}: the folder {} does not exist", show(path), show(dir))));
    }
    let probe = dir.join(format!(".{}.{}.probe", name.to_string_lossy(), std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(Error::input(flag, format!("{}: cannot write in {}: {e}", show(path), show(dir)))),
    }
}

/// Checks, before any work, that `dir` is a folder that exists or can be created (its nearest
/// existing ancestor is a folder) — for the commands that write several files into a folder.
pub fn check_output_dir(flag: &str, dir: &Path) -> Result<()> {
    let mut at = dir;
    loop {
        if at.exists() {
            if !at.is_dir() {
                return Err(Error::input(flag, format!("{}: {} is not a folder", show(dir), show(at))));
            }
            return Ok(());
        }
        match at.parent() {
            Some(p) if !p.as_os_str().is_empty() => at = p,
            _ => return Ok(()),
        }
    }
}

fn temp_path(path: &Path) -> Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| Error::input(show(path), "not a file name"))?;
    Ok(parent_of(path).join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id())))
}

fn write_temp(tmp: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(tmp)?;
    f.write_all(bytes)?;
    f.sync_all()
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_all_atomic(&[(path, bytes)])
}

/// Writes several files atomically as one: every temporary file is written and flushed first, then
/// each is renamed over its target. A failure while writing leaves every target as it was.
pub fn write_all_atomic(outputs: &[(&Path, &[u8])]) -> Result<()> {
    let mut temps: Vec<PathBuf> = Vec::with_capacity(outputs.len());
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    for (path, bytes) in outputs {
        let tmp = match temp_path(path) {
            Ok(t) => t,
            Err(e) => {
                cleanup(&temps);
                return Err(e);
            }
        };
        let result = write_temp(&tmp, bytes);
        temps.push(tmp);
        if let Err(e) = result {
            cleanup(&temps);
            return Err(Error::io(path, e));
        }
    }
    for (k, ((path, _), tmp)) in outputs.iter().zip(&temps).enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&temps[k..]);
            return Err(Error::io(path, e));
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quote_cuts_and_escapes() {
        assert_eq!(quote("a\nb\u{1b}"), "a\\nb\\u{1b}");
        let long = "x".repeat(1000);
        let q = quote(&long);
        assert!(q.starts_with(&"x".repeat(QUOTE_CHARS)) && q.ends_with("(1000 bytes in all)"), "{q}");
    }
}
