//! Timestamp queries: two per pass, reset inside the command buffer, read after the fence with
//! `TYPE_64 | WAIT`, masked to `timestampValidBits` and scaled by `timestampPeriod`.

use ash::vk;

use super::{vk_err, Context};
use crate::error::Result;

pub struct Timestamps {
    pool: vk::QueryPool,
    capacity: u32,
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
        Ok(Timestamps { pool, capacity, names: Vec::new() })
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
    }
}
