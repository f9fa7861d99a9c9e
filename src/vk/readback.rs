//! Reading an `RGBA32F` image back to the host: copy into a host-visible buffer, barrier to
//! `HOST_READ`, wait, then read the mapping.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{Buffer, Context, Image};
use crate::error::Result;

/// A host-visible buffer sized for `image`'s level 0 (`RGBA32F`).
pub fn buffer_for(ctx: &Context, image: &Image) -> Result<Buffer> {
    let size = image.width as u64 * image.height as u64 * 16;
    Buffer::new(ctx, size, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu, "readback")
}

/// Records the copy of `image` (in `layout`, written by `src`) into `buffer`, made visible to the host.
pub fn record(ctx: &Context, cmd: vk::CommandBuffer, image: &Image, layout: vk::ImageLayout, buffer: &Buffer) {
    image.barrier(
        ctx,
        cmd,
        layout,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_WRITE),
        (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ),
    );
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D { width: image.width, height: image.height, depth: 1 });
    // SAFETY: `cmd` is recording; the buffer holds the whole level.
    unsafe {
        ctx.raw().cmd_copy_image_to_buffer(cmd, image.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer.raw, &[region])
    };
    let b = [vk::BufferMemoryBarrier2::default()
        .buffer(buffer.raw)
        .size(vk::WHOLE_SIZE)
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)];
    let dep = vk::DependencyInfo::default().buffer_memory_barriers(&b);
    // SAFETY: `cmd` is recording.
    unsafe { ctx.raw().cmd_pipeline_barrier2(cmd, &dep) };
}

/// The pixels of a buffer filled by [`record`], after the submission completed.
pub fn pixels(buffer: &Buffer) -> Vec<[f32; 4]> {
    let floats: Vec<f32> =
        buffer.mapped().chunks_exact(4).map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect();
    floats.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
}
