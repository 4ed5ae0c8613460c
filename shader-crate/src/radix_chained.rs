//! The chained-scan variant of the radix sort's passes (Merrill & Garland 2016, "Single-pass
//! parallel prefix scan with decoupled look-back"; Adinets & Merrill 2022, "Onesweep"): one
//! dispatch per pass replaces upsweep, spine and downsweep, so each pass reads the keys once.
//!
//! Per workgroup ([`chained_tile`]):
//! 1. invocation 0 claims the next tile from the pass's counter (an atomic add), so a tile's
//!    predecessors were claimed by workgroups that already run;
//! 2. the tile is ranked ([`rank_tile`]); invocation `d` publishes the tile's count of digit
//!    `d` as an *aggregate* (tile 0 publishes it as an inclusive *prefix* at once);
//! 3. look-back: invocation `d` walks the earlier tiles' words of digit `d`, adding aggregates
//!    until it meets a prefix, waiting on tiles that have published nothing yet; then it
//!    publishes its own inclusive prefix;
//! 4. the tile is scattered ([`scatter_tile`]) at the digit's global start (the global
//!    histogram's exclusive sum over lower digits) plus the prefix.
//!
//! A status word packs a flag (2 bits: not ready / aggregate / prefix), the pass (2 bits, so a
//! word left by the previous pass reads as not ready and one zero fill serves every pass) and
//! a count (28 bits: at most [`CHAINED_MAX_PAIRS`] pairs). The words are plain relaxed device
//! atomics: each carries all the data it publishes.
//!
//! **Forward progress.** Step 3 waits for other workgroups. A workgroup waits only on tiles
//! claimed before its own, by workgroups already running, so it finishes wherever running
//! workgroups keep being scheduled: true on discrete NVIDIA and AMD GPUs, not promised by Vulkan.
//! lavapipe would not deadlock either (its threads run each workgroup to the end), but its loop
//! limiter ends a spinning loop after 65 535 iterations and silently goes on with a wrong count,
//! so the host never picks this variant there (`host/src/render/sort.rs`). The CPU emulation
//! ([`emulated`]) runs the workgroups on a few "resident" threads in orders it chooses and fails
//! on a deadlock instead of hanging.
//!
//! Memory: `4 · 256 · ⌈n / 2048⌉` B of status words and [`MAX_PASSES`] counters.
use super::*;

/// Flag of a status word: nothing published yet.
pub const NOT_READY: u32 = 0;
/// Flag: the tile's own count.
pub const AGGREGATE: u32 = 1 << 30;
/// Flag: the count of this and every earlier tile.
pub const PREFIX: u32 = 2 << 30;
const FLAG_MASK: u32 = 3 << 30;
const PASS_SHIFT: u32 = 28;
const PASS_MASK: u32 = 3 << PASS_SHIFT;
const COUNT_MASK: u32 = (1 << PASS_SHIFT) - 1;
/// Most pairs the chained variant sorts (the counts' 28 bits).
pub const CHAINED_MAX_PAIRS: u32 = COUNT_MASK;

const _: () = assert!(MAX_PASSES <= 4, "two bits of pass in a status word");

/// Words of the status buffer for `tiles` tiles: one per (tile, digit), then one tile counter
/// per pass (everything zeroed before the sort).
#[inline]
pub fn status_words(tiles: u32) -> u32 {
    tiles * RADIX + MAX_PASSES
}

/// A status word of pass `pass` published by the workgroup: `flag | pass | count`.
#[inline]
fn status(flag: u32, pass: u32, count: u32) -> u32 {
    flag | (pass << PASS_SHIFT) | count
}

/// Whether `word` holds something pass `pass` published (older passes' words read as not ready).
#[inline]
pub fn is_ready(word: u32, pass: u32) -> bool {
    word & FLAG_MASK != NOT_READY && (word & PASS_MASK) >> PASS_SHIFT == pass
}

/// The status words and counters of the chained scan: device atomics on the GPU.
pub trait Chain {
    /// Atomic add returning the old value (claims a tile).
    fn claim(&mut self, i: u32) -> u32;
    /// Atomic store.
    fn publish(&mut self, i: u32, v: u32);
    /// Atomic load (the look-back; the CPU emulation blocks here until pass `pass` published).
    fn look(&mut self, i: u32, pass: u32) -> u32;
}

/// A storage buffer: `OpAtomicIAdd` / `OpAtomicStore` / `OpAtomicLoad`, device scope, relaxed.
/// Off the GPU plain accesses (sequential use only; the emulation has its own [`Chain`]).
impl Chain for [u32] {
    #[inline]
    fn claim(&mut self, i: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_i_add::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(&mut self[i as usize], 1)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            self[i as usize] += 1;
            self[i as usize] - 1
        }
    }
    #[inline]
    fn publish(&mut self, i: u32, v: u32) {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_store::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(&mut self[i as usize], v)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            self[i as usize] = v;
        }
    }
    #[inline]
    fn look(&mut self, i: u32, _pass: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_load::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(&self[i as usize])
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            self[i as usize]
        }
    }
}

/// Steps 2–3 for invocation `d` of tile `tile`: publishes the tile's `count` of digit `d`, looks
/// back, publishes the inclusive prefix; returns the count of digit `d` in earlier tiles.
#[inline]
pub fn look_back<Ch: Chain + ?Sized>(chain: &mut Ch, pass: u32, tile: u32, d: u32, count: u32) -> u32 {
    let mut before = 0;
    let mut t = tile;
    while t > 0 {
        let word = chain.look((t - 1) * RADIX + d, pass);
        if is_ready(word, pass) {
            before += word & COUNT_MASK;
            t = if word & FLAG_MASK == PREFIX { 0 } else { t - 1 };
        }
    }
    if tile > 0 {
        chain.publish(tile * RADIX + d, status(PREFIX, pass, before + count));
    }
    before
}

/// One workgroup of a chained pass over `n` pairs (`key_of(i)`, `value_of(i)`, global
/// indices): claims a tile, ranks it, looks back and calls `write(destination, key, value)` as
/// [`scatter_tile`] does. `hist_of(d)` is the global histogram's count of digit `d` this pass.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn chained_tile<C: Coop, S: SharedU32 + ?Sized, Ch: Chain + ?Sized>(
    c: &C,
    sh: &mut S,
    chain: &mut Ch,
    n: u32,
    tiles: u32,
    (pass, key_bits): (u32, u32),
    hist_of: impl Fn(u32) -> u32,
    key_of: impl Fn(u32) -> u32,
    value_of: impl Fn(u32) -> u32,
    write: impl FnMut(u32, u32, u32),
) {
    let me = c.local_index();
    // 1. The tile, and the digit's global start.
    if me == 0 {
        sh.store(SH_GLOBAL, chain.claim(tiles * RADIX + pass));
    }
    let (digit_start, _) = workgroup_exclusive_scan_at(c, sh, SH_SCAN, hist_of(me));
    let tile = sh.load(SH_GLOBAL);
    if tile >= tiles {
        return; // a workgroup of a 2D-folded dispatch past the last tile (the whole workgroup)
    }
    let base = tile * RADIX_TILE;
    let len = (n - base).min(RADIX_TILE);
    let (shift, bits) = pass_digit(pass, key_bits);
    // 2.
    let slots = Slots::of(c);
    let keys = load_items(slots, len, u32::MAX, |i| key_of(base + i));
    let (place, count) = rank_tile(c, sh, slots, &keys, shift, bits);
    chain.publish(tile * RADIX + me, status(if tile == 0 { PREFIX } else { AGGREGATE }, pass, count));
    // Every digit's aggregate is out before any invocation waits.
    c.workgroup_barrier();
    // 3.
    let before = look_back(chain, pass, tile, me, count);
    // 4.
    scatter_tile(c, sh, slots, &place, &keys, len, digit_start + before, (shift, bits), |i| value_of(base + i), write);
}

#[cfg(not(target_arch = "spirv"))]
#[path = "radix_chained_emulated.rs"]
pub mod emulated;
