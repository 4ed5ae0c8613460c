//! What the driver's compiler made of each compute kernel (`VK_KHR_pipeline_executable_properties`):
//! registers per invocation, binary size, local and shared memory, as the driver names them.
//! Registers bound occupancy (the invocations resident per multiprocessor), and with it how well
//! a kernel hides its latencies; the binary size shows what unrolling and specialisation cost.
//!
//! Off unless asked for (`ContextOptions::kernel_statistics`). Statistics come from a second,
//! throwaway pipeline of the same kernel created with `CAPTURE_STATISTICS_KHR`; the pipeline that
//! runs never carries the flag, because with it NVIDIA's driver compiled kernels that ran several
//! times slower (H200, Sponza 1080p: the clustered shading kernel 0.81 ms against 0.16 ms), so
//! timings taken with `--kernel-stats` stay the timings without it. Devices without the
//! extension report none.
use super::context::Context;
use super::device::cstr;
use ash::khr::pipeline_executable_properties;
use ash::vk;
use std::sync::Mutex;

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

/// A context's statistics: the extension's functions and what was read so far.
pub struct Capture {
    ext: pipeline_executable_properties::Device,
    list: Mutex<Vec<KernelStatistics>>,
}

impl Capture {
    /// On a device created with the extension and its `pipelineExecutableInfo` feature.
    pub(crate) fn new(instance: &ash::Instance, device: &ash::Device) -> Self {
        Self { ext: pipeline_executable_properties::Device::new(instance, device), list: Mutex::new(Vec::new()) }
    }

    /// The statistics read so far, in the order the kernels were made.
    pub fn statistics(&self) -> Vec<KernelStatistics> {
        self.list.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Compiles `info` once more with `CAPTURE_STATISTICS_KHR` and reads the statistics of every
/// executable of that pipeline into the context's list, then destroys it. A failing call loses
/// only the statistics.
pub(crate) fn capture(ctx: &Context, info: vk::ComputePipelineCreateInfo<'_>, entry: &str) {
    let Some(Capture { ext, list }) = &ctx.kernel_statistics else { return };
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

fn read(list: &Mutex<Vec<KernelStatistics>>, ext: &pipeline_executable_properties::Device, pipeline: vk::Pipeline, entry: &str) {
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    // SAFETY: a `Capture` exists only on a device with the extension and its feature enabled.
    let Ok(executables) = (unsafe { ext.get_pipeline_executable_properties(&info) }) else { return };
    for (index, exe) in executables.iter().enumerate() {
        let exe_info = vk::PipelineExecutableInfoKHR::default().pipeline(pipeline).executable_index(index as u32);
        let Ok(stats) = (unsafe { ext.get_pipeline_executable_statistics(&exe_info) }) else { continue };
        let values = stats.iter().map(|s| (cstr(&s.name), value(s))).collect();
        let executable = cstr(&exe.name);
        let entry = entry.to_string();
        list.lock().unwrap_or_else(|e| e.into_inner()).push(KernelStatistics { entry, executable, values });
    }
}
