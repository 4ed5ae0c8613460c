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
//!    about 6 µs, more than scanning them in one workgroup.
//! 4. **store** — per pixel: `slots[page_base[key >> 9]·512 + (key & 511)] = 1`.
//! 5. **compact** — exclusive scan of `slots` → `slot_rank`; per set slot `s`:
//!    `unique[slot_rank[s]] = key_of_slot(s)`.
//!
//! Marks and slots start at zero once (at allocation) and each is cleared by its last reader
//! (allocation clears the marks it records, compaction the slots it scatters), so a frame touches
//! the slots of its own pages only and never clears a table at capacity. Because pages are allocated in page order and
//!    slots scanned in order, `unique` is the *sorted* list of distinct keys, and
//!    `slot_rank[slot of key]` is the cluster index a pixel uses to find its light list.
//!
//! Memory (derived from the resolution, never hard-coded): `marks` + `page_base` = 2 × 4 B per
//! page of the key space (e.g. 1920×1080, 32 px tiles: 2^6·2^6·2^9 keys / 512 = 4096 pages →
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

/// Invocations of the page-allocation workgroup.
pub const ALLOCATE_WORKGROUP: u32 = crate::scan::SCAN_WORKGROUP;

/// The contiguous run of pages invocation `local` of the allocation workgroup allocates.
#[inline]
pub fn allocate_span(pages: u32, local: u32) -> (u32, u32) {
    let per = pages.div_ceil(ALLOCATE_WORKGROUP);
    let start = local * per;
    let end = start + per;
    (if start < pages { start } else { pages }, if end < pages { end } else { pages })
}

/// Step 3, part 1 (every invocation of the one workgroup): the marked pages of this invocation's
/// run, scanned over the workgroup → (dense index of its first marked page, pages marked in all).
#[inline]
pub fn allocate_scan<C: Coop, S: SharedU32 + ?Sized>(c: &C, shared: &mut S, pages: u32, marks: &[u32]) -> (u32, u32) {
    let (start, end) = allocate_span(pages, c.local_index());
    let mut marked = 0;
    let mut i = start;
    while i < end {
        marked += (marks[i as usize] != 0) as u32;
        i += 1;
    }
    crate::scan::workgroup_exclusive_scan(c, shared, marked)
}

/// Step 3, part 2: invocation `local` numbers its run from `base`: `page_base` of each page,
/// `page_of_alloc` of each marked page that fits `capacity` allocated pages, and its mark cleared
/// (the mark's last reader).
#[inline]
pub fn allocate_run(pages: u32, local: u32, base: u32, capacity: u32, marks: &mut [u32], page_base: &mut [u32], page_of_alloc: &mut [u32]) {
    let (start, end) = allocate_span(pages, local);
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
}
