use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::indirect::dispatch_args;
use crate::page_table::{pixel_key, unique_keys_reference, INVALID_KEY};
use std::sync::atomic::{AtomicU32, Ordering};

/// A depth buffer (reversed Z, `near / d`) with background, steps between surfaces and a
/// depth range that crosses many slices, including ones past the first mask word.
fn depth_buffer(g: &ClusterGrid, seed: u32) -> Vec<f32> {
    (0..g.width * g.height)
        .map(|i| {
            let (x, y) = (i % g.width, i / g.width);
            let h = (x.wrapping_mul(2_654_435_761) ^ y.wrapping_mul(40_503) ^ seed).wrapping_mul(2_246_822_519) >> 8;
            match h % 11 {
                0 => 0.0,
                1..=3 => g.near / (0.5 + (h % 997) as f32 * 0.9),
                _ => g.near / (1.0 + 0.05 * x as f32 + 0.03 * y as f32),
            }
        })
        .collect()
}

struct Frame {
    keys: Vec<u32>,
    records: Vec<u32>,
    unique: Vec<u32>,
    args: [u32; 3],
}

/// The tile kernel over every tile of `g`, tiles launched in `order`, in the CPU emulation at
/// subgroup width `width`; the writes the GPU entry makes, made from each invocation's result.
/// `depth` holds one plane of `width × height` per sample (MSAA, `crate::msaa`): entry `s·n + i`.
fn run(g: &ClusterGrid, bounds: &[f32], depth: &[f32], width: u32, per_group: u32, reversed: bool) -> Frame {
    let plane = g.width * g.height;
    let planes = depth.len() as u32 / plane;
    let tiles = g.tiles_x * g.tiles_y;
    let words = mask_words(g);
    let counter = AtomicU32::new(0);
    let args: [AtomicU32; 3] = Default::default();
    let emu = Emulation { width, workgroup_size: TILE_WORKGROUP, shared_words: SHARED_WORDS };
    let tile_of = |group: u32| if reversed { tiles - 1 - group } else { group };
    let results = run_workgroups(emu, tiles, |group, c, s| {
        let t = tile_of(group);
        let rect = tile_rect(g, t % g.tiles_x, t / g.tiles_x);
        let slice_of = |s: u32, q: u32| {
            let (px, py) = tile_pixel(rect, q);
            let key = pixel_key(g, bounds, px, py, depth[(s * plane + py * g.width + px) as usize]);
            if key == INVALID_KEY { NO_SLICE } else { g.unpack(key).2 }
        };
        let reserve = |n: u32| {
            let first = counter.fetch_add(n, Ordering::Relaxed);
            let (x, y) = dispatch_raise(first + n, per_group);
            args[0].fetch_max(x, Ordering::Relaxed);
            if y > 1 {
                args[1].fetch_max(y, Ordering::Relaxed);
            }
            first
        };
        tile_clusters(c, s, words, rect.2 * rect.3, planes, slice_of, reserve)
    });
    // Workgroup (0, 0)'s raise of the rows and the depth.
    args[1].fetch_max(1, Ordering::Relaxed);
    args[2].fetch_max(1, Ordering::Relaxed);
    let total = counter.load(Ordering::Relaxed);
    let mut records = vec![u32::MAX; record_words(g) as usize];
    let mut unique = vec![u32::MAX; total as usize];
    for group in 0..tiles {
        let t = tile_of(group);
        let (i, j) = (t % g.tiles_x, t / g.tiles_x);
        for w in 0..words {
            let (mask, first) = results[(group * TILE_WORKGROUP + w) as usize];
            let at = record_at(g, i, j, w) as usize;
            records[at] = mask;
            records[at + 1] = first;
            emit_word_clusters(g, i, j, w, mask, first, |n, key| {
                assert_eq!(unique[n as usize], u32::MAX, "index {n} given twice");
                unique[n as usize] = key;
            });
        }
    }
    let keys = (0..planes * plane).map(|e| pixel_key(g, bounds, e % plane % g.width, e % plane / g.width, depth[e as usize])).collect();
    Frame { keys, records, unique, args: args.map(|a| a.into_inner()) }
}

/// Every tile finds exactly its distinct keys: the list holds each key of the frame once and
/// nothing else, every pixel's lookup lands on its own key, and the assignment's dispatch
/// covers the list, at every subgroup width, for tiles of fewer and more pixels than the
/// workgroup, partial border tiles, whatever order the tiles reserve in, and one or four sample
/// planes (each sample's key found in its own plane).
#[test]
fn each_tile_lists_its_distinct_keys_once_and_pixels_find_them() {
    for (w, h, tile, planes) in [(67, 45, 8, 1), (130, 70, 16, 1), (200, 97, 32, 1), (300, 200, 64, 1), (67, 45, 8, 4), (200, 97, 32, 4)] {
        let g = ClusterGrid::new(w, h, tile, 0.1, 1000.0, 1.0).expect("valid grid");
        assert!(serves(&g) && mask_words(&g) > 1, "{g:?}");
        let bounds = crate::cluster_key::slice_bounds(&g);
        let depth: Vec<f32> = (0..planes).flat_map(|s| depth_buffer(&g, w ^ tile ^ (s << 20))).collect();
        for width in [4, 8, 16, 32, 64] {
            for reversed in [false, true] {
                let per_group = 2;
                let f = run(&g, &bounds, &depth, width, per_group, reversed);
                let case = format!("{w}x{h}, {tile} px tiles, {planes} planes, width {width}, reversed {reversed}");
                let mut sorted = f.unique.clone();
                sorted.sort_unstable();
                assert_eq!(sorted, unique_keys_reference(&f.keys), "{case}");
                for (p, &key) in f.keys.iter().enumerate() {
                    if key != INVALID_KEY {
                        let c = cluster_of_key(&g, &f.records, key);
                        assert_eq!(f.unique[c as usize], key, "{case}: pixel {p}");
                    }
                }
                assert_eq!(f.args, dispatch_args(f.unique.len() as u32, per_group), "{case}");
            }
        }
    }
}

/// A frame of background only reserves nothing and dispatches no assignment workgroup; the
/// raised words give `indirect::dispatch_args` of any count, past one row of workgroups too.
#[test]
fn a_frame_without_geometry_has_no_clusters() {
    let g = ClusterGrid::new(70, 40, 32, 0.1, 1000.0, 1.0).expect("valid grid");
    let bounds = crate::cluster_key::slice_bounds(&g);
    let f = run(&g, &bounds, &vec![0.0; 70 * 40], 8, 2, false);
    assert!(f.unique.is_empty());
    assert_eq!(f.args, dispatch_args(0, 2));
    for end in [1, 2, 3, 131_070, 131_071, 131_072, 10_000_000] {
        let (x, y) = dispatch_raise(end, 2);
        assert_eq!([x, y.max(1), 1], dispatch_args(end, 2), "{end}");
        let (x2, y2) = dispatch_raise(end + 1, 2);
        assert!(x2 >= x && y2 >= y, "never decreases past {end}");
    }
}

/// The next frame's atomics start from zero: the hand-over keeps the count for the host.
#[test]
fn the_hand_over_keeps_the_count_and_zeroes_the_atomics() {
    use crate::layout::*;
    let mut counters = [17, 5, 0, 0];
    let mut args = [9, 9, 9, 4, 2, 1];
    hand_over_counters(&mut counters, &mut args);
    assert_eq!(counters[COUNTER_FRAME_CLUSTERS as usize], 17);
    assert_eq!(counters[COUNTER_UNIQUE_CLUSTERS as usize], 0);
    assert_eq!(counters[COUNTER_LIGHT_REFS as usize], 5);
    assert_eq!(args, [9, 9, 9, 0, 0, 0]);
}
