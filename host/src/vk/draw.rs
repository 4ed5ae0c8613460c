//! Raster recording on a [`Recorder`]: target transitions, dynamic rendering, indexed draws with
//! push descriptors, and copies of targets into storage buffers — so that passes that rasterise
//! (the G-buffer, Forward+) name targets and bindings, never Vulkan.
//!
//! A frame's raster pass is `transition(target, Undefined → Colour/DepthTarget)` →
//! `begin_rendering` → `draw_indexed`… → `end_rendering` → `transition(→ CopySource)` →
//! `copy_to_buffers`, after which compute kernels and copies see the pixels.
use super::error::{VkError, VkResult};
use super::image::{Image, Sampler};
use super::memory::{barrier, Buffer};
use super::pipeline::Recorder;
use super::raster::GraphicsPipeline;
use ash::vk;
use bytemuck::Pod;

/// What a draw binds at one binding of set 0, in the handle's order: storage buffers (vertex
/// stage, then fragment stage), then sampled textures.
pub enum Binding<'a> {
    Buffer(&'a Buffer),
    Texture(&'a Image, &'a Sampler),
}

/// How a render target starts a raster pass.
#[derive(Clone, Copy, Debug)]
pub enum Load {
    /// Cleared to these words (integer colour targets).
    ClearU32([u32; 4]),
    /// Cleared to these values (normalised colour targets).
    ClearF32([f32; 4]),
    /// Cleared to this depth.
    ClearDepth(f32),
    /// Kept as an earlier pass left it.
    Keep,
}

/// A render target of a raster pass.
pub struct Attachment<'a> {
    pub image: &'a Image,
    pub load: Load,
}

/// What an image is used for between passes; a transition moves it from one use to another
/// with the matching layouts, stages and accesses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageUse {
    /// Contents not needed (the first use in a frame).
    Undefined,
    ColourTarget,
    DepthTarget,
    /// Read by a copy into a buffer.
    CopySource,
    /// Read texel by texel by compute kernels (sampled images, e.g. multisampled targets).
    KernelRead,
}

impl ImageUse {
    fn state(self) -> (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags) {
        match self {
            Self::Undefined => (vk::ImageLayout::UNDEFINED, vk::PipelineStageFlags::TOP_OF_PIPE, vk::AccessFlags::empty()),
            Self::ColourTarget => (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
            Self::DepthTarget => (
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS,
                vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
            Self::CopySource => (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ),
            Self::KernelRead => (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_READ),
        }
    }
}

impl Recorder<'_> {
    /// Moves `image` from use `from` to use `to` (layout transition + memory dependency).
    pub fn transition(&mut self, image: &Image, from: ImageUse, to: ImageUse) {
        let (old, src_stage, src_access) = from.state();
        let (new, dst_stage, dst_access) = to.state();
        image.transition(self.cmd, old, new, src_stage, src_access, dst_stage, dst_access);
    }

    /// Begins dynamic rendering into `colours` and `depth` over their whole extent (viewport and
    /// scissor set to it) with `indices` as the index buffer of the draws.
    pub fn begin_rendering(&mut self, colours: &[Attachment<'_>], depth: Attachment<'_>, indices: &Buffer) {
        self.begin_drawing(colours, depth);
        unsafe { self.ctx.device.cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32) };
    }

    /// As [`Recorder::begin_rendering`] for draws without indices ([`Recorder::draw`]).
    pub fn begin_drawing(&mut self, colours: &[Attachment<'_>], depth: Attachment<'_>) {
        let attachment = |a: &Attachment<'_>, layout: vk::ImageLayout| {
            let (load, clear) = match a.load {
                Load::ClearU32(v) => (vk::AttachmentLoadOp::CLEAR, vk::ClearValue { color: vk::ClearColorValue { uint32: v } }),
                Load::ClearF32(v) => (vk::AttachmentLoadOp::CLEAR, vk::ClearValue { color: vk::ClearColorValue { float32: v } }),
                Load::ClearDepth(d) => (vk::AttachmentLoadOp::CLEAR, vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: d, stencil: 0 } }),
                Load::Keep => (vk::AttachmentLoadOp::LOAD, vk::ClearValue::default()),
            };
            vk::RenderingAttachmentInfo::default()
                .image_view(a.image.view)
                .image_layout(layout)
                .load_op(load)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(clear)
        };
        let colour_infos: Vec<_> = colours.iter().map(|a| attachment(a, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)).collect();
        let depth_info = attachment(&depth, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        let extent = depth.image.extent;
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&colour_infos).depth_attachment(&depth_info);
        let viewport = vk::Viewport { x: 0.0, y: 0.0, width: extent.width as f32, height: extent.height as f32, min_depth: 0.0, max_depth: 1.0 };
        let d = &self.ctx.device;
        unsafe {
            d.cmd_begin_rendering(self.cmd, &info);
            d.cmd_set_viewport(self.cmd, 0, &[viewport]);
            d.cmd_set_scissor(self.cmd, 0, &[area]);
        }
        self.bound_graphics = vk::Pipeline::null();
        self.mark_raster();
    }

    /// Draws `index_count` indices from `first_index` with `pipe`, `bindings` pushed at set 0 (in
    /// the handle's order and kinds) and `params` as the fragment stage's push constants.
    pub fn draw_indexed<P: Pod>(&mut self, pipe: &GraphicsPipeline<P>, bindings: &[Binding<'_>], params: &P, first_index: u32, index_count: u32) -> VkResult<()> {
        self.bind_draw(pipe, bindings, params)?;
        unsafe { self.ctx.device.cmd_draw_indexed(self.cmd, index_count, 1, first_index, 0, 0) };
        Ok(())
    }

    /// Draws vertices `0..vertex_count` without indices (the vertex shader makes each vertex
    /// from its index), as [`Recorder::draw_indexed`] otherwise.
    pub fn draw<P: Pod>(&mut self, pipe: &GraphicsPipeline<P>, bindings: &[Binding<'_>], params: &P, vertex_count: u32) -> VkResult<()> {
        self.bind_draw(pipe, bindings, params)?;
        unsafe { self.ctx.device.cmd_draw(self.cmd, vertex_count, 1, 0, 0) };
        Ok(())
    }

    /// As [`Recorder::draw_indexed`], with the index count, first index and vertex offset a
    /// kernel wrote: the `VkDrawIndexedIndirectCommand` number `draw` of `args` (5 words each).
    pub fn draw_indexed_indirect<P: Pod>(&mut self, pipe: &GraphicsPipeline<P>, bindings: &[Binding<'_>], params: &P, args: &Buffer, draw: u32) -> VkResult<()> {
        const STRIDE: u64 = std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u64;
        if STRIDE * (draw as u64 + 1) > args.size {
            return Err(VkError::Kernel { entry: pipe.kernel.fragment, what: format!("indirect draw {draw} past the end of {}", args.name) });
        }
        self.bind_draw(pipe, bindings, params)?;
        unsafe { self.ctx.device.cmd_draw_indexed_indirect(self.cmd, args.raw, STRIDE * draw as u64, 1, STRIDE as u32) };
        Ok(())
    }

    /// As [`Recorder::draw`], with the vertex count a kernel wrote: the `VkDrawIndirectCommand`
    /// at the start of `args` (4 words).
    pub fn draw_indirect<P: Pod>(&mut self, pipe: &GraphicsPipeline<P>, bindings: &[Binding<'_>], params: &P, args: &Buffer) -> VkResult<()> {
        const SIZE: u64 = std::mem::size_of::<vk::DrawIndirectCommand>() as u64;
        if SIZE > args.size {
            return Err(VkError::Kernel { entry: pipe.kernel.fragment, what: format!("indirect draw arguments past the end of {}", args.name) });
        }
        self.bind_draw(pipe, bindings, params)?;
        unsafe { self.ctx.device.cmd_draw_indirect(self.cmd, args.raw, 0, 1, SIZE as u32) };
        Ok(())
    }

    /// Binds `pipe` (if not bound), pushes `bindings` at set 0 and `params` for a draw.
    fn bind_draw<P: Pod>(&mut self, pipe: &GraphicsPipeline<P>, bindings: &[Binding<'_>], params: &P) -> VkResult<()> {
        let k = &pipe.kernel;
        let buffers = k.vertex_storage_buffers + k.fragment_storage_buffers;
        let kinds_match = bindings.len() == k.bindings() as usize
            && bindings.iter().enumerate().all(|(i, b)| matches!(b, Binding::Buffer(_)) == ((i as u32) < buffers));
        if !kinds_match {
            return Err(VkError::Kernel {
                entry: k.fragment,
                what: format!("binds {buffers} storage buffers then {} textures; {} bindings given", k.fragment_samplers, bindings.len()),
            });
        }
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .filter_map(|b| match b {
                Binding::Buffer(buf) => Some([vk::DescriptorBufferInfo::default().buffer(buf.raw).range(vk::WHOLE_SIZE)]),
                Binding::Texture(..) => None,
            })
            .collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
            .iter()
            .filter_map(|b| match b {
                Binding::Texture(img, sampler) => Some([vk::DescriptorImageInfo::default()
                    .sampler(sampler.raw)
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]),
                Binding::Buffer(_) => None,
            })
            .collect();
        let mut writes: Vec<_> = buffer_infos
            .iter()
            .enumerate()
            .map(|(i, info)| vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(vk::DescriptorType::STORAGE_BUFFER).buffer_info(info))
            .collect();
        writes.extend(image_infos.iter().enumerate().map(|(s, info)| {
            vk::WriteDescriptorSet::default()
                .dst_binding(buffers + s as u32)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(info)
        }));
        let d = &self.ctx.device;
        unsafe {
            if self.bound_graphics != pipe.raw {
                d.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::GRAPHICS, pipe.raw);
                self.bound_graphics = pipe.raw;
            }
            self.ctx.push_descriptor.cmd_push_descriptor_set(self.cmd, vk::PipelineBindPoint::GRAPHICS, pipe.layout, 0, &writes);
            d.cmd_push_constants(self.cmd, pipe.layout, super::raster::PUSH_CONSTANT_STAGES, 0, bytemuck::bytes_of(params));
        }
        Ok(())
    }

    /// Makes the storage-buffer writes of earlier fragment shaders visible to later kernels,
    /// copies and host reads (the transparent pass's lists and counters).
    pub fn kernels_read_fragment_writes(&mut self) {
        barrier(self.ctx, self.cmd, vk::AccessFlags::SHADER_WRITE, vk::PipelineStageFlags::FRAGMENT_SHADER);
    }

    /// Makes earlier kernels' storage-buffer writes visible to the vertex stage of later raster
    /// passes: as index-buffer reads and as storage-buffer reads of vertex shaders (geometry that
    /// kernels wrote, e.g. tessellated NURBS grids).
    pub fn draws_read_kernel_writes(&mut self) {
        let b = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE)
            .dst_access_mask(vk::AccessFlags::INDEX_READ | vk::AccessFlags::SHADER_READ);
        unsafe {
            self.ctx.device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::PipelineStageFlags::VERTEX_INPUT | vk::PipelineStageFlags::VERTEX_SHADER,
                vk::DependencyFlags::empty(),
                &[b],
                &[],
                &[],
            )
        };
    }

    /// Ends the raster pass begun by [`Recorder::begin_rendering`].
    pub fn end_rendering(&mut self) {
        unsafe { self.ctx.device.cmd_end_rendering(self.cmd) };
        self.bound_graphics = vk::Pipeline::null();
    }

    /// Copies each image (in use [`ImageUse::CopySource`]) into its buffer, one texel after the
    /// other, and makes the copies visible to later kernels and copies.
    pub fn copy_to_buffers(&mut self, pairs: &[(&Image, &Buffer)]) {
        for (img, buf) in pairs {
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(img.aspect()).layer_count(1))
                .image_extent(vk::Extent3D { width: img.extent.width, height: img.extent.height, depth: 1 });
            unsafe { self.ctx.device.cmd_copy_image_to_buffer(self.cmd, img.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buf.raw, &[region]) };
        }
        barrier(self.ctx, self.cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
    }

    /// Makes earlier kernel writes and buffer fills/copies visible to the fragment shaders of
    /// later raster passes (e.g. light lists read per fragment, page tables and counters the
    /// transparent pass writes to).
    pub fn fragments_read_earlier_writes(&mut self) {
        let b = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE);
        unsafe {
            self.ctx.device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::DependencyFlags::empty(),
                &[b],
                &[],
                &[],
            )
        };
    }
}
