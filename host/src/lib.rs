//! manylights host: the Vulkan backend (`vk`), the kernels as the algorithms see them (`gpu`),
//! GPU-vs-CPU parity checks (`parity`), debug frames, the interactive viewer (`viewer`) and the CLI.
pub mod args;
pub mod bad_input;
pub mod bench;
pub mod cli;
pub mod debug_frame;
pub mod gpu;
pub mod parity;
pub mod preflight;
pub mod render;
pub mod render_cmd;
pub mod scene;
pub mod viewer;
pub mod vk;
