//! Timestamp queries: a pair around the whole frame (the first written right after the reset, the
//! last just before the command buffer ends, so every clear and copy between passes is inside it) and,
//! in a frame that times its passes, two per pass; reset inside the command buffer, read after the fence with `TYPE_64 | WAIT`, masked
//! to `timestampValidBits` and scaled by `timestampPeriod`.
//!
//! On a CPU device (lavapipe) each timestamp is followed by a copy of its result with `WAIT` into a
//! small device buffer (`settle`), which nothing reads. llvmpipe does not read the clock when it
//! executes a timestamp while a framebuffer is bound: it bins the query into the rasteriser's
//! scene, and the clock is read when that scene is rasterised, at the next flush, on the rasteriser's
//! threads. Compute dispatches run synchronously in between, so a compute pass's first timestamp was
//! read after the pass had run: the editor's lobe passes read a small fraction of their real time
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
    /// Whether the whole frame's closing timestamp was written (`end_frame`).
    ended: bool,
    /// Whether this frame times its passes (`reset`); false: the whole frame's pair alone.
    passes: bool,
}

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    pub name: String,
    pub ms: f64,
}

/// A finished frame's GPU times: each timed pass's and the whole frame's (first command to last).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameTimes {
    pub passes: Vec<PassTime>,
    /// The whole frame; 0 for a frame that recorded nothing.
    pub frame_ms: f64,
}

impl FrameTimes {
    /// The sum of the timed passes.
    pub fn passes_ms(&self) -> f64 {
        self.passes.iter().map(|t| t.ms).sum::<f64>() + 0.0
    }

    /// The part of the whole frame no pass timed (clears, copies, barriers between passes): the
    /// whole frame less the passes, at least 0.
    pub fn untimed_ms(&self) -> f64 {
        untimed_ms(self.frame_ms, self.passes_ms())
    }
}

/// `frame_ms − passes_ms`, at least 0 (the two timestamps of a pass and of the frame are read from
/// the same clock, but a driver may round each).
pub fn untimed_ms(frame_ms: f64, passes_ms: f64) -> f64 {
    (frame_ms - passes_ms).max(0.0)
}

/// The queries of the whole frame's pair; the passes' pairs follow.
const FRAME_QUERIES: u32 = 2;

impl Timestamps {
    /// Room for `passes` passes and the whole frame.
    pub fn new(ctx: &Context, passes: u32) -> Result<Timestamps> {
        let capacity = FRAME_QUERIES + 2 * passes.max(1);
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
        Ok(Timestamps { pool, capacity, settle, names: Vec::new(), ended: false, passes: true })
    }

    /// Resets every query and writes the whole frame's first timestamp; recorded first in the
    /// command buffer. `passes`: the frame also times each pass ([`Timestamps::time`]); false records
    /// the whole frame's pair alone, two timestamps where a frame of `n` passes has `2 n + 2` (on
    /// lavapipe each is a wait for the queue, see the module's comment).
    pub fn reset(&mut self, ctx: &Context, cmd: vk::CommandBuffer, passes: bool) {
        self.names.clear();
        self.ended = false;
        self.passes = passes;
        // SAFETY: `cmd` is recording outside a render pass; the pool is live.
        unsafe { ctx.raw().cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
        self.write(ctx, cmd, 0);
    }

    /// Writes the whole frame's last timestamp, outside a render pass: recorded last in the command
    /// buffer (`FrameRing::submit`), or earlier by a frame that leaves what follows out of its time
    /// (the headless render's readback copy); once a frame.
    pub fn end_frame(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        if !self.ended {
            self.write(ctx, cmd, 1);
            self.ended = true;
        }
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

    /// Records `pass` between two timestamps (skipped when the pool is full or the frame does not
    /// time its passes).
    pub fn time<T>(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        pass: impl FnOnce() -> Result<T>,
    ) -> Result<T> {
        let index = FRAME_QUERIES + 2 * self.names.len() as u32;
        let timed = self.passes && index + 1 < self.capacity;
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

    /// The times of the frame and of the passes recorded, after the submission completed.
    pub fn read(&self, ctx: &Context) -> Result<FrameTimes> {
        if !self.ended {
            return Ok(FrameTimes::default());
        }
        let mut ticks = vec![0u64; (FRAME_QUERIES as usize) + 2 * self.names.len()];
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
        let ms = |i: usize| {
            let (a, b) = (ticks[i] & mask, ticks[i + 1] & mask);
            (b.wrapping_sub(a) & mask) as f64 * period * 1e-6
        };
        let f = FRAME_QUERIES as usize;
        let passes =
            self.names.iter().enumerate().map(|(i, name)| PassTime { name: name.clone(), ms: ms(f + 2 * i) }).collect();
        Ok(FrameTimes { passes, frame_ms: ms(0) })
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: no submission using the pool is pending.
        unsafe { ctx.raw().destroy_query_pool(self.pool, None) };
        if let Some(settle) = self.settle {
            settle.destroy(ctx);
        }
    }
}
