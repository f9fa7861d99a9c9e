//! The editor as a user drives it: under Xvfb on this machine's Vulkan device (lavapipe in CI),
//! `edit --replay S --screenshot P --out M --quit` paints the strokes through the window's input path,
//! saves a screenshot and the material, and leaves the recovery file. Debug builds run with the
//! validation layer, and a validation error ends the editor with exit status 4.

use std::path::Path;
use std::process::Command;

use brdf_shop::brdf::Material;

mod common;
#[path = "editor/window.rs"]
mod window;

/// Relative tolerance between the editor's material and `paint`'s: the stroke points pass through
/// window pixel coordinates (`x = x0 + cu·s`, then back), which changes them by about one ulp; the
/// brushes' solves turn that into differences of ~1e-14 (measured), far below 1e-9.
const SAME: f64 = 1e-9;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME * a.abs().max(b.abs()).max(1e-12)
}

fn same_material(a: &Material, b: &Material) -> bool {
    a.lobes.len() == b.lobes.len()
        && a.normalization == b.normalization
        && a.symmetrize == b.symmetrize
        && (0..3).all(|c| close(a.diffuse[c], b.diffuse[c]))
        && a.lobes.iter().zip(&b.lobes).all(|(x, y)| {
            (0..3).all(|c| close(x.albedo[c], y.albedo[c]))
                && close(x.alpha_x, y.alpha_x)
                && close(x.alpha_y, y.alpha_y)
                && close(x.tangent_angle.cos(), y.tangent_angle.cos())
                && close(x.tangent_angle.sin(), y.tangent_angle.sin())
                && x.rotation.abs_diff_eq(y.rotation, 1e-9)
                && x.split == y.split
        })
}

#[test]
fn replay_through_the_window_equals_paint() {
    let dir = tempfile::TempDir::new().unwrap();
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let (shot, out, recovery, painted) = (
        dir.path().join("shot.png"),
        dir.path().join("m.brdf.json"),
        dir.path().join("recovery.brdf.json"),
        dir.path().join("p.brdf.json"),
    );
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x720x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--replay"])
        .arg(&strokes)
        .arg("--screenshot")
        .arg(&shot)
        .arg("--out")
        .arg(&out)
        .args(["--quit", "--size", "960x540"])
        .env("BRDF_SHOP_RECOVERY", &recovery)
        .output()
        .expect("xvfb-run (tools/setup installs xvfb)");
    assert!(run.status.success(), "editor failed: {}", String::from_utf8_lossy(&run.stderr));
    assert!(!String::from_utf8_lossy(&run.stderr).contains("panicked"), "{}", String::from_utf8_lossy(&run.stderr));
    let paint = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["paint", "--strokes"])
        .arg(&strokes)
        .arg("--out")
        .arg(&painted)
        .output()
        .unwrap();
    assert!(paint.status.success());
    let (a, b) = (Material::load(&out).unwrap(), Material::load(&painted).unwrap());
    assert!(same_material(&a, &b), "editor: {a:?}\npaint: {b:?}");
    // The recovery file holds the same material.
    let r = Material::load(&recovery).expect("the recovery file exists and loads");
    assert!(same_material(&r, &a));
    // Every panel of the screenshot has content: mesh (left half), canvas (upper right), graph
    // (lower right). A clear colour would have a spread of 0; 2 (of 255) is well above rounding.
    let img = image::open(&shot).expect("a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (960, 540));
    let canvas = 324; // Layout::new(960, 540): min(480, 540·3/5)
    for (name, rect) in
        [("mesh", (0, 0, 480, 540)), ("canvas", (480, 0, canvas, canvas)), ("graph", (480, canvas, 480, 540 - canvas))]
    {
        let s = common::spread(&img, rect);
        assert!(s > 2.0, "{name} panel looks empty (spread {s:.2})");
    }
}

/// Progressive refinement through the window: with `--converge` the editor keeps adding `mis`
/// samples while nothing changes, up to 1024 per pixel, then leaves (small window to stay fast).
/// The default strokes' material with its lobes alone (`preserve_energy` false), for the sessions
/// that count frames: an energy-preserving material draws one more interaction frame when its
/// tables arrive, after the first or not, as the bake and the pipeline builds share the cores.
fn lobes_alone(dir: &Path) -> std::path::PathBuf {
    let painted = dir.join("painted.brdf.json");
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let (code, _, err) =
        common::run(&["paint", "--strokes", strokes.to_str().unwrap(), "--out", painted.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let m = Material { preserve_energy: false, ..Material::load(&painted).unwrap() };
    let out = dir.join("lobes-alone.brdf.json");
    m.save(&out).unwrap();
    out
}

#[test]
fn idle_frames_refine_the_mesh_view() {
    let dir = tempfile::TempDir::new().unwrap();
    let material = lobes_alone(dir.path());
    let shot = dir.path().join("converged.png");
    let stats = dir.path().join("frames.json");
    let run = Command::new("xvfb-run")
        .args([
            "-a",
            "-s",
            "-screen 0 640x480x24",
            env!("CARGO_BIN_EXE_brdf-shop"),
            "edit",
            "--mesh",
            "sphere",
            "--quit",
            "--converge",
        ])
        .arg("--material")
        .arg(&material)
        // Without a frame budget every refinement frame adds 16 samples (see the next test for the
        // budget's steps).
        .args(["--frame-budget", "0", "--size", "256x144", "--screenshot"])
        .arg(&shot)
        .arg("--frame-stats")
        .arg(&stats)
        .env("BRDF_SHOP_RECOVERY", dir.path().join("recovery.brdf.json"))
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("mesh view at mis 1024 spp"), "{stderr}");
    assert!(!stderr.contains("panicked"), "a thread panicked: {stderr}");
    let img = image::open(&shot).unwrap().to_rgba8();
    assert!(common::spread(&img, (0, 0, 128, 144)) > 2.0, "the mesh view is empty");
    // --frame-stats: one interaction frame (mesh view, compose), then 1024 / 16 =
    // 64 refinement frames, each adding `mis` samples on the GPU (mis, accumulate, compose) without
    // re-rendering the canvas (nothing changed it), each with its GPU time and its passes named.
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let frames = doc["frames"].as_array().unwrap();
    let kind = |k: &str| frames.iter().filter(|f| f["kind"] == k).count();
    assert_eq!((kind("interaction"), kind("refinement")), (1, 64), "{doc}");
    // The canvas is rendered once, by the first frame (which may be one waiting for the mesh
    // view's lobe pipelines).
    let canvases = frames.iter().filter(|f| f["passes"].as_array().unwrap().iter().any(|p| p["name"] == "canvas"));
    assert_eq!(canvases.count(), 1, "{doc}");
    for f in frames {
        let (wall, gpu) = (f["wall_ms"].as_f64().unwrap(), f["gpu_ms"].as_f64().unwrap());
        let passes = f["passes"].as_array().unwrap();
        let has = |n: &str| passes.iter().any(|p| p["name"] == n);
        // (A frame waiting for the mesh view's pipelines may have nothing new to compose.)
        assert!(f["kind"] == "waiting" || (gpu > 0.0 && has("compose")), "{f}");
        assert!(wall > 0.0, "{f}");
        let ms = |n: &str| passes.iter().filter(|p| p["name"] == n).map(|p| p["ms"].as_f64().unwrap()).sum::<f64>();
        if f["kind"] == "refinement" {
            assert!(has("mis") && has("accumulate") && !has("canvas"), "{f}");
            assert_eq!(f["spp"], 16, "{f}");
            // The timestamps time the passes they bracket: 16 `mis` samples a pixel over the
            // sphere cost about two orders of magnitude more than the compose pass (one read and
            // write a window pixel). A first timestamp written only when the next pass flushes the
            // rasteriser, after the pass has run, reads these `mis` passes below the compose pass:
            // this catches a timestamp that does not bracket its pass.
            assert!(ms("mis") > ms("compose"), "the mis pass timed below the compose pass: {f}");
        } else if f["kind"] == "waiting" {
            // The mesh view waits for its lobe pipelines, built off the UI thread: nothing of it.
            assert!(!has("gbuffer") && !passes.iter().any(|p| p["name"].as_str().unwrap().starts_with("lobe")), "{f}");
        } else {
            assert!(has("gbuffer"), "{f}");
        }
        let sum: f64 = passes.iter().map(|p| p["ms"].as_f64().unwrap()).sum();
        assert!((sum - gpu).abs() <= 1e-9 * gpu, "{f}");
        // The whole frame holds its passes (1 ns slack for each tick's rounding); the untimed part
        // is the difference.
        let (frame, untimed) = (f["frame_ms"].as_f64().unwrap(), f["untimed_ms"].as_f64().unwrap());
        assert!(frame > 0.0 && frame + 1e-6 >= gpu, "{f}");
        assert!((untimed - (frame - gpu).max(0.0)).abs() < 1e-9, "{f}");
    }
    assert!(doc["refinement"]["median_frame_ms"].as_f64().unwrap() > 0.0, "{doc}");
    assert!(doc["refinement"]["median_untimed_ms"].as_f64().is_some(), "{doc}");
    assert_eq!(doc["views"]["mesh"]["refined_spp"], 1024);
    assert_eq!(doc["size"], serde_json::json!([256, 144]));
    assert_eq!(doc["refinement"]["frames"], 64);
}

/// With a frame budget (the default, 50 ms), a refinement frame adds as many samples as the budget
/// holds by the refinement frames just finished — one before any was timed, at most 16 — so that a
/// stroke never waits behind seconds of refinement (16 samples at 1280×720 took 1.7–2.5 s on
/// lavapipe); the samples still add up to 1024, weighed by their count (`accumulate`).
#[test]
fn refinement_frames_add_what_the_frame_budget_holds() {
    let dir = tempfile::TempDir::new().unwrap();
    let stats = dir.path().join("frames.json");
    let material = lobes_alone(dir.path());
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--mesh", "sphere"])
        .arg("--material")
        .arg(&material)
        .args(["--quit", "--converge", "--size", "256x144", "--frame-stats"])
        .arg(&stats)
        .env("BRDF_SHOP_RECOVERY", dir.path().join("recovery.brdf.json"))
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success() && !stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("mesh view at mis 1024 spp"), "{stderr}");
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let steps: Vec<u64> = doc["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["kind"] == "refinement")
        .map(|f| f["spp"].as_u64().unwrap())
        .collect();
    assert_eq!(steps.iter().sum::<u64>(), 1024, "{steps:?}");
    assert_eq!(steps[0], 1, "the first refinement frame has nothing to go by: {steps:?}");
    assert!(steps.iter().all(|&s| (1..=16).contains(&s)), "{steps:?}");
    assert_eq!(doc["views"]["mesh"]["refined_spp"], 1024);
}

/// Unsaved work is offered back, not forced: a start that finds a recovery file says so and keeps
/// the starter material until the user presses R (here nobody does).
#[test]
fn recovery_file_is_offered_back() {
    let dir = tempfile::TempDir::new().unwrap();
    let recovery = dir.path().join("recovery.brdf.json");
    let mut m = Material::scratch();
    m.diffuse = [0.1, 0.2, 0.3];
    m.save(&recovery).unwrap();
    let out = dir.path().join("out.brdf.json");
    let run = Command::new("xvfb-run")
        .args([
            "-a",
            "-s",
            "-screen 0 640x480x24",
            env!("CARGO_BIN_EXE_brdf-shop"),
            "edit",
            "--quit",
            "--size",
            "256x144",
            "--out",
        ])
        .arg(&out)
        .env("BRDF_SHOP_RECOVERY", &recovery)
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("press R"), "{stderr}");
    let written = Material::load(&out).unwrap();
    assert_ne!(written.diffuse, [0.1, 0.2, 0.3], "the recovery file was loaded without asking");
    assert_eq!(
        Material::load(&recovery).unwrap().diffuse,
        [0.1, 0.2, 0.3],
        "the offer left the recovery file as it was"
    );
}

/// `brdf-shop` without arguments opens the editor where there is a display; without one it says so
/// in one line and runs the headless demo instead of failing.
#[test]
fn no_arguments_without_a_display_runs_the_demo() {
    let dir = tempfile::TempDir::new().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("no display") && stderr.contains("brdf-shop edit"), "{stderr}");
    assert!(dir.path().join("brdf-shop-demo/material.brdf.json").exists());
}

/// The input logic without a window: strokes through synthesised inputs, undo/redo, the light drag
/// and its reset, orbit only on the mesh view, and the layout's canvas mapping.
#[test]
fn state_handles_inputs_like_the_window() {
    use brdf_shop::brush::strokes::{default_strokes, BrushKind};
    use brdf_shop::editor::state::{stroke_inputs, Input, State};
    use brdf_shop::layout::Layout;
    let strokes = default_strokes().unwrap();
    let settings = strokes.settings("test").unwrap();
    let layout = Layout::new(1280, 720);
    // Canvas coordinates survive the trip through window pixels to 1e-12.
    let (x, y) = layout.canvas_point(0.62, 0.35);
    let (cu, cv) = layout.canvas_coords(x, y);
    assert!((cu - 0.62).abs() < 1e-12 && (cv - 0.35).abs() < 1e-12);
    assert!(layout.in_canvas(x, y) && !layout.in_mesh(x, y));
    let mut s = State::new(Material::scratch(), settings, layout);
    for st in &strokes.strokes {
        for i in stroke_inputs(&s.layout, st) {
            s.handle(i);
        }
    }
    let painted = strokes.replay(&Material::scratch(), "test").unwrap();
    assert!(same_material(s.material(), &painted));
    assert!(s.handle(Input::Undo).material_changed);
    assert!(!same_material(s.material(), &painted));
    assert!(s.handle(Input::Redo).material_changed);
    assert!(same_material(s.material(), &painted));
    // Right-drag on the canvas moves the light to the normal under the cursor; reset brings it back.
    let before = s.settings.canvas.light;
    let (lx, ly) = s.layout.canvas_point(0.5, 0.5);
    s.handle(Input::CursorMoved(lx, ly));
    s.handle(Input::Button { pressed: true, right: true });
    s.handle(Input::Button { pressed: false, right: true });
    assert!(s.light_moved && (s.settings.canvas.light - glam::DVec3::Z).length() < 1e-9);
    s.handle(Input::ResetLight);
    assert!(!s.light_moved && s.settings.canvas.light == before);
    // Dragging on the mesh view orbits; a brush key changes the brush, not the material.
    let yaw = s.yaw;
    let (mx, my) = (s.layout.mesh_x as f64 + 50.0, 300.0);
    s.handle(Input::CursorMoved(mx, my));
    assert!(!s.dragging());
    s.handle(Input::Button { pressed: true, right: false });
    s.handle(Input::CursorMoved(mx + 40.0, my));
    // A held button: the editor keeps its previews until it is released (`preview::steps`).
    assert!(s.dragging());
    s.handle(Input::Button { pressed: false, right: false });
    assert!(!s.dragging());
    assert!(s.yaw != yaw);
    assert!(same_material(s.material(), &painted), "orbiting changed the material");
    s.handle(Input::Brush(BrushKind::Streak));
    assert_eq!(s.brush, BrushKind::Streak);
}

/// Scripted drops (`--drop`): good files (a map, a mesh, a PLY with a second `vertex` element, a
/// material) take effect, bad ones (a broken EXR, a missing OBJ, a glTF whose buffer lies outside
/// its folder, a truncated material) are one stderr line each and a status line, and the session
/// goes on to write `--out` — the material dropped last, after the bad files.
#[test]
fn dropped_files_that_do_not_load_do_not_end_the_session() {
    let dir = tempfile::TempDir::new().unwrap();
    let d = |n: &str| dir.path().join(n);
    std::fs::write(d("broken.exr"), b"not an exr").unwrap();
    std::fs::write(d("cut.brdf.json"), b"{\"format\": \"brdf-shop/material\", \"vers").unwrap();
    std::fs::write(
        d("two-vertex.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nelement vertex 1\nproperty float q\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n5\n",
    )
    .unwrap();
    std::fs::create_dir(d("mesh")).unwrap();
    let escape = serde_json::json!({
        "asset": { "version": "2.0" }, "scenes": [{ "nodes": [0] }], "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0] }],
        "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
        "buffers": [{ "uri": "../two-vertex.ply", "byteLength": 36 }],
    });
    std::fs::write(d("mesh/escape.gltf"), escape.to_string()).unwrap();
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let good = assets.join("bench-4lobes.brdf.json");
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--replay"])
        .arg(assets.join("default.strokes.json"))
        .arg("--drop")
        .arg(d("broken.exr"))
        .arg("--drop")
        .arg(assets.join("hdri/city.exr"))
        .arg("--drop")
        .arg(d("missing.obj"))
        .arg("--drop")
        .arg(d("two-vertex.ply"))
        .arg("--drop")
        .arg(d("mesh/escape.gltf"))
        .arg("--drop")
        .arg(assets.join("meshes/bunny.obj"))
        .arg("--drop")
        .arg(d("cut.brdf.json"))
        .arg("--drop")
        .arg(&good)
        .arg("--out")
        .arg(d("out.brdf.json"))
        .args(["--quit", "--size", "480x320"])
        .env("BRDF_SHOP_RECOVERY", d("recovery.brdf.json"))
        .output()
        .expect("xvfb-run (tools/setup installs xvfb)");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "editor ended: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let refusals: Vec<&str> = stderr.lines().filter(|l| l.contains("not loaded")).collect();
    assert_eq!(refusals.len(), 4, "{stderr}");
    for (line, name) in refusals.iter().zip(["broken.exr", "missing.obj", "escape.gltf", "cut.brdf.json"]) {
        assert!(line.contains(name), "{line}");
    }
    let out = Material::load(&d("out.brdf.json")).unwrap();
    assert!(same_material(&out, &Material::load(&good).unwrap()), "{out:?}");
}

/// A window larger than the display is clamped to it with a message (an Xvfb screen of 640×480,
/// 2000×1500 asked): the session runs and the screenshot is the clamped window.
#[test]
fn a_window_larger_than_the_display_is_clamped() {
    let dir = tempfile::TempDir::new().unwrap();
    let shot = dir.path().join("shot.png");
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--replay"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json"))
        .arg("--screenshot")
        .arg(&shot)
        .args(["--quit", "--size", "2000x1500"])
        .env("BRDF_SHOP_RECOVERY", dir.path().join("recovery.brdf.json"))
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("--size 2000x1500 is larger than the display (640x480): the window is 640x480"),
        "{stderr}"
    );
    let img = image::open(&shot).unwrap().to_rgba8();
    assert!(img.width() <= 640 && img.height() <= 480, "{:?}", img.dimensions());
}

/// `--minimise` without a window manager (plain Xvfb: nobody acts on the request): the script waits
/// its 10 s, says so in one stderr line naming `--minimise`, and the session goes on to its end
/// with nothing skipped (the window was never minimised) and the screenshot taken. Under `timeout`
/// (120 s; the session takes about 13): a script that stops waking up after the wait hangs instead
/// of ending, and fails here with status 124.
#[test]
fn minimise_without_a_window_manager_is_one_line_and_the_session_goes_on() {
    let dir = tempfile::TempDir::new().unwrap();
    let d = |n: &str| dir.path().join(n);
    let run = Command::new("timeout")
        .args(["120", "xvfb-run", "-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit"])
        .arg("--replay")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json"))
        .args(["--minimise", "--quit", "--size", "200x120", "--screenshot"])
        .arg(d("shot.png"))
        .arg("--frame-stats")
        .arg(d("stats.json"))
        .env("BRDF_SHOP_RECOVERY", d("recovery.brdf.json"))
        .output()
        .expect("timeout and xvfb-run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{:?}: {stderr}", run.status);
    assert!(!stderr.contains("panicked") && !stderr.contains("alidation"), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.contains("--minimise")).collect();
    assert_eq!(
        lines,
        ["brdf-shop: --minimise: the window was not minimised within 10 s (is a window manager running?)"]
    );
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d("stats.json")).unwrap()).unwrap();
    assert_eq!(doc["skipped_minimised"], 0);
    assert_eq!(image::open(d("shot.png")).unwrap().to_rgba8().dimensions(), (200, 120));
}

/// The layout fills the window at every size (panel, mesh view and the canvas column side by side,
/// no strip left over), and the orbit camera frames the mesh in the mesh view's narrower extent
/// after every resize; `F` brings the zoom back to that framing.
#[test]
fn the_layout_fills_the_window_and_the_camera_frames_the_mesh() {
    use brdf_shop::editor::state::{Input, State, FRAME_MARGIN};
    use brdf_shop::layout::Layout;
    use brdf_shop::scene::camera::fit_distance;
    for (w, h) in [(1280, 720), (720, 1280), (1920, 800), (640, 480), (300, 2000), (2000, 300)] {
        let l = Layout::new(w, h);
        assert_eq!(l.mesh_x + l.mesh_w + l.canvas, w, "{w}x{h}: {l:?}");
        assert_eq!(l.canvas_x, l.mesh_x + l.mesh_w);
        assert!(l.canvas <= h * 3 / 5 && l.canvas <= l.mesh_w + 1, "{w}x{h}: {l:?}");
    }
    let settings = brdf_shop::brush::strokes::default_strokes().unwrap().settings("test").unwrap();
    let mut s = State::new(Material::scratch(), settings, Layout::new(1280, 720));
    let framed =
        |s: &State| fit_distance(s.fov_deg, s.layout.mesh_w as f64 / s.layout.height as f64, 1.0, FRAME_MARGIN);
    assert!((s.distance - framed(&s)).abs() < 1e-12);
    s.handle(Input::Resized(720, 1280));
    assert!((s.distance - framed(&s)).abs() < 1e-12 && s.distance > 6.0, "{}", s.distance);
    let (mx, my) = (s.layout.mesh_x as f64 + 10.0, 10.0);
    s.handle(Input::CursorMoved(mx, my));
    s.handle(Input::Scroll(2.0));
    assert!(s.distance < framed(&s) * 0.9, "the wheel zooms in: {}", s.distance);
    s.handle(Input::FrameView);
    assert!((s.distance - framed(&s)).abs() < 1e-12 && s.zoom == 1.0);
}

/// Shift-drag on the mesh view turns the environment (and nothing else: the orbit stays); the
/// backdrop's keys switch it to black and back, blur it and brighten it within their ranges; each
/// asks for the session's view settings to be kept.
#[test]
fn shift_drag_turns_the_environment_and_keys_set_the_backdrop() {
    use brdf_shop::editor::backdrop::{Backdrop, BLUR_RANGE};
    use brdf_shop::editor::state::{Input, State, TURN_DEG_PER_PIXEL};
    use brdf_shop::layout::Layout;
    let settings = brdf_shop::brush::strokes::default_strokes().unwrap().settings("test").unwrap();
    let mut s = State::new(Material::scratch(), settings, Layout::new(1280, 720));
    let (mx, my) = (s.layout.mesh_x as f64 + 100.0, 300.0);
    let (yaw, pitch) = (s.yaw, s.pitch);
    s.handle(Input::CursorMoved(mx, my));
    s.handle(Input::Modifiers { shift: true });
    s.handle(Input::Button { pressed: true, right: false });
    let fx = s.handle(Input::CursorMoved(mx + 40.0, my + 25.0));
    assert!(fx.env_turned && fx.session_changed && fx.redraw, "{fx:?}");
    assert!((s.env_rotation - 40.0 * TURN_DEG_PER_PIXEL).abs() < 1e-12, "{}", s.env_rotation);
    assert_eq!((s.yaw, s.pitch), (yaw, pitch), "a Shift-drag does not orbit");
    // Back past zero: the turn stays in [0, 360).
    s.handle(Input::CursorMoved(mx - 200.0, my));
    assert!((s.env_rotation - (360.0 - 200.0 * TURN_DEG_PER_PIXEL)).abs() < 1e-9, "{}", s.env_rotation);
    s.handle(Input::Button { pressed: false, right: false });
    s.handle(Input::Modifiers { shift: false });
    // Without Shift the same drag orbits and leaves the turn.
    let turned = s.env_rotation;
    s.handle(Input::CursorMoved(mx, my));
    s.handle(Input::Button { pressed: true, right: false });
    let fx = s.handle(Input::CursorMoved(mx + 10.0, my));
    assert!(!fx.env_turned && s.env_rotation == turned && s.yaw != yaw);
    s.handle(Input::Button { pressed: false, right: false });
    // The backdrop's keys.
    assert_eq!(s.backdrop, Backdrop::default());
    assert!(s.handle(Input::ToggleBackdrop).session_changed && !s.backdrop.shown);
    s.handle(Input::ToggleBackdrop);
    for _ in 0..40 {
        s.handle(Input::BackdropBlur(true));
    }
    assert_eq!(s.backdrop.blur, BLUR_RANGE.1);
    s.handle(Input::BackdropBrightness(true));
    assert!((s.backdrop.brightness - 1.25).abs() < 1e-12 && s.backdrop.shown);
}
