//! Typed kernel handles: the one place an entry-point name is written down (host side only).
//! A handle carries its push-constant type `P`, the number of storage buffers the entry binds
//! (set 0, bindings `0..storage_buffers`, in order) and its workgroup size, so the host cannot
//! dispatch a kernel with the wrong parameters or buffer count.
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

// Clustered-deferred chain (`clustered.rs`). Linear kernels: 256 invocations, 2D-folded dispatch
// (`shading::linear_index`).
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

// Brute-force deferred reference (`deferred.rs`).
pub const SHADE_DEFERRED_DIFFUSE: Kernel<FrameParams> = linear("deferred::shade_deferred_diffuse", 7);
pub const SHADE_DEFERRED_SPECULAR: Kernel<FrameParams> = linear("deferred::shade_deferred_specular", 7);

// Device-wide scan fix-ups (`entries.rs`).
pub const SCAN_ADD_OFFSETS: Kernel<ScanFixParams> = linear("entries::scan_add_offsets", 2);
pub const SCAN_STORE_TOTAL: Kernel<ScanFixParams> = Kernel::new("entries::scan_store_total", 2, [1, 1, 1], false);

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
pub const SHADE_TILED_DIFFUSE: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_diffuse", 8, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true);
pub const SHADE_TILED_SPECULAR: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_specular", 8, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true);

// Clustered-AABB technique (`clustered_aabb.rs`): fixed grid, precomputed boxes.
pub const AABB_BOUNDS: Kernel<FrameParams> = linear("clustered_aabb::aabb_bounds", 2);
pub const AABB_MARK: Kernel<FrameParams> = linear("clustered_aabb::aabb_mark", 4);
pub const AABB_COMPACT: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_compact", 3, [256, 1, 1], true);
pub const AABB_ASSIGN: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_assign", 7, [256, 1, 1], true);
pub const SHADE_AABB_DIFFUSE: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_diffuse", 12);
pub const SHADE_AABB_SPECULAR: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_specular", 12);

// Forward+ (`forward_plus.rs`): tiled culling into per-tile linked lists.
pub const FORWARD_PLUS_CULL: Kernel<TiledParams> = Kernel::new("forward_plus::forward_plus_cull", 5, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true);

// Bitonic-warp merge sort (`entries.rs`, `bitonic.rs`): block sort and merge give each subgroup
// a block / piece (cooperative); the splitters are one invocation per sample.
pub const BITONIC_BLOCK_SORT: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_block_sort", 4, [crate::bitonic::BITONIC_WORKGROUP, 1, 1], true);
pub const BITONIC_SPLITTERS: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_splitters", 2, [crate::bitonic::SPLITTER_WORKGROUP, 1, 1], false);
pub const BITONIC_MERGE: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_merge", 5, [crate::bitonic::BITONIC_WORKGROUP, 1, 1], true);
