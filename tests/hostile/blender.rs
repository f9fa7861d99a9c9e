//! The script `brdf-shop export --format blender` writes, run as a program by the Blender module
//! (`bpy`, in `<target>/blender-venv`, installed by tools/setup; a missing one fails these tests):
//! outputs whose temporary names are planted, outputs in folders nothing can be written in, output
//! names of 255 bytes, outputs that are devices or FIFOs, a .blend saved over an existing one, and
//! environment maps whose headers declare more texels than brdf-shop reads. Every run is the real
//! exported script (a diffuse-only material, 8×8 pixels, 1 sample) under `BLENDER_MEM_KIB` of
//! address space and `BLENDER_SECS` of wall time.
//!
//! Limits of the runs (why these numbers):
//! - `BLENDER_MEM_KIB` = 8 GiB of virtual memory: the Blender module reserves address space for its
//!   libraries, Cycles' threads and their malloc arenas; an 8×8 render fails at `ulimit -v 1400000`
//!   and runs at 1600000 (1.6 GB, measured on the 2-core development machine). 8 GiB leaves 5× that
//!   for machines with more cores (more Cycles threads, each with its own stack and arena), and is
//!   20× below the 160 GB a header of 100000×100000 float RGBA texels asks for.
//! - `BLENDER_SECS` = 120 s of wall time per run: a run here takes about 2 s alone, under 20 s beside
//!   the rest of the suite on 2 cores; a write into a planted FIFO waits forever.

use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::support::*;

const BLENDER_MEM_KIB: u64 = 8 << 20;
const BLENDER_SECS: u64 = 120;

/// The Python of the virtual environment tools/setup makes: `<target>/blender-venv/bin/python3`.
fn python() -> PathBuf {
    let target = Path::new(env!("CARGO_TARGET_TMPDIR")).parent().expect("the target folder").to_path_buf();
    let p = target.join("blender-venv/bin/python3");
    assert!(p.exists(), "{} missing: run tools/setup (it installs Blender's bpy 5.0.1 there)", p.display());
    p
}

/// The exported script of a diffuse-only material `NAME.brdf.json` (no facet, no lookup image: the
/// export and the scene are quick), written into `dir`.
fn script(dir: &Path, name: &str) -> PathBuf {
    let m = write_material(dir, &format!("{name}.brdf.json"), &material_json(0));
    let py = dir.join(format!("{name}.py"));
    let r = cpu(&["export", "--material", s(&m), "--format", "blender", "--out", s(&py)]);
    assert_eq!(r.code, 0, "export: {}", r.stderr);
    py
}

/// The script run by the venv's Python with `args` after `--size 8x8 --spp 1`, under the limits.
fn run_script(script: &Path, args: &[&str]) -> Run {
    let what = format!("{} {}", script.display(), args.iter().map(|a| short(a)).collect::<Vec<_>>().join(" "));
    // `ulimit -v` in a shell that then becomes Python: the limit covers the script's process alone.
    let child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {BLENDER_MEM_KIB} && exec \"$0\" \"$@\""))
        .arg(python())
        .arg(script)
        .args(["--size", "8x8", "--spp", "1"])
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the venv's Python starts");
    finish(child, BLENDER_SECS, &what)
}

/// The next `n` process ids the kernel hands out (it counts up from the last one: the id of a child
/// started here), for planting files at the names a writer that names them by its process id picks.
fn next_pids(n: u32) -> std::ops::Range<u32> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .arg("--version")
        .stdout(Stdio::null())
        .spawn()
        .expect("start brdf-shop --version");
    let last = child.id();
    child.wait().expect("brdf-shop --version");
    last + 1..last + 1 + n
}

/// A successful run: exit status 0 and nothing on stderr (Blender's progress goes to stdout).
fn succeeded(r: &Run) {
    assert_eq!(r.code, 0, "exit status; stderr: {}", short_stderr(&r.stderr));
    assert!(r.stderr.trim().is_empty(), "stderr: {}", short_stderr(&r.stderr));
}

/// At the names `.o.exr.PID.render.exr` and `.o.exr.PID.tmp.exr` beside the output, for the next
/// 2000 process ids (the test's threads and other processes take ids too), symlinks to a victim file
/// (`fifos` false) or FIFOs (true): the script writes through neither, waits on neither, leaves
/// them as they are and leaves nothing else.
fn planted(fifos: bool) {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    let victim = write(d, "victim.txt", b"do not touch");
    let outs = d.join("out");
    std::fs::create_dir(&outs).unwrap();
    let mut names = Vec::new();
    for pid in next_pids(2000) {
        for kind in ["render", "tmp"] {
            let name = format!(".o.exr.{pid}.{kind}.exr");
            if fifos {
                mkfifo(&outs.join(&name));
            } else {
                std::os::unix::fs::symlink(&victim, outs.join(&name)).unwrap();
            }
            names.push(name);
        }
    }
    let out = outs.join("o.exr");
    succeeded(&run_script(&py, &["--out", s(&out)]));
    let kept = std::fs::read(&victim).unwrap();
    assert!(kept == b"do not touch", "a planted symlink was followed: the victim holds {} other bytes", kept.len());
    assert!(std::fs::symlink_metadata(&out).unwrap().file_type().is_file(), "--out is not a regular file");
    for name in &names {
        let p = outs.join(name);
        let kept = if fifos { is_fifo(&p) } else { std::fs::read_link(&p).is_ok_and(|t| t == victim) };
        assert!(kept, "{name} was replaced");
    }
    names.push("o.exr".into());
    names.sort();
    assert_eq!(listing(&outs), names, "a temporary file was left behind");
}

#[test]
fn blender_script_does_not_follow_symlinks_planted_at_temporary_names() {
    planted(false);
}

#[test]
fn blender_script_does_not_wait_on_fifos_planted_at_temporary_names() {
    planted(true);
}

/// Folders nothing can be written in, root included: a "folder" that is a file, a link that loops
/// on itself, a missing folder; and (when the test does not run as root, for whom permission bits
/// stop nothing) a folder without write permission. All are made in the test's own folder.
#[test]
fn blender_script_refuses_unwritable_output_folders_in_one_line() {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    let file = write(d, "file", b"a file");
    let locked = d.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let looped = d.join("loop");
    std::os::unix::fs::symlink("loop", &looped).unwrap();
    let mut cases: Vec<(&str, PathBuf)> = vec![
        ("--out", looped.join("o.exr")),
        ("--save", looped.join("s.blend")),
        ("--out", file.join("o.exr")),
        ("--save", file.join("s.blend")),
        ("--save", d.join("missing/s.blend")),
    ];
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        cases.push(("--out", locked.join("o.exr")));
        cases.push(("--save", locked.join("s.blend")));
    }
    for (flag, path) in &cases {
        let r = run_script(&py, &[flag, s(path)]);
        refused(&r, 1, &[flag, s(path)]);
    }
    assert_eq!(std::fs::read(&file).unwrap(), b"a file");
    assert_eq!(listing(&locked), Vec::<String>::new());
    assert_eq!(listing(d), ["file", "locked", "loop", "m.brdf.json", "m.py"]);
}

/// Output names of 250 and 255 bytes (the longest a file name may be) are written: the temporary
/// names stay short. A name of 256 bytes is refused in one line.
#[test]
fn blender_script_writes_output_names_of_255_bytes() {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    let outs = d.join("out");
    std::fs::create_dir(&outs).unwrap();
    let exr = |len: usize| format!("{}.exr", "n".repeat(len - 4));
    let blend = format!("{}.blend", "s".repeat(255 - 6));
    for name in [exr(250), exr(255)] {
        succeeded(&run_script(&py, &["--out", s(&outs.join(&name))]));
        assert_eq!(listing(&outs), std::slice::from_ref(&name));
        std::fs::remove_file(outs.join(&name)).unwrap();
    }
    succeeded(&run_script(&py, &["--save", s(&outs.join(&blend))]));
    assert_eq!(listing(&outs), std::slice::from_ref(&blend));
    let long = outs.join(exr(256));
    refused(&run_script(&py, &["--out", s(&long)]), 1, &["--out", "too long"]);
    assert_eq!(listing(&outs), [blend]);
}

/// Outputs that are FIFOs, links to a FIFO, devices (a null device made in the test's folder, when
/// the test runs as root, who may make one) or folders are refused before any work, and stay what
/// they are.
#[test]
fn blender_script_refuses_outputs_that_are_not_regular_files() {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    for name in ["pipe.exr", "pipe.blend"] {
        mkfifo(&d.join(name));
    }
    for (link, to) in [("link.exr", "pipe.exr"), ("link.blend", "pipe.blend")] {
        std::os::unix::fs::symlink(to, d.join(link)).unwrap();
    }
    std::fs::create_dir(d.join("folder.exr")).unwrap();
    let mut cases = vec![
        ("--out", "pipe.exr", "regular file"),
        ("--save", "pipe.blend", "regular file"),
        ("--out", "link.exr", "regular file"),
        ("--save", "link.blend", "regular file"),
        ("--out", "folder.exr", "folder"),
    ];
    let mut want = vec!["folder.exr", "link.blend", "link.exr", "m.brdf.json", "m.py", "pipe.blend", "pipe.exr"];
    // SAFETY: geteuid has no preconditions.
    let root = unsafe { libc::geteuid() } == 0;
    if root {
        for name in ["null.exr", "null.blend"] {
            let c = std::ffi::CString::new(s(&d.join(name))).unwrap();
            // SAFETY: `c` is a valid NUL-terminated path that outlives the call; (1, 3) is the null
            // device, which takes writes and keeps nothing.
            let rc = unsafe { libc::mknod(c.as_ptr(), libc::S_IFCHR | 0o666, libc::makedev(1, 3)) };
            assert_eq!(rc, 0, "mknod {name}: {}", std::io::Error::last_os_error());
        }
        cases.extend([("--out", "null.exr", "regular file"), ("--save", "null.blend", "regular file")]);
        want.extend(["null.blend", "null.exr"]);
        want.sort();
    }
    for (flag, name, why) in cases {
        let path = d.join(name);
        refused(&run_script(&py, &[flag, s(&path)]), 1, &[flag, s(&path), why]);
    }
    assert!(is_fifo(&d.join("pipe.exr")) && is_fifo(&d.join("pipe.blend")));
    for (link, to) in [("link.exr", "pipe.exr"), ("link.blend", "pipe.blend")] {
        assert_eq!(std::fs::read_link(d.join(link)).unwrap(), Path::new(to));
    }
    for name in ["null.exr", "null.blend"].into_iter().filter(|_| root) {
        let kind = std::fs::symlink_metadata(d.join(name)).unwrap().file_type();
        assert!(kind.is_char_device(), "{name} was replaced");
    }
    assert_eq!(listing(d), want);
    assert_eq!(listing(&d.join("folder.exr")), Vec::<String>::new());
}

/// `--save` over an existing .blend and `--out` over an existing image replace them, keeping their
/// permission bits, and leave nothing beside them (no .blend1 backup, no temporary file).
#[test]
fn blender_script_replaces_existing_outputs_without_leaving_backups() {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    let outs = d.join("out");
    std::fs::create_dir(&outs).unwrap();
    let (blend, exr) = (write(&outs, "s.blend", b"old blend"), write(&outs, "o.exr", b"old image"));
    for p in [&blend, &exr] {
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o640)).unwrap();
    }
    succeeded(&run_script(&py, &["--save", s(&blend), "--out", s(&exr)]));
    assert_eq!(listing(&outs), ["o.exr", "s.blend"]);
    // A .blend starts with `BLENDER`, or with the Zstandard frame magic when compressed (Blender 5's
    // default).
    let saved = std::fs::read(&blend).unwrap();
    assert!(saved.starts_with(b"BLENDER") || saved.starts_with(&[0x28, 0xb5, 0x2f, 0xfd]), "s.blend is not a .blend");
    assert!(std::fs::read(&exr).unwrap().starts_with(&[0x76, 0x2f, 0x31, 0x01]), "o.exr is not an EXR file");
    for p in [&blend, &exr] {
        assert_eq!(std::fs::metadata(p).unwrap().permissions().mode() & 0o7777, 0o640, "{}", p.display());
    }
}

/// Environment maps whose headers declare more texels than brdf-shop reads (src/scene/env.rs:
/// 16384 a side, 8192×4096 in all) are refused from the header, before Blender allocates for them
/// (an EXR of 100000×100000 asks for 160 GB); a FIFO is refused without waiting for a writer.
#[test]
fn blender_script_refuses_environment_headers_beyond_the_limit() {
    let dir = tmp();
    let d = dir.path();
    let py = script(d, "m");
    let big = lying_exr(d, "big.exr", 100_000, 100_000);
    let wide = lying_exr(d, "wide.exr", 65536, 1);
    let square = lying_exr(d, "square.exr", 8192, 8192);
    let hdr = write(d, "big.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n");
    let pipe = d.join("pipe.exr");
    mkfifo(&pipe);
    let out = d.join("o.exr");
    let cases: [(&Path, &[&str]); 5] = [
        (&big, &["100000x100000", "limit"]),
        (&wide, &["65536x1", "16384"]),
        (&square, &["8192x8192", "limit"]),
        (&hdr, &["100000x100000", "limit"]),
        (&pipe, &["regular file"]),
    ];
    for (env, names) in cases {
        let r = run_script(&py, &["--env", s(env), "--out", s(&out)]);
        refused(&r, 1, &[&["--env", s(env)], names].concat());
    }
    assert!(is_fifo(&pipe));
    assert_eq!(listing(d), ["big.exr", "big.hdr", "m.brdf.json", "m.py", "pipe.exr", "square.exr", "wide.exr"]);
}
