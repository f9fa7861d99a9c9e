//! The hostile suite's runner and fixtures: every run under `ulimit -v` and a wall-time limit, the
//! one-line refusal check, and the files the cases are made of (lying EXR headers, sparse oversized
//! files, materials of many lobes). The limits and why they are what they are: `tests/hostile.rs`.

// Each case uses a different part of this module.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tempfile::TempDir;

pub const CPU_MEM_KIB: u64 = 1 << 20;
pub const GPU_MEM_KIB: u64 = 8 << 20;
pub const CPU_SECS: u64 = 60;
pub const GPU_SECS: u64 = 180;

/// What a run gave.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// How to feed stdin.
pub enum Input {
    None,
    Text(String),
    /// `total` bytes of `pattern` repeated, written until the child stops reading.
    Stream {
        pattern: Vec<u8>,
        total: u64,
    },
}

pub fn spawn(args: &[&str], mem_kib: u64, envs: &[(&str, &str)], stdin: bool) -> Child {
    // `ulimit -v` in a shell that then becomes the binary: the limit covers the binary alone.
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {mem_kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(args)
        .stdin(if stdin { Stdio::piped() } else { Stdio::null() })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.spawn().expect("the binary starts")
}

/// Waits for `child` at most `secs`, killing it (and failing) past that.
pub fn finish(mut child: Child, secs: u64, what: &str) -> Run {
    let start = Instant::now();
    let mut out = child.stdout.take().expect("piped");
    let mut err = child.stderr.take().expect("piped");
    let out_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut out, &mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut err, &mut v);
        v
    });
    let status = loop {
        if let Some(s) = child.try_wait().expect("waiting for the binary") {
            break s;
        }
        if start.elapsed() > Duration::from_secs(secs) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running after {secs} s (killed)");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = String::from_utf8_lossy(&out_reader.join().expect("stdout reader")).into_owned();
    let stderr = String::from_utf8_lossy(&err_reader.join().expect("stderr reader")).into_owned();
    let code = status.code().unwrap_or_else(|| panic!("{what}: killed by a signal ({status:?}); stderr: {stderr}"));
    assert!(!stderr.contains("panicked"), "{what}: panicked: {stderr}");
    assert!(!stderr.contains("memory allocation of"), "{what}: aborted on allocation: {stderr}");
    Run { code, stdout, stderr }
}

pub fn run_with(args: &[&str], input: Input, mem_kib: u64, secs: u64, envs: &[(&str, &str)]) -> Run {
    let what = format!("brdf-shop {}", args.iter().map(|a| short(a)).collect::<Vec<_>>().join(" "));
    let mut child = spawn(args, mem_kib, envs, !matches!(input, Input::None));
    let writer = match input {
        Input::None => None,
        Input::Text(text) => {
            let mut pipe = child.stdin.take().expect("piped");
            Some(std::thread::spawn(move || {
                let _ = pipe.write_all(text.as_bytes());
            }))
        }
        Input::Stream { pattern, total } => {
            let mut pipe = child.stdin.take().expect("piped");
            Some(std::thread::spawn(move || {
                // Whole copies of the pattern, so that lines are not cut between chunks.
                let copies = ((1usize << 20) / pattern.len()).max(1);
                let chunk: Vec<u8> = pattern.iter().copied().cycle().take(copies * pattern.len()).collect();
                let mut sent = 0u64;
                while sent < total {
                    // A refusal stops reading: the broken pipe ends the stream.
                    if pipe.write_all(&chunk).is_err() {
                        return;
                    }
                    sent += chunk.len() as u64;
                }
            }))
        }
    };
    let r = finish(child, secs, &what);
    if let Some(w) = writer {
        w.join().expect("the stdin writer");
    }
    r
}

/// A CPU-only run (no stdin).
pub fn cpu(args: &[&str]) -> Run {
    run_with(args, Input::None, CPU_MEM_KIB, CPU_SECS, &[])
}

/// A run that starts Vulkan.
pub fn gpu(args: &[&str]) -> Run {
    run_with(args, Input::None, GPU_MEM_KIB, GPU_SECS, &[])
}

pub fn short(a: &str) -> String {
    if a.chars().count() > 60 {
        format!("{}…", a.chars().take(60).collect::<String>())
    } else {
        a.to_string()
    }
}

/// A clean refusal: `want` exit status, nothing on stdout, exactly one non-empty line on stderr of
/// at most [`MAX_LINE`] bytes without control characters, naming each of `names`.
pub fn refused(r: &Run, want: i32, names: &[&str]) {
    assert_eq!(r.code, want, "exit status; stderr: {}", short_stderr(&r.stderr));
    assert!(r.stdout.is_empty(), "a refusal printed on stdout: {}", short_stderr(&r.stdout));
    one_line(&r.stderr);
    for n in names {
        assert!(r.stderr.contains(n), "stderr does not name {n:?}: {}", r.stderr);
    }
}

/// The longest stderr line a refusal may print (bytes): the path of a temporary file, a field name
/// and 80 characters of a quoted value fit with room to spare; a message echoing a 100 MB value
/// does not.
pub const MAX_LINE: usize = 600;

pub fn one_line(stderr: &str) {
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        lines.len() == 1 && !lines[0].trim().is_empty() && stderr.ends_with('\n'),
        "stderr must be exactly one non-empty line, got {}",
        short_stderr(stderr)
    );
    assert!(stderr.len() <= MAX_LINE, "stderr line of {} bytes: {}", stderr.len(), short_stderr(stderr));
    assert!(
        !stderr.trim_end_matches('\n').chars().any(|c| c.is_control()),
        "stderr holds a raw control character: {stderr:?}"
    );
}

pub fn short_stderr(s: &str) -> String {
    if s.len() > 2000 {
        format!("{}… ({} bytes)", &s[..s.floor_char_boundary_compat(2000)], s.len())
    } else {
        s.to_string()
    }
}

pub trait FloorBoundary {
    fn floor_char_boundary_compat(&self, i: usize) -> usize;
}

impl FloorBoundary for str {
    fn floor_char_boundary_compat(&self, mut i: usize) -> usize {
        while !self.is_char_boundary(i) {
            i -= 1;
        }
        i
    }
}

pub fn tmp() -> TempDir {
    TempDir::new().expect("a temporary folder")
}

pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("writing a test file");
    p
}

/// A sparse file of `len` bytes (costs no disk).
pub fn sparse(dir: &Path, name: &str, len: u64) -> PathBuf {
    let p = dir.join(name);
    std::fs::File::create(&p).expect("create").set_len(len).expect("set_len");
    p
}

/// The file names in `dir`, sorted (temporary files included: none may be left).
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

pub fn material_json(lobes: usize) -> Value {
    let a = 0.5 / lobes.max(1) as f64;
    let lobe = json!({ "albedo": [a, a, a], "alpha_x": 0.2, "alpha_y": 0.2 });
    json!({
        "format": "brdf-shop/material",
        "version": 2,
        "diffuse": [0.1, 0.1, 0.1],
        "lobes": vec![lobe; lobes],
    })
}

pub fn write_material(dir: &Path, name: &str, m: &Value) -> PathBuf {
    write(dir, name, serde_json::to_string(m).expect("json"))
}

/// An 8×4 RGB EXR of `rgb` everywhere.
pub fn exr_file(dir: &Path, name: &str, rgb: f32) -> PathBuf {
    let p = dir.join(name);
    exr::prelude::write_rgb_file(&p, 8, 4, |_, _| (rgb, rgb, rgb)).expect("writing an EXR");
    p
}

/// An EXR whose header declares `w`×`h`: an 8×4 file with its data and display windows patched, so
/// its offset table and pixels are those of 8×4 — the header lies.
pub fn lying_exr(dir: &Path, name: &str, w: i32, h: i32) -> PathBuf {
    let good = exr_file(dir, "good.exr", 1.0);
    let mut bytes = std::fs::read(&good).expect("read");
    std::fs::remove_file(&good).expect("rm");
    for attr in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes.windows(attr.len()).position(|w| w == attr).expect("the window attribute") + attr.len() + 4;
        bytes[at + 8..at + 12].copy_from_slice(&(w - 1).to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&(h - 1).to_le_bytes());
    }
    write(dir, name, bytes)
}

/// A FIFO at `p`, made without starting a process (the planting cases count process ids).
pub fn mkfifo(p: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).expect("a path without NUL");
    // SAFETY: `c` is a valid NUL-terminated path that outlives the call.
    let rc = unsafe { libc::mkfifo(c.as_ptr(), 0o600) };
    assert_eq!(rc, 0, "mkfifo {}: {}", p.display(), std::io::Error::last_os_error());
}

/// Whether `p` is a FIFO (not followed if it is a link).
pub fn is_fifo(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_fifo())
}
