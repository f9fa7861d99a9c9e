//! The swapchain: created for the surface's current size (never zero: a minimised window has no
//! swapchain), recreated when out of date. An image is acquired with the frame's semaphore (no CPU
//! wait); the frame's submission waits on it, writes the image (a copy, then the tool panel drawn
//! into its view) and signals the image's own render-done semaphore, which the present waits on.

use ash::vk;

use super::surface::Surface;
use super::{vk_err, Context};
use crate::error::{Error, Result};

pub struct Swapchain {
    loader: ash::khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    /// One view per image (the tool panel renders into it).
    pub views: Vec<vk::ImageView>,
    /// One render-done semaphore per image: signalled by the frame that wrote it, waited by present.
    pub rendered: Vec<vk::Semaphore>,
    pub extent: vk::Extent2D,
    pub format: vk::Format,
    /// The images can be copied from (a screenshot reads the presented pixels).
    pub readable: bool,
}

/// What acquiring gave.
pub enum Acquired {
    Image(u32),
    /// The swapchain does not match the surface: recreate it.
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
        let needed = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(needed) {
            return Err(Error::NoDevice("the window surface cannot be written by copies and drawing".into()));
        }
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let usage = if readable { needed | vk::ImageUsageFlags::TRANSFER_SRC } else { needed };
        let count =
            (caps.min_image_count + 1).min(if caps.max_image_count == 0 { u32::MAX } else { caps.max_image_count });
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
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
        let mut sc = Swapchain {
            loader,
            raw,
            images,
            views: Vec::new(),
            rendered: Vec::new(),
            extent,
            format: chosen.format,
            readable,
        };
        for (i, &image) in sc.images.iter().enumerate() {
            let info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(sc.format)
                .subresource_range(super::barrier::color());
            // SAFETY: the image belongs to this swapchain; the view is destroyed in `destroy`.
            let view = unsafe { ctx.raw().create_image_view(&info, None) };
            // SAFETY: the device is live; the semaphore is destroyed in `destroy`.
            let sem = unsafe { ctx.raw().create_semaphore(&vk::SemaphoreCreateInfo::default(), None) };
            match (view, sem) {
                (Ok(v), Ok(s)) => {
                    ctx.device.set_name(s, &format!("swapchain.rendered{i}"));
                    sc.views.push(v);
                    sc.rendered.push(s);
                }
                (v, s) => {
                    // SAFETY: unused.
                    unsafe {
                        if let Ok(v) = v {
                            ctx.raw().destroy_image_view(v, None);
                        }
                        if let Ok(s) = s {
                            ctx.raw().destroy_semaphore(s, None);
                        }
                    }
                    let e = v.err().map(vk_err("vkCreateImageView")).or(s.err().map(vk_err("vkCreateSemaphore")));
                    sc.destroy(ctx);
                    return Err(e.expect("one of the two failed"));
                }
            }
        }
        ctx.device.set_name(raw, "swapchain");
        Ok(Some(sc))
    }

    /// Acquires an image; `signal` is signalled when it can be written (the frame's submission
    /// waits on it). Does not wait.
    pub fn acquire(&self, signal: vk::Semaphore) -> Result<Acquired> {
        // SAFETY: the semaphore is unsignalled (its last signal was waited by the frame that used it,
        // which completed before the frame slot was reused); the swapchain is live.
        let got = unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, signal, vk::Fence::null()) };
        match got {
            Ok((index, _suboptimal)) => Ok(Acquired::Image(index)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(result) => Err(vk_err("vkAcquireNextImageKHR")(result)),
        }
    }

    /// Presents image `index` once its `rendered` semaphore is signalled; false when the swapchain
    /// turned out of date or suboptimal.
    pub fn present(&self, ctx: &Context, index: u32) -> Result<bool> {
        let swapchains = [self.raw];
        let indices = [index];
        let waits = [self.rendered[index as usize]];
        let info =
            vk::PresentInfoKHR::default().swapchains(&swapchains).image_indices(&indices).wait_semaphores(&waits);
        // SAFETY: the image was acquired and a submission that signals `waits` was made.
        match unsafe { self.loader.queue_present(ctx.device.queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(result) => Err(vk_err("vkQueuePresentKHR")(result)),
        }
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the caller waited for the frames that used the images (the device is idle with
        // respect to them); each object is destroyed once.
        unsafe {
            let _ = ctx.raw().device_wait_idle();
            for &v in &self.views {
                ctx.raw().destroy_image_view(v, None);
            }
            for &s in &self.rendered {
                ctx.raw().destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
