//! Unique clusters through a virtual page table (Karas' Vulkan design of Olsson et al. 2012's
//! clustered shading, §"finding unique clusters"), made deterministic with prefix sums.
//!
//! The key space (`2^(bits_i+bits_j+bits_k)` keys) is cut into pages of [`PAGE_SIZE`] = 512
//! keys. Only pages some pixel touches get physical storage:
//! 1. **keys** — per pixel: its cluster key ([`pixel_key`]; background pixels get
//!    [`INVALID_KEY`]).
//! 2. **mark** — per pixel: `marks[key >> 9] = 1` (idempotent same-value stores).
//! 3. **allocate** — exclusive scan of `marks` → `page_base[p]` (dense index of marked page `p`,
//!    in page order); marked pages also record `page_of_alloc[page_base[p]] = p`. One workgroup
//!    does it all ([`allocate_scan`], [`allocate_run`]): the key space has few pages (4096 at
//!    1080p, 16 384 at 4K), and on the H200 each dependent dispatch of a device-wide scan costs
//!    about 6 µs, more than scanning them in one workgroup. Steps 3 and 5 take 4 dispatches in
//!    all, where device-wide scans of the marks and of the slots took 14.
//! 4. **store** — per pixel: `slots[page_base[key >> 9]·512 + (key & 511)] = 1`.
//! 5. **compact** — exclusive scan of `slots` → `slot_rank`; per set slot `s`:
//!    `unique[slot_rank[s]] = key_of_slot(s)`. In three dispatches over the allocated pages: a
//!    workgroup per page counts its set slots ([`page_slot_scan`]), one workgroup scans the
//!    pages' counts ([`run_scan`]), a workgroup per page ranks its slots from its page's offset
//!    (the same [`page_slot_scan`]) and scatters them. Only set slots get a rank: nothing reads
//!    the rank of an unset one (a fragment's lookup checks `unique[rank] == key`).
//!
//! Marks and slots start at zero once (at allocation) and each is cleared by its last reader
//! (allocation clears the marks it records, compaction the slots it scatters), so a frame touches
//! the slots of its own pages only and never clears a table at capacity. Because pages are allocated in page order and
//!    slots scanned in order, `unique` is the *sorted* list of distinct keys, and
//!    `slot_rank[slot of key]` is the cluster index a pixel uses to find its light list.
//!
//! Memory (derived from the resolution, never hard-coded): `marks` + `page_base` = 2 × 4 B per
//! page of the key space; the allocated pages' slot counts and offsets 2 × 4 B per allocatable page (e.g. 1920×1080, 32 px tiles: 2^6·2^6·2^9 keys / 512 = 4096 pages →
//! 32 KiB; Karas' 7-bit-k seed layout: 2^12 pages, 16 KiB per table); `slots` + `slot_rank` =
//! 2 × 4 B × 512 × min(pages, pixels) (every pixel allocates at most one page);
//! `unique` = 4 B × min(keys, pixels).
use crate::cluster_key::ClusterGrid;
use crate::coop::{Coop, SharedU32};
use crate::layout::{PAGE_SHIFT, PAGE_SIZE};
use crate::reconstruct;

/// Key of a pixel that shows no geometry.
pub const INVALID_KEY: u32 = u32::MAX;

/// Step 1: the cluster key of a pixel from its reversed-Z depth.
#[inline]
pub fn pixel_key(grid: &ClusterGrid, bounds: &[f32], px: u32, py: u32, depth: f32) -> u32 {
    if reconstruct::is_background(depth) {
        return INVALID_KEY;
    }
    let d = reconstruct::distance_from_depth(grid.near, depth);
    grid.key(bounds, px, py, -d)
}

#[inline]
pub fn page_of(key: u32) -> u32 {
    key >> PAGE_SHIFT
}

#[inline]
pub fn slot_in_page(key: u32) -> u32 {
    key & (PAGE_SIZE - 1)
}

/// Step 4: index into `slots` of a key whose page has dense index `base`.
#[inline]
pub fn slot_index(base: u32, key: u32) -> u32 {
    base * PAGE_SIZE + slot_in_page(key)
}

/// Step 5: the key a slot stands for.
#[inline]
pub fn key_of_slot(page_of_alloc: &[u32], s: u32) -> u32 {
    (page_of_alloc[(s / PAGE_SIZE) as usize] << PAGE_SHIFT) | (s % PAGE_SIZE)
}

/// Invocations of the page-table workgroups: the one that allocates pages or scans their slot
/// counts, and those that count or compact one page's slots (two slots each).
pub const ALLOCATE_WORKGROUP: u32 = crate::scan::SCAN_WORKGROUP;
const _: () = assert!(PAGE_SIZE == 2 * ALLOCATE_WORKGROUP, "a page's workgroup takes two slots per invocation");

/// The contiguous run of items `0..n` that invocation `local` of a one-workgroup scan takes.
#[inline]
pub fn run_span(n: u32, local: u32) -> (u32, u32) {
    let per = n.div_ceil(ALLOCATE_WORKGROUP);
    let start = local * per;
    let end = start + per;
    (if start < n { start } else { n }, if end < n { end } else { n })
}

/// One workgroup's exclusive scan of `weight(0..n)`, each invocation summing its run
/// ([`run_span`]) first: (the sum before this invocation's run, the sum of all).
#[inline]
pub fn run_scan<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, n: u32, weight: impl Fn(u32) -> u32) -> (u32, u32) {
    let (start, end) = run_span(n, c.local_index());
    let mut sum = 0u32;
    let mut i = start;
    while i < end {
        sum = sum.wrapping_add(weight(i));
        i += 1;
    }
    crate::scan::workgroup_exclusive_scan(c, shared, sum)
}

/// Step 3, part 1 (every invocation of the one workgroup): the marked pages of this invocation's
/// run, scanned over the workgroup → (dense index of its first marked page, pages marked in all).
#[inline]
pub fn allocate_scan<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, pages: u32, marks: &[u32]) -> (u32, u32) {
    run_scan(c, shared, pages, |i| (marks[i as usize] != 0) as u32)
}

/// Step 3, part 2: invocation `local` numbers its run from `base`: `page_base` of each page,
/// `page_of_alloc` of each marked page that fits `capacity` allocated pages, and its mark
/// cleared (the mark's last reader).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn allocate_run(pages: u32, local: u32, base: u32, capacity: u32, marks: &mut [u32], page_base: &mut [u32], page_of_alloc: &mut [u32]) {
    let (start, end) = run_span(pages, local);
    let mut next = base;
    let mut i = start;
    while i < end {
        page_base[i as usize] = next;
        if marks[i as usize] != 0 {
            if next < capacity {
                page_of_alloc[next as usize] = i;
            }
            marks[i as usize] = 0;
            next += 1;
        }
        i += 1;
    }
}

/// The first of the two slots invocation `local` of allocated page `page`'s workgroup takes.
#[inline]
pub fn slot_pair(page: u32, local: u32) -> u32 {
    page * PAGE_SIZE + 2 * local
}

/// Step 5a (one workgroup per allocated page): the page's set slots → (set slots before this
/// invocation's pair in the page, set slots of the page).
#[inline]
pub fn page_slot_scan<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, slots: &[u32], page: u32) -> (u32, u32) {
    let s = slot_pair(page, c.local_index()) as usize;
    let set = (slots[s] != 0) as u32 + (slots[s + 1] != 0) as u32;
    crate::scan::workgroup_exclusive_scan(c, shared, set)
}

/// Pages of the key space of `grid`.
#[inline]
pub fn page_count(grid: &ClusterGrid) -> u32 {
    let bits = grid.bits_i + grid.bits_j + grid.bits_k;
    if bits <= PAGE_SHIFT {
        1
    } else {
        1 << (bits - PAGE_SHIFT)
    }
}

/// CPU reference of steps 1–5: the sorted distinct keys of the valid pixels.
#[cfg(not(target_arch = "spirv"))]
pub fn unique_keys_reference(keys: &[u32]) -> Vec<u32> {
    let mut u: Vec<u32> = keys.iter().copied().filter(|&k| k != INVALID_KEY).collect();
    u.sort_unstable();
    u.dedup();
    u
}

#[cfg(test)]
mod allocate_tests {
    use super::*;
    use crate::coop::cpu::{run_workgroups, Emulation};
    use crate::scan::SCAN_SHARED_WORDS;

    /// The one-workgroup allocation numbers the marked pages in page order (an exclusive scan of
    /// the marks), records each allocated page, clears the marks and counts them, at every
    /// subgroup width and for page counts below, at and past a multiple of the workgroup.
    #[test]
    fn one_workgroup_allocates_the_marked_pages_in_order() {
        let w = ALLOCATE_WORKGROUP;
        for pages in [1, 7, w - 1, w, w + 1, 4096, 4096 + 17, 16384] {
            let marks: Vec<u32> = (0..pages).map(|p| ((p.wrapping_mul(2_654_435_761) >> 13) % 3 == 0 || p == pages - 1) as u32).collect();
            let want_total = marks.iter().sum::<u32>();
            for width in [4, 8, 16, 32, 64] {
                let emu = Emulation { width, workgroup_size: w, shared_words: SCAN_SHARED_WORDS };
                let scans = run_workgroups(emu, 1, |_, c, s| allocate_scan(c, s, pages, &marks));
                let capacity = want_total - want_total / 4; // some pages do not fit
                let (mut m, mut base, mut of_alloc) = (marks.clone(), vec![u32::MAX; pages as usize], vec![u32::MAX; capacity as usize]);
                for (local, &(first, total)) in scans.iter().enumerate() {
                    assert_eq!(total, want_total, "{pages} pages, width {width}");
                    allocate_run(pages, local as u32, first, capacity, &mut m, &mut base, &mut of_alloc);
                }
                let mut next = 0;
                for p in 0..pages as usize {
                    assert_eq!(base[p], next, "{pages} pages, width {width}, page {p}");
                    if marks[p] != 0 {
                        if next < capacity {
                            assert_eq!(of_alloc[next as usize], p as u32);
                        }
                        next += 1;
                    }
                }
                assert!(m.iter().all(|&x| x == 0), "marks cleared");
                assert!(of_alloc.iter().all(|&x| x != u32::MAX), "every allocated page that fits is recorded");
            }
        }
    }

    /// Steps 5a–5c: each allocated page's set slots counted by its workgroup, the counts scanned
    /// by one workgroup, each page's slots ranked from its offset: the ranks of the set slots are
    /// an exclusive scan of all the slots, at every width, for page counts that fill the scan
    /// workgroup's runs unevenly.
    #[test]
    fn pages_count_scan_and_rank_their_slots_as_one_scan() {
        let w = ALLOCATE_WORKGROUP;
        for pages in [1u32, 3, w - 1, w + 5, 700] {
            let n = (pages * PAGE_SIZE) as usize;
            let slots: Vec<u32> = (0..n as u32).map(|s| ((s.wrapping_mul(2_246_822_519) >> 11) % 7 == 0 || s == 1 || s as usize == n - 1) as u32).collect();
            for width in [4, 8, 16, 32, 64] {
                let emu = Emulation { width, workgroup_size: w, shared_words: SCAN_SHARED_WORDS };
                let counted = run_workgroups(emu, pages, |g, c, s| page_slot_scan(c, s, &slots, g));
                let counts: Vec<u32> = (0..pages as usize).map(|g| counted[g * w as usize].1).collect();
                let scanned = run_workgroups(emu, 1, |_, c, s| run_scan(c, s, pages, |i| counts[i as usize]));
                let mut offsets = vec![u32::MAX; pages as usize];
                for (local, &(first, total)) in scanned.iter().enumerate() {
                    assert_eq!(total, slots.iter().sum::<u32>(), "{pages} pages, width {width}");
                    let (start, end) = run_span(pages, local as u32);
                    let mut next = first;
                    for p in start..end {
                        offsets[p as usize] = next;
                        next += counts[p as usize];
                    }
                }
                let ranked = run_workgroups(emu, pages, |g, c, s| page_slot_scan(c, s, &slots, g));
                let mut want = 0;
                for page in 0..pages {
                    for local in 0..w {
                        let (before, _) = ranked[(page * w + local) as usize];
                        let s = slot_pair(page, local) as usize;
                        let rank = offsets[page as usize] + before;
                        assert_eq!(rank, want, "{pages} pages, width {width}, slot {s}");
                        want += slots[s] + slots[s + 1];
                    }
                }
            }
        }
    }
}
