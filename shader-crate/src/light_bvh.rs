//! Light BVH over Morton-sorted lights (Karas' design; the tree of "Clustered deferred and forward
//! shading", Olsson et al. 2012, §4.2): leaves are the sorted lights; node `n` of level 0 bounds
//! lights `[B·n, B·n + B)`, node `n` of level ℓ bounds nodes `[B·n, B·n + B)` of level ℓ − 1, up
//! to a top level of at most `B` nodes. `B` = [`BVH_BRANCHING`] = 32. The tree is implicit
//! (children are consecutive), so a node is just its AABB (32 B); levels are stored bottom-up in
//! one buffer at offsets `level_offset(ℓ)`. Memory: 32 B × (N/32 + N/1024 + …) ≈ N B.
//!
//! Traversal per cluster ([`for_each_bvh_light`]) is a stackless depth-first walk: one cursor per
//! level; a node whose box misses the cluster box is skipped with its subtree. A light meets the
//! cluster exactly when its sphere does (the same `sphere_intersects_aabb` as the naive search),
//! and every ancestor box contains the light's sphere box, so the lists equal the naive lists as
//! sets (in Morton order instead of index order).
use crate::layout::{ClusterAabb, PointLight};
use crate::lighting;
use spirv_std::glam::Vec3;

/// Children per node.
pub const BVH_BRANCHING: u32 = 32;
/// Levels supported (32^6 > 10^9 lights).
pub const BVH_MAX_LEVELS: u32 = 6;

/// Nodes of level `level` for `n` lights: `⌈n / B^(level+1)⌉`.
#[inline]
pub fn level_nodes(n: u32, level: u32) -> u32 {
    let mut m = n;
    let mut l = 0;
    while l <= level {
        m = m.div_ceil(BVH_BRANCHING);
        l += 1;
    }
    m
}

/// Levels of the tree over `n` lights (≥ 1 for n ≥ 1): until a level has at most B nodes.
#[inline]
pub fn level_count(n: u32) -> u32 {
    let mut levels = 1;
    while level_nodes(n, levels - 1) > BVH_BRANCHING && levels < BVH_MAX_LEVELS {
        levels += 1;
    }
    levels
}

/// First node of level `level` in the node buffer.
#[inline]
pub fn level_offset(n: u32, level: u32) -> u32 {
    let mut off = 0;
    let mut l = 0;
    while l < level {
        off += level_nodes(n, l);
        l += 1;
    }
    off
}

/// Box of a light's sphere.
#[inline]
pub fn light_box(l: &PointLight) -> ClusterAabb {
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

/// Box of level-0 node `node`: its lights (sorted order; `order[s]` is the light index).
#[inline]
pub fn leaf_node_box(lights: &[PointLight], order: &[u32], n: u32, node: u32) -> ClusterAabb {
    let mut b = EMPTY_BOX;
    let first = node * BVH_BRANCHING;
    let mut s = first;
    while s < first + BVH_BRANCHING && s < n {
        b = union(&b, &light_box(&lights[order[s as usize] as usize]));
        s += 1;
    }
    b
}

/// Box of node `node` of level `level ≥ 1` from its children in `nodes`.
#[inline]
pub fn inner_node_box(nodes: &[ClusterAabb], n: u32, level: u32, node: u32) -> ClusterAabb {
    let children = level_nodes(n, level - 1);
    let base = level_offset(n, level - 1);
    let mut b = EMPTY_BOX;
    let first = node * BVH_BRANCHING;
    let mut c = first;
    while c < first + BVH_BRANCHING && c < children {
        b = union(&b, &nodes[(base + c) as usize]);
        c += 1;
    }
    b
}

/// Lights (indices, via `order`) whose sphere meets `cluster`, found by walking the tree; calls
/// `emit(k, light)` for the k-th one and returns the count.
#[inline]
pub fn for_each_bvh_light(
    nodes: &[ClusterAabb],
    lights: &[PointLight],
    order: &[u32],
    n: u32,
    cluster: &ClusterAabb,
    mut emit: impl FnMut(u32, u32),
) -> u32 {
    if n == 0 {
        return 0;
    }
    let levels = level_count(n);
    // Per-level node counts and buffer offsets, once: the walk itself must not loop over levels
    // at every node (cost, and llvmpipe's loop limiter counts every iteration).
    let mut count = [0u32; BVH_MAX_LEVELS as usize];
    let mut offset = [0u32; BVH_MAX_LEVELS as usize];
    let mut m = n;
    let mut acc = 0;
    let mut l = 0;
    while l < levels {
        m = m.div_ceil(BVH_BRANCHING);
        count[l as usize] = m;
        offset[l as usize] = acc;
        acc += m;
        l += 1;
    }
    // cursor[l]: next node to visit at level l; end[l]: one past the last node of the current
    // parent's children at level l.
    let mut cursor = [0u32; BVH_MAX_LEVELS as usize];
    let mut end = [0u32; BVH_MAX_LEVELS as usize];
    let top = levels - 1;
    cursor[top as usize] = 0;
    end[top as usize] = count[top as usize];
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
        if !boxes_overlap(&nodes[(offset[l] + node) as usize], cluster) {
            continue;
        }
        if level == 0 {
            let first = node * BVH_BRANCHING;
            let last = if first + BVH_BRANCHING < n { first + BVH_BRANCHING } else { n };
            // 8 lights per iteration: llvmpipe's loop limiter (see `clustered`).
            let mut s0 = first;
            while s0 < last {
                unroll8!(u => {
                    let s = s0 + u;
                    if s < last {
                        let light = lights[order[s as usize] as usize];
                        if lighting::sphere_intersects_aabb(Vec3::from_array(light.position), light.radius, cluster) {
                            emit(found, order[s as usize]);
                            found += 1;
                        }
                    }
                });
                s0 += 8;
            }
        } else {
            let below = level - 1;
            let children = count[below as usize];
            let first = node * BVH_BRANCHING;
            cursor[below as usize] = first;
            end[below as usize] = if first + BVH_BRANCHING < children { first + BVH_BRANCHING } else { children };
            level = below;
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contains(outer: &ClusterAabb, inner: &ClusterAabb) -> bool {
        (0..3).all(|a| outer.min[a] <= inner.min[a] && inner.max[a] <= outer.max[a])
    }

    /// Builds the tree on the CPU with the kernels' functions.
    fn build(lights: &[PointLight], order: &[u32]) -> Vec<ClusterAabb> {
        let n = lights.len() as u32;
        let total: u32 = (0..level_count(n)).map(|l| level_nodes(n, l)).sum();
        let mut nodes = vec![EMPTY_BOX; total as usize];
        for node in 0..level_nodes(n, 0) {
            nodes[node as usize] = leaf_node_box(lights, order, n, node);
        }
        for level in 1..level_count(n) {
            for node in 0..level_nodes(n, level) {
                let b = inner_node_box(&nodes, n, level, node);
                nodes[(level_offset(n, level) + node) as usize] = b;
            }
        }
        nodes
    }

    fn lights(n: usize, seed: u32, radius: f32) -> Vec<PointLight> {
        let mut x = seed | 1;
        let mut r = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        (0..n)
            .map(|_| PointLight { position: [r() * 100.0, r() * 20.0, -r() * 100.0], radius: radius * r(), colour: [1.0; 3], intensity: 1.0 })
            .collect()
    }

    /// Every node's box contains its children's (down to the lights' sphere boxes), at sizes that
    /// give 1, 2 and 3 levels and partial last nodes; traversal finds exactly the brute-force set.
    #[test]
    fn nodes_contain_children_and_traversal_equals_brute_force() {
        for (n, radius) in [(1usize, 3.0), (31, 3.0), (33, 0.0), (1025, 5.0), (40_000, 2.0), (3000, 500.0)] {
            let ls = lights(n, n as u32, radius);
            let order: Vec<u32> = (0..n as u32).rev().collect(); // any permutation is a valid order
            let nodes = build(&ls, &order);
            let nn = n as u32;
            for node in 0..level_nodes(nn, 0) {
                let b = nodes[node as usize];
                for s in node * BVH_BRANCHING..((node + 1) * BVH_BRANCHING).min(nn) {
                    assert!(contains(&b, &light_box(&ls[order[s as usize] as usize])), "n={n}: leaf node {node}");
                }
            }
            for level in 1..level_count(nn) {
                for node in 0..level_nodes(nn, level) {
                    let b = nodes[(level_offset(nn, level) + node) as usize];
                    let below = level_offset(nn, level - 1);
                    for c in node * BVH_BRANCHING..((node + 1) * BVH_BRANCHING).min(level_nodes(nn, level - 1)) {
                        assert!(contains(&b, &nodes[(below + c) as usize]), "n={n}: level {level} node {node}");
                    }
                }
            }
            assert!(level_nodes(nn, level_count(nn) - 1) <= BVH_BRANCHING);
            for (i, c) in lights(64, 7, 15.0).iter().enumerate() {
                let cluster = light_box(c);
                let mut got = Vec::new();
                let count = for_each_bvh_light(&nodes, &ls, &order, nn, &cluster, |_, l| got.push(l));
                got.sort_unstable();
                let expected: Vec<u32> = (0..nn)
                    .filter(|&l| {
                        let p = &ls[l as usize];
                        lighting::sphere_intersects_aabb(Vec3::from_array(p.position), p.radius, &cluster)
                    })
                    .collect();
                assert_eq!(count as usize, got.len());
                assert_eq!(got, expected, "n={n}, cluster {i}");
            }
        }
    }
}
