//! The Vulkan context: instance + device + queues + allocator + command pool, shared (`Arc`) by
//! every RAII object made from it, so each can free itself in `Drop`.
use super::device::{self, DeviceInfo};
use super::error::{CallContext, VkError, VkResult};
use super::instance::Instance;
use super::kernel_stats::Capture;
use super::pipeline::Recorder;
use super::profiler::Profiler;
use ash::{ext, khr, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

/// How to open the context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable the Khronos validation layer with synchronization validation.
    pub validation: bool,
    /// Case-insensitive substring of the device name to use.
    pub device: Option<String>,
    /// Record what the driver compiled each compute kernel to (`vk::kernel_stats`), where the
    /// device can say.
    pub kernel_statistics: bool,
}

pub struct Shared {
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub info: DeviceInfo,
    pub queue: Mutex<vk::Queue>,
    /// Compute-only queue (family `info.async_compute_family`), when the device has one.
    pub async_compute_queue: Option<Mutex<vk::Queue>>,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub push_descriptor: khr::push_descriptor::Device,
    debug_utils: Option<ext::debug_utils::Device>,
    command_pool: Mutex<vk::CommandPool>,
    /// Command pool of the async-compute family (with `async_compute_queue`).
    async_command_pool: Option<Mutex<vk::CommandPool>>,
    /// The kernels' compiled statistics, with `ContextOptions::kernel_statistics` on a device
    /// that reports them (`vk::kernel_stats`).
    pub kernel_statistics: Option<Capture>,
    /// Dropped last (after `Drop::drop` destroyed the device).
    pub instance: Instance,
}

/// Cheap to clone; the device lives until the last clone and the last resource are gone.
#[derive(Clone)]
pub struct Context(pub Arc<Shared>);

impl std::ops::Deref for Context {
    type Target = Shared;
    fn deref(&self) -> &Shared {
        &self.0
    }
}

impl Context {
    pub fn new(opts: &ContextOptions) -> VkResult<Self> {
        Self::open(opts, None)
    }

    /// A context that can present to windows of `display` (its surface extensions on the
    /// instance, `VK_KHR_swapchain` on the device): the viewer's (`vk::present`).
    pub fn for_display(opts: &ContextOptions, display: raw_window_handle::RawDisplayHandle) -> VkResult<Self> {
        Self::open(opts, Some(display))
    }

    fn open(opts: &ContextOptions, display: Option<raw_window_handle::RawDisplayHandle>) -> VkResult<Self> {
        let surface_exts = match display {
            Some(d) => ash_window::enumerate_required_extensions(d).call("the window system's Vulkan surface extensions")?,
            None => &[],
        };
        let instance = Instance::with_extensions(opts.validation, surface_exts)?;
        let (physical, mut info) = device::select(&instance.raw, opts.device.as_deref())?;
        info.timestamps_across_queues = device::device_time_domain(&instance.entry, &instance.raw, physical, &info);
        let kernel_statistics = opts.kernel_statistics && info.kernel_statistics;
        let device = device::create(&instance.raw, physical, &info, display.is_some(), kernel_statistics)?;
        let queue = unsafe { device.get_device_queue(info.graphics_family, 0) };
        let async_compute_queue =
            info.async_compute_family.map(|f| Mutex::new(unsafe { device.get_device_queue(f, 0) }));
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| VkError::Alloc { name: "allocator".into(), bytes: 0, source })?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(info.graphics_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT | vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }.call("vkCreateCommandPool")?;
        let async_command_pool = match info.async_compute_family {
            Some(f) => {
                let info = vk::CommandPoolCreateInfo::default().queue_family_index(f).flags(pool_info.flags);
                Some(Mutex::new(unsafe { device.create_command_pool(&info, None) }.call("vkCreateCommandPool (async compute)")?))
            }
            None => None,
        };
        let push_descriptor = khr::push_descriptor::Device::new(&instance.raw, &device);
        let kernel_statistics = kernel_statistics.then(|| Capture::new(&instance.raw, &device));
        let debug_utils = instance.debug_utils.then(|| ext::debug_utils::Device::new(&instance.raw, &device));
        Ok(Self(Arc::new(Shared {
            physical,
            device,
            info,
            queue: Mutex::new(queue),
            async_compute_queue,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            push_descriptor,
            debug_utils,
            command_pool: Mutex::new(command_pool),
            async_command_pool,
            kernel_statistics,
            instance,
        })))
    }

    /// Validation messages reported so far (always empty without validation).
    pub fn validation_messages(&self) -> Vec<String> {
        self.instance.messages()
    }

    /// Takes (and clears) the validation messages reported so far.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.instance.take_messages()
    }

    /// Gives a Vulkan object a debug name (shown by RenderDoc and in validation messages).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.debug_utils {
            let Ok(name) = std::ffi::CString::new(name.replace('\0', " ")) else { return };
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // Naming is best effort: a failure only loses a label.
            let _ = unsafe { du.set_debug_utils_object_name(&info) };
        }
    }

    /// Records with `f` on a [`Recorder`] (its passes timed by `profiler`), submits to the
    /// graphics+compute queue, waits.
    pub fn run<R>(&self, profiler: Option<&mut Profiler>, f: impl FnOnce(&mut Recorder<'_>) -> VkResult<R>) -> VkResult<R> {
        self.submit_and_wait(|cmd| f(&mut Recorder::new(self, cmd, profiler)))
    }

    /// Records `on_async` for the async-compute queue, and `on_main_first` then `on_main` for the
    /// graphics queue; waits for all. `on_main_first` (the raster passes) is a batch of its own,
    /// which does not wait; `on_main` is a second batch of the same submission that waits for the
    /// async work (a timeline semaphore). A semaphore wait can hold a whole batch back whatever its
    /// stage mask (NVIDIA's driver did, so nothing overlapped), hence the split: the raster runs
    /// beside the async work.
    /// Passes of `on_async` are timed by `async_profiler`, both main submissions by `profiler`.
    /// Without an async-compute queue (or with `overlap` false) everything goes into one command
    /// buffer, `on_main_first`, `on_async`, `on_main` in that order, timed by `profiler`.
    pub fn run_overlapped<A, B, C>(
        &self,
        overlap: bool,
        profiler: Option<&mut Profiler>,
        async_profiler: Option<&mut Profiler>,
        on_async: impl FnOnce(&mut Recorder<'_>) -> VkResult<A>,
        on_main_first: impl FnOnce(&mut Recorder<'_>) -> VkResult<B>,
        on_main: impl FnOnce(&mut Recorder<'_>) -> VkResult<C>,
    ) -> VkResult<(A, B, C)> {
        if !overlap || self.async_compute_queue.is_none() {
            return self.run(profiler, |rec| {
                let b = on_main_first(rec)?;
                let a = on_async(rec)?;
                Ok((a, b, on_main(rec)?))
            });
        }
        self.submit_overlapped_and_wait(|cmd| on_async(&mut Recorder::new(self, cmd, async_profiler)), |first, second| {
            let mut profiler = profiler;
            let b = on_main_first(&mut Recorder::new(self, first, profiler.as_deref_mut()))?;
            let c = on_main(&mut Recorder::continuing(self, second, profiler))?;
            Ok((b, c))
        })
        .map(|r| r.map(|(a, (b, c))| (a, b, c)))
        .expect("an async-compute queue (checked above)")
    }

    /// Records commands with `record`, submits them to the graphics+compute queue and waits.
    pub fn submit_and_wait<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> VkResult<R>) -> VkResult<R> {
        self.submit_signalling_and_wait(None, record)
    }

    /// [`Context::submit_and_wait`] whose submission also signals `signal` (a presentation waits
    /// for it).
    pub(crate) fn submit_signalling_and_wait<R>(&self, signal: Option<vk::Semaphore>, record: impl FnOnce(vk::CommandBuffer) -> VkResult<R>) -> VkResult<R> {
        let pool = self.command_pool.lock().unwrap_or_else(|e| e.into_inner());
        let cmd = self.begin_commands(*pool)?;
        let result = (|| {
            let r = record(cmd)?;
            unsafe { self.device.end_command_buffer(cmd) }.call("vkEndCommandBuffer")?;
            self.submit_all_and_wait(&[(&self.queue, cmd, None, signal)])?;
            Ok(r)
        })();
        unsafe { self.device.free_command_buffers(*pool, &[cmd]) };
        result
    }

    /// Overlapped submission: `record_async` goes to the async-compute queue; `record_main`
    /// records two command buffers for the graphics+compute queue, two batches of one submission:
    /// the first runs beside the async work, the second waits for it (a timeline semaphore, at the
    /// compute stage; [`Context::submit_overlapped`]). Waits for all three. `None` without an
    /// async queue.
    pub fn submit_overlapped_and_wait<A, B>(
        &self,
        record_async: impl FnOnce(vk::CommandBuffer) -> VkResult<A>,
        record_main: impl FnOnce(vk::CommandBuffer, vk::CommandBuffer) -> VkResult<B>,
    ) -> Option<VkResult<(A, B)>> {
        let (Some(async_queue), Some(async_pool)) = (&self.async_compute_queue, &self.async_command_pool) else {
            return None;
        };
        let d = &self.device;
        let async_pool = async_pool.lock().unwrap_or_else(|e| e.into_inner());
        let main_pool = self.command_pool.lock().unwrap_or_else(|e| e.into_inner());
        let result = (|| {
            // A timeline semaphore: the main queue's wait may be submitted before the async
            // queue's signal, so both main command buffers go in one submission.
            let mut timeline = vk::SemaphoreTypeCreateInfo::default().semaphore_type(vk::SemaphoreType::TIMELINE).initial_value(0);
            let semaphore = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default().push_next(&mut timeline), None) }.call("vkCreateSemaphore")?;
            let mut allocated: Vec<(vk::CommandPool, vk::CommandBuffer)> = Vec::new();
            let submitted = (|| {
                for pool in [*async_pool, *main_pool, *main_pool] {
                    allocated.push((pool, self.begin_commands(pool)?));
                }
                let (ca, cm1, cm2) = (allocated[0].1, allocated[1].1, allocated[2].1);
                let a = record_async(ca)?;
                let b = record_main(cm1, cm2)?;
                for c in [ca, cm1, cm2] {
                    unsafe { d.end_command_buffer(c) }.call("vkEndCommandBuffer")?;
                }
                self.submit_overlapped(async_queue, semaphore, ca, cm1, cm2)?;
                Ok((a, b))
            })();
            unsafe {
                for (pool, c) in allocated {
                    d.free_command_buffers(pool, &[c]);
                }
                d.destroy_semaphore(semaphore, None);
            }
            submitted
        })();
        Some(result)
    }

    /// Submits the raster `cm1` and the main queue's compute `cm2` in one submission (the raster
    /// starts at once; `cm2` waits at the compute stage for value 1 of the timeline `semaphore`),
    /// then the async work `ca`, which signals it; waits for both. One main submission, not two
    /// with a fence each: on the H200 (Sponza 1080p, `clustered-bvh`, 10k lights) the main
    /// queue's time outside its passes went from 0.019 ms to 0.010 (0.015 with the raster's
    /// fence dropped alone; 0.004 with everything on one queue). Where the async submission
    /// fails, the host signals the semaphore so that the main queue does not wait for ever, and
    /// the error is returned once it has finished.
    fn submit_overlapped(&self, async_queue: &Mutex<vk::Queue>, semaphore: vk::Semaphore, ca: vk::CommandBuffer, cm1: vk::CommandBuffer, cm2: vk::CommandBuffer) -> VkResult<()> {
        let d = &self.device;
        let fence = || unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.call("vkCreateFence");
        let (first, second, asynchronous, one) = ([cm1], [cm2], [ca], [1u64]);
        let (sems, stages) = ([semaphore], [vk::PipelineStageFlags::COMPUTE_SHADER]);
        let main_fence = fence()?;
        let mut wait_value = vk::TimelineSemaphoreSubmitInfo::default().wait_semaphore_values(&one);
        let batches = [
            vk::SubmitInfo::default().command_buffers(&first),
            vk::SubmitInfo::default().command_buffers(&second).wait_semaphores(&sems).wait_dst_stage_mask(&stages).push_next(&mut wait_value),
        ];
        let submitted = {
            let q = self.queue.lock().unwrap_or_else(|e| e.into_inner());
            unsafe { d.queue_submit(*q, &batches, main_fence) }.call("vkQueueSubmit")
        };
        if let Err(e) = submitted {
            unsafe { d.destroy_fence(main_fence, None) };
            return Err(e);
        }
        let mut result = Ok(());
        let mut fences = vec![main_fence];
        let mut signal_value = vk::TimelineSemaphoreSubmitInfo::default().signal_semaphore_values(&one);
        let signalled = fence().and_then(|async_fence| {
            let batch = vk::SubmitInfo::default().command_buffers(&asynchronous).signal_semaphores(&sems).push_next(&mut signal_value);
            let q = async_queue.lock().unwrap_or_else(|e| e.into_inner());
            match unsafe { d.queue_submit(*q, &[batch], async_fence) }.call("vkQueueSubmit") {
                Ok(()) => {
                    fences.push(async_fence);
                    Ok(())
                }
                Err(e) => {
                    unsafe { d.destroy_fence(async_fence, None) };
                    Err(e)
                }
            }
        });
        if let Err(e) = signalled {
            let release = vk::SemaphoreSignalInfo::default().semaphore(semaphore).value(1);
            let _ = unsafe { d.signal_semaphore(&release) };
            result = Err(e);
        }
        let waited = unsafe { d.wait_for_fences(&fences, true, u64::MAX) }.call("vkWaitForFences");
        for f in fences {
            unsafe { d.destroy_fence(f, None) };
        }
        result.and(waited)
    }

    /// Allocates and begins a one-time command buffer from `pool`.
    fn begin_commands(&self, pool: vk::CommandPool) -> VkResult<vk::CommandBuffer> {
        let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).level(vk::CommandBufferLevel::PRIMARY).command_buffer_count(1);
        let cmd = unsafe { self.device.allocate_command_buffers(&alloc) }.call("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        if let Err(e) = unsafe { self.device.begin_command_buffer(cmd, &begin) }.call("vkBeginCommandBuffer") {
            unsafe { self.device.free_command_buffers(pool, &[cmd]) };
            return Err(e);
        }
        Ok(cmd)
    }

    /// Submits each `(queue, commands, wait, signal)` in order, then waits for all of them. A
    /// failed submission still waits for the ones before it, so nothing is freed in flight.
    #[allow(clippy::type_complexity)]
    fn submit_all_and_wait(
        &self,
        submits: &[(&Mutex<vk::Queue>, vk::CommandBuffer, Option<(vk::Semaphore, vk::PipelineStageFlags)>, Option<vk::Semaphore>)],
    ) -> VkResult<()> {
        let d = &self.device;
        let mut fences = Vec::new();
        let mut result = Ok(());
        for (queue, cmd, wait, signal) in submits {
            let fence = match unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.call("vkCreateFence") {
                Ok(f) => f,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            };
            let cmds = [*cmd];
            let (wait_sems, wait_stages) = match wait {
                Some((s, st)) => (vec![*s], vec![*st]),
                None => (vec![], vec![]),
            };
            let signal_sems: Vec<vk::Semaphore> = signal.iter().copied().collect();
            let submit = vk::SubmitInfo::default()
                .command_buffers(&cmds)
                .wait_semaphores(&wait_sems)
                .wait_dst_stage_mask(&wait_stages)
                .signal_semaphores(&signal_sems);
            let q = queue.lock().unwrap_or_else(|e| e.into_inner());
            match unsafe { d.queue_submit(*q, &[submit], fence) }.call("vkQueueSubmit") {
                Ok(()) => fences.push(fence),
                Err(e) => {
                    unsafe { d.destroy_fence(fence, None) };
                    result = Err(e);
                    break;
                }
            }
        }
        if !fences.is_empty() {
            let waited = unsafe { d.wait_for_fences(&fences, true, u64::MAX) }.call("vkWaitForFences");
            if result.is_ok() {
                result = waited;
            }
        }
        for f in fences {
            unsafe { d.destroy_fence(f, None) };
        }
        result
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: every resource holds an `Arc` to this, so none is alive any more; the device is
        // idle after the wait. Order: allocator → pool → device; `instance` drops after this.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_command_pool(*self.command_pool.get_mut().unwrap_or_else(|e| e.into_inner()), None);
            if let Some(p) = self.async_command_pool.as_mut() {
                self.device.destroy_command_pool(*p.get_mut().unwrap_or_else(|e| e.into_inner()), None);
            }
            self.device.destroy_device(None);
        }
    }
}
