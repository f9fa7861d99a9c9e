//! The material file (`*.brdf.json`, docs/formats.md, Material file): parsing with every refusal naming the field and
//! the reason, validation (ranges, unit quaternions, the energy bound), and serialisation.
//!
//! Unknown fields are refused. Version 2 (what this program writes) adds `"model"`: `"reciprocal"`
//! (the default: the reciprocal, energy-bounded facet lobes; `rotation` is the facet frame `Q`,
//! `normalization` and `symmetrize` are not allowed) or `"paper"` (the paper's rotated views, with
//! `normalization` and `symmetrize` as in version 1). Version-1 files have no `model` and mean the
//! paper's construction. A missing `normalization` means `"ward"` (the paper's eq. 1); missing
//! `symmetrize`, `tangent_angle`, `rotation` and `split` mean `false`, 0, identity and `false`.
//! A reciprocal material's `"preserve_energy"` (docs/model.md, Energy preservation) says whether its
//! lobes add their energy compensation; missing, it means `false` (how such a file always rendered).

use std::path::Path;

use glam::DQuat;
use serde::{Deserialize, Serialize};

use super::material::{Lobe, Material, ALPHA_MAX, ALPHA_MIN, MAX_LOBES};
use super::ward::Normalization;
use crate::error::{Error, Result};

pub const MATERIAL_FORMAT: &str = "brdf-shop/material";
pub const MATERIAL_VERSION: u32 = 2;

/// The largest material or strokes file read (bytes), checked before it is read: a material of
/// [`MAX_LOBES`] lobes is about 100 kB and a long editor session's strokes a few MB, so 16 MiB is
/// ample while keeping the parsed document (a few times the text) well under a gigabyte.
pub const MAX_JSON_BYTES: u64 = 16 << 20;

/// The construction a version-2 file's lobes follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum Model {
    Reciprocal,
    Paper,
}

fn identity() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LobeFile {
    albedo: [f64; 3],
    alpha_x: f64,
    alpha_y: f64,
    #[serde(default)]
    tangent_angle: f64,
    #[serde(default = "identity")]
    rotation: [f64; 4],
    #[serde(default)]
    split: bool,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialFile {
    format: String,
    version: u32,
    diffuse: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    model: Option<Model>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normalization: Option<Normalization>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    symmetrize: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    preserve_energy: Option<bool>,
    lobes: Vec<LobeFile>,
}

/// The normalisation and `symmetrize` a file means, by version (see the module note).
fn model_of(origin: &str, f: &MaterialFile) -> Result<(Normalization, bool)> {
    let symmetrize = f.symmetrize.unwrap_or(false);
    if f.normalization == Some(Normalization::Reciprocal) {
        return Err(Error::input(
            origin,
            "normalization: \"reciprocal\" is not a normalisation; version 2 says \"model\": \"reciprocal\"",
        ));
    }
    match (f.version, f.model) {
        (1, Some(_)) => {
            Err(Error::input(origin, "model: needs \"version\": 2 (version 1 means the paper's construction)"))
        }
        (1, None) | (_, Some(Model::Paper)) => {
            if f.preserve_energy.is_some() {
                return Err(Error::input(
                    origin,
                    "preserve_energy: only for \"model\": \"reciprocal\" (the paper's model is as the paper has it)",
                ));
            }
            Ok((f.normalization.unwrap_or_default(), symmetrize))
        }
        (_, None | Some(Model::Reciprocal)) => {
            if f.normalization.is_some() {
                return Err(Error::input(
                    origin,
                    "normalization: only for \"model\": \"paper\" (the reciprocal model has its own normalisation)",
                ));
            }
            if f.symmetrize.is_some() {
                return Err(Error::input(
                    origin,
                    "symmetrize: only for \"model\": \"paper\" (the reciprocal model is exactly reciprocal already)",
                ));
            }
            Ok((Normalization::Reciprocal, false))
        }
    }
}

/// Parses JSON into `T`, naming the path of the field that failed (`lobes[0].alpha_x: …`).
pub(crate) fn parse_json<'de, T: Deserialize<'de>>(text: &'de str, origin: &str) -> Result<T> {
    if text.trim().is_empty() {
        return Err(Error::input(origin, "the file is empty"));
    }
    let de = &mut serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
        let path = e.path().to_string();
        // serde echoes values and unknown names whole: cut to what a message quotes.
        let inner = crate::fsio::shorten_words(&e.into_inner().to_string(), crate::fsio::QUOTE_CHARS);
        // `?` is serde_path_to_error's unknown segment (e.g. end of file): it names no field.
        if path == "." || path == "?" || path.is_empty() {
            Error::input(origin, inner)
        } else {
            Error::input(origin, format!("{}: {inner}", crate::fsio::quote(&path)))
        }
    })?;
    // Anything after the JSON value (a second object, stray text) makes the file invalid.
    de.end().map_err(|e| Error::input(origin, crate::fsio::shorten_words(&e.to_string(), crate::fsio::QUOTE_CHARS)))?;
    Ok(value)
}

/// Checks the `format` tag and that `version` is one of `1..=newest`.
pub(crate) fn check_format(origin: &str, format: &str, want: &str, version: u32, newest: u32) -> Result<()> {
    if format != want {
        return Err(Error::input(
            origin,
            format!("format: expected \"{want}\", got \"{}\"", crate::fsio::quote(format)),
        ));
    }
    if !(1..=newest).contains(&version) {
        let reads = if newest == 1 { "version 1".to_owned() } else { format!("versions 1 to {newest}") };
        return Err(Error::input(
            origin,
            format!("version: unsupported version {version} (this program reads {reads})"),
        ));
    }
    Ok(())
}

fn check_albedo(origin: &str, field: &str, c: [f64; 3]) -> Result<()> {
    for (i, v) in c.iter().enumerate() {
        if !(v.is_finite() && *v >= 0.0) {
            return Err(Error::input(origin, format!("{field}[{i}]: must be a finite number ≥ 0, got {v}")));
        }
    }
    Ok(())
}

const CHANNELS: [&str; 3] = ["red", "green", "blue"];

impl Material {
    /// Checks ranges and the energy bound; `origin` names the file in the message.
    pub fn validate(&self, origin: &str) -> Result<()> {
        if self.lobes.len() > MAX_LOBES {
            return Err(Error::input(
                origin,
                format!("lobes: {} lobes, more than the limit of {MAX_LOBES}", self.lobes.len()),
            ));
        }
        check_albedo(origin, "diffuse", self.diffuse)?;
        if self.preserve_energy && self.normalization != Normalization::Reciprocal {
            return Err(Error::input(origin, "preserve_energy: only for the reciprocal model"));
        }
        for (k, l) in self.lobes.iter().enumerate() {
            check_albedo(origin, &format!("lobes[{k}].albedo"), l.albedo)?;
            for (name, a) in [("alpha_x", l.alpha_x), ("alpha_y", l.alpha_y)] {
                if !(a.is_finite() && (ALPHA_MIN..=ALPHA_MAX).contains(&a)) {
                    return Err(Error::input(
                        origin,
                        format!("lobes[{k}].{name}: must be in [{ALPHA_MIN}, {ALPHA_MAX}], got {a}"),
                    ));
                }
            }
            if !l.tangent_angle.is_finite() {
                return Err(Error::input(origin, format!("lobes[{k}].tangent_angle: must be finite")));
            }
        }
        if let Some((c, sum)) = self.energy_violation() {
            return Err(Error::input(
                origin,
                format!("energy bound broken in the {} channel: diffuse + Σ lobe albedos = {sum} > 1", CHANNELS[c]),
            ));
        }
        Ok(())
    }

    /// Parses and validates a material file's text.
    pub fn from_json(text: &str, origin: &str) -> Result<Material> {
        let f: MaterialFile = parse_json(text, origin)?;
        check_format(origin, &f.format, MATERIAL_FORMAT, f.version, MATERIAL_VERSION)?;
        let (normalization, symmetrize) = model_of(origin, &f)?;
        if f.lobes.len() > MAX_LOBES {
            return Err(Error::input(
                origin,
                format!("lobes: {} lobes, more than the limit of {MAX_LOBES}", f.lobes.len()),
            ));
        }
        let mut lobes = Vec::with_capacity(f.lobes.len());
        for (k, l) in f.lobes.into_iter().enumerate() {
            let [w, x, y, z] = l.rotation;
            let q = DQuat::from_xyzw(x, y, z, w);
            // Scaled by its largest component first, so that a finite quaternion whose squared
            // length overflows (components near 1e154 and above) still normalises.
            let big = [w, x, y, z].iter().fold(0.0f64, |a, c| a.max(c.abs()));
            let len = q.length();
            if !(big.is_finite() && big > 0.0 && (q / big).length() * big > 1e-12) {
                return Err(Error::input(
                    origin,
                    format!("lobes[{k}].rotation: a quaternion of length {len} cannot be normalised"),
                ));
            }
            // A quaternion that is already unit to rounding is kept as written, so files read back
            // bit for bit.
            let rotation = if (len - 1.0).abs() < 1e-14 {
                q
            } else {
                let s = q / big;
                s / s.length()
            };
            lobes.push(Lobe {
                albedo: l.albedo,
                alpha_x: l.alpha_x,
                alpha_y: l.alpha_y,
                tangent_angle: l.tangent_angle,
                rotation,
                split: l.split,
            });
        }
        let preserve_energy = f.preserve_energy.unwrap_or(false);
        let m = Material { diffuse: f.diffuse, normalization, symmetrize, lobes, preserve_energy };
        m.validate(origin)?;
        Ok(m)
    }

    /// Reads and validates a material file.
    pub fn load(path: &Path) -> Result<Material> {
        let text = crate::fsio::read_text_limited(path, MAX_JSON_BYTES, "a material file")?;
        Material::from_json(&text, &crate::fsio::show(path))
    }

    /// The file's JSON text (pretty, full `f64` precision: it reads back bit for bit).
    pub fn to_json(&self) -> String {
        let reciprocal = self.normalization == Normalization::Reciprocal;
        let f = MaterialFile {
            format: MATERIAL_FORMAT.into(),
            version: MATERIAL_VERSION,
            diffuse: self.diffuse,
            model: Some(if reciprocal { Model::Reciprocal } else { Model::Paper }),
            normalization: (!reciprocal).then_some(self.normalization),
            symmetrize: (!reciprocal).then_some(self.symmetrize),
            preserve_energy: reciprocal.then_some(self.preserve_energy),
            lobes: self
                .lobes
                .iter()
                .map(|l| LobeFile {
                    albedo: l.albedo,
                    alpha_x: l.alpha_x,
                    alpha_y: l.alpha_y,
                    tangent_angle: l.tangent_angle,
                    rotation: [l.rotation.w, l.rotation.x, l.rotation.y, l.rotation.z],
                    split: l.split,
                })
                .collect(),
        };
        let mut s = serde_json::to_string_pretty(&f).expect("a material always serialises");
        s.push('\n');
        s
    }

    /// Validates, then writes atomically (temp file + rename): a failure leaves `path` untouched.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(&path.display().to_string())?;
        crate::fsio::write_atomic(path, self.to_json().as_bytes())
    }
}
