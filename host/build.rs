//! Compiles `shader-crate` to SPIR-V with rust-gpu.
//!
//! `cargo-gpu-install` installs the pinned nightly (with rust-src, rustc-dev, llvm-tools) through
//! rustup when it is missing and builds the `rustc_codegen_spirv` backend once into
//! `~/.cache/rust-gpu` (≈ 10 min cold on 2 cores; seconds afterwards). The host itself stays on
//! stable. The produced module's path reaches the host as `MANYLIGHTS_COMPUTE_SPV`
//! (`include_bytes!`), so the binary is self-contained and can be carried to another machine.
//!
//! One module for now: compute kernels, with the subgroup capabilities. Graphics shaders will be
//! a second module built without them (lavapipe rejects GroupNonUniform* in vertex stages).
use cargo_gpu_install::install::Install;
use cargo_gpu_install::spirv_builder::{Capability, ShaderPanicStrategy, SpirvMetadata};

fn main() -> anyhow::Result<()> {
    let crate_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shader-crate");
    let backend = Install::from_shader_crate(crate_path.clone())
        .within_build_script()
        .run()?;
    let mut builder = backend.to_spirv_builder(crate_path, "spirv-unknown-vulkan1.3");
    builder.build_script.defaults = true;
    builder.shader_panic_strategy = ShaderPanicStrategy::SilentExit;
    builder.spirv_metadata = SpirvMetadata::NameVariables;
    builder.capabilities.extend([
        Capability::GroupNonUniform,
        Capability::GroupNonUniformBallot,
        Capability::GroupNonUniformShuffle,
        Capability::VulkanMemoryModelDeviceScope,
        Capability::Int64,
    ]);
    let result = builder.build()?;
    let spv = result.module.unwrap_single();
    println!("cargo::rustc-env=MANYLIGHTS_COMPUTE_SPV={}", spv.display());
    Ok(())
}
