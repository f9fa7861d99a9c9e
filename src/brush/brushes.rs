//! The five brushes (docs/model.md, The paper model; paper §3.1, §3.3): create, modify, streak, intensify,
//! de-intensify. Each takes a material and a canvas point and returns the changed material or says why it cannot
//! act there. Every brush keeps the energy bound `ρ_d + Σρ_k ≤ 1` per channel.
//!
//! Owns the mapping from strokes to lobe parameters; the canvas geometry is `canvas.rs`.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use super::canvas::{Canvas, Site};
use crate::brdf::{Lobe, Material, Normalization, ALPHA_MAX, ALPHA_MIN};
use crate::error::{Error, Result};

/// How the modify brush turns a brush distance into a roughness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ModifyRule {
    /// The product's rule: after the stroke the lobe's canvas radiance at the brush is `γ` of its peak.
    #[default]
    Gamma,
    /// Paper eq. 3 read with Ward's Phong relation: `α = √(2 ln(ω_r · R ω_o) / ln γ)`.
    Eq3,
    /// Paper eq. 3 as printed: `α = √2 ln(ω_r · R ω_o) / ln γ`.
    Eq3Printed,
}

/// Everything a brush needs besides the material and the point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub canvas: Canvas,
    /// Fraction of the peak left at the brush position by modify and streak (paper: 0.8).
    pub gamma: f64,
    /// Create split lobes (paper §3.3.2); off gives a material that is not reciprocal.
    pub split_lobes: bool,
    pub modify_rule: ModifyRule,
    /// Roughness of a freshly created highlight: a very high-frequency circular highlight.
    pub create_alpha: f64,
    /// Albedo (per channel) of a freshly created lobe.
    pub create_albedo: f64,
    /// Canvas distance (normalised units) within which create snaps to the mirror point.
    pub snap_radius: f64,
    /// Albedo moved by one point of an intensify or de-intensify stroke.
    pub step: f64,
}

impl Settings {
    pub fn new(canvas: Canvas) -> Self {
        Settings {
            canvas,
            gamma: 0.8,
            split_lobes: true,
            modify_rule: ModifyRule::Gamma,
            create_alpha: 0.02,
            create_albedo: 0.2,
            snap_radius: 0.015,
            step: 0.05,
        }
    }
}

fn fmt_point(p: (f64, f64)) -> String {
    format!("({:.4}, {:.4})", p.0, p.1)
}

/// The canvas site under `p`, lit: refuses points off the sphere and points the light does not reach.
fn lit_site(canvas: &Canvas, p: (f64, f64)) -> Result<Site> {
    let site = canvas
        .site(p.0, p.1)
        .ok_or_else(|| Error::Brush(format!("point {} is off the canvas sphere", fmt_point(p))))?;
    if site.n_dot_l <= 0.0 {
        return Err(Error::Brush(format!(
            "the canvas light does not reach point {} (n·L = {:.4} ≤ 0)",
            fmt_point(p),
            site.n_dot_l
        )));
    }
    Ok(site)
}

/// The lobe with the highest canvas radiance under `p` (albedo included), if any lobe shows there.
pub fn lobe_under(m: &Material, canvas: &Canvas, p: (f64, f64)) -> Option<usize> {
    (0..m.lobes.len())
        .map(|k| {
            let a = m.lobes[k].albedo.iter().sum::<f64>() / 3.0;
            (k, canvas.lobe_ln_radiance(m, k, p.0, p.1) + a.ln())
        })
        .filter(|&(_, v)| v > f64::NEG_INFINITY)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// Frees `want[c]` of albedo per channel for lobe `keep`: first the unused budget, then the diffuse
/// term, then the other lobes in proportion to their albedo. Returns what could be freed.
fn make_room(m: &mut Material, keep: Option<usize>, want: [f64; 3]) -> [f64; 3] {
    let sums = m.energy_sums();
    let mut got = [0.0; 3];
    for c in 0..3 {
        let free = (1.0 - sums[c]).max(0.0);
        let mut need = (want[c] - free).max(0.0);
        got[c] = want[c].min(free);
        let d = m.diffuse[c].min(need);
        m.diffuse[c] -= d;
        need -= d;
        got[c] += d;
        let others: f64 = m.lobes.iter().enumerate().filter(|(k, _)| Some(*k) != keep).map(|(_, l)| l.albedo[c]).sum();
        if need > 0.0 && others > 0.0 {
            let take = need.min(others);
            let scale = 1.0 - take / others;
            for (k, l) in m.lobes.iter_mut().enumerate() {
                if Some(k) != keep {
                    l.albedo[c] *= scale;
                }
            }
            got[c] += take;
        }
    }
    got
}

/// Create: a new sharp lobe whose highlight peaks exactly at `p` (docs/model.md, The paper model; paper §3.3.1).
/// Returns the new lobe's index.
pub fn create(m: &Material, s: &Settings, p: (f64, f64)) -> Result<(Material, usize)> {
    if m.lobes.len() >= crate::brdf::material::MAX_LOBES {
        return Err(Error::Brush(format!(
            "the material has {} lobes already, the most a material may have",
            crate::brdf::material::MAX_LOBES
        )));
    }
    let site = lit_site(&s.canvas, p)?;
    // Near the mirror point the brush snaps to it, where R = I exactly.
    let snapped = s.canvas.mirror_point().is_some_and(|mp| (mp.0 - p.0).hypot(mp.1 - p.1) < s.snap_radius);
    let rotation = if snapped {
        DQuat::IDENTITY
    } else if m.normalization == Normalization::Reciprocal {
        // The facet that mirrors L into the viewer here: m = normalize(L + ω_o) in the local frame.
        DQuat::from_rotation_arc(DVec3::Z, (site.wi + site.wo).normalize()).normalize()
    } else {
        let wr = 2.0 * site.wi.z * DVec3::Z - site.wi; // reflect(L, n) in the local frame
        DQuat::from_rotation_arc(site.wo, wr.normalize()).normalize()
    };
    let mut out = m.clone();
    let got = make_room(&mut out, None, [s.create_albedo; 3]);
    let mut lobe = Lobe::isotropic(got, s.create_alpha);
    lobe.rotation = rotation;
    lobe.split = s.split_lobes;
    out.lobes.push(lobe);
    Ok((out, m.lobes.len()))
}

/// The smallest `α ∈ [ALPHA_MIN, ALPHA_MAX]` with `ratio(α) = γ`: a scan of `ln α` for the first
/// crossing, then bisection inside it. The ratio need not be monotonic (for rough lobes the peak moves
/// toward grazing angles and drops); where no `α` reaches `γ` the one that comes closest is returned.
fn solve_alpha(gamma: f64, ratio: impl Fn(f64) -> f64) -> f64 {
    const SCAN: usize = 24;
    let (lo, hi) = (ALPHA_MIN.ln(), ALPHA_MAX.ln());
    let at = |i: usize| lo + (hi - lo) * i as f64 / SCAN as f64;
    if ratio(ALPHA_MIN) >= gamma {
        return ALPHA_MIN;
    }
    let mut best = (f64::NEG_INFINITY, ALPHA_MIN);
    for i in 1..=SCAN {
        let r = ratio(at(i).exp());
        if r >= gamma {
            let (mut a, mut b) = (at(i - 1), at(i));
            for _ in 0..48 {
                let mid = 0.5 * (a + b);
                if ratio(mid.exp()) < gamma {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            return (0.5 * (a + b)).exp();
        }
        if r > best.0 {
            best = (r, at(i).exp());
        }
    }
    best.1
}

/// `radiance(p) / peak` of lobe `k` (per unit albedo, so the ratio is colour-free). For a split
/// reciprocal lobe, of the highlight the brush acts on: its first facet term alone (the V-groove's
/// other face lights a second highlight of its own brightness elsewhere on the canvas).
fn peak_ratio(m: &Material, canvas: &Canvas, k: usize, p: (f64, f64)) -> f64 {
    if m.normalization == Normalization::Reciprocal && m.lobes[k].split {
        let mut one = m.clone();
        one.lobes[k].split = false;
        return peak_ratio(&one, canvas, k, p);
    }
    let at = canvas.lobe_ln_radiance(m, k, p.0, p.1);
    match canvas.lobe_peak(m, k) {
        Some(peak) if at > f64::NEG_INFINITY => (at - peak.ln_value).exp().min(1.0),
        _ => 0.0,
    }
}

fn check_lobe(m: &Material, k: usize) -> Result<()> {
    if k >= m.lobes.len() {
        return Err(Error::Brush(format!("lobe {k} does not exist (the material has {} lobes)", m.lobes.len())));
    }
    Ok(())
}

/// Modify: sets `αx = αy = α` from the brush's distance to the highlight (docs/model.md, The paper model; paper
/// §3.3.3).
pub fn modify(m: &Material, s: &Settings, k: usize, p: (f64, f64)) -> Result<Material> {
    check_lobe(m, k)?;
    let site = lit_site(&s.canvas, p)?;
    let mut out = m.clone();
    let alpha = match s.modify_rule {
        ModifyRule::Gamma => solve_alpha(s.gamma, |a| {
            let mut t = out.clone();
            t.lobes[k].alpha_x = a;
            t.lobes[k].alpha_y = a;
            peak_ratio(&t, &s.canvas, k, p)
        }),
        rule => {
            let c = if m.normalization == Normalization::Reciprocal {
                // The angle between the mirror directions of the facet and of the brush's half vector
                // is twice the angle between the two: ω_r · R ω_o's counterpart is cos 2θ.
                let h = m.lobes[k].half_vector(m.normalization, site.wi, site.wo).unwrap_or(DVec3::Z);
                2.0 * h.z * h.z - 1.0
            } else {
                let wr = 2.0 * site.wi.z * DVec3::Z - site.wi;
                wr.dot(m.lobes[k].rotation * site.wo)
            };
            if !(c > 0.0) {
                return Err(Error::Brush(format!(
                    "eq. 3 is undefined at point {}: ω_r · R ω_o = {c:.4} ≤ 0",
                    fmt_point(p)
                )));
            }
            eq3_alpha(rule, c, s.gamma).clamp(ALPHA_MIN, ALPHA_MAX)
        }
    };
    out.lobes[k].alpha_x = alpha;
    out.lobes[k].alpha_y = alpha;
    Ok(out)
}

/// Paper eq. 3 for `c = ω_r · R ω_o`, in the chosen reading (not clamped).
pub fn eq3_alpha(rule: ModifyRule, c: f64, gamma: f64) -> f64 {
    let c = c.min(1.0);
    match rule {
        ModifyRule::Eq3Printed => std::f64::consts::SQRT_2 * c.ln() / gamma.ln(),
        _ => (2.0 * c.ln() / gamma.ln()).sqrt(),
    }
}

/// Streak: turns the tangent angle so `x̂` points from the highlight toward the brush, and sets `αx`
/// alone so the brush position sits at `γ` of the peak (docs/model.md, The paper model; paper §3.3.4).
pub fn streak(m: &Material, s: &Settings, k: usize, p: (f64, f64)) -> Result<Material> {
    check_lobe(m, k)?;
    let site = lit_site(&s.canvas, p)?;
    let lobe = &m.lobes[k];
    // The half vector the lobe sees at the brush; aligning x̂ with its tangential part puts the brush
    // on the streak's axis (h·ŷ = 0 there), whatever αx becomes.
    let h = lobe.half_vector(m.normalization, site.wi, site.wo).unwrap_or(DVec3::Z);
    if h.x.hypot(h.y) < 1e-12 {
        return Err(Error::Brush(format!(
            "point {} is the highlight's centre: drag away from it to streak",
            fmt_point(p)
        )));
    }
    let mut out = m.clone();
    out.lobes[k].tangent_angle = h.y.atan2(h.x);
    let alpha_x = solve_alpha(s.gamma, |a| {
        let mut t = out.clone();
        t.lobes[k].alpha_x = a;
        peak_ratio(&t, &s.canvas, k, p)
    });
    out.lobes[k].alpha_x = alpha_x;
    Ok(out)
}

fn hue(albedo: [f64; 3]) -> [f64; 3] {
    let m = albedo.iter().copied().fold(0.0, f64::max);
    if m > 0.0 {
        albedo.map(|a| a / m)
    } else {
        [1.0; 3]
    }
}

/// Intensify: moves `s.step` of albedo (keeping the lobe's hue) into lobe `k`, from the unused budget,
/// the diffuse term, then the other lobes in proportion.
pub fn intensify(m: &Material, s: &Settings, k: usize) -> Result<Material> {
    check_lobe(m, k)?;
    let mut out = m.clone();
    let want = hue(m.lobes[k].albedo).map(|h| h * s.step);
    let got = make_room(&mut out, Some(k), want);
    for c in 0..3 {
        out.lobes[k].albedo[c] += got[c];
    }
    Ok(out)
}

/// De-intensify: moves up to `s.step` of albedo (keeping the hue) from lobe `k` to the diffuse term.
pub fn deintensify(m: &Material, s: &Settings, k: usize) -> Result<Material> {
    check_lobe(m, k)?;
    let mut out = m.clone();
    let h = hue(m.lobes[k].albedo);
    for c in 0..3 {
        let d = (h[c] * s.step).min(out.lobes[k].albedo[c]);
        out.lobes[k].albedo[c] -= d;
        out.diffuse[c] += d;
    }
    Ok(out)
}
