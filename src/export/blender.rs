//! `--format blender`: a Python file that builds the material in Blender as Cycles closures and,
//! run as a program, renders it (`blender_material.py`, its template, documents both).
//!
//! Cycles cannot define a new BSDF, so the export is an approximation: each facet frame of the
//! reciprocal model becomes a Beckmann Glossy BSDF about the facet's mean normal, and a per-facet
//! lookup image, computed here, scales its colour by the ratio of brdf-shop's directional albedo of
//! that facet term to Cycles' Beckmann + Smith albedo of the closure, so that the reflected energy
//! matches per view direction (docs/exports.md, Blender (Cycles)). An energy-preserving material's
//! compensation terms join the Diffuse closure, its colour raised by a lookup image of the terms'
//! directional albedo over the view ([`compensation_image`]). Materials of the paper model go
//! through the reciprocal model first (`Material::converted`).

use std::fmt::Write as _;

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::brdf::sampling;
use crate::brdf::ward::Shape;
use crate::brdf::{Material, Normalization};
use crate::error::{Error, Result};
use crate::scene::env::{MAX_ENV_FILE_BYTES, MAX_ENV_SIDE, MAX_ENV_TEXELS};

/// Texels per side of a facet's lookup image.
pub const TABLE_SIZE: usize = 48;

/// Closures Cycles keeps in one shader (`MAX_CLOSURE`); it drops the rest without a message.
pub const MAX_CLOSURES: usize = 64;

/// Cells per side of the quadrature of both albedos at one view (the sampler's unit square). Both
/// albedos use the same half vectors, so the ratio's quadrature error largely cancels.
const GRID: usize = 48;

/// The largest lookup value: near the facet's horizon Cycles' albedo goes to 0 faster than
/// brdf-shop's, and an unbounded ratio there would turn a few grazing texels into fireflies.
const RATIO_MAX: f64 = 4.0;

/// The note printed and written into the file for a material of the paper model.
pub const PAPER_NOTE: &str = "the paper-model material is approximated twice: converted to the reciprocal model \
     (as the editor's model switch does), then to Cycles closures";

const TEMPLATE: &str = include_str!("blender_material.py");

/// One Glossy closure: a facet frame of a reciprocal lobe with its share of the albedo.
struct Facet {
    colour: [f64; 3],
    frame: DQuat,
    shape: Shape<f64>,
    tangent_angle: f64,
}

fn facets(m: &Material) -> Vec<Facet> {
    let mut out = Vec::new();
    for l in &m.lobes {
        if l.albedo.iter().all(|&a| a <= 0.0) {
            continue;
        }
        let (frames, n) = l.facet_frames();
        for &frame in &frames[..n] {
            out.push(Facet {
                colour: l.albedo.map(|a| a / n as f64),
                frame,
                shape: l.shape(),
                tangent_angle: l.tangent_angle,
            });
        }
    }
    out
}

/// Whether `m` (of the reciprocal model) has a compensation term to show: an energy-preserving
/// material with a lobe of some albedo.
fn compensates(m: &Material) -> bool {
    m.compensated() && m.lobes.iter().any(|l| l.albedo.iter().any(|&a| a > 0.0))
}

/// The closures `m` needs in Cycles (diffuse, which carries the compensation terms too, then one per
/// facet frame), counted after the conversion to the reciprocal model.
pub fn closure_count(m: &Material) -> usize {
    let m = m.converted(Normalization::Reciprocal);
    usize::from(m.diffuse.iter().any(|&d| d > 0.0) || compensates(&m)) + facets(&m).len()
}

/// The compensation image of an energy-preserving material (`None` for any other), rows from the
/// bottom, texels as [`texel_view`] places them but in the local shading frame: per channel
/// `Σ_k ρ_k · term_albedo_k(ω_o)`, the directional albedo of the lobes' compensation terms at the
/// texel's view (`compensation::Table::term_albedo`). Added to the Diffuse closure's colour, it makes
/// the white furnace of the terms exact per view (within the image's bilinear resolution); the
/// closure spreads that energy over `cos θ_i` where the terms spread it over `(1 − Ê_k(ω_i)) cos θ_i`
/// (docs/exports.md, Blender (Cycles), Energy-preserving materials).
pub fn compensation_image(m: &Material) -> Option<Vec<[f64; 3]>> {
    if !compensates(m) {
        return None;
    }
    let tables = m.tables()?;
    let n = TABLE_SIZE;
    let texel = |k: usize| {
        let v = texel_view(k % n, k / n);
        let mut c = [0.0; 3];
        for (l, t) in m.lobes.iter().zip(&tables) {
            let a = t.term_albedo(v);
            for (c, r) in c.iter_mut().zip(l.albedo) {
                *c += r * a;
            }
        }
        c
    };
    Some((0..n * n).map(texel).collect())
}

/// Cycles' Smith Λ for its Beckmann closures: Walter et al. 2007's rational approximation below
/// their eq. 69, of `α² tan²θ` along the direction (`bsdf_lambda_from_sqr_alpha_tan_n` in
/// intern/cycles/kernel/closure/bsdf_microfacet.h).
fn cycles_lambda(sqr_alpha_tan: f64) -> f64 {
    if sqr_alpha_tan < 0.39 {
        return 0.0;
    }
    let a = 1.0 / sqr_alpha_tan.sqrt();
    ((0.396 * a - 1.259) * a + 1.0) / ((2.181 * a + 3.535) * a)
}

/// `(α_x V_x)² + (α_y V_y)²) / V_z²` with `V` in the tangent frame of the closure.
fn sqr_alpha_tan(shape: &Shape<f64>, v: DVec3) -> f64 {
    let x = v.x * shape.cos_phi + v.y * shape.sin_phi;
    let y = -v.x * shape.sin_phi + v.y * shape.cos_phi;
    ((shape.alpha_x * x).powi(2) + (shape.alpha_y * y).powi(2)) / (v.z * v.z)
}

/// The view `v` in the facet frame of texel `(i, j)` (column `i`, row `j` from the bottom): the
/// stereographic projection from `−ẑ`, `(u, v) = ½ + ½ (v_x, v_y) / (1 + v_z)`, which puts the
/// facet's horizon on the unit circle and gives grazing views twice the resolution of the normal.
/// Texels outside the circle take the view on it (just above the horizon).
pub fn texel_view(i: usize, j: usize) -> DVec3 {
    let px = 2.0 * (i as f64 + 0.5) / TABLE_SIZE as f64 - 1.0;
    let py = 2.0 * (j as f64 + 0.5) / TABLE_SIZE as f64 - 1.0;
    let r = px.hypot(py);
    let s = if r > 0.999 { 0.999 / r } else { 1.0 };
    let (px, py) = (px * s, py * s);
    let r2 = px * px + py * py;
    DVec3::new(2.0 * px / (1.0 + r2), 2.0 * py / (1.0 + r2), (1.0 - r2) / (1.0 + r2))
}

/// brdf-shop's albedo of one facet term at the view `v` (facet frame), and Cycles' albedo of the
/// Beckmann closure about the same frame, both per unit albedo, by the product midpoint rule on
/// the half-vector sampler's square. Cycles' closure returns `D G₂ / (4 cos θ_v)` (cosines about the
/// facet normal, `G₂ = 1 / (1 + Λ(v) + Λ(l))`, height-correlated) for light above both the facet
/// plane and the surface; per sample of `D cos θ_h` that weighs `G₂ (v·h) / (v_z h_z)`.
pub fn albedos(shape: &Shape<f64>, frame: DQuat, v: DVec3) -> (f64, f64) {
    let wo = frame * v;
    let lambda_v = cycles_lambda(sqr_alpha_tan(shape, v));
    let (mut ours, mut cycles) = (0.0, 0.0);
    for a in 0..GRID {
        let u1 = (a as f64 + 0.5) / GRID as f64;
        for b in 0..GRID {
            let u2 = (b as f64 + 0.5) / GRID as f64;
            let h = sampling::sample_half_vector(shape, u1, u2);
            let vh = h.dot(v);
            if vh <= 0.0 {
                continue;
            }
            let l = 2.0 * vh * h - v;
            let wi = frame * l;
            ours += sampling::facet_weight(wi, wo);
            if l.z > 0.0 && wi.z > 0.0 && v.z > 0.0 && wo.z > 0.0 {
                let g2 = 1.0 / (1.0 + lambda_v + cycles_lambda(sqr_alpha_tan(shape, l)));
                cycles += g2 * vh / (v.z * h.z);
            }
        }
    }
    let n = (GRID * GRID) as f64;
    (ours / n, cycles / n)
}

/// A facet's lookup image, rows from the bottom: brdf-shop's albedo over Cycles' at each texel's
/// view, capped at [`RATIO_MAX`]. Texels no visible view reaches (Cycles' albedo below 1e-4 or the
/// view below the surface) take the mean of their valid neighbours, repeatedly, so that bilinear
/// lookups next to them stay unbiased.
fn table(f: &Facet) -> Vec<f64> {
    let n = TABLE_SIZE;
    let raw: Vec<Option<f64>> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let v = texel_view(k % n, k / n);
            if (f.frame * v).z <= 0.0 {
                return None;
            }
            let (ours, cycles) = albedos(&f.shape, f.frame, v);
            (cycles > 1e-4).then(|| (ours / cycles).min(RATIO_MAX))
        })
        .collect();
    let mut t = raw;
    for _ in 0..2 * n {
        if t.iter().all(Option::is_some) {
            break;
        }
        let prev = t.clone();
        for k in 0..n * n {
            if prev[k].is_some() {
                continue;
            }
            let (i, j) = ((k % n) as isize, (k / n) as isize);
            let mut sum = (0.0, 0);
            for (di, dj) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                let (a, b) = (i + di, j + dj);
                if a >= 0 && b >= 0 && a < n as isize && b < n as isize {
                    if let Some(v) = prev[b as usize * n + a as usize] {
                        sum = (sum.0 + v, sum.1 + 1);
                    }
                }
            }
            if sum.1 > 0 {
                t[k] = Some(sum.0 / sum.1 as f64);
            }
        }
    }
    t.into_iter().map(|v| v.unwrap_or(1.0)).collect()
}

fn vec3(v: [f64; 3]) -> String {
    format!("({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

/// The exported Python text of `m`; its Blender material and node group are named `name`. A
/// material needing more than [`MAX_CLOSURES`] closures is refused.
pub fn blender(m: &Material, name: &str) -> Result<String> {
    let paper = m.normalization != Normalization::Reciprocal;
    let count = closure_count(m);
    if count > MAX_CLOSURES {
        return Err(Error::input(
            "--format blender",
            format!(
                "the material needs {count} Cycles closures (the diffuse term and one per facet frame, a split \
                 lobe has two), and Cycles keeps {MAX_CLOSURES} per shader: remove or merge lobes"
            ),
        ));
    }
    let r = m.converted(Normalization::Reciprocal);
    let facets = facets(&r);
    let tables: Vec<Vec<f64>> = facets.iter().map(table).collect();
    let mut data = String::new();
    let _ = writeln!(data, "NAME = {}", serde_json::to_string(name).expect("a string serialises"));
    let _ = writeln!(data, "PAPER_NOTE = {}", if paper { format!("{PAPER_NOTE:?}") } else { "None".into() });
    let _ = writeln!(data, "DIFFUSE = {}", vec3(r.diffuse));
    let _ = writeln!(data, "TABLE_SIZE = {TABLE_SIZE}");
    let _ = writeln!(data, "ENV_MAX_SIDE = {MAX_ENV_SIDE}");
    let _ = writeln!(data, "ENV_MAX_TEXELS = {MAX_ENV_TEXELS}");
    let _ = writeln!(data, "ENV_MAX_BYTES = {MAX_ENV_FILE_BYTES}");
    let _ = writeln!(data, "FACETS = [");
    for (f, t) in facets.iter().zip(&tables) {
        let q = f.frame;
        let _ = writeln!(
            data,
            "    Facet(colour={}, rotation=({:?}, {:?}, {:?}, {:?}), alpha_x={:?}, alpha_y={:?}, tangent_angle={:?},",
            vec3(f.colour),
            q.w,
            q.x,
            q.y,
            q.z,
            f.shape.alpha_x,
            f.shape.alpha_y,
            f.tangent_angle
        );
        let _ = write!(data, "          table=[");
        for (k, v) in t.iter().enumerate() {
            if k % 12 == 0 {
                let _ = write!(data, "\n            ");
            }
            let _ = write!(data, "{v:.5}, ");
        }
        let _ = writeln!(data, "\n          ]),");
    }
    let _ = writeln!(data, "]");
    match compensation_image(&r) {
        None => {
            let _ = writeln!(data, "COMPENSATION = None");
        }
        Some(image) => {
            let _ = write!(data, "COMPENSATION = [");
            for (k, c) in image.iter().enumerate() {
                if k % 6 == 0 {
                    let _ = write!(data, "\n    ");
                }
                let _ = write!(data, "({:.6}, {:.6}, {:.6}), ", c[0], c[1], c[2]);
            }
            let _ = writeln!(data, "\n]");
        }
    }
    Ok(TEMPLATE.replacen("# @MATERIAL_DATA@\n", &data, 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Lobe;

    /// Cycles' Λ is 0 where `α tan θ` is small (the approximation's own cut-off) and grows toward
    /// grazing: its masking term `1 / (1 + Λ)` lies in (0, 1].
    #[test]
    fn cycles_lambda_is_zero_near_the_normal_and_grows_toward_grazing() {
        assert_eq!(cycles_lambda(0.0), 0.0);
        assert_eq!(cycles_lambda(0.3), 0.0);
        let mut last = 0.0;
        for k in 1..50 {
            let l = cycles_lambda(0.39 + k as f64 * 0.5);
            assert!(l >= last && l.is_finite(), "{l}");
            last = l;
        }
    }

    /// At normal view on an untilted facet both models reflect most of the light of a rough lobe:
    /// Cycles' closure all but its masking loss, brdf-shop's lobe the mean of `cos θ_i` over it
    /// (its weight `cos θ_i / max(cos θ_i, cos θ_o)` with `cos θ_o = 1`), both at most 1.
    #[test]
    fn albedos_at_normal_view_are_close_to_one() {
        let l = Lobe::isotropic([1.0; 3], 0.2);
        let (ours, cycles) = albedos(&l.shape(), DQuat::IDENTITY, DVec3::Z);
        assert!(ours <= 1.0 + 1e-9 && ours > 0.9, "{ours}");
        assert!(cycles <= 1.0 + 1e-9 && cycles > 0.95, "{cycles}");
    }

    #[test]
    fn texel_views_are_unit_and_in_the_upper_half() {
        for j in 0..TABLE_SIZE {
            for i in 0..TABLE_SIZE {
                let v = texel_view(i, j);
                assert!((v.length() - 1.0).abs() < 1e-12 && v.z > 0.0, "{v}");
            }
        }
    }

    /// The compensation image holds the terms' directional albedo at each texel's view (so a
    /// uniform white light makes the Diffuse closure reflect what the terms reflect there), per
    /// channel; a material that does not preserve energy has none.
    #[test]
    fn compensation_image_is_the_terms_albedo_at_each_texel() {
        let lobe = Lobe { rotation: DQuat::from_rotation_x(0.3), ..Lobe::isotropic([0.5, 0.4, 0.3], 0.3) };
        let m = Material { preserve_energy: true, lobes: vec![lobe], ..Material::scratch() };
        let image = compensation_image(&m).unwrap();
        let table = crate::brdf::compensation::table(&m.lobes[0]);
        let n = TABLE_SIZE;
        for k in [0, 100, n * n / 2 + n / 2, n * n - 1] {
            let a = table.term_albedo(texel_view(k % n, k / n));
            assert_eq!(image[k], [0.5 * a, 0.4 * a, 0.3 * a], "texel {k}");
        }
        assert!(image.iter().all(|c| c[0] >= 0.0) && image.iter().any(|c| c[0] > 0.01));
        assert!(compensation_image(&Material { preserve_energy: false, ..m }).is_none());
    }

    #[test]
    fn more_than_64_closures_are_refused() {
        let lobe = Lobe { split: true, ..Lobe::isotropic([0.01; 3], 0.2) };
        let m = Material { lobes: vec![lobe; 32], ..Material::scratch() };
        assert_eq!(closure_count(&m), 65);
        assert!(blender(&m, "x").is_err());
    }
}
