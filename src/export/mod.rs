//! `brdf-shop export`: a material as a file other tools read — a Mitsuba 3 BSDF plug-in with a ready
//! scene (`mitsuba`), a Disney BRDF Explorer analytic BRDF (`brdf-explorer`), and a self-contained
//! GLSL function (`glsl`). Each evaluates exactly what `brdf-shop eval` does: the GLSL formats ship
//! the renderer's own model source (`glsl/include/math.glsl`, `brdf.glsl`), the Mitsuba plug-in
//! mirrors `src/brdf` in double precision.
//!
//! Owns the text of each format; writes files only through `fsio::write_atomic`. No GPU code.

mod glsl;
mod mitsuba;

use std::path::Path;

use crate::brdf::Material;
use crate::error::{Error, Result};

pub use glsl::{brdf_explorer, glsl, model_source, BRDF_EXPLORER_MAX_LOBES};
pub use mitsuba::mitsuba;

/// The formats `export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Mitsuba,
    BrdfExplorer,
    Glsl,
}

impl Format {
    pub const ALL: [Format; 3] = [Format::Mitsuba, Format::BrdfExplorer, Format::Glsl];

    pub fn name(self) -> &'static str {
        match self {
            Format::Mitsuba => "mitsuba",
            Format::BrdfExplorer => "brdf-explorer",
            Format::Glsl => "glsl",
        }
    }

    /// The file name ending a user expects for this format.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Mitsuba => "py",
            Format::BrdfExplorer => "brdf",
            Format::Glsl => "glsl",
        }
    }

    /// Parses a `--format` value; an unknown one is refused naming the known ones.
    pub fn parse(text: &str) -> Result<Format> {
        Format::ALL.into_iter().find(|f| f.name() == text).ok_or_else(|| {
            let known: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
            Error::input(
                "--format",
                format!("unknown format \"{}\" (known: {})", crate::fsio::quote(text), known.join(", ")),
            )
        })
    }
}

/// The exported text of `material` in `format`; a material the format cannot express is refused.
pub fn text(material: &Material, format: Format) -> Result<String> {
    match format {
        Format::Mitsuba => Ok(mitsuba(material)),
        Format::BrdfExplorer => brdf_explorer(material),
        Format::Glsl => Ok(glsl(material)),
    }
}

/// Writes `material` in `format` to `out` atomically (temp file + rename): on any failure `out` is
/// left as it was.
pub fn write(material: &Material, format: Format, out: &Path) -> Result<()> {
    crate::fsio::check_output("--out", out)?;
    let text = text(material, format)?;
    crate::fsio::write_atomic(out, text.as_bytes())
}
