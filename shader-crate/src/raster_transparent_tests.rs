//! CPU tests of `raster_transparent`: the cluster pre-pass beside the opaque page-table steps
//! (every transparent fragment's cluster becomes a unique cluster; without the pre-pass the
//! lookup reports the fragment), and the list insert with an overflowing node buffer.
use super::*;
use crate::cluster_key::{slice_bounds, ClusterGrid};
use crate::page_table::{key_of_slot, page_count, pixel_key, slot_index, unique_keys_reference};

/// A frame's page table as the opaque kernels and the pre-pass build it (page_table steps 1–5).
struct Table {
    page_base: Vec<u32>,
    slot_rank: Vec<u32>,
    unique: Vec<u32>,
}

fn exclusive_scan(v: &[u32]) -> Vec<u32> {
    v.iter().scan(0, |s, &x| { let o = *s; *s += x; Some(o) }).collect()
}

fn params(grid: ClusterGrid, stage: u32, capacity: u32) -> TransparentParams {
    let frame = FrameParams {
        grid,
        count: grid.width * grid.height,
        num_lights: 0,
        light_capacity: 0,
        effects: 0,
        normal_precision: PRECISION_OCT16,
        view: VIEW_SHADED,
        exposure: 1.0,
        heat_max: 64,
    };
    let draw = TransparentDraw { albedo: [0.5; 3], material: 0, normal_precision: PRECISION_OCT16, first_primitive: 7, capacity, lists: stage };
    TransparentParams { frame, draw }
}

/// Opaque depth per pixel and transparent fragments `(px, py, z_buf)`; `prepass`: whether the
/// fragments mark their clusters.
fn build(grid: ClusterGrid, bounds: &[f32], depth: &[f32], fragments: &[(u32, u32, f32)], prepass: bool) -> Table {
    let keys: Vec<u32> = (0..depth.len() as u32).map(|i| pixel_key(&grid, bounds, i % grid.width, i / grid.width, depth[i as usize])).collect();
    let mut marks = vec![0u32; page_count(&grid) as usize];
    for &k in keys.iter().filter(|&&k| k != INVALID_KEY) {
        marks[page_table::page_of(k) as usize] = 1;
    }
    let frag = |&(x, y, z): &(u32, u32, f32)| Vec4::new(x as f32 + 0.5, y as f32 + 0.5, z, 1.0);
    let (mut no_slots, no_base) = (Vec::new(), Vec::new());
    if prepass {
        for f in fragments {
            mark_cluster(&params(grid, TRANSPARENT_MARK_PAGES, 0), bounds, &mut marks, &no_base, &mut no_slots, frag(f));
        }
    }
    let page_base = exclusive_scan(&marks);
    let allocated: u32 = marks.iter().sum();
    let page_of_alloc: Vec<u32> = (0..marks.len() as u32).filter(|&p| marks[p as usize] != 0).collect();
    let mut slots = vec![0u32; (allocated * PAGE_SIZE) as usize];
    for &k in keys.iter().filter(|&&k| k != INVALID_KEY) {
        slots[slot_index(page_base[page_table::page_of(k) as usize], k) as usize] = 1;
    }
    if prepass {
        let mut no_marks = Vec::new();
        for f in fragments {
            mark_cluster(&params(grid, TRANSPARENT_STORE_SLOTS, 0), bounds, &mut no_marks, &page_base, &mut slots, frag(f));
        }
    }
    let slot_rank = exclusive_scan(&slots);
    let unique = (0..slots.len() as u32).filter(|&s| slots[s as usize] != 0).map(|s| key_of_slot(&page_of_alloc, s)).collect();
    // The lookup reads past the allocated slots for keys of unmarked pages: stale ranks there.
    let mut slot_rank = slot_rank;
    slot_rank.resize(slot_rank.len() + 2 * PAGE_SIZE as usize, 0);
    Table { page_base, slot_rank, unique }
}

#[test]
fn every_transparent_fragment_finds_its_cluster_and_a_missing_mark_is_reported() {
    let grid = ClusterGrid::new(64, 36, 32, 0.1, 1000.0, 1.0).unwrap();
    let bounds = slice_bounds(&grid);
    // Opaque: a wall 50 m away (reversed Z: near / d), the top rows background.
    let depth: Vec<f32> = (0..64 * 36).map(|i| if i < 64 * 4 { 0.0 } else { 0.1 / 50.0 }).collect();
    // Transparent fragments at 2, 5 and 20 m, over the wall and over the background.
    let fragments: Vec<(u32, u32, f32)> =
        [(3, 10, 2.0), (40, 20, 5.0), (63, 35, 20.0), (10, 1, 5.0), (33, 2, 2.0)].iter().map(|&(x, y, d)| (x, y, 0.1 / d)).collect();
    let key = |&(x, y, z): &(u32, u32, f32)| pixel_key(&grid, &bounds, x, y, z);
    let t = build(grid, &bounds, &depth, &fragments, true);
    let opaque: Vec<u32> = (0..depth.len() as u32).map(|i| pixel_key(&grid, &bounds, i % 64, i / 64, depth[i as usize])).collect();
    let mut all = opaque.clone();
    all.extend(fragments.iter().map(key));
    assert_eq!(t.unique, unique_keys_reference(&all), "the opaque pixels' clusters and the fragments'");
    let clusters = t.unique.len() as u32;
    for f in &fragments {
        let c = fragment_cluster(&grid, &bounds, &t.page_base, &t.slot_rank, &t.unique, clusters, f.0, f.1, f.2);
        assert!(c != NO_CLUSTER && t.unique[c as usize] == key(f), "fragment {f:?}: cluster {c}");
    }
    // Without the pre-pass the fragments' clusters (none shared with the wall's) have no list.
    let t = build(grid, &bounds, &depth, &fragments, false);
    let clusters = t.unique.len() as u32;
    for f in &fragments {
        assert!(!opaque.contains(&key(f)), "fragment {f:?} shares an opaque cluster");
        let c = fragment_cluster(&grid, &bounds, &t.page_base, &t.slot_rank, &t.unique, clusters, f.0, f.1, f.2);
        assert_eq!(c, NO_CLUSTER, "fragment {f:?} found a cluster that was never marked");
    }
}

/// Fragments past the node buffer's capacity are counted but store nothing and leave the head
/// alone: every list holds stored nodes only, and the counter says how many nodes the frame needs.
#[test]
fn the_insert_counts_every_fragment_and_stores_those_that_fit() {
    let grid = ClusterGrid::new(4, 4, 32, 0.1, 1000.0, 1.0).unwrap();
    let p = params(grid, 0, 2);
    let lights: [PointLight; 0] = [];
    let materials = [MaterialGpu { specular: 0.0, roughness: 1.0, opacity: 0.5, _pad: 0.0 }];
    let b = TransparentBuffers {
        bounds: &[],
        page_base: &[],
        slot_rank: &[],
        unique: &[],
        cluster_counters: &[],
        counts: &[],
        offsets: &[],
        list: &[],
        lights: &lights,
        materials: &materials,
    };
    let (mut heads, mut nodes, mut counters) = (vec![OIT_END; 16], vec![OitNode { colour: [0; 2], depth: 0, next: 0, tie: 0 }; 2], vec![0u32; OIT_COUNTERS as usize]);
    for (i, z) in [0.5f32, 0.25, 0.125].into_iter().enumerate() {
        let frag = Vec4::new(1.5, 2.5, z, 1.0);
        transparent_fragment::<true>(&p, &b, frag, Vec3::Z, true, Vec3::ONE, i as u32, &mut heads, &mut nodes, &mut counters);
    }
    assert_eq!(counters[OIT_COUNTER_NODES as usize], 3, "every fragment counted");
    assert!(oit::overflowed(counters[OIT_COUNTER_NODES as usize], p.draw.capacity));
    let head = heads[2 * 4 + 1];
    assert_eq!(head, 1, "the last stored node heads the list");
    assert_eq!((nodes[1].next, nodes[0].next), (0, OIT_END));
    assert_eq!((nodes[0].tie, nodes[1].tie), (7, 8), "tie = the draw's first primitive + PrimitiveId");
    assert_eq!(heads.iter().filter(|&&h| h != OIT_END).count(), 1);
}

/// Buffers of a lookup test: `flags` as the cluster counters, `tiles` as the counts (tile
/// techniques) or per-cluster `counts`/`offsets` (dense grid).
fn lookup_buffers<'a>(bounds: &'a [f32], counters: &'a [u32], counts: &'a [u32], offsets: &'a [u32]) -> TransparentBuffers<'a> {
    TransparentBuffers { bounds, page_base: &[], slot_rank: &[], unique: &[], cluster_counters: counters, counts, offsets, list: &[], lights: &[], materials: &[] }
}

/// `clustered-aabb`: the pre-pass flags each fragment's dense cluster beside the opaque pixels'
/// flags; the lookup gives that cluster's range, and a cluster left unflagged has no list.
#[test]
fn dense_grid_fragments_flag_and_find_their_clusters() {
    let grid = ClusterGrid::new(64, 36, 32, 0.1, 1000.0, 1.0).unwrap();
    let bounds = slice_bounds(&grid);
    let n = dense_grid::cluster_count(&grid) as usize;
    let fragments: Vec<(u32, u32, f32)> = [(3, 10, 2.0), (40, 20, 5.0), (63, 35, 20.0), (10, 1, 5.0)].iter().map(|&(x, y, d)| (x, y, 0.1 / d)).collect();
    let frag = |&(x, y, z): &(u32, u32, f32)| Vec4::new(x as f32 + 0.5, y as f32 + 0.5, z, 1.0);
    let counts: Vec<u32> = (0..n as u32).map(|c| c % 7).collect();
    let offsets: Vec<u32> = (0..n as u32).map(|c| 3 * c).collect();
    for prepass in [true, false] {
        let mut flags = vec![0u32; n];
        let p = params(grid, TRANSPARENT_DENSE_GRID, 0);
        if prepass {
            for f in &fragments {
                mark_cluster(&p, &bounds, &mut flags, &[], &mut [], frag(f));
            }
        }
        let b = lookup_buffers(&bounds, &flags, &counts, &offsets);
        for f in &fragments {
            let c = dense_grid::pixel_cluster(&grid, &bounds, f.0, f.1, f.2);
            let got = fragment_list(&p, &b, f.0, f.1, f.2);
            if prepass {
                assert_eq!(flags[c as usize], 1, "fragment {f:?} flags its cluster");
                assert_eq!(got, FragmentList::range(offsets[c as usize], counts[c as usize]), "fragment {f:?}");
            } else {
                assert_eq!(got, FragmentList::NONE, "fragment {f:?}: an unflagged cluster has no list");
            }
        }
    }
}

/// `forward-plus`: the pre-pass widens each tile's depth range to its fragments; the lookup gives
/// the tile's range (arrays) or head (linked lists), and nothing in a frame whose lists overflowed.
#[test]
fn tile_fragments_widen_their_tile_and_find_its_list() {
    let grid = ClusterGrid::new(64, 36, 16, 0.1, 1000.0, 1.0).unwrap();
    let tiles = (grid.tiles_x * grid.tiles_y) as usize;
    let fragments: Vec<(u32, u32, f32)> = [(3, 10, 2.0), (5, 12, 9.0), (40, 20, 5.0)].iter().map(|&(x, y, d)| (x, y, 0.1 / d)).collect();
    let frag = |&(x, y, z): &(u32, u32, f32)| Vec4::new(x as f32 + 0.5, y as f32 + 0.5, z, 1.0);
    let mut words = vec![0u32; TILE_DEPTH_WORDS as usize * tiles];
    for f in &fragments {
        mark_cluster(&params(grid, TRANSPARENT_TILE_ARRAYS, 0), &[], &mut words, &[], &mut [], frag(f));
    }
    let dist = |z: f32| crate::reconstruct::distance_from_depth(grid.near, z);
    let tile = |x: u32, y: u32| {
        let (tx, ty) = grid.tile_of_pixel(x, y);
        (ty * grid.tiles_x + tx) as usize
    };
    let t0 = tile(3, 10);
    assert_eq!((!words[2 * t0], words[2 * t0 + 1]), (dist(0.1 / 2.0).to_bits(), dist(0.1 / 9.0).to_bits()), "the first tile spans 2 to 9 m");
    let marked = words.chunks(2).filter(|w| w[1] != 0).count();
    assert_eq!(marked, 2, "two tiles hold fragments");
    let ranges: Vec<u32> = (0..2 * tiles as u32).collect();
    for (lists, overflow) in [(TRANSPARENT_TILE_ARRAYS, false), (TRANSPARENT_TILE_LINKED, false), (TRANSPARENT_TILE_ARRAYS, true)] {
        let mut p = params(grid, lists, 0);
        p.frame.light_capacity = 100;
        let counters = [if overflow { 101 } else { 100 }];
        let b = lookup_buffers(&[], &counters, &ranges, &[]);
        for f in &fragments {
            let t = tile(f.0, f.1) as u32;
            let want = match (overflow, lists) {
                (true, _) => FragmentList::NONE,
                (false, TRANSPARENT_TILE_ARRAYS) => FragmentList::range(2 * t, 2 * t + 1),
                _ => FragmentList { kind: LIST_LINKED, first: t, count: 0 },
            };
            assert_eq!(fragment_list(&p, &b, f.0, f.1, f.2), want, "lists {lists}, overflow {overflow}, fragment {f:?}");
        }
    }
}
