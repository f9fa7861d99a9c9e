//! Energy compensation of the reciprocal lobes (docs/model.md, Energy preservation): each lobe of
//! an energy-preserving material adds `f_ms(ω_i, ω_o) = (1 − Ê(ω_i)) (1 − Ê(ω_o)) / (π (1 − Ē))`,
//! with `Ê ≥ E` a certified upper bound of the lobe's directional albedo `E` (per unit albedo) and
//! `Ē` a lower bound of `Ê`'s cosine-weighted mean. The term is symmetric in its two directions,
//! and its albedo at `ω_o` is at most `1 − Ê(ω_o) ≤ 1 − E(ω_o)`: a lobe with it reflects at most
//! its albedo, and, where `Ê` is close to `E`, all of it.
//!
//! `Ê` is a [`Table`] over the view slope `V = (ω_x/ω_z, ω_y/ω_z)` of the local frame, made by
//! [`bake`] (`bake.rs`, the certificate) and read by hand in `f32` ([`Table::albedo`]), the same
//! arithmetic as the shaders and the exports. Tables are cached by lobe shape ([`table`]): baking
//! one takes milliseconds to a few tenths of a second.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use glam::DVec3;

use super::material::Lobe;

mod bake;
mod bounds;
mod nodes;
#[cfg(test)]
mod tests;

pub use bake::bake;

/// What the f32 lookup may lose against the interpolant it computes: the view slope in `f32`
/// (a few ulps of `|V| ≤ tan 89° < 58`, and the `f32` frame's `c² + s²` off 1 by an ulp or two)
/// moves `E` by at most `|ΔV|` (`|∇_V E| ≤ 1`: `|∇_V f_h| = 2 |(p, q)| / (1 + p² + q²) ≤ 1`), the
/// bilinear weights and sums in `f32` a few ulps of 1: added to every lookup, it keeps `Ê ≥ E`
/// through the rounding (docs/model.md, Energy preservation, The certificate).
pub const LOOKUP_MARGIN: f32 = 1.0 / 16384.0;

/// `Ê` of one lobe: node values over the view slope, bilinear between them, and 1 off the grid
/// (grazing views, where the term is then 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// `(cos γ, sin γ)` of the table's frame about the normal: the lookup's view slope is
    /// `((c ω_x + s ω_y) / ω_z, (c ω_y − s ω_x) / ω_z)` in `f32` ([`Table::slope`]), so that the
    /// grid's axes can follow a lobe's tilt. `[1, 0]` for a radial table.
    pub rotation: [f32; 2],
    /// The grid's nodes along `V_x` and `V_y`, increasing, exact in `f32`. A lobe whose `E`
    /// depends on `|V|` alone (isotropic, untilted) has one node along `V_y` and `xs` runs over
    /// `|V|` ([`Table::radial`]).
    pub xs: Vec<f32>,
    pub ys: Vec<f32>,
    /// `Ê` at node `(i, j)`: `values[j * xs.len() + i]`, each an upper bound (rounded up).
    pub values: Vec<f32>,
    /// `Ē`: a lower bound of the cosine-weighted mean `(1/π) ∫ Ê cos θ dω`.
    pub mean: f64,
    /// `1 / (π (1 − Ē))` in `f32` (rounded down), or 0 where `Ē` is 1 to within rounding.
    pub scale: f32,
    /// `(1/π) ∫ (1 − Ê) cos θ dω` as measured by a 256² midpoint rule over the cosine-weighted
    /// hemisphere (at most `1 − Ē`): what [`Table::term_albedo`] integrates the term with.
    pub deficit: f64,
}

impl Table {
    /// Whether the table is over `|V|` alone.
    pub fn radial(&self) -> bool {
        self.ys.len() == 1
    }

    /// The lookup coordinates of a unit `ω` of the local frame with `ω_z > 0`, in `f32` in this
    /// order of operations (the shaders and the exports compute the same): `(|V|, 0)` for a radial
    /// table, else the view slope in the table's frame.
    pub fn slope(&self, w: [f32; 3]) -> (f32, f32) {
        if self.radial() {
            return ((w[0] * w[0] + w[1] * w[1]).sqrt() / w[2], 0.0);
        }
        let [c, s] = self.rotation;
        ((c * w[0] + s * w[1]) / w[2], (c * w[1] - s * w[0]) / w[2])
    }

    /// `Ê(ω)` for a unit `ω` of the local frame, in `f32` as every evaluator computes it.
    pub fn albedo(&self, w: [f32; 3]) -> f32 {
        if !(w[2] > 0.0) {
            return 1.0;
        }
        let (x, y) = self.slope(w);
        let nx = self.xs.len();
        let Some((i, a)) = cell(&self.xs, x) else { return 1.0 };
        if self.radial() {
            let v = (1.0 - a) * self.values[i] + a * self.values[i + 1];
            return (v + LOOKUP_MARGIN).min(1.0);
        }
        let Some((j, b)) = cell(&self.ys, y) else { return 1.0 };
        let v = |i: usize, j: usize| self.values[j * nx + i];
        let lo = (1.0 - b) * v(i, j) + b * v(i, j + 1);
        let hi = (1.0 - b) * v(i + 1, j) + b * v(i + 1, j + 1);
        ((1.0 - a) * lo + a * hi + LOOKUP_MARGIN).min(1.0)
    }

    /// The term's directional albedo at `ω_o`, `(1 − Ê(ω_o)) · c · π · deficit`, the measured
    /// deficit taken at most `1 − Ē` (which the exact one is): at most `1 − Ê(ω_o)`.
    pub fn term_albedo(&self, wo: DVec3) -> f64 {
        (1.0 - f64::from(self.albedo(wo.as_vec3().to_array())))
            * f64::from(self.scale)
            * std::f64::consts::PI
            * self.deficit.min(1.0 - self.mean)
    }

    /// `f_ms(ω_i, ω_o)` per unit albedo, `(u(ω_i) · u(ω_o)) · c` with `u = 1 − Ê` and `c` the
    /// [`Table::scale`]: the same product in either order of the directions (bitwise reciprocal).
    pub fn term(&self, wi: DVec3, wo: DVec3) -> f64 {
        let u = |w: DVec3| 1.0 - self.albedo(w.as_vec3().to_array());
        f64::from((u(wi) * u(wo)) * self.scale)
    }
}

/// Words of a lobe's header in [`words`].
pub const HEADER_WORDS: usize = 8;

/// The tables of a material's lobes as the shaders and the GLSL exports read them
/// (`glsl/include/brdf.glsl`, `brdf_table_albedo`; docs/formats.md, Compensation tables): for lobe
/// `k` a header of [`HEADER_WORDS`] words at `8k` (the offset of its table, `nx`, `ny`, the frame's
/// `cos γ` and `sin γ` and the term's scale as `f32` bits, two zeros), then each table's `xs`, `ys`
/// and `values` as `f32` bits. A lobe without a table (`None`: not baked yet) has `nx = 0`: the
/// shaders read `Ê = 1` and the term 0. At least one word, so the buffer is never empty.
pub fn words(tables: &[Option<&Table>]) -> Vec<u32> {
    let mut out = vec![0u32; (HEADER_WORDS * tables.len()).max(1)];
    for (k, t) in tables.iter().enumerate() {
        let Some(t) = t else { continue };
        let h = HEADER_WORDS * k;
        out[h] = out.len() as u32;
        out[h + 1] = t.xs.len() as u32;
        out[h + 2] = t.ys.len() as u32;
        out[h + 3] = t.rotation[0].to_bits();
        out[h + 4] = t.rotation[1].to_bits();
        out[h + 5] = t.scale.to_bits();
        out.extend(t.xs.iter().chain(&t.ys).chain(&t.values).map(|v| v.to_bits()));
    }
    out
}

/// The cell `i` of the increasing nodes `nodes` that holds `x` and the weight of its far node
/// (`nodes[i + 1]`), in `f32`; `None` off the nodes (or for NaN).
fn cell(nodes: &[f32], x: f32) -> Option<(usize, f32)> {
    let last = nodes.len().checked_sub(1)?;
    if !(x >= nodes[0] && x <= nodes[last]) || last == 0 {
        return None;
    }
    let i = nodes.partition_point(|&n| n <= x).clamp(1, last) - 1;
    let t = ((x - nodes[i]) / (nodes[i + 1] - nodes[i])).clamp(0.0, 1.0);
    Some((i, t))
}

/// What a lobe's table depends on: its shape and facet frame, bit for bit.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Key([u64; 8]);

impl Key {
    fn of(l: &Lobe) -> Key {
        let q = l.rotation;
        Key([
            l.alpha_x.to_bits(),
            l.alpha_y.to_bits(),
            l.tangent_angle.to_bits(),
            q.x.to_bits(),
            q.y.to_bits(),
            q.z.to_bits(),
            q.w.to_bits(),
            u64::from(l.split),
        ])
    }
}

/// The most tables kept; past it the cache starts again (a session paints a few hundred lobes).
const CACHE_TABLES: usize = 4096;

type Slot = Arc<OnceLock<Arc<Table>>>;

fn cache() -> &'static Mutex<HashMap<Key, Slot>> {
    static CACHE: OnceLock<Mutex<HashMap<Key, Slot>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

/// Lobe `l`'s table, baked once per shape: threads asking for the same shape wait for one bake.
pub fn table(l: &Lobe) -> Arc<Table> {
    slot(l).get_or_init(|| Arc::new(bake(l))).clone()
}

/// The cache's slot of lobe `l`'s shape.
fn slot(l: &Lobe) -> Slot {
    let mut map = cache().lock().unwrap_or_else(|e| e.into_inner());
    if map.len() >= CACHE_TABLES {
        map.clear();
    }
    map.entry(Key::of(l)).or_default().clone()
}

/// Whether lobe `l`'s table is baked (without baking it).
pub fn baked(l: &Lobe) -> bool {
    slot(l).get().is_some()
}

/// Lobe `l`'s table if it is baked. If not, a thread of its own bakes it and then calls `done` — one
/// such thread at a time: while it runs, other lobes wait for the next call (a modify-brush drag asks
/// for a new shape every frame; only the shape asked for when a bake ends is baked next).
pub fn table_or_bake(l: &Lobe, done: impl FnOnce() + Send + 'static) -> Option<Arc<Table>> {
    static BAKING: Mutex<bool> = Mutex::new(false);
    let slot = slot(l);
    if let Some(t) = slot.get() {
        return Some(t.clone());
    }
    let mut baking = BAKING.lock().unwrap_or_else(|e| e.into_inner());
    if !*baking {
        *baking = true;
        let lobe = l.clone();
        std::thread::spawn(move || {
            slot.get_or_init(|| Arc::new(bake(&lobe)));
            *BAKING.lock().unwrap_or_else(|e| e.into_inner()) = false;
            done();
        });
    }
    None
}

/// The views of the white furnace `check` reports: the polar angles of `energy::THETA_SET_DEG` up
/// to 80°, 12 azimuths each.
fn furnace_views() -> Vec<DVec3> {
    use super::energy::{direction, THETA_SET_DEG};
    THETA_SET_DEG
        .iter()
        .filter(|&&t| t <= 80.0)
        .flat_map(|&t| (0..12).map(move |k| direction(t.to_radians(), (30.0 * k as f64).to_radians())))
        .collect()
}

/// The white furnace of an energy-preserving material at views up to 80° (docs/model.md, Energy
/// preservation): each lobe's directional albedo per unit albedo, and the material's over
/// `ρ_d + Σρ_k` (the channels' mean), as the least and largest over the views, by the quadrature of
/// `check` (`energy::FACET_GRID`² cells per facet term). `None` for any other material.
pub fn furnace(m: &super::Material) -> Option<(Vec<[f64; 2]>, [f64; 2])> {
    use rayon::prelude::*;
    if !m.compensated() {
        return None;
    }
    let views = furnace_views();
    let per_view: Vec<Vec<f64>> =
        views.par_iter().map(|&w| super::energy::facet_lobe_terms(m, w, super::energy::FACET_GRID)).collect();
    let range = |it: &mut dyn Iterator<Item = f64>| {
        it.fold([f64::INFINITY, f64::NEG_INFINITY], |r, v| [r[0].min(v), r[1].max(v)])
    };
    let lobes = (0..m.lobes.len()).map(|k| range(&mut per_view.iter().map(|t| t[k]))).collect();
    let mean = |c: [f64; 3]| (c[0] + c[1] + c[2]) / 3.0;
    let total = mean(m.energy_sums());
    let material = range(&mut per_view.iter().map(|t| {
        let a = mean(m.diffuse) + m.lobes.iter().zip(t).map(|(l, &t)| mean(l.albedo) * t).sum::<f64>();
        if total > 0.0 {
            a / total
        } else {
            1.0
        }
    }));
    Some((lobes, material))
}
