//! Forward+ (Harada, McKee, Yang 2012, "Forward+: Bringing Deferred Lighting to the Next Level",
//! Eurographics short papers): light culling between a depth pre-pass and a forward shading pass.
//! Two layouts of the per-tile light lists (`render --fp-lists`): **linked** lists built with
//! atomics, and contiguous **arrays**, one range of an index buffer per tile.
//!
//! # Steps
//!
//! 1. **Depth pre-pass** (raster, `raster_forward::depth_fs*`): depth only, reversed-Z as the
//!    G-buffer pass, copied into a buffer.
//! 2. **Culling** (compute, one workgroup per screen tile): the tile's depth bounds and frustum
//!    exactly as `tiled` ([`crate::tile_cull`]: [`tile_bounds`], [`TileCull::keeps_pair`]),
//!    lights tested [`LIGHTS_PER_INVOCATION`] per invocation per batch of [`CULL_BATCH`]
//!    (the array variant ranks a batch's survivors with [`TileCull::keep_batch`], as `tiled`).
//!    * **linked** ([`cull_tile`]): each surviving light gets a node of a per-tile linked list:
//!      node slots come from one atomic counter (reserved once per subgroup,
//!      [`subgroup_reserve`]); the node is pushed on the tile's list by an atomic exchange of the
//!      tile's head (`next = exchange(head[tile], node)`). List order is the atomics' order.
//!    * **array** ([`cull_tile_array`]): the workgroup itself writes its tile's array; no linked
//!      list exists. Survivors are appended in light-index order through a workgroup prefix sum
//!      to a staging list in workgroup memory ([`STAGE_CAPACITY`] entries) while a whole batch
//!      still fits; the scans' totals count every survivor. Once every light is tested the
//!      workgroup knows its tile's count and reserves its range with one atomic add on the
//!      counter (invocation 0), copies the staged entries out (coalesced), culls the lights
//!      after the stage filled up a second time writing them straight to the range, and writes
//!      the tile's `(offset, count)`. A tile of more than [`STAGE_CAPACITY`] lights therefore
//!      costs work (those lights are tested twice), never capacity: nothing is dropped, and the
//!      staging list's size is fixed whatever the light count. Both passes run the same loop
//!      body, so a light is kept or rejected by the very same instructions each time, and
//!      writes are clamped to the reserved range.
//! 3. **Forward pass** (raster, `raster_forward::forward_fs*`): the scene again with depth test
//!    EQUAL and no depth writes — one shaded fragment per pixel, no overdraw — each fragment
//!    summing its tile's lights with the light loop of every technique
//!    ([`crate::shading::shade_lights`]): the linked variant walks its tile's list
//!    ([`crate::shading::linked_lights`]: one dependent load per light), the array variant reads
//!    `(offset, count)` and a contiguous index range ([`crate::shading::index_range`], as the
//!    clustered techniques read their lists).
//!
//! **Why the culling workgroup writes the array** (rather than a compaction pass that walks the
//! linked lists afterwards): walking a list is serial — one dependent load per light, however
//! many invocations own the tile —, so a compaction pass would add, per tile, the latency of one
//! whole walk after the culling, and it needs the linked list and the array in memory at once
//! (12 B per light reference). The culling workgroup already holds its survivors in index order
//! and knows their count after its prefix sums; writing the array there costs one atomic per
//! tile and, only for tiles longer than the staging list, a second culling pass over the lights
//! after that point. The array is in light-index order, the order `deferred` and `tiled` sum in.
//!
//! **Capacity.** The node (linked) or index (array) buffer has a capacity; the counter ends at
//! the light references the frame needs. Entries past the capacity are not written; the host
//! sees the counter, grows the buffer and re-runs the frame (shading of an overflowed frame
//! writes background).
//!
//! **llvmpipe's loop limiter**: the host allows [`MAX_LIGHTS_LLVMPIPE`] lights there (the forward
//! pass takes one loop iteration per light of the tile; the array variant's culling takes at
//! most two passes of `N / CULL_BATCH` batches).
//!
//! **Memory** (one counter, a depth and a colour target of 4 B per pixel each besides):
//! * linked: heads 4 B per tile, nodes 8 B per light reference (light, next); workgroup memory
//!   [`TILE_CULL_SHARED_WORDS`] words (1 KiB);
//! * array: ranges 8 B per tile (offset, count), indices 4 B per light reference — half the
//!   linked variant's per-reference bytes; workgroup memory [`FP_ARRAY_SHARED_WORDS`] words
//!   (5 KiB: the tile culling's words, the broadcast range base and the staging list).
use crate::coop::gpu::GpuCoop;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::light_lists::{subgroup_reserve, AtomicAdd, AtomicExchange, ListSink};
use crate::tile_cull::{tile_bounds, tile_widening, CULL_BATCH, NO_WIDENING, LIGHTS_PER_INVOCATION, TILED_WORKGROUP, TILE_CULL_SHARED_WORDS};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Most lights of a forward+ frame on llvmpipe.
pub const MAX_LIGHTS_LLVMPIPE: u32 = 65_535;

/// Entries of the array variant's staging list (workgroup memory): a tile with more lights
/// tests those after the stage filled up twice.
pub const STAGE_CAPACITY: u32 = 1024;
/// Workgroup-memory layout of the array variant (words): the tile culling's words, the range
/// base broadcast by invocation 0, then the staging list.
pub const SHARED_BASE: u32 = TILE_CULL_SHARED_WORDS;
pub const SHARED_STAGE: u32 = SHARED_BASE + 1;
pub const FP_ARRAY_SHARED_WORDS: usize = (SHARED_STAGE + STAGE_CAPACITY) as usize;
const _: () = assert!(FP_ARRAY_SHARED_WORDS * 4 <= 32 * 1024, "lavapipe has 32 KiB of workgroup memory");
const _: () = assert!(CULL_BATCH <= STAGE_CAPACITY);

/// Pushes `light` as node `node` on the list whose head is `head` (if the node fits).
#[inline]
fn push<H: AtomicExchange + ?Sized, L: ListSink + ?Sized>(head: &mut H, nodes: &mut L, node: u32, light: u32, capacity: u32) {
    if node < capacity {
        nodes.put(2 * node, light);
        let next = head.exchange(node);
        nodes.put(2 * node + 1, next);
    }
}

/// Step 2 of the linked variant for one invocation of tile `(tx, ty)`: depth bounds, frustum
/// (and the 2.5D mask with `p.mode == MODE_TILED_25D`), batches of lights pushed on the tile's
/// list. Returns the lights this invocation pushed. Called by every invocation of the workgroup.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn cull_tile<C: Coop, S: SharedU32 + ?Sized, A: AtomicAdd + ?Sized, H: AtomicExchange + ?Sized, L: ListSink + ?Sized>(
    c: &C,
    s: &mut S,
    p: &TiledParams,
    tx: u32,
    ty: u32,
    depth: &[f32],
    lights: &[PointLight],
    counter: &mut A,
    head: &mut H,
    nodes: &mut L,
    capacity: u32,
    widen: (u32, u32),
) -> u32 {
    let li = c.local_index();
    let (_, cull) = tile_bounds(c, s, &p.frame.grid, tx, ty, p.mode, depth, widen);
    let n = p.frame.num_lights;
    let mut pushed = 0;
    let mut next = if cull.empty { n } else { 0 };
    let batch = c.num_subgroups() * c.subgroup_size() * LIGHTS_PER_INVOCATION;
    while next < n {
        let first = next + li * LIGHTS_PER_INVOCATION;
        let (a, b) = cull.keeps_pair(lights, n, first, p.frame.effects);
        let base = subgroup_reserve(c, counter, a as u32 + b as u32);
        if a {
            push(head, nodes, base, first, capacity);
        }
        if b {
            push(head, nodes, base + a as u32, first + 1, capacity);
        }
        pushed += a as u32 + b as u32;
        next += batch;
    }
    pushed
}

/// Declares one culling entry (one workgroup of 256 per tile, `(wg.x, wg.y)` = tile) over
/// bindings 0–4 and the `$extra` ones, with `$widen` bound to `$widen_expr` for `$body`.
macro_rules! cull_entry {
    (
        $entry:ident, $doc:expr, $shared:expr, [$($extra:tt)*], $widen:ident = $widen_expr:expr,
        |$c:ident, $shared_arg:ident, $p:ident, $wg:ident, $local:ident, $depth:ident, $lights:ident, $counters:ident, $tiles:ident, $entries:ident| $body:block
    ) => {
        #[doc = $doc]
        #[spirv(compute(threads(256)))]
        #[allow(clippy::too_many_arguments)]
        pub fn $entry(
            #[spirv(workgroup_id)] $wg: UVec3,
            #[spirv(local_invocation_index)] $local: u32,
            #[spirv(subgroup_size)] subgroup_size: u32,
            #[spirv(subgroup_local_invocation_id)] lane: u32,
            #[spirv(subgroup_id)] subgroup_id: u32,
            #[spirv(num_subgroups)] num_subgroups: u32,
            #[spirv(push_constant)] $p: &TiledParams,
            #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
            #[spirv(workgroup)] $shared_arg: &mut [u32; $shared],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] $depth: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] $lights: &[PointLight],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] $counters: &mut [u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] $tiles: &mut [u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] $entries: &mut [u32],
            $($extra)*
        ) {
            let $p = &crate::light_types::specialise($p, light_types);
            let $c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index: $local };
            let $widen = $widen_expr;
            $body
        }
    };
}

/// Declares a culling entry over `$body` and its `_widened` twin: binding 5 holds the transparent
/// fragments' depth range per tile (`TILE_DEPTH_WORDS`), which the tile's bounds then span
/// (scenes with transparent draws; the plain entry reads no such buffer).
macro_rules! cull_entries {
    ($plain:ident, $widened:ident, $shared:expr, |$c:ident, $s:ident, $p:ident, $wg:ident, $local:ident, $depth:ident, $lights:ident, $counters:ident, $tiles:ident, $entries:ident, $widen:ident| $body:block) => {
        cull_entry!(
            $plain, concat!("Step 2: `", stringify!($plain), "`, bounds from the opaque depth only."), $shared, [], $widen = NO_WIDENING,
            |$c, $s, $p, $wg, $local, $depth, $lights, $counters, $tiles, $entries| $body
        );
        cull_entry!(
            $widened, concat!("Step 2: `", stringify!($plain), "` with bounds widened to the tile's transparent fragments."), $shared,
            [#[spirv(storage_buffer, descriptor_set = 0, binding = 5)] tile_depths: &[u32],],
            $widen = tile_widening(tile_depths, $wg.y * $p.frame.grid.tiles_x + $wg.x),
            |$c, $s, $p, $wg, $local, $depth, $lights, $counters, $tiles, $entries| $body
        );
    };
}

cull_entries!(forward_plus_cull, forward_plus_cull_widened, TILE_CULL_SHARED_WORDS as usize, |c, shared, p, wg, local_index, depth, lights, counters, heads, nodes, widen| {
    // Step 2 of the linked variant; `p.frame.light_capacity` = node capacity.
    let tile = (wg.y * p.frame.grid.tiles_x + wg.x) as usize;
    cull_tile(&c, shared, p, wg.x, wg.y, depth, lights, &mut counters[FP_COUNTER_REFS as usize], &mut heads[tile], nodes, p.frame.light_capacity, widen);
});

/// A tile's list in the array variant: entries `offset..offset + count` of the index buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileRange {
    pub offset: u32,
    pub count: u32,
}

/// Writes `light` as entry `at` of the range reserved at `base` for `count` entries, if it lies
/// in that range and below the buffer's `capacity`.
#[inline]
fn put_in_range<L: ListSink + ?Sized>(indices: &mut L, base: u32, at: u32, count: u32, light: u32, capacity: u32) {
    let i = base.wrapping_add(at);
    if at < count && i < capacity {
        indices.put(i, light);
    }
}

/// Reserves `count` entries of `counter` for the workgroup (one atomic add, by invocation 0;
/// none for an empty tile) and returns the first to every invocation. Uniform control flow.
#[inline]
fn reserve_range<C: Coop, S: SharedU32 + ?Sized, A: AtomicAdd + ?Sized>(c: &C, s: &mut S, counter: &mut A, count: u32) -> u32 {
    if c.local_index() == 0 {
        let base = if count > 0 { counter.fetch_add(count) } else { 0 };
        s.store(SHARED_BASE, base);
    }
    c.workgroup_barrier();
    s.load(SHARED_BASE)
}

/// Step 2 of the array variant for one invocation of tile `(tx, ty)` (module docs): culls every
/// light, staging the survivors in index order; reserves the tile's range; copies the stage out
/// and writes the survivors past it in a second pass over the lights after the stage filled up.
/// Returns the tile's range (the same for every invocation). Called by every invocation of the
/// workgroup (it synchronises).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn cull_tile_array<C: Coop, S: SharedU32 + ?Sized, A: AtomicAdd + ?Sized, L: ListSink + ?Sized>(
    c: &C,
    s: &mut S,
    p: &TiledParams,
    tx: u32,
    ty: u32,
    depth: &[f32],
    lights: &[PointLight],
    counter: &mut A,
    indices: &mut L,
    capacity: u32,
    widen: (u32, u32),
) -> TileRange {
    let li = c.local_index();
    let (_, cull) = tile_bounds(c, s, &p.frame.grid, tx, ty, p.mode, depth, widen);
    let n = p.frame.num_lights;
    // Workgroup-uniform state: survivors counted (first pass), staged, the first batch not
    // staged (`n`: none), whether the range is reserved (second pass), entries written.
    let (mut count, mut staged, mut resume) = (0u32, 0u32, n);
    let (mut writing, mut written, mut base) = (false, 0u32, 0u32);
    let mut next = if cull.empty { n } else { 0 };
    while next < n {
        let kept = cull.keep_batch(c, s, lights, n, next, p.frame.effects);
        if writing {
            kept.emit(|k, light| put_in_range(indices, base, written + k, count, light, capacity));
            written += kept.total;
        } else {
            if resume == n && count + CULL_BATCH > STAGE_CAPACITY {
                resume = next;
            }
            if resume == n {
                kept.emit(|k, light| s.store(SHARED_STAGE + count + k, light));
                staged += kept.total;
            }
            count += kept.total;
        }
        next += CULL_BATCH;
        c.workgroup_barrier();
        if !writing && next >= n {
            // Every light tested: reserve the range, copy the stage out, then (if the stage
            // filled up) test the lights after it again.
            base = reserve_range(c, s, counter, count);
            let mut t = li;
            while t < staged {
                put_in_range(indices, base, t, count, s.load(SHARED_STAGE + t), capacity);
                t += TILED_WORKGROUP;
            }
            writing = true;
            written = staged;
            next = resume;
        }
    }
    TileRange { offset: base, count }
}

cull_entries!(forward_plus_cull_array, forward_plus_cull_array_widened, FP_ARRAY_SHARED_WORDS, |c, shared, p, wg, local_index, depth, lights, counters, ranges, indices, widen| {
    // Step 2 of the array variant: writes the tile's `(offset, count)` at `ranges[2·tile]`;
    // `p.frame.light_capacity` = index capacity.
    let r = cull_tile_array(&c, shared, p, wg.x, wg.y, depth, lights, &mut counters[FP_COUNTER_REFS as usize], indices, p.frame.light_capacity, widen);
    if local_index == 0 {
        let tile = 2 * (wg.y * p.frame.grid.tiles_x + wg.x) as usize;
        ranges[tile] = r.offset;
        ranges[tile + 1] = r.count;
    }
});

#[cfg(test)]
#[path = "forward_plus_tests.rs"]
mod tests;
