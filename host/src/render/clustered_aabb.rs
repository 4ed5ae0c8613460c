//! Host side of `clustered-aabb` (kernels and algorithm: `shaders::clustered_aabb`): a fixed
//! cluster grid whose boxes are computed once per grid, active clusters marked from depth and
//! compacted with subgroup-aggregated atomics, staged per-cluster light assignment, shading.
//!
//! The one view-dependent capacity is the light-list buffer. The assignment's reservation counter
//! ends at the references the frame needs; if that exceeds the buffer, the buffer grows (needed +
//! 25 %) and the frame re-runs, so no light is ever dropped.
//!
//! Scenes with transparent draws (`transparent.rs`): after the opaque pixels flag their clusters,
//! a raster pre-pass of the transparent draws flags the dense clusters of their fragments
//! (`TRANSPARENT_DENSE_GRID`), so the compaction and assignment give them lists; after the
//! shading, the transparent pass reads those lists and its resolve composites.
//!
//! Memory: see the shader module (boxes 32 B, flags/offsets/counts 4 B each per grid cluster;
//! active list, of `min(clusters, pixels)` entries — every cluster with transparent draws; 4 B
//! per pixel; 4 B per light reference).
use super::technique::{boxed, grew_together, grown_capacity, initial_list_capacity, llvmpipe_chunked_lights, Description, FrameInputs, LightCost, LightingTechnique, ListStats, TransparentDraws};
use super::transparent::{ClusterInputs, Marks, OpaqueDepth, Transparency, TransparencyStats};
use crate::gpu::{Gpu, LightCompute};
use crate::vk::{Buffer, ImageUse, Recorder, VkResult};
use anyhow::{Context as _, Result};
use shaders::clustered_aabb::{cluster_count, AABB_COUNTER_ACTIVE, AABB_COUNTER_REFS};
use shaders::layout::{FrameParams, COUNTERS, TRANSPARENT_DENSE_GRID};

pub const CLUSTERED_AABB: Description = Description {
    name: "clustered-aabb",
    summary: "Clustered deferred on a fixed grid with precomputed cluster boxes: active clusters from depth, staged sphere–box assignment with subgroup-aggregated atomics.",
    create: |gpu, f| boxed(ClusteredAabb::new(gpu, f)),
    transparent: TransparentDraws::Drawn,
    gbuffer: true,
    raster_passes: &[],
    cost: LightCost::EveryLightPerCluster,
    max_tile: None,
    llvmpipe_lights: llvmpipe_chunked_lights,
    knobs: &[],
    own_kernels: &[],
    own_raster: &[],
    msaa: true,
    light_words: 0,
    shadows: true,
};

pub struct ClusteredAabb {
    clusters: u32,
    /// Assignment invocations: the most clusters a frame can touch (`min(clusters, pixels)`
    /// without transparent draws, every cluster with them).
    slots: u32,
    pub capacity: u32,
    boxes: Buffer,
    flags: Buffer,
    active: Buffer,
    pixel_clusters: Buffer,
    offsets: Buffer,
    counts: Buffer,
    list: Buffer,
    counters: Buffer,
    /// `(active clusters, light references needed)` of the last frame.
    last: (u32, u32),
    /// The transparent pass, for scenes with transparent draws.
    transparency: Option<Transparency>,
    /// The MSAA edge pass (`--msaa` above 1).
    edges: Option<[LightCompute<FrameParams>; 2]>,
}

impl ClusteredAabb {
    /// Allocates for the frame's grid and computes every cluster's box.
    pub fn new(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        let transparency = Transparency::new(f, gpu, Some(TRANSPARENT_DENSE_GRID)).context("creating the transparent pass")?;
        let mut t = Self::allocate(gpu, &f.params, f.bounds, initial_list_capacity(f.params.num_lights), transparency.is_some()).context("allocating the clustered-aabb buffers")?;
        t.transparency = transparency;
        t.edges = super::msaa::edge_pipelines(gpu, f.msaa, shaders::kernels::SHADE_EDGES_AABB);
        Ok(t)
    }

    /// Allocates for `p`'s grid and computes every cluster's box (`bounds`: the slice table);
    /// `transparent`: the scene has transparent draws.
    fn allocate(gpu: &Gpu, p: &FrameParams, bounds: &Buffer, capacity: u32, transparent: bool) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let clusters = cluster_count(&p.grid);
        // Every sample may add a cluster with MSAA.
        let pixels = p.grid.width * p.grid.height * p.grid.samples;
        let slots = if transparent { clusters } else { clusters.min(pixels) };
        let words = |name: &str, n: u32| {
            crate::vk::memory::check_range(ctx, name, 4 * n as u64)?;
            Buffer::storage(ctx, name, 4 * n as u64)
        };
        let b = Self {
            clusters,
            slots,
            capacity,
            boxes: {
                crate::vk::memory::check_range(ctx, "cluster boxes", 32 * clusters as u64)?;
                Buffer::storage(ctx, "cluster boxes", 32 * clusters as u64)?
            },
            flags: words("cluster flags", clusters)?,
            active: words("active clusters", slots)?,
            pixel_clusters: words("pixel clusters", p.grid.width * p.grid.height)?,
            offsets: words("light offsets", clusters)?,
            counts: words("light counts", clusters)?,
            list: words("light lists", capacity)?,
            counters: words("counters", COUNTERS)?,
            last: (0, 0),
            transparency: None,
            edges: None,
        };
        let q = FrameParams { count: clusters, ..*p };
        gpu.run(None, |rec| rec.dispatch_linear(&gpu.kernels.aabb_bounds, &[bounds, &b.boxes], &q, clusters))?;
        Ok(b)
    }

    /// Reads the frame's totals; grows the list buffer to the references needed + 25 % when
    /// they did not fit.
    fn grow_list(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        self.last = self.totals()?;
        let need = self.last.1;
        if need <= self.capacity {
            return Ok(None);
        }
        let grown = grown_capacity(need);
        crate::vk::memory::check_range(&gpu.ctx, "light lists", 4 * grown as u64).and_then(|()| {
            self.list = Buffer::storage(&gpu.ctx, "light lists", 4 * grown as u64)?;
            Ok(())
        })
        .with_context(|| format!("growing the light list to {grown} references"))?;
        self.capacity = grown;
        Ok(Some(format!("light list to {grown} references")))
    }

    /// `(active clusters, light references needed)` of the last frame.
    fn totals(&mut self) -> VkResult<(u32, u32)> {
        let c: Vec<u32> = self.counters.read(COUNTERS as usize)?;
        Ok((c[AABB_COUNTER_ACTIVE as usize], c[AABB_COUNTER_REFS as usize]))
    }
}

impl LightingTechnique for ClusteredAabb {
    /// Records active-cluster marking, assignment and shading.
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let k = &gpu.kernels;
        let g = f.targets;
        let n = f.params.count;
        let p = FrameParams { light_capacity: self.capacity, ..f.params };
        rec.pass("active clusters", |rec| {
            rec.fill(&self.flags, 0);
            rec.fill(&self.counters, 0);
            rec.dispatch_linear(&k.aabb_mark, &[&g.depth_buf, f.bounds, &self.pixel_clusters, &self.flags], &p, n)?;
            if let Some(t) = &self.transparency {
                let m = Marks { stage: TRANSPARENT_DENSE_GRID, marks: &self.flags, page_table: None };
                t.record_clusters(rec, f, &p, OpaqueDepth { image: &g.depth, from: ImageUse::CopySource }, &m)?;
            }
            rec.dispatch_linear(&k.aabb_compact, &[&self.flags, &self.counters, &self.active], &FrameParams { count: self.clusters, ..p }, self.clusters)
        })?;
        rec.pass("assignment", |rec| {
            rec.dispatch_linear(
                k.aabb_assign.get(p.effects)?,
                &[&self.active, &self.boxes, f.lights, &self.counters, &self.offsets, &self.counts, &self.list],
                &FrameParams { count: self.slots, ..p },
                self.slots,
            )
        })?;
        let [slots, maps] = f.shadow_buffers();
        rec.pass("shading", |rec| {
            rec.dispatch_blocks(
                super::shading_pipeline(&k.shade_aabb, &p)?,
                &[&g.depth_buf, &g.normal_buf, &g.albedo_buf, &self.pixel_clusters, &self.offsets, &self.counts, &self.list, &self.counters, f.lights, f.materials, f.frame, f.bounds, slots, maps],
                &p,
                p.grid.width,
                p.grid.height,
            )
        })?;
        if let (Some(m), Some(pipes)) = (f.msaa, &self.edges) {
            let buffers = [&g.depth_buf, &g.normal_buf, &g.albedo_buf, &self.offsets, &self.counts, &self.list, &self.counters, f.lights, f.materials, f.frame, f.bounds];
            m.record_edges(rec, pipes, &p, &buffers)?;
        }
        let Some(t) = &self.transparency else { return Ok(()) };
        // The pre-pass left the depth a depth target.
        let from = ImageUse::DepthTarget;
        let lists = ClusterInputs::dense_grid(&self.flags, &self.counts, &self.offsets, &self.list);
        t.record_shade(rec, f, &p, OpaqueDepth { image: &g.depth, from }, Some(&lists))
    }

    /// The node buffer of the transparent pass and the list buffer grow to what the frame
    /// needed + 25 %.
    fn grow_if_needed(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        let nodes = Transparency::grow(self.transparency.as_mut(), &gpu.ctx)?;
        Ok(grew_together(nodes, self.grow_list(gpu)?))
    }

    /// Active clusters, references, and the longest list among the active clusters.
    fn stats(&mut self) -> Result<ListStats> {
        let (active, refs) = self.last;
        let ids: Vec<u32> = self.active.read(active as usize)?;
        let counts: Vec<u32> = self.counts.read(self.clusters as usize)?;
        let max_list = ids.iter().map(|&c| counts[c as usize]).max().unwrap_or(0);
        Ok(ListStats { clusters: active, light_refs: refs, max_list, ..ListStats::default() })
    }

    fn transparency(&self) -> Option<TransparencyStats> {
        self.transparency.as_ref().map(Transparency::stats)
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> = [&self.boxes, &self.flags, &self.active, &self.pixel_clusters, &self.offsets, &self.counts, &self.list, &self.counters]
            .iter()
            .map(|b| (b.name.clone(), b.size))
            .collect();
        v.extend(self.transparency.iter().flat_map(Transparency::buffers));
        v
    }
}
