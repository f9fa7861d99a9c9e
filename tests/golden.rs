//! The frames the renderer draws are the frames it is known to draw, bit for bit: every estimator,
//! canvas and mesh views, sparse and dense filtered frames, frames that keep their G-buffer,
//! previews at other sizes, the refinement's sum, both device plans. Each image's pixels (the `f32`
//! bits of every channel) are hashed and compared with `tests/golden/frames.txt`, the hashes of the
//! images this code drew on lavapipe. A change to what a frame records that should not change an
//! image is checked by this test; a change that should (a new model, a shader fix) writes the file
//! again with `BRDF_SHOP_BLESS=1 cargo test --test golden` and says why in its commit.
//!
//! The hashes hold for one rasteriser: Mesa lavapipe on x86-64 (LLVM's code for the machine's
//! vector width and FMA). On a mismatch the test writes the images to `target/test-output/golden/`
//! and names every frame that differs, with its mean, so a reader sees how far it moved.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use brdf_shop::brdf::Material;
use brdf_shop::reference::Image;
use brdf_shop::render::plan::DevicePlan;
use brdf_shop::render::{Estimator, Progress, Recorded, Renderer, Settings, View};
use brdf_shop::scene::{Camera, Environment, Mesh};
use brdf_shop::vk::Context;
use common::settings;
use glam::DVec3;

fn manifest() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/frames.txt")
}

fn env(name: &str) -> Environment {
    let path = common::asset(&format!("hdri/{name}"));
    Environment::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// FNV-1a over the bits of every channel: equal for bit-identical images.
fn hash(im: &Image) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in im.pixels.iter().flatten() {
        for b in v.to_bits().to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

fn mean(im: &Image) -> [f64; 3] {
    let n = im.pixels.len().max(1) as f64;
    let mut m = [0.0; 3];
    for p in &im.pixels {
        for c in 0..3 {
            m[c] += f64::from(p[c]) / n;
        }
    }
    m
}

/// The frames drawn, in order, by name.
struct Frames(Vec<(String, Image)>);

impl Frames {
    fn add(&mut self, name: String, image: Image) {
        assert!(self.0.iter().all(|(n, _)| *n != name), "two frames named {name}");
        self.0.push((name, image));
    }
}

/// One frame recorded as the editor records it (the view's persistent targets, a kept G-buffer
/// where mesh, camera and size stay), read back as the view shows it.
fn editor_frame(r: &mut Renderer, m: &Material, s: &Settings, progress: Progress) -> Image {
    r.begin_frame(m).unwrap();
    assert_eq!(r.record(m, s, progress).unwrap(), Recorded::Done);
    r.submit_frame(None, None).unwrap();
    r.read_mesh_view().unwrap()
}

fn materials() -> Vec<(String, Material)> {
    let mut all: Vec<(String, Material)> =
        common::feature_materials().into_iter().map(|(n, m)| (n.to_string(), m)).collect();
    for name in ["bench-4lobes", "bench-8lobes"] {
        let path = common::asset(&format!("{name}.brdf.json"));
        all.push((name.to_string(), Material::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))));
    }
    all
}

/// Headless frames: every estimator on every material, on a map with key lights (studio) and one
/// with a sun (sky); sparse (64², ≤ 64 spp) and dense (48², and 64² at 128 spp) `key` frames; the
/// canvas. With `all` false, the frames where the device plans differ: the `key` frames on studio
/// (the others start and zero their images the same way on either plan, and the canvas is one pass).
fn headless(r: &mut Renderer, plan: &str, frames: &mut Frames, all: bool) {
    let mats = materials();
    let maps: &[&str] = if all { &["studio.exr", "sky.exr"] } else { &["studio.exr"] };
    for &map in maps {
        r.set_environment(&env(map)).unwrap();
        for (mesh_name, mesh) in [("sphere", Mesh::sphere()), ("torus", Mesh::torus())] {
            r.set_mesh(&mesh).unwrap();
            for (name, m) in &mats {
                let runs: &[(u32, u32, Estimator)] = if mesh_name == "sphere" {
                    &[
                        (64, 4, Estimator::Key),
                        (48, 4, Estimator::Key),
                        (64, 128, Estimator::Key),
                        (64, 4, Estimator::Fis),
                        (64, 4, Estimator::Plain),
                        (64, 8, Estimator::Mis),
                    ]
                } else {
                    &[(64, 16, Estimator::Key)]
                };
                for &(size, spp, estimator) in runs.iter().filter(|run| all || run.2 == Estimator::Key) {
                    let s = settings(size, spp, estimator);
                    let image = r.render(m, &s).unwrap_or_else(|e| panic!("{name}: {e}")).image;
                    let tag = format!("{plan}/{map}/{mesh_name}/{name}/{}-{size}-{spp}", estimator.name());
                    frames.add(tag, image);
                }
            }
        }
    }
    for (name, m) in mats.iter().filter(|_| all) {
        let s = Settings { view: View::Canvas, ..settings(48, 1, Estimator::Fis) };
        frames.add(format!("{plan}/canvas/{name}"), r.render(m, &s).unwrap().image);
    }
}

/// Editor frames: a kept G-buffer and its saved base, a new diffuse albedo on it, previews at
/// other sizes and back, and the refinement's sum of `mis` frames.
fn editor(r: &mut Renderer, plan: &str, frames: &mut Frames) {
    let mats = materials();
    r.set_environment(&env("venice.exr")).unwrap();
    r.set_mesh(&Mesh::torus()).unwrap();
    for (name, m) in mats.iter().filter(|(n, _)| n == "tilted-reciprocal" || n == "bench-4lobes") {
        let recoloured = Material { diffuse: [0.1, 0.2, 0.3], ..m.clone() };
        for estimator in [Estimator::Key, Estimator::Fis] {
            let s = settings(64, 4, estimator);
            let moved =
                Settings { camera: Camera { eye: DVec3::new(1.0, 2.0, 4.0), ..Camera::default() }, ..s.clone() };
            let tag = |what: &str| format!("{plan}/editor/{name}/{}/{what}", estimator.name());
            frames.add(tag("moved"), editor_frame(r, m, &moved, Progress::Fresh));
            frames.add(tag("raster"), editor_frame(r, m, &s, Progress::Fresh));
            frames.add(tag("kept"), editor_frame(r, m, &s, Progress::Fresh));
            frames.add(tag("base"), editor_frame(r, m, &s, Progress::Fresh));
            frames.add(tag("recoloured"), editor_frame(r, &recoloured, &s, Progress::Fresh));
            frames.add(tag("recoloured-base"), editor_frame(r, &recoloured, &s, Progress::Fresh));
            let preview = Settings { width: 32, height: 32, spp: 1, ..s.clone() };
            frames.add(tag("preview-32"), editor_frame(r, m, &preview, Progress::Fresh));
            frames.add(tag("preview-32-kept"), editor_frame(r, m, &preview, Progress::Fresh));
            frames.add(tag("back-to-64"), editor_frame(r, m, &s, Progress::Fresh));
        }
        let s = settings(64, 8, Estimator::Mis);
        let tag = |what: &str| format!("{plan}/editor/{name}/mis/{what}");
        frames.add(tag("fresh"), editor_frame(r, m, &s, Progress::Fresh));
        frames.add(tag("refined-16"), editor_frame(r, m, &s, Progress::Refine));
        frames.add(tag("refined-24"), editor_frame(r, m, &s, Progress::Refine));
        let canvas = Settings { view: View::Canvas, ..settings(48, 1, Estimator::Key) };
        r.begin_frame(m).unwrap();
        assert_eq!(r.record(m, &canvas, Progress::Fresh).unwrap(), Recorded::Done);
        r.submit_frame(None, None).unwrap();
        r.finish_frames().unwrap();
    }
}

fn draw_all() -> Frames {
    let mut frames = Frames(Vec::new());
    for (plan_name, plan) in [("cpu", DevicePlan::CPU), ("gpu", DevicePlan::GPU)] {
        let ctx =
            Context::new(true, None).expect("a Vulkan 1.3 device with validation (tools/setup installs lavapipe)");
        let mut r = Renderer::new(ctx).expect("renderer");
        r.device_plan = plan;
        headless(&mut r, plan_name, &mut frames, plan == DevicePlan::CPU);
        editor(&mut r, plan_name, &mut frames);
    }
    frames
}

fn line(name: &str, im: &Image) -> String {
    let m = mean(im);
    format!("{name} {:016x} {}x{} {:.6e} {:.6e} {:.6e}", hash(im), im.width, im.height, m[0], m[1], m[2])
}

#[test]
fn every_test_scene_draws_the_known_frames_bit_for_bit() {
    let frames = draw_all();
    let mut text = String::from(
        "# name hash(FNV-1a of the f32 bits) size mean(r g b): tests/golden.rs; remade with BRDF_SHOP_BLESS=1\n",
    );
    for (name, im) in &frames.0 {
        assert!(im.pixels.iter().flatten().all(|v| v.is_finite()), "{name}: a pixel is not finite");
        writeln!(text, "{}", line(name, im)).unwrap();
    }
    if std::env::var("BRDF_SHOP_BLESS").as_deref() == Ok("1") {
        std::fs::create_dir_all(manifest().parent().unwrap()).unwrap();
        std::fs::write(manifest(), &text).unwrap();
        eprintln!("wrote {} ({} frames)", manifest().display(), frames.0.len());
        return;
    }
    let known = std::fs::read_to_string(manifest()).expect("tests/golden/frames.txt");
    let known: Vec<&str> = known.lines().filter(|l| !l.starts_with('#')).collect();
    let drawn: Vec<String> = frames.0.iter().map(|(n, im)| line(n, im)).collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/golden");
    let mut differ = Vec::new();
    for ((name, im), now) in frames.0.iter().zip(&drawn) {
        match known.iter().find(|k| k.split(' ').next() == Some(name.as_str())) {
            Some(k) if *k == now => {}
            Some(k) => {
                differ.push(format!("  was {k}\n  now {now}"));
                let file = dir.join(format!("{}.exr", name.replace(['/', '.'], "_")));
                let _ = std::fs::create_dir_all(&dir);
                let _ = brdf_shop::imageio::write(&file, im.width, im.height, &im.pixels, 1.0);
            }
            None => differ.push(format!("  new {now}")),
        }
    }
    for k in &known {
        let name = k.split(' ').next().unwrap_or("");
        if frames.0.iter().all(|(n, _)| n != name) {
            differ.push(format!("  gone {k}"));
        }
    }
    assert!(
        differ.is_empty(),
        "{} of {} frames differ from tests/golden/frames.txt (images in {}):\n{}",
        differ.len(),
        frames.0.len(),
        dir.display(),
        differ.join("\n")
    );
}
