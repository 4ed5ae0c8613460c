//! `clustered-naive` and `clustered-bvh`: clustered deferred shading (Olsson et al. 2012, §3–4)
//! in Karas' Vulkan design (virtual page table of unique clusters, Morton-sorted lights in a
//! light BVH), one kernel per step:
//! 1. **G-buffer** (raster, recorded by the frame loop) → depth | normal | albedo buffers.
//!
//! Steps 2–3 find the frame's unique clusters one of two ways ([`UniqueClusters`]):
//! * **unique clusters** (the default, `--unique-clusters tiles`) — one dispatch, one workgroup
//!   per screen tile (`clustered::tile_clusters`, `shaders::tile_clusters`): the tile's pixel
//!   keys, a mask of its slices in workgroup memory, its clusters reserved in the list with one
//!   atomic add, and a record per mask word for the shading's lookup. It replaces the six
//!   dispatches below: on the H200 (Sponza 1080p, 10k lights) 0.027 ms against 0.060 + 0.052,
//!   and `clustered-bvh`'s compute 0.279 ms against 0.360 (`docs/results/h200/unique-clusters/`).
//! * Karas' virtual page table (`--unique-clusters page-table`, and scenes with transparent
//!   draws):
//!
//! 2. **keys** — cluster key per pixel, and its page's mark (`clustered::pixel_keys`): 32 px
//!    tiles × exponential depth slices, `k = ⌊ln(−z/near) / ln(1 + 2·tanθ/S_y)⌋`.
//! 3. **page table** — (pages marked with the keys) allocate in one workgroup (a scan of the
//!    marks) → store slots → per allocated page count its set slots → scan those counts in one
//!    workgroup → per page rank and compact its slots into the sorted unique-cluster list
//!    (`page_table`). Five dispatches, two of them one workgroup, where device-wide scans of the
//!    marks and of the slots made the pass fifteen, on the H200 about 6 µs each whatever their
//!    size. Allocation is sized from the resolution; the per-page passes cover the pages the
//!    frame allocated (indirect dispatches that the allocation writes). Marks and slots are
//!    cleared by their last readers, never at capacity.
//! 4. **assignment** — per unique cluster, its lights counted and its list's place reserved with
//!    one atomic add (`shaders::clustered::reserve_list`), then filled; offsets + counts give
//!    each cluster's list. Both run for the frame's unique clusters (indirect dispatches from the
//!    GPU's cluster counter), never for the buffers' capacity. (A device-wide scan of the counts
//!    placed the lists before: seven dependent dispatches, 0.05 ms on the H200.)
//!    `clustered-naive` tests every light against the cluster's AABB; `clustered-bvh` walks the
//!    light BVH (`bvh.rs`: Morton keys → sort (`sort.rs`) → 32/64-ary node boxes, on the
//!    async-compute queue, overlapping the G-buffer raster) in one pass
//!    (`clustered_bvh::assign_lights_bvh`): its walk stages each cluster's lights as it counts
//!    them, and once the list is reserved copies every list that fits instead of walking again
//!    (H200, Sponza 1080p, 10k lights: assignment 0.260 → 0.158 ms with 64 staged per cluster,
//!    when a second pass copied them). The stage's words are shared out among the frame's
//!    clusters (`clustered_bvh::stage_stride`, stored by the page table's scan: up to 1 024
//!    lights each).
//! 5. **shading** — per pixel: key → page → slot → cluster → list → lights (tile path: key →
//!    its tile's record → cluster; the kernel then hands the tile path's cluster count to the
//!    host and zeroes its atomics for the next frame).
//! 6. **transparency** (scenes with transparent draws, `transparent.rs`): inside steps 2 and 3 a
//!    raster pre-pass of the transparent draws marks their fragments' pages, then slots, so
//!    their clusters get lists; after step 5 the transparent pass and its resolve.
//!
//! Capacities that depend on the view (pages touched, light references) are GPU counters read
//! back after the frame; if one exceeded its buffer, the buffer grows and the frame re-runs.
//!
//! Memory: 4 B per pixel (keys); tile path: 8 B per mask word per tile (147 KB at 1080p), unique
//! clusters at most one per pixel or per grid cluster; page table: 4 B per page of the key space ×2 (marks, page table); 8 B per
//! slot (512 slots per touched page) and 12 B per allocatable page (its key-space page, slot
//! count and offset); 12 B per unique cluster (list, counts, offsets); 4 B per light reference;
//! the BVH (`bvh.rs`); `clustered-bvh`'s staged lists, 256 B per cluster of the capacity for
//! up to `STAGED_CLUSTERS` = 65 536 (≤ 16 MiB), shared out among the frame's clusters.
use super::bvh::LightBvh;
use super::technique::{boxed, grew_together, grown_capacity, initial_list_capacity, llvmpipe_chunked_lights, ClusterLists, Description, FrameInputs, Knob, LightCost, LightingTechnique, ListStats, TransparentDraws};
use super::transparent::{ClusterInputs, Marks, OpaqueDepth, Transparency, TransparencyStats};
use crate::gpu::{Gpu, LightCompute};
use crate::vk::{Buffer, ImageUse, Recorder, VkResult};
use anyhow::{bail, Context as _, Result};
use shaders::clustered_bvh::{STAGED_CLUSTERS, STAGED_LIGHTS};
use shaders::cluster_key::ClusterGrid;
use shaders::layout::*;
use shaders::page_table::page_count;

pub const CLUSTERED_NAIVE: Description = Description {
    name: "clustered-naive",
    summary: "Clustered deferred with unique clusters and naive (all-lights) assignment.",
    create: |gpu, f| boxed(Clustered::naive(gpu, f)),
    transparent: TransparentDraws::Drawn,
    gbuffer: true,
    raster_passes: &[],
    cost: LightCost::EveryLightPerCluster,
    max_tile: None,
    llvmpipe_lights: llvmpipe_chunked_lights,
    knobs: &[Knob::UniqueClusters],
    own_kernels: &[],
    own_raster: &[],
    msaa: true,
    light_words: 1,
    shadows: true,
};

pub const CLUSTERED_BVH: Description = Description {
    name: "clustered-bvh",
    summary: "Clustered deferred with lights Morton-sorted on the GPU into a 32- or 64-ary BVH that each unique cluster walks.",
    create: |gpu, f| boxed(Clustered::bvh(gpu, f)),
    cost: LightCost::Culled,
    knobs: &[Knob::UniqueClusters, Knob::LightHierarchy],
    ..CLUSTERED_NAIVE
};

/// `clustered-naive` (`bvh` none) or `clustered-bvh`.
pub struct Clustered {
    bvh: Option<LightBvh>,
    grid: ClusterGrid,
    /// How the unique clusters are found (`render --unique-clusters`).
    unique: UniqueClusters,
    buffers: ClusterBuffers,
    /// The transparent pass, for scenes with transparent draws.
    transparency: Option<Transparency>,
    /// `(unique clusters, light references, pages)` of the last frame.
    last: (u32, u32, u32),
    /// The MSAA edge pass of the frame's path (`--msaa` above 1).
    edges: Option<[LightCompute<FrameParams>; 2]>,
}

impl Clustered {
    /// `clustered-naive`: every light tested against every unique cluster.
    pub fn naive(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        Self::new(gpu, f, None)
    }

    /// `clustered-bvh`: lights sorted into a BVH that each unique cluster walks.
    pub fn bvh(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        let s = f.settings;
        let branching = match s.bvh_branching {
            0 => LightBvh::default_branching(gpu.ctx.info.subgroup_size),
            b if shaders::light_bvh::valid_branching(b) => b,
            b => bail!("BVH branching {b}: 32 or 64"),
        };
        let morton_bits = super::bvh::morton_bits(s.morton_bits);
        super::bvh::check_morton_bits(morton_bits)?;
        let bvh = LightBvh::new(gpu, f.lights_view, branching, s.sort, morton_bits).context("allocating the light BVH")?;
        Self::new(gpu, f, Some(bvh))
    }

    fn new(gpu: &Gpu, f: &FrameInputs<'_>, bvh: Option<LightBvh>) -> Result<Self> {
        let grid = f.params.grid;
        let caps = Capacities::initial(&grid, f.params.num_lights);
        let transparency = Transparency::new(f, gpu, Some(TRANSPARENT_MARK_PAGES)).context("creating the transparent pass")?;
        let unique = f.settings.unique_clusters;
        let buffers = ClusterBuffers::new(gpu, &grid, caps, unique, transparency.is_some(), bvh.is_some()).context("allocating the cluster buffers")?;
        let edge_kernels = match buffers.path {
            UniqueBuffers::Tiles { .. } => shaders::kernels::SHADE_EDGES_CLUSTERED_TILES,
            UniqueBuffers::PageTable(_) => shaders::kernels::SHADE_EDGES_CLUSTERED,
        };
        let edges = super::msaa::edge_pipelines(gpu, f.msaa, edge_kernels);
        Ok(Self { bvh, grid, unique, buffers, transparency, last: (0, 0, 0), edges })
    }
}

impl LightingTechnique for Clustered {
    fn has_async_work(&self) -> bool {
        self.bvh.is_some()
    }

    /// The light sort + BVH build depend on the lights only: on the async-compute queue they
    /// overlap the G-buffer raster (the assignment waits for them).
    fn record_async(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        self.bvh.as_ref().map_or(Ok(()), |b| b.record(gpu, rec, f.lights, f.params.effects))
    }

    fn lights_moved(&mut self, f: &FrameInputs<'_>) {
        if let Some(b) = self.bvh.as_mut() {
            b.requantize(f.lights_view);
        }
    }

    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let p = FrameParams { light_capacity: self.buffers.caps.light_refs, ..f.params };
        self.buffers.record(gpu, rec, &p, f, self.bvh.as_ref(), self.transparency.as_ref())?;
        match (f.msaa, &self.edges) {
            (Some(m), Some(pipes)) => m.record_edges(rec, pipes, &p, &self.buffers.edge_bindings(f)),
            _ => Ok(()),
        }
    }

    fn grow_if_needed(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let nodes = Transparency::grow(self.transparency.as_mut(), &gpu.ctx)?;
        Ok(grew_together(nodes, self.grow_lists(gpu)?))
    }

    fn transparency(&self) -> Option<TransparencyStats> {
        self.transparency.as_ref().map(Transparency::stats)
    }

    fn stats(&mut self) -> Result<ListStats> {
        let (clusters, light_refs, pages) = self.last;
        Ok(ListStats { clusters, light_refs, pages, max_list: 0 })
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> = self.bvh.iter().map(|b| ("light bvh".to_string(), b.bytes())).collect();
        v.extend(self.buffers.sizes());
        v.extend(self.transparency.iter().flat_map(Transparency::buffers));
        v
    }

    fn cluster_lists(&mut self) -> Result<Option<ClusterLists>> {
        let (unique, refs, _) = self.last;
        Ok(Some(self.buffers.read_back(self.grid.width * self.grid.height, unique, refs)?))
    }
}

impl Clustered {
    /// Reads the cluster counters of the last frame; grows the cluster buffers when a view-dependent
    /// capacity was too small.
    fn grow_lists(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let c: Vec<u32> = self.buffers.counters.read(COUNTERS as usize)?;
        self.last = (c[COUNTER_FRAME_CLUSTERS as usize], c[COUNTER_LIGHT_REFS as usize], c[COUNTER_PAGES as usize]);
        let (_, refs, pages) = self.last;
        let Some(caps) = self.buffers.caps.grown(pages, refs) else { return Ok(None) };
        self.buffers = ClusterBuffers::new(gpu, &self.grid, caps, self.unique, self.transparency.is_some(), self.bvh.is_some())
            .with_context(|| format!("growing the cluster buffers to {} pages and {} light references", caps.pages, caps.light_refs))?;
        Ok(Some(format!("cluster buffers to {} pages and {} light references", caps.pages, caps.light_refs)))
    }
}

/// View-dependent capacities.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capacities {
    /// Pages of 512 slots that can be allocated.
    pub pages: u32,
    /// Entries of the light-index list.
    pub light_refs: u32,
}

impl Capacities {
    /// A first guess: pages for a few slices per tile row, lists of 8 lights per pixel-tile.
    pub fn initial(grid: &ClusterGrid, lights: u32) -> Self {
        let pixels = grid.width * grid.height;
        // A page holds 512 keys of one slice: about 2 tile rows at 4K. Frames touch far fewer
        // pages than pixels; 1 page per 2048 pixels covers every view we tried, and more grows.
        let pages = page_count(grid).min(pixels.div_ceil(2048).max(64));
        Self { pages, light_refs: initial_list_capacity(lights) }
    }

    /// The capacities a frame that needed `pages` and `light_refs` requires, if larger.
    pub fn grown(&self, pages: u32, light_refs: u32) -> Option<Self> {
        if pages <= self.pages && light_refs <= self.light_refs {
            return None;
        }
        let grow = |need: u32, have: u32| if need > have { grown_capacity(need).max(have) } else { have };
        Some(Self { pages: grow(pages, self.pages), light_refs: grow(light_refs, self.light_refs) })
    }

    pub fn slots(&self) -> u32 {
        self.pages.saturating_mul(PAGE_SIZE)
    }
}

/// How the clustered techniques find the frame's unique clusters (`render --unique-clusters`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum UniqueClusters {
    /// One workgroup per screen tile builds a mask of its slices and reserves its clusters
    /// (`shaders::tile_clusters`): one dispatch. The default; scenes with transparent draws and
    /// grids of more than `shaders::tile_clusters::MAX_TILE_SLICES` slices take the page table.
    #[default]
    Tiles,
    /// Karas' virtual page table (`shaders::page_table`): five dispatches.
    PageTable,
}

impl UniqueClusters {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tiles => "tiles",
            Self::PageTable => "page-table",
        }
    }

    /// The path a frame of `grid` takes (`transparent`: the scene has transparent draws, whose
    /// fragments only the page table serves).
    pub fn for_frame(self, grid: &ClusterGrid, transparent: bool) -> Self {
        match self {
            Self::Tiles if transparent || !shaders::tile_clusters::serves(grid) => Self::PageTable,
            u => u,
        }
    }
}

/// The buffers of the path that finds the unique clusters.
enum UniqueBuffers {
    /// The tiles' records (mask words and the list index of their lowest bit).
    Tiles { records: Buffer },
    PageTable(Box<PageTable>),
}

/// The virtual page table's buffers.
struct PageTable {
    page_count: u32,
    marks: Buffer,
    page_base: Buffer,
    page_of_alloc: Buffer,
    slots: Buffer,
    slot_rank: Buffer,
    /// Set slots per allocated page, and their exclusive scan (`page_table` step 5).
    page_counts: Buffer,
    page_offsets: Buffer,
}

struct ClusterBuffers {
    pub caps: Capacities,
    max_clusters: u32,
    path: UniqueBuffers,
    pub keys: Buffer,
    pub unique: Buffer,
    pub counts: Buffer,
    pub offsets: Buffer,
    pub list: Buffer,
    pub counters: Buffer,
    /// `clustered-bvh`: the lists the walk stages (`shaders::clustered_bvh::stage`) for the
    /// frame's clusters (`stage_words` words shared out among them), copied to their place once
    /// reserved instead of a second walk.
    staged: Option<Buffer>,
    stage_words: u32,
    /// Workgroup counts written on the GPU from its counters (`VkDispatchIndirectCommand`s):
    /// [`ARGS_PAGES`] one per allocated page, [`ARGS_ASSIGNMENT`] for the unique clusters.
    dispatch_args: Buffer,
}

impl ClusterBuffers {
    /// Buffers at `caps` for `unique`'s path; with `transparent`, transparent fragments add
    /// clusters of their own, so the unique clusters are bounded by the slots, not by the pixels;
    /// `staged`: with the stage of the BVH walks.
    pub fn new(gpu: &Gpu, grid: &ClusterGrid, caps: Capacities, unique: UniqueClusters, transparent: bool, staged: bool) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        // Every sample has a key with MSAA (`shaders::msaa`): the keys and the bound on the
        // clusters count samples.
        let pixels = grid.width * grid.height * grid.samples;
        let words = |name: &str, n: u32| {
            crate::vk::memory::check_range(ctx, name, 4 * n as u64)?;
            Buffer::storage(ctx, name, 4 * n as u64)
        };
        let zeroed = |name: &str, n: u32| {
            crate::vk::memory::check_range(ctx, name, 4 * n as u64)?;
            Buffer::zeroed(ctx, name, 4 * n as u64)
        };
        let (path, max_clusters) = match unique.for_frame(grid, transparent) {
            UniqueClusters::Tiles => {
                let grid_clusters = (grid.tiles_x * grid.tiles_y).saturating_mul(grid.num_slices);
                (UniqueBuffers::Tiles { records: words("tile cluster records", shaders::tile_clusters::record_words(grid))? }, pixels.min(grid_clusters))
            }
            UniqueClusters::PageTable => {
                let pages = page_count(grid);
                let slots = caps.slots();
                let t = PageTable {
                    page_count: pages,
                    marks: zeroed("page marks", pages)?,
                    page_base: words("page table", pages)?,
                    page_of_alloc: words("page of allocation", caps.pages)?,
                    slots: zeroed("page slots", slots)?,
                    slot_rank: words("slot ranks", slots)?,
                    page_counts: words("page slot counts", caps.pages)?,
                    page_offsets: words("page slot offsets", caps.pages)?,
                };
                (UniqueBuffers::PageTable(Box::new(t)), if transparent { slots } else { pixels.min(slots) })
            }
        };
        let stage_words = if staged { max_clusters.min(STAGED_CLUSTERS) * STAGED_LIGHTS } else { 0 };
        Ok(Self {
            caps,
            max_clusters,
            path,
            staged: if staged { Some(words("staged light lists", stage_words)?) } else { None },
            stage_words,
            keys: words("cluster keys", pixels)?,
            unique: words("unique clusters", max_clusters)?,
            counts: words("light counts", max_clusters)?,
            offsets: words("light offsets", max_clusters)?,
            list: words("light lists", caps.light_refs)?,
            // Zero: the tile path's atomics start from them (and its shading zeroes them after).
            counters: zeroed("counters", COUNTERS)?,
            dispatch_args: zeroed("indirect dispatches", ARGS_WORDS)?,
        })
    }

    /// The edge pass's buffers before the edge list (`shaders::kernels::SHADE_EDGES_CLUSTERED*`).
    fn edge_bindings<'a>(&'a self, f: &'a FrameInputs<'_>) -> Vec<&'a Buffer> {
        let g = f.targets;
        let path: Vec<&Buffer> = match &self.path {
            UniqueBuffers::Tiles { records } => vec![records],
            UniqueBuffers::PageTable(t) => vec![&t.page_base, &t.slot_rank],
        };
        [&g.depth_buf, &g.normal_buf, &g.albedo_buf, &self.keys]
            .into_iter()
            .chain(path)
            .chain([&self.counts, &self.offsets, &self.list, f.lights, f.materials, f.frame, f.bounds])
            .collect()
    }

    /// Bytes per buffer, for the stats file.
    pub fn sizes(&self) -> Vec<(String, u64)> {
        let common = [&self.keys, &self.unique, &self.counts, &self.offsets, &self.list, &self.counters, &self.dispatch_args];
        let path: Vec<&Buffer> = match &self.path {
            UniqueBuffers::Tiles { records } => vec![records],
            UniqueBuffers::PageTable(t) => vec![&t.marks, &t.page_base, &t.page_of_alloc, &t.slots, &t.slot_rank, &t.page_counts, &t.page_offsets],
        };
        common.into_iter().chain(path).chain(self.staged.as_ref()).map(|b| (b.name.clone(), b.size)).collect()
    }

    /// Records steps 2–5 (keys … shading) of the clustered chain. With `bvh`, the assignment
    /// traverses the light BVH instead of testing every light; with `transparency`, the
    /// transparent draws mark their clusters inside steps 2–3 and are drawn after step 5.
    pub fn record(
        &self,
        gpu: &Gpu,
        rec: &mut Recorder<'_>,
        p: &FrameParams,
        f: &FrameInputs<'_>,
        bvh: Option<&super::bvh::LightBvh>,
        transparency: Option<&Transparency>,
    ) -> VkResult<()> {
        let (g, bounds, lights, materials, frame) = (f.targets, f.bounds, f.lights, f.materials, f.frame);
        let k = &gpu.kernels;
        // The assignment's workgroups (for the frame's unique clusters, not for the buffers'
        // capacity): sized by the pass that finds them.
        let c = FrameParams { count: self.max_clusters, ..*p };
        let walk = bvh.zip(self.staged.as_ref()).map(|(b, st)| (b, st, BvhAssignParams { frame: c, branching: b.branching, stage_words: self.stage_words, _pad: [0; 2] }));
        let per_group = match walk {
            None => shaders::kernels::CLUSTER_LIGHT_COUNTS.invocations(),
            Some(_) => rec.subgroup_items_per_group(k.assign_lights_bvh.get(c.effects)?),
        };
        match &self.path {
            UniqueBuffers::Tiles { records } => rec.pass("unique clusters", |rec| {
                let t = TileClusterParams { frame: c, per_group, _pad: [0; 3] };
                let tiles = [p.grid.tiles_x, p.grid.tiles_y, 1];
                rec.dispatch(&k.tile_clusters, &[&g.depth_buf, bounds, &self.keys, records, &self.unique, &self.counters, &self.dispatch_args], &t, tiles)
            })?,
            UniqueBuffers::PageTable(t) => self.record_page_table(gpu, rec, p, f, t, per_group, transparency)?,
        }
        rec.pass("assignment", |rec| {
            let args = &self.dispatch_args;
            match walk {
                None => {
                    rec.dispatch_indirect(
                        k.cluster_light_counts.get(c.effects)?,
                        &[&self.unique, &self.counters, bounds, lights, &self.counts, &self.offsets],
                        &c,
                        args,
                        ARGS_ASSIGNMENT,
                    )?;
                    // The counting pass placed each list (`shaders::clustered::reserve_list`): no scan.
                    rec.dispatch_indirect(k.cluster_light_fill.get(c.effects)?, &[&self.unique, &self.counters, bounds, lights, &self.offsets, &self.list], &c, args, ARGS_ASSIGNMENT)
                }
                // One pass: walk, reserve, copy the staged list (`shaders::clustered_bvh::assign_lights_bvh`).
                Some((b, st, w)) => rec.dispatch_indirect(
                    k.assign_lights_bvh.get(c.effects)?,
                    &[&self.unique, &self.counters, bounds, &b.spheres, &self.counts, &b.order, &b.nodes, st, lights, &self.offsets, &self.list],
                    &w,
                    args,
                    ARGS_ASSIGNMENT,
                ),
            }
        })?;
        let (w, h) = (p.grid.width, p.grid.height);
        let (gbuffer, lists) = ([&g.depth_buf, &g.normal_buf, &g.albedo_buf], [&self.counts, &self.offsets, &self.list, lights, materials, frame, bounds]);
        let t = match &self.path {
            UniqueBuffers::Tiles { records } => {
                // Also hands the cluster count over and zeroes the tile path's atomics.
                let buffers: Vec<&Buffer> = gbuffer.into_iter().chain([&self.keys, records]).chain(lists).chain([&self.counters, &self.dispatch_args]).chain(f.shadow_buffers()).collect();
                return rec.pass("shading", |rec| rec.dispatch_blocks(super::shading_pipeline(&k.shade_clustered_tiles, p)?, &buffers, p, w, h));
            }
            UniqueBuffers::PageTable(t) => t,
        };
        let buffers: Vec<&Buffer> = gbuffer.into_iter().chain([&self.keys, &t.page_base, &t.slot_rank]).chain(lists).chain(f.shadow_buffers()).collect();
        rec.pass("shading", |rec| rec.dispatch_blocks(super::shading_pipeline(&k.shade_clustered, p)?, &buffers, p, w, h))?;
        let Some(tr) = transparency else { return Ok(()) };
        let c = ClusterInputs {
            page_base: &t.page_base,
            slot_rank: &t.slot_rank,
            unique: &self.unique,
            counters: &self.counters,
            counts: &self.counts,
            offsets: &self.offsets,
            list: &self.list,
        };
        tr.record_shade(rec, f, p, OpaqueDepth { image: &g.depth, from: ImageUse::DepthTarget }, Some(&c))
    }

    /// Steps 2–3 through the virtual page table, with the transparent draws' marks.
    #[allow(clippy::too_many_arguments)]
    fn record_page_table(&self, gpu: &Gpu, rec: &mut Recorder<'_>, p: &FrameParams, f: &FrameInputs<'_>, t: &PageTable, per_group: u32, transparency: Option<&Transparency>) -> VkResult<()> {
        let (g, bounds) = (f.targets, f.bounds);
        let k = &gpu.kernels;
        // Every sample's key with MSAA (`shaders::clustered::pixel_keys`).
        let n = p.count * p.grid.samples;
        let all = FrameParams { count: n, ..*p };
        // Marks and slots are zero at allocation and cleared by their last readers
        // (`allocate_pages`, `compact_page_slots`): no fill at their capacity.
        // The counters are stored whole by the passes that count (the light references start
        // at 0 in `allocate_pages`): no fill.
        rec.pass("keys", |rec| {
            rec.dispatch_linear(&k.pixel_keys, &[&g.depth_buf, bounds, &self.keys, &t.marks], &all, n)?;
            match transparency {
                Some(tr) => {
                    let m = Marks { stage: TRANSPARENT_MARK_PAGES, marks: &t.marks, page_table: Some((&t.page_base, &t.slots)) };
                    tr.record_clusters(rec, f, p, OpaqueDepth { image: &g.depth, from: ImageUse::CopySource }, &m)
                }
                None => Ok(()),
            }
        })?;
        rec.pass("page table", |rec| {
            // One workgroup allocates the marked pages (and sizes the per-page dispatches).
            let a = PageTableParams { pages: t.page_count, capacity: self.caps.pages, per_group: 1, args_offset: ARGS_PAGES, _pad: [0; 4] };
            rec.dispatch(&k.allocate_pages, &[&t.marks, &t.page_base, &t.page_of_alloc, &self.counters, &self.dispatch_args], &a, [1, 1, 1])?;
            rec.dispatch_linear(&k.store_slots, &[&self.keys, &t.page_base, &t.slots], &all, n)?;
            if let Some(tr) = transparency {
                let m = Marks { stage: TRANSPARENT_STORE_SLOTS, marks: &t.marks, page_table: Some((&t.page_base, &t.slots)) };
                tr.record_clusters(rec, f, p, OpaqueDepth { image: &g.depth, from: ImageUse::DepthTarget }, &m)?;
            }
            // The allocated pages' slots: counted per page, the counts scanned in one
            // workgroup, the slots ranked and compacted per page.
            let args = &self.dispatch_args;
            rec.dispatch_indirect(&k.count_page_slots, &[&t.slots, &t.page_counts], &(), args, ARGS_PAGES)?;
            let s = PageTableParams { pages: t.page_count, capacity: self.caps.pages, per_group, args_offset: ARGS_ASSIGNMENT, _pad: [0; 4] };
            rec.dispatch(&k.scan_page_counts, &[&t.page_counts, &t.page_offsets, &self.counters, args], &s, [1, 1, 1])?;
            let compact = [&t.slots, &t.page_offsets, &t.page_of_alloc, &t.slot_rank, &self.unique];
            rec.dispatch_indirect(&k.compact_page_slots, &compact, &(), args, ARGS_PAGES)
        })
    }

    /// Reads the cluster data back (tests, statistics).
    fn read_back(&mut self, pixels: u32, unique: u32, refs: u32) -> VkResult<ClusterLists> {
        Ok(ClusterLists {
            keys: self.keys.read(pixels as usize)?,
            unique: self.unique.read(unique as usize)?,
            counts: self.counts.read(unique as usize)?,
            offsets: self.offsets.read(unique as usize)?,
            list: self.list.read(refs as usize)?,
        })
    }
}
