//! Light BVH over Morton-sorted lights (Karas' design; the tree of "Clustered deferred and forward
//! shading", Olsson et al. 2012, §4.2): leaves are the sorted lights; node `n` of level 0 bounds
//! lights `[B·n, B·n + B)`, node `n` of level ℓ bounds nodes `[B·n, B·n + B)` of level ℓ − 1, up
//! to a top level of at most `B` nodes. The branching `B` is 32 or 64 ([`valid_branching`]; the
//! host's default is the subgroup width clamped to that range, so one subgroup tests one node's
//! children in one or two steps). The tree is implicit (children are consecutive), so a node is
//! just its AABB (32 B); levels are stored bottom-up in one buffer at offsets
//! `level_offset(ℓ)`. Memory: 32 B × (N/B + N/B² + …) ≈ N B (B = 32) or N/2 B (B = 64).
//!
//! Two walks find the lights of one cluster box, both depth-first and stackless (one cursor or
//! one child mask per level, at most [`BVH_MAX_LEVELS`]):
//! * [`for_each_bvh_light`] — one invocation per cluster, children tested one after the other.
//!   It is the CPU reference of the walk.
//! * [`walk_subgroup`] — one *subgroup* per cluster (the GPU's walk): the lanes test the
//!   children of a node in parallel, a ballot gives the mask of children to visit, the walk pops
//!   them lowest first; at the leaves the lanes test the lights of two leaves per step (each lane
//!   loads its two chunks' spheres before testing either: one round trip of loads instead of one
//!   per chunk and leaf) and the voting lanes write their light at `found + ballot_rank`. Every
//!   lane ends with the same count. Four chunks per step loaded two chunks for nothing on a
//!   32-wide subgroup (0.081 against 0.078 ms of assignment at 10k lights on the H200), and four
//!   leaves per step cost more than the round trips they saved (0.097 ms).
//!
//! A light meets the cluster exactly when its sphere does (the same `sphere_intersects_aabb` as
//! the naive search), and every ancestor box contains the light's sphere box, so both walks give
//! the naive lists as sets (in Morton order instead of index order).
use crate::coop::{ballot_count, ballot_rank, Coop};
use crate::layout::{ClusterAabb, LightSphere, PointLight};
use crate::lighting;
use spirv_std::glam::Vec3;

/// The branchings the tree supports.
pub const BVH_BRANCHINGS: [u32; 2] = [32, 64];
/// Largest branching: a node's child mask fits two 32-bit words.
pub const BVH_MAX_BRANCHING: u32 = 64;
/// Levels supported (32^6 > 10^9 lights).
pub const BVH_MAX_LEVELS: u32 = 6;

/// Invocations per workgroup of the assignment: `WALK_WORKGROUP / subgroup width` clusters per
/// workgroup (the host dispatches for the device's largest subgroup width, so every cluster is
/// covered whatever width the driver picks; surplus subgroups find no cluster and return).
pub const WALK_WORKGROUP: u32 = 64;

/// Whether `b` is a supported branching (32 or 64).
#[inline]
pub fn valid_branching(b: u32) -> bool {
    b == 32 || b == 64
}

/// Nodes of level `level` for `n` lights: `⌈n / B^(level+1)⌉`.
#[inline]
pub fn level_nodes(n: u32, level: u32, b: u32) -> u32 {
    let mut m = n;
    let mut l = 0;
    while l <= level {
        m = m.div_ceil(b);
        l += 1;
    }
    m
}

/// Levels of the tree over `n` lights (≥ 1 for n ≥ 1): until a level has at most B nodes.
#[inline]
pub fn level_count(n: u32, b: u32) -> u32 {
    let mut levels = 1;
    while level_nodes(n, levels - 1, b) > b && levels < BVH_MAX_LEVELS {
        levels += 1;
    }
    levels
}

/// First node of level `level` in the node buffer.
#[inline]
pub fn level_offset(n: u32, level: u32, b: u32) -> u32 {
    let mut off = 0;
    let mut l = 0;
    while l < level {
        off += level_nodes(n, l, b);
        l += 1;
    }
    off
}

/// Nodes of the whole tree (the node buffer's length).
#[inline]
pub fn total_nodes(n: u32, b: u32) -> u32 {
    level_offset(n, level_count(n, b), b)
}

/// Per-level node counts and buffer offsets, computed once per walk: the walk itself must not
/// loop over levels at every node (cost, and llvmpipe's loop limiter counts every iteration).
#[derive(Clone, Copy)]
pub struct Levels {
    pub levels: u32,
    pub count: [u32; BVH_MAX_LEVELS as usize],
    pub offset: [u32; BVH_MAX_LEVELS as usize],
}

impl Levels {
    #[inline]
    pub fn new(n: u32, b: u32) -> Self {
        let levels = level_count(n, b);
        let mut count = [0u32; BVH_MAX_LEVELS as usize];
        let mut offset = [0u32; BVH_MAX_LEVELS as usize];
        let mut m = n;
        let mut acc = 0;
        let mut l = 0;
        while l < levels {
            m = m.div_ceil(b);
            count[l as usize] = m;
            offset[l as usize] = acc;
            acc += m;
            l += 1;
        }
        Self { levels, count, offset }
    }
}

/// Box of a light's sphere.
#[inline]
pub fn light_box(l: &PointLight) -> ClusterAabb {
    sphere_box(&sphere_of(l))
}

/// The bounding sphere of a light.
#[inline]
pub fn sphere_of(l: &PointLight) -> LightSphere {
    LightSphere { position: l.position, radius: l.radius }
}

/// Box of a light's sphere (a negative radius counts as 0).
#[inline]
pub fn sphere_box(l: &LightSphere) -> ClusterAabb {
    let r = if l.radius > 0.0 { l.radius } else { 0.0 };
    let p = l.position;
    ClusterAabb { min: [p[0] - r, p[1] - r, p[2] - r], _pad0: 0.0, max: [p[0] + r, p[1] + r, p[2] + r], _pad1: 0.0 }
}

/// Union of two boxes.
#[inline]
pub fn union(a: &ClusterAabb, b: &ClusterAabb) -> ClusterAabb {
    let lo = |x: f32, y: f32| if x < y { x } else { y };
    let hi = |x: f32, y: f32| if x > y { x } else { y };
    ClusterAabb {
        min: [lo(a.min[0], b.min[0]), lo(a.min[1], b.min[1]), lo(a.min[2], b.min[2])],
        _pad0: 0.0,
        max: [hi(a.max[0], b.max[0]), hi(a.max[1], b.max[1]), hi(a.max[2], b.max[2])],
        _pad1: 0.0,
    }
}

/// An empty box (the identity of [`union`]).
pub const EMPTY_BOX: ClusterAabb = ClusterAabb { min: [f32::MAX; 3], _pad0: 0.0, max: [-f32::MAX; 3], _pad1: 0.0 };

/// Whether two closed boxes overlap.
#[inline]
pub fn boxes_overlap(a: &ClusterAabb, b: &ClusterAabb) -> bool {
    !(a.max[0] < b.min[0] || b.max[0] < a.min[0] || a.max[1] < b.min[1] || b.max[1] < a.min[1] || a.max[2] < b.min[2] || b.max[2] < a.min[2])
}

/// The spheres of the lights in sorted order: `spheres[s]` is light `order[s]`'s (step 2a of the
/// build, one invocation per light on the GPU).
#[cfg(not(target_arch = "spirv"))]
pub fn sorted_spheres(lights: &[PointLight], order: &[u32]) -> Vec<LightSphere> {
    order.iter().map(|&i| sphere_of(&lights[i as usize])).collect()
}

/// Box of level-0 node `node`: its lights' spheres (sorted order).
#[inline]
pub fn leaf_node_box(spheres: &[LightSphere], n: u32, b: u32, node: u32) -> ClusterAabb {
    let mut bx = EMPTY_BOX;
    let first = node * b;
    let mut s = first;
    while s < first + b && s < n {
        // In bounds: `s < n`, the sorted lights.
        bx = union(&bx, &sphere_box(crate::unchecked::get(spheres, s)));
        s += 1;
    }
    bx
}

/// [`leaf_node_box`] by one subgroup (every lane calls it and gets the box): lane `l` unites
/// spheres `first + l, first + l + w, …` (coalesced reads, `b / w` of them instead of `b` in a
/// row), then the lanes' boxes are united by butterfly shuffles. A union of boxes is exact in
/// any order, so the box is [`leaf_node_box`]'s at every width.
#[inline]
pub fn leaf_node_box_subgroup<C: Coop>(c: &C, spheres: &[LightSphere], n: u32, b: u32, node: u32) -> ClusterAabb {
    let w = c.subgroup_size();
    let first = node * b;
    let end = if first + b < n { first + b } else { n };
    let mut bx = EMPTY_BOX;
    let mut s = first + c.lane();
    while s < end {
        // In bounds: `s < end ≤ n`.
        bx = union(&bx, &sphere_box(crate::unchecked::get(spheres, s)));
        s += w;
    }
    let mut m = 1;
    while m < w {
        let x = |v: f32| f32::from_bits(c.shuffle_xor(v.to_bits(), m));
        let other = ClusterAabb {
            min: [x(bx.min[0]), x(bx.min[1]), x(bx.min[2])],
            _pad0: 0.0,
            max: [x(bx.max[0]), x(bx.max[1]), x(bx.max[2])],
            _pad1: 0.0,
        };
        bx = union(&bx, &other);
        m *= 2;
    }
    bx
}

/// Box of node `node` of level `level ≥ 1` from its children in `nodes`.
#[inline]
pub fn inner_node_box(nodes: &[ClusterAabb], n: u32, b: u32, level: u32, node: u32) -> ClusterAabb {
    let children = level_nodes(n, level - 1, b);
    let base = level_offset(n, level - 1, b);
    let mut bx = EMPTY_BOX;
    let first = node * b;
    let mut c = first;
    while c < first + b && c < children {
        bx = union(&bx, &nodes[(base + c) as usize]);
        c += 1;
    }
    bx
}

/// Whether a light's sphere meets `cluster`: the one leaf test of both walks.
#[inline]
fn sphere_hits(sphere: &LightSphere, cluster: &ClusterAabb) -> bool {
    lighting::sphere_intersects_aabb(Vec3::from_array(sphere.position), sphere.radius, cluster)
}

/// Lights (indices, via `order`) whose sphere meets `cluster`, found by walking the tree with one
/// invocation; calls `emit(k, light)` for the k-th one and returns the count.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn for_each_bvh_light(
    nodes: &[ClusterAabb],
    spheres: &[LightSphere],
    order: &[u32],
    n: u32,
    b: u32,
    cluster: &ClusterAabb,
    mut emit: impl FnMut(u32, u32),
) -> u32 {
    if n == 0 {
        return 0;
    }
    let t = Levels::new(n, b);
    // cursor[l]: next node to visit at level l; end[l]: one past the last node of the current
    // parent's children at level l.
    let mut cursor = [0u32; BVH_MAX_LEVELS as usize];
    let mut end = [0u32; BVH_MAX_LEVELS as usize];
    let top = t.levels - 1;
    cursor[top as usize] = 0;
    end[top as usize] = t.count[top as usize];
    let mut level = top;
    let mut found = 0;
    loop {
        let l = level as usize;
        if cursor[l] >= end[l] {
            if level == top {
                break;
            }
            level += 1;
            continue;
        }
        let node = cursor[l];
        cursor[l] += 1;
        if !boxes_overlap(&nodes[(t.offset[l] + node) as usize], cluster) {
            continue;
        }
        if level == 0 {
            let first = node * b;
            let last = if first + b < n { first + b } else { n };
            // 8 lights per iteration: llvmpipe's loop limiter (see `clustered`).
            let mut s0 = first;
            while s0 < last {
                unroll8!(u => {
                    let s = s0 + u;
                    if s < last && sphere_hits(crate::unchecked::get(spheres, s), cluster) {
                        emit(found, order[s as usize]);
                        found += 1;
                    }
                });
                s0 += 8;
            }
        } else {
            let below = level - 1;
            let children = t.count[below as usize];
            let first = node * b;
            cursor[below as usize] = first;
            end[below as usize] = if first + b < children { first + b } else { children };
            level = below;
        }
    }
    found
}

/// ORs the ballot of lanes `0..w` (w ≤ 64) into a 64-bit child mask (two words) at bit `shift`.
#[inline]
fn or_ballot(mask: &mut [u32; 2], ballot: [u32; 4], shift: u32) {
    if shift == 0 {
        mask[0] |= ballot[0];
        mask[1] |= ballot[1];
    } else if shift < 32 {
        mask[0] |= ballot[0] << shift;
        mask[1] |= (ballot[0] >> (32 - shift)) | (ballot[1] << shift);
    } else {
        mask[1] |= ballot[0] << (shift - 32);
    }
}

/// Child mask of `count ≤ b` consecutive children: lane `i` of each chunk of `w` tests child
/// `chunk + i` with `test`; a ballot per chunk. Chunks are unrolled 8 per loop iteration, so a
/// node costs one iteration of llvmpipe's loop limiter at `b / w ≤ 8`.
#[inline]
fn child_mask<C: Coop>(c: &C, b: u32, count: u32, test: impl Fn(u32) -> bool) -> [u32; 2] {
    let w = c.subgroup_size();
    let lane = c.lane();
    let mut mask = [0u32; 2];
    let mut ch = 0;
    while ch < b {
        unroll8!(u => {
            let first = ch + u * w;
            if first < b {
                let i = first + lane;
                let hit = i < b && i < count && test(i);
                or_ballot(&mut mask, c.ballot(hit), first);
            }
        });
        ch += 8 * w;
    }
    mask
}

/// Pops the lowest set bit of a two-word mask (the mask must not be empty).
#[inline]
fn pop_lowest(mask: &mut [u32; 2]) -> u32 {
    if mask[0] != 0 {
        let bit = mask[0].trailing_zeros();
        mask[0] &= mask[0] - 1;
        bit
    } else {
        let bit = mask[1].trailing_zeros();
        mask[1] &= mask[1] - 1;
        32 + bit
    }
}

/// No second leaf in a [`LeafPair`].
const NO_LEAF: u32 = u32::MAX;

/// The lights of one or two level-0 nodes as one range of slots: slot `v < B` is light `v` of
/// leaf `first`, slot `B + v` light `v` of leaf `second` (where there is one).
struct LeafPair {
    first: u32,
    second: u32,
    b: u32,
    n: u32,
}

/// A lane's light of one chunk of a [`LeafPair`], loaded ahead of its test.
struct LeafSlot {
    sphere: LightSphere,
    light: u32,
    valid: bool,
}

impl LeafPair {
    /// Slot `v`'s sphere and light index. Branch-free: every lane reads a valid slot (the last
    /// light of the leaf where `v` is past it) and `valid` says whether the slot holds a light.
    #[inline]
    fn load(&self, spheres: &[LightSphere], order: &[u32], v: u32) -> LeafSlot {
        let (leaf, k) = if v >= self.b && self.second != NO_LEAF { (self.second, v - self.b) } else { (self.first, v) };
        let s = leaf * self.b + k;
        let last = if leaf * self.b + self.b < self.n { leaf * self.b + self.b } else { self.n };
        let sv = if s < last { s } else { last - 1 };
        // In bounds: `sv < last ≤ n`, the length of `spheres` and `order` (the sorted lights).
        LeafSlot { sphere: crate::unchecked::at(spheres, sv), light: crate::unchecked::at(order, sv), valid: s < last }
    }
}

impl LeafSlot {
    /// The subgroup's vote on one chunk (`in_span`: the chunk is part of the range, uniform):
    /// lanes whose light meets the cluster (sphere, and cone for spots) emit it at `found` plus
    /// their rank; returns the new count.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn vote<C: Coop>(&self, c: &C, in_span: bool, found: u32, cluster: &ClusterAabb, effects: u32, lights: &[PointLight], n: u32, c0: Vec3, r0: f32, emit: &mut impl FnMut(u32, u32)) -> u32 {
        if !in_span {
            return found;
        }
        // The tests are combined with `&` (a short-circuit chain here miscompiled on lavapipe).
        let hit = self.valid & sphere_hits(&self.sphere, cluster) & crate::light_types::spot_may_meet(effects, lights, n, self.light, c0, r0);
        let vote = c.ballot(hit);
        if hit {
            emit(found + ballot_rank(vote, c.lane()), self.light);
        }
        found + ballot_count(vote)
    }
}

/// The subgroup-parallel walk: every lane of the subgroup calls it with the same `cluster` (in
/// subgroup-uniform control flow). Lanes whose light meets the cluster call `emit(k, light)` with
/// its dense slot `k`; every lane returns the cluster's count. Spot lights (`effects` with
/// `EFFECT_SPOT`): the nodes keep range spheres, and a leaf light whose sphere meets the cluster
/// has its cone tested too (`light_types::spot_may_meet`, its record in `lights`).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn walk_subgroup<C: Coop>(
    c: &C,
    nodes: &[ClusterAabb],
    spheres: &[LightSphere],
    order: &[u32],
    n: u32,
    b: u32,
    cluster: &ClusterAabb,
    effects: u32,
    lights: &[crate::layout::PointLight],
    mut emit: impl FnMut(u32, u32),
) -> u32 {
    if n == 0 {
        return 0;
    }
    let (c0, r0) = crate::light_types::box_sphere(Vec3::from_array(cluster.min), Vec3::from_array(cluster.max));
    let t = Levels::new(n, b);
    let w = c.subgroup_size();
    let lane = c.lane();
    let top = t.levels - 1;
    // pending[l]: children of the current level-(l+1) node (or the top level) still to visit;
    // first[l]: index of child bit 0 at level l.
    let mut pending = [[0u32; 2]; BVH_MAX_LEVELS as usize];
    let mut first = [0u32; BVH_MAX_LEVELS as usize];
    let top_offset = t.offset[top as usize];
    // In bounds (both child tests): child `i < count` of a level lies inside the level's range
    // of the node buffer, which holds the whole tree (`total_nodes`).
    pending[top as usize] = child_mask(c, b, t.count[top as usize], |i| boxes_overlap(crate::unchecked::get(nodes, top_offset + i), cluster));
    let mut level = top;
    let mut found = 0;
    loop {
        let l = level as usize;
        if pending[l][0] == 0 && pending[l][1] == 0 {
            if level == top {
                break;
            }
            level += 1;
            continue;
        }
        let node = first[l] + pop_lowest(&mut pending[l]);
        let child0 = node * b;
        if level == 0 {
            // Two leaves per step where the node has two left: one round trip of loads for both.
            let second = if pending[0][0] != 0 || pending[0][1] != 0 { first[0] + pop_lowest(&mut pending[0]) } else { NO_LEAF };
            let leaves = LeafPair { first: node, second, b, n };
            let span = if second == NO_LEAF { b } else { 2 * b };
            let mut v0 = 0;
            while v0 < span {
                // Every lane loads its slot of two chunks before either is tested, so both loads
                // are in flight together (a walk is a chain of dependent steps).
                let k0 = leaves.load(spheres, order, v0 + lane);
                let k1 = leaves.load(spheres, order, v0 + w + lane);
                found = k0.vote(c, v0 < span, found, cluster, effects, lights, n, c0, r0, &mut emit);
                found = k1.vote(c, v0 + w < span, found, cluster, effects, lights, n, c0, r0, &mut emit);
                v0 += 2 * w;
            }
        } else {
            let below = (level - 1) as usize;
            let children = t.count[below] - child0;
            let offset = t.offset[below] + child0;
            pending[below] = child_mask(c, b, children, |i| boxes_overlap(crate::unchecked::get(nodes, offset + i), cluster));
            first[below] = child0;
            level -= 1;
        }
    }
    found
}

#[cfg(test)]
#[path = "light_bvh_tests.rs"]
mod tests;
