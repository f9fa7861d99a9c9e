//! Key lights: the compact, very bright sources of an environment map (a sun, a studio lamp) split
//! off the map, the groundwork of issue 10's estimator (treat them analytically, prefilter and
//! project onto SH9 only what is left).
//!
//! A key light is a connected region (8-neighbour, wrapping in `u`) of texels whose luminance exceeds
//! [`THRESHOLD_OVER_MEAN`] times the map's mean radiance, no larger than [`MAX_SOLID_ANGLE`], together
//! with one ring of texels around it (the glare and the compression ringing of a sun, which may be
//! negative). Its texels are replaced by the median of the next ring (the local background), and the
//! light keeps the difference: `power = Σ (L − background) dω` per channel. So the residual map plus the
//! lights carry exactly the map's energy, texel for texel. Lights carrying less than [`MIN_SHARE`] of
//! the map's energy are left in the map (not worth a pass); at most [`MAX_LIGHTS`] are kept.
//!
//! Pure CPU, no GPU; owns no file I/O.

use std::collections::HashSet;

use glam::DVec3;

use super::env::Environment;

/// A texel belongs to a light where its luminance exceeds this multiple of the map's mean
/// (solid-angle-weighted) luminance. A clear-sky sun is 10³–10⁴ times the mean; bright windows and
/// overcast skies are 3–10 times it.
pub const THRESHOLD_OVER_MEAN: f64 = 30.0;

/// The largest solid angle of a compact light, in steradians (a disc of about 7° radius): anything
/// wider (a window, a bright patch of sky) is left to the prefiltered map.
pub const MAX_SOLID_ANGLE: f64 = 0.05;

/// The smallest share of the map's energy (luminance × solid angle) a light must carry to be split off.
pub const MIN_SHARE: f64 = 0.02;

/// At most this many lights, the brightest first.
pub const MAX_LIGHTS: usize = 4;

/// One compact light of the map.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLight {
    /// Unit direction toward the light: the centroid of `(L − background)` luminance over its texels.
    pub direction: DVec3,
    /// The angular radius of the cap with the light's solid angle, in radians.
    pub angular_radius: f64,
    /// The solid angle of the replaced texels, in steradians.
    pub solid_angle: f64,
    /// `Σ (L − background) dω` per channel: the irradiance the light gives a surface facing it.
    pub power: [f64; 3],
    /// How many texels were replaced.
    pub texels: usize,
}

/// The key lights of a map and what is left of it.
#[derive(Clone, Debug)]
pub struct KeyLights {
    pub lights: Vec<KeyLight>,
    /// The map with each light's texels replaced by its local background.
    pub residual: Environment,
    /// The lights' share of the map's energy (luminance × solid angle, texels of either sign).
    pub share: f64,
    /// The luminance threshold used (`THRESHOLD_OVER_MEAN` × the mean).
    pub threshold: f64,
}

fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// The 8 neighbours of texel `(i, j)`, wrapping in `u`, clamped in `v`.
fn neighbours(i: usize, j: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    let rows = j.saturating_sub(1)..=(j + 1).min(h - 1);
    rows.flat_map(move |jj| [w - 1, 0, 1].into_iter().map(move |di| ((i + di) % w, jj)))
        .filter(move |&(ii, jj)| (ii, jj) != (i, j))
}

/// Texel direction at its centre.
fn texel_direction(i: usize, j: usize, w: usize, h: usize) -> DVec3 {
    Environment::direction((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64)
}

/// The median of each channel over `texels` (0 for none).
fn median(env: &Environment, texels: &[usize]) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut v: Vec<f32> = texels.iter().map(|&k| env.texels[k][c]).collect();
        if v.is_empty() {
            continue;
        }
        v.sort_by(f32::total_cmp);
        *o = v[v.len() / 2];
    }
    out
}

/// Finds the key lights of `env` (see the module note). A map without any gives no lights and a
/// residual equal to the map.
pub fn detect(env: &Environment) -> KeyLights {
    let (w, h) = (env.width, env.height);
    let d_omega: Vec<f64> = (0..h).map(|j| env.texel_solid_angle(j)).collect();
    let lum: Vec<f64> = env.texels.iter().map(|&t| luminance(t)).collect();
    let total: f64 = lum.iter().enumerate().map(|(k, l)| l * d_omega[k / w]).sum();
    let total_abs: f64 = lum.iter().enumerate().map(|(k, l)| l.abs() * d_omega[k / w]).sum();
    let mean = total / (4.0 * std::f64::consts::PI);
    let threshold = THRESHOLD_OVER_MEAN * mean;
    let mut residual = env.clone();
    let none = |residual| KeyLights { lights: Vec::new(), residual, share: 0.0, threshold };
    if !(mean > 0.0 && w > 2 && h > 2) {
        return none(residual);
    }

    // Connected components of the bright texels.
    let bright = |k: usize| lum[k] > threshold;
    let mut label = vec![u32::MAX; w * h];
    let mut components: Vec<Vec<usize>> = Vec::new();
    for start in 0..w * h {
        if !bright(start) || label[start] != u32::MAX {
            continue;
        }
        let id = components.len() as u32;
        let (mut members, mut stack) = (Vec::new(), vec![start]);
        label[start] = id;
        while let Some(k) = stack.pop() {
            members.push(k);
            for (i, j) in neighbours(k % w, k / w, w, h) {
                let n = j * w + i;
                if bright(n) && label[n] == u32::MAX {
                    label[n] = id;
                    stack.push(n);
                }
            }
        }
        components.push(members);
    }

    // Each compact component, grown by one ring, against the median of the ring beyond.
    let mut candidates: Vec<(KeyLight, Vec<usize>, [f32; 3])> = Vec::new();
    for members in components {
        let solid: f64 = members.iter().map(|&k| d_omega[k / w]).sum();
        if solid > MAX_SOLID_ANGLE {
            continue;
        }
        let mut inside: HashSet<usize> = members.iter().copied().collect();
        let ring = |set: &[usize], inside: &HashSet<usize>| -> Vec<usize> {
            let mut out: Vec<usize> = set
                .iter()
                .flat_map(|&k| neighbours(k % w, k / w, w, h).map(|(i, j)| j * w + i))
                .filter(|n| !inside.contains(n))
                .collect();
            out.sort_unstable();
            out.dedup();
            out
        };
        let glare = ring(&members, &inside);
        let mut region = members.clone();
        inside.extend(glare.iter().copied());
        region.extend_from_slice(&glare);
        let outer = ring(&glare, &inside);
        let background = median(env, &outer);
        let bg_lum = luminance(background);
        let (mut power, mut centroid, mut solid_angle) = ([0.0f64; 3], DVec3::ZERO, 0.0);
        for &k in &region {
            let (i, j) = (k % w, k / w);
            let t = env.texels[k];
            for c in 0..3 {
                power[c] += (t[c] as f64 - background[c] as f64) * d_omega[j];
            }
            let excess = (lum[k] - bg_lum).max(0.0) * d_omega[j];
            centroid += excess * texel_direction(i, j, w, h);
            solid_angle += d_omega[j];
        }
        let Some(direction) = crate::brdf::material::unit(centroid) else { continue };
        let light = KeyLight {
            direction,
            angular_radius: (1.0 - solid_angle / (2.0 * std::f64::consts::PI)).clamp(-1.0, 1.0).acos(),
            solid_angle,
            power,
            texels: region.len(),
        };
        candidates.push((light, region, background));
    }
    let power_lum = |l: &KeyLight| 0.2126 * l.power[0] + 0.7152 * l.power[1] + 0.0722 * l.power[2];
    candidates.sort_by(|a, b| power_lum(&b.0).total_cmp(&power_lum(&a.0)));
    let mut lights = Vec::new();
    let mut moved = 0.0;
    for (light, region, background) in candidates.into_iter().take(MAX_LIGHTS) {
        let p = power_lum(&light);
        if !(p >= MIN_SHARE * total_abs) {
            continue;
        }
        for &k in &region {
            residual.texels[k] = background;
        }
        moved += p;
        lights.push(light);
    }
    residual.origin = format!("{} (key lights removed)", env.origin);
    KeyLights { lights, residual, share: moved / total_abs, threshold }
}
