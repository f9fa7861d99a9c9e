//! Pipeline barriers in one place: image layout transitions, global memory barriers between passes
//! and the barrier that makes a copy visible to the host. A scope is `(stages, accesses)`.

use ash::vk;

use super::Context;

/// `(stages, accesses)` on one side of a barrier.
pub type Scope = (vk::PipelineStageFlags2, vk::AccessFlags2);

/// Nothing before (a fresh image) or after.
pub const NONE: Scope = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);

/// Any earlier compute or transfer work that read the image: overwriting it must wait for those reads
/// (persistent targets are read by the previous frame, possibly still in flight).
pub const EARLIER_READS: Scope = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw()
            | vk::PipelineStageFlags2::ALL_TRANSFER.as_raw()
            | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw(),
    ),
    vk::AccessFlags2::NONE,
);

pub const COMPUTE_WRITE: Scope = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE);

pub const COMPUTE_READ_WRITE: Scope = (
    vk::PipelineStageFlags2::COMPUTE_SHADER,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw() | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
    ),
);

/// Every later access (the accumulation image after a copy: compute passes, or a readback).
pub const ANY: Scope = (
    vk::PipelineStageFlags2::ALL_COMMANDS,
    vk::AccessFlags2::from_raw(vk::AccessFlags2::MEMORY_READ.as_raw() | vk::AccessFlags2::MEMORY_WRITE.as_raw()),
);
pub const TRANSFER_READ: Scope = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_READ);
pub const TRANSFER_WRITE: Scope = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);

pub const COLOR_ATTACHMENT: Scope = (
    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw() | vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw(),
    ),
);

/// A layout transition of `range` of `image`, ordering `src` stages/accesses before `dst`.
pub fn transition(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    (from, to): (vk::ImageLayout, vk::ImageLayout),
    src: Scope,
    dst: Scope,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(from)
        .new_layout(to)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(range)
}

/// Records [`transition`] (the whole colour image when `range` is [`color`]).
pub fn image(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    layouts: (vk::ImageLayout, vk::ImageLayout),
    src: Scope,
    dst: Scope,
) {
    let b = [transition(image, range, layouts, src, dst)];
    ctx.counts.barrier();
    // SAFETY: `cmd` is recording; the image is live (the caller's).
    unsafe { ctx.raw().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b)) };
}

/// The single level and layer of a colour image.
pub fn color() -> vk::ImageSubresourceRange {
    super::image::range(vk::ImageAspectFlags::COLOR, 1)
}

/// Orders every `src` access before every `dst` access (all resources).
pub fn memory(ctx: &Context, cmd: vk::CommandBuffer, src: Scope, dst: Scope) {
    let b = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    ctx.counts.barrier();
    // SAFETY: `cmd` is recording.
    unsafe { ctx.raw().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&b)) };
}

/// Makes transfer writes to `buffer` visible to host reads after the submission's fence.
pub fn to_host(ctx: &Context, cmd: vk::CommandBuffer, buffer: vk::Buffer) {
    let b = [vk::BufferMemoryBarrier2::default()
        .buffer(buffer)
        .size(vk::WHOLE_SIZE)
        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)];
    ctx.counts.barrier();
    // SAFETY: `cmd` is recording; the buffer is live (the caller's).
    unsafe { ctx.raw().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&b)) };
}

/// One barrier ordering each `(resource, src)` before `dst`: an image barrier (`GENERAL` kept, every
/// level and layer) per image, a buffer barrier (the whole buffer) per buffer.
pub fn resources(ctx: &Context, cmd: vk::CommandBuffer, list: &[(super::hazards::Resource, Scope)], dst: Scope) {
    use super::hazards::Resource;
    let all = vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: vk::REMAINING_MIP_LEVELS,
        base_array_layer: 0,
        layer_count: vk::REMAINING_ARRAY_LAYERS,
    };
    let general = (vk::ImageLayout::GENERAL, vk::ImageLayout::GENERAL);
    let images: Vec<vk::ImageMemoryBarrier2> = list
        .iter()
        .filter_map(|&(r, src)| match r {
            Resource::Image(image) => Some(transition(image, all, general, src, dst)),
            Resource::Buffer(_) => None,
        })
        .collect();
    let buffers: Vec<vk::BufferMemoryBarrier2> = list
        .iter()
        .filter_map(|&(r, src)| match r {
            Resource::Buffer(buffer) => Some(
                vk::BufferMemoryBarrier2::default()
                    .buffer(buffer)
                    .size(vk::WHOLE_SIZE)
                    .src_stage_mask(src.0)
                    .src_access_mask(src.1)
                    .dst_stage_mask(dst.0)
                    .dst_access_mask(dst.1)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED),
            ),
            Resource::Image(_) => None,
        })
        .collect();
    ctx.counts.barrier();
    let info = vk::DependencyInfo::default().image_memory_barriers(&images).buffer_memory_barriers(&buffers);
    // SAFETY: `cmd` is recording; every image and buffer is live (the caller's), images in `GENERAL`.
    unsafe { ctx.raw().cmd_pipeline_barrier2(cmd, &info) };
}
