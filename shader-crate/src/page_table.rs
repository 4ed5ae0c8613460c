//! Unique clusters through a virtual page table (Karas' Vulkan design of Olsson et al. 2012's
//! clustered shading, §"finding unique clusters"), made deterministic with prefix sums.
//!
//! The key space (`2^(bits_i+bits_j+bits_k)` keys) is cut into pages of [`PAGE_SIZE`] = 512
//! keys. Only pages some pixel touches get physical storage:
//! 1. **keys** — per pixel: its cluster key ([`pixel_key`]; background pixels get
//!    [`INVALID_KEY`]).
//! 2. **mark** — per pixel: `marks[key >> 9] = 1` (idempotent same-value stores).
//! 3. **allocate** — exclusive scan of `marks` → `page_base[p]` (dense index of marked page `p`,
//!    in page order); marked pages also record `page_of_alloc[page_base[p]] = p`.
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
