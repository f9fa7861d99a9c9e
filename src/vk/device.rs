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
    /// What `bench` names the device by and what the device plan (`render::plan::DevicePlan`) and the pipeline
    /// cache's header read.
    pub info: DeviceInfo,
    debug_utils: ash::ext::debug_utils::Device,
}

/// The device's vendor, driver, subgroup size and pipeline-cache identity.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DeviceInfo {
    /// PCI vendor id (`0x10de` NVIDIA, `0x1002` AMD, `0x8086` Intel, `0x10005` Mesa's software devices).
    pub vendor_id: u32,
    pub device_id: u32,
    /// `VkPhysicalDeviceDriverProperties`: the driver's name and its free-form information.
    pub driver_name: String,
    pub driver_info: String,
    /// `VkPhysicalDeviceProperties::driverVersion`, as the vendor encodes it.
    pub driver_version: u32,
    pub api_version: u32,
    /// `VkPhysicalDeviceProperties::pipelineCacheUUID`: a cache written by another device or driver
    /// is refused by this.
    pub pipeline_cache_uuid: [u8; 16],
    pub subgroup_size: u32,
}

impl DeviceInfo {
    /// The driver's version as its vendor writes it: NVIDIA `major.minor.patch` of 10.8.8 bits,
    /// the others Vulkan's `major.minor.patch`.
    pub fn driver_version_text(&self) -> String {
        let v = self.driver_version;
        if self.vendor_id == 0x10de {
            format!("{}.{}.{}", v >> 22, (v >> 14) & 0xff, (v >> 6) & 0xff)
        } else {
            format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
        }
    }
}

fn c_text(chars: &[std::ffi::c_char]) -> String {
    CStr::from_bytes_until_nul(bytemuck_name(chars)).map(|c| c.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The device's [`DeviceInfo`] (a Vulkan 1.3 device: driver properties are core).
fn device_info(instance: &Instance, physical: vk::PhysicalDevice) -> DeviceInfo {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut driver).push_next(&mut subgroup);
    // SAFETY: `physical` came from this instance, a Vulkan 1.3 instance; `props` and its chain
    // outlive the call.
    unsafe { instance.raw.get_physical_device_properties2(physical, &mut props) };
    let p = props.properties;
    DeviceInfo {
        vendor_id: p.vendor_id,
        device_id: p.device_id,
        driver_name: c_text(&driver.driver_name),
        driver_info: c_text(&driver.driver_info),
        driver_version: p.driver_version,
        api_version: p.api_version,
        pipeline_cache_uuid: p.pipeline_cache_uuid,
        subgroup_size: subgroup.subgroup_size,
    }
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
        let info = device_info(instance, chosen.physical);
        Ok(Device {
            info,
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
