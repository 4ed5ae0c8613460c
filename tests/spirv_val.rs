//! Both produced SPIR-V modules pass `spirv-val` for the Vulkan 1.3 environment they are built
//! for (`./dev.sh test` installs spirv-tools; only outside CI may a missing tool skip with a
//! note), and the entry-point lists of `shaders::kernels` describe the modules exactly: every
//! entry point of a module is listed and every listed name is an entry point of the right
//! stage; each compute handle's workgroup size is the entry's `LocalSize`, and the storage
//! buffers the entry uses are exactly those the host binds (set 0, bindings `0..n`). A
//! registered technique's own kernels (`Description::own_kernels`, `own_raster`) count as listed.
mod common;
use common::spirv::{entry_points, EntryPoint, FRAGMENT, GL_COMPUTE, VERTEX};
use host::render::Technique;
use shaders::kernels::{self, Kernel};
use std::collections::BTreeSet;

/// Every compute handle: `shaders::kernels::ALL` and the registered techniques' own.
fn compute_handles() -> Vec<Kernel<()>> {
    let own = Technique::ALL.iter().flat_map(|t| t.description().own_kernels.iter().copied());
    kernels::ALL.iter().copied().chain(own).collect()
}

/// Every entry name of a raster stage: `listed`, and that stage's entries of the registered
/// techniques' own raster handles (`stage` picks vertex or fragment), each once.
fn raster_names(listed: &[&'static str], stage: fn(&kernels::RasterKernel<()>) -> &'static str) -> Vec<&'static str> {
    let mut own: Vec<&'static str> = Technique::ALL.iter().flat_map(|t| t.description().own_raster.iter().map(stage)).collect();
    own.sort_unstable();
    own.dedup();
    listed.iter().copied().chain(own.into_iter().filter(|n| !listed.contains(n))).collect()
}

/// The environment both modules are built for (`host/build.rs`: `spirv-unknown-vulkan1.3`).
const TARGET_ENV: &str = "vulkan1.3";

fn spirv_val(name: &str, module: &[u8]) {
    let path = std::env::temp_dir().join(format!("manylights-{name}-{}.spv", std::process::id()));
    std::fs::write(&path, module).unwrap();
    let result = std::process::Command::new("spirv-val").args(["--target-env", TARGET_ENV]).arg(&path).output();
    let _ = std::fs::remove_file(&path);
    match result {
        Ok(out) => assert!(out.status.success(), "spirv-val rejects the {name} module:\n{}", String::from_utf8_lossy(&out.stderr)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound && std::env::var_os("CI").is_none() => {
            eprintln!("note: spirv-val not installed: {name} module not validated (./dev.sh test installs spirv-tools)");
        }
        Err(e) => panic!("cannot run spirv-val: {e}"),
    }
}

#[test]
fn compute_module_passes_spirv_val() {
    spirv_val("compute", host::gpu::COMPUTE_SPV);
}

#[test]
fn raster_module_passes_spirv_val() {
    spirv_val("raster", host::gpu::GRAPHICS_SPV);
}

/// Asserts that the entry points of execution model `model` are exactly `listed`.
fn assert_same_names(entries: &[EntryPoint], model: u32, listed: &[&str], what: &str) {
    let in_module: BTreeSet<&str> = entries.iter().filter(|e| e.model == model).map(|e| e.name.as_str()).collect();
    let listed_set: BTreeSet<&str> = listed.iter().copied().collect();
    assert_eq!(listed_set.len(), listed.len(), "{what}: a name is listed twice");
    let unlisted: Vec<_> = in_module.difference(&listed_set).collect();
    let missing: Vec<_> = listed_set.difference(&in_module).collect();
    assert!(
        unlisted.is_empty() && missing.is_empty(),
        "{what}: entry points not listed in shaders::kernels: {unlisted:?}; listed names that are not such entry points: {missing:?}"
    );
}

#[test]
fn every_kernel_handle_names_an_entry_point() {
    let entries = entry_points(host::gpu::COMPUTE_SPV);
    let handles = compute_handles();
    let names: Vec<&str> = handles.iter().map(|k| k.entry).collect();
    assert_same_names(&entries, GL_COMPUTE, &names, "compute module");
    assert!(entries.iter().all(|e| e.model == GL_COMPUTE), "the compute module holds only compute entries");
    for k in &handles {
        let e = entries.iter().find(|e| e.name == k.entry).unwrap();
        assert_eq!(e.local_size, Some(k.workgroup_size), "{}: the handle's workgroup size is not the entry's LocalSize", k.entry);
        let bound: Vec<(u32, u32)> = (0..k.storage_buffers).map(|b| (0, b)).collect();
        assert_eq!(e.storage_buffers, bound, "{}: the storage buffers (set, binding) the entry uses, against those the host binds", k.entry);
    }
}

#[test]
fn every_raster_entry_name_names_an_entry_point() {
    let entries = entry_points(host::gpu::GRAPHICS_SPV);
    assert_same_names(&entries, VERTEX, &raster_names(kernels::VERTEX_ENTRIES, |k| k.vertex), "raster module, vertex stage");
    assert_same_names(&entries, FRAGMENT, &raster_names(kernels::FRAGMENT_ENTRIES, |k| k.fragment), "raster module, fragment stage");
    let others: Vec<_> = entries.iter().filter(|e| e.model != VERTEX && e.model != FRAGMENT).map(|e| &e.name).collect();
    assert!(others.is_empty(), "raster module: entries of other stages {others:?}");
}
