//! `brdf-shop render` and `reference` through the binary: outputs, `--timings`, and every refusal
//! (one line on stderr, exit 1, no output file left behind). Runs on this machine's Vulkan device
//! (lavapipe in CI); debug builds run with the validation layer, whose errors fail a render.

use std::path::{Path, PathBuf};
use std::process::Command;

use tempfile::TempDir;

fn hdri(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hdri").join(name).display().to_string()
}

fn mesh(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/meshes").join(name).display().to_string()
}

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_brdf-shop")).args(args).output().expect("the binary runs");
    let code = out.status.code().unwrap_or_else(|| panic!("killed by a signal: {:?}", out.status));
    (code, String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn assert_refused((code, stdout, stderr): (i32, String, String), want: i32, names: &[&str]) {
    assert_eq!(code, want, "exit status; stderr: {stderr}");
    assert!(stdout.is_empty(), "{stdout}");
    assert_eq!(stderr.lines().count(), 1, "one line on stderr, got {stderr:?}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in names {
        assert!(stderr.contains(n), "stderr does not name {n:?}: {stderr}");
    }
}

fn out(dir: &TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

#[test]
fn render_writes_exr_png_and_timings() {
    let dir = TempDir::new().unwrap();
    let exr = out(&dir, "a.exr");
    let timings = out(&dir, "t.json");
    let (code, _, stderr) = run(&[
        "render",
        "--env",
        &hdri("studio.exr"),
        "--mesh",
        "torus",
        "--size",
        "48x32",
        "--out",
        exr.to_str().unwrap(),
        "--timings",
        timings.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    // The loader's report names both counts and the negative energy fraction.
    assert!(stderr.contains("negative texel(s) kept") && stderr.contains("% of the energy"), "{stderr}");
    let env = brdf_shop::scene::Environment::load(&exr).expect("the output reads back as EXR");
    assert_eq!((env.width, env.height), (48, 32));
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&timings).unwrap()).unwrap();
    let names: Vec<&str> = t["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    // The default material has a diffuse term and energy-preserving lobes: the G-buffer's pass
    // (which starts the image with the background and the diffuse term), the lobes, then their
    // compensation terms.
    assert_eq!(names[0], "gbuffer", "{names:?}");
    assert_eq!(names.last(), Some(&"compensation"), "{names:?}");
    let lobes = &names[1..names.len() - 1];
    assert!(lobes.iter().all(|n| n.starts_with("lobe")) && !lobes.is_empty(), "{names:?}");
    assert!(t["passes"].as_array().unwrap().iter().all(|p| p["ms"].as_f64().unwrap() >= 0.0));
    // The whole frame holds every pass (their timestamps lie between its two, on one clock: 1 ns
    // slack for the drivers' rounding of each tick), and its untimed part is the difference.
    let (total, frame, untimed) =
        (t["total_ms"].as_f64().unwrap(), t["frame_ms"].as_f64().unwrap(), t["untimed_ms"].as_f64().unwrap());
    assert!(frame + 1e-6 >= total && total > 0.0, "frame {frame} ms, passes {total} ms");
    assert!((untimed - (frame - total).max(0.0)).abs() < 1e-9, "{untimed} {frame} {total}");
    assert!(stderr.contains("(whole frame;") && stderr.contains("untimed"), "{stderr}");
    // The default `key` estimator states its decision: studio's lamp, split off, its lobes with lights.
    assert_eq!(t["estimator"], "key");
    let k = &t["key_lights"];
    assert_eq!(k["lights"].as_array().map(Vec::len), Some(1), "{k}");
    assert!(k["share"].as_f64().unwrap() > 0.5 && k["threshold_over_mean"].as_f64() == Some(30.0), "{k}");
    assert!(lobes.iter().all(|n| n.contains("key,lights")), "{names:?}");
    assert!(stderr.contains("key estimator: 1 key light(s)"), "{stderr}");
    // Beside the lamp, studio's softbox is a wide light, taken as points by lobes of α ≥ 0.42.
    let wide = &k["wide"];
    assert_eq!(wide["lights"].as_array().map(Vec::len), Some(1), "{k}");
    assert!(wide["share"].as_f64().unwrap() > 0.02 && wide["threshold_over_mean"].as_f64() == Some(7.0), "{k}");
    let min_alpha = wide["quadrature_min_alpha"].as_f64().unwrap();
    assert!((0.3..0.45).contains(&min_alpha), "{k}");
    assert!(stderr.contains("1 wide light(s)"), "{stderr}");

    // A map without a compact light: the decision says so and no pass takes the light term.
    let (code, _, stderr) = run(&[
        "render",
        "--env",
        &hdri("venice.exr"),
        "--size",
        "32x32",
        "--out",
        exr.to_str().unwrap(),
        "--timings",
        timings.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&timings).unwrap()).unwrap();
    assert_eq!(t["key_lights"]["lights"].as_array().map(Vec::len), Some(0), "{t}");
    assert_eq!(t["key_lights"]["wide"]["lights"].as_array().map(Vec::len), Some(0), "{t}");
    assert!(t["key_lights"]["wide"]["quadrature_min_alpha"].is_null(), "{t}");
    assert!(t["key_lights"]["decision"].as_str().unwrap().starts_with("no key light"), "{t}");
    let names: Vec<&str> = t["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert!(names.iter().any(|n| n.contains("key")) && !names.iter().any(|n| n.contains("lights")), "{names:?}");

    let png = out(&dir, "a.png");
    let (code, _, stderr) = run(&[
        "render",
        "--view",
        "canvas",
        "--size",
        "40x40",
        "--out",
        png.to_str().unwrap(),
        "--timings",
        timings.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let img = image::open(&png).expect("a PNG").to_rgb8();
    assert_eq!(img.dimensions(), (40, 40));
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&timings).unwrap()).unwrap();
    let names: Vec<&str> = t["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["canvas"], "a canvas view runs the canvas pass alone");
}

#[test]
fn obj_meshes_render() {
    let dir = TempDir::new().unwrap();
    let o = out(&dir, "bunny.exr");
    let (code, _, stderr) = run(&[
        "render",
        "--env",
        &hdri("city.exr"),
        "--mesh",
        &mesh("bunny.obj"),
        "--size",
        "32x32",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(o.exists());
}

#[test]
fn refusals_name_the_problem_and_leave_no_file() {
    let dir = TempDir::new().unwrap();
    let o = out(&dir, "x.exr");
    let os = o.to_str().unwrap();
    let garbage = out(&dir, "garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    let bad_obj = out(&dir, "bad.obj");
    std::fs::write(&bad_obj, "v 0 0 0\nf 1 2 3\n").unwrap();
    let sky = hdri("sky.exr");
    let (no_exr, no_obj) = (out(&dir, "no/such.exr"), out(&dir, "no/such.obj"));
    let (no_exr, no_obj) = (no_exr.to_str().unwrap(), no_obj.to_str().unwrap());
    assert_refused(run(&["render", "--out", os]), 1, &["--env"]);
    assert_refused(run(&["render", "--env", no_exr, "--out", os]), 1, &[no_exr]);
    assert_refused(run(&["render", "--env", garbage.to_str().unwrap(), "--out", os]), 1, &["garbage.exr"]);
    assert_refused(run(&["render", "--env", &sky, "--mesh", bad_obj.to_str().unwrap(), "--out", os]), 1, &["bad.obj"]);
    assert_refused(run(&["render", "--env", &sky, "--mesh", no_obj, "--out", os]), 1, &[no_obj]);
    assert_refused(run(&["render", "--env", &sky, "--size", "0x10", "--out", os]), 1, &["--size"]);
    assert_refused(run(&["render", "--env", &sky, "--size", "ten", "--out", os]), 1, &["--size"]);
    assert_refused(run(&["render", "--env", &sky, "--size", "100000x8", "--out", os]), 1, &["--size", "largest"]);
    assert_refused(run(&["render", "--env", &sky, "--spp", "0", "--out", os]), 1, &["--spp"]);
    assert_refused(
        run(&["render", "--env", &sky, "--estimator", "mis", "--no-prefilter", "--out", os]),
        1,
        &["--no-prefilter"],
    );
    assert_refused(
        run(&["render", "--env", &sky, "--camera", "eye=0,0,0 target=0,0,0", "--out", os]),
        1,
        &["--camera"],
    );
    assert_refused(run(&["render", "--view", "canvas", "--light", "0,0,0", "--out", os]), 1, &["--light"]);
    assert_refused(run(&["render", "--env", &sky, "--out", out(&dir, "x.tiff").to_str().unwrap()]), 1, &["x.tiff"]);
    assert_refused(run(&["render", "--env", &sky, "--frobnicate", "--out", os]), 1, &["--frobnicate"]);
    assert_refused(run(&["reference", "--env", garbage.to_str().unwrap(), "--out", os]), 1, &["garbage.exr"]);
    assert!(!o.exists(), "a refused render left {os}");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 2, "only the two input files remain: {leftovers:?}");
}

#[test]
fn no_vulkan_driver_is_exit_2_with_how_to() {
    let dir = TempDir::new().unwrap();
    let o = out(&dir, "x.png");
    let out = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["render", "--view", "canvas", "--out", o.to_str().unwrap()])
        .env("VK_DRIVER_FILES", dir.path().join("nonexistent/icd.json"))
        .env("VK_ICD_FILENAMES", dir.path().join("nonexistent/icd.json"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("tools/setup"), "{stderr}");
    assert!(!o.exists());
}

#[test]
fn reference_writes_the_same_image_size() {
    let dir = TempDir::new().unwrap();
    let o = out(&dir, "r.exr");
    let (code, _, stderr) = run(&[
        "reference",
        "--env",
        &hdri("venice.exr"),
        "--size",
        "16x12",
        "--spp",
        "16",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let env = brdf_shop::scene::Environment::load(&o).expect("EXR");
    assert_eq!((env.width, env.height), (16, 12));
}

/// `render --plan` prints the frame's plan and renders nothing; with `--out` it renders as well and
/// prints each pass's GPU time beside it, the same passes `--timings` names, whose JSON carries the
/// plan.
#[test]
fn render_plan_prints_the_passes_and_what_is_left_out() {
    let dir = TempDir::new().unwrap();
    let material = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench-4lobes.brdf.json");
    let base = ["render", "--plan", "--material", material.to_str().unwrap(), "--env", &hdri("studio.exr")];
    let sized = |size: &'static str| -> Vec<String> {
        base.iter().map(|s| s.to_string()).chain(["--size".to_string(), size.to_string()]).collect()
    };
    let args = sized("64x64");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, stdout, stderr) = run(&args);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.starts_with("plan of the mesh view: 7 passes\n"), "{stdout}");
    for pass in ["1. gbuffer", "2. clear", "3. lobe0[", "7. denoise[sparse,diffuse]"] {
        assert!(stdout.contains(pass), "{pass}: {stdout}");
    }
    assert!(stdout.contains("left out:\n  - diffuse: drawn by the sparse filter"), "{stdout}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "a plan writes no file");
    // The canvas view is one pass.
    let mut canvas = args.clone();
    canvas.extend(["--view", "canvas"]);
    let (code, stdout, _) = run(&canvas);
    assert_eq!(code, 0, "{stdout}");
    assert!(stdout.starts_with("plan of the canvas view: 1 pass\n  1. canvas\n"), "{stdout}");
    // With `--out`: rendered, each pass timed beside it, the plan in the timings' JSON.
    let (exr, timings) = (out(&dir, "a.exr"), out(&dir, "t.json"));
    let mut rendered = args.clone();
    rendered.extend(["--out", exr.to_str().unwrap(), "--timings", timings.to_str().unwrap()]);
    let (code, stdout, stderr) = run(&rendered);
    assert_eq!(code, 0, "{stderr}");
    assert!(exr.is_file());
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&timings).unwrap()).unwrap();
    let planned: Vec<&str> =
        t["plan"]["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    let timed: Vec<&str> = t["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    let planned_timed: Vec<&str> = planned.iter().copied().filter(|n| *n != "clear").collect();
    assert_eq!(planned_timed, timed, "the plan's timed passes are the frame's");
    assert!(stdout.lines().any(|l| l.contains(" ms ") && l.contains("1. gbuffer")), "{stdout}");
    assert!(stdout.lines().any(|l| l.contains("untimed") && l.contains("2. clear")), "{stdout}");
    // `--timings` without `--out` has no frame to time; the reference has no plan.
    let mut untimed = args.clone();
    untimed.extend(["--timings", timings.to_str().unwrap()]);
    assert_refused(run(&untimed), 1, &["--timings", "--out"]);
    let reference = ["reference", "--plan", "--env", &hdri("studio.exr"), "--size", "8x8"];
    assert_refused(run(&reference), 1, &["--plan"]);
    // Without `--plan`, `--out` is required.
    let (code, _, stderr) = run(&["render", "--env", &hdri("studio.exr")]);
    assert!(code != 0 && stderr.contains("--out"), "{code} {stderr}");
}
