//! Graphics pipelines with dynamic rendering (Vulkan 1.3), no vertex-input state (vertex
//! pulling from storage buffers), push-descriptor bindings and one push-constant block.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use super::pipeline::ShaderModule;
use ash::vk;
use std::ffi::CString;

/// What a raster pipeline draws into and how.
pub struct RasterDesc<'a> {
    pub name: &'a str,
    pub vertex_entry: &'a str,
    pub fragment_entry: &'a str,
    /// Storage buffers read by the vertex stage (set 0, bindings `0..n`).
    pub vertex_storage_buffers: u32,
    /// Storage buffers read by the fragment stage (bindings after the vertex stage's).
    pub fragment_storage_buffers: u32,
    /// Combined image samplers read by the fragment stage (bindings after the storage buffers).
    pub fragment_samplers: u32,
    /// Push-constant bytes (fragment stage).
    pub push_constant_bytes: u32,
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    pub depth_compare: vk::CompareOp,
    /// Whether passing fragments write depth (off for a pass over a pre-pass's depth).
    pub depth_write: bool,
}

pub struct GraphicsPipeline {
    ctx: Context,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
}

impl GraphicsPipeline {
    pub fn new(ctx: &Context, module: &ShaderModule, desc: &RasterDesc<'_>) -> VkResult<Self> {
        let d = &ctx.device;
        let mut bindings: Vec<_> = (0..desc.vertex_storage_buffers)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::VERTEX)
            })
            .collect();
        bindings.extend((0..desc.fragment_storage_buffers).map(|b| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(desc.vertex_storage_buffers + b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::FRAGMENT)
        }));
        bindings.extend((0..desc.fragment_samplers).map(|s| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(desc.vertex_storage_buffers + desc.fragment_storage_buffers + s)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::FRAGMENT)
        }));
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        let set_layout = unsafe { d.create_descriptor_set_layout(&set_info, None) }.call("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::FRAGMENT).size(desc.push_constant_bytes)];
        let set_layouts = [set_layout];
        let layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&ranges);
        let layout = match unsafe { d.create_pipeline_layout(&layout_info, None) }.call("vkCreatePipelineLayout") {
            Ok(l) => l,
            Err(e) => {
                unsafe { d.destroy_descriptor_set_layout(set_layout, None) };
                return Err(e);
            }
        };
        let mut this = Self { ctx: ctx.clone(), raw: vk::Pipeline::null(), layout, set_layout };
        let vs = CString::new(desc.vertex_entry).expect("entry names have no NUL");
        let fs = CString::new(desc.fragment_entry).expect("entry names have no NUL");
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(module.raw).name(&vs),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(module.raw).name(&fs),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        // No culling: OBJ scenes (Sponza's foliage, banners) are not reliably closed or wound.
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(desc.depth_write)
            .depth_compare_op(desc.depth_compare);
        let blend: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blend_state = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic_state = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend_state)
            .dynamic_state(&dynamic_state)
            .layout(layout)
            .push_next(&mut rendering);
        this.raw = match unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) } {
            Ok(p) => p[0],
            Err((_, result)) => return Err(VkError::Call { call: "vkCreateGraphicsPipelines", result }),
        };
        ctx.set_name(this.raw, desc.name);
        Ok(this)
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        unsafe {
            if self.raw != vk::Pipeline::null() {
                self.ctx.device.destroy_pipeline(self.raw, None);
            }
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
            self.ctx.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
