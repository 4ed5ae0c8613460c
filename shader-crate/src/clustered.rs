//! Entry points of the clustered-deferred chain (and the brute-force deferred reference). Each
//! unpacks its invocation's linear index and calls a pure function; the steps, paper references
//! and memory costs are in [`crate::page_table`], [`crate::cluster_bounds`] and
//! [`crate::lighting`].
//!
//! Linear domains larger than 65 535 workgroups fold into 2D dispatches: element
//! `(wg.y · num_wg.x + wg.x) · 256 + local` ([`linear_index`]).
// Entry points take one parameter per built-in and binding.
#![allow(clippy::too_many_arguments)]

use crate::layout::*;
use crate::page_table::{self, INVALID_KEY};
use crate::{cluster_bounds, lighting, octahedral, reconstruct};
use spirv_std::glam::{UVec3, Vec3};
use spirv_std::spirv;

/// Declares a `_diffuse` and a `_specular` compute entry point (256 invocations) with the given
/// parameters, calling `$imp::<false>` / `$imp::<true>`: one parameter list, two pipelines.
macro_rules! specular_variants {
    ($diffuse:ident, $specular:ident, $imp:ident, ($($(#[$attr:meta])* $arg:ident: $ty:ty),* $(,)?)) => {
        #[spirv(compute(threads(256)))]
        pub fn $diffuse($($(#[$attr])* $arg: $ty),*) {
            $imp::<false>($($arg),*);
        }

        #[spirv(compute(threads(256)))]
        pub fn $specular($($(#[$attr])* $arg: $ty),*) {
            $imp::<true>($($arg),*);
        }
    };
}

/// Colour of pixels that show no geometry.
pub const BACKGROUND_RGBA8: u32 = 0xff_20_18_18;

/// Workgroup size of every linear kernel here.
pub const LINEAR_WORKGROUP: u32 = 256;

#[inline]
pub fn linear_index(wg: UVec3, num_wg: UVec3, local: u32) -> u32 {
    (wg.y * num_wg.x + wg.x) * LINEAR_WORKGROUP + local
}

/// Albedo and material index of a G-buffer albedo word.
#[inline]
pub fn gbuffer_albedo(word: u32) -> (Vec3, u32) {
    let c = |s: u32| ((word >> s) & 255) as f32 * (1.0 / 255.0);
    (Vec3::new(c(0), c(8), c(16)), word >> 24)
}

/// Decoded G-buffer normal of pixel `i` from the normal buffer: one word per pixel (octahedral),
/// or four (`F32`: three bit patterns and a pad), per `p.normal_precision` (frame-uniform, so the
/// branch never diverges).
#[inline]
pub fn gbuffer_normal(p: &FrameParams, normals: &[u32], i: u32) -> Vec3 {
    let precision = octahedral::Precision::from_u32(p.normal_precision);
    let words = if precision.gbuffer_words() == 4 {
        let b = 4 * i as usize;
        [normals[b], normals[b + 1], normals[b + 2]]
    } else {
        [normals[i as usize], 0, 0]
    };
    Vec3::from_array(octahedral::decode(words, precision))
}

/// Shading inputs of one pixel: view position, normal, albedo, material.
#[inline]
pub fn surface(p: &FrameParams, i: u32, depth: f32, normals: &[u32], albedo: u32) -> (Vec3, Vec3, Vec3, u32) {
    let g = &p.grid;
    let (px, py) = (i % g.width, i / g.width);
    let d = reconstruct::distance_from_depth(g.near, depth);
    let pos = reconstruct::view_position(g, px, py, d);
    let n = gbuffer_normal(p, normals, i);
    let (a, m) = gbuffer_albedo(albedo);
    (pos, n, a, m)
}

/// Final colour of a pixel: tonemapped radiance, or one of the debug views (`VIEW_*`).
#[inline]
pub fn output_colour(p: &FrameParams, bounds: &[f32], i: u32, pos: Vec3, n: Vec3, radiance: Vec3, lights: u32) -> u32 {
    let g = &p.grid;
    let rgb = match p.view {
        VIEW_HEATMAP => lighting::heat_ramp(lights, p.heat_max),
        VIEW_CLUSTERS => {
            let h = crate::debug_view::hash_u32(g.key(bounds, i % g.width, i / g.width, pos.z));
            Vec3::new((h & 255) as f32, ((h >> 8) & 255) as f32, ((h >> 16) & 255) as f32) * (1.0 / 255.0)
        }
        VIEW_NORMALS => n * 0.5 + Vec3::splat(0.5),
        VIEW_DEPTH => crate::debug_view::ramp(g.slice_of_depth(bounds, -pos.z) as f32 / g.num_slices as f32),
        _ => lighting::tonemap(radiance, p.exposure),
    };
    lighting::encode_srgb8(rgb)
}

/// 1. Cluster key per pixel from the depth buffer.
#[spirv(compute(threads(256)))]
pub fn pixel_keys(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] keys: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let g = &p.grid;
    keys[i as usize] = page_table::pixel_key(g, bounds, i % g.width, i / g.width, depth[i as usize]);
}

/// 2. Mark the pages pixels touch.
#[spirv(compute(threads(256)))]
pub fn mark_pages(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] marks: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let key = keys[i as usize];
    if key != INVALID_KEY {
        marks[page_table::page_of(key) as usize] = 1;
    }
}

/// 3b. Record which page each dense page index stands for (after the scan of the marks).
#[spirv(compute(threads(256)))]
pub fn record_pages(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] marks: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_base: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] page_of_alloc: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i < p.count && marks[i as usize] != 0 {
        page_of_alloc[page_base[i as usize] as usize] = i;
    }
}

/// 4. Flag each pixel's key in its page.
#[spirv(compute(threads(256)))]
pub fn store_slots(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] page_base: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] slots: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let key = keys[i as usize];
    if key != INVALID_KEY {
        let base = page_base[page_table::page_of(key) as usize];
        slots[page_table::slot_index(base, key) as usize] = 1;
    }
}

/// 5. Scatter the set slots (after their scan) into the sorted unique-cluster list.
#[spirv(compute(threads(256)))]
pub fn compact_clusters(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] slots: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] slot_rank: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] page_of_alloc: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] unique: &mut [u32],
) {
    let s = linear_index(wg, nwg, local);
    if s < p.count && slots[s as usize] != 0 {
        unique[slot_rank[s as usize] as usize] = page_table::key_of_slot(page_of_alloc, s);
    }
}

/// Lights handled per loop iteration. llvmpipe (lavapipe) stops an invocation's loops after
/// 65 535 iterations in all (its loop limiter) and silently drops the rest; straight-line
/// unrolling by 8 lets one invocation visit [`MAX_LIGHTS_PER_INVOCATION_LLVMPIPE`] lights there.
pub const LIGHTS_PER_ITERATION: u32 = 8;
/// The most lights one invocation may loop over on llvmpipe (the host refuses more there):
/// naive loops take `N/8` iterations, a BVH walk that meets every light `N/8 + N/32 + N/1024 + …`
/// ≈ 0.157·N, both under 65 535 for N ≤ 400 000.
pub const MAX_LIGHTS_PER_INVOCATION_LLVMPIPE: u32 = 400_000;


/// The view-space box of the cluster with key `key` (both light searches test against it).
#[inline]
pub fn cluster_box(p: &FrameParams, bounds: &[f32], key: u32) -> ClusterAabb {
    let (i, j, k) = p.grid.unpack(key);
    cluster_bounds::cluster_aabb(&p.grid, bounds, i, j, k)
}

/// Lights of cluster `key` whose sphere meets its box (naive: all lights), in index order;
/// returns the count and calls `emit(n, light)` for each. With `EFFECT_CULL_PLANES` or
/// `EFFECT_CULL_EXACT` (the accuracy study) the cluster's frustum planes or the exact
/// sphere–frustum test (`cluster_test`) replace the box.
#[inline]
pub fn for_each_cluster_light(p: &FrameParams, bounds: &[f32], lights: &[PointLight], key: u32, emit: impl FnMut(u32, u32)) -> u32 {
    // The mode is uniform: one loop per test, so the default loop carries no other test's code.
    let mode = p.effects & (EFFECT_CULL_PLANES | EFFECT_CULL_EXACT);
    if mode == 0 {
        let aabb = cluster_box(p, bounds, key);
        return lights_meeting(p.num_lights, lights, emit, |c, r| lighting::sphere_intersects_aabb(c, r, &aabb));
    }
    let (i, j, k) = p.grid.unpack(key);
    let frustum = crate::cluster_test::cluster_frustum(&p.grid, bounds, i, j, k);
    if mode == EFFECT_CULL_PLANES {
        lights_meeting(p.num_lights, lights, emit, |c, r| !crate::cluster_test::sphere_outside_planes(&frustum, c, r))
    } else {
        lights_meeting(p.num_lights, lights, emit, |c, r| crate::cluster_test::sphere_meets_frustum(&frustum, c, r))
    }
}

/// Lights `0..n` passing `test(centre, radius)`, in index order, 8 per loop iteration.
#[inline]
fn lights_meeting(n: u32, lights: &[PointLight], mut emit: impl FnMut(u32, u32), test: impl Fn(Vec3, f32) -> bool) -> u32 {
    let mut found = 0;
    let mut base = 0;
    while base < n {
        unroll8!(u => {
            let l = base + u;
            if l < n {
                let light = lights[l as usize];
                if test(Vec3::from_array(light.position), light.radius) {
                    emit(found, l);
                    found += 1;
                }
            }
        });
        base += LIGHTS_PER_ITERATION;
    }
    found
}

/// 6. Naive light assignment, pass 1: lights per unique cluster.
#[spirv(compute(threads(256)))]
pub fn cluster_light_counts(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] counts: &mut [u32],
) {
    let c = linear_index(wg, nwg, local);
    if c >= p.count {
        return;
    }
    counts[c as usize] = if c < counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        for_each_cluster_light(p, bounds, lights, unique[c as usize], |_, _| {})
    } else {
        0
    };
}

/// 7. Naive light assignment, pass 2: write each cluster's light indices at its offset.
#[spirv(compute(threads(256)))]
pub fn cluster_light_fill(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] unique: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] list: &mut [u32],
) {
    let c = linear_index(wg, nwg, local);
    if c >= p.count || c >= counters[COUNTER_UNIQUE_CLUSTERS as usize] {
        return;
    }
    // A frame whose lists do not fit writes nothing; the host sees the total and grows the list.
    if counters[COUNTER_LIGHT_REFS as usize] > p.light_capacity {
        return;
    }
    let base = offsets[c as usize];
    for_each_cluster_light(p, bounds, lights, unique[c as usize], |n, l| list[(base + n) as usize] = l);
}

/// 8. Clustered shading: per pixel, its cluster's lights.
///
/// Two entry points: `_diffuse` for scenes without specular materials (the specular term is
/// compiled out) and `_specular`.
#[inline]
fn shade_clustered_impl<const SPECULAR: bool>(
    wg: UVec3,
    nwg: UVec3,
    local: u32,
    p: &FrameParams,
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    keys: &[u32],
    page_base: &[u32],
    slot_rank: &[u32],
    counts: &[u32],
    offsets: &[u32],
    list: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    frame: &mut [u32],
    bounds: &[f32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let key = keys[i as usize];
    if key == INVALID_KEY {
        frame[i as usize] = BACKGROUND_RGBA8;
        return;
    }
    let (pos, n, albedo, m) = surface(p, i, depth[i as usize], normals, albedo[i as usize]);
    let mat = materials[m as usize];
    let cluster = slot_rank[page_table::slot_index(page_base[page_table::page_of(key) as usize], key) as usize] as usize;
    let (first, count) = (offsets[cluster], counts[cluster]);
    let mut sum = Vec3::ZERO;
    let (mut base, end) = (first, first + count);
    while base < end {
        unroll8!(u => {
            let t = base + u;
            if t < end {
                let light = lights[list[t as usize] as usize];
                sum += lighting::shade(pos, n, albedo, mat.specular, mat.roughness, &light, if SPECULAR { EFFECT_SPECULAR } else { 0 });
            }
        });
        base += LIGHTS_PER_ITERATION;
    }
    frame[i as usize] = output_colour(p, bounds, i, pos, n, sum, count);
}

specular_variants!(shade_clustered_diffuse, shade_clustered_specular, shade_clustered_impl, (
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] keys: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] page_base: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] slot_rank: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] counts: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] offsets: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] list: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] materials: &[MaterialGpu],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] frame: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] bounds: &[f32],
));

/// Brute-force deferred shading: every light for every pixel (the correctness reference), in
/// `_diffuse` and `_specular` variants like the clustered shading.
#[inline]
fn shade_deferred_impl<const SPECULAR: bool>(
    wg: UVec3,
    nwg: UVec3,
    local: u32,
    p: &FrameParams,
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    frame: &mut [u32],
    bounds: &[f32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let z = depth[i as usize];
    if reconstruct::is_background(z) {
        frame[i as usize] = BACKGROUND_RGBA8;
        return;
    }
    let (pos, n, albedo, m) = surface(p, i, z, normals, albedo[i as usize]);
    let mat = materials[m as usize];
    let mut sum = Vec3::ZERO;
    let mut touching = 0;
    let mut base = 0;
    while base < p.num_lights {
        unroll8!(u => {
            let l = base + u;
            if l < p.num_lights {
                let light = lights[l as usize];
                if lighting::light_touches(&light, pos) {
                    sum += lighting::shade(pos, n, albedo, mat.specular, mat.roughness, &light, if SPECULAR { EFFECT_SPECULAR } else { 0 });
                    touching += 1;
                }
            }
        });
        base += LIGHTS_PER_ITERATION;
    }
    frame[i as usize] = output_colour(p, bounds, i, pos, n, sum, touching);
}

specular_variants!(shade_deferred_diffuse, shade_deferred_specular, shade_deferred_impl, (
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] materials: &[MaterialGpu],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] frame: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] bounds: &[f32],
));

/// Device-wide scan, step 3: add each workgroup's offset to its elements.
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

/// Device-wide scan: copy the grand total (the top level's single total) into a counter.
#[spirv(compute(threads(1)))]
pub fn scan_store_total(
    #[spirv(push_constant)] p: &ScanFixParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] totals: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] counters: &mut [u32],
) {
    counters[p.slot as usize] = totals[0];
}
