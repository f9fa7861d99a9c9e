//! The list of the mesh view's shaded pixels (`compact.comp`), built once per G-buffer: the lobe and
//! `mis` passes are dispatched over it instead of over the image, so no vector of lanes is spent on
//! pixels off the mesh (on llvmpipe those still ran one round of every loop). Images are unchanged.
//! The same pass starts the frame's image (the background and diffuse passes' work) in a frame that
//! rasterises.

use ash::vk;

use super::Recording;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Buffer, Context};
use crate::Result;

/// Invocations per group of the passes dispatched over the list (their `local_size_x`).
pub const GROUP: u32 = 64;

/// The bytes before the list: the count, then the groups of `vkCmdDispatchIndirect` (x, y, z).
pub const HEADER: u64 = 16;

/// Where in the list buffer the indirect dispatch's groups are.
pub const GROUPS_OFFSET: u64 = 4;

/// A list buffer of `entries` entries at most: the header and one `u32` an entry.
pub fn list_buffer(ctx: &Context, entries: u64, name: &str) -> Result<Buffer> {
    Buffer::new(
        ctx,
        HEADER + 4 * entries,
        vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuOnly,
        name,
    )
}

/// What reads the list: the indirect dispatches and the shaders of the passes over it.
pub const LIST_READ: barrier::Scope = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::DRAW_INDIRECT.as_raw() | vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::INDIRECT_COMMAND_READ.as_raw() | vk::AccessFlags2::SHADER_STORAGE_READ.as_raw(),
    ),
);

pub use super::plan::Start;

pub struct CompactPass {
    /// `Start::Here`, `Start::Later` with the pixels listed, and without (`compact.comp`'s LATER
    /// and PIXELS).
    pipelines: [Pipeline; 3],
}

impl CompactPass {
    pub fn new(ctx: &Context) -> Result<CompactPass> {
        let variants = [("compact", &[0, 1][..]), ("compact.later", &[1, 1]), ("compact.later.blocks", &[1, 0])];
        let pipelines = Pipeline::compute_variants(ctx, crate::spirv!("compact.comp"), 128, variants)?;
        Ok(CompactPass { pipelines })
    }

    /// Rebuilds the lists of `rec.targets` from its G-buffer (after the G-buffer pass; the pixels'
    /// as `start` says), and starts the frame's image as the background pass would, plus, as `start`
    /// says, the diffuse pass's term: in the same pass over the G-buffer, one read of it a pixel
    /// instead of three.
    pub fn record(&self, rec: &Recording<'_>, start: Start) -> Result<()> {
        let (ctx, cmd, t) = (rec.ctx, rec.cmd, rec.targets);
        let env = rec.env()?;
        let mut push = rec.push;
        let diffuse = match start {
            Start::Here(d) => d,
            Start::Later { .. } => None,
        };
        // Without a diffuse term: zero albedo, no lights, and params[1] 0 skips the term.
        let (albedo, residual) = diffuse.unwrap_or(([0.0; 3], false));
        let [sh, lights] = super::diffuse::term(env, albedo, residual, &mut push);
        push.params[1] = u32::from(diffuse.is_some());
        let pipeline = match start {
            Start::Here(_) => {
                t.start_accum(ctx, cmd);
                &self.pipelines[0]
            }
            Start::Later { pixels } => {
                t.accum.fill_to_general(ctx, cmd, [0.0, 0.0, 0.0, 1.0], barrier::COMPUTE_READ_WRITE);
                &self.pipelines[if pixels { 1 } else { 2 }]
            }
        };
        let set = rec.set(
            pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::Storage(&t.pixels),
                Binding::Storage(&t.blocks),
                Binding::StorageImage(&t.accum),
                Binding::Sampled(&env.texture, env.sampler),
                Binding::StorageRead(sh),
                Binding::StorageRead(lights),
                Binding::Storage(&t.background_blocks),
            ],
        )?;
        // The previous list's readers (an earlier frame may still be in flight) before the reset.
        barrier::memory(ctx, cmd, (LIST_READ.0, vk::AccessFlags2::NONE), barrier::TRANSFER_WRITE);
        let header: [u32; 4] = [0, 0, 1, 1];
        // SAFETY: `cmd` is recording; the buffers are live and have TRANSFER_DST usage; 16 bytes, a
        // multiple of 4 at offset 0.
        unsafe {
            ctx.raw().cmd_update_buffer(cmd, t.pixels.raw, 0, bytemuck::cast_slice(&header));
            ctx.raw().cmd_update_buffer(cmd, t.blocks.raw, 0, bytemuck::cast_slice(&header));
            ctx.raw().cmd_update_buffer(cmd, t.background_blocks.raw, 0, bytemuck::cast_slice(&header));
        }
        barrier::memory(ctx, cmd, barrier::TRANSFER_WRITE, barrier::COMPUTE_READ_WRITE);
        // One invocation a 2 × 2 block, 8 × 8 invocations a group. The lists' and the image's readers
        // wait for it through the barriers derived from their accesses (`Recording::dispatch_over`).
        rec.dispatch_groups(pipeline, set, &push, (t.width.div_ceil(16), t.height.div_ceil(16)));
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        for p in self.pipelines {
            p.destroy(ctx);
        }
    }
}
