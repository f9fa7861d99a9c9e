//! Energy and reciprocity measurements of a material (SPEC §2 "Energy"): directional albedo
//! `a(ω_o) = ∫ f(ω_i, ω_o) cos θ_i dω_i` by importance-sampled Monte Carlo with a standard error, its
//! maximum over a dense set of view directions (up to 89.9°), and the reciprocity error
//! `max |f(a,b) − f(b,a)| / max f` over random pairs.
//!
//! Every estimate is reproducible: each view direction has its own seeded generator, so parallel
//! evaluation (rayon) does not change a digit.

use glam::DVec3;
use rayon::prelude::*;

use super::material::Material;
use super::sampling::MaterialSampler;
use crate::rng::Pcg32;

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
    let sampler = MaterialSampler::new(m, wo);
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut sum = [0.0f64; 3];
    let mut sum2 = [0.0f64; 3];
    for _ in 0..n {
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
    Estimate { value, std_err }
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
    let symmetric_in_phi = m.lobes.iter().all(|l| !l.is_anisotropic() && !l.is_rotated());
    let phis: Vec<f64> = if symmetric_in_phi { vec![0.0] } else { (0..12).map(|i| i as f64 * 30.0).collect() };
    let dirs: Vec<(f64, f64)> = THETA_SET_DEG.iter().flat_map(|&t| phis.iter().map(move |&p| (t, p))).collect();
    dirs.par_iter()
        .enumerate()
        .map(|(i, &(t, p))| {
            let e = directional_albedo(m, direction(t.to_radians(), p.to_radians()), n, i as u64);
            let c = (1..3).fold(0, |best, c| if e.value[c] > e.value[best] { c } else { best });
            MaxAlbedo { value: e.value[c], std_err: e.std_err[c], channel: c, theta_deg: t, phi_deg: p }
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold(MaxAlbedo { value: f64::NEG_INFINITY, std_err: 0.0, channel: 0, theta_deg: 0.0, phi_deg: 0.0 }, |a, b| {
            if b.value > a.value {
                b
            } else {
                a
            }
        })
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
    let mut rng = Pcg32::new(seed, 0xec1);
    let mut max_diff = [0.0f64; 3];
    let mut max_f = [0.0f64; 3];
    let mut sum_diff = [0.0f64; 3];
    let mut sum_f = [0.0f64; 3];
    for i in 0..n {
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
    Reciprocity { max_rel: ratio(max_diff, max_f), mean_rel: ratio(sum_diff, sum_f) }
}

/// `max |f(a,b) − f(b,a)| / max f` over `n` pairs; see [`reciprocity`].
pub fn reciprocity_error(m: &Material, n: usize, seed: u64) -> f64 {
    reciprocity(m, n, seed).max_rel
}

/// Everything `brdf-shop check` and the editor's energy readout show.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// `ρ_d + Σρ_k` per channel.
    pub sums: [f64; 3],
    pub max_albedo: MaxAlbedo,
    pub reciprocity: Reciprocity,
}

impl Report {
    pub fn measure(m: &Material, samples: usize, pairs: usize) -> Report {
        Report {
            sums: m.energy_sums(),
            max_albedo: max_directional_albedo(m, samples),
            reciprocity: reciprocity(m, pairs, 1),
        }
    }

    /// Whether the measured albedo exceeds 1 by more than three standard errors.
    pub fn albedo_exceeds_one(&self) -> bool {
        self.max_albedo.value - 3.0 * self.max_albedo.std_err > 1.0
    }
}
