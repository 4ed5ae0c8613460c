//! Host side of `forward-plus` (algorithm: `shaders::forward_plus`, shaders:
//! `shaders::raster_forward`): depth pre-pass → tiled culling into per-tile linked lists (head
//! buffer + node buffer + atomic counter) → forward raster pass with depth test EQUAL.
//!
//! The node buffer's capacity is the one view-dependent size: the culling counter ends at the
//! nodes the frame needs; if that exceeds the buffer, it grows (need + 25 %) and the frame re-runs.
//! The pre-pass depth is copied into the G-buffer's depth buffer, so CPU checks and `--stats`
//! read it as for every other technique.
//!
//! Memory: heads 4 B per tile, nodes 8 B per light reference, a depth and a colour target
//! (4 B per pixel each).
use super::clustered_aabb::Outcome;
use super::gbuffer::{Geometry, Targets, Textures, DEPTH_FORMAT, GRAPHICS_SPV};
use crate::gpu::Gpu;
use crate::vk::memory::barrier;
use crate::vk::{Buffer, GraphicsPipeline, Image, Profiler, RasterDesc, Recorder, ShaderModule, VkResult};
use anyhow::{bail, Context as _, Result};
use ash::vk;
use shaders::forward_plus::{FP_COUNTER_NODES, MAX_LIGHTS_LLVMPIPE};
use shaders::layout::{ForwardParams, FrameParams, TiledParams, COUNTERS};
use shaders::tile_cull::{MAX_TILED_TILE, MODE_TILED};

/// Format of the forward pass's colour target: the frame's packed RGBA8 word.
const COLOUR_FORMAT: vk::Format = vk::Format::R32_UINT;

/// Pre-pass pipelines `[opaque, alpha-tested]` and shading pipelines `[plain, textured,
/// alpha-tested]` (like the G-buffer's variants).
struct Pipelines {
    depth: [GraphicsPipeline; 2],
    shade: [GraphicsPipeline; 3],
}

fn pipelines(gpu: &Gpu) -> VkResult<Pipelines> {
    let module = ShaderModule::new(&gpu.ctx, "manylights raster shaders (forward+)", GRAPHICS_SPV)?;
    let make = |name, vertex_entry, fragment_entry, fragment_storage_buffers, fragment_samplers, push: usize, colour: &[vk::Format], compare, write| {
        GraphicsPipeline::new(
            &gpu.ctx,
            &module,
            &RasterDesc {
                name,
                vertex_entry,
                fragment_entry,
                vertex_storage_buffers: 4,
                fragment_storage_buffers,
                fragment_samplers,
                push_constant_bytes: push as u32,
                color_formats: colour,
                depth_format: DEPTH_FORMAT,
                depth_compare: compare,
                depth_write: write,
            },
        )
    };
    let fwd = std::mem::size_of::<ForwardParams>();
    let (greater, equal) = (vk::CompareOp::GREATER, vk::CompareOp::EQUAL);
    let c = [COLOUR_FORMAT];
    Ok(Pipelines {
        depth: [
            make("depth pre-pass", "raster_forward::depth_vs", "raster_forward::depth_fs", 0, 0, fwd, &c, greater, true)?,
            make("depth pre-pass alpha-tested", "raster_forward::depth_vs_uv", "raster_forward::depth_fs_masked", 0, 2, fwd, &c, greater, true)?,
        ],
        shade: [
            make("forward", "raster::gbuffer_vs", "raster_forward::forward_fs", 6, 0, fwd, &c, equal, false)?,
            make("forward textured", "raster::gbuffer_vs_uv", "raster_forward::forward_fs_textured", 6, 1, fwd, &c, equal, false)?,
            make("forward alpha-tested", "raster::gbuffer_vs_uv", "raster_forward::forward_fs_masked", 6, 2, fwd, &c, equal, false)?,
        ],
    })
}

/// The scene as the raster passes draw it.
pub struct SceneGpu<'a> {
    pub geometry: &'a Geometry,
    /// The merged index list (the forward pass draws its triangles in reverse order).
    pub indices: &'a [u32],
    pub textures: &'a Textures,
    pub camera: &'a Buffer,
    pub lights: &'a Buffer,
    pub materials: &'a Buffer,
}

struct ForwardPlus {
    pipes: Pipelines,
    depth: Image,
    colour: Image,
    /// Pre-pass colour target: the index of the draw that wins each pixel (and its copy).
    winner: Image,
    winners: Buffer,
    /// The index list with its triangles in reverse order (module docs, coplanar surfaces).
    reversed: Buffer,
    heads: Buffer,
    nodes: Buffer,
    counters: Buffer,
    capacity: u32,
    params: TiledParams,
}

impl ForwardPlus {
    fn new(gpu: &Gpu, frame: &FrameParams, capacity: u32, indices: &[u32]) -> Result<Self> {
        let ctx = &gpu.ctx;
        let g = &frame.grid;
        let (w, h) = (g.width, g.height);
        Ok(Self {
            pipes: pipelines(gpu).context("creating the forward+ pipelines")?,
            depth: Image::new_2d(ctx, "forward+ depth", w, h, DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)?,
            colour: Image::new_2d(ctx, "forward+ colour", w, h, COLOUR_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)?,
            winner: Image::new_2d(ctx, "forward+ winning draw", w, h, COLOUR_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC)?,
            winners: Buffer::storage(ctx, "winning draws", 4 * w as u64 * h as u64)?,
            reversed: {
                let rev: Vec<u32> = indices.chunks_exact(3).rev().flatten().copied().collect();
                let mut b = Buffer::new(ctx, "reversed indices", 4 * rev.len().max(1) as u64, crate::vk::memory::STORAGE | vk::BufferUsageFlags::INDEX_BUFFER, crate::vk::MemoryLocation::GpuOnly)?;
                if !rev.is_empty() {
                    b.write(&rev)?;
                }
                b
            },
            heads: Buffer::storage(ctx, "tile list heads", 4 * (g.tiles_x * g.tiles_y) as u64)?,
            nodes: Self::node_buffer(gpu, capacity)?,
            counters: Buffer::storage(ctx, "counters", 4 * COUNTERS as u64)?,
            capacity,
            params: TiledParams { frame: *frame, mode: MODE_TILED, _pad: [0; 3] },
        })
    }

    fn node_buffer(gpu: &Gpu, capacity: u32) -> VkResult<Buffer> {
        crate::vk::memory::check_range(&gpu.ctx, "light list nodes", 8 * capacity as u64)?;
        Buffer::storage(&gpu.ctx, "light list nodes", 8 * capacity as u64)
    }

    fn sizes(&self) -> Vec<(String, u64)> {
        let g = &self.params.frame.grid;
        let targets = 12 * g.width as u64 * g.height as u64;
        vec![
            (self.heads.name.clone(), self.heads.size),
            (self.nodes.name.clone(), self.nodes.size),
            (self.counters.name.clone(), self.counters.size),
            (self.winners.name.clone(), self.winners.size),
            (self.reversed.name.clone(), self.reversed.size),
            ("forward+ targets".into(), targets),
        ]
    }

    /// Draws every draw of the scene with `pipes` (variant per draw: see [`Pipelines`]), pushing
    /// `extra` storage buffers after the vertex stage's and the draw's textures after them.
    fn draw_all(&self, gpu: &Gpu, rec: &Recorder<'_>, scene: &SceneGpu<'_>, pipes: &[GraphicsPipeline], extra: &[&Buffer], forward: bool) {
        let d = &gpu.ctx.device;
        let cmd = rec.cmd;
        let geo = scene.geometry;
        let buffers: Vec<&Buffer> = [&geo.positions, &geo.normals, &geo.uvs, scene.camera].into_iter().chain(extra.iter().copied()).collect();
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers.iter().map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)]).collect();
        let mut bound = usize::MAX;
        let total = self.reversed.size as u32 / 4;
        let draws: Vec<(usize, &super::Draw)> = geo.draws.iter().enumerate().filter(|(_, d)| d.index_count > 0).collect();
        // The forward pass draws everything in reverse order: of coplanar fragments, which all
        // pass EQUAL, the last one drawn — the first in scene order, the G-buffer's — stays.
        let order: Vec<(usize, &super::Draw)> = if forward { draws.into_iter().rev().collect() } else { draws };
        for (index, draw) in order {
            let first_index = if forward { total - draw.first_index - draw.index_count } else { draw.first_index };
            // Pre-pass: opaque (0) or alpha-tested (1); forward: the G-buffer's variant index.
            let (variant, samplers) = match (forward, draw.variant()) {
                (false, 2) => (1, 2),
                (false, _) => (0, 0),
                (true, v) => (v, v),
            };
            let pipe = &pipes[variant];
            let images = [scene.textures.info(draw.albedo_texture), scene.textures.info(draw.mask_texture)];
            let mut writes: Vec<_> = infos
                .iter()
                .enumerate()
                .map(|(i, info)| vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(vk::DescriptorType::STORAGE_BUFFER).buffer_info(info))
                .collect();
            writes.extend(images.iter().take(samplers).enumerate().map(|(s, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_binding((infos.len() + s) as u32)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(info)
            }));
            let push = ForwardParams { frame: FrameParams { light_capacity: self.capacity, count: index as u32, ..self.params.frame }, draw: draw.params };
            let bytes: &[u8] = bytemuck::bytes_of(&push);
            unsafe {
                if bound != variant {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipe.raw);
                    bound = variant;
                }
                gpu.ctx.push_descriptor.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::GRAPHICS, pipe.layout, 0, &writes);
                d.cmd_push_constants(cmd, pipe.layout, vk::ShaderStageFlags::FRAGMENT, 0, bytes);
                d.cmd_draw_indexed(cmd, draw.index_count, 1, first_index, 0, 0);
            }
        }
    }

    /// Begins dynamic rendering over the whole frame into `target` cleared to `clear`; the depth is
    /// loaded (`load_depth`, the forward pass) or cleared (the pre-pass).
    fn begin(&self, gpu: &Gpu, rec: &Recorder<'_>, scene: &SceneGpu<'_>, target: &Image, clear: u32, load_depth: bool) {
        let g = &self.params.frame.grid;
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: g.width, height: g.height } };
        let colours = [vk::RenderingAttachmentInfo::default()
            .image_view(target.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { uint32: [clear, 0, 0, 0] } })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(if load_depth { vk::AttachmentLoadOp::LOAD } else { vk::AttachmentLoadOp::CLEAR })
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
        let info = vk::RenderingInfo::default().render_area(area).layer_count(1).depth_attachment(&depth).color_attachments(&colours);
        let d = &gpu.ctx.device;
        unsafe {
            d.cmd_begin_rendering(rec.cmd, &info);
            d.cmd_set_viewport(rec.cmd, 0, &[vk::Viewport { x: 0.0, y: 0.0, width: g.width as f32, height: g.height as f32, min_depth: 0.0, max_depth: 1.0 }]);
            d.cmd_set_scissor(rec.cmd, 0, &[area]);
            let indices = if load_depth { &self.reversed } else { &scene.geometry.indices };
            d.cmd_bind_index_buffer(rec.cmd, indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    /// Copies a target into a buffer (one word per pixel).
    fn copy(&self, gpu: &Gpu, rec: &Recorder<'_>, img: &Image, buf: &Buffer) {
        let g = &self.params.frame.grid;
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(img.aspect()).layer_count(1))
            .image_extent(vk::Extent3D { width: g.width, height: g.height, depth: 1 });
        unsafe { gpu.ctx.device.cmd_copy_image_to_buffer(rec.cmd, img.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buf.raw, &[region]) };
        barrier(&gpu.ctx, rec.cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
    }

    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, scene: &SceneGpu<'_>, targets: &Targets, frame: &Buffer) -> VkResult<()> {
        let d = &gpu.ctx.device;
        let tests = vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let ds = vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ;
        let (top, transfer) = (vk::PipelineStageFlags::TOP_OF_PIPE, vk::PipelineStageFlags::TRANSFER);
        let out = (vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags::COLOR_ATTACHMENT_WRITE);
        rec.pass("depth pre-pass", |rec| {
            self.depth.transition(rec.cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, top, vk::AccessFlags::empty(), tests, ds);
            self.winner.transition(rec.cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, top, vk::AccessFlags::empty(), out.0, out.1);
            self.begin(gpu, rec, scene, &self.winner, u32::MAX, false);
            self.draw_all(gpu, rec, scene, &self.pipes.depth, &[], false);
            unsafe { d.cmd_end_rendering(rec.cmd) };
            self.winner.transition(rec.cmd, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, out.0, out.1, transfer, vk::AccessFlags::TRANSFER_READ);
            self.copy(gpu, rec, &self.winner, &self.winners);
            self.depth.transition(rec.cmd, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, tests, ds, transfer, vk::AccessFlags::TRANSFER_READ);
            self.copy(gpu, rec, &self.depth, &targets.depth_buf);
            self.depth.transition(rec.cmd, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, transfer, vk::AccessFlags::TRANSFER_READ, tests, ds);
            Ok(())
        })?;
        rec.pass("culling", |rec| {
            rec.fill(&self.heads, u32::MAX);
            rec.fill(&self.counters, 0);
            let g = &self.params.frame.grid;
            let p = TiledParams { frame: FrameParams { light_capacity: self.capacity, ..self.params.frame }, ..self.params };
            rec.dispatch(&gpu.kernels.forward_plus_cull, &[&targets.depth_buf, scene.lights, &self.counters, &self.heads, &self.nodes], &p, [g.tiles_x, g.tiles_y, 1])?;
            // The lists (and the counter) are read by the forward pass's fragments.
            let b = vk::MemoryBarrier::default().src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE).dst_access_mask(vk::AccessFlags::SHADER_READ);
            unsafe {
                d.cmd_pipeline_barrier(
                    rec.cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::FRAGMENT_SHADER,
                    vk::DependencyFlags::empty(),
                    &[b],
                    &[],
                    &[],
                )
            };
            Ok(())
        })?;
        rec.pass("shading", |rec| {
            self.colour.transition(rec.cmd, vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, top, vk::AccessFlags::empty(), out.0, out.1);
            self.begin(gpu, rec, scene, &self.colour, shaders::shading::BACKGROUND_RGBA8, true);
            self.draw_all(gpu, rec, scene, &self.pipes.shade, &[&self.heads, &self.nodes, scene.lights, scene.materials, &self.counters, &self.winners], true);
            unsafe { d.cmd_end_rendering(rec.cmd) };
            self.colour.transition(rec.cmd, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, out.0, out.1, transfer, vk::AccessFlags::TRANSFER_READ);
            self.copy(gpu, rec, &self.colour, frame);
            Ok(())
        })
    }
}

/// Renders the warm-up frame and `frames` timed ones; a frame whose lists overflowed the node
/// buffer grows it and re-runs.
pub fn run(gpu: &Gpu, p: &FrameParams, frames: u32, profiler: &mut Profiler, scene: &SceneGpu<'_>, targets: &Targets, frame: &Buffer) -> Result<Outcome> {
    let g = &p.grid;
    if g.tile_size > MAX_TILED_TILE {
        bail!("--tile-size {}: forward+ culls tiles of up to {MAX_TILED_TILE} px", g.tile_size);
    }
    if gpu.ctx.info.driver_name.to_lowercase().contains("llvmpipe") && p.num_lights > MAX_LIGHTS_LLVMPIPE {
        bail!("{} lights: on lavapipe (loop limiter) a forward+ fragment walks at most {MAX_LIGHTS_LLVMPIPE} list nodes", p.num_lights);
    }
    let mut fp = ForwardPlus::new(gpu, p, super::clustered_aabb::initial_capacity(p.num_lights), scene.indices)?;
    let mut out = Outcome { timings: Vec::new(), active: 0, refs: 0, max_list: 0, regrowths: 0, buffers: Vec::new() };
    let mut f = 0;
    while f <= frames {
        gpu.run(Some(&mut *profiler), |rec| fp.record(gpu, rec, scene, targets, frame))?;
        let c: Vec<u32> = fp.counters.read(COUNTERS as usize)?;
        out.refs = c[FP_COUNTER_NODES as usize];
        if out.refs > fp.capacity {
            out.regrowths += 1;
            if out.regrowths > 8 {
                bail!("the forward+ node buffer keeps growing ({} nodes): giving up", out.refs);
            }
            fp.capacity = out.refs.saturating_add(out.refs / 4);
            fp.nodes = ForwardPlus::node_buffer(gpu, fp.capacity).with_context(|| format!("growing the node buffer to {} nodes", fp.capacity))?;
            continue; // re-run this frame
        }
        if f > 0 || frames == 0 {
            out.timings.push(profiler.results()?);
        }
        f += 1;
    }
    out.max_list = fp.longest_list(g.tiles_x * g.tiles_y, out.refs)?;
    out.buffers = fp.sizes();
    Ok(out)
}

impl ForwardPlus {
    /// The longest tile list of the last frame, walked on the CPU from the read-back heads and
    /// nodes (node `n` = words `2n` light, `2n + 1` next; at most `refs` steps per list).
    fn longest_list(&mut self, tiles: u32, refs: u32) -> Result<u32> {
        let heads: Vec<u32> = self.heads.read(tiles as usize)?;
        let nodes: Vec<u32> = self.nodes.read(2 * refs as usize)?;
        let mut longest = 0;
        for &h in &heads {
            let (mut n, mut len) = (h, 0u32);
            while n != shaders::shading::NO_NODE && n < refs && len <= refs {
                len += 1;
                n = nodes[2 * n as usize + 1];
            }
            longest = longest.max(len);
        }
        Ok(longest)
    }
}
