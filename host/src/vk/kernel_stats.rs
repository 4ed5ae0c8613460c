//! What the driver's compiler made of each compute kernel (`VK_KHR_pipeline_executable_properties`):
//! registers per invocation, binary size, local and shared memory, as the driver names them.
//! Registers bound occupancy, and a latency-bound kernel (a chain of dependent loads per
//! invocation, as in the shading kernels) runs as fast as the number of invocations resident per
//! multiprocessor lets it: these are the numbers behind such a kernel's time.
//!
//! Off unless asked for (`ContextOptions::kernel_statistics`). Statistics come from a second,
//! throwaway pipeline of the same kernel created with `CAPTURE_STATISTICS_KHR`; the pipeline that
//! runs never carries the flag, because with it NVIDIA's driver compiled kernels that ran several
//! times slower (H200, Sponza 1080p: the clustered shading kernel 0.81 ms against 0.16 ms), so
//! timings taken with `--kernel-stats` stay the timings without it. Devices without the
//! extension report none.
use super::context::Context;
use ash::vk;
use std::ffi::CStr;

/// One executable of one kernel's pipeline and the driver's statistics of it.
#[derive(Clone, Debug)]
pub struct KernelStatistics {
    /// The kernel's entry point.
    pub entry: String,
    /// The executable's name as the driver gives it (e.g. the stage).
    pub executable: String,
    /// `(name, value)` in the driver's order.
    pub values: Vec<(String, String)>,
}

impl KernelStatistics {
    /// `entry: name value, name value, …` on one line.
    pub fn line(&self) -> String {
        let values: Vec<String> = self.values.iter().map(|(n, v)| format!("{n} {v}")).collect();
        format!("{} ({}): {}", self.entry, self.executable, values.join(", "))
    }
}

fn text(chars: &[std::ffi::c_char]) -> String {
    // The driver fills a NUL-terminated array; a missing NUL gives the whole array.
    let bytes: Vec<u8> = chars.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

fn value(s: &vk::PipelineExecutableStatisticKHR<'_>) -> String {
    // SAFETY: `format` says which member of the union the driver wrote.
    unsafe {
        match s.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => (s.value.b32 != 0).to_string(),
            vk::PipelineExecutableStatisticFormatKHR::INT64 => s.value.i64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::UINT64 => s.value.u64.to_string(),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => format!("{:.3}", s.value.f64),
            _ => "?".into(),
        }
    }
}

/// Compiles `info` once more with `CAPTURE_STATISTICS_KHR` and reads the statistics of every
/// executable of that pipeline into the context's list, then destroys it. A failing call loses
/// only the statistics.
pub(crate) fn capture(ctx: &Context, info: vk::ComputePipelineCreateInfo<'_>, entry: &str) {
    let (Some(list), Some(ext)) = (&ctx.kernel_statistics, &ctx.executable_properties) else { return };
    let info = info.flags(info.flags | vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR);
    // SAFETY: `info` is the create info of a pipeline that was just made from live objects.
    let pipeline = match unsafe { ctx.device.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) } {
        Ok(p) => p[0],
        Err(_) => return,
    };
    read(list, ext, pipeline, entry);
    // SAFETY: the pipeline was made above and was never recorded.
    unsafe { ctx.device.destroy_pipeline(pipeline, None) };
}

fn read(
    list: &std::sync::Mutex<Vec<KernelStatistics>>,
    ext: &ash::khr::pipeline_executable_properties::Device,
    pipeline: vk::Pipeline,
    entry: &str,
) {
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: the extension and its feature are enabled whenever `executable_properties` is set.
    let Ok(executables) = (unsafe { ext.get_pipeline_executable_properties(&info) }) else { return };
    for (index, exe) in executables.iter().enumerate() {
        let exe_info = vk::PipelineExecutableInfoKHR::default().pipeline(pipeline).executable_index(index as u32);
        let Ok(stats) = (unsafe { ext.get_pipeline_executable_statistics(&exe_info) }) else { continue };
        let values = stats.iter().map(|s| (text(&s.name), value(s))).collect();
        let executable = text(&exe.name);
        let entry = entry.to_string();
        list.lock().unwrap_or_else(|e| e.into_inner()).push(KernelStatistics { entry, executable, values });
    }
}

/// Whether the device can report statistics: the extension and its `pipelineExecutableInfo`.
pub(crate) fn supported(exts: &[vk::ExtensionProperties], feature: &vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR<'_>) -> bool {
    let name: &CStr = ash::khr::pipeline_executable_properties::NAME;
    exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name)) && feature.pipeline_executable_info == vk::TRUE
}
