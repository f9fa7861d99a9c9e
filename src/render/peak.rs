//! The device's arithmetic peak as `bench` states it: a compute pass of independent `vec4` fused
//! multiply-adds (`glsl/peak.comp`), grown until one submission runs at least 20 ms, timed on the
//! host around the submission and its wait (timestamps around this dispatch read near zero on
//! lavapipe once a frame has been rendered; at 20 ms the submission's own cost is under 1 %). What the shading passes reach is quoted as a share of this.

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

/// Rounds per invocation, and flops per round (`peak.comp`: 4 × 8 `vec4` FMAs, 4 lanes, 2 flops).
const ITERATIONS: u32 = 128;
const FLOPS_PER_ROUND: f64 = 256.0;
/// Invocations per workgroup (`peak.comp`'s local size).
const GROUP: u32 = 64;
/// The dispatch grows (doubling its workgroups) until one run takes this long.
const MIN_MS: f64 = 20.0;
const MAX_GROUPS: u32 = 1 << 24;
/// Workgroups along x (the rest go along y: every device takes 65535 either way).
const ROW: u32 = 1 << 15;
/// `vec4`s of output: every invocation writes one, wrapping (the values are never read).
const OUT_VEC4S: u64 = 4096;

pub struct PeakPass {
    pipeline: Pipeline,
}

impl PeakPass {
    pub fn new(ctx: &Context) -> Result<PeakPass> {
        let bindings = [vk::DescriptorType::STORAGE_BUFFER];
        Ok(PeakPass { pipeline: Pipeline::compute(ctx, crate::spirv!("peak.comp"), "peak", &bindings, 12, &[])? })
    }

    /// GFLOP/s: the median of `repeats` runs of the first dispatch that takes at least 20 ms.
    pub fn gflops(&self, ctx: &Context, repeats: usize) -> Result<f64> {
        let mut groups = 64u32;
        loop {
            let ms = self.run(ctx, groups)?;
            if ms >= MIN_MS || groups >= MAX_GROUPS {
                let mut runs = vec![ms];
                for _ in 1..repeats.max(1) {
                    runs.push(self.run(ctx, groups)?);
                }
                runs.sort_by(f64::total_cmp);
                let median = runs[runs.len() / 2];
                let flops = f64::from(groups) * f64::from(GROUP) * f64::from(ITERATIONS) * FLOPS_PER_ROUND;
                return Ok(flops / (median * 1e-3) / 1e9);
            }
            groups *= 2;
        }
    }

    /// One dispatch of `groups` workgroups (a power of two, so rows of [`ROW`] hold them exactly):
    /// milliseconds from submission to completion.
    fn run(&self, ctx: &Context, groups: u32) -> Result<f64> {
        let out = Buffer::new(
            ctx,
            OUT_VEC4S * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
            "peak.out",
        )?;
        let mut pool = None;
        let result = (|| -> Result<f64> {
            let p = descriptor::pool(ctx, 1, "peak.descriptors")?;
            pool = Some(p);
            let set = descriptor::allocate(ctx, p, self.pipeline.set_layout)?;
            descriptor::write(ctx, set, &[Binding::Storage(&out)]);
            let push: Vec<u8> = [ITERATIONS.to_ne_bytes(), 0.999f32.to_ne_bytes(), 0.001f32.to_ne_bytes()].concat();
            let start = std::time::Instant::now();
            ctx.commands.run(&ctx.device, |cmd| {
                self.pipeline.bind(ctx, cmd, set, &push);
                // SAFETY: `cmd` is recording with the compute pipeline bound.
                unsafe { ctx.raw().cmd_dispatch(cmd, groups.min(ROW), groups.div_ceil(ROW), 1) };
                Ok(())
            })?;
            Ok(start.elapsed().as_secs_f64() * 1e3)
        })();
        if let Some(p) = pool {
            // SAFETY: the submission was waited on (or never made).
            unsafe { ctx.raw().destroy_descriptor_pool(p, None) };
        }
        out.destroy(ctx);
        result
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
