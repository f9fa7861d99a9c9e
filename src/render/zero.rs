//! The zero pass: zeroes the images the lobe passes add into (the sparse filter's cells and their
//! lights, or the rough lobes' image) with a compute dispatch, where the device plan
//! ([`super::plan::DevicePlan::zero_by_compute`]) prefers it to a transfer clear.

use ash::vk;

use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Context, Image};
use crate::Result;

pub struct ZeroPass {
    pipeline: Pipeline,
}

impl ZeroPass {
    pub fn new(ctx: &Context) -> Result<ZeroPass> {
        Ok(ZeroPass { pipeline: Pipeline::compute(ctx, crate::spirv!("zero.comp"), "zero", 16, &[])? })
    }

    /// Zeroes `images` (one or two RGBA32F storage images of one size) in `GENERAL`, ready for the
    /// passes that read and add into them.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        pool: vk::DescriptorPool,
        images: &[&Image],
    ) -> Result<()> {
        let (first, second) = match images {
            [a] => (*a, None),
            [a, b] => (*a, Some(*b)),
            _ => return Err(crate::Error::Bug("the zero pass takes one or two images".into())),
        };
        for i in images {
            i.discard_to_general(ctx, cmd, barrier::COMPUTE_WRITE);
        }
        let bindings = [Binding::StorageImage(first), Binding::StorageImage(second.unwrap_or(first))];
        let set = descriptor::allocate(ctx, pool, self.pipeline.set_layout)?;
        self.pipeline.write_set(ctx, set, &bindings)?;
        let (w, h) = (first.width, first.height);
        let push = [w, h, u32::from(second.is_some()), 0];
        self.pipeline.bind(ctx, cmd, set, bytemuck::cast_slice(&push));
        ctx.counts.dispatch();
        // SAFETY: `cmd` is recording with the compute pipeline bound.
        unsafe { ctx.raw().cmd_dispatch(cmd, w.div_ceil(8), h.div_ceil(8), 1) };
        barrier::memory(ctx, cmd, barrier::COMPUTE_WRITE, barrier::COMPUTE_READ_WRITE);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
