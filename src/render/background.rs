//! Pass 1 (mesh views): starts the accumulation image — the environment at level 0 behind the
//! object (alpha 0) and `(0, 0, 0, 1)` on it.

use ash::vk;

use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::Context;
use crate::Result;

const BINDINGS: [vk::DescriptorType; 3] =
    [vk::DescriptorType::STORAGE_IMAGE, vk::DescriptorType::STORAGE_IMAGE, vk::DescriptorType::COMBINED_IMAGE_SAMPLER];

pub struct BackgroundPass {
    pipeline: Pipeline,
}

impl BackgroundPass {
    pub fn new(ctx: &Context) -> Result<BackgroundPass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("background.comp"), "background", &BINDINGS, 128, &[])?;
        Ok(BackgroundPass { pipeline })
    }

    pub fn record(&self, rec: &Recording<'_>) -> Result<()> {
        let t = rec.targets;
        let env = rec.env()?;
        t.start_accum(rec.ctx, rec.cmd);
        let set = rec.set(
            &self.pipeline,
            &[
                Binding::StorageImage(t.normal.view),
                Binding::StorageImage(t.accum.view),
                Binding::Sampled(env.texture.view, env.sampler),
            ],
        )?;
        rec.dispatch(&self.pipeline, set, &rec.push);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
