//! LSD radix sort of 32-bit keys with 32-bit values: 8-bit digits, reduce-then-scan, tiles of
//! [`RADIX_TILE`] keys held in registers and ranked with subgroup ballots. The design follows
//! the fast GPU radix sorts (Merrill & Grimshaw 2011 for reduce-then-scan; Adinets & Merrill
//! 2022, "Onesweep", for the up-front histogram of every digit and ballot ranking; b0nes164's
//! GPUSorting "DeviceRadixSort" for a portable Vulkan/D3D form at any subgroup width).
//!
//! Passes: only the bits the keys use are sorted, 8 per pass, the last pass narrower
//! ([`passes`], [`pass_digit`]): 30-bit Morton keys take 4 passes of 8, 8, 8 and 6 bits — the
//! fewest passes with digits of at most 8 bits (a 9th bit would double the 256-bin tables and
//! the ballots per key).
//!
//! Steps (`host/src/render/sort.rs` records them):
//! 1. **histogram** ([`global_histogram`]) — one read of the keys counts the digits of every
//!    pass: each workgroup counts [`HISTOGRAM_TILES`] tiles into a `passes × 256` table in
//!    workgroup memory (atomics), then adds its non-zero bins into the global table (one atomic
//!    per bin and workgroup).
//! 2. per pass:
//!    1. **upsweep** ([`upsweep_tile`]) — each tile counts its digits (workgroup-memory atomics)
//!       into `tile_count[digit · tiles + tile]`;
//!    2. **spine** ([`spine`]) — the digit-major tile counts scanned in order give every
//!       (digit, tile) its first output slot; the global histogram splits that scan between
//!       1–256 workgroups (a workgroup's digits start at the sum of the lower digits' bins, a
//!       workgroup reduction of at most 256 bins that stands in for a separate scan dispatch of
//!       the histogram), so a small input takes one workgroup, and no scan is multi-level;
//!    3. **downsweep** ([`downsweep_tile`]) — each tile ranks its keys by digit ([`rank_tile`]),
//!       reorders keys and then values through workgroup memory, and writes each run of equal
//!       digits contiguously (coalesced) at its (digit, tile) start.
//! 3. **Small inputs** (`n ≤ RADIX_TILE`) take one workgroup ([`sort_tile`]): every pass ranks
//!    and reorders the tile in workgroup memory; no histogram, no scan, one dispatch.
//!
//! **Ranking** ([`rank_tile`], the multi-split): subgroup `s` owns a chunk of `8·W` consecutive
//! keys (lane `l`, item `j`: key `j·W + l` of the chunk, so loads are coalesced). For each item,
//! one ballot per digit bit, ANDed (or ANDed with the complement), gives the lanes holding the same
//! digit; a lane's rank is the number of those lanes below it plus the subgroup's running count
//! of that digit, which the lowest such lane reads from workgroup memory, broadcasts with a
//! shuffle and advances. Running counts live in [`RANK_ROWS`] rows of 256 bins: where a
//! workgroup has more subgroups than rows (widths below 32), subgroups take turns in rounds and
//! subgroups sharing a row own consecutive chunks, so a row's counts always cover consecutive
//! keys. The rows' exclusive sums per digit and a workgroup scan over digits give every key its
//! place in the tile: stable, so the passes compose into a sort. Works at every subgroup width
//! 4…128 (ballots are 128 bits).
//!
//! **Two cross-tile variants.** Steps 2.1–2.3 (reduce-then-scan) read the keys twice per pass
//! and no workgroup ever waits on another, so they run on every device. The chained variant
//! ([`chained`], Onesweep's) does a pass in one dispatch that reads the keys once, but a
//! workgroup waits for earlier tiles' counts, which needs forward progress between workgroups:
//! Vulkan does not promise it, so the host picks it only where the device gives it in practice
//! (`host/src/render/sort.rs`).
//!
//! Memory: keys + values double-buffered (8 B per pair of scratch), two tables of
//! `4 · 256 · ⌈n / 2048⌉` B (tile counts and starts: 0.5 B per pair each) and `4 · 4 · 256` B of
//! global histogram: ≈ 9 B per pair.
//!
//! Workgroup memory of the tile kernels ([`RADIX_SHARED_WORDS`], 2624 words = 10.25 KiB;
//! lavapipe allows 32 KiB, NVIDIA 48 KiB): the rank rows ([`RANK_ROWS`] · 256 words = 8 KiB),
//! which become the reorder buffer ([`RADIX_TILE`] words) once the tile is ranked, the tile's
//! digit starts and the global starts (256 words each) and the scan's subgroup totals (64
//! words, enough for width 4). The global histogram uses 1024 words of the same array type and
//! the upsweep 256: Debian's validation layer (1.3.239) adds up every workgroup variable of the
//! module against the 32 KiB, and rust-gpu merges variables of one type, so sharing the type
//! keeps the compute module's sum (25 KiB) under it.
use crate::coop::{ballot_count, ballot_first, ballot_rank, subgroup_lanes, Coop, SharedU32};
use crate::scan::{workgroup_exclusive_scan_at, SCAN_SHARED_WORDS};

/// Bits of the widest digit.
pub const RADIX_BITS: u32 = 8;
/// Bins per pass.
pub const RADIX: u32 = 1 << RADIX_BITS;
/// Invocations per workgroup of every sort kernel (invocation `d` owns bin `d`).
pub const SORT_WORKGROUP: u32 = 256;
/// Keys each invocation holds in registers (the loops over them are unrolled by `unroll8!`).
pub const KEYS_PER_INVOCATION: u32 = 8;
/// Keys per tile.
pub const RADIX_TILE: u32 = SORT_WORKGROUP * KEYS_PER_INVOCATION;
/// Rows of running digit counts in the ranking (one per subgroup at widths ≥ 32).
pub const RANK_ROWS: u32 = 8;
/// Passes of 32-bit keys (rows of the global histogram).
pub const MAX_PASSES: u32 = 32 / RADIX_BITS;
/// Tiles each workgroup of the global histogram reads.
pub const HISTOGRAM_TILES: u32 = 8;
/// Keys each workgroup of the global histogram reads.
pub const HISTOGRAM_KEYS: u32 = HISTOGRAM_TILES * RADIX_TILE;

/// Tile counts one spine workgroup scans per round (8 per invocation).
pub const SPINE_CHUNK: u32 = SORT_WORKGROUP * KEYS_PER_INVOCATION;
/// Most tile counts per spine workgroup where more than one digit shares it ([`spine_digits`]).
pub const SPINE_COUNTS: u32 = 4 * SPINE_CHUNK;

/// Workgroup memory of the tile kernels: the rank rows (`RANK_ROWS × RADIX`) while a tile is
/// ranked, then the reorder buffer ([`RADIX_TILE`] words) — [`rank_tile`] ends with a barrier.
pub const SH_ROWS: u32 = 0;
/// … the reorder buffer (the same words as the rank rows).
pub const SH_TILE: u32 = 0;
/// … each digit's first slot in the tile.
pub const SH_DIGIT_BASE: u32 = if RADIX_TILE > RANK_ROWS * RADIX { RADIX_TILE } else { RANK_ROWS * RADIX };
/// … each digit's global start minus its tile start (downsweep).
pub const SH_GLOBAL: u32 = SH_DIGIT_BASE + RADIX;
/// … the scan's subgroup totals.
pub const SH_SCAN: u32 = SH_GLOBAL + RADIX;
/// Words of workgroup memory of the tile kernels and the global histogram (one array type, so
/// the module holds one such variable).
pub const RADIX_SHARED_WORDS: usize = SH_SCAN as usize + SCAN_SHARED_WORDS;
/// Words of workgroup memory of the upsweep (one bin per digit).
pub const UPSWEEP_SHARED_WORDS: usize = RADIX as usize;
/// Words the global histogram uses (`MAX_PASSES × RADIX`, within [`RADIX_SHARED_WORDS`]).
pub const HISTOGRAM_SHARED_WORDS: usize = (MAX_PASSES * RADIX) as usize;

const _: () = assert!(HISTOGRAM_SHARED_WORDS <= RADIX_SHARED_WORDS);
const _: () = assert!(KEYS_PER_INVOCATION == 8, "the per-key loops are unroll8!");
const _: () = assert!(SORT_WORKGROUP == RADIX, "invocation d owns bin d");
const _: () = assert!(MAX_PASSES == 4, "global_histogram returns four rows");
const _: () = assert!(RADIX_SHARED_WORDS * 4 <= 32 * 1024, "lavapipe's 32 KiB of workgroup memory");
const _: () = assert!(SCAN_SHARED_WORDS as u32 >= SORT_WORKGROUP / 4, "scan totals at width 4");

/// The invocation's keys (or values), item `j` at [`Slots::item`]`(j)` of the tile.
pub type Items = [u32; KEYS_PER_INVOCATION as usize];

/// Passes for keys below `2^key_bits` (0 for `key_bits = 0`: every key is 0).
#[inline]
pub fn passes(key_bits: u32) -> u32 {
    key_bits.min(32).div_ceil(RADIX_BITS)
}

/// `(shift, bits)` of pass `pass`'s digit for keys below `2^key_bits`.
#[inline]
pub fn pass_digit(pass: u32, key_bits: u32) -> (u32, u32) {
    let shift = pass * RADIX_BITS;
    (shift, (key_bits.min(32) - shift).min(RADIX_BITS))
}

/// The `bits`-bit digit of `key` starting at bit `shift`.
#[inline]
pub fn digit(key: u32, shift: u32, bits: u32) -> u32 {
    (key >> shift) & ((1u32 << bits) - 1)
}

/// Where an invocation's items lie in its tile and which rank row and round it uses.
#[derive(Clone, Copy, Debug)]
pub struct Slots {
    /// Rank rows in use: `min(subgroups, RANK_ROWS)`.
    pub rows: u32,
    /// Rounds of ranking: `subgroups / rows`.
    pub rounds: u32,
    pub row: u32,
    pub round: u32,
    /// Tile index of item 0.
    pub first: u32,
    /// Distance between items (the subgroup width).
    pub stride: u32,
}

impl Slots {
    /// Subgroup `s` uses row `s % rows` in round `s / rows` and owns chunk
    /// `row · rounds + round` (chunks of a row are consecutive).
    #[inline]
    pub fn of<C: Coop>(c: &C) -> Self {
        let width = c.subgroup_size();
        let subgroups = c.num_subgroups();
        let rows = if subgroups < RANK_ROWS { subgroups } else { RANK_ROWS };
        let s = c.subgroup_id();
        let (row, round, rounds) = (s % rows, s / rows, subgroups / rows);
        let chunk = row * rounds + round;
        Slots { rows, rounds, row, round, first: chunk * width * KEYS_PER_INVOCATION + c.lane(), stride: width }
    }

    /// Tile index of item `j`.
    #[inline]
    pub fn item(&self, j: u32) -> u32 {
        self.first + j * self.stride
    }
}

/// Of the lanes whose digit `d` equals this lane's (its peers, found by one ballot per digit
/// bit): the lowest (the leader), how many lie below this lane, and how many there are.
/// Subgroups of up to 32 lanes work on the ballots' first word alone (a quarter of the mask
/// arithmetic per bit); wider ones on all four. Subgroup-uniform.
#[inline]
fn peer_rank<C: Coop>(c: &C, d: u32, bits: u32) -> (u32, u32, u32) {
    let width = c.subgroup_size();
    if width <= 32 {
        let mut same = if width == 32 { u32::MAX } else { (1u32 << width) - 1 };
        let mut b = 0;
        while b < bits {
            let set = (d >> b) & 1 == 1;
            let m = c.ballot(set)[0];
            same &= if set { m } else { !m };
            b += 1;
        }
        let below = (1u32 << c.lane()) - 1;
        (same.trailing_zeros(), (same & below).count_ones(), same.count_ones())
    } else {
        let same = peers(c, d, bits);
        (ballot_first(same), ballot_rank(same, c.lane()), ballot_count(same))
    }
}

/// The lanes of the subgroup whose `d` equals this lane's, from one ballot per digit bit.
#[inline]
fn peers<C: Coop>(c: &C, d: u32, bits: u32) -> [u32; 4] {
    let mut same = subgroup_lanes(c.subgroup_size());
    let mut b = 0;
    while b < bits {
        let set = (d >> b) & 1 == 1;
        let m = c.ballot(set);
        let flip = if set { 0 } else { u32::MAX };
        same = [same[0] & (m[0] ^ flip), same[1] & (m[1] ^ flip), same[2] & (m[2] ^ flip), same[3] & (m[3] ^ flip)];
        b += 1;
    }
    same
}

/// The place of each of the invocation's keys in the tile sorted stably by digit (see the module
/// doc), and the tile's count of digit `local_index`. Leaves each digit's first slot at
/// `SH_DIGIT_BASE + digit`. Keys past the input's end are `u32::MAX` (the largest digit, after
/// every real key of it; counted too). Called by every invocation.
#[inline]
pub fn rank_tile<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, slots: Slots, keys: &Items, shift: u32, bits: u32) -> (Items, u32) {
    let me = c.local_index();
    let mut r = 0;
    while r < RANK_ROWS {
        sh.store(SH_ROWS + r * RADIX + me, 0);
        r += 1;
    }
    c.workgroup_barrier();
    let row = SH_ROWS + slots.row * RADIX;
    let lane = c.lane();
    let mut rank: Items = [0; KEYS_PER_INVOCATION as usize];
    let mut round = 0;
    while round < slots.rounds {
        if round == slots.round {
            unroll8!(j => {
                let d = digit(keys[j as usize], shift, bits);
                let (leader, below, count) = peer_rank(c, d, bits);
                let mine = if lane == leader { sh.load(row + d) } else { 0 };
                let before = c.shuffle(mine, leader);
                rank[j as usize] = before + below;
                if lane == leader {
                    sh.store(row + d, before + count);
                }
                c.subgroup_barrier();
            });
        }
        c.workgroup_barrier();
        round += 1;
    }
    // Digit `me`: each row's count becomes the sum of the rows before it.
    let mut total = 0;
    r = 0;
    while r < slots.rows {
        let i = SH_ROWS + r * RADIX + me;
        let v = sh.load(i);
        sh.store(i, total);
        total += v;
        r += 1;
    }
    let (base, _) = workgroup_exclusive_scan_at(c, sh, SH_SCAN, total);
    sh.store(SH_DIGIT_BASE + me, base);
    c.workgroup_barrier();
    let mut place: Items = [0; KEYS_PER_INVOCATION as usize];
    unroll8!(j => {
        let d = digit(keys[j as usize], shift, bits);
        place[j as usize] = sh.load(SH_DIGIT_BASE + d) + sh.load(row + d) + rank[j as usize];
    });
    // The rows' words become the reorder buffer.
    c.workgroup_barrier();
    (place, total)
}

/// Moves item `j` to tile slot `place[j]` and returns the items of the invocation's slots in
/// the reordered tile.
#[inline]
fn permute<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, slots: Slots, place: &Items, x: &Items) -> Items {
    unroll8!(j => { sh.store(SH_TILE + place[j as usize], x[j as usize]); });
    c.workgroup_barrier();
    let mut y: Items = [0; KEYS_PER_INVOCATION as usize];
    unroll8!(j => { y[j as usize] = sh.load(SH_TILE + slots.item(j)); });
    c.workgroup_barrier();
    y
}

/// The invocation's items of a tile of `len` pairs: `load(i)` at its slots below `len`, `pad`
/// past the end.
#[inline]
pub fn load_items(slots: Slots, len: u32, pad: u32, load: impl Fn(u32) -> u32) -> Items {
    let mut x: Items = [pad; KEYS_PER_INVOCATION as usize];
    unroll8!(j => {
        let i = slots.item(j);
        if i < len {
            x[j as usize] = load(i);
        }
    });
    x
}

/// Calls `store(i, x[j])` for the invocation's slots `i < len` ([`load_items`] reversed).
#[inline]
pub fn store_items(slots: Slots, len: u32, x: &Items, mut store: impl FnMut(u32, u32)) {
    unroll8!(j => {
        let i = slots.item(j);
        if i < len {
            store(i, x[j as usize]);
        }
    });
}

/// Step 3: sorts one tile of at most [`RADIX_TILE`] pairs entirely in workgroup memory, every
/// pass of keys below `2^key_bits`. `keys` and `values` are the invocation's items at `slots`
/// ([`load_items`]: key `u32::MAX` past the input's end, which stays behind every real key);
/// returns its items of the sorted tile.
#[inline]
pub fn sort_tile<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, slots: Slots, mut keys: Items, mut values: Items, key_bits: u32) -> (Items, Items) {
    let mut pass = 0;
    while pass < passes(key_bits) {
        let (shift, bits) = pass_digit(pass, key_bits);
        let (place, _) = rank_tile(c, sh, slots, &keys, shift, bits);
        keys = permute(c, sh, slots, &place, &keys);
        values = permute(c, sh, slots, &place, &values);
        pass += 1;
    }
    (keys, values)
}

/// Inputs of at most this many pairs take the single-workgroup path ([`sort_tile`]).
#[inline]
pub fn fits_one_tile(n: u32) -> bool {
    n <= RADIX_TILE
}

/// Step 1 for one workgroup: counts every pass's digits of keys `0..len` of its range
/// (`key_of(i)`); returns the count of digit `local_index` for each pass (0 past `passes`).
#[inline]
pub fn global_histogram<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, len: u32, key_bits: u32, key_of: impl Fn(u32) -> u32) -> [u32; MAX_PASSES as usize] {
    let me = c.local_index();
    let passes = passes(key_bits);
    let mut p = 0;
    while p < MAX_PASSES {
        sh.store(p * RADIX + me, 0);
        p += 1;
    }
    c.workgroup_barrier();
    let mut base = 0;
    while base < len {
        unroll8!(u => {
            let i = base + u * SORT_WORKGROUP + me;
            if i < len {
                let key = key_of(i);
                let mut p = 0;
                while p < passes {
                    let (shift, bits) = pass_digit(p, key_bits);
                    sh.atomic_add(p * RADIX + digit(key, shift, bits), 1);
                    p += 1;
                }
            }
        });
        base += RADIX_TILE;
    }
    c.workgroup_barrier();
    [sh.load(me), sh.load(RADIX + me), sh.load(2 * RADIX + me), sh.load(3 * RADIX + me)]
}

/// Step 2.1 for one tile: the count of digit `local_index` among keys `0..len` of the tile
/// (`key_of(i)`).
#[inline]
pub fn upsweep_tile<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, len: u32, shift: u32, bits: u32, key_of: impl Fn(u32) -> u32) -> u32 {
    let me = c.local_index();
    sh.store(me, 0);
    c.workgroup_barrier();
    unroll8!(u => {
        let i = u * SORT_WORKGROUP + me;
        if i < len {
            sh.atomic_add(digit(key_of(i), shift, bits), 1);
        }
    });
    c.workgroup_barrier();
    sh.load(me)
}

/// Digits each spine workgroup scans for `tiles` tiles: the most (a power of two, at most 256)
/// whose counts stay within [`SPINE_COUNTS`], so that small inputs take one workgroup and large
/// ones spread over up to 256.
#[inline]
pub fn spine_digits(tiles: u32) -> u32 {
    let mut d = RADIX;
    while d > 1 && d * tiles > SPINE_COUNTS {
        d /= 2;
    }
    d
}

/// Step 2.2 for digits `first..first + digits` (one workgroup): the tile counts of those digits,
/// digit-major (`count_of(d · tiles + t)`), scanned in order from the digits' global start (the
/// global histogram's `Σ hist_of(e)` over `e < first`): `write(d · tiles + t, start)` gives
/// every (digit, tile) its first output slot. Each invocation scans 8 consecutive counts per
/// round of [`SPINE_CHUNK`].
#[inline]
#[allow(clippy::too_many_arguments, unused_assignments)] // the last unrolled `run +=` is unread
pub fn spine<C: Coop, S: SharedU32 + ?Sized>(
    c: &C,
    sh: &mut S,
    first: u32,
    digits: u32,
    tiles: u32,
    hist_of: impl Fn(u32) -> u32,
    count_of: impl Fn(u32) -> u32,
    mut write: impl FnMut(u32, u32),
) {
    let me = c.local_index();
    let (_, mut carry) = workgroup_exclusive_scan_at(c, sh, 0, if me < first { hist_of(me) } else { 0 });
    c.workgroup_barrier();
    let end = (first + digits) * tiles;
    let mut base = first * tiles;
    while base < end {
        let at = base + me * KEYS_PER_INVOCATION;
        let mut v: Items = [0; KEYS_PER_INVOCATION as usize];
        let mut sum = 0;
        unroll8!(u => {
            if at + u < end {
                v[u as usize] = count_of(at + u);
            }
            sum += v[u as usize];
        });
        let (before, total) = workgroup_exclusive_scan_at(c, sh, 0, sum);
        let mut run = carry + before;
        unroll8!(u => {
            if at + u < end {
                write(at + u, run);
            }
            run += v[u as usize];
        });
        carry += total;
        base += SPINE_CHUNK;
        c.workgroup_barrier();
    }
}

/// Step 2.3 for one tile of `len` pairs (`key_of(i)`, `value_of(i)`, `i` in the tile): ranks
/// the keys and [`scatter_tile`]s them. `start` is digit `local_index`'s first global slot for
/// this tile.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn downsweep_tile<C: Coop, S: SharedU32 + ?Sized>(
    c: &C,
    sh: &mut S,
    len: u32,
    start: u32,
    (shift, bits): (u32, u32),
    key_of: impl Fn(u32) -> u32,
    value_of: impl Fn(u32) -> u32,
    write: impl FnMut(u32, u32, u32),
) {
    let slots = Slots::of(c);
    let keys = load_items(slots, len, u32::MAX, key_of);
    let (place, _) = rank_tile(c, sh, slots, &keys, shift, bits);
    scatter_tile(c, sh, slots, &place, &keys, len, start, (shift, bits), value_of, write);
}

/// The end of a downsweep once the tile is ranked ([`rank_tile`] ran last on `sh`): reorders
/// keys then values (`value_of(tile index)`) through workgroup memory and calls
/// `write(destination, key, value)` for each of the invocation's slots `i · 256 + local_index`
/// below `len` of the reordered tile, so that consecutive invocations write consecutive places.
/// `start` is digit `local_index`'s first global slot for this tile.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn scatter_tile<C: Coop, S: SharedU32 + ?Sized>(
    c: &C,
    sh: &mut S,
    slots: Slots,
    place: &Items,
    keys: &Items,
    len: u32,
    start: u32,
    (shift, bits): (u32, u32),
    value_of: impl Fn(u32) -> u32,
    mut write: impl FnMut(u32, u32, u32),
) {
    let me = c.local_index();
    sh.store(SH_GLOBAL + me, start.wrapping_sub(sh.load(SH_DIGIT_BASE + me)));
    unroll8!(j => { sh.store(SH_TILE + place[j as usize], keys[j as usize]); });
    c.workgroup_barrier();
    let mut out: Items = [0; KEYS_PER_INVOCATION as usize];
    let mut dst: Items = [0; KEYS_PER_INVOCATION as usize];
    unroll8!(u => {
        let i = u * SORT_WORKGROUP + me;
        let key = sh.load(SH_TILE + i);
        out[u as usize] = key;
        dst[u as usize] = sh.load(SH_GLOBAL + digit(key, shift, bits)).wrapping_add(i);
    });
    c.workgroup_barrier();
    let values = load_items(slots, len, 0, value_of);
    unroll8!(j => { sh.store(SH_TILE + place[j as usize], values[j as usize]); });
    c.workgroup_barrier();
    unroll8!(u => {
        let i = u * SORT_WORKGROUP + me;
        if i < len {
            write(dst[u as usize], out[u as usize], sh.load(SH_TILE + i));
        }
    });
}

#[path = "radix_chained.rs"]
pub mod chained;

#[cfg(not(target_arch = "spirv"))]
#[path = "radix_emulated.rs"]
pub mod emulated;

#[cfg(test)]
#[path = "radix_tests.rs"]
mod tests;
