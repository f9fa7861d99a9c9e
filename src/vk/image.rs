//! 2D images with one view, their memory, layout transitions, uploads from a staging buffer, and
//! samplers. Freed by [`Image::destroy`], which takes the image by value.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::buffer::poisoned;
use super::{alloc_err, vk_err, Buffer, Context};
use crate::error::Result;

pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub width: u32,
    pub height: u32,
    pub format: vk::Format,
    pub mip_levels: u32,
    pub aspect: vk::ImageAspectFlags,
    allocation: Allocation,
}

impl Image {
    pub fn new(
        ctx: &Context,
        (width, height): (u32, u32),
        format: vk::Format,
        mip_levels: u32,
        usage: vk::ImageUsageFlags,
        name: &str,
    ) -> Result<Image> {
        let dev = ctx.raw();
        let aspect =
            if format == vk::Format::D32_SFLOAT { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width, height, depth: 1 })
            .mip_levels(mip_levels)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: the device is live; the image is destroyed in `destroy` or on the error paths below.
        let raw = unsafe { dev.create_image(&info, None) }.map_err(vk_err("vkCreateImage"))?;
        // SAFETY: `raw` is a live image of this device.
        let requirements = unsafe { dev.get_image_memory_requirements(raw) };
        let allocated = ctx.allocator.lock().map_err(|_| poisoned())?.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: never used.
                unsafe { dev.destroy_image(raw, None) };
                return Err(alloc_err("gpu_allocator::allocate")(e));
            }
        };
        let free = |allocation| {
            // SAFETY: never used.
            unsafe { dev.destroy_image(raw, None) };
            let _ = ctx.allocator.lock().map(|mut a| a.free(allocation));
        };
        // SAFETY: the allocation satisfies `requirements` and is bound once.
        if let Err(result) = unsafe { dev.bind_image_memory(raw, allocation.memory(), allocation.offset()) } {
            free(allocation);
            return Err(vk_err("vkBindImageMemory")(result));
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range(aspect, mip_levels));
        // SAFETY: `raw` is live with memory bound.
        let view = match unsafe { dev.create_image_view(&view_info, None) } {
            Ok(v) => v,
            Err(result) => {
                free(allocation);
                return Err(vk_err("vkCreateImageView")(result));
            }
        };
        ctx.device.set_name(raw, name);
        ctx.device.set_name(view, &format!("{name}.view"));
        Ok(Image { raw, view, width, height, format, mip_levels, aspect, allocation })
    }

    /// A transition of every mip level from `from` to `to`, ordering `src` stages/accesses before `dst`.
    #[allow(clippy::too_many_arguments)]
    pub fn barrier(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        from: vk::ImageLayout,
        to: vk::ImageLayout,
        src: (vk::PipelineStageFlags2, vk::AccessFlags2),
        dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
    ) {
        super::barrier::image(ctx, cmd, self.raw, range(self.aspect, self.mip_levels), (from, to), src, dst);
    }

    /// Clears the image (a colour image made with `TRANSFER_DST`) to zero in `GENERAL`, ready for `dst`.
    pub fn clear_to_general(&self, ctx: &Context, cmd: vk::CommandBuffer, dst: super::barrier::Scope) {
        self.fill_to_general(ctx, cmd, [0.0; 4], dst);
    }

    /// Clears the image (a colour image made with `TRANSFER_DST`, of a float format) to `value` in
    /// `GENERAL`, ready for `dst`.
    pub fn fill_to_general(&self, ctx: &Context, cmd: vk::CommandBuffer, value: [f32; 4], dst: super::barrier::Scope) {
        use super::barrier::{EARLIER_READS, TRANSFER_WRITE};
        self.barrier(ctx, cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL, EARLIER_READS, TRANSFER_WRITE);
        let ranges = [range(self.aspect, self.mip_levels)];
        // SAFETY: `cmd` is recording outside a render pass; the image is in GENERAL (above) and was
        // made with TRANSFER_DST (the caller's contract).
        unsafe {
            ctx.raw().cmd_clear_color_image(
                cmd,
                self.raw,
                vk::ImageLayout::GENERAL,
                &vk::ClearColorValue { float32: value },
                &ranges,
            )
        };
        self.barrier(ctx, cmd, vk::ImageLayout::GENERAL, vk::ImageLayout::GENERAL, TRANSFER_WRITE, dst);
    }

    /// Makes the image writable in `GENERAL` by `dst`, dropping its contents once earlier frames'
    /// reads of it are done (the persistent targets are rewritten each frame).
    pub fn discard_to_general(&self, ctx: &Context, cmd: vk::CommandBuffer, dst: super::barrier::Scope) {
        self.barrier(
            ctx,
            cmd,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::GENERAL,
            super::barrier::EARLIER_READS,
            dst,
        );
    }

    /// Records a copy of level 0 into `dst` (the same size and format), both in `GENERAL` (this
    /// image made with `TRANSFER_SRC`, `dst` with `TRANSFER_DST`: the caller's contract, with the
    /// barriers around it).
    pub fn record_copy_to(&self, ctx: &Context, cmd: vk::CommandBuffer, dst: &Image) {
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(self.aspect).layer_count(1);
        let region = [vk::ImageCopy::default().src_subresource(layers).dst_subresource(layers).extent(vk::Extent3D {
            width: self.width.min(dst.width),
            height: self.height.min(dst.height),
            depth: 1,
        })];
        // SAFETY: `cmd` is recording outside a render pass; both images are live, in GENERAL, with
        // the usages above (the caller's contract), and the region lies within both.
        unsafe {
            ctx.raw().cmd_copy_image(
                cmd,
                self.raw,
                vk::ImageLayout::GENERAL,
                dst.raw,
                vk::ImageLayout::GENERAL,
                &region,
            )
        };
    }

    /// Records copies of every level from `staging` (levels packed one after another, tightly) and
    /// leaves the image in `SHADER_READ_ONLY_OPTIMAL` for compute shaders.
    pub fn record_upload(&self, ctx: &Context, cmd: vk::CommandBuffer, staging: &Buffer, level_offsets: &[u64]) {
        self.barrier(
            ctx,
            cmd,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
        );
        let regions: Vec<vk::BufferImageCopy> = level_offsets
            .iter()
            .enumerate()
            .map(|(level, &offset)| {
                vk::BufferImageCopy::default()
                    .buffer_offset(offset)
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: self.aspect,
                        mip_level: level as u32,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D {
                        width: (self.width >> level).max(1),
                        height: (self.height >> level).max(1),
                        depth: 1,
                    })
            })
            .collect();
        // SAFETY: `cmd` is recording; buffer and image are live and the regions lie inside both.
        unsafe {
            ctx.raw().cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                self.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
        self.barrier(
            ctx,
            cmd,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_WRITE),
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
        );
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the caller guarantees the GPU is done with the image (work is waited on).
        unsafe {
            ctx.raw().destroy_image_view(self.view, None);
            ctx.raw().destroy_image(self.raw, None);
        }
        if let Ok(mut a) = ctx.allocator.lock() {
            let _ = a.free(self.allocation);
        }
    }
}

pub fn range(aspect: vk::ImageAspectFlags, levels: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: levels,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// Whether `format` supports `features` with optimal tiling on this device.
pub fn supports(ctx: &Context, format: vk::Format, features: vk::FormatFeatureFlags) -> bool {
    // SAFETY: the physical device belongs to the instance.
    let props = unsafe { ctx.instance.raw.get_physical_device_format_properties(ctx.device.physical, format) };
    props.optimal_tiling_features.contains(features)
}

/// An equirect sampler: linear filtering (where `linear`) and mips (between two levels with
/// `mipmap` LINEAR, from the nearest level with NEAREST), `u` repeating (the seam), `v` clamped.
pub fn equirect_sampler(ctx: &Context, linear: bool, mipmap: vk::SamplerMipmapMode, name: &str) -> Result<vk::Sampler> {
    let filter = if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter)
        .min_filter(filter)
        .mipmap_mode(mipmap)
        .address_mode_u(vk::SamplerAddressMode::REPEAT)
        .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .min_lod(0.0)
        .max_lod(vk::LOD_CLAMP_NONE);
    // SAFETY: the device is live; the sampler is destroyed by its owner.
    let s = unsafe { ctx.raw().create_sampler(&info, None) }.map_err(vk_err("vkCreateSampler"))?;
    ctx.device.set_name(s, name);
    Ok(s)
}
