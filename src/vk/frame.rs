//! The frame ring: [`FRAMES_IN_FLIGHT`] frames, each with its own command buffer, fence, acquire
//! semaphore, descriptor pool (reset, not recreated), timestamp queries and host-visible buffers
//! (the material, the light samples). A slot is reused only after its fence, so the CPU records
//! frame N+1 while the GPU runs frame N, and nothing in the frame path waits for the whole device.
//! Headless commands take the same path and wait for their one frame ([`FrameRing::wait`]).

use std::collections::HashMap;

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::query::{FrameTimes, PassTime, Timestamps};
use super::{descriptor, vk_err, Buffer, Context};
use crate::error::Result;

/// Frames the CPU may record ahead of the GPU.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// One slot of the ring.
pub struct Frame {
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Signalled by the swapchain's acquire of this frame (the editor's submission waits on it).
    pub acquired: vk::Semaphore,
    pub pool: vk::DescriptorPool,
    pool_sets: u32,
    pub timestamps: Timestamps,
    passes: u32,
    buffers: HashMap<&'static str, Buffer>,
    /// The frame number this slot last ran (0: never) and whether it awaits its fence.
    number: u64,
    pending: bool,
    /// Its timestamps were read (by `wait`) since it was submitted.
    read: bool,
}

impl Frame {
    fn new(ctx: &Context, cmd: vk::CommandBuffer, index: usize) -> Result<Frame> {
        let raw = ctx.raw();
        // SAFETY: the device is live; each object is destroyed in `destroy`.
        let fence =
            unsafe { raw.create_fence(&vk::FenceCreateInfo::default(), None) }.map_err(vk_err("vkCreateFence"))?;
        // SAFETY: as above.
        let acquired = match unsafe { raw.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) } {
            Ok(s) => s,
            Err(r) => {
                // SAFETY: unused.
                unsafe { raw.destroy_fence(fence, None) };
                return Err(vk_err("vkCreateSemaphore")(r));
            }
        };
        let pool_sets = 32;
        let cleanup = |pool: Option<vk::DescriptorPool>| {
            // SAFETY: none of these was used.
            unsafe {
                raw.destroy_fence(fence, None);
                raw.destroy_semaphore(acquired, None);
                if let Some(p) = pool {
                    raw.destroy_descriptor_pool(p, None);
                }
            }
        };
        let pool = descriptor::pool(ctx, pool_sets, "frame.descriptors").inspect_err(|_| cleanup(None))?;
        let timestamps = Timestamps::new(ctx, 16).inspect_err(|_| cleanup(Some(pool)))?;
        ctx.device.set_name(fence, &format!("frame{index}.fence"));
        ctx.device.set_name(acquired, &format!("frame{index}.acquired"));
        ctx.device.set_name(cmd, &format!("frame{index}.commands"));
        Ok(Frame {
            cmd,
            fence,
            acquired,
            pool,
            pool_sets,
            timestamps,
            passes: 16,
            buffers: HashMap::new(),
            number: 0,
            pending: false,
            read: true,
        })
    }

    /// Writes `bytes` into this frame's host-visible buffer `name` (made, or grown, while the slot is
    /// idle: between `begin` and `submit`).
    pub fn upload(&mut self, ctx: &Context, name: &'static str, bytes: &[u8]) -> Result<()> {
        if self.buffers.get(name).is_none_or(|b| b.size < bytes.len() as u64) {
            if let Some(old) = self.buffers.remove(name) {
                old.destroy(ctx);
            }
            let size = (bytes.len() as u64).next_power_of_two().max(256);
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::UNIFORM_BUFFER;
            let b = Buffer::new(ctx, size, usage, MemoryLocation::CpuToGpu, name)?;
            self.buffers.insert(name, b);
        }
        self.buffers.get_mut(name).expect("made above").write(bytes);
        Ok(())
    }

    /// The buffer last written by [`Frame::upload`] under `name`.
    pub fn buffer(&self, name: &'static str) -> Option<&Buffer> {
        self.buffers.get(name)
    }

    /// The queries and the buffers at once (passes are timed while they bind the buffers).
    pub fn parts(&mut self) -> (&mut Timestamps, &HashMap<&'static str, Buffer>) {
        (&mut self.timestamps, &self.buffers)
    }

    /// Grows the descriptor pool and the timestamp queries to `sets` sets and `passes` passes.
    fn reserve(&mut self, ctx: &Context, sets: u32, passes: u32) -> Result<()> {
        if sets > self.pool_sets {
            let pool = descriptor::pool(ctx, sets.next_power_of_two(), "frame.descriptors")?;
            // SAFETY: the slot is idle (its fence was waited), so no set of the old pool is in use.
            unsafe { ctx.raw().destroy_descriptor_pool(self.pool, None) };
            self.pool = pool;
            self.pool_sets = sets.next_power_of_two();
        }
        if passes > self.passes {
            let t = Timestamps::new(ctx, passes.next_power_of_two())?;
            std::mem::replace(&mut self.timestamps, t).destroy(ctx);
            self.passes = passes.next_power_of_two();
        }
        Ok(())
    }

    fn destroy(self, ctx: &Context) {
        // SAFETY: the ring waited for every pending frame; each object is destroyed once.
        unsafe {
            ctx.raw().destroy_fence(self.fence, None);
            ctx.raw().destroy_semaphore(self.acquired, None);
            ctx.raw().destroy_descriptor_pool(self.pool, None);
        }
        self.timestamps.destroy(ctx);
        for (_, b) in self.buffers {
            b.destroy(ctx);
        }
    }
}

/// The GPU times of a finished frame.
#[derive(Clone, Debug)]
pub struct Finished {
    pub number: u64,
    pub timings: Vec<PassTime>,
    /// The whole frame, first command to last (`Timestamps::end_frame`).
    pub frame_ms: f64,
}

pub struct FrameRing {
    pool: vk::CommandPool,
    frames: Vec<Frame>,
    current: usize,
    count: u64,
    recording: bool,
    /// Times of settled frames not yet taken ([`FrameRing::take_finished`]).
    finished: Vec<Finished>,
}

impl FrameRing {
    pub fn new(ctx: &Context) -> Result<FrameRing> {
        let raw = ctx.raw();
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.device.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is live; the pool is destroyed in `destroy`.
        let pool = unsafe { raw.create_command_pool(&info, None) }.map_err(vk_err("vkCreateCommandPool"))?;
        ctx.device.set_name(pool, "frames.pool");
        let mut ring =
            FrameRing { pool, frames: Vec::new(), current: 0, count: 0, recording: false, finished: Vec::new() };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(FRAMES_IN_FLIGHT as u32);
        // SAFETY: `pool` was just created from this device.
        let cmds = match unsafe { raw.allocate_command_buffers(&alloc) } {
            Ok(c) => c,
            Err(r) => {
                ring.destroy(ctx);
                return Err(vk_err("vkAllocateCommandBuffers")(r));
            }
        };
        for (i, cmd) in cmds.into_iter().enumerate() {
            match Frame::new(ctx, cmd, i) {
                Ok(f) => ring.frames.push(f),
                Err(e) => {
                    ring.destroy(ctx);
                    return Err(e);
                }
            }
        }
        Ok(ring)
    }

    /// Waits for the next slot's previous frame, readies its pool (reset; grown to `sets` sets) and
    /// queries (room for `passes` passes), and begins its command buffer with the queries reset;
    /// `time_passes`: the frame times each pass, else the whole frame alone (`Timestamps::reset`).
    /// That earlier frame's GPU times join the finished ones.
    pub fn begin(&mut self, ctx: &Context, sets: u32, passes: u32, time_passes: bool) -> Result<()> {
        if self.recording {
            return Err(crate::Error::Bug("a frame was begun twice".into()));
        }
        self.current = (self.current + 1) % self.frames.len();
        self.settle(ctx, self.current)?;
        let f = &mut self.frames[self.current];
        f.reserve(ctx, sets, passes)?;
        let raw = ctx.raw();
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the slot's last submission completed (settled above): pool sets and command buffer
        // are not in use.
        unsafe {
            raw.reset_descriptor_pool(f.pool, vk::DescriptorPoolResetFlags::empty())
                .map_err(vk_err("vkResetDescriptorPool"))?;
            raw.reset_command_buffer(f.cmd, vk::CommandBufferResetFlags::empty())
                .map_err(vk_err("vkResetCommandBuffer"))?;
            raw.begin_command_buffer(f.cmd, &begin).map_err(vk_err("vkBeginCommandBuffer"))?;
        }
        f.timestamps.reset(ctx, f.cmd, time_passes);
        self.count += 1;
        f.number = self.count;
        self.recording = true;
        Ok(())
    }

    /// Waits for slot `i` if it is pending; its times join the finished ones.
    fn settle(&mut self, ctx: &Context, i: usize) -> Result<()> {
        let f = &mut self.frames[i];
        if !f.pending {
            return Ok(());
        }
        // SAFETY: the fence belongs to a submission of this slot.
        unsafe {
            ctx.raw().wait_for_fences(&[f.fence], true, u64::MAX).map_err(vk_err("vkWaitForFences"))?;
            ctx.raw().reset_fences(&[f.fence]).map_err(vk_err("vkResetFences"))?;
        }
        f.pending = false;
        if !f.read {
            f.read = true;
            let t = f.timestamps.read(ctx)?;
            self.finished.push(Finished { number: f.number, timings: t.passes, frame_ms: t.frame_ms });
        }
        Ok(())
    }

    /// The GPU times of the frames finished since the last call, oldest first.
    pub fn take_finished(&mut self) -> Vec<Finished> {
        let mut out = std::mem::take(&mut self.finished);
        out.sort_by_key(|f| f.number);
        out
    }

    /// The frame being recorded.
    pub fn current(&mut self) -> &mut Frame {
        &mut self.frames[self.current]
    }

    pub fn current_ref(&self) -> &Frame {
        &self.frames[self.current]
    }

    /// The number of the frame being recorded (or last submitted).
    pub fn number(&self) -> u64 {
        self.count
    }

    /// Ends and submits the current frame: waiting on `wait` (at `stage`) and signalling `signal`
    /// when given, its fence always.
    pub fn submit(
        &mut self,
        ctx: &Context,
        wait: Option<(vk::Semaphore, vk::PipelineStageFlags)>,
        signal: Option<vk::Semaphore>,
    ) -> Result<()> {
        self.recording = false;
        let f = &mut self.frames[self.current];
        let raw = ctx.raw();
        f.timestamps.end_frame(ctx, f.cmd);
        // SAFETY: the buffer is recording (begun in `begin`).
        unsafe { raw.end_command_buffer(f.cmd) }.map_err(vk_err("vkEndCommandBuffer"))?;
        let cmds = [f.cmd];
        let (wait_sems, wait_stages): (Vec<_>, Vec<_>) = wait.into_iter().unzip();
        let signals: Vec<_> = signal.into_iter().collect();
        let info = vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(&wait_sems)
            .wait_dst_stage_mask(&wait_stages)
            .signal_semaphores(&signals);
        // SAFETY: the fence is unsignalled (reset when settled); everything the buffer uses lives
        // until the fence is waited.
        unsafe { raw.queue_submit(ctx.device.queue, &[info], f.fence) }.map_err(vk_err("vkQueueSubmit"))?;
        f.pending = true;
        f.read = false;
        Ok(())
    }

    /// Ends the current frame without submitting it (nothing it recorded runs).
    pub fn abandon(&mut self, ctx: &Context) -> Result<()> {
        self.recording = false;
        let f = &self.frames[self.current];
        // SAFETY: the buffer is recording; ending it leaves it executable but it is never submitted
        // and is reset by the next `begin` of this slot.
        unsafe { ctx.raw().end_command_buffer(f.cmd) }.map_err(vk_err("vkEndCommandBuffer"))?;
        Ok(())
    }

    /// Ends the current frame without running what it recorded, but consumes `acquired` (a swapchain
    /// acquire already signalled it): an empty submission waits on it and signals the slot's fence,
    /// so the semaphore is unsignalled before the slot acquires with it again. The frame has no times.
    pub fn abandon_acquired(&mut self, ctx: &Context, acquired: vk::Semaphore) -> Result<()> {
        self.abandon(ctx)?;
        let f = &mut self.frames[self.current];
        let (waits, stages) = ([acquired], [vk::PipelineStageFlags::ALL_COMMANDS]);
        let info = vk::SubmitInfo::default().wait_semaphores(&waits).wait_dst_stage_mask(&stages);
        // SAFETY: the fence is unsignalled (reset when settled); the submission has no command buffers.
        unsafe { ctx.raw().queue_submit(ctx.device.queue, &[info], f.fence) }.map_err(vk_err("vkQueueSubmit"))?;
        f.pending = true;
        f.read = true;
        Ok(())
    }

    /// Waits for the frame just submitted and returns its GPU times (the headless path).
    pub fn wait(&mut self, ctx: &Context) -> Result<FrameTimes> {
        self.settle(ctx, self.current)?;
        let number = self.frames[self.current].number;
        Ok(match self.finished.iter().position(|f| f.number == number) {
            Some(k) => {
                let f = self.finished.remove(k);
                FrameTimes { passes: f.timings, frame_ms: f.frame_ms }
            }
            None => FrameTimes::default(),
        })
    }

    /// Waits for every frame in flight (before objects they use are destroyed); their times join
    /// the finished ones.
    pub fn wait_all(&mut self, ctx: &Context) -> Result<()> {
        for i in 0..self.frames.len() {
            self.settle(ctx, i)?;
        }
        Ok(())
    }

    pub fn destroy(mut self, ctx: &Context) {
        if self.recording {
            let _ = self.abandon(ctx);
        }
        let _ = self.wait_all(ctx);
        for f in self.frames.drain(..) {
            f.destroy(ctx);
        }
        // SAFETY: no buffer of the pool is pending (waited above).
        unsafe { ctx.raw().destroy_command_pool(self.pool, None) };
    }
}
