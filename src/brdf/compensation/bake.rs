//! The certified table of `Ê ≥ E` (docs/model.md, Energy preservation, The certificate).
//!
//! A facet lobe's albedo per unit albedo is `E(V) = ∫ g_h(V) dP(h)`: `P` the Gaussian of the facet
//! slopes (standard normal `X, Y` with `h ∝ M (X, Y, 1)`, [`matrix`]) and, for the view slope `V`,
//! `g_h(V) = clamp(f_h(V), 0, 1)`, `f_h(V) = 2 (1 + p V_x + q V_y) / (1 + p² + q²) − 1` with `(p, q)`
//! the world slopes of `h` (`f_h + 1 = 2 h_z (h·ω_o) / ω_z`: `g` is `cos θ_i / cos θ_o` clamped, 0
//! where the reflected direction is under the horizon). `f_h` is affine in `V`, so for `χ ∈ {0, 1}`
//! `g_h ≤ max(0, f_h) − χ (f_h − 1)`, whose integral over a box `b` of slopes is convex in `V`; a
//! convex function on a rectangle is at most the bilinear interpolant of its corner values. So on
//! a table cell with corner views `n_i`, `∫_b g dP ≤ Σ λ_i w_{b,i}` with `w_{b,i}` a bound of that
//! integral at `n_i`: `P_b max(0, S_b(n_i))` (`χ = 0`), `P_b (max(0, S_b(n_i)) + 1 − I_b(n_i))`
//! (`χ = 1`) or `P_b` (`g ≤ 1`), with `S_b, I_b` bounds of `f_h(n_i)` over the box (exact where the
//! box is saturated at all four corners). Summed over boxes that cover the slopes (the Gaussian's
//! mass past `±L` counted as `g = 1`), a cell's corner sums bound `E` on the cell by their
//! bilinear interpolant; each node takes the largest over the cells it is a corner of, so the
//! table's interpolant is at least `E` on every cell. Boxes are split where their bounds are
//! loose, until a cell's slack is under [`CELL_SLACK`].

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

use super::super::material::Lobe;
use super::Table;

/// Nodes of the table along each view-slope axis (a radial table: along `|V|`).
pub const NODES: usize = 33;
/// The view slope the table reaches along each axis: `tan 85°`. Past it `Ê = 1`.
pub const V_MAX: f64 = 11.430052302761343;
/// Where the nodes thin out: node `k` is at `C s / (1 − |s|)` for `s` uniform in
/// `[−V_MAX/(C + V_MAX), V_MAX/(C + V_MAX)]`, dense near the normal view, sparse at grazing.
const C: f64 = 1.0;
/// The slopes' box `[−L, L]²` (standard deviations); the mass outside, `≤ 4 Φ(−L)`, counts as 1.
const L: f64 = 8.0;
/// The first boxes' edges along each axis.
const EDGES: [f64; 7] = [-L, -2.0, -1.0, 0.0, 1.0, 2.0, L];
/// The largest bound slack a cell keeps (the sum over its boxes of upper minus lower bound).
pub const CELL_SLACK: f64 = 2.0e-3;
/// The most rounds of box splitting a cell takes.
const MAX_ROUNDS: usize = 24;
/// The most boxes a cell keeps (its slack stops falling by splitting first at grazing cells).
const MAX_BOXES: usize = 6000;
/// Relative margin on every bound computed in `f64` (the rounding of a few dozen operations).
const REL: f64 = 1.0e-12;

/// The world half vector `M (X, Y, 1)` of facet frame `q`, unnormalised, for standard normal `X, Y`:
/// the facet slopes are `(αx/√2) X, (αy/√2) Y` about the tangent angle.
pub fn matrix(l: &Lobe, q: DQuat) -> DMat3 {
    let (s, c) = l.tangent_angle.sin_cos();
    let (sx, sy) = (l.alpha_x * FRAC_1_SQRT_2, l.alpha_y * FRAC_1_SQRT_2);
    let a = DMat3::from_cols(DVec3::new(c * sx, s * sx, 0.0), DVec3::new(-s * sy, c * sy, 0.0), DVec3::Z);
    DMat3::from_quat(q) * a
}

/// Whether a lobe's `E` depends on `|V|` alone: isotropic and untilted (a split lobe's two faces
/// are then the same).
pub fn is_radial(l: &Lobe) -> bool {
    l.alpha_x == l.alpha_y && l.rotation.xyz().length() == 0.0
}

/// The nodes along one axis, from `−V_MAX` (or 0 for a radial table) to `V_MAX`, exact in `f32`.
pub fn nodes(radial: bool) -> Vec<f32> {
    let sm = V_MAX / (C + V_MAX);
    let n = NODES - 1;
    let s = |k: usize| if radial { sm * k as f64 / n as f64 } else { -sm + 2.0 * sm * k as f64 / n as f64 };
    (0..=n).map(|k| (C * s(k) / (1.0 - s(k).abs())) as f32).collect()
}

/// `Φ(b) − Φ(a)` for `a ≤ b`, from the upper tail where `a > 0` (no cancellation), with its
/// rounding: `libm::erfc` is within an ulp or two.
fn mass(a: f64, b: f64) -> f64 {
    let tail = |x: f64| 0.5 * libm::erfc(x * FRAC_1_SQRT_2);
    if a > 0.0 {
        tail(a) - tail(b)
    } else if b < 0.0 {
        tail(-b) - tail(-a)
    } else {
        1.0 - tail(-a) - tail(b)
    }
}

/// One box of standard slopes, with its probability.
#[derive(Clone, Copy)]
struct Box2 {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    p: f64,
}

impl Box2 {
    fn new(x0: f64, x1: f64, y0: f64, y1: f64) -> Box2 {
        Box2 { x0, x1, y0, y1, p: mass(x0, x1) * mass(y0, y1) }
    }

    fn split(&self) -> [Box2; 4] {
        let (xm, ym) = (0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1));
        [
            Box2::new(self.x0, xm, self.y0, ym),
            Box2::new(xm, self.x1, self.y0, ym),
            Box2::new(self.x0, xm, ym, self.y1),
            Box2::new(xm, self.x1, ym, self.y1),
        ]
    }
}

/// A box's weights at a cell's four corner views and its slack (weights minus a certified lower
/// bound of `∫_b g dP`, at the worst corner).
fn weights(m: &DMat3, b: &Box2, corners: &[[f64; 2]; 4]) -> ([f64; 4], f64) {
    let ws = [(b.x0, b.y0), (b.x1, b.y0), (b.x1, b.y1), (b.x0, b.y1)].map(|(x, y)| *m * DVec3::new(x, y, 1.0));
    let tol = 1e-12 * ws.iter().map(|w| w.abs().element_sum()).fold(0.0, f64::max);
    if ws.iter().all(|w| w.z < -tol) {
        // Every half vector under the horizon: g = 0.
        return ([0.0; 4], 0.0);
    }
    if !ws.iter().all(|w| w.z > tol) {
        // The horizon crosses the box: g ≤ 1, the slack all of it.
        return ([b.p; 4], b.p);
    }
    let pq = ws.map(|w| [w.x / w.z, w.y / w.z]);
    let r2 = pq.map(|[p, q]| p * p + q * q);
    let rmax2 = r2.iter().fold(0.0f64, |a, &r| a.max(r)) * (1.0 + 1e-10) + 1e-12;
    let rmin2 = (min_distance2(&pq) * (1.0 - 1e-10) - 1e-12 * (1.0 + rmax2)).max(0.0);
    let (dmin, dmax) = (1.0 + rmin2, 1.0 + rmax2);
    let mut s = [0.0; 4];
    let mut i = [0.0; 4];
    for (k, v) in corners.iter().enumerate() {
        let num = pq.map(|[p, q]| 1.0 + p * v[0] + q * v[1]);
        let nmax = num.iter().fold(f64::NEG_INFINITY, |a, &n| a.max(n));
        let nmin = num.iter().fold(f64::INFINITY, |a, &n| a.min(n));
        let mag = 1.0 + pq.iter().map(|[p, q]| p.abs() + q.abs()).fold(0.0, f64::max) * (1.0 + v[0].abs() + v[1].abs());
        let margin = 8.0 * REL * mag;
        s[k] = 2.0 * if nmax >= 0.0 { nmax / dmin } else { nmax / dmax } - 1.0 + margin;
        i[k] = 2.0 * if nmin >= 0.0 { nmin / dmax } else { nmin / dmin } - 1.0 - margin;
    }
    let p = b.p;
    if i.iter().all(|&v| v >= 1.0) {
        return ([p; 4], 0.0);
    }
    if s.iter().all(|&v| v <= 0.0) {
        return ([0.0; 4], 0.0);
    }
    let only_positive = s.map(|v| p * v.max(0.0));
    let with_line = std::array::from_fn(|k| p * (s[k].max(0.0) + 1.0 - i[k]));
    let sum = |w: &[f64; 4]| w.iter().sum::<f64>();
    let mut w = [p; 4];
    for option in [only_positive, with_line] {
        if sum(&option) < sum(&w) {
            w = option;
        }
    }
    let slack = (0..4).map(|k| w[k] - p * i[k].clamp(0.0, 1.0)).fold(0.0, f64::max);
    (w, slack)
}

/// The least squared distance from the origin to the convex quadrilateral `pq` (0 inside it).
fn min_distance2(pq: &[[f64; 2]; 4]) -> f64 {
    let mut inside_pos = true;
    let mut inside_neg = true;
    let mut best = f64::INFINITY;
    for k in 0..4 {
        let [px, py] = pq[k];
        let [qx, qy] = pq[(k + 1) % 4];
        let (ex, ey) = (qx - px, qy - py);
        let cross = ex * (-py) - ey * (-px);
        inside_pos &= cross >= 0.0;
        inside_neg &= cross <= 0.0;
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 { (-(px * ex + py * ey) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let (dx, dy) = (px + t * ex, py + t * ey);
        best = best.min(dx * dx + dy * dy);
    }
    if inside_pos || inside_neg {
        0.0
    } else {
        best
    }
}

/// The four corner sums of one cell (corner views `corners`), each a bound at its corner of the
/// convex majorant of `E` on the cell.
fn cell_sums(m: &DMat3, corners: &[[f64; 2]; 4]) -> [f64; 4] {
    let mut boxes: Vec<(Box2, [f64; 4], f64)> = Vec::new();
    for x in EDGES.windows(2) {
        for y in EDGES.windows(2) {
            let b = Box2::new(x[0], x[1], y[0], y[1]);
            let (w, slack) = weights(m, &b, corners);
            boxes.push((b, w, slack));
        }
    }
    for _ in 0..MAX_ROUNDS {
        let total: f64 = boxes.iter().map(|b| b.2).sum();
        if total <= CELL_SLACK || boxes.len() >= MAX_BOXES {
            break;
        }
        let worst = boxes.iter().map(|b| b.2).fold(0.0, f64::max);
        let (split, kept): (Vec<_>, Vec<_>) = boxes.into_iter().partition(|b| b.2 >= 0.3 * worst && b.2 > 0.0);
        boxes = kept;
        for (b, _, _) in split {
            for c in b.split() {
                let (w, slack) = weights(m, &c, corners);
                boxes.push((c, w, slack));
            }
        }
    }
    let mut sums = [0.0; 4];
    for (_, w, _) in &boxes {
        for k in 0..4 {
            sums[k] += w[k];
        }
    }
    // The mass past ±L (at most 4 Φ(−L)), and the rounding of the box masses and of the sum.
    let tail = 2.0 * libm::erfc(L * FRAC_1_SQRT_2);
    sums.map(|s| s * (1.0 + 1e-12) + tail + 1e-13 * boxes.len() as f64 + 1e-12)
}

/// The node values of facet frame `q` on the grid `xs × ys` (`ys` one node: radial), row-major.
fn certify(l: &Lobe, q: DQuat, xs: &[f32], ys: &[f32]) -> Vec<f64> {
    let m = matrix(l, q);
    let nx = xs.len();
    let radial = ys.len() == 1;
    let cells: Vec<(usize, usize)> = if radial {
        (0..nx - 1).map(|i| (i, 0)).collect()
    } else {
        (0..ys.len() - 1).flat_map(|j| (0..nx - 1).map(move |i| (i, j))).collect()
    };
    let sums: Vec<[f64; 4]> = cells
        .par_iter()
        .map(|&(i, j)| {
            let (x0, x1) = (f64::from(xs[i]), f64::from(xs[i + 1]));
            let corners = if radial {
                [[x0, 0.0], [x1, 0.0], [x1, 0.0], [x0, 0.0]]
            } else {
                let (y0, y1) = (f64::from(ys[j]), f64::from(ys[j + 1]));
                [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
            };
            cell_sums(&m, &corners)
        })
        .collect();
    let mut v = vec![f64::NEG_INFINITY; nx * ys.len()];
    for (&(i, j), s) in cells.iter().zip(&sums) {
        let at = |di: usize, dj: usize| if radial { i + di } else { (j + dj) * nx + i + di };
        for (k, (di, dj)) in [(0, 0), (1, 0), (1, 1), (0, 1)].into_iter().enumerate() {
            let n = at(di, dj);
            v[n] = v[n].max(s[k]);
        }
    }
    v
}

/// `(1/π) ∫∫ dx dy / (1 + x² + y²)²` over a rectangle of view slopes: the cosine-weighted solid
/// angle over `π` (the whole plane is 1).
fn rect_weight(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let f = |a: f64, b: f64| {
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        0.5 * (a / sa * (b / sa).atan() + b / sb * (a / sb).atan())
    };
    (f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)) / PI
}

/// `(1/π) ∫ 2π r dr / (1 + r²)²` over `[r0, r1]`.
fn ring_weight(r0: f64, r1: f64) -> f64 {
    1.0 / (1.0 + r0 * r0) - 1.0 / (1.0 + r1 * r1)
}

/// A lower bound of `Ē = (1/π) ∫ Ê cos θ dω` for the table's `Ê ≥ min(1, B)`, `B` its
/// interpolant (1 off the grid): one minus the largest deficit `1 − min(1, B)` of each of
/// `SUB × SUB` pieces of a cell times its weight (a bilinear function is least at a corner).
fn mean_lower(t: &Table) -> f64 {
    const SUB: usize = 8;
    let nx = t.xs.len();
    let v = |i: usize, j: usize| f64::from(t.values[j * nx + i]);
    let mut deficit = 0.0;
    let frac = |k: usize| k as f64 / SUB as f64;
    if t.radial() {
        for i in 0..nx - 1 {
            let (x0, x1) = (f64::from(t.xs[i]), f64::from(t.xs[i + 1]));
            for k in 0..SUB {
                let at = |a: f64| 1.0 - ((1.0 - a) * v(i, 0) + a * v(i + 1, 0)).min(1.0);
                let d = at(frac(k)).max(at(frac(k + 1)));
                deficit += d * ring_weight(x0 + frac(k) * (x1 - x0), x0 + frac(k + 1) * (x1 - x0));
            }
        }
    } else {
        for j in 0..t.ys.len() - 1 {
            let (y0, y1) = (f64::from(t.ys[j]), f64::from(t.ys[j + 1]));
            for i in 0..nx - 1 {
                let (x0, x1) = (f64::from(t.xs[i]), f64::from(t.xs[i + 1]));
                let b = |a: f64, c: f64| {
                    (1.0 - c) * ((1.0 - a) * v(i, j) + a * v(i + 1, j))
                        + c * ((1.0 - a) * v(i, j + 1) + a * v(i + 1, j + 1))
                };
                for kx in 0..SUB {
                    for ky in 0..SUB {
                        let d = [(kx, ky), (kx + 1, ky), (kx, ky + 1), (kx + 1, ky + 1)]
                            .map(|(a, c)| 1.0 - b(frac(a), frac(c)).min(1.0))
                            .into_iter()
                            .fold(0.0, f64::max);
                        let (ax, bx) = (x0 + frac(kx) * (x1 - x0), x0 + frac(kx + 1) * (x1 - x0));
                        let (ay, by) = (y0 + frac(ky) * (y1 - y0), y0 + frac(ky + 1) * (y1 - y0));
                        deficit += d * rect_weight(ax, bx, ay, by);
                    }
                }
            }
        }
    }
    1.0 - deficit * (1.0 + 1e-9) - 1e-9
}

/// Lobe `l`'s table: the node values of each facet frame (a split lobe's two, averaged), rounded up
/// to `f32`, with `Ē` and the term's scale.
pub fn bake(l: &Lobe) -> Table {
    let radial = is_radial(l);
    let xs = nodes(radial);
    let ys = if radial { vec![0.0] } else { nodes(false) };
    let (frames, n) = if radial { ([DQuat::IDENTITY; 2], 1) } else { l.facet_frames() };
    let mut sum = vec![0.0; xs.len() * ys.len()];
    for &q in &frames[..n] {
        for (s, v) in sum.iter_mut().zip(certify(l, q, &xs, &ys)) {
            *s += v;
        }
    }
    let values = sum
        .iter()
        .map(|&s| {
            let v = (s / n as f64 * (1.0 + 1e-15)).min(1.0);
            let f = v as f32;
            if f64::from(f) < v {
                up(f)
            } else {
                f
            }
        })
        .collect();
    let mut t = Table { rotation: [1.0, 0.0], xs, ys, values, mean: 1.0, scale: 0.0, deficit: 0.0 };
    t.mean = mean_lower(&t).clamp(0.0, 1.0);
    let deficit = 1.0 - t.mean;
    // Rounded down, and a few ulps more for the two f32 products of `Table::term`.
    t.scale = if deficit > 1e-6 { down((1.0 / (PI * deficit)) as f32) * (1.0 - 1.0 / 1048576.0) } else { 0.0 };
    t.deficit = measured_deficit(&t);
    t
}

/// The next `f32` above `x`, for finite `x ≥ 0`.
fn up(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1)
}

/// The next `f32` below `x`, for finite `x > 0`.
fn down(x: f32) -> f32 {
    f32::from_bits(x.to_bits() - 1)
}

/// `(1/π) ∫ (1 − Ê) cos θ dω` by the midpoint rule on 256² cells of the cosine-weighted square.
fn measured_deficit(t: &Table) -> f64 {
    const N: usize = 256;
    let mut sum = 0.0;
    for i in 0..N {
        for j in 0..N {
            let w = crate::brdf::sampling::sample_cosine((i as f64 + 0.5) / N as f64, (j as f64 + 0.5) / N as f64);
            sum += 1.0 - f64::from(t.albedo(w.as_vec3().to_array()));
        }
    }
    sum / (N * N) as f64
}
