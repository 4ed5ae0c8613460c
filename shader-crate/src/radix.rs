//! LSD radix sort of 32-bit keys with 32-bit values (reduce-then-scan), the "future work" of
//! Karas' light sorting. One pass per 8-bit digit (4 for 32-bit keys, fewer for narrower keys):
//! 1. **histogram** — each workgroup loads a tile of [`RADIX_TILE`] keys into workgroup memory;
//!    invocation `d` counts the tile's keys whose digit is `d` → `hist[d · groups + g]`
//!    (digit-major, so one exclusive scan gives every (digit, tile) its global start);
//! 2. **scan** — device-wide exclusive scan of the `256 · groups` counts;
//! 3. **scatter** — each key's destination is its (digit, tile) start plus its rank among the
//!    tile's earlier keys with the same digit: stable, so the passes compose into a sort.
//!
//! Both tile steps count in workgroup memory instead of using atomics: 256 comparisons per
//! invocation, deterministic, and far under llvmpipe's 65 535-iteration loop limit.
//! Memory: keys + values double-buffered (16 B per element) and `4 · 256 · ⌈n/256⌉` B of counts.
//!
//! **Why reduce-then-scan, not Onesweep.** Onesweep (Adinets & Merrill 2022) scans with a chained
//! scan and decoupled look-back: a workgroup spins until an earlier workgroup publishes its
//! prefix. That needs forward progress between workgroups, which Vulkan does not promise: lavapipe
//! runs workgroups as tasks on a few threads, so a spinning workgroup can hold the thread the one
//! it waits on needs (a hang). Reduce-then-scan has no inter-workgroup waits, so one kernel source runs
//! on every device; it reads the keys twice per pass instead of once, the price measured in
//! `benches/sort.rs` (CUB's Onesweep-style sort is 9–15× faster on the H100).
//!
//! The CPU version ([`sort_emulated`]) runs the same tile functions and the host's device-wide
//! scan in the lock-step emulation at any subgroup width (the acceptance matrix in
//! `sort_acceptance_tests.rs`).
use crate::coop::{Coop, SharedU32};

/// Bits per pass.
pub const RADIX_BITS: u32 = 8;
/// Buckets per pass.
pub const RADIX: u32 = 1 << RADIX_BITS;
/// Keys per workgroup tile (= invocations per workgroup = buckets).
pub const RADIX_TILE: u32 = 256;
/// Workgroup-memory words the tile steps need.
pub const RADIX_SHARED_WORDS: usize = RADIX_TILE as usize;
/// Digit stored for the tile slots past the end of the input (matches no bucket).
pub const NO_DIGIT: u32 = RADIX;

/// The digit of `key` in the pass that starts at bit `shift`.
#[inline]
pub fn digit(key: u32, shift: u32) -> u32 {
    (key >> shift) & (RADIX - 1)
}

/// Step 1 for one invocation: publishes its key's digit (or [`NO_DIGIT`]) and returns how many of
/// the tile's keys have digit `local_index`. Called by every invocation of the workgroup.
#[inline]
pub fn tile_histogram<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, my_digit: u32) -> u32 {
    let me = c.local_index();
    shared.store(me, my_digit);
    c.workgroup_barrier();
    let mut n = 0;
    let mut t = 0;
    while t < RADIX_TILE {
        if shared.load(t) == me {
            n += 1;
        }
        t += 1;
    }
    c.workgroup_barrier();
    n
}

/// Step 3 for one invocation: its rank among the tile's earlier keys with the same digit.
/// Called by every invocation of the workgroup.
#[inline]
pub fn tile_rank<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, my_digit: u32) -> u32 {
    let me = c.local_index();
    shared.store(me, my_digit);
    c.workgroup_barrier();
    let mut rank = 0;
    let mut t = 0;
    while t < me {
        if shared.load(t) == my_digit {
            rank += 1;
        }
        t += 1;
    }
    c.workgroup_barrier();
    rank
}

/// Passes needed for keys below `2^key_bits`.
#[inline]
pub fn passes(key_bits: u32) -> u32 {
    key_bits.div_ceil(RADIX_BITS).max(1)
}

/// One whole pass on the CPU, through the same kernels in the lock-step emulation at subgroup
/// width `width`: the tile histogram, the device-wide scan of the host
/// ([`crate::scan::exclusive_scan_emulated`]) and the tile ranks of the scatter.
#[cfg(not(target_arch = "spirv"))]
pub fn pass_emulated(width: u32, keys: &[u32], values: &[u32], shift: u32) -> (Vec<u32>, Vec<u32>) {
    use crate::coop::cpu::{run_workgroups, Emulation};
    let n = keys.len();
    let groups = n.div_ceil(RADIX_TILE as usize).max(1);
    let emu = Emulation { width, workgroup_size: RADIX_TILE, shared_words: RADIX_SHARED_WORDS };
    let digit_of = |g: u32, l: u32| {
        let i = (g * RADIX_TILE + l) as usize;
        if i < n { digit(keys[i], shift) } else { NO_DIGIT }
    };
    // 1. Invocation d of tile g counts digit d: stored digit-major, `hist[d · groups + g]`.
    let counts = run_workgroups(emu, groups as u32, |g, c, s| tile_histogram(c, s, digit_of(g, c.local_index())));
    let mut hist = vec![0u32; RADIX as usize * groups];
    for (i, &count) in counts.iter().enumerate() {
        let (g, d) = (i / RADIX_TILE as usize, i % RADIX_TILE as usize);
        hist[d * groups + g] = count;
    }
    // 2. Every (digit, tile)'s first output slot.
    let (start, total) = crate::scan::exclusive_scan_emulated(width, &hist);
    assert_eq!(total as usize, n, "the histogram counts every key once");
    // 3. Scatter: the (digit, tile) start plus the key's rank among the tile's same-digit keys.
    let ranks = run_workgroups(emu, groups as u32, |g, c, s| tile_rank(c, s, digit_of(g, c.local_index())));
    let (mut k2, mut v2) = (vec![0; n], vec![0; n]);
    for i in 0..n {
        let (g, d) = (i / RADIX_TILE as usize, digit(keys[i], shift) as usize);
        let dst = (start[d * groups + g] + ranks[i]) as usize;
        k2[dst] = keys[i];
        v2[dst] = values[i];
    }
    (k2, v2)
}

/// The whole sort on the CPU at subgroup width `width`: one emulated pass per digit of 32-bit keys.
#[cfg(not(target_arch = "spirv"))]
pub fn sort_emulated(width: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let (mut k, mut v) = (keys.to_vec(), values.to_vec());
    for p in 0..passes(32) {
        (k, v) = pass_emulated(width, &k, &v, p * RADIX_BITS);
    }
    (k, v)
}
