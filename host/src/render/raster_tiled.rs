//! `raster-tiled`: tiled deferred shading whose tile lists the rasteriser builds (kernels,
//! steps, paper and bounds: `shaders::raster_tiled`). After the G-buffer: the tiles' depth
//! bounds (compute), each light's quad of tiles (compute), the quads drawn into a target of one
//! pixel per tile whose fragments test their light against their tile and append it to the
//! tile's list (raster), then a per-pixel shading over the tile's list (compute).
//!
//! The lists are fixed-capacity arrays, one per tile; a frame whose longest list passed the
//! capacity grows them (the longest count + 25 %) and the frame loop renders it again, so no
//! light is ever dropped. Scenes with transparent draws are refused (the lists cover the opaque
//! pixels' depth ranges only).
//!
//! Memory: 12 B per tile (depth bounds, count) + 4 B per list entry (tiles × capacity; the first
//! capacity is min(lights, 256)), 16 B per light (its quad), a 4-byte depth target of one pixel
//! per tile.
use super::technique::{boxed, grown_capacity, Description, FrameInputs, LightCost, LightingTechnique, ListStats, TransparentDraws};
use crate::gpu::{Gpu, LightCompute, LightRaster};
use crate::vk::{Attachment, Binding, Blend, Buffer, ComputePipeline, DepthTest, Image, ImageUse, LightTyped, Load, Recorder, TargetFormat, VkResult};
use anyhow::{bail, Context as _, Result};
use shaders::layout::FrameParams;
use shaders::raster_tiled::{handles, DEPTH_BOUND_WORDS, RECT_WORDS, VERTICES_PER_LIGHT};
use shaders::tile_cull::MAX_TILED_TILE;

pub const RASTER_TILED: Description = Description {
    name: "raster-tiled",
    summary: "Tiled deferred with raster-built tile lists (Douda's thesis, §4): light quads drawn into a one-pixel-per-tile target, each fragment appending its light to its tile's list.",
    create: |gpu, f| boxed(RasterTiled::new(gpu, f)),
    transparent: TransparentDraws::Refused,
    gbuffer: true,
    raster_passes: &["raster assignment"],
    cost: LightCost::Culled,
    // The depth bounds are `tiled`'s workgroup reduction: tiles of at most 32 px.
    max_tile: Some(MAX_TILED_TILE),
    llvmpipe_lights: super::technique::llvmpipe_chunked_lights,
    knobs: &[],
    own_kernels: handles::COMPUTE,
    own_raster: handles::RASTER,
    msaa: true,
    light_words: RECT_WORDS,
    shadows: true,
};

/// Entries of each tile's first list.
const FIRST_CAPACITY: u32 = 256;

pub struct RasterTiled {
    tile_depths_pipe: ComputePipeline<FrameParams>,
    rects_pipe: LightCompute<FrameParams>,
    append_pipe: LightRaster<FrameParams>,
    shade_pipes: [LightCompute<FrameParams>; 2],
    /// The MSAA edge pass (`--msaa` above 1).
    edge_pipes: Option<[LightCompute<FrameParams>; 2]>,
    tiles: u32,
    /// List entries per tile.
    capacity: u32,
    tile_depths: Buffer,
    counts: Buffer,
    lists: Buffer,
    rects: Buffer,
    /// The raster target: one pixel per tile (depth only, untested).
    target: Image,
    /// `(light references, longest list)` of the last frame.
    last: (u32, u32),
}

impl RasterTiled {
    pub fn new(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        let (ctx, g) = (&gpu.ctx, &f.params.grid);
        if g.tile_size > MAX_TILED_TILE {
            bail!("--tile-size {}: raster-tiled bounds tiles of up to {MAX_TILED_TILE} px (one workgroup of 256 per tile)", g.tile_size);
        }
        let tiles = g.tiles_x * g.tiles_y;
        let lights = f.params.num_lights;
        let capacity = FIRST_CAPACITY.min(lights).max(1);
        let words = |name: &str, n: u64| -> Result<Buffer> {
            crate::vk::memory::check_range(ctx, name, 4 * n)?;
            Ok(Buffer::storage(ctx, name, 4 * n.max(1))?)
        };
        let raster = &gpu.light_graphics;
        Ok(Self {
            tile_depths_pipe: ComputePipeline::new(ctx, &gpu.compute_module, handles::TILE_DEPTHS)?,
            rects_pipe: LightTyped::compute(&gpu.light_compute, handles::LIGHT_RECTS),
            append_pipe: LightTyped::raster(raster, handles::APPEND, &[] as &[(TargetFormat, Blend)], DepthTest::Off),
            shade_pipes: handles::SHADE.map(|k| LightTyped::compute(&gpu.light_compute, k)),
            edge_pipes: super::msaa::edge_pipelines(gpu, f.msaa, handles::SHADE_EDGES),
            tiles,
            capacity,
            tile_depths: words("raster-tiled tile depth bounds", (DEPTH_BOUND_WORDS * tiles) as u64)?,
            counts: words("raster-tiled list counts", tiles as u64)?,
            lists: words("raster-tiled lists", tiles as u64 * capacity as u64).context("allocating the tile lists")?,
            rects: words("raster-tiled light quads", RECT_WORDS as u64 * lights as u64)?,
            target: Image::target(ctx, "raster-tiled tile target", g.tiles_x, g.tiles_y, TargetFormat::Depth32)?,
            last: (0, 0),
        })
    }

    /// The frame's parameters with the lists' capacity.
    fn params(&self, f: &FrameInputs<'_>) -> FrameParams {
        FrameParams { light_capacity: self.capacity, ..f.params }
    }
}

impl LightingTechnique for RasterTiled {
    fn record(&self, _gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let (t, p) = (f.targets, self.params(f));
        let g = &p.grid;
        rec.pass("tile depth bounds", |rec| rec.dispatch(&self.tile_depths_pipe, &[&t.depth_buf, &self.tile_depths, &self.counts], &p, [g.tiles_x, g.tiles_y, 1]))?;
        rec.pass("light quads", |rec| rec.dispatch_linear(self.rects_pipe.get(p.effects)?, &[f.lights, &self.rects], &FrameParams { count: p.num_lights, ..p }, p.num_lights))?;
        rec.pass("raster assignment", |rec| {
            rec.draws_read_kernel_writes();
            rec.fragments_read_earlier_writes();
            rec.transition(&self.target, ImageUse::Undefined, ImageUse::DepthTarget);
            rec.begin_drawing(&[], Attachment { image: &self.target, load: Load::ClearDepth(0.0) });
            let bindings = [&self.rects, &self.tile_depths, f.lights, &self.counts, &self.lists].map(Binding::Buffer);
            rec.draw(self.append_pipe.get(p.effects)?, &bindings, &p, VERTICES_PER_LIGHT * p.num_lights)?;
            rec.end_rendering();
            rec.kernels_read_fragment_writes();
            Ok(())
        })?;
        let [slots, maps] = f.shadow_buffers();
        rec.pass("shading", |rec| {
            rec.dispatch_linear(
                super::shading_pipeline(&self.shade_pipes, &p)?,
                &[&t.depth_buf, &t.normal_buf, &t.albedo_buf, f.lights, f.materials, f.frame, f.bounds, &self.counts, &self.lists, slots, maps],
                &p,
                p.count,
            )
        })?;
        match (f.msaa, &self.edge_pipes) {
            (Some(m), Some(pipes)) => m.record_edges(rec, pipes, &p, &[&t.depth_buf, &t.normal_buf, &t.albedo_buf, f.lights, f.materials, f.frame, f.bounds, &self.counts, &self.lists]),
            _ => Ok(()),
        }
    }

    /// Reads the tiles' counts; grows the lists past the longest when it passed the capacity.
    fn grow_if_needed(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let counts: Vec<u32> = self.counts.read(self.tiles as usize)?;
        let longest = counts.iter().copied().max().unwrap_or(0);
        self.last = (counts.iter().fold(0u32, |a, &c| a.saturating_add(c)), longest);
        if longest <= self.capacity {
            return Ok(None);
        }
        let grown = grown_capacity(longest);
        let bytes = 4 * self.tiles as u64 * grown as u64;
        crate::vk::memory::check_range(&gpu.ctx, "raster-tiled lists", bytes)
            .and_then(|()| Buffer::storage(&gpu.ctx, "raster-tiled lists", bytes))
            .map(|b| self.lists = b)
            .with_context(|| format!("growing the tile lists to {grown} lights per tile ({} tiles)", self.tiles))?;
        self.capacity = grown;
        Ok(Some(format!("tile lists to {grown} lights per tile")))
    }

    fn stats(&mut self) -> Result<ListStats> {
        Ok(ListStats { light_refs: self.last.0, max_list: self.last.1, ..ListStats::default() })
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        [&self.tile_depths, &self.counts, &self.lists, &self.rects].iter().map(|b| (b.name.clone(), b.size)).collect()
    }

    fn tile_lists(&mut self) -> Result<Option<Vec<Vec<u32>>>> {
        let counts: Vec<u32> = self.counts.read(self.tiles as usize)?;
        let lists: Vec<u32> = self.lists.read((self.tiles * self.capacity) as usize)?;
        Ok(Some(
            counts
                .iter()
                .enumerate()
                .map(|(t, &n)| {
                    let start = t * self.capacity as usize;
                    let mut l = lists[start..start + n.min(self.capacity) as usize].to_vec();
                    l.sort_unstable();
                    l
                })
                .collect(),
        ))
    }
}
