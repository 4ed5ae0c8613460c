//! The produced SPIR-V module passes `spirv-val` (when the tool is installed; `./dev.sh test`
//! installs it) and declares every entry point a kernel handle names.
use shaders::kernels;

#[test]
fn module_passes_spirv_val() {
    let path = std::env::temp_dir().join(format!("manylights-{}.spv", std::process::id()));
    std::fs::write(&path, host::gpu::COMPUTE_SPV).unwrap();
    match std::process::Command::new("spirv-val").arg("--target-env").arg("vulkan1.3").arg(&path).output() {
        Ok(out) => assert!(out.status.success(), "spirv-val failed:\n{}", String::from_utf8_lossy(&out.stderr)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound && std::env::var_os("CI").is_none() => {
            eprintln!("spirv-val not installed: skipped (./dev.sh test installs spirv-tools)");
        }
        Err(e) => panic!("cannot run spirv-val: {e}"),
    }
    let _ = std::fs::remove_file(path);
}

#[test]
fn every_kernel_handle_names_an_entry_point() {
    let names = [
        kernels::OCTA_ROUNDTRIP.entry,
        kernels::CLUSTER_KEYS.entry,
        kernels::MORTON_CODES.entry,
        kernels::WORKGROUP_SCAN.entry,
        kernels::DEBUG_VIEW.entry,
    ];
    for n in names {
        let needle: Vec<u8> = n.bytes().chain([0]).collect();
        assert!(
            host::gpu::COMPUTE_SPV.windows(needle.len()).any(|w| w == needle.as_slice()),
            "entry point {n:?} not in the module"
        );
    }
}
