//! CPU tests of `forward_plus`: the emulated culling (widths 4…64) builds, per tile, a linked list
//! holding exactly the lights the tile's frustum test keeps (each once) — every light touching a
//! pixel among them — and with too few nodes links nothing past the capacity while the counter
//! still reaches the frame's need. The array variant writes, per tile, exactly those lights in
//! index order into one range of its own (the ranges tile the counter's span without overlap),
//! also for tiles longer than the staging list, and with too small a buffer writes nothing past
//! the capacity while the counter still reaches the need.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::lighting::light_touches;
use crate::light_lists::ListSink;
use crate::shading::NO_NODE;
use crate::test_support::{frame_params, gbuffer, test_lights, GBuffer, Rng};
use crate::tile_cull::{depth_cell, depth_cells, keep_light, tile_frustum, tile_rect, DepthCells, TileFrustum, MODE_TILED_25D, TILED_WORKGROUP};
use crate::reconstruct;
use std::sync::atomic::{AtomicU32, Ordering};

struct Nodes<'a>(&'a [AtomicU32]);

impl ListSink for Nodes<'_> {
    fn put(&mut self, i: u32, v: u32) {
        self.0[i as usize].store(v, Ordering::Relaxed);
    }
}

/// The tile's frustum and mask as the kernel computes them, on the CPU; the bounds also span
/// `widen` (view distances of transparent fragments), and a widened tile's mask keeps every cell.
fn tile_test(g: &ClusterGrid, depth: &[f32], tx: u32, ty: u32, widen: Option<(f32, f32)>) -> Option<(TileFrustum, DepthCells, u32)> {
    let (x0, x1, y0, y1) = tile_rect(g, tx, ty);
    let d: Vec<f32> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (y * g.width + x) as usize))
        .filter(|&i| !reconstruct::is_background(depth[i]))
        .map(|i| reconstruct::distance_from_depth(g.near, depth[i]))
        .collect();
    let ends = widen.map(|(a, b)| [a, b]).unwrap_or_default();
    let all = || d.iter().chain(ends.iter().take(if widen.is_some() { 2 } else { 0 })).cloned();
    let lo = all().reduce(f32::min)?;
    let hi = all().reduce(f32::max)?;
    let cells = depth_cells(lo, hi);
    let mask = if widen.is_some() { u32::MAX } else { d.iter().fold(0, |m, &x| m | 1u32 << depth_cell(&cells, x)) };
    Some((tile_frustum(g, tx, ty, lo, hi), cells, mask))
}

/// The lights each tile keeps, in index order, by the CPU tests (the frame's need).
fn expected_lists(g: &ClusterGrid, depth: &[f32], lights: &[PointLight], mode: u32) -> Vec<Vec<u32>> {
    expected_widened(g, depth, lights, mode, &vec![None; (g.tiles_x * g.tiles_y) as usize])
}

/// [`expected_lists`] with each tile's bounds widened to `widen[tile]`.
fn expected_widened(g: &ClusterGrid, depth: &[f32], lights: &[PointLight], mode: u32, widen: &[Option<(f32, f32)>]) -> Vec<Vec<u32>> {
    (0..g.tiles_x * g.tiles_y)
        .map(|t| match tile_test(g, depth, t % g.tiles_x, t / g.tiles_x, widen[t as usize]) {
            None => vec![],
            Some((f, cells, mask)) => (0..lights.len() as u32).filter(|&l| keep_light(&f, &cells, mask, mode, &lights[l as usize])).collect(),
        })
        .collect()
}

/// A 40×24 frame of 16 px tiles, its synthetic G-buffer, and `n` lights plus `coincident` ones
/// at one point.
struct Fixture {
    g: ClusterGrid,
    gb: GBuffer,
    lights: Vec<PointLight>,
}

fn fixture(seed: u64, n: usize, coincident: usize) -> Fixture {
    let g = ClusterGrid::new(40, 24, 16, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).unwrap();
    let mut rng = Rng(seed);
    let gb = gbuffer(&g, &mut rng);
    let lights = test_lights(&g, &mut rng, n, coincident);
    Fixture { g, gb, lights }
}

impl Fixture {
    /// The culling parameters for `mode`, each tile's expected list ([`expected_lists`]) and the
    /// frame's need (their total).
    fn expect(&self, mode: u32) -> (TiledParams, Vec<Vec<u32>>, u32) {
        let p = TiledParams { frame: frame_params(self.g, self.lights.len() as u32), mode, _pad: [0; 3] };
        let expected = expected_lists(&self.g, &self.gb.depth, &self.lights, mode);
        let need = expected.iter().map(|e| e.len() as u32).sum();
        (p, expected, need)
    }
}

#[test]
fn emulated_lists_hold_exactly_the_kept_lights() {
    let f = fixture(17, 400, 700);
    let (g, gb, lights) = (f.g, &f.gb, &f.lights);
    let tiles = g.tiles_x * g.tiles_y;
    for (width, mode) in [(4, MODE_TILED_25D), (8, 0), (16, MODE_TILED_25D), (32, 0), (64, MODE_TILED_25D)] {
        let (p, expected, need) = f.expect(mode);
        for capacity in [need, need / 3] {
            let heads: Vec<AtomicU32> = (0..tiles).map(|_| AtomicU32::new(NO_NODE)).collect();
            let nodes: Vec<AtomicU32> = (0..2 * need).map(|_| AtomicU32::new(0xdead)).collect();
            let counter = AtomicU32::new(0);
            let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: TILE_CULL_SHARED_WORDS as usize };
            run_workgroups(emu, tiles, |t, c, s| {
                let (mut ctr, mut head, mut sink) = (&counter, &heads[t as usize], Nodes(&nodes));
                cull_tile(c, s, &p, t % g.tiles_x, t / g.tiles_x, &gb.depth, lights, &mut ctr, &mut head, &mut sink, capacity, NO_WIDENING)
            });
            assert_eq!(counter.load(Ordering::Relaxed), need, "width {width}: the counter ends at the nodes needed");
            let mut linked = 0;
            for t in 0..tiles as usize {
                let mut got = Vec::new();
                let mut node = heads[t].load(Ordering::Relaxed);
                while node != NO_NODE {
                    assert!(node < capacity, "width {width}: node {node} linked past the capacity {capacity}");
                    got.push(nodes[2 * node as usize].load(Ordering::Relaxed));
                    node = nodes[2 * node as usize + 1].load(Ordering::Relaxed);
                }
                linked += got.len() as u32;
                got.sort_unstable();
                if capacity == need {
                    assert_eq!(got, expected[t], "width {width}, tile {t}");
                }
            }
            assert_eq!(linked, capacity.min(need), "width {width}: every node within the capacity is linked once");
        }
        // The kept lights include every light touching a pixel of the tile.
        for i in 0..(g.width * g.height) as usize {
            if reconstruct::is_background(gb.depth[i]) {
                continue;
            }
            let (px, py) = (i as u32 % g.width, i as u32 / g.width);
            let pos = reconstruct::view_position(&g, px, py, reconstruct::distance_from_depth(g.near, gb.depth[i]));
            let (tx, ty) = g.tile_of_pixel(px, py);
            let list = &expected[(ty * g.tiles_x + tx) as usize];
            for (l, light) in lights.iter().enumerate() {
                if light_touches(light, pos) {
                    assert!(list.binary_search(&(l as u32)).is_ok(), "light {l} touches pixel {i} but is not in its tile's list");
                }
            }
        }
    }
}

/// The array variant: per tile exactly the kept lights, in index order, in a range of its own;
/// tiles longer than the staging list (1500 coincident lights) take the second pass; with a third
/// of the need as capacity nothing lands past it, every entry below it is written, and the
/// counter still ends at the need.
#[test]
fn emulated_arrays_hold_exactly_the_kept_lights_in_index_order() {
    let f = fixture(23, 400, 1500);
    let (g, gb, lights) = (f.g, &f.gb, &f.lights);
    let tiles = g.tiles_x * g.tiles_y;
    for (width, mode) in [(4, 0), (8, MODE_TILED_25D), (16, 0), (32, MODE_TILED_25D), (64, 0)] {
        let (p, expected, need) = f.expect(mode);
        assert!(expected.iter().any(|e| e.len() as u32 > STAGE_CAPACITY), "some tile should hold more lights than the staging list");
        for capacity in [need, need / 3] {
            const UNWRITTEN: u32 = 0xdead;
            let indices: Vec<AtomicU32> = (0..need).map(|_| AtomicU32::new(UNWRITTEN)).collect();
            let counter = AtomicU32::new(0);
            let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: FP_ARRAY_SHARED_WORDS };
            let ranges = run_workgroups(emu, tiles, |t, c, s| {
                let (mut ctr, mut sink) = (&counter, Nodes(&indices));
                cull_tile_array(c, s, &p, t % g.tiles_x, t / g.tiles_x, &gb.depth, lights, &mut ctr, &mut sink, capacity, NO_WIDENING)
            });
            assert_eq!(counter.load(Ordering::Relaxed), need, "width {width}: the counter ends at the references needed");
            let mut covered = vec![false; need as usize];
            for t in 0..tiles as usize {
                let group = &ranges[t * TILED_WORKGROUP as usize..(t + 1) * TILED_WORKGROUP as usize];
                let r = group[0];
                assert!(group.iter().all(|&x| x == r), "width {width}, tile {t}: every invocation returns the tile's range");
                assert_eq!(r.count as usize, expected[t].len(), "width {width}, tile {t}: count");
                for (k, &light) in expected[t].iter().enumerate() {
                    let i = (r.offset + k as u32) as usize;
                    assert!(!covered[i], "width {width}, tile {t}: entry {i} belongs to two tiles");
                    covered[i] = true;
                    let got = indices[i].load(Ordering::Relaxed);
                    if (i as u32) < capacity {
                        assert_eq!(got, light, "width {width}, tile {t}: entry {k} of its range (index order)");
                    } else {
                        assert_eq!(got, UNWRITTEN, "width {width}, tile {t}: entry {i} written past the capacity {capacity}");
                    }
                }
            }
            assert!(covered.iter().all(|&c| c), "width {width}: the ranges tile the counter's span");
        }
    }
}

/// A frame without lights, and tiles of sky only: every range is empty and no atomic is spent.
#[test]
fn emulated_arrays_of_empty_tiles_are_empty() {
    let Fixture { g, gb, lights } = fixture(5, 50, 0);
    let sky = vec![0.0f32; gb.depth.len()];
    for (depth, n) in [(&gb.depth, 0), (&sky, lights.len() as u32)] {
        let p = TiledParams { frame: frame_params(g, n), mode: 0, _pad: [0; 3] };
        let counter = AtomicU32::new(0);
        let emu = Emulation { width: 8, workgroup_size: TILED_WORKGROUP, shared_words: FP_ARRAY_SHARED_WORDS };
        let ranges = run_workgroups(emu, g.tiles_x * g.tiles_y, |t, c, s| {
            let (mut ctr, mut sink) = (&counter, Nodes(&[]));
            cull_tile_array(c, s, &p, t % g.tiles_x, t / g.tiles_x, depth, &lights, &mut ctr, &mut sink, 0, NO_WIDENING)
        });
        assert!(ranges.iter().all(|r| r.count == 0), "{n} lights: every tile is empty");
        assert_eq!(counter.load(Ordering::Relaxed), 0, "{n} lights: nothing reserved");
    }
}

/// The tile depth words as the transparent pre-pass leaves them (atomic max of `!bits` and of
/// `bits` from 0) give back the fragments' range; a tile no fragment reached widens nothing.
#[test]
fn tile_depth_words_hold_the_transparent_range() {
    let mut words = vec![0u32; 2 * TILE_DEPTH_WORDS as usize];
    for d in [3.5f32, 0.25, 17.0, 4.0] {
        let w = TILE_DEPTH_WORDS as usize;
        words[w] = words[w].max(!d.to_bits());
        words[w + 1] = words[w + 1].max(d.to_bits());
    }
    assert_eq!(tile_widening(&words, 0), NO_WIDENING);
    assert_eq!(tile_widening(&words, 1), (0.25f32.to_bits(), 17.0f32.to_bits()));
}

/// Widened bounds (Forward+ with transparent draws): per tile exactly the lights the CPU keeps
/// for the opaque pixels and the transparent range together — in sky-only tiles too — and every
/// light touching a point of the tile at a transparent distance is among them; in both modes
/// (a widened tile's 2.5D mask keeps every cell), both list layouts.
#[test]
fn emulated_widened_tiles_keep_the_lights_of_their_transparent_fragments() {
    let f = fixture(31, 600, 0);
    let (g, lights) = (f.g, &f.lights);
    let tiles = g.tiles_x * g.tiles_y;
    // Opaque depth with a sky half, so some widened tiles have no opaque pixel at all.
    let depth: Vec<f32> = f.gb.depth.iter().enumerate().map(|(i, &z)| if (i as u32 % g.width) < g.width / 2 { 0.0 } else { z }).collect();
    let mut rng = Rng(99);
    let mut words = vec![0u32; (TILE_DEPTH_WORDS * tiles) as usize];
    let mut widen = vec![None; tiles as usize];
    for (t, w) in widen.iter_mut().enumerate() {
        if rng.below(3) == 0 {
            continue;
        }
        let (a, b) = (1.0 + rng.unit() * 40.0, 1.0 + rng.unit() * 40.0);
        let (lo, hi) = (a.min(b), a.max(b));
        for d in [lo, hi, 0.5 * (lo + hi)] {
            let w = (TILE_DEPTH_WORDS as usize) * t;
            words[w] = words[w].max(!d.to_bits());
            words[w + 1] = words[w + 1].max(d.to_bits());
        }
        *w = Some((lo, hi));
    }
    for (width, mode) in [(8, 0), (32, MODE_TILED_25D), (64, 0)] {
        let p = TiledParams { frame: frame_params(g, lights.len() as u32), mode, _pad: [0; 3] };
        let expected = expected_widened(&g, &depth, lights, mode, &widen);
        let need: u32 = expected.iter().map(|e| e.len() as u32).sum();
        // Arrays.
        let indices: Vec<AtomicU32> = (0..need).map(|_| AtomicU32::new(0)).collect();
        let counter = AtomicU32::new(0);
        let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: FP_ARRAY_SHARED_WORDS };
        let ranges = run_workgroups(emu, tiles, |t, c, s| {
            let (mut ctr, mut sink) = (&counter, Nodes(&indices));
            cull_tile_array(c, s, &p, t % g.tiles_x, t / g.tiles_x, &depth, lights, &mut ctr, &mut sink, need, tile_widening(&words, t))
        });
        // Linked lists.
        let heads: Vec<AtomicU32> = (0..tiles).map(|_| AtomicU32::new(NO_NODE)).collect();
        let nodes: Vec<AtomicU32> = (0..2 * need).map(|_| AtomicU32::new(0)).collect();
        let linked_counter = AtomicU32::new(0);
        let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: TILE_CULL_SHARED_WORDS as usize };
        run_workgroups(emu, tiles, |t, c, s| {
            let (mut ctr, mut head, mut sink) = (&linked_counter, &heads[t as usize], Nodes(&nodes));
            cull_tile(c, s, &p, t % g.tiles_x, t / g.tiles_x, &depth, lights, &mut ctr, &mut head, &mut sink, need, tile_widening(&words, t))
        });
        for t in 0..tiles {
            let r = ranges[(t * TILED_WORKGROUP) as usize];
            let got: Vec<u32> = (r.offset..r.offset + r.count).map(|i| indices[i as usize].load(Ordering::Relaxed)).collect();
            assert_eq!(got, expected[t as usize], "width {width}, mode {mode}, tile {t}: arrays");
            let mut walked = Vec::new();
            let mut node = heads[t as usize].load(Ordering::Relaxed);
            while node != NO_NODE {
                walked.push(nodes[2 * node as usize].load(Ordering::Relaxed));
                node = nodes[2 * node as usize + 1].load(Ordering::Relaxed);
            }
            walked.sort_unstable();
            assert_eq!(walked, expected[t as usize], "width {width}, mode {mode}, tile {t}: linked lists");
            let Some((lo, hi)) = widen[t as usize] else { continue };
            let (x0, x1, y0, y1) = tile_rect(&g, t % g.tiles_x, t / g.tiles_x);
            for k in 0..64 {
                let (px, py) = (x0 + rng.below(x1 - x0), y0 + rng.below(y1 - y0));
                let d = lo + (hi - lo) * (k as f32 / 63.0);
                let pos = reconstruct::view_position(&g, px, py, d);
                for (l, light) in lights.iter().enumerate() {
                    if light_touches(light, pos) {
                        assert!(got.contains(&(l as u32)), "light {l} touches a transparent point of tile {t} at distance {d} but is not in its list");
                    }
                }
            }
        }
        assert!(widen.iter().enumerate().any(|(t, w)| w.is_some() && (t as u32 % g.tiles_x) < g.tiles_x / 2 && !expected[t].is_empty()), "a sky-only widened tile keeps lights");
    }
}
