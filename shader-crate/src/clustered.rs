//! Entry points of the clustered-deferred chain (`clustered-naive`, and the steps
//! `clustered-bvh` shares with it; Olsson, Billeter, Assarsson 2012, "Clustered Deferred and
//! Forward Shading", HPG, with Karas' virtual page table for the unique clusters).
//!
//! # Steps (one entry each; each unpacks its invocation's [`shading::linear_index`] and calls a
//! pure function)
//!
//! 1–5. **Unique clusters** — [`pixel_keys`] (keys, and the marks of their pages),
//!    [`allocate_pages`], [`store_slots`], [`count_page_slots`], [`scan_page_counts`],
//!    [`compact_page_slots`]: the page table of
//!    [`crate::page_table`] (steps and memory there). Each mark and slot is cleared by its last
//!    reader, so no frame clears the tables at their capacity.
//! 6–7. **Naive assignment** — [`cluster_light_counts`] (and each list's place: [`reserve_list`]),
//!    [`cluster_light_fill`]: every
//!    light against each unique cluster's box ([`for_each_cluster_light`], [`crate::lighting`],
//!    [`crate::cluster_bounds`]); `clustered-bvh` replaces these two with [`crate::clustered_bvh`].
//! 8. **Shading** — [`shade_clustered_diffuse`] / [`shade_clustered_specular`]: per pixel, key →
//!    page → slot → cluster → its list, through [`shading::shade_lights`].
//! 9. **Edge shading** (MSAA only, [`crate::msaa`]) — [`shade_edges_clustered_diffuse`] / `_specular`
//!    (and the tile path's `shade_edges_clustered_tiles_*`): each edge pixel's samples with their
//!    own clusters' lists; steps 1–5 found every sample's cluster.
//!
//! **Memory**: the page table's (see [`crate::page_table`]), counts and offsets 4 B per unique
//! cluster, 4 B per light reference; the page-table kernels use the scan's workgroup memory
//! (`scan::SCAN_SHARED_WORDS` words).
// Entry points take one parameter per built-in and binding.
#![allow(clippy::too_many_arguments)]

use crate::coop::gpu::GpuCoop;
use crate::layout::*;
use crate::light_lists::{lights_meeting, lights_meeting_spots};
use crate::light_types::{box_sphere, EFFECT_SPOT};
use crate::page_table::{self, INVALID_KEY};
use crate::shading::{self, linear_index, specular_entries, BACKGROUND_RGBA8};
use crate::tile_clusters;
use crate::{cluster_bounds, cluster_test, lighting};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// 1–2. Cluster key per pixel from the depth buffer, and the mark of its page. With MSAA
/// (`crate::msaa`) per sample: entry `e = s·n + i` of every plane (`p.count` = samples × pixels),
/// so the edge pixels' samples have their clusters too.
#[spirv(compute(threads(256)))]
pub fn pixel_keys(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] marks: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let g = &p.grid;
    let (e, i) = (i, i % (g.width * g.height));
    let key = page_table::pixel_key(g, bounds, i % g.width, i / g.width, depth[e as usize]);
    keys[e as usize] = key;
    // Most pixels find their page marked already: a load instead of a store to a word that
    // thousands of pixels share.
    if key != INVALID_KEY {
        let page = page_table::page_of(key) as usize;
        if marks[page] == 0 {
            marks[page] = 1;
        }
    }
}

/// 1–5 on the tile path ([`crate::tile_clusters`]), one workgroup per tile: the tile's pixel
/// keys, its clusters (a mask of its slices) reserved in the unique-cluster list, their keys
/// there, the tile's records for the shading's lookup, and the assignment's dispatch raised to
/// cover them (one atomic add and one atomic maximum per tile). Workgroup (0, 0) zeroes the
/// light-reference counter (the page count stays at the zero the buffer starts with: this path
/// allocates no pages).
#[spirv(compute(threads(256)))] // tile_clusters::TILE_WORKGROUP
pub fn tile_clusters(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &TileClusterParams,
    #[spirv(workgroup)] shared: &mut [u32; tile_clusters::SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] records: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] unique: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] args: &mut [u32],
) {
    use crate::light_lists::{AtomicAdd, AtomicMax};
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let g = &p.frame.grid;
    let (i, j) = (wg.x, wg.y);
    let rect = tile_clusters::tile_rect(g, i, j);
    let words = tile_clusters::mask_words(g);
    // Captured by value (`move`): a closure holding a reference to a local is a pointer that
    // `spirv-val` may reject.
    // With MSAA (`crate::msaa`) every sample's key, plane by plane (`s·n + i`).
    let to_keys = &mut *keys;
    let (tile_pixels, plane) = (rect.2 * rect.3, g.width * g.height);
    let slice_of = move |s: u32, q: u32| {
        let (px, py) = tile_clusters::tile_pixel(rect, q);
        let at = s * plane + py * g.width + px;
        let key = page_table::pixel_key(g, bounds, px, py, depth[at as usize]);
        to_keys[at as usize] = key;
        if key == INVALID_KEY {
            tile_clusters::NO_SLICE
        } else {
            g.unpack(key).2
        }
    };
    let (per_group, a) = (p.per_group, ARGS_ASSIGNMENT as usize);
    let (to_counters, to_args) = (&mut *counters, &mut *args);
    let reserve = move |n: u32| {
        let first = to_counters[COUNTER_UNIQUE_CLUSTERS as usize].fetch_add(n);
        let (x, y) = tile_clusters::dispatch_raise(first + n, per_group);
        to_args[a].fetch_max(x);
        if y > 1 {
            to_args[a + 1].fetch_max(y);
        }
        first
    };
    let (mask, first) = tile_clusters::tile_clusters(&c, shared, words, tile_pixels, g.samples, slice_of, reserve);
    if local_index < words {
        let at = tile_clusters::record_at(g, i, j, local_index) as usize;
        records[at] = mask;
        records[at + 1] = first;
        let (capacity, to_unique) = (p.frame.count, &mut *unique);
        tile_clusters::emit_word_clusters(g, i, j, local_index, mask, first, move |n, key| {
            if n < capacity {
                to_unique[n as usize] = key;
            }
        });
    }
    if i == 0 && j == 0 && local_index == 0 {
        counters[COUNTER_LIGHT_REFS as usize] = 0;
        // Rows and depth of the dispatch: at least one each (more rows only past 65 535 groups).
        args[a + 1].fetch_max(1);
        args[a + 2].fetch_max(1);
    }
}

/// 3. Allocate the marked pages in one workgroup (`page_table::allocate_scan`,
/// `page_table::allocate_run`): page table, pages of the allocation, marks cleared, the page
/// count, a dispatch of one workgroup per allocated page, and the light-reference counter zeroed.
#[spirv(compute(threads(256)))] // page_table::ALLOCATE_WORKGROUP
pub fn allocate_pages(
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &PageTableParams,
    #[spirv(workgroup)] shared: &mut [u32; crate::scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] marks: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_base: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] page_of_alloc: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] args: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let (base, total) = page_table::allocate_scan(&c, shared, p.pages, marks);
    page_table::allocate_run(p.pages, local_index, base, p.capacity, marks, page_base, page_of_alloc);
    if local_index == 0 {
        counters[COUNTER_PAGES as usize] = total;
        // The frame's other counters are stored whole by their passes; the light references
        // are summed by atomics (`reserve_list`) and start here, so no pass clears the counters.
        counters[COUNTER_LIGHT_REFS as usize] = 0;
        let allocated = if total < p.capacity { total } else { p.capacity };
        store_args(args, p.args_offset, crate::indirect::dispatch_args(allocated, 1));
    }
}

/// Writes a `VkDispatchIndirectCommand` at word `offset`.
#[inline]
fn store_args(args: &mut [u32], offset: u32, a: [u32; 3]) {
    let o = offset as usize;
    args[o] = a[0];
    args[o + 1] = a[1];
    args[o + 2] = a[2];
}

/// The allocated page a page-table workgroup takes (2D-folded dispatches).
#[inline]
fn page_of_group(wg: UVec3, nwg: UVec3) -> u32 {
    wg.y * nwg.x + wg.x
}

/// 4. Flag each pixel's key in its page.
#[spirv(compute(threads(256)))]
pub fn store_slots(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_base: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] slots: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let key = keys[i as usize];
    if key != INVALID_KEY {
        let base = page_base[page_table::page_of(key) as usize];
        let slot = page_table::slot_index(base, key) as usize;
        // A load first: a cluster's pixels share its slot.
        if slots[slot] == 0 {
            slots[slot] = 1;
        }
    }
}

/// 5a. The set slots of each allocated page (one workgroup per page, `page_table::page_slot_scan`).
#[spirv(compute(threads(256)))] // page_table::ALLOCATE_WORKGROUP
pub fn count_page_slots(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(workgroup)] shared: &mut [u32; crate::scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] slots: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_counts: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let page = page_of_group(wg, nwg);
    let (_, set) = page_table::page_slot_scan(&c, shared, slots, page);
    if local_index == 0 {
        page_counts[page as usize] = set;
    }
}

/// 5b. The allocated pages' slot counts scanned in one workgroup (`page_table::run_scan`): each
/// page's first rank, the unique clusters, the assignment's dispatch and the staged lists' stride.
#[spirv(compute(threads(256)))] // page_table::ALLOCATE_WORKGROUP
pub fn scan_page_counts(
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &PageTableParams,
    #[spirv(workgroup)] shared: &mut [u32; crate::scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] page_counts: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_offsets: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] args: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let pages = counters[COUNTER_PAGES as usize];
    let n = if pages < p.capacity { pages } else { p.capacity };
    let (base, total) = page_table::run_scan(&c, shared, n, |i| page_counts[i as usize]);
    let (start, end) = page_table::run_span(n, local_index);
    let mut next = base;
    let mut i = start;
    while i < end {
        page_offsets[i as usize] = next;
        next += page_counts[i as usize];
        i += 1;
    }
    if local_index == 0 {
        counters[COUNTER_UNIQUE_CLUSTERS as usize] = total;
        counters[COUNTER_FRAME_CLUSTERS as usize] = total;
        store_args(args, p.args_offset, crate::indirect::dispatch_args(total, p.per_group));
    }
}

/// 5c. Each allocated page's set slots ranked from its offset (one workgroup per page, two slots
/// per invocation, `page_table::page_slot_scan`) and scattered into the sorted unique-cluster
/// list; each slot cleared (its last reader).
#[spirv(compute(threads(256)))] // page_table::ALLOCATE_WORKGROUP
pub fn compact_page_slots(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(workgroup)] shared: &mut [u32; crate::scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] slots: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] page_of_alloc: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] slot_rank: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] unique: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let page = page_of_group(wg, nwg);
    let (before, _) = page_table::page_slot_scan(&c, shared, slots, page);
    let first = page_table::slot_pair(page, local_index);
    let mut rank = page_offsets[page as usize] + before;
    let mut s = first;
    while s < first + 2 {
        if slots[s as usize] != 0 {
            slot_rank[s as usize] = rank;
            unique[rank as usize] = page_table::key_of_slot(page_of_alloc, s);
            slots[s as usize] = 0;
            rank += 1;
        }
        s += 1;
    }
}

/// Lights of cluster `key` whose sphere meets its box (naive: all lights), in index order;
/// returns the count and calls `emit(n, light)` for each. With `EFFECT_CULL_PLANES` or
/// `EFFECT_CULL_EXACT` (the accuracy study) the cluster's frustum planes or the exact
/// sphere–frustum test (`cluster_test`) replace the box.
#[inline]
pub fn for_each_cluster_light(p: &FrameParams, bounds: &[f32], lights: &[PointLight], key: u32, emit: impl FnMut(u32, u32)) -> u32 {
    // The mode is uniform: one loop per test, so the default loop carries no other test's code.
    let mode = p.effects & (EFFECT_CULL_PLANES | EFFECT_CULL_EXACT);
    let aabb = cluster_bounds::cluster_aabb_of_key(&p.grid, bounds, key);
    if p.effects & EFFECT_SPOT != 0 {
        // Spot lights: the same range tests, then the cone against the box's bounding sphere.
        let (c0, r0) = box_sphere(spirv_std::glam::Vec3::from_array(aabb.min), spirv_std::glam::Vec3::from_array(aabb.max));
        let (i, j, k) = p.grid.unpack(key);
        let frustum = cluster_test::cluster_frustum(&p.grid, bounds, i, j, k);
        let (e, n) = (p.effects, p.num_lights);
        return if mode == 0 {
            lights_meeting_spots(e, n, lights, emit, |c, r| lighting::sphere_intersects_aabb(c, r, &aabb), c0, r0)
        } else if mode == EFFECT_CULL_PLANES {
            lights_meeting_spots(e, n, lights, emit, |c, r| !cluster_test::sphere_outside_planes(&frustum, c, r), c0, r0)
        } else {
            lights_meeting_spots(e, n, lights, emit, |c, r| cluster_test::sphere_meets_frustum(&frustum, c, r), c0, r0)
        };
    }
    if mode == 0 {
        return lights_meeting(p.effects, p.num_lights, lights, emit, |c, r| lighting::sphere_intersects_aabb(c, r, &aabb));
    }
    let (i, j, k) = p.grid.unpack(key);
    let frustum = cluster_test::cluster_frustum(&p.grid, bounds, i, j, k);
    if mode == EFFECT_CULL_PLANES {
        lights_meeting(p.effects, p.num_lights, lights, emit, |c, r| !cluster_test::sphere_outside_planes(&frustum, c, r))
    } else {
        lights_meeting(p.effects, p.num_lights, lights, emit, |c, r| cluster_test::sphere_meets_frustum(&frustum, c, r))
    }
}

/// 6. Naive light assignment, pass 1: lights per unique cluster.
#[spirv(compute(threads(256)))]
pub fn cluster_light_counts(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] offsets: &mut [u32],
) {
    let p = &crate::light_types::specialise(p, light_types);
    let c = linear_index(wg, nwg, local);
    if c >= p.count || c >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    let n = for_each_cluster_light(p, bounds, lights, unique[c as usize], |_, _| {});
    counts[c as usize] = n;
    offsets[c as usize] = reserve_list(counters, n);
}

/// 6–7 (both assignments). The start of a cluster's list of `n` lights in the global list: `n`
/// entries reserved with one atomic add on [`COUNTER_LIGHT_REFS`], which ends the pass as the
/// frame's total of light references (the host grows the list when it exceeds the capacity: the
/// naive fill pass then writes nothing, the BVH assignment no list that would end past it).
/// Lists land in the order the clusters reserve them; each cluster's own list is in light order
/// whatever that order, and shading reads it through its offset and count. One atomic per cluster instead of a device-wide scan of the counts
/// (seven dependent dispatches on the H200: 6 µs each).
#[inline]
pub fn reserve_list(counters: &mut [u32], n: u32) -> u32 {
    use crate::light_lists::AtomicAdd;
    counters[COUNTER_LIGHT_REFS as usize].fetch_add(n)
}

/// 7. Naive light assignment, pass 2: write each cluster's light indices at its offset.
#[spirv(compute(threads(256)))]
pub fn cluster_light_fill(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] list: &mut [u32],
) {
    let p = &crate::light_types::specialise(p, light_types);
    let c = linear_index(wg, nwg, local);
    if c >= p.count || c >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    // A frame whose lists do not fit writes nothing; the host sees the total and grows the list.
    if counters[COUNTER_LIGHT_REFS as usize] > p.light_capacity {
        return;
    }
    let base = offsets[c as usize];
    for_each_cluster_light(p, bounds, lights, unique[c as usize], |n, l| list[(base + n) as usize] = l);
}

specular_entries! {
    shade_clustered_diffuse, shade_clustered_specular;
    /// 8. Clustered shading: per pixel, its cluster's lights (`_diffuse` for scenes without specular
    /// materials, the specular term compiled out, and `_specular`).
    fn shade_clustered_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] page_base: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] slot_rank: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 14)] shadow_maps: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let Some((i, key)) = keyed_pixel(p, wg, local, keys, frame) else { return };
        let cluster = slot_rank[page_table::slot_index(page_base[page_table::page_of(key) as usize], key) as usize] as usize;
        let cluster_list = shading::list_range(list, offsets[cluster], counts[cluster]);
        let shadows = crate::shadow::CubeShadows { slots: shadow_slots, maps: shadow_maps };
        frame[i as usize] = shading::shade_gbuffer_pixel::<SPECULAR, _, _>(p, bounds, i, depth, normals, albedo, materials, lights, &cluster_list, &shadows);
    }
}

specular_entries! {
    shade_edges_clustered_diffuse, shade_edges_clustered_specular;
    /// 9. With MSAA (`crate::msaa`): edge `slot` of the edge list, each sample with the list of
    /// its own cluster (its key from step 1, found through the page table as in step 8).
    fn shade_edges_clustered_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(num_workgroups)] nwg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] page_base: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] slot_rank: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] edges: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let Some(i) = edge_pixel(wg, nwg, local, edges) else { return };
        let (n, effects, num_lights) = (p.count, p.effects, p.num_lights);
        let shade = move |s: u32, surface: &shading::Surface| {
            let key = keys[(s * n + i) as usize];
            let cluster = slot_rank[page_table::slot_index(page_base[page_table::page_of(key) as usize], key) as usize] as usize;
            shade_cluster::<SPECULAR>(surface, effects, num_lights, lights, &shading::list_range(list, offsets[cluster], counts[cluster]))
        };
        frame[i as usize] = crate::msaa::shade_edge_pixel(p, i, bounds, depth, normals, albedo, materials, shade);
    }
}

specular_entries! {
    shade_edges_clustered_tiles_diffuse, shade_edges_clustered_tiles_specular;
    /// 9 on the tile path: each sample's cluster through its tile's record
    /// ([`tile_clusters::cluster_of_key`]).
    fn shade_edges_clustered_tiles_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(num_workgroups)] nwg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] records: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] edges: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let Some(i) = edge_pixel(wg, nwg, local, edges) else { return };
        let (n, effects, num_lights, grid) = (p.count, p.effects, p.num_lights, p.grid);
        let shade = move |s: u32, surface: &shading::Surface| {
            let cluster = tile_clusters::cluster_of_key(&grid, records, keys[(s * n + i) as usize]) as usize;
            shade_cluster::<SPECULAR>(surface, effects, num_lights, lights, &shading::list_range(list, offsets[cluster], counts[cluster]))
        };
        frame[i as usize] = crate::msaa::shade_edge_pixel(p, i, bounds, depth, normals, albedo, materials, shade);
    }
}

/// The pixel of an edge-pass invocation: entry `slot` of the edge list, or `None` past its end.
#[inline]
fn edge_pixel(wg: UVec3, nwg: UVec3, local: u32, edges: &[u32]) -> Option<u32> {
    let slot = linear_index(wg, nwg, local);
    if slot >= edges[0] {
        return None;
    }
    Some(edges[(crate::msaa::EDGE_HEADER_WORDS + slot) as usize])
}

/// A sample's radiance over its cluster's list and the directional lights, and the list's length.
#[inline]
fn shade_cluster<const SPECULAR: bool>(surface: &shading::Surface, effects: u32, num_lights: u32, lights: &[PointLight], list: &impl shading::LightList) -> (spirv_std::glam::Vec3, u32) {
    let mut sum = spirv_std::glam::Vec3::ZERO;
    let count = shading::shade_lights::<SPECULAR, true, _>(surface, effects, num_lights, lights, list, &mut sum);
    shading::shade_directional_lights::<SPECULAR>(surface, effects, num_lights, lights, &mut sum);
    (sum, count)
}

/// The pixel (and its key) a cluster-list shading invocation shades, or `None` past the frame
/// and for background, whose colour it stores.
#[inline]
fn keyed_pixel(p: &FrameParams, wg: UVec3, local: u32, keys: &[u32], frame: &mut [u32]) -> Option<(u32, u32)> {
    let i = shading::block_pixel(wg, local, p.grid.width, p.grid.height);
    if i == shading::NO_PIXEL {
        return None;
    }
    let key = keys[i as usize];
    if key == INVALID_KEY {
        frame[i as usize] = BACKGROUND_RGBA8;
        return None;
    }
    Some((i, key))
}

specular_entries! {
    shade_clustered_tiles_diffuse, shade_clustered_tiles_specular;
    /// 8 on the tile path: per pixel, key → its tile's record → cluster → its list
    /// ([`tile_clusters::cluster_of_key`]). The first invocation, the last reader of the
    /// cluster counter and the assignment's dispatch, hands the count to the host
    /// (`COUNTER_FRAME_CLUSTERS`) and zeroes both for the next frame's [`tile_clusters`].
    fn shade_clustered_tiles_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] records: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] offsets: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] list: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] counters: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] args: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 14)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] shadow_maps: &[u32],
    ) {
        if wg.x == 0 && wg.y == 0 && local == 0 {
            tile_clusters::hand_over_counters(counters, args);
        }
        let p = &crate::light_types::specialise(p, light_types);
        let Some((i, key)) = keyed_pixel(p, wg, local, keys, frame) else { return };
        let cluster = tile_clusters::cluster_of_key(&p.grid, records, key) as usize;
        let cluster_list = shading::list_range(list, offsets[cluster], counts[cluster]);
        let shadows = crate::shadow::CubeShadows { slots: shadow_slots, maps: shadow_maps };
        frame[i as usize] = shading::shade_gbuffer_pixel::<SPECULAR, _, _>(p, bounds, i, depth, normals, albedo, materials, lights, &cluster_list, &shadows);
    }
}
