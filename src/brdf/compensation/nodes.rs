//! Where a table's frame and nodes go (docs/model.md, Energy preservation, The certificate). None
//! of this bears on the certificate's validity, only on how close `Ê` comes to `E`: the frame turns
//! `V_y` towards the tilt of the facet normal (or along the tangent of an untilted anisotropic
//! lobe), the nodes are denser where a cheap preview of `E` bends, and extra `V_y` nodes run along
//! the kink lines of the mean facet normal, where `E` bends sharply.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

use super::super::material::Lobe;
use super::bounds::Facets;

/// Nodes a side (plus one) of a 2-D table, and of a radial one.
pub const NODES: usize = 33;
/// The view slope the table reaches along each axis: `tan 89°`. Past it `Ê = 1`.
pub const V_MAX: f64 = 57.289961630759144;
/// Where the nodes of a 2-D table thin out: `C s / (1 − |s|)` for `s` in
/// `[−V_MAX/(C + V_MAX), V_MAX/(C + V_MAX)]`.
const C: f64 = 4.5;
/// The same for a radial table.
const C_RADIAL: f64 = 3.0;
/// Points a side of the preview of `E`.
const PREVIEW: usize = 65;
/// Quadrature points a side of the preview's `E` (midpoints over `[−8, 8]`, Gaussian weights).
const PREVIEW_QUAD: usize = 40;
/// The preview's curvature counts up to this view (`tan 81°`).
const PREVIEW_ROI: f64 = 6.313751514675043;
/// A floor on the node density, relative to its largest.
const FLOOR: f64 = 0.02;
/// Kink nodes about each kink line, in units of `α √(1 + k²)`.
const KINK_OFFSETS: [f64; 7] = [-3.0, -1.5, -0.5, 0.0, 0.5, 1.5, 3.0];

/// Whether a lobe's `E` depends on `|V|` alone: isotropic and untilted (a split lobe's two faces
/// are then the same).
pub fn is_radial(l: &Lobe) -> bool {
    l.alpha_x == l.alpha_y && l.rotation.xyz().length() == 0.0
}

/// The facets of frame `q` in the table's frame `rot = (cos γ, sin γ)` (see [`Facets`]): `M` is
/// `R_z(−γ) Q A` for the slope scales `A` (`(αx/√2) X, (αy/√2) Y` about the tangent angle).
pub fn facets(l: &Lobe, q: DQuat, rot: [f32; 2]) -> Facets {
    let (s, c) = l.tangent_angle.sin_cos();
    let (sx, sy) = (l.alpha_x * FRAC_1_SQRT_2, l.alpha_y * FRAC_1_SQRT_2);
    let a = DMat3::from_cols(DVec3::new(c * sx, s * sx, 0.0), DVec3::new(-s * sy, c * sy, 0.0), DVec3::Z);
    let (gc, gs) = (f64::from(rot[0]), f64::from(rot[1]));
    let r = gc.hypot(gs);
    let (gc, gs) = (gc / r, gs / r);
    let pre = DMat3::from_cols(DVec3::new(gc, -gs, 0.0), DVec3::new(gs, gc, 0.0), DVec3::Z);
    Facets { m: pre * DMat3::from_quat(q) * a, sx, sy }
}

/// The table's frame `(cos γ, sin γ)` in `f32`: `V_y` along the horizontal part of the (first) facet
/// normal `Q ẑ` where it tilts, else along the facets' `x` axis (`[1, 0]` for a radial table).
pub fn frame(l: &Lobe) -> [f32; 2] {
    if is_radial(l) {
        return [1.0, 0.0];
    }
    let m = DMat3::from_quat(l.rotation);
    let n = m * DVec3::Z;
    let gamma = if n.x.hypot(n.y) > 1e-9 {
        // The rotated normal's x, c n_x + s n_y, is 0 (and its y, c n_y − s n_x = −|n_h|).
        n.y.atan2(n.x) + 0.5 * PI
    } else {
        let t = m * DVec3::new(l.tangent_angle.cos(), l.tangent_angle.sin(), 0.0);
        t.y.atan2(t.x)
    };
    let (s, c) = gamma.sin_cos();
    [c as f32, s as f32]
}

/// The nodes of a radial table: `C s / (1 − s)` for `s` uniform from 0, exact in `f32`.
pub fn radial_nodes() -> Vec<f32> {
    let sm = V_MAX / (C_RADIAL + V_MAX);
    let n = NODES - 1;
    (0..=n)
        .map(|k| {
            let s = sm * k as f64 / n as f64;
            (C_RADIAL * s / (1.0 - s)) as f32
        })
        .collect()
}

/// `E` of the facets `fs` (their mean) at view slope `v` by a coarse midpoint rule in the standard
/// slopes: for the preview only.
struct Preview {
    /// Unit half vectors of each frame and their weights.
    points: Vec<(DVec3, f64)>,
    frames: usize,
}

impl Preview {
    fn new(fs: &[Facets]) -> Preview {
        let n = PREVIEW_QUAD;
        let h = 16.0 / n as f64;
        let xs: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let x = -8.0 + (k as f64 + 0.5) * h;
                (x, (-0.5 * x * x).exp() / (2.0 * PI).sqrt() * h)
            })
            .collect();
        let mut points = Vec::new();
        for f in fs {
            for &(x, wx) in &xs {
                for &(y, wy) in &xs {
                    let w = wx * wy;
                    if w > 1e-17 {
                        points.push(((f.m * DVec3::new(x, y, 1.0)).normalize(), w));
                    }
                }
            }
        }
        Preview { points, frames: fs.len() }
    }

    fn e(&self, v: [f64; 2]) -> f64 {
        let vt = DVec3::new(v[0], v[1], 1.0);
        let sum: f64 = self
            .points
            .iter()
            .map(|&(w, wt)| {
                let f = 2.0 * w.dot(vt).max(0.0) * w.z - 1.0;
                f.clamp(0.0, 1.0) * wt
            })
            .sum();
        sum / self.frames as f64
    }
}

/// The `V_y` of the kink lines `f_m = 0` and `f_m = 1` of each frame's mean facet normal `m` (where
/// `m_x = 0` in the table's frame), with [`KINK_OFFSETS`] about each (the facets' spread smooths a
/// kink over about `α |Ṽ|`).
fn kinks(fs: &[Facets], alpha: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for f in fs {
        let m = f.m.z_axis;
        if m.y.abs() < 1e-9 || m.x.abs() > 1e-6 * m.y.abs() || m.z <= 0.0 {
            continue;
        }
        for c in [0.0, 1.0] {
            let k = ((c + 1.0) / (2.0 * m.z) - m.z) / m.y;
            for d in KINK_OFFSETS {
                let y = k + d * alpha * (1.0 + k * k).sqrt();
                if y.abs() < V_MAX {
                    out.push(y);
                }
            }
        }
    }
    out
}

/// The nodes of a 2-D table for the facets `fs` (each frame of the lobe, in the table's frame):
/// along each axis, `N + 1` nodes that equidistribute the square root of the preview's largest
/// second difference across the other axis (up to 81°), then the kink nodes along `V_y`; exact in
/// `f32`, increasing, from `−V_MAX` to `V_MAX`.
pub fn axes(fs: &[Facets], alpha: f64) -> (Vec<f32>, Vec<f32>) {
    let sm = V_MAX / (C + V_MAX);
    let ss: Vec<f64> = (0..PREVIEW).map(|k| -sm + 2.0 * sm * k as f64 / (PREVIEW - 1) as f64).collect();
    let vs: Vec<f64> = ss.iter().map(|&s| C * s / (1.0 - s.abs())).collect();
    let pre = Preview::new(fs);
    let e: Vec<Vec<f64>> = vs.par_iter().map(|&x| vs.iter().map(|&y| pre.e([x, y])).collect()).collect();
    let roi = |i: usize, j: usize| vs[i].hypot(vs[j]) <= PREVIEW_ROI;
    let mut kx = vec![0.0f64; PREVIEW];
    let mut ky = vec![0.0f64; PREVIEW];
    for i in 1..PREVIEW - 1 {
        for j in 0..PREVIEW {
            if roi(i, j) {
                kx[i] = kx[i].max((e[i + 1][j] - 2.0 * e[i][j] + e[i - 1][j]).abs());
            }
            if roi(j, i) {
                ky[i] = ky[i].max((e[j][i + 1] - 2.0 * e[j][i] + e[j][i - 1]).abs());
            }
        }
    }
    let place = |k: &[f64]| -> Vec<f64> {
        let kmax = k.iter().fold(0.0f64, |a, &b| a.max(b));
        let dens: Vec<f64> = k.iter().map(|&v| (v + FLOOR * kmax + 1e-12).sqrt()).collect();
        let mut cum = vec![0.0; PREVIEW];
        for i in 1..PREVIEW {
            cum[i] = cum[i - 1] + 0.5 * (dens[i] + dens[i - 1]);
        }
        let total = cum[PREVIEW - 1];
        let n = NODES - 1;
        (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64 * total;
                let s = if k == 0 {
                    -sm
                } else if k == n {
                    sm
                } else {
                    let i = cum.partition_point(|&c| c <= t).clamp(1, PREVIEW - 1);
                    let a = (t - cum[i - 1]) / (cum[i] - cum[i - 1]);
                    ss[i - 1] + a * (ss[i] - ss[i - 1])
                };
                C * s / (1.0 - s.abs())
            })
            .collect()
    };
    let xs = place(&kx);
    let mut ys = place(&ky);
    ys.extend(kinks(fs, alpha));
    ys.sort_by(f64::total_cmp);
    let mut kept: Vec<f64> = Vec::with_capacity(ys.len());
    for y in ys {
        if kept.last().is_none_or(|&l| y - l > 1e-3) {
            kept.push(y);
        }
    }
    (to_f32(&xs), to_f32(&kept))
}

/// Rounded to `f32`, strictly increasing.
fn to_f32(v: &[f64]) -> Vec<f32> {
    let mut out: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    out.dedup();
    out
}
