//! `brdf-shop plot` through the binary (README, Commands; docs/editor.md, The BRDF graphs): the
//! albedo plot's maximum is `check`'s measured maximum directional albedo to the bit, for both
//! models; the 3-D view decodes at its `--size` and shows every lobe's colour and the sum's; and
//! every refusal is one line naming the flag or file, exit status 1, nothing written.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use brdf_shop::plot::{lobe_colour, BACKGROUND, SUM_COLOUR};
use serde_json::Value;
use tempfile::TempDir;

/// Runs the binary with `args`; returns the exit status, stdout and stderr.
fn brdf_shop(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs");
    let code = out.status.code().unwrap_or_else(|| panic!("killed by a signal: {:?}", out.status));
    (code, String::from_utf8(out.stdout).expect("UTF-8 stdout"), String::from_utf8(out.stderr).expect("UTF-8 stderr"))
}

fn s(path: &Path) -> &str {
    path.to_str().expect("UTF-8 temporary path")
}

/// The default strokes painted with `paint` onto the scratch material of `model` in `dir`.
fn painted(dir: &Path, model: &str) -> PathBuf {
    let strokes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/default.strokes.json");
    let out = dir.join(format!("{model}.brdf.json"));
    let (code, _, stderr) = brdf_shop(&["paint", "--strokes", s(&strokes), "--model", model, "--out", s(&out)]);
    assert_eq!(code, 0, "paint: {stderr}");
    out
}

/// `check --json`'s measured maximum directional albedo with `samples` Monte Carlo samples.
fn checked_maximum(material: &Path, samples: &str) -> f64 {
    let (code, stdout, stderr) =
        brdf_shop(&["check", "--material", s(material), "--samples", samples, "--pairs", "1000", "--json"]);
    assert!(code == 0 || code == 3, "check: {stderr}");
    let v: Value = serde_json::from_str(&stdout).expect("check --json prints JSON");
    v["max_albedo"]["value"].as_f64().expect("max_albedo.value")
}

/// `plot --kind albedo`'s maximum (the number on its stdout line, printed to the last bit); the PNG
/// it wrote must decode at its `--size`.
fn plotted_maximum(material: &Path, samples: &str, dir: &Path) -> f64 {
    let png = dir.join("albedo.png");
    let args = ["plot", "--material", s(material), "--kind", "albedo", "--samples", samples, "--size", "500x300"];
    let (code, stdout, stderr) = brdf_shop(&[&args[..], &["--out", s(&png)]].concat());
    assert_eq!(code, 0, "plot: {stderr}");
    assert_eq!(image::image_dimensions(&png).expect("a PNG"), (500, 300));
    let value = stdout
        .strip_prefix("maximum directional albedo: ")
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap_or_else(|| panic!("no maximum on stdout: {stdout:?}"));
    value.parse().expect("a number")
}

/// The reciprocal model's quadrature and the paper model's Monte Carlo are deterministic and the
/// plot draws the report's own measurement: the maxima are the same bits, not merely close.
#[test]
fn the_albedo_plots_maximum_is_checks_measured_maximum() {
    let dir = TempDir::new().expect("a temporary folder");
    for (model, samples) in [("reciprocal", "20000"), ("paper", "3000")] {
        let m = painted(dir.path(), model);
        let (plotted, checked) = (plotted_maximum(&m, samples, dir.path()), checked_maximum(&m, samples));
        assert_eq!(plotted.to_bits(), checked.to_bits(), "{model}: plot {plotted} against check {checked}");
    }
}

/// The number of pixels within 40 (RGB distance) of `colour`: a line's pixels, the anti-aliased
/// ones off by at most 40 % of the way to the background.
fn pixels_near(img: &image::RgbImage, colour: [u8; 3]) -> usize {
    img.pixels()
        .filter(|p| (0..3).map(|c| (p.0[c] as f64 - colour[c] as f64).powi(2)).sum::<f64>().sqrt() <= 40.0)
        .count()
}

#[test]
fn the_3d_view_decodes_at_its_size_and_shows_every_lobe_and_the_sum() {
    let dir = TempDir::new().expect("a temporary folder");
    let m = painted(dir.path(), "reciprocal");
    let png = dir.path().join("lobe3d.png");
    let (code, _, stderr) =
        brdf_shop(&["plot", "--material", s(&m), "--kind", "lobe3d", "--size", "400x300", "--out", s(&png)]);
    assert_eq!(code, 0, "plot: {stderr}");
    let img = image::open(&png).expect("a PNG").to_rgb8();
    assert_eq!(img.dimensions(), (400, 300));
    let drawn = img.pixels().filter(|p| p.0 != BACKGROUND).count();
    assert!(drawn > 2_000, "nearly blank: {drawn} pixels off the background");
    let material: Value = serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    let lobes = material["lobes"].as_array().expect("lobes").len();
    assert!(lobes >= 2, "the default strokes paint {lobes} lobes");
    for (what, colour) in (0..lobes).map(|k| (format!("lobe {k}"), lobe_colour(k))).chain([("sum".into(), SUM_COLOUR)])
    {
        let n = pixels_near(&img, colour);
        assert!(n >= 50, "{what}: {n} pixels of {colour:?}");
    }
}

/// Asserts a clean refusal: exit 1, nothing on stdout, one line on stderr naming `name`, and the
/// folder `dir` unchanged by the run.
fn assert_refused(args: &[&str], name: &str, dir: &Path) {
    let listed = listing(dir);
    let (code, stdout, stderr) = brdf_shop(args);
    assert_eq!(code, 1, "{args:?}: exit status; stderr: {stderr}");
    assert!(stdout.is_empty(), "{args:?}: printed {stdout:?}");
    assert!(stderr.lines().count() == 1 && stderr.ends_with('\n'), "{args:?}: stderr must be one line: {stderr:?}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(name), "{args:?}: stderr does not name {name:?}: {stderr}");
    assert_eq!(listing(dir), listed, "{args:?} wrote something");
}

fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[test]
fn refusals_are_one_line_exit_1_and_write_nothing() {
    let dir = TempDir::new().expect("a temporary folder");
    let m = painted(dir.path(), "reciprocal");
    let out = dir.path().join("p.png");
    let (m, o) = (s(&m), s(&out));
    let plot = |kind: &'static str, extra: &[&'static str]| -> Vec<String> {
        let mut a: Vec<String> = ["plot", "--material", m, "--kind", kind, "--out", o].map(String::from).to_vec();
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let cases: Vec<(Vec<String>, String)> = vec![
        (plot("polar", &[]), "--kind".into()),
        (plot("lobe3d", &["--light", "1,2"]), "--light".into()),
        (plot("lobe3d", &["--light", "0,0,0"]), "--light".into()),
        (plot("lobe3d", &["--light", "1,nan,1"]), "--light".into()),
        (plot("lobe3d", &["--size", "10x10"]), "--size".into()),
        (plot("lobe3d", &["--pitch", "95"]), "--pitch".into()),
        (plot("albedo", &["--samples", "1"]), "--samples".into()),
    ];
    for (args, name) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_refused(&args, name, dir.path());
    }
    let missing = dir.path().join("missing.brdf.json");
    assert_refused(
        &["plot", "--material", s(&missing), "--kind", "lobe3d", "--out", o],
        "missing.brdf.json",
        dir.path(),
    );
    let nowhere = dir.path().join("no-such-folder").join("p.png");
    for kind in ["lobe3d", "albedo"] {
        assert_refused(&["plot", "--material", m, "--kind", kind, "--out", s(&nowhere)], "--out", dir.path());
    }
    assert_refused(
        &["plot", "--material", m, "--kind", "lobe3d", "--out", &o.replace(".png", ".jpg")],
        "--out",
        dir.path(),
    );
}

#[test]
fn help_names_every_flag() {
    let (code, stdout, stderr) = brdf_shop(&["plot", "--help"]);
    assert_eq!(code, 0, "{stderr}");
    for flag in ["--material", "--kind", "--out", "--light", "--size", "--yaw", "--pitch", "--scale", "--samples"] {
        assert!(stdout.contains(flag), "--help does not describe {flag}: {stdout}");
    }
    assert!(stdout.contains("lobe3d") && stdout.contains("albedo"), "{stdout}");
}
