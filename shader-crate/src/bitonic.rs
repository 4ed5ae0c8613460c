//! Bitonic-warp merge sort of 32-bit keys with 32-bit values (Ye et al. 2010, "High performance
//! comparison-based sorting algorithm on many-core GPUs", §3–§4; the sort Karas uses for the
//! lights of clustered shading). An alternative to [`crate::radix`]; not stable.
//!
//! Steps (W = subgroup width from [`Coop::subgroup_size`], never hard-coded; M = 4·W):
//! 1. **block sort** ([`block_sort`], one dispatch) — each subgroup sorts a block of
//!    `run0 ≤ M` elements barrier-free: lane `l` holds elements `4l..4l+3` (Ye §3.1), the bitonic
//!    network runs distances `d < 4` in registers and `d ≥ 4` with `shuffle_xor(d/4)`. Slots past
//!    the block or the input are *pads*, ordered after every real key by comparing
//!    `(pad flag, key)`, so a real key `0xFFFF_FFFF` is never mistaken for padding.
//! 2. **merge levels**, run length `R = run0, 2·run0, …` while `R < n`, ping-ponging buffers:
//!    - a. **splitters** ([`splitter`], only at levels where a pair of runs is larger than one
//!      piece — "when the runs no longer fill the GPU", Ye §4.2): for each pair of runs (A, B)
//!      every `g`-th element of A and of B is a sample (strided samples of sorted runs are sorted,
//!      so a sample's rank in the merged sample list is its own index + a binary-search co-rank
//!      in the other run's samples); every `k`-th sample by rank is kept. All orders are by
//!      (key, position), A left of B, so ties split consistently (all-equal input splits
//!      evenly). A kept A sample `i` bounds a piece at `(i·g, lower_bound(B, key))`, a B sample
//!      `j` at `(upper_bound(A, key), j·g)`. Pieces are then contiguous segments of the merged
//!      run: ∀a∈S_i, b∈S_j, i<j ⇒ a ≤ b, and each holds at most `(k+2)·g − 2` elements, with or
//!      without duplicates (the composite order is strict: k sample gaps + 2 partial ones).
//!    - b. **warp merge** ([`merge_piece`], one subgroup per piece, Ye §3.2): a register buffer of
//!      M elements in column layout (element `e = j·W + lane`); its lower half (`t = M/2`) is
//!      kept, its upper half is refilled with the next `t` elements, *reversed*, from the run
//!      whose next unread element is smaller, which makes the buffer bitonic; half-cleaners
//!      `d = M/2 … 1` sort it (`d ≥ W` in registers, `d < W` by shuffles), the lower half is
//!      written out, the upper half becomes the kept half (a register move). A first load primes
//!      the kept half. Why the refill rule is right: say X's next element `x` is ≤ Y's next
//!      `y`. Every kept element was read from a prefix of X (so it is ≤ `x` ≤ `y`) or of Y (so it
//!      is ≤ `y`): the `t` kept elements are all ≤ `y`, so none of Y's unread elements is among
//!      the `t` smallest of (kept ∪ unread), and X's unread ones among them are within the `t`
//!      just read. The lower half written is therefore the next `t` of the merged output.
//!
//! Parameters: `g` = [`sample_stride`] = `2·W_min` (one merge step of the narrowest subgroup the
//! device may pick), `k` = [`SPLITTER_KEEP`] = 8 → a piece is at most 10 merge steps, so one
//! invocation's loops run a few hundred iterations — far under llvmpipe's 65 535-iteration
//! limiter — and a level has about `n / (g·k)` pieces (2 048 for 2^20 keys at W = 32). Levels with
//! `2·⌈R/g⌉ ≤ k` (R ≤ 2·M) give one piece per pair and skip the splitter dispatch, so a level is
//! 1 or 2 dispatches; `⌈log₂(n / run0)⌉` levels: 2^20 keys take 29 dispatches at W = 8 (15
//! levels) and 25 at W = 32 (13 levels).
//!
//! Memory: keys + values double-buffered (8 B of scratch per element) plus 8 B per piece of
//! boundaries (≈ n/16 B at W = 8, n/64 B at W = 32).
//!
//! Width independence: the host plans blocks and strides with the device's *smallest* subgroup
//! width (`run0 = 4·W_min`, `g = 2·W_min`); a kernel that runs with a wider subgroup sorts a
//! `run0` block in its larger register buffer (the rest is padding) and merges with larger steps,
//! so the result does not depend on the width the driver picks (tested on the CPU).
use crate::coop::Coop;

/// Elements each lane holds in registers.
pub const PER_LANE: u32 = 4;
/// Every `SPLITTER_KEEP`-th sample (by rank in a pair's merged sample list) bounds a piece.
pub const SPLITTER_KEEP: u32 = 8;
/// Invocations per workgroup of the cooperative kernels (block sort, merge); the subgroups per
/// workgroup come from the built-ins.
pub const BITONIC_WORKGROUP: u32 = 128;
/// Invocations per workgroup of the splitter kernel (one invocation per sample).
pub const SPLITTER_WORKGROUP: u32 = 256;
/// Piece index of a sample that is not a kept splitter.
pub const NO_PIECE: u32 = u32::MAX;

/// Elements of the first sorted runs (the block sort's blocks) for a device whose narrowest
/// subgroup is `min_width` lanes.
#[inline]
pub fn block_elems(min_width: u32) -> u32 {
    PER_LANE * min_width
}

/// Sample stride `g` of the splitters: one merge step (`t = 2·W`) of the narrowest subgroup.
#[inline]
pub fn sample_stride(min_width: u32) -> u32 {
    2 * min_width
}

/// The four elements a lane holds: keys, values and a bit mask of pad slots (bit `j`).
#[derive(Clone, Copy)]
pub struct Lane4 {
    pub k: [u32; 4],
    pub v: [u32; 4],
    pub pad: u32,
}

impl Lane4 {
    /// All four slots padding.
    #[inline]
    pub fn pads() -> Self {
        Self { k: [u32::MAX; 4], v: [0; 4], pad: 0xF }
    }
}

/// `(pad_a, a) < (pad_b, b)`: real keys before pads, pads all equal.
#[inline]
fn less(a: u32, pad_a: u32, b: u32, pad_b: u32) -> bool {
    if pad_a != pad_b {
        pad_a < pad_b
    } else {
        pad_a == 0 && a < b
    }
}

/// Compare-exchange of slots `i < i2` of one lane: slot `i` keeps the minimum when `ascending`.
#[inline]
fn exchange_regs(mut x: Lane4, i: usize, i2: usize, ascending: bool) -> Lane4 {
    let (pi, pi2) = ((x.pad >> i) & 1, (x.pad >> i2) & 1);
    let swap = if ascending { less(x.k[i2], pi2, x.k[i], pi) } else { less(x.k[i], pi, x.k[i2], pi2) };
    if swap {
        let (k, v) = (x.k[i], x.v[i]);
        x.k[i] = x.k[i2];
        x.v[i] = x.v[i2];
        x.k[i2] = k;
        x.v[i2] = v;
        if pi != pi2 {
            x.pad ^= (1 << i) | (1 << i2);
        }
    }
    x
}

/// Compare-exchange of slot `j` of this lane with slot `j` of lane `lane ^ mask`, for each `j`:
/// the lower lane of the pair keeps the minimum where bit `j` of `ascending` is set.
/// 9 shuffles (4 keys, 4 values, 1 pad mask). Subgroup-uniform.
#[inline]
fn exchange_lanes<C: Coop>(c: &C, x: Lane4, mask: u32, ascending: u32) -> Lane4 {
    let lower = c.lane() & mask == 0;
    let partner_pad = c.shuffle_xor(x.pad, mask);
    let mut y = x;
    let mut j = 0;
    while j < PER_LANE as usize {
        let pk = c.shuffle_xor(x.k[j], mask);
        let pv = c.shuffle_xor(x.v[j], mask);
        let (pp, mp) = ((partner_pad >> j) & 1, (x.pad >> j) & 1);
        let keep_min = lower == ((ascending >> j) & 1 != 0);
        let take = if keep_min { less(pk, pp, x.k[j], mp) } else { less(x.k[j], mp, pk, pp) };
        if take {
            y.k[j] = pk;
            y.v[j] = pv;
            y.pad = (y.pad & !(1 << j)) | (pp << j);
        }
        j += 1;
    }
    y
}

/// Step 1: sorts the subgroup's `4·W` elements, lane-major (element `4·lane + j`), ascending,
/// pads last. Subgroup-uniform; no barriers, no shared memory.
pub fn block_sort<C: Coop>(c: &C, mut x: Lane4) -> Lane4 {
    let m = PER_LANE * c.subgroup_size();
    let lane = c.lane();
    let mut size = 2;
    while size <= m {
        let mut d = size / 2;
        while d > 0 {
            if d >= PER_LANE {
                let mut asc = 0;
                let mut j = 0;
                while j < PER_LANE {
                    if (PER_LANE * lane + j) & size == 0 {
                        asc |= 1 << j;
                    }
                    j += 1;
                }
                x = exchange_lanes(c, x, d / PER_LANE, asc);
            } else {
                // Slot `j` meets `j ^ d`; direction from element `4·lane + j`.
                let e = PER_LANE * lane;
                if d == 1 {
                    x = exchange_regs(x, 0, 1, e & size == 0);
                    x = exchange_regs(x, 2, 3, (e + 2) & size == 0);
                } else {
                    x = exchange_regs(x, 0, 2, e & size == 0);
                    x = exchange_regs(x, 1, 3, (e + 1) & size == 0);
                }
            }
            d /= 2;
        }
        size *= 2;
    }
    x
}

/// Half-cleaners `d = M/2 … 1` on a bitonic buffer in column layout (`e = j·W + lane`): the
/// buffer ends ascending.
#[inline]
fn merge_bitonic<C: Coop>(c: &C, mut x: Lane4) -> Lane4 {
    x = exchange_regs(x, 0, 2, true);
    x = exchange_regs(x, 1, 3, true);
    x = exchange_regs(x, 0, 1, true);
    x = exchange_regs(x, 2, 3, true);
    let mut d = c.subgroup_size() / 2;
    while d > 0 {
        x = exchange_lanes(c, x, d, 0xF);
        d /= 2;
    }
    x
}

/// Geometry of one merge level: pairs of runs of `run` elements out of `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    pub n: u32,
    pub run: u32,
    /// Sample stride `g`.
    pub stride: u32,
    /// Keep every `keep`-th sample.
    pub keep: u32,
}

impl Level {
    /// Pairs `(A, B)` of runs (the last may have no B).
    #[inline]
    pub fn pairs(&self) -> u32 {
        self.n.div_ceil(2 * self.run)
    }
    /// `(first element, |A|, |B|)` of pair `p`.
    #[inline]
    pub fn pair(&self, p: u32) -> (u32, u32, u32) {
        let base = 2 * p * self.run;
        let a = self.run.min(self.n - base);
        let b = self.run.min(self.n - base - a);
        (base, a, b)
    }
    /// Sample slots of a full pair: `⌈R/g⌉` from A, then `⌈R/g⌉` from B.
    #[inline]
    pub fn slots_per_pair(&self) -> u32 {
        2 * self.run.div_ceil(self.stride)
    }
    /// Pieces of a full pair (the stride of the boundary array between pairs).
    #[inline]
    pub fn pieces_per_pair(&self) -> u32 {
        self.slots_per_pair().div_ceil(self.keep)
    }
    /// Pieces of a pair with runs of `a` and `b` elements.
    #[inline]
    pub fn pair_pieces(&self, a: u32, b: u32) -> u32 {
        (a.div_ceil(self.stride) + b.div_ceil(self.stride)).div_ceil(self.keep)
    }
    /// Whether this level needs the splitter dispatch (more than one piece per pair).
    #[inline]
    pub fn split(&self) -> bool {
        self.pieces_per_pair() > 1
    }
    /// Slots of the splitter dispatch, and the boundary entries (pieces) it may write.
    #[inline]
    pub fn slots(&self) -> u32 {
        self.pairs() * self.slots_per_pair()
    }
    #[inline]
    pub fn pieces(&self) -> u32 {
        self.pairs() * self.pieces_per_pair()
    }
}

/// Elements `keys[start + i·stride]`, `i < count`, that are `< key` (or `≤ key` with `or_equal`).
#[inline]
pub fn rank_in(keys: &[u32], start: u32, count: u32, stride: u32, key: u32, or_equal: bool) -> u32 {
    let (mut lo, mut hi) = (0, count);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        let x = keys[(start + mid * stride) as usize];
        if x < key || (or_equal && x == key) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// A kept splitter: the boundary of piece `piece` (global index in the level's boundary array)
/// as `(elements of A before it, elements of B before it)`; `piece == NO_PIECE` otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Boundary {
    pub piece: u32,
    pub a: u32,
    pub b: u32,
}

/// Step 2a for sample slot `slot` of level `lv` (one invocation each).
pub fn splitter(keys: &[u32], lv: &Level, slot: u32) -> Boundary {
    let none = Boundary { piece: NO_PIECE, a: 0, b: 0 };
    let per_pair = lv.slots_per_pair();
    let (pair, s) = (slot / per_pair, slot % per_pair);
    if pair >= lv.pairs() {
        return none;
    }
    let (base, a, b) = lv.pair(pair);
    let g = lv.stride;
    let half = per_pair / 2;
    let from_a = s < half;
    let i = if from_a { s } else { s - half };
    if i * g >= if from_a { a } else { b } {
        return none;
    }
    let (own, other, other_len) = if from_a { (base, base + a, b) } else { (base + a, base, a) };
    let key = keys[(own + i * g) as usize];
    // A before B at equal keys: an A sample counts the B samples strictly below it, a B sample
    // the A samples at or below it.
    let rank = i + rank_in(keys, other, other_len.div_ceil(g), g, key, !from_a);
    // Kept: ranks 0, k, 2k, … (rank 0 is the pair's first element: boundary (0, 0)).
    let (kept, after_kept) = (rank / lv.keep, rank % lv.keep);
    if after_kept != 0 {
        return none;
    }
    let co = rank_in(keys, other, other_len, 1, key, !from_a);
    let piece = pair * lv.pieces_per_pair() + kept;
    if from_a {
        Boundary { piece, a: i * g, b: co }
    } else {
        Boundary { piece, a: co, b: i * g }
    }
}

/// One piece of a merge: `keys[a0..a1)` and `keys[b0..b1)` (absolute indices) merge into
/// `out[out0..out0 + (a1−a0) + (b1−b0))`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Piece {
    pub a0: u32,
    pub a1: u32,
    pub b0: u32,
    pub b1: u32,
    pub out0: u32,
}

/// The piece a subgroup merges: global subgroup `index` of the level, or `None` past the last.
/// `boundaries` holds `(a, b)` pairs written by [`splitter`] (unused when `!lv.split()`).
#[inline]
pub fn piece_of(lv: &Level, boundaries: &[u32], index: u32) -> Option<Piece> {
    let ppp = lv.pieces_per_pair();
    let (pair, q) = (index / ppp, index % ppp);
    if pair >= lv.pairs() {
        return None;
    }
    let (base, a, b) = lv.pair(pair);
    let np = lv.pair_pieces(a, b);
    if q >= np {
        return None;
    }
    let first = 2 * (pair * ppp + q) as usize;
    let (s0, t0) = if ppp == 1 { (0, 0) } else { (boundaries[first], boundaries[first + 1]) };
    let (s1, t1) = if q + 1 < np { (boundaries[first + 2], boundaries[first + 3]) } else { (a, b) };
    Some(Piece { a0: base + s0, a1: base + s1, b0: base + a + t0, b1: base + a + t1, out0: base + s0 + t0 })
}

/// Output of [`merge_piece`]: `keys_out[i] = k`, `values_out[i] = v`.
pub trait Store {
    fn store(&mut self, i: u32, v: u32);
}

impl Store for [u32] {
    #[inline]
    fn store(&mut self, i: u32, v: u32) {
        self[i as usize] = v;
    }
}

/// Loads `t` elements of one run into the slots `j ∈ {2·h, 2·h + 1}` (`h` = 0: lower half,
/// ascending; `h` = 1: upper half, reversed). Positions at or past `end` become pads.
#[inline]
fn load_half<C: Coop>(c: &C, mut x: Lane4, keys: &[u32], values: &[u32], start: u32, end: u32, upper: bool) -> Lane4 {
    let w = c.subgroup_size();
    let t = 2 * w;
    let mut h = 0;
    while h < 2 {
        let q = h * w + c.lane();
        let src = if upper { start + t - 1 - q } else { start + q };
        let j = (if upper { 2 } else { 0 } + h) as usize;
        if src < end {
            x.k[j] = keys[src as usize];
            x.v[j] = values[src as usize];
            x.pad &= !(1 << j);
        } else {
            x.k[j] = u32::MAX;
            x.v[j] = 0;
            x.pad |= 1 << j;
        }
        h += 1;
    }
    x
}

/// Whether the next chunk comes from A: A's next element `ia` is smaller than B's next `ib`
/// (or equal: A lies left of B), or B is exhausted.
#[inline]
fn take_a(keys: &[u32], p: &Piece, ia: u32, ib: u32) -> bool {
    ia < p.a1 && (ib >= p.b1 || keys[ia as usize] <= keys[ib as usize])
}

/// Step 2b: merges one piece with one subgroup (see the module doc). Subgroup-uniform.
/// Returns the number of merge steps (for tests of the loop bound).
pub fn merge_piece<C: Coop, O: Store + ?Sized>(c: &C, keys: &[u32], values: &[u32], p: Piece, keys_out: &mut O, values_out: &mut O) -> u32 {
    let len = (p.a1 - p.a0) + (p.b1 - p.b0);
    if len == 0 {
        return 0;
    }
    let t = 2 * c.subgroup_size();
    let (mut ia, mut ib) = (p.a0, p.b0);
    let mut x = Lane4::pads();
    // Prime the kept half from the run with the smaller head (A at equal keys).
    if take_a(keys, &p, ia, ib) {
        x = load_half(c, x, keys, values, ia, p.a1, false);
        ia += t;
    } else {
        x = load_half(c, x, keys, values, ib, p.b1, false);
        ib += t;
    }
    let mut written = 0;
    let mut steps = 0;
    while written < len {
        if take_a(keys, &p, ia, ib) {
            x = load_half(c, x, keys, values, ia, p.a1, true);
            ia += t;
        } else {
            x = load_half(c, x, keys, values, ib, p.b1, true);
            ib += t;
        }
        x = merge_bitonic(c, x);
        let mut h = 0;
        while h < 2 {
            let e = h * c.subgroup_size() + c.lane();
            if written + e < len {
                let dst = p.out0 + written + e;
                keys_out.store(dst, x.k[h as usize]);
                values_out.store(dst, x.v[h as usize]);
            }
            h += 1;
        }
        // The upper half becomes the kept half.
        x = Lane4 { k: [x.k[2], x.k[3], u32::MAX, u32::MAX], v: [x.v[2], x.v[3], 0, 0], pad: (x.pad >> 2) | 0xC };
        written += t;
        steps += 1;
    }
    steps
}

/// Merge levels of a sort of `n` elements whose first runs have `run0` elements.
pub fn level_count(n: u32, run0: u32) -> u32 {
    let mut levels = 0;
    let mut run = run0 as u64;
    while run < n as u64 {
        run *= 2;
        levels += 1;
    }
    levels
}

/// Merge level `index` (0: the first, run length `4·W_min`) of a sort of `n` elements planned
/// for a narrowest subgroup of `min_width` lanes.
#[inline]
pub fn level(n: u32, min_width: u32, index: u32) -> Level {
    Level { n, run: block_elems(min_width) << index, stride: sample_stride(min_width), keep: SPLITTER_KEEP }
}

#[cfg(not(target_arch = "spirv"))]
#[path = "bitonic_emulated.rs"]
pub mod emulated;

#[cfg(test)]
#[path = "bitonic_tests.rs"]
mod tests;
