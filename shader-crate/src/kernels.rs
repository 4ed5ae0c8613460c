//! Typed kernel and raster handles: the one place an entry-point name is written
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
    /// Sampled images bound after the storage buffers, at bindings
    /// `storage_buffers..storage_buffers + sampled_images` (read texel by texel).
    pub sampled_images: u32,
    _params: PhantomData<fn() -> P>,
}

impl<P> Kernel<P> {
    /// A handle (a technique's own kernels are declared beside its entries with this).
    pub const fn new(entry: &'static str, storage_buffers: u32, workgroup_size: [u32; 3], cooperative: bool) -> Self {
        Self { entry, storage_buffers, workgroup_size, cooperative, sampled_images: 0, _params: PhantomData }
    }

    /// The handle of an entry that also binds `n` sampled images after its storage buffers.
    pub const fn with_sampled_images(self, n: u32) -> Self {
        Self { sampled_images: n, ..self }
    }

    /// Invocations per workgroup.
    pub const fn invocations(&self) -> u32 {
        self.workgroup_size[0] * self.workgroup_size[1] * self.workgroup_size[2]
    }

    /// The handle without its push-constant type, for the list of every kernel ([`ALL`]).
    pub const fn erased(&self) -> Kernel<()> {
        Kernel::new(self.entry, self.storage_buffers, self.workgroup_size, self.cooperative).with_sampled_images(self.sampled_images)
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
pub const PIXEL_KEYS: Kernel<FrameParams> = linear("clustered::pixel_keys", 4);
const PAGE_WORKGROUP: [u32; 3] = [crate::page_table::ALLOCATE_WORKGROUP, 1, 1];
pub const ALLOCATE_PAGES: Kernel<PageTableParams> = Kernel::new("clustered::allocate_pages", 5, PAGE_WORKGROUP, true);
pub const COUNT_PAGE_SLOTS: Kernel<()> = Kernel::new("clustered::count_page_slots", 2, PAGE_WORKGROUP, true);
pub const SCAN_PAGE_COUNTS: Kernel<PageTableParams> = Kernel::new("clustered::scan_page_counts", 4, PAGE_WORKGROUP, true);
pub const COMPACT_PAGE_SLOTS: Kernel<()> = Kernel::new("clustered::compact_page_slots", 5, PAGE_WORKGROUP, true);
pub const STORE_SLOTS: Kernel<FrameParams> = linear("clustered::store_slots", 3);
pub const CLUSTER_LIGHT_COUNTS: Kernel<FrameParams> = linear("clustered::cluster_light_counts", 6);
pub const CLUSTER_LIGHT_FILL: Kernel<FrameParams> = linear("clustered::cluster_light_fill", 6);
pub const SHADE_CLUSTERED_DIFFUSE: Kernel<FrameParams> = linear("clustered::shade_clustered_diffuse", 15);
pub const SHADE_CLUSTERED_SPECULAR: Kernel<FrameParams> = linear("clustered::shade_clustered_specular", 15);
/// The tile path of the unique clusters (`tile_clusters`): one workgroup per tile, and the
/// shading that looks clusters up in the tiles' records.
pub const TILE_CLUSTERS: Kernel<TileClusterParams> =
    Kernel::new("clustered::tile_clusters", 7, [crate::tile_clusters::TILE_WORKGROUP, 1, 1], true);
pub const SHADE_CLUSTERED_TILES_DIFFUSE: Kernel<FrameParams> = linear("clustered::shade_clustered_tiles_diffuse", 16);
pub const SHADE_CLUSTERED_TILES_SPECULAR: Kernel<FrameParams> = linear("clustered::shade_clustered_tiles_specular", 16);
/// The MSAA edge passes (`msaa.rs` step 5) of the page-table and tile paths: the shading's
/// buffers (without the tile path's counters and dispatch) and the edge list.
pub const SHADE_EDGES_CLUSTERED: [Kernel<FrameParams>; 2] =
    [linear("clustered::shade_edges_clustered_diffuse", 14), linear("clustered::shade_edges_clustered_specular", 14)];
pub const SHADE_EDGES_CLUSTERED_TILES: [Kernel<FrameParams>; 2] =
    [linear("clustered::shade_edges_clustered_tiles_diffuse", 13), linear("clustered::shade_edges_clustered_tiles_specular", 13)];

/// The MSAA edge pass of `clustered-aabb` (`msaa.rs` step 5): the G-buffer, offsets, counts,
/// list, counters, lights, materials, frame, bounds, edges.
pub const SHADE_EDGES_AABB: [Kernel<FrameParams>; 2] = [linear("clustered_aabb::shade_edges_aabb_diffuse", 12), linear("clustered_aabb::shade_edges_aabb_specular", 12)];

// Brute-force deferred reference (`deferred.rs`).
pub const SHADE_DEFERRED_DIFFUSE: Kernel<FrameParams> = linear("deferred::shade_deferred_diffuse", 9);
pub const SHADE_DEFERRED_SPECULAR: Kernel<FrameParams> = linear("deferred::shade_deferred_specular", 9);
/// Its MSAA edge pass (`msaa.rs` step 5): the shading buffers and the edge list.
pub const SHADE_EDGES_DEFERRED: [Kernel<FrameParams>; 2] =
    [linear("deferred::shade_edges_deferred_diffuse", 8), linear("deferred::shade_edges_deferred_specular", 8)];

// MSAA (`msaa.rs`).
/// The samples of the multisampled G-buffer into the buffers, and the edge list: depth, normals,
/// albedo, edges; the three targets as sampled images.
pub const MSAA_GATHER: Kernel<FrameParams> = linear("msaa::msaa_gather", 4).with_sampled_images(3);
/// The edge pass's indirect workgroup counts: edges.
pub const MSAA_EDGE_ARGS: Kernel<()> = Kernel::new("msaa::msaa_edge_args", 1, [1, 1, 1], false);
/// Forward+ with MSAA (`forward_msaa.rs`): the pre-pass's samples into the depth and winner planes.
pub const FORWARD_GATHER: Kernel<FrameParams> = linear("forward_msaa::forward_gather", 2).with_sampled_images(2);
/// Forward+ with MSAA: frame, depth planes, edge count; the colour, normal and albedo targets.
pub const FORWARD_RESOLVE: Kernel<FrameParams> = linear("forward_msaa::forward_resolve", 3).with_sampled_images(3);
/// Resolve of the transparent pass: heads, nodes, frame, counters (`transparency`).
pub const OIT_RESOLVE: Kernel<OitParams> = linear("transparency::oit_resolve", 4);
/// Resolve of the weighted blended variant: accumulation, revealage, frame.
pub const OIT_RESOLVE_WEIGHTED: Kernel<OitParams> = linear("transparency::oit_resolve_weighted", 3);

// Device-wide scan fix-ups (`entries.rs`).
pub const SCAN_ADD_OFFSETS: Kernel<ScanFixParams> = linear("entries::scan_add_offsets", 2);

// NURBS tessellation pass (`tessellation.rs`): one invocation per grid vertex, one per quad.
/// Headers, knots, control points, positions, normals, uvs.
pub const NURBS_VERTICES: Kernel<TessellationParams> = linear("tessellation::nurbs_vertices", 6);
/// Headers, indices.
pub const NURBS_INDICES: Kernel<TessellationParams> = linear("tessellation::nurbs_indices", 2);
/// Adaptive levels, one invocation per patch: headers, knots, control points, draw arguments.
pub const NURBS_LEVELS: Kernel<TessLevelParams> = Kernel::new("tessellation::nurbs_levels", 4, [64, 1, 1], false);

// Radix sort (`entries.rs`, `radix.rs`): cooperative (barriers, ballots).
const fn radix<P>(entry: &'static str, storage_buffers: u32) -> Kernel<P> {
    Kernel::new(entry, storage_buffers, [crate::radix::SORT_WORKGROUP, 1, 1], true)
}
pub const RADIX_HISTOGRAM: Kernel<RadixParams> = radix("entries::radix_histogram", 2);
pub const RADIX_UPSWEEP: Kernel<RadixParams> = radix("entries::radix_upsweep", 2);
pub const RADIX_SPINE: Kernel<RadixParams> = radix("entries::radix_spine", 3);
pub const RADIX_DOWNSWEEP: Kernel<RadixParams> = radix("entries::radix_downsweep", 5);
pub const RADIX_SORT_TILE: Kernel<RadixParams> = radix("entries::radix_sort_tile", 2);
pub const RADIX_CHAINED: Kernel<RadixParams> = radix("entries::radix_chained", 6);

// Clustered-BVH technique (`clustered_bvh.rs`).
pub const LIGHT_KEYS: Kernel<MortonParams> = linear("clustered_bvh::light_keys", 3);
pub const BVH_SPHERES: Kernel<BvhParams> = linear("clustered_bvh::bvh_spheres", 3);
/// One subgroup per leaf node: cooperative.
pub const BVH_LEAVES: Kernel<BvhParams> = Kernel::new("clustered_bvh::bvh_leaves", 2, [crate::light_bvh::WALK_WORKGROUP, 1, 1], true);
pub const BVH_LEVEL: Kernel<BvhParams> = linear("clustered_bvh::bvh_level", 1);
/// One subgroup per unique cluster (subgroup-parallel walk): cooperative.
pub const ASSIGN_LIGHTS_BVH: Kernel<BvhAssignParams> =
    Kernel::new("clustered_bvh::assign_lights_bvh", 11, [crate::light_bvh::WALK_WORKGROUP, 1, 1], true);

// Tiled techniques (`tiled.rs`): one cooperative workgroup of 256 per screen tile.
pub const SHADE_TILED_DIFFUSE: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_diffuse", 10, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true);
pub const SHADE_TILED_SPECULAR: Kernel<TiledParams> = Kernel::new("tiled::shade_tiled_specular", 10, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true);

// Clustered-AABB technique (`clustered_aabb.rs`): fixed grid, precomputed boxes.
pub const AABB_BOUNDS: Kernel<FrameParams> = linear("clustered_aabb::aabb_bounds", 2);
pub const AABB_MARK: Kernel<FrameParams> = linear("clustered_aabb::aabb_mark", 4);
pub const AABB_COMPACT: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_compact", 3, [256, 1, 1], true);
pub const AABB_ASSIGN: Kernel<FrameParams> = Kernel::new("clustered_aabb::aabb_assign", 7, [256, 1, 1], true);
pub const SHADE_AABB_DIFFUSE: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_diffuse", 14);
pub const SHADE_AABB_SPECULAR: Kernel<FrameParams> = linear("clustered_aabb::shade_aabb_specular", 14);

// Forward+ (`forward_plus.rs`): tiled culling into per-tile lists, `[linked, array]` (the list
// layouts of `render --fp-lists`).
pub const FORWARD_PLUS_CULL: [Kernel<TiledParams>; 2] = [
    Kernel::new("forward_plus::forward_plus_cull", 5, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true),
    Kernel::new("forward_plus::forward_plus_cull_array", 5, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true),
];
/// [`FORWARD_PLUS_CULL`] with each tile's bounds widened to its transparent fragments (binding 5:
/// their depth ranges; scenes with transparent draws).
pub const FORWARD_PLUS_CULL_WIDENED: [Kernel<TiledParams>; 2] = [
    Kernel::new("forward_plus::forward_plus_cull_widened", 6, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true),
    Kernel::new("forward_plus::forward_plus_cull_array_widened", 6, [crate::tile_cull::TILED_WORKGROUP, 1, 1], true),
];

// Bitonic-warp merge sort (`entries.rs`, `bitonic.rs`): the block sort gives each workgroup a
// block, the merge each subgroup a piece (both cooperative); the splitters are one invocation
// per sample.
pub const BITONIC_BLOCK_SORT: Kernel<BitonicParams> =
    Kernel::new("entries::bitonic_block_sort", 4, [crate::bitonic::BLOCK_WORKGROUP, 1, 1], true);
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
    ALLOCATE_PAGES.erased(),
    STORE_SLOTS.erased(),
    COUNT_PAGE_SLOTS.erased(),
    SCAN_PAGE_COUNTS.erased(),
    COMPACT_PAGE_SLOTS.erased(),
    CLUSTER_LIGHT_COUNTS.erased(),
    CLUSTER_LIGHT_FILL.erased(),
    SHADE_CLUSTERED_DIFFUSE.erased(),
    SHADE_CLUSTERED_SPECULAR.erased(),
    TILE_CLUSTERS.erased(),
    SHADE_CLUSTERED_TILES_DIFFUSE.erased(),
    SHADE_CLUSTERED_TILES_SPECULAR.erased(),
    SHADE_EDGES_AABB[0].erased(),
    SHADE_EDGES_AABB[1].erased(),
    SHADE_EDGES_CLUSTERED[0].erased(),
    SHADE_EDGES_CLUSTERED[1].erased(),
    SHADE_EDGES_CLUSTERED_TILES[0].erased(),
    SHADE_EDGES_CLUSTERED_TILES[1].erased(),
    SHADE_DEFERRED_DIFFUSE.erased(),
    SHADE_DEFERRED_SPECULAR.erased(),
    SHADE_EDGES_DEFERRED[0].erased(),
    SHADE_EDGES_DEFERRED[1].erased(),
    MSAA_GATHER.erased(),
    MSAA_EDGE_ARGS.erased(),
    FORWARD_GATHER.erased(),
    FORWARD_RESOLVE.erased(),
    OIT_RESOLVE.erased(),
    OIT_RESOLVE_WEIGHTED.erased(),
    SCAN_ADD_OFFSETS.erased(),
    NURBS_VERTICES.erased(),
    NURBS_INDICES.erased(),
    NURBS_LEVELS.erased(),
    RADIX_HISTOGRAM.erased(),
    RADIX_UPSWEEP.erased(),
    RADIX_SPINE.erased(),
    RADIX_DOWNSWEEP.erased(),
    RADIX_SORT_TILE.erased(),
    RADIX_CHAINED.erased(),
    LIGHT_KEYS.erased(),
    BVH_SPHERES.erased(),
    BVH_LEAVES.erased(),
    BVH_LEVEL.erased(),
    ASSIGN_LIGHTS_BVH.erased(),
    SHADE_TILED_DIFFUSE.erased(),
    SHADE_TILED_SPECULAR.erased(),
    AABB_BOUNDS.erased(),
    AABB_MARK.erased(),
    AABB_COMPACT.erased(),
    AABB_ASSIGN.erased(),
    SHADE_AABB_DIFFUSE.erased(),
    SHADE_AABB_SPECULAR.erased(),
    FORWARD_PLUS_CULL[0].erased(),
    FORWARD_PLUS_CULL[1].erased(),
    FORWARD_PLUS_CULL_WIDENED[0].erased(),
    FORWARD_PLUS_CULL_WIDENED[1].erased(),
    BITONIC_BLOCK_SORT.erased(),
    BITONIC_SPLITTERS.erased(),
    BITONIC_MERGE.erased(),
    crate::shadow_cull::handles::SHADOW_CULL.erased(),
    crate::shadow_cull::handles::SHADOW_DRAW_ARGS.erased(),
    crate::shadow_raster::handles::SHADOW_RASTER.erased(),
    crate::shadow_receivers::handles::SHADOW_RECEIVER_TILES.erased(),
    crate::shadow_receivers::handles::SHADOW_RECEIVER_FACES.erased(),
    crate::shadow_atlas::handles::SHADOW_FACE_LEVELS.erased(),
    crate::shadow_atlas::handles::SHADOW_FACE_ALLOC.erased(),
];

/// A vertex + fragment entry pair of the raster module, drawn with vertex pulling: set 0 holds
/// `vertex_storage_buffers` storage buffers read by the vertex stage, then
/// `fragment_storage_buffers` read by the fragment stage, then `fragment_samplers` combined image
/// samplers; the fragment stage's push constants are a `P`.
pub struct RasterKernel<P> {
    pub vertex: &'static str,
    pub fragment: &'static str,
    pub vertex_storage_buffers: u32,
    pub fragment_storage_buffers: u32,
    pub fragment_samplers: u32,
    _params: PhantomData<fn() -> P>,
}

impl<P> RasterKernel<P> {
    /// A pass drawing scene geometry: its vertex stage binds the [`RASTER_VERTEX_BUFFERS`].
    pub const fn new(vertex: &'static str, fragment: &'static str, fragment_storage_buffers: u32, fragment_samplers: u32) -> Self {
        Self::with_vertex_buffers(vertex, fragment, RASTER_VERTEX_BUFFERS, fragment_storage_buffers, fragment_samplers)
    }

    /// A pass whose vertex stage binds `vertex_storage_buffers` buffers of its own (a draw of
    /// something else than the scene's meshes).
    pub const fn with_vertex_buffers(vertex: &'static str, fragment: &'static str, vertex_storage_buffers: u32, fragment_storage_buffers: u32, fragment_samplers: u32) -> Self {
        Self { vertex, fragment, vertex_storage_buffers, fragment_storage_buffers, fragment_samplers, _params: PhantomData }
    }

    /// The handle without its push-constant type, for lists of entries.
    pub const fn erased(&self) -> RasterKernel<()> {
        RasterKernel::with_vertex_buffers(self.vertex, self.fragment, self.vertex_storage_buffers, self.fragment_storage_buffers, self.fragment_samplers)
    }

    /// Bindings of set 0, every stage.
    pub const fn bindings(&self) -> u32 {
        self.vertex_storage_buffers + self.fragment_storage_buffers + self.fragment_samplers
    }
}

impl<P> Clone for RasterKernel<P> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<P> Copy for RasterKernel<P> {}

/// Storage buffers of every raster vertex stage: positions, normals, uvs, camera.
pub const RASTER_VERTEX_BUFFERS: u32 = 4;

/// G-buffer variants by what a draw's material needs (`[plain, textured, alpha-tested]`; the
/// samplers: none, albedo, albedo + mask), writing octahedral normals (one word per pixel).
pub const GBUFFER: [RasterKernel<DrawParams>; 3] = [
    RasterKernel::new("raster::gbuffer_vs", "raster::gbuffer_fs", 0, 0),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_textured", 0, 1),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_masked", 0, 2),
];
/// [`GBUFFER`] writing float32 normals (four words per pixel).
pub const GBUFFER_F32: [RasterKernel<DrawParams>; 3] = [
    RasterKernel::new("raster::gbuffer_vs", "raster::gbuffer_fs_f32", 0, 0),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_textured_f32", 0, 1),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_masked_f32", 0, 2),
];
/// [`GBUFFER`] for the multisampled G-buffer (`--msaa`, `msaa.rs`): normals of any precision in
/// a float target (`msaa::float_normal`).
pub const GBUFFER_MS: [RasterKernel<DrawParams>; 3] = [
    RasterKernel::new("raster::gbuffer_vs", "raster::gbuffer_fs_ms", 0, 0),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_textured_ms", 0, 1),
    RasterKernel::new("raster::gbuffer_vs_uv", "raster::gbuffer_fs_masked_ms", 0, 2),
];
/// Forward+ depth pre-pass `[opaque, alpha-tested]`: writes each pixel's winning draw.
pub const FORWARD_DEPTH: [RasterKernel<ForwardParams>; 2] = [
    RasterKernel::new("raster_forward::depth_vs", "raster_forward::depth_fs", 0, 0),
    RasterKernel::new("raster_forward::depth_vs_uv", "raster_forward::depth_fs_masked", 0, 2),
];
/// [`FORWARD_DEPTH`] at `N` samples (`--msaa`, `forward_msaa.rs`): the winning draw as a float.
pub const FORWARD_DEPTH_MS: [RasterKernel<ForwardParams>; 2] = [
    RasterKernel::new("raster_forward::depth_vs", "raster_forward_ms::depth_fs_ms", 0, 0),
    RasterKernel::new("raster_forward::depth_vs_uv", "raster_forward_ms::depth_fs_masked_ms", 0, 2),
];
/// Storage buffers of the forward pass's fragment stage: the tile lists (heads and nodes, or
/// ranges and indices), lights, materials, counters, winning draws, and the shadow slots and maps
/// (`shadow::CubeShadows`).
pub const FORWARD_FRAGMENT_BUFFERS: u32 = 8;
/// Forward+ shading pass `[list layout][plain, textured, alpha-tested]` (layouts `[linked,
/// array]` as [`FORWARD_PLUS_CULL`]; variants as [`GBUFFER`]).
pub const FORWARD_SHADE: [[RasterKernel<ForwardParams>; 3]; 2] = [
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_forward::forward_fs", FORWARD_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward::forward_fs_textured", FORWARD_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward::forward_fs_masked", FORWARD_FRAGMENT_BUFFERS, 2),
    ],
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_forward::forward_fs_array", FORWARD_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward::forward_fs_textured_array", FORWARD_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward::forward_fs_masked_array", FORWARD_FRAGMENT_BUFFERS, 2),
    ],
];
/// Storage buffers of the multisampled forward pass's fragment stage: the tile lists, lights,
/// materials, counters, winning triangles and the pre-pass's depth planes (no shadow maps:
/// shadows are shaded once per pixel, and `render` refuses them with `--msaa`).
pub const FORWARD_FRAGMENT_BUFFERS_MS: u32 = 7;
/// [`FORWARD_SHADE`] at `N` samples (`--msaa`, `forward_msaa.rs`).
pub const FORWARD_SHADE_MS: [[RasterKernel<ForwardParams>; 3]; 2] = [
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_forward_ms::forward_fs_ms", FORWARD_FRAGMENT_BUFFERS_MS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward_ms::forward_fs_textured_ms", FORWARD_FRAGMENT_BUFFERS_MS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward_ms::forward_fs_masked_ms", FORWARD_FRAGMENT_BUFFERS_MS, 2),
    ],
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_forward_ms::forward_fs_ms_array", FORWARD_FRAGMENT_BUFFERS_MS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward_ms::forward_fs_textured_ms_array", FORWARD_FRAGMENT_BUFFERS_MS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_forward_ms::forward_fs_masked_ms_array", FORWARD_FRAGMENT_BUFFERS_MS, 2),
    ],
];

/// Cluster pre-pass of the transparent draws (`raster_transparent`): bounds, marks (page marks,
/// dense-grid flags or tile depth ranges), page table, slots.
pub const TRANSPARENT_KEYS: RasterKernel<TransparentParams> = RasterKernel::new("raster_forward::depth_vs", "raster_transparent::transparent_keys_fs", 4, 0);
/// Storage buffers of the transparent pass's fragment stage (`raster_transparent`): bounds, page
/// table, slot ranks, unique clusters, cluster counters, counts, offsets, list, lights,
/// materials, heads, nodes, OIT counters (the techniques without a page table bind their own
/// lists in some of these: `raster_transparent::fragment_list`).
pub const TRANSPARENT_FRAGMENT_BUFFERS: u32 = 13;
/// The transparent pass `[over the cluster lists, over every light][plain, textured, alpha-tested]`
/// (variants and vertex shaders as [`GBUFFER`]).
pub const TRANSPARENT_SHADE: [[RasterKernel<TransparentParams>; 3]; 2] = [
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_transparent::transparent_fs", TRANSPARENT_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::transparent_fs_textured", TRANSPARENT_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::transparent_fs_masked", TRANSPARENT_FRAGMENT_BUFFERS, 2),
    ],
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_transparent::transparent_fs_all_lights", TRANSPARENT_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::transparent_fs_textured_all_lights", TRANSPARENT_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::transparent_fs_masked_all_lights", TRANSPARENT_FRAGMENT_BUFFERS, 2),
    ],
];

/// Storage buffers of the weighted blended pass's fragment stage: [`TRANSPARENT_FRAGMENT_BUFFERS`]
/// without heads and nodes.
pub const WEIGHTED_FRAGMENT_BUFFERS: u32 = 11;
/// The weighted blended transparent pass (`--oit weighted`), as [`TRANSPARENT_SHADE`].
pub const TRANSPARENT_WEIGHTED: [[RasterKernel<TransparentParams>; 3]; 2] = [
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_transparent::weighted_fs", WEIGHTED_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::weighted_fs_textured", WEIGHTED_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::weighted_fs_masked", WEIGHTED_FRAGMENT_BUFFERS, 2),
    ],
    [
        RasterKernel::new("raster::gbuffer_vs", "raster_transparent::weighted_fs_all_lights", WEIGHTED_FRAGMENT_BUFFERS, 0),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::weighted_fs_textured_all_lights", WEIGHTED_FRAGMENT_BUFFERS, 1),
        RasterKernel::new("raster::gbuffer_vs_uv", "raster_transparent::weighted_fs_masked_all_lights", WEIGHTED_FRAGMENT_BUFFERS, 2),
    ],
];

/// Every vertex entry point of the raster module (from the handles above).
pub const VERTEX_ENTRIES: &[&str] = &[GBUFFER[0].vertex, GBUFFER[1].vertex, FORWARD_DEPTH[0].vertex, FORWARD_DEPTH[1].vertex, crate::shadow_cull::handles::SHADOW_BATCHES.vertex];
/// Every fragment entry point of the raster module (from the handles above).
pub const FRAGMENT_ENTRIES: &[&str] = &[
    GBUFFER[0].fragment,
    GBUFFER[1].fragment,
    GBUFFER[2].fragment,
    GBUFFER_F32[0].fragment,
    GBUFFER_F32[1].fragment,
    GBUFFER_F32[2].fragment,
    GBUFFER_MS[0].fragment,
    GBUFFER_MS[1].fragment,
    GBUFFER_MS[2].fragment,
    FORWARD_DEPTH[0].fragment,
    FORWARD_DEPTH[1].fragment,
    FORWARD_SHADE[0][0].fragment,
    FORWARD_SHADE[0][1].fragment,
    FORWARD_SHADE[0][2].fragment,
    FORWARD_SHADE[1][0].fragment,
    FORWARD_SHADE[1][1].fragment,
    FORWARD_SHADE[1][2].fragment,
    FORWARD_DEPTH_MS[0].fragment,
    FORWARD_DEPTH_MS[1].fragment,
    FORWARD_SHADE_MS[0][0].fragment,
    FORWARD_SHADE_MS[0][1].fragment,
    FORWARD_SHADE_MS[0][2].fragment,
    FORWARD_SHADE_MS[1][0].fragment,
    FORWARD_SHADE_MS[1][1].fragment,
    FORWARD_SHADE_MS[1][2].fragment,
    TRANSPARENT_KEYS.fragment,
    TRANSPARENT_SHADE[0][0].fragment,
    TRANSPARENT_SHADE[0][1].fragment,
    TRANSPARENT_SHADE[0][2].fragment,
    TRANSPARENT_SHADE[1][0].fragment,
    TRANSPARENT_SHADE[1][1].fragment,
    TRANSPARENT_SHADE[1][2].fragment,
    TRANSPARENT_WEIGHTED[0][0].fragment,
    TRANSPARENT_WEIGHTED[0][1].fragment,
    TRANSPARENT_WEIGHTED[0][2].fragment,
    TRANSPARENT_WEIGHTED[1][0].fragment,
    TRANSPARENT_WEIGHTED[1][1].fragment,
    TRANSPARENT_WEIGHTED[1][2].fragment,
    crate::shadow_cull::handles::SHADOW_BATCHES.fragment,
];
