//! The strokes file (`*.strokes.json`, docs/formats.md, Strokes file) and its replay: a canvas setup and a list of
//! strokes in normalised canvas coordinates, applied in order through the same brush functions the editor
//! uses. Replay is sequential `f64` arithmetic, so it yields the same material bit for bit every run.

use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::brushes::{self, ModifyRule, Settings};
use super::canvas::Canvas;
use crate::brdf::file::{check_format, parse_json};
use crate::brdf::Material;
use crate::error::{Error, Result};

pub const STROKES_FORMAT: &str = "brdf-shop/strokes";

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BrushKind {
    Create,
    Modify,
    Streak,
    Intensify,
    #[serde(rename = "de-intensify", alias = "deintensify")]
    Deintensify,
}

impl BrushKind {
    pub fn name(self) -> &'static str {
        match self {
            BrushKind::Create => "create",
            BrushKind::Modify => "modify",
            BrushKind::Streak => "streak",
            BrushKind::Intensify => "intensify",
            BrushKind::Deintensify => "de-intensify",
        }
    }
}

/// One stroke: the brush, its points in canvas coordinates, and optionally the lobe it acts on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stroke {
    pub brush: BrushKind,
    pub points: Vec<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lobe: Option<usize>,
}

fn default_gamma() -> f64 {
    0.8
}
fn default_true() -> bool {
    true
}
fn default_intensity() -> f64 {
    1.0
}

/// A whole strokes file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Strokes {
    pub format: String,
    pub version: u32,
    /// Canvas light direction (normalised on load).
    pub light: [f64; 3],
    #[serde(default = "default_gamma")]
    pub gamma: f64,
    #[serde(default = "default_true")]
    pub split_lobes: bool,
    /// Canvas light radiance scale `I`.
    #[serde(default = "default_intensity")]
    pub intensity: f64,
    /// How modify strokes set roughness (extension; default `gamma`).
    #[serde(default)]
    pub modify_rule: ModifyRule,
    pub strokes: Vec<Stroke>,
}

impl Strokes {
    pub fn from_json(text: &str, origin: &str) -> Result<Strokes> {
        let s: Strokes = parse_json(text, origin)?;
        check_format(origin, &s.format, STROKES_FORMAT, s.version, 1)?;
        s.settings(origin)?;
        for (i, st) in s.strokes.iter().enumerate() {
            if st.points.is_empty() {
                return Err(Error::input(origin, format!("strokes[{i}].points: a stroke needs at least one point")));
            }
            for (j, p) in st.points.iter().enumerate() {
                if !p.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
                    return Err(Error::input(
                        origin,
                        format!(
                            "strokes[{i}].points[{j}]: canvas coordinates must lie in [0, 1], got [{}, {}]",
                            p[0], p[1]
                        ),
                    ));
                }
            }
            let needs_two = matches!(st.brush, BrushKind::Modify | BrushKind::Streak) && st.lobe.is_none();
            if needs_two && st.points.len() < 2 {
                return Err(Error::input(
                    origin,
                    format!(
                        "strokes[{i}].points: {} needs two points (the highlight, then the brush) or a \"lobe\"",
                        st.brush.name()
                    ),
                ));
            }
        }
        Ok(s)
    }

    pub fn load(path: &Path) -> Result<Strokes> {
        let text = crate::fsio::read_text_limited(path, crate::brdf::file::MAX_JSON_BYTES, "a strokes file")?;
        Strokes::from_json(&text, &crate::fsio::show(path))
    }

    /// The brush settings this file asks for.
    pub fn settings(&self, origin: &str) -> Result<Settings> {
        let l = DVec3::from_array(self.light);
        let canvas = Canvas::new(l, self.intensity).ok_or_else(|| {
            Error::input(origin, format!("light: must be a finite, non-zero direction, got {:?}", self.light))
        })?;
        if !(self.gamma > 0.0 && self.gamma < 1.0) {
            return Err(Error::input(origin, format!("gamma: must be in (0, 1), got {}", self.gamma)));
        }
        if !(self.intensity.is_finite() && self.intensity > 0.0) {
            return Err(Error::input(
                origin,
                format!("intensity: must be a finite number > 0, got {}", self.intensity),
            ));
        }
        let mut s = Settings::new(canvas);
        s.gamma = self.gamma;
        s.split_lobes = self.split_lobes;
        s.modify_rule = self.modify_rule;
        Ok(s)
    }

    /// Applies every stroke in order to `start`. An error names the stroke.
    pub fn replay(&self, start: &Material, origin: &str) -> Result<Material> {
        let settings = self.settings(origin)?;
        let mut m = start.clone();
        for (i, st) in self.strokes.iter().enumerate() {
            m = apply(&m, &settings, st)
                .map_err(|e| Error::input(origin, format!("strokes[{i}] ({}): {e}", st.brush.name())))?;
        }
        Ok(m)
    }
}

/// The strokes the editor's starter material and the `demo` command are painted with.
pub const DEFAULT_STROKES: &str = include_str!("../../assets/default.strokes.json");

/// The embedded default strokes.
pub fn default_strokes() -> Result<Strokes> {
    Strokes::from_json(DEFAULT_STROKES, "embedded default strokes")
}

/// The starter material: the default strokes painted on the scratch material.
pub fn default_material() -> Result<Material> {
    default_strokes()?.replay(&Material::scratch(), "embedded default strokes")
}

/// Applies one stroke: `create` at its first point; the others act on `lobe`, or on the lobe under
/// the first point. Modify and streak put the brush at the last point; intensify and de-intensify
/// step once per point.
pub fn apply(m: &Material, s: &Settings, st: &Stroke) -> Result<Material> {
    let pts: Vec<(f64, f64)> = st.points.iter().map(|p| (p[0], p[1])).collect();
    let (Some(&first), Some(&last)) = (pts.first(), pts.last()) else {
        return Err(Error::Brush("a stroke needs at least one point".into()));
    };
    let lobe = || match st.lobe {
        Some(k) => Ok(k),
        None => brushes::lobe_under(m, &s.canvas, first)
            .ok_or_else(|| Error::Brush(format!("no highlight under point ({:.4}, {:.4})", first.0, first.1))),
    };
    match st.brush {
        BrushKind::Create => brushes::create(m, s, first).map(|(m, _)| m),
        BrushKind::Modify => brushes::modify(m, s, lobe()?, last),
        BrushKind::Streak => brushes::streak(m, s, lobe()?, last),
        BrushKind::Intensify | BrushKind::Deintensify => {
            let k = lobe()?;
            let mut out = m.clone();
            for _ in &pts {
                out = if st.brush == BrushKind::Intensify {
                    brushes::intensify(&out, s, k)?
                } else {
                    brushes::deintensify(&out, s, k)?
                };
            }
            Ok(out)
        }
    }
}
