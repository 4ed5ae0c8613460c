//! GPU key–value sorts on the local device, validation on, for both light sorters and the one
//! that picks between them by size (`auto`, stable above its switch):
//! - radix (stable): the output equals a stable sort of the input;
//! - bitonic (not stable): the keys equal `sort` of the input keys and the (key, value) multiset
//!   is unchanged.
//!
//! Lengths 0–3, 127–129; for the radix sort 255–257, 2047 and every length from one tile to two
//! tiles + 1 (2048..=4097: the edge of the single-workgroup path and every partial last tile);
//! for the size-picked sort (`auto`) both sides of its switch from the bitonic to the radix sort
//! (2^15 − 1..=2^15 + 1) and a few lengths below and above it;
//! for the bitonic sort every length from one block (4·W) to two blocks + 1 and from one piece
//! (`g·k`, the largest pair merged without splitters) to two pieces + 1; and 2^20 (+17); on
//! all-equal, sorted, reverse, few-distinct and random keys. The radix sort also runs at every
//! key width's pass count (odd counts end with a copy) and refuses bad input with an error, as
//! every sorter refuses more pairs than its buffers. Where
//! the device runs the chained scan, the radix lengths run on both cross-tile variants (the
//! device picks by size, `render::sort::CHAINED_UP_TO_PAIRS`).
mod common;
use host::gpu::Gpu;
use host::render::sort::{CrossTile, LightSorter, RadixSort, SortKind, SMALL_SORT_PAIRS};
use host::vk::Buffer;
use shaders::bitonic::{sample_stride, BLOCK, SPLITTER_KEEP};
use shaders::radix::RADIX_TILE;
use shaders::sort_inputs::shapes as inputs;

fn check(gpu: &Gpu, sorter: &LightSorter, keys: &[u32], what: &str) {
    check_bits(gpu, sorter, keys, 32, what);
}

/// Sorts `keys` (below `2^key_bits`), values = their indices, and compares with the CPU.
fn check_bits(gpu: &Gpu, sorter: &LightSorter, keys: &[u32], key_bits: u32, what: &str) {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let mut kb = Buffer::from_slice(&gpu.ctx, "keys", keys).unwrap();
    let mut vb = Buffer::from_slice(&gpu.ctx, "values", &values).unwrap();
    gpu.run(None, |rec| sorter.record(gpu, rec, &kb, &vb, n as u32, key_bits)).unwrap();
    let (k, v): (Vec<u32>, Vec<u32>) = (kb.read(n).unwrap(), vb.read(n).unwrap());
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    let mut got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
    let kind = match sorter {
        LightSorter::Radix(_) => "radix",
        LightSorter::Bitonic(_) => "bitonic",
        LightSorter::Auto { .. } => "auto",
    };
    expected.sort_by_key(|e| e.0); // stable: equal keys keep index order
    if !sorter.stable(n as u32) {
        let keys_differ = got.iter().zip(&expected).position(|(a, b)| a.0 != b.0);
        if let Some(i) = keys_differ {
            panic!("{kind}, {what} (n = {n}): keys differ first at {i}");
        }
        got.sort_unstable();
        expected.sort_unstable();
    }
    if got != expected {
        let first = got.iter().zip(&expected).position(|(a, b)| a != b);
        panic!("{kind}, {what} (n = {n}): first difference at {first:?}");
    }
}

fn lengths(gpu: &Gpu, kind: SortKind) -> Vec<usize> {
    let mut lengths: Vec<usize> = vec![0, 1, 2, 3, 127, 128, 129];
    if kind == SortKind::Radix {
        let tile = RADIX_TILE as usize;
        lengths.extend([255, 256, 257, tile - 1]);
        lengths.extend(tile..=2 * tile + 1); // every size from one tile to two tiles + 1
    }
    if kind == SortKind::Auto {
        let small = SMALL_SORT_PAIRS as usize;
        lengths.extend([BLOCK as usize + 1, RADIX_TILE as usize + 1, small - 1, small, small + 1, 2 * small + 3]);
    }
    if kind == SortKind::Bitonic {
        let w = gpu.ctx.info.min_subgroup_size;
        let (block, piece) = (BLOCK as usize, (SPLITTER_KEEP * sample_stride(w)) as usize);
        lengths.extend(block..=2 * block + 1);
        lengths.extend(piece..=2 * piece + 1);
    }
    lengths.sort_unstable();
    lengths.dedup();
    lengths
}

/// The sorters of `kind` for `capacity` pairs: the device's choice, and for the radix sort on a
/// device that runs the chained scan also the other variant.
fn sorters(gpu: &Gpu, kind: SortKind, capacity: u32) -> Vec<LightSorter> {
    let mut v = vec![LightSorter::new(gpu, kind, capacity).unwrap()];
    if kind == SortKind::Radix && gpu.ctx.info.workgroups_progress() {
        for cross in [CrossTile::Chained, CrossTile::ReduceThenScan] {
            v.push(LightSorter::Radix(Box::new(RadixSort::with_cross_tile(gpu, capacity, cross).unwrap())));
        }
    }
    v
}

fn small_and_partial_lengths(kind: SortKind) {
    let gpu = common::gpu();
    // Plan for the longest length: the piece-boundary lengths grow with the subgroup width
    // (1024 fits lavapipe's width 8, not NVIDIA's 32).
    let lengths = lengths(&gpu, kind);
    let capacity = lengths.iter().copied().max().unwrap_or(1).max(1) as u32;
    for sorter in sorters(&gpu, kind, capacity) {
        for &n in &lengths {
            for (what, keys) in inputs(n, n as u32 + 1) {
                let edge = [0..=3, 127..=129, 255..=257, 1023..=1025, 2047..=2049, 4095..=4097, 32767..=32769].iter().any(|r| r.contains(&n));
                if !edge && what != "random" {
                    continue; // every shape at the edges, random keys at every length
                }
                check(&gpu, &sorter, &keys, what);
            }
        }
    }
    common::assert_clean(&gpu);
}

fn a_million(kind: SortKind) {
    let gpu = common::gpu();
    let n = (1 << 20) + 17;
    for sorter in sorters(&gpu, kind, n as u32) {
        for (what, keys) in inputs(n, 99) {
            check(&gpu, &sorter, &keys, what);
            check(&gpu, &sorter, &keys[..1 << 20], what);
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn radix_small_and_partial_tile_lengths() {
    small_and_partial_lengths(SortKind::Radix);
}

#[test]
fn radix_a_million_keys() {
    a_million(SortKind::Radix);
}

/// Every pass count (odd ones end with a copy into the caller's buffers), keys masked to the
/// width, on both radix paths.
#[test]
fn radix_every_key_width() {
    let gpu = common::gpu();
    let n = 3 * RADIX_TILE as usize + 5;
    let sorter = LightSorter::new(&gpu, SortKind::Radix, n as u32).unwrap();
    for key_bits in [1, 8, 12, 16, 24, 30, 32] {
        let mask = if key_bits == 32 { u32::MAX } else { (1u32 << key_bits) - 1 };
        for (what, keys) in inputs(n, key_bits) {
            let keys: Vec<u32> = keys.iter().map(|k| k & mask).collect();
            check_bits(&gpu, &sorter, &keys, key_bits, what);
            check_bits(&gpu, &sorter, &keys[..RADIX_TILE as usize - 1], key_bits, what);
        }
    }
    common::assert_clean(&gpu);
}

/// The error of recording a sort of `n` pairs of `key_bits`-bit keys with a `kind` sorter made
/// for 100 pairs (buffers of 200).
fn refusal(gpu: &Gpu, kind: SortKind, n: u32, key_bits: u32) -> String {
    let sorter = LightSorter::new(gpu, kind, 100).unwrap();
    let kb = Buffer::from_slice(&gpu.ctx, "keys", &[0u32; 200]).unwrap();
    let vb = Buffer::from_slice(&gpu.ctx, "values", &[0u32; 200]).unwrap();
    gpu.run(None, |rec| sorter.record(gpu, rec, &kb, &vb, n, key_bits)).unwrap_err().to_string()
}

/// Keys wider than 32 bits: an error, no dispatch.
#[test]
fn radix_refuses_bad_input() {
    let gpu = common::gpu();
    let err = refusal(&gpu, SortKind::Radix, 50, 33);
    assert!(err.contains("keys of 33 bits"), "{err}");
    common::assert_clean(&gpu);
}

/// More pairs than the buffers were made for: the same error from every sorter (`auto` with a
/// capacity below its switch too), no dispatch.
#[test]
fn every_sorter_refuses_more_pairs_than_its_buffers() {
    let gpu = common::gpu();
    for kind in [SortKind::Radix, SortKind::Bitonic, SortKind::Auto] {
        let err = refusal(&gpu, kind, 101, 30);
        assert!(err.contains("sorting 101 pairs with buffers for 100"), "{kind:?}: {err}");
    }
    common::assert_clean(&gpu);
}

/// The default light sort: the bitonic sort up to `SMALL_SORT_PAIRS`, the radix sort above,
/// around the switch.
#[test]
fn auto_sorts_on_both_sides_of_the_switch() {
    small_and_partial_lengths(SortKind::Auto);
}

#[test]
fn bitonic_small_block_and_piece_lengths() {
    small_and_partial_lengths(SortKind::Bitonic);
}

#[test]
fn bitonic_a_million_keys() {
    a_million(SortKind::Bitonic);
}
