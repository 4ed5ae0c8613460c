//! Host side of `forward-plus` (algorithm: `shaders::forward_plus`, shaders:
//! `shaders::raster_forward`; Harada et al. 2012, "Forward+"):
//! 1. **depth pre-pass** (raster) → depth target and each pixel's winning draw; the depth is
//!    copied into the G-buffer's depth buffer, so CPU checks and `--stats` read it as for every
//!    other technique;
//! 2. **culling** — tiled culling (per-tile depth bounds and frustum) into per-tile lists, in the
//!    layout `--fp-lists` picks ([`TileLists`]):
//!    * `linked`: head buffer + node buffer + an atomic node counter;
//!    * `array`: range buffer (`(offset, count)` per tile) + index buffer + an atomic counter;
//!      each culling workgroup writes its tile's array itself (`shaders::forward_plus` says why);
//! 3. **shading** (raster) — forward pass with depth test EQUAL over the pre-pass's depth, each
//!    fragment walking its tile's linked list or reading its tile's index range; the colour
//!    target is copied into the frame.
//!
//! Scenes with shadow-casting lights record the cube shadow maps (`shadow_maps.rs`) between
//! steps 1 and 2: their receivers are the pre-pass's depths (copied into the G-buffer's depth
//! buffer in step 1, as the deferred techniques' G-buffer pass leaves them), and step 3's
//! fragments look each casting light's visibility up as every compute-shaded technique does.
//!
//! Scenes with transparent draws (`transparent.rs`) add, after step 1, a raster pre-pass of the
//! transparent draws against the pre-pass depth that widens each tile's depth range to its
//! transparent fragments (`TILE_DEPTH_WORDS` per tile); step 2 then culls with the
//! `_widened` kernel, whose tile bounds span the opaque depths and those ranges together (one list
//! per tile serves both: Harada et al. keep a second list for transparent geometry; one widened
//! list is conservative for both and costs no second culling pass). After step 3 the transparent
//! pass reads the tile lists and its resolve composites into the frame.
//!
//! With `--msaa N` (N > 1; `shaders::forward_msaa` has the steps) step 1 draws at `N` samples
//! and records each sample's winning triangle, a gather puts depths and winners into per-sample
//! planes, step 3's fragments write their samples' colours, normal and albedo at `N` samples, and
//! a resolve applies the deferred techniques' edge rule: the frame equals `deferred --msaa N`.
//! 60 B per sample ([`shaders::forward_msaa::BYTES_PER_SAMPLE`]); none of it with one sample.
//!
//! The node or index buffer's capacity is the one view-dependent size: the culling counter ends
//! at the light references the frame needs; if that exceeds the buffer, it grows (need + 25 %)
//! and the frame re-runs.
//!
//! Memory: `linked` heads 4 B per tile and nodes 8 B per light reference, `array` ranges 8 B per
//! tile and indices 4 B per light reference; both the reversed index list, and a depth, a colour
//! and a winning-draw target (4 B per pixel each) plus the winners' buffer copy; with transparent
//! draws 8 B per tile of depth ranges and the transparent pass's buffers.
use super::technique::{boxed, grew_together, grown_capacity, initial_list_capacity, Description, FrameInputs, Knob, LightCost, LightingTechnique, ListStats, TransparentDraws};
use super::transparent::{ClusterInputs, Marks, OpaqueDepth, Transparency, TransparencyStats};
use super::Draw;
use crate::gpu::{Gpu, LightRaster, ALBEDO_FORMAT, FORWARD_COLOUR_FORMAT};
use crate::vk::{Attachment, Blend, Buffer, ComputePipeline, DepthTest, GraphicsPipeline, Image, ImageUse, LightTyped, Load, Recorder, TargetFormat, VkResult};
use shaders::kernels;
use anyhow::{bail, Context as _, Result};
use shaders::forward_plus::MAX_LIGHTS_LLVMPIPE;
use shaders::shading::NO_NODE;
use shaders::layout::{ForwardParams, FrameParams, TiledParams, COUNTERS, FP_COUNTER_REFS, TILE_DEPTH_WORDS, TRANSPARENT_TILE_ARRAYS, TRANSPARENT_TILE_LINKED};
use shaders::tile_cull::{MAX_TILED_TILE, MODE_TILED};

/// Layout of Forward+'s per-tile light lists (`render --fp-lists`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TileLists {
    /// Linked lists built with atomics (a node per light reference: light, next); each fragment
    /// walks its tile's list, one dependent load per light.
    Linked,
    /// Contiguous arrays written by the culling workgroups (an index per light reference, an
    /// `(offset, count)` per tile); each fragment reads its tile's index range. The default: on
    /// the H200 (Sponza 1080p) its frames take 15.0 / 32.9 ms at 1k / 100k lights against the
    /// linked lists' 15.9 / 36.6 ms. (On lavapipe the linked lists once took 61 s for a lit
    /// 480×270 frame against 2.2 s, masked-off lanes walking to the driver's loop limit; since a
    /// self-linked node ends the walk both take about 4 s for the city with 1000 lights there,
    /// wall time of the whole command.)
    #[default]
    Array,
}

impl TileLists {
    /// Both layouts.
    pub const ALL: [TileLists; 2] = [TileLists::Linked, TileLists::Array];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Linked => "linked",
            Self::Array => "array",
        }
    }

    /// Index of the layout's pipelines (`Kernels::forward_plus_cull`, `RasterPipelines::forward_shade`).
    fn index(self) -> usize {
        match self {
            Self::Linked => 0,
            Self::Array => 1,
        }
    }

    /// Words per tile of the tile buffer (a head; an offset and a count) and per light reference
    /// of the entry buffer (light and next; an index).
    fn words(self) -> (u64, u64) {
        match self {
            Self::Linked => (1, 2),
            Self::Array => (2, 1),
        }
    }

    /// `TransparentDraw::lists` of the layout.
    fn transparent_lists(self) -> u32 {
        match self {
            Self::Linked => TRANSPARENT_TILE_LINKED,
            Self::Array => TRANSPARENT_TILE_ARRAYS,
        }
    }

    /// Names of the tile buffer and the entry buffer.
    fn buffer_names(self) -> (&'static str, &'static str) {
        match self {
            Self::Linked => ("tile list heads", "light list nodes"),
            Self::Array => ("tile light ranges", "tile light indices"),
        }
    }
}

/// What scenes with transparent draws add: the transparent pass, the tiles' transparent depth
/// ranges (`Kernels::forward_plus_cull_widened` culls with the tiles' bounds widened to them).
struct TransparentTiles {
    pass: Transparency,
    depths: Buffer,
}

pub const FORWARD_PLUS: Description = Description {
    name: "forward-plus",
    summary: "Forward+ (Harada et al. 2012): depth pre-pass, tiled culling into per-tile linked lists or arrays (`--fp-lists`), forward raster shading with depth test EQUAL.",
    create: |gpu, f| boxed(ForwardPlus::new(gpu, f)),
    transparent: TransparentDraws::Drawn,
    gbuffer: false,
    raster_passes: &["depth pre-pass", "shading"],
    cost: LightCost::Culled,
    max_tile: Some(MAX_TILED_TILE),
    llvmpipe_lights: |_| MAX_LIGHTS_LLVMPIPE,
    knobs: &[Knob::FpLists],
    own_kernels: &[],
    own_raster: &[],
    msaa: true,
    light_words: 0,
    shadows: true,
};

/// What `--msaa N` (N > 1) adds (`shaders::forward_msaa`): the pre-pass's and the forward pass's
/// targets at `N` samples, their pipelines, the gather, the resolve and its edge count.
struct Multisampled {
    depth: Image,
    /// The winning triangle of each sample: its draw and primitive, as floats.
    winner: Image,
    /// Each sample's edge colour and its fragment's centre colour (`forward_msaa::colour_texel`).
    colour: Image,
    /// The normal and albedo the G-buffer would hold (the resolve's edge rule reads them).
    normal: Image,
    albedo: Image,
    /// Edge pixels of the last frame (one word).
    edges: Buffer,
    depth_pipes: [GraphicsPipeline<ForwardParams>; 2],
    shade_pipes: [LightRaster<ForwardParams>; 3],
    gather: ComputePipeline<FrameParams>,
    resolve: ComputePipeline<FrameParams>,
}

impl Multisampled {
    fn new(gpu: &Gpu, lists: TileLists, w: u32, h: u32, samples: u32) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let depth = |h: shaders::kernels::RasterKernel<ForwardParams>| GraphicsPipeline::multisampled(ctx, &gpu.graphics_module, h.fragment, h, &[TargetFormat::Rg32Float], DepthTest::NearestWrites, samples);
        let d = &kernels::FORWARD_DEPTH_MS;
        let colours = [(TargetFormat::Rgba32Float, Blend::Replace), (super::msaa::NORMAL_FORMAT, Blend::Replace), (ALBEDO_FORMAT, Blend::Replace)];
        let target = |name: &str, format: TargetFormat| Image::multisampled_target(ctx, name, w, h, format, samples);
        Ok(Self {
            depth: target("forward+ depth (samples)", TargetFormat::Depth32)?,
            winner: target("forward+ winning triangles (samples)", TargetFormat::Rg32Float)?,
            colour: target("forward+ colour (samples)", TargetFormat::Rgba32Float)?,
            normal: target("forward+ normal (samples)", super::msaa::NORMAL_FORMAT)?,
            albedo: target("forward+ albedo (samples)", ALBEDO_FORMAT)?,
            edges: Buffer::storage(ctx, "forward+ edge count", 4)?,
            depth_pipes: [depth(d[0])?, depth(d[1])?],
            shade_pipes: kernels::FORWARD_SHADE_MS[lists.index()].map(|k| LightTyped::raster_multisampled(&gpu.light_graphics, k, &colours, DepthTest::EqualReadOnly, samples)),
            gather: ComputePipeline::new(ctx, &gpu.compute_module, kernels::FORWARD_GATHER)?,
            resolve: ComputePipeline::new(ctx, &gpu.compute_module, kernels::FORWARD_RESOLVE)?,
        })
    }
}

pub struct ForwardPlus {
    depth: Image,
    colour: Image,
    /// Pre-pass colour target: the index of the draw that wins each pixel (and its copy).
    winner: Image,
    winners: Buffer,
    /// The index list with its triangles in reverse order (see [`ForwardPlus::draw_all`]).
    reversed: Buffer,
    /// Index count of the merged list.
    total_indices: u32,
    lists: TileLists,
    /// Per tile: the list's head (`linked`) or its `(offset, count)` (`array`).
    tiles: Buffer,
    /// Per light reference: a node (`linked`) or a light index (`array`).
    entries: Buffer,
    counters: Buffer,
    /// Light references `entries` holds.
    capacity: u32,
    params: TiledParams,
    /// Light references the last frame needed.
    last_refs: u32,
    /// Scenes with transparent draws.
    transparent: Option<TransparentTiles>,
    /// `--msaa` above 1.
    msaa: Option<Multisampled>,
}

impl ForwardPlus {
    /// Checks the tile size and, on llvmpipe, the light count (its loop limiter), and allocates.
    pub fn new(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        let frame = &f.params;
        let g = &frame.grid;
        if g.tile_size > MAX_TILED_TILE {
            bail!("--tile-size {}: forward+ culls tiles of up to {MAX_TILED_TILE} px", g.tile_size);
        }
        if gpu.ctx.info.is_llvmpipe() && frame.num_lights > MAX_LIGHTS_LLVMPIPE {
            bail!("{} lights: on lavapipe (loop limiter) a forward+ fragment shades at most {MAX_LIGHTS_LLVMPIPE} lights of its tile's list", frame.num_lights);
        }
        let ctx = &gpu.ctx;
        let (w, h) = (g.width, g.height);
        let capacity = initial_list_capacity(frame.num_lights);
        let lists = f.settings.fp_lists;
        let tile_bytes = 4 * lists.words().0 * (g.tiles_x * g.tiles_y) as u64;
        let reversed: Vec<u32> = f.indices.chunks_exact(3).rev().flatten().copied().collect();
        let transparent = match Transparency::new(f, gpu, Some(lists.transparent_lists())).context("creating the transparent pass")? {
            None => None,
            Some(pass) => {
                let depths = Buffer::storage(ctx, "tile transparent depths", 4 * TILE_DEPTH_WORDS as u64 * (g.tiles_x * g.tiles_y) as u64)?;
                Some(TransparentTiles { pass, depths })
            }
        };
        let samples = g.samples.max(1);
        let most = shaders::forward_msaa::MAX_DRAWS as u64;
        let largest = f.geometry.draws.iter().map(|d| d.index_count as u64 / 3).max().unwrap_or(0);
        if samples > 1 && (f.geometry.draws.len() as u64 >= most || largest >= most) {
            bail!(
                "{} draws, the largest of {largest} triangles: with --msaa forward+ records each sample's draw and triangle in a float target, exact below {most} of each",
                f.geometry.draws.len()
            );
        }
        let made = (|| -> VkResult<Self> {
            Ok(Self {
                depth: Image::target(ctx, "forward+ depth", w, h, TargetFormat::Depth32)?,
                colour: Image::target(ctx, "forward+ colour", w, h, FORWARD_COLOUR_FORMAT)?,
                winner: Image::target(ctx, "forward+ winning draw", w, h, FORWARD_COLOUR_FORMAT)?,
                // One word per pixel (the winning draw), or two per sample with MSAA (draw and
                // primitive, `shaders::forward_msaa`).
                winners: Buffer::storage(ctx, "winning draws", if samples > 1 { 8 } else { 4 } * w as u64 * h as u64 * samples as u64)?,
                reversed: Buffer::indices(ctx, "reversed indices", &reversed)?,
                total_indices: reversed.len() as u32,
                lists,
                tiles: Buffer::storage(ctx, lists.buffer_names().0, tile_bytes)?,
                entries: Self::entry_buffer(gpu, lists, capacity)?,
                counters: Buffer::storage(ctx, "counters", 4 * COUNTERS as u64)?,
                capacity,
                params: TiledParams { frame: *frame, mode: MODE_TILED, _pad: [0; 3] },
                last_refs: 0,
                transparent,
                msaa: if samples > 1 { Some(Multisampled::new(gpu, lists, w, h, samples)?) } else { None },
            })
        })();
        made.context("allocating the forward+ buffers")
    }

    /// The node or index buffer for `capacity` light references.
    fn entry_buffer(gpu: &Gpu, lists: TileLists, capacity: u32) -> VkResult<Buffer> {
        let (name, bytes) = (lists.buffer_names().1, 4 * lists.words().1 * capacity as u64);
        crate::vk::memory::check_range(&gpu.ctx, name, bytes)?;
        Buffer::storage(&gpu.ctx, name, bytes)
    }

    /// Draws every draw of the scene with `pipes` (variant per draw: see `shaders::kernels`'
    /// `FORWARD_DEPTH` and `FORWARD_SHADE`), binding `extra` storage buffers after the vertex
    /// stage's and the draw's textures after them.
    ///
    /// The one-sample forward pass (`reversed`, over [`ForwardPlus::reversed`]) draws everything
    /// in reverse order: of coplanar fragments, which all pass EQUAL, the last one drawn — the
    /// first in scene order, the G-buffer's — stays. The multisampled one keeps the scene order:
    /// its fragments write only the samples the pre-pass gave their triangle.
    fn draw_all(&self, rec: &mut Recorder<'_>, f: &FrameInputs<'_>, pipes: &[&GraphicsPipeline<ForwardParams>], extra: &[&Buffer], forward: bool, reversed: bool) -> VkResult<()> {
        let draws: Vec<(usize, &Draw)> = f.geometry.draws.iter().enumerate().filter(|(_, d)| d.index_count > 0).collect();
        let order: Vec<(usize, &Draw)> = if reversed { draws.into_iter().rev().collect() } else { draws };
        for (index, draw) in order {
            let first_index = if reversed { self.total_indices - draw.first_index - draw.index_count } else { draw.first_index };
            // Pre-pass: opaque (0) or alpha-tested (1); forward: the G-buffer's variant index.
            let (variant, textures) = match (forward, draw.variant()) {
                (false, 2) => (1, 2),
                (false, _) => (0, 0),
                (true, v) => (v, v),
            };
            let bindings = f.draw_bindings(extra, draw, textures);
            let push = ForwardParams { frame: FrameParams { light_capacity: self.capacity, count: index as u32, ..self.params.frame }, draw: draw.params };
            rec.draw_indexed(pipes[variant], &bindings, &push, first_index, draw.index_count)?;
        }
        Ok(())
    }

    /// Each tile's light list of the last frame, read back: walked from the heads and nodes
    /// (`linked`: node `n` = words `2n` light, `2n + 1` next; at most `refs` steps per list), or
    /// the tile's range of the indices (`array`), clamped to the `refs` entries written.
    fn read_tile_lists(&mut self, refs: u32) -> Result<Vec<Vec<u32>>> {
        let g = &self.params.frame.grid;
        let tiles = (g.tiles_x * g.tiles_y) as usize;
        let (tile_words, entry_words) = self.lists.words();
        let per_tile: Vec<u32> = self.tiles.read(tile_words as usize * tiles)?;
        let entries: Vec<u32> = self.entries.read(entry_words as usize * refs as usize)?;
        Ok(match self.lists {
            TileLists::Linked => per_tile
                .iter()
                .map(|&h| {
                    let (mut n, mut list) = (h, Vec::new());
                    while n != NO_NODE && n < refs && list.len() <= refs as usize {
                        list.push(entries[2 * n as usize]);
                        n = entries[2 * n as usize + 1];
                    }
                    list
                })
                .collect(),
            TileLists::Array => per_tile
                .chunks_exact(2)
                .map(|r| {
                    let end = (r[0] as u64 + r[1] as u64).min(refs as u64) as usize;
                    entries[(r[0] as usize).min(end)..end].to_vec()
                })
                .collect(),
        })
    }
}

impl LightingTechnique for ForwardPlus {
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        if let Some(m) = &self.msaa {
            return self.record_multisampled(gpu, rec, f, m);
        }
        let raster = &gpu.raster;
        rec.pass("depth pre-pass", |rec| {
            rec.transition(&self.depth, ImageUse::Undefined, ImageUse::DepthTarget);
            rec.transition(&self.winner, ImageUse::Undefined, ImageUse::ColourTarget);
            let winner = Attachment { image: &self.winner, load: Load::ClearU32([u32::MAX, 0, 0, 0]) };
            rec.begin_rendering(&[winner], Attachment { image: &self.depth, load: Load::ClearDepth(0.0) }, &f.geometry.indices);
            self.draw_all(rec, f, &raster.forward_depth.each_ref(), &[], false, false)?;
            rec.end_rendering();
            rec.transition(&self.winner, ImageUse::ColourTarget, ImageUse::CopySource);
            rec.transition(&self.depth, ImageUse::DepthTarget, ImageUse::CopySource);
            rec.copy_to_buffers(&[(&self.winner, &self.winners), (&self.depth, &f.targets.depth_buf)]);
            rec.transition(&self.depth, ImageUse::CopySource, ImageUse::DepthTarget);
            match &self.transparent {
                Some(t) => {
                    rec.fill(&t.depths, 0);
                    let m = Marks { stage: self.lists.transparent_lists(), marks: &t.depths, page_table: None };
                    t.pass.record_clusters(rec, f, &self.params.frame, OpaqueDepth { image: &self.depth, from: ImageUse::DepthTarget }, &m)
                }
                None => Ok(()),
            }
        })?;
        // The receivers of the shadow maps are the pre-pass's depths, now in the G-buffer's
        // depth buffer; the culling's barrier puts the maps before the forward pass's fragments.
        f.record_shadow_maps(rec)?;
        self.record_culling(gpu, rec, f)?;
        rec.pass("shading", |rec| {
            rec.transition(&self.colour, ImageUse::Undefined, ImageUse::ColourTarget);
            let colour = Attachment { image: &self.colour, load: Load::ClearU32([shaders::shading::BACKGROUND_RGBA8, 0, 0, 0]) };
            rec.begin_rendering(&[colour], Attachment { image: &self.depth, load: Load::Keep }, &self.reversed);
            let [slots, maps] = f.shadow_buffers();
            let extra = [&self.tiles, &self.entries, f.lights, f.materials, &self.counters, &self.winners, slots, maps];
            // The variants for the frame's light types.
            let [a, b, c] = raster.forward_shade[self.lists.index()].each_ref().map(|v| v.get(self.params.frame.effects));
            self.draw_all(rec, f, &[a?, b?, c?], &extra, true, true)?;
            rec.end_rendering();
            rec.transition(&self.colour, ImageUse::ColourTarget, ImageUse::CopySource);
            rec.copy_to_buffers(&[(&self.colour, f.frame)]);
            Ok(())
        })?;
        let Some(t) = &self.transparent else { return Ok(()) };
        let frame = FrameParams { light_capacity: self.capacity, ..self.params.frame };
        let lists = ClusterInputs::tiles(&self.counters, &self.tiles, &self.entries);
        t.pass.record_shade(rec, f, &frame, OpaqueDepth { image: &self.depth, from: ImageUse::DepthTarget }, Some(&lists))
    }

    fn grow_if_needed(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let nodes = Transparency::grow(self.transparent.as_mut().map(|t| &mut t.pass), &gpu.ctx)?;
        Ok(grew_together(nodes, self.grow_entries(gpu)?))
    }

    fn msaa_bytes_per_sample(&self) -> Option<u64> {
        Some(shaders::forward_msaa::BYTES_PER_SAMPLE)
    }

    fn msaa_edge_pixels(&mut self) -> VkResult<Option<u32>> {
        match &mut self.msaa {
            Some(m) => Ok(Some(m.edges.read::<u32>(1)?[0])),
            None => Ok(None),
        }
    }

    fn transparency(&self) -> Option<TransparencyStats> {
        self.transparent.as_ref().map(|t| t.pass.stats())
    }

    fn stats(&mut self) -> Result<ListStats> {
        let refs = self.last_refs;
        let max_list = self.read_tile_lists(refs)?.iter().map(|l| l.len() as u32).max().unwrap_or(0);
        Ok(ListStats { light_refs: refs, max_list, ..ListStats::default() })
    }

    fn tile_lists(&mut self) -> Result<Option<Vec<Vec<u32>>>> {
        Ok(Some(self.read_tile_lists(self.last_refs)?))
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        let g = &self.params.frame.grid;
        let targets = 12 * g.width as u64 * g.height as u64;
        let mut v = vec![
            (self.tiles.name.clone(), self.tiles.size),
            (self.entries.name.clone(), self.entries.size),
            (self.counters.name.clone(), self.counters.size),
            (self.winners.name.clone(), self.winners.size),
            (self.reversed.name.clone(), self.reversed.size),
            ("forward+ targets".into(), targets),
        ];
        if self.msaa.is_some() {
            // The targets at `N` samples (the planes are in `winners` and the G-buffer's depth).
            v.push(("forward+ targets (samples)".into(), g.samples as u64 * g.width as u64 * g.height as u64 * (shaders::forward_msaa::BYTES_PER_SAMPLE - 8)));
            v.push(("forward+ edge count".into(), 4));
        }
        if let Some(t) = &self.transparent {
            v.push((t.depths.name.clone(), t.depths.size));
            v.extend(t.pass.buffers());
        }
        v
    }
}

impl ForwardPlus {
    /// Step 2: the tile lists (the tile bounds span every sample with `--msaa`).
    fn record_culling(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        rec.pass("culling", |rec| {
            if self.lists == TileLists::Linked {
                rec.fill(&self.tiles, NO_NODE);
            }
            rec.fill(&self.counters, 0);
            let g = &self.params.frame.grid;
            let p = TiledParams { frame: FrameParams { light_capacity: self.capacity, ..self.params.frame }, ..self.params };
            let buffers = [&f.targets.depth_buf, f.lights, &self.counters, &self.tiles, &self.entries];
            match &self.transparent {
                None => rec.dispatch(gpu.kernels.forward_plus_cull[self.lists.index()].get(p.frame.effects)?, &buffers, &p, [g.tiles_x, g.tiles_y, 1])?,
                Some(t) => {
                    let widened: Vec<&Buffer> = buffers.into_iter().chain([&t.depths]).collect();
                    rec.dispatch(gpu.kernels.forward_plus_cull_widened[self.lists.index()].get(p.frame.effects)?, &widened, &p, [g.tiles_x, g.tiles_y, 1])?
                }
            }
            // The lists (and the counter) are read by the forward pass's fragments; every
            // workgroup writes its tile's range (`array`), so only the heads need a fill.
            rec.fragments_read_earlier_writes();
            Ok(())
        })
    }

    /// The frame at `N` samples (`shaders::forward_msaa` steps 1–5); scenes with transparent
    /// draws are refused with MSAA before this is created.
    fn record_multisampled(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>, m: &Multisampled) -> VkResult<()> {
        let p = self.params.frame;
        rec.pass("depth pre-pass", |rec| {
            rec.transition(&m.depth, ImageUse::Undefined, ImageUse::DepthTarget);
            rec.transition(&m.winner, ImageUse::Undefined, ImageUse::ColourTarget);
            let winner = Attachment { image: &m.winner, load: Load::ClearF32([-1.0; 4]) };
            rec.begin_rendering(&[winner], Attachment { image: &m.depth, load: Load::ClearDepth(0.0) }, &f.geometry.indices);
            self.draw_all(rec, f, &m.depth_pipes.each_ref(), &[], false, false)?;
            rec.end_rendering();
            rec.transition(&m.winner, ImageUse::ColourTarget, ImageUse::KernelRead);
            rec.transition(&m.depth, ImageUse::DepthTarget, ImageUse::KernelRead);
            rec.dispatch_linear_reading(&m.gather, &[&f.targets.depth_buf, &self.winners], &[&m.depth, &m.winner], &p, p.count)?;
            rec.transition(&m.depth, ImageUse::KernelRead, ImageUse::DepthTarget);
            Ok(())
        })?;
        self.record_culling(gpu, rec, f)?;
        rec.pass("shading", |rec| {
            let targets = [&m.colour, &m.normal, &m.albedo];
            for t in targets {
                rec.transition(t, ImageUse::Undefined, ImageUse::ColourTarget);
            }
            // Sky samples keep the background: its linear colour as the edge colour, its word as
            // the centre colour (`forward_msaa::colour_texel`).
            let bg = shaders::shading::BACKGROUND_RGBA8;
            let background = shaders::forward_msaa::colour_texel(shaders::lighting::decode_srgb8(bg), bg).to_array();
            let attachments = [
                Attachment { image: &m.colour, load: Load::ClearF32(background) },
                Attachment { image: &m.normal, load: Load::ClearF32([0.0; 4]) },
                Attachment { image: &m.albedo, load: Load::ClearF32([0.0; 4]) },
            ];
            rec.begin_rendering(&attachments, Attachment { image: &m.depth, load: Load::Keep }, &f.geometry.indices);
            let extra = [&self.tiles, &self.entries, f.lights, f.materials, &self.counters, &self.winners, &f.targets.depth_buf];
            let [a, b, c] = m.shade_pipes.each_ref().map(|v| v.get(p.effects));
            self.draw_all(rec, f, &[a?, b?, c?], &extra, true, false)?;
            rec.end_rendering();
            for t in targets {
                rec.transition(t, ImageUse::ColourTarget, ImageUse::KernelRead);
            }
            rec.fill(&m.edges, 0);
            rec.dispatch_linear_reading(&m.resolve, &[f.frame, &f.targets.depth_buf, &m.edges], &targets, &p, p.count)
        })
    }
}

impl ForwardPlus {
    /// Reads the counter; grows the node or index buffer to the references needed + 25 % when
    /// they did not fit.
    fn grow_entries(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let c: Vec<u32> = self.counters.read(COUNTERS as usize)?;
        self.last_refs = c[FP_COUNTER_REFS as usize];
        if self.last_refs <= self.capacity {
            return Ok(None);
        }
        let grown = grown_capacity(self.last_refs);
        let name = self.lists.buffer_names().1;
        self.entries = Self::entry_buffer(gpu, self.lists, grown).with_context(|| format!("growing the {name} to {grown} light references"))?;
        self.capacity = grown;
        Ok(Some(format!("{name} to {grown} light references")))
    }
}
