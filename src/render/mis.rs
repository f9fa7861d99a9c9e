//! The `mis` estimator pass: the whole material (diffuse included) by multiple importance sampling
//! between the environment (CDF inversion over `|L| sin θ`) and the material's mixture, balance
//! heuristic, deterministic QMC. Dispatched in chunks of samples so no dispatch runs long.

use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

/// Samples per dispatch.
pub const CHUNK: u32 = 32;

pub struct MisPass {
    pipeline: Pipeline,
}

impl MisPass {
    pub fn new(ctx: &Context) -> Result<MisPass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("mis.comp"), "mis", 128, &[])?;
        Ok(MisPass { pipeline })
    }

    /// Adds the estimate over samples `first..first + samples` of the `sequence` buffer (their mean);
    /// the material's buffer and its compensation tables (`compensation::words`).
    pub fn record(
        &self,
        rec: &Recording<'_>,
        first: u32,
        samples: u32,
        [material, tables]: [&Buffer; 2],
        sequence: &Buffer,
    ) -> Result<()> {
        let t = rec.targets;
        let env = rec.env()?;
        let set = rec.set(
            &self.pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::StorageImage(&t.accum),
                Binding::Sampled(&env.texture, env.sampler),
                Binding::Uniform(material, 0, super::gpu::MATERIAL_UNIFORM_BYTES as u64),
                Binding::StorageRead(sequence),
                Binding::StorageRead(&env.marginal),
                Binding::StorageRead(&env.conditional),
                Binding::StorageRead(&env.pdf),
                Binding::StorageRead(&t.pixels),
                Binding::StorageRead(tables),
            ],
        )?;
        let (mut at, end) = (first, first + samples);
        while at < end {
            let count = CHUNK.min(end - at);
            let mut push = rec.push;
            push.params = [0, count, at, samples];
            push.fparams[3] = 1.0 / samples as f32;
            rec.dispatch_listed(&self.pipeline, set, &push);
            at += count;
        }
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
