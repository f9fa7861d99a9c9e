//! The environment on the GPU: the equirect texture with its full mip chain (filtered across the
//! `u` seam on the CPU, sampled with `u` repeating), the 9 SH irradiance coefficients, and the
//! importance-sampling tables, and the key lights split off the map with the residual's own texture and
//! SH (the `key` estimator). Built once per environment and kept until it changes.

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use super::gpu;
use super::plan::KeyLightSet;
use crate::scene::env::{Environment, MipLevel};
use crate::scene::keylight::{self, KeyLights};
use crate::vk::{image, Buffer, Context, Image};
use crate::Result;

mod summary;
pub use summary::KeyLightSummary;

/// How the `key` estimator's lobe passes read the residual's mip chain: bilinear within the nearest
/// level, not between two. Their lod is already the sample's own footprint (`lobe::KEY_LOD_BIAS`),
/// and on llvmpipe a trilinear `RGBA32F` lookup is most of a sample's cost: one level makes the
/// lobe passes cheaper for a small rise of the error at 8 spp (none on the filtered rough lobes),
/// more at 1 spp on the sharp lobes. Nearest-texel lookups as well are cheaper still but raise the
/// error far more than they save (docs/renderer.md, Alternatives measured and rejected).
pub const KEY_MIPMAP: vk::SamplerMipmapMode = vk::SamplerMipmapMode::NEAREST;

pub struct GpuEnvironment {
    pub texture: Image,
    pub sampler: vk::Sampler,
    /// The `key` estimator's lobe passes' sampler: bilinear within the nearest mip level
    /// ([`KEY_MIPMAP`]).
    pub key_sampler: vk::Sampler,
    /// `Â_l · L_lm`, 9 × `vec4`.
    pub sh: Buffer,
    pub marginal: Buffer,
    pub conditional: Buffer,
    pub pdf: Buffer,
    pub width: u32,
    pub height: u32,
    /// Whether the texture is filtered linearly (it is wherever `RGBA32F` supports it).
    pub linear: bool,
    /// What this was built from (to rebuild only when the environment changes).
    pub key: (String, usize, usize, u64),
    /// The map's key lights, when it has any.
    pub keys: Option<GpuKeyLights>,
    pub key_summary: KeyLightSummary,
}

/// Identifies an environment's contents cheaply: origin, size and a hash of the texels.
pub fn key(env: &Environment) -> (String, usize, usize, u64) {
    let mut h: u64 = 0xcbf29ce484222325;
    for t in env.texels.iter().step_by(7) {
        for c in t {
            h = (h ^ c.to_bits() as u64).wrapping_mul(0x100000001b3);
        }
    }
    (env.origin.clone(), env.width, env.height, h)
}

fn vec4(c: DVec3) -> [f32; 4] {
    [c.x as f32, c.y as f32, c.z as f32, 0.0]
}

/// The SH coefficients of the irradiance: `Â_l · L_lm` with `Â_0 = π`, `Â_1 = 2π/3`, `Â_2 = π/4`
/// (Ramamoorthi & Hanrahan 2001), so that `E(n) = Σ Â_l L_lm Y_lm(n)`.
pub fn irradiance_coefficients(l: &[DVec3; 9]) -> [DVec3; 9] {
    use std::f64::consts::PI;
    let a = [PI, 2.0 * PI / 3.0, 2.0 * PI / 3.0, 2.0 * PI / 3.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0, PI / 4.0];
    std::array::from_fn(|i| l[i] * a[i])
}

fn storage(ctx: &Context, data: &[f32], name: &str) -> Result<Buffer> {
    Buffer::upload(ctx, bytemuck::cast_slice(data), vk::BufferUsageFlags::STORAGE_BUFFER, name)
}

/// Quadrature points as the lobe pass's uniform light set (`gpu::light_set_bytes`).
fn point_set(ctx: &Context, rows: &[[f32; 8]], name: &str) -> Result<Buffer> {
    Buffer::upload(ctx, &gpu::light_set_bytes(rows), vk::BufferUsageFlags::UNIFORM_BUFFER, name)
}

/// The key lights of a map on the GPU (the `key` estimator): the residual map (lights replaced by
/// their local background) with its mip chain and SH, and the lights' cones. Absent when the map has
/// no key light.
pub struct GpuKeyLights {
    pub residual: Image,
    /// `Â_l · L_lm` of the residual, 9 × `vec4`.
    pub sh: Buffer,
    /// `uvec4(lights, 0, 0, 0)`, then per light `vec4(direction, cos extent)` and
    /// `vec4(power rgb, extent)` (the extent in radians: the reach test of
    /// `glsl/include/lobe_lights.glsl`).
    pub cones: Buffer,
    /// Per texel of the map: the lights' radiance (rgb, read nearest) and the pdf over `(u, v)` of
    /// [`keylight::LightSampling`] (alpha): one fetch gives a BRDF sample both.
    pub texels: Image,
    /// Where each frame's light samples come from.
    pub sampling: keylight::LightSampling,
    /// The lights' quadrature points (`keylight::point_table`), for lobes much wider than the lights.
    pub points: Buffer,
    /// The wide lights' buffers, if the map has any.
    pub wide: Option<GpuWideLights>,
    /// The key and wide lights as the frame's plan sees them, with their tiles.
    pub set: KeyLightSet,
}

/// The wide lights on the GPU: the residual map without them (and without the key lights), and
/// the key and wide lights' quadrature points together, for the lobes that see all of them as
/// points or as tiles.
pub struct GpuWideLights {
    pub residual: Image,
    pub points: Buffer,
    /// How many points `points` holds (four per light).
    pub count: u32,
    /// [`cone_table`] of the key and wide lights (`WideLightSet::all`), for the reach test of a
    /// lobe that sees them all as tiles, and with [`GpuWideLights::sh`] for the energy compensation
    /// pass; `None` where they are more than the test's slots (`WideLightSet::reach_testable`): such
    /// a lobe takes no reach test.
    pub cones: Option<Buffer>,
    /// `Â_l · L_lm` of `residual`, 9 × `vec4`, as [`GpuKeyLights::sh`].
    pub sh: Buffer,
}

impl GpuWideLights {
    fn new(ctx: &Context, keys: &KeyLights, wide: &keylight::WideLights) -> Result<GpuWideLights> {
        let all: Vec<keylight::KeyLight> = keys.lights.iter().chain(&wide.lights).cloned().collect();
        let residual = upload_texture(ctx, &wide.residual, "keylights.wide.residual")?;
        let points = match point_set(ctx, &keylight::point_table(&all), "keylights.wide.points") {
            Ok(points) => points,
            Err(e) => {
                residual.destroy(ctx);
                return Err(e);
            }
        };
        let sh = match sh_buffer(ctx, &wide.residual, "keylights.wide.sh") {
            Ok(sh) => sh,
            Err(e) => {
                residual.destroy(ctx);
                points.destroy(ctx);
                return Err(e);
            }
        };
        let cones = if all.len() <= crate::scene::keylight::MAX_LIGHTS {
            match storage(ctx, &cone_table(&all), "keylights.wide.cones") {
                Ok(c) => Some(c),
                Err(e) => {
                    residual.destroy(ctx);
                    points.destroy(ctx);
                    sh.destroy(ctx);
                    return Err(e);
                }
            }
        } else {
            None
        };
        let count = 4 * all.len() as u32;
        Ok(GpuWideLights { residual, points, count, cones, sh })
    }

    fn destroy(self, ctx: &Context) {
        self.residual.destroy(ctx);
        self.points.destroy(ctx);
        self.sh.destroy(ctx);
        if let Some(c) = self.cones {
            c.destroy(ctx);
        }
    }
}

/// Uploads `env`'s mip chain into a new sampled image.
fn upload_texture(ctx: &Context, env: &Environment, name: &str) -> Result<Image> {
    upload_levels(ctx, &env.mip_chain(), name)
}

/// Uploads mip levels (level 0 first) into a new sampled image.
fn upload_levels(ctx: &Context, levels: &[MipLevel], name: &str) -> Result<Image> {
    let (w, h) = (levels[0].width as u32, levels[0].height as u32);
    let mut bytes: Vec<u8> = Vec::new();
    let mut offsets = Vec::with_capacity(levels.len());
    for level in levels {
        offsets.push(bytes.len() as u64);
        bytes.extend_from_slice(bytemuck::cast_slice(&level.texels));
    }
    let mut staging =
        Buffer::new(ctx, bytes.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu, name)?;
    staging.write(&bytes);
    let texture = match Image::new(
        ctx,
        (w, h),
        FORMAT,
        levels.len() as u32,
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        name,
    ) {
        Ok(t) => t,
        Err(e) => {
            staging.destroy(ctx);
            return Err(e);
        }
    };
    let uploaded = ctx.commands.run(&ctx.device, |cmd| {
        texture.record_upload(ctx, cmd, &staging, &offsets);
        Ok(())
    });
    staging.destroy(ctx);
    if let Err(e) = uploaded {
        texture.destroy(ctx);
        return Err(e);
    }
    Ok(texture)
}

const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

fn sh_buffer(ctx: &Context, env: &Environment, name: &str) -> Result<Buffer> {
    let sh: Vec<f32> = irradiance_coefficients(&env.sh9()).iter().flat_map(|c| vec4(*c)).collect();
    storage(ctx, &sh, name)
}

/// Destroys `made` when `result` is an error (the buffers a constructor made before failing).
fn or_destroy<T>(ctx: &Context, result: Result<T>, made: Vec<Buffer>) -> Result<(T, Vec<Buffer>)> {
    match result {
        Ok(t) => Ok((t, made)),
        Err(e) => {
            for b in made {
                b.destroy(ctx);
            }
            Err(e)
        }
    }
}

impl GpuKeyLights {
    /// The light samples of frame `seed` (`M = samples`): frame 0 takes the middle of each stratum,
    /// a later frame shifts the strata and the points within texels by a hash of its seed.
    pub fn frame_samples(&self, samples: u32, seed: u32) -> Vec<[f32; 8]> {
        let shift = if seed == 0 {
            [0.5, 0.0, 0.0]
        } else {
            let mut h = crate::rng::Pcg32::new(u64::from(seed), 0x6b65_796c_6967_6874);
            [h.next_f64(), h.next_f64(), h.next_f64()]
        };
        self.sampling.frame_samples(samples.max(1), shift)
    }

    fn new(ctx: &Context, env: &Environment, keys: &KeyLights) -> Result<GpuKeyLights> {
        let residual = upload_texture(ctx, &keys.residual, "keylights.residual")?;
        let mut made: Vec<Buffer> = Vec::new();
        let built = (|| -> Result<keylight::LightSampling> {
            made.push(sh_buffer(ctx, &keys.residual, "keylights.sh")?);
            let Some(sampling) = keys.sampling(env) else {
                return Err(crate::Error::input(env.origin.clone(), "the key lights carry no energy"));
            };
            made.push(storage(ctx, &cone_table(&keys.lights), "keylights.cones")?);
            made.push(point_set(ctx, &keylight::point_table(&keys.lights), "keylights.points")?);
            Ok(sampling)
        })();
        let texels = built.and_then(|sampling| {
            let map = keys.light_map(env);
            let texels = map.iter().zip(&sampling.pdf_uv).map(|(l, &p)| [l[0], l[1], l[2], p]).collect();
            let level = MipLevel { width: env.width, height: env.height, texels };
            upload_levels(ctx, &[level], "keylights.texels").map(|t| (t, sampling))
        });
        let ((texels, sampling), made) = match or_destroy(ctx, texels, made) {
            Ok(r) => r,
            Err(e) => {
                residual.destroy(ctx);
                return Err(e);
            }
        };
        let [sh, cones, points]: [Buffer; 3] = match made.try_into() {
            Ok(b) => b,
            Err(_) => unreachable!("the closure pushed three buffers before succeeding"),
        };
        let set = KeyLightSet::new(keys.lights.clone(), keys.wide.as_ref().map(|w| w.lights.clone()));
        let mut gpu = GpuKeyLights { residual, sh, cones, texels, sampling, points, wide: None, set };
        if let Some(w) = &keys.wide {
            match GpuWideLights::new(ctx, keys, w) {
                Ok(g) => gpu.wide = Some(g),
                Err(e) => {
                    gpu.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(gpu)
    }

    fn destroy(self, ctx: &Context) {
        self.residual.destroy(ctx);
        self.texels.destroy(ctx);
        for b in [self.sh, self.cones, self.points] {
            b.destroy(ctx);
        }
        if let Some(w) = self.wide {
            w.destroy(ctx);
        }
    }
}

/// The `Lights` buffer of `lobe.comp`, `compact.comp` and `diffuse.comp` (see
/// [`GpuKeyLights::cones`]) for one light or more: the count, then `keylight::MAX_LIGHTS` lights (at
/// least), the last repeated past the count, so that the shaders
/// read them at constant indices (`lobe.comp`, `diffuse.glsl`; the lights past the count add no
/// power there and repeat a cone the reach test already has).
pub fn cone_table(lights: &[crate::scene::keylight::KeyLight]) -> Vec<f32> {
    debug_assert!(!lights.is_empty(), "a cone table without a light to repeat");
    let mut out: Vec<f32> = vec![f32::from_bits(lights.len() as u32), 0.0, 0.0, 0.0];
    let padding = crate::scene::keylight::MAX_LIGHTS.saturating_sub(lights.len());
    for l in lights.iter().chain(std::iter::repeat_n(lights.last(), padding).flatten()) {
        let d = l.direction;
        out.extend_from_slice(&[d.x as f32, d.y as f32, d.z as f32, l.extent.cos() as f32]);
        out.extend_from_slice(&[l.power[0] as f32, l.power[1] as f32, l.power[2] as f32, l.extent as f32]);
    }
    out
}

impl GpuEnvironment {
    pub fn new(ctx: &Context, env: &Environment) -> Result<GpuEnvironment> {
        let (w, h) = (env.width as u32, env.height as u32);
        let linear = image::supports(ctx, FORMAT, vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        let texture = upload_texture(ctx, env, "env.texture")?;
        let mut made: Vec<Buffer> = Vec::new();
        let built = (|| -> Result<(vk::Sampler, vk::Sampler)> {
            made.push(sh_buffer(ctx, env, "env.sh")?);
            let (marginal, conditional, pdf) = sampling_tables(env);
            made.push(storage(ctx, &marginal, "env.marginal")?);
            made.push(storage(ctx, &conditional, "env.conditional")?);
            made.push(storage(ctx, &pdf, "env.pdf")?);
            let sampler = image::equirect_sampler(ctx, linear, vk::SamplerMipmapMode::LINEAR, "env.sampler")?;
            match image::equirect_sampler(ctx, linear, KEY_MIPMAP, "env.key_sampler") {
                Ok(key) => Ok((sampler, key)),
                Err(e) => {
                    // SAFETY: never used.
                    unsafe { ctx.raw().destroy_sampler(sampler, None) };
                    Err(e)
                }
            }
        })();
        let ((sampler, key_sampler), made) = match or_destroy(ctx, built, made) {
            Ok(r) => r,
            Err(e) => {
                texture.destroy(ctx);
                return Err(e);
            }
        };
        let [sh, marginal, conditional, pdf]: [Buffer; 4] = match made.try_into() {
            Ok(b) => b,
            Err(_) => unreachable!("the closure pushed four buffers before succeeding"),
        };
        let detected = keylight::detect(env);
        let mut out = GpuEnvironment {
            texture,
            sampler,
            key_sampler,
            sh,
            marginal,
            conditional,
            pdf,
            width: w,
            height: h,
            linear,
            key: key(env),
            keys: None,
            key_summary: KeyLightSummary {
                lights: detected.lights.clone(),
                share: detected.share,
                threshold: detected.threshold,
                wide: detected.wide.as_ref().map_or(Vec::new(), |w| w.lights.clone()),
                wide_share: detected.wide.as_ref().map_or(0.0, |w| w.share),
            },
        };
        if !detected.lights.is_empty() {
            match GpuKeyLights::new(ctx, env, &detected) {
                Ok(k) => out.keys = Some(k),
                Err(e) => {
                    out.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(out)
    }

    /// The texture and SH the key estimator's residual passes read: the residual's where the map
    /// has key lights, the map's own otherwise.
    pub fn residual(&self) -> (&Image, &Buffer) {
        match &self.keys {
            Some(k) => (&k.residual, &k.sh),
            None => (&self.texture, &self.sh),
        }
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: no pending work uses the sampler.
        unsafe {
            ctx.raw().destroy_sampler(self.sampler, None);
            ctx.raw().destroy_sampler(self.key_sampler, None);
        }
        self.texture.destroy(ctx);
        for b in [self.sh, self.marginal, self.conditional, self.pdf] {
            b.destroy(ctx);
        }
        if let Some(k) = self.keys {
            k.destroy(ctx);
        }
    }
}

/// The GPU's tables: the marginal CDF over rows (H+1), the conditional CDFs per row (H × (W+1)) and
/// the per-texel pdf over `(u, v)` (`W·H · p_ij`), all zero for an all-black map.
pub fn sampling_tables(env: &Environment) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let d = env.distribution();
    let (w, h) = (d.width, d.height);
    if !(d.total > 0.0) {
        return (vec![0.0; h + 1], vec![0.0; h * (w + 1)], vec![0.0; w * h]);
    }
    let mut pdf = vec![0.0f32; w * h];
    for j in 0..h {
        let pj = d.marginal_cdf[j + 1] as f64 - d.marginal_cdf[j] as f64;
        for i in 0..w {
            let row = j * (w + 1);
            let pi = d.conditional_cdf[row + i + 1] as f64 - d.conditional_cdf[row + i] as f64;
            pdf[j * w + i] = (pj * pi * (w * h) as f64) as f32;
        }
    }
    (d.marginal_cdf.clone(), d.conditional_cdf.clone(), pdf)
}
