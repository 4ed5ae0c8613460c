//! The GPU as the algorithms see it: a Vulkan context plus one typed pipeline per kernel of the
//! compute module that `build.rs` compiled from `shader-crate` (embedded in the binary).
use crate::vk::{ComputePipeline, Context, ContextOptions, Profiler, Recorder, ShaderModule, VkResult};
use shaders::kernels;
use shaders::layout::*;

/// The compute SPIR-V module (rust-gpu output), embedded at build time.
pub const COMPUTE_SPV: &[u8] = include_bytes!(env!("MANYLIGHTS_COMPUTE_SPV"));

/// Pipelines of every compute kernel.
pub struct Kernels {
    pub octa_roundtrip: ComputePipeline<OctaParams>,
    pub cluster_keys: ComputePipeline<ClusterKeyParams>,
    pub morton_codes: ComputePipeline<MortonParams>,
    pub workgroup_scan: ComputePipeline<ScanParams>,
    pub debug_view: ComputePipeline<DebugViewParams>,
}

impl Kernels {
    pub fn new(ctx: &Context) -> VkResult<Self> {
        let module = ShaderModule::new(ctx, "manylights compute kernels", COMPUTE_SPV)?;
        Ok(Self {
            octa_roundtrip: ComputePipeline::new(ctx, &module, kernels::OCTA_ROUNDTRIP)?,
            cluster_keys: ComputePipeline::new(ctx, &module, kernels::CLUSTER_KEYS)?,
            morton_codes: ComputePipeline::new(ctx, &module, kernels::MORTON_CODES)?,
            workgroup_scan: ComputePipeline::new(ctx, &module, kernels::WORKGROUP_SCAN)?,
            debug_view: ComputePipeline::new(ctx, &module, kernels::DEBUG_VIEW)?,
        })
    }
}

pub struct Gpu {
    pub kernels: Kernels,
    pub ctx: Context,
}

impl Gpu {
    pub fn new(opts: &ContextOptions) -> VkResult<Self> {
        let ctx = Context::new(opts)?;
        let kernels = Kernels::new(&ctx)?;
        Ok(Self { kernels, ctx })
    }

    /// Records with `f`, submits, waits. With a profiler, its passes are timed.
    pub fn run<R>(&self, profiler: Option<&mut Profiler>, f: impl FnOnce(&mut Recorder<'_>) -> VkResult<R>) -> VkResult<R> {
        self.ctx.submit_and_wait(|cmd| {
            let mut profiler = profiler;
            if let Some(p) = profiler.as_deref_mut() {
                p.reset(cmd);
            }
            let mut rec = Recorder { ctx: &self.ctx, cmd, profiler };
            f(&mut rec)
        })
    }
}
