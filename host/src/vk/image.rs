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
    pub name: String,
}

impl Image {
    /// A device-local, optimally tiled 2D image with one mip level and a colour or depth view.
    pub fn new_2d(ctx: &Context, name: &str, width: u32, height: u32, format: vk::Format, usage: vk::ImageUsageFlags) -> VkResult<Self> {
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
            .samples(vk::SampleCountFlags::TYPE_1)
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
