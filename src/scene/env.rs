//! The environment map as plain CPU data (docs/model.md, Frames and conventions): loading (EXR through `exr`, scanline
//! or tiled, any compression it reads; Radiance `.hdr` through `image`), the texel policy (NaN/Inf → 0,
//! negatives kept and reported), bilinear lookup (what a `LINEAR`/`REPEAT u`/`CLAMP v` sampler
//! returns at level 0 — the definition of the environment's radiance for the reference and `mis`),
//! the solid-angle-weighted mip chain, the SH9 projection in `f64`, the brightest direction, and
//! the importance-sampling distribution over `|L| sin θ`.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};

/// The longest side of an environment map (texels): the side of the largest 2D image a desktop
/// GPU accepts (`maxImageDimension2D` is 16384 on lavapipe and most discrete GPUs).
pub const MAX_ENV_SIDE: usize = 16384;

/// The most texels an environment map may have, checked against the file's header before any
/// pixel is read or allocated: 8192×4096, the largest map the stability report uses. Loading and
/// preparing a map (texels, mip chain, sampling tables in `f64`) takes about 80 bytes per texel,
/// so the largest map needs about 2.7 GB.
pub const MAX_ENV_TEXELS: usize = 8192 * 4096;

/// The largest environment file read (bytes): an uncompressed 8192×4096 RGBA `f32` EXR is 512 MiB.
pub const MAX_ENV_FILE_BYTES: u64 = 1 << 30;

/// Refuses (naming `origin`) a declared size beyond [`MAX_ENV_SIDE`] or [`MAX_ENV_TEXELS`].
fn check_declared_size(origin: &str, width: usize, height: usize) -> Result<()> {
    if width > MAX_ENV_SIDE || height > MAX_ENV_SIDE {
        return Err(Error::input(
            origin,
            format!("the header declares {width}x{height}, longer than the limit of {MAX_ENV_SIDE} texels a side"),
        ));
    }
    if width.saturating_mul(height) > MAX_ENV_TEXELS {
        return Err(Error::input(
            origin,
            format!("the header declares {width}x{height}, more than the limit of {MAX_ENV_TEXELS} texels (8192x4096)"),
        ));
    }
    Ok(())
}

/// What the loader changed or kept.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EnvStats {
    /// NaN or ±Inf texel channels, set to 0.
    pub non_finite: usize,
    /// Texels with a negative channel, kept.
    pub negative: usize,
    /// `Σ_neg |Y| Ω / Σ_all |Y| Ω` with `Y` the mean of RGB per texel and `Ω` its solid angle.
    pub negative_energy_fraction: f64,
}

#[derive(Clone, Debug)]
pub struct Environment {
    pub width: usize,
    pub height: usize,
    /// Row-major, row 0 at the top (`+y`).
    pub texels: Vec<[f32; 3]>,
    pub stats: EnvStats,
    /// The file it came from, for messages.
    pub origin: String,
}

/// One level of the mip chain, `RGBA` with alpha 1.
#[derive(Clone, Debug)]
pub struct MipLevel {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<[f32; 4]>,
}

/// Importance sampling over `w_ij = mean(|R|,|G|,|B|)_ij · sin θ_j` by CDF inversion.
#[derive(Clone, Debug)]
pub struct EnvDistribution {
    pub width: usize,
    pub height: usize,
    /// `H + 1` entries from 0 to 1 (all 0 for a black map).
    pub marginal_cdf: Vec<f32>,
    /// `H × (W + 1)`, each row from 0 to 1 (0 for a black row).
    pub conditional_cdf: Vec<f32>,
    /// `Σ w_ij`.
    pub total: f64,
    marginal: Vec<f64>,
    conditional: Vec<f64>,
    weights: Vec<f64>,
}

fn luminance(t: [f32; 3]) -> f64 {
    (t[0] as f64 + t[1] as f64 + t[2] as f64) / 3.0
}

fn abs_mean(t: [f32; 3]) -> f64 {
    (t[0].abs() as f64 + t[1].abs() as f64 + t[2].abs() as f64) / 3.0
}

fn row_sin(j: usize, h: usize) -> f64 {
    (PI * (j as f64 + 0.5) / h as f64).sin()
}

impl Environment {
    /// Loads `.exr` or `.hdr` (by extension).
    pub fn load(path: &Path) -> Result<Environment> {
        let origin = crate::fsio::show(path);
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("exr") | Some("hdr")) {
            return Err(Error::input(origin, "an environment map must be .exr or .hdr"));
        }
        let bytes = crate::fsio::read_limited(path, MAX_ENV_FILE_BYTES, "an environment map")?;
        let (w, h, texels) =
            if ext.as_deref() == Some("exr") { read_exr(&bytes, &origin)? } else { read_hdr(&bytes, &origin)? };
        Environment::from_texels(w, h, texels, &origin)
    }

    /// An EXR held in memory (the embedded default).
    pub fn from_exr_bytes(bytes: &[u8], origin: &str) -> Result<Environment> {
        let (w, h, texels) = read_exr(bytes, origin)?;
        Environment::from_texels(w, h, texels, origin)
    }

    /// Applies the texel policy and computes the statistics.
    pub fn from_texels(width: usize, height: usize, mut texels: Vec<[f32; 3]>, origin: &str) -> Result<Environment> {
        if width == 0 || height == 0 {
            return Err(Error::input(origin, format!("the image is empty ({width}x{height})")));
        }
        if texels.len() != width * height {
            return Err(Error::input(origin, format!("{} texels for {width}x{height}", texels.len())));
        }
        let mut stats = EnvStats::default();
        let (mut neg, mut all) = (0.0, 0.0);
        for (k, t) in texels.iter_mut().enumerate() {
            for c in t.iter_mut() {
                if !c.is_finite() {
                    *c = 0.0;
                    stats.non_finite += 1;
                }
            }
            let omega = row_sin(k / width, height);
            let y = luminance(*t).abs() * omega;
            all += y;
            if t.iter().any(|&c| c < 0.0) {
                stats.negative += 1;
                neg += y;
            }
        }
        stats.negative_energy_fraction = if all > 0.0 { neg / all } else { 0.0 };
        Ok(Environment { width, height, texels, stats, origin: origin.to_string() })
    }

    /// The map turned by `deg` degrees about the up axis (`+y`), counter-clockwise seen from above:
    /// what lay in direction `d` lies in `R_y(deg) d`, so every use of the map — the lighting, the key
    /// lights, the SH, the backdrop — turns with it. A turn about `y` moves every row along `u` by
    /// `deg / 360`: the texel at column `i` takes the map at `i + W·deg/360`, linearly between the two
    /// nearest columns (a copy, bit for bit, when that is a whole number of columns).
    pub fn rotated(&self, deg: f64) -> Environment {
        let w = self.width;
        let shift = (deg / 360.0).rem_euclid(1.0) * w as f64;
        let (whole, f) = (shift.floor() as usize, shift - shift.floor());
        let mut texels = Vec::with_capacity(self.texels.len());
        for row in self.texels.chunks_exact(w) {
            for i in 0..w {
                let a = row[(i + whole) % w];
                if f == 0.0 {
                    texels.push(a);
                } else {
                    let b = row[(i + whole + 1) % w];
                    texels.push(std::array::from_fn(|c| ((1.0 - f) * a[c] as f64 + f * b[c] as f64) as f32));
                }
            }
        }
        Environment { width: w, height: self.height, texels, stats: self.stats.clone(), origin: self.origin.clone() }
    }

    /// A uniform 16×8 map, for tests.
    pub fn constant(rgb: [f32; 3]) -> Environment {
        Environment::from_texels(16, 8, vec![rgb; 128], "constant").expect("a valid size")
    }

    /// docs/model.md, Frames and conventions: `u = fract(atan2(d.x, −d.z) / 2π)`, `v = acos(d.y) / π`.
    pub fn uv(dir: DVec3) -> (f64, f64) {
        let d = dir.normalize_or_zero();
        let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
        let u = if u >= 1.0 { 0.0 } else { u };
        (u, d.y.clamp(-1.0, 1.0).acos() / PI)
    }

    /// The inverse of [`Environment::uv`].
    pub fn direction(u: f64, v: f64) -> DVec3 {
        let (phi, theta) = (2.0 * PI * u, PI * v);
        DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
    }

    /// `(2π/W)(π/H) sin θ_j` at the centre of row `j`.
    pub fn texel_solid_angle(&self, row: usize) -> f64 {
        (2.0 * PI / self.width as f64) * (PI / self.height as f64) * row_sin(row, self.height)
    }

    fn at(&self, i: i64, j: i64) -> DVec3 {
        let i = i.rem_euclid(self.width as i64) as usize;
        let j = j.clamp(0, self.height as i64 - 1) as usize;
        let t = self.texels[j * self.width + i];
        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
    }

    /// Bilinear at level 0, exactly as a Vulkan sampler with `LINEAR` filtering, `u` repeating and
    /// `v` clamped to the edge: texel centres at `((i + ½)/W, (j + ½)/H)`.
    pub fn lookup(&self, dir: DVec3) -> DVec3 {
        let (u, v) = Environment::uv(dir);
        let x = u * self.width as f64 - 0.5;
        let y = v * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let top = self.at(i, j) * (1.0 - fx) + self.at(i + 1, j) * fx;
        let bottom = self.at(i, j + 1) * (1.0 - fx) + self.at(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The radiance along `dir` at mip level `lod` of `chain` (this map's [`Environment::mip_chain`]),
    /// as a Vulkan sampler with `LINEAR` filtering and mipmap mode returns it: `lod` clamped to the
    /// chain, the two levels around it blended linearly, each read bilinearly (`u` repeating, `v`
    /// clamped) — what the mesh view's backdrop shows at that blur.
    pub fn lookup_chain(chain: &[MipLevel], dir: DVec3, lod: f64) -> DVec3 {
        let lod = lod.clamp(0.0, (chain.len() - 1) as f64);
        let (k, t) = (lod.floor() as usize, lod - lod.floor());
        let (u, v) = Environment::uv(dir);
        let at = |m: &MipLevel| {
            let texel = |i: i64, j: i64| {
                let i = i.rem_euclid(m.width as i64) as usize;
                let j = j.clamp(0, m.height as i64 - 1) as usize;
                let t = m.texels[j * m.width + i];
                DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
            };
            let (x, y) = (u * m.width as f64 - 0.5, v * m.height as f64 - 0.5);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (i, j) = (x0 as i64, y0 as i64);
            let top = texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx;
            let bottom = texel(i, j + 1) * (1.0 - fx) + texel(i + 1, j + 1) * fx;
            top * (1.0 - fy) + bottom * fy
        };
        let a = at(&chain[k]);
        if t == 0.0 {
            a
        } else {
            a * (1.0 - t) + at(&chain[k + 1]) * t
        }
    }

    /// The full mip chain down to 1×1: level `k + 1` is `max(w/2, 1) × max(h/2, 1)`, each texel the
    /// solid-angle-weighted (sin θ) average of the level-`k` texels it covers, with fractional
    /// coverage where a size is odd. Level 0 is the map itself.
    pub fn mip_chain(&self) -> Vec<MipLevel> {
        let mut levels = vec![MipLevel {
            width: self.width,
            height: self.height,
            texels: self.texels.iter().map(|t| [t[0], t[1], t[2], 1.0]).collect(),
        }];
        loop {
            let src = levels.last().expect("level 0");
            if src.width == 1 && src.height == 1 {
                break;
            }
            let (dw, dh) = ((src.width / 2).max(1), (src.height / 2).max(1));
            let xs = coverage(src.width, dw);
            let ys = coverage(src.height, dh);
            let mut texels = vec![[0.0f32; 4]; dw * dh];
            for (y, row_w) in ys.iter().enumerate() {
                for (x, col_w) in xs.iter().enumerate() {
                    let (mut acc, mut wsum) = ([0.0f64; 3], 0.0);
                    for &(sj, wy) in row_w {
                        let s = row_sin(sj, src.height);
                        for &(si, wx) in col_w {
                            let w = wx * wy * s;
                            let t = src.texels[sj * src.width + si];
                            for c in 0..3 {
                                acc[c] += w * t[c] as f64;
                            }
                            wsum += w;
                        }
                    }
                    let inv = if wsum > 0.0 { 1.0 / wsum } else { 0.0 };
                    texels[y * dw + x] = [(acc[0] * inv) as f32, (acc[1] * inv) as f32, (acc[2] * inv) as f32, 1.0];
                }
            }
            levels.push(MipLevel { width: dw, height: dh, texels });
        }
        levels
    }

    /// Projection onto the real SH basis of [`sh_basis`] (l ≤ 2), `Σ L(d_j) Y_lm(d_j) Ω_j` over texel
    /// centres, in `f64`.
    pub fn sh9(&self) -> [DVec3; 9] {
        let mut c = [DVec3::ZERO; 9];
        for j in 0..self.height {
            let omega = self.texel_solid_angle(j);
            for i in 0..self.width {
                let d =
                    Environment::direction((i as f64 + 0.5) / self.width as f64, (j as f64 + 0.5) / self.height as f64);
                let t = self.texels[j * self.width + i];
                let l = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * omega;
                for (k, y) in sh_basis(d).iter().enumerate() {
                    c[k] += l * *y;
                }
            }
        }
        c
    }

    /// The direction of the brightest feature: the maximum of the luminance smoothed over 3×3 texels
    /// (solid-angle weighted, `u` wrapping) — so a lone hot texel or a negative ring does not win over
    /// a sun a few texels wide, and a large wall of lower radiance never does — refined to the
    /// radiance-weighted centroid of the texels around it above half that maximum.
    pub fn brightest_direction(&self) -> DVec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let lum = |i: i64, j: i64| -> f64 {
            let jj = j.clamp(0, h - 1) as usize;
            luminance(self.texels[jj * self.width + i.rem_euclid(w) as usize])
        };
        let smooth = |i: i64, j: i64| -> f64 {
            let (mut s, mut ws) = (0.0, 0.0);
            for dj in -1..=1 {
                let jj = j + dj;
                if jj < 0 || jj >= h {
                    continue;
                }
                let o = row_sin(jj as usize, self.height);
                for di in -1..=1 {
                    s += lum(i + di, jj) * o;
                    ws += o;
                }
            }
            if ws > 0.0 {
                s / ws
            } else {
                0.0
            }
        };
        let (mut best, mut bi, mut bj) = (f64::NEG_INFINITY, 0i64, 0i64);
        for j in 0..h {
            for i in 0..w {
                let v = smooth(i, j);
                if v > best {
                    (best, bi, bj) = (v, i, j);
                }
            }
        }
        let centre = |i: i64, j: i64| {
            Environment::direction((i as f64 + 0.5) / w as f64, (j.clamp(0, h - 1) as f64 + 0.5) / h as f64)
        };
        if !(best > 0.0) {
            return centre(bi, bj);
        }
        let mut acc = DVec3::ZERO;
        for dj in -4..=4 {
            for di in -4..=4 {
                let (i, j) = (bi + di, bj + dj);
                if j < 0 || j >= h {
                    continue;
                }
                let l = lum(i, j);
                if l >= 0.5 * best {
                    acc += centre(i, j) * l * row_sin(j as usize, self.height);
                }
            }
        }
        acc.try_normalize().unwrap_or_else(|| centre(bi, bj))
    }

    pub fn distribution(&self) -> EnvDistribution {
        let (w, h) = (self.width, self.height);
        let weights: Vec<f64> = (0..w * h).map(|k| abs_mean(self.texels[k]) * row_sin(k / w, h)).collect();
        let mut conditional = vec![0.0f64; h * (w + 1)];
        let mut rows = vec![0.0f64; h];
        for j in 0..h {
            let row = &weights[j * w..(j + 1) * w];
            let sum: f64 = row.iter().sum();
            rows[j] = sum;
            let c = &mut conditional[j * (w + 1)..(j + 1) * (w + 1)];
            let mut acc = 0.0;
            for i in 0..w {
                c[i] = if sum > 0.0 { acc / sum } else { 0.0 };
                acc += row[i];
            }
            c[w] = if sum > 0.0 { 1.0 } else { 0.0 };
        }
        let total: f64 = rows.iter().sum();
        let mut marginal = vec![0.0f64; h + 1];
        let mut acc = 0.0;
        for j in 0..h {
            marginal[j] = if total > 0.0 { acc / total } else { 0.0 };
            acc += rows[j];
        }
        marginal[h] = if total > 0.0 { 1.0 } else { 0.0 };
        EnvDistribution {
            width: w,
            height: h,
            marginal_cdf: marginal.iter().map(|&v| v as f32).collect(),
            conditional_cdf: conditional.iter().map(|&v| v as f32).collect(),
            total,
            marginal,
            conditional,
            weights,
        }
    }
}

/// For each of `dst` cells over `src` cells, the source cells it covers with their coverage.
fn coverage(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|d| {
            let (a, b) = (d as f64 * scale, (d + 1) as f64 * scale);
            (a.floor() as usize..(b.ceil() as usize).min(src))
                .map(|s| (s, (b.min(s as f64 + 1.0) - a.max(s as f64)).max(0.0)))
                .filter(|c| c.1 > 0.0)
                .collect()
        })
        .collect()
}

/// Largest `k` in `0..n` with `cdf[k] <= x` (0 when none).
fn upper(cdf: &[f64], n: usize, x: f64) -> usize {
    let (mut lo, mut hi) = (0usize, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if cdf[mid] <= x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

impl EnvDistribution {
    /// Samples a direction from `(u1, u2) ∈ [0,1)²`, with its pdf over solid angle. Row `j` = the
    /// largest with `marginal[j] ≤ u1`, `t = (u1 − marginal[j]) / (marginal[j+1] − marginal[j])`,
    /// `v = (j + t)/H`; column `i` likewise in row `j`'s conditional CDF with `u2`, `u = (i + s)/W`;
    /// `pdf = (w_ij / total) · W·H / (2π² sin θ(v))`. `None` for a black map.
    pub fn sample(&self, u1: f64, u2: f64) -> Option<(DVec3, f64)> {
        if !(self.total > 0.0) {
            return None;
        }
        let (w, h) = (self.width, self.height);
        let j = upper(&self.marginal, h, u1);
        let (c0, c1) = (self.marginal[j], self.marginal[j + 1]);
        let t = if c1 > c0 { ((u1 - c0) / (c1 - c0)).clamp(0.0, 1.0) } else { 0.5 };
        let row = &self.conditional[j * (w + 1)..(j + 1) * (w + 1)];
        let i = upper(row, w, u2);
        let (d0, d1) = (row[i], row[i + 1]);
        let s = if d1 > d0 { ((u2 - d0) / (d1 - d0)).clamp(0.0, 1.0) } else { 0.5 };
        let (u, v) = ((i as f64 + s) / w as f64, (j as f64 + t) / h as f64);
        let sin_t = (PI * v).sin();
        if !(sin_t > 0.0) {
            return None;
        }
        let pdf = self.weights[j * w + i] / self.total * (w * h) as f64 / (2.0 * PI * PI * sin_t);
        (pdf > 0.0).then(|| (Environment::direction(u, v), pdf))
    }

    /// The pdf over solid angle of [`Self::sample`] at `dir`.
    pub fn pdf(&self, dir: DVec3) -> f64 {
        if !(self.total > 0.0) {
            return 0.0;
        }
        let (u, v) = Environment::uv(dir);
        let (w, h) = (self.width, self.height);
        let i = ((u * w as f64) as usize).min(w - 1);
        let j = ((v * h as f64) as usize).min(h - 1);
        let d = dir.normalize_or_zero();
        let sin_t = (1.0 - d.y * d.y).max(0.0).sqrt();
        if !(sin_t > 0.0) {
            return 0.0;
        }
        self.weights[j * w + i] / self.total * (w * h) as f64 / (2.0 * PI * PI * sin_t)
    }
}

/// The real SH basis (l ≤ 2) in world coordinates: `0.282095`; `0.488603 (y, z, x)`;
/// `1.092548 xy, 1.092548 yz, 0.315392 (3z² − 1), 1.092548 xz, 0.546274 (x² − y²)`.
pub fn sh_basis(d: DVec3) -> [f64; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282095,
        0.488603 * y,
        0.488603 * z,
        0.488603 * x,
        1.092548 * x * y,
        1.092548 * y * z,
        0.315392 * (3.0 * z * z - 1.0),
        1.092548 * x * z,
        0.546274 * (x * x - y * y),
    ]
}

/// The irradiance `E(n) = Σ Â_l L_lm Y_lm(n)` of SH9 coefficients (Ramamoorthi & Hanrahan 2001,
/// `Â_0 = π`, `Â_1 = 2π/3`, `Â_2 = π/4`); the diffuse radiance is `ρ_d/π · E(n)`.
pub fn sh_irradiance(coeffs: &[DVec3; 9], n: DVec3) -> DVec3 {
    const A: [f64; 9] =
        [PI, 2.0 * PI / 3.0, 2.0 * PI / 3.0, 2.0 * PI / 3.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0];
    sh_basis(n).iter().zip(coeffs).zip(A).map(|((y, c), a)| *c * (a * y)).sum()
}

type Texels = (usize, usize, Vec<[f32; 3]>);

fn read_exr(bytes: &[u8], origin: &str) -> Result<Texels> {
    use exr::prelude::*;
    // The headers first: a declared size beyond the limits is refused before the reader allocates
    // anything for it.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| crate::error::Error::input(origin, format!("not a readable EXR file: {e}")))?;
    for h in meta.headers.iter() {
        check_declared_size(origin, h.layer_size.width(), h.layer_size.height())?;
    }
    struct Px {
        w: usize,
        data: Vec<[f32; 3]>,
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| Px { w: res.width(), data: vec![[0.0; 3]; res.width() * res.height()] },
            |px: &mut Px, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let k = pos.y() * px.w + pos.x();
                px.data[k] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| {
            crate::error::Error::input(origin, format!("not a readable EXR file with R, G, B channels: {e}"))
        })?;
    let size = image.layer_data.size;
    let px = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), px.data))
}

fn read_hdr(bytes: &[u8], origin: &str) -> Result<Texels> {
    use image::ImageDecoder as _;
    let bad = |e: image::ImageError| Error::input(origin, format!("not a readable Radiance HDR file: {e}"));
    let decoder = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes)).map_err(bad)?;
    let (w, h) = decoder.dimensions();
    check_declared_size(origin, w as usize, h as usize)?;
    let img = image::DynamicImage::from_decoder(decoder).map_err(bad)?.into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Ok((w, h, img.pixels().map(|p| p.0).collect()))
}
