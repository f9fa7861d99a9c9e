//! The device plan: how a frame starts and zeroes its images on this kind of device, a pure function
//! of the device's type (tested without a device). Every choice draws the same image (within the
//! rounding of a different order of additions); they differ in where the bytes go.
//!
//! On a CPU device (Mesa lavapipe) a transfer clear or copy is a `memset`/`memcpy` on the host, far
//! cheaper than a shader over the same pixels (whose cost is per lane), so the frame clears and
//! copies. On a GPU, image clears and copies go through the transfer or raster path, far slower
//! than compute shaders writing the same images (docs/renderer.md, Device plan), so the frame
//! writes its images from compute passes instead.

use ash::vk;

/// The choices of one device kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DevicePlan {
    /// A frame that rasterises and filters sparsely clears the accumulation image and leaves the
    /// diffuse term to the sparse filter and the background to a pass over the blocks off the
    /// object (`compact::Start::Later`); false: the compact pass writes every pixel of it, the
    /// background and the diffuse term (`compact::Start::Here`), with no clear.
    pub clear_then_later: bool,
    /// The images the lobe passes add into (the sparse filter's cells, the rough lobes' image) are
    /// zeroed by a compute pass (`zero.comp`) rather than `vkCmdClearColorImage`.
    pub zero_by_compute: bool,
    /// A frame that keeps its G-buffer starts from a copy of the image the background and diffuse
    /// passes drew the frame before (`Targets::base`); false: it draws that image again in the
    /// compact pass over the G-buffer (`compact::Start::Here`), with no copy in either frame.
    pub copy_base: bool,
}

impl DevicePlan {
    /// The plan of a CPU device: clears and copies.
    pub const CPU: DevicePlan = DevicePlan { clear_then_later: true, zero_by_compute: false, copy_base: true };

    /// The plan of a GPU: compute passes write every image, no transfer clears or copies.
    pub const GPU: DevicePlan = DevicePlan { clear_then_later: false, zero_by_compute: true, copy_base: false };

    /// The plan for a device of type `kind`.
    pub fn for_device(kind: vk::PhysicalDeviceType) -> DevicePlan {
        if kind == vk::PhysicalDeviceType::CPU {
            DevicePlan::CPU
        } else {
            DevicePlan::GPU
        }
    }

    /// `BRDF_SHOP_FRAME_PLAN` (`cpu` or `gpu`) where set, else the plan for `kind`.
    pub fn from_env(kind: vk::PhysicalDeviceType) -> DevicePlan {
        match std::env::var(ENV).as_deref() {
            Ok("cpu") => DevicePlan::CPU,
            Ok("gpu") => DevicePlan::GPU,
            _ => DevicePlan::for_device(kind),
        }
    }

    /// The plan's name (`cpu` or `gpu`; `mixed` for a hand-made one).
    pub fn name(&self) -> &'static str {
        match *self {
            DevicePlan::CPU => "cpu",
            DevicePlan::GPU => "gpu",
            _ => "mixed",
        }
    }
}

/// The environment variable that forces a plan (`cpu` or `gpu`) on any device.
pub const ENV: &str = "BRDF_SHOP_FRAME_PLAN";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_devices_clear_and_copy_gpus_write_from_compute() {
        let cpu = DevicePlan::for_device(vk::PhysicalDeviceType::CPU);
        assert_eq!(cpu, DevicePlan { clear_then_later: true, zero_by_compute: false, copy_base: true });
        for gpu in [
            vk::PhysicalDeviceType::DISCRETE_GPU,
            vk::PhysicalDeviceType::INTEGRATED_GPU,
            vk::PhysicalDeviceType::VIRTUAL_GPU,
            vk::PhysicalDeviceType::OTHER,
        ] {
            let p = DevicePlan::for_device(gpu);
            assert_eq!(p, DevicePlan { clear_then_later: false, zero_by_compute: true, copy_base: false }, "{gpu:?}");
        }
        assert_eq!((DevicePlan::CPU.name(), DevicePlan::GPU.name()), ("cpu", "gpu"));
    }
}
