//! The renderer on this machine's Vulkan device (lavapipe in CI) with the validation layer on: every
//! frame that reports a validation error fails (`Renderer::render` returns it). Images are compared
//! with the CPU reference by relative L1 over the pixels both cover (`reference::relative_l1`); on a
//! failure the images go to `target/test-output/` for a look.

// `!(err < bound)` fails on NaN too, which `err >= bound` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::too_many_arguments)]

mod common;
#[path = "render/filter.rs"]
mod filter;
#[path = "render/frames.rs"]
mod frames;
#[path = "render/furnace.rs"]
mod furnace;
#[path = "render/key.rs"]
mod key;

use std::path::{Path, PathBuf};

use brdf_shop::brdf::{Lobe, Material, Normalization};
use brdf_shop::brush::canvas::Canvas;
use brdf_shop::reference::{self, Image};
use brdf_shop::render::{Estimator, Progress, Recorded, Renderer, Settings, View};
use brdf_shop::scene::{Camera, Environment, Mesh};
use brdf_shop::vk::Context;
use common::settings;
use glam::{DQuat, DVec3};

fn hdri(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hdri").join(name)
}

fn env(name: &str) -> Environment {
    Environment::load(&hdri(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn renderer() -> Renderer {
    let ctx = Context::new(true, None).expect("a Vulkan 1.3 device with validation (tools/setup installs lavapipe)");
    Renderer::new(ctx).expect("renderer")
}

/// Writes the images of a failed comparison for a look.
fn dump(name: &str, images: &[(&str, &Image)]) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output");
    let _ = std::fs::create_dir_all(&dir);
    for (tag, im) in images {
        let _ = brdf_shop::imageio::write(&dir.join(format!("{name}-{tag}.exr")), im.width, im.height, &im.pixels, 1.0);
    }
}

fn assert_finite(name: &str, im: &Image) {
    let bad = im.pixels.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
    assert_eq!(bad, 0, "{name}: {bad} pixels with NaN or Inf");
}

/// The largest difference of any colour channel between `a` and `b`, and `b`'s largest channel value.
fn worst_and_peak(a: &Image, b: &Image) -> (f32, f32) {
    let peak = b.pixels.iter().flat_map(|p| p[..3].iter().copied()).fold(0.0f32, f32::max);
    let worst = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    (worst, peak)
}

/// Renders `estimator` and the reference, returns the relative L1 over the object.
fn compare(
    bound: f64,
    r: &mut Renderer,
    name: &str,
    m: &Material,
    env: &Environment,
    size: u32,
    gpu_spp: u32,
    estimator: Estimator,
    ref_spp: u32,
) -> f64 {
    let mesh = Mesh::sphere();
    r.set_environment(env).expect("environment");
    r.set_mesh(&mesh).expect("mesh");
    let s = settings(size, gpu_spp, estimator);
    let gpu = r.render(m, &s).unwrap_or_else(|e| panic!("{name}: {e}")).image;
    let cpu = reference::render_mesh(m, env, &mesh, &s.camera, size, size, ref_spp, false);
    assert_finite(name, &gpu);
    let err = reference::relative_l1(&gpu, &cpu).expect("the sphere covers pixels");
    eprintln!("{name}: {} at {gpu_spp} spp vs reference at {ref_spp} spp: relative L1 {:.4}", estimator.name(), err);
    if !(err < bound) {
        dump(name, &[("gpu", &gpu), ("reference", &cpu)]);
    }
    err
}

// Test size and sample counts: small images keep lavapipe and the CPU reference fast; the sample
// counts are chosen so that the Monte Carlo noise of both images together stays well under the 2 %
// tolerance (measured on lavapipe: `mis` at 4096 spp within 0.6–1.3 % of the reference on sky and
// studio, `plain` at 1024 within 0.3–0.5 % on venice and city).
const SIZE: u32 = 32;
const MIS_SPP: u32 = 4096;
const REF_SPP: u32 = 8192;

#[test]
fn mis_converges_to_the_reference_on_sun_maps() {
    let mut r = renderer();
    let mut failures = Vec::new();
    for map in ["sky.exr", "studio.exr"] {
        let e = env(map);
        for (name, m) in common::feature_materials() {
            let tag = format!("mis-{map}-{name}");
            let err = compare(0.02, &mut r, &tag, &m, &e, SIZE, MIS_SPP, Estimator::Mis, REF_SPP);
            // The bound: 2 % relative L1 over the object.
            if !(err < 0.02) {
                failures.push(format!("{tag}: {err:.4}"));
            }
        }
    }
    assert!(failures.is_empty(), "over 2 %: {failures:?}");
}

#[test]
fn plain_converges_on_low_dynamic_range_maps() {
    let mut r = renderer();
    let mut failures = Vec::new();
    for map in ["venice.exr", "city.exr"] {
        let e = env(map);
        for (name, m) in common::feature_materials() {
            let tag = format!("plain-{map}-{name}");
            let err = compare(0.02, &mut r, &tag, &m, &e, SIZE, PLAIN_SPP, Estimator::Plain, REF_SPP);
            // The bound: 2 % relative L1 over the object.
            if !(err < 0.02) {
                failures.push(format!("{tag}: {err:.4}"));
            }
        }
    }
    assert!(failures.is_empty(), "over 2 %: {failures:?}");
}

const PLAIN_SPP: u32 = 1024;

/// The paper's 8-spp prefiltered estimate against the reference, per map, with the bound measured
/// on lavapipe for these materials (`FIS_BOUNDS`) plus a margin of a fifth: the estimate is biased
/// by design (prefiltering and the SH9 diffuse), so its bound is a property of the map.
#[test]
fn fis_at_8_spp_is_within_the_measured_error_per_map() {
    let mut r = renderer();
    let mut failures = Vec::new();
    for (map, bound) in FIS_BOUNDS {
        let e = env(map);
        for (name, m) in common::feature_materials() {
            let tag = format!("fis-{map}-{name}");
            let err = compare(bound, &mut r, &tag, &m, &e, SIZE, 8, Estimator::Fis, REF_SPP);
            if !(err < bound) {
                failures.push(format!("{tag}: {err:.4} over {bound}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

// Worst measured per map over the four materials (lavapipe, 32², Halton from index 1): sky 0.49,
// studio 0.64, venice 0.15, city 0.22; the bounds add a fifth. The error falls with samples (studio,
// iso-ward: 0.52 at 8 spp, 0.24 at 32, 0.08 at 256), so it is the estimator's, not a bug's.
const FIS_BOUNDS: [(&str, f64); 4] =
    [("sky.exr", 0.59), ("studio.exr", 0.77), ("venice.exr", 0.18), ("city.exr", 0.27)];

/// The SH diffuse pass against the exact SH9 irradiance of the map computed on the CPU in f64:
/// 0.5 % (f32 arithmetic on the GPU is far below that; the bound is the issue's).
#[test]
fn sh_diffuse_pass_equals_cpu_sh9_irradiance() {
    use brdf_shop::render::environment::irradiance_coefficients;
    use brdf_shop::scene::env::sh_irradiance;
    let mut r = renderer();
    let mesh = Mesh::sphere();
    let m = Material {
        preserve_energy: false,
        diffuse: [0.8, 0.5, 0.3],
        normalization: Normalization::Ward,
        symmetrize: false,
        lobes: vec![],
    };
    for map in ["sky.exr", "studio.exr", "city.exr"] {
        let e = env(map);
        r.set_environment(&e).unwrap();
        r.set_mesh(&mesh).unwrap();
        let s = settings(SIZE, 8, Estimator::Fis);
        let gpu = r.render(&m, &s).unwrap().image;
        let hits = reference::rasterize(&mesh, &s.camera, SIZE, SIZE);
        let sh = e.sh9();
        let _ = irradiance_coefficients(&sh);
        let (mut num, mut den, mut n) = (0.0, 0.0, 0);
        for (p, hit) in gpu.pixels.iter().zip(&hits.hits) {
            let (Some(hit), true) = (hit, p[3] > 0.5) else { continue };
            if hit.normal.dot(s.camera.eye - hit.position) <= 0.0 {
                continue;
            }
            let irr = sh_irradiance(&sh, hit.normal);
            for c in 0..3 {
                let want = m.diffuse[c] / std::f64::consts::PI * irr[c];
                num += (p[c] as f64 - want).abs();
                den += want.abs();
            }
            n += 1;
        }
        assert!(n > 500, "{map}: only {n} pixels compared");
        let err = num / den;
        eprintln!("{map}: SH diffuse pass vs CPU SH9 irradiance: relative L1 {err:.2e} over {n} pixels");
        assert!(err < 0.005, "{map}: {err}");
        // Its distance from the converged reference (SH9 truncation), measured on lavapipe: sky 0.051,
        // studio 0.116, city 0.012.
        let cpu = reference::render_mesh(&m, &e, &mesh, &s.camera, SIZE, SIZE, 1024, false);
        let d = reference::relative_l1(&gpu, &cpu).unwrap();
        eprintln!("{map}: SH diffuse pass vs reference (diffuse only): relative L1 {d:.4}");
        assert!(d < 0.25, "{map}: SH9 diffuse is {d} from the reference");
    }
}

/// The canvas pass against the CPU canvas of `src/brush` (f64): 1e-3 relative per pixel wherever the
/// CPU radiance is above 1e-6 of the image's peak (below that, f32 exponent underflow differs).
#[test]
fn canvas_pass_matches_the_cpu_canvas() {
    let mut r = renderer();
    let light = DVec3::new(0.3, 0.4, 0.866).normalize();
    let canvas = Canvas { light, intensity: 1.0 };
    for (name, m) in common::feature_materials() {
        let size = 64;
        let s = Settings { view: View::Canvas, light, ..settings(size, 8, Estimator::Fis) };
        let gpu = r.render(&m, &s).unwrap().image;
        let cpu = canvas.image(&m, size as usize);
        let peak = cpu.iter().flat_map(|p| p.iter()).fold(0.0f64, |a, &b| a.max(b));
        let mut worst = 0.0f64;
        for (g, c) in gpu.pixels.iter().zip(&cpu) {
            for k in 0..3 {
                if c[k] > 1e-6 * peak {
                    worst = worst.max((g[k] as f64 - c[k]).abs() / c[k]);
                }
            }
        }
        eprintln!("canvas {name}: worst relative difference {worst:.2e}");
        assert!(worst < 1e-3, "canvas {name}: {worst}");
    }
}

/// Stress: no NaN or Inf anywhere for the sun map with extreme lobes, grazing views and many lobes.
#[test]
fn stress_cases_stay_finite() {
    let mut r = renderer();
    let e = env("sky.exr");
    r.set_environment(&e).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let mut many = Material {
        preserve_energy: false,
        diffuse: [0.02; 3],
        normalization: Normalization::Ward,
        symmetrize: true,
        lobes: vec![],
    };
    for k in 0..32 {
        let a = 1e-4f64 * 10f64.powf(k as f64 / 31.0 * 4.0);
        many.lobes.push(Lobe {
            rotation: DQuat::from_rotation_x(0.05 * k as f64),
            split: k % 2 == 0,
            tangent_angle: 0.3 * k as f64,
            ..common::lobe(0.03, a, (a * 3.0).min(1.0))
        });
    }
    let cases = vec![
        ("alpha-1e-4", Material { lobes: vec![common::lobe(0.5, 1e-4, 1e-4)], ..Material::scratch() }),
        (
            "alpha-1",
            Material {
                lobes: vec![common::lobe(0.5, 1.0, 1.0)],
                normalization: Normalization::Ward,
                preserve_energy: false,
                ..Material::scratch()
            },
        ),
        ("aniso-1000", Material { lobes: vec![common::lobe(0.5, 1.0, 1e-3)], ..Material::scratch() }),
        ("32-lobes", many),
    ];
    // A grazing camera: the sphere seen almost edge-on fills the frame with grazing views.
    let grazing = Camera { eye: DVec3::new(0.0, 0.0, 1.02), fov_deg: 170.0, ..Camera::default() };
    for (name, m) in cases {
        for estimator in [Estimator::Fis, Estimator::Plain, Estimator::Mis] {
            for camera in [Camera::default(), grazing.clone()] {
                let s =
                    Settings { camera, ..settings(24, if estimator == Estimator::Mis { 64 } else { 8 }, estimator) };
                let im = r.render(&m, &s).unwrap_or_else(|err| panic!("{name}: {err}")).image;
                assert_finite(&format!("{name}-{}", estimator.name()), &im);
            }
        }
        let s = Settings { view: View::Canvas, ..settings(32, 8, Estimator::Fis) };
        assert_finite(&format!("{name}-canvas"), &r.render(&m, &s).unwrap().image);
    }
}

/// What a scene does not need is left out, and `mips and SH` are kept across frames.
#[test]
fn passes_follow_the_scene() {
    let mut r = renderer();
    let e = env("city.exr");
    r.set_environment(&e).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let names = |r: &mut Renderer, m: &Material, est| -> Vec<String> {
        r.render(m, &settings(16, 8, est)).unwrap().timings.into_iter().map(|t| t.name).collect()
    };
    let mut m = Material {
        preserve_energy: false,
        diffuse: [0.0; 3],
        normalization: Normalization::Ward,
        symmetrize: false,
        lobes: vec![common::lobe(0.5, 0.1, 0.1), common::lobe(0.0, 0.2, 0.2)],
    };
    // A frame that rasterises starts its image in the G-buffer's pass (`CompactPass::record`):
    // no background or diffuse pass.
    assert_eq!(names(&mut r, &m, Estimator::Fis), ["gbuffer", "lobe0[]"]);
    m.diffuse = [0.3; 3];
    m.lobes[1].albedo = [0.2; 3];
    m.lobes[1].rotation = DQuat::from_rotation_z(0.2);
    m.lobes[1].split = true;
    assert_eq!(names(&mut r, &m, Estimator::Fis), ["gbuffer", "lobe0[]", "lobe1[rot,split]"]);
    assert_eq!(names(&mut r, &m, Estimator::Plain), ["gbuffer", "lobe0[level0]", "lobe1[rot,split,level0]"]);
    assert_eq!(names(&mut r, &m, Estimator::Mis), ["gbuffer", "mis"]);
}

/// One frame recorded and submitted as the editor does (`Progress::Fresh`): its passes' names and
/// the mesh view's image.
fn frame(r: &mut Renderer, m: &Material, s: &Settings) -> (Vec<String>, Image) {
    r.begin_frame(m).unwrap();
    assert_eq!(r.record(m, s, Progress::Fresh).unwrap(), Recorded::Done);
    r.submit_frame(None, None).unwrap();
    let image = r.read_mesh_view().unwrap();
    let starts = |f: &brdf_shop::vk::frame::Finished| {
        f.timings.iter().any(|t| ["gbuffer", "compact", "background", "base"].contains(&t.name.as_str()))
    };
    let names = r.take_finished().into_iter().rev().find(starts);
    (names.unwrap().timings.into_iter().map(|t| t.name).collect(), image)
}

/// A rough Ward lobe alone (α 0.5, albedo 0.8): the filter's case.
fn rough_ward() -> Material {
    Material {
        preserve_energy: false,
        diffuse: [0.0; 3],
        normalization: Normalization::Ward,
        symmetrize: false,
        lobes: vec![common::lobe(0.8, 0.5, 0.5)],
    }
}

/// A broken invariant of the renderer is a bug (exit status 5), never a validation message: the
/// mesh view read back before it was rendered, and a refinement frame of an estimator other than
/// `mis`.
#[test]
fn broken_invariants_are_bugs_not_validation() {
    let mut r = renderer();
    let unread = r.read_mesh_view().map(|_| ()).expect_err("no mesh view was rendered");
    let refined = r
        .record(&rough_ward(), &settings(16, 1, Estimator::Fis), Progress::Refine)
        .map(|_| ())
        .expect_err("refinement frames are mis frames");
    for e in [unread, refined] {
        assert!(matches!(e, brdf_shop::Error::Bug(_)), "{e:?}");
        assert_eq!(e.exit_status(), brdf_shop::error::EXIT_BUG);
        assert!(e.to_string().starts_with("internal error (a bug in brdf-shop): "), "{e}");
    }
    r.ctx.check_validation().expect("no validation error");
}
