//! The plan's rules, one test each, named after the rule of docs/renderer.md it checks; no device.

use glam::{DQuat, DVec3};

use super::variant::{Into, KeyLights, Output, Reach};
use super::*;
use crate::brdf::{Lobe, Material, Normalization};
use crate::scene::{keylight, Environment};

fn material(diffuse: f64, lobes: Vec<Lobe>) -> Material {
    Material {
        preserve_energy: false,
        diffuse: [diffuse; 3],
        normalization: Normalization::Reciprocal,
        symmetrize: false,
        lobes,
    }
}

fn lobe(albedo: f64, alpha: f64) -> Lobe {
    Lobe::isotropic([albedo; 3], alpha)
}

/// A map of a dim sky (0.2) and a small bright lamp near the zenith: one key light.
fn lamp_lights() -> KeyLightSet {
    let (w, h) = (128, 64);
    let mut texels = vec![[0.2f32; 3]; w * h];
    for j in 10..13 {
        for i in 60..63 {
            texels[j * w + i] = [4000.0; 3];
        }
    }
    let env = Environment::from_texels(w, h, texels, "lamp").expect("a valid map");
    let found = keylight::detect(&env);
    assert!(!found.lights.is_empty(), "the lamp is a key light");
    KeyLightSet::new(found.lights, found.wide.map(|w| w.lights))
}

struct Ask {
    view: View,
    size: u32,
    spp: u32,
    estimator: Estimator,
    refine_from: Option<u32>,
    kept: Kept,
    device: DevicePlan,
    options: Options,
}

impl Ask {
    fn new(estimator: Estimator, size: u32, spp: u32) -> Ask {
        Ask {
            view: View::Mesh,
            size,
            spp,
            estimator,
            refine_from: None,
            kept: Kept::default(),
            device: DevicePlan::CPU,
            options: Options::default(),
        }
    }

    fn plan(&self, m: &Material, lights: Option<&KeyLightSet>) -> Plan {
        let camera = Camera::default();
        plan(&Request {
            view: self.view,
            width: self.size,
            height: self.size,
            spp: self.spp,
            estimator: self.estimator,
            camera: &camera,
            refine_from: self.refine_from,
            material: m,
            lights,
            kept: self.kept,
            device: self.device,
            options: &self.options,
        })
    }
}

fn names(p: &Plan) -> Vec<String> {
    p.steps.iter().map(Step::name).collect()
}

fn left(p: &Plan, what: &str) -> Option<String> {
    p.left_out.iter().find(|l| l.what == what).map(|l| l.why.clone())
}

#[test]
fn the_canvas_view_is_the_canvas_pass_alone() {
    let p =
        Ask { view: View::Canvas, ..Ask::new(Estimator::Key, 64, 8) }.plan(&material(0.2, vec![lobe(0.5, 0.1)]), None);
    assert_eq!(names(&p), ["canvas"]);
    assert!(p.left_out.is_empty() && !p.raster);
}

#[test]
fn a_lobe_of_zero_albedo_has_no_pass() {
    let m = material(0.0, vec![lobe(0.5, 0.1), lobe(0.0, 0.2), lobe(0.3, 0.05)]);
    let p = Ask::new(Estimator::Fis, 32, 8).plan(&m, None);
    assert_eq!(names(&p), ["gbuffer", "lobe0[facet]", "lobe2[facet]"]);
    assert_eq!(left(&p, "lobe1").as_deref(), Some("its albedo is 0"));
}

#[test]
fn the_pass_names_are_the_timings_names() {
    let mut m = material(0.3, vec![lobe(0.5, 0.1), lobe(0.2, 0.2)]);
    m.normalization = Normalization::Ward;
    m.lobes[1].rotation = DQuat::from_rotation_z(0.2);
    m.lobes[1].split = true;
    assert_eq!(names(&Ask::new(Estimator::Fis, 16, 8).plan(&m, None)), ["gbuffer", "lobe0[]", "lobe1[rot,split]"]);
    let plain = Ask::new(Estimator::Plain, 16, 8).plan(&m, None);
    assert_eq!(names(&plain), ["gbuffer", "lobe0[level0]", "lobe1[rot,split,level0]"]);
    let scalar =
        Ask { options: Options { scalar_lobes: true, ..Options::default() }, ..Ask::new(Estimator::Fis, 16, 8) };
    assert_eq!(names(&scalar.plan(&m, None))[1], "lobe0[scalar]");
}

#[test]
fn mis_draws_the_whole_material_in_one_pass() {
    let m = material(0.3, vec![lobe(0.5, 0.1)]);
    let p = Ask::new(Estimator::Mis, 64, 8).plan(&m, None);
    assert_eq!(names(&p), ["gbuffer", "mis"]);
    assert_eq!(p.steps[0].pass, Pass::GBuffer { cull: true, start: Start::Here(None), background_blocks: false });
    assert_eq!(p.steps[1].pass, Pass::Mis { offset: 0, samples: 8 });
}

#[test]
fn a_frame_that_rasterises_starts_its_image_in_the_gbuffer_pass() {
    let m = material(0.3, vec![lobe(0.5, 0.1)]);
    let p = Ask::new(Estimator::Fis, 32, 8).plan(&m, None);
    assert_eq!(
        p.steps[0].pass,
        Pass::GBuffer { cull: true, start: Start::Here(Some(([0.3; 3], false))), background_blocks: false }
    );
    assert!(p.raster && p.pixels_listed == Some(true));
    assert!(left(&p, "diffuse").is_some_and(|w| w.contains("G-buffer")));
    let none = Ask::new(Estimator::Fis, 32, 8).plan(&material(0.0, vec![lobe(0.5, 0.1)]), None);
    assert!(matches!(none.steps[0].pass, Pass::GBuffer { start: Start::Here(None), .. }));
    assert_eq!(left(&none, "diffuse").as_deref(), Some("the diffuse albedo is 0"));
}

#[test]
fn frames_that_keep_the_gbuffer_copy_the_base_on_a_cpu_device() {
    let m = material(0.3, vec![lobe(0.5, 0.1)]);
    let kept = |pixels_listed, base| Kept { gbuffer: true, pixels_listed, base };
    let ask = |k| Ask { kept: k, ..Ask::new(Estimator::Fis, 32, 8) };
    // The second frame draws the start again and saves it; the third copies it back.
    let second = ask(kept(true, false)).plan(&m, None);
    assert_eq!(names(&second), ["background", "diffuse", "base.save", "lobe0[facet]"]);
    assert!(!second.raster && second.base_used && left(&second, "gbuffer").is_some());
    let third = ask(kept(true, true)).plan(&m, None);
    assert_eq!(names(&third), ["base", "lobe0[facet]"]);
    // A G-buffer whose pixels are not listed lists them in the compact pass, which starts the image.
    let unlisted = ask(kept(false, true)).plan(&m, None);
    assert_eq!(names(&unlisted), ["compact", "base.save", "lobe0[facet]"]);
    assert_eq!(unlisted.pixels_listed, Some(true));
    // `mis` leaves the base alone.
    let mis = Ask { kept: kept(true, true), ..Ask::new(Estimator::Mis, 32, 8) }.plan(&m, None);
    assert_eq!(names(&mis), ["background", "mis"]);
    assert!(!mis.base_used);
}

#[test]
fn frames_that_keep_the_gbuffer_draw_the_start_again_on_a_gpu() {
    let m = material(0.3, vec![lobe(0.5, 0.1)]);
    let kept = Kept { gbuffer: true, pixels_listed: true, base: true };
    let p = Ask { kept, device: DevicePlan::GPU, ..Ask::new(Estimator::Fis, 32, 8) }.plan(&m, None);
    assert_eq!(names(&p), ["compact", "lobe0[facet]"]);
    assert_eq!(p.steps[0].pass, Pass::Compact { diffuse: Some(([0.3; 3], false)) });
    assert!(!p.base_used);
}

#[test]
fn sparse_key_frames_filter_rough_lobes_by_blocks_and_defer_the_diffuse_term_on_a_cpu_device() {
    let m = material(0.2, vec![lobe(0.5, 0.5)]);
    let p = Ask::new(Estimator::Key, 64, 4).plan(&m, None);
    assert!(p.sparse);
    assert_eq!(names(&p), ["gbuffer", "clear", "lobe0[facet,key]", "denoise[sparse,diffuse]"]);
    assert_eq!(
        p.steps[0].pass,
        Pass::GBuffer { cull: true, start: Start::Later { pixels: false }, background_blocks: true }
    );
    assert_eq!(p.steps[1].pass, Pass::Zero { images: LobeImages::Cells, by_compute: false });
    let Pass::Lobe(l) = &p.steps[2].pass else { panic!("a lobe pass") };
    assert_eq!((l.into, l.variant.output), (Into::Cells { pixel_lights: false }, Output::Cells));
    assert!(!p.steps[1].timed() && p.steps[2].timed());
    // On a GPU the compact pass starts every pixel and a compute pass zeroes the cells.
    let gpu = Ask { device: DevicePlan::GPU, ..Ask::new(Estimator::Key, 64, 4) }.plan(&m, None);
    assert_eq!(names(&gpu), ["gbuffer", "zero", "lobe0[facet,key]", "denoise[sparse]"]);
    assert!(matches!(gpu.steps[0].pass, Pass::GBuffer { start: Start::Here(Some(_)), background_blocks: false, .. }));
}

#[test]
fn dense_key_frames_filter_rough_lobes_per_pixel() {
    let m = material(0.2, vec![lobe(0.5, 0.5), lobe(0.3, 0.01)]);
    // Under 64 pixels a side, or over 64 samples, a frame is dense.
    for (size, spp) in [(48, 4), (64, 128)] {
        let p = Ask::new(Estimator::Key, size, spp).plan(&m, None);
        assert!(!p.sparse);
        assert_eq!(names(&p), ["gbuffer", "clear", "lobe0[facet,key]", "lobe1[facet,key]", "denoise"], "{size} {spp}");
        let Pass::Lobe(sharp) = &p.steps[3].pass else { panic!("a lobe pass") };
        assert_eq!(sharp.into, Into::Accum, "a sharp lobe is not filtered");
        assert!(
            matches!(p.steps[4].pass, Pass::Denoise { min_alpha, sparse: false, diffuse: None } if min_alpha == 0.5)
        );
    }
    let sharp = material(0.2, vec![lobe(0.3, 0.01)]);
    let p = Ask::new(Estimator::Key, 48, 4).plan(&sharp, None);
    assert_eq!(left(&p, "zero, denoise").as_deref(), Some("no lobe is rough enough for the filter"));
    assert_eq!(
        left(&Ask::new(Estimator::Fis, 48, 4).plan(&m, None), "zero, denoise").as_deref(),
        Some("only the `key` estimator filters")
    );
}

#[test]
fn a_map_without_key_lights_gets_no_light_code() {
    let m = material(0.0, vec![lobe(0.5, 0.05)]);
    let p = Ask::new(Estimator::Key, 32, 8).plan(&m, None);
    assert_eq!(left(&p, "light term").as_deref(), Some("the map has no key lights"));
    let l = p.lobes().next().expect("a lobe pass");
    assert!(l.variant.lights == KeyLights::None && l.lights == LobeLights::None && p.light_samples.is_none());
}

#[test]
fn key_lobes_see_the_lights_as_points_tiles_or_samples_by_their_width() {
    let lights = lamp_lights();
    let m = material(0.0, vec![lobe(0.5, 0.6), lobe(0.3, 0.02)]);
    let p = Ask::new(Estimator::Key, 32, 8).plan(&m, Some(&lights));
    let lobes: Vec<&LobeStep> = p.lobes().collect();
    // A lobe much wider than the lamp sees it as its four points.
    assert_eq!(lobes[0].lights, LobeLights::Points);
    assert!(lobes[0].variant.points() && lobes[0].variant.reach() == Reach::Untested);
    // A narrow lobe resolves the lamp: tiles, with the reach test (it pays for a lobe this narrow).
    assert!(matches!(lobes[1].lights, LobeLights::Tiles(_)), "{:?}", lobes[1].lights);
    assert!(lobes[1].variant.points() && lobes[1].variant.reach() != Reach::Untested);
    assert!(p.light_samples.is_none());
    // A lobe too narrow for tiles within its allowance takes MIS light samples, which the frame draws.
    let p = Ask::new(Estimator::Key, 32, 8).plan(&material(0.0, vec![lobe(0.3, 0.0005)]), Some(&lights));
    let sharpest = p.lobes().next().expect("a lobe pass");
    assert_eq!(sharpest.lights, LobeLights::Samples);
    assert!(matches!(sharpest.variant.lights, KeyLights::Samples { reach: Reach::Tested { .. } }));
    assert_eq!(p.light_samples, Some(8));
    // The reach test is the options' to turn off, never the image's.
    let unreached =
        Ask { options: Options { light_reach_test: false, ..Options::default() }, ..Ask::new(Estimator::Key, 32, 8) };
    assert!(unreached.plan(&m, Some(&lights)).lobes().all(|l| l.variant.reach() == Reach::Untested));
    // `fis` ignores the lights.
    assert!(Ask::new(Estimator::Fis, 32, 8).plan(&m, Some(&lights)).lobes().all(|l| l.lights == LobeLights::None));
}

#[test]
fn refinement_frames_add_to_the_running_sum() {
    let m = material(0.3, vec![lobe(0.5, 0.1)]);
    let first = Ask { refine_from: Some(0), ..Ask::new(Estimator::Mis, 32, 8) }.plan(&m, None);
    assert_eq!(names(&first), ["gbuffer", "mis", "accumulate"]);
    assert_eq!(first.steps[2].pass, Pass::Accumulate { first: true, samples: 8 });
    let later = Ask { refine_from: Some(16), ..Ask::new(Estimator::Mis, 32, 8) }.plan(&m, None);
    assert_eq!(later.steps[1].pass, Pass::Mis { offset: 16, samples: 8 });
    assert_eq!(later.steps[2].pass, Pass::Accumulate { first: false, samples: 8 });
    let fresh = Ask::new(Estimator::Mis, 32, 8).plan(&m, None);
    assert!(left(&fresh, "accumulate").is_some());
}

#[test]
fn hidden_faces_are_culled_only_for_an_eye_outside_the_mesh() {
    let o = Options::default();
    assert!(culls(&Camera::default(), 64, 64, &o));
    let inside = Camera { eye: DVec3::new(0.0, 0.0, 0.9), ..Camera::default() };
    assert!(!culls(&inside, 64, 64, &o));
    // Just outside the unit sphere, the near plane's corners may still reach into it.
    let grazing = Camera { eye: DVec3::new(0.0, 0.0, 1.0 + 1e-4), ..Camera::default() };
    assert!(!culls(&grazing, 64, 64, &o));
    assert!(!culls(&Camera::default(), 64, 64, &Options { cull_hidden_faces: false, ..o }));
}

#[test]
fn the_any_output_stand_in_takes_every_lobe() {
    let m = material(0.0, vec![lobe(0.5, 0.5), lobe(0.3, 0.01)]);
    let ask =
        Ask { options: Options { any_output_lobes: true, ..Options::default() }, ..Ask::new(Estimator::Key, 64, 4) };
    let p = ask.plan(&m, None);
    assert!(p.lobes().all(|l| l.variant.output == Output::Any));
    assert_eq!(p.lobes().next().map(|l| l.into), Some(Into::Cells { pixel_lights: false }));
}

#[test]
fn the_plan_reads_in_words_and_as_json() {
    let lights = lamp_lights();
    let m = material(0.2, vec![lobe(0.5, 0.5), lobe(0.0, 0.1), lobe(0.3, 0.02)]);
    let p = Ask::new(Estimator::Key, 64, 4).plan(&m, Some(&lights));
    let text = p.describe();
    assert!(text.starts_with(&format!("plan of the mesh view: {} passes\n", p.steps.len())), "{text}");
    for s in &p.steps {
        assert!(text.contains(&s.name()) && text.contains(&s.why), "{text}");
    }
    assert!(text.contains("left out:\n  - lobe1: its albedo is 0"), "{text}");
    let json = p.to_json();
    let passes = json["passes"].as_array().expect("passes");
    assert_eq!(passes.len(), p.steps.len());
    assert_eq!(passes[0]["name"], "gbuffer");
    assert!(json["left_out"].as_array().is_some_and(|l| l.iter().any(|x| x["what"] == "lobe1")));
}
