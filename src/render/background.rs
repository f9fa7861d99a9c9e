//! Pass 1 (mesh views): starts the accumulation image — the environment at level 0 behind the
//! object (alpha 0) and `(0, 0, 0, 1)` on it. In a frame that rasterises and filters sparsely
//! (`compact::Start::Later`) it runs over the blocks with a pixel off the object instead
//! ([`BackgroundPass::record_blocks`]).

use ash::vk;

use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::Context;
use crate::Result;

pub struct BackgroundPass {
    pipeline: Pipeline,
    /// `background.comp` BLOCKS: over the list of blocks with a pixel off the object.
    blocks: Pipeline,
}

impl BackgroundPass {
    pub fn new(ctx: &Context) -> Result<BackgroundPass> {
        let variants = [("background", &[0][..]), ("background.blocks", &[1])];
        let [pipeline, blocks] = Pipeline::compute_variants(ctx, crate::spirv!("background.comp"), 128, variants)?;
        Ok(BackgroundPass { pipeline, blocks })
    }

    /// The whole image: the environment off the object, `(0, 0, 0, 1)` on it.
    pub fn record(&self, rec: &Recording<'_>) -> Result<()> {
        rec.targets.start_accum(rec.ctx, rec.cmd);
        let set = self.set(rec, &self.pipeline)?;
        rec.dispatch(&self.pipeline, set, &rec.push);
        Ok(())
    }

    /// The environment at the pixels off the object of the blocks `compact.comp` listed
    /// (`Targets::background_blocks`; after the compact pass with `Start::Later`, which cleared the
    /// image to `(0, 0, 0, 1)`): the same values as [`Self::record`]'s.
    pub fn record_blocks(&self, rec: &Recording<'_>) -> Result<()> {
        let set = self.set(rec, &self.blocks)?;
        rec.dispatch_over(&rec.targets.background_blocks, &self.blocks, set, &rec.push);
        Ok(())
    }

    fn set(&self, rec: &Recording<'_>, pipeline: &Pipeline) -> Result<vk::DescriptorSet> {
        let t = rec.targets;
        let env = rec.env()?;
        rec.set(
            pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::StorageImage(&t.accum),
                Binding::Sampled(&env.texture, env.sampler),
                Binding::StorageRead(&t.background_blocks),
            ],
        )
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.blocks.destroy(ctx);
    }
}
