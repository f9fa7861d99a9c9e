//! Buffers and their memory (through `gpu-allocator`). Host-visible buffers are written and read
//! through their persistent mapping; a buffer is freed by [`Buffer::destroy`], which takes it by value.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::{alloc_err, vk_err, Context};
use crate::error::{Error, Result};

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Allocation,
}

impl Buffer {
    pub fn new(
        ctx: &Context,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        name: &str,
    ) -> Result<Buffer> {
        let raw_dev = ctx.raw();
        let info =
            vk::BufferCreateInfo::default().size(size.max(4)).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: the device is live; the buffer is destroyed in `destroy` or on the error path below.
        let raw = unsafe { raw_dev.create_buffer(&info, None) }.map_err(vk_err("vkCreateBuffer"))?;
        // SAFETY: `raw` is a live buffer of this device.
        let requirements = unsafe { raw_dev.get_buffer_memory_requirements(raw) };
        let allocated = ctx.allocator.lock().map_err(|_| poisoned())?.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer has no memory bound and was never used.
                unsafe { raw_dev.destroy_buffer(raw, None) };
                return Err(alloc_err("gpu_allocator::allocate")(e));
            }
        };
        // SAFETY: the allocation satisfies `requirements` and is not bound to anything else.
        if let Err(result) = unsafe { raw_dev.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            // SAFETY: never used.
            unsafe { raw_dev.destroy_buffer(raw, None) };
            let _ = ctx.allocator.lock().map(|mut a| a.free(allocation));
            return Err(vk_err("vkBindBufferMemory")(result));
        }
        ctx.device.set_name(raw, name);
        Ok(Buffer { raw, size, allocation })
    }

    /// A host-visible buffer holding `bytes`.
    pub fn upload(ctx: &Context, bytes: &[u8], usage: vk::BufferUsageFlags, name: &str) -> Result<Buffer> {
        let mut b = Buffer::new(ctx, bytes.len() as u64, usage, MemoryLocation::CpuToGpu, name)?;
        b.write(bytes);
        Ok(b)
    }

    /// Writes `bytes` at the start of a host-visible buffer (no-op for device-local memory, which
    /// this program never writes from the host).
    pub fn write(&mut self, bytes: &[u8]) {
        if let Some(dst) = self.allocation.mapped_slice_mut() {
            let n = bytes.len().min(dst.len());
            dst[..n].copy_from_slice(&bytes[..n]);
        }
    }

    /// The contents of a host-visible buffer.
    pub fn mapped(&self) -> &[u8] {
        let s = self.allocation.mapped_slice().unwrap_or(&[]);
        &s[..(self.size as usize).min(s.len())]
    }

    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default().buffer(self.raw).offset(0).range(vk::WHOLE_SIZE)
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU is done with the buffer (work is waited on).
        unsafe { ctx.raw().destroy_buffer(self.raw, None) };
        if let Ok(mut a) = ctx.allocator.lock() {
            let _ = a.free(self.allocation);
        }
    }
}

pub(super) fn poisoned() -> Error {
    Error::Vulkan { call: "allocator lock", result: vk::Result::ERROR_UNKNOWN }
}
