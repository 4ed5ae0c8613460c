//! Unique clusters found tile by tile in one dispatch: the alternative to the virtual page table
//! ([`crate::page_table`]) for frames whose clusters all come from the depth buffer.
//!
//! A cluster is a screen tile × a depth slice ([`crate::cluster_key`]). The clusters a frame
//! uses are the distinct keys of its pixels. The page table finds them device-wide: marks,
//! allocation, slots, counts, a scan and a compaction, five dependent dispatches. But the pixels
//! of a cluster all lie in its tile, so one workgroup per tile can find that tile's clusters alone,
//! as a bit mask of its slices in workgroup memory (the distinct keys a sort of the tile's keys
//! would leave, without the sort):
//!
//! # Steps (one workgroup of [`TILE_WORKGROUP`] invocations per tile, one dispatch)
//! 1. Clear the tile's slice mask: [`mask_words`] words of workgroup memory.
//! 2. Each invocation takes pixels `local, local + 256, …` of the tile: stores the pixel's key
//!    (the same `page_table::pixel_key` as the page table's key kernel) and sets its slice's bit
//!    with a workgroup atomic OR.
//! 3. One invocation counts the set bits word by word (a running total per word), reserves the
//!    tile's clusters in the frame's unique-cluster list with one device atomic add, and raises
//!    the assignment's indirect dispatch to cover the list's new end (an atomic maximum of
//!    [`dispatch_raise`], which never decreases as the count grows: the largest end wins,
//!    whatever order the tiles finish in).
//! 4. Word `w` of the mask and the list index of its first set bit go to the tile's record;
//!    each set bit's key to its place in the unique-cluster list.
//!
//! Shading finds a pixel's cluster from its key in O(1) ([`cluster_of_key`]): the record's index
//! plus the set bits below the slice's bit. The list is grouped by tile, in the order tiles
//! reserve, and within a tile by slice: its order carries no meaning (the assignment and shading
//! read each cluster through its index), and the same set of keys as the page table's sorted list.
//!
//! Counter and dispatch words only grow during the dispatch, so they must start at zero: the
//! shading kernel, their last reader, copies the count to `COUNTER_FRAME_CLUSTERS` for the host
//! and zeroes them for the next frame (no fill at the frame's start).
//!
//! Transparent fragments add clusters that no opaque pixel has; scenes with transparent draws,
//! and grids of more than [`MAX_TILE_SLICES`] slices, use the page table.
//!
//! # Layout of a tile's record (`tile_records`, [`RECORD_WORDS`] words per mask word)
//! ```text
//! record of tile t = j · tiles_x + i, word w:  [ 2(t·W + w) ]     mask: bit b ⇔ slice 32w + b used
//!                                              [ 2(t·W + w) + 1 ] list index of its lowest set bit
//! W = mask_words(grid) = ⌈S / 32⌉
//! ```
//!
//! # Memory
//! 8 B per mask word per tile: 1080p, 32 px tiles, 276 slices: 60 · 34 tiles · 9 words · 8 B =
//! 147 KB (the page table: 4 B per page of the key space ×2, 8 B per slot of each touched page).
//! Workgroup memory: [`SHARED_WORDS`] words.
use crate::coop::{Coop, SharedU32};
use crate::layout::ClusterGrid;

/// Invocations of the tile kernel's workgroup.
pub const TILE_WORKGROUP: u32 = 256;
/// Most mask words a tile may have: the tile path serves grids of up to [`MAX_TILE_SLICES`]
/// slices.
pub const MAX_MASK_WORDS: u32 = 64;
/// Most depth slices the tile path serves (the page table serves more).
pub const MAX_TILE_SLICES: u32 = 32 * MAX_MASK_WORDS;
/// Workgroup memory of the tile kernel: the mask, the running totals, the tile's first index.
pub const SHARED_WORDS: usize = (2 * MAX_MASK_WORDS + 1) as usize;
/// Words of a tile's record per mask word: the mask and the index of its lowest set bit.
pub const RECORD_WORDS: u32 = 2;
/// Where the running totals start in workgroup memory.
const TOTALS: u32 = MAX_MASK_WORDS;
/// Where the tile's first index lies in workgroup memory.
const FIRST: u32 = 2 * MAX_MASK_WORDS;
/// What a pixel's slice is when it shows no geometry.
pub const NO_SLICE: u32 = u32::MAX;

/// Words of one tile's slice mask: `⌈S / 32⌉`.
#[inline]
pub fn mask_words(g: &ClusterGrid) -> u32 {
    g.num_slices.div_ceil(32)
}

/// Words of the records of every tile.
#[inline]
pub fn record_words(g: &ClusterGrid) -> u32 {
    g.tiles_x * g.tiles_y * mask_words(g) * RECORD_WORDS
}

/// Whether the tile path can serve `g` (its mask fits the kernel's workgroup memory).
#[inline]
pub fn serves(g: &ClusterGrid) -> bool {
    g.num_slices <= MAX_TILE_SLICES
}

/// Pixel rectangle `(x0, y0, w, h)` of tile `(i, j)` (the last row and column of tiles may be
/// partial).
#[inline]
pub fn tile_rect(g: &ClusterGrid, i: u32, j: u32) -> (u32, u32, u32, u32) {
    let (x0, y0) = (i * g.tile_size, j * g.tile_size);
    let w = if x0 + g.tile_size <= g.width { g.tile_size } else { g.width - x0 };
    let h = if y0 + g.tile_size <= g.height { g.tile_size } else { g.height - y0 };
    (x0, y0, w, h)
}

/// Pixel `(x, y)` number `q < w·h` (row-major) of tile rectangle `(x0, y0, w, h)`.
#[inline]
pub fn tile_pixel(rect: (u32, u32, u32, u32), q: u32) -> (u32, u32) {
    let (x0, y0, w, _) = rect;
    (x0 + q % w, y0 + q / w)
}

/// Steps 1–3 for one tile, by every invocation of its workgroup: `slice_of(s, q)` is the slice
/// of the tile's pixel `q < pixels` in sample plane `s < planes` (1 plane without MSAA;
/// [`NO_SLICE`] for background; it may store the pixel's key on the way), `reserve(n)` reserves `n` places in the unique-cluster list and returns the first
/// (called by one invocation). Returns, for invocations `w < words`, mask word `w` and the list
/// index of its lowest set bit; `(0, 0)` for the others.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn tile_clusters<C: Coop, S: SharedU32>(
    c: &C,
    shared: &mut S,
    words: u32,
    pixels: u32,
    planes: u32,
    mut slice_of: impl FnMut(u32, u32) -> u32,
    reserve: impl FnOnce(u32) -> u32,
) -> (u32, u32) {
    let local = c.local_index();
    // 1. Clear the mask.
    if local < words {
        shared.store(local, 0);
    }
    c.workgroup_barrier();
    // 2. Mark each pixel's slice, plane by plane: a pixel number is never divided by the tile's
    // size to find its plane (a division per pixel cost the one-sample kernel 6 %).
    let mut plane = 0;
    while plane < planes {
        let mut q = local;
        while q < pixels {
            let s = slice_of(plane, q);
            if s != NO_SLICE {
                shared.atomic_or(s / 32, 1 << (s % 32));
            }
            q += TILE_WORKGROUP;
        }
        plane += 1;
    }
    c.workgroup_barrier();
    // 3. Running totals and the tile's reservation (at most 64 words: one invocation).
    if local == 0 {
        let mut total = 0;
        let mut w = 0;
        while w < words {
            shared.store(TOTALS + w, total);
            total += shared.load(w).count_ones();
            w += 1;
        }
        shared.store(FIRST, reserve(total));
    }
    c.workgroup_barrier();
    if local < words {
        (shared.load(local), shared.load(FIRST) + shared.load(TOTALS + local))
    } else {
        (0, 0)
    }
}

/// The assignment's dispatch for a unique-cluster list that ends at `end` (`per_group`
/// clusters per workgroup) as the words a tile raises: its workgroups per row, and its rows
/// (above 1 only past `indirect::MAX_GROUPS_PER_AXIS` workgroups; the depth and at least one row
/// are raised once per frame). Both never decrease as `end` grows, so the largest end wins.
#[inline]
pub fn dispatch_raise(end: u32, per_group: u32) -> (u32, u32) {
    let d = crate::indirect::dispatch_args(end, per_group);
    (d[0], d[1])
}

/// Step 4 for mask word `w` of tile `(i, j)`: `emit(index, key)` for each cluster of the word
/// (slice `32w + b` for each set bit `b`), at its list index from `first` on.
#[inline]
pub fn emit_word_clusters(g: &ClusterGrid, i: u32, j: u32, w: u32, mask: u32, first: u32, mut emit: impl FnMut(u32, u32)) {
    let mut bits = mask;
    let mut n = 0;
    while bits != 0 {
        let b = bits.trailing_zeros();
        emit(first + n, g.pack(i, j, 32 * w + b));
        bits &= bits - 1;
        n += 1;
    }
}

/// Word of `records` where the record of mask word `w` of tile `(i, j)` starts.
#[inline]
pub fn record_at(g: &ClusterGrid, i: u32, j: u32, w: u32) -> u32 {
    ((j * g.tiles_x + i) * mask_words(g) + w) * RECORD_WORDS
}

/// The list index of the cluster of `key` (a key some pixel of the frame has): the index of its
/// mask word's lowest set bit plus the set bits below its own.
#[inline]
pub fn cluster_of_key(g: &ClusterGrid, records: &[u32], key: u32) -> u32 {
    let (i, j, k) = g.unpack(key);
    let at = record_at(g, i, j, k / 32) as usize;
    let below = records[at] & ((1u32 << (k % 32)) - 1);
    records[at + 1] + below.count_ones()
}

/// The end of the frame on the tile path, by one invocation of the shading kernel (the last
/// reader of both): the frame's cluster count to `COUNTER_FRAME_CLUSTERS` for the host, then
/// the count and the assignment's dispatch zeroed for the next frame's atomics.
#[inline]
pub fn hand_over_counters(counters: &mut [u32], args: &mut [u32]) {
    use crate::layout::{ARGS_ASSIGNMENT, COUNTER_FRAME_CLUSTERS, COUNTER_UNIQUE_CLUSTERS};
    counters[COUNTER_FRAME_CLUSTERS as usize] = counters[COUNTER_UNIQUE_CLUSTERS as usize];
    counters[COUNTER_UNIQUE_CLUSTERS as usize] = 0;
    let a = ARGS_ASSIGNMENT as usize;
    args[a] = 0;
    args[a + 1] = 0;
    args[a + 2] = 0;
}

#[cfg(test)]
#[path = "tile_clusters_tests.rs"]
mod tests;
