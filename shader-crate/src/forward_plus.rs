//! Forward+ (Harada, McKee, Yang 2012, "Forward+: Bringing Deferred Lighting to the Next Level",
//! Eurographics short papers): light culling between a depth pre-pass and a forward shading pass.
//!
//! # Steps
//!
//! 1. **Depth pre-pass** (raster, `raster_forward::depth_fs*`): depth only, reversed-Z as the
//!    G-buffer pass, copied into a buffer.
//! 2. **Culling** ([`cull_tile`], compute, one workgroup per screen tile): the tile's depth bounds
//!    and frustum exactly as `tiled` ([`crate::tiled`]: [`crate::tiled::sphere_in_tile`]), lights
//!    tested [`LIGHTS_PER_INVOCATION`] per invocation per batch; each surviving light gets a node
//!    of a per-tile **linked list**: node slots come from one atomic counter (reserved once per
//!    subgroup, [`subgroup_reserve`]); the node is pushed on the tile's list by an atomic exchange
//!    of the tile's head (`next = exchange(head[tile], node)`).
//! 3. **Forward pass** (raster, `raster_forward::forward_fs*`): the scene again with depth test
//!    EQUAL and no depth writes — one shaded fragment per pixel, no overdraw — each walking its
//!    tile's list.
//!
//! **Capacity.** The node buffer has a capacity; the counter ends at the nodes the frame needs.
//! Nodes past the capacity are not linked; the host sees the counter, grows the buffer and
//! re-runs the frame (shading of an overflowed frame writes background).
//!
//! **llvmpipe's loop limiter**: a list is walked one node per iteration, so a tile may list at
//! most 65 535 lights there; the host allows [`MAX_LIGHTS_LLVMPIPE`] lights.
//!
//! **Memory**: heads 4 B per tile, nodes 8 B per light reference (light, next), one counter; the
//! depth target and a colour target (4 B per pixel each).
use crate::clustered_aabb::{subgroup_reserve, AtomicAdd, ListSink};
use crate::coop::gpu::GpuCoop;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::reconstruct;
use crate::tiled::{depth_cells, depth_cell, keep_light, slot_pixel, tile_frustum, workgroup_min_max, workgroup_or, MAX_PIXELS_PER_INVOCATION, MODE_TILED_25D, NO_PIXEL, TILED_SHARED_WORDS};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Lights each invocation tests per batch.
pub const LIGHTS_PER_INVOCATION: u32 = 2;
/// End of a tile's list.
pub const NO_NODE: u32 = u32::MAX;
/// Counter slot of the node allocator.
pub const FP_COUNTER_NODES: u32 = 0;
/// Most lights of a forward+ frame on llvmpipe (one list node per loop iteration).
pub const MAX_LIGHTS_LLVMPIPE: u32 = 65_535;

/// A word that can be swapped atomically (`OpAtomicExchange` on the GPU; plain off the GPU).
pub trait AtomicExchange {
    fn exchange(&mut self, v: u32) -> u32;
}

impl AtomicExchange for u32 {
    #[inline]
    fn exchange(&mut self, v: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_exchange::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(self, v)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            core::mem::replace(self, v)
        }
    }
}

#[cfg(not(target_arch = "spirv"))]
impl AtomicExchange for &std::sync::atomic::AtomicU32 {
    fn exchange(&mut self, v: u32) -> u32 {
        std::sync::atomic::AtomicU32::swap(self, v, std::sync::atomic::Ordering::Relaxed)
    }
}

/// Pushes `light` as node `node` on the list whose head is `head` (if the node fits).
#[inline]
fn push<H: AtomicExchange + ?Sized, L: ListSink + ?Sized>(head: &mut H, nodes: &mut L, node: u32, light: u32, capacity: u32) {
    if node < capacity {
        nodes.put(2 * node, light);
        let next = head.exchange(node);
        nodes.put(2 * node + 1, next);
    }
}

/// Step 2 for one invocation of tile `(tx, ty)`: depth bounds, frustum (and the 2.5D mask with
/// `p.mode == MODE_TILED_25D`), batches of lights pushed on the tile's list. Returns the lights
/// this invocation pushed. Called by every invocation of the workgroup.
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
) -> u32 {
    let g = &p.frame.grid;
    let li = c.local_index();
    let (mut lo, mut hi) = (f32::MAX.to_bits(), 0u32);
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = slot_pixel(g, tx, ty, li, slot);
        if i != NO_PIXEL && !reconstruct::is_background(depth[i as usize]) {
            let b = reconstruct::distance_from_depth(g.near, depth[i as usize]).to_bits();
            lo = if b < lo { b } else { lo };
            hi = if b > hi { b } else { hi };
        }
        slot += 1;
    }
    let (lo, hi) = workgroup_min_max(c, s, lo, hi);
    let empty = lo > hi;
    let (d_min, d_max) = (f32::from_bits(lo), f32::from_bits(hi));
    let frustum = tile_frustum(g, tx, ty, d_min, d_max);
    let cells = depth_cells(d_min, d_max);
    let mut tile_mask = u32::MAX;
    if p.mode == MODE_TILED_25D && !empty {
        let mut mine = 0;
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            let i = slot_pixel(g, tx, ty, li, slot);
            if i != NO_PIXEL && !reconstruct::is_background(depth[i as usize]) {
                mine |= 1u32 << depth_cell(&cells, reconstruct::distance_from_depth(g.near, depth[i as usize]));
            }
            slot += 1;
        }
        tile_mask = workgroup_or(c, s, mine);
    }
    let n = p.frame.num_lights;
    let mut pushed = 0;
    let mut next = if empty { n } else { 0 };
    let batch = c.num_subgroups() * c.subgroup_size() * LIGHTS_PER_INVOCATION;
    while next < n {
        let first = next + li * LIGHTS_PER_INVOCATION;
        let a = first < n && keep_light(&frustum, &cells, tile_mask, p.mode, &lights[first as usize]);
        let b = first + 1 < n && keep_light(&frustum, &cells, tile_mask, p.mode, &lights[first as usize + 1]);
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

/// Step 2: one workgroup of 256 per tile, `(wg.x, wg.y)` = tile; `p.frame.light_capacity` =
/// node capacity.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn forward_plus_cull(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &TiledParams,
    #[spirv(workgroup)] shared: &mut [u32; TILED_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] counters: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] heads: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] nodes: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let tile = (wg.y * p.frame.grid.tiles_x + wg.x) as usize;
    cull_tile(&c, shared, p, wg.x, wg.y, depth, lights, &mut counters[FP_COUNTER_NODES as usize], &mut heads[tile], nodes, p.frame.light_capacity);
}

#[cfg(test)]
#[path = "forward_plus_tests.rs"]
mod tests;
