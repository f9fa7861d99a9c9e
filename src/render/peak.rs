//! The device's arithmetic peak as `bench` states it: a compute pass of independent `vec4` fused
//! multiply-adds (`glsl/peak.comp`), grown until one submission runs at least 20 ms, timed on the
//! host around the submission and its wait (timestamps around this dispatch read near zero on
//! lavapipe once a frame has been rendered; at 20 ms the submission's own cost is under 1 %). What
//! the shading passes reach is quoted as a share of this.
//!
//! And what a timed pass costs before any work ([`fixed_costs`]), which `report error-vs-time`
//! states next to its small frames' times: the same pipeline with no rounds, one workgroup.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::Renderer;
use crate::brdf::{Material, Normalization};
use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Buffer, Context};
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

/// A descriptor set of the pass's layout pointing at an output buffer of its own.
struct Scratch {
    out: Buffer,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

impl Scratch {
    fn new(ctx: &Context, pass: &PeakPass) -> Result<Scratch> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let out = Buffer::new(ctx, OUT_VEC4S * 16, usage, MemoryLocation::GpuOnly, "peak.out")?;
        let pool = match descriptor::pool(ctx, 1, "peak.descriptors") {
            Ok(p) => p,
            Err(e) => {
                out.destroy(ctx);
                return Err(e);
            }
        };
        let mut scratch = Scratch { out, pool, set: vk::DescriptorSet::null() };
        let bindings = [Binding::Storage(&scratch.out)];
        match descriptor::allocate(ctx, pool, pass.pipeline.set_layout)
            .and_then(|set| pass.pipeline.write_set(ctx, set, &bindings).map(|()| set))
        {
            Ok(set) => {
                scratch.set = set;
                Ok(scratch)
            }
            Err(e) => {
                scratch.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Frees both; the submissions that used them were waited on.
    fn destroy(self, ctx: &Context) {
        // SAFETY: no submission that uses the pool's set is pending (the caller waited).
        unsafe { ctx.raw().destroy_descriptor_pool(self.pool, None) };
        self.out.destroy(ctx);
    }
}

impl PeakPass {
    pub fn new(ctx: &Context) -> Result<PeakPass> {
        Ok(PeakPass { pipeline: Pipeline::compute(ctx, crate::spirv!("peak.comp"), "peak", 12, &[])? })
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
        let scratch = Scratch::new(ctx, self)?;
        let start = std::time::Instant::now();
        let ran = ctx.commands.run(&ctx.device, |cmd| {
            self.record(ctx, cmd, scratch.set, ITERATIONS, groups);
            Ok(())
        });
        let ms = start.elapsed().as_secs_f64() * 1e3;
        // The submission was waited on (or never made).
        scratch.destroy(ctx);
        ran.map(|_| ms)
    }

    /// Records one dispatch of `groups` workgroups of `iterations` rounds each.
    fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, set: vk::DescriptorSet, iterations: u32, groups: u32) {
        let push: Vec<u8> = [iterations.to_ne_bytes(), 0.999f32.to_ne_bytes(), 0.001f32.to_ne_bytes()].concat();
        self.pipeline.bind(ctx, cmd, set, &push);
        ctx.counts.dispatch();
        // SAFETY: `cmd` is recording with the compute pipeline bound.
        unsafe { ctx.raw().cmd_dispatch(cmd, groups.min(ROW), groups.div_ceil(ROW), 1) };
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}

/// What a timed pass costs before any work, timed as the renderer times its passes
/// (`Renderer::time`, the same timestamps): a timed region with nothing in it, one with one dispatch
/// of one workgroup that does next to nothing (`peak.comp` with no rounds: each invocation writes one
/// `vec4`) followed by the barrier every pass records after its dispatch, and one with two of those;
/// the median over the frames, ms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedCosts {
    pub frames: usize,
    pub empty: f64,
    pub one_dispatch: f64,
    pub two_dispatches: f64,
}

/// [`FixedCosts`] over `frames` frames of `r` (at least one), after the frames in flight (whose
/// times this drops).
pub fn fixed_costs(r: &mut Renderer, frames: usize) -> Result<FixedCosts> {
    const NAMES: [&str; 3] = ["fixed.empty", "fixed.one", "fixed.two"];
    r.finish_frames()?;
    r.take_finished();
    let pass = PeakPass::new(&r.ctx)?;
    let nothing = Material {
        preserve_energy: false,
        diffuse: [0.0; 3],
        normalization: Normalization::Ward,
        symmetrize: false,
        lobes: vec![],
    };
    let scratch = match Scratch::new(&r.ctx, &pass) {
        Ok(s) => s,
        Err(e) => {
            pass.destroy(&r.ctx);
            return Err(e);
        }
    };
    let times = (|| -> Result<[Vec<f64>; 3]> {
        let mut times = [Vec::new(), Vec::new(), Vec::new()];
        for _ in 0..frames.max(1) {
            r.begin_frame(&nothing)?;
            let recorded = (|| -> Result<()> {
                for (k, name) in NAMES.iter().enumerate() {
                    r.time(name, |ctx, cmd| {
                        for _ in 0..k {
                            pass.record(ctx, cmd, scratch.set, 0, 1);
                            barrier::memory(ctx, cmd, barrier::COMPUTE_WRITE, barrier::COMPUTE_READ_WRITE);
                        }
                        Ok(())
                    })?;
                }
                Ok(())
            })();
            match recorded {
                Ok(()) => r.submit_frame(None, None)?,
                Err(e) => {
                    // The recording's error is the one to report.
                    let _ = r.abandon_frame();
                    return Err(e);
                }
            }
        }
        r.finish_frames()?;
        for f in r.take_finished() {
            for t in f.timings {
                if let Some(k) = NAMES.iter().position(|&n| n == t.name) {
                    times[k].push(t.ms);
                }
            }
        }
        Ok(times)
    })();
    // Freed once every frame that used them is done (an error before the wait leaves frames in
    // flight: wait for them first).
    if let Err(e) = r.finish_frames() {
        // Left, not freed under the GPU; the first error is the one to report.
        return Err(times.err().unwrap_or(e));
    }
    scratch.destroy(&r.ctx);
    pass.destroy(&r.ctx);
    let times = times?;
    if let Some(k) = times.iter().position(|t| t.is_empty()) {
        return Err(crate::Error::Bug(format!("no GPU time came back for {}", NAMES[k])));
    }
    let median = |mut t: Vec<f64>| {
        t.sort_by(f64::total_cmp);
        let n = t.len();
        if n % 2 == 1 {
            t[n / 2]
        } else {
            0.5 * (t[n / 2 - 1] + t[n / 2])
        }
    };
    let [empty, one, two] = times.map(median);
    r.ctx.check_validation()?;
    Ok(FixedCosts { frames: frames.max(1), empty, one_dispatch: one, two_dispatches: two })
}
