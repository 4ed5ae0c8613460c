//! Entry points of the `clustered-bvh` technique: Morton keys of the lights, the light BVH build
//! (one dispatch per level, bottom-up) and the traversal-based light assignment (one subgroup per
//! unique cluster, [`light_bvh::walk_subgroup`]), which replaces
//! the naive search of [`crate::clustered`] and writes the same counts and lists (as sets).
//! The assignment is one dispatch ([`assign_cluster`]): the naive search counts, scans and fills
//! in three kernels and a scan; each walk subgroup counts, reserves its range with an atomic add
//! and fills.
use crate::cluster_bounds::cluster_aabb_of_key;
use crate::coop::gpu::GpuCoop;
use crate::coop::Coop;
use crate::light_lists::{AtomicAdd, ListSink};
use crate::layout::*;
use crate::light_bvh;
use crate::shading::linear_index;
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
        nodes[node as usize] = light_bvh::leaf_node_box(lights, order, p.count, p.branching, node);
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
        let b = light_bvh::inner_node_box(nodes, p.count, p.branching, p.level, node);
        nodes[(light_bvh::level_offset(p.count, p.level, p.branching) + node) as usize] = b;
    }
}

/// Unique cluster handled by this subgroup.
#[inline]
pub fn walk_cluster<C: Coop>(c: &C, wg: UVec3, nwg: UVec3) -> u32 {
    (wg.y * nwg.x + wg.x) * c.num_subgroups() + c.subgroup_id()
}

/// The light BVH as the walk reads it: node boxes, Morton-sorted light order, lights, branching.
#[derive(Clone, Copy)]
pub struct Tree<'a> {
    pub nodes: &'a [ClusterAabb],
    pub order: &'a [u32],
    pub lights: &'a [PointLight],
    pub count: u32,
    pub branching: u32,
}

impl Tree<'_> {
    /// Lights overlapping `cluster` by the subgroup-parallel walk ([`light_bvh::walk_subgroup`]).
    #[inline]
    fn walk<C: Coop>(&self, c: &C, cluster: &ClusterAabb, emit: impl FnMut(u32, u32)) -> u32 {
        light_bvh::walk_subgroup(c, self.nodes, self.lights, self.order, self.count, self.branching, cluster, emit)
    }
}

/// Step 3 for the subgroup's cluster box (pure; every lane of the subgroup calls it):
/// 1. walk the BVH, counting the lights that meet the box;
/// 2. reserve the list's range with one atomic add on `refs` (the frame's light references);
/// 3. walk again (nodes and lights now in cache), writing each light at its place.
///
/// Both walks in one dispatch replace the count kernel, the scan of the counts and the fill
/// kernel of the naive assignment: two dispatches and four scan dispatches fewer, each with the
/// barrier that follows it. (Staging the list in workgroup memory to skip the second walk lost
/// the last staged store of some clusters on lavapipe.)
///
/// Entries at or past `capacity` are not written: the counter still counts them, so the host
/// grows the list and re-runs the frame. Returns `(count, offset)` of the cluster's list. The
/// order of the clusters' ranges in the list depends on the atomics; each list's own order (the
/// walk's, Morton order) does not.
#[inline]
pub fn assign_cluster<C: Coop, A: AtomicAdd + ?Sized, L: ListSink + ?Sized>(
    c: &C,
    tree: &Tree<'_>,
    cluster: &ClusterAabb,
    refs: &mut A,
    list: &mut L,
    capacity: u32,
) -> (u32, u32) {
    let found = tree.walk(c, cluster, |_, _| {});
    let reserved = if c.lane() == 0 && found > 0 { refs.fetch_add(found) } else { 0 };
    let base = c.shuffle(reserved, 0);
    if found > 0 {
        // `move`: a closure holding a pointer to a local leaves pointers in composites, which
        // SPIR-V's logical addressing rejects.
        tree.walk(c, cluster, move |k, l| {
            if base + k < capacity {
                list.put(base + k, l)
            }
        });
    }
    (found, base)
}

/// Step 3: each unique cluster's light count, offset and list (one subgroup per cluster,
/// [`assign_cluster`]).
#[spirv(compute(threads(64)))] // light_bvh::WALK_WORKGROUP
#[allow(clippy::too_many_arguments)]
pub fn cluster_lights_assign_bvh(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &BvhAssignParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] offsets: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] list: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] order: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] nodes: &[ClusterAabb],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let cl = walk_cluster(&c, wg, nwg);
    if cl >= p.frame.count || cl >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    let f = &p.frame;
    let tree = Tree { nodes, order, lights, count: f.num_lights, branching: p.branching };
    let cluster = cluster_aabb_of_key(&f.grid, bounds, unique[cl as usize]);
    let refs = &mut counters[COUNTER_LIGHT_REFS as usize];
    let (n, base) = assign_cluster(&c, &tree, &cluster, refs, list, f.light_capacity);
    if lane == 0 {
        counts[cl as usize] = n;
        offsets[cl as usize] = base;
    }
}

#[cfg(test)]
#[path = "clustered_bvh_tests.rs"]
mod tests;
