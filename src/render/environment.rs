//! The environment on the GPU: the equirect texture with its full mip chain (filtered across the
//! `u` seam on the CPU, sampled with `u` repeating), the 9 SH irradiance coefficients, and the
//! importance-sampling tables. Built once per environment and kept until it changes.

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use crate::scene::env::Environment;
use crate::vk::{image, Buffer, Context, Image};
use crate::Result;

pub struct GpuEnvironment {
    pub texture: Image,
    pub sampler: vk::Sampler,
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

impl GpuEnvironment {
    pub fn new(ctx: &Context, env: &Environment) -> Result<GpuEnvironment> {
        let (w, h) = (env.width as u32, env.height as u32);
        let format = vk::Format::R32G32B32A32_SFLOAT;
        let linear = image::supports(ctx, format, vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        let levels = env.mip_chain();
        let mut bytes: Vec<u8> = Vec::new();
        let mut offsets = Vec::with_capacity(levels.len());
        for level in &levels {
            offsets.push(bytes.len() as u64);
            bytes.extend_from_slice(bytemuck::cast_slice(&level.texels));
        }
        let staging = Buffer::new(
            ctx,
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
            "env.staging",
        )?;
        let mut staging = staging;
        staging.write(&bytes);
        let texture = match Image::new(
            ctx,
            (w, h),
            format,
            levels.len() as u32,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            "env.texture",
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
        let mut made: Vec<Buffer> = Vec::new();
        let built = (|| -> Result<vk::Sampler> {
            let sh: Vec<f32> = irradiance_coefficients(&env.sh9()).iter().flat_map(|c| vec4(*c)).collect();
            made.push(storage(ctx, &sh, "env.sh")?);
            let (marginal, conditional, pdf) = sampling_tables(env);
            made.push(storage(ctx, &marginal, "env.marginal")?);
            made.push(storage(ctx, &conditional, "env.conditional")?);
            made.push(storage(ctx, &pdf, "env.pdf")?);
            image::equirect_sampler(ctx, linear)
        })();
        match built {
            Ok(sampler) => {
                let [sh, marginal, conditional, pdf]: [Buffer; 4] = match made.try_into() {
                    Ok(b) => b,
                    Err(_) => unreachable!("the closure pushed four buffers before succeeding"),
                };
                Ok(GpuEnvironment {
                    texture,
                    sampler,
                    sh,
                    marginal,
                    conditional,
                    pdf,
                    width: w,
                    height: h,
                    linear,
                    key: key(env),
                })
            }
            Err(e) => {
                for b in made {
                    b.destroy(ctx);
                }
                texture.destroy(ctx);
                Err(e)
            }
        }
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: no pending work uses the sampler.
        unsafe { ctx.raw().destroy_sampler(self.sampler, None) };
        self.texture.destroy(ctx);
        for b in [self.sh, self.marginal, self.conditional, self.pdf] {
            b.destroy(ctx);
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
