//! Vulkan instance with optional Khronos validation (+ synchronization validation).
//!
//! Validation messages (warnings and errors) are collected into a shared list instead of being
//! printed, so tests can fail on any of them and the CLI can report them at the end.
use super::error::{CallContext, VkError, VkResult};
use ash::{ext, vk};
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Validation messages collected from the debug messenger.
pub type MessageLog = Arc<Mutex<Vec<String>>>;

pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    debug: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Kept alive for the messenger's user-data pointer.
    log: MessageLog,
    pub validation: bool,
    pub debug_utils: bool,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the `Mutex` inside the instance's `MessageLog`, alive until the messenger
    // is destroyed; `data` is valid for the duration of the callback.
    let log = unsafe { &*(user as *const Mutex<Vec<String>>) };
    let text = unsafe { data.as_ref() }
        .and_then(|d| unsafe { d.message_as_c_str() })
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    if let Ok(mut l) = log.lock() {
        l.push(format!("[{severity:?}] {text}"));
    }
    vk::FALSE
}

impl Instance {
    /// Creates a Vulkan 1.3 instance. With `validation`, the Khronos layer with synchronization
    /// validation is required (an error says how to install it when absent).
    pub fn new(validation: bool) -> VkResult<Self> {
        Self::with_extensions(validation, &[])
    }

    /// [`Instance::new`] with more instance extensions (a window system's surface extensions).
    pub fn with_extensions(validation: bool, extra: &[*const std::ffi::c_char]) -> VkResult<Self> {
        // SAFETY: loading libvulkan; the returned entry outlives every object made from it.
        let entry = unsafe { ash::Entry::load()? };
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.call("vkEnumerateInstanceLayerProperties")?;
        let has_layer = layers.iter().any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
        if validation && !has_layer {
            return Err(VkError::NoValidationLayer);
        }
        let exts = unsafe { entry.enumerate_instance_extension_properties(None) }
            .call("vkEnumerateInstanceExtensionProperties")?;
        let debug_utils = validation
            || exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(ext::debug_utils::NAME));

        let app = vk::ApplicationInfo::default()
            .application_name(c"manylights")
            .engine_name(c"manylights")
            .api_version(vk::API_VERSION_1_3);
        let layer_names = [VALIDATION_LAYER.as_ptr()];
        let debug_name = [ext::debug_utils::NAME.as_ptr()];
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app);
        let ext_names: Vec<*const std::ffi::c_char> = debug_name.iter().take(usize::from(debug_utils)).chain(extra).copied().collect();
        if !ext_names.is_empty() {
            info = info.enabled_extension_names(&ext_names);
        }
        if validation {
            info = info.enabled_layer_names(&layer_names).push_next(&mut features);
        }
        let raw = unsafe { entry.create_instance(&info, None) }.call("vkCreateInstance")?;

        let log: MessageLog = Arc::default();
        let mut this = Self { entry, raw, debug: None, log, validation, debug_utils };
        if validation {
            let loader = ext::debug_utils::Instance::new(&this.entry, &this.raw);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                )
                .pfn_user_callback(Some(on_message))
                .user_data(Arc::as_ptr(&this.log) as *mut c_void);
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
                .call("vkCreateDebugUtilsMessengerEXT")?;
            this.debug = Some((loader, messenger));
        }
        Ok(this)
    }

    /// The validation messages so far (empty without validation).
    pub fn messages(&self) -> Vec<String> {
        self.log.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// Takes the validation messages so far.
    pub fn take_messages(&self) -> Vec<String> {
        self.log.lock().map(|mut l| std::mem::take(&mut *l)).unwrap_or_default()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: the device (owner of every child object) was destroyed before the instance.
        unsafe {
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
