//! The command pool, its one primary command buffer and the fence a submission waits on. Work is
//! recorded by a closure and submitted once; the call returns when the GPU is done.

use ash::vk;

use super::{vk_err, Device};
use crate::error::Result;

pub struct Commands {
    pub pool: vk::CommandPool,
    pub buffer: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Commands {
    pub fn new(device: &Device) -> Result<Commands> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the device is live; the pool is destroyed in `destroy`.
        let pool = unsafe { device.raw.create_command_pool(&info, None) }.map_err(vk_err("vkCreateCommandPool"))?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `pool` was just created from this device.
        let buffer = match unsafe { device.raw.allocate_command_buffers(&alloc) } {
            Ok(b) => b[0],
            Err(result) => {
                // SAFETY: the pool has no buffers in use.
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(vk_err("vkAllocateCommandBuffers")(result));
            }
        };
        // SAFETY: the device is live.
        let fence = match unsafe { device.raw.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(result) => {
                // SAFETY: the pool's buffer was never submitted.
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(vk_err("vkCreateFence")(result));
            }
        };
        device.set_name(pool, "commands.pool");
        device.set_name(buffer, "commands.buffer");
        device.set_name(fence, "commands.fence");
        Ok(Commands { pool, buffer, fence })
    }

    /// Records with `record`, submits, and waits for completion. An error from `record` ends the
    /// recording without submitting.
    pub fn run(&self, device: &Device, record: impl FnOnce(vk::CommandBuffer) -> Result<()>) -> Result<()> {
        let raw = &device.raw;
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the buffer is not pending (every submission is waited on before returning).
        unsafe {
            raw.reset_command_buffer(self.buffer, vk::CommandBufferResetFlags::empty())
                .map_err(vk_err("vkResetCommandBuffer"))?;
            raw.begin_command_buffer(self.buffer, &begin).map_err(vk_err("vkBeginCommandBuffer"))?;
        }
        let recorded = record(self.buffer);
        // SAFETY: the buffer is in the recording state.
        let ended = unsafe { raw.end_command_buffer(self.buffer) }.map_err(vk_err("vkEndCommandBuffer"));
        recorded?;
        ended?;
        let buffers = [self.buffer];
        let submit = vk::SubmitInfo::default().command_buffers(&buffers);
        // SAFETY: the fence is unsignalled (reset after every wait); the queue belongs to the device.
        unsafe {
            raw.queue_submit(device.queue, &[submit], self.fence).map_err(vk_err("vkQueueSubmit"))?;
            let waited = raw.wait_for_fences(&[self.fence], true, u64::MAX).map_err(vk_err("vkWaitForFences"));
            raw.reset_fences(&[self.fence]).map_err(vk_err("vkResetFences"))?;
            waited
        }
    }

    pub fn destroy(self, device: &Device) {
        // SAFETY: the device is idle (the context waited); the objects are destroyed once.
        unsafe {
            device.raw.destroy_fence(self.fence, None);
            device.raw.destroy_command_pool(self.pool, None);
        }
    }
}
