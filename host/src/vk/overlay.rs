//! The viewer's overlay on the GPU: egui's tessellated shapes drawn by `egui-ash-renderer` into a
//! swapchain image over the presented frame (dynamic rendering, the image's contents kept), so
//! the frame buffer — what screenshots save — never holds it. The layout (text, graph) is the
//! viewer's (`crate::viewer::overlay`), with no Vulkan.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use super::present::Presenter;
use ash::vk;
use egui_ash_renderer::{allocator::DefaultAllocator, DynamicRendering, Options, RenderMode, Renderer};

fn overlay_error(e: egui_ash_renderer::RendererError) -> VkError {
    VkError::Overlay(e.to_string())
}

/// egui's renderer for one swapchain format, with the shapes of the next frame.
pub struct Overlay {
    // Dropped first: it frees its pipeline, buffers and textures while the device lives.
    renderer: Renderer<DefaultAllocator>,
    ctx: Context,
    /// Command pool of the renderer's texture uploads.
    pool: vk::CommandPool,
    primitives: Vec<egui::ClippedPrimitive>,
    pixels_per_point: f32,
    /// Textures egui released with the last shapes, freed once those were drawn.
    to_free: Vec<egui::TextureId>,
}

impl Overlay {
    /// A renderer drawing into `presenter`'s swapchain images.
    pub fn new(ctx: &Context, presenter: &Presenter) -> VkResult<Self> {
        let mode = RenderMode::DynamicRendering(DynamicRendering { color_attachment_format: presenter.format(), depth_attachment_format: None, stencil_attachment_format: None });
        let options = Options { in_flight_frames: 1, enable_depth_test: false, enable_depth_write: false, srgb_framebuffer: false };
        let renderer = Renderer::with_default_allocator(&ctx.instance.raw, ctx.physical, ctx.device.clone(), mode, options).map_err(overlay_error)?;
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(ctx.info.graphics_family).flags(vk::CommandPoolCreateFlags::TRANSIENT);
        let pool = unsafe { ctx.device.create_command_pool(&info, None) }.call("vkCreateCommandPool (overlay)")?;
        Ok(Self { renderer, ctx: ctx.clone(), pool, primitives: Vec::new(), pixels_per_point: 1.0, to_free: Vec::new() })
    }

    /// Takes the next frame's shapes: uploads egui's texture changes now (the previous frame,
    /// drawn already, no longer needs the textures it released).
    pub fn set_frame(&mut self, mut textures: egui::TexturesDelta, primitives: Vec<egui::ClippedPrimitive>, pixels_per_point: f32) -> VkResult<()> {
        for id in self.to_free.drain(..) {
            self.renderer.free_texture(id).map_err(overlay_error)?;
        }
        if !textures.set.is_empty() {
            let queue = self.ctx.queue.lock().unwrap_or_else(|e| e.into_inner());
            for (id, deltas) in textures.set.drain() {
                for delta in &deltas {
                    self.renderer.set_texture(*queue, self.pool, id, delta).map_err(overlay_error)?;
                }
            }
        }
        self.to_free = textures.free.drain().collect();
        self.primitives = primitives;
        self.pixels_per_point = pixels_per_point;
        Ok(())
    }

    /// Draws the shapes into `view` (in `COLOR_ATTACHMENT_OPTIMAL`, contents kept).
    pub(crate) fn record(&mut self, cmd: vk::CommandBuffer, view: vk::ImageView, extent: vk::Extent2D) -> VkResult<()> {
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&attachment);
        let d = &self.ctx.device;
        unsafe { d.cmd_begin_rendering(cmd, &info) };
        let drawn = self.renderer.cmd_draw(cmd, extent, self.pixels_per_point, &self.primitives).map_err(overlay_error);
        unsafe { d.cmd_end_rendering(cmd) };
        drawn
    }
}

impl Drop for Overlay {
    fn drop(&mut self) {
        // SAFETY: every submission drawing the overlay was waited for; the pool's command
        // buffers were freed by the renderer after each upload.
        unsafe { self.ctx.device.destroy_command_pool(self.pool, None) };
    }
}
