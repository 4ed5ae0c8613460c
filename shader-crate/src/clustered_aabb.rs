//! Clustered deferred with a fixed cluster grid and precomputed boxes (`clustered-aabb`): the
//! classic compute formulation of Olsson, Billeter, Assarsson 2012 ("Clustered Deferred and
//! Forward Shading", HPG), without the page table of `clustered-naive`.
//!
//! # Steps
//!
//! 1. **Bounds** (once per grid) — the view-space AABB of every cluster of the full grid (screen
//!    tiles × the exponential depth slices of [`crate::cluster_key`]), [`cluster_aabb`]:
//!    conservative for every pixel position of the cluster, across CPU and GPU
//!    ([`crate::cluster_bounds`]).
//! 2. **Active clusters** — each pixel stores its dense cluster index ([`pixel_cluster`]) and flags
//!    it; then one invocation per cluster appends the flagged ones to the active list with a
//!    subgroup-aggregated atomic ([`subgroup_reserve`] of [`crate::light_lists`]: a ballot elects one lane, which reserves
//!    the whole subgroup's slots with one atomic add).
//! 3. **Assignment** — one invocation per active cluster. The workgroup stages [`LIGHT_BATCH`]
//!    lights at a time in workgroup memory; every invocation tests all staged lights against its
//!    box ([`lighting::sphere_intersects_aabb`]). Pass 1 counts, [`subgroup_reserve`] reserves
//!    the cluster's list space with one atomic per subgroup, pass 2 writes the light indices (in
//!    index order) — only if they fit the list buffer.
//! 4. **Shading** — per pixel, the lights of its cluster's list ([`shading::shade_lights`]).
//! 5. **Edge shading** (MSAA only, [`crate::msaa`]) — each edge pixel's samples with their own
//!    clusters' lists ([`shade_edges_aabb_diffuse`] / `_specular`).
//!
//! **Capacity.** The list buffer has a capacity; the reservation counter ends at the number of
//! references the frame needs, the host reads it back and, if it exceeds the capacity, grows the
//! buffer and re-runs the frame (nothing is written beyond it, and shading of an overflowed frame
//! writes background, never a partial sum).
//!
//! **llvmpipe's loop limiter**: per assignment invocation `2 · (N/16 + N/256)` iterations
//! (16 lights per iteration, straight-line) — 53 k for `N = 400 000`.
//!
//! **Memory** (`C = tiles_x · tiles_y · slices` clusters): boxes 32 B·C, flags, offsets and counts
//! 4 B·C each, the active list 4 B·min(C, pixels), 4 B per pixel of cluster indices, 4 B per light
//! reference. 1920×1080 with 32 px tiles (276 slices): C = 563 040 → 25.9 MB of grid data.
//! Workgroup memory: [`AABB_SHARED_WORDS`] words (8 KiB).
use crate::cluster_bounds::cluster_aabb;
pub use crate::dense_grid::{cluster_count, dense_coords, dense_index, pixel_cluster, NO_CLUSTER};
use crate::coop::gpu::GpuCoop;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::light_lists::{subgroup_reserve, AtomicAdd, ListSink};
use crate::light_types::{box_sphere, spot_may_meet};
use crate::shading::{self, linear_index, specular_entries, BACKGROUND_RGBA8};
use crate::lighting;
use glam::Vec3;
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Invocations per workgroup of every kernel here.
pub const AABB_WORKGROUP: u32 = 256;
/// Lights staged in workgroup memory per batch (one per invocation).
pub const LIGHT_BATCH: u32 = AABB_WORKGROUP;
/// Words of one staged light.
const LIGHT_WORDS: u32 = 8;
/// Workgroup memory of the assignment: one batch of lights.
pub const AABB_SHARED_WORDS: usize = (LIGHT_BATCH * LIGHT_WORDS) as usize;
const _: () = assert!(AABB_SHARED_WORDS * 4 <= 32 * 1024, "lavapipe has 32 KiB of workgroup memory");
const _: () = assert!(LIGHT_BATCH.is_multiple_of(16));

/// Slots of the counters buffer.
pub const AABB_COUNTER_ACTIVE: u32 = 0;
pub const AABB_COUNTER_REFS: u32 = 1;

#[inline]
fn stage_light<S: SharedU32 + ?Sized>(s: &mut S, slot: u32, l: &PointLight) {
    let b = slot * LIGHT_WORDS;
    s.store(b, l.position[0].to_bits());
    s.store(b + 1, l.position[1].to_bits());
    s.store(b + 2, l.position[2].to_bits());
    s.store(b + 3, l.radius.to_bits());
}

/// The staged light's sphere `(centre, radius)`.
#[inline]
fn staged_sphere<S: SharedU32 + ?Sized>(s: &S, slot: u32) -> (Vec3, f32) {
    let b = slot * LIGHT_WORDS;
    let f = |k: u32| f32::from_bits(s.load(b + k));
    (Vec3::new(f(0), f(1), f(2)), f(3))
}

/// One pass over all lights in staged batches: counts the lights whose sphere meets `aabb` (only
/// for `active` invocations) and, with `write`, puts them at `list[base + n]` in index order.
/// Called by every invocation of the workgroup (it synchronises).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn staged_pass<C: Coop, S: SharedU32 + ?Sized, L: ListSink + ?Sized>(
    c: &C,
    s: &mut S,
    lights: &[PointLight],
    num_lights: u32,
    effects: u32,
    aabb: &ClusterAabb,
    active: bool,
    list: &mut L,
    base: u32,
    write: bool,
) -> u32 {
    let (c0, r0) = box_sphere(Vec3::from_array(aabb.min), Vec3::from_array(aabb.max));
    let li = c.local_index();
    let mut n = 0;
    let mut batch = 0;
    while batch < num_lights {
        if batch + li < num_lights {
            stage_light(s, li, &crate::compact_light::light_at(lights, effects, num_lights, batch + li));
        }
        c.workgroup_barrier();
        let m = if num_lights - batch < LIGHT_BATCH { num_lights - batch } else { LIGHT_BATCH };
        if active {
            let mut t = 0;
            while t < m {
                unroll8!(u => {
                    if t + u < m {
                        let (centre, r) = staged_sphere(s, t + u);
                        // Spot lights (`EFFECT_SPOT`): the cone too, read and tested only for the
                        // few lights whose sphere meets the box.
                        if lighting::sphere_intersects_aabb(centre, r, aabb) && spot_may_meet(effects, lights, num_lights, batch + t + u, c0, r0) {
                            if write {
                                list.put(base + n, batch + t + u);
                            }
                            n += 1;
                        }
                    }
                });
                unroll8!(u => {
                    if t + 8 + u < m {
                        let (centre, r) = staged_sphere(s, t + 8 + u);
                        // Spot lights (`EFFECT_SPOT`): the cone too, read and tested only for the
                        // few lights whose sphere meets the box.
                        if lighting::sphere_intersects_aabb(centre, r, aabb) && spot_may_meet(effects, lights, num_lights, batch + t + 8 + u, c0, r0) {
                            if write {
                                list.put(base + n, batch + t + 8 + u);
                            }
                            n += 1;
                        }
                    }
                });
                t += 16;
            }
        }
        c.workgroup_barrier();
        batch += LIGHT_BATCH;
    }
    n
}

/// Step 3 for one invocation (`active`: it has a cluster with box `aabb`): count, reserve, fill.
/// Returns `(offset, count)`; the lights are written only if `offset + count ≤ capacity`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn assign<C: Coop, S: SharedU32 + ?Sized, A: AtomicAdd + ?Sized, L: ListSink + ?Sized>(
    c: &C,
    s: &mut S,
    lights: &[PointLight],
    num_lights: u32,
    effects: u32,
    aabb: &ClusterAabb,
    active: bool,
    refs: &mut A,
    list: &mut L,
    capacity: u32,
) -> (u32, u32) {
    let count = staged_pass(c, s, lights, num_lights, effects, aabb, active, list, 0, false);
    let base = subgroup_reserve(c, refs, count);
    let fits = active && base <= capacity && count <= capacity - base;
    staged_pass(c, s, lights, num_lights, effects, aabb, active, list, base, fits);
    (base, count)
}

/// 1. The box of every cluster of the grid.
#[spirv(compute(threads(256)))]
pub fn aabb_bounds(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] boxes: &mut [ClusterAabb],
) {
    let c = linear_index(wg, nwg, local);
    if c < p.count {
        let (i, j, k) = dense_coords(&p.grid, c);
        boxes[c as usize] = cluster_aabb(&p.grid, bounds, i, j, k);
    }
}

/// 2a. Each pixel's cluster, flagged; with MSAA (`crate::msaa`) every sample's cluster is
/// flagged too (the edge pass shades edge pixels' samples with them).
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn aabb_mark(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] pixel_clusters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] flags: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let g = &p.grid;
    let c = pixel_cluster(g, bounds, i % g.width, i / g.width, depth[i as usize]);
    pixel_clusters[i as usize] = c;
    if c != NO_CLUSTER {
        flags[c as usize] = 1;
    }
    let mut s = 1;
    while s < g.samples {
        let c = pixel_cluster(g, bounds, i % g.width, i / g.width, depth[(s * p.count + i) as usize]);
        if c != NO_CLUSTER && flags[c as usize] == 0 {
            flags[c as usize] = 1;
        }
        s += 1;
    }
}

/// 2b. Append the flagged clusters to the active list (one atomic per subgroup).
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn aabb_compact(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] flags: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] active: &mut [u32],
) {
    let co = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let c = linear_index(wg, nwg, local_index);
    let flagged = c < p.count && flags[c as usize] != 0;
    let slot = subgroup_reserve(&co, &mut counters[AABB_COUNTER_ACTIVE as usize], flagged as u32);
    if flagged {
        active[slot as usize] = c;
    }
}

/// 3. Light lists of the active clusters (`p.count` = slots dispatched, `p.light_capacity` = list
/// capacity).
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn aabb_assign(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(workgroup)] shared: &mut [u32; AABB_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] active: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] boxes: &[ClusterAabb],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] offsets: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] list: &mut [u32],
) {
    let p = &crate::light_types::specialise(p, light_types);
    let co = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let slot = linear_index(wg, nwg, local_index);
    let num_active = counters[AABB_COUNTER_ACTIVE as usize];
    // Whole workgroups past the active list leave together (uniform).
    if slot - local_index >= num_active {
        return;
    }
    let is_active = slot < num_active;
    let cluster = if is_active { active[slot as usize] } else { 0 };
    let aabb = boxes[cluster as usize];
    let (base, count) =
        assign(&co, shared, lights, p.num_lights, p.effects, &aabb, is_active, &mut counters[AABB_COUNTER_REFS as usize], list, p.light_capacity);
    if is_active {
        offsets[cluster as usize] = base;
        counts[cluster as usize] = count;
    }
}

specular_entries! {
    shade_aabb_diffuse, shade_aabb_specular;
    /// 4. Shading: per pixel, its cluster's lights (`_diffuse` / `_specular` variants).
    fn shade_aabb_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] pixel_clusters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] shadow_maps: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let i = shading::block_pixel(wg, local, p.grid.width, p.grid.height);
        if i == shading::NO_PIXEL {
            return;
        }
        let cluster = pixel_clusters[i as usize];
        // An overflowed frame is re-run with a larger list: draw nothing from a partial one.
        if cluster == NO_CLUSTER || counters[AABB_COUNTER_REFS as usize] > p.light_capacity {
            frame[i as usize] = BACKGROUND_RGBA8;
            return;
        }
        let cluster_list = shading::index_range(offsets[cluster as usize], counts[cluster as usize], |t| list[t as usize]);
        let shadows = crate::shadow::CubeShadows { slots: shadow_slots, maps: shadow_maps };
        frame[i as usize] = shading::shade_gbuffer_pixel::<SPECULAR, _, _>(p, bounds, i, depth, normals, albedo, materials, lights, &cluster_list, &shadows);
    }
}

specular_entries! {
    shade_edges_aabb_diffuse, shade_edges_aabb_specular;
    /// 5. With MSAA (`crate::msaa`): edge `slot` of the edge list, each sample with its own
    /// cluster's list (step 2 flagged every sample's cluster).
    fn shade_edges_aabb_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(num_workgroups)] nwg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] edges: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let slot = linear_index(wg, nwg, local);
        // An overflowed frame is re-run with a larger list (its pixels were drawn as background).
        if slot >= edges[0] || counters[AABB_COUNTER_REFS as usize] > p.light_capacity {
            return;
        }
        let i = edges[(crate::msaa::EDGE_HEADER_WORDS + slot) as usize];
        let (n, effects, num_lights, g) = (p.count, p.effects, p.num_lights, p.grid);
        let shade = move |s: u32, surface: &shading::Surface| {
            let c = pixel_cluster(&g, bounds, i % g.width, i / g.width, depth[(s * n + i) as usize]) as usize;
            let mut sum = Vec3::ZERO;
            let count = shading::shade_lights::<SPECULAR, true, _>(surface, effects, num_lights, lights, &shading::list_range(list, offsets[c], counts[c]), &mut sum);
            shading::shade_directional_lights::<SPECULAR>(surface, effects, num_lights, lights, &mut sum);
            (sum, count)
        };
        frame[i as usize] = crate::msaa::shade_edge_pixel(p, i, bounds, depth, normals, albedo, materials, shade);
    }
}

#[cfg(test)]
#[path = "clustered_aabb_tests.rs"]
mod tests;
