//! GPU key–value sorts on the local device, validation on, for both light sorters:
//! - radix (stable): the output equals a stable sort of the input;
//! - bitonic (not stable): the keys equal `sort` of the input keys and the (key, value) multiset
//!   is unchanged.
//!
//! Lengths 0–3, 127–129, every length from one radix tile to two tiles + 1 (256..=513), for the
//! bitonic sort also every length from one block (4·W) to two blocks + 1 and from one piece
//! (`g·k`, the largest pair merged without splitters) to two pieces + 1, and 2^20 (+17); on
//! all-equal, sorted, reverse, few-distinct and random keys.
mod common;
use host::gpu::Gpu;
use host::render::sort::{LightSorter, SortKind};
use host::vk::Buffer;
use shaders::bitonic::{block_elems, sample_stride, SPLITTER_KEEP};
use shaders::sort_inputs::shapes as inputs;

fn check(gpu: &Gpu, sorter: &LightSorter, keys: &[u32], what: &str) {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let mut kb = Buffer::from_slice(&gpu.ctx, "keys", keys).unwrap();
    let mut vb = Buffer::from_slice(&gpu.ctx, "values", &values).unwrap();
    gpu.run(None, |rec| sorter.record(gpu, rec, &kb, &vb, n as u32, 32)).unwrap();
    let (k, v): (Vec<u32>, Vec<u32>) = (kb.read(n).unwrap(), vb.read(n).unwrap());
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    let mut got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
    let kind = match sorter {
        LightSorter::Radix(_) => {
            expected.sort_by_key(|e| e.0); // stable: equal keys keep index order
            "radix"
        }
        LightSorter::Bitonic(_) => {
            expected.sort_by_key(|e| e.0);
            let keys_differ = got.iter().zip(&expected).position(|(a, b)| a.0 != b.0);
            if let Some(i) = keys_differ {
                panic!("bitonic, {what} (n = {n}): keys differ first at {i}");
            }
            got.sort_unstable();
            expected.sort_unstable();
            "bitonic"
        }
    };
    if got != expected {
        let first = got.iter().zip(&expected).position(|(a, b)| a != b);
        panic!("{kind}, {what} (n = {n}): first difference at {first:?}");
    }
}

fn lengths(gpu: &Gpu, kind: SortKind) -> Vec<usize> {
    let mut lengths: Vec<usize> = vec![0, 1, 2, 3, 127, 128, 129];
    lengths.extend(256..=513); // every size from one radix tile to two tiles + 1
    if kind == SortKind::Bitonic {
        let w = gpu.ctx.info.min_subgroup_size;
        let (block, piece) = (block_elems(w) as usize, (SPLITTER_KEEP * sample_stride(w)) as usize);
        lengths.extend(block..=2 * block + 1);
        lengths.extend(piece..=2 * piece + 1);
        lengths.sort_unstable();
        lengths.dedup();
    }
    lengths
}

fn small_and_partial_lengths(kind: SortKind) {
    let gpu = common::gpu();
    // Plan for the longest length: the piece-boundary lengths grow with the subgroup width
    // (1024 fits lavapipe's width 8, not NVIDIA's 32).
    let lengths = lengths(&gpu, kind);
    let capacity = lengths.iter().copied().max().unwrap_or(1).max(1) as u32;
    let sorter = LightSorter::new(&gpu, kind, capacity).unwrap();
    for n in lengths {
        for (what, keys) in inputs(n, n as u32 + 1) {
            if n > 3 && n < 256 && !(127..=129).contains(&n) && what != "random" {
                continue; // the shapes matter for the boundary lengths, not every small one
            }
            check(&gpu, &sorter, &keys, what);
        }
    }
    common::assert_clean(&gpu);
}

fn a_million(kind: SortKind) {
    let gpu = common::gpu();
    let n = (1 << 20) + 17;
    let sorter = LightSorter::new(&gpu, kind, n as u32).unwrap();
    for (what, keys) in inputs(n, 99) {
        check(&gpu, &sorter, &keys, what);
        check(&gpu, &sorter, &keys[..1 << 20], what);
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

#[test]
fn bitonic_small_block_and_piece_lengths() {
    small_and_partial_lengths(SortKind::Bitonic);
}

#[test]
fn bitonic_a_million_keys() {
    a_million(SortKind::Bitonic);
}
