//! CPU tests of the light BVH: containment of every node, and both walks (one invocation, one
//! emulated subgroup at widths 4–64) against brute force, at branchings 32 and 64.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};

fn contains(outer: &ClusterAabb, inner: &ClusterAabb) -> bool {
    (0..3).all(|a| outer.min[a] <= inner.min[a] && inner.max[a] <= outer.max[a])
}

/// Builds the tree on the CPU with the kernels' functions.
fn build(spheres: &[LightSphere], b: u32) -> Vec<ClusterAabb> {
    let n = spheres.len() as u32;
    let mut nodes = vec![EMPTY_BOX; total_nodes(n, b) as usize];
    for node in 0..level_nodes(n, 0, b) {
        nodes[node as usize] = leaf_node_box(spheres, n, b, node);
    }
    for level in 1..level_count(n, b) {
        for node in 0..level_nodes(n, level, b) {
            let bx = inner_node_box(&nodes, n, b, level, node);
            nodes[(level_offset(n, level, b) + node) as usize] = bx;
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

fn brute_force(ls: &[PointLight], cluster: &ClusterAabb) -> Vec<u32> {
    (0..ls.len() as u32)
        .filter(|&l| {
            let p = &ls[l as usize];
            lighting::sphere_intersects_aabb(Vec3::from_array(p.position), p.radius, cluster)
        })
        .collect()
}

/// Sizes giving 1, 2 and 3 levels and partial last nodes; radius 0 and radius ≫ scene.
const CASES: [(usize, f32); 6] = [(1, 3.0), (31, 3.0), (33, 0.0), (1025, 5.0), (40_000, 2.0), (3000, 500.0)];

/// Every node's box contains its children's (down to the lights' sphere boxes); the
/// one-invocation walk finds exactly the brute-force set.
#[test]
fn nodes_contain_children_and_traversal_equals_brute_force() {
    for b in BVH_BRANCHINGS {
        for (n, radius) in CASES {
            let ls = lights(n, n as u32, radius);
            let order: Vec<u32> = (0..n as u32).rev().collect(); // any permutation is a valid order
            let spheres = sorted_spheres(&ls, &order);
            let nodes = build(&spheres, b);
            let nn = n as u32;
            for node in 0..level_nodes(nn, 0, b) {
                let bx = nodes[node as usize];
                for s in node * b..((node + 1) * b).min(nn) {
                    assert!(contains(&bx, &light_box(&ls[order[s as usize] as usize])), "b={b} n={n}: leaf node {node}");
                }
            }
            for level in 1..level_count(nn, b) {
                for node in 0..level_nodes(nn, level, b) {
                    let bx = nodes[(level_offset(nn, level, b) + node) as usize];
                    let below = level_offset(nn, level - 1, b);
                    for c in node * b..((node + 1) * b).min(level_nodes(nn, level - 1, b)) {
                        assert!(contains(&bx, &nodes[(below + c) as usize]), "b={b} n={n}: level {level} node {node}");
                    }
                }
            }
            assert!(level_nodes(nn, level_count(nn, b) - 1, b) <= b);
            for (i, c) in lights(64, 7, 15.0).iter().enumerate() {
                let cluster = light_box(c);
                let mut got = Vec::new();
                let count = for_each_bvh_light(&nodes, &spheres, &order, nn, b, &cluster, |_, l| got.push(l));
                got.sort_unstable();
                assert_eq!(count as usize, got.len());
                assert_eq!(got, brute_force(&ls, &cluster), "b={b} n={n}, cluster {i}");
            }
        }
    }
}

/// The subgroup's leaf box equals the one-invocation box at every width 4–64 and both branchings.
#[test]
fn subgroup_leaf_boxes_equal_the_serial_ones() {
    for b in BVH_BRANCHINGS {
        for (n, radius) in CASES {
            let ls = lights(n, n as u32 ^ 0x77, radius);
            let order: Vec<u32> = (0..n as u32).collect();
            let spheres = sorted_spheres(&ls, &order);
            let leaves = level_nodes(n as u32, 0, b);
            for width in [4, 8, 16, 32, 64] {
                let emu = Emulation { width, workgroup_size: width, shared_words: 0 };
                let boxes = run_workgroups(emu, leaves, |node, c, _| leaf_node_box_subgroup(c, &spheres, n as u32, b, node));
                for node in 0..leaves {
                    let want = leaf_node_box(&spheres, n as u32, b, node);
                    for lane in 0..width {
                        assert_eq!(boxes[(node * width + lane) as usize], want, "b={b} n={n} w={width} node {node} lane {lane}");
                    }
                }
            }
        }
    }
}

/// The subgroup walk at every width 4–64 and both branchings: every lane returns the same count,
/// the emitted slots are exactly `0..count` (dense, no slot twice), and the lights are the
/// brute-force set.
#[test]
fn subgroup_walk_equals_brute_force_at_every_width() {
    for b in BVH_BRANCHINGS {
        for (n, radius) in CASES {
            let ls = lights(n, n as u32 ^ 0x55, radius);
            let order: Vec<u32> = (0..n as u32).map(|i| (i * 7919) % n as u32).collect(); // a permutation (7919 is prime)
            let spheres = sorted_spheres(&ls, &order);
            let nodes = build(&spheres, b);
            let clusters: Vec<ClusterAabb> = lights(6, 11, 15.0).iter().map(light_box).collect();
            for width in [4, 8, 16, 32, 64] {
                let emu = Emulation { width, workgroup_size: width, shared_words: 0 };
                let per_lane = run_workgroups(emu, clusters.len() as u32, |g, c, _| {
                    let mut emitted = Vec::new();
                    let count = walk_subgroup(c, &nodes, &spheres, &order, n as u32, b, &clusters[g as usize], 0, &[], |k, l| emitted.push((k, l)));
                    (count, emitted)
                });
                for (g, cluster) in clusters.iter().enumerate() {
                    let lanes = &per_lane[g * width as usize..(g + 1) * width as usize];
                    let count = lanes[0].0;
                    assert!(lanes.iter().all(|l| l.0 == count), "b={b} n={n} w={width}: lanes disagree on the count");
                    let mut slots: Vec<(u32, u32)> = lanes.iter().flat_map(|l| l.1.iter().copied()).collect();
                    slots.sort_unstable();
                    assert!(slots.iter().enumerate().all(|(k, s)| s.0 == k as u32), "b={b} n={n} w={width}: slots not dense");
                    assert_eq!(slots.len() as u32, count);
                    let mut got: Vec<u32> = slots.iter().map(|s| s.1).collect();
                    got.sort_unstable();
                    assert_eq!(got, brute_force(&ls, cluster), "b={b} n={n} w={width}, cluster {g}");
                }
            }
        }
    }
}
