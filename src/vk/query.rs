//! Timestamp queries: two per pass, reset inside the command buffer, read after the fence with
//! `TYPE_64 | WAIT`, masked to `timestampValidBits` and scaled by `timestampPeriod`.
//!
//! On a CPU device (lavapipe) each timestamp is followed by a copy of its result with `WAIT` into a
//! small device buffer (`settle`), which nothing reads. llvmpipe does not read the clock when it
//! executes a timestamp while a framebuffer is bound: it bins the query into the rasteriser's
//! scene, and the clock is read when that scene is rasterised, at the next flush, on the rasteriser's
//! threads. Compute dispatches run synchronously in between, so a compute pass's first timestamp was
//! read after the pass had run: the editor's lobe passes read 0.05–0.1 ms for passes of ~200 ms
//! (frames that reuse the G-buffer, after egui had drawn into the swapchain image). The copy makes
//! the queue wait until the clock has been read, before the pass's work starts.

use ash::vk;

use gpu_allocator::MemoryLocation;

use super::buffer::Buffer;
use super::{vk_err, Context};
use crate::error::Result;

pub struct Timestamps {
    pool: vk::QueryPool,
    capacity: u32,
    /// Where a CPU device's timestamps are copied with `WAIT` (see the module's comment).
    settle: Option<Buffer>,
    names: Vec<String>,
}

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    pub name: String,
    pub ms: f64,
}

impl Timestamps {
    /// Room for `passes` passes.
    pub fn new(ctx: &Context, passes: u32) -> Result<Timestamps> {
        let capacity = 2 * passes.max(1);
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        // SAFETY: the device is live; the pool is destroyed in `destroy`.
        let pool = unsafe { ctx.raw().create_query_pool(&info, None) }.map_err(vk_err("vkCreateQueryPool"))?;
        ctx.device.set_name(pool, "timestamps");
        let settle = if ctx.device.kind == vk::PhysicalDeviceType::CPU {
            let usage = vk::BufferUsageFlags::TRANSFER_DST;
            match Buffer::new(ctx, 8 * capacity as u64, usage, MemoryLocation::GpuOnly, "timestamps.settle") {
                Ok(b) => Some(b),
                Err(e) => {
                    // SAFETY: the pool was never used.
                    unsafe { ctx.raw().destroy_query_pool(pool, None) };
                    return Err(e);
                }
            }
        } else {
            None
        };
        Ok(Timestamps { pool, capacity, settle, names: Vec::new() })
    }

    /// Resets every query; recorded first in the command buffer.
    pub fn reset(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.names.clear();
        // SAFETY: `cmd` is recording outside a render pass; the pool is live.
        unsafe { ctx.raw().cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
    }

    fn write(&self, ctx: &Context, cmd: vk::CommandBuffer, index: u32) {
        // SAFETY: `cmd` is recording; `index` is below the capacity and was reset in this buffer.
        unsafe { ctx.raw().cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, index) };
        if let Some(settle) = &self.settle {
            let flags = vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT;
            // SAFETY: `cmd` is recording outside a render pass; the query was written just above;
            // `settle` holds 8 bytes per query and is a transfer destination.
            unsafe {
                ctx.raw().cmd_copy_query_pool_results(cmd, self.pool, index, 1, settle.raw, 8 * index as u64, 8, flags)
            };
        }
    }

    /// Records `pass` between two timestamps (skipped when the pool is full).
    pub fn time<T>(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        pass: impl FnOnce() -> Result<T>,
    ) -> Result<T> {
        let index = 2 * self.names.len() as u32;
        let timed = index + 1 < self.capacity;
        if timed {
            self.write(ctx, cmd, index);
        }
        let out = pass()?;
        if timed {
            self.write(ctx, cmd, index + 1);
            self.names.push(name.to_string());
        }
        Ok(out)
    }

    /// The times of the passes recorded, after the submission completed.
    pub fn read(&self, ctx: &Context) -> Result<Vec<PassTime>> {
        if self.names.is_empty() {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; 2 * self.names.len()];
        // SAFETY: the queries were written by a submission the caller waited on.
        unsafe {
            ctx.raw().get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_err("vkGetQueryPoolResults"))?;
        let bits = ctx.device.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let period = ctx.device.timestamp_period as f64;
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let (a, b) = (ticks[2 * i] & mask, ticks[2 * i + 1] & mask);
                let delta = b.wrapping_sub(a) & mask;
                PassTime { name: name.clone(), ms: delta as f64 * period * 1e-6 }
            })
            .collect())
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: no submission using the pool is pending.
        unsafe { ctx.raw().destroy_query_pool(self.pool, None) };
        if let Some(settle) = self.settle {
            settle.destroy(ctx);
        }
    }
}
