//! `brdf-shop export --format mitsuba` against Mitsuba 3 itself (from PyPI, installed by tools/setup
//! into `<cargo target folder>/mitsuba-venv`, `llvm_ad_rgb` variant on Dr.Jit's LLVM backend).
//!
//! 1. The plug-in's `eval` (through Mitsuba's BSDF interface) equals `brdf-shop eval` to 1e-5
//!    relative on random directions, and its `sample` weights equal `eval / pdf`.
//! 2. The exported file, run as a program, renders a sphere under real maps in Mitsuba's `direct`
//!    integrator (emitter and BSDF sampling with MIS), and the image matches `brdf-shop reference`
//!    within 2 % relative L1 over the object.

// `!(err < bound)` fails on NaN too, which `err >= bound` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use brdf_shop::brdf::Material;
use brdf_shop::reference::relative_l1;
use brdf_shop::rng::Pcg32;
use glam::DVec3;

/// The virtual environment tools/setup makes: `<target>/mitsuba-venv`.
fn python() -> PathBuf {
    common::venv_python("mitsuba-venv", "Mitsuba 3")
}

/// Random pairs over the sphere (a quarter of each below the horizon), as `f32` values.
fn pairs(n: usize) -> Vec<(DVec3, DVec3)> {
    let mut rng = Pcg32::new(5, 11);
    let mut dir = || {
        let t = (rng.next_f64() * 1.25 - 0.25).acos();
        let p = 2.0 * std::f64::consts::PI * rng.next_f64();
        DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos()).as_vec3().as_dvec3()
    };
    (0..n).map(|_| (dir(), dir())).collect()
}

fn numbers(line: &str, tag: &str) -> Vec<f64> {
    let mut it = line.split_whitespace();
    assert_eq!(it.next(), Some(tag), "{line}");
    it.map(|v| v.parse::<f64>().unwrap_or_else(|_| panic!("{line}"))).collect()
}

/// Tolerance 1e-5 (the issue's): the plug-in evaluates in `f64` and returns `f · cos θ_i` in `f32`,
/// which rounds by 6e-8 relative; Dr.Jit's double-precision `exp`/`log` are accurate to ~1e-15.
/// Values below 1e-30 (where `f32` itself loses precision) are compared absolutely.
const EVAL_TOLERANCE: f64 = 1e-5;

#[test]
fn plugin_eval_equals_eval_and_sample_weights_are_eval_over_pdf() {
    let dir = tempfile::tempdir().unwrap();
    let pairs = pairs(2000);
    let text: String =
        pairs.iter().map(|(a, b)| format!("{:?} {:?} {:?} {:?} {:?} {:?}\n", a.x, a.y, a.z, b.x, b.y, b.z)).collect();
    let pairs_file = dir.path().join("pairs.txt");
    std::fs::write(&pairs_file, &text).unwrap();
    let harness = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mitsuba/check_plugin.py");
    for (name, path) in common::export_materials(dir.path()) {
        let m = Material::load(&path).unwrap();
        let plugin = dir.path().join(format!("{name}.py"));
        common::export("mitsuba", &path, &plugin);
        let out = Command::new(python()).arg(&harness).arg(&plugin).arg(&pairs_file).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let lines: Vec<&str> = stdout.lines().collect();
        assert_eq!(lines.len(), 2 * pairs.len(), "{name}");
        let (mut worst, mut worst_w, mut sampled) = (0.0f64, 0.0f64, 0usize);
        for (k, (wi, wo)) in pairs.iter().enumerate() {
            let e = numbers(lines[2 * k], "E");
            let f = m.eval(*wi, *wo);
            let cos = if wi.z > 0.0 && wo.z > 0.0 { wi.z } else { 0.0 };
            for c in 0..3 {
                let want = f[c] * cos;
                let err = (e[c] - want).abs() / want.max(1e-30);
                assert!(err.is_finite(), "{name}: {e:?} against {want}");
                worst = worst.max(err);
            }
            if !(wo.z > 0.0 && wi.z > 0.0) {
                assert_eq!(e[3], 0.0, "{name}: pdf below the horizon");
            }
            // The sample: weight = eval/pdf where the sample is valid, 0 otherwise.
            let s = numbers(lines[2 * k + 1], "S");
            let (w, pdf, ratio) = (&s[3..6], s[6], &s[7..10]);
            if pdf > 0.0 {
                sampled += 1;
                assert!(s[2] > 0.0, "{name}: sample below the horizon with pdf {pdf}");
                for c in 0..3 {
                    worst_w = worst_w.max((w[c] - ratio[c]).abs() / ratio[c].max(1e-6));
                }
            } else {
                assert!(w.iter().all(|&v| v == 0.0), "{name}: weight {w:?} without pdf");
            }
        }
        println!("mitsuba plug-in {name:28} eval worst relative {worst:.2e}, sample weight vs eval/pdf {worst_w:.2e}, {sampled} valid samples");
        assert!(worst < EVAL_TOLERANCE, "{name}: eval differs by {worst:.3e}");
        // eval/pdf in f32 from the same f64 values: a few f32 roundings apart.
        assert!(worst_w < 1e-5, "{name}: sample weights differ from eval/pdf by {worst_w:.3e}");
        // Views above the horizon (3/5 of the pairs) sample valid directions most of the time.
        assert!(sampled > pairs.len() / 3, "{name}: only {sampled} valid samples");
    }
}

/// Renders the exported material with Mitsuba and with `brdf-shop reference`, the map turned by
/// `turn` degrees in both (`--env-rotation`); returns the relative L1 over the object and Mitsuba's
/// wall time in seconds.
#[allow(clippy::too_many_arguments)]
fn compare(
    dir: &Path,
    name: &str,
    material: &Path,
    map: &str,
    size: u32,
    spp: u32,
    ref_spp: u32,
    turn: f64,
) -> (f64, f64) {
    let plugin = dir.join(format!("{name}.py"));
    common::export("mitsuba", material, &plugin);
    let env = common::asset(&format!("hdri/{map}"));
    let size_arg = format!("{size}x{size}");
    let ours = dir.join(format!("{name}-{map}-{turn}-mitsuba.exr"));
    let t = std::time::Instant::now();
    let out = Command::new(python())
        .arg(&plugin)
        .args(["--env", env.to_str().unwrap(), "--size", &size_arg, "--spp", &spp.to_string()])
        .args(["--env-rotation", &turn.to_string(), "--out"])
        .arg(&ours)
        .output()
        .unwrap();
    let seconds = t.elapsed().as_secs_f64();
    assert!(out.status.success(), "{name} {map}: {}", String::from_utf8_lossy(&out.stderr));
    let reference = dir.join(format!("{name}-{map}-reference.exr"));
    common::reference_turned(material, &env, &turn.to_string(), "sphere", &size_arg, ref_spp, &reference);
    let a = common::read_exr(&ours);
    let b = common::read_exr(&reference);
    let covered = a.pixels.iter().zip(&b.pixels).filter(|(p, q)| p[3] >= 0.5 && q[3] >= 0.5).count();
    assert!(covered > (size * size / 4) as usize, "{name} {map}: only {covered} pixels on the object in both");
    (relative_l1(&a, &b).expect("same size, covered pixels"), seconds)
}

/// Tolerance 2 % relative L1 (the issue's). Both sides are Monte Carlo estimates of the same
/// integral (the same bilinear map — the plug-in's scene resamples it for Mitsuba's row convention —,
/// the same BRDF, pixel-centre rays; the tessellated sphere of `reference` against Mitsuba's analytic
/// one). Their noise, measured on studio.exr at 48² (each image against one at 4× the samples):
/// Mitsuba's independent sampler 1.1 % at 4096 spp and so ≈ 0.55 % at 16384, `reference`'s
/// quasi-random MIS 0.5 % at 4096; the pair at 16384/4096 spp measured 0.7–0.9 %. So 2 % leaves the
/// noise room and fails on a systematic difference above about 1 % (the map's row convention left
/// unmatched measured 1.6 % on the background alone; a flipped frame or mis-sampled lobe is 10 %+).
const RENDER_TOLERANCE: f64 = 0.02;

#[test]
fn mitsuba_renders_what_reference_renders() {
    let dir = tempfile::tempdir().unwrap();
    let materials = common::export_materials(dir.path());
    let pick = |n: &str| materials.iter().find(|(name, _)| name == n).unwrap().1.clone();
    // The last two: the map turned (`--env-rotation` in both) by a whole number of columns and by
    // a fraction of one.
    let cases = [
        ("painted-default", "studio.exr", 0.0),
        ("painted-default", "venice.exr", 0.0),
        ("rotated-split-ward", "city.exr", 0.0),
        ("energy-preserving", "venice.exr", 0.0),
        ("painted-default", "studio.exr", 90.0),
        ("rotated-split-ward", "city.exr", -37.0),
    ];
    for (name, map, turn) in cases {
        let (err, seconds) = compare(dir.path(), name, &pick(name), map, 32, 16384, 4096, turn);
        println!("mitsuba vs reference {name:20} {map:12} {turn:5}° relative L1 {err:.4} (mitsuba {seconds:.1} s)");
        assert!(err < RENDER_TOLERANCE, "{name} on {map} turned {turn}°: {err:.4}");
    }
    // The turn is not a no-op: studio turned by 90° lights the painted sphere unlike the unturned map
    // (far beyond the tolerance), so a turn the plug-in ignored or took the other way would fail
    // above.
    let read =
        |turn: &str| common::read_exr(&dir.path().join(format!("painted-default-studio.exr-{turn}-mitsuba.exr")));
    let moved = relative_l1(&read("90"), &read("0")).expect("same size");
    assert!(moved > 5.0 * RENDER_TOLERANCE, "turning the map by 90° moved the image by {moved:.4} only");
}

/// `--mesh F.obj` places the mesh as brdf-shop does (centred on its bounding-box centre, scaled to a
/// bounding sphere of radius 1): the bunny covers the same pixels in Mitsuba as in `reference`, to
/// the rasterisation of its silhouette (the pixel-centre rays are the same; a pixel whose centre
/// grazes a silhouette triangle may go either way: 2 % of the covered count).
#[test]
fn mitsuba_places_mesh_files_like_brdf_shop() {
    let dir = tempfile::tempdir().unwrap();
    let (_, material) = common::export_materials(dir.path()).pop().unwrap();
    let plugin = dir.path().join("p.py");
    common::export("mitsuba", &material, &plugin);
    let bunny = common::asset("meshes/bunny.obj");
    let ours = dir.path().join("bunny-mitsuba.exr");
    // An existing output of other permissions: replaced by a complete image that keeps them.
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(&ours, b"old").unwrap();
    std::fs::set_permissions(&ours, std::fs::Permissions::from_mode(0o640)).unwrap();
    let out = Command::new(python())
        .arg(&plugin)
        .args(["--mesh", bunny.to_str().unwrap(), "--size", "40x40", "--spp", "4", "--out"])
        .arg(&ours)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::metadata(&ours).unwrap().permissions().mode() & 0o7777, 0o640);
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".brdf-shop-"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    let reference = dir.path().join("bunny-reference.exr");
    common::reference_mesh(&material, &bunny, &reference);
    let count = |p: &Path| common::read_exr(p).pixels.iter().filter(|p| p[3] >= 0.5).count() as f64;
    let (a, b) = (count(&ours), count(&reference));
    println!("bunny coverage: mitsuba {a} pixels, reference {b}");
    assert!(b > 200.0 && (a - b).abs() <= 0.02 * b, "mitsuba {a} against reference {b}");
}

/// The exported script's own refusals: one line, exit status 1, no image written.
#[test]
fn mitsuba_script_refuses_bad_arguments_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let (_, material) = common::export_materials(dir.path()).pop().unwrap();
    let plugin = dir.path().join("p.py");
    common::export("mitsuba", &material, &plugin);
    let out_exr = dir.path().join("o.exr");
    let o = out_exr.to_str().unwrap();
    let missing = dir.path().join("missing.exr");
    let png = dir.path().join("o.png");
    // An output that is a FIFO (a device node in a shared folder, a planted pipe): refused before the
    // render, never replaced.
    let fifo = dir.path().join("pipe.exr");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let cases: [(Vec<&str>, &str); 9] = [
        (vec!["--size", "4x4", "--spp", "1", "--out", fifo.to_str().unwrap()], "regular file"),
        (vec!["--env-rotation", "nan", "--out", o], "--env-rotation"),
        (vec!["--env-rotation", "east", "--out", o], "--env-rotation"),
        (vec!["--env", missing.to_str().unwrap(), "--out", o], "missing.exr"),
        (vec!["--env", plugin.to_str().unwrap(), "--out", o], "--env"),
        (vec!["--size", "0x5", "--out", o], "--size"),
        (vec!["--spp", "-3", "--out", o], "--spp"),
        (vec!["--mesh", "cube", "--out", o], "--mesh"),
        (vec!["--out", png.to_str().unwrap()], "--out"),
    ];
    for (args, needle) in cases {
        let r = Command::new(python()).arg(&plugin).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!out_exr.exists(), "{args:?} wrote an image");
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO was replaced");
}

/// Directions of tiny non-unit length (subnormal components, 1e-320): the plug-in's normalisation
/// scales them exactly before taking a reciprocal, so its `brdf_eval` (called directly in `f64`, as
/// Mitsuba's `f32` interface cannot carry 1e-320) equals the model's, which normalises them the same
/// way. Same tolerance as [`EVAL_TOLERANCE`]: both sides evaluate in `f64`.
#[test]
fn plugin_normalises_subnormal_directions() {
    let dir = tempfile::tempdir().unwrap();
    let (name, path) = common::export_materials(dir.path()).swap_remove(0);
    let m = Material::load(&path).unwrap();
    let plugin = dir.path().join("p.py");
    common::export("mitsuba", &path, &plugin);
    let cases = [
        (DVec3::new(1e-320, 2e-320, 3e-320), DVec3::new(0.0, 1e-320, 1e-320)),
        (DVec3::new(0.0, 0.0, 5e-324), DVec3::new(3e-320, 0.0, 4e-320)),
        (DVec3::new(1e-310, -2e-310, 1e-309), DVec3::new(0.3, 0.1, 0.9)),
    ];
    let vec = |v: DVec3| format!("(F64({:e}), F64({:e}), F64({:e}))", v.x, v.y, v.z);
    let mut script = String::from(
        "import importlib.util, sys\nimport mitsuba as mi\nmi.set_variant('llvm_ad_rgb')\n\
         spec = importlib.util.spec_from_file_location('p', sys.argv[1])\n\
         p = importlib.util.module_from_spec(spec)\nspec.loader.exec_module(p)\nF64 = mi.Float64\n",
    );
    for (wi, wo) in &cases {
        script += &format!("print(*[float(c[0]) for c in p.brdf_eval({}, {})])\n", vec(*wi), vec(*wo));
    }
    let out = Command::new(python()).arg("-c").arg(&script).arg(&plugin).output().unwrap();
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), cases.len(), "{stdout}");
    for ((wi, wo), line) in cases.iter().zip(lines) {
        let got: Vec<f64> = line.split_whitespace().map(|v| v.parse().unwrap()).collect();
        let want = m.eval(*wi, *wo);
        for c in 0..3 {
            assert!(want[c] > 0.0, "{name}: the model gives 0 for {wi:?}, {wo:?}");
            let err = (got[c] - want[c]).abs() / want[c];
            assert!(err < EVAL_TOLERANCE, "{name}: {wi:?} {wo:?}: plug-in {} against eval {}", got[c], want[c]);
        }
    }
}
