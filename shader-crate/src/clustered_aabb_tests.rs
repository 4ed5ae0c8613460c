//! CPU tests of `clustered_aabb`: the staged assignment (lists equal the brute-force sphere–box
//! search in index order; nothing written past the capacity), at widths 4…64.
use super::*;
use crate::cluster_key::slice_bounds;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::lighting::light_touches;
use crate::reconstruct::{self, view_position};
use crate::test_support::{Counting, Rng};
use std::sync::atomic::{AtomicU32, Ordering};

const WIDTHS: [u32; 5] = [4, 8, 16, 32, 64];

/// A list buffer shared by the emulated invocations; remembers the highest index written.
struct SharedList<'a> {
    words: &'a [AtomicU32],
    highest: &'a AtomicU32,
}

impl ListSink for SharedList<'_> {
    fn put(&mut self, i: u32, light: u32) {
        self.words[i as usize].store(light, Ordering::Relaxed);
        self.highest.fetch_max(i + 1, Ordering::Relaxed);
    }
}

fn grid() -> ClusterGrid {
    ClusterGrid::new(96, 64, 16, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).unwrap()
}

/// Lights around pixels of the grid, at several depths and radii.
fn lights(g: &ClusterGrid, rng: &mut Rng, n: usize) -> Vec<PointLight> {
    (0..n)
        .map(|_| {
            let d = [0.3, 2.0, 20.0, 200.0][rng.below(4) as usize] * (0.5 + rng.unit());
            let c = view_position(g, rng.below(g.width), rng.below(g.height), d);
            PointLight { position: c.to_array(), radius: d * 0.2 * rng.unit(), colour: [1.0; 3], intensity: 1.0 }
        })
        .collect()
}

/// The emulated assignment equals the brute-force search per cluster, in index order, at every
/// width; with a capacity too small nothing is written beyond it and the counter still ends at
/// the total the frame needs.
#[test]
fn staged_assignment_equals_brute_force() {
    let g = grid();
    let bounds = slice_bounds(&g);
    let mut rng = Rng(3);
    let lights = lights(&g, &mut rng, 600);
    // 200 active clusters (random), 56 idle invocations.
    let clusters: Vec<u32> = (0..200).map(|_| rng.below(cluster_count(&g))).collect();
    let boxes: Vec<ClusterAabb> = clusters.iter().map(|&c| {
        let (i, j, k) = dense_coords(&g, c);
        cluster_aabb(&g, &bounds, i, j, k)
    }).collect();
    let expected: Vec<Vec<u32>> = boxes
        .iter()
        .map(|b| (0..lights.len() as u32).filter(|&l| lighting::sphere_intersects_aabb(Vec3::from_array(lights[l as usize].position), lights[l as usize].radius, b)).collect())
        .collect();
    let need: u32 = expected.iter().map(|e| e.len() as u32).sum();
    assert!(need > 200, "the case must have lights to assign ({need})");
    for width in WIDTHS {
        for capacity in [need, need / 2] {
            let words: Vec<AtomicU32> = (0..need).map(|_| AtomicU32::new(u32::MAX)).collect();
            let (refs, calls, highest) = (AtomicU32::new(0), AtomicU32::new(0), AtomicU32::new(0));
            let emu = Emulation { width, workgroup_size: AABB_WORKGROUP, shared_words: AABB_SHARED_WORDS };
            let out = run_workgroups(emu, 1, |_, c, s| {
                let li = c.local_index() as usize;
                let active = li < clusters.len();
                let aabb = if active { boxes[li] } else { boxes[0] };
                let mut counter = Counting { value: &refs, calls: &calls };
                let mut sink = SharedList { words: &words, highest: &highest };
                assign(c, s, &lights, lights.len() as u32, 0, &aabb, active, &mut counter, &mut sink, capacity)
            });
            assert_eq!(refs.load(Ordering::Relaxed), need, "width {width}: the counter ends at the references needed");
            assert!(highest.load(Ordering::Relaxed) <= capacity, "width {width}: written past the capacity {capacity}");
            for (li, e) in expected.iter().enumerate() {
                let (base, count) = out[li];
                assert_eq!(count as usize, e.len(), "width {width}, cluster {li}");
                if base + count <= capacity {
                    let got: Vec<u32> = (base..base + count).map(|k| words[k as usize].load(Ordering::Relaxed)).collect();
                    assert_eq!(&got, e, "width {width}, cluster {li}: list differs from brute force");
                }
            }
        }
    }
}

/// Dense indices round-trip, and a pixel's cluster box holds its position and every light that
/// touches it passes the box test (the conservativeness the shading relies on).
#[test]
fn pixel_clusters_hold_their_pixels() {
    let g = grid();
    let bounds = slice_bounds(&g);
    let mut rng = Rng(11);
    for c in [0, 1, cluster_count(&g) - 1, 12345 % cluster_count(&g)] {
        let (i, j, k) = dense_coords(&g, c);
        assert_eq!(dense_index(&g, i, j, k), c);
    }
    let lights = lights(&g, &mut rng, 400);
    for _ in 0..5000 {
        let (px, py) = (rng.below(g.width), rng.below(g.height));
        let d = 0.1 + 500.0 * rng.unit() * rng.unit();
        let z_buf = g.near / d;
        let c = pixel_cluster(&g, &bounds, px, py, z_buf);
        let (i, j, k) = dense_coords(&g, c);
        let b = cluster_aabb(&g, &bounds, i, j, k);
        let p = view_position(&g, px, py, reconstruct::distance_from_depth(g.near, z_buf));
        assert!((0..3).all(|a| b.min[a] <= p[a] && p[a] <= b.max[a]), "pixel ({px}, {py}) at {d} outside its cluster box");
        for l in &lights {
            if light_touches(l, p) {
                assert!(lighting::sphere_intersects_aabb(Vec3::from_array(l.position), l.radius, &b));
            }
        }
    }
    assert_eq!(pixel_cluster(&g, &bounds, 0, 0, 0.0), NO_CLUSTER);
}
