//! manylights GPU kernels, written once in Rust.
//!
//! Every kernel is a pure function (CPU-testable with `cargo test`) plus a thin `#[spirv(...)]`
//! entry point in [`entries`] that only unpacks built-ins and buffers and calls it. rust-gpu
//! compiles this crate to SPIR-V (`host/build.rs`); on the host it is an ordinary rlib, so the
//! host, the tests and the benchmarks call the very same functions as CPU references.
//!
//! * [`layout`] — every host↔GPU struct and constant (`#[repr(C)]`, size-asserted).
//! * [`kernels`] — typed handles naming each entry point with its push-constant type (host only).
//! * [`octahedral`] — normal encodings (2×8, 2×12, 2×16 bit octahedral; float32).
//! * [`cluster_key`] — tile × exponential-slice cluster keys.
//! * [`morton`] — 30/63-bit 3D Morton codes.
//! * [`coop`] — the cooperative-kernel traits (GPU intrinsics / CPU lock-step emulation).
//! * [`scan`] — subgroup/workgroup prefix sums.
//! * [`radix`] — LSD radix sort (key–value): histogram, upsweep, spine, ballot-ranked downsweep,
//!   single-tile sort, and the chained-scan variant ([`radix::chained`]).
//! * [`bitonic`] — bitonic-warp merge sort (key–value): block sort, splitters, warp merge.
//! * [`raster`] — the G-buffer vertex/fragment shaders (graphics module).
//! * [`debug_view`] — an analytic test scene for debug frames (normals, keys, encoding error).
//! * [`lighting`] — culling tests, falloff, BRDF, tonemapping and output encoding.
//! * [`nurbs`] — rational B-spline surfaces: knot spans, basis functions and derivatives, rational
//!   surface points and normals, the per-vertex / per-quad tessellation of a patch; the
//!   tessellation pass's kernels ([`tessellation`]) write every patch's grid into the raster
//!   passes' vertex streams and index buffer.
//! * [`oit`] — order-independent transparency: per-pixel linked lists (list building, exact and
//!   k-nearest resolves) and weighted blended OIT; the transparent pass's fragment shaders
//!   ([`raster_transparent`], graphics module) and its resolve kernel ([`transparency`]).
//!
//! Shared by the techniques (each technique module imports only these, never a sibling):
//! * [`shading`] — shading I/O: pixel index, surface fetch, the light-list shading loop (the
//!   frame's effect bits reach `lighting::shade` there), output colour, the `_diffuse` /
//!   `_specular` entry macro (every shading kernel, the Forward+ fragment shader included).
//! * [`light_lists`] — light-list building: atomics, subgroup-aggregated reservation, list sinks,
//!   the naive light search loop, llvmpipe's loop limit.
//! * [`tile_cull`] — tile depth bounds, frustum and 2.5D mask (tiled, tiled-2.5d, Forward+; its
//!   pure tests also serve raster passes).
//! * [`fragment_atomics`] — atomics on storage-buffer words from fragment shaders.
//! * [`shadow`] — cube shadow maps: the raster pass that fills them and the per-light lookup
//!   of the shading loop; [`shadow_cull`] — the batches of triangles culled per face that the
//!   raster pass draws; [`shadow_raster`] — the same batches rasterised in a compute kernel;
//!   [`shadow_receivers`] — the faces whose texels the frame's pixels look up; [`shadow_atlas`]
//!   — each face's resolution and place in the shared atlas.
//!
//! Techniques: [`deferred`] (brute force), [`clustered`] (+ [`clustered_bvh`]), [`tiled`],
//! [`clustered_aabb`], [`forward_plus`] (+ [`raster_forward`]).
#![cfg_attr(target_arch = "spirv", no_std)]
// `raster::sample_draw_uniform` emits one SPIR-V instruction with `asm!` (as spirv-std does).
#![cfg_attr(all(target_arch = "spirv", feature = "graphics"), feature(asm_experimental_arch))]
// NaN-aware comparisons are deliberate: `!(x > a)` is true for NaN, which is how every kernel maps
// bad input to a defined result; `clamp`/`contains` would change that (and `f32::clamp` asserts).
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::manual_clamp, clippy::manual_range_contains)]

/// Runs `$body` four times with `$u` = 0..4 as straight-line code (no loop, no closure:
/// rust-gpu cannot legalise closures capturing other closures mutably). Register arrays indexed
/// only by these constants stay in registers; a loop index would leave them in addressable
/// (function-local) memory unless the driver unrolls the loop itself.
macro_rules! unroll4 {
    ($u:ident => $body:block) => {{
        { let $u = 0u32; $body }
        { let $u = 1u32; $body }
        { let $u = 2u32; $body }
        { let $u = 3u32; $body }
    }};
}

/// As [`unroll4`], twice.
macro_rules! unroll2 {
    ($u:ident => $body:block) => {{
        { let $u = 0u32; $body }
        { let $u = 1u32; $body }
    }};
}

/// As [`unroll4`], eight times.
macro_rules! unroll8 {
    ($u:ident => $body:block) => {{
        { let $u = 0u32; $body }
        { let $u = 1u32; $body }
        { let $u = 2u32; $body }
        { let $u = 3u32; $body }
        { let $u = 4u32; $body }
        { let $u = 5u32; $body }
        { let $u = 6u32; $body }
        { let $u = 7u32; $body }
    }};
}

pub mod bitonic;
pub mod cluster_bounds;
pub mod cluster_key;
pub mod cluster_test;
#[cfg(feature = "compute")]
pub mod clustered;
#[cfg(feature = "compute")]
pub mod clustered_aabb;
#[cfg(feature = "compute")]
pub mod clustered_bvh;
pub mod compact_light;
pub mod coop;
pub mod debug_view;
#[cfg(feature = "compute")]
pub mod deferred;
pub mod dense_grid;
#[cfg(feature = "compute")]
pub mod entries;
#[cfg(feature = "compute")]
pub mod forward_plus;
pub mod forward_msaa;
pub mod indirect;
pub mod layout;
pub mod light_bvh;
#[cfg(feature = "compute")]
pub mod light_lists;
pub mod light_types;
pub mod lighting;
pub mod morton;
pub mod msaa;
pub mod nurbs;
pub mod octahedral;
pub mod oit;
pub mod page_table;
pub mod radix;
#[cfg(feature = "graphics")]
pub mod raster;
#[cfg(feature = "graphics")]
pub mod raster_forward;
#[cfg(feature = "graphics")]
pub mod raster_forward_ms;
#[cfg(feature = "graphics")]
pub mod raster_transparent;
pub mod reconstruct;
pub mod scan;
pub mod shading;
pub mod shadow;
pub mod shadow_atlas;
pub mod shadow_cull;
pub mod shadow_raster;
pub mod shadow_receivers;
pub mod spot;
#[cfg(test)]
mod sort_acceptance_tests;
#[cfg(not(target_arch = "spirv"))]
pub mod sort_inputs;
#[cfg(test)]
mod test_support;
pub mod tile_clusters;
pub mod tile_cull;
#[cfg(feature = "compute")]
pub mod tessellation;
#[cfg(feature = "compute")]
pub mod tiled;
#[cfg(feature = "compute")]
pub mod transparency;
pub mod unchecked;
#[cfg(feature = "graphics")]
pub mod fragment_atomics;

// Techniques whose kernels are files of `src/techniques/` alone: `build.rs` declares each file
// there as a module of this root (no line to add here).
include!(concat!(env!("OUT_DIR"), "/techniques.rs"));

#[cfg(not(target_arch = "spirv"))]
pub mod kernels;
