//! The files the program keeps for itself (the pipeline cache, the editor's recovery file, the
//! report's cached references), the XDG folders they live in, and the editor's outputs with its
//! exports: a FIFO planted at a kept file's name never hangs a command and is left as it is, a
//! relative XDG variable never makes the program write into the current folder, and two outputs of
//! `edit` at one file (however spelled) are refused before the window opens, naming both flags.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::support::*;

fn strokes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json")
}

/// `brdf-shop ARGS` (or, with `window`, `xvfb-run brdf-shop ARGS`) in `cwd` under the GPU limits,
/// with `envs` set and `XDG_CACHE_HOME`, `XDG_STATE_HOME`, `BRDF_SHOP_RECOVERY` and
/// `BRDF_SHOP_PIPELINE_CACHE` removed unless `envs` sets them.
fn run_in(cwd: &Path, window: bool, args: &[&str], envs: &[(&str, &str)]) -> Run {
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg(format!("ulimit -v {GPU_MEM_KIB} && exec \"$0\" \"$@\""));
    if window {
        cmd.arg("xvfb-run").args(["-a", "-s", "-screen 0 640x480x24"]);
    }
    cmd.arg(env!("CARGO_BIN_EXE_brdf-shop")).args(args).current_dir(cwd);
    for k in ["XDG_CACHE_HOME", "XDG_STATE_HOME", "BRDF_SHOP_RECOVERY", "BRDF_SHOP_PIPELINE_CACHE"] {
        cmd.env_remove(k);
    }
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    let what = format!("brdf-shop {}", args.join(" "));
    finish(cmd.spawn().expect("the binary starts (xvfb-run: tools/setup installs xvfb)"), GPU_SECS, &what)
}

/// A FIFO at the pipeline cache's path: `render` and `edit` run as without a cache (the FIFO is
/// never opened for reading, and the cache written at the end is refused at it silently) and
/// leave the FIFO as it is.
#[test]
fn own_files_a_fifo_at_the_pipeline_cache() {
    let dir = tmp();
    let d = dir.path();
    let cache = d.join("cache");
    std::fs::create_dir_all(cache.join("brdf-shop")).unwrap();
    let fifo = cache.join("brdf-shop/pipelines.bin");
    mkfifo(&fifo);
    let envs = [("XDG_CACHE_HOME", s(&cache))];
    let out = d.join("o.png");
    let r = run_in(d, false, &["render", "--view", "canvas", "--size", "8x8", "--out", s(&out)], &envs);
    assert_eq!(r.code, 0, "render: {}", r.stderr);
    assert!(r.stderr.lines().count() == 1 && r.stderr.starts_with("rendered 8x8"), "render said: {}", r.stderr);
    assert_eq!(image::open(&out).expect("a PNG").to_rgba8().dimensions(), (8, 8));
    let m = d.join("m.brdf.json");
    let recovery = d.join("recovery.brdf.json");
    let envs = [("XDG_CACHE_HOME", s(&cache)), ("BRDF_SHOP_RECOVERY", s(&recovery))];
    let strokes = strokes();
    let args = ["edit", "--replay", s(&strokes), "--out", s(&m), "--quit", "--size", "320x200"];
    let r = run_in(d, true, &args, &envs);
    assert_eq!(r.code, 0, "edit: {}", r.stderr);
    brdf_shop::brdf::Material::load(&m).expect("edit wrote --out");
    assert!(is_fifo(&fifo), "the FIFO is left as it is");
    assert_eq!(listing(&cache.join("brdf-shop")), ["pipelines.bin"]);
}

/// A FIFO, a link or a file that is not a material at `BRDF_SHOP_RECOVERY`: `edit` starts without
/// offering it, says so in one warning line naming the file, and leaves it as it is.
#[test]
fn own_files_a_fifo_or_link_at_the_recovery_file() {
    let dir = tmp();
    let d = dir.path();
    let fifo = d.join("fifo.brdf.json");
    mkfifo(&fifo);
    // A link to a material that differs from the start: read through the link, it would be offered.
    let target = write_material(d, "elsewhere.brdf.json", &material_json(2));
    let link = d.join("link.brdf.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let target_bytes = std::fs::read(&target).unwrap();
    let garbage = write(d, "garbage.brdf.json", b"{\"format\": 7");
    for (recovery, why) in [(&fifo, "not a regular file"), (&link, "not a regular file"), (&garbage, "")] {
        let r = run_in(d, true, &["edit", "--quit", "--size", "320x200"], &[("BRDF_SHOP_RECOVERY", s(recovery))]);
        assert_eq!(r.code, 0, "{}: {}", recovery.display(), r.stderr);
        let warnings: Vec<&str> = r.stderr.lines().filter(|l| l.contains("recovery file")).collect();
        assert_eq!(warnings.len(), 1, "one warning line expected: {}", r.stderr);
        assert!(warnings[0].contains(s(recovery)) && warnings[0].contains(why), "{}", warnings[0]);
        assert!(!r.stderr.contains("press R"), "{}: offered: {}", recovery.display(), r.stderr);
    }
    assert!(is_fifo(&fifo), "the FIFO is left as it is");
    assert_eq!(std::fs::read_link(&link).unwrap(), target);
    assert_eq!(std::fs::read(&target).unwrap(), target_bytes);
    assert_eq!(std::fs::read(&garbage).unwrap(), b"{\"format\": 7");
    assert_eq!(listing(d), ["elsewhere.brdf.json", "fifo.brdf.json", "garbage.brdf.json", "link.brdf.json"]);
}

/// Relative `XDG_CACHE_HOME` and `XDG_STATE_HOME` are ignored (the XDG Base Directory
/// specification calls them invalid): the pipeline cache goes to `$HOME/.cache`, the recovery
/// file to `$HOME/.local/state`, and nothing is written into the current folder, by the program
/// or by the driver and layers it loads (Mesa's shader cache, the validation layer's cache).
#[test]
fn own_files_relative_xdg_folders_are_ignored() {
    let dir = tmp();
    let d = dir.path();
    let (home, cwd) = (d.join("home"), d.join("cwd"));
    std::fs::create_dir_all(&home).unwrap();
    std::fs::create_dir_all(&cwd).unwrap();
    let envs = [("HOME", s(&home)), ("XDG_CACHE_HOME", "relcache"), ("XDG_STATE_HOME", "relstate")];
    let out = d.join("o.png");
    let r = run_in(&cwd, false, &["render", "--view", "canvas", "--size", "8x8", "--out", s(&out)], &envs);
    assert_eq!(r.code, 0, "render: {}", r.stderr);
    let m = d.join("m.brdf.json");
    let strokes = strokes();
    let r = run_in(&cwd, true, &["edit", "--replay", s(&strokes), "--out", s(&m), "--quit"], &envs);
    assert_eq!(r.code, 0, "edit: {}", r.stderr);
    assert!(listing(&cwd).is_empty(), "written into the current folder: {:?}", listing(&cwd));
    assert!(home.join(".cache/brdf-shop/pipelines.bin").is_file(), "no pipeline cache under $HOME/.cache");
    let recovered = home.join(".local/state/brdf-shop/recovery.brdf.json");
    assert_eq!(
        brdf_shop::brdf::Material::load(&recovered).expect("the recovery file under $HOME/.local/state"),
        brdf_shop::brdf::Material::load(&m).unwrap()
    );
}

/// `edit`'s exports take part in its same-output check: an export at the file of `--out`,
/// `--screenshot`, `--frame-stats` or another export, however spelled, is refused before the
/// window opens (no display is needed to be refused), naming both flags, and every file is left
/// as it was.
#[test]
fn own_files_edit_exports_are_distinct_outputs() {
    let dir = tmp();
    let d = dir.path();
    std::fs::create_dir(d.join("sub")).unwrap();
    let x = write(d, "x", b"old");
    let other = d.join("sub/../x");
    let (new, new_spelled) = (d.join("new"), d.join("./new"));
    let strokes = strokes();
    let cases: &[(&[&str], &[&str])] = &[
        (&["--out", s(&x), "--export", &format!("glsl={}", s(&x))], &["--export glsl", "--out"]),
        (&["--screenshot", s(&x), "--export", &format!("mitsuba={}", s(&x))], &["--export mitsuba", "--screenshot"]),
        (&["--frame-stats", s(&x), "--export", &format!("blender={}", s(&x))], &["--export blender", "--frame-stats"]),
        (
            &["--export", &format!("glsl={}", s(&x)), "--export", &format!("brdf-explorer={}", s(&other))],
            &["--export brdf-explorer", "--export glsl"],
        ),
        (&["--out", s(&other), "--export", &format!("glsl={}", s(&x))], &["--export glsl", "--out"]),
        (&["--export", &format!("glsl={}", s(&new)), "--out", s(&new_spelled)], &["--export glsl"]),
    ];
    for (args, names) in cases {
        let all = [&["edit", "--replay", s(&strokes), "--quit"][..], args].concat();
        let r = run_with(&all, Input::None, CPU_MEM_KIB, CPU_SECS, &[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")]);
        refused(&r, 1, names);
        assert!(r.stderr.contains("names the same file"), "{}", r.stderr);
    }
    assert_eq!(std::fs::read(&x).unwrap(), b"old");
    assert_eq!(listing(d), ["sub", "x"]);
    assert!(listing(&d.join("sub")).is_empty());
}

/// The report's cached references: a FIFO at an entry's name is refused by its name (one line,
/// exit 1, the FIFO left as it is) instead of hanging the report; an entry larger than the image
/// it holds (a 64 GiB sparse file, past the run's address-space limit if it were read) or full of
/// NaN is computed again with a note naming it, and replaced.
#[test]
fn own_files_the_reference_cache() {
    let dir = tmp();
    let d = dir.path();
    let out = d.join("evt");
    let sweep =
        ["report", "error-vs-time", "--quick", "--size", "8", "--maps", "venice.exr", "--materials", "rough-gm"];
    let args = [&sweep[..], &["--out", s(&out)]].concat();
    let hdri = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hdri");
    let envs = [("BRDF_SHOP_HDRI", s(&hdri))];
    let first = run_with(&args, Input::None, GPU_MEM_KIB, GPU_SECS, &envs);
    assert_eq!(first.code, 0, "{}", first.stderr);
    let cache = out.join("cache");
    let names = listing(&cache);
    assert_eq!(names.len(), 1, "{names:?}");
    let entry = cache.join(&names[0]);
    let good = std::fs::read(&entry).unwrap();
    // NaN values behind a valid header: computed again, with a note.
    let mut nan = good[..16].to_vec();
    nan.extend(std::iter::repeat_n(f32::NAN.to_le_bytes(), (good.len() - 16) / 4).flatten());
    std::fs::write(&entry, &nan).unwrap();
    let r = run_with(&args, Input::None, GPU_MEM_KIB, GPU_SECS, &envs);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let notes: Vec<&str> = r.stderr.lines().filter(|l| l.contains("note:")).collect();
    assert!(notes.len() == 1 && notes[0].contains(s(&entry)) && notes[0].contains("not finite"), "{}", r.stderr);
    assert_eq!(std::fs::read(&entry).unwrap(), good, "the entry is computed again, as it was");
    // A 64 GiB sparse file: refused by its size before it is read.
    let f = std::fs::File::create(&entry).unwrap();
    f.set_len(64 << 30).unwrap();
    drop(f);
    let r = run_with(&args, Input::None, GPU_MEM_KIB, GPU_SECS, &envs);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains(s(&entry)) && r.stderr.contains("larger than the limit"), "{}", r.stderr);
    assert_eq!(std::fs::read(&entry).unwrap(), good);
    // A FIFO: refused by its name.
    std::fs::remove_file(&entry).unwrap();
    mkfifo(&entry);
    let r = run_with(&args, Input::None, GPU_MEM_KIB, GPU_SECS, &envs);
    refused(&r, 1, &[s(&entry), "not a regular file"]);
    assert!(is_fifo(&entry), "the FIFO is left as it is");
    assert_eq!(listing(&cache), names);
}

/// A negative `report error-vs-time --size` is refused naming the flag.
#[test]
fn own_files_a_negative_report_size_names_the_flag() {
    let dir = tmp();
    let out = dir.path().join("evt");
    let r = cpu(&["report", "error-vs-time", "--quick", "--size", "-1", "--out", s(&out)]);
    refused(&r, 1, &["--size", "-1"]);
    assert!(listing(dir.path()).is_empty());
}
