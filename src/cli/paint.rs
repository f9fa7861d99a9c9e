//! `brdf-shop paint`: replays a strokes file onto a material and writes the result atomically.

use std::path::Path;

use brdf_shop::brdf::Material;
use brdf_shop::brush::Strokes;

pub fn run(strokes: &Path, material: Option<&Path>, out: &Path) -> anyhow::Result<()> {
    let s = Strokes::load(strokes)?;
    let start = match material {
        Some(p) => Material::load(p)?,
        None => Material::scratch(),
    };
    let m = s.replay(&start, &strokes.display().to_string())?;
    m.save(out)?;
    eprintln!("wrote {} ({} lobes)", out.display(), m.lobes.len());
    Ok(())
}
