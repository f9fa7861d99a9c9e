//! Energy and reciprocity measurements of a material (docs/model.md, The energy bound): directional albedo
//! `a(ω_o) = ∫ f(ω_i, ω_o) cos θ_i dω_i` by importance-sampled Monte Carlo with a standard error, its
//! maximum over a dense set of view directions (up to 89.9°) with the curve of that maximum against
//! the view angle (total and per lobe, [`AlbedoCurve`]), and the reciprocity error
//! `max |f(a,b) − f(b,a)| / max f` over random pairs.
//!
//! Every estimate is reproducible: each view direction has its own seeded generator, so parallel
//! evaluation (rayon) does not change a digit.

use glam::DVec3;
use rayon::prelude::*;

use super::material::Material;
use super::sampling::{self, MaterialSampler};
use super::ward::Normalization;
use crate::rng::Pcg32;

/// The most Monte Carlo samples per view direction `check` takes (`--samples`): 50× the default.
/// Each costs one mixture sample and weight (O(lobes)) at each of up to 288 views, so 10⁶ samples
/// of a few lobes take about half a minute on two cores.
pub const MAX_SAMPLES: usize = 1_000_000;

/// The most direction pairs of the reciprocity error (`--pairs`): 50× the default, two evaluations
/// each, a few seconds for a few lobes.
pub const MAX_PAIRS: usize = 10_000_000;

/// Units of work between two looks at [`Watch::stop`].
const CHUNK: usize = 4096;

/// How a long measurement shows progress and is stopped: `advance(n)` after `n` units of work (a
/// sample, a quadrature cell, a pair); `stop()` returning true ends it early (the result is then
/// `None`). [`Watch::NONE`] does neither.
#[derive(Clone, Copy)]
pub struct Watch<'a> {
    pub advance: &'a (dyn Fn(u64) + Sync),
    pub stop: &'a (dyn Fn() -> bool + Sync),
}

impl Watch<'_> {
    /// At sample `k` of `n`, every [`CHUNK`] samples: `false` when the watch says stop, else
    /// advances it by the chunk's samples.
    fn chunk(&self, k: usize, n: usize) -> bool {
        if k % CHUNK == 0 {
            if (self.stop)() {
                return false;
            }
            (self.advance)(CHUNK.min(n - k) as u64);
        }
        true
    }
}

fn no_advance(_: u64) {}

fn never() -> bool {
    false
}

impl Watch<'static> {
    pub const NONE: Watch<'static> = Watch { advance: &no_advance, stop: &never };
}

/// A Monte Carlo estimate per channel with its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub value: [f64; 3],
    pub std_err: [f64; 3],
}

/// The direction at polar angle `theta` (radians from the normal) and azimuth `phi`.
pub fn direction(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

/// `a(ω_o)` from `n` samples of the material's mixture sampler, seeded by `seed`.
pub fn directional_albedo(m: &Material, wo: DVec3, n: usize, seed: u64) -> Estimate {
    directional_albedo_watched(m, wo, n, seed, Watch::NONE).expect("never stopped")
}

/// [`directional_albedo`] under a [`Watch`] (one unit per sample; `None` when stopped).
pub fn directional_albedo_watched(m: &Material, wo: DVec3, n: usize, seed: u64, watch: Watch<'_>) -> Option<Estimate> {
    let sampler = MaterialSampler::new(m, wo);
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut sum = [0.0f64; 3];
    let mut sum2 = [0.0f64; 3];
    for k in 0..n {
        if !watch.chunk(k, n) {
            return None;
        }
        let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        let w = match sampler.sample(u0, 1.0 - u1, u2) {
            Some(wi) => sampler.weight(wi),
            None => [0.0; 3],
        };
        for c in 0..3 {
            sum[c] += w[c];
            sum2[c] += w[c] * w[c];
        }
    }
    let nf = n as f64;
    let value = sum.map(|s| s / nf);
    let std_err = [0, 1, 2].map(|c| ((sum2[c] / nf - value[c] * value[c]).max(0.0) / (nf - 1.0)).sqrt());
    Some(Estimate { value, std_err })
}

/// The largest directional albedo found, where, and how sure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxAlbedo {
    pub value: f64,
    pub std_err: f64,
    pub channel: usize,
    pub theta_deg: f64,
    pub phi_deg: f64,
}

/// The polar angles (degrees) of the dense view set: every 5° to 85°, then ever closer to grazing.
pub const THETA_SET_DEG: [f64; 24] = [
    0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 87.0,
    88.0, 89.0, 89.5, 89.7, 89.9,
];

/// The maximum of `a(ω_o)` over [`THETA_SET_DEG`] × 12 azimuths (one azimuth when the material is
/// isotropic and unrotated), `n` samples per direction.
pub fn max_directional_albedo(m: &Material, n: usize) -> MaxAlbedo {
    max_directional_albedo_watched(m, n, Watch::NONE).expect("never stopped")
}

/// The view directions [`max_directional_albedo`] measures.
fn albedo_directions(m: &Material) -> Vec<(f64, f64)> {
    let symmetric_in_phi = m.lobes.iter().all(|l| !l.is_anisotropic() && !l.is_rotated());
    let phis: Vec<f64> = if symmetric_in_phi { vec![0.0] } else { (0..12).map(|i| i as f64 * 30.0).collect() };
    THETA_SET_DEG.iter().flat_map(|&t| phis.iter().map(move |&p| (t, p))).collect()
}

/// [`max_directional_albedo`] under a [`Watch`] (`None` when stopped).
pub fn max_directional_albedo_watched(m: &Material, n: usize, watch: Watch<'_>) -> Option<MaxAlbedo> {
    mc_views_watched(m, n, watch).map(|views| mc_max(&views))
}

/// The largest channel of `a(ω_o)` at each of [`albedo_directions`] (in its order), `n` samples each,
/// the `i`-th seeded by `i`.
fn mc_views_watched(m: &Material, n: usize, watch: Watch<'_>) -> Option<Vec<MaxAlbedo>> {
    albedo_directions(m)
        .par_iter()
        .enumerate()
        .map(|(i, &(t, p))| {
            let e = directional_albedo_watched(m, direction(t.to_radians(), p.to_radians()), n, i as u64, watch)?;
            let c = (1..3).fold(0, |best, c| if e.value[c] > e.value[best] { c } else { best });
            Some(MaxAlbedo { value: e.value[c], std_err: e.std_err[c], channel: c, theta_deg: t, phi_deg: p })
        })
        .collect()
}

/// [`max_directional_albedo_watched`] and the albedo curve from the same estimates, each point's
/// lobes measured again from the same samples ([`directional_albedo_lobes_watched`]).
fn mc_measure_watched(m: &Material, n: usize, watch: Watch<'_>) -> Option<(MaxAlbedo, AlbedoCurve)> {
    let views = mc_views_watched(m, n, watch)?;
    let points = per_theta(&views, |v| *v)
        .par_iter()
        .map(|&i| {
            let total = views[i];
            let wo = direction(total.theta_deg.to_radians(), total.phi_deg.to_radians());
            let lobes: Vec<f64> = if m.lobes.is_empty() {
                Vec::new()
            } else {
                let shares = directional_albedo_lobes_watched(m, wo, n, i as u64, watch)?;
                shares.iter().map(|s| s[total.channel]).collect()
            };
            Some(AlbedoPoint::new(total, &lobes))
        })
        .collect::<Option<Vec<_>>>()?;
    Some((mc_max(&views), AlbedoCurve::new(points)))
}

/// The largest of the Monte Carlo views (the first of equals).
fn mc_max(views: &[MaxAlbedo]) -> MaxAlbedo {
    views.iter().copied().fold(
        MaxAlbedo { value: f64::NEG_INFINITY, std_err: 0.0, channel: 0, theta_deg: 0.0, phi_deg: 0.0 },
        |a, b| {
            if b.value > a.value {
                b
            } else {
                a
            }
        },
    )
}

/// Each lobe's share of the estimate [`directional_albedo`] makes from the same `n` samples (same
/// `seed`): the mean of `ρ_k F_k(ω_i, ω_o) cos θ_i / p(ω_i)` per channel, `F_k` the lobe's term as
/// the material evaluates it (symmetrised where the material is). With the diffuse term's share
/// they add up to the estimate, to rounding. One unit of [`Watch`] per sample; `None` when stopped.
pub fn directional_albedo_lobes_watched(
    m: &Material,
    wo: DVec3,
    n: usize,
    seed: u64,
    watch: Watch<'_>,
) -> Option<Vec<[f64; 3]>> {
    let sampler = MaterialSampler::new(m, wo);
    let wo_unit = super::material::unit(wo);
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut sums = vec![[0.0f64; 3]; m.lobes.len()];
    for k in 0..n {
        if !watch.chunk(k, n) {
            return None;
        }
        let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        // The weight's own `ω_i` for the pdf and the cosine; the lobe terms take unit inputs.
        let Some(wi) = sampler.sample(u0, 1.0 - u1, u2) else { continue };
        let (Some(wi_unit), Some(wo)) = (super::material::unit(wi), wo_unit) else { continue };
        let p = sampler.pdf(wi);
        if !(p > 0.0) {
            continue;
        }
        for (j, (sum, lobe)) in sums.iter_mut().zip(&m.lobes).enumerate() {
            let f = m.lobe_ln(j, wi_unit, wo).min(f64::MAX.ln()).exp();
            for c in 0..3 {
                sum[c] += (lobe.albedo[c] * f).min(f64::MAX) * wi.z / p;
            }
        }
    }
    let nf = n as f64;
    Some(sums.into_iter().map(|s| s.map(|v| v / nf)).collect())
}

/// Cells per side of the deterministic quadrature of a reciprocal lobe's albedo.
pub const FACET_GRID: usize = 128;

/// `∫ F cos θ_i dω_i` of one facet term of a reciprocal lobe at `ω_o`, per unit albedo, by the
/// product midpoint rule on the sampler's unit square (`n × n` cells). The sampler maps the square
/// onto the facet distribution preserving measure, and the integrand there is the closed-form weight
/// `cos θ_i / max(cos θ_i, cos θ_o) ∈ [0, 1]` (0 where the reflected direction leaves the
/// hemisphere), so the exact value lies in [0, 1] and this deterministic rule cannot exceed 1.
pub fn facet_term_albedo(shape: &super::ward::Shape<f64>, frame: glam::DQuat, wo: DVec3, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let u1 = (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let u2 = (j as f64 + 0.5) / n as f64;
            if let Some(wi) = sampling::sample_facet(shape, frame, wo, u1, u2) {
                sum += sampling::facet_weight(wi, wo);
            }
        }
    }
    sum / (n * n) as f64
}

/// `a(ω_o)` per channel of a reciprocal material by [`facet_term_albedo`] (`n × n` cells per facet
/// term): `ρ_d + Σ_k ρ_k · mean over its facet terms`.
pub fn facet_albedo(m: &Material, wo: DVec3, n: usize) -> [f64; 3] {
    facet_albedo_of(m, &facet_lobe_terms(m, wo, n))
}

/// Each lobe's albedo per unit albedo at `ω_o`: the mean of [`facet_term_albedo`] over its facet
/// terms (`n × n` cells each), with its compensation term's albedo in an energy-preserving material.
/// There the quadrature's estimate of the lobe's own albedo `E` is taken at most `Ê(ω_o)`, which
/// the exact `E` is (the certificate, docs/model.md): the rule's error on a sharp lobe would
/// otherwise add to a term that fills the rest up to 1.
pub fn facet_lobe_terms(m: &Material, wo: DVec3, n: usize) -> Vec<f64> {
    let tables = m.tables();
    m.lobes
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let (frames, count) = l.facet_frames();
            let shape = l.shape();
            let e = frames[..count].iter().map(|&q| facet_term_albedo(&shape, q, wo, n)).sum::<f64>() / count as f64;
            match &tables {
                Some(t) => e.min(f64::from(t[k].albedo(wo.as_vec3().to_array()))) + t[k].term_albedo(wo),
                None => e,
            }
        })
        .collect()
}

/// `ρ_d + Σ_k ρ_k t_k` per channel, `t_k` from [`facet_lobe_terms`].
fn facet_albedo_of(m: &Material, terms: &[f64]) -> [f64; 3] {
    let mut a = m.diffuse;
    for (l, &t) in m.lobes.iter().zip(terms) {
        for c in 0..3 {
            a[c] += l.albedo[c] * t;
        }
    }
    a
}

/// The maximum directional albedo of a reciprocal material over [`THETA_SET_DEG`] × 12 azimuths by
/// deterministic quadrature ([`FACET_GRID`]² cells per term). `std_err` carries the quadrature's
/// error estimate at the maximum, `|A(n) − A(n/2)|`.
pub fn facet_max_albedo(m: &Material) -> MaxAlbedo {
    facet_max_albedo_watched(m, Watch::NONE).expect("never stopped")
}

/// The view directions of [`facet_max_albedo`].
fn facet_directions() -> Vec<(f64, f64)> {
    THETA_SET_DEG.iter().flat_map(|&t| (0..12).map(move |i| (t, i as f64 * 30.0))).collect()
}

/// Units of work of [`facet_max_albedo_watched`]: one per view direction and lobe.
fn facet_work(m: &Material) -> u64 {
    (facet_directions().len() * m.lobes.len().max(1)) as u64
}

/// [`facet_max_albedo`] under a [`Watch`] (one unit per view direction and lobe; `None` when
/// stopped).
pub fn facet_max_albedo_watched(m: &Material, watch: Watch<'_>) -> Option<MaxAlbedo> {
    facet_measure_watched(m, watch).map(|(best, _)| best)
}

/// The largest channel of the quadrature albedo at each of [`facet_directions`] (in its order), with
/// each lobe's albedo in that channel there (`ρ_k[c] t_k`).
fn facet_views_watched(m: &Material, watch: Watch<'_>) -> Option<Vec<(MaxAlbedo, Vec<f64>)>> {
    facet_directions()
        .par_iter()
        .map(|&(t, p)| {
            if (watch.stop)() {
                return None;
            }
            let terms = facet_lobe_terms(m, direction(t.to_radians(), p.to_radians()), FACET_GRID);
            let a = facet_albedo_of(m, &terms);
            (watch.advance)(m.lobes.len().max(1) as u64);
            let c = (1..3).fold(0, |best, c| if a[c] > a[best] { c } else { best });
            let lobes = m.lobes.iter().zip(&terms).map(|(l, &t)| l.albedo[c] * t).collect();
            Some((MaxAlbedo { value: a[c], std_err: 0.0, channel: c, theta_deg: t, phi_deg: p }, lobes))
        })
        .collect()
}

/// [`facet_max_albedo_watched`] and the albedo curve from the same quadrature.
fn facet_measure_watched(m: &Material, watch: Watch<'_>) -> Option<(MaxAlbedo, AlbedoCurve)> {
    let views = facet_views_watched(m, watch)?;
    let best = views
        .iter()
        .map(|v| v.0)
        .fold(None::<MaxAlbedo>, |a, b| match a {
            Some(a) if a.value >= b.value => Some(a),
            _ => Some(b),
        })
        .expect("the view set is not empty");
    let coarse = facet_albedo(m, direction(best.theta_deg.to_radians(), best.phi_deg.to_radians()), FACET_GRID / 2);
    let points = per_theta(&views, |v| v.0).into_iter().map(|i| AlbedoPoint::new(views[i].0, &views[i].1)).collect();
    Some((MaxAlbedo { std_err: (best.value - coarse[best.channel]).abs(), ..best }, AlbedoCurve::new(points)))
}

/// The index of the largest view (the first of equals) at each polar angle of `views`, which run
/// through [`THETA_SET_DEG`] in order, each angle's azimuths together.
fn per_theta<T>(views: &[T], at: impl Fn(&T) -> MaxAlbedo) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for (i, v) in views.iter().enumerate() {
        let a = at(v);
        match out.last_mut() {
            Some(j) if at(&views[*j]).theta_deg == a.theta_deg => {
                if a.value > at(&views[*j]).value {
                    *j = i;
                }
            }
            _ => out.push(i),
        }
    }
    out
}

/// The maximum directional albedo and its [`AlbedoCurve`] as [`Report::measure_watched`] measures
/// them (the same numbers, bit for bit): by quadrature for the reciprocal model, by Monte Carlo with
/// `samples` per direction for the paper's. `None` when stopped.
pub fn albedo_curve_watched(m: &Material, samples: usize, watch: Watch<'_>) -> Option<(MaxAlbedo, AlbedoCurve)> {
    if m.normalization == Normalization::Reciprocal {
        facet_measure_watched(m, watch)
    } else {
        mc_measure_watched(m, samples, watch)
    }
}

/// The most lobes an [`AlbedoPoint`] keeps one by one: the first this many of the material's (the
/// total counts every lobe). A fixed number keeps the report a plain `Copy` value.
pub const CURVE_LOBES: usize = 16;

/// One view angle of an [`AlbedoCurve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlbedoPoint {
    /// The total directional albedo at its largest over the azimuths and channels at this `θ_o`, and
    /// where (`std_err`: the Monte Carlo standard error; 0 for the quadrature).
    pub total: MaxAlbedo,
    lobes: [f64; CURVE_LOBES],
    lobe_count: usize,
}

impl AlbedoPoint {
    /// The point of `total`, keeping the first [`CURVE_LOBES`] of `lobes`.
    pub fn new(total: MaxAlbedo, lobes: &[f64]) -> AlbedoPoint {
        let lobe_count = lobes.len().min(CURVE_LOBES);
        let mut kept = [0.0; CURVE_LOBES];
        kept[..lobe_count].copy_from_slice(&lobes[..lobe_count]);
        AlbedoPoint { total, lobes: kept, lobe_count }
    }

    /// Each lobe's directional albedo at the same direction, in the same channel: `ρ_k[c]` times
    /// the lobe's albedo per unit albedo, for the first [`CURVE_LOBES`] lobes. For a material of at
    /// most that many lobes they add up, with the diffuse albedo `ρ_d[c]` and in lobe order, to
    /// `total.value`: exactly in the quadrature's arithmetic, to the rounding of the per-lobe sums
    /// for Monte Carlo.
    pub fn lobes(&self) -> &[f64] {
        &self.lobes[..self.lobe_count]
    }
}

/// The directional albedo against the view angle, one point per angle of [`THETA_SET_DEG`] (in its
/// order), from the measurement of the report's maximum: the largest `total.value` is the report's
/// `max_albedo.value`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlbedoCurve {
    pub points: [AlbedoPoint; THETA_SET_DEG.len()],
}

impl AlbedoCurve {
    /// The curve of one point per view angle, in [`THETA_SET_DEG`]'s order.
    fn new(points: Vec<AlbedoPoint>) -> AlbedoCurve {
        AlbedoCurve { points: points.try_into().expect("one point per angle of THETA_SET_DEG") }
    }
}

/// Uniform direction on the upper hemisphere.
fn uniform_hemisphere(u1: f64, u2: f64) -> DVec3 {
    let z = u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
    DVec3::new(r * c, r * s, z)
}

/// How far a material is from reciprocal, over random direction pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reciprocity {
    /// `max |f(a,b) − f(b,a)| / max f` (the maximum over channels). Dominated by grazing pairs: a
    /// rotated lobe is cut off where `R ω_o` crosses the horizon, so any rotation off the normal makes
    /// this close to 1 somewhere near grazing.
    pub max_rel: f64,
    /// `Σ |f(a,b) − f(b,a)| cos θ_a cos θ_b / Σ ½(f(a,b) + f(b,a)) cos θ_a cos θ_b` over the uniform
    /// pairs: the non-reciprocal share of the reflected energy.
    pub mean_rel: f64,
}

/// [`Reciprocity`] over `n` pairs (the maximum over channels): half uniform on the hemisphere, half
/// with `a` importance-sampled about `b` so that sharp lobes are hit.
pub fn reciprocity(m: &Material, n: usize, seed: u64) -> Reciprocity {
    reciprocity_watched(m, n, seed, Watch::NONE).expect("never stopped")
}

/// [`reciprocity`] under a [`Watch`] (one unit per pair; `None` when stopped).
pub fn reciprocity_watched(m: &Material, n: usize, seed: u64, watch: Watch<'_>) -> Option<Reciprocity> {
    let mut rng = Pcg32::new(seed, 0xec1);
    let mut max_diff = [0.0f64; 3];
    let mut max_f = [0.0f64; 3];
    let mut sum_diff = [0.0f64; 3];
    let mut sum_f = [0.0f64; 3];
    for i in 0..n {
        if i % CHUNK == 0 {
            if (watch.stop)() {
                return None;
            }
            (watch.advance)(CHUNK.min(n - i) as u64);
        }
        let b = uniform_hemisphere(rng.next_f64(), rng.next_f64());
        let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        let uniform = i % 2 == 0;
        let a = if uniform {
            uniform_hemisphere(u1, u2)
        } else {
            match MaterialSampler::new(m, b).sample(u0, 1.0 - u1, u2) {
                Some(a) => a,
                None => continue,
            }
        };
        let (fab, fba) = (m.eval(a, b), m.eval(b, a));
        for c in 0..3 {
            let d = (fab[c] - fba[c]).abs();
            max_diff[c] = max_diff[c].max(d);
            max_f[c] = max_f[c].max(fab[c]).max(fba[c]);
            if uniform {
                let w = a.z * b.z;
                sum_diff[c] += d * w;
                sum_f[c] += 0.5 * (fab[c] + fba[c]) * w;
            }
        }
    }
    let ratio = |num: [f64; 3], den: [f64; 3]| {
        (0..3).map(|c| if den[c] > 0.0 { num[c] / den[c] } else { 0.0 }).fold(0.0, f64::max)
    };
    Some(Reciprocity { max_rel: ratio(max_diff, max_f), mean_rel: ratio(sum_diff, sum_f) })
}

/// `max |f(a,b) − f(b,a)| / max f` over `n` pairs; see [`reciprocity`].
pub fn reciprocity_error(m: &Material, n: usize, seed: u64) -> f64 {
    reciprocity(m, n, seed).max_rel
}

/// What the albedo bound of a report rests on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlbedoBound {
    /// The reciprocal form: `a(ω_o) ≤ ρ_d + Σρ_k` for every `ω_o` by construction (the integrand of
    /// every facet term is at most 1 against a normalised distribution), so the bound is the largest
    /// channel sum, exact to the rounding of that sum ([`BOUND_ROUNDING`]). `max_albedo` is then a
    /// deterministic quadrature of the actual maximum, with its error estimate in `std_err`.
    Exact,
    /// The paper's forms: only the Monte Carlo maximum (± 3σ in `max_albedo`) says anything.
    Measured,
}

/// Relative rounding error of the exact bound: the sum of at most a few thousand terms in `f64`.
pub const BOUND_ROUNDING: f64 = 1.0e-12;

/// Everything `brdf-shop check` and the editor's energy readout show.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// `ρ_d + Σρ_k` per channel.
    pub sums: [f64; 3],
    pub bound: AlbedoBound,
    pub max_albedo: MaxAlbedo,
    /// The directional albedo against `θ_o` from the same measurement (its maximum is `max_albedo`).
    pub curve: AlbedoCurve,
    pub reciprocity: Reciprocity,
}

/// Reciprocity error below which a material counts as exactly reciprocal (docs/model.md, The verdict).
pub const RECIPROCITY_EXACT: f64 = 1.0e-12;

impl Report {
    pub fn measure(m: &Material, samples: usize, pairs: usize) -> Report {
        Report::measure_watched(m, samples, pairs, Watch::NONE).expect("never stopped")
    }

    /// The units of work [`Report::measure_watched`] advances its [`Watch`] by in all.
    pub fn work(m: &Material, samples: usize, pairs: usize) -> u64 {
        let albedo = if m.normalization == Normalization::Reciprocal {
            facet_work(m)
        } else {
            // The views, then the lobes at each polar angle's largest view.
            let lobes = if m.lobes.is_empty() { 0 } else { THETA_SET_DEG.len() };
            ((albedo_directions(m).len() + lobes) * samples) as u64
        };
        albedo + pairs as u64
    }

    /// [`Report::measure`] under a [`Watch`]; `None` when stopped.
    pub fn measure_watched(m: &Material, samples: usize, pairs: usize, watch: Watch<'_>) -> Option<Report> {
        let exact = m.normalization == Normalization::Reciprocal;
        let (max_albedo, curve) = albedo_curve_watched(m, samples, watch)?;
        Some(Report {
            sums: m.energy_sums(),
            bound: if exact { AlbedoBound::Exact } else { AlbedoBound::Measured },
            max_albedo,
            curve,
            reciprocity: reciprocity_watched(m, pairs, 1, watch)?,
        })
    }

    /// The upper bound of the maximum directional albedo: the largest channel sum for the reciprocal
    /// form, the measured maximum + 3σ otherwise.
    pub fn albedo_upper_bound(&self) -> f64 {
        match self.bound {
            AlbedoBound::Exact => self.sums.iter().copied().fold(0.0, f64::max),
            AlbedoBound::Measured => self.max_albedo.value + 3.0 * self.max_albedo.std_err,
        }
    }

    /// Whether the albedo exceeds 1: for the paper's forms, the measurement by more than three
    /// standard errors; for the reciprocal form, the exact bound.
    pub fn albedo_exceeds_one(&self) -> bool {
        match self.bound {
            AlbedoBound::Exact => self.albedo_upper_bound() > 1.0 + super::material::ENERGY_SLACK,
            AlbedoBound::Measured => self.max_albedo.value - 3.0 * self.max_albedo.std_err > 1.0,
        }
    }

    pub fn is_reciprocal(&self) -> bool {
        self.reciprocity.max_rel <= RECIPROCITY_EXACT
    }

    /// Reciprocal and bounded: what "physically correct" promises.
    pub fn is_physically_correct(&self) -> bool {
        self.is_reciprocal()
            && !self.albedo_exceeds_one()
            && self.albedo_upper_bound() <= 1.0 + super::material::ENERGY_SLACK
    }

    /// A plain verdict: "physically correct", or what breaks it.
    pub fn verdict(&self) -> String {
        let mut broken = Vec::new();
        if !self.is_reciprocal() {
            broken.push(format!("not reciprocal (error {:.3e} > {RECIPROCITY_EXACT:e})", self.reciprocity.max_rel));
        }
        if self.albedo_exceeds_one() {
            broken.push(format!("reflects more than it receives (albedo {:.4} > 1)", self.max_albedo.value));
        } else if self.albedo_upper_bound() > 1.0 + super::material::ENERGY_SLACK {
            broken.push(format!("albedo not bounded by 1 within the measurement ({:.4} + 3σ)", self.max_albedo.value));
        }
        if broken.is_empty() {
            "physically correct".into()
        } else {
            format!("not physically correct: {}", broken.join("; "))
        }
    }
}
