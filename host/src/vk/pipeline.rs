//! Shader modules, typed compute pipelines and the command recorder that dispatches them.
//!
//! Bindings use `VK_KHR_push_descriptor`: each dispatch pushes its storage buffers (set 0,
//! bindings `0..n` in the order of the kernel handle), so no descriptor pools or sets are managed.
//! Every dispatch is followed by a compute→compute/transfer memory barrier ([`dispatch_barrier`]):
//! passes are serialised, which keeps synchronization validation clean (passes that could overlap
//! will opt out later). The validation layer does not see buffers bound with push descriptors, so
//! it cannot check these dispatches itself; `tests/validation.rs` shows, with descriptor sets it
//! does see, that it reports two unordered dispatches and that this barrier orders them.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use super::image::Image;
use super::memory::{barrier, Buffer};
use super::profiler::Profiler;
use ash::vk;
use bytemuck::Pod;
use shaders::kernels::Kernel;
use std::ffi::CString;

pub struct ShaderModule {
    pub(crate) ctx: Context,
    pub raw: vk::ShaderModule,
}

impl ShaderModule {
    /// A module of `spirv` with its specialization constant `spec_id` frozen to the constant
    /// `value` ([`freeze_spec_constant`]): what a pipeline specialised to `value` compiles, with
    /// no specialization constant left in the module.
    pub fn frozen(ctx: &Context, name: &str, spirv: &[u8], spec_id: u32, value: u32) -> VkResult<Self> {
        Self::from_words(ctx, name, &freeze_spec_constant(&Self::words(name, spirv)?, spec_id, value))
    }

    fn words(name: &str, spirv: &[u8]) -> VkResult<Vec<u32>> {
        ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| VkError::Kernel { entry: "<module>", what: format!("{name}: invalid SPIR-V: {e}") })
    }

    fn from_words(ctx: &Context, name: &str, words: &[u32]) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(words);
        let raw = unsafe { ctx.device.create_shader_module(&info, None) }.call("vkCreateShaderModule")?;
        ctx.set_name(raw, name);
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

/// `OpDecorate`, `OpConstant`, `OpSpecConstant` and the `SpecId` decoration (SPIR-V 1.6 §3).
const OP_DECORATE: u32 = 71;
const OP_CONSTANT: u32 = 43;
const OP_SPEC_CONSTANT: u32 = 50;
const DECORATION_SPEC_ID: u32 = 1;

/// `words` (a SPIR-V module) with the 32-bit specialization constant whose `SpecId` is `spec_id`
/// turned into the plain constant `value`: its `OpSpecConstant` becomes an `OpConstant` of the
/// same type and id, its `SpecId` decoration is dropped. Every instruction keeps its word count,
/// so the module stays valid. Why not a `VkSpecializationInfo`: the validation layer re-runs the
/// optimizer and validator over the whole module for every pipeline created from a module that
/// declares specialization constants (about 1.5 s per pipeline on lavapipe for these modules,
/// a minute for a device's pipelines); frozen modules have none, and the driver folds the
/// constant all the same.
pub fn freeze_spec_constant(words: &[u32], spec_id: u32, value: u32) -> Vec<u32> {
    const HEADER: usize = 5;
    let instructions = |w: &[u32]| {
        let mut at = HEADER;
        let mut out = Vec::new();
        while at < w.len() {
            let count = (w[at] >> 16).max(1) as usize;
            out.push(at..(at + count).min(w.len()));
            at += count;
        }
        out
    };
    let instructions = instructions(words);
    let spec_target = instructions.iter().find_map(|r| {
        let i = &words[r.clone()];
        if i.len() == 4 && i[0] & 0xffff == OP_DECORATE && i[2] == DECORATION_SPEC_ID && i[3] == spec_id {
            Some(i[1])
        } else {
            None
        }
    });
    let Some(target) = spec_target else { return words.to_vec() };
    let mut out = words[..HEADER.min(words.len())].to_vec();
    for r in instructions {
        let i = &words[r];
        let op = i[0] & 0xffff;
        if op == OP_DECORATE && i.len() == 4 && i[1] == target && i[2] == DECORATION_SPEC_ID {
            continue;
        }
        if op == OP_SPEC_CONSTANT && i.len() == 4 && i[2] == target {
            out.extend([(4 << 16) | OP_CONSTANT, i[1], i[2], value]);
            continue;
        }
        out.extend_from_slice(i);
    }
    out
}

impl Drop for ShaderModule {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}

/// A compute pipeline for kernel handle `Kernel<P>`: dispatching it takes a `&P`.
pub struct ComputePipeline<P> {
    ctx: Context,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub kernel: Kernel<P>,
}

impl<P: Pod> ComputePipeline<P> {
    pub fn new(ctx: &Context, module: &ShaderModule, kernel: Kernel<P>) -> VkResult<Self> {
        let d = &ctx.device;
        let (buffers, images) = (kernel.storage_buffers, kernel.sampled_images);
        let bindings: Vec<_> = (0..buffers + images)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(if b < buffers { vk::DescriptorType::STORAGE_BUFFER } else { vk::DescriptorType::SAMPLED_IMAGE })
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        let set_layout = unsafe { d.create_descriptor_set_layout(&set_info, None) }.call("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<P>() as u32)];
        let set_layouts = [set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if std::mem::size_of::<P>() > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        let layout = match unsafe { d.create_pipeline_layout(&layout_info, None) }.call("vkCreatePipelineLayout") {
            Ok(l) => l,
            Err(e) => {
                unsafe { d.destroy_descriptor_set_layout(set_layout, None) };
                return Err(e);
            }
        };
        let entry = CString::new(kernel.entry).expect("entry names have no NUL");
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(&entry);
        let full = kernel.cooperative
            && ctx.info.full_subgroups
            && kernel.workgroup_size[0].is_multiple_of(ctx.info.max_subgroup_size);
        if full {
            stage = stage.flags(vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS);
        }
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
        let raw = match unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) } {
            Ok(p) => p[0],
            Err((_, result)) => {
                unsafe {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                }
                // Name the kernel: a driver's compiler may refuse one entry of a module.
                return Err(VkError::Kernel { entry: kernel.entry, what: format!("vkCreateComputePipelines failed: {result}") });
            }
        };
        ctx.set_name(raw, kernel.entry);
        super::kernel_stats::capture(ctx, info, kernel.entry);
        Ok(Self { ctx: ctx.clone(), raw, layout, set_layout, kernel })
    }
}

impl<P> Drop for ComputePipeline<P> {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_pipeline(self.raw, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
            self.ctx.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

pub use shaders::indirect::{fold, MAX_GROUPS_PER_AXIS};

/// The barrier [`Recorder::dispatch`] records after every dispatch: the dispatch's shader writes
/// become visible to later compute shaders and copies, which wait for it.
pub fn dispatch_barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    barrier(ctx, cmd, vk::AccessFlags::SHADER_WRITE, vk::PipelineStageFlags::COMPUTE_SHADER);
}

/// Records dispatches, raster passes (`draw.rs`) and profiler scopes into one command buffer.
pub struct Recorder<'a> {
    pub ctx: &'a Context,
    pub(crate) cmd: vk::CommandBuffer,
    profiler: Option<&'a mut Profiler>,
    /// The graphics pipeline bound last inside the current raster pass (null outside one).
    pub(crate) bound_graphics: vk::Pipeline,
}

impl<'a> Recorder<'a> {
    /// A recorder over `cmd`; resets the profiler's queries first.
    pub(crate) fn new(ctx: &'a Context, cmd: vk::CommandBuffer, mut profiler: Option<&'a mut Profiler>) -> Self {
        if let Some(p) = profiler.as_deref_mut() {
            p.reset(cmd);
        }
        Self { ctx, cmd, profiler, bound_graphics: vk::Pipeline::null() }
    }

    /// A recorder over `cmd` that goes on timing into `profiler` where an earlier command buffer
    /// of the same queue left it (no reset: both command buffers' passes are one frame's).
    pub(crate) fn continuing(ctx: &'a Context, cmd: vk::CommandBuffer, profiler: Option<&'a mut Profiler>) -> Self {
        Self { ctx, cmd, profiler, bound_graphics: vk::Pipeline::null() }
    }
}

impl Recorder<'_> {
    /// Dispatches `groups` workgroups of `pipe` with `buffers` at bindings `0..n` and `params`
    /// as push constants, then a barrier.
    pub fn dispatch<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, groups: [u32; 3]) -> VkResult<()> {
        let limit = MAX_GROUPS_PER_AXIS;
        if groups.iter().any(|&g| g > limit) {
            return Err(VkError::Kernel { entry: pipe.kernel.entry, what: format!("dispatch of {groups:?} workgroups exceeds {limit} per axis") });
        }
        if groups.contains(&0) {
            return self.check_bindings(pipe, buffers, &[]);
        }
        self.bind(pipe, buffers, &[], params)?;
        let part = self.begin_part(pipe.kernel.entry);
        unsafe { self.ctx.device.cmd_dispatch(self.cmd, groups[0], groups[1], groups[2]) };
        dispatch_barrier(self.ctx, self.cmd);
        self.end_part(part);
        Ok(())
    }

    /// Dispatches `pipe` with the workgroup counts a kernel wrote at word `offset` of `args`
    /// (`shaders::indirect::dispatch_args`), then a barrier.
    pub fn dispatch_indirect<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, args: &Buffer, offset: u32) -> VkResult<()> {
        if 4 * (offset as u64 + 3) > args.size {
            return Err(VkError::Kernel { entry: pipe.kernel.entry, what: format!("indirect arguments at word {offset} past the end of {}", args.name) });
        }
        self.bind(pipe, buffers, &[], params)?;
        let part = self.begin_part(pipe.kernel.entry);
        unsafe { self.ctx.device.cmd_dispatch_indirect(self.cmd, args.raw, 4 * offset as u64) };
        dispatch_barrier(self.ctx, self.cmd);
        self.end_part(part);
        Ok(())
    }

    /// Items of a subgroup-per-item kernel each workgroup covers ([`Recorder::dispatch_subgroups`]).
    pub fn subgroup_items_per_group<P>(&self, pipe: &ComputePipeline<P>) -> u32 {
        (pipe.kernel.invocations() / self.ctx.info.max_subgroup_size.max(1)).max(1)
    }

    fn check_bindings<P>(&self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], images: &[&Image]) -> VkResult<()> {
        let k = &pipe.kernel;
        if buffers.len() != k.storage_buffers as usize || images.len() != k.sampled_images as usize {
            return Err(VkError::Kernel {
                entry: k.entry,
                what: format!("binds {} storage buffers and {} sampled images, {} and {} given", k.storage_buffers, k.sampled_images, buffers.len(), images.len()),
            });
        }
        Ok(())
    }

    /// A linear dispatch over `n` elements ([`Recorder::dispatch_linear`]) of a kernel that also
    /// reads `images` (in use `ImageUse::KernelRead`) as sampled images after its buffers.
    pub fn dispatch_linear_reading<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], images: &[&Image], params: &P, n: u32) -> VkResult<()> {
        let groups = fold(n.div_ceil(pipe.kernel.invocations()));
        if groups.contains(&0) {
            return self.check_bindings(pipe, buffers, images);
        }
        self.bind(pipe, buffers, images, params)?;
        let part = self.begin_part(pipe.kernel.entry);
        unsafe { self.ctx.device.cmd_dispatch(self.cmd, groups[0], groups[1], groups[2]) };
        dispatch_barrier(self.ctx, self.cmd);
        self.end_part(part);
        Ok(())
    }

    /// Binds `pipe`, pushes `buffers` at bindings `0..n` and `params` as push constants.
    fn bind<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], images: &[&Image], params: &P) -> VkResult<()> {
        self.check_bindings(pipe, buffers, images)?;
        let d = &self.ctx.device;
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            buffers.iter().map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)]).collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> =
            images.iter().map(|i| [vk::DescriptorImageInfo::default().image_view(i.view).image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]).collect();
        let mut writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        writes.extend(image_infos.iter().enumerate().map(|(i, info)| {
            vk::WriteDescriptorSet::default()
                .dst_binding((buffers.len() + i) as u32)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(info)
        }));
        unsafe {
            d.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, pipe.raw);
            if !writes.is_empty() {
                self.ctx.push_descriptor.cmd_push_descriptor_set(self.cmd, vk::PipelineBindPoint::COMPUTE, pipe.layout, 0, &writes);
            }
            if std::mem::size_of::<P>() > 0 {
                d.cmd_push_constants(self.cmd, pipe.layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(params));
            }
        }
        Ok(())
    }

    /// Dispatches enough workgroups to cover `invocations` (x, y, z) threads.
    pub fn dispatch_threads<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, invocations: [u32; 3]) -> VkResult<()> {
        let wg = pipe.kernel.workgroup_size;
        let groups = [0, 1, 2].map(|a| invocations[a].div_ceil(wg[a]));
        self.dispatch(pipe, buffers, params, groups)
    }

    /// Dispatches a linear kernel over `n` elements: `ceil(n / workgroup)` workgroups folded into a
    /// 2D grid (the kernel linearises `wg.y · num_wg.x + wg.x`).
    pub fn dispatch_linear<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, n: u32) -> VkResult<()> {
        let groups = n.div_ceil(pipe.kernel.invocations());
        self.dispatch(pipe, buffers, params, fold(groups))
    }

    /// Dispatches a kernel over a `width × height` frame in blocks of
    /// `shaders::shading::BLOCK_WIDTH × BLOCK_HEIGHT` pixels (`shaders::shading::block_pixel`).
    pub fn dispatch_blocks<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, width: u32, height: u32) -> VkResult<()> {
        use shaders::shading::{BLOCK_HEIGHT, BLOCK_WIDTH};
        debug_assert_eq!(BLOCK_WIDTH * BLOCK_HEIGHT, pipe.kernel.invocations(), "{}: a block per workgroup", pipe.kernel.entry);
        self.dispatch(pipe, buffers, params, [width.div_ceil(BLOCK_WIDTH), height.div_ceil(BLOCK_HEIGHT), 1])
    }

    /// Dispatches a kernel that gives each of `items` its own subgroup (item = workgroup index ·
    /// subgroups per workgroup + subgroup id): enough workgroups for the device's *largest*
    /// subgroup width (fewest subgroups per workgroup), so every item is covered whatever width
    /// the driver picks; surplus subgroups find no item and return.
    pub fn dispatch_subgroups<P: Pod>(&mut self, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, items: u32) -> VkResult<()> {
        let per_group = self.subgroup_items_per_group(pipe);
        self.dispatch(pipe, buffers, params, fold(items.div_ceil(per_group)))
    }

    /// Fills the first `bytes` of a buffer with a repeated `u32` and makes it visible to kernels.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) {
        let part = self.begin_part("fill");
        unsafe { self.ctx.device.cmd_fill_buffer(self.cmd, buffer.raw, 0, buffer.size, value) };
        barrier(self.ctx, self.cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
        self.end_part(part);
    }

    /// Copies the first `bytes` of `src` into `dst` and makes them visible to kernels and copies.
    pub fn copy(&mut self, src: &Buffer, dst: &Buffer, bytes: u64) -> VkResult<()> {
        if bytes > src.size.min(dst.size) {
            let (name, have) = if src.size < dst.size { (&src.name, src.size) } else { (&dst.name, dst.size) };
            return Err(VkError::BufferTooSmall { name: name.clone(), have, need: bytes });
        }
        if bytes > 0 {
            let region = vk::BufferCopy::default().size(bytes);
            let part = self.begin_part("copy");
            unsafe { self.ctx.device.cmd_copy_buffer(self.cmd, src.raw, dst.raw, &[region]) };
            barrier(self.ctx, self.cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
            self.end_part(part);
        }
        Ok(())
    }

    /// Notes (for the profiler) that the pass being recorded does raster work.
    pub(crate) fn mark_raster(&mut self) {
        if let Some(p) = self.profiler.as_mut() {
            p.mark_raster();
        }
    }

    /// Starts timing one command as a part of the open pass (profilers that time parts).
    fn begin_part(&mut self, command: &str) -> Option<u32> {
        let cmd = self.cmd;
        self.profiler.as_mut().and_then(|p| p.begin_part(cmd, command))
    }

    fn end_part(&mut self, part: Option<u32>) {
        let cmd = self.cmd;
        if let Some(p) = self.profiler.as_mut() {
            p.end_part(cmd, part);
        }
    }

    /// Runs `f` inside a named GPU-timed pass (when a profiler is attached).
    pub fn pass<R>(&mut self, name: &str, f: impl FnOnce(&mut Self) -> VkResult<R>) -> VkResult<R> {
        let cmd = self.cmd;
        let scope = self.profiler.as_mut().map(|p| p.begin(cmd, name));
        let r = f(self)?;
        if let (Some(p), Some(s)) = (self.profiler.as_mut(), scope) {
            p.end(cmd, s);
        }
        Ok(r)
    }
}

#[cfg(test)]
mod freeze_tests {
    use super::*;

    #[test]
    fn the_spec_constant_becomes_a_constant_and_its_decoration_goes() {
        let header = [0x0723_0203, 0x0001_0600, 0, 10, 0];
        let decorate = [(4 << 16) | OP_DECORATE, 7, DECORATION_SPEC_ID, 0];
        let other = [(4 << 16) | OP_DECORATE, 8, DECORATION_SPEC_ID, 3];
        let spec = [(4 << 16) | OP_SPEC_CONSTANT, 2, 7, 0];
        let spec3 = [(4 << 16) | OP_SPEC_CONSTANT, 2, 8, 5];
        let nop = [1 << 16]; // OpNop
        let module: Vec<u32> = [&header[..], &decorate, &other, &nop, &spec, &spec3].concat();
        let frozen = freeze_spec_constant(&module, 0, 0x1c0);
        let want: Vec<u32> = [&header[..], &other, &nop, &[(4 << 16) | OP_CONSTANT, 2, 7, 0x1c0], &spec3].concat();
        assert_eq!(frozen, want);
        assert_eq!(freeze_spec_constant(&module, 9, 1), module, "no such spec id: unchanged");
    }
}
