//! The window's presentation surface (`VK_KHR_surface` through `ash-window`). Destroyed by
//! [`Surface::destroy`] before the instance.

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::{vk_err, Context};
use crate::error::Result;

pub struct Surface {
    pub loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

/// The instance extensions a surface on `display` needs.
pub fn required_extensions(display: RawDisplayHandle) -> Result<Vec<*const std::ffi::c_char>> {
    Ok(ash_window::enumerate_required_extensions(display).map_err(vk_err("enumerate_required_extensions"))?.to_vec())
}

impl Surface {
    pub fn new(ctx: &Context, display: RawDisplayHandle, window: RawWindowHandle) -> Result<Surface> {
        // SAFETY: the handles come from a live window that outlives the surface (the editor drops
        // the surface before the window); the instance has the extensions `required_extensions` named.
        let raw = unsafe { ash_window::create_surface(&ctx.instance.entry, &ctx.instance.raw, display, window, None) }
            .map_err(vk_err("vkCreateSurfaceKHR"))?;
        let loader = ash::khr::surface::Instance::new(&ctx.instance.entry, &ctx.instance.raw);
        // SAFETY: `raw` was just created on this instance; the queue family belongs to the device.
        let ok =
            unsafe { loader.get_physical_device_surface_support(ctx.device.physical, ctx.device.queue_family, raw) }
                .map_err(vk_err("vkGetPhysicalDeviceSurfaceSupportKHR"))?;
        if !ok {
            // SAFETY: unused.
            unsafe { loader.destroy_surface(raw, None) };
            return Err(crate::Error::NoDevice(format!("{} cannot present to this window", ctx.device.name)));
        }
        Ok(Surface { loader, raw })
    }

    pub fn destroy(self) {
        // SAFETY: the swapchain made from it is destroyed first.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}
