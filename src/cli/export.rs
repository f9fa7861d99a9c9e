//! `brdf-shop export --material M --format F --out P`: the material as a file for another tool
//! (`brdf_shop::export`). The format is checked before the material is read; the output is written
//! atomically, so a failure leaves an existing file as it was.

use std::path::Path;

use brdf_shop::brdf::Material;
use brdf_shop::export::{self, Format};

pub fn run(material: &Path, format: &str, out: &Path) -> anyhow::Result<()> {
    let format = Format::parse(format)?;
    brdf_shop::fsio::check_output("--out", out)?;
    let m = Material::load(material)?;
    export::write_named(&m, format, &export::name_of(material), out)?;
    eprintln!("brdf-shop: wrote {} ({})", brdf_shop::fsio::show(out), format.name());
    if let Some(note) = export::note(&m, format) {
        eprintln!("brdf-shop: note: {note}");
    }
    Ok(())
}
