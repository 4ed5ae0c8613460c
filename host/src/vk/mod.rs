//! The Vulkan layer: small RAII types over `ash`, no algorithm code.
//!
//! | file | what |
//! |---|---|
//! | `instance.rs` | instance, validation layer + synchronization validation, message capture |
//! | `device.rs` | physical-device selection (`--device`), capabilities, logical device |
//! | `context.rs` | the shared context (device, queues, allocator, command submission) |
//! | `image.rs` | 2D images with views, layout transitions |
//! | `memory.rs` | buffers (`gpu-allocator`), upload/read-back, barriers |
//! | `pipeline.rs` | shader modules, typed compute pipelines, the dispatch recorder |
//! | `profiler.rs` | GPU timestamps per pass |
//! | `kernel_stats.rs` | what the driver compiled each kernel to (registers, sizes) |
//! | `raster.rs` | typed graphics pipelines (dynamic rendering, vertex pulling), target formats |
//! | `draw.rs` | raster recording: target transitions, rendering, indexed draws, target copies |
//! | `present.rs` | a window's surface and swapchain, frames copied into it (the viewer) |
//! | `overlay.rs` | the viewer's egui overlay drawn into swapchain images |
pub mod context;
pub mod device;
pub mod draw;
pub mod error;
pub mod image;
pub mod instance;
pub mod kernel_stats;
pub mod light_typed;
pub mod memory;
pub mod overlay;
pub mod pipeline;
pub mod present;
pub mod profiler;
pub mod raster;

pub use context::{Context, ContextOptions};
pub use device::DeviceInfo;
pub use kernel_stats::KernelStatistics;
pub use error::{VkError, VkResult};
pub use image::{Image, Sampler};
pub use memory::{Buffer, MemoryLocation};
pub use draw::{Attachment, Binding, ImageUse, Load};
pub use overlay::Overlay;
pub use present::{PresentMode, Presented, Presenter};
pub use pipeline::{fold, ComputePipeline, Recorder, ShaderModule, MAX_GROUPS_PER_AXIS};
pub use light_typed::{LightTyped, LightTypedModules};
pub use profiler::{PassTiming, Profiler, Queue};
pub use raster::{Blend, DepthTest, GraphicsPipeline, TargetFormat};
