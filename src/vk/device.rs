//! Physical-device choice and the logical device with its one graphics+compute queue.
//! Choice: discrete > integrated > virtual > CPU (lavapipe), or by name through `BRDF_SHOP_DEVICE`.

use std::ffi::CStr;

use ash::vk;

use super::Instance;
use crate::error::{Error, Result};

pub struct Device {
    pub physical: vk::PhysicalDevice,
    pub raw: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    pub timestamp_valid_bits: u32,
    pub limits: vk::PhysicalDeviceLimits,
    debug_utils: ash::ext::debug_utils::Device,
}

/// A Vulkan 1.3 device the program can use.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub physical: vk::PhysicalDevice,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub queue_family: u32,
    pub timestamp_period: f32,
}

fn rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Every Vulkan 1.3 device with a graphics+compute queue, best first.
pub fn candidates(instance: &Instance) -> Result<Vec<Candidate>> {
    // SAFETY: the instance is live.
    let physicals = unsafe { instance.raw.enumerate_physical_devices() }
        .map_err(|result| Error::Vulkan { call: "vkEnumeratePhysicalDevices", result })?;
    let mut out = Vec::new();
    for physical in physicals {
        // SAFETY: `physical` came from this instance.
        let (props, families) = unsafe {
            (
                instance.raw.get_physical_device_properties(physical),
                instance.raw.get_physical_device_queue_family_properties(physical),
            )
        };
        if props.api_version < vk::API_VERSION_1_3 || !ballot_in_compute(instance, physical) {
            continue;
        }
        let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
        let Some(family) = families.iter().position(|f| f.queue_flags.contains(want) && f.timestamp_valid_bits > 0)
        else {
            continue;
        };
        let name = CStr::from_bytes_until_nul(bytemuck_name(&props.device_name))
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_else(|_| "unnamed device".into());
        out.push(Candidate {
            physical,
            name,
            kind: props.device_type,
            queue_family: family as u32,
            timestamp_period: props.limits.timestamp_period,
        });
    }
    out.sort_by_key(|c| rank(c.kind));
    Ok(out)
}

/// Whether compute shaders may use subgroup ballots (`compact.comp` appends a subgroup's pixels with
/// one atomic); desktop Vulkan drivers and lavapipe all do.
fn ballot_in_compute(instance: &Instance, physical: vk::PhysicalDevice) -> bool {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    // SAFETY: `physical` came from this instance, a Vulkan 1.3 instance; `props` outlives the call.
    unsafe { instance.raw.get_physical_device_properties2(physical, &mut props) };
    subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
        && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::BALLOT)
}

fn bytemuck_name(name: &[std::ffi::c_char]) -> &[u8] {
    // SAFETY: `c_char` and `u8` have the same size and alignment; the slice covers the same bytes.
    unsafe { std::slice::from_raw_parts(name.as_ptr().cast::<u8>(), name.len()) }
}

impl Device {
    pub fn new(instance: &Instance, filter: Option<&str>) -> Result<Device> {
        Device::with_swapchain(instance, filter, false)
    }

    /// A device, with `VK_KHR_swapchain` enabled when `swapchain` (the editor's window).
    pub fn with_swapchain(instance: &Instance, filter: Option<&str>, swapchain: bool) -> Result<Device> {
        let all = candidates(instance)?;
        let chosen = match filter {
            Some(f) => all.iter().find(|c| c.name.to_lowercase().contains(&f.to_lowercase())).ok_or_else(|| {
                let names: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
                Error::NoDevice(format!("no Vulkan device named like \"{f}\" (found: {})", names.join(", ")))
            })?,
            None => all.first().ok_or_else(|| {
                Error::NoDevice("no Vulkan 1.3 device with subgroup ballots in compute shaders found; run tools/setup to install Mesa lavapipe".into())
            })?,
        };
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(chosen.queue_family)
            .queue_priorities(&priorities)];
        let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true)
            .maintenance4(true);
        let extensions = [ash::khr::swapchain::NAME.as_ptr()];
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(if swapchain { &extensions[..] } else { &[] })
            .push_next(&mut features13);
        // SAFETY: `chosen.physical` belongs to this instance; `info` outlives the call.
        let raw = unsafe { instance.raw.create_device(chosen.physical, &info, None) }
            .map_err(|result| Error::Vulkan { call: "vkCreateDevice", result })?;
        // SAFETY: queue 0 of the family was requested above.
        let queue = unsafe { raw.get_device_queue(chosen.queue_family, 0) };
        // SAFETY: `chosen.physical` belongs to this instance.
        let props = unsafe { instance.raw.get_physical_device_properties(chosen.physical) };
        // SAFETY: as above.
        let families = unsafe { instance.raw.get_physical_device_queue_family_properties(chosen.physical) };
        let debug_utils = ash::ext::debug_utils::Device::new(&instance.raw, &raw);
        Ok(Device {
            physical: chosen.physical,
            debug_utils,
            limits: props.limits,
            timestamp_valid_bits: families[chosen.queue_family as usize].timestamp_valid_bits,
            raw,
            queue,
            queue_family: chosen.queue_family,
            name: chosen.name.clone(),
            kind: chosen.kind,
            timestamp_period: chosen.timestamp_period,
        })
    }
}

impl Device {
    /// Names a Vulkan object for validation messages and captures.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Ok(name) = std::ffi::CString::new(name) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
        // SAFETY: `handle` is a live object of this device; naming is advisory, a failure is ignored.
        let _ = unsafe { self.debug_utils.set_debug_utils_object_name(&info) };
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: nothing else uses the device once its owner drops it; wait, then destroy once.
        unsafe {
            let _ = self.raw.device_wait_idle();
            self.raw.destroy_device(None);
        }
    }
}
