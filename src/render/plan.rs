//! The frame plan: how a frame starts and zeroes its images on this kind of device, a pure function
//! of the device's type (tested without a device). Every choice draws the same image (within the
//! rounding of a different order of additions); they differ in where the bytes go.
//!
//! On a CPU device (Mesa lavapipe) a transfer clear or copy is a `memset`/`memcpy` on the host, far
//! cheaper than a shader over the same pixels (whose cost is per lane), so the frame clears and
//! copies. On a GPU, image clears and copies go through the transfer or raster path: on an H200 they
//! ran at 50–60 GB/s against 2.4–2.9 TB/s for compute shaders writing the same images, so the frame
//! writes its images from compute passes instead.

use ash::vk;

/// The choices of one device kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePlan {
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

impl FramePlan {
    /// The plan of a CPU device: clears and copies.
    pub const CPU: FramePlan = FramePlan { clear_then_later: true, zero_by_compute: false, copy_base: true };

    /// The plan of a GPU: compute passes write every image, no transfer clears or copies.
    pub const GPU: FramePlan = FramePlan { clear_then_later: false, zero_by_compute: true, copy_base: false };

    /// The plan for a device of type `kind`.
    pub fn for_device(kind: vk::PhysicalDeviceType) -> FramePlan {
        if kind == vk::PhysicalDeviceType::CPU {
            FramePlan::CPU
        } else {
            FramePlan::GPU
        }
    }

    /// `BRDF_SHOP_FRAME_PLAN` (`cpu` or `gpu`) where set, else the plan for `kind`.
    pub fn from_env(kind: vk::PhysicalDeviceType) -> FramePlan {
        match std::env::var(ENV).as_deref() {
            Ok("cpu") => FramePlan::CPU,
            Ok("gpu") => FramePlan::GPU,
            _ => FramePlan::for_device(kind),
        }
    }

    /// The plan's name (`cpu` or `gpu`; `mixed` for a hand-made one).
    pub fn name(&self) -> &'static str {
        match *self {
            FramePlan::CPU => "cpu",
            FramePlan::GPU => "gpu",
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
        let cpu = FramePlan::for_device(vk::PhysicalDeviceType::CPU);
        assert_eq!(cpu, FramePlan { clear_then_later: true, zero_by_compute: false, copy_base: true });
        for gpu in [
            vk::PhysicalDeviceType::DISCRETE_GPU,
            vk::PhysicalDeviceType::INTEGRATED_GPU,
            vk::PhysicalDeviceType::VIRTUAL_GPU,
            vk::PhysicalDeviceType::OTHER,
        ] {
            let p = FramePlan::for_device(gpu);
            assert_eq!(p, FramePlan { clear_then_later: false, zero_by_compute: true, copy_base: false }, "{gpu:?}");
        }
        assert_eq!((FramePlan::CPU.name(), FramePlan::GPU.name()), ("cpu", "gpu"));
    }
}
