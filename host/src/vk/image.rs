//! RAII 2D images (G-buffer targets, frames) with a view, and layout transitions.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;


pub struct Image {
    ctx: Context,
    pub raw: vk::Image,
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// Samples per pixel (1 but for multisampled targets).
    pub samples: u32,
    pub name: String,
}

impl Image {
    /// A render target of `format` (drawn into, then copied out).
    pub fn target(ctx: &Context, name: &str, width: u32, height: u32, format: super::raster::TargetFormat) -> VkResult<Self> {
        let usage = if format.is_depth() { vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT } else { vk::ImageUsageFlags::COLOR_ATTACHMENT };
        Self::new_2d(ctx, name, width, height, format.raw(), usage | vk::ImageUsageFlags::TRANSFER_SRC)
    }

    /// A render target of `format` with `samples` samples per pixel (a count the device supports
    /// for it), drawn into, then read sample by sample by kernels (`ImageUse::KernelRead`).
    pub fn multisampled_target(ctx: &Context, name: &str, width: u32, height: u32, format: super::raster::TargetFormat, samples: u32) -> VkResult<Self> {
        let usage = if format.is_depth() { vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT } else { vk::ImageUsageFlags::COLOR_ATTACHMENT };
        Self::with_samples(ctx, name, width, height, format.raw(), usage | vk::ImageUsageFlags::SAMPLED, samples)
    }

    /// A device-local, optimally tiled 2D image with one mip level and a colour or depth view.
    pub fn new_2d(ctx: &Context, name: &str, width: u32, height: u32, format: vk::Format, usage: vk::ImageUsageFlags) -> VkResult<Self> {
        Self::with_samples(ctx, name, width, height, format, usage, 1)
    }

    fn with_samples(ctx: &Context, name: &str, width: u32, height: u32, format: vk::Format, usage: vk::ImageUsageFlags, samples: u32) -> VkResult<Self> {
        let sample_flags = vk::SampleCountFlags::from_raw(samples);
        if !samples.is_power_of_two() || samples > 64 {
            return Err(VkError::InvalidImage { name: name.into(), what: format!("{samples} samples per pixel (a power of two up to 64)") });
        }
        let limit = unsafe { ctx.instance.raw.get_physical_device_properties(ctx.physical) }.limits.max_image_dimension2_d;
        if width == 0 || height == 0 || width > limit || height > limit {
            return Err(VkError::InvalidImage { name: name.into(), what: format!("size {width}x{height} outside 1..={limit}") });
        }
        let d = &ctx.device;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width, height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(sample_flags)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { d.create_image(&info, None) }.call("vkCreateImage")?;
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let allocated = ctx.allocator.lock().unwrap_or_else(|e| e.into_inner()).allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(source) => {
                unsafe { d.destroy_image(raw, None) };
                return Err(VkError::Alloc { name: name.into(), bytes: requirements.size, source });
            }
        };
        let mut this = Self {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            format,
            extent: vk::Extent2D { width, height },
            samples,
            name: name.into(),
        };
        let a = this.allocation.as_ref().expect("just allocated");
        unsafe { d.bind_image_memory(raw, a.memory(), a.offset()) }.call("vkBindImageMemory")?;
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(this.range());
        this.view = unsafe { d.create_image_view(&view_info, None) }.call("vkCreateImageView")?;
        ctx.set_name(raw, name);
        ctx.set_name(this.view, name);
        Ok(this)
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }

    /// The whole image as a subresource range.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default().aspect_mask(self.aspect()).level_count(1).layer_count(1)
    }

    /// Records a layout transition with a full memory dependency between the given stages.
    #[allow(clippy::too_many_arguments)]
    pub fn transition(
        &self,
        cmd: vk::CommandBuffer,
        old: vk::ImageLayout,
        new: vk::ImageLayout,
        src_stage: vk::PipelineStageFlags,
        src_access: vk::AccessFlags,
        dst_stage: vk::PipelineStageFlags,
        dst_access: vk::AccessFlags,
    ) {
        let b = vk::ImageMemoryBarrier::default()
            .old_layout(old)
            .new_layout(new)
            .src_access_mask(src_access)
            .dst_access_mask(dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(self.raw)
            .subresource_range(self.range());
        unsafe { self.ctx.device.cmd_pipeline_barrier(cmd, src_stage, dst_stage, vk::DependencyFlags::empty(), &[], &[], &[b]) };
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            if self.view != vk::ImageView::null() {
                self.ctx.device.destroy_image_view(self.view, None);
            }
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(a);
        }
        unsafe { self.ctx.device.destroy_image(self.raw, None) };
    }
}

/// A linear, repeating sampler (RAII).
pub struct Sampler {
    ctx: Context,
    pub raw: vk::Sampler,
}

impl Sampler {
    pub fn linear_repeat(ctx: &Context) -> VkResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::REPEAT)
            .max_lod(0.0);
        let raw = unsafe { ctx.device.create_sampler(&info, None) }.call("vkCreateSampler")?;
        Ok(Self { ctx: ctx.clone(), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}

/// Uploads tightly packed RGBA8 texels into a new sampled image, left in
/// `SHADER_READ_ONLY_OPTIMAL` for fragment shaders.
/// sRGB colour data (`srgb`) is decoded to linear when sampled; masks and linear data are not.
pub fn upload_rgba8(ctx: &Context, name: &str, width: u32, height: u32, srgb: bool, texels: &[u8]) -> VkResult<Image> {
    let format = if srgb { vk::Format::R8G8B8A8_SRGB } else { vk::Format::R8G8B8A8_UNORM };
    if texels.len() as u64 != 4 * width as u64 * height as u64 {
        return Err(VkError::InvalidImage { name: name.into(), what: format!("{} bytes for {width}x{height} RGBA8", texels.len()) });
    }
    let img = Image::new_2d(ctx, name, width, height, format, vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)?;
    let mut staging = super::memory::Buffer::new(
        ctx,
        &format!("{name} (upload)"),
        texels.len() as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
    )?;
    staging.write(texels)?;
    ctx.submit_and_wait(|cmd| {
        img.transition(
            cmd,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::AccessFlags::empty(),
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
        );
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1))
            .image_extent(vk::Extent3D { width, height, depth: 1 });
        unsafe { ctx.device.cmd_copy_buffer_to_image(cmd, staging.raw, img.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region]) };
        img.transition(
            cmd,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            vk::PipelineStageFlags::TRANSFER,
            vk::AccessFlags::TRANSFER_WRITE,
            vk::PipelineStageFlags::FRAGMENT_SHADER,
            vk::AccessFlags::SHADER_READ,
        );
        Ok(())
    })?;
    Ok(img)
}
