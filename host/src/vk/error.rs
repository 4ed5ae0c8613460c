//! Backend errors (`thiserror`); the CLI adds context with `anyhow`.
use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}; install it (Debian: `apt-get install libvulkan1 mesa-vulkan-drivers`)")]
    Loader(#[from] ash::LoadingError),
    #[error("Vulkan call {call} failed: {result}")]
    Call { call: &'static str, result: vk::Result },
    #[error("the Vulkan device was lost ({call} answered VK_ERROR_DEVICE_LOST: the driver reset or the GPU hung or was removed); nothing can be rendered any more")]
    DeviceLost { call: &'static str },
    #[error("the Khronos validation layer (VK_LAYER_KHRONOS_validation) is not installed; install it (Debian: `apt-get install vulkan-validationlayers`) or run without validation")]
    NoValidationLayer,
    #[error("no Vulkan device found: install a driver (Debian: `apt-get install mesa-vulkan-drivers` for the CPU driver lavapipe)")]
    NoDevices,
    #[error("no Vulkan device matches {wanted:?}; devices present:\n{listing}")]
    NoMatchingDevice { wanted: String, listing: String },
    #[error("device {device:?} cannot run manylights: {missing}")]
    Unsupported { device: String, missing: String },
    #[error("GPU memory allocation for {name:?} ({bytes} bytes) failed: {source}")]
    Alloc { name: String, bytes: u64, source: gpu_allocator::AllocationError },
    #[error("buffer {name:?} holds {have} bytes, {need} requested")]
    BufferTooSmall { name: String, have: u64, need: u64 },
    #[error("{what} needs {bytes} bytes in one buffer; this device addresses at most {max} per binding (use a smaller resolution, fewer lights or larger tiles)")]
    TooLarge { what: String, bytes: u64, max: u64 },
    #[error("{during}; the validation layer reported:\n{messages}")]
    Validation { during: String, messages: String },
    #[error("image {name:?}: {what}")]
    InvalidImage { name: String, what: String },
    #[error("window: {0}")]
    Window(String),
    #[error("overlay: {0}")]
    Overlay(String),
    #[error("kernel {entry:?}: {what}")]
    Kernel { entry: &'static str, what: String },
}

pub type VkResult<T> = Result<T, VkError>;

/// Maps a raw `vk::Result` error to [`VkError::Call`] naming the call.
pub(crate) trait CallContext<T> {
    fn call(self, call: &'static str) -> VkResult<T>;
}

impl<T> CallContext<T> for Result<T, vk::Result> {
    fn call(self, call: &'static str) -> VkResult<T> {
        self.map_err(|result| match result {
            vk::Result::ERROR_DEVICE_LOST => VkError::DeviceLost { call },
            result => VkError::Call { call, result },
        })
    }
}
