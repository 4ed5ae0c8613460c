//! Every host↔GPU struct and constant, in one place.
//!
//! Rules: `#[repr(C)]`, only `u32`/`f32`/arrays of them (no `vec3`: std430 would pad it), explicit
//! padding fields, size a multiple of 16 bytes, and a compile-time size assert next to each
//! struct. The host derives `bytemuck::Pod` (derive is compiled only off the GPU). Push-constant
//! structs stay within the 128 bytes Vulkan guarantees ([`MAX_PUSH_CONSTANT_BYTES`]).

#[cfg(not(target_arch = "spirv"))]
use bytemuck::{Pod, Zeroable};

/// Push-constant bytes every Vulkan implementation provides.
pub const MAX_PUSH_CONSTANT_BYTES: usize = 128;

/// Screen tiles × exponential depth slices (Olsson et al. 2012, §3.1; Karas' Vulkan design).
/// Built on the host by [`ClusterGrid::new`](crate::cluster_key); methods in [`crate::cluster_key`].
///
/// Cluster key bit layout (widths derived from the resolution, see `cluster_key`):
/// ```text
///  31            bits_i+bits_j   bits_i          0
///  ┌────────────────┬───────────────┬─────────────┐
///  │  k (slice)     │  j (tile row) │ i (tile col)│
///  └────────────────┴───────────────┴─────────────┘
///   bits_k bits       bits_j bits     bits_i bits      (at 3840×2160, 32 px: 7 + 7 + 10)
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ClusterGrid {
    pub width: u32,
    pub height: u32,
    /// Tile edge in pixels.
    pub tile_size: u32,
    /// `ceil(width / tile_size)`.
    pub tiles_x: u32,
    /// `ceil(height / tile_size)` — `S_y` of the slice formula.
    pub tiles_y: u32,
    /// Depth slices between `near` and `far`.
    pub num_slices: u32,
    pub bits_i: u32,
    pub bits_j: u32,
    pub bits_k: u32,
    /// Near plane distance (> 0), view-space units.
    pub near: f32,
    pub far: f32,
    /// `ln(1 + 2·tan(θ)/S_y)`, θ = half the vertical field of view: the log-depth of one slice.
    pub log_growth: f32,
    /// `1 / log_growth`.
    pub inv_log_growth: f32,
    /// `tan(θ)`.
    pub tan_half_fov_y: f32,
    /// Samples per pixel of the G-buffer (`--msaa`, `crate::msaa`): 1 but for multisampled frames,
    /// whose G-buffer buffers hold one plane of `width × height` entries per sample.
    pub samples: u32,
    pub _pad: u32,
}
const _: () = assert!(core::mem::size_of::<ClusterGrid>() == 64);

/// Normal-encoding precisions (values of [`OctaParams::precision`]); see [`crate::octahedral`].
pub const PRECISION_OCT8: u32 = 0;
pub const PRECISION_OCT12: u32 = 1;
pub const PRECISION_OCT16: u32 = 2;
pub const PRECISION_F32: u32 = 3;

/// `octa_roundtrip` kernel: `count` normals (`[f32; 4]`, w ignored) → encoded words + decoded.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct OctaParams {
    pub count: u32,
    pub precision: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<OctaParams>() == 16);

/// `cluster_keys` kernel: one key per `(px, py, view_z)` sample.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ClusterKeyParams {
    pub grid: ClusterGrid,
    pub count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ClusterKeyParams>() == 80);
const _: () = assert!(core::mem::size_of::<ClusterKeyParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Input sample of the `cluster_keys` kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct KeySample {
    pub px: u32,
    pub py: u32,
    /// View-space z (negative in front of the camera).
    pub view_z: f32,
    pub _pad: u32,
}
const _: () = assert!(core::mem::size_of::<KeySample>() == 16);

/// `workgroup_scan` kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ScanParams {
    pub count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ScanParams>() == 16);

/// `debug_view` kernel: one RGBA8 pixel per invocation.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct DebugViewParams {
    pub grid: ClusterGrid,
    /// `VIEW_*` code of a [`View::DEBUG`] view.
    pub view: u32,
    /// One of `PRECISION_*`.
    pub precision: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<DebugViewParams>() == 80);
const _: () = assert!(core::mem::size_of::<DebugViewParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// `morton_codes` kernel: quantisers for the 30-bit (10 bits/axis) and 63-bit (21 bits/axis)
/// codes, built on the host by `MortonQuantizer::new` (the only division happens there).
#[repr(C)]
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug, PartialEq, Pod, Zeroable))]
pub struct MortonParams {
    pub q30: crate::morton::MortonQuantizer,
    pub q63: crate::morton::MortonQuantizer,
    pub count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<MortonParams>() == 64);

// ─── Clustered shading ───────────────────────────────────────────────────────────────────────

/// Keys per page of the virtual page table (Karas: 512-entry pages). `page = key >> PAGE_SHIFT`,
/// `slot = key & (PAGE_SIZE − 1)`.
pub const PAGE_SHIFT: u32 = 9;
pub const PAGE_SIZE: u32 = 1 << PAGE_SHIFT;

/// Scene effect flags (`FrameParams::effects`): a scene without one runs no shader path for it.
pub const EFFECT_SPECULAR: u32 = 1;
pub const EFFECT_TEXTURES: u32 = 2;
pub const EFFECT_ALPHA_TEST: u32 = 4;
/// Falloff: plain inverse square `1/(d² + 1)` cut to 0 at the light's radius (the accuracy
/// study's intensity-threshold cut, `lighting::falloff`) instead of Karis' window.
pub const EFFECT_INVERSE_SQUARE_CUT: u32 = 8;
/// Naive clustered assignment tests lights against the cluster's six frustum planes instead of
/// its AABB (accuracy study: `cluster_test::sphere_outside_planes`).
pub const EFFECT_CULL_PLANES: u32 = 16;
/// Naive clustered assignment tests lights against the cluster's frustum exactly (accuracy study:
/// `cluster_test::sphere_meets_frustum`).
pub const EFFECT_CULL_EXACT: u32 = 32;

/// A point light with a finite range. In GPU buffers `position` is in view space (the host
/// transforms lights each frame); in scenes it is in world space.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct PointLight {
    pub position: [f32; 3],
    /// Range: the light contributes exactly 0 at distance ≥ radius.
    pub radius: f32,
    /// Linear RGB.
    pub colour: [f32; 3],
    pub intensity: f32,
}
const _: () = assert!(core::mem::size_of::<PointLight>() == 32);

/// A light's bounding sphere in the BVH's sorted order (`light_bvh`): what the walk tests, 16 B
/// instead of the light's 32, read coalesced at the leaves instead of through the sort's order.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct LightSphere {
    pub position: [f32; 3],
    pub radius: f32,
}
const _: () = assert!(core::mem::size_of::<LightSphere>() == 16);

/// View-space axis-aligned box of one cluster.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ClusterAabb {
    pub min: [f32; 3],
    pub _pad0: f32,
    pub max: [f32; 3],
    pub _pad1: f32,
}
const _: () = assert!(core::mem::size_of::<ClusterAabb>() == 32);

/// Camera of the raster passes (storage buffer, binding 3 of the G-buffer pass). Column-major
/// matrices (glam `Mat4::to_cols_array_2d`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct RasterCamera {
    /// World → view rotation alone: vertex positions arrive relative to the eye (the host draws
    /// camera-relative).
    pub view: [[f32; 4]; 4],
    /// View → clip: reversed-Z, infinite far, y flipped for Vulkan (`clip = (f/a·x, −f·y, near, −z)`).
    pub proj: [[f32; 4]; 4],
}
const _: () = assert!(core::mem::size_of::<RasterCamera>() == 128);

/// Per-draw push constants of the G-buffer pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct DrawParams {
    /// Linear albedo of the material (multiplied with its texture when textured).
    pub albedo: [f32; 3],
    /// Material index (written to the G-buffer, ≤ [`MAX_MATERIALS`] − 1).
    pub material: u32,
    /// `PRECISION_OCT8/12/16`: encoding of the normal target.
    pub normal_precision: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<DrawParams>() == 32);

/// Materials addressable by the G-buffer's 8-bit material index.
pub const MAX_MATERIALS: u32 = 256;

/// Shading parameters of one material (storage buffer indexed by the G-buffer material index).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct MaterialGpu {
    pub specular: f32,
    pub roughness: f32,
    /// In [0, 1], 1 opaque. Draws of materials below 1 leave the G-buffer and are drawn by the
    /// transparent pass (`raster_transparent`), which stores it as their coverage α.
    pub opacity: f32,
    pub _pad: f32,
}
const _: () = assert!(core::mem::size_of::<MaterialGpu>() == 16);

/// Push constants of the clustered / deferred compute chain.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct FrameParams {
    pub grid: ClusterGrid,
    /// Elements of the kernel's linear domain (pixels, pages, slots or clusters).
    pub count: u32,
    pub num_lights: u32,
    /// Capacity of the light-index list (entries); fill never writes beyond it.
    pub light_capacity: u32,
    /// `EFFECT_*` bits of the scene.
    pub effects: u32,
    /// `PRECISION_OCT*` of the G-buffer normals.
    pub normal_precision: u32,
    /// `VIEW_*` of `shading`: shaded image or lights-per-pixel heatmap.
    pub view: u32,
    pub exposure: f32,
    /// Heatmap: count mapped to the top of the ramp.
    pub heat_max: u32,
}
const _: () = assert!(core::mem::size_of::<FrameParams>() == 96);
const _: () = assert!(core::mem::size_of::<FrameParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// `FrameParams::view`: the shaded image, or lights evaluated per pixel as a heat ramp.
pub const VIEW_SHADED: u32 = 0;
pub const VIEW_HEATMAP: u32 = 1;
/// Cluster keys hashed to colours.
pub const VIEW_CLUSTERS: u32 = 2;
/// Decoded G-buffer normals, `0.5·n + 0.5`.
pub const VIEW_NORMALS: u32 = 3;
/// Depth slice `k / S` on a colour ramp.
pub const VIEW_DEPTH: u32 = 4;
/// Angular error of the normal encoding's round trip over its proven bound (debug frame only).
pub const VIEW_OCTA_ERROR: u32 = 5;

/// What a frame shows. One code space serves the shading passes (`FrameParams::view`,
/// [`View::FRAME`]) and the analytic debug frame (`DebugViewParams::view`, [`View::DEBUG`]):
/// each discriminant is the kernel's `VIEW_*` constant.
#[derive(Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug))]
#[repr(u32)]
pub enum View {
    Shaded = VIEW_SHADED,
    Heatmap = VIEW_HEATMAP,
    Clusters = VIEW_CLUSTERS,
    Normals = VIEW_NORMALS,
    Depth = VIEW_DEPTH,
    OctaError = VIEW_OCTA_ERROR,
}

impl View {
    /// Views the shading passes of a rendered frame produce.
    pub const FRAME: [View; 5] = [View::Shaded, View::Heatmap, View::Clusters, View::Normals, View::Depth];
    /// Views of the analytic debug frame (`debug_view`).
    pub const DEBUG: [View; 4] = [View::Normals, View::OctaError, View::Clusters, View::Depth];

    /// The kernel constant (`VIEW_*`).
    #[inline]
    pub const fn code(self) -> u32 {
        self as u32
    }
}

/// Slots of the `counters` buffer of the clustered chain.
pub const COUNTER_UNIQUE_CLUSTERS: u32 = 0;
pub const COUNTER_LIGHT_REFS: u32 = 1;
pub const COUNTER_PAGES: u32 = 2;
/// The frame's unique clusters as the host reads them after the frame: stored by the page
/// table's scan beside `COUNTER_UNIQUE_CLUSTERS`, or, on the tile path (`tile_clusters`), by the
/// shading kernel before it zeroes `COUNTER_UNIQUE_CLUSTERS` for the next frame's atomics.
pub const COUNTER_FRAME_CLUSTERS: u32 = 3;
pub const COUNTERS: u32 = 4;

/// `scan_add_offsets`: the elements `0..count` its workgroups update.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ScanFixParams {
    pub count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ScanFixParams>() == 16);

/// The page table's one-workgroup kernels (`page_table`): `clustered::allocate_pages` allocates
/// the marked ones of `pages` pages of the key space, at most `capacity`, and stores the count of
/// allocated pages in `counters[COUNTER_PAGES]` and a dispatch of one workgroup per allocated
/// page at word `args_offset` of the arguments buffer; `clustered::scan_page_counts` scans the
/// allocated pages' slot counts, stores the unique clusters in
/// `counters[COUNTER_UNIQUE_CLUSTERS]` (and `COUNTER_FRAME_CLUSTERS`) and the assignment's
/// dispatch (`per_group` clusters per workgroup) at word `args_offset`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct PageTableParams {
    pub pages: u32,
    pub capacity: u32,
    pub per_group: u32,
    pub args_offset: u32,
    pub _pad: [u32; 4],
}
const _: () = assert!(core::mem::size_of::<PageTableParams>() == 32);

/// Word offsets of the clustered chain's indirect dispatches (`VkDispatchIndirectCommand`s) in
/// its arguments buffer: one workgroup per allocated page (the page table), and the assignment.
pub const ARGS_PAGES: u32 = 0;
pub const ARGS_ASSIGNMENT: u32 = 3;
pub const ARGS_WORDS: u32 = 6;

/// `clustered::tile_clusters` (`tile_clusters` module): the frame (`count`: the unique-cluster
/// list's capacity) and the assignment's clusters per workgroup (`per_group`), whose dispatch
/// it writes at [`ARGS_ASSIGNMENT`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TileClusterParams {
    pub frame: FrameParams,
    pub per_group: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<TileClusterParams>() == 112);
const _: () = assert!(core::mem::size_of::<TileClusterParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Radix sort kernels (`radix_histogram`, `radix_upsweep`, `radix_spine`, `radix_downsweep`,
/// `radix_sort_tile`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct RadixParams {
    /// Pairs to sort.
    pub count: u32,
    /// Keys are below `2^key_bits` (`radix::passes`, `radix::pass_digit`).
    pub key_bits: u32,
    /// The pass being recorded (its digit and its row of the global histogram).
    pub pass: u32,
    /// Tiles: `⌈count / RADIX_TILE⌉` (the row length of the tile counts).
    pub tiles: u32,
    /// Digits per spine workgroup (`radix::spine_digits`).
    pub spine_digits: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<RadixParams>() == 32);

/// Light-BVH kernels: `count` lights; the level being built and its node count.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct BvhParams {
    pub count: u32,
    pub level: u32,
    /// Nodes of `level`.
    pub nodes: u32,
    /// Children per node (32 or 64: `light_bvh::valid_branching`).
    pub branching: u32,
}
const _: () = assert!(core::mem::size_of::<BvhParams>() == 16);

/// Push constants of the BVH light assignment: the frame's parameters plus the tree's branching.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct BvhAssignParams {
    pub frame: FrameParams,
    /// Children per node of the light BVH (32 or 64).
    pub branching: u32,
    /// Words of the staged light lists, shared out among the frame's clusters
    /// (`clustered_bvh::stage_stride`; 0 without a stage).
    pub stage_words: u32,
    pub _pad: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<BvhAssignParams>() == 112);
const _: () = assert!(core::mem::size_of::<BvhAssignParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Push constants of the tiled techniques (`tiled.rs`): the frame plus the culling mode
/// (`tile_cull::MODE_TILED` or `tile_cull::MODE_TILED_25D`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TiledParams {
    pub frame: FrameParams,
    pub mode: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<TiledParams>() == 112);
const _: () = assert!(core::mem::size_of::<TiledParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Push constants of the Forward+ raster passes (`raster_forward.rs`): the frame and the draw;
/// `frame.count` carries the draw's index (the pre-pass records each pixel's winning draw).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct ForwardParams {
    pub frame: FrameParams,
    pub draw: DrawParams,
}
const _: () = assert!(core::mem::size_of::<ForwardParams>() == 128);
const _: () = assert!(core::mem::size_of::<ForwardParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Bitonic-warp merge sort kernels (`bitonic_block_sort`, `bitonic_splitters`, `bitonic_merge`;
/// see [`crate::bitonic`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct BitonicParams {
    /// Elements to sort.
    pub count: u32,
    /// Splitters / merge: run length of the level (the block sort's blocks are `bitonic::BLOCK`).
    pub run: u32,
    /// Sample stride `g` of the splitters.
    pub stride: u32,
    /// Every `keep`-th sample bounds a piece.
    pub keep: u32,
    /// Block sort: 1 writes back to bindings 0/1 (in place), 0 writes to bindings 2/3.
    pub in_place: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<BitonicParams>() == 32);

// ─── Order-independent transparency ──────────────────────────────────────────────────────────

/// End of a per-pixel fragment list: the cleared value of every head, `next` of a list's last
/// node. Any index `≥ OitParams::capacity` ends a walk too (`oit::walk`).
pub const OIT_END: u32 = u32::MAX;

/// `OitParams::variant`: how a pixel's transparent fragments are resolved (`crate::oit`).
/// Every fragment sorted, back to front, over the opaque colour (exact up to
/// `oit::MAX_EXACT_LAYERS` layers per pixel).
pub const OIT_EXACT: u32 = 0;
/// The `k` nearest sorted over an order-independent average of the others.
pub const OIT_K_NEAREST: u32 = 1;
/// Weighted blended OIT (McGuire & Bavoil 2013): no sorting at all.
pub const OIT_WEIGHTED: u32 = 2;

/// One transparent fragment in a per-pixel linked list (Yang et al. 2010): 20 B.
/// ```text
///  word 0  colour[0]  31             16 15              0
///                    ┌─────────────────┬─────────────────┐
///                    │      G·α        │      R·α        │   16-bit UNORM each: premultiplied
///                    └─────────────────┴─────────────────┘   linear RGBA (`oit::pack_unorm4x16`)
///  word 1  colour[1] │       α         │      B·α        │
///                    └─────────────────┴─────────────────┘
///  word 2  depth    f32 bits of the reversed-Z depth z_buf = near/d, clamped to [0, 1]
///                   (1 = near plane, 0 = infinitely far): as u32, larger = nearer
///  word 3  next     node index of the fragment inserted before it at this pixel, or OIT_END
///  word 4  tie      frame-unique id of the fragment's primitive: orders fragments of equal depth
/// ```
/// The colour is premultiplied (`oit` module docs, "Why premultiplied"): tonemapped linear RGB
/// (display-referred, before the sRGB encoding) times α, and α, 16 bits each ("Why 16 bits").
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct OitNode {
    pub colour: [u32; 2],
    pub depth: u32,
    pub next: u32,
    pub tie: u32,
}
const _: () = assert!(core::mem::size_of::<OitNode>() == 20);

/// Push constants of the transparency passes (list building and resolve).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct OitParams {
    /// Nodes the node buffer holds: fragments whose counter value is at or past it are not
    /// stored (the host grows the buffer to the counter and re-runs the frame).
    pub capacity: u32,
    /// Heads: one per pixel, `py · width + px`.
    pub width: u32,
    pub height: u32,
    /// One of `OIT_*`.
    pub variant: u32,
    /// `OIT_K_NEAREST`: fragments kept sorted (1, 2, 4 or 8; `oit::MAX_K`).
    pub k: u32,
    /// Near-plane distance: view depth `near / z_buf` of a node (the weights of `OIT_WEIGHTED`).
    pub near: f32,
    pub _pad: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<OitParams>() == 32);
const _: () = assert!(core::mem::size_of::<OitParams>() <= MAX_PUSH_CONSTANT_BYTES);

/// Counters of the transparent pass (a buffer of [`OIT_COUNTERS`] words, zeroed per frame).
/// Transparent fragments the frame produced (the node counter: past the capacity, the node
/// buffer grows and the frame re-runs).
pub const OIT_COUNTER_NODES: u32 = 0;
/// Most layers one pixel's list held (the resolve's atomic max).
pub const OIT_COUNTER_MAX_LAYERS: u32 = 1;
/// Pixels the exact resolve composited as k-nearest (more than `oit::MAX_EXACT_LAYERS` layers).
pub const OIT_COUNTER_FALLBACKS: u32 = 2;
/// Transparent fragments whose cluster had no light list (the cluster pre-pass failed to mark
/// it); such a fragment is shaded with no light. Every test requires 0.
pub const OIT_COUNTER_UNLISTED: u32 = 3;
pub const OIT_COUNTERS: u32 = 4;

/// `TransparentDraw::lists`: which light lists the technique keeps, so how a transparent fragment
/// finds its list and what the cluster pre-pass (`raster_transparent::transparent_keys_fs`)
/// marks. The page table (`clustered-naive`, `clustered-bvh`; lookup key → page → slot →
/// cluster) is marked in two steps: the pages of the fragments' clusters (before the page
/// scan) …
pub const TRANSPARENT_MARK_PAGES: u32 = 0;
/// … then their slots (after the pages are allocated).
pub const TRANSPARENT_STORE_SLOTS: u32 = 1;
/// The dense grid (`clustered-aabb`): the pre-pass flags each fragment's dense cluster beside
/// the opaque pixels' flags; the lookup reads that cluster's `(offset, count)`.
pub const TRANSPARENT_DENSE_GRID: u32 = 2;
/// Per-tile arrays (`forward-plus --fp-lists array`): the pre-pass widens its tile's depth range
/// to the fragment (`TILE_DEPTH_WORDS` per tile); the lookup reads the tile's `(offset, count)`.
pub const TRANSPARENT_TILE_ARRAYS: u32 = 3;
/// Per-tile linked lists (`forward-plus --fp-lists linked`): as the arrays, walking the tile's list.
pub const TRANSPARENT_TILE_LINKED: u32 = 4;
/// Words per tile of the transparent fragments' depth range (Forward+): `!min` and `max` of their
/// view distances' bits, both kept by atomic max from 0 (bits of positive floats order like the
/// floats, and `!` turns the minimum into a maximum, so one fill of 0 empties both).
pub const TILE_DEPTH_WORDS: u32 = 2;

/// Slot of the Forward+ counters buffer that allocates light references (nodes or indices).
pub const FP_COUNTER_REFS: u32 = 0;

/// Per-draw push constants of the transparent passes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TransparentDraw {
    /// Linear albedo of the material (multiplied with its texture when textured).
    pub albedo: [f32; 3],
    /// Material index (its specular, roughness and opacity).
    pub material: u32,
    /// `PRECISION_*` the frame's G-buffer normals use (the transparent normal is quantised the same).
    pub normal_precision: u32,
    /// Frame-unique id of the draw's first triangle (the transparent draws' triangles numbered in
    /// draw order): the tie key of `OitNode::tie` is this + `PrimitiveId`.
    pub first_primitive: u32,
    /// Nodes the node buffer holds (`OitParams::capacity`).
    pub capacity: u32,
    /// `TRANSPARENT_MARK_PAGES` … `TRANSPARENT_TILE_LINKED`: the technique's light lists (and
    /// the page table's pre-pass step).
    pub lists: u32,
}
const _: () = assert!(core::mem::size_of::<TransparentDraw>() == 32);

/// Push constants of the transparent raster passes: the frame's and the draw's.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TransparentParams {
    pub frame: FrameParams,
    pub draw: TransparentDraw,
}
const _: () = assert!(core::mem::size_of::<TransparentParams>() == 128);
const _: () = assert!(core::mem::size_of::<TransparentParams>() <= MAX_PUSH_CONSTANT_BYTES);

// ─── NURBS surfaces ──────────────────────────────────────────────────────────────────────────

/// One rational B-spline patch in the tessellation pass's storage buffers (`crate::nurbs`).
///
/// Knots are `f32` in one shared buffer: the u vector at `knot_offset_u` (`size_u + degree_u + 1`
/// values), the v vector at `knot_offset_v` (`size_v + degree_v + 1`). Control points are
/// homogeneous `[f32; 4]` **with premultiplied weights**, `(w·x, w·y, w·z, w)`, in one shared
/// buffer: point `(i, j)` (i along u) at `cp_offset + j·size_u + i`. The tessellated grid has
/// `(level + 1)²` vertices from `vertex_offset` and `6·level²` indices from `index_offset`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct NurbsPatchGpu {
    /// Degree in u, 1..=`nurbs::MAX_DEGREE`.
    pub degree_u: u32,
    pub degree_v: u32,
    /// Control points along u (`n + 1`), at least `degree_u + 1`.
    pub size_u: u32,
    pub size_v: u32,
    /// Element index of the first u knot in the knot buffer.
    pub knot_offset_u: u32,
    pub knot_offset_v: u32,
    /// Element index of control point (0, 0) in the control-point buffer.
    pub cp_offset: u32,
    /// Quads along each parameter direction (≥ 1).
    pub level: u32,
    /// First vertex of the patch in the vertex streams.
    pub vertex_offset: u32,
    /// First index of the patch in the index buffer.
    pub index_offset: u32,
    /// Material index of the patch's triangles.
    pub material: u32,
    pub _pad: u32,
}
const _: () = assert!(core::mem::size_of::<NurbsPatchGpu>() == 48);

/// Push constants of the tessellation kernels (`crate::tessellation`): the patches' headers are
/// `patch_count` entries of the header buffer, sorted by their vertex and index offsets; the
/// grids fill the vertex streams from `first_vertex` (`vertex_count` vertices) and the index
/// buffer from `first_index` (`quad_count` quads of six indices), without gaps.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TessellationParams {
    pub patch_count: u32,
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub quad_count: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<TessellationParams>() == 32);

/// Push constants of the adaptive level kernel (`crate::tessellation::nurbs_levels`): each of
/// `patch_count` patches gets the level (1..=`max_level`) at which its grid stays within
/// `tolerance` pixels of the surface, its control points being camera-relative and the frame
/// `pixel_scale = height / (2·tan(fov_y / 2))` pixels per unit of size at unit distance.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Pod, Zeroable))]
pub struct TessLevelParams {
    pub patch_count: u32,
    pub max_level: u32,
    pub pixel_scale: f32,
    /// Pixels, > 0.
    pub tolerance: f32,
    /// The near plane: the smallest distance the estimate divides by.
    pub near: f32,
    pub _pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<TessLevelParams>() == 32);
