//! Shared test helpers. Every GPU test opens its own context with the Khronos validation layer
//! and synchronization validation on, and fails if the layer reported anything.
//!
//! - [`assets`]: where Sponza and the bunny are, and what a test does without them;
//! - [`render`]: test settings, one frame, the scenes;
//! - [`pixels`]: frame comparison;
//! - [`compare`]: every technique against a reference, a CPU shading of a read-back frame;
//! - [`scenes`]: the hard light cases and the geometry the built-in scenes lack;
//! - [`csv`]: CSV files read by column name;
//! - [`gltf`]: small glTF documents built in code;
//! - [`cli`]: running the binary, one-line errors;
//! - [`spirv`]: entry points of a SPIR-V module;
//! - [`temp`]: per-test temporary directories.
#![allow(dead_code)]
pub mod assets;
pub mod cli;
pub mod compare;
pub mod csv;
pub mod gltf;
pub mod pixels;
pub mod render;
pub mod scenes;
pub mod spirv;
pub mod temp;

use host::gpu::Gpu;
use host::vk::ContextOptions;

/// A validated GPU context (device: `MANYLIGHTS_DEVICE`, else the best usable one).
pub fn gpu() -> Gpu {
    let opts = ContextOptions { validation: true, device: std::env::var("MANYLIGHTS_DEVICE").ok(), ..Default::default() };
    match Gpu::new(&opts) {
        Ok(g) => {
            assert_clean(&g);
            g
        }
        Err(e) => panic!("cannot open a validated Vulkan device: {e}\n(run ./dev.sh test, which installs lavapipe and the validation layers)"),
    }
}

/// Panics with every validation message reported so far.
pub fn assert_clean(gpu: &Gpu) {
    let msgs = gpu.ctx.take_validation_messages();
    assert!(msgs.is_empty(), "validation layer reported {} message(s):\n{}", msgs.len(), msgs.join("\n"));
}
