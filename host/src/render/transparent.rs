//! The transparent pass: draws of materials with opacity below 1, left out of the G-buffer,
//! shaded per fragment over the technique's light lists and composited with per-pixel linked
//! lists (Yang, Hensley, Grün, Thibieroz 2010, "Real-Time Concurrent Linked List Construction on
//! the GPU", EGSR), resolved exactly or keeping the k nearest sorted (the compute-shader OIT
//! article's insertion sort into a k = 4 register array, here k = 1, 2, 4 or 8 by `--oit`).
//!
//! Steps (`shaders::raster_transparent` has the kernels' side and why the clusters are marked by
//! a raster pre-pass):
//! 1. **cluster pre-pass** (all but `deferred`): [`Transparency::record_clusters`]; the
//!    transparent draws mark their clusters' pages, then their slots, inside the page-table steps
//!    (`clustered-naive`, `clustered-bvh`), their dense clusters' flags (`clustered-aabb`), or
//!    their tiles' depth ranges before the culling (`forward-plus`);
//! 2. **transparent pass** ([`Transparency::record_shade`], after the opaque shading): raster
//!    over the opaque depth (GREATER, no writes, no blending, early fragment tests), each
//!    fragment shaded over its cluster's list (`deferred`: every light) and inserted into its
//!    pixel's list;
//! 3. **resolve** (compute, one invocation per pixel): the list over the opaque frame colour; it
//!    clears each head it read (cheaper than a fill of every head at the frame's start: a store
//!    to a word just read, and only where a list exists). The heads are filled once, at
//!    allocation.
//!
//! `--oit weighted` (McGuire & Bavoil 2013, "Weighted Blended Order-Independent Transparency")
//! replaces the lists of steps 2–3: the fragments blend into an additive accumulation target
//! and a multiplicative revealage target ([`WEIGHTED_TARGETS`]), copied into buffers that the
//! weighted resolve composites over the opaque colour.
//!
//! The node counter is read back after the frame: past the node buffer's capacity the buffer
//! grows to the need + 25 % and the frame re-runs (never a silent drop).
//!
//! Memory: heads 4 B per pixel, nodes 20 B per transparent fragment (first guess: two per pixel,
//! within one storage-buffer range; it grows), 16 B of counters; weighted: 20 B per pixel as
//! targets and 20 B as buffers, no lists. A scene without transparent draws allocates none of it and
//! creates none of its pipelines.
use super::gbuffer::Draw;
use super::technique::{grown_capacity, FrameInputs};
use super::Technique;
use crate::gpu::{Gpu, LightRaster};
use crate::vk::{Attachment, Blend, Buffer, ComputePipeline, DepthTest, GraphicsPipeline, Image, ImageUse, LightTyped, Load, Recorder, TargetFormat, VkResult};
use anyhow::{Context as _, Result};
use shaders::kernels;
use shaders::layout::*;
use shaders::oit::MAX_K;

/// How a pixel's transparent fragments are resolved (`--oit`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum OitVariant {
    /// Every fragment sorted, far to near (exact up to `shaders::oit::MAX_EXACT_LAYERS` layers).
    Exact,
    /// The nearest fragment sorted over an order-independent average of the others.
    K1,
    K2,
    /// The 4 nearest sorted (the default).
    #[default]
    K4,
    K8,
    /// Weighted blended OIT (McGuire & Bavoil 2013): no lists, no sorting; an approximation.
    Weighted,
}

impl OitVariant {
    pub const ALL: [OitVariant; 6] = [Self::Exact, Self::K1, Self::K2, Self::K4, Self::K8, Self::Weighted];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Exact => "exact",
            Self::K1 => "k1",
            Self::K2 => "k2",
            Self::K4 => "k4",
            Self::K8 => "k8",
            Self::Weighted => "weighted",
        }
    }

    /// `(OitParams::variant, OitParams::k)`.
    pub fn params(self) -> (u32, u32) {
        match self {
            Self::Exact => (OIT_EXACT, MAX_K),
            Self::K1 => (OIT_K_NEAREST, 1),
            Self::K2 => (OIT_K_NEAREST, 2),
            Self::K4 => (OIT_K_NEAREST, 4),
            Self::K8 => (OIT_K_NEAREST, 8),
            Self::Weighted => (OIT_WEIGHTED, MAX_K),
        }
    }
}

/// Weighted blended OIT's colour targets: additive accumulation `(Σ C·w, Σ α·w)` and the
/// revealage `Π (1 − α)` (cleared to 1). Float32 rather than the paper's RGBA16F + R8: no
/// overflow past a few dozen heavy layers, and the resolve reads plain floats.
const WEIGHTED_TARGETS: [(TargetFormat, Blend); 2] = [(TargetFormat::Rgba32Float, Blend::Add), (TargetFormat::R32Float, Blend::Revealage)];


/// Bytes of one node of the per-pixel lists (`shaders::layout::OitNode`: 16-bit colour channels).
const NODE_BYTES: u64 = std::mem::size_of::<shaders::layout::OitNode>() as u64;
/// The error of a technique without the transparent pass for a scene with transparent draws.
pub fn refusal(t: Technique, transparent: &[Draw], names: &[String], materials: &[MaterialGpu]) -> String {
    let mut used: Vec<u32> = transparent.iter().map(|d| d.params.material).collect();
    used.sort_unstable();
    used.dedup();
    let listed: Vec<String> = used
        .iter()
        .map(|&m| {
            let name = names.get(m as usize).map_or_else(|| format!("material {m}"), |n| format!("{n:?}"));
            format!("{name} (opacity {})", materials.get(m as usize).map_or(1.0, |x| x.opacity))
        })
        .collect();
    let drawn: Vec<&str> = Technique::ALL.iter().filter(|t| t.draws_transparency()).map(|t| t.name()).collect();
    format!(
        "{} has no transparent pass and would draw the scene's transparent materials opaque: {}; use {}",
        t.name(),
        listed.join(", "),
        drawn.join(", ")
    )
}

/// What the transparent pass of the last frame did (the stats file's `transparency`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TransparencyStats {
    /// Transparent fragments (the node counter).
    pub fragments: u32,
    /// Most layers of one pixel (0 with `weighted`: no lists).
    pub max_layers: u32,
    /// Pixels the exact resolve composited as k-nearest (past its layer bound).
    pub fallbacks: u32,
    /// Transparent fragments whose cluster had no light list (0 unless the marking is broken).
    pub unlisted: u32,
    /// Bytes of the node buffer (0 with `weighted`).
    pub node_bytes: u64,
}

/// The light lists a transparent fragment reads, as `shaders::raster_transparent::fragment_list`
/// names them (the page table's buffers; the other techniques bind theirs in some of these
/// places and any buffer in the others: [`ClusterInputs::dense_grid`], [`ClusterInputs::tiles`]).
pub struct ClusterInputs<'a> {
    pub page_base: &'a Buffer,
    pub slot_rank: &'a Buffer,
    pub unique: &'a Buffer,
    pub counters: &'a Buffer,
    pub counts: &'a Buffer,
    pub offsets: &'a Buffer,
    pub list: &'a Buffer,
}

impl<'a> ClusterInputs<'a> {
    /// `clustered-aabb`: the clusters' flags, counts, offsets and the index list.
    pub fn dense_grid(flags: &'a Buffer, counts: &'a Buffer, offsets: &'a Buffer, list: &'a Buffer) -> Self {
        Self { page_base: flags, slot_rank: flags, unique: flags, counters: flags, counts, offsets, list }
    }

    /// `forward-plus`: its counters, the tiles' ranges or heads, and the indices or nodes.
    pub fn tiles(counters: &'a Buffer, tiles: &'a Buffer, entries: &'a Buffer) -> Self {
        Self { page_base: counters, slot_rank: counters, unique: counters, counters, counts: tiles, offsets: tiles, list: entries }
    }
}

/// What the cluster pre-pass marks (`TransparentDraw::lists`'s step, the buffer it marks) and,
/// for the page table's steps, the page bases and slots it reads and sets.
pub struct Marks<'a> {
    pub stage: u32,
    pub marks: &'a Buffer,
    pub page_table: Option<(&'a Buffer, &'a Buffer)>,
}

/// The opaque depth the transparent draws test against, and the use it is in.
#[derive(Clone, Copy)]
pub struct OpaqueDepth<'a> {
    pub image: &'a Image,
    pub from: ImageUse,
}

/// Where the transparent fragments go (one per technique: the variants' sizes do not matter).
#[allow(clippy::large_enum_variant)]
enum Store {
    /// Per-pixel linked lists: heads, nodes and the nodes they hold.
    Lists { heads: Buffer, nodes: Buffer, capacity: u32 },
    /// Weighted blended OIT's targets.
    Weighted(Box<WeightedStore>),
}

/// Weighted blended OIT's targets (accumulation RGBA32F, revealage R32F) and their buffer copies.
struct WeightedStore {
    accum: Image,
    revealage: Image,
    accum_buf: Buffer,
    revealage_buf: Buffer,
}

/// The transparent pass of one technique (module docs).
pub struct Transparency {
    variant: OitVariant,
    /// `TransparentDraw::lists` of the transparent pass (the technique's lists).
    lists: u32,
    keys: Option<GraphicsPipeline<TransparentParams>>,
    /// `[plain, textured, alpha-tested]`, for the frame's light types.
    shade: [LightRaster<TransparentParams>; 3],
    resolve: ComputePipeline<OitParams>,
    store: Store,
    counters: Buffer,
    /// Bound where the pre-pass of a technique without a page table has no slots (a buffer of
    /// its own: the shader may write there, and another buffer read by the same draws would be a
    /// hazard between them).
    spare: Buffer,
    /// Each transparent draw's first primitive id (its triangles numbered in draw order).
    first_primitives: Vec<u32>,
    last: TransparencyStats,
}

impl Transparency {
    /// The pass for a frame whose scene has transparent draws (`None` otherwise: nothing is
    /// allocated or created), over the technique's `lists` (`TRANSPARENT_MARK_PAGES` …
    /// `TRANSPARENT_TILE_LINKED`); `None`: every fragment sums every light (the brute-force
    /// reference).
    pub fn new(f: &FrameInputs<'_>, gpu: &Gpu, lists: Option<u32>) -> Result<Option<Self>> {
        let ctx = &gpu.ctx;
        let all_lights = lists.is_none();
        let draws = &f.geometry.transparent;
        if draws.is_empty() {
            return Ok(None);
        }
        let weighted = f.settings.oit == OitVariant::Weighted;
        let colours: &[(TargetFormat, Blend)] = if weighted { &WEIGHTED_TARGETS } else { &[] };
        let raster = &gpu.graphics_module;
        let pipe = |h: kernels::RasterKernel<TransparentParams>, colours| GraphicsPipeline::blended(ctx, raster, h.fragment, h, colours, DepthTest::NearerReadOnly);
        let keys = if all_lights { None } else { Some(pipe(kernels::TRANSPARENT_KEYS, &[])?) };
        let s = if weighted { &kernels::TRANSPARENT_WEIGHTED } else { &kernels::TRANSPARENT_SHADE }[usize::from(all_lights)];
        let shade = s.map(|h| LightTyped::raster(&gpu.light_graphics, h, colours, DepthTest::NearerReadOnly));
        let resolve = ComputePipeline::new(ctx, &gpu.compute_module, if weighted { kernels::OIT_RESOLVE_WEIGHTED } else { kernels::OIT_RESOLVE })?;
        let (pixels, g) = (f.params.count as u64, &f.params.grid);
        let store = if weighted {
            let [(accum, _), (revealage, _)] = WEIGHTED_TARGETS;
            crate::vk::memory::check_range(ctx, "oit accumulation", accum.bytes() * pixels)?;
            Store::Weighted(Box::new(WeightedStore {
                accum: Image::target(ctx, "oit accumulation", g.width, g.height, accum)?,
                revealage: Image::target(ctx, "oit revealage", g.width, g.height, revealage)?,
                accum_buf: Buffer::storage(ctx, "oit accumulation", accum.bytes() * pixels)?,
                revealage_buf: Buffer::storage(ctx, "oit revealage", revealage.bytes() * pixels)?,
            }))
        } else {
            crate::vk::memory::check_range(ctx, "oit heads", 4 * pixels)?;
            // Two nodes per pixel, within one storage-buffer range (lavapipe: 128 MiB); more grows.
            let fits = u32::try_from(ctx.info.max_storage_buffer_range as u64 / NODE_BYTES).unwrap_or(u32::MAX);
            let capacity = f.params.count.saturating_mul(2).clamp(1024, fits.max(1024));
            Store::Lists { heads: Buffer::filled(ctx, "oit heads", 4 * pixels, OIT_END)?, nodes: Self::node_buffer(ctx, capacity)?, capacity }
        };
        let mut first_primitives = Vec::with_capacity(draws.len());
        let mut next = 0u32;
        for d in draws {
            first_primitives.push(next);
            next = next.wrapping_add(d.index_count / 3);
        }
        Ok(Some(Self {
            variant: f.settings.oit,
            lists: lists.unwrap_or(TRANSPARENT_MARK_PAGES),
            keys,
            shade,
            resolve,
            store,
            counters: Buffer::storage(ctx, "oit counters", 4 * OIT_COUNTERS as u64)?,
            spare: Buffer::storage(ctx, "oit spare", 4)?,
            first_primitives,
            last: TransparencyStats::default(),
        }))
    }

    fn node_buffer(ctx: &crate::vk::Context, capacity: u32) -> VkResult<Buffer> {
        let bytes = NODE_BYTES * capacity as u64;
        crate::vk::memory::check_range(ctx, "oit nodes", bytes)?;
        Buffer::storage(ctx, "oit nodes", bytes)
    }

    /// Nodes the node buffer holds (0: weighted, no lists).
    fn capacity(&self) -> u32 {
        match self.store {
            Store::Lists { capacity, .. } => capacity,
            Store::Weighted(_) => 0,
        }
    }

    fn push(&self, f: &FrameInputs<'_>, frame: &FrameParams, i: usize, lists: u32) -> TransparentParams {
        let d = &f.geometry.transparent[i];
        TransparentParams {
            frame: *frame,
            draw: TransparentDraw {
                albedo: d.params.albedo,
                material: d.params.material,
                normal_precision: d.params.normal_precision,
                first_primitive: self.first_primitives[i],
                capacity: self.capacity(),
                lists,
            },
        }
    }

    /// Draws every transparent draw over the opaque `depth` (left as a depth target) into
    /// `colours` with `extra` storage buffers after the vertex stage's: the cluster pre-pass at
    /// `keys` = `Some(stage)`, else the transparent pass of the draw's variant with its textures.
    #[allow(clippy::too_many_arguments)]
    fn draw_all(&self, rec: &mut Recorder<'_>, f: &FrameInputs<'_>, frame: &FrameParams, depth: OpaqueDepth<'_>, colours: &[Attachment<'_>], extra: &[&Buffer], keys: Option<u32>) -> VkResult<()> {
        let (depth, from) = (depth.image, depth.from);
        rec.transition(depth, from, ImageUse::DepthTarget);
        rec.fragments_read_earlier_writes();
        rec.begin_rendering(colours, Attachment { image: depth, load: Load::Keep }, &f.geometry.indices);
        for (i, d) in f.geometry.transparent.iter().enumerate() {
            let (pipe, textures) = match (&self.keys, keys) {
                (Some(k), Some(_)) => (k, 0),
                _ => (self.shade[d.variant()].get(frame.effects)?, d.variant()),
            };
            let bindings = f.draw_bindings(extra, d, textures);
            rec.draw_indexed(pipe, &bindings, &self.push(f, frame, i, keys.unwrap_or(self.lists)), d.first_index, d.index_count)?;
        }
        rec.end_rendering();
        rec.kernels_read_fragment_writes();
        Ok(())
    }

    /// Step 1: the page table's `TRANSPARENT_MARK_PAGES` (after the key kernel, before the pages
    /// are allocated) and `TRANSPARENT_STORE_SLOTS` (after `store_slots`, before the slots are
    /// counted); the dense grid's flags (after `aabb_mark`, before the compaction); the tiles'
    /// depth ranges (after Forward+'s depth pre-pass, before the culling). The G-buffer leaves its depth a copy
    /// source.
    pub fn record_clusters(&self, rec: &mut Recorder<'_>, f: &FrameInputs<'_>, frame: &FrameParams, depth: OpaqueDepth<'_>, m: &Marks<'_>) -> VkResult<()> {
        let (page_base, slots) = m.page_table.unwrap_or((f.bounds, &self.spare));
        self.draw_all(rec, f, frame, depth, &[], &[f.bounds, m.marks, page_base, slots], Some(m.stage))
    }

    /// Steps 2 and 3, after the opaque shading: the transparent pass and the resolve into the
    /// frame. `clusters`: the lists each fragment reads (`None` with `all_lights`).
    pub fn record_shade(&self, rec: &mut Recorder<'_>, f: &FrameInputs<'_>, frame: &FrameParams, depth: OpaqueDepth<'_>, clusters: Option<&ClusterInputs<'_>>) -> VkResult<()> {
        rec.pass("transparent", |rec| {
            rec.fill(&self.counters, 0);
            // The brute-force variant reads no cluster data: any buffer fills those bindings.
            let any = &self.counters;
            let c = clusters.map_or([any; 7], |c| [c.page_base, c.slot_rank, c.unique, c.counters, c.counts, c.offsets, c.list]);
            let mut extra = vec![f.bounds, c[0], c[1], c[2], c[3], c[4], c[5], c[6], f.lights, f.materials];
            match &self.store {
                Store::Lists { heads, nodes, .. } => {
                    extra.extend([heads, nodes, &self.counters]);
                    self.draw_all(rec, f, frame, depth, &[], &extra, None)
                }
                Store::Weighted(w) => {
                    let WeightedStore { accum, revealage, accum_buf, revealage_buf } = &**w;
                    extra.push(&self.counters);
                    rec.transition(accum, ImageUse::Undefined, ImageUse::ColourTarget);
                    rec.transition(revealage, ImageUse::Undefined, ImageUse::ColourTarget);
                    let targets = [
                        Attachment { image: accum, load: Load::ClearF32([0.0; 4]) },
                        Attachment { image: revealage, load: Load::ClearF32([1.0; 4]) },
                    ];
                    self.draw_all(rec, f, frame, depth, &targets, &extra, None)?;
                    rec.transition(accum, ImageUse::ColourTarget, ImageUse::CopySource);
                    rec.transition(revealage, ImageUse::ColourTarget, ImageUse::CopySource);
                    rec.copy_to_buffers(&[(accum, accum_buf), (revealage, revealage_buf)]);
                    Ok(())
                }
            }
        })?;
        rec.pass("oit resolve", |rec| {
            let (variant, k) = self.variant.params();
            let g = &frame.grid;
            let p = OitParams { capacity: self.capacity(), width: g.width, height: g.height, variant, k, near: g.near, _pad: [0; 2] };
            match &self.store {
                Store::Lists { heads, nodes, .. } => rec.dispatch_linear(&self.resolve, &[heads, nodes, f.frame, &self.counters], &p, frame.count),
                Store::Weighted(w) => rec.dispatch_linear(&self.resolve, &[&w.accum_buf, &w.revealage_buf, f.frame], &p, frame.count),
            }
        })
    }

    /// After a frame: reads the counters; grows the node buffer when the frame's fragments did
    /// not fit (the frame then re-runs).
    pub fn grow_if_needed(&mut self, ctx: &crate::vk::Context) -> Result<Option<String>> {
        let c: Vec<u32> = self.counters.read(OIT_COUNTERS as usize)?;
        self.last = TransparencyStats {
            fragments: c[OIT_COUNTER_NODES as usize],
            max_layers: c[OIT_COUNTER_MAX_LAYERS as usize],
            fallbacks: c[OIT_COUNTER_FALLBACKS as usize],
            unlisted: c[OIT_COUNTER_UNLISTED as usize],
            node_bytes: match &self.store {
                Store::Lists { nodes, .. } => nodes.size,
                Store::Weighted(_) => 0,
            },
        };
        let Store::Lists { nodes, capacity, .. } = &mut self.store else { return Ok(None) };
        if !shaders::oit::overflowed(self.last.fragments, *capacity) {
            return Ok(None);
        }
        let grown = grown_capacity(self.last.fragments);
        *nodes = Self::node_buffer(ctx, grown).with_context(|| format!("growing the oit nodes to {grown} fragments"))?;
        *capacity = grown;
        Ok(Some(format!("oit nodes to {grown} fragments")))
    }

    /// [`Self::grow_if_needed`] of a technique's optional pass.
    pub fn grow(pass: Option<&mut Self>, ctx: &crate::vk::Context) -> Result<Option<String>> {
        pass.map_or(Ok(None), |t| t.grow_if_needed(ctx))
    }

    pub fn stats(&self) -> TransparencyStats {
        self.last
    }

    /// Bytes per buffer (weighted: each target with its buffer copy).
    pub fn buffers(&self) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> = match &self.store {
            Store::Lists { heads, nodes, .. } => [heads, nodes].iter().map(|b| (b.name.clone(), b.size)).collect(),
            Store::Weighted(w) => [&w.accum_buf, &w.revealage_buf].iter().map(|b| (b.name.clone(), 2 * b.size)).collect(),
        };
        v.extend([&self.counters, &self.spare].map(|b| (b.name.clone(), b.size)));
        v
    }
}
