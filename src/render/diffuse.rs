//! Pass 2 (paper §4): the diffuse term `ρ_d/π · E(n)` from the environment's 9 SH coefficients,
//! added into the accumulation image. Left out when `ρ_d = 0`.

use super::environment::GpuEnvironment;
use super::gpu::Push;
use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::Buffer;
use crate::vk::Context;
use crate::Result;

/// What the diffuse term reads (`glsl/include/diffuse.glsl`, in this pass and in the G-buffer's,
/// `CompactPass`): the SH9 coefficients and the key lights' cones (`residual`: the `key` estimator's,
/// where the map has key lights; the coefficients stand in for the lights otherwise), and its push
/// constants: the albedo in `fparams`, whether the lights are added in `params[0]`.
pub fn term<'a>(env: &'a GpuEnvironment, albedo: [f64; 3], residual: bool, push: &mut Push) -> [&'a Buffer; 2] {
    // The coefficients' 9 vec4 stand in for the lights' table, which `diffuse.glsl` reads whole at
    // constant indices: the count and 4 lights of 2 vec4.
    const _: () = assert!(9 * 16 >= 16 + 2 * 16 * crate::scene::keylight::MAX_LIGHTS);
    let keys = env.keys.as_ref().filter(|_| residual);
    push.fparams = [albedo[0] as f32, albedo[1] as f32, albedo[2] as f32, 0.0];
    push.params[0] = u32::from(keys.is_some());
    [keys.map_or(&env.sh, |k| &k.sh), keys.map_or(&env.sh, |k| &k.cones)]
}

pub struct DiffusePass {
    pipeline: Pipeline,
}

impl DiffusePass {
    pub fn new(ctx: &Context) -> Result<DiffusePass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("diffuse.comp"), "diffuse", 128, &[])?;
        Ok(DiffusePass { pipeline })
    }

    /// Adds `ρ_d/π · E(n)`; `residual`: E of the map without its key lights plus each light as a
    /// distant source, `power · max(n·d, 0)` (the `key` estimator).
    pub fn record(&self, rec: &Recording<'_>, diffuse: [f64; 3], residual: bool) -> Result<()> {
        let t = rec.targets;
        let mut push = rec.push;
        let [sh, lights] = term(rec.env()?, diffuse, residual, &mut push);
        let set = rec.set(
            &self.pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::StorageImage(&t.accum),
                Binding::StorageRead(sh),
                Binding::StorageRead(lights),
                Binding::StorageRead(&t.pixels),
            ],
        )?;
        rec.dispatch_over(&t.pixels, &self.pipeline, set, &push);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
