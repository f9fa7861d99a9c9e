//! The canvas pass (docs/model.md, Frames and conventions): the material on the point-lit unit sphere, written to the
//! whole accumulation image (alpha 1 on the sphere). The only pass of a canvas view.

use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

pub struct CanvasPass {
    pipeline: Pipeline,
}

impl CanvasPass {
    pub fn new(ctx: &Context) -> Result<CanvasPass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("canvas.comp"), "canvas", 128, &[])?;
        Ok(CanvasPass { pipeline })
    }

    /// `tables`: the compensation tables (`compensation::words`).
    pub fn record(&self, rec: &Recording<'_>, material: &Buffer, tables: &Buffer) -> Result<()> {
        let t = rec.targets;
        t.start_accum(rec.ctx, rec.cmd);
        let bindings = [Binding::StorageImage(&t.accum), Binding::StorageRead(material), Binding::StorageRead(tables)];
        let set = rec.set(&self.pipeline, &bindings)?;
        rec.dispatch(&self.pipeline, set, &rec.push);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
