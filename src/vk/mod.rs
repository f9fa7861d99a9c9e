//! Explicit Vulkan through `ash`: one concept per file. This module owns every Vulkan handle the
//! program creates; `brdf`, `brush` and `scene` never see any of it.
//!
//! [`Context`] is the root: instance (with the validation messenger), logical device, memory
//! allocator, the command pool and the pipeline cache. Drop order: wait idle → pipeline cache
//! (saved) → allocator → commands → device → instance.

pub mod barrier;
pub mod buffer;
pub mod commands;
pub mod counts;
pub mod descriptor;
pub mod device;
pub mod frame;
pub mod hazards;
pub mod image;
pub mod instance;
pub mod pipeline;
pub mod pipeline_cache;
pub mod query;
pub mod readback;
pub mod reflect;
pub mod shader;
pub mod surface;
pub mod swapchain;

use std::mem::ManuallyDrop;
use std::sync::Mutex;

pub use buffer::Buffer;
pub use commands::Commands;
pub use device::Device;
pub use image::Image;
pub use instance::Instance;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::error::{Error, Result};

/// The environment variable that picks a device by (part of) its name, e.g. `llvmpipe`.
pub const DEVICE_ENV: &str = "BRDF_SHOP_DEVICE";

/// The environment variable that turns the validation layer on in release builds (`1`) or off in
/// debug builds (`0`).
pub const VALIDATION_ENV: &str = "BRDF_SHOP_VALIDATION";

/// Maps a failed call to the library's error.
pub fn vk_err(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| Error::Vulkan { call, result }
}

/// Maps an allocator failure (out of memory and the rest).
pub fn alloc_err(call: &'static str) -> impl Fn(gpu_allocator::AllocationError) -> Error {
    move |e| Error::Vulkan {
        call,
        result: match e {
            gpu_allocator::AllocationError::OutOfMemory => vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            _ => vk::Result::ERROR_UNKNOWN,
        },
    }
}

/// Instance, device, allocator, command pool and pipeline cache.
pub struct Context {
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub commands: ManuallyDrop<Commands>,
    /// Every pipeline is built through it (`Pipeline::compute`, `Pipeline::graphics`).
    pub pipeline_cache: ManuallyDrop<pipeline_cache::PipelineCache>,
    pub device: Device,
    pub instance: Instance,
    /// The barriers and dispatches recorded so far.
    pub counts: counts::CommandCounts,
}

impl Context {
    /// Creates the instance (validation layer on when `validation`) and the device: discrete >
    /// integrated > virtual > CPU, or the first whose name contains `device_filter`.
    pub fn new(validation: bool, device_filter: Option<&str>) -> Result<Context> {
        Context::with_window_extensions(validation, device_filter, &[])
    }

    /// A context that can present: the instance gets `surface_extensions`, the device
    /// `VK_KHR_swapchain` (when any surface extension is asked for).
    pub fn with_window_extensions(
        validation: bool,
        device_filter: Option<&str>,
        surface_extensions: &[*const std::ffi::c_char],
    ) -> Result<Context> {
        let instance = Instance::with_extensions(validation, surface_extensions)?;
        let device = Device::with_swapchain(&instance, device_filter, !surface_extensions.is_empty())?;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: device.raw.clone(),
            physical_device: device.physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(alloc_err("gpu_allocator::Allocator::new"))?;
        let commands = Commands::new(&device)?;
        let pipeline_cache = pipeline_cache::PipelineCache::open_default(&device);
        Ok(Context {
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            commands: ManuallyDrop::new(commands),
            pipeline_cache: ManuallyDrop::new(pipeline_cache),
            device,
            instance,
            counts: counts::CommandCounts::default(),
        })
    }

    /// The context the program uses: validation on in debug builds (or as `BRDF_SHOP_VALIDATION`
    /// says), device by `BRDF_SHOP_DEVICE`.
    pub fn from_env() -> Result<Context> {
        Context::from_env_with(&[])
    }

    /// [`Context::from_env`] with surface extensions for a window.
    pub fn from_env_with(surface_extensions: &[*const std::ffi::c_char]) -> Result<Context> {
        let validation = match std::env::var(VALIDATION_ENV).as_deref() {
            Ok("1") => true,
            Ok("0") => false,
            _ => cfg!(debug_assertions),
        };
        let filter = std::env::var(DEVICE_ENV).ok().filter(|s| !s.is_empty());
        Context::with_window_extensions(validation, filter.as_deref(), surface_extensions)
    }

    /// ERROR messages the validation layer reported so far.
    pub fn validation_errors(&self) -> Vec<String> {
        self.instance.validation_errors()
    }

    /// Fails with every validation error reported so far (debug builds treat them as bugs).
    pub fn check_validation(&self) -> Result<()> {
        let errors = self.validation_errors();
        match errors.first() {
            None => Ok(()),
            Some(first) => Err(Error::Validation(format!("{} validation error(s), first: {first}", errors.len()))),
        }
    }

    pub fn raw(&self) -> &ash::Device {
        &self.device.raw
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: nothing else records or submits once the context drops.
        let _ = unsafe { self.device.raw.device_wait_idle() };
        // SAFETY: each is dropped exactly once, here, before the device they were made from; the
        // owners of pipeline-building threads join them before the context drops.
        unsafe {
            ManuallyDrop::take(&mut self.pipeline_cache).destroy(&self.device);
            ManuallyDrop::drop(&mut self.allocator);
            let commands = ManuallyDrop::take(&mut self.commands);
            commands.destroy(&self.device);
        }
    }
}
