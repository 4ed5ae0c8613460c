//! `#[spirv]` entry points. Each one only unpacks built-ins and buffers, bounds-checks its
//! invocation and calls a pure function from another module. The literal workgroup sizes here
//! must match the handles in [`crate::kernels`] (the GPU parity tests cover every element, so a
//! mismatch fails them).
use crate::coop::gpu::GpuCoop;
use crate::coop::subgroup_item;
use crate::layout::*;
use crate::light_lists::AtomicAdd;
use crate::shading::linear_index;
use crate::{bitonic, debug_view, octahedral, radix, scan};
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Normal encode → decode round trip ([`octahedral`]).
#[spirv(compute(threads(64)))]
pub fn octa_roundtrip(
    #[spirv(global_invocation_id)] gid: UVec3,
    #[spirv(push_constant)] p: &OctaParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] normals: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] encoded: &mut [[u32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] decoded: &mut [[f32; 4]],
) {
    let i = gid.x as usize;
    if gid.x >= p.count {
        return;
    }
    let n = normals[i];
    let precision = octahedral::Precision::from_u32(p.precision);
    let w = octahedral::encode([n[0], n[1], n[2]], precision);
    let d = octahedral::decode(w, precision);
    encoded[i] = [w[0], w[1], w[2], 0];
    decoded[i] = [d[0], d[1], d[2], 0.0];
}

/// Cluster keys of `(pixel, view_z)` samples ([`crate::cluster_key`]).
#[spirv(compute(threads(64)))]
pub fn cluster_keys(
    #[spirv(global_invocation_id)] gid: UVec3,
    #[spirv(push_constant)] p: &ClusterKeyParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] samples: &[KeySample],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] slice_bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] keys: &mut [u32],
) {
    let i = gid.x as usize;
    if gid.x >= p.count {
        return;
    }
    let s = samples[i];
    keys[i] = p.grid.key(slice_bounds, s.px, s.py, s.view_z);
}

/// 30- and 63-bit Morton codes of positions ([`morton`]).
#[spirv(compute(threads(64)))]
pub fn morton_codes(
    #[spirv(global_invocation_id)] gid: UVec3,
    #[spirv(push_constant)] p: &MortonParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] codes30: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] codes63: &mut [[u32; 2]],
) {
    let i = gid.x as usize;
    if gid.x >= p.count {
        return;
    }
    let q = positions[i];
    let pos = [q[0], q[1], q[2]];
    codes30[i] = p.q30.morton30_of(pos);
    let c = p.q63.morton63_of(pos);
    codes63[i] = [c as u32, (c >> 32) as u32];
}

/// Workgroup exclusive scan ([`scan::workgroup_exclusive_scan`]); also writes each workgroup's
/// total. Cooperative: every invocation takes part, out-of-range ones with value 0. Workgroups
/// whose whole range lies past `count` (the tail of a 2D-folded dispatch) write a zero total.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn workgroup_scan(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &ScanParams,
    #[spirv(workgroup)] shared: &mut [u32; scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] input: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] output: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] totals: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    // Large inputs fold into 2D dispatches: workgroup `wg.y · num_wg.x + wg.x`.
    let group = wg.y * nwg.x + wg.x;
    let gi = group * scan::SCAN_WORKGROUP + local_index;
    let v = if gi < p.count { input[gi as usize] } else { 0 };
    let (prefix, total) = scan::workgroup_exclusive_scan(&c, shared, v);
    if gi < p.count {
        output[gi as usize] = prefix;
    }
    if local_index == 0 {
        totals[group as usize] = total;
    }
}

/// A scan over several workgroups, step 2: add each workgroup's offset (the scanned totals of
/// [`workgroup_scan`]) to its elements.
#[spirv(compute(threads(256)))]
pub fn scan_add_offsets(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &ScanFixParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] data: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i < p.count {
        data[i as usize] = data[i as usize].wrapping_add(offsets[(i / crate::scan::SCAN_WORKGROUP) as usize]);
    }
}

/// Debug frame of the analytic scene ([`debug_view`]); 8×8 pixel tiles.
#[spirv(compute(threads(8, 8)))]
pub fn debug_view(
    #[spirv(global_invocation_id)] gid: UVec3,
    #[spirv(push_constant)] p: &DebugViewParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] slice_bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] pixels: &mut [u32],
) {
    if gid.x >= p.grid.width || gid.y >= p.grid.height {
        return;
    }
    pixels[(gid.y * p.grid.width + gid.x) as usize] = debug_view::shade_pixel(p, slice_bounds, gid.x, gid.y);
}

/// Radix sort step 1 ([`crate::radix`]): every pass's digit counts of [`radix::HISTOGRAM_KEYS`]
/// keys, added into `hist[pass · 256 + digit]` (zeroed by the host).
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_histogram(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; radix::RADIX_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] hist: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let base = (wg.y * nwg.x + wg.x) * radix::HISTOGRAM_KEYS;
    if base >= p.count {
        return;
    }
    let len = (p.count - base).min(radix::HISTOGRAM_KEYS);
    let counts = radix::global_histogram(&c, shared, len, p.key_bits, |i| keys[(base + i) as usize]);
    let mut pass = 0;
    while pass < radix::passes(p.key_bits) {
        let n = counts[pass as usize];
        if n != 0 {
            hist[(pass * radix::RADIX + local_index) as usize].fetch_add(n);
        }
        pass += 1;
    }
}

/// Radix sort step 2.1: tile `t`'s count of digit `d` → `counts[d · tiles + t]`.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_upsweep(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; radix::UPSWEEP_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counts: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let t = wg.y * nwg.x + wg.x;
    if t >= p.tiles {
        return;
    }
    let base = t * radix::RADIX_TILE;
    let len = (p.count - base).min(radix::RADIX_TILE);
    let (shift, bits) = radix::pass_digit(p.pass, p.key_bits);
    let n = radix::upsweep_tile(&c, shared, len, shift, bits, |i| keys[(base + i) as usize]);
    counts[(local_index * p.tiles + t) as usize] = n;
}

/// Radix sort step 2.2: workgroup `g` turns the tile counts of digits
/// `g · spine_digits ..` into global starts.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_spine(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; scan::SCAN_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] hist: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counts: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] starts: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let bins = p.pass * radix::RADIX;
    radix::spine(&c, shared, wg.x * p.spine_digits, p.spine_digits, p.tiles, |e| hist[(bins + e) as usize], |i| counts[i as usize], |i, start| {
        starts[i as usize] = start;
    });
}

/// Radix sort step 2.3: ranks tile `t`, reorders it in workgroup memory and writes each key and
/// value at its digit's start for the tile plus its rank.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_downsweep(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; radix::RADIX_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] values: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] starts: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys_out: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] values_out: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let t = wg.y * nwg.x + wg.x;
    if t >= p.tiles {
        return;
    }
    let base = t * radix::RADIX_TILE;
    let len = (p.count - base).min(radix::RADIX_TILE);
    let start = starts[(local_index * p.tiles + t) as usize];
    let digit = radix::pass_digit(p.pass, p.key_bits);
    radix::downsweep_tile(&c, shared, len, start, digit, |i| keys[(base + i) as usize], |i| values[(base + i) as usize], |dst, k, v| {
        keys_out[dst as usize] = k;
        values_out[dst as usize] = v;
    });
}

/// Radix sort, chained variant ([`radix::chained`]): one dispatch per pass claims tiles,
/// ranks them, looks back through `status` and writes as [`radix_downsweep`] does.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_chained(
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; radix::RADIX_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] values: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] hist: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] status: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] keys_out: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] values_out: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let bins = p.pass * radix::RADIX;
    radix::chained::chained_tile(
        &c,
        shared,
        status,
        p.count,
        p.tiles,
        (p.pass, p.key_bits),
        |d| hist[(bins + d) as usize],
        |i| keys[i as usize],
        |i| values[i as usize],
        |dst, k, v| {
            keys_out[dst as usize] = k;
            values_out[dst as usize] = v;
        },
    );
}

/// Radix sort of at most one tile (step 3): one workgroup sorts `keys[..count]` and its values
/// in place, every pass in workgroup memory.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn radix_sort_tile(
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &RadixParams,
    #[spirv(workgroup)] shared: &mut [u32; radix::RADIX_SHARED_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] values: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let slots = radix::Slots::of(&c);
    let k = radix::load_items(slots, p.count, u32::MAX, |i| keys[i as usize]);
    let v = radix::load_items(slots, p.count, 0, |i| values[i as usize]);
    let (k, v) = radix::sort_tile(&c, shared, slots, k, v, p.key_bits);
    radix::store_items(slots, p.count, &k, |i, x| keys[i as usize] = x);
    radix::store_items(slots, p.count, &v, |i, x| values[i as usize] = x);
}

/// Bitonic sort step 1 ([`crate::bitonic`]): workgroup `b` sorts elements
/// `[b·BLOCK, (b+1)·BLOCK)` (each element's position in the block rides along as its tag; the
/// values are gathered by it afterwards) and writes them in place or to the scratch pair
/// (`p.in_place`). A workgroup writes exactly the block it read, after every gather.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn bitonic_block_sort(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &BitonicParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] values: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] keys_out: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] values_out: &mut [u32],
    #[spirv(workgroup)] shared: &mut [u32; radix::RADIX_SHARED_WORDS],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let base = (wg.y * nwg.x + wg.x) * bitonic::BLOCK;
    if base >= p.count {
        return;
    }
    let (k, v) = bitonic::sort_block(&c, shared, base, p.count, |i| keys[i as usize], |i| values[i as usize]);
    let first = bitonic::block_first(&c);
    unroll4!(j => {
        let i = base + first + j;
        if i < p.count {
            if p.in_place != 0 {
                keys[i as usize] = k[j as usize];
                values[i as usize] = v[j as usize];
            } else {
                keys_out[i as usize] = k[j as usize];
                values_out[i as usize] = v[j as usize];
            }
        }
    });
}

/// Bitonic sort step 2a: one invocation per sample slot of the level; kept splitters write
/// their piece's boundary `(a, b)`.
#[spirv(compute(threads(256)))]
pub fn bitonic_splitters(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(push_constant)] p: &BitonicParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] boundaries: &mut [u32],
) {
    let slot = (wg.y * nwg.x + wg.x) * bitonic::SPLITTER_WORKGROUP + local_index;
    let lv = bitonic::Level { n: p.count, run: p.run, stride: p.stride, keep: p.keep };
    if slot >= lv.slots() {
        return;
    }
    let s = bitonic::splitter(keys, &lv, slot);
    if s.piece != bitonic::NO_PIECE {
        boundaries[(2 * s.piece) as usize] = s.a;
        boundaries[(2 * s.piece + 1) as usize] = s.b;
    }
}

/// Bitonic sort step 2b: subgroup `s` (global) merges piece `s` of the level.
#[spirv(compute(threads(128)))]
#[allow(clippy::too_many_arguments)]
pub fn bitonic_merge(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &BitonicParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] values: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] boundaries: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys_out: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] values_out: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let index = subgroup_item(&c, wg, nwg);
    let lv = bitonic::Level { n: p.count, run: p.run, stride: p.stride, keep: p.keep };
    if let Some(piece) = bitonic::piece_of(&lv, boundaries, index) {
        bitonic::merge_piece(&c, keys, values, piece, keys_out, values_out);
    }
}
