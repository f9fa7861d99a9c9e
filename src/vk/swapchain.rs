//! The swapchain: created for the surface's current size (never zero: a minimised window has no
//! swapchain), recreated when out of date. An image is acquired with a fence, filled by a copy the
//! caller records, and presented after that submission completed.

use ash::vk;

use super::surface::Surface;
use super::{vk_err, Context};
use crate::error::{Error, Result};

pub struct Swapchain {
    loader: ash::khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub extent: vk::Extent2D,
    pub format: vk::Format,
    fence: vk::Fence,
}

/// What acquiring gave.
pub enum Acquired {
    Image(u32),
    /// The swapchain no longer matches the surface: recreate it.
    OutOfDate,
}

impl Swapchain {
    /// A swapchain of `size` (clamped to what the surface allows); `None` when that is zero.
    pub fn new(ctx: &Context, surface: &Surface, size: (u32, u32)) -> Result<Option<Swapchain>> {
        let pd = ctx.device.physical;
        // SAFETY: surface and physical device belong to this instance.
        let (caps, formats) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_capabilities(pd, surface.raw)
                    .map_err(vk_err("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?,
                surface
                    .loader
                    .get_physical_device_surface_formats(pd, surface.raw)
                    .map_err(vk_err("vkGetPhysicalDeviceSurfaceFormatsKHR"))?,
            )
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        let chosen = formats
            .iter()
            .find(|f| matches!(f.format, vk::Format::B8G8R8A8_UNORM | vk::Format::R8G8B8A8_UNORM))
            .or(formats.first())
            .copied()
            .ok_or_else(|| Error::NoDevice("the window surface offers no format".into()))?;
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(Error::NoDevice("the window surface cannot be written by copies".into()));
        }
        let count =
            (caps.min_image_count + 1).min(if caps.max_image_count == 0 { u32::MAX } else { caps.max_image_count });
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true);
        let loader = ash::khr::swapchain::Device::new(&ctx.instance.raw, &ctx.device.raw);
        // SAFETY: the surface is live and supported by this device's queue family.
        let raw = unsafe { loader.create_swapchain(&info, None) }.map_err(vk_err("vkCreateSwapchainKHR"))?;
        // SAFETY: `raw` is live.
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(i) => i,
            Err(result) => {
                // SAFETY: unused.
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(vk_err("vkGetSwapchainImagesKHR")(result));
            }
        };
        // SAFETY: the device is live.
        let fence = match unsafe { ctx.raw().create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(result) => {
                // SAFETY: unused.
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(vk_err("vkCreateFence")(result));
            }
        };
        ctx.device.set_name(raw, "swapchain");
        Ok(Some(Swapchain { loader, raw, images, extent, format: chosen.format, fence }))
    }

    /// Acquires an image and waits until it can be written.
    pub fn acquire(&self, ctx: &Context) -> Result<Acquired> {
        // SAFETY: the fence is unsignalled (reset after each wait); the swapchain is live.
        let got = unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, vk::Semaphore::null(), self.fence) };
        match got {
            Ok((index, _suboptimal)) => {
                // SAFETY: the fence was handed to the acquire above.
                unsafe {
                    ctx.raw().wait_for_fences(&[self.fence], true, u64::MAX).map_err(vk_err("vkWaitForFences"))?;
                    ctx.raw().reset_fences(&[self.fence]).map_err(vk_err("vkResetFences"))?;
                }
                Ok(Acquired::Image(index))
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(vk_err("vkAcquireNextImageKHR")(result)),
        }
    }

    /// Lets `record` write image `index` (in `TRANSFER_DST_OPTIMAL`, by copies or blits) and
    /// presents it; false when the swapchain turned out of date or suboptimal.
    pub fn present(
        &self,
        ctx: &Context,
        index: u32,
        record: impl FnOnce(vk::CommandBuffer, vk::Image) -> Result<()>,
    ) -> Result<bool> {
        let image = self.images[index as usize];
        let range = super::image::range(vk::ImageAspectFlags::COLOR, 1);
        let copy = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
        let none = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
        ctx.commands.run(&ctx.device, |cmd| {
            let before = [super::image::transition(
                image,
                range,
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
                none,
                copy,
            )];
            // SAFETY: `cmd` is recording; the image was acquired.
            unsafe {
                ctx.raw().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&before))
            };
            record(cmd, image)?;
            let after = [super::image::transition(
                image,
                range,
                (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::PRESENT_SRC_KHR),
                copy,
                none,
            )];
            // SAFETY: as above.
            unsafe {
                ctx.raw().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&after))
            };
            Ok(())
        })?;
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default().swapchains(&swapchains).image_indices(&indices);
        // SAFETY: the writes completed (`run` waited); the image is in PRESENT_SRC.
        match unsafe { self.loader.queue_present(ctx.device.queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(result) => Err(vk_err("vkQueuePresentKHR")(result)),
        }
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the device is idle with respect to the swapchain's images (presents are waited).
        unsafe {
            let _ = ctx.raw().device_wait_idle();
            ctx.raw().destroy_fence(self.fence, None);
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
