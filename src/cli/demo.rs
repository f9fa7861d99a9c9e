//! The headless main job (until the editor lands): paints the embedded default strokes onto the
//! scratch material and writes `material.brdf.json`, `canvas.png` (the CPU canvas, 512²) and
//! `check.txt` (the energy report) into a folder.

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

    let (samples, pairs) = (20_000, 200_000);
    let report = Report::measure(&m, samples, pairs);
    let text = super::check::report_text(&m, &report, samples, pairs);
    brdf_shop::fsio::write_atomic(&out.join("check.txt"), text.as_bytes())?;
    print!("{text}");
    println!("wrote {0}/material.brdf.json, {0}/canvas.png, {0}/check.txt", brdf_shop::fsio::show(out));
    Ok(())
}
