//! The Vulkan instance: loader, optional Khronos validation (with debug printf), and a
//! debug messenger that routes validation output to the log.
//!
//! Validation is on when `LANTERNA_VALIDATION=1` or when the caller asks for it (the test
//! suite always does). Errors the layer reports are counted so that tests can fail on
//! them; debug-printf lines from kernels are collected for `--pixel` traces.

use super::{CheckVk, Result, VkError};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

static VALIDATION_ERRORS: AtomicU64 = AtomicU64::new(0);
static PRINTF_LINES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Number of validation errors reported so far in this process.
pub fn validation_error_count() -> u64 {
    VALIDATION_ERRORS.load(Ordering::SeqCst)
}

/// Take the debug-printf lines the kernels have printed since the last call.
pub fn take_debug_printf_messages() -> Vec<String> {
    std::mem::take(&mut *PRINTF_LINES.lock().unwrap())
}

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create the instance.
#[derive(Clone, Debug, Default)]
pub struct InstanceOptions {
    /// Enable the Khronos validation layer (also enabled by `LANTERNA_VALIDATION=1`).
    pub validation: bool,
    /// Enable `GL_EXT_debug_printf` output through the validation layer.
    pub debug_printf: bool,
}

impl InstanceOptions {
    /// Options from the environment: `LANTERNA_VALIDATION=1` turns validation on.
    pub fn from_env() -> Self {
        InstanceOptions {
            validation: env_flag("LANTERNA_VALIDATION"),
            debug_printf: false,
        }
    }
}

pub(crate) fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// A Vulkan instance with its loader and debug messenger.
pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    debug_utils: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Whether the validation layer is active.
    pub validation: bool,
    /// Whether debug printf is active.
    pub debug_printf: bool,
}

impl Instance {
    pub fn new(options: &InstanceOptions) -> Result<Self> {
        // lavapipe's SIMD width and its cache folder, before any instance exists.
        super::lavapipe::configure();
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;
        let want_validation =
            options.validation || options.debug_printf || env_flag("LANTERNA_VALIDATION");

        let layers = unsafe { entry.enumerate_instance_layer_properties() }
            .check("vkEnumerateInstanceLayerProperties")?;
        let has_validation = layers
            .iter()
            .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        let validation = want_validation && has_validation;
        if want_validation && !has_validation {
            log::warn!(
                "validation requested but VK_LAYER_KHRONOS_validation is not installed \
                 (package vulkan-validationlayers); continuing without it"
            );
        }
        let extensions = unsafe { entry.enumerate_instance_extension_properties(None) }
            .check("vkEnumerateInstanceExtensionProperties")?;
        let has_debug_utils = extensions.iter().any(|e| {
            e.extension_name_as_c_str()
                .is_ok_and(|n| n == ash::ext::debug_utils::NAME)
        });

        let app_info = vk::ApplicationInfo::default()
            .application_name(c"lanterna")
            .application_version(1)
            .engine_name(c"lanterna")
            .api_version(vk::API_VERSION_1_2);
        let mut layer_names = Vec::new();
        if validation {
            layer_names.push(VALIDATION_LAYER.as_ptr());
        }
        let mut ext_names = Vec::new();
        if has_debug_utils {
            ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        // Debug printf (for --pixel traces) and synchronization validation exclude each
        // other in the layer; every other validating run checks synchronization, unless
        // LANTERNA_SYNC_VALIDATION=0 (its access history grows the heap by ~30 KiB per
        // render, which a leak test must not see).
        let printf_features = [vk::ValidationFeatureEnableEXT::DEBUG_PRINTF];
        let sync_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let debug_printf = validation && options.debug_printf;
        let mut validation_features = vk::ValidationFeaturesEXT::default()
            .enabled_validation_features(if debug_printf {
                &printf_features
            } else {
                &sync_features
            });
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&ext_names);
        let sync_validation = std::env::var("LANTERNA_SYNC_VALIDATION").map_or(true, |v| v != "0");
        if validation && (debug_printf || sync_validation) {
            info = info.push_next(&mut validation_features);
        }
        if debug_printf {
            configure_printf_layer();
        }
        let raw = unsafe { entry.create_instance(&info, None) }.check("vkCreateInstance")?;

        let debug_utils = if has_debug_utils && validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            let mut severity = vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR;
            if debug_printf {
                severity |= vk::DebugUtilsMessageSeverityFlagsEXT::INFO;
            }
            let messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(severity)
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback));
            let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_info, None) }
                .check("vkCreateDebugUtilsMessengerEXT")?;
            Some((loader, messenger))
        } else {
            None
        };
        if validation {
            log::debug!(
                "Vulkan validation enabled{}",
                if debug_printf {
                    " with debug printf"
                } else {
                    ""
                }
            );
        }
        Ok(Instance {
            entry,
            raw,
            debug_utils,
            validation,
            debug_printf,
        })
    }

    /// Whether `VK_EXT_debug_utils` is active (object names, labels).
    pub fn has_debug_utils(&self) -> bool {
        self.debug_utils.is_some()
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Some((loader, messenger)) = self.debug_utils.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}

/// Debug printf sends every line through the debug callback under one message id, which
/// the layer's duplicate-message limit would cut after ten, and its default buffer holds
/// only 1 KiB per submission. Point the layer at a settings file that lifts both (unless
/// the user has their own).
fn configure_printf_layer() {
    if std::env::var_os("VK_LAYER_SETTINGS_PATH").is_some() {
        return;
    }
    let path = std::env::temp_dir().join(format!(
        "lanterna-vk_layer_settings-{}.txt",
        std::process::id()
    ));
    let text = "khronos_validation.printf_buffer_size = 1048576\n\
                khronos_validation.enable_message_limit = false\n\
                khronos_validation.printf_verbose = false\n";
    if std::fs::write(&path, text).is_ok() {
        // Set before the instance exists; the layer reads it at vkCreateInstance.
        std::env::set_var("VK_LAYER_SETTINGS_PATH", &path);
    }
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    let data = unsafe { &*data };
    let id = if data.p_message_id_name.is_null() {
        String::new()
    } else {
        unsafe { CStr::from_ptr(data.p_message_id_name) }
            .to_string_lossy()
            .into_owned()
    };
    let message = if data.p_message.is_null() {
        String::new()
    } else {
        unsafe { CStr::from_ptr(data.p_message) }
            .to_string_lossy()
            .into_owned()
    };
    if id.contains("DEBUG-PRINTF") || message.contains("DEBUG-PRINTF") {
        // The layer prefixes printf output with its own header; keep the kernel's text.
        let text = message
            .rsplit(" | ")
            .next()
            .unwrap_or(&message)
            .trim()
            .to_string();
        PRINTF_LINES.lock().unwrap().push(text);
        return vk::FALSE;
    }
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        VALIDATION_ERRORS.fetch_add(1, Ordering::SeqCst);
        log::error!("[vulkan] {id}: {message}");
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        log::warn!("[vulkan] {id}: {message}");
    } else {
        log::debug!("[vulkan] {id}: {message}");
    }
    vk::FALSE
}
