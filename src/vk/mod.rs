//! Explicit Vulkan through `ash`: one concept per file. This module owns every Vulkan handle the
//! program creates; `brdf` and `brush` never see any of it.
//!
//! [`Context`] is the root: the instance (with the validation messenger) and the logical device,
//! dropped device first.

pub mod device;
pub mod instance;

pub use device::Device;
pub use instance::Instance;

use crate::error::Result;

/// The environment variable that picks a device by (part of) its name, e.g. `llvmpipe`.
pub const DEVICE_ENV: &str = "BRDF_SHOP_DEVICE";

/// Instance and device. Field order is drop order: the device goes before the instance.
pub struct Context {
    pub device: Device,
    pub instance: Instance,
}

impl Context {
    /// Creates the instance (validation layer on when `validation`) and the device: discrete >
    /// integrated > virtual > CPU, or the first whose name contains `device_filter`.
    pub fn new(validation: bool, device_filter: Option<&str>) -> Result<Context> {
        let instance = Instance::new(validation)?;
        let device = Device::new(&instance, device_filter)?;
        Ok(Context { device, instance })
    }

    /// ERROR messages the validation layer reported so far.
    pub fn validation_errors(&self) -> Vec<String> {
        self.instance.validation_errors()
    }
}
