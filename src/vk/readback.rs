//! Reading an image back to the host: copy into a host-visible buffer, barrier to `HOST_READ`,
//! wait, then read the mapping.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{barrier, Buffer, Context, Image};
use crate::error::Result;

/// A host-visible buffer sized for `image`'s level 0 (`RGBA32F`).
pub fn buffer_for(ctx: &Context, image: &Image) -> Result<Buffer> {
    let size = image.width as u64 * image.height as u64 * 16;
    Buffer::new(ctx, size, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu, "readback")
}

/// Records the copy of `image` (in `layout`: `GENERAL` or `TRANSFER_SRC_OPTIMAL`, after any earlier
/// writes) into `buffer`, made visible to the host. The image keeps its layout.
pub fn record(ctx: &Context, cmd: vk::CommandBuffer, image: &Image, layout: vk::ImageLayout, buffer: &Buffer) {
    barrier::memory(
        ctx,
        cmd,
        (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
        barrier::TRANSFER_READ,
    );
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D { width: image.width, height: image.height, depth: 1 });
    // SAFETY: `cmd` is recording; the buffer holds the whole level; the image is in `layout`.
    unsafe { ctx.raw().cmd_copy_image_to_buffer(cmd, image.raw, layout, buffer.raw, &[region]) };
    barrier::to_host(ctx, cmd, buffer.raw);
}

/// The pixels of a buffer filled by [`record`], after the submission completed.
pub fn pixels(buffer: &Buffer) -> Vec<[f32; 4]> {
    let floats: Vec<f32> =
        buffer.mapped().chunks_exact(4).map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect();
    floats.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
}
