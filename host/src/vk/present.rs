//! Presenting frames in a window: the window's surface, its swapchain and the copy of a rendered
//! frame into a swapchain image (RAII; the viewer, `crate::viewer`).
//!
//! Per displayed frame ([`Presenter::present`]):
//! 1. acquire an image (waited for on the host with a fence, so the copy needs no semaphore);
//! 2. one submission: the frame buffer (packed RGBA8 words, what `render` writes as PNG) copied
//!    into an RGBA8 image, blitted (nearest, scaled only while a resize is under way) into the
//!    swapchain image, which converts to the swapchain's byte order; then the overlay
//!    ([`super::overlay`]) drawn over it; the submission signals the image's own semaphore;
//! 3. present, waiting for that semaphore. One semaphore per swapchain image: an image is
//!    acquired again only once its previous presentation has consumed its semaphore.
//!
//! Out-of-date and suboptimal swapchains are recreated (from the old one) before the next frame;
//! a window of zero extent (minimised) has no swapchain, and nothing is presented until it has
//! an extent again.
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use super::image::Image;
use super::memory::{Buffer, MemoryLocation};
use super::overlay::Overlay;
use ash::{khr, vk};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

/// How presented images reach the screen (`--present-mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresentMode {
    /// Wait for vertical blank, queueing images (always supported; no tearing).
    Fifo,
    /// Wait for vertical blank, the newest image replacing a queued one (no tearing, low latency).
    Mailbox,
    /// No wait (may tear).
    Immediate,
}

impl PresentMode {
    fn raw(self) -> vk::PresentModeKHR {
        match self {
            Self::Fifo => vk::PresentModeKHR::FIFO,
            Self::Mailbox => vk::PresentModeKHR::MAILBOX,
            Self::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

/// What became of a frame handed to [`Presenter::present`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// On screen.
    Shown,
    /// Not shown: the window has no extent (minimised) or its swapchain was out of date (it has
    /// been recreated; the next frame is shown).
    Skipped,
}

/// A window's Vulkan surface (destroyed before the instance: it holds the context).
struct Surface {
    /// Keeps the instance alive until the surface is destroyed.
    _ctx: Context,
    loader: khr::surface::Instance,
    raw: vk::SurfaceKHR,
}

impl Drop for Surface {
    fn drop(&mut self) {
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// A swapchain, its images and one "rendered" semaphore per image.
struct Chain {
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    rendered: Vec<vk::Semaphore>,
    extent: vk::Extent2D,
}

/// Presents frames in one window (see the module doc). The window must outlive it.
pub struct Presenter {
    ctx: Context,
    surface: Surface,
    loader: khr::swapchain::Device,
    chain: Option<Chain>,
    format: vk::Format,
    mode: vk::PresentModeKHR,
    acquired: vk::Fence,
    /// The frame as an image (the blit's source), at the last frame's size.
    frame_image: Option<Image>,
    /// The swapchain must be recreated before the next frame (suboptimal, resized).
    stale: bool,
    /// The swapchain's images can be copied from (the surface offers `TRANSFER_SRC`).
    readable: bool,
    /// Read the next presented image back ([`Presenter::capture_next`]).
    capture: bool,
    /// The last image read back: `(width, height, RGBA8 words, R in the low byte)`.
    captured: Option<(u32, u32, Vec<u32>)>,
    window_extent: vk::Extent2D,
}

impl Presenter {
    /// A surface for `window`, whose size is `extent` (physical pixels), and its swapchain in
    /// present mode `mode` — FIFO where the surface lacks it, with the warning returned beside.
    pub fn new<W: HasDisplayHandle + HasWindowHandle>(ctx: &Context, window: &W, mode: PresentMode, extent: (u32, u32)) -> VkResult<(Self, Option<String>)> {
        let handle_error = |e: raw_window_handle::HandleError| VkError::Window(format!("no window handle: {e}"));
        let display = window.display_handle().map_err(handle_error)?.as_raw();
        let handle = window.window_handle().map_err(handle_error)?.as_raw();
        let (entry, instance) = (&ctx.instance.entry, &ctx.instance.raw);
        // SAFETY: the instance has the display's surface extensions (`Context::for_display`); the
        // window outlives the presenter (documented), which destroys the surface first.
        let raw = unsafe { ash_window::create_surface(entry, instance, display, handle, None) }.call("vkCreate*SurfaceKHR")?;
        let surface = Surface { _ctx: ctx.clone(), loader: khr::surface::Instance::new(entry, instance), raw };
        let family = ctx.info.graphics_family;
        let supported = unsafe { surface.loader.get_physical_device_surface_support(ctx.physical, family, raw) }.call("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            return Err(VkError::Unsupported { device: ctx.info.name.clone(), missing: format!("presentation to this window from queue family {family}") });
        }
        let modes = unsafe { surface.loader.get_physical_device_surface_present_modes(ctx.physical, raw) }.call("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        let (mode, warning) = match modes.contains(&mode.raw()) {
            true => (mode.raw(), None),
            false => (vk::PresentModeKHR::FIFO, Some(format!("present mode {mode:?} is not supported by this surface (it offers {modes:?}): using fifo"))),
        };
        let formats = unsafe { surface.loader.get_physical_device_surface_formats(ctx.physical, raw) }.call("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        // UNORM: the frame's bytes are sRGB-encoded already and are copied unchanged.
        let preferred = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM, vk::Format::A8B8G8R8_UNORM_PACK32];
        let Some(format) = preferred.into_iter().find(|f| formats.iter().any(|s| s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)) else {
            return Err(VkError::Unsupported { device: ctx.info.name.clone(), missing: format!("an 8-bit UNORM swapchain format for this window (it offers {formats:?})") });
        };
        let features = unsafe { ctx.instance.raw.get_physical_device_format_properties(ctx.physical, format) }.optimal_tiling_features;
        if !features.contains(vk::FormatFeatureFlags::BLIT_DST | vk::FormatFeatureFlags::COLOR_ATTACHMENT) {
            return Err(VkError::Unsupported { device: ctx.info.name.clone(), missing: format!("blits into and drawing to {format:?} images") });
        }
        let acquired = unsafe { ctx.device.create_fence(&vk::FenceCreateInfo::default(), None) }.call("vkCreateFence")?;
        let mut this = Self {
            ctx: ctx.clone(),
            loader: khr::swapchain::Device::new(instance, &ctx.device),
            surface,
            chain: None,
            format,
            mode,
            acquired,
            frame_image: None,
            stale: true,
            readable: false,
            capture: false,
            captured: None,
            window_extent: vk::Extent2D { width: extent.0, height: extent.1 },
        };
        this.recreate()?;
        Ok((this, warning))
    }

    /// The swapchain images' format (the overlay draws into them).
    pub(crate) fn format(&self) -> vk::Format {
        self.format
    }

    /// The present mode in use.
    pub fn mode(&self) -> String {
        format!("{:?}", self.mode).to_lowercase()
    }

    /// The extent images are presented at (`None` while the window has none: minimised).
    pub fn extent(&self) -> Option<(u32, u32)> {
        self.chain.as_ref().map(|c| (c.extent.width, c.extent.height))
    }

    /// Recreates the swapchain where the window changed, and says the extent the next frame is
    /// presented at (`None`: the window has none).
    pub fn prepare(&mut self) -> VkResult<Option<(u32, u32)>> {
        if self.stale {
            self.recreate()?;
        }
        Ok(self.extent())
    }

    /// The window's size changed (physical pixels; 0 when minimised): the swapchain is
    /// recreated before the next frame.
    pub fn resize(&mut self, extent: (u32, u32)) {
        self.window_extent = vk::Extent2D { width: extent.0, height: extent.1 };
        self.stale = true;
    }

    /// Recreates the swapchain for the window's current extent (none for a zero extent).
    fn recreate(&mut self) -> VkResult<()> {
        let ctx = &self.ctx;
        let caps = unsafe { self.surface.loader.get_physical_device_surface_capabilities(ctx.physical, self.surface.raw) }
            .call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        // The surface's own extent where it fixes one (X11: the window's), else the window's.
        let extent = match caps.current_extent.width {
            u32::MAX => vk::Extent2D {
                width: self.window_extent.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: self.window_extent.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            },
            _ => caps.current_extent,
        };
        unsafe { ctx.device.device_wait_idle() }.call("vkDeviceWaitIdle")?;
        let old = self.chain.take();
        self.stale = false;
        if extent.width == 0 || extent.height == 0 {
            if let Some(old) = old {
                self.destroy(old);
            }
            return Ok(());
        }
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(usage) {
            return Err(VkError::Unsupported { device: ctx.info.name.clone(), missing: format!("swapchain images usable as {usage:?} (the surface offers {:?})", caps.supported_usage_flags) });
        }
        // Copied from only when a presented image is read back ([`Presenter::capture_next`]).
        self.readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        if self.readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [vk::CompositeAlphaFlagsKHR::OPAQUE, vk::CompositeAlphaFlagsKHR::INHERIT, vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED, vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED]
            .into_iter()
            .find(|a| caps.supported_composite_alpha.contains(*a))
            .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface.raw)
            .min_image_count(count)
            .image_format(self.format)
            .image_color_space(vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(self.mode)
            .clipped(true)
            .old_swapchain(old.as_ref().map_or(vk::SwapchainKHR::null(), |c| c.raw));
        let created = unsafe { self.loader.create_swapchain(&info, None) }.call("vkCreateSwapchainKHR");
        if let Some(old) = old {
            self.destroy(old);
        }
        let raw = created?;
        let mut chain = Chain { raw, images: Vec::new(), views: Vec::new(), rendered: Vec::new(), extent };
        let filled = (|| {
            chain.images = unsafe { self.loader.get_swapchain_images(raw) }.call("vkGetSwapchainImagesKHR")?;
            for (i, &image) in chain.images.iter().enumerate() {
                let range = vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
                let view_info = vk::ImageViewCreateInfo::default().image(image).view_type(vk::ImageViewType::TYPE_2D).format(self.format).subresource_range(range);
                chain.views.push(unsafe { ctx.device.create_image_view(&view_info, None) }.call("vkCreateImageView")?);
                chain.rendered.push(unsafe { ctx.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.call("vkCreateSemaphore")?);
                ctx.set_name(image, &format!("swapchain image {i}"));
            }
            Ok(())
        })();
        match filled {
            Ok(()) => {
                self.chain = Some(chain);
                Ok(())
            }
            Err(e) => {
                self.destroy(chain);
                Err(e)
            }
        }
    }

    fn destroy(&self, c: Chain) {
        let d = &self.ctx.device;
        // SAFETY: the device is idle (waited for by the callers), so no presentation or copy
        // uses the chain's images or semaphores.
        unsafe {
            for v in c.views {
                d.destroy_image_view(v, None);
            }
            for s in c.rendered {
                d.destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(c.raw, None);
        }
    }

    /// Shows the frame `frame` (`width × height` packed RGBA8 words) with the overlay over it
    /// (see the module doc).
    /// Reads the next presented image back (after the overlay, before it is presented):
    /// [`Presenter::take_capture`] then has it. Fails where the surface's images cannot be
    /// copied from.
    pub fn capture_next(&mut self) -> VkResult<()> {
        if !self.readable {
            return Err(VkError::Unsupported { device: self.ctx.info.name.clone(), missing: "swapchain images that can be read back (TRANSFER_SRC)".into() });
        }
        self.capture = true;
        Ok(())
    }

    /// The image [`Presenter::capture_next`] asked for, once presented: `(width, height, RGBA8
    /// words, R in the low byte)`.
    pub fn take_capture(&mut self) -> Option<(u32, u32, Vec<u32>)> {
        self.captured.take()
    }

    pub fn present(&mut self, frame: &Buffer, width: u32, height: u32, overlay: Option<&mut Overlay>) -> VkResult<Presented> {
        if self.stale {
            self.recreate()?;
        }
        let Some(chain) = self.chain.as_ref() else { return Ok(Presented::Skipped) };
        let d = &self.ctx.device;
        let acquired = unsafe { self.loader.acquire_next_image(chain.raw, u64::MAX, vk::Semaphore::null(), self.acquired) };
        let (index, suboptimal) = match acquired {
            Ok(r) => r,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(Presented::Skipped);
            }
            Err(e) => return Err(e).call("vkAcquireNextImageKHR"),
        };
        unsafe { d.wait_for_fences(&[self.acquired], true, u64::MAX) }.call("vkWaitForFences (swapchain image)")?;
        unsafe { d.reset_fences(&[self.acquired]) }.call("vkResetFences")?;
        let needs_image = self.frame_image.as_ref().is_none_or(|i| (i.extent.width, i.extent.height) != (width, height));
        if needs_image {
            // Sampled only because every image gets a view; it is copied into and blitted from.
            let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
            self.frame_image = None;
            self.frame_image = Some(Image::new_2d(&self.ctx, "presented frame", width, height, vk::Format::R8G8B8A8_UNORM, usage)?);
        }
        let (src, image, view, extent) = (self.frame_image.as_ref().expect("made above"), chain.images[index as usize], chain.views[index as usize], chain.extent);
        let semaphore = chain.rendered[index as usize];
        let ctx = &self.ctx;
        let mut readback = match self.capture {
            true => Some(Buffer::new(ctx, "presented image (read-back)", 4 * extent.width as u64 * extent.height as u64, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu)?),
            false => None,
        };
        ctx.submit_signalling_and_wait(Some(semaphore), |cmd| {
            let colour = vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
            let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
            let frame_ready = vk::BufferMemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .buffer(frame.raw)
                .size(vk::WHOLE_SIZE);
            let to_dst = |img: vk::Image, old: vk::ImageLayout| {
                vk::ImageMemoryBarrier::default()
                    .old_layout(old)
                    .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                    .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(img)
                    .subresource_range(colour)
            };
            unsafe {
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[frame_ready],
                    &[to_dst(src.raw, vk::ImageLayout::UNDEFINED), to_dst(image, vk::ImageLayout::UNDEFINED)],
                );
                let region = vk::BufferImageCopy::default().image_subresource(layers).image_extent(vk::Extent3D { width, height, depth: 1 });
                d.cmd_copy_buffer_to_image(cmd, frame.raw, src.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region]);
            }
            src.transition(
                cmd,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            );
            let corner = |w: u32, h: u32| [vk::Offset3D::default(), vk::Offset3D { x: w as i32, y: h as i32, z: 1 }];
            let blit = vk::ImageBlit::default()
                .src_subresource(layers)
                .src_offsets(corner(width, height))
                .dst_subresource(layers)
                .dst_offsets(corner(extent.width, extent.height));
            unsafe {
                d.cmd_blit_image(cmd, src.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[blit], vk::Filter::NEAREST);
            }
            let mut layout = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
            let (mut stage, mut access) = (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_WRITE);
            if let Some(o) = overlay {
                let to_colour = vk::ImageMemoryBarrier::default()
                    .old_layout(layout)
                    .new_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .src_access_mask(access)
                    .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(image)
                    .subresource_range(colour);
                unsafe {
                    d.cmd_pipeline_barrier(cmd, stage, vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT, vk::DependencyFlags::empty(), &[], &[], &[to_colour]);
                }
                o.record(cmd, view, extent)?;
                layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
                (stage, access) = (vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags::COLOR_ATTACHMENT_WRITE);
            }
            if let Some(buf) = &readback {
                let to_src = vk::ImageMemoryBarrier::default()
                    .old_layout(layout)
                    .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                    .src_access_mask(access)
                    .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(image)
                    .subresource_range(colour);
                let region = vk::BufferImageCopy::default().image_subresource(layers).image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
                let host = vk::MemoryBarrier::default().src_access_mask(vk::AccessFlags::TRANSFER_WRITE).dst_access_mask(vk::AccessFlags::HOST_READ);
                unsafe {
                    d.cmd_pipeline_barrier(cmd, stage, vk::PipelineStageFlags::TRANSFER, vk::DependencyFlags::empty(), &[], &[], &[to_src]);
                    d.cmd_copy_image_to_buffer(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buf.raw, &[region]);
                    d.cmd_pipeline_barrier(cmd, vk::PipelineStageFlags::TRANSFER, vk::PipelineStageFlags::HOST, vk::DependencyFlags::empty(), &[host], &[], &[]);
                }
                layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
                (stage, access) = (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ);
            }
            let to_present = vk::ImageMemoryBarrier::default()
                .old_layout(layout)
                .new_layout(vk::ImageLayout::PRESENT_SRC_KHR)
                .src_access_mask(access)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(colour);
            unsafe { d.cmd_pipeline_barrier(cmd, stage, vk::PipelineStageFlags::BOTTOM_OF_PIPE, vk::DependencyFlags::empty(), &[], &[], &[to_present]) };
            Ok(())
        })?;
        if let Some(buf) = readback.as_mut() {
            let words: Vec<u32> = buf.read((extent.width * extent.height) as usize)?;
            // The surface's byte order to RGBA (R in the low byte), as the frame is packed.
            let bgra = matches!(self.format, vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB);
            let rgba = words.into_iter().map(|w| if bgra { (w & 0xff00_ff00) | ((w >> 16) & 0xff) | ((w & 0xff) << 16) } else { w }).collect();
            self.captured = Some((extent.width, extent.height, rgba));
            self.capture = false;
        }
        let (swapchains, indices, waits) = ([chain.raw], [index], [semaphore]);
        let info = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        let queue = self.ctx.queue.lock().unwrap_or_else(|e| e.into_inner());
        match unsafe { self.loader.queue_present(*queue, &info) } {
            Ok(false) if !suboptimal => {}
            Ok(_) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(e) => return Err(e).call("vkQueuePresentKHR"),
        }
        Ok(Presented::Shown)
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
        if let Some(c) = self.chain.take() {
            self.destroy(c);
        }
        unsafe { self.ctx.device.destroy_fence(self.acquired, None) };
    }
}
