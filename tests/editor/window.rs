//! The editor's window against the headless renderer and its frame budget: screenshots, preview
//! frames while interacting, and a scripted session with every kind of input.

use super::*;

/// The window shows what the headless renderer renders: the screenshot's mesh view and
/// canvas equal `render` of the same views — size, camera, exposure and canvas light read from
/// `--frame-stats`'s `views`, the backdrop's brightness and blur and the environment's turn
/// included — within 1 level of 255 per channel. Both run the same passes with the
/// same frame seed; what may differ is the sRGB encoding (the compose pass in f32 and the PNG writer
/// in f64 can round a value within f32 error of a half level differently: one level). The snap
/// marker's pixels (its colour exactly) are left out of the canvas.
#[test]
fn screenshot_equals_the_headless_render_of_the_same_views() {
    let dir = tempfile::TempDir::new().unwrap();
    let d = |n: &str| dir.path().join(n);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let map = root.join("assets/hdri/studio.exr");
    let bin = env!("CARGO_BIN_EXE_brdf-shop");
    // A kept session: the map turned and the backdrop brighter and blurred (what the render below
    // must match).
    let session = r#"{"env_rotation": 40.0, "backdrop": {"shown": true, "brightness": 1.5, "blur": 1.5}}"#;
    std::fs::write(d("session.json"), session).unwrap();
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x720x24", bin, "edit", "--env"])
        .arg(&map)
        .arg("--replay")
        .arg(root.join("assets/default.strokes.json"))
        .arg("--screenshot")
        .arg(d("shot.png"))
        .arg("--out")
        .arg(d("m.brdf.json"))
        .arg("--frame-stats")
        .arg(d("stats.json"))
        // A budget no device meets: every interaction frame after the first is previewed at the
        // smallest step, and the screenshot is of the frame that settles the views at full size.
        .args(["--quit", "--size", "960x540", "--frame-budget", "1"])
        .env("BRDF_SHOP_RECOVERY", d("recovery.brdf.json"))
        .env("BRDF_SHOP_SESSION", d("session.json"))
        .output()
        .expect("xvfb-run (tools/setup installs xvfb)");
    assert!(run.status.success(), "editor failed: {}", String::from_utf8_lossy(&run.stderr));
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d("stats.json")).unwrap()).unwrap();
    let (mesh, canvas) = (&doc["views"]["mesh"], &doc["views"]["canvas"]);
    let n = |v: &serde_json::Value| v.as_u64().unwrap() as u32;
    let (mx, mw, mh) = (n(&mesh["x"]), n(&mesh["width"]), n(&mesh["height"]));
    assert_eq!((mesh["env_rotation"].as_f64(), mesh["backdrop"]["blur"].as_f64()), (Some(40.0), Some(1.5)));
    let (cx, side) = (n(&canvas["x"]), n(&canvas["side"]));
    let render = |out: &Path, args: &[String]| {
        let r = Command::new(bin)
            .args(["render", "--material"])
            .arg(d("m.brdf.json"))
            .args(args)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        assert!(r.status.success(), "render failed: {}", String::from_utf8_lossy(&r.stderr));
        image::open(out).unwrap().to_rgb8()
    };
    let mesh_img = render(
        &d("mesh.png"),
        &[
            "--env".into(),
            map.display().to_string(),
            "--mesh".into(),
            "torus".into(),
            "--size".into(),
            format!("{mw}x{mh}"),
            "--spp".into(),
            mesh["spp"].to_string(),
            "--camera".into(),
            mesh["camera"].as_str().unwrap().into(),
            "--exposure".into(),
            mesh["exposure"].to_string(),
            "--env-rotation".into(),
            mesh["env_rotation"].to_string(),
            "--backdrop-brightness".into(),
            mesh["backdrop"]["brightness"].to_string(),
            "--backdrop-blur".into(),
            mesh["backdrop"]["blur"].to_string(),
        ],
    );
    let canvas_img = render(
        &d("canvas.png"),
        &[
            "--view".into(),
            "canvas".into(),
            "--size".into(),
            format!("{side}x{side}"),
            "--light".into(),
            canvas["light"].as_str().unwrap().into(),
            "--exposure".into(),
            canvas["exposure"].to_string(),
        ],
    );
    let shot = image::open(d("shot.png")).unwrap().to_rgba8();
    let mut worst = [0i32; 2];
    let mut compared = [0usize; 2];
    for (k, (img, x0, w, h)) in [(&mesh_img, mx, mw, mh), (&canvas_img, cx, side, side)].into_iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                let s = shot.get_pixel(x0 + x, y);
                if k == 1 && [s[0], s[1], s[2]] == [255, 210, 60] {
                    continue;
                }
                let r = img.get_pixel(x, y);
                let diff = (0..3).map(|c| (s[c] as i32 - r[c] as i32).abs()).max().unwrap();
                worst[k] = worst[k].max(diff);
                compared[k] += 1;
            }
        }
    }
    assert!(compared[0] == (mw * mh) as usize && compared[1] > (side * side) as usize * 9 / 10, "{compared:?}");
    assert!(worst[0] <= 1 && worst[1] <= 1, "largest difference (mesh view, canvas): {worst:?} levels");
}

/// While the user paints, the views that change are rendered smaller to fit `--frame-budget` (the
/// steps of `editor::preview::LEVELS`) and magnified; the first frame without a change renders them
/// at full size (a settle frame), so a session's last frame is never a preview. `--frame-budget 0`
/// renders every frame at full size.
#[test]
fn interaction_frames_are_previewed_to_fit_the_budget_and_settle_at_full_size() {
    let dir = tempfile::TempDir::new().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // The scratch material with its lobes alone: an energy-preserving one draws one more frame when
    // its compensation tables arrive, which this session's count of frames does not expect.
    let scratch = dir.path().join("scratch.brdf.json");
    brdf_shop::brdf::Material { preserve_energy: false, ..brdf_shop::brdf::Material::scratch() }
        .save(&scratch)
        .unwrap();
    let session = |budget: &str| {
        let stats = dir.path().join(format!("stats-{budget}.json"));
        let run = Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 1280x720x24", env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--replay"])
            .arg(root.join("assets/default.strokes.json"))
            .arg("--material")
            .arg(&scratch)
            .arg("--frame-stats")
            .arg(&stats)
            .args(["--quit", "--size", "640x360", "--frame-budget", budget])
            .env("BRDF_SHOP_RECOVERY", dir.path().join("recovery.brdf.json"))
            .output()
            .expect("xvfb-run (tools/setup installs xvfb)");
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success() && !stderr.contains("panicked"), "{stderr}");
        let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        doc
    };
    let names = |f: &serde_json::Value| -> Vec<String> {
        f["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
    };
    // 1 ms: no device draws these frames so fast, so every frame after the first one timed is
    // previewed at the smallest step, 0.25.
    let doc = session("1");
    let frames = doc["frames"].as_array().unwrap();
    let scale = |f: &serde_json::Value| f["scale"].as_f64().unwrap();
    let interaction: Vec<_> = frames.iter().filter(|f| f["kind"] == "interaction").collect();
    assert!(interaction.len() >= 4, "{doc}");
    // The first frame (the scratch material: no lobe pipeline to wait for) has nothing to predict
    // from. It is filed once the frame that reuses its slot of the ring has begun (two frames in
    // flight), after that frame's scale was chosen: so from the fourth frame on (of any kind),
    // every interaction frame is a preview.
    assert_eq!((frames[0]["kind"].as_str(), scale(&frames[0])), (Some("interaction"), 1.0), "{doc}");
    for f in frames[3..].iter().filter(|f| f["kind"] == "interaction") {
        assert_eq!(scale(f), 0.25, "{f}");
    }
    assert!(frames[3..].iter().filter(|f| f["kind"] == "interaction").count() >= 3, "{doc}");
    let last = frames.last().unwrap();
    assert_eq!((last["kind"].as_str(), scale(last)), (Some("settle"), 1.0), "{doc}");
    assert!(names(last).iter().any(|p| p.starts_with("lobe")), "{last}");
    assert_eq!(doc["settle"]["frames"], 1, "{doc}");
    // The canvas settles in the first full-size frame after the previews: the settle frame
    // (`waiting` frames, the mesh view waiting for a pipeline, may come before it).
    let after = frames.iter().rposition(|f| f["kind"] == "interaction").expect("interaction frames") + 1;
    let settling = &frames[after..];
    assert!(settling.iter().all(|f| ["waiting", "settle"].contains(&f["kind"].as_str().unwrap())), "{doc}");
    assert!(settling.iter().all(|f| scale(f) == 1.0), "{doc}");
    let canvas = settling.iter().filter(|f| names(f).iter().any(|p| p == "canvas")).count();
    assert_eq!(canvas, 1, "the canvas was settled {canvas} times: {doc}");
    // The previews' lobe passes cost less than the settle frame's (a sixteenth of the pixels: 1.5–3.9
    // ms a frame against 22.8 at 640×360 on lavapipe, release build, measured).
    let lobe_ms = |f: &serde_json::Value| {
        let p = f["passes"].as_array().unwrap();
        p.iter()
            .filter(|p| p["name"].as_str().unwrap().starts_with("lobe"))
            .map(|p| p["ms"].as_f64().unwrap())
            .sum::<f64>()
    };
    let last_preview = interaction.iter().rev().find(|f| lobe_ms(f) > 0.0).expect("a previewed frame with lobes");
    assert!(lobe_ms(last_preview) < lobe_ms(last), "{last_preview} against {last}");
    // 0: every frame at full size, nothing to settle.
    let doc = session("0");
    let frames = doc["frames"].as_array().unwrap();
    assert!(frames.iter().all(|f| scale(f) == 1.0 && f["kind"] != "settle"), "{doc}");
    assert_eq!(doc["settle"]["frames"], 0, "{doc}");
}

/// The start of a command line that runs the rest under Xvfb with a window manager (openbox,
/// which `tools/setup` installs): minimising is the window manager's to do. The program starts once
/// openbox has started (its `--startup` command), or the command fails naming openbox.
fn xvfb_with_window_manager() -> Command {
    let script = r#"ready="$(mktemp -u)"
openbox --sm-disable --startup "touch $ready" >/dev/null 2>&1 &
i=0
while [ ! -e "$ready" ]; do
  i=$((i + 1)); [ $i -le 400 ] || { echo "openbox did not start within 20 s" >&2; exit 3; }
  sleep 0.05
done
rm -f "$ready"
exec "$@""#;
    let mut c = Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 800x600x24", "sh", "-c", script, "sh"]);
    c
}

/// A whole scripted session under the validation layer (debug builds turn it on, and a validation
/// error ends the editor with an error), with a window manager: paint the default strokes, drop a
/// good map, a broken map, a good mesh and a cut material (the broken ones are status lines), resize
/// the window twice, minimise it (the script waits for the window manager, holds it minimised for
/// half a second and asks it to redraw, which must draw nothing) and restore it, then refine the
/// mesh view to 1024 spp. The session ends cleanly, the last frame has the last size, the
/// refinement reached 1024 spp, and the minimised window skipped its redraws without spinning:
/// at least the one the script asks for, and fewer than 10 in the half second (a window that asks
/// to redraw itself after every redraw skips hundreds).
#[test]
fn a_scripted_session_paints_drops_resizes_minimises_and_refines_without_validation_errors() {
    let dir = tempfile::TempDir::new().unwrap();
    let d = |n: &str| dir.path().join(n);
    std::fs::write(d("broken.exr"), b"not an exr").unwrap();
    std::fs::write(d("cut.brdf.json"), b"{\"format\": \"brdf-shop/material\", \"vers").unwrap();
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let run = xvfb_with_window_manager()
        .args([env!("CARGO_BIN_EXE_brdf-shop"), "edit", "--replay"])
        .arg(assets.join("default.strokes.json"))
        .arg("--drop")
        .arg(assets.join("hdri/venice.exr"))
        .arg("--drop")
        .arg(d("broken.exr"))
        .arg("--drop")
        .arg(assets.join("meshes/bunny.obj"))
        .arg("--drop")
        .arg(d("cut.brdf.json"))
        .args(["--resize", "400x300", "--resize", "360x200", "--minimise", "--quit", "--converge"])
        .args(["--size", "320x240", "--frame-stats"])
        .arg(d("stats.json"))
        .env("BRDF_SHOP_RECOVERY", d("recovery.brdf.json"))
        .output()
        .expect("xvfb-run (tools/setup installs xvfb)");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "editor ended: {stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("alidation"), "{stderr}");
    assert!(stderr.contains("mesh view at mis 1024 spp"), "{stderr}");
    assert_eq!(stderr.lines().filter(|l| l.contains("not loaded")).count(), 2, "{stderr}");
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d("stats.json")).unwrap()).unwrap();
    assert_eq!(doc["size"], serde_json::json!([360, 200]), "{}", doc["size"]);
    assert_eq!(doc["views"]["mesh"]["refined_spp"], 1024);
    assert!(doc["refinement"]["frames"].as_u64().unwrap() >= 64, "{}", doc["refinement"]);
    assert!(!stderr.contains("--minimise"), "{stderr}");
    let skipped = doc["skipped_minimised"].as_u64().unwrap();
    assert!((1..10).contains(&skipped), "redraws skipped while minimised: {skipped}");
}

/// The editor frames the whole mesh in its view at every window shape, and its layout fills the
/// window: under Xvfb at 1280×720, 720×1280 and 1920×800, with the backdrop switched to black (a
/// kept session), every pixel of the mesh view's border band (4 pixels wide) is black — no object
/// pixel touches the view's edges — while the view holds the lit torus; and the panel, the mesh
/// view and the canvas column fill the window's width exactly.
#[test]
fn the_mesh_is_framed_in_its_view_at_every_window_shape() {
    let dir = tempfile::TempDir::new().unwrap();
    let d = |n: &str| dir.path().join(n);
    std::fs::write(
        d("session.json"),
        r#"{"env_rotation": 0, "backdrop": {"shown": false, "brightness": 1, "blur": 0}}"#,
    )
    .unwrap();
    let bin = env!("CARGO_BIN_EXE_brdf-shop");
    for (w, h) in [(1280u32, 720u32), (720, 1280), (1920, 800)] {
        let run = Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 1920x1280x24", bin, "edit", "--screenshot"])
            .arg(d("shot.png"))
            .arg("--frame-stats")
            .arg(d("stats.json"))
            .args(["--quit", "--size", &format!("{w}x{h}")])
            .env("BRDF_SHOP_RECOVERY", d("recovery.brdf.json"))
            .env("BRDF_SHOP_SESSION", d("session.json"))
            .output()
            .expect("xvfb-run (tools/setup installs xvfb)");
        assert!(run.status.success(), "{w}x{h}: {}", String::from_utf8_lossy(&run.stderr));
        let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d("stats.json")).unwrap()).unwrap();
        let (mesh, canvas) = (&doc["views"]["mesh"], &doc["views"]["canvas"]);
        let n = |v: &serde_json::Value| v.as_u64().unwrap() as u32;
        let (mx, mw, mh) = (n(&mesh["x"]), n(&mesh["width"]), n(&mesh["height"]));
        let shot = image::open(d("shot.png")).unwrap().to_rgba8();
        assert_eq!(shot.dimensions(), (w, h));
        assert_eq!((mh, n(&canvas["x"]) + n(&canvas["side"])), (h, w), "{w}x{h}: the layout leaves a strip");
        assert_eq!(mx + mw, n(&canvas["x"]));
        const BAND: u32 = 4;
        let lit = |x: u32, y: u32| shot.get_pixel(mx + x, y).0[..3].iter().any(|&c| c > 0);
        let (mut lo, mut hi) = ((mw, mh), (0, 0));
        for y in 0..mh {
            for x in 0..mw {
                let border = x < BAND || y < BAND || x >= mw - BAND || y >= mh - BAND;
                if lit(x, y) {
                    assert!(!border, "{w}x{h}: an object pixel at ({x}, {y}) of the {mw}x{mh} mesh view's border");
                    (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
                }
            }
        }
        // Framed, not lost: the torus's outer rim (its bounding sphere's equator) spans about
        // 1 / FRAME_MARGIN = 80 % of the view's narrower extent across the image; more than half
        // of it, so the check is not vacuous.
        let span = hi.0.saturating_sub(lo.0).max(hi.1.saturating_sub(lo.1));
        assert!(2 * span > mw.min(mh), "{w}x{h}: the object spans {span} of {}", mw.min(mh));
    }
}
