//! Compiles `shader-crate` to SPIR-V with rust-gpu.
//!
//! `cargo-gpu-install` installs the pinned nightly (with rust-src, rustc-dev, llvm-tools) through
//! rustup when it is missing and builds the `rustc_codegen_spirv` backend once into
//! `~/.cache/rust-gpu` (`$XDG_CACHE_HOME/rust-gpu` where that is set); afterwards a build takes
//! seconds. [`backend::prepare`] first builds that backend against the system's SPIRV-Tools
//! when they are installed, which spares compiling SPIRV-Tools' C++ sources: a cold build on 2
//! cores took 878 CPU-seconds this way against 1478 (the README's first-build note; its
//! "Toolchain" section says how the modules differ). The host itself stays on stable. The
//! produced module's path reaches the host as `MANYLIGHTS_COMPUTE_SPV` (`include_bytes!`;
//! `MANYLIGHTS_GRAPHICS_SPV` for the raster module), so the binary is self-contained and can be
//! carried to another machine.
//!
//! Two modules: compute kernels (feature `compute`, with the subgroup capabilities) and raster
//! shaders (feature `graphics`, without them: lavapipe rejects GroupNonUniform* in vertex stages).
#[path = "build/backend.rs"]
mod backend;

use backend::Tools;
use cargo_gpu_install::install::Install;
use cargo_gpu_install::spirv_builder::{Capability, ShaderPanicStrategy, SpirvMetadata};

fn main() -> anyhow::Result<()> {
    let crate_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shader-crate");
    match backend::prepare(&crate_path)? {
        Tools::Cached => {}
        Tools::Installed(versions) => println!("cargo::warning=rust-gpu backend built against the installed SPIRV-Tools ({versions}), cached in {}", backend::cache_dir().display()),
        Tools::Compiled(why) => println!(
            "cargo::warning=compiling SPIRV-Tools into the rust-gpu backend (several CPU-minutes, once; cached in {}): {why}",
            backend::cache_dir().display()
        ),
    }
    let backend = Install::from_shader_crate(crate_path.clone())
        .within_build_script()
        .run()?;
    // Module 1: compute kernels, with the subgroup capabilities.
    let mut compute = backend.to_spirv_builder(&crate_path, "spirv-unknown-vulkan1.3");
    configure(&mut compute, "compute");
    compute.capabilities.extend([
        Capability::GroupNonUniform,
        Capability::GroupNonUniformBallot,
        Capability::GroupNonUniformShuffle,
        Capability::VulkanMemoryModelDeviceScope,
        Capability::Int64,
    ]);
    let spv = compute.build()?.module.unwrap_single().to_path_buf();
    println!("cargo::rustc-env=MANYLIGHTS_COMPUTE_SPV={}", spv.display());
    // Module 2: raster shaders, without them (separate target dir so the two feature sets do
    // not keep invalidating each other's build).
    let mut graphics = backend.to_spirv_builder(&crate_path, "spirv-unknown-vulkan1.3");
    configure(&mut graphics, "graphics");
    graphics.target_dir_path = Some("spirv-builder-graphics".into());
    // PrimitiveId in the transparent pass's fragment shaders needs the Geometry capability.
    graphics.capabilities.extend([Capability::DemoteToHelperInvocation, Capability::Geometry]);
    let spv = graphics.build()?.module.unwrap_single().to_path_buf();
    println!("cargo::rustc-env=MANYLIGHTS_GRAPHICS_SPV={}", spv.display());
    Ok(())
}

fn configure(b: &mut cargo_gpu_install::spirv_builder::SpirvBuilder, feature: &str) {
    b.build_script.defaults = true;
    b.shader_panic_strategy = ShaderPanicStrategy::SilentExit;
    b.spirv_metadata = SpirvMetadata::NameVariables;
    b.shader_crate_features.default_features = false;
    b.shader_crate_features.features = vec![feature.to_owned()];
}
