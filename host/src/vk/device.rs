//! Physical-device selection and what we learn about the chosen device.
//!
//! Selection: with a wanted substring (`--device`, `MANYLIGHTS_DEVICE`) the first device whose
//! name contains it (case-insensitive); otherwise the best usable one by type (discrete >
//! integrated > virtual > CPU). A device is usable when it offers Vulkan 1.3, compute-stage
//! subgroup ballot + shuffle, the Vulkan memory model at device scope, 64-bit integers and
//! `VK_KHR_push_descriptor`. Errors list every device with the reason it was not taken.
use super::error::{CallContext, VkError, VkResult};
use ash::{khr, vk};
use std::ffi::CStr;

/// Facts about the selected device (also written into stats files).
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: &'static str,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
    /// PCI vendor id (`VkPhysicalDeviceProperties::vendorID`).
    pub vendor_id: u32,
    /// The subgroup width compute kernels run with (never hard-coded: read here).
    pub subgroup_size: u32,
    pub min_subgroup_size: u32,
    pub max_subgroup_size: u32,
    /// Whether pipelines can require full subgroups (`computeFullSubgroups`).
    pub full_subgroups: bool,
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    /// Valid timestamp bits of the async-compute family (0: no timestamps there, or no family).
    pub async_timestamp_valid_bits: u32,
    /// Timestamps of different queues share one time line, so a frame can be timed from its first
    /// to its last timestamp across queues. Vulkan compares timestamps only within one queue
    /// unless the device offers the *device* time domain of calibrated timestamps
    /// (`VK_KHR/EXT_calibrated_timestamps`), whose values "are comparable with device timestamp
    /// values captured using vkCmdWriteTimestamp" on any queue ([`device_time_domain`]).
    pub timestamps_across_queues: bool,
    /// The device advertises `VK_EXT_calibrated_timestamps` (its time domains are then queried).
    pub calibrated_timestamps_ext: bool,
    pub max_shared_memory_bytes: u32,
    /// The largest storage-buffer binding the kernels may use: `maxStorageBufferRange`, below
    /// [`MAX_BINDING_BYTES`] ([`usable_storage_range`]).
    pub max_storage_buffer_range: u32,
    /// `maxStorageBufferRange` as the device reports it: the range of the bindings whose
    /// length no kernel reads (the light buffer, the light BVH's sorted spheres:
    /// `shaders::compact_light::light_at`, `tests/spirv_lengths.rs`). The driver that reads a
    /// binding of 2^31 bytes as empty ([`MAX_BINDING_BYTES`]) does so through its length.
    pub reported_storage_buffer_range: u32,
    /// Largest width or height of a 2D image (`maxImageDimension2D`; lavapipe: 16384).
    pub max_image_dimension_2d: u32,
    /// Size of the largest device-local memory heap, bytes (what one frame's buffers share).
    pub device_local_bytes: u64,
    pub max_workgroup_invocations: u32,
    pub graphics_family: u32,
    /// A compute-only queue family ("async compute"), when the device has one.
    pub async_compute_family: Option<u32>,
    /// The driver reports what it compiled each kernel to (`VK_KHR_pipeline_executable_properties`:
    /// registers, sizes; `vk::kernel_stats`).
    pub kernel_statistics: bool,
    /// Sample counts (bit `N` for `N` samples) a multisampled G-buffer can have here: counts the
    /// device renders and samples for float and depth targets alike, with its standard sample
    /// locations (`--msaa`; 1 alone where it has none of them). Vulkan requires 1 and 4.
    pub msaa_sample_counts: u32,
}

/// Bytes a storage-buffer binding stays below on every device: `2^31 − 1`. On an NVIDIA H200
/// (driver 580.159.04) the shaders read a binding of exactly 2^31 bytes as holding nothing: 2^26
/// lights of 32 bytes rendered a black frame, 2^26 − 1 a lit one (`docs/results/h200/
/// light-buffer-boundary/`), so byte sizes are kept within a signed 32-bit range whatever the
/// device reports. The cause is the binding's length (`OpArrayLength`): the buffers whose length
/// no kernel reads (`memory::Buffer::length_free`: the lights, the BVH's sorted spheres) take the
/// whole reported range, and read correctly past 2^31 bytes (`docs/results/h100/
/// lights-past-2gib/`: 2^26 lights of 32 bytes list their lights).
pub const MAX_BINDING_BYTES: u32 = i32::MAX as u32;

/// The storage-buffer range the renderer uses on a device reporting `maxStorageBufferRange =
/// reported` ([`MAX_BINDING_BYTES`]).
pub fn usable_storage_range(reported: u32) -> u32 {
    reported.min(MAX_BINDING_BYTES)
}

impl DeviceInfo {
    /// Mesa's CPU driver (lavapipe on llvmpipe), whose loop limiter ends a shader's loops after
    /// 65 535 iterations: techniques cap the lights one invocation visits there.
    pub fn is_llvmpipe(&self) -> bool {
        self.driver_name.to_lowercase().contains("llvmpipe")
    }

    /// Whether workgroups that wait on one another (a chained scan's look-back) finish here:
    /// discrete NVIDIA and AMD GPUs keep every launched workgroup running, so a workgroup that
    /// waits only on workgroups launched before it (tiles claimed in launch order) waits a
    /// bounded time. Vulkan promises no forward progress between workgroups, so every other
    /// device answers no — lavapipe included: its loop limiter would end a spinning look-back.
    pub fn workgroups_progress(&self) -> bool {
        const NVIDIA: u32 = 0x10de;
        const AMD: u32 = 0x1002;
        self.kind == "discrete GPU" && matches!(self.vendor_id, NVIDIA | AMD) && !self.is_llvmpipe()
    }

    /// One line naming the device, e.g. for the CLI's stderr and the notes.
    pub fn line(&self) -> String {
        format!(
            "{} ({}; driver {} {}; Vulkan {}; subgroup {} [{}..{}]; shared memory {} KiB; storage binding {} MiB)",
            self.name,
            self.kind,
            self.driver_name,
            self.driver_info,
            self.api_version,
            self.subgroup_size,
            self.min_subgroup_size,
            self.max_subgroup_size,
            self.max_shared_memory_bytes / 1024,
            self.max_storage_buffer_range / (1 << 20)
        )
    }
}

fn kind_name(t: vk::PhysicalDeviceType) -> (&'static str, u32) {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => ("discrete GPU", 0),
        vk::PhysicalDeviceType::INTEGRATED_GPU => ("integrated GPU", 1),
        vk::PhysicalDeviceType::VIRTUAL_GPU => ("virtual GPU", 2),
        vk::PhysicalDeviceType::CPU => ("CPU", 3),
        _ => ("other", 4),
    }
}

fn version(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

/// [`DeviceInfo::msaa_sample_counts`] from the device's limits.
fn msaa_sample_counts(l: &vk::PhysicalDeviceLimits) -> u32 {
    if l.standard_sample_locations != vk::TRUE {
        return 1;
    }
    let all = l.framebuffer_color_sample_counts
        & l.framebuffer_depth_sample_counts
        & l.sampled_image_color_sample_counts
        & l.sampled_image_depth_sample_counts;
    all.as_raw() | 1
}

/// A Vulkan fixed-size string (NUL-terminated within its array; a missing NUL gives the whole
/// array).
pub(super) fn cstr(bytes: &[std::ffi::c_char]) -> String {
    let bytes: Vec<u8> = bytes.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Whether `name` is among the device's extensions.
fn has_extension(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name))
}

/// Inspects one device: its info, its type rank, or why it cannot be used.
fn inspect(instance: &ash::Instance, pd: vk::PhysicalDevice) -> VkResult<(DeviceInfo, u32, Option<String>)> {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Properties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut subgroup)
        .push_next(&mut driver)
        .push_next(&mut v13);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let p = props2.properties;
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut exe = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12).push_next(&mut f13).push_next(&mut exe);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let f10 = f2.features;
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }
        .call("vkEnumerateDeviceExtensionProperties")?;
    let has_push = has_extension(&exts, khr::push_descriptor::NAME);
    let calibrated_timestamps_ext = has_extension(&exts, ash::ext::calibrated_timestamps::NAME);
    let kernel_statistics = has_extension(&exts, khr::pipeline_executable_properties::NAME) && exe.pipeline_executable_info == vk::TRUE;

    let gfx = families.iter().position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE));
    let async_compute = families
        .iter()
        .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE) && !q.queue_flags.contains(vk::QueueFlags::GRAPHICS));
    let (kind, rank) = kind_name(p.device_type);
    let memory = unsafe { instance.get_physical_device_memory_properties(pd) };
    let device_local_bytes = memory.memory_heaps[..(memory.memory_heap_count as usize).min(vk::MAX_MEMORY_HEAPS)]
        .iter()
        .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|h| h.size)
        .max()
        .unwrap_or(0);
    let info = DeviceInfo {
        name: cstr(&p.device_name),
        kind,
        driver_name: cstr(&driver.driver_name),
        driver_info: cstr(&driver.driver_info),
        api_version: version(p.api_version),
        vendor_id: p.vendor_id,
        subgroup_size: subgroup.subgroup_size,
        min_subgroup_size: v13.min_subgroup_size.max(1),
        max_subgroup_size: v13.max_subgroup_size.max(subgroup.subgroup_size),
        full_subgroups: f13.compute_full_subgroups == vk::TRUE,
        timestamp_period_ns: p.limits.timestamp_period,
        timestamp_valid_bits: gfx.map(|g| families[g].timestamp_valid_bits).unwrap_or(0),
        async_timestamp_valid_bits: async_compute.map(|f| families[f].timestamp_valid_bits).unwrap_or(0),
        timestamps_across_queues: false,
        calibrated_timestamps_ext,
        max_shared_memory_bytes: p.limits.max_compute_shared_memory_size,
        max_storage_buffer_range: usable_storage_range(p.limits.max_storage_buffer_range),
        reported_storage_buffer_range: p.limits.max_storage_buffer_range,
        max_image_dimension_2d: p.limits.max_image_dimension2_d,
        device_local_bytes,
        max_workgroup_invocations: p.limits.max_compute_work_group_invocations,
        graphics_family: gfx.unwrap_or(0) as u32,
        async_compute_family: async_compute.map(|f| f as u32),
        kernel_statistics,
        msaa_sample_counts: msaa_sample_counts(&p.limits),
    };
    let mut missing = Vec::new();
    if p.api_version < vk::API_VERSION_1_3 {
        missing.push(format!("Vulkan 1.3 (has {})", info.api_version));
    }
    if gfx.is_none() {
        missing.push("a graphics+compute queue".into());
    }
    if !subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE) {
        missing.push("subgroup operations in compute shaders".into());
    }
    let ops = vk::SubgroupFeatureFlags::BASIC | vk::SubgroupFeatureFlags::BALLOT | vk::SubgroupFeatureFlags::SHUFFLE;
    if !subgroup.supported_operations.contains(ops) {
        missing.push(format!("subgroup basic/ballot/shuffle (has {:?})", subgroup.supported_operations));
    }
    if f12.vulkan_memory_model == 0 || f12.vulkan_memory_model_device_scope == 0 {
        missing.push("vulkanMemoryModel + vulkanMemoryModelDeviceScope".into());
    }
    if f10.shader_int64 == 0 {
        missing.push("shaderInt64".into());
    }
    // The transparent pass: fragment shaders append to per-pixel lists and read PrimitiveId;
    // weighted blended OIT blends its two targets differently.
    if f10.fragment_stores_and_atomics == 0 || f10.geometry_shader == 0 || f10.independent_blend == 0 {
        missing.push("fragmentStoresAndAtomics + geometryShader (PrimitiveId in fragment shaders) + independentBlend".into());
    }
    if !has_push {
        missing.push("VK_KHR_push_descriptor".into());
    }
    if info.subgroup_size > 128 || !info.subgroup_size.is_power_of_two() {
        missing.push(format!("a power-of-two subgroup size <= 128 (has {})", info.subgroup_size));
    }
    let why = (!missing.is_empty()).then(|| missing.join(", "));
    Ok((info, rank, why))
}

/// Whether `pd` offers the device time domain of calibrated timestamps (see
/// [`DeviceInfo::timestamps_across_queues`]); false where the extension is absent or the query fails.
pub fn device_time_domain(entry: &ash::Entry, instance: &ash::Instance, pd: vk::PhysicalDevice, info: &DeviceInfo) -> bool {
    if !info.calibrated_timestamps_ext {
        return false;
    }
    let calibrated = ash::ext::calibrated_timestamps::Instance::new(entry, instance);
    // SAFETY: the device advertises the extension, so the loader resolves this command for it.
    let domains = unsafe { calibrated.get_physical_device_calibrateable_time_domains(pd) };
    domains.is_ok_and(|d| d.contains(&vk::TimeDomainKHR::DEVICE))
}

/// A physical device, its info, its type rank (0 = discrete) and why it is unusable (None: usable).
pub type Candidate = (vk::PhysicalDevice, DeviceInfo, u32, Option<String>);

/// Every physical device, inspected.
pub fn list(instance: &ash::Instance) -> VkResult<Vec<Candidate>> {
    let devices = unsafe { instance.enumerate_physical_devices() }.call("vkEnumeratePhysicalDevices")?;
    devices
        .into_iter()
        .map(|pd| inspect(instance, pd).map(|(info, rank, why)| (pd, info, rank, why)))
        .collect()
}

/// Chooses the physical device (see the module docs).
pub fn select(instance: &ash::Instance, wanted: Option<&str>) -> VkResult<(vk::PhysicalDevice, DeviceInfo)> {
    let inspected = list(instance)?;
    if inspected.is_empty() {
        return Err(VkError::NoDevices);
    }
    let listing = inspected
        .iter()
        .map(|(_, i, _, why)| match why {
            None => format!("  {} ({})", i.name, i.kind),
            Some(w) => format!("  {} ({}) — unusable: lacks {}", i.name, i.kind, w),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let wanted = wanted.map(str::trim).filter(|w| !w.is_empty());
    let pick = match wanted {
        Some(w) => {
            let lw = w.to_lowercase();
            let found = inspected.iter().find(|(_, i, _, _)| i.name.to_lowercase().contains(&lw));
            match found {
                Some((_, i, _, Some(why))) => {
                    return Err(VkError::Unsupported { device: i.name.clone(), missing: why.clone() })
                }
                Some(d) => d,
                None => return Err(VkError::NoMatchingDevice { wanted: w.into(), listing }),
            }
        }
        None => match inspected.iter().filter(|d| d.3.is_none()).min_by_key(|d| d.2) {
            Some(d) => d,
            None => return Err(VkError::NoMatchingDevice { wanted: "any usable device".into(), listing }),
        },
    };
    Ok((pick.0, pick.1.clone()))
}

/// Creates the logical device with the features the kernels need; returns it and its queues.
/// With `swapchain`, `VK_KHR_swapchain` is enabled too (a window's presentation); with
/// `kernel_statistics` (where `info.kernel_statistics`), `VK_KHR_pipeline_executable_properties`.
pub fn create(instance: &ash::Instance, pd: vk::PhysicalDevice, info: &DeviceInfo, swapchain: bool, kernel_statistics: bool) -> VkResult<ash::Device> {
    let priorities = [1.0f32];
    let mut queues = vec![vk::DeviceQueueCreateInfo::default()
        .queue_family_index(info.graphics_family)
        .queue_priorities(&priorities)];
    if let Some(f) = info.async_compute_family {
        queues.push(vk::DeviceQueueCreateInfo::default().queue_family_index(f).queue_priorities(&priorities));
    }
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .vulkan_memory_model(true)
        .vulkan_memory_model_device_scope(true)
        .host_query_reset(true)
        .timeline_semaphore(true);
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
        .subgroup_size_control(true)
        .compute_full_subgroups(info.full_subgroups)
        .synchronization2(true)
        .dynamic_rendering(true)
        .shader_demote_to_helper_invocation(true);
    let f10 = vk::PhysicalDeviceFeatures::default().shader_int64(true).fragment_stores_and_atomics(true).geometry_shader(true).independent_blend(true);
    let mut f2 = vk::PhysicalDeviceFeatures2::default().features(f10).push_next(&mut f12).push_next(&mut f13);
    let mut exe = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default().pipeline_executable_info(true);
    let mut exts = vec![khr::push_descriptor::NAME.as_ptr()];
    if swapchain {
        exts.push(khr::swapchain::NAME.as_ptr());
    }
    if kernel_statistics {
        exts.push(khr::pipeline_executable_properties::NAME.as_ptr());
        f2 = f2.push_next(&mut exe);
    }
    let create = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&exts)
        .push_next(&mut f2);
    unsafe { instance.create_device(pd, &create, None) }.call("vkCreateDevice")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_stay_below_two_gibibytes() {
        assert_eq!(usable_storage_range(u32::MAX), (1 << 31) - 1);
        assert_eq!(usable_storage_range(1 << 31), (1 << 31) - 1, "a binding of exactly 2^31 bytes reads as empty on an H200");
        assert_eq!(usable_storage_range(128 << 20), 128 << 20, "lavapipe's 128 MiB stays");
        assert!((1u64 << 26) * 32 > MAX_BINDING_BYTES as u64 && ((1u64 << 26) - 1) * 32 <= MAX_BINDING_BYTES as u64);
    }
}
