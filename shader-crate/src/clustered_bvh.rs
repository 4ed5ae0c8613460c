//! Entry points of the `clustered-bvh` technique: Morton keys of the lights, the light BVH build
//! (one dispatch per level, bottom-up) and the traversal-based light assignment, which replaces
//! the naive search of [`crate::clustered`] and writes the same counts and lists (as sets).
use crate::clustered::{cluster_box, linear_index};
use crate::layout::*;
use crate::light_bvh;
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Step 1: Morton key (view-space position quantised in the lights' bounds) and index per light.
#[spirv(compute(threads(256)))]
pub fn light_keys(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &MortonParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] order: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i < p.count {
        keys[i as usize] = p.q30.morton30_of(lights[i as usize].position);
        order[i as usize] = i;
    }
}

/// Step 2a: boxes of level-0 nodes (`B` sorted lights each).
#[spirv(compute(threads(256)))]
pub fn bvh_leaves(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &BvhParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] nodes: &mut [ClusterAabb],
) {
    let node = linear_index(wg, nwg, local);
    if node < p.nodes {
        nodes[node as usize] = light_bvh::leaf_node_box(lights, order, p.count, node);
    }
}

/// Step 2b: boxes of level `p.level ≥ 1` from the level below (same buffer, disjoint ranges).
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
        let b = light_bvh::inner_node_box(nodes, p.count, p.level, node);
        nodes[(light_bvh::level_offset(p.count, p.level) + node) as usize] = b;
    }
}

/// Lights of cluster `key` by BVH traversal (count, and `emit(k, light)` per light).
#[inline]
pub fn for_each_cluster_light_bvh(
    p: &FrameParams,
    bounds: &[f32],
    lights: &[PointLight],
    order: &[u32],
    nodes: &[ClusterAabb],
    key: u32,
    emit: impl FnMut(u32, u32),
) -> u32 {
    light_bvh::for_each_bvh_light(nodes, lights, order, p.num_lights, &cluster_box(p, bounds, key), emit)
}

/// Step 3, pass 1: lights per unique cluster.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn cluster_light_counts_bvh(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] nodes: &[ClusterAabb],
) {
    let c = linear_index(wg, nwg, local);
    if c >= p.count {
        return;
    }
    counts[c as usize] = if c < counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        for_each_cluster_light_bvh(p, bounds, lights, order, nodes, unique[c as usize], |_, _| {})
    } else {
        0
    };
}

/// Step 3, pass 2: each cluster's light indices at its offset.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn cluster_light_fill_bvh(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] list: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] nodes: &[ClusterAabb],
) {
    let c = linear_index(wg, nwg, local);
    if c >= p.count || c >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    if counters[COUNTER_LIGHT_REFS as usize] > p.light_capacity {
        return;
    }
    let base = offsets[c as usize];
    for_each_cluster_light_bvh(p, bounds, lights, order, nodes, unique[c as usize], |n, l| list[(base + n) as usize] = l);
}
