//! Entry points of the `clustered-bvh` technique: Morton keys of the lights, the light BVH build
//! (one dispatch per level, bottom-up) and the traversal-based light assignment (one subgroup per
//! unique cluster, [`light_bvh::walk_subgroup`]), which replaces
//! the naive search of [`crate::clustered`] and writes the same counts and lists (as sets).
use crate::cluster_bounds::cluster_aabb_of_key;
use crate::compact_light::light_at;
use crate::coop::gpu::GpuCoop;
use crate::coop::{subgroup_item, Coop};
use crate::layout::*;
use crate::light_bvh;
use crate::shading::linear_index;
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Step 1: Morton key (view-space position quantised in the lights' bounds) and index per light.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn light_keys(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &MortonParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] order: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i < p.count {
        keys[i as usize] = p.q30.morton30_of(light_at(lights, light_types, p.count, i).position);
        order[i as usize] = i;
    }
}

/// Step 2a: the lights' spheres in sorted order (`spheres[s]` = light `order[s]`'s), so that the
/// leaves and the walks read them coalesced, 16 B each, instead of through `order`.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn bvh_spheres(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &BvhParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] spheres: &mut [LightSphere],
) {
    let s = linear_index(wg, nwg, local);
    if s < p.count {
        // In bounds: `s < count`, the sorted lights `order` and `spheres` hold.
        crate::unchecked::set(spheres, s, light_bvh::sphere_of(&light_at(lights, light_types, p.count, crate::unchecked::at(order, s))));
    }
}

/// Step 2b: boxes of level-0 nodes (`B` sorted lights each), one subgroup per node
/// ([`light_bvh::leaf_node_box_subgroup`]).
#[spirv(compute(threads(64)))] // light_bvh::WALK_WORKGROUP
#[allow(clippy::too_many_arguments)]
pub fn bvh_leaves(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &BvhParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] spheres: &[LightSphere],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] nodes: &mut [ClusterAabb],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let node = subgroup_item(&c, wg, nwg);
    if node < p.nodes {
        let bx = light_bvh::leaf_node_box_subgroup(&c, spheres, p.count, p.branching, node);
        if lane == 0 {
            nodes[node as usize] = bx;
        }
    }
}

/// Step 2c: boxes of level `p.level ≥ 1` from the level below (same buffer, disjoint ranges).
#[spirv(compute(threads(256)))]
pub fn bvh_level(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &BvhParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] nodes: &mut [ClusterAabb],
) {
    let node = linear_index(wg, nwg, local);
    if node < p.nodes {
        let b = light_bvh::inner_node_box(nodes, p.count, p.branching, p.level, node);
        nodes[(light_bvh::level_offset(p.count, p.level, p.branching) + node) as usize] = b;
    }
}

/// Lights of cluster `key` by the subgroup-parallel BVH walk (count on every lane; `emit(k,
/// light)` on the lanes that found a light).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn cluster_lights_bvh<C: Coop>(
    c: &C,
    p: &BvhAssignParams,
    bounds: &[f32],
    spheres: &[LightSphere],
    order: &[u32],
    nodes: &[ClusterAabb],
    lights: &[PointLight],
    key: u32,
    emit: impl FnMut(u32, u32),
) -> u32 {
    let f = &p.frame;
    light_bvh::walk_subgroup(c, nodes, spheres, order, f.num_lights, p.branching, &cluster_aabb_of_key(&f.grid, bounds, key), f.effects, lights, emit)
}

/// The staged lists: the walk stores each cluster's lights as it counts them, and copies every
/// list that fits to its place once reserved instead of walking the tree again (longer lists
/// are walked twice). The buffer's words are shared out among the frame's unique clusters
/// ([`stage_stride`]), so a frame with few clusters stages long lists: on the H200 (Sponza
/// 1080p, 6 732 clusters, 16 MiB) every list up to 1 024 lights, where 64 per cluster left the
/// fill pass re-walking most clusters at 1M lights (0.165 ms of its 0.404 ms assignment).
/// Lights each cluster's stage holds at most: a 2 000-light cluster still walks twice (the
/// path the tests keep exercised).
pub const MAX_STAGE_STRIDE: u32 = 1024;
/// Lights per cluster the stage is sized for (`STAGED_CLUSTERS` clusters of this many words).
pub const STAGED_LIGHTS: u32 = 64;
/// Clusters the stage is sized for: the host allocates `min(this, its cluster capacity) ·
/// STAGED_LIGHTS` words (16 MiB at most). A 1080p Sponza frame has about 7k unique clusters.
pub const STAGED_CLUSTERS: u32 = 1 << 16;

/// Words of the stage per cluster for `clusters` unique clusters sharing `words`: at most
/// [`MAX_STAGE_STRIDE`] (0 without a stage).
#[inline]
pub fn stage_stride(words: u32, clusters: u32) -> u32 {
    let s = words.checked_div(clusters).unwrap_or(0);
    if s < MAX_STAGE_STRIDE { s } else { MAX_STAGE_STRIDE }
}

/// Whether a cluster with `count` lights has its whole list staged (`stride` words each).
#[inline]
pub fn staged(count: u32, stride: u32) -> bool {
    count <= stride
}

/// Stores light `light` of cluster `cl`'s list at slot `k` of its stage, where it fits.
#[inline]
pub fn stage(stage: &mut [u32], cl: u32, k: u32, light: u32, stride: u32) {
    if k < stride {
        stage[(cl * stride + k) as usize] = light;
    }
}

/// Step 3 for a staged cluster: its `count` lights copied to `list[base..]`, lane by lane.
#[inline]
pub fn copy_staged<C: Coop>(c: &C, stage: &[u32], cl: u32, count: u32, stride: u32, base: u32, mut store: impl FnMut(u32, u32)) {
    let mut i = c.lane();
    while i < count {
        store(base + i, stage[(cl * stride + i) as usize]);
        i += c.subgroup_size();
    }
}

/// Step 3: the lights of each unique cluster, one subgroup per cluster, in one pass. The walk
/// counts the lights and stages the first [`stage_stride`] of them; lane 0
/// reserves the list ([`crate::clustered::reserve_list`]); a staged list is then copied to its
/// place (after a subgroup barrier on storage memory: a lane copies entries other lanes staged),
/// a longer one walked again straight into it. A list that would end past the list's capacity
/// is not written: the counter ends as the frame's total and the host grows the list.
#[spirv(compute(threads(64)))] // light_bvh::WALK_WORKGROUP
#[allow(clippy::too_many_arguments)]
pub fn assign_lights_bvh(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &BvhAssignParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] spheres: &[LightSphere],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] nodes: &[ClusterAabb],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] staged_lists: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] offsets: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] list: &mut [u32],
) {
    let p = &crate::light_types::specialise(p, light_types);
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let cl = subgroup_item(&c, wg, nwg);
    if cl >= p.frame.count || cl >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    let stride = stage_stride(p.stage_words, counters[COUNTER_UNIQUE_CLUSTERS as usize]);
    let key = unique[cl as usize];
    // One walk in the code, run once (staging) or twice (the second straight into the list):
    // one inlined walk keeps the kernel as small as the two it replaces.
    let mut base = 0;
    let mut second = false;
    loop {
        // Captured by value: a closure holding a reference to a loop variable is a pointer
        // that `spirv-val` rejects.
        let (at, into_list, to_stage, to_list) = (base, second, &mut *staged_lists, &mut *list);
        let count = cluster_lights_bvh(&c, p, bounds, spheres, order, nodes, lights, key, move |k, l| {
            if into_list {
                to_list[(at + k) as usize] = l;
            } else {
                stage(to_stage, cl, k, l, stride);
            }
        });
        if second {
            return;
        }
        let reserved = if lane == 0 { crate::clustered::reserve_list(counters, count) } else { 0 };
        base = c.shuffle(reserved, 0);
        if lane == 0 {
            counts[cl as usize] = count;
            offsets[cl as usize] = base;
        }
        if !fits(base, count, p.frame.light_capacity) {
            return;
        }
        if staged(count, stride) {
            c.subgroup_storage_barrier();
            copy_staged(&c, staged_lists, cl, count, stride, base, |i, l| list[i as usize] = l);
            return;
        }
        second = true;
    }
}

/// Whether a list of `count` entries at `base` ends within `capacity` (no overflow of `u32`).
#[inline]
pub fn fits(base: u32, count: u32, capacity: u32) -> bool {
    count <= capacity && base <= capacity - count
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stage's words are shared out among the frame's clusters, capped per cluster; a frame
    /// with more clusters than words, or none, stages nothing.
    #[test]
    fn the_stage_is_shared_out_among_the_frames_clusters() {
        let words = STAGED_CLUSTERS * STAGED_LIGHTS;
        assert_eq!(stage_stride(words, 6732), 623);
        assert_eq!(stage_stride(words, 25_255), 166);
        assert_eq!(stage_stride(words, 100), MAX_STAGE_STRIDE);
        assert_eq!(stage_stride(words, STAGED_CLUSTERS), STAGED_LIGHTS);
        assert_eq!(stage_stride(words, words + 1), 0);
        assert_eq!(stage_stride(words, 0), 0);
        assert_eq!(stage_stride(0, 10), 0);
        // A list is written only where it ends within the capacity.
        assert!(fits(0, 10, 10) && fits(6, 4, 10) && fits(10, 0, 10));
        assert!(!fits(7, 4, 10) && !fits(0, 11, 10) && !fits(u32::MAX, 2, 10) && !fits(3, u32::MAX, 10));
        // Every cluster's stage lies inside the buffer.
        for clusters in [1, 7, 6732, 65_536, 1 << 20] {
            let s = stage_stride(words, clusters);
            assert!(clusters as u64 * s as u64 <= words as u64, "{clusters} clusters");
            assert!(staged(s, s) && !staged(s + 1, s));
        }
    }
}
