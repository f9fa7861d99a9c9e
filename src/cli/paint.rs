//! `brdf-shop paint`: replays a strokes file onto a material and writes the result atomically.

use std::path::Path;

use brdf_shop::brdf::Material;
use brdf_shop::brush::Strokes;

use super::UsageError;

pub fn run(strokes: &Path, material: Option<&Path>, out: &Path, model: Option<&str>) -> anyhow::Result<()> {
    let scratch = match model {
        None | Some("reciprocal") => Material::scratch(),
        Some("paper") => Material::scratch_paper(),
        Some(other) => {
            let shown: String = other.chars().take(40).flat_map(char::escape_default).collect();
            return Err(UsageError(format!("--model: expected reciprocal or paper, got \"{shown}\"")).into());
        }
    };
    if model.is_some() && material.is_some() {
        return Err(UsageError(
            "--model chooses the scratch material's construction; --material brings its own".into(),
        )
        .into());
    }
    brdf_shop::fsio::check_output("--out", out)?;
    let s = Strokes::load(strokes)?;
    let start = match material {
        Some(p) => Material::load(p)?,
        None => scratch,
    };
    let m = s.replay(&start, &brdf_shop::fsio::show(strokes))?;
    m.save(out)?;
    eprintln!("wrote {} ({} lobes)", brdf_shop::fsio::show(out), m.lobes.len());
    Ok(())
}
