//! The evaluation pass: `f(ω_i, ω_o)` in `f32` on the GPU for a list of direction pairs, with the
//! same GLSL as every shading pass — what the stability report compares with the `f64` model.

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use crate::brdf::Material;
use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

pub struct EvalPass {
    pipeline: Pipeline,
}

impl EvalPass {
    pub fn new(ctx: &Context) -> Result<EvalPass> {
        EvalPass::from_spirv(ctx, crate::spirv!("eval.comp"), "eval")
    }

    /// The same pass from other SPIR-V with `eval.comp`'s interface (binding 0 the pairs, 1 the
    /// values, 2 the material buffer and 3 its compensation tables, which it may leave unused; push
    /// constant `uint count`; 64
    /// invocations a group): how the tests run exported GLSL (`brdf-shop export`) on the device.
    pub fn from_spirv(ctx: &Context, spv: &[u8], name: &str) -> Result<EvalPass> {
        Ok(EvalPass { pipeline: Pipeline::compute(ctx, spv, name, 4, &[])? })
    }

    /// `f` per pair `(ω_i, ω_o)` (local frame, not necessarily unit: the shader uses them as given).
    pub fn run(&self, ctx: &Context, material: &Material, pairs: &[(DVec3, DVec3)]) -> Result<Vec<[f32; 3]>> {
        let n = pairs.len().max(1);
        let data: Vec<[f32; 4]> = pairs
            .iter()
            .flat_map(|(wi, wo)| [super::gpu::vec4(*wi, 0.0), super::gpu::vec4(*wo, 0.0)])
            .chain(std::iter::repeat_n([0.0; 4], if pairs.is_empty() { 2 } else { 0 }))
            .collect();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut made: Vec<Buffer> = Vec::new();
        let mut pool = None;
        let result = (|| -> Result<Vec<[f32; 3]>> {
            made.push(Buffer::upload(ctx, bytemuck::cast_slice(&data), usage, "eval.pairs")?);
            made.push(Buffer::new(ctx, 16 * n as u64, usage, MemoryLocation::GpuToCpu, "eval.values")?);
            made.push(Buffer::upload(ctx, &super::gpu::material_bytes(material), usage, "eval.material")?);
            let tables = material.tables().unwrap_or_default();
            let tables: Vec<Option<&crate::brdf::compensation::Table>> = tables.iter().map(|t| Some(&**t)).collect();
            let words = crate::brdf::compensation::words(&tables);
            made.push(Buffer::upload(ctx, bytemuck::cast_slice(&words), usage, "eval.tables")?);
            let p = descriptor::pool(ctx, 1, "eval.descriptors")?;
            pool = Some(p);
            let bindings = [
                Binding::StorageRead(&made[0]),
                Binding::Storage(&made[1]),
                Binding::StorageRead(&made[2]),
                Binding::StorageRead(&made[3]),
            ];
            let set = descriptor::allocate(ctx, p, self.pipeline.set_layout)?;
            self.pipeline.write_set(ctx, set, &bindings)?;
            ctx.commands.run(&ctx.device, |cmd| {
                self.pipeline.bind(ctx, cmd, set, &(pairs.len() as u32).to_ne_bytes());
                ctx.counts.dispatch();
                // SAFETY: `cmd` is recording with the compute pipeline bound.
                unsafe { ctx.raw().cmd_dispatch(cmd, (n as u32).div_ceil(64), 1, 1) };
                crate::vk::barrier::memory(
                    ctx,
                    cmd,
                    crate::vk::barrier::COMPUTE_WRITE,
                    (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
                );
                Ok(())
            })?;
            let floats: Vec<f32> =
                made[1].mapped().chunks_exact(4).map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect();
            Ok(floats.chunks_exact(4).take(pairs.len()).map(|c| [c[0], c[1], c[2]]).collect())
        })();
        if let Some(p) = pool {
            // SAFETY: the submission was waited on (or never made).
            unsafe { ctx.raw().destroy_descriptor_pool(p, None) };
        }
        for b in made {
            b.destroy(ctx);
        }
        result
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
