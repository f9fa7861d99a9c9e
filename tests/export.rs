//! `brdf-shop export` for the GLSL formats and the command's refusals, through the real binary.
//!
//! The exported GLSL (`--format glsl`) and BRDF Explorer file (`--format brdf-explorer`) are compiled
//! with shaderc's `glslc` (installed by tools/setup) and run on this machine's Vulkan device
//! (lavapipe in CI) with the validation layer on, through the evaluation pass's interface
//! (`EvalPass::from_spirv`); their values are compared with the `f64` model that `brdf-shop eval`
//! prints. The BRDF Explorer file is read the way BRDF Explorer reads it (`BRDFBase::loadBRDF`: the
//! first line names the type, blank lines and lines starting with `#` are skipped, `::begin`/`::end`
//! sections, parameter lines `float NAME MIN MAX VALUE`, `bool NAME VALUE`, `color NAME R G B`) and
//! wrapped the way it wraps it (`loadShaderFromFile`: one `uniform` per parameter at
//! `::INSERT_UNIFORMS_HERE::`, the shader section at `::INSERT_BRDF_FUNCTION_HERE::` of its
//! `#version 410` lit-sphere template), which must compile for OpenGL; the values are then computed
//! with the uniforms replaced by constants holding the parameter values BRDF Explorer would set.

// `!(err < bound)` fails on NaN too, which `err >= bound` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod common;

use std::path::Path;
use std::process::Command;

use brdf_shop::brdf::{Lobe, Material};
use brdf_shop::render::eval::EvalPass;
use brdf_shop::rng::Pcg32;
use brdf_shop::vk::Context;
use glam::DVec3;

fn export(material: &Path, format: &str, out: &Path) -> String {
    let (code, _, err) = common::run(&[
        "export",
        "--material",
        material.to_str().unwrap(),
        "--format",
        format,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "export {format}: {err}");
    std::fs::read_to_string(out).unwrap()
}

/// `glslc` on `src` (stage and target as glslc flags); SPIR-V bytes, or the compiler's message.
fn glslc(src: &str, dir: &Path, name: &str, flags: &[&str]) -> Result<Vec<u8>, String> {
    let input = dir.join(name);
    std::fs::write(&input, src).unwrap();
    let spv = dir.join(format!("{name}.spv"));
    let out = Command::new("glslc")
        .args(flags)
        .arg(&input)
        .arg("-o")
        .arg(&spv)
        .output()
        .expect("glslc (tools/setup installs it)");
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    Ok(std::fs::read(spv).unwrap())
}

/// A compute shader with `eval.comp`'s interface around `body`, writing `call` for each pair
/// (`wi`, `wo` in scope).
fn compute_wrapper(body: &str, call: &str) -> String {
    format!(
        "#version 450
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Pairs {{ vec4 v[]; }} pairs;
layout(std430, set = 0, binding = 1) writeonly buffer Values {{ vec4 v[]; }} values;
layout(push_constant) uniform Push {{ uint count; }} pc;
{body}
void main() {{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 wi = pairs.v[2u * i].xyz;
    vec3 wo = pairs.v[2u * i + 1u].xyz;
    values.v[i] = vec4({call}, 0.0);
}}
"
    )
}

/// Random unit pairs over the whole sphere (a quarter below the horizon, where f is 0), plus the
/// stiff ones: normal incidence, grazing (89.9°), mirror and retro-reflection.
fn pairs() -> Vec<(DVec3, DVec3)> {
    let mut rng = Pcg32::new(12, 7);
    let dir = |t: f64, p: f64| DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
    let mut out = Vec::new();
    for _ in 0..4000 {
        let wi = dir((rng.next_f64() * 2.0 - 0.5).acos().min(3.1), std::f64::consts::TAU * rng.next_f64());
        let wo = dir((rng.next_f64() * 2.0 - 0.5).acos().min(3.1), std::f64::consts::TAU * rng.next_f64());
        out.push((wi, wo));
    }
    let g = 89.9f64.to_radians();
    for (a, b) in [(0.0, 0.0), (g, g), (0.5, 0.5)] {
        out.push((dir(a, 0.3), dir(b, 0.3 + std::f64::consts::PI)));
        out.push((dir(a, 0.3), dir(b, 0.3)));
    }
    out
}

/// The worst `|g − f| / max(f, 1e-4 · peak)` over pairs and channels (the value where it matters,
/// absolute in the far tails where `f32`'s `exp` of a large exponent keeps no relative precision).
/// Values below the horizon must be exactly 0 on both sides.
fn worst_error(m: &Material, pairs: &[(DVec3, DVec3)], got: &[[f32; 3]]) -> f64 {
    let want: Vec<[f64; 3]> = pairs.iter().map(|(wi, wo)| m.eval(*wi, *wo)).collect();
    let peak = want.iter().flatten().copied().fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for ((f, g), (wi, wo)) in want.iter().zip(got).zip(pairs) {
        for c in 0..3 {
            let g = g[c] as f64;
            assert!(g.is_finite(), "non-finite {g} at {wi:?} {wo:?}");
            if !(wi.z > 0.0 && wo.z > 0.0) {
                assert_eq!(g, 0.0, "below the horizon at {wi:?} {wo:?}");
            }
            let e = (g - f[c]).abs() / f[c].max(1e-4 * peak).max(1e-300);
            worst = worst.max(e);
        }
    }
    worst
}

/// The f32 tolerance of `tests/model.rs` (`f32_agrees_with_f64`): `f32` carries 6e-8 relative
/// rounding, the lobe exponent loses ~1e-7 absolute to the cancellation in `ω_i + ω_o`, which at
/// α ≥ 0.08 (these materials) and 4σ off the peak is < 1e-5 nats; a formula error shows as O(1).
const F32_TOLERANCE: f64 = 2e-3;

fn device() -> Context {
    Context::new(true, None).expect("a Vulkan 1.3 device with validation (tools/setup installs lavapipe)")
}

fn gpu_values(ctx: &Context, spv: &[u8], name: &str, m: &Material, pairs: &[(DVec3, DVec3)]) -> Vec<[f32; 3]> {
    let pass = EvalPass::from_spirv(ctx, spv, name).expect("pipeline from the exported GLSL");
    let got = pass.run(ctx, m, pairs).expect("dispatch");
    pass.destroy(ctx);
    let errors = ctx.validation_errors();
    assert!(errors.is_empty(), "validation errors: {errors:?}");
    got
}

#[test]
fn glsl_export_evaluates_what_eval_does_on_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = device();
    let pairs = pairs();
    for (name, path) in common::export_materials(dir.path()) {
        let m = Material::load(&path).unwrap();
        let text = export(&path, "glsl", &dir.path().join(format!("{name}.glsl")));
        let src = compute_wrapper(&text, "material_eval(wi, wo)");
        let spv = glslc(&src, dir.path(), &format!("{name}.comp"), &["--target-env=vulkan1.3", "-O"])
            .unwrap_or_else(|e| panic!("{name}: the exported GLSL does not compile:\n{e}"));
        let got = gpu_values(&ctx, &spv, &name, &m, &pairs);
        let worst = worst_error(&m, &pairs, &got);
        println!("glsl export {name:28} worst relative difference to eval: {worst:.2e}");
        assert!(worst < F32_TOLERANCE, "{name}: {worst:.3e}");
    }
}

#[test]
fn glsl_export_is_the_renderers_model_source() {
    // Every line of glsl/include/brdf.glsl but its include guards stands in the export, in order:
    // the export is the renderer's source, not a copy that can drift.
    let dir = tempfile::tempdir().unwrap();
    let (_, path) = common::export_materials(dir.path()).pop().unwrap();
    let text = export(&path, "glsl", &dir.path().join("m.glsl"));
    let brdf = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/include/brdf.glsl")).unwrap();
    let mut rest = text.as_str();
    for line in brdf.lines().filter(|l| !l.trim_start().starts_with('#')) {
        let at = rest.find(line).unwrap_or_else(|| panic!("brdf.glsl line missing from the export: {line:?}"));
        rest = &rest[at + line.len()..];
    }
    assert!(!text.lines().any(|l| l.trim_start().starts_with("#include")), "the export has an #include");
}

/// The grazing cut-off of docs/model.md (Frames and conventions, The horizon), written out here so
/// that a change to the model's constant fails the test below: `2⁻²⁰`.
const GRAZING_COS: f64 = 9.5367431640625e-7;

/// Heights above (and on) the horizon, to the last bit: far under the cut-off (1e-300, 1e-30, 1e-8,
/// the subnormals 5e-324, 1e-310 and the largest one, −0 and 0), just under and over it (½ and 2 ×
/// [`GRAZING_COS`]) and well over it (1e-4).
const GRAZING_Z: [f64; 12] = [
    1e-300,
    1e-30,
    1e-8,
    1e-4,
    5e-324,
    1e-310,
    2.225073858507201e-308,
    -0.0,
    0.0,
    0.5 * GRAZING_COS,
    2.0 * GRAZING_COS,
    1e-6,
];

/// Each height of [`GRAZING_Z`] as ω_i, ω_o or both, normalised in `f64`: mirror pairs in two
/// azimuths, the retro-reflection, crossed azimuths, one grazing direction against the normal or a
/// 45° one; then views `(0.6, ±y, 0.8)` that the 120° rotation about (1, 1, 1) of
/// [`horizon_view_material`] turns onto the horizon (its rotated view has height `±y` plus the
/// rotation's rounding), for the heights more than 10× from the cut-off: in `f32` a rotated view's
/// height is known to ~1e-7 absolute, so one near the cut-off may fall on either side.
fn grazing_pairs() -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    let d = |x: f64, y: f64, z: f64| DVec3::new(x, y, z).normalize();
    for &z in &GRAZING_Z {
        out.push((d(1.0, 0.0, z), d(-1.0, 0.0, z)));
        out.push((d(0.6, 0.8, z), d(-0.6, -0.8, z)));
        out.push((d(1.0, 0.0, z), d(1.0, 0.0, z)));
        out.push((d(1.0, 0.0, z), d(0.0, 1.0, z)));
        out.push((d(1.0, 0.0, z), d(0.0, 0.0, 1.0)));
        out.push((d(0.0, 0.0, 1.0), d(-1.0, 0.0, z)));
        out.push((d(0.5, -0.5, 0.7), d(0.3, 0.9, z)));
        if (0.1 * GRAZING_COS..10.0 * GRAZING_COS).contains(&z.abs()) {
            continue;
        }
        for y in [z, -z] {
            out.push((d(0.0, 0.0, 1.0), d(0.6, y, 0.8)));
            out.push((d(-0.5, -0.4, 0.7), d(0.6, y, 0.8)));
        }
    }
    out
}

/// Directions on the cut-off to the last bit, paired with an ordinary one (as ω_i and as ω_o): for
/// three azimuths and three scales (unnormalised; 1e-300 puts every component far under the cut-off
/// before normalisation), the height whose normalised cosine (the model's `unit`) first reaches
/// [`GRAZING_COS`], found one ulp at a time, and the four heights on either side of it. For the two
/// `f64` evaluators, which normalise with the same operations: the `f32` GLSL takes unit vectors
/// rounded to `f32`, which moves a cosine by far more than these steps.
fn cut_off_pairs() -> Vec<(DVec3, DVec3)> {
    let unit = |v: DVec3| brdf_shop::brdf::material::unit(v).expect("a non-zero direction");
    let step = |z: f64, k: i64| f64::from_bits((z.to_bits() as i64 + k) as u64);
    let other = DVec3::new(-0.3, 0.1, 0.9);
    let mut out = Vec::new();
    for (x, y) in [(1.0, 0.0), (0.6, 0.8), (-0.28, 0.96)] {
        for scale in [1.0, 3.0, 1e-300] {
            let v = |z: f64| DVec3::new(x, y, z) * scale;
            // From the cut-off itself, whose normalised cosine is about 2¹¹ ulp under it (the
            // length exceeds 1 by c_min²/2 = 2⁻⁴¹ relative): down while at or over, then up while
            // under.
            let mut z = GRAZING_COS;
            while unit(v(z)).z >= GRAZING_COS {
                z = step(z, -1);
            }
            while unit(v(z)).z < GRAZING_COS {
                z = step(z, 1);
            }
            for k in -4..=4 {
                out.push((v(step(z, k)), other));
                out.push((other, v(step(z, k))));
            }
        }
    }
    out
}

/// A paper-model Ward lobe rotated 120° about (1, 1, 1) (`x → y → z → x`, exact in the quaternion),
/// so the rotated view of `ω_o = (0.6, y, 0.8)` is `(0.8, 0.6, y)` up to the rotation's rounding.
fn horizon_view_material() -> Material {
    let lobe = Lobe { rotation: glam::DQuat::from_xyzw(0.5, 0.5, 0.5, 0.5), ..common::lobe(0.5, 0.3, 0.3) };
    Material {
        diffuse: [0.2, 0.3, 0.4],
        normalization: brdf_shop::brdf::Normalization::Ward,
        preserve_energy: false,
        lobes: vec![lobe],
        ..Material::scratch()
    }
}

/// `brdf-shop eval --material M` on `pairs`: one RGB line per pair.
fn eval_binary(material: &Path, pairs: &[(DVec3, DVec3)]) -> Vec<[f64; 3]> {
    use std::io::Write;
    let text: String =
        pairs.iter().map(|(a, b)| format!("{:?} {:?} {:?} {:?} {:?} {:?}\n", a.x, a.y, a.z, b.x, b.y, b.z)).collect();
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .args(["eval", "--material"])
        .arg(material)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("brdf-shop eval starts");
    child.stdin.take().unwrap().write_all(text.as_bytes()).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "eval: {}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<[f64; 3]> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> =
                l.split(' ').map(|x| x.parse().unwrap_or_else(|_| panic!("eval printed {l:?}"))).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(lines.len(), pairs.len(), "eval: one line per pair");
    lines
}

/// The exported Mitsuba plug-in's module-level `brdf_eval` (`f64`, Dr.Jit's LLVM backend) on
/// `pairs`, through the virtual environment tools/setup makes.
fn plugin_brdf_eval(dir: &Path, material: &Path, pairs: &[(DVec3, DVec3)]) -> Vec<[f64; 3]> {
    let plugin = dir.join("grazing-plugin.py");
    common::export("mitsuba", material, &plugin);
    let pairs_file = dir.join("grazing-pairs.txt");
    let text: String =
        pairs.iter().map(|(a, b)| format!("{:?} {:?} {:?} {:?} {:?} {:?}\n", a.x, a.y, a.z, b.x, b.y, b.z)).collect();
    std::fs::write(&pairs_file, text).unwrap();
    let script = "import importlib.util, sys
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
spec = importlib.util.spec_from_file_location('p', sys.argv[1])
p = importlib.util.module_from_spec(spec)
spec.loader.exec_module(p)
rows = [[float(v) for v in line.split()] for line in open(sys.argv[2]) if line.strip()]
col = lambda k: mi.Float64([r[k] for r in rows])
f = p.brdf_eval((col(0), col(1), col(2)), (col(3), col(4), col(5)))
cols = [[float(v) for v in c] for c in f]
for i in range(len(rows)):
    print(repr(cols[0][i]), repr(cols[1][i]), repr(cols[2][i]))
";
    let python = common::venv_python("mitsuba-venv", "Mitsuba 3");
    let out = Command::new(python).arg("-c").arg(script).arg(&plugin).arg(&pairs_file).output().unwrap();
    assert!(out.status.success(), "plug-in: {}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<[f64; 3]> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(lines.len(), pairs.len(), "plug-in: one line per pair");
    lines
}

/// Tolerance of the plug-in's `brdf_eval` against `eval`, both `f64`: the same formulas in the same
/// order, so what differs is Dr.Jit's `exp`/`log` against Rust's (a few ulp each) on exponents of at
/// most ~60 nats here: ≤ 1e-13 relative. 1e-12 leaves a margin; a cut-off or saturation applied
/// differently shows as O(1) (the 2.3× of a pair 1e-300 above the horizon).
const GRAZING_PLUGIN_TOLERANCE: f64 = 1e-12;

/// Grazing to the last bit (docs/model.md, Frames and conventions, The horizon): `brdf-shop eval`,
/// the Mitsuba plug-in's `brdf_eval` and the exported GLSL's `material_eval` give the same answer on
/// [`grazing_pairs`] (and eval and the plug-in on [`cut_off_pairs`]) for every export material (both
/// paper normalisations, symmetrised, rotated and split lobes, the reciprocal model) and a lobe whose
/// rotated view lies on the horizon. Where the normalised cosine of ω_i or ω_o is under
/// [`GRAZING_COS`] all of them return exactly 0. Elsewhere the plug-in agrees to
/// [`GRAZING_PLUGIN_TOLERANCE`] and the GLSL (`f32`, fed each pair rounded to `f32`) to
/// [`F32_TOLERANCE`] relative, on the value itself: over the cut-off no value leaves `f32`'s range,
/// the mirror pairs cancel exactly in `f32`, and the inputs' rounding (6e-8 relative, ~1e-7
/// absolute in a rotated view's height, which the 120° lobe's rotated views of height 1e-4 turn
/// into ~5e-4) stays under it.
#[test]
fn grazing_pairs_give_one_answer_in_eval_the_plugin_and_the_glsl_export() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = device();
    let pairs = grazing_pairs();
    let f64_pairs: Vec<_> = pairs.iter().copied().chain(cut_off_pairs()).collect();
    let mut materials = common::export_materials(dir.path());
    let horizon = dir.path().join("horizon-view.brdf.json");
    horizon_view_material().save(&horizon).unwrap();
    materials.push(("horizon-view-ward".into(), horizon));
    let below = |v: DVec3| !(brdf_shop::brdf::material::unit(v).is_some_and(|u| u.z >= GRAZING_COS));
    let (mut zeros, mut compared) = (0usize, 0usize);
    for (name, path) in &materials {
        let m = Material::load(path).unwrap();
        let eval = eval_binary(path, &f64_pairs);
        let plugin = plugin_brdf_eval(dir.path(), path, &f64_pairs);
        let text = export(path, "glsl", &dir.path().join(format!("{name}.glsl")));
        let src = compute_wrapper(&text, "material_eval(wi, wo)");
        let spv = glslc(&src, dir.path(), &format!("{name}-grazing.comp"), &["--target-env=vulkan1.3", "-O"])
            .unwrap_or_else(|e| panic!("{name}: the exported GLSL does not compile:\n{e}"));
        let glsl = gpu_values(&ctx, &spv, name, &m, &pairs);
        let (mut worst_plugin, mut worst_glsl) = (0.0f64, 0.0f64);
        for (k, (wi, wo)) in f64_pairs.iter().enumerate() {
            let what = format!("{name}: ω_i {wi:?}, ω_o {wo:?}");
            // The GLSL's value where it has one (the grazing pairs), else eval's.
            let (f, p) = (eval[k], plugin[k]);
            let g = glsl.get(k).map_or(f, |g| g.map(f64::from));
            if below(*wi) || below(*wo) {
                assert!(
                    f == [0.0; 3] && p == [0.0; 3] && g == [0.0; 3],
                    "{what}: under the cut-off, yet eval {f:?}, plug-in {p:?}, GLSL {g:?}"
                );
                zeros += 1;
                continue;
            }
            for c in 0..3 {
                assert!(f[c] > 0.0 && f[c].is_finite(), "{what}: eval {f:?}");
                let ep = (p[c] - f[c]).abs() / f[c];
                let eg = (g[c] - f[c]).abs() / f[c];
                assert!(ep <= GRAZING_PLUGIN_TOLERANCE, "{what}: plug-in {p:?} against eval {f:?} ({ep:.2e})");
                assert!(eg <= F32_TOLERANCE, "{what}: GLSL {g:?} against eval {f:?} ({eg:.2e})");
                worst_plugin = worst_plugin.max(ep);
                worst_glsl = worst_glsl.max(eg);
            }
            compared += 1;
        }
        println!("grazing {name:28} plug-in worst {worst_plugin:.1e}, GLSL worst {worst_glsl:.1e}");
    }
    // Both sides of the cut-off are exercised, the last bit included.
    assert!(zeros > 500 && compared > 200, "{zeros} pairs under the cut-off, {compared} over it");
    let cut = cut_off_pairs();
    let under = cut.iter().filter(|(a, b)| below(*a) || below(*b)).count();
    assert!(under > 0 && under < cut.len(), "{under} of the {} pairs on the cut-off under it", cut.len());
}

/// A BRDF Explorer parameter as its loader reads it.
enum Param {
    Float(String, f32),
    Bool(String, bool),
    Color(String, [f32; 3]),
}

/// `BRDFBase::loadBRDF` on the text: the parameters and the shader section.
fn load_brdf_explorer(text: &str) -> (Vec<Param>, String) {
    let mut lines = text.lines();
    let kind = lines.next().unwrap().trim();
    assert_eq!(kind.split(' ').next(), Some("analytic"), "first line must name the type");
    let (mut params, mut shader, mut section) = (Vec::new(), String::new(), String::new());
    for line in lines {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let mut tok = t.split_whitespace();
        match tok.next().unwrap() {
            "::begin" => {
                assert!(section.is_empty(), "nested section");
                section = tok.next().unwrap().to_string();
            }
            "::end" => {
                assert_eq!(tok.next().unwrap(), section, "::end of another section");
                section.clear();
            }
            first if section == "parameters" => {
                let name = tok.next().expect("parameter name").to_string();
                let nums: Vec<f32> = tok.map(|v| v.parse().expect("parameter value")).collect();
                params.push(match first {
                    "float" => {
                        assert_eq!(nums.len(), 3, "float NAME MIN MAX VALUE: {t}");
                        assert!(nums[0] <= nums[2] && nums[2] <= nums[1], "value outside its range: {t}");
                        Param::Float(name, nums[2])
                    }
                    "bool" => Param::Bool(name, nums[0] != 0.0),
                    "color" => Param::Color(name, [nums[0], nums[1], nums[2]]),
                    other => panic!("BRDF Explorer has no parameter type {other}"),
                });
            }
            _ if section == "shader" => {
                shader.push_str(line);
                shader.push('\n');
            }
            _ => panic!("line outside a section: {t}"),
        }
    }
    (params, shader)
}

/// The `::INSERT_UNIFORMS_HERE::` text: `uniform` declarations (floats, then bools, then colours).
fn uniforms(params: &[Param]) -> String {
    let mut s = String::new();
    for kind in 0..3 {
        for p in params {
            match (kind, p) {
                (0, Param::Float(n, _)) => s += &format!("uniform float {n};\n"),
                (1, Param::Bool(n, _)) => s += &format!("uniform bool {n};\n"),
                (2, Param::Color(n, _)) => s += &format!("uniform vec3 {n};\n"),
                _ => {}
            }
        }
    }
    s
}

/// The same names as constants holding the values BRDF Explorer sets (its `adjustShaderPreRender`).
fn constants(params: &[Param]) -> String {
    let f = |v: f32| format!("{v:?}");
    params
        .iter()
        .map(|p| match p {
            Param::Float(n, v) => format!("const float {n} = {};\n", f(*v)),
            Param::Bool(n, v) => format!("const bool {n} = {v};\n"),
            Param::Color(n, c) => format!("const vec3 {n} = vec3({}, {}, {});\n", f(c[0]), f(c[1]), f(c[2])),
        })
        .collect()
}

/// BRDF Explorer's lit-sphere fragment template (`brdftemplatesphere.frag`), its declarations and
/// the call it makes, with the two insertion points.
const LIT_SPHERE_TEMPLATE: &str = "#version 410
uniform vec3 incidentVector;
uniform float incidentTheta;
uniform float incidentPhi;
uniform float brightness;
uniform float gamma;
uniform float exposure;
uniform float useNDotL;
in vec4 worldSpaceVert;
in vec4 eyeSpaceVert;
out vec4 fragColor;
::INSERT_UNIFORMS_HERE::
::INSERT_BRDF_FUNCTION_HERE::
void main(void)
{
    vec3 normal = normalize( worldSpaceVert.xyz );
    vec3 tangent = normalize( cross( vec3(0,1,0), normal ) );
    vec3 bitangent = normalize( cross( normal, tangent ) );
    vec3 viewVec = vec3(0,0,1);
    vec3 b = max( BRDF( incidentVector, viewVec, normal, tangent, bitangent ), vec3(0.0) );
    if (useNDotL != 0) b *= dot( normal, incidentVector );
    b *= brightness * pow( 2.0, exposure );
    b = pow( b, vec3( 1.0 / gamma ) );
    fragColor = vec4( clamp( b, vec3(0.0), vec3(1.0) ), 1.0 );
}
";

#[test]
fn brdf_explorer_export_loads_compiles_and_evaluates_what_eval_does() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = device();
    let pairs = pairs();
    // BRDF(L, V, N, X, Y) in a tilted world frame: N off every axis, X and Y from the rule of docs/model.md, Frames and
    // conventions (BRDF Explorer's own tangent), the local pairs rotated into it.
    let call = "BRDF(wi.x * X + wi.y * Y + wi.z * N, wo.x * X + wo.y * Y + wo.z * N, N, X, Y)";
    let frame = "const vec3 N = normalize(vec3(0.3, 0.8, 0.52));
const vec3 X = normalize(cross(vec3(0.0, 1.0, 0.0), N));
const vec3 Y = cross(N, X);
";
    for (name, path) in common::export_materials(dir.path()) {
        let m = Material::load(&path).unwrap();
        let text = export(&path, "brdf-explorer", &dir.path().join(format!("{name}.brdf")));
        let (params, shader) = load_brdf_explorer(&text);
        assert!(shader.contains("vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"), "{name}: no BRDF function");
        // As BRDF Explorer compiles it: OpenGL 4.1, loose uniforms.
        let gl = LIT_SPHERE_TEMPLATE
            .replace("::INSERT_UNIFORMS_HERE::\n", &uniforms(&params))
            .replace("::INSERT_BRDF_FUNCTION_HERE::\n", &format!("\n{shader}\n"));
        glslc(&gl, dir.path(), &format!("{name}.frag"), &["--target-env=opengl4.5", "-fauto-map-locations"])
            .unwrap_or_else(|e| panic!("{name}: BRDF Explorer's wrapping does not compile:\n{e}"));
        // Its values, with the parameters BRDF Explorer would set.
        let src = compute_wrapper(&format!("{}{frame}{shader}", constants(&params)), call);
        let spv = glslc(&src, dir.path(), &format!("{name}.comp"), &["--target-env=vulkan1.3", "-O"])
            .unwrap_or_else(|e| panic!("{name}: the BRDF Explorer shader does not compile for Vulkan:\n{e}"));
        let got = gpu_values(&ctx, &spv, &name, &m, &pairs);
        let worst = worst_error(&m, &pairs, &got);
        println!("brdf-explorer export {name:28} worst relative difference to eval: {worst:.2e}");
        assert!(worst < F32_TOLERANCE, "{name}: {worst:.3e}");
    }
}

/// Tangent angles far outside (−π, π] (1e300 would be `inf` as BRDF Explorer's `f32` parameter,
/// 12345.678 off by 2.7e-4 rad) are written reduced in `f64`: the parameter's cosine and sine are the
/// model's to 1e-6 (an `f32` within ±π is within 1.2e-7 rad of the reduced angle; the bound leaves
/// room for the reduction's own rounding). A CPU check of the file: the GPU comparison above covers
/// the shader for in-range angles.
#[test]
fn brdf_explorer_export_reduces_tangent_angles_in_double_precision() {
    let dir = tempfile::tempdir().unwrap();
    let angles = [1e300, 12345.678, -1e10, -3.1, 3.0, 7.0];
    let lobes = angles.iter().map(|&a| Lobe { tangent_angle: a, ..common::lobe(0.1, 0.2, 0.05) }).collect();
    let path = dir.path().join("angles.brdf.json");
    Material { diffuse: [0.2; 3], lobes, ..Material::scratch() }.save(&path).unwrap();
    let text = export(&path, "brdf-explorer", &dir.path().join("angles.brdf"));
    let (params, _) = load_brdf_explorer(&text);
    for (k, a) in angles.iter().enumerate() {
        let name = format!("lobe{k}_tangent_angle");
        let v = params
            .iter()
            .find_map(|p| match p {
                Param::Float(n, v) if *n == name => Some(*v as f64),
                _ => None,
            })
            .unwrap_or_else(|| panic!("no {name}"));
        let pi = std::f64::consts::PI as f32 as f64;
        assert!(v.abs() <= pi, "{name} = {v} for {a}");
        let (dc, ds) = ((v.cos() - a.cos()).abs(), (v.sin() - a.sin()).abs());
        assert!(dc < 1e-6 && ds < 1e-6, "{name} = {v} for {a}: cos off by {dc:.1e}, sin by {ds:.1e}");
    }
}

#[test]
fn export_refusals_are_one_line_and_leave_outputs_alone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, good) = common::export_materials(d).pop().unwrap();
    let good = good.to_str().unwrap();
    let existing = d.join("existing.glsl");
    std::fs::write(&existing, "keep me").unwrap();
    let many = d.join("many.brdf.json");
    let lobes = (0..65).map(|k| Lobe { tangent_angle: 0.01 * k as f64, ..common::lobe(0.01, 0.2, 0.2) }).collect();
    Material { diffuse: [0.2; 3], lobes, ..Material::scratch() }.save(&many).unwrap();
    let bad = d.join("bad.brdf.json");
    std::fs::write(&bad, "{\"format\": \"brdf-shop/material\", \"version\": 2, \"diffuse\": [2, 0, 0], \"lobes\": []}")
        .unwrap();
    let e = existing.to_str().unwrap();
    let missing_dir = d.join("no-such-folder/m.py");
    let none = d.join("none.json");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--material", good, "--format", "maya", "--out", e], "unknown format"),
        (vec!["--material", good, "--format", "gl\u{1b}[31msl", "--out", e], "unknown format"),
        (vec!["--material", good, "--format", "glsl", "--out", missing_dir.to_str().unwrap()], "no-such-folder"),
        (vec!["--material", good, "--format", "glsl", "--out", d.to_str().unwrap()], "folder"),
        (vec!["--material", many.to_str().unwrap(), "--format", "brdf-explorer", "--out", e], "at most 64"),
        (vec!["--material", bad.to_str().unwrap(), "--format", "mitsuba", "--out", e], "bad.brdf.json"),
        (vec!["--material", none.to_str().unwrap(), "--format", "glsl", "--out", e], "none.json"),
        (vec!["--material", good, "--out", e], "--format"),
    ];
    for (args, needle) in cases {
        let mut all = vec!["export"];
        all.extend(&args);
        let (code, stdout, stderr) = common::run(&all);
        assert_eq!(code, 1, "{args:?}: exit {code}, stderr {stderr}");
        assert!(stdout.is_empty(), "{args:?}: stdout {stdout}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: not one line: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr} does not say {needle}");
        assert!(!stderr.contains('\u{1b}'), "{args:?}: raw control character in {stderr:?}");
        assert_eq!(std::fs::read_to_string(&existing).unwrap(), "keep me", "{args:?} touched the output");
        assert!(!missing_dir.exists());
    }
    // Nothing but the inputs and the untouched output are left (no temporary files).
    let mut names: Vec<String> =
        std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    assert!(names.iter().all(|n| !n.contains(".tmp")), "{names:?}");
    // The 64-lobe limit is the format's: glsl and mitsuba take the 65-lobe material.
    for (format, ext) in [("glsl", "glsl"), ("mitsuba", "py")] {
        let out = d.join(format!("many.{ext}"));
        let text = export(&many, format, &out);
        assert!(text.len() > 1000, "{format}");
    }
}
