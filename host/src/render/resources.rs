//! Buffers of the clustered chain and their capacities.
//!
//! Sizes follow from the grid (page table: one word per page of the key space) and from two
//! view-dependent capacities that grow on demand: pages touched (`slots` = 512 words per page)
//! and light references (the concatenated light lists).
use super::scan::DeviceScan;
use super::gbuffer::Targets;
use super::Readback;
use crate::gpu::Gpu;
use crate::vk::{Buffer, Recorder, VkResult};
use shaders::cluster_key::ClusterGrid;
use shaders::layout::*;
use shaders::page_table::page_count;

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
        Self { pages, light_refs: lights.saturating_mul(8).clamp(4096, 1 << 24) }
    }

    /// The capacities a frame that needed `pages` and `light_refs` requires, if larger.
    pub fn grown(&self, pages: u32, light_refs: u32) -> Option<Self> {
        if pages <= self.pages && light_refs <= self.light_refs {
            return None;
        }
        let grow = |need: u32, have: u32| if need > have { need.saturating_add(need / 4).max(have) } else { have };
        Some(Self { pages: grow(pages, self.pages), light_refs: grow(light_refs, self.light_refs) })
    }

    pub fn slots(&self) -> u32 {
        self.pages.saturating_mul(PAGE_SIZE)
    }
}

pub struct ClusterBuffers {
    pub caps: Capacities,
    page_count: u32,
    max_clusters: u32,
    pub keys: Buffer,
    marks: Buffer,
    page_base: Buffer,
    page_of_alloc: Buffer,
    slots: Buffer,
    slot_rank: Buffer,
    pub unique: Buffer,
    pub counts: Buffer,
    pub offsets: Buffer,
    pub list: Buffer,
    pub counters: Buffer,
    page_scan: DeviceScan,
    slot_scan: DeviceScan,
    cluster_scan: DeviceScan,
}

impl ClusterBuffers {
    pub fn new(gpu: &Gpu, grid: &ClusterGrid, caps: Capacities) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let pixels = grid.width * grid.height;
        let pages = page_count(grid);
        let slots = caps.slots();
        let max_clusters = pixels.min(slots);
        let words = |name: &str, n: u32| {
            crate::vk::memory::check_range(ctx, name, 4 * n as u64)?;
            Buffer::storage(ctx, name, 4 * n as u64)
        };
        Ok(Self {
            caps,
            page_count: pages,
            max_clusters,
            keys: words("cluster keys", pixels)?,
            marks: words("page marks", pages)?,
            page_base: words("page table", pages)?,
            page_of_alloc: words("page of allocation", caps.pages)?,
            slots: words("page slots", slots)?,
            slot_rank: words("slot ranks", slots)?,
            unique: words("unique clusters", max_clusters)?,
            counts: words("light counts", max_clusters)?,
            offsets: words("light offsets", max_clusters)?,
            list: words("light lists", caps.light_refs)?,
            counters: words("counters", COUNTERS)?,
            page_scan: DeviceScan::new(gpu, "pages", pages)?,
            slot_scan: DeviceScan::new(gpu, "slots", slots)?,
            cluster_scan: DeviceScan::new(gpu, "clusters", max_clusters)?,
        })
    }

    /// Bytes per buffer, for the stats file.
    pub fn sizes(&self) -> Vec<(String, u64)> {
        let b = [
            &self.keys, &self.marks, &self.page_base, &self.page_of_alloc, &self.slots, &self.slot_rank, &self.unique,
            &self.counts, &self.offsets, &self.list, &self.counters,
        ];
        let mut v: Vec<(String, u64)> = b.iter().map(|b| (b.name.clone(), b.size)).collect();
        v.push(("scan scratch".into(), self.page_scan.bytes() + self.slot_scan.bytes() + self.cluster_scan.bytes()));
        v
    }

    /// Records steps 2–5 (keys … shading) of the clustered chain.
    #[allow(clippy::too_many_arguments)]
    /// With `bvh`, the assignment traverses the light BVH instead of testing every light.
    pub fn record(
        &self,
        gpu: &Gpu,
        rec: &mut Recorder<'_>,
        p: &FrameParams,
        g: &Targets,
        bounds: &Buffer,
        lights: &Buffer,
        materials: &Buffer,
        frame: &Buffer,
        bvh: Option<&super::bvh::LightBvh>,
    ) -> VkResult<()> {
        let k = &gpu.kernels;
        let n = p.count;
        let with = |count: u32| FrameParams { count, ..*p };
        rec.pass("keys", |rec| rec.dispatch_linear(&k.pixel_keys, &[&g.depth_buf, bounds, &self.keys], p, n))?;
        rec.pass("page table", |rec| {
            rec.fill(&self.marks, 0);
            rec.fill(&self.slots, 0);
            rec.fill(&self.counters, 0);
            rec.dispatch_linear(&k.mark_pages, &[&self.keys, &self.marks], p, n)?;
            self.page_scan.record(gpu, rec, &self.marks, &self.page_base, self.page_count, Some((&self.counters, COUNTER_PAGES)))?;
            rec.dispatch_linear(&k.record_pages, &[&self.marks, &self.page_base, &self.page_of_alloc], &with(self.page_count), self.page_count)?;
            rec.dispatch_linear(&k.store_slots, &[&self.keys, &self.page_base, &self.slots], p, n)?;
            let slots = self.caps.slots();
            self.slot_scan.record(gpu, rec, &self.slots, &self.slot_rank, slots, Some((&self.counters, COUNTER_UNIQUE_CLUSTERS)))?;
            rec.dispatch_linear(&k.compact_clusters, &[&self.slots, &self.slot_rank, &self.page_of_alloc, &self.unique], &with(slots), slots)
        })?;
        let c = with(self.max_clusters);
        rec.pass("assignment", |rec| {
            let m = self.max_clusters;
            let walk = bvh.map(|b| (b, BvhAssignParams { frame: c, branching: b.branching, _pad: [0; 3] }));
            match walk {
                None => rec.dispatch_linear(&k.cluster_light_counts, &[&self.unique, &self.counters, bounds, lights, &self.counts], &c, m)?,
                Some((b, w)) => rec.dispatch_subgroups(
                    &k.cluster_light_counts_bvh,
                    &[&self.unique, &self.counters, bounds, lights, &self.counts, &b.order, &b.nodes],
                    &w,
                    m,
                )?,
            }
            self.cluster_scan.record(gpu, rec, &self.counts, &self.offsets, m, Some((&self.counters, COUNTER_LIGHT_REFS)))?;
            match walk {
                None => rec.dispatch_linear(&k.cluster_light_fill, &[&self.unique, &self.counters, bounds, lights, &self.offsets, &self.list], &c, m),
                Some((b, w)) => rec.dispatch_subgroups(
                    &k.cluster_light_fill_bvh,
                    &[&self.unique, &self.counters, bounds, lights, &self.offsets, &self.list, &b.order, &b.nodes],
                    &w,
                    m,
                ),
            }
        })?;
        rec.pass("shading", |rec| {
            rec.dispatch_linear(
                &k.shade_clustered[super::specular_variant(p)],
                &[&g.depth_buf, &g.normal_buf, &g.albedo_buf, &self.keys, &self.page_base, &self.slot_rank, &self.counts, &self.offsets, &self.list, lights, materials, frame, bounds],
                p,
                n,
            )
        })
    }

    /// Reads the cluster data back (tests, statistics).
    pub fn read_back(&mut self, gbuffer: Vec<u32>, unique: u32, refs: u32, lights_view: Vec<PointLight>, grid: ClusterGrid, bounds: Vec<f32>) -> VkResult<Readback> {
        let pixels = (grid.width * grid.height) as usize;
        Ok(Readback {
            depth: gbuffer,
            normals: Vec::new(),
            keys: self.keys.read(pixels)?,
            unique: self.unique.read(unique as usize)?,
            counts: self.counts.read(unique as usize)?,
            offsets: self.offsets.read(unique as usize)?,
            list: self.list.read(refs as usize)?,
            lights_view,
            grid,
            bounds,
        })
    }
}
