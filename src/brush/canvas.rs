//! The spherical canvas (docs/model.md, Frames and conventions): a unit sphere seen orthographically down `−z`, lit by
//! one point light at infinity. Maps normalised canvas coordinates to surface points and local shading frames,
//! and computes the canvas radiance of a material, of one lobe, and whole canvas images on the CPU.
//!
//! Owns canvas geometry only; what a stroke does to a material lives in `brushes.rs`.

use glam::DVec3;
use rayon::prelude::*;

use crate::brdf::Material;

/// The canvas viewer's direction: every canvas pixel is seen from `+z`.
pub const VIEW: DVec3 = DVec3::Z;

/// The local shading frame (docs/model.md, Frames and conventions): `z = n`, `x = t = normalize(Y × n)` (or `(1,0,0)`
/// where
/// `|Y × n| < 1e-6`, made orthogonal to `n`), `y = n × t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub t: DVec3,
    pub b: DVec3,
    pub n: DVec3,
}

impl Frame {
    pub fn from_normal(n: DVec3) -> Frame {
        let c = DVec3::Y.cross(n);
        let t = if c.length() < 1e-6 { (DVec3::X - DVec3::X.dot(n) * n).normalize() } else { c.normalize() };
        Frame { t, b: n.cross(t), n }
    }

    /// World (canvas) direction → local frame.
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// Local frame direction → world (canvas).
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

/// The sphere's normal under canvas point `(cu, cv)` (`cv` grows downwards), if the point is on it.
pub fn normal_at(cu: f64, cv: f64) -> Option<DVec3> {
    let (x, y) = (2.0 * cu - 1.0, 1.0 - 2.0 * cv);
    let r2 = x * x + y * y;
    (r2 < 1.0 && cu.is_finite() && cv.is_finite()).then(|| DVec3::new(x, y, (1.0 - r2).sqrt()))
}

/// The canvas coordinates of a visible normal.
pub fn coords_of(n: DVec3) -> (f64, f64) {
    ((n.x + 1.0) / 2.0, (1.0 - n.y) / 2.0)
}

/// The canvas light: direction `L` (unit, canvas space) and radiance scale `I`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Canvas {
    pub light: DVec3,
    pub intensity: f64,
}

/// A canvas point with what the BRDF needs there: the frame, and `L` and `ω_o` in it.
#[derive(Clone, Copy, Debug)]
pub struct Site {
    pub frame: Frame,
    pub wi: DVec3,
    pub wo: DVec3,
    pub n_dot_l: f64,
}

impl Canvas {
    /// A canvas lit from `light` (normalised here); `None` for a zero or non-finite direction.
    pub fn new(light: DVec3, intensity: f64) -> Option<Canvas> {
        crate::brdf::material::unit(light).map(|light| Canvas { light, intensity })
    }

    pub fn site(&self, cu: f64, cv: f64) -> Option<Site> {
        let n = normal_at(cu, cv)?;
        let frame = Frame::from_normal(n);
        Some(Site { frame, wi: frame.to_local(self.light), wo: frame.to_local(VIEW), n_dot_l: n.dot(self.light) })
    }

    /// The mirror point, where `n ∝ L + ω_o` and an unrotated lobe peaks; `None` when it is not on
    /// the visible half of the sphere.
    pub fn mirror_point(&self) -> Option<(f64, f64)> {
        let h = crate::brdf::material::unit(self.light + VIEW)?;
        (h.z > 0.0).then(|| coords_of(h))
    }

    /// Canvas radiance `f(L, ω_o) max(n·L, 0) I` per channel; 0 off the sphere.
    pub fn radiance(&self, m: &Material, cu: f64, cv: f64) -> [f64; 3] {
        match self.site(cu, cv) {
            Some(s) if s.n_dot_l > 0.0 => m.eval(s.wi, s.wo).map(|f| f * s.n_dot_l * self.intensity),
            _ => [0.0; 3],
        }
    }

    /// `ln` of lobe `k`'s canvas radiance per unit albedo and unit intensity; `−∞` where it is 0.
    pub fn lobe_ln_radiance(&self, m: &Material, k: usize, cu: f64, cv: f64) -> f64 {
        match self.site(cu, cv) {
            Some(s) if s.n_dot_l > 0.0 => m.lobe_ln(k, s.wi, s.wo) + s.n_dot_l.ln(),
            _ => f64::NEG_INFINITY,
        }
    }

    /// The radiance image at `size × size`, row-major from the top, sampled at pixel centres.
    pub fn image(&self, m: &Material, size: usize) -> Vec<[f64; 3]> {
        (0..size * size)
            .into_par_iter()
            .map(|p| {
                let (i, j) = (p % size, p / size);
                self.radiance(m, (i as f64 + 0.5) / size as f64, (j as f64 + 0.5) / size as f64)
            })
            .collect()
    }

    /// Where lobe `k`'s canvas radiance peaks, and `ln` of the peak (per unit albedo). A grid search
    /// on the log radiance (smooth even where the radiance underflows) refined by a pattern search
    /// from the best few cells, so split lobes' second highlight is not missed.
    pub fn lobe_peak(&self, m: &Material, k: usize) -> Option<Peak> {
        const GRID: usize = 96;
        let mut cells: Vec<(f64, f64, f64)> = Vec::with_capacity(GRID * GRID);
        for j in 0..GRID {
            for i in 0..GRID {
                let (cu, cv) = ((i as f64 + 0.5) / GRID as f64, (j as f64 + 0.5) / GRID as f64);
                let v = self.lobe_ln_radiance(m, k, cu, cv);
                if v > f64::NEG_INFINITY {
                    cells.push((v, cu, cv));
                }
            }
        }
        cells.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut best: Option<Peak> = None;
        let mut starts: Vec<(f64, f64)> = Vec::new();
        for &(_, cu, cv) in &cells {
            // Distinct starting cells only: at least four cells apart.
            if starts.iter().any(|&(u, v)| (u - cu).abs() + (v - cv).abs() < 4.0 / GRID as f64) {
                continue;
            }
            starts.push((cu, cv));
            let p = self.refine(m, k, cu, cv);
            if best.is_none_or(|b| p.ln_value > b.ln_value) {
                best = Some(p);
            }
            if starts.len() == 3 {
                break;
            }
        }
        best
    }

    /// Newton's method on the log radiance (central-difference gradient and Hessian), with a
    /// backtracking line search and a gradient step where the Hessian is not negative definite. Near
    /// a peak the log radiance is close to a quadratic, so this converges in a few steps even on the
    /// thin, curved ridge of a streak where a compass search crawls.
    fn refine(&self, m: &Material, k: usize, cu: f64, cv: f64) -> Peak {
        let f = |u: f64, v: f64| self.lobe_ln_radiance(m, k, u, v);
        let (mut u, mut v) = (cu, cv);
        let mut f0 = f(u, v);
        const E: f64 = 1e-6;
        for _ in 0..200 {
            let (fpu, fmu, fpv, fmv) = (f(u + E, v), f(u - E, v), f(u, v + E), f(u, v - E));
            let (fpp, fpm, fmp, fmm) = (f(u + E, v + E), f(u + E, v - E), f(u - E, v + E), f(u - E, v - E));
            if ![fpu, fmu, fpv, fmv, fpp, fpm, fmp, fmm].iter().all(|x| x.is_finite()) {
                break; // at the rim or where the lobe vanishes: keep the best point found
            }
            let g = [(fpu - fmu) / (2.0 * E), (fpv - fmv) / (2.0 * E)];
            let huu = (fpu - 2.0 * f0 + fmu) / (E * E);
            let hvv = (fpv - 2.0 * f0 + fmv) / (E * E);
            let huv = (fpp - fpm - fmp + fmm) / (4.0 * E * E);
            let det = huu * hvv - huv * huv;
            let mut step = if huu < 0.0 && det > 0.0 {
                [-(hvv * g[0] - huv * g[1]) / det, -(-huv * g[0] + huu * g[1]) / det]
            } else {
                let gn = g[0].hypot(g[1]).max(1e-300);
                [0.01 * g[0] / gn, 0.01 * g[1] / gn]
            };
            let mut improved = false;
            for _ in 0..60 {
                let val = f(u + step[0], v + step[1]);
                if val > f0 {
                    (u, v, f0, improved) = (u + step[0], v + step[1], val, true);
                    break;
                }
                step = [step[0] * 0.5, step[1] * 0.5];
            }
            if !improved || step[0].hypot(step[1]) < 1e-13 {
                break;
            }
        }
        Peak { cu: u, cv: v, ln_value: f0 }
    }
}

/// A lobe's highlight peak on the canvas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub cu: f64,
    pub cv: f64,
    /// `ln` of the peak canvas radiance per unit albedo.
    pub ln_value: f64,
}
