//! Graphics pipelines with dynamic rendering (Vulkan 1.3), no vertex-input state (vertex
//! pulling from storage buffers), push-descriptor bindings and one push-constant block; typed by
//! the raster handle (`shaders::kernels::RasterKernel<P>`) they are made from, as compute
//! pipelines are by their `Kernel<P>`.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use super::pipeline::ShaderModule;
use ash::vk;
use shaders::kernels::RasterKernel;
use std::ffi::CString;

/// The stages a raster pipeline's push constants reach (a vertex stage may read them, as the
/// shadow maps' draw does for its render area).
pub const PUSH_CONSTANT_STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(vk::ShaderStageFlags::VERTEX.as_raw() | vk::ShaderStageFlags::FRAGMENT.as_raw());

/// Formats of render targets, named by what the renderer stores in them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetFormat {
    /// One 32-bit word per pixel (octahedral normals, packed RGBA8 frames, draw indices).
    R32Uint,
    /// Four 32-bit words per pixel (float32 normals).
    Rgba32Uint,
    /// Linear RGBA8 (albedo).
    Rgba8Unorm,
    /// 32-bit float depth (reversed Z).
    Depth32,
    /// Four 32-bit floats (weighted blended OIT's accumulation).
    Rgba32Float,
    /// One 32-bit float (weighted blended OIT's revealage).
    R32Float,
    /// Two 32-bit floats (Forward+'s winning triangles with MSAA).
    Rg32Float,
}

impl TargetFormat {
    pub(crate) fn raw(self) -> vk::Format {
        match self {
            Self::R32Uint => vk::Format::R32_UINT,
            Self::Rgba32Uint => vk::Format::R32G32B32A32_UINT,
            Self::Rgba8Unorm => vk::Format::R8G8B8A8_UNORM,
            Self::Depth32 => vk::Format::D32_SFLOAT,
            Self::Rgba32Float => vk::Format::R32G32B32A32_SFLOAT,
            Self::R32Float => vk::Format::R32_SFLOAT,
            Self::Rg32Float => vk::Format::R32G32_SFLOAT,
        }
    }

    pub fn is_depth(self) -> bool {
        self == Self::Depth32
    }

    /// Bytes per pixel.
    pub fn bytes(self) -> u64 {
        match self {
            Self::Rgba32Uint | Self::Rgba32Float => 16,
            Self::Rg32Float => 8,
            _ => 4,
        }
    }
}

/// The depth test of a raster pipeline (reversed Z: nearer is greater).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// Keep the nearest fragment and write its depth.
    NearestWrites,
    /// Pass fragments at exactly the stored depth (a pass over a pre-pass's depth); no writes.
    EqualReadOnly,
    /// Pass fragments nearer than the stored depth (transparent surfaces in front of the opaque
    /// ones); no writes.
    NearerReadOnly,
    /// Every fragment passes; no writes (draws of something other than surfaces, e.g. light
    /// bounds into a one-pixel-per-tile target).
    Off,
}

/// How a colour target combines a fragment's output with what it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// The output replaces it.
    Replace,
    /// Added to it (`ONE, ONE`): weighted blended OIT's accumulation.
    Add,
    /// It is multiplied by one minus the output (`ZERO, ONE_MINUS_SRC_COLOR`): the revealage.
    Revealage,
}

/// A raster pipeline for handle `RasterKernel<P>`: drawing with it takes a `&P`.
pub struct GraphicsPipeline<P> {
    ctx: Context,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub kernel: RasterKernel<P>,
}

impl<P> GraphicsPipeline<P> {
    /// A pipeline drawing `kernel` into colour targets of `colours` and a depth target.
    pub fn new(ctx: &Context, module: &ShaderModule, name: &str, kernel: RasterKernel<P>, colours: &[TargetFormat], depth: DepthTest) -> VkResult<Self> {
        let replace: Vec<(TargetFormat, Blend)> = colours.iter().map(|&c| (c, Blend::Replace)).collect();
        Self::blended(ctx, module, name, kernel, &replace, depth)
    }

    /// A pipeline drawing `kernel` into colour targets of the given formats and blending, and a
    /// depth target.
    pub fn blended(ctx: &Context, module: &ShaderModule, name: &str, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest) -> VkResult<Self> {
        Self::with_samples(ctx, module, name, kernel, colours, depth, 1)
    }

    /// [`GraphicsPipeline::new`] for targets of `samples` samples per pixel (the fragment shader
    /// runs once per pixel and primitive; depth is tested per sample).
    pub fn multisampled(ctx: &Context, module: &ShaderModule, name: &str, kernel: RasterKernel<P>, colours: &[TargetFormat], depth: DepthTest, samples: u32) -> VkResult<Self> {
        let replace: Vec<(TargetFormat, Blend)> = colours.iter().map(|&c| (c, Blend::Replace)).collect();
        Self::with_samples(ctx, module, name, kernel, &replace, depth, samples)
    }

    /// [`GraphicsPipeline::blended`] for targets of `samples` samples per pixel.
    pub fn blended_multisampled(ctx: &Context, module: &ShaderModule, name: &str, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest, samples: u32) -> VkResult<Self> {
        Self::with_samples(ctx, module, name, kernel, colours, depth, samples)
    }

    fn with_samples(ctx: &Context, module: &ShaderModule, name: &str, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest, samples: u32) -> VkResult<Self> {
        let d = &ctx.device;
        let binding = |b: u32, ty: vk::DescriptorType, stage: vk::ShaderStageFlags| {
            vk::DescriptorSetLayoutBinding::default().binding(b).descriptor_type(ty).descriptor_count(1).stage_flags(stage)
        };
        let (vb, fb) = (kernel.vertex_storage_buffers, kernel.fragment_storage_buffers);
        let mut bindings: Vec<_> = (0..vb).map(|b| binding(b, vk::DescriptorType::STORAGE_BUFFER, vk::ShaderStageFlags::VERTEX)).collect();
        bindings.extend((0..fb).map(|b| binding(vb + b, vk::DescriptorType::STORAGE_BUFFER, vk::ShaderStageFlags::FRAGMENT)));
        bindings.extend(
            (0..kernel.fragment_samplers).map(|s| binding(vb + fb + s, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, vk::ShaderStageFlags::FRAGMENT)),
        );
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        let set_layout = unsafe { d.create_descriptor_set_layout(&set_info, None) }.call("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default().stage_flags(PUSH_CONSTANT_STAGES).size(std::mem::size_of::<P>() as u32)];
        let set_layouts = [set_layout];
        let layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&ranges);
        let layout = match unsafe { d.create_pipeline_layout(&layout_info, None) }.call("vkCreatePipelineLayout") {
            Ok(l) => l,
            Err(e) => {
                unsafe { d.destroy_descriptor_set_layout(set_layout, None) };
                return Err(e);
            }
        };
        let mut this = Self { ctx: ctx.clone(), raw: vk::Pipeline::null(), layout, set_layout, kernel };
        let vs = CString::new(kernel.vertex).expect("entry names have no NUL");
        let fs = CString::new(kernel.fragment).expect("entry names have no NUL");
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
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::from_raw(samples));
        let (compare, write) = match depth {
            DepthTest::NearestWrites => (vk::CompareOp::GREATER, true),
            DepthTest::EqualReadOnly => (vk::CompareOp::EQUAL, false),
            DepthTest::NearerReadOnly => (vk::CompareOp::GREATER, false),
            DepthTest::Off => (vk::CompareOp::ALWAYS, false),
        };
        let depth_state = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(depth != DepthTest::Off)
            .depth_write_enable(write)
            .depth_compare_op(compare);
        let blend: Vec<_> = colours
            .iter()
            .map(|&(_, b)| {
                let state = vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA);
                let (src, dst) = match b {
                    Blend::Replace => return state,
                    Blend::Add => (vk::BlendFactor::ONE, vk::BlendFactor::ONE),
                    Blend::Revealage => (vk::BlendFactor::ZERO, vk::BlendFactor::ONE_MINUS_SRC_COLOR),
                };
                state
                    .blend_enable(true)
                    .src_color_blend_factor(src)
                    .dst_color_blend_factor(dst)
                    .color_blend_op(vk::BlendOp::ADD)
                    .src_alpha_blend_factor(src)
                    .dst_alpha_blend_factor(dst)
                    .alpha_blend_op(vk::BlendOp::ADD)
            })
            .collect();
        let blend_state = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic_state = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let formats: Vec<vk::Format> = colours.iter().map(|(f, _)| f.raw()).collect();
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&formats)
            .depth_attachment_format(TargetFormat::Depth32.raw());
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth_state)
            .color_blend_state(&blend_state)
            .dynamic_state(&dynamic_state)
            .layout(layout)
            .push_next(&mut rendering);
        this.raw = match unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) } {
            Ok(p) => p[0],
            Err((_, result)) => return Err(VkError::Call { call: "vkCreateGraphicsPipelines", result }),
        };
        ctx.set_name(this.raw, name);
        Ok(this)
    }
}

impl<P> Drop for GraphicsPipeline<P> {
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
