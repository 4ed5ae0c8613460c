//! Typed kernel handles and raster entry names: the one place an entry-point name is written
//! down (host side only). A handle carries its push-constant type `P`, the number of storage
//! buffers the entry binds (set 0, bindings `0..storage_buffers`, in order) and its workgroup
//! size, so the host cannot dispatch a kernel with the wrong parameters or buffer count.
//!
//! [`ALL`], [`VERTEX_ENTRIES`] and [`FRAGMENT_ENTRIES`] list every entry point.
//! `tests/spirv_val.rs` checks them against the built modules in both directions (every entry
//! point of a module is listed, every listed name is an entry point of the right stage) and checks
//! each handle's workgroup size and storage-buffer bindings against the module's declarations, so
//! a kernel left out of a list, or a handle that disagrees with its entry, fails that test.
use crate::layout::*;
use core::marker::PhantomData;

/// A compute entry point of the kernel module.
pub struct Kernel<P> {
    /// SPIR-V entry-point name: rust-gpu names entries by their path in the crate (`entries::name`).
    pub entry: &'static str,
    /// Storage buffers bound at set 0, bindings `0..storage_buffers`.
    pub storage_buffers: u32,
    /// Local size `[x, y, z]` (must match the entry's `threads(..)`).
    pub workgroup_size: [u32; 3],
    /// Uses subgroup operations: the host then requires full subgroups.
    pub cooperative: bool,
    _params: PhantomData<fn() -> P>,
}

impl<P> Kernel<P> {
    const fn new(entry: &'static str, storage_buffers: u32, workgroup_size: [u32; 3], cooperative: bool) -> Self {
        Self { entry, storage_buffers, workgroup_size, cooperative, _params: PhantomData }
    }

    /// Invocations per workgroup.
    pub const fn invocations(&self) -> u32 {
        self.workgroup_size[0] * self.workgroup_size[1] * self.workgroup_size[2]
    }

    /// The handle without its push-constant type, for the list of every kernel ([`ALL`]).
    pub const fn erased(&self) -> Kernel<()> {
        Kernel::new(self.entry, self.storage_buffers, self.workgroup_size, self.cooperative)
    }
}

impl<P> Clone for Kernel<P> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<P> Copy for Kernel<P> {}

pub const OCTA_ROUNDTRIP: Kernel<OctaParams> = Kernel::new("entries::octa_roundtrip", 3, [64, 1, 1], false);
pub const CLUSTER_KEYS: Kernel<ClusterKeyParams> = Kernel::new("entries::cluster_keys", 3, [64, 1, 1], false);
pub const MORTON_CODES: Kernel<MortonParams> = Kernel::new("entries::morton_codes", 3, [64, 1, 1], false);
pub const WORKGROUP_SCAN: Kernel<ScanParams> = Kernel::new("entries::workgroup_scan", 3, [crate::scan::SCAN_WORKGROUP, 1, 1], true);
pub const DEBUG_VIEW: Kernel<DebugViewParams> = Kernel::new("entries::debug_view", 2, [8, 8, 1], false);

// Clustered-deferred chain (`clustered.rs`). Linear kernels: 256 invocations, 2D-folded dispatch.
const fn linear<P>(entry: &'static str, storage_buffers: u32) -> Kernel<P> {
    Kernel::new(entry, storage_buffers, [256, 1, 1], false)
}
pub const PIXEL_KEYS: Kernel<FrameParams> = linear("clustered::pixel_keys", 3);
pub const MARK_PAGES: Kernel<FrameParams> = linear("clustered::mark_pages", 2);
pub const RECORD_PAGES: Kernel<FrameParams> = linear("clustered::record_pages", 3);
pub const STORE_SLOTS: Kernel<FrameParams> = linear("clustered::store_slots", 3);
pub const COMPACT_CLUSTERS: Kernel<FrameParams> = linear("clustered::compact_clusters", 4);
pub const CLUSTER_LIGHT_COUNTS: Kernel<FrameParams> = linear("clustered::cluster_light_counts", 5);
pub const CLUSTER_LIGHT_FILL: Kernel<FrameParams> = linear("clustered::cluster_light_fill", 6);
pub const SHADE_CLUSTERED_DIFFUSE: Kernel<FrameParams> = linear("clustered::shade_clustered_diffuse", 13);
pub const SHADE_CLUSTERED_SPECULAR: Kernel<FrameParams> = linear("clustered::shade_clustered_specular", 13);
pub const SHADE_DEFERRED_DIFFUSE: Kernel<FrameParams> = linear("clustered::shade_deferred_diffuse", 7);
pub const SHADE_DEFERRED_SPECULAR: Kernel<FrameParams> = linear("clustered::shade_deferred_specular", 7);
pub const SCAN_ADD_OFFSETS: Kernel<ScanFixParams> = linear("clustered::scan_add_offsets", 2);
pub const SCAN_STORE_TOTAL: Kernel<ScanFixParams> = Kernel::new("clustered::scan_store_total", 2, [1, 1, 1], false);

// Radix sort (`entries.rs`, `radix.rs`): cooperative (workgroup barriers).
pub const RADIX_HISTOGRAM: Kernel<RadixParams> = Kernel::new("entries::radix_histogram", 2, [256, 1, 1], true);
pub const RADIX_SCATTER: Kernel<RadixParams> = Kernel::new("entries::radix_scatter", 5, [256, 1, 1], true);

// Clustered-BVH technique (`clustered_bvh.rs`).
pub const LIGHT_KEYS: Kernel<MortonParams> = linear("clustered_bvh::light_keys", 3);
pub const BVH_LEAVES: Kernel<BvhParams> = linear("clustered_bvh::bvh_leaves", 3);
pub const BVH_LEVEL: Kernel<BvhParams> = linear("clustered_bvh::bvh_level", 1);
/// One subgroup per unique cluster (subgroup-parallel walk): cooperative.
pub const CLUSTER_LIGHT_COUNTS_BVH: Kernel<BvhAssignParams> =
    Kernel::new("clustered_bvh::cluster_light_counts_bvh", 7, [crate::light_bvh::WALK_WORKGROUP, 1, 1], true);
pub const CLUSTER_LIGHT_FILL_BVH: Kernel<BvhAssignParams> =
    Kernel::new("clustered_bvh::cluster_light_fill_bvh", 8, [crate::light_bvh::WALK_WORKGROUP, 1, 1], true);

// Tiled techniques (`tiled.rs`): one cooperative workgroup of 256 per screen tile.
pub const SHADE_TILED_DIFFUSE: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_diffuse", 8, [crate::tiled::TILED_WORKGROUP, 1, 1], true);
pub const SHADE_TILED_SPECULAR: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_specular", 8, [crate::tiled::TILED_WORKGROUP, 1, 1], true);

// Clustered-AABB technique (`clustered_aabb.rs`): fixed grid, precomputed boxes.
pub const AABB_BOUNDS: Kernel<FrameParams> = linear("clustered_aabb::aabb_bounds", 2);
pub const AABB_MARK: Kernel<FrameParams> = linear("clustered_aabb::aabb_mark", 4);
pub const AABB_COMPACT: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_compact", 3, [256, 1, 1], true);
pub const AABB_ASSIGN: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_assign", 7, [256, 1, 1], true);
pub const SHADE_AABB_DIFFUSE: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_diffuse", 12);
pub const SHADE_AABB_SPECULAR: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_specular", 12);

// Forward+ (`forward_plus.rs`): tiled culling into per-tile linked lists.
pub const FORWARD_PLUS_CULL: Kernel<TiledParams> = Kernel::new("forward_plus::forward_plus_cull", 5, [crate::tiled::TILED_WORKGROUP, 1, 1], true);

// Bitonic-warp merge sort (`entries.rs`, `bitonic.rs`): block sort and merge give each subgroup
// a block / piece (cooperative); the splitters are one invocation per sample.
pub const BITONIC_BLOCK_SORT: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_block_sort", 4, [crate::bitonic::BITONIC_WORKGROUP, 1, 1], true);
pub const BITONIC_SPLITTERS: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_splitters", 2, [crate::bitonic::SPLITTER_WORKGROUP, 1, 1], false);
pub const BITONIC_MERGE: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_merge", 5, [crate::bitonic::BITONIC_WORKGROUP, 1, 1], true);

/// Every compute kernel handle (see the module doc: a test keeps this list complete).
pub const ALL: &[Kernel<()>] = &[
    OCTA_ROUNDTRIP.erased(),
    CLUSTER_KEYS.erased(),
    MORTON_CODES.erased(),
    WORKGROUP_SCAN.erased(),
    DEBUG_VIEW.erased(),
    PIXEL_KEYS.erased(),
    MARK_PAGES.erased(),
    RECORD_PAGES.erased(),
    STORE_SLOTS.erased(),
    COMPACT_CLUSTERS.erased(),
    CLUSTER_LIGHT_COUNTS.erased(),
    CLUSTER_LIGHT_FILL.erased(),
    SHADE_CLUSTERED_DIFFUSE.erased(),
    SHADE_CLUSTERED_SPECULAR.erased(),
    SHADE_DEFERRED_DIFFUSE.erased(),
    SHADE_DEFERRED_SPECULAR.erased(),
    SCAN_ADD_OFFSETS.erased(),
    SCAN_STORE_TOTAL.erased(),
    RADIX_HISTOGRAM.erased(),
    RADIX_SCATTER.erased(),
    LIGHT_KEYS.erased(),
    BVH_LEAVES.erased(),
    BVH_LEVEL.erased(),
    CLUSTER_LIGHT_COUNTS_BVH.erased(),
    CLUSTER_LIGHT_FILL_BVH.erased(),
    SHADE_TILED_DIFFUSE.erased(),
    SHADE_TILED_SPECULAR.erased(),
    AABB_BOUNDS.erased(),
    AABB_MARK.erased(),
    AABB_COMPACT.erased(),
    AABB_ASSIGN.erased(),
    SHADE_AABB_DIFFUSE.erased(),
    SHADE_AABB_SPECULAR.erased(),
    FORWARD_PLUS_CULL.erased(),
    BITONIC_BLOCK_SORT.erased(),
    BITONIC_SPLITTERS.erased(),
    BITONIC_MERGE.erased(),
];

// Raster entry points (graphics module: `raster.rs`, `raster_forward.rs`). Fragment shaders that
// write the normal target come as `[octahedral target, float32 target]`.

/// G-buffer and forward vertex shaders: positions only / with uvs.
pub const GBUFFER_VS: &str = "raster::gbuffer_vs";
pub const GBUFFER_VS_UV: &str = "raster::gbuffer_vs_uv";
/// G-buffer fragment shaders: plain, textured, alpha-tested.
pub const GBUFFER_FS: [&str; 2] = ["raster::gbuffer_fs", "raster::gbuffer_fs_f32"];
pub const GBUFFER_FS_TEXTURED: [&str; 2] = ["raster::gbuffer_fs_textured", "raster::gbuffer_fs_textured_f32"];
pub const GBUFFER_FS_MASKED: [&str; 2] = ["raster::gbuffer_fs_masked", "raster::gbuffer_fs_masked_f32"];
/// Forward+ depth pre-pass: vertex shaders (positions only / with uvs) and fragment shaders
/// (opaque / alpha-tested).
pub const DEPTH_VS: &str = "raster_forward::depth_vs";
pub const DEPTH_VS_UV: &str = "raster_forward::depth_vs_uv";
pub const DEPTH_FS: &str = "raster_forward::depth_fs";
pub const DEPTH_FS_MASKED: &str = "raster_forward::depth_fs_masked";
/// Forward+ shading fragment shaders: plain, textured, alpha-tested.
pub const FORWARD_FS: &str = "raster_forward::forward_fs";
pub const FORWARD_FS_TEXTURED: &str = "raster_forward::forward_fs_textured";
pub const FORWARD_FS_MASKED: &str = "raster_forward::forward_fs_masked";

/// Every vertex entry point of the raster module.
pub const VERTEX_ENTRIES: &[&str] = &[GBUFFER_VS, GBUFFER_VS_UV, DEPTH_VS, DEPTH_VS_UV];
/// Every fragment entry point of the raster module.
pub const FRAGMENT_ENTRIES: &[&str] = &[
    GBUFFER_FS[0],
    GBUFFER_FS[1],
    GBUFFER_FS_TEXTURED[0],
    GBUFFER_FS_TEXTURED[1],
    GBUFFER_FS_MASKED[0],
    GBUFFER_FS_MASKED[1],
    DEPTH_FS,
    DEPTH_FS_MASKED,
    FORWARD_FS,
    FORWARD_FS_TEXTURED,
    FORWARD_FS_MASKED,
];
