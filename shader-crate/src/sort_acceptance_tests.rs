//! The sort acceptance matrix on the CPU, for both light sorters — the radix sort as the host
//! records it and with its chained-scan passes ([`crate::radix::chained`], workgroups launched
//! in a shuffled order) — in the lock-step emulation of their GPU kernels
//! ([`crate::coop::cpu`]) at subgroup widths 4, 8, 16, 32 and 64:
//!
//! * lengths 0, 1, 2, 3, 127, 128, 129, 2^20 and 2^20 + 17, and every length from one partition
//!   to two partitions + 1 — for the radix sort its tile ([`RADIX_TILE`] keys: 2048..=4097, every
//!   partial last tile, with 255–257 and 2047–2049 the edges of its single-workgroup path), for
//!   the bitonic sort both of its partitions: the block of the block sort (`M = 4·W`:
//!   `M..=2M+1`) and the piece merged without splitters (`P = k·g = 16·W`: `P..=2P+1`, the
//!   lengths whose merge levels start splitting);
//! * every length on all five input shapes: all equal, already sorted, reverse sorted, few
//!   distinct values (4) and random (with a real `0xFFFF_FFFF`, the bitonic pads' key);
//! * radix (both variants) is stable, so its output must equal a stable sort of the (key, value) pairs exactly;
//!   the bitonic sort is not, so its keys must equal `sort` of the keys and its (key, value)
//!   multiset must be unchanged.
//!
//! The same lengths and shapes run on the GPU (lavapipe, and the H100) in `tests/sort.rs`.
use crate::bitonic::{emulated::sort_emulated as bitonic_sort, sample_stride, BLOCK, SPLITTER_KEEP};
use crate::radix::chained::emulated::{sort_chained_emulated, Order, Schedule};
use crate::radix::{emulated::sort_emulated as radix_sort, RADIX_TILE};
pub use crate::sort_inputs::shapes as inputs;

/// A million and seventeen: the acceptance's 2^20 + 17.
const MILLION: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Sorter {
    /// As the host records it: one workgroup up to one tile, reduce-then-scan passes above.
    Radix,
    /// The chained-scan passes at every length, workgroups launched in a shuffled order on 3
    /// resident threads.
    RadixChained,
    Bitonic,
}

/// Sorts `keys` (values = their indices) in the emulation at `width` and checks the result;
/// returns the most merge steps one subgroup took (bitonic; 0 for radix).
fn check(sorter: Sorter, width: u32, keys: &[u32], what: &str) -> u32 {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    expected.sort_by_key(|e| e.0); // stable: equal keys keep index order
    let ctx = format!("{sorter:?}, {what}, n = {n}, width {width}");
    let (k, v, steps) = match sorter {
        Sorter::Radix => {
            let (k, v) = radix_sort(width, keys, &values);
            (k, v, 0)
        }
        Sorter::RadixChained => {
            let schedule = Schedule { resident: 3, order: Order::Shuffled(n as u32 ^ width) };
            let (k, v) = sort_chained_emulated(width, keys, &values, 32, schedule);
            (k, v, 0)
        }
        Sorter::Bitonic => bitonic_sort(width, width, keys, &values),
    };
    let mut got: Vec<(u32, u32)> = k.iter().copied().zip(v).collect();
    if let Some(i) = (0..n).find(|&i| k[i] != expected[i].0) {
        panic!("{ctx}: keys differ first at {i} ({} instead of {})", k[i], expected[i].0);
    }
    if sorter == Sorter::Bitonic {
        got.sort_unstable();
        expected.sort_unstable();
    }
    if let Some(i) = (0..n).find(|&i| got[i] != expected[i]) {
        panic!("{ctx}: (key, value) pairs differ first at {i}: {:?} instead of {:?}", got[i], expected[i]);
    }
    steps
}

/// Every length of the matrix below 2^20 for `sorter` at `width`.
fn partition_lengths(sorter: Sorter, width: u32) -> Vec<usize> {
    let mut lengths: Vec<usize> = vec![0, 1, 2, 3, 127, 128, 129];
    match sorter {
        Sorter::Radix | Sorter::RadixChained => {
            // The single-workgroup path's boundaries (it takes up to one tile), then every
            // length from one tile to two tiles + 1: every partial last tile of the tile path.
            lengths.extend([255, 256, 257, RADIX_TILE as usize - 1]);
            lengths.extend(RADIX_TILE as usize..=2 * RADIX_TILE as usize + 1);
        }
        Sorter::Bitonic => {
            let block = BLOCK as usize;
            let piece = (SPLITTER_KEEP * sample_stride(width)) as usize;
            lengths.extend(block..=2 * block + 1);
            lengths.extend(piece..=2 * piece + 1);
        }
    }
    lengths.sort_unstable();
    lengths.dedup();
    lengths
}

fn partitions(sorter: Sorter, width: u32) {
    let mut max_steps = 0;
    for n in partition_lengths(sorter, width) {
        for (what, keys) in inputs(n, n as u32 ^ width) {
            max_steps = max_steps.max(check(sorter, width, &keys, what));
        }
    }
    // One merge step consumes t = 2·W = g elements; a piece holds at most (k+2)·g − 2.
    assert!(max_steps <= SPLITTER_KEEP + 2, "{sorter:?} width {width}: {max_steps} merge steps in one subgroup");
}

fn a_million(sorter: Sorter, width: u32) {
    for (what, keys) in inputs(MILLION + 17, 99 ^ width) {
        check(sorter, width, &keys, what);
        check(sorter, width, &keys[..MILLION], what);
    }
}

macro_rules! matrix {
    ($($name:ident: $sorter:ident, $width:literal;)*) => {
        mod partitions {
            use super::*;
            $(#[test] fn $name() { partitions(Sorter::$sorter, $width); })*
        }
        mod a_million_keys {
            use super::*;
            $(#[test] fn $name() { a_million(Sorter::$sorter, $width); })*
        }
    };
}

matrix! {
    radix_width_4: Radix, 4;
    radix_width_8: Radix, 8;
    radix_width_16: Radix, 16;
    radix_width_32: Radix, 32;
    radix_width_64: Radix, 64;
    radix_chained_width_4: RadixChained, 4;
    radix_chained_width_8: RadixChained, 8;
    radix_chained_width_16: RadixChained, 16;
    radix_chained_width_32: RadixChained, 32;
    radix_chained_width_64: RadixChained, 64;
    bitonic_width_4: Bitonic, 4;
    bitonic_width_8: Bitonic, 8;
    bitonic_width_16: Bitonic, 16;
    bitonic_width_32: Bitonic, 32;
    bitonic_width_64: Bitonic, 64;
}
