//! The whole bitonic-warp merge sort on the CPU: the same kernel functions as the GPU, run in the
//! lock-step emulation of [`crate::coop::cpu`] (one subgroup per emulated workgroup: the kernels
//! index subgroups themselves), with the host's plan ([`plan`]). Reference for the tests at any
//! subgroup width, and the CPU version of the kernels in `benches/sort.rs`.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use std::sync::atomic::{AtomicU32, Ordering};

/// The host's plan of a sort of `n` elements for a device whose narrowest subgroup is
/// `min_width` lanes, keeping every `keep`-th splitter sample: the block size and the merge
/// levels in order.
pub fn plan_with_keep(n: u32, min_width: u32, keep: u32) -> (u32, Vec<Level>) {
    let run0 = BLOCK;
    let levels = (0..level_count(n, run0)).map(|l| level(n, min_width, l, keep)).collect();
    (run0, levels)
}

/// [`plan_with_keep`] with [`SPLITTER_KEEP`].
pub fn plan(n: u32, min_width: u32) -> (u32, Vec<Level>) {
    plan_with_keep(n, min_width, SPLITTER_KEEP)
}

/// Output words shared by the emulated invocations (each index written once per dispatch).
pub struct AtomicOut<'a>(pub &'a [AtomicU32]);

impl Store for AtomicOut<'_> {
    fn store(&mut self, i: u32, v: u32) {
        self.0[i as usize].store(v, Ordering::Relaxed);
    }
}

fn atomics(n: usize) -> Vec<AtomicU32> {
    (0..n).map(|_| AtomicU32::new(u32::MAX)).collect()
}

fn plain(v: Vec<AtomicU32>) -> Vec<u32> {
    v.into_iter().map(AtomicU32::into_inner).collect()
}

/// Step 1 at subgroup width `width`: blocks of [`BLOCK`] elements sorted, as the kernel does
/// ([`sort_block`]).
pub fn block_sort_emulated(width: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let n = keys.len() as u32;
    let emu = Emulation { width, workgroup_size: BLOCK_WORKGROUP, shared_words: BLOCK_SHARED_WORDS };
    let lanes = run_workgroups(emu, n.div_ceil(BLOCK), |block, c, sh| {
        let base = block * BLOCK;
        (base + block_first(c), sort_block(c, sh, base, n, |i| keys[i as usize], |i| values[i as usize]))
    });
    let (mut k, mut v) = (keys.to_vec(), values.to_vec());
    for (first, (bk, bv)) in lanes {
        for j in 0..PER_LANE {
            let i = (first + j) as usize;
            if i < keys.len() {
                k[i] = bk[j as usize];
                v[i] = bv[j as usize];
            }
        }
    }
    (k, v)
}

/// Step 2a: the level's boundary array (`(a, b)` per piece), as the splitter kernel writes it.
pub fn splitters_emulated(keys: &[u32], lv: &Level) -> Vec<u32> {
    let mut out = vec![u32::MAX; 2 * lv.pieces() as usize];
    for slot in 0..lv.slots() {
        let s = splitter(keys, lv, slot);
        if s.piece != NO_PIECE {
            let i = 2 * s.piece as usize;
            assert_eq!(out[i], u32::MAX, "two splitters for piece {}", s.piece);
            out[i] = s.a;
            out[i + 1] = s.b;
        }
    }
    out
}

/// Step 2b at subgroup width `width`; returns the merged level and the most merge steps any
/// subgroup took.
pub fn merge_emulated(width: u32, lv: &Level, boundaries: &[u32], keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>, u32) {
    let n = keys.len();
    let (ko, vo) = (atomics(n), atomics(n));
    let emu = Emulation { width, workgroup_size: width, shared_words: 0 };
    let steps = run_workgroups(emu, lv.pieces(), |index, c, _| match piece_of(lv, boundaries, index) {
        Some(p) => merge_piece(c, keys, values, p, &mut AtomicOut(&ko), &mut AtomicOut(&vo)),
        None => 0,
    });
    (plain(ko), plain(vo), steps.into_iter().max().unwrap_or(0))
}

/// The whole sort at subgroup width `width`, planned for a narrowest width `plan_width`
/// (`≤ width`; equal on devices with one subgroup size). Returns keys, values and the most merge
/// steps one subgroup took.
pub fn sort_emulated(width: u32, plan_width: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>, u32) {
    sort_emulated_with_keep(width, plan_width, SPLITTER_KEEP, keys, values)
}

/// [`sort_emulated`] keeping every `keep`-th splitter sample.
pub fn sort_emulated_with_keep(width: u32, plan_width: u32, keep: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>, u32) {
    assert!(plan_width <= width);
    let (_, levels) = plan_with_keep(keys.len() as u32, plan_width, keep);
    if keys.len() <= 1 {
        return (keys.to_vec(), values.to_vec(), 0);
    }
    let (mut k, mut v) = block_sort_emulated(width, keys, values);
    let mut max_steps = 0;
    for lv in &levels {
        let boundaries = if lv.split() { splitters_emulated(&k, lv) } else { vec![0; 2] };
        let (k2, v2, s) = merge_emulated(width, lv, &boundaries, &k, &v);
        (k, v, max_steps) = (k2, v2, max_steps.max(s));
    }
    (k, v, max_steps)
}
