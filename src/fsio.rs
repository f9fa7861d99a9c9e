//! Text and file input/output. `shortest` prints an `f64` so it reads back bit for bit.
//!
//! Atomic file writes: the bytes go to a temporary file beside the target (created exclusively under
//! an unpredictable name, with the permissions of the file it replaces), are flushed to disk, and
//! the temporary file is renamed over the target. A failure at any step leaves the target as it was.
//! An existing output that is not a regular file (a device, FIFO, socket) is refused.
//! [`write_all_atomic`] does the same for several outputs of one command: every temporary file is
//! written before the first rename, so a failure leaves every target as it was.
//!
//! Output paths are checked before any work ([`check_output`]); input files are read with a stated
//! size limit ([`read_limited`]), checked before anything is allocated. How a message shows a path
//! or a value the user gave ([`quote`], [`show`]…) is [`crate::text`]'s, re-exported here.

use std::io::{Read, Write};
use std::path::Path;

use crate::error::{Error, Result};
pub use crate::text::{escape_controls, quote, shorten_words, show, QUOTE_CHARS};

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

/// [`read_limited`] for a file that must be a regular file: anything else (a FIFO, a device,
/// `/dev/stdin`, a socket, a symbolic link) is refused before it is opened, and the file is opened
/// without blocking (`O_NONBLOCK`) and without following a symlink at its last component
/// (`O_NOFOLLOW`) and checked again once open, so a file swapped for a FIFO or a link in between
/// cannot make the read wait forever or read elsewhere. The size is checked before anything is read.
/// The one way to read the files a file refers to (a glTF file's buffers) and the files the program
/// keeps for itself (the pipeline cache, the editor's recovery file, the report's cached
/// references); the files a user names are read with [`read_limited`]. The error says what is wrong
/// without naming the path (the caller names it); [`Unreadable::Missing`] tells a file that is not
/// there from one that is there but not readable.
pub fn read_regular_limited(path: &Path, limit: u64) -> std::result::Result<Vec<u8>, Unreadable> {
    use std::os::unix::fs::OpenOptionsExt;
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::NotFound => Unreadable::Missing,
        _ => Unreadable::Refused(e.kind().to_string()),
    };
    let not_regular = || Unreadable::Refused("is not a regular file (a FIFO, device, socket or link)".into());
    let meta = std::fs::symlink_metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
        .open(path)
        .map_err(|e| if e.raw_os_error() == Some(libc::ELOOP) { not_regular() } else { io(e) })?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    let too_big =
        |len: u64| Unreadable::Refused(format!("{len} bytes or more is larger than the limit ({limit} bytes)"));
    if meta.len() > limit {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Why [`read_regular_limited`] read nothing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Unreadable {
    /// Nothing is at the path.
    Missing,
    /// Something is there that is not read: what is wrong with it.
    Refused(String),
}

impl std::fmt::Display for Unreadable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unreadable::Missing => f.write_str("no such file"),
            Unreadable::Refused(why) => f.write_str(why),
        }
    }
}

/// The XDG Base Directory variables whose relative values [`ignore_relative_xdg`] removes.
pub const XDG_VARS: [&str; 4] = ["XDG_CACHE_HOME", "XDG_STATE_HOME", "XDG_CONFIG_HOME", "XDG_DATA_HOME"];

/// Removes from this process's environment each XDG Base Directory variable that is set to a
/// relative path (the specification calls such a value invalid, to be ignored). Called first in
/// `main`, before any thread starts: the libraries loaded in-process read these variables too (Mesa
/// keeps its shader cache and the validation layer its own cache under `XDG_CACHE_HOME`), and with
/// a relative value they would write into the current folder.
pub fn ignore_relative_xdg() {
    for var in XDG_VARS {
        if std::env::var_os(var).is_some_and(|v| !std::path::Path::new(&v).is_absolute()) {
            std::env::remove_var(var);
        }
    }
}

/// A per-user folder of the XDG Base Directory specification: `$VAR` where it is an absolute path,
/// else `$HOME/fallback` where `HOME` is absolute (`~/.cache`, `~/.local/state`); `None` when
/// neither is. The specification calls a relative value invalid and says to ignore it, so a
/// relative `XDG_CACHE_HOME` never makes the program write into the current folder.
pub fn user_dir(var: &str, fallback: &str) -> Option<std::path::PathBuf> {
    let absolute = |k: &str| std::env::var_os(k).map(std::path::PathBuf::from).filter(|p| p.is_absolute());
    absolute(var).or_else(|| absolute("HOME").map(|h| h.join(fallback)))
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

/// The start of every temporary file name: short, so that an output name of up to 255 bytes (the
/// longest most file systems take) still works, and with a random part after it (from `tempfile`),
/// so that nothing planted in the folder can be at the name before the file is created.
const TEMP_PREFIX: &str = ".brdf-shop-";

/// A new, empty temporary file in `dir`, created exclusively (`O_EXCL`, so a symlink or FIFO planted
/// at its name is never followed or opened) under an unpredictable name, with the permissions a new
/// file gets (`0666` less the umask; `tempfile`'s default is `0600`).
fn new_temp(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    use std::os::unix::fs::PermissionsExt;
    tempfile::Builder::new()
        .prefix(TEMP_PREFIX)
        .rand_bytes(8)
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(dir)
}

/// Checks, before any work, that `path` can be written atomically: it has a file name, is not a
/// folder, is not something other than a regular file (a device, FIFO or socket: replacing
/// `/dev/null` by a file is never meant), and its folder exists and accepts a new file (a temporary
/// file is created there and removed). `flag` names the option in the message.
pub fn check_output(flag: &str, path: &Path) -> Result<()> {
    if path.file_name().is_none() {
        return Err(Error::input(flag, format!("{}: not a file name", show(path))));
    }
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err(Error::input(flag, format!("{}: is a folder, not a file", show(path)))),
        Ok(m) if !m.is_file() => {
            return Err(Error::input(
                flag,
                format!(
                    "{}: is not a regular file (a device, FIFO or socket); outputs replace regular files only",
                    show(path)
                ),
            ))
        }
        _ => {}
    }
    let dir = parent_of(path);
    if !dir.is_dir() {
        return Err(Error::input(flag, format!("{}: the folder {} does not exist", show(path), show(dir))));
    }
    match new_temp(dir) {
        Ok(probe) => {
            drop(probe);
            Ok(())
        }
        Err(e) => Err(Error::input(flag, format!("{}: cannot write in {}: {e}", show(path), show(dir)))),
    }
}

/// Whether two output paths name the same file, however spelled (`o.exr`, `./o.exr`, `d/../o.exr`,
/// a symlink to it): by device and inode where both exist, else by canonical folder and file name.
pub fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        return ma.dev() == mb.dev() && ma.ino() == mb.ino();
    }
    let spot = |p: &Path| Some((std::fs::canonicalize(parent_of(p)).ok()?, p.file_name()?.to_owned()));
    match (spot(a), spot(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// [`check_output`] for every output of one command, then refuses two that name the same file
/// (compared by [`same_file`]): all before any work, so a refusal leaves every existing file as it
/// was. `outputs` are (flag, path) in the order the command's help lists them.
pub fn check_outputs(outputs: &[(&str, &Path)]) -> Result<()> {
    for (flag, path) in outputs {
        check_output(flag, path)?;
    }
    check_distinct(outputs)
}

/// Refuses two outputs that name the same file (compared by [`same_file`]), naming both flags.
pub fn check_distinct(outputs: &[(&str, &Path)]) -> Result<()> {
    for (k, (flag_b, b)) in outputs.iter().enumerate() {
        if let Some((flag_a, _)) = outputs[..k].iter().find(|(_, a)| same_file(a, b)) {
            return Err(Error::input(*flag_b, format!("{}: names the same file as {flag_a}", show(b))));
        }
    }
    Ok(())
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

/// A complete temporary file for `path` in its folder: created by [`new_temp`], with the
/// permissions of the file it replaces (when there is one), `bytes` written and flushed to disk.
fn write_temp(path: &Path, bytes: &[u8]) -> std::io::Result<tempfile::NamedTempFile> {
    let mut tmp = new_temp(parent_of(path))?;
    if let Ok(m) = std::fs::metadata(path) {
        tmp.as_file().set_permissions(m.permissions())?;
    }
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    Ok(tmp)
}

/// Refuses an existing output that is not a regular file (checked again at writing: it may have
/// appeared after [`check_output`] ran).
fn refuse_special(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(Error::input(
            show(path),
            "is not a regular file (a device, FIFO or socket); outputs replace regular files only",
        )),
        _ => Ok(()),
    }
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_all_atomic(&[(path, bytes)])
}

/// Writes several files atomically as one: every temporary file is written and flushed first, then
/// each is renamed over its target. A failure while writing leaves every target as it was and
/// removes the temporary files. A temporary file is only ever left behind by a process killed
/// between creating and renaming it (`kill -9`, power loss): a hidden `.brdf-shop-XXXXXXXX` file
/// beside the output, which no run reads or reuses and which may be deleted at any time.
pub fn write_all_atomic(outputs: &[(&Path, &[u8])]) -> Result<()> {
    let mut temps = Vec::with_capacity(outputs.len());
    for (path, bytes) in outputs {
        if path.file_name().is_none() {
            return Err(Error::input(show(path), "not a file name"));
        }
        refuse_special(path)?;
        // On an error, the temporary files written so far are removed as `temps` is dropped.
        temps.push(write_temp(path, bytes).map_err(|e| Error::io(*path, e))?);
    }
    for ((path, _), tmp) in outputs.iter().zip(temps) {
        tmp.persist(path).map_err(|e| Error::io(*path, e.error))?;
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
    fn same_file_sees_through_spellings() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        // Not yet existing: by canonical folder and name.
        assert!(same_file(&d.join("o.exr"), &d.join("sub/../o.exr")));
        assert!(same_file(&d.join("o.exr"), &d.join("./o.exr")));
        assert!(!same_file(&d.join("o.exr"), &d.join("sub/o.exr")));
        // Existing: by device and inode, a symlink included.
        std::fs::write(d.join("o.exr"), b"x").unwrap();
        std::os::unix::fs::symlink("o.exr", d.join("link")).unwrap();
        assert!(same_file(&d.join("o.exr"), &d.join("link")));
        assert!(!same_file(&d.join("o.exr"), &d.join("p.exr")));
    }

    #[test]
    fn a_failed_write_leaves_targets_and_no_temporary_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = d.join("a.txt");
        std::fs::write(&a, b"old").unwrap();
        let bad = d.join("missing/b.txt");
        assert!(write_all_atomic(&[(&a, b"new"), (&bad, b"new")]).is_err());
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        let names: Vec<_> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["a.txt"]);
    }
}
