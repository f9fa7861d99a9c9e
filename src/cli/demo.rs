//! The headless main job: paints the embedded default strokes onto the scratch material and writes
//! into a folder `mesh.png` (the material on the torus under the studio map, with the map behind it
//! as the editor shows it: rendered on the GPU), `canvas.png` (the CPU canvas, 512²),
//! `material.brdf.json` and `check.txt` (the energy report), then says what to run next.

use std::path::Path;

use anyhow::Context;
use brdf_shop::brdf::energy::Report;
use brdf_shop::brdf::Material;
use image::ImageEncoder;

pub fn run(out: &Path) -> anyhow::Result<()> {
    let strokes = brdf_shop::brush::strokes::default_strokes()?;
    let m = strokes.replay(&Material::scratch(), "embedded default strokes")?;
    brdf_shop::fsio::check_output_dir("--out", out)?;
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create the folder", out.display()))?;
    m.save(&out.join("material.brdf.json"))?;

    let settings = strokes.settings("embedded default strokes")?;
    const SIZE: usize = 512;
    let img = settings.canvas.image(&m, SIZE);
    let mut rgb = Vec::with_capacity(SIZE * SIZE * 3);
    for p in &img {
        rgb.extend(p.map(|v| brdf_shop::imageio::srgb8(v, 0.5)));
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, SIZE as u32, SIZE as u32, image::ExtendedColorType::Rgb8)
        .context("encoding canvas.png")?;
    brdf_shop::fsio::write_atomic(&out.join("canvas.png"), &png)?;

    let mesh_png = render_mesh(&m)?;
    brdf_shop::fsio::write_atomic(&out.join("mesh.png"), &mesh_png)?;

    let (samples, pairs) = (20_000, 200_000);
    let report = Report::measure(&m, samples, pairs);
    let text = super::check::report_text(&m, &report, None, samples, pairs);
    brdf_shop::fsio::write_atomic(&out.join("check.txt"), text.as_bytes())?;
    print!("{text}");
    println!("wrote {0}/mesh.png, {0}/canvas.png, {0}/material.brdf.json, {0}/check.txt", brdf_shop::fsio::show(out));
    println!(
        "next: `brdf-shop edit` paints it in the editor (needs a display); `brdf-shop render --material {}/material.brdf.json --env assets/hdri/studio.exr --out m.png` renders it",
        brdf_shop::fsio::show(out)
    );
    Ok(())
}

/// The side lengths of `mesh.png`.
const MESH_SIZE: (u32, u32) = (800, 600);

/// `m` on the torus under the embedded studio map, seen as the editor first shows it (the orbit's
/// start, framed; the map's mean at mid grey on the object, its median at mid grey behind it, two
/// levels down its mip chain), `key` at 32 samples per lobe, as PNG bytes.
fn render_mesh(m: &Material) -> anyhow::Result<Vec<u8>> {
    use brdf_shop::editor::{backdrop, lighting, state};
    use brdf_shop::render::{Estimator, Renderer, Settings, View};
    let env = brdf_shop::measure::embedded_environment()?;
    let (w, h) = MESH_SIZE;
    let distance = brdf_shop::scene::camera::fit_distance(30.0, w as f64 / h as f64, 1.0, state::FRAME_MARGIN);
    let pitch = state::DEFAULT_PITCH;
    let eye = glam::DVec3::new(0.0, pitch.sin(), pitch.cos()) * distance;
    let camera = brdf_shop::scene::Camera { eye, ..Default::default() };
    let look = backdrop::Backdrop::default();
    let mut renderer = Renderer::new(brdf_shop::vk::Context::from_env()?)?;
    renderer.set_environment(&env)?;
    renderer.set_mesh(&brdf_shop::scene::Mesh::torus())?;
    let settings = Settings {
        width: w,
        height: h,
        spp: 32,
        estimator: Estimator::Key,
        view: View::Mesh,
        light: lighting::light_from(&lighting::EnvSummary::of(&env), &camera),
        camera,
        intensity: 1.0,
        backdrop_blur: look.blur,
    };
    let mut image = renderer.render(m, &settings)?.image;
    let brightness = look.scale(backdrop::auto_brightness(&env));
    brdf_shop::imageio::scale_backdrop(&mut image.pixels, brightness);
    let exposure = lighting::auto_exposure(&env);
    Ok(brdf_shop::imageio::encode_view(std::path::Path::new("mesh.png"), w, h, &image.pixels, exposure, 1.0)?)
}
