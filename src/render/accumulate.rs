//! Progressive refinement on the GPU: each refinement frame's estimate (the accumulation image, the
//! mean of its samples) times its sample count is added into the mesh view's running sum
//! (`Targets::sum`); the compose pass shows sum / samples, so frames may add different counts.
//! Nothing goes through the host.

use ash::vk;

use super::targets::Targets;
use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Context};
use crate::Result;

pub struct AccumulatePass {
    pipeline: Pipeline,
}

impl AccumulatePass {
    pub fn new(ctx: &Context) -> Result<AccumulatePass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("accumulate.comp"), "accumulate", 32, &[])?;
        Ok(AccumulatePass { pipeline })
    }

    /// Adds `targets.accum` times `samples` into `targets.sum` (`first`: starts the sum instead). The sum stays in
    /// `GENERAL`, its writes ordered before later compute and transfer reads.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        pool: vk::DescriptorPool,
        targets: &Targets,
        first: bool,
        samples: u32,
    ) -> Result<()> {
        if first {
            targets.sum.discard_to_general(ctx, cmd, barrier::COMPUTE_READ_WRITE);
        }
        let bindings = [Binding::StorageImageRead(&targets.accum), Binding::StorageImage(&targets.sum)];
        let set = descriptor::allocate(ctx, pool, self.pipeline.set_layout)?;
        self.pipeline.write_set(ctx, set, &bindings)?;
        let push = [targets.width, targets.height, first as u32, 0, (samples as f32).to_bits(), 0, 0, 0];
        self.pipeline.bind(ctx, cmd, set, bytemuck::cast_slice(&push));
        ctx.counts.dispatch();
        // SAFETY: `cmd` is recording with the compute pipeline bound.
        unsafe { ctx.raw().cmd_dispatch(cmd, targets.width.div_ceil(8), targets.height.div_ceil(8), 1) };
        barrier::memory(
            ctx,
            cmd,
            barrier::COMPUTE_WRITE,
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::TRANSFER_READ,
            ),
        );
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
