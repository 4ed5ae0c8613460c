//! Shared test setup: every GPU test opens its own context with the Khronos validation layer and
//! synchronization validation on, and fails if the layer reported anything.
#![allow(dead_code)]
use host::gpu::Gpu;
use host::vk::ContextOptions;

/// A validated GPU context (device: `MANYLIGHTS_DEVICE`, else the best usable one).
pub fn gpu() -> Gpu {
    let opts = ContextOptions { validation: true, device: std::env::var("MANYLIGHTS_DEVICE").ok() };
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
