//! The measurement commands at their CI size (`--quick`) on this machine's Vulkan device (lavapipe in
//! CI), through the library and once each through the binary. They assert what must hold whatever
//! the machine's speed: which passes run, what scales with what, error trends, and zero NaN/Inf.

use std::path::{Path, PathBuf};
use std::process::Command;

use brdf_shop::measure::{bench, error_vs_time, stability};
use brdf_shop::render::{Estimator, Renderer};
use brdf_shop::vk::Context;

/// The repository's maps, wherever the clone is.
fn hdri() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hdri")
}

fn renderer() -> Renderer {
    Renderer::new(Context::new(true, None).expect("a Vulkan 1.3 device with validation (tools/setup)"))
        .expect("renderer")
}

/// What a scene does not need costs nothing: a zero-albedo lobe gets no pass, a diffuse-free
/// material no diffuse pass; and the lobe passes shade from the G-buffer, so their time does not
/// follow the triangle count: from 1 k to 100 k triangles of the same sphere the G-buffer pass grows
/// tens of times while the lobe passes stay within a factor 3 (fastest of 3 frames each; the factor
/// is a bound on the noise of lavapipe sharing 2 cores with the rest of the suite, not a speed target —
/// alone they stay within 1.4). The rows count their pixel-samples, and the device's peak is measured
/// for the share of it the lobe passes reach. The goal scene's `goal-kept` row (the editor's frame
/// while its camera stays) runs the goal row's lobe passes, no G-buffer pass, and a copy of the
/// kept background and diffuse image (`base`) in place of those two passes.
#[test]
fn bench_quick_shows_what_a_scene_does_not_need_costs_nothing() {
    let mut r = renderer();
    let plan = bench::Plan { hdri: hdri(), ..bench::Plan::quick() };
    let rows = bench::run(&mut r, &plan, false).expect("bench");
    let zero = rows.iter().find(|m| m.label == "0 lobes").expect("0 lobes");
    assert!(zero.passes.iter().all(|p| !p.0.starts_with("lobe")), "{:?}", zero.passes);
    let four = rows.iter().find(|m| m.label == "4 lobes").expect("4 lobes");
    assert_eq!(four.passes.iter().filter(|p| p.0.starts_with("lobe")).count(), 4);
    let tri: Vec<_> = rows.iter().filter(|m| m.group == "triangles").collect();
    assert_eq!(tri.len(), 2);
    let (few, many) = (tri[0], tri[1]);
    assert!(many.triangles > 50 * few.triangles);
    let ratio = many.min_ms("lobe") / few.min_ms("lobe");
    eprintln!(
        "lobe passes: {:.3} ms at {} triangles, {:.3} ms at {} (ratio {ratio:.2}); gbuffer {:.3} → {:.3} ms",
        few.min_ms("lobe"),
        few.triangles,
        many.min_ms("lobe"),
        many.triangles,
        few.ms("gbuffer"),
        many.ms("gbuffer")
    );
    assert!(ratio < 3.0, "lobe passes grew with the triangle count: ×{ratio:.2}");
    assert!(many.min_ms("gbuffer") > 5.0 * few.min_ms("gbuffer"), "the G-buffer pass is the one that sees triangles");
    // The scalar baseline runs the same passes.
    let names = |label: &str| -> Vec<String> {
        rows.iter()
            .find(|m| m.label == label)
            .unwrap()
            .passes
            .iter()
            .map(|p| p.0.replace(",scalar", "").replace("[scalar]", "[]"))
            .collect()
    };
    assert_eq!(names("vec4"), names("scalar"));
    // Pixel-samples: the same covered pixels at the same size and spp, so 4 one-view lobes take 4×
    // the samples of 1; the goal material's split rotated lobe counts twice (5 components), `mis`
    // once per pixel and sample.
    let one = rows.iter().find(|m| m.label == "1 lobes").expect("1 lobes");
    assert!(one.pixel_samples > 0 && one.pixel_samples % 8 == 0, "{}", one.pixel_samples);
    assert_eq!(four.pixel_samples, 4 * one.pixel_samples);
    let goal = rows.iter().find(|m| m.group == "goal").expect("the goal row");
    assert_eq!(goal.pixel_samples, 5 * one.pixel_samples, "{}", goal.label);
    // The goal scene with its G-buffer kept: the same shading passes, no G-buffer pass, and the
    // background and diffuse passes' image kept too (one `base` copy in their place). The frame that
    // rasterises adds the diffuse term in its sparse filter (`denoise[sparse,diffuse]`), the kept
    // one has it in `base`.
    let kept = rows.iter().find(|m| m.group == "goal-kept").expect("the kept goal row");
    let shading = |m: &bench::Measurement| -> Vec<String> {
        let kept_base = ["gbuffer", "background", "diffuse"];
        m.passes
            .iter()
            .map(|p| p.0.replace("denoise[sparse,diffuse]", "denoise[sparse]"))
            .filter(|n| !kept_base.contains(&n.as_str()))
            .collect()
    };
    assert!(goal.passes.iter().any(|p| p.0 == "gbuffer"), "{:?}", goal.passes);
    assert!(goal.passes.iter().any(|p| p.0 == "denoise[sparse,diffuse]"), "{:?}", goal.passes);
    assert!(kept.passes.iter().any(|p| p.0 == "denoise[sparse]"), "{:?}", kept.passes);
    assert_eq!(kept.passes.first().map(|p| p.0.as_str()), Some("base"), "{:?}", kept.passes);
    assert_eq!(shading(kept)[1..], shading(goal)[..]);
    assert_eq!(kept.pixel_samples, goal.pixel_samples);
    let mis = rows.iter().find(|m| m.label == "mis").expect("mis");
    assert_eq!(mis.pixel_samples, one.pixel_samples);
    // The peak is measured, and no lobe pass reaches it: lavapipe runs them at 3–10 % of it, so a
    // share past 1 would mean a wrong peak or a flop count off more than tenfold.
    let peak = bench::peak(&r, 3).expect("peak");
    assert!(peak.is_finite() && peak > 0.0, "{peak}");
    for m in rows.iter().filter(|m| m.ms("lobe") > 0.0) {
        let share = m.share_of_peak(peak).expect("lobe rows have a share");
        assert!(share > 0.0 && share < 1.0, "{}: {share} of {peak} GFLOP/s", m.label);
        assert!(m.ns_per_sample() > 0.0);
    }
    let text = bench::table(&rows, "test", peak);
    assert!(text.lines().count() > rows.len(), "{text}");
    assert!(text.contains("goal scene") && text.contains("G-buffer kept"), "{text}");
    // The control row at the start, in the middle and at the end, its verdict in the table; a goal
    // row at each goal size.
    let controls: Vec<_> = rows.iter().filter(|m| m.group == "control").collect();
    assert_eq!(controls.len(), 3, "{:?}", rows.iter().map(|m| &m.label).collect::<Vec<_>>());
    assert_eq!((rows.first().unwrap().group, rows.last().unwrap().group), ("control", "control"));
    assert!(text.contains("control rows") && (text.contains("stable") || text.contains("UNSTABLE")), "{text}");
    let goals: Vec<_> = rows.iter().filter(|m| m.group == "goal").map(|m| m.label.as_str()).collect();
    assert_eq!(goals, ["96x96 key", "160x90 key"]);
    // Every row's whole frame holds its passes (1 ns slack for each tick's rounding).
    for m in &rows {
        assert!(m.frame.0 > 0.0 && m.frame.0 + 1e-6 >= m.total.0 && m.untimed.0 >= 0.0, "{}: {:?}", m.label, m);
    }
}

/// The bench's stability rule at its edge: control rows 4.9 % apart are stable, 5.1 % apart are
/// not (in any order, with a median between), and a row that timed nothing makes a run unstable.
#[test]
fn control_rows_within_five_percent_are_stable() {
    use brdf_shop::measure::control::stability;
    assert!(stability(&[1.0, 1.049]).stable);
    assert!(stability(&[1.049, 1.02, 1.0]).stable);
    assert!(!stability(&[1.0, 1.051]).stable);
    assert!(!stability(&[1.051, 1.02, 1.0]).stable);
    assert!((stability(&[2.0, 2.098]).spread - 0.049).abs() < 1e-12);
    assert!(stability(&[3.0]).stable, "one control row: nothing to compare");
    assert!(!stability(&[1.0, 0.0]).stable && !stability(&[1.0, f64::NAN]).stable);
}

/// The run's verdict counts the goal row of the control rows' configuration beside them: three
/// control rows that agree around a goal row 20 % faster (a run measured on lavapipe: 77.3, 78.0,
/// 75.3 ms around 62.6) make an unstable run; a goal row of another size does not count.
#[test]
fn the_goal_row_at_the_control_size_counts_in_the_verdict() {
    use brdf_shop::measure::bench::{stability, Measurement};
    let row = |group: &'static str, label: &str, ms: f64| Measurement {
        group,
        label: label.to_string(),
        triangles: 1,
        passes: Vec::new(),
        total: (ms, ms, ms),
        frame: (ms, ms, ms),
        untimed: (0.0, 0.0, 0.0),
        pixel_samples: 1,
    };
    let run = |goal: f64, size: &str| {
        vec![
            row("control", "512x512 key, start", 77.331),
            row("goal", size, goal),
            row("goal", "1920x1080 key", 258.8),
            row("control", "512x512 key, middle", 77.971),
            row("control", "512x512 key, end", 75.323),
        ]
    };
    let agreeing = stability(&run(76.0, "512x512 key"));
    assert!(agreeing.stable && (agreeing.spread - (77.971 / 75.323 - 1.0)).abs() < 1e-12, "{agreeing:?}");
    let off = stability(&run(62.574, "512x512 key"));
    assert!(!off.stable && (off.spread - (77.971 / 62.574 - 1.0)).abs() < 1e-12, "{off:?}");
    assert!(stability(&run(62.574, "96x96 key")).stable, "a goal row of another size does not count");
}

/// Error trends on the quick sweep: `plain` and `mis` converge (the error at the most samples is
/// below a third of the error at one sample per pixel), and `mis` at the Monte Carlo rate: below
/// twice 1/√(128/1) ≈ 0.088 of it, the factor 2 for the spread of the two errors, each measured on
/// one 32² frame (measured: 0.023–0.059). `plain` is held to the third alone: it samples the BRDF
/// only, and on studio's small lamps its 1-spp error is a few rare hits, far from the asymptotic
/// rate at these counts (measured: 0.16–0.24 on studio's medium, rough and painted anisotropic
/// lobes, 0.02–0.09 elsewhere). `key` improves to within 2 % relative L1; on the sun
/// map, `fis` at 8 spp beats `plain` at 8 spp on the medium and rough lobes; `key` is within the
/// frontier goal's 8 % at 8 spp on every scene and, for the rough lobe, at 1 spp. Also writes and
/// checks the CSV, plot and summary.
#[test]
fn error_vs_time_quick_trends() {
    let mut r = renderer();
    let dir = tempfile::TempDir::new().unwrap();
    let plan = error_vs_time::Plan { hdri: hdri(), ..error_vs_time::Plan::quick() };
    let (rows, files) = error_vs_time::report(&mut r, &plan, dir.path(), false).expect("report");
    for f in &files {
        assert!(std::fs::metadata(f).map(|m| m.len() > 100).unwrap_or(false), "{} missing or empty", f.display());
    }
    let md = std::fs::read_to_string(&files[2]).unwrap();
    assert!(md.contains("The frontier goal, `key` within 8 %"), "{md}");
    // The fixed costs of a timed pass, measured in the same run: three finite, non-negative numbers.
    let fixed = md.lines().find(|l| l.starts_with("What a timed pass costs before any work")).expect("fixed costs");
    let costs: Vec<f64> = fixed.split(" ms").filter_map(|p| p.rsplit(' ').next()?.parse().ok()).collect();
    assert!(costs.len() == 3 && costs.iter().all(|c| c.is_finite() && *c >= 0.0), "{fixed}");
    let csv = std::fs::read_to_string(&files[0]).unwrap();
    assert_eq!(csv.lines().count(), 1 + plan.envs.len() * plan.materials.len() * 4 * plan.spps.len());
    let png = image::open(&files[1]).expect("the plot is a PNG");
    assert!(png.width() > 500 && png.height() > 400);
    let err = |env: &str, mat: &str, e: Estimator, spp: u32| {
        rows.iter()
            .find(|r| r.env == env && r.material == mat && r.estimator == e && r.spp == spp)
            .unwrap_or_else(|| panic!("{env} {mat} {e:?} {spp}"))
            .rel_l1
    };
    let (first, last) = (plan.spps[0], *plan.spps.last().unwrap());
    for env in &plan.envs {
        for mat in &plan.materials {
            for e in [Estimator::Plain, Estimator::Mis] {
                let (a, b) = (err(env, mat, e, first), err(env, mat, e, last));
                eprintln!("{env} {mat} {}: {a:.4} at {first} spp, {b:.4} at {last}: ratio {:.3}", e.name(), b / a);
                assert!(b < a / 3.0, "{env} {mat} {}: {a} at {first} spp, {b} at {last}", e.name());
                let mc_rate = (first as f64 / last as f64).sqrt();
                if e == Estimator::Mis {
                    assert!(b < 2.0 * mc_rate * a, "{env} {mat} mis: {a} at {first} spp, {b} at {last}");
                }
            }
            // `key` can start near its floor (studio's sharp lobe as the lamp's points: 0.023 at
            // 1 spp), so it must improve and reach 2 % instead; the painted reciprocal materials, which
            // preserve energy, 3 % (their studio scenes measure 0.021 and 0.029 at 128 spp — the
            // compensation pass's SH9 of the residual map is most of the tilted one's —, venice's
            // 0.009 and 0.008).
            let (a, b) = (err(env, mat, Estimator::Key, first), err(env, mat, Estimator::Key, last));
            let bound = if mat.starts_with("painted") { 0.03 } else { 0.02 };
            assert!(b < a && b <= bound, "{env} {mat} key: {a} at {first} spp, {b} at {last}");
        }
    }
    // The default `key` estimator beats the paper's at equal samples, at 8 and at the most, on every
    // scene, and at 8 spp it is within the frontier goal's 8 % on every scene (below; studio's
    // medium lobe, 0.026, sees the lamp as tiles and the softbox as points); and the
    // paper's `fis` renders what `FIS_AT_8` records: lavapipe renders it deterministically (to 1e-3
    // relative: a different LLVM may reorder f32 arithmetic, a changed estimator moves them by far
    // more).
    for env in &plan.envs {
        for mat in &plan.materials {
            for spp in [8, last] {
                let (k, f) = (err(env, mat, Estimator::Key, spp), err(env, mat, Estimator::Fis, spp));
                eprintln!("{env} {mat} {spp} spp: key {k:.4}, fis {f:.4}");
                assert!(k < f, "{env} {mat}: key {k} not below fis {f} at {spp} spp");
            }
            // Within 8 % at 8 spp on every scene: the largest are studio's painted materials,
            // `painted-aniso` 0.055 and `painted-tilted` 0.034; venice's painted scenes 0.022 and
            // 0.011.
            let k8 = err(env, mat, Estimator::Key, 8);
            assert!(k8 <= 0.08, "{env} {mat}: key at 8 spp {k8}, over 8 %");
        }
        // The rough lobe's 1-spp frame (filtered, its shifts stratified over the filter's window,
        // `glsl/lobe.comp`) is within the 8 % too (on lavapipe studio 0.041, venice 0.070).
        let k1 = err(env, "rough-gm", Estimator::Key, 1);
        eprintln!("{env} rough-gm 1 spp: key {k1:.4}");
        assert!(k1 <= 0.08, "{env} rough-gm: key at 1 spp {k1}, over 8 %");
    }
    // The frontier goal on the painted reciprocal scenes: `key` within 8 % at no more whole-frame
    // GPU time than `fis` at 8 spp. Its time half is counted and printed, not asserted: on
    // lavapipe at 32² both estimators' whole frames are 1.7–5.2 ms, mostly fixed cost, and `key`'s
    // filter pass for the rough lobes costs more than the margin, so the count follows the frames'
    // noise (the paper scenes' too); at 256² every quick scene holds it (docs/performance.md,
    // Error against GPU time).
    let painted: Vec<_> = rows.iter().filter(|r| r.material.starts_with("painted")).cloned().collect();
    assert_eq!(painted.len(), plan.envs.len() * 2 * 4 * plan.spps.len(), "two painted materials");
    let (within, scenes) = error_vs_time::goal_count(&painted, |r| r.ms_median);
    eprintln!("frontier goal on the painted reciprocal scenes: {within} of {scenes}");
    for (env, mat, want) in FIS_AT_8 {
        let got = err(env, mat, Estimator::Fis, 8);
        assert!((got / want - 1.0).abs() < 1e-3, "{env} {mat}: fis at 8 spp {got}, recorded {want}");
    }
    for mat in ["medium-gm", "rough-gm"] {
        let (f, p) = (err("studio.exr", mat, Estimator::Fis, 8), err("studio.exr", mat, Estimator::Plain, 8));
        eprintln!("studio {mat}: fis 8 spp {f:.4}, plain 8 spp {p:.4}");
        assert!(f < p, "studio {mat}: fis {f} not below plain {p} at 8 spp");
    }
    // The cache holds one entry a scene; that a run reads an entry back (and computes an unusable
    // one again) is tested where it can fail alone: `measure::reference_cache`'s unit test, and
    // `tests/hostile/own_files.rs` through the binary.
    let cached = std::fs::read_dir(dir.path().join("cache")).unwrap().count();
    assert_eq!(cached, plan.envs.len() * plan.materials.len());
}

/// `fis` at 8 spp on the quick sweep (lavapipe, Mesa 22.3, 32²), as `report error-vs-time --quick`
/// writes them (`rel_l1` of its CSV). A snapshot of this code's own output, not an independent
/// bound: it fails when the paper's estimator renders anything else (a regression check); the
/// independent checks of the estimators are the bounds above (convergence, `key` below `fis`, the
/// 8 % goal, `fis` below `plain`).
const FIS_AT_8: [(&str, &str, f64); 6] = [
    ("studio.exr", "sharp-ward", 0.316382),
    ("studio.exr", "medium-gm", 0.777872),
    ("studio.exr", "rough-gm", 0.621492),
    ("venice.exr", "sharp-ward", 0.047240),
    ("venice.exr", "medium-gm", 0.140379),
    ("venice.exr", "rough-gm", 0.307464),
];

/// The stability grid at its quick size: no NaN or Inf anywhere, and every evaluation case's GPU
/// `f32` within `stability::AGREEMENT_BOUND` of the `f64` model (its doc says why that bound).
#[test]
fn stability_quick_has_no_nan_and_f32_agrees() {
    let mut r = renderer();
    let cases = stability::run(&mut r, true).expect("stability");
    eprint!("{}", stability::table(&cases, "test"));
    assert!(cases.len() >= 20);
    for c in &cases {
        assert_eq!(c.non_finite, 0, "{}: {} non-finite of {}", c.name, c.non_finite, c.values);
        assert!(c.values > 0, "{}", c.name);
        if let Some(a) = c.agreement {
            assert!(a < stability::AGREEMENT_BOUND, "{}: {a}", c.name);
        }
        if let Some(a) = c.max_albedo {
            assert!(a.is_finite() && a > 0.0, "{}: {a}", c.name);
        }
    }
}

#[test]
fn commands_run_through_the_binary() {
    let dir = tempfile::TempDir::new().unwrap();
    let json = dir.path().join("bench.json");
    // Run from the repository root without --hdri or BRDF_SHOP_HDRI: the default `assets/hdri`.
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env_remove("BRDF_SHOP_HDRI")
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let text = run(&["bench", "--quick", "--json", json.to_str().unwrap()]);
    assert!(text.contains("per lobe") && text.contains("scalar"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["configurations"].as_array().unwrap().len() > 5);
    // The run's verdict, the device, its driver, and the clocks (none on lavapipe: not NVIDIA's).
    assert!(v["stable"].is_boolean() && v["control_frame_ms"].as_array().unwrap().len() == 3, "{v}");
    // The goal row at the control size (96², the first goal size) counts in the verdict too.
    assert!(v["control_goal_frame_ms"].as_f64().is_some_and(|ms| ms > 0.0), "{v}");
    assert!(text.contains("control rows") && text.contains("and the goal row"), "{text}");
    assert!(!v["device"].as_str().unwrap().is_empty());
    let driver = &v["driver"];
    assert!(!driver["name"].as_str().unwrap().is_empty() && driver["info"].is_string(), "{driver}");
    assert!(driver["version"].as_str().unwrap().contains('.'), "{driver}");
    assert!(v.get("clocks").is_some_and(|c| c.is_null() || c["start"]["sm_mhz"].is_u64()), "{v}");
    for c in v["configurations"].as_array().unwrap() {
        for k in ["total_ms", "frame_ms", "untimed_ms"] {
            assert!(c[k]["median"].as_f64().is_some(), "{k}: {c}");
        }
    }
    let goal_sizes: Vec<&str> = v["configurations"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["group"] == "goal")
        .map(|c| c["label"].as_str().unwrap())
        .collect();
    assert_eq!(goal_sizes, ["96x96 key", "160x90 key"]);
    let md = dir.path().join("stability.md");
    let text = run(&["report", "stability", "--quick", "--out", md.to_str().unwrap()]);
    assert!(text.contains("NaN/Inf") && md.exists(), "{text}");
    // The sweep at another size, cut down to one map and one material: its summary says the size.
    let evt = dir.path().join("evt");
    let sweep = ["--size", "16", "--maps", "venice.exr", "--materials", "rough-gm", "--out", evt.to_str().unwrap()];
    let text = run(&[&["report", "error-vs-time", "--quick"][..], &sweep[..]].concat());
    assert!(text.contains("Sphere, 16x16") && text.contains("venice.exr/rough-gm"), "{text}");
    let csv = std::fs::read_to_string(evt.join("error-vs-time.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4 * error_vs_time::Plan::quick().spps.len(), "{csv}");
    let out =
        Command::new(env!("CARGO_BIN_EXE_brdf-shop")).args(["report", "error-vs-time", "--quick"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "a missing --out is a usage error");
}

/// A measurement whose map is missing is refused by the map's path (one line, exit 1, nothing
/// written), never measured on the embedded studio map under another name: from `--hdri`, from
/// `BRDF_SHOP_HDRI`, and from the default `assets/hdri` of a current directory that has none.
#[test]
fn a_missing_map_is_refused_by_its_path() {
    let dir = tempfile::TempDir::new().unwrap();
    let empty = dir.path().join("no-maps");
    std::fs::create_dir(&empty).unwrap();
    // Only studio.exr: the report also needs venice.exr.
    let partial = dir.path().join("partial");
    std::fs::create_dir(&partial).unwrap();
    std::fs::copy(hdri().join("studio.exr"), partial.join("studio.exr")).unwrap();
    let (report, json) = (dir.path().join("report"), dir.path().join("bench.json"));
    let (e, p) = (empty.to_str().unwrap(), partial.to_str().unwrap());
    let r = report.to_str().unwrap();
    let cases: [(&[&str], Option<&str>, String); 5] = [
        (&["report", "error-vs-time", "--quick", "--hdri", e, "--out", r], None, format!("{e}/studio.exr")),
        (&["report", "error-vs-time", "--quick", "--hdri", p, "--out", r], None, format!("{p}/venice.exr")),
        (&["report", "error-vs-time", "--quick", "--out", r], Some(e), format!("{e}/studio.exr")),
        (&["bench", "--quick", "--hdri", e, "--json", json.to_str().unwrap()], None, format!("{e}/studio.exr")),
        (&["bench", "--quick", "--json", json.to_str().unwrap()], None, "assets/hdri/studio.exr".into()),
    ];
    for (args, env, names) in cases {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_brdf-shop"));
        // The last case runs where there is no `assets/hdri`.
        cmd.args(args).current_dir(dir.path()).env_remove("BRDF_SHOP_HDRI");
        if let Some(v) = env {
            cmd.env("BRDF_SHOP_HDRI", v);
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{args:?}: {}", String::from_utf8_lossy(&out.stdout));
        assert_eq!(stderr.lines().count(), 1, "{args:?}: one line on stderr, got {stderr:?}");
        assert!(stderr.contains(&names) && stderr.contains("not found"), "{args:?}: {stderr}");
        assert!(!report.exists() && !json.exists(), "{args:?}: something was written");
    }
}

/// `bench --goal`: the goal scene at the control size between a start and an end control row, no
/// other row and no viewer rows, with the run's verdict over the three.
#[test]
fn bench_goal_runs_the_goal_row_between_two_control_rows() {
    let dir = tempfile::TempDir::new().unwrap();
    let json = dir.path().join("goal.json");
    let out = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["bench", "--goal", "--quick", "--json", json.to_str().unwrap()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("BRDF_SHOP_HDRI")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("goal scene 96x96 key") && !text.contains("viewer frames"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows: Vec<(&str, &str)> = v["configurations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["group"].as_str().unwrap(), c["label"].as_str().unwrap()))
        .collect();
    assert_eq!(rows, [("control", "96x96 key, start"), ("goal", "96x96 key"), ("control", "96x96 key, end")], "{v}");
    assert!(v["stable"].is_boolean() && v["control_frame_ms"].as_array().unwrap().len() == 2, "{v}");
    assert!(v["control_goal_frame_ms"].as_f64().is_some_and(|ms| ms > 0.0), "{v}");
    assert_eq!(v["viewer"].as_array().map(Vec::len), Some(0), "{v}");
}

/// `tools/bench-pair`: one pair of the same binary (under validation, as every GPU test) prints both
/// runs' goal rows and a finite ratio; a missing binary or a bad pair count is one line and exit 1.
#[test]
fn bench_pair_compares_two_binaries_in_turn() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/bench-pair");
    let bin = env!("CARGO_BIN_EXE_brdf-shop");
    let run = |args: &[&str]| {
        Command::new(&script).args(args).env("QUICK", "1").env("BRDF_SHOP_VALIDATION", "1").output().unwrap()
    };
    let out = run(&[bin, bin, "1"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary = text.lines().find(|l| l.contains("NEW/OLD over 1 pairs: median")).unwrap_or_else(|| panic!("{text}"));
    let ratio: f64 = summary.split("median ").last().unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(ratio.is_finite() && ratio > 0.0, "{summary}");
    let dir = tempfile::TempDir::new().unwrap();
    let missing = dir.path().join("brdf-shop");
    let missing = missing.to_str().unwrap();
    for (args, what) in [(&[missing, bin][..], "OLD"), (&[bin, bin, "0"][..], "PAIRS")] {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.lines().count() == 1 && err.contains(what), "{args:?}: {err}");
    }
}

/// `tools/gpu-bench` with a stand-in binary (no device needed: it runs the script's own logic): a
/// stable bench writes the six files into `DEST`; an unstable one runs once more, and is written
/// if that run is stable; two unstable runs exit with status 3 and write nothing.
#[test]
fn gpu_bench_reruns_an_unstable_bench_once_and_writes_only_a_stable_run() {
    let dir = tempfile::TempDir::new().unwrap();
    // The stand-in: `bench` answers stable from its STABLE_AT-th run on (counted in a file).
    let fake = dir.path().join("fake-brdf-shop");
    let count = dir.path().join("count");
    let script = r#"#!/bin/sh
case "$1" in
devices) echo '* stand-in';;
bench) n=$(cat 'COUNT' 2>/dev/null || echo 0); n=$((n + 1)); echo $n >'COUNT'
  s=false; [ $n -ge $STABLE_AT ] && s=true; echo "{\"stable\": $s}" >"$3"; echo "run $n";;
report) mkdir -p "$5"; for f in csv md png; do echo x >"$5/error-vs-time.$f"; done;;
*) exit 2;;
esac
"#
    .replace("COUNT", count.to_str().unwrap());
    std::fs::write(&fake, script).unwrap();
    std::fs::set_permissions(&fake, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let run = |stable_at: u32| {
        let _ = std::fs::remove_file(&count);
        let dest = dir.path().join(format!("dest-{stable_at}"));
        // Run from the temporary folder: no `.gl` loader packages or `.gpu-bench` there to use.
        let out = Command::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gpu-bench"))
            .current_dir(dir.path())
            .env("BIN", &fake)
            .env("DEST", &dest)
            .env("STABLE_AT", stable_at.to_string())
            .output()
            .unwrap();
        let runs = std::fs::read_to_string(&count).unwrap().trim().parse::<u32>().unwrap();
        let mut files: Vec<String> = std::fs::read_dir(&dest)
            .map(|d| d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect())
            .unwrap_or_default();
        files.sort();
        (out.status.code(), runs, files, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let all: Vec<String> =
        ["bench.json", "bench.txt", "error-vs-time.csv", "error-vs-time.md", "error-vs-time.png", "gpu.log"]
            .map(String::from)
            .to_vec();
    let (code, runs, files, err) = run(1);
    assert_eq!((code, runs, &files), (Some(0), 1, &all), "{err}");
    let (code, runs, files, err) = run(2);
    assert_eq!((code, runs, &files), (Some(0), 2, &all), "{err}");
    assert!(err.contains("the bench once more"), "{err}");
    let (code, runs, files, err) = run(3);
    assert_eq!((code, runs, files.len()), (Some(3), 2, 0), "{err}");
    assert!(err.contains("unstable run") && err.contains("nothing written"), "{err}");
}
