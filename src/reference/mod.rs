//! The CPU reference renderer: the same image as the GPU's, from the `f64` model. Mesh views are
//! rasterised by casting each pixel-centre ray at the triangles whose screen bounds hold it (so
//! coverage matches the GPU rasteriser up to ties on edges), then converged by multiple importance
//! sampling: per iteration one environment sample (CDF inversion over `|L| sin θ`) and one sample of
//! the material's mixture, balance heuristic. Canvas views are the exact point-lit canvas.
//!
//! Owns the CPU image type shared with the GPU renderer ([`Image`]), the hit buffer, both reference
//! images and the image metric [`relative_l1`]; writes no files (output is `imageio`'s) and imports
//! nothing from `ash`.

use glam::DVec3;
use rayon::prelude::*;

use crate::brdf::sampling::MaterialSampler;
use crate::brdf::Material;
use crate::brush::canvas::{normal_at, Canvas, Frame};
use crate::rng::{radical_inverse, Pcg32};
use crate::scene::camera::{Rays, NEAR};
use crate::scene::{Camera, Environment, Mesh};

/// The memory budget of a reference image, in pixels: 4096×4096. The reference keeps per pixel a
/// hit record (64 bytes), the band buffers while casting (up to 72), the rows and the image (16
/// each), about 170 bytes at the peak, so the largest image stays under 3 GB.
pub const MAX_PIXELS: u64 = 4096 * 4096;

/// The most samples per pixel of a reference: the same number as the GPU's limit (`render::MAX_SPP`,
/// not imported: this module knows nothing of the GPU), so the quasi-random table (40 bytes a
/// sample) stays at 2.6 MB; at 1024 spp a 512² reference takes minutes on two cores already.
pub const MAX_SPP: u32 = 1 << 16;

/// Refuses (naming the flag) a reference image beyond [`MAX_PIXELS`] or [`MAX_SPP`], before
/// anything is allocated.
pub fn check_limits(width: u32, height: u32, spp: u32) -> crate::Result<()> {
    crate::imageio::check_image_limits((width, height, spp), (MAX_PIXELS, MAX_SPP), "4096x4096", "a reference")
}

/// A linear RGBA image, row-major from the top; alpha 1 on the object, 0 on the background.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// Where a pixel-centre ray first meets the mesh.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub position: DVec3,
    /// Interpolated, unit.
    pub normal: DVec3,
    pub triangle: u32,
}

pub struct HitBuffer {
    pub width: u32,
    pub height: u32,
    pub hits: Vec<Option<Hit>>,
}

/// Rows per band when binning triangles.
const BAND: usize = 16;

/// Möller–Trumbore in `f64`: distance and barycentrics `(b1, b2)` of the hit, if any. Edges and
/// vertices count as inside (a ray through a shared edge hits both triangles at the same distance,
/// so there are no cracks); a ray within 1e-12 rad of the triangle's plane misses it, and so does a
/// hit nearer than [`NEAR`] (the GPU's near plane).
fn intersect(o: DVec3, d: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    // |det| = |d · (e1 × e2)|: the sine of the ray's angle with the plane times twice the area.
    if !(det.abs() > 1e-12 * e1.cross(e2).length()) {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > NEAR).then_some((t, u, v))
}

/// The first hit of every pixel-centre ray, row-major from the top. Each triangle is projected to
/// the screen and binned into bands of 16 rows by its bounding box (the whole image when a vertex is
/// not in front of the near plane); bands run in parallel, and each pixel centre in a triangle's box
/// is intersected with it (`intersect`), keeping the nearest (the first triangle in index order on
/// ties). The normal is the barycentric interpolation of the vertex normals, normalised (the
/// triangle's geometric normal where they cancel).
pub fn rasterize(mesh: &Mesh, camera: &Camera, width: u32, height: u32) -> HitBuffer {
    let (w, h) = (width as usize, height as usize);
    if w == 0 || h == 0 {
        return HitBuffer { width, height, hits: Vec::new() };
    }
    let rays = Rays::new(camera, width, height);
    let (right, up, forward) = camera.basis();
    let t = (camera.fov_deg.to_radians() / 2.0).tan();
    let aspect = w as f64 / h as f64;
    let pos: Vec<DVec3> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    // Screen bounds of each triangle in pixels (the whole image when a vertex is behind the eye).
    let project = |p: DVec3| -> Option<(f64, f64)> {
        let v = p - camera.eye;
        let z = v.dot(forward);
        (z > NEAR).then(|| {
            let x = v.dot(right) / (z * t * aspect);
            let y = -v.dot(up) / (z * t);
            ((x + 1.0) * w as f64 / 2.0, (y + 1.0) * h as f64 / 2.0)
        })
    };
    let bands = h.div_ceil(BAND);
    let mut binned: Vec<Vec<(u32, [usize; 4])>> = vec![Vec::new(); bands];
    for (k, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let ps: Option<Vec<(f64, f64)>> = tri.iter().map(|&i| project(pos[i as usize])).collect();
        let (x0, x1, y0, y1) = match ps {
            Some(ps) => {
                let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                for (x, y) in ps {
                    (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                }
                // Pixel centres i + ½ within [x0, x1], one pixel of slack for rounding.
                let lo = |v: f64| (v - 1.5).floor().max(0.0) as usize;
                let hi = |v: f64, n: usize| ((v + 0.5).ceil().max(0.0) as usize).min(n);
                if x1 < -1.0 || y1 < -1.0 || x0 > w as f64 + 1.0 || y0 > h as f64 + 1.0 {
                    continue;
                }
                (lo(x0), hi(x1, w), lo(y0), hi(y1, h))
            }
            None => (0, w, 0, h),
        };
        if x0 >= x1 || y0 >= y1 {
            continue;
        }
        for band in (y0 / BAND)..y1.div_ceil(BAND).min(bands) {
            binned[band].push((k as u32, [x0, x1, y0, y1]));
        }
    }
    let hits: Vec<Option<Hit>> = (0..bands)
        .into_par_iter()
        .flat_map_iter(|band| {
            let rows = band * BAND..((band + 1) * BAND).min(h);
            let mut out: Vec<Option<(f64, Hit)>> = vec![None; rows.len() * w];
            let dirs: Vec<DVec3> =
                rows.clone().flat_map(|j| (0..w).map(move |i| rays.at(i as f64 + 0.5, j as f64 + 0.5))).collect();
            for &(k, [x0, x1, y0, y1]) in &binned[band] {
                let tri = &mesh.indices[3 * k as usize..3 * k as usize + 3];
                let (a, b, c) = (pos[tri[0] as usize], pos[tri[1] as usize], pos[tri[2] as usize]);
                for j in y0.max(rows.start)..y1.min(rows.end) {
                    for i in x0..x1 {
                        let d = dirs[(j - rows.start) * w + i];
                        let Some((dist, u, v)) = intersect(camera.eye, d, a, b, c) else { continue };
                        let slot = &mut out[(j - rows.start) * w + i];
                        if slot.is_some_and(|s| s.0 <= dist) {
                            continue;
                        }
                        let n = (mesh.normals[tri[0] as usize].as_dvec3() * (1.0 - u - v)
                            + mesh.normals[tri[1] as usize].as_dvec3() * u
                            + mesh.normals[tri[2] as usize].as_dvec3() * v)
                            .try_normalize()
                            .unwrap_or_else(|| (b - a).cross(c - a).normalize());
                        *slot = Some((dist, Hit { position: camera.eye + d * dist, normal: n, triangle: k }));
                    }
                }
            }
            out.into_iter().map(|s| s.map(|s| s.1))
        })
        .collect();
    HitBuffer { width, height, hits }
}

/// The QMC sequence: per sample Halton in bases 2, 3 (environment) and 5, 7, 11 (BRDF), from index 1.
fn sequence(spp: u32) -> Vec<[f64; 5]> {
    (1..=spp as u64).map(|i| [2, 3, 5, 7, 11].map(|b| radical_inverse(i, b))).collect()
}

/// The converged mesh image: background = the environment seen along each ray (alpha 0); object
/// (alpha 1) = the MIS estimate of `∫ f(ω_i, ω_o) L(ω_i) cos θ_i dω_i`, black where the view is
/// below the shading horizon. Iteration `s` of `spp` (at least one) takes one environment sample
/// (Halton bases 2, 3 at index `s + 1`) and one material sample (bases 5, 7, 11), each weighted by
/// the balance heuristic `f L cos / (p_env + p_brdf)`, both pdfs over solid angle. Each pixel's five
/// coordinates are Cranley–Patterson rotated by five `next_f64` draws of `Pcg32::new(pixel index,
/// 0x5eed)` (pixel index `j·W + i`), so the image is deterministic and the same at any thread
/// count. `L` is [`Environment::lookup`], signed. A non-finite contribution is a bug: it fails a
/// `debug_assert` and is dropped in release builds. With `progress` an `indicatif` bar counts rows
/// on stderr.
#[allow(clippy::too_many_arguments)]
pub fn render_mesh(
    material: &Material,
    env: &Environment,
    mesh: &Mesh,
    camera: &Camera,
    width: u32,
    height: u32,
    spp: u32,
    progress: bool,
) -> Image {
    render_mesh_watched(material, env, mesh, camera, width, height, spp, progress, &|| false).expect("never stopped")
}

/// [`render_mesh`], polling `stop` before each row: `None` as soon as it returns true.
#[allow(clippy::too_many_arguments)]
pub fn render_mesh_watched(
    material: &Material,
    env: &Environment,
    mesh: &Mesh,
    camera: &Camera,
    width: u32,
    height: u32,
    spp: u32,
    progress: bool,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Image> {
    let hits = rasterize(mesh, camera, width, height);
    let dist = env.distribution();
    let seq = sequence(spp.max(1));
    let w = width as usize;
    let rays = Rays::new(camera, width.max(1), height.max(1));
    let bar = progress.then(|| {
        let b = indicatif::ProgressBar::new(height as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("reference {bar:40} {pos}/{len} rows, {eta} left")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let rows: Option<Vec<Vec<[f32; 4]>>> = (0..height as usize)
        .into_par_iter()
        .map(|j| {
            if stop() {
                return None;
            }
            let row = (0..w)
                .map(|i| {
                    // Polled per pixel: a pixel of the largest sample count takes well under a second.
                    if stop() {
                        return None;
                    }
                    let pixel = j * w + i;
                    match hits.hits[pixel] {
                        None => {
                            let l = env.lookup(rays.at(i as f64 + 0.5, j as f64 + 0.5));
                            Some([l.x as f32, l.y as f32, l.z as f32, 0.0])
                        }
                        Some(hit) => {
                            let l = shade(material, env, &dist, &seq, camera.eye, hit, pixel as u64);
                            Some([l.x as f32, l.y as f32, l.z as f32, 1.0])
                        }
                    }
                })
                .collect::<Option<Vec<_>>>()?;
            if let Some(b) = &bar {
                b.inc(1);
            }
            Some(row)
        })
        .collect();
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Some(Image { width, height, pixels: rows?.concat() })
}

fn shade(
    material: &Material,
    env: &Environment,
    dist: &crate::scene::env::EnvDistribution,
    seq: &[[f64; 5]],
    eye: DVec3,
    hit: Hit,
    pixel: u64,
) -> DVec3 {
    let frame = Frame::from_normal(hit.normal);
    let wo = frame.to_local((eye - hit.position).normalize());
    if !(wo.z > 0.0) {
        return DVec3::ZERO;
    }
    let sampler = MaterialSampler::new(material, wo);
    let mut rng = Pcg32::new(pixel, 0x5eed);
    let rot: [f64; 5] = std::array::from_fn(|_| rng.next_f64());
    let f = |wi: DVec3| DVec3::from_array(sampler.eval(wi));
    let mut sum = DVec3::ZERO;
    for q in seq {
        let u: [f64; 5] = std::array::from_fn(|k| (q[k] + rot[k]).fract());
        if let Some((dir, pe)) = dist.sample(u[0], u[1]) {
            let wi = frame.to_local(dir);
            if wi.z > 0.0 {
                let pb = sampler.pdf(wi);
                let c = f(wi) * env.lookup(dir) * wi.z / (pe + pb);
                debug_assert!(c.is_finite(), "environment sample {c}");
                if c.is_finite() {
                    sum += c;
                }
            }
        }
        // Ward's half-vector sampling takes its first coordinate in (0, 1]: 1 − u, same sequence.
        if let Some(wi) = sampler.sample(u[2], 1.0 - u[3], u[4]) {
            let dir = frame.to_world(wi);
            let (pb, pe) = (sampler.pdf(wi), dist.pdf(dir));
            if pb + pe > 0.0 {
                let c = f(wi) * env.lookup(dir) * wi.z / (pe + pb);
                debug_assert!(c.is_finite(), "BRDF sample {c}");
                if c.is_finite() {
                    sum += c;
                }
            }
        }
    }
    sum / seq.len() as f64
}

/// The canvas view: the exact point-lit canvas of `src/brush` at pixel centres, alpha 1 on the sphere.
pub fn render_canvas(material: &Material, canvas: &Canvas, width: u32, height: u32) -> Image {
    let (w, h) = (width as usize, height as usize);
    let pixels = (0..w * h)
        .into_par_iter()
        .map(|p| {
            let (cu, cv) = (((p % w) as f64 + 0.5) / w as f64, ((p / w) as f64 + 0.5) / h as f64);
            match normal_at(cu, cv) {
                Some(_) => {
                    let r = canvas.radiance(material, cu, cv);
                    [r[0] as f32, r[1] as f32, r[2] as f32, 1.0]
                }
                None => [0.0; 4],
            }
        })
        .collect();
    Image { width, height, pixels }
}

/// `Σ|a − b| / Σ|b|` over RGB of the pixels both images cover (alpha ≥ ½); `None` when none is, or
/// when the sizes differ. Where `b` is black on all of them the result is 0 if `a` is too and
/// infinite otherwise.
pub fn relative_l1(a: &Image, b: &Image) -> Option<f64> {
    if (a.width, a.height) != (b.width, b.height) || a.pixels.len() != b.pixels.len() {
        return None;
    }
    let (mut num, mut den, mut n) = (0.0, 0.0, 0usize);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        if p[3] >= 0.5 && q[3] >= 0.5 {
            for c in 0..3 {
                num += (p[c] as f64 - q[c] as f64).abs();
                den += (q[c] as f64).abs();
            }
            n += 1;
        }
    }
    (n > 0).then(|| if num == 0.0 { 0.0 } else { num / den })
}
