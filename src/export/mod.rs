//! `brdf-shop export`: a material as a file other tools read — a Mitsuba 3 BSDF plug-in with a ready
//! scene (`mitsuba`), a Disney BRDF Explorer analytic BRDF (`brdf-explorer`), and a self-contained
//! GLSL function (`glsl`), and a Blender material of Cycles closures with a ready scene (`blender`).
//! The first three evaluate exactly what `brdf-shop eval` does: the GLSL formats ship the
//! renderer's own model source (`glsl/include/math.glsl`, `brdf.glsl`), the Mitsuba plug-in mirrors
//! `src/brdf` in double precision. The Blender material approximates the model with Cycles' own
//! closures, its reflected energy matched per view direction (`blender.rs`).
//!
//! Owns the text of each format; writes files only through `fsio::write_atomic`. No GPU code.

mod blender;
mod glsl;
mod mitsuba;

use std::path::Path;

use crate::brdf::Material;
use crate::error::{Error, Result};

pub use blender::{blender, closure_count, MAX_CLOSURES, PAPER_NOTE};
pub use glsl::{brdf_explorer, glsl, model_source, BRDF_EXPLORER_MAX_LOBES};
pub use mitsuba::mitsuba;

/// The formats `export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Mitsuba,
    BrdfExplorer,
    Glsl,
    Blender,
}

impl Format {
    pub const ALL: [Format; 4] = [Format::Mitsuba, Format::BrdfExplorer, Format::Glsl, Format::Blender];

    pub fn name(self) -> &'static str {
        match self {
            Format::Mitsuba => "mitsuba",
            Format::BrdfExplorer => "brdf-explorer",
            Format::Glsl => "glsl",
            Format::Blender => "blender",
        }
    }

    /// The file name ending a user expects for this format.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Mitsuba => "py",
            Format::BrdfExplorer => "brdf",
            Format::Glsl => "glsl",
            Format::Blender => "py",
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
/// `name` names what the format names (the Blender material and node group).
pub fn text(material: &Material, format: Format, name: &str) -> Result<String> {
    match format {
        Format::Mitsuba => Ok(mitsuba(material)),
        Format::BrdfExplorer => brdf_explorer(material),
        Format::Glsl => Ok(glsl(material)),
        Format::Blender => blender(material, name),
    }
}

/// What a user should know about exporting `material` in `format` (one line), if anything.
pub fn note(material: &Material, format: Format) -> Option<&'static str> {
    (format == Format::Blender && material.normalization != crate::brdf::Normalization::Reciprocal)
        .then_some(PAPER_NOTE)
}

/// The name a material file gives its export: the file name without `.brdf.json` or `.json` (in any
/// case): `glossy.brdf.json` → `glossy`, `m.JSON` → `m`; `material` when nothing is left.
pub fn name_of(path: &Path) -> String {
    let file = path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let cut = |end: &str| {
        let at = file.len().checked_sub(end.len())?;
        (file.is_char_boundary(at) && file[at..].eq_ignore_ascii_case(end)).then(|| &file[..at])
    };
    let stem = cut(".brdf.json").or_else(|| cut(".json")).unwrap_or(&file);
    if stem.is_empty() {
        "material".into()
    } else {
        stem.into()
    }
}

/// Writes `material` in `format` to `out` atomically (temp file + rename): on any failure `out` is
/// left as it was. Named after `out`'s file name without its extension.
pub fn write(material: &Material, format: Format, out: &Path) -> Result<()> {
    let name = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "brdf-shop".into());
    write_named(material, format, &name, out)
}

/// [`write`] with the name given (`brdf-shop export` passes the material file's, [`name_of`]).
pub fn write_named(material: &Material, format: Format, name: &str, out: &Path) -> Result<()> {
    crate::fsio::check_output("--out", out)?;
    let text = text(material, format, name)?;
    crate::fsio::write_atomic(out, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_material_file_names_its_export_without_its_endings() {
        assert_eq!(name_of(Path::new("a/painted.brdf.json")), "painted");
        assert_eq!(name_of(Path::new("metal.json")), "metal");
        assert_eq!(name_of(Path::new("plain")), "plain");
        assert_eq!(name_of(Path::new(".brdf.json")), "material");
        assert_eq!(name_of(Path::new("m.JSON")), "m");
    }

    #[test]
    fn every_format_parses_from_its_name() {
        for f in Format::ALL {
            assert_eq!(Format::parse(f.name()).unwrap(), f);
        }
        assert_eq!(Format::parse("blender").unwrap().extension(), "py");
    }
}
