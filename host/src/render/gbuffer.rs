//! G-buffer pass: rasterise the scene (rust-gpu `raster::gbuffer_vs/fs`) into depth, normal and
//! albedo targets, then copy each into a storage buffer that every compute pass and CPU reference
//! reads (one buffer each: at 7680×4320 a word per pixel is 133 MB, just inside lavapipe's
//! 128 MiB storage-buffer range).
//!
//! The normal target is one word per pixel (`R32_UINT`, an octahedral code) or, with float32
//! normals, four (`R32G32B32A32_UINT`: three bit patterns and a pad; the `_f32` fragment
//! variants write it). Memory: targets 4 + 4 (16) + 4 B/px, plus the same again as buffers:
//! 24 MB at 1080p in all, 49 MB with float32 normals.
use crate::gpu::Gpu;
use crate::vk::image::upload_rgba8;
use crate::vk::{Buffer, Context, GraphicsPipeline, Image, RasterDesc, Recorder, Sampler, ShaderModule, VkResult};
use ash::vk;
use shaders::kernels;
use shaders::layout::{DrawParams, RasterCamera};
use shaders::octahedral::Precision;

/// Normal target formats: `[octahedral, float32]`.
pub const NORMAL_FORMATS: [vk::Format; 2] = [vk::Format::R32_UINT, vk::Format::R32G32B32A32_UINT];
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The raster module (rust-gpu output of the `graphics` feature), embedded at build time.
pub const GRAPHICS_SPV: &[u8] = include_bytes!(env!("MANYLIGHTS_GRAPHICS_SPV"));

/// G-buffer pipeline variants, by what a draw's material needs: `(name, vertex, fragment
/// [octahedral, float32 normal target], combined image samplers)`. A scene without textures
/// binds and samples none.
pub const VARIANTS: [(&str, &str, [&str; 2], u32); 3] = [
    ("gbuffer", kernels::GBUFFER_VS, kernels::GBUFFER_FS, 0),
    ("gbuffer textured", kernels::GBUFFER_VS_UV, kernels::GBUFFER_FS_TEXTURED, 1),
    ("gbuffer alpha-tested", kernels::GBUFFER_VS_UV, kernels::GBUFFER_FS_MASKED, 2),
];

/// Index into [`NORMAL_FORMATS`] and the outer index of [`pipelines`] for a `PRECISION_*`.
pub fn normal_target(precision: u32) -> usize {
    usize::from(Precision::from_u32(precision).gbuffer_words() == 4)
}

/// The G-buffer pipelines: `[normal target][variant]` (see [`normal_target`], [`VARIANTS`]).
pub fn pipelines(ctx: &Context) -> VkResult<[[GraphicsPipeline; 3]; 2]> {
    let module = ShaderModule::new(ctx, "manylights raster shaders", GRAPHICS_SPV)?;
    let make = |target: usize, (name, vertex_entry, fragment, fragment_samplers): (&str, &str, [&str; 2], u32)| {
        let name = if target == 1 { format!("{name} (float32 normals)") } else { name.to_string() };
        let fragment_entry = fragment[target];
        GraphicsPipeline::new(
            ctx,
            &module,
            &RasterDesc {
                name: &name,
                vertex_entry,
                fragment_entry,
                vertex_storage_buffers: 4,
                fragment_storage_buffers: 0,
                fragment_samplers,
                push_constant_bytes: std::mem::size_of::<DrawParams>() as u32,
                color_formats: &[NORMAL_FORMATS[target], ALBEDO_FORMAT],
                depth_format: DEPTH_FORMAT,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
            },
        )
    };
    Ok([
        [make(0, VARIANTS[0])?, make(0, VARIANTS[1])?, make(0, VARIANTS[2])?],
        [make(1, VARIANTS[0])?, make(1, VARIANTS[1])?, make(1, VARIANTS[2])?],
    ])
}

/// One draw: a range of the merged index buffer, its material and its textures (indices into
/// the scene's texture list).
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub params: DrawParams,
    pub albedo_texture: Option<u32>,
    pub mask_texture: Option<u32>,
}

impl Draw {
    /// Index into [`VARIANTS`].
    pub fn variant(&self) -> usize {
        match (self.albedo_texture, self.mask_texture) {
            (_, Some(_)) => 2,
            (Some(_), None) => 1,
            (None, None) => 0,
        }
    }
}

/// Texels of one texture, as the scene loaded them.
#[derive(Clone, Copy, Debug)]
pub struct TextureData<'a> {
    pub width: u32,
    pub height: u32,
    pub rgba8: &'a [u8],
    /// Colour data stored in sRGB (sampled as linear); masks are linear.
    pub srgb: bool,
}

/// The scene's textures on the GPU, a white fallback and the sampler.
pub struct Textures {
    images: Vec<Image>,
    white: Image,
    sampler: Sampler,
}

impl Textures {
    pub fn upload(ctx: &Context, textures: &[TextureData<'_>]) -> VkResult<Self> {
        let images = textures
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let format = if t.srgb { vk::Format::R8G8B8A8_SRGB } else { vk::Format::R8G8B8A8_UNORM };
                upload_rgba8(ctx, &format!("texture {i}"), t.width, t.height, format, t.rgba8)
            })
            .collect::<VkResult<Vec<_>>>()?;
        let white = upload_rgba8(ctx, "white texture", 1, 1, vk::Format::R8G8B8A8_UNORM, &[255; 4])?;
        Ok(Self { images, white, sampler: Sampler::linear_repeat(ctx)? })
    }

    pub fn info(&self, index: Option<u32>) -> [vk::DescriptorImageInfo; 1] {
        let img = index.and_then(|i| self.images.get(i as usize)).unwrap_or(&self.white);
        [vk::DescriptorImageInfo::default()
            .sampler(self.sampler.raw)
            .image_view(img.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
    }

    pub fn bytes(&self) -> u64 {
        self.images.iter().map(|i| 4 * i.extent.width as u64 * i.extent.height as u64).sum()
    }
}

/// Scene geometry on the GPU (merged buffers; world space).
pub struct Geometry {
    pub positions: Buffer,
    pub normals: Buffer,
    pub uvs: Buffer,
    pub indices: Buffer,
    pub draws: Vec<Draw>,
}

impl Geometry {
    pub fn upload(ctx: &Context, positions: &[[f32; 3]], normals: &[[f32; 3]], uvs: &[[f32; 2]], indices: &[u32], draws: Vec<Draw>) -> VkResult<Self> {
        let idx = Buffer::new(
            ctx,
            "indices",
            4 * indices.len() as u64,
            crate::vk::memory::STORAGE | vk::BufferUsageFlags::INDEX_BUFFER,
            crate::vk::MemoryLocation::GpuOnly,
        );
        let mut idx = idx?;
        idx.write(indices)?;
        Ok(Self {
            positions: Buffer::from_slice(ctx, "positions", positions)?,
            normals: Buffer::from_slice(ctx, "normals", normals)?,
            uvs: Buffer::from_slice(ctx, "uvs", uvs)?,
            indices: idx,
            draws,
        })
    }

    pub fn bytes(&self) -> u64 {
        self.positions.size + self.normals.size + self.uvs.size + self.indices.size
    }
}

/// Render targets and their buffer copy.
pub struct Targets {
    pub width: u32,
    pub height: u32,
    depth: Image,
    normal: Image,
    albedo: Image,
    /// Reversed-Z depth (`f32`), one word per pixel.
    pub depth_buf: Buffer,
    /// View-space normal: one word per pixel (octahedral) or four (float32).
    pub normal_buf: Buffer,
    /// Index into [`NORMAL_FORMATS`].
    pub normal_target: usize,
    /// RGBA8 albedo + material index, one word per pixel.
    pub albedo_buf: Buffer,
}

impl Targets {
    /// Targets for `width × height` pixels and normals at `precision` (`PRECISION_*`).
    pub fn new(ctx: &Context, width: u32, height: u32, precision: u32) -> VkResult<Self> {
        let color = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let n = width as u64 * height as u64;
        let normal_target = normal_target(precision);
        let normal_words = Precision::from_u32(precision).gbuffer_words() as u64;
        crate::vk::memory::check_range(ctx, "G-buffer", 4 * n)?;
        crate::vk::memory::check_range(ctx, "G-buffer normals", 4 * normal_words * n)?;
        Ok(Self {
            width,
            height,
            depth: Image::new_2d(ctx, "gbuffer depth", width, height, DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)?,
            normal: Image::new_2d(ctx, "gbuffer normal", width, height, NORMAL_FORMATS[normal_target], color)?,
            albedo: Image::new_2d(ctx, "gbuffer albedo", width, height, ALBEDO_FORMAT, color)?,
            depth_buf: Buffer::storage(ctx, "gbuffer depth", 4 * n)?,
            normal_buf: Buffer::storage(ctx, "gbuffer normals", 4 * normal_words * n)?,
            normal_target,
            albedo_buf: Buffer::storage(ctx, "gbuffer albedo", 4 * n)?,
        })
    }

    pub fn bytes(&self) -> u64 {
        // The targets hold what their buffers hold.
        2 * (self.depth_buf.size + self.normal_buf.size + self.albedo_buf.size)
    }
}

/// Records the G-buffer pass and the copies into the targets' buffers.
pub fn record(gpu: &Gpu, rec: &mut Recorder<'_>, geo: &Geometry, textures: &Textures, camera: &Buffer, t: &Targets) -> VkResult<()> {
    let d = &gpu.ctx.device;
    let cmd = rec.cmd;
    let color_out = (vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags::COLOR_ATTACHMENT_WRITE);
    let depth_out = (
        vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS,
        vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ,
    );
    let top = (vk::PipelineStageFlags::TOP_OF_PIPE, vk::AccessFlags::empty());
    let transfer_read = (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ);
    for img in [&t.normal, &t.albedo] {
        img.transition(cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, top.0, top.1, color_out.0, color_out.1);
    }
    t.depth.transition(cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, top.0, top.1, depth_out.0, depth_out.1);
    let clear = |c: vk::ClearColorValue| vk::ClearValue { color: c };
    let colors = [
        vk::RenderingAttachmentInfo::default()
            .image_view(t.normal.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(clear(vk::ClearColorValue { uint32: [0; 4] })),
        vk::RenderingAttachmentInfo::default()
            .image_view(t.albedo.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(clear(vk::ClearColorValue { float32: [0.0; 4] })),
    ];
    let depth = vk::RenderingAttachmentInfo::default()
        .image_view(t.depth.view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
    let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: t.width, height: t.height } };
    let info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&colors).depth_attachment(&depth);
    let buffers = [&geo.positions, &geo.normals, &geo.uvs, camera];
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
        buffers.iter().map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)]).collect();
    unsafe {
        d.cmd_begin_rendering(cmd, &info);
        d.cmd_set_viewport(cmd, 0, &[vk::Viewport { x: 0.0, y: 0.0, width: t.width as f32, height: t.height as f32, min_depth: 0.0, max_depth: 1.0 }]);
        d.cmd_set_scissor(cmd, 0, &[area]);
        d.cmd_bind_index_buffer(cmd, geo.indices.raw, 0, vk::IndexType::UINT32);
    }
    let mut bound = usize::MAX;
    for draw in geo.draws.iter().filter(|d| d.index_count > 0) {
        let variant = draw.variant();
        let pipe = &gpu.gbuffer[t.normal_target][variant];
        let images = [textures.info(draw.albedo_texture), textures.info(draw.mask_texture)];
        let mut writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(vk::DescriptorType::STORAGE_BUFFER).buffer_info(info))
            .collect();
        writes.extend(images.iter().take(VARIANTS[variant].3 as usize).enumerate().map(|(s, info)| {
            vk::WriteDescriptorSet::default()
                .dst_binding(4 + s as u32)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(info)
        }));
        unsafe {
            if bound != variant {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipe.raw);
                bound = variant;
            }
            gpu.ctx.push_descriptor.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::GRAPHICS, pipe.layout, 0, &writes);
            d.cmd_push_constants(cmd, pipe.layout, vk::ShaderStageFlags::FRAGMENT, 0, bytemuck::bytes_of(&draw.params));
            d.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, 0, 0);
        }
    }
    unsafe { d.cmd_end_rendering(cmd) };
    for img in [&t.normal, &t.albedo] {
        img.transition(cmd, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, color_out.0, color_out.1, transfer_read.0, transfer_read.1);
    }
    t.depth.transition(cmd, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, depth_out.0, depth_out.1, transfer_read.0, transfer_read.1);
    for (img, buf) in [(&t.depth, &t.depth_buf), (&t.normal, &t.normal_buf), (&t.albedo, &t.albedo_buf)] {
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(img.aspect()).layer_count(1))
            .image_extent(vk::Extent3D { width: t.width, height: t.height, depth: 1 });
        unsafe { d.cmd_copy_image_to_buffer(cmd, img.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buf.raw, &[region]) };
    }
    crate::vk::memory::barrier(&gpu.ctx, cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
    Ok(())
}

/// Reversed-Z, infinite-far projection with Vulkan's y-down clip space:
/// `clip = (f/a·x, −f·y, near, −z)`, so the stored depth is `near / d`.
pub fn projection(fov_y_radians: f32, aspect: f32, near: f32) -> glam::Mat4 {
    let f = 1.0 / (0.5 * fov_y_radians).tan();
    glam::Mat4::from_cols(
        glam::Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, -f, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, 0.0, -1.0),
        glam::Vec4::new(0.0, 0.0, near, 0.0),
    )
}

/// The camera block of the G-buffer pass.
pub fn raster_camera(view: glam::Mat4, fov_y_radians: f32, aspect: f32, near: f32) -> RasterCamera {
    RasterCamera { view: view.to_cols_array_2d(), proj: projection(fov_y_radians, aspect, near).to_cols_array_2d() }
}
