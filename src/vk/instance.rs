//! The Vulkan instance and the debug-utils messenger that collects validation ERROR messages (every
//! GPU test asserts the list is empty), synchronization validation's hazards among them. Owns the
//! loader entry; nothing else.

use std::ffi::{c_void, CStr};
use std::sync::Mutex;

use ash::vk;

use crate::error::{Error, Result};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Validation ERROR messages, shared with the messenger callback.
type Sink = Mutex<Vec<String>>;

pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    // Boxed so its address, handed to the callback, stays fixed; dropped after the messenger.
    errors: Box<Sink>,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) && !data.is_null() && !user.is_null() {
        // SAFETY: the layer passes a valid callback-data pointer for the duration of the call, and
        // `user` is the `Sink` boxed in `Instance`, alive until the messenger is destroyed.
        let (msg, sink) = unsafe {
            let msg = (*data).message_as_c_str().map(|m| m.to_string_lossy().into_owned());
            (msg.unwrap_or_else(|| "(no message)".into()), &*(user as *const Sink))
        };
        if let Ok(mut v) = sink.lock() {
            v.push(msg);
        }
    }
    vk::FALSE
}

fn vk_err(call: &'static str) -> impl Fn(vk::Result) -> Error {
    move |result| Error::Vulkan { call, result }
}

impl Instance {
    pub fn new(validation: bool) -> Result<Instance> {
        Instance::with_extensions(validation, &[])
    }

    /// An instance with `extra` extensions besides debug utils (the window's surface extensions).
    pub fn with_extensions(validation: bool, extra: &[*const std::ffi::c_char]) -> Result<Instance> {
        // SAFETY: loading the system Vulkan loader; no Vulkan call has been made before.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| {
            Error::NoDevice(format!(
                "cannot load the Vulkan loader ({e}); run tools/setup to install it and Mesa lavapipe"
            ))
        })?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"brdf-shop")
            .engine_name(c"brdf-shop")
            .api_version(vk::API_VERSION_1_3);
        let layers = if validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
        let mut extensions = vec![ash::ext::debug_utils::NAME.as_ptr()];
        if validation {
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }
        extensions.extend_from_slice(extra);
        // With the layer, synchronization validation too: a missing or wrong barrier between two
        // commands (a read after a write, a write after a read or a write) is an error like any other.
        let features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&features);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            info = info.push_next(&mut validation_features);
        }
        // SAFETY: `info` and everything it points to outlive the call.
        let raw = unsafe { entry.create_instance(&info, None) }.map_err(|result| match result {
            vk::Result::ERROR_LAYER_NOT_PRESENT => {
                Error::NoDevice("the Vulkan validation layer is not installed; run tools/setup".into())
            }
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
                Error::NoDevice("no Vulkan 1.3 driver; run tools/setup to install Mesa lavapipe".into())
            }
            result => Error::Vulkan { call: "vkCreateInstance", result },
        })?;
        let errors: Box<Sink> = Box::default();
        let mut instance = Instance { entry, raw, messenger: None, errors };
        if validation {
            let utils = ash::ext::debug_utils::Instance::new(&instance.entry, &instance.raw);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(on_message))
                .user_data(&*instance.errors as *const Sink as *mut c_void);
            // SAFETY: the instance is live; the user-data box outlives the messenger (see Drop).
            let m = unsafe { utils.create_debug_utils_messenger(&info, None) }
                .map_err(vk_err("vkCreateDebugUtilsMessengerEXT"))?;
            instance.messenger = Some((utils, m));
        }
        Ok(instance)
    }

    pub fn validation_errors(&self) -> Vec<String> {
        self.errors.lock().map(|v| v.clone()).unwrap_or_default()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if let Some((utils, m)) = self.messenger.take() {
            // SAFETY: the messenger was created from this instance and is destroyed once.
            unsafe { utils.destroy_debug_utils_messenger(m, None) };
        }
        // SAFETY: every child object (the device) is destroyed first: `Context` drops it before us.
        unsafe { self.raw.destroy_instance(None) };
    }
}
