//! Host side of `clustered-aabb` (kernels and algorithm: `shaders::clustered_aabb`): a fixed
//! cluster grid whose boxes are computed once per grid, active clusters marked from depth and
//! compacted with subgroup-aggregated atomics, staged per-cluster light assignment, shading.
//!
//! The one view-dependent capacity is the light-list buffer. The assignment's reservation counter
//! ends at the references the frame needs; if that exceeds the buffer, the buffer grows (needed +
//! 25 %) and the frame re-runs, so no light is ever dropped.
//!
//! Memory: see the shader module (boxes 32 B, flags/offsets/counts 4 B each per grid cluster;
//! active list; 4 B per pixel; 4 B per light reference).
use super::gbuffer::Targets;
use crate::gpu::Gpu;
use crate::vk::{Buffer, PassTiming, Profiler, Recorder, VkResult};
use anyhow::{bail, Context as _, Result};
use shaders::clustered_aabb::{cluster_count, AABB_COUNTER_ACTIVE, AABB_COUNTER_REFS};
use shaders::layout::{FrameParams, COUNTERS};

/// First guess of the list capacity (as the page-table chain): 8 references per light.
pub fn initial_capacity(lights: u32) -> u32 {
    lights.saturating_mul(8).clamp(4096, 1 << 24)
}

pub struct AabbBuffers {
    clusters: u32,
    /// Assignment invocations: `min(clusters, pixels)` (the most clusters a frame can touch).
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
}

impl AabbBuffers {
    /// Allocates for `p`'s grid and computes every cluster's box (`bounds`: the slice table).
    pub fn new(gpu: &Gpu, p: &FrameParams, bounds: &Buffer, capacity: u32) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let clusters = cluster_count(&p.grid);
        let pixels = p.grid.width * p.grid.height;
        let slots = clusters.min(pixels);
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
            pixel_clusters: words("pixel clusters", pixels)?,
            offsets: words("light offsets", clusters)?,
            counts: words("light counts", clusters)?,
            list: words("light lists", capacity)?,
            counters: words("counters", COUNTERS)?,
        };
        let q = FrameParams { count: clusters, ..*p };
        gpu.run(None, |rec| rec.dispatch_linear(&gpu.kernels.aabb_bounds, &[bounds, &b.boxes], &q, clusters))?;
        Ok(b)
    }

    pub fn sizes(&self) -> Vec<(String, u64)> {
        [&self.boxes, &self.flags, &self.active, &self.pixel_clusters, &self.offsets, &self.counts, &self.list, &self.counters]
            .iter()
            .map(|b| (b.name.clone(), b.size))
            .collect()
    }

    /// Records active-cluster marking, assignment and shading.
    #[allow(clippy::too_many_arguments)]
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, p: &FrameParams, g: &Targets, bounds: &Buffer, lights: &Buffer, materials: &Buffer, frame: &Buffer) -> VkResult<()> {
        let k = &gpu.kernels;
        let n = p.count;
        let p = FrameParams { light_capacity: self.capacity, ..*p };
        rec.pass("active clusters", |rec| {
            rec.fill(&self.flags, 0);
            rec.fill(&self.counters, 0);
            rec.dispatch_linear(&k.aabb_mark, &[&g.depth_buf, bounds, &self.pixel_clusters, &self.flags], &p, n)?;
            rec.dispatch_linear(&k.aabb_compact, &[&self.flags, &self.counters, &self.active], &FrameParams { count: self.clusters, ..p }, self.clusters)
        })?;
        rec.pass("assignment", |rec| {
            rec.dispatch_linear(
                &k.aabb_assign,
                &[&self.active, &self.boxes, lights, &self.counters, &self.offsets, &self.counts, &self.list],
                &FrameParams { count: self.slots, ..p },
                self.slots,
            )
        })?;
        rec.pass("shading", |rec| {
            rec.dispatch_linear(
                &k.shade_aabb[super::specular_variant(&p)],
                &[&g.depth_buf, &g.normal_buf, &g.albedo_buf, &self.pixel_clusters, &self.offsets, &self.counts, &self.list, &self.counters, lights, materials, frame, bounds],
                &p,
                n,
            )
        })
    }

    /// `(active clusters, light references needed)` of the last frame.
    pub fn totals(&mut self) -> VkResult<(u32, u32)> {
        let c: Vec<u32> = self.counters.read(COUNTERS as usize)?;
        Ok((c[AABB_COUNTER_ACTIVE as usize], c[AABB_COUNTER_REFS as usize]))
    }

    /// The longest list among the `active` clusters of the last frame.
    pub fn max_list(&mut self, active: u32) -> VkResult<u32> {
        let ids: Vec<u32> = self.active.read(active as usize)?;
        let counts: Vec<u32> = self.counts.read(self.clusters as usize)?;
        Ok(ids.iter().map(|&c| counts[c as usize]).max().unwrap_or(0))
    }

    /// Replaces the list buffer by one of `capacity` entries.
    pub fn grow(&mut self, gpu: &Gpu, capacity: u32) -> VkResult<()> {
        crate::vk::memory::check_range(&gpu.ctx, "light lists", 4 * capacity as u64)?;
        self.list = Buffer::storage(&gpu.ctx, "light lists", 4 * capacity as u64)?;
        self.capacity = capacity;
        Ok(())
    }
}

/// What the frames of a `clustered-aabb` render produced.
pub struct Outcome {
    /// Per-pass timings of each timed frame.
    pub timings: Vec<Vec<PassTiming>>,
    pub active: u32,
    pub refs: u32,
    pub max_list: u32,
    pub regrowths: u32,
    pub buffers: Vec<(String, u64)>,
}

/// Renders the warm-up frame and `frames` timed ones; `gbuffer` records the G-buffer pass. A frame
/// whose lists overflowed grows the list and re-runs.
#[allow(clippy::too_many_arguments)]
pub fn run(
    gpu: &Gpu,
    p: &FrameParams,
    frames: u32,
    profiler: &mut Profiler,
    gbuffer: &dyn Fn(&mut Recorder<'_>) -> VkResult<()>,
    targets: &Targets,
    bounds: &Buffer,
    lights: &Buffer,
    materials: &Buffer,
    frame: &Buffer,
) -> Result<Outcome> {
    let mut b = AabbBuffers::new(gpu, p, bounds, initial_capacity(p.num_lights)).context("allocating the clustered-aabb buffers")?;
    let mut out = Outcome { timings: Vec::new(), active: 0, refs: 0, max_list: 0, regrowths: 0, buffers: Vec::new() };
    let mut f = 0;
    while f <= frames {
        gpu.run(Some(&mut *profiler), |rec| {
            gbuffer(rec)?;
            b.record(gpu, rec, p, targets, bounds, lights, materials, frame)
        })?;
        (out.active, out.refs) = b.totals()?;
        if out.refs > b.capacity {
            out.regrowths += 1;
            if out.regrowths > 8 {
                bail!("the clustered-aabb light list keeps growing ({} references): giving up", out.refs);
            }
            let grown = out.refs.saturating_add(out.refs / 4);
            b.grow(gpu, grown).with_context(|| format!("growing the light list to {grown} references"))?;
            continue; // re-run this frame
        }
        if f > 0 || frames == 0 {
            out.timings.push(profiler.results()?);
        }
        f += 1;
    }
    out.max_list = b.max_list(out.active)?;
    out.buffers = b.sizes();
    Ok(out)
}
