//! The whole bitonic-warp merge sort on the CPU: the same kernel functions as the GPU, run in the
//! lock-step emulation of [`crate::coop::cpu`] (one subgroup per emulated workgroup: the kernels
//! index subgroups themselves), with the host's plan ([`plan`]). Reference for the tests at any
//! subgroup width, and the CPU version of the kernels in `benches/sort.rs`.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use std::sync::atomic::{AtomicU32, Ordering};

/// The host's plan of a sort of `n` elements for a device whose narrowest subgroup is
/// `min_width` lanes: the block size and the merge levels in order.
pub fn plan(n: u32, min_width: u32) -> (u32, Vec<Level>) {
    let run0 = block_elems(min_width);
    let levels = (0..level_count(n, run0)).map(|l| level(n, min_width, l)).collect();
    (run0, levels)
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

/// Step 1 at subgroup width `width`: blocks of `run0 ≤ 4·width` elements sorted.
pub fn block_sort_emulated(width: u32, run0: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    assert!(run0 <= PER_LANE * width, "block of {run0} elements at width {width}");
    let n = keys.len() as u32;
    let emu = Emulation { width, workgroup_size: width, shared_words: 0 };
    let lanes = run_workgroups(emu, n.div_ceil(run0), |block, c, _| {
        let base = block * run0;
        let mut x = Lane4::pads();
        for j in 0..PER_LANE {
            let e = PER_LANE * c.lane() + j;
            if e < run0 && base + e < n {
                x.k[j as usize] = keys[(base + e) as usize];
                x.v[j as usize] = values[(base + e) as usize];
                x.pad &= !(1 << j);
            }
        }
        (base, block_sort(c, x))
    });
    let (mut k, mut v) = (keys.to_vec(), values.to_vec());
    for (i, (base, x)) in lanes.iter().enumerate() {
        let lane = i as u32 % width;
        for j in 0..PER_LANE {
            let e = PER_LANE * lane + j;
            if e < run0 && base + e < n {
                assert_eq!(x.pad >> j & 1, 0, "a pad sorted before a real element");
                k[(base + e) as usize] = x.k[j as usize];
                v[(base + e) as usize] = x.v[j as usize];
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
    assert!(plan_width <= width);
    let (run0, levels) = plan(keys.len() as u32, plan_width);
    if keys.len() <= 1 {
        return (keys.to_vec(), values.to_vec(), 0);
    }
    let (mut k, mut v) = block_sort_emulated(width, run0, keys, values);
    let mut max_steps = 0;
    for lv in &levels {
        let boundaries = if lv.split() { splitters_emulated(&k, lv) } else { vec![0; 2] };
        let (k2, v2, s) = merge_emulated(width, lv, &boundaries, &k, &v);
        (k, v, max_steps) = (k2, v2, max_steps.max(s));
    }
    (k, v, max_steps)
}
