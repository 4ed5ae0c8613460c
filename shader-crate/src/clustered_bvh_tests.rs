//! CPU tests of the one-dispatch light assignment ([`assign_cluster`]) in the lock-step emulation
//! at subgroup widths 4–64: every cluster's range holds exactly its brute-force lights, the
//! ranges tile the list without overlap (clusters with thousands of lights included), and a list
//! too small for the frame writes nothing out of range while its counter still counts every
//! reference.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::light_bvh::tests::{brute_force, build, lights};
use crate::light_bvh::{light_box, WALK_WORKGROUP};
use std::sync::atomic::{AtomicU32, Ordering};

/// The list as the emulated workgroups share it (they run on several threads).
struct SharedList<'a>(&'a [AtomicU32]);

impl ListSink for SharedList<'_> {
    fn put(&mut self, i: u32, light: u32) {
        self.0[i as usize].store(light, Ordering::Relaxed);
    }
}

/// Runs the assignment for `clusters` (one subgroup each) with a list of `capacity` entries;
/// returns per cluster `(count, offset)`, the list and the counter's final value.
fn assign(tree: &Tree<'_>, clusters: &[ClusterAabb], width: u32, capacity: u32) -> (Vec<(u32, u32)>, Vec<u32>, u32) {
    const UNWRITTEN: u32 = u32::MAX;
    let per_group = WALK_WORKGROUP / width;
    let groups = (clusters.len() as u32).div_ceil(per_group);
    let refs = AtomicU32::new(0);
    let list: Vec<AtomicU32> = (0..capacity).map(|_| AtomicU32::new(UNWRITTEN)).collect();
    let emu = Emulation { width, workgroup_size: WALK_WORKGROUP, shared_words: 0 };
    let lanes = run_workgroups(emu, groups, |g, c, _| {
        let cl = g * c.num_subgroups() + c.subgroup_id();
        if cl as usize >= clusters.len() {
            return None;
        }
        let (count, base) = assign_cluster(c, tree, &clusters[cl as usize], &mut &refs, &mut SharedList(&list), capacity);
        (c.lane() == 0).then_some((cl, count, base))
    });
    let mut ranges = vec![(0, 0); clusters.len()];
    for (cl, count, base) in lanes.into_iter().flatten() {
        ranges[cl as usize] = (count, base);
    }
    (ranges, list.iter().map(|w| w.load(Ordering::Relaxed)).collect(), refs.load(Ordering::Relaxed))
}

#[test]
fn one_walk_lists_equal_brute_force_at_every_width() {
    // Radius ≫ scene: every cluster meets all 3000 lights.
    for (n, radius) in [(1, 3.0), (33, 0.0), (1025, 5.0), (3000, 500.0), (40_000, 2.0)] {
        let ls = lights(n, n as u32 ^ 0x9e37, radius);
        let order: Vec<u32> = (0..n as u32).map(|i| (i * 7919) % n as u32).collect();
        for b in [32, 64] {
            let nodes = build(&ls, &order, b);
            let tree = Tree { nodes: &nodes, order: &order, lights: &ls, count: n as u32, branching: b };
            let clusters: Vec<ClusterAabb> = lights(13, 7, 25.0).iter().map(light_box).collect();
            let expected: Vec<Vec<u32>> = clusters.iter().map(|cl| brute_force(&ls, cl)).collect();
            let total: u32 = expected.iter().map(|e| e.len() as u32).sum();
            for width in [4, 8, 16, 32, 64] {
                let (ranges, list, refs) = assign(&tree, &clusters, width, total);
                assert_eq!(refs, total, "n={n} b={b} w={width}: the counter counts every reference");
                let mut covered = vec![false; total as usize];
                for (cl, &(count, base)) in ranges.iter().enumerate() {
                    let range = base as usize..(base + count) as usize;
                    let mut got = list[range.clone()].to_vec();
                    got.sort_unstable();
                    assert_eq!(got, expected[cl], "n={n} b={b} w={width}, cluster {cl}");
                    for k in range {
                        assert!(!covered[k], "n={n} b={b} w={width}: entry {k} in two ranges");
                        covered[k] = true;
                    }
                }
            }
        }
    }
}

#[test]
fn a_list_too_small_is_counted_and_never_overrun() {
    let ls = lights(3000, 5, 500.0);
    let order: Vec<u32> = (0..3000).collect();
    let nodes = build(&ls, &order, 32);
    let tree = Tree { nodes: &nodes, order: &order, lights: &ls, count: 3000, branching: 32 };
    let clusters: Vec<ClusterAabb> = lights(5, 3, 25.0).iter().map(light_box).collect();
    let total: u32 = clusters.iter().map(|cl| brute_force(&ls, cl).len() as u32).sum();
    for width in [4, 32] {
        for capacity in [0, 1, total / 2, total - 1] {
            // The list vector has exactly `capacity` words: a write past it would panic.
            let (ranges, _, refs) = assign(&tree, &clusters, width, capacity);
            assert_eq!(refs, total, "w={width} capacity={capacity}: the host must see the need");
            assert_eq!(ranges.iter().map(|r| r.0).sum::<u32>(), total);
        }
    }
}
