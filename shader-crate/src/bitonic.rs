//! Bitonic-warp merge sort of 32-bit keys with 32-bit values (Ye et al. 2010, "High performance
//! comparison-based sorting algorithm on many-core GPUs", §3–§4; the sort Karas uses for the
//! lights of clustered shading). An alternative to [`crate::radix`]; not stable.
//!
//! Steps (W = subgroup width from [`Coop::subgroup_size`], never hard-coded; M = 4·W):
//! 1. **block sort** ([`sort_block`], one dispatch) — each workgroup of 256 invocations sorts a
//!    block of [`BLOCK`] = 1 024 elements with a bitonic network: an invocation holds 4
//!    consecutive elements (Ye §3.1), distances `d < 4` run in registers, `4 ≤ d < M` with
//!    `shuffle_xor(d/4)` inside a subgroup, `d ≥ M` through workgroup memory (8 KiB: keys and
//!    tags). The network moves each element's position in the block (its tag) instead of its
//!    value; the values are gathered once at the end. Slots past the input are *pads*, ordered
//!    after every real key by comparing `(pad flag, key)`, so a real key `0xFFFF_FFFF` is never
//!    mistaken for padding. (A block of one subgroup's M elements, as Ye's, left 3 more merge
//!    levels at W = 32: on an NVIDIA H200 the workgroup block took 1M pairs from 1.134 to
//!    0.555 ms together with the pipelined merge below.)
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
//! limiter — and a level has about `n / (g·k)` pieces (2 048 for 2^20 keys at W = 32). The host
//! picks `k` per sort size ([`splitter_keep`]: 1 … 8, about [`TARGET_PIECES`] pieces a level).
//! Levels with `2·⌈R/g⌉ ≤ k` give one piece per pair and skip the splitter dispatch, so a level
//! is 1 or 2 dispatches; `⌈log₂(n / BLOCK)⌉` levels: 2^20 keys take 10 levels at every width.
//!
//! Memory: keys + values double-buffered (8 B of scratch per element) plus 8 B per piece of
//! boundaries (≈ n/16 B at W = 8, n/64 B at W = 32).
//!
//! Width independence: blocks are [`BLOCK`] elements at every width, and the host plans the sample
//! stride with the device's *smallest* subgroup width (`g = 2·W_min`); a merge that runs with a
//! wider subgroup takes larger steps, so the result does not depend on the width the driver
//! picks (tested on the CPU).
//!
//! The merge step is software-pipelined ([`merge_piece`]): the next chunk and its run's next
//! head are loaded while the current chunk is merged, so each step waits for one load, where the
//! plain loop waited for the head and then for the chunk.
use crate::coop::{Coop, SharedU32};

/// Elements each lane holds in registers.
pub const PER_LANE: u32 = 4;
/// Every `SPLITTER_KEEP`-th sample (by rank in a pair's merged sample list) bounds a piece: the
/// largest keep [`splitter_keep`] picks.
pub const SPLITTER_KEEP: u32 = 8;
/// Pieces per merge level that [`splitter_keep`] aims for: enough subgroups to hide the merge
/// steps' load latency on a large GPU.
pub const TARGET_PIECES: u32 = 2048;

/// The splitter keep for a sort of `n` elements with sample stride `2·min_width`: about
/// [`TARGET_PIECES`] pieces per level (`n / (g·k)`), a power of two in `1..=SPLITTER_KEEP`.
/// Measured on an NVIDIA H200 (uniform 30-bit keys, GPU ms for keep 1 / 2 / 4 / 8): 64k pairs
/// 0.153 / 0.164 / 0.194 / 0.256, 1M 0.621 / 0.550 / 0.526 / 0.555, 4M 2.22 / 1.81 / 1.65 / 1.59,
/// 16M 9.66 / 7.38 / 6.47 / 6.10. Smaller pieces put more subgroups to work while a level has
/// few; each piece also pays one priming load, which costs more than it gains once the GPU is
/// full.
#[inline]
pub fn splitter_keep(n: u32, min_width: u32) -> u32 {
    let k = n / (sample_stride(min_width) * TARGET_PIECES);
    if k >= SPLITTER_KEEP {
        SPLITTER_KEEP
    } else if k >= 1 {
        1 << (31 - k.leading_zeros())
    } else {
        1
    }
}
/// Invocations per workgroup of the merge; the subgroups per workgroup come from the built-ins.
pub const BITONIC_WORKGROUP: u32 = 128;
/// Invocations per workgroup of the splitter kernel (one invocation per sample).
pub const SPLITTER_WORKGROUP: u32 = 256;
/// Piece index of a sample that is not a kept splitter.
pub const NO_PIECE: u32 = u32::MAX;

/// Invocations per workgroup of the block sort.
pub const BLOCK_WORKGROUP: u32 = 256;
/// Elements of the first sorted runs (the block sort's blocks): 1 024, whatever the subgroup
/// width.
pub const BLOCK: u32 = BLOCK_WORKGROUP * PER_LANE;
/// Words of workgroup memory the block sort uses (keys and tags of a block).
pub const BLOCK_SHARED_WORDS: usize = 2 * BLOCK as usize;
const _: () = assert!(BLOCK_SHARED_WORDS <= crate::radix::RADIX_SHARED_WORDS, "the block sort shares the sort kernels' workgroup array");
const _: () = assert!(BLOCK <= 1 << 31, "tags keep their top bit for the pad flag");

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
    // Non-short-circuit `&` / `|`: no branches in the sorting network.
    (pad_a < pad_b) | ((pad_a == pad_b) & (pad_a == 0) & (a < b))
}

/// `if s { a } else { b }` by masks, branch-free.
#[inline]
fn pick(s: bool, a: u32, b: u32) -> u32 {
    let m = 0u32.wrapping_sub(s as u32);
    (a & m) | (b & !m)
}

/// Compare-exchange of slots `i < i2` of one lane: slot `i` keeps the minimum when `ascending`.
#[inline]
fn exchange_regs(mut x: Lane4, i: usize, i2: usize, ascending: bool) -> Lane4 {
    let (pi, pi2) = ((x.pad >> i) & 1, (x.pad >> i2) & 1);
    let up = less(x.k[i2], pi2, x.k[i], pi);
    let down = less(x.k[i], pi, x.k[i2], pi2);
    let swap = (ascending & up) | (!ascending & down);
    let (k, v, k2, v2) = (x.k[i], x.v[i], x.k[i2], x.v[i2]);
    x.k[i] = pick(swap, k2, k);
    x.v[i] = pick(swap, v2, v);
    x.k[i2] = pick(swap, k, k2);
    x.v[i2] = pick(swap, v, v2);
    x.pad ^= pick(swap & (pi != pi2), (1 << i) | (1 << i2), 0);
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
    unroll4!(j => {
        let pk = c.shuffle_xor(x.k[j as usize], mask);
        let pv = c.shuffle_xor(x.v[j as usize], mask);
        let (pp, mp) = ((partner_pad >> j) & 1, (x.pad >> j) & 1);
        let keep_min = lower == ((ascending >> j) & 1 != 0);
        let take = if keep_min { less(pk, pp, x.k[j as usize], mp) } else { less(x.k[j as usize], mp, pk, pp) };
        // A branch, not `pick`: lavapipe (Mesa 22.3) sorted wrongly when the shuffled elements
        // were selected by masks here (the CPU emulation did not).
        if take {
            y.k[j as usize] = pk;
            y.v[j as usize] = pv;
            y.pad = (y.pad & !(1 << j)) | (pp << j);
        }
    });
    y
}

/// Element `first + j` of the block is slot `j` of the invocation whose slot 0 is `first`:
/// sets bit `j` of the result where that element's bitonic sequence of `size` ascends.
#[inline]
fn ascending_bits(first: u32, size: u32) -> u32 {
    let mut asc = 0;
    unroll4!(j => {
        if (first + j) & size == 0 {
            asc |= 1 << j;
        }
    });
    asc
}

/// The pad flag rides in the top bit of a tag in workgroup memory.
const TAG_PAD: u32 = 1 << 31;

/// Compare-exchange of elements `e` and `e ^ d` across subgroups, through workgroup memory
/// (keys at `[0, BLOCK)`, tags with the pad flag at `[BLOCK, 2·BLOCK)`). Workgroup-uniform.
#[inline]
fn exchange_shared<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, x: Lane4, first: u32, size: u32, d: u32) -> Lane4 {
    unroll4!(j => {
        sh.store(first + j, x.k[j as usize]);
        sh.store(BLOCK + first + j, x.v[j as usize] | (((x.pad >> j) & 1) * TAG_PAD));
    });
    c.workgroup_barrier();
    let mut y = x;
    unroll4!(j => {
        let e = first + j;
        let pk = sh.load(e ^ d);
        let pt = sh.load(BLOCK + (e ^ d));
        let (pp, mp) = (pt >> 31, (x.pad >> j) & 1);
        let keep_min = (e & d == 0) == (e & size == 0);
        let take = (keep_min & less(pk, pp, x.k[j as usize], mp)) | (!keep_min & less(x.k[j as usize], mp, pk, pp));
        y.k[j as usize] = pick(take, pk, x.k[j as usize]);
        y.v[j as usize] = pick(take, pt & !TAG_PAD, x.v[j as usize]);
        y.pad = pick(take, (y.pad & !(1 << j)) | (pp << j), y.pad);
    });
    c.workgroup_barrier();
    y
}

/// Step 1: sorts the workgroup's block of [`BLOCK`] elements, ascending, pads last: the
/// invocation of subgroup `s`, lane `l` holds elements `first = 4·(s·W + l) … first + 3`
/// ([`block_first`]). Distances `d < 4` run in registers, `4 ≤ d < 4·W` with `shuffle_xor(d/4)`,
/// `d ≥ 4·W` through workgroup memory ([`exchange_shared`]: 2 barriers each). With `W` = 32:
/// 55 stages, 6 of them through memory. Workgroup-uniform. `x.v` is carried as a tag (the
/// kernel sorts each element's position in the block and gathers the values afterwards), whose
/// top bit must be clear.
pub fn block_sort<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, mut x: Lane4) -> Lane4 {
    let sub = PER_LANE * c.subgroup_size();
    let first = block_first(c);
    let mut size = 2;
    while size <= BLOCK {
        let mut d = size / 2;
        while d > 0 {
            if d >= sub {
                x = exchange_shared(c, sh, x, first, size, d);
            } else if d >= PER_LANE {
                x = exchange_lanes(c, x, d / PER_LANE, ascending_bits(first, size));
            } else if d == 1 {
                x = exchange_regs(x, 0, 1, first & size == 0);
                x = exchange_regs(x, 2, 3, (first + 2) & size == 0);
            } else {
                x = exchange_regs(x, 0, 2, first & size == 0);
                x = exchange_regs(x, 1, 3, (first + 1) & size == 0);
            }
            d /= 2;
        }
        size *= 2;
    }
    x
}

/// Step 1 for the block at `base` of an input of `count` elements: loads the invocation's
/// elements (`key_of`), sorts the block with each element's position in it as its tag, and
/// gathers the values of the sorted order (`value_of`). Returns the keys and values of block
/// elements `block_first(c) + j` (those at or past `count` are not to be written). Ends with a
/// barrier after every gather, so the caller may write the block in place. Workgroup-uniform.
#[inline]
pub fn sort_block<C: Coop, S: SharedU32 + ?Sized>(c: &C, sh: &mut S, base: u32, count: u32, key_of: impl Fn(u32) -> u32, value_of: impl Fn(u32) -> u32) -> ([u32; 4], [u32; 4]) {
    let first = block_first(c);
    let mut x = Lane4::pads();
    unroll4!(j => {
        let e = first + j;
        if base + e < count {
            x.k[j as usize] = key_of(base + e);
            x.v[j as usize] = e;
            x.pad &= !(1 << j);
        }
    });
    x = block_sort(c, sh, x);
    let mut v = [0u32; 4];
    unroll4!(j => {
        if (x.pad >> j) & 1 == 0 {
            v[j as usize] = value_of(base + x.v[j as usize]);
        }
    });
    c.workgroup_barrier();
    (x.k, v)
}

/// The block element of an invocation's slot 0 in [`block_sort`]: subgroups hold consecutive
/// `4·W` elements, lanes consecutive 4.
#[inline]
pub fn block_first<C: Coop>(c: &C) -> u32 {
    PER_LANE * (c.subgroup_id() * c.subgroup_size() + c.lane())
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

/// `t = 2·W` consecutive elements of one run as a lane holds them (element `h·W + lane` in slot
/// `h`, or reversed: element `t − 1 − (h·W + lane)`), pad bits `h` at or past the run's end; and
/// the run's key right after the chunk, its next head (read with the chunk, so one load latency
/// per merge step decides the next step too).
#[derive(Clone, Copy)]
struct Chunk {
    k: [u32; 2],
    v: [u32; 2],
    pad: u32,
    /// `keys[start + t]`, or `u32::MAX` at or past `end` (then unused: the run is exhausted).
    head: u32,
}

/// The key at `i` of a run ending at `end`: [`Chunk::head`].
#[inline]
fn head_at(keys: &[u32], i: u32, end: u32) -> u32 {
    if i < end { keys[i as usize] } else { u32::MAX }
}

#[inline]
fn load_chunk<C: Coop>(c: &C, keys: &[u32], values: &[u32], start: u32, end: u32, reversed: bool) -> Chunk {
    let w = c.subgroup_size();
    let t = 2 * w;
    let mut x = Chunk { k: [u32::MAX; 2], v: [0; 2], pad: 0b11, head: head_at(keys, start + t, end) };
    unroll2!(h => {
        let q = h * w + c.lane();
        let src = if reversed { start + t - 1 - q } else { start + q };
        if src < end {
            x.k[h as usize] = keys[src as usize];
            x.v[h as usize] = values[src as usize];
            x.pad &= !(1 << h);
        }
    });
    x
}

/// A piece's read positions and the keys there (its runs' heads).
#[derive(Clone, Copy)]
struct Cursor {
    ia: u32,
    ib: u32,
    head_a: u32,
    head_b: u32,
}

impl Cursor {
    /// The next chunk, from A when A's head is smaller than B's (or equal: A lies left of B) or
    /// B is exhausted; advances past it. `reversed`: for the upper half of the buffer.
    #[inline]
    fn next<C: Coop>(&mut self, c: &C, keys: &[u32], values: &[u32], p: &Piece, reversed: bool) -> Chunk {
        let t = 2 * c.subgroup_size();
        let take_a = self.ia < p.a1 && (self.ib >= p.b1 || self.head_a <= self.head_b);
        if take_a {
            let x = load_chunk(c, keys, values, self.ia, p.a1, reversed);
            self.ia += t;
            self.head_a = x.head;
            x
        } else {
            let x = load_chunk(c, keys, values, self.ib, p.b1, reversed);
            self.ib += t;
            self.head_b = x.head;
            x
        }
    }
}

/// Step 2b: merges one piece with one subgroup (see the module doc). Subgroup-uniform.
/// Software-pipelined: the chunk of step `s + 1` is chosen and its load issued before step `s`
/// merges, so the merge network runs while the load is in flight (the chunks and their order are
/// those of the plain loop: a choice depends only on the read positions, which change only when
/// a chunk is read). Returns the number of merge steps (for tests of the loop bound).
pub fn merge_piece<C: Coop, O: Store + ?Sized>(c: &C, keys: &[u32], values: &[u32], p: Piece, keys_out: &mut O, values_out: &mut O) -> u32 {
    let len = (p.a1 - p.a0) + (p.b1 - p.b0);
    if len == 0 {
        return 0;
    }
    let t = 2 * c.subgroup_size();
    let mut cur = Cursor { ia: p.a0, ib: p.b0, head_a: head_at(keys, p.a0, p.a1), head_b: head_at(keys, p.b0, p.b1) };
    // Prime the kept half from the run with the smaller head.
    let first = cur.next(c, keys, values, &p, false);
    let mut x = Lane4 { k: [first.k[0], first.k[1], u32::MAX, u32::MAX], v: [first.v[0], first.v[1], 0, 0], pad: first.pad | 0xC };
    let mut pending = cur.next(c, keys, values, &p, true);
    let mut written = 0;
    let mut steps = 0;
    while written < len {
        let upper = pending;
        if written + t < len {
            pending = cur.next(c, keys, values, &p, true);
        }
        x.k[2] = upper.k[0];
        x.k[3] = upper.k[1];
        x.v[2] = upper.v[0];
        x.v[3] = upper.v[1];
        x.pad = (x.pad & 0b11) | (upper.pad << 2);
        x = merge_bitonic(c, x);
        unroll2!(h => {
            let e = h * c.subgroup_size() + c.lane();
            if written + e < len {
                let dst = p.out0 + written + e;
                keys_out.store(dst, x.k[h as usize]);
                values_out.store(dst, x.v[h as usize]);
            }
        });
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

/// Merge level `index` (0: the first, run length [`BLOCK`]) of a sort of `n` elements planned
/// for a narrowest subgroup of `min_width` lanes, keeping every `keep`-th sample (≥ 1).
#[inline]
pub fn level(n: u32, min_width: u32, index: u32, keep: u32) -> Level {
    Level { n, run: BLOCK << index, stride: sample_stride(min_width), keep }
}

#[cfg(not(target_arch = "spirv"))]
#[path = "bitonic_emulated.rs"]
pub mod emulated;

#[cfg(test)]
#[path = "bitonic_tests.rs"]
mod tests;
