//! VK_EXT_debug_utils messenger: forwards validation messages to `log` and counts them, so a
//! test can assert that a whole run produced none (leak reports at device destruction included).

use ash::vk;
use std::ffi::{CStr, c_void};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

/// Counts of validation messages, shared between the messenger callback and its readers.
#[derive(Debug, Default)]
pub struct ValidationCounters {
    warnings: AtomicU32,
    errors: AtomicU32,
    /// The first few messages, kept so a failing test can say what went wrong.
    first: Mutex<Vec<String>>,
}

impl ValidationCounters {
    /// Validation warnings counted so far.
    pub fn warnings(&self) -> u32 {
        self.warnings.load(Ordering::SeqCst)
    }
    /// Validation errors counted so far.
    pub fn errors(&self) -> u32 {
        self.errors.load(Ordering::SeqCst)
    }
    /// Warnings plus errors.
    pub fn total(&self) -> u32 {
        self.warnings() + self.errors()
    }
    /// Up to the first 16 messages seen.
    pub fn messages(&self) -> Vec<String> {
        self.first.lock().map(|m| m.clone()).unwrap_or_default()
    }
    fn record(&self, is_error: bool, text: String) {
        let counter = if is_error { &self.errors } else { &self.warnings };
        counter.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut first) = self.first.lock()
            && first.len() < 16
        {
            first.push(text);
        }
    }
}

/// An owned debug-utils messenger. Destroy it before the instance (see `Gpu`'s Drop).
pub(crate) struct DebugMessenger {
    pub(crate) loader: ash::ext::debug_utils::Instance,
    pub(crate) messenger: vk::DebugUtilsMessengerEXT,
    /// Kept alive here because the callback holds a raw pointer to it.
    #[allow(dead_code)]
    pub(crate) counters: Arc<ValidationCounters>,
}

impl DebugMessenger {
    pub(crate) fn create_info(counters: &Arc<ValidationCounters>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
        vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(callback))
            .user_data(Arc::as_ptr(counters) as *mut c_void)
    }

    pub(crate) fn new(
        entry: &ash::Entry,
        instance: &ash::Instance,
        counters: Arc<ValidationCounters>,
    ) -> Result<Self, vk::Result> {
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let info = Self::create_info(&counters);
        // SAFETY: the user-data pointer stays valid while `counters` lives in this struct, and the
        // messenger is destroyed (Drop of Gpu) before this struct is dropped.
        let messenger = unsafe { loader.create_debug_utils_messenger(&info, None)? };
        Ok(Self { loader, messenger, counters })
    }

    /// # Safety
    /// Call once, before the instance is destroyed.
    pub(crate) unsafe fn destroy(&self) {
        // SAFETY: the caller's contract: called once, while the instance that made the messenger
        // is still alive.
        unsafe { self.loader.destroy_debug_utils_messenger(self.messenger, None) };
    }
}

unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: Vulkan passes valid callback data for the duration of the call; `user` is the
    // `ValidationCounters` pointer given at creation, alive until the messenger is destroyed.
    let (text, counters) = unsafe {
        let message = if data.is_null() || (*data).p_message.is_null() {
            "(no message)".to_string()
        } else {
            CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
        };
        (message, (user as *const ValidationCounters).as_ref())
    };
    let is_error = severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR);
    let text = format!("[vulkan {kind:?}] {text}");
    if is_error {
        log::error!("{text}");
    } else {
        log::warn!("{text}");
    }
    if let Some(counters) = counters {
        counters.record(is_error, text);
    }
    vk::FALSE
}
