//! The GPU as the algorithms see it: a Vulkan context plus one typed pipeline per kernel of the
//! compute module and per raster pass of the raster module that `build.rs` compiled from
//! `shader-crate` (both embedded in the binary, each module created once and shared), built when
//! the device opens. The entries that shade or cull punctual lights are [`LightCompute`] /
//! [`LightRaster`]: a pipeline per light-type mix, created when a frame first needs it
//! (`vk::light_typed`).
use crate::vk::{Blend, ComputePipeline, Context, ContextOptions, DepthTest, GraphicsPipeline, LightTyped, LightTypedModules, Profiler, Recorder, ShaderModule, TargetFormat, VkResult};
use shaders::kernels::{self, RasterKernel};
use shaders::layout::*;
use std::sync::Arc;

/// A compute kernel specialised by the frame's light types ([`LightTyped::get`]).
pub type LightCompute<P> = LightTyped<ComputePipeline<P>>;
/// A raster pass specialised by the frame's light types ([`LightTyped::get`]).
pub type LightRaster<P> = LightTyped<GraphicsPipeline<P>>;

/// The compute SPIR-V module (rust-gpu output), embedded at build time.
pub const COMPUTE_SPV: &[u8] = include_bytes!(env!("MANYLIGHTS_COMPUTE_SPV"));

/// Pipelines of every compute kernel.
pub struct Kernels {
    pub octa_roundtrip: ComputePipeline<OctaParams>,
    pub cluster_keys: ComputePipeline<ClusterKeyParams>,
    pub morton_codes: ComputePipeline<MortonParams>,
    pub workgroup_scan: ComputePipeline<ScanParams>,
    pub debug_view: ComputePipeline<DebugViewParams>,
    pub pixel_keys: ComputePipeline<FrameParams>,
    pub allocate_pages: ComputePipeline<PageTableParams>,
    pub count_page_slots: ComputePipeline<()>,
    pub scan_page_counts: ComputePipeline<PageTableParams>,
    pub compact_page_slots: ComputePipeline<()>,
    pub store_slots: ComputePipeline<FrameParams>,
    pub cluster_light_counts: LightCompute<FrameParams>,
    pub cluster_light_fill: LightCompute<FrameParams>,
    /// Shading variants `[diffuse only, with specular]`: a scene runs only the one it needs.
    pub shade_clustered: [LightCompute<FrameParams>; 2],
    /// The tile path of the unique clusters (`shaders::tile_clusters`) and its shading.
    pub tile_clusters: ComputePipeline<TileClusterParams>,
    pub shade_clustered_tiles: [LightCompute<FrameParams>; 2],
    pub shade_deferred: [LightCompute<FrameParams>; 2],
    pub scan_add_offsets: ComputePipeline<ScanFixParams>,
    pub radix_histogram: ComputePipeline<RadixParams>,
    pub radix_upsweep: ComputePipeline<RadixParams>,
    pub radix_spine: ComputePipeline<RadixParams>,
    pub radix_downsweep: ComputePipeline<RadixParams>,
    pub radix_sort_tile: ComputePipeline<RadixParams>,
    pub radix_chained: ComputePipeline<RadixParams>,
    pub bitonic_block_sort: ComputePipeline<BitonicParams>,
    pub bitonic_splitters: ComputePipeline<BitonicParams>,
    pub bitonic_merge: ComputePipeline<BitonicParams>,
    pub light_keys: LightCompute<MortonParams>,
    pub bvh_spheres: LightCompute<BvhParams>,
    pub bvh_leaves: ComputePipeline<BvhParams>,
    pub bvh_level: ComputePipeline<BvhParams>,
    pub assign_lights_bvh: LightCompute<BvhAssignParams>,
    /// Tiled culling + shading `[diffuse only, with specular]`.
    pub shade_tiled: [LightCompute<TiledParams>; 2],
    pub aabb_bounds: ComputePipeline<FrameParams>,
    pub aabb_mark: ComputePipeline<FrameParams>,
    pub aabb_compact: ComputePipeline<FrameParams>,
    pub aabb_assign: LightCompute<FrameParams>,
    pub shade_aabb: [LightCompute<FrameParams>; 2],
    /// Forward+ culling into per-tile lists `[linked, array]` (`render::forward_plus::TileLists`).
    pub forward_plus_cull: [LightCompute<TiledParams>; 2],
    /// [`Kernels::forward_plus_cull`] over tile bounds widened to the transparent fragments.
    pub forward_plus_cull_widened: [LightCompute<TiledParams>; 2],
}

impl Kernels {
    pub fn new(ctx: &Context, module: &Arc<ShaderModule>, light: &Arc<LightTypedModules>) -> VkResult<Self> {
        Ok(Self {
            octa_roundtrip: ComputePipeline::new(ctx, module, kernels::OCTA_ROUNDTRIP)?,
            cluster_keys: ComputePipeline::new(ctx, module, kernels::CLUSTER_KEYS)?,
            morton_codes: ComputePipeline::new(ctx, module, kernels::MORTON_CODES)?,
            workgroup_scan: ComputePipeline::new(ctx, module, kernels::WORKGROUP_SCAN)?,
            debug_view: ComputePipeline::new(ctx, module, kernels::DEBUG_VIEW)?,
            pixel_keys: ComputePipeline::new(ctx, module, kernels::PIXEL_KEYS)?,
            allocate_pages: ComputePipeline::new(ctx, module, kernels::ALLOCATE_PAGES)?,
            count_page_slots: ComputePipeline::new(ctx, module, kernels::COUNT_PAGE_SLOTS)?,
            scan_page_counts: ComputePipeline::new(ctx, module, kernels::SCAN_PAGE_COUNTS)?,
            compact_page_slots: ComputePipeline::new(ctx, module, kernels::COMPACT_PAGE_SLOTS)?,
            store_slots: ComputePipeline::new(ctx, module, kernels::STORE_SLOTS)?,
            cluster_light_counts: LightTyped::compute(light, kernels::CLUSTER_LIGHT_COUNTS),
            cluster_light_fill: LightTyped::compute(light, kernels::CLUSTER_LIGHT_FILL),
            shade_clustered: [
                LightTyped::compute(light, kernels::SHADE_CLUSTERED_DIFFUSE),
                LightTyped::compute(light, kernels::SHADE_CLUSTERED_SPECULAR),
            ],
            tile_clusters: ComputePipeline::new(ctx, module, kernels::TILE_CLUSTERS)?,
            shade_clustered_tiles: [
                LightTyped::compute(light, kernels::SHADE_CLUSTERED_TILES_DIFFUSE),
                LightTyped::compute(light, kernels::SHADE_CLUSTERED_TILES_SPECULAR),
            ],
            shade_deferred: [
                LightTyped::compute(light, kernels::SHADE_DEFERRED_DIFFUSE),
                LightTyped::compute(light, kernels::SHADE_DEFERRED_SPECULAR),
            ],
            scan_add_offsets: ComputePipeline::new(ctx, module, kernels::SCAN_ADD_OFFSETS)?,
            radix_histogram: ComputePipeline::new(ctx, module, kernels::RADIX_HISTOGRAM)?,
            radix_upsweep: ComputePipeline::new(ctx, module, kernels::RADIX_UPSWEEP)?,
            radix_spine: ComputePipeline::new(ctx, module, kernels::RADIX_SPINE)?,
            radix_downsweep: ComputePipeline::new(ctx, module, kernels::RADIX_DOWNSWEEP)?,
            radix_sort_tile: ComputePipeline::new(ctx, module, kernels::RADIX_SORT_TILE)?,
            radix_chained: ComputePipeline::new(ctx, module, kernels::RADIX_CHAINED)?,
            bitonic_block_sort: ComputePipeline::new(ctx, module, kernels::BITONIC_BLOCK_SORT)?,
            bitonic_splitters: ComputePipeline::new(ctx, module, kernels::BITONIC_SPLITTERS)?,
            bitonic_merge: ComputePipeline::new(ctx, module, kernels::BITONIC_MERGE)?,
            light_keys: LightTyped::compute(light, kernels::LIGHT_KEYS),
            bvh_spheres: LightTyped::compute(light, kernels::BVH_SPHERES),
            bvh_leaves: ComputePipeline::new(ctx, module, kernels::BVH_LEAVES)?,
            bvh_level: ComputePipeline::new(ctx, module, kernels::BVH_LEVEL)?,
            assign_lights_bvh: LightTyped::compute(light, kernels::ASSIGN_LIGHTS_BVH),
            shade_tiled: [
                LightTyped::compute(light, kernels::SHADE_TILED_DIFFUSE),
                LightTyped::compute(light, kernels::SHADE_TILED_SPECULAR),
            ],
            aabb_bounds: ComputePipeline::new(ctx, module, kernels::AABB_BOUNDS)?,
            aabb_mark: ComputePipeline::new(ctx, module, kernels::AABB_MARK)?,
            aabb_compact: ComputePipeline::new(ctx, module, kernels::AABB_COMPACT)?,
            aabb_assign: LightTyped::compute(light, kernels::AABB_ASSIGN),
            shade_aabb: [
                LightTyped::compute(light, kernels::SHADE_AABB_DIFFUSE),
                LightTyped::compute(light, kernels::SHADE_AABB_SPECULAR),
            ],
            forward_plus_cull: [
                LightTyped::compute(light, kernels::FORWARD_PLUS_CULL[0]),
                LightTyped::compute(light, kernels::FORWARD_PLUS_CULL[1]),
            ],
            forward_plus_cull_widened: kernels::FORWARD_PLUS_CULL_WIDENED.map(|k| LightTyped::compute(light, k)),
        })
    }
}

/// The raster SPIR-V module (rust-gpu output of the `graphics` feature), embedded at build time.
pub const GRAPHICS_SPV: &[u8] = include_bytes!(env!("MANYLIGHTS_GRAPHICS_SPV"));

/// G-buffer normal target formats: `[octahedral (one word), float32 (four words)]`.
pub const NORMAL_FORMATS: [TargetFormat; 2] = [TargetFormat::R32Uint, TargetFormat::Rgba32Uint];
/// G-buffer albedo (RGBA8, alpha = material index).
pub const ALBEDO_FORMAT: TargetFormat = TargetFormat::Rgba8Unorm;
/// Forward+'s colour targets: the frame's packed RGBA8 word, and each pixel's winning draw.
pub const FORWARD_COLOUR_FORMAT: TargetFormat = TargetFormat::R32Uint;

/// Index into [`NORMAL_FORMATS`] (and the outer index of [`RasterPipelines::gbuffer`]) for a
/// normal precision (`PRECISION_*`).
pub fn normal_target(precision: u32) -> usize {
    usize::from(shaders::octahedral::Precision::from_u32(precision).gbuffer_words() == 4)
}

/// Pipelines of every raster pass, built once with the device.
pub struct RasterPipelines {
    /// G-buffer `[normal target][variant]` ([`normal_target`]; variants of `kernels::GBUFFER`).
    pub gbuffer: [[GraphicsPipeline<DrawParams>; 3]; 2],
    /// Forward+ depth pre-pass `[opaque, alpha-tested]`.
    pub forward_depth: [GraphicsPipeline<ForwardParams>; 2],
    /// Forward+ shading `[list layout][plain, textured, alpha-tested]` (layouts `[linked, array]`,
    /// `render::forward_plus::TileLists`).
    pub forward_shade: [[LightRaster<ForwardParams>; 3]; 2],
}

impl RasterPipelines {
    pub fn new(ctx: &Context, module: &Arc<ShaderModule>, light: &Arc<LightTypedModules>) -> VkResult<Self> {
        let gbuffer = |target: usize, handles: &[RasterKernel<DrawParams>; 3]| -> VkResult<[GraphicsPipeline<DrawParams>; 3]> {
            let colours = [NORMAL_FORMATS[target], ALBEDO_FORMAT];
            let make = |h: RasterKernel<DrawParams>| GraphicsPipeline::new(ctx, module, h.fragment, h, &colours, DepthTest::NearestWrites);
            Ok([make(handles[0])?, make(handles[1])?, make(handles[2])?])
        };
        let colour = [FORWARD_COLOUR_FORMAT];
        let forward = |h: RasterKernel<ForwardParams>, depth| GraphicsPipeline::new(ctx, module, h.fragment, h, &colour, depth);
        let d = &kernels::FORWARD_DEPTH;
        let shade = |s: &[RasterKernel<ForwardParams>; 3]| s.map(|h| LightTyped::raster(light, h, &[(FORWARD_COLOUR_FORMAT, Blend::Replace)], DepthTest::EqualReadOnly));
        Ok(Self {
            gbuffer: [gbuffer(0, &kernels::GBUFFER)?, gbuffer(1, &kernels::GBUFFER_F32)?],
            forward_depth: [forward(d[0], DepthTest::NearestWrites)?, forward(d[1], DepthTest::NearestWrites)?],
            forward_shade: [shade(&kernels::FORWARD_SHADE[0]), shade(&kernels::FORWARD_SHADE[1])],
        })
    }
}

pub struct Gpu {
    pub kernels: Kernels,
    pub raster: RasterPipelines,
    /// The compute module ([`COMPUTE_SPV`]): passes that create pipelines of their own (the
    /// transparent pass, the tessellation) create them from this one.
    pub compute_module: Arc<ShaderModule>,
    /// The raster module ([`GRAPHICS_SPV`]), likewise.
    pub graphics_module: Arc<ShaderModule>,
    /// The compute module frozen to each light-type mix, for the light-typed kernels.
    pub light_compute: Arc<LightTypedModules>,
    /// The raster module frozen to each light-type mix, for the light-typed raster passes.
    pub light_graphics: Arc<LightTypedModules>,
    pub ctx: Context,
}

impl Gpu {
    pub fn new(opts: &ContextOptions) -> VkResult<Self> {
        Self::with_context(Context::new(opts)?)
    }

    /// A GPU that can also present to windows of `display` (the viewer).
    pub fn for_display(opts: &ContextOptions, display: raw_window_handle::RawDisplayHandle) -> VkResult<Self> {
        Self::with_context(Context::for_display(opts, display)?)
    }

    fn with_context(ctx: Context) -> VkResult<Self> {
        let made = (|| {
            // The entries that do not read the light types get the modules frozen to point
            // lights (`vk::pipeline::freeze_spec_constant`: no specialization constant left).
            let (id, points) = (shaders::light_types::LIGHT_TYPES_SPEC_ID, 0);
            let compute = Arc::new(ShaderModule::frozen(&ctx, "manylights compute kernels", COMPUTE_SPV, id, points)?);
            let graphics = Arc::new(ShaderModule::frozen(&ctx, "manylights raster shaders", GRAPHICS_SPV, id, points)?);
            let light_compute = LightTypedModules::new(&ctx, "manylights compute kernels (light types)", COMPUTE_SPV);
            let light_graphics = LightTypedModules::new(&ctx, "manylights raster shaders (light types)", GRAPHICS_SPV);
            let kernels = Kernels::new(&ctx, &compute, &light_compute)?;
            let raster = RasterPipelines::new(&ctx, &graphics, &light_graphics)?;
            Ok((kernels, raster, compute, graphics, light_compute, light_graphics))
        })();
        match made {
            Ok((kernels, raster, compute_module, graphics_module, light_compute, light_graphics)) => {
                Ok(Self { kernels, raster, compute_module, graphics_module, light_compute, light_graphics, ctx })
            }
            // Name what the validation layer saw, not just the failed call.
            Err(e) => match ctx.take_validation_messages() {
                m if m.is_empty() => Err(e),
                m => Err(crate::vk::VkError::Validation { during: e.to_string(), messages: m.join("\n") }),
            },
        }
    }

    /// The light-type variants (`shaders::light_types::light_type_variant`) of the light-typed
    /// pipelines created so far ([`LightCompute`], [`LightRaster`], here or by a technique or
    /// pass from [`Gpu::light_compute`] / [`Gpu::light_graphics`]): the variants whose frozen
    /// module a pipeline asked for. A scene of point lights creates only variant 0.
    pub fn light_type_variants(&self) -> std::collections::BTreeSet<usize> {
        self.light_compute.created().chain(self.light_graphics.created()).collect()
    }

    /// Records with `f`, submits, waits. With a profiler, its passes are timed.
    pub fn run<R>(&self, profiler: Option<&mut Profiler>, f: impl FnOnce(&mut Recorder<'_>) -> VkResult<R>) -> VkResult<R> {
        self.ctx.run(profiler, f)
    }
}
