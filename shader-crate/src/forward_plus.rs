//! Forward+ (Harada, McKee, Yang 2012, "Forward+: Bringing Deferred Lighting to the Next Level",
//! Eurographics short papers): light culling between a depth pre-pass and a forward shading pass.
//!
//! # Steps
//!
//! 1. **Depth pre-pass** (raster, `raster_forward::depth_fs*`): depth only, reversed-Z as the
//!    G-buffer pass, copied into a buffer.
//! 2. **Culling** ([`cull_tile`], compute, one workgroup per screen tile): the tile's depth bounds
//!    and frustum exactly as `tiled` ([`crate::tile_cull`]: [`tile_bounds`],
//!    [`TileCull::keeps_pair`]), lights tested [`LIGHTS_PER_INVOCATION`] per invocation per batch;
//!    each surviving light gets a node of a per-tile **linked list**: node slots come from one
//!    atomic counter (reserved once per subgroup, [`subgroup_reserve`]); the node is pushed on the
//!    tile's list by an atomic exchange of the tile's head (`next = exchange(head[tile], node)`).
//! 3. **Forward pass** (raster, `raster_forward::forward_fs*`): the scene again with depth test
//!    EQUAL and no depth writes — one shaded fragment per pixel, no overdraw — each walking its
//!    tile's list ([`crate::shading::linked_lights`], [`crate::shading::shade_lights`]).
//!
//! **Capacity.** The node buffer has a capacity; the counter ends at the nodes the frame needs.
//! Nodes past the capacity are not linked; the host sees the counter, grows the buffer and
//! re-runs the frame (shading of an overflowed frame writes background).
//!
//! **llvmpipe's loop limiter**: the host allows [`MAX_LIGHTS_LLVMPIPE`] lights there (the forward
//! pass walks 16 nodes per loop iteration; the limit predates that and stays conservative).
//!
//! **Memory**: heads 4 B per tile, nodes 8 B per light reference (light, next), one counter; the
//! depth target and a colour target (4 B per pixel each); workgroup memory
//! [`TILE_CULL_SHARED_WORDS`] words (1 KiB).
use crate::coop::gpu::GpuCoop;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::light_lists::{subgroup_reserve, AtomicAdd, AtomicExchange, ListSink};
use crate::tile_cull::{tile_bounds, LIGHTS_PER_INVOCATION, TILE_CULL_SHARED_WORDS};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Counter slot of the node allocator.
pub const FP_COUNTER_NODES: u32 = 0;
/// Most lights of a forward+ frame on llvmpipe.
pub const MAX_LIGHTS_LLVMPIPE: u32 = 65_535;

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
    let li = c.local_index();
    let (_, cull) = tile_bounds(c, s, &p.frame.grid, tx, ty, p.mode, depth);
    let n = p.frame.num_lights;
    let mut pushed = 0;
    let mut next = if cull.empty { n } else { 0 };
    let batch = c.num_subgroups() * c.subgroup_size() * LIGHTS_PER_INVOCATION;
    while next < n {
        let first = next + li * LIGHTS_PER_INVOCATION;
        let (a, b) = cull.keeps_pair(lights, n, first);
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
    #[spirv(workgroup)] shared: &mut [u32; TILE_CULL_SHARED_WORDS as usize],
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
