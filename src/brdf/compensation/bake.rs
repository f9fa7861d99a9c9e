//! The certified table of `Ê ≥ E` (docs/model.md, Energy preservation, The certificate).
//!
//! A facet lobe's albedo per unit albedo is `E(V) = ∫ g_h(V) dP(h)`: `P` the Gaussian of the facet
//! slopes (standard normal `X, Y` with `h ∝ M (X, Y, 1)`, [`nodes::facets`]) and, for the view slope
//! `V` in the table's frame, `g_h(V) = clamp(f_h(V), 0, 1)`, `f_h(V) = 2 (1 + p V_x + q V_y) /
//! (1 + p² + q²) − 1` with `(p, q)` the slopes of `h` (`f_h + 1 = 2 h_z (h·ω_o) / ω_z`: `g` is
//! `cos θ_i / cos θ_o` clamped, 0 where the reflected direction is under the horizon). `f_h` is
//! affine in `V`, so for `χ ∈ {0, 1}` `g_h ≤ max(0, f_h) − χ (f_h − 1)`, whose integral over a box
//! `b` of slopes is convex in `V`; a convex function on a rectangle is at most the bilinear
//! interpolant of its corner values. So on a table cell with corner views `n_i`,
//! `∫_b g dP ≤ Σ λ_i w_{b,i}` with `w_{b,i}` a bound of that integral at `n_i`, the same `χ` (or
//! `g ≤ 1`) at every corner ([`bounds::weights`]). Summed over boxes that cover the slopes (the
//! Gaussian's mass past `±L` counted as `g = 1`), a cell's corner sums bound `E` on the cell by
//! their bilinear interpolant; each node takes the largest over the cells it is a corner of, so
//! the table's interpolant is at least `E` on every cell. Boxes are split while their certified
//! gap exceeds [`ETA`] ([`ETA_GRAZING`] past 81°; see [`cell_sums`]).

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use rayon::prelude::*;

use super::super::material::Lobe;
use super::bounds::{weights, Box2, Facets};
use super::nodes::{self, is_radial};
use super::Table;

/// The slopes' box `[−L, L]²` (standard deviations); the mass outside, `≤ 4 Φ(−L)`, counts as 1.
const L: f64 = 8.0;
/// The first boxes' edges along each axis.
const EDGES: [f64; 7] = [-L, -2.0, -1.0, 0.0, 1.0, 2.0, L];
/// A box is split while its certified gap (upper minus lower bound) exceeds this...
pub const ETA: f64 = 1.0e-4;
/// ... but the part of it due to facets whose `f` crosses 0 or 1 within the cell's views only
/// while splitting shrinks that part (summed over the four children) below this fraction of the
/// parent's.
const VIEW_RATIO: f64 = 0.6;
/// The same for cells wholly past 81° from the normal (`|V| > tan 81°`): their looseness only
/// lowers `Ē`, and `Ē`'s bound and the measured deficit fall together.
pub const ETA_GRAZING: f64 = 1.0e-3;
const TAN_81: f64 = 6.313751514675043;
/// The most rounds of box splitting a cell takes.
const MAX_ROUNDS: usize = 30;
/// The most box evaluations a cell takes (past it no box is split): caps a stiff lobe's bake.
const CELL_EVALS: usize = 4000;

/// The corner sums of one cell (corner views `corners[..n]`, `n` 2 or 4), each a bound at its
/// corner of the convex majorant of `E` on the cell, and the box evaluations taken.
///
/// Each round evaluates the boxes pending and splits those whose gap is over [`ETA`] in the part
/// that splitting can shrink, or in the rest while the previous split shrank it enough
/// ([`VIEW_RATIO`]); the others are kept (their weights summed). Past [`CELL_EVALS`] the boxes
/// with the largest gaps are split first and the rest kept.
fn cell_sums(f: &Facets, corners: &[[f64; 2]; 4], n: usize, eta: f64) -> ([f64; 4], usize) {
    let mut pending: Vec<(Box2, f64)> = Vec::with_capacity(64);
    for x in EDGES.windows(2) {
        for y in EDGES.windows(2) {
            pending.push((Box2 { x0: x[0], x1: x[1], y0: y[0], y1: y[1] }, f64::INFINITY));
        }
    }
    let mut sums = [0.0; 4];
    let mut kept = 0usize;
    let mut evals = 0usize;
    let mut first = true;
    let mut cand: Vec<(usize, f64)> = Vec::new();
    let mut results = Vec::new();
    for round in 0..MAX_ROUNDS {
        if pending.is_empty() {
            break;
        }
        results.clear();
        results.extend(pending.iter().map(|(b, _)| weights(f, b, corners, n)));
        evals += pending.len();
        // Which boxes want splitting: children come in groups of four (after the first round).
        cand.clear();
        let groups = if first { pending.len() } else { pending.len() / 4 };
        let group = if first { 1 } else { 4 };
        for g in 0..groups {
            let view_part: f64 =
                (0..group).map(|k| (results[g * group + k].gap - results[g * group + k].split_gap).max(0.0)).sum();
            let helps = first || view_part < VIEW_RATIO * pending[g * group].1;
            for k in 0..group {
                let r = &results[g * group + k];
                let view = (r.gap - r.split_gap).max(0.0);
                if r.split_gap > eta || (view > eta && helps) {
                    cand.push((g * group + k, r.gap));
                }
            }
        }
        first = false;
        let room = CELL_EVALS.saturating_sub(evals) / 4;
        if round + 1 == MAX_ROUNDS {
            cand.clear();
        } else if cand.len() > room {
            // The largest gaps first (ties by position: deterministic).
            cand.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            cand.truncate(room);
            cand.sort_by_key(|c| c.0);
        }
        let mut split = vec![false; pending.len()];
        for &(k, _) in &cand {
            split[k] = true;
        }
        let mut next = Vec::with_capacity(cand.len() * 4);
        for (k, (b, _)) in pending.iter().enumerate() {
            let r = &results[k];
            if split[k] {
                let view = (r.gap - r.split_gap).max(0.0);
                next.extend(b.split().map(|c| (c, view)));
            } else {
                for i in 0..n {
                    sums[i] += r.w[i];
                }
                kept += 1;
            }
        }
        pending = next;
    }
    // The mass past ±L (at most 4 Φ(−L)), and the rounding of the box masses (about 10⁻¹⁶ each,
    // times weights up to 2 |Ṽ|) and of the sum.
    let tail = 2.0 * libm::erfc(L * FRAC_1_SQRT_2);
    let mut out = [0.0; 4];
    for i in 0..n {
        let v = corners[i];
        let per_box = 1e-13 * (1.0 + v[0].abs() + v[1].abs());
        out[i] = sums[i] * (1.0 + 1e-12) + tail + per_box * kept as f64 + 1e-12;
    }
    (out, evals)
}

/// The node values of one frame's facets on the grid `xs × ys` (`ys` one node: radial),
/// row-major, and the box evaluations taken.
fn certify(f: &Facets, xs: &[f32], ys: &[f32]) -> (Vec<f64>, usize) {
    let nx = xs.len();
    let radial = ys.len() == 1;
    let cells: Vec<(usize, usize)> = if radial {
        (0..nx - 1).map(|i| (i, 0)).collect()
    } else {
        (0..ys.len() - 1).flat_map(|j| (0..nx - 1).map(move |i| (i, j))).collect()
    };
    let sums: Vec<([f64; 4], usize)> = cells
        .par_iter()
        .map(|&(i, j)| {
            let (x0, x1) = (f64::from(xs[i]), f64::from(xs[i + 1]));
            let near = |a: f64, b: f64| 0.0f64.clamp(a, b);
            if radial {
                let eta = if x0 > TAN_81 { ETA_GRAZING } else { ETA };
                cell_sums(f, &[[x0, 0.0], [x1, 0.0], [0.0; 2], [0.0; 2]], 2, eta)
            } else {
                let (y0, y1) = (f64::from(ys[j]), f64::from(ys[j + 1]));
                let eta = if near(x0, x1).hypot(near(y0, y1)) > TAN_81 { ETA_GRAZING } else { ETA };
                cell_sums(f, &[[x0, y0], [x1, y0], [x1, y1], [x0, y1]], 4, eta)
            }
        })
        .collect();
    let mut v = vec![f64::NEG_INFINITY; nx * ys.len()];
    let corners: &[(usize, usize)] = if radial { &[(0, 0), (1, 0)] } else { &[(0, 0), (1, 0), (1, 1), (0, 1)] };
    for (&(i, j), (s, _)) in cells.iter().zip(&sums) {
        for (k, &(di, dj)) in corners.iter().enumerate() {
            let n = (j + dj) * nx + i + di;
            v[n] = v[n].max(s[k]);
        }
    }
    (v, sums.iter().map(|s| s.1).sum())
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

/// Antiderivatives `G_k(a, b)` with `∂²G_k/∂a∂b = a^i b^j / (1 + a² + b²)²` for
/// `(i, j) = (0, 0), (1, 0), (0, 1), (1, 1)`.
fn moments_at(a: f64, b: f64) -> [f64; 4] {
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    [
        0.5 * (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()),
        -(b / sa).atan() / (2.0 * sa),
        -(a / sb).atan() / (2.0 * sb),
        -0.25 * (a * a + b * b).ln_1p(),
    ]
}

/// An upper bound of `(1/π) ∫ (1 − B) dx dy / (1 + x² + y²)²` over one cell where the bilinear `B`
/// (node values `v = [v00, v10, v01, v11]`) is at most 1: `B`'s integral in closed form, the sum
/// of each node's value times the integral of its basis function, with a bound of the rounding
/// (relative to the magnitudes the closed forms cancel).
fn cell_deficit_exact(x0: f64, x1: f64, y0: f64, y1: f64, v: [f64; 4]) -> f64 {
    let corners = [moments_at(x1, y1), moments_at(x0, y1), moments_at(x1, y0), moments_at(x0, y0)];
    let sign = [1.0, -1.0, -1.0, 1.0];
    let mut g = [0.0; 4];
    let mut e = [0.0; 4];
    for k in 0..4 {
        for c in 0..4 {
            g[k] += sign[c] * corners[c][k];
            e[k] += corners[c][k].abs();
        }
        e[k] *= 1e-14;
    }
    let (hx, hy) = (x1 - x0, y1 - y0);
    // ∫ basis · w for the node at (x_a, y_b): ± (x − x_a')(y − y_b') over hx hy, expanded.
    let basis = |xa: f64, yb: f64, s: f64| {
        // s (x − xa)(y − yb) = s (xy − yb x − xa y + xa yb)
        let val = s * (g[3] - yb * g[1] - xa * g[2] + xa * yb * g[0]);
        let err = e[3] + yb.abs() * e[1] + xa.abs() * e[2] + (xa * yb).abs() * e[0];
        let mag = g[3].abs() + (yb * g[1]).abs() + (xa * g[2]).abs() + (xa * yb * g[0]).abs();
        (val / (hx * hy), (err + 1e-15 * mag) / (hx * hy))
    };
    let parts = [basis(x1, y1, 1.0), basis(x0, y1, -1.0), basis(x1, y0, -1.0), basis(x0, y0, 1.0)];
    let mut int_b = 0.0;
    let mut err = e[0];
    for k in 0..4 {
        int_b += v[k] * parts[k].0;
        err += v[k].abs() * parts[k].1 + 1e-15 * (v[k] * parts[k].0).abs();
    }
    ((g[0] - int_b + 2.0 * err) / PI * (1.0 + 1e-12)).max(0.0)
}

/// `(1/π) ∫ 2π r dr / (1 + r²)²` over `[r0, r1]`.
fn ring_weight(r0: f64, r1: f64) -> f64 {
    1.0 / (1.0 + r0 * r0) - 1.0 / (1.0 + r1 * r1)
}

/// A lower bound of `Ē = (1/π) ∫ Ê cos θ dω` for the table's `Ê ≥ min(1, B)`, `B` its
/// interpolant (1 off the grid): one minus a bound of the deficit `1 − min(1, B)` on each cell,
/// the least of the closed form (where `B ≤ 1` on the cell) and of the largest deficit of each of
/// `SUB × SUB` pieces times its weight (a bilinear function is least at a corner).
fn mean_lower(t: &Table) -> f64 {
    const SUB: usize = 8;
    const SUB_RADIAL: usize = 64;
    let nx = t.xs.len();
    let v = |i: usize, j: usize| f64::from(t.values[j * nx + i]);
    let mut deficit = 0.0;
    if t.radial() {
        let frac = |k: usize| k as f64 / SUB_RADIAL as f64;
        for i in 0..nx - 1 {
            let (x0, x1) = (f64::from(t.xs[i]), f64::from(t.xs[i + 1]));
            for k in 0..SUB_RADIAL {
                let at = |a: f64| 1.0 - ((1.0 - a) * v(i, 0) + a * v(i + 1, 0)).min(1.0);
                let d = at(frac(k)).max(at(frac(k + 1)));
                deficit += d * ring_weight(x0 + frac(k) * (x1 - x0), x0 + frac(k + 1) * (x1 - x0));
            }
        }
    } else {
        let frac = |k: usize| k as f64 / SUB as f64;
        for j in 0..t.ys.len() - 1 {
            let (y0, y1) = (f64::from(t.ys[j]), f64::from(t.ys[j + 1]));
            for i in 0..nx - 1 {
                let (x0, x1) = (f64::from(t.xs[i]), f64::from(t.xs[i + 1]));
                let b = |a: f64, c: f64| {
                    (1.0 - c) * ((1.0 - a) * v(i, j) + a * v(i + 1, j))
                        + c * ((1.0 - a) * v(i, j + 1) + a * v(i + 1, j + 1))
                };
                let mut pieces = 0.0;
                for kx in 0..SUB {
                    for ky in 0..SUB {
                        let d = [(kx, ky), (kx + 1, ky), (kx, ky + 1), (kx + 1, ky + 1)]
                            .map(|(a, c)| 1.0 - b(frac(a), frac(c)).min(1.0))
                            .into_iter()
                            .fold(0.0, f64::max);
                        let (ax, bx) = (x0 + frac(kx) * (x1 - x0), x0 + frac(kx + 1) * (x1 - x0));
                        let (ay, by) = (y0 + frac(ky) * (y1 - y0), y0 + frac(ky + 1) * (y1 - y0));
                        pieces += d * rect_weight(ax, bx, ay, by);
                    }
                }
                let vs = [v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)];
                if vs.iter().all(|&x| x <= 1.0) {
                    pieces = pieces.min(cell_deficit_exact(x0, x1, y0, y1, vs));
                }
                deficit += pieces;
            }
        }
    }
    1.0 - deficit * (1.0 + 1e-9) - 1e-9
}

/// Lobe `l`'s table: its frame ([`nodes::frame`]) and nodes ([`nodes::axes`]), the node values of
/// each facet frame (a split lobe's two, averaged) rounded up to `f32`, with `Ē` and the term's
/// scale.
pub fn bake(l: &Lobe) -> Table {
    bake_counted(l).0
}

/// [`bake`], with the box evaluations it took.
pub fn bake_counted(l: &Lobe) -> (Table, usize) {
    let radial = is_radial(l);
    let rotation = nodes::frame(l);
    let (frames, n) = if radial { ([glam::DQuat::IDENTITY; 2], 1) } else { l.facet_frames() };
    let fs: Vec<Facets> = frames[..n].iter().map(|&q| nodes::facets(l, q, rotation)).collect();
    let (xs, ys) = if radial { (nodes::radial_nodes(), vec![0.0]) } else { nodes::axes(&fs, l.alpha_x.max(l.alpha_y)) };
    let mut sum = vec![0.0; xs.len() * ys.len()];
    let mut evals = 0;
    for f in &fs {
        let (v, e) = certify(f, &xs, &ys);
        evals += e;
        for (s, v) in sum.iter_mut().zip(v) {
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
    let mut t = Table { rotation, xs, ys, values, mean: 1.0, scale: 0.0, deficit: 0.0 };
    t.mean = mean_lower(&t).clamp(0.0, 1.0);
    let deficit = 1.0 - t.mean;
    // Rounded down, and a few ulps more for the two f32 products of `Table::term`.
    t.scale = if deficit > 1e-6 { down((1.0 / (PI * deficit)) as f32) * (1.0 - 1.0 / 1048576.0) } else { 0.0 };
    t.deficit = measured_deficit(&t);
    (t, evals)
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
