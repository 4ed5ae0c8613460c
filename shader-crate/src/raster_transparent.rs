//! Raster shaders of the transparent pass: per-pixel linked-list OIT (Yang, Hensley, Grün,
//! Thibieroz 2010, "Real-Time Concurrent Linked List Construction on the GPU", EGSR) over the
//! clustered light lists (the kernels' algebra and resolve: [`crate::oit`]).
//!
//! # Steps (a frame with transparent draws; the host's `render/transparent.rs` records them)
//!
//! 1. **G-buffer** of the opaque draws only (materials of opacity 1), then the opaque chain.
//! 2. **Cluster pre-pass** ([`transparent_keys_fs`], [`mark_cluster`]): the transparent draws
//!    rasterised against the opaque depth (test GREATER, no depth writes, early fragment tests);
//!    each fragment marks what the technique's lists (`TransparentDraw::lists`) are built from:
//!    * page table (`clustered-naive`, `clustered-bvh`), two passes: the cluster key of the
//!      opaque key kernel's function ([`page_table::pixel_key`], from its own depth) marks its
//!      page (beside the key kernel's marks, before the pages are allocated), then — after
//!      that — sets its slot (beside `store_slots`, before the slots are counted and compacted);
//!    * dense grid (`clustered-aabb`): its dense cluster's flag, beside `aabb_mark`'s;
//!    * tiles (`forward-plus`): its tile's transparent depth range, which the culling's tile
//!      bounds then span.
//!
//!    Its cluster is then a cluster like any opaque pixel's and gets a list from the same
//!    assignment; its tile's list holds the lights of its depth.
//! 3. **Opaque shading** as usual.
//! 4. **Transparent pass** ([`transparent_fs`] …): the same draws, same test; each fragment finds
//!    its list ([`fragment_list`]: key → page → slot → cluster, the dense cluster, or the tile:
//!    the opaque shading's lookup), sums that list's
//!    lights with the opaque surfaces' light loop ([`shading::shade_lights`]; the `_all_lights`
//!    variants of the brute-force reference sum every light), tonemaps, and inserts a node into
//!    its pixel's list ([`oit::insert_node`]: atomic counter, head exchange). The tie key is the
//!    draw's first primitive in the frame + `PrimitiveId`.
//! 5. **Resolve** (compute, `transparency::oit_resolve`): per pixel, the list composited over the
//!    opaque colour; the head is cleared for the next frame.
//!
//! Weighted blended OIT (McGuire & Bavoil 2013, `--oit weighted`) replaces steps 4–5: the
//! fragments ([`weighted_fs`] …) blend `oit::weighted_fragment` into an additive accumulation
//! target and a multiplicative revealage target, which `transparency::oit_resolve_weighted`
//! composites over the opaque colour; no lists, no sorting.
//!
//! # Why a raster pre-pass marks the clusters
//!
//! The clustered techniques build lists only for clusters that some pixel's key names. A
//! transparent fragment's cluster is the key of its own depth, in front of the opaque surface.
//! Marking, per pixel, every cluster between the nearest transparent depth and the opaque depth
//! would also be exact but marks every slice in between (a stack of panes spans many empty
//! slices) and needs a min-depth pass anyway. The pre-pass marks exactly the clusters the
//! transparent pass will read: the same vertex positions ([`crate::raster::clip_position`]), the
//! same fixed-function depth and test, the same key function. It costs two depth-tested raster
//! passes over the transparent geometry, with no colour target. The transparent pass counts any
//! fragment whose cluster is not among the unique clusters ([`OIT_COUNTER_UNLISTED`]); the tests
//! require none.
//!
//! # Memory
//!
//! Heads 4 B per pixel, nodes 20 B per transparent fragment ([`OitNode`]), 4 counters; the key
//! pre-pass adds nothing (the page table's marks and slots). Weighted: 16 B (RGBA32F
//! accumulation) + 4 B (R32F revealage) per pixel, each once as a target and once as a buffer,
//! nothing per fragment.
use crate::layout::*;
use crate::octahedral::{self, Precision};
use crate::oit;
use crate::page_table::{self, INVALID_KEY};
use crate::dense_grid;
use crate::raster::{encode_gbuffer_normal, sample_draw_uniform, unorm8, Texture2d, ALPHA_CUTOFF};
use crate::shading::{self, variant_entries, LightList, Surface};
use crate::fragment_atomics::{atomic_add, atomic_exchange, atomic_max};
use spirv_std::glam::{Vec2, Vec3, Vec4};
use spirv_std::spirv;

/// Sets a mark word shared by many fragments (a load first: most find it set already).
#[inline]
fn set_mark(word: &mut u32) {
    if *word == 0 {
        *word = 1;
    }
}

/// Step 2 for one fragment (`frag`: its pixel and reversed-Z depth), by the technique's lists
/// (`p.draw.lists`): the page table's page (`TRANSPARENT_MARK_PAGES`) or slot
/// (`TRANSPARENT_STORE_SLOTS`) of its key, as `pixel_keys` and `store_slots` do for an opaque
/// pixel; the dense grid's flag of its cluster (`TRANSPARENT_DENSE_GRID`, beside `aabb_mark`'s);
/// or its tile's transparent depth range (`TRANSPARENT_TILE_*`, `TILE_DEPTH_WORDS` in `marks`).
#[inline]
pub fn mark_cluster(p: &TransparentParams, bounds: &[f32], marks: &mut [u32], page_base: &[u32], slots: &mut [u32], frag: Vec4) {
    let g = &p.frame.grid;
    let (px, py) = (frag.x as u32, frag.y as u32);
    let lists = p.draw.lists;
    if lists == TRANSPARENT_DENSE_GRID {
        let c = dense_grid::pixel_cluster(g, bounds, px, py, frag.z);
        if c != dense_grid::NO_CLUSTER {
            set_mark(&mut marks[c as usize]);
        }
        return;
    }
    if lists == TRANSPARENT_TILE_ARRAYS || lists == TRANSPARENT_TILE_LINKED {
        let (tx, ty) = g.tile_of_pixel(px, py);
        let w = (TILE_DEPTH_WORDS * (ty * g.tiles_x + tx)) as usize;
        // A load first: the words only grow, so a fragment inside the range already marked
        // (most of a tile's) needs no atomic.
        let d = crate::reconstruct::distance_from_depth(g.near, frag.z).to_bits();
        if marks[w] < !d {
            atomic_max(&mut marks[w], !d);
        }
        if marks[w + 1] < d {
            atomic_max(&mut marks[w + 1], d);
        }
        return;
    }
    let key = page_table::pixel_key(g, bounds, px, py, frag.z);
    if key == INVALID_KEY {
        return;
    }
    let page = page_table::page_of(key) as usize;
    if lists == TRANSPARENT_MARK_PAGES {
        set_mark(&mut marks[page]);
    } else {
        set_mark(&mut slots[page_table::slot_index(page_base[page], key) as usize]);
    }
}

/// No cluster: [`fragment_cluster`] found no list for the fragment's key.
pub const NO_CLUSTER: u32 = u32::MAX;

/// The unique cluster of a fragment (key → page → slot → cluster, the opaque shading's lookup),
/// or [`NO_CLUSTER`] when its key is not among the frame's `clusters` unique clusters (its
/// cluster was not marked).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn fragment_cluster(grid: &crate::cluster_key::ClusterGrid, bounds: &[f32], page_base: &[u32], slot_rank: &[u32], unique: &[u32], clusters: u32, px: u32, py: u32, z_buf: f32) -> u32 {
    let key = page_table::pixel_key(grid, bounds, px, py, z_buf);
    if key == INVALID_KEY {
        return NO_CLUSTER;
    }
    let c = slot_rank[page_table::slot_index(page_base[page_table::page_of(key) as usize], key) as usize];
    if c < clusters && unique[c as usize] == key {
        c
    } else {
        NO_CLUSTER
    }
}

/// The sum over `list` at `surface` (the variant of the frame's specular bit), into `sum`;
/// returns the lights evaluated.
#[inline]
fn shade_sum<L: LightList>(f: &FrameParams, surface: &Surface, lights: &[PointLight], list: &L, sum: &mut Vec3) -> u32 {
    if f.effects & EFFECT_SPECULAR != 0 {
        let count = shading::shade_lights::<true, false, _>(surface, f.effects, f.num_lights, lights, list, sum);
        shading::shade_directional_lights::<true>(surface, f.effects, f.num_lights, lights, sum);
        count
    } else {
        let count = shading::shade_lights::<false, false, _>(surface, f.effects, f.num_lights, lights, list, sum);
        shading::shade_directional_lights::<false>(surface, f.effects, f.num_lights, lights, sum);
        count
    }
}

/// The surface of a transparent fragment, as the opaque passes would read it back from the
/// G-buffer: position from the pixel centre and the fragment's depth, the normal facing the
/// viewer through the G-buffer's encoding, the albedo quantised to 8 bits.
#[inline]
pub fn fragment_surface(p: &TransparentParams, materials: &[MaterialGpu], frag: Vec4, in_normal: Vec3, front_facing: bool, texel: Vec3) -> Surface {
    let f = &p.frame;
    let facing = if front_facing { in_normal } else { -in_normal };
    let normal = Vec3::from_array(octahedral::decode(encode_gbuffer_normal(facing, p.draw.normal_precision), Precision::from_u32(f.normal_precision)));
    let a = Vec3::from_array(p.draw.albedo) * texel;
    let mat = materials[p.draw.material as usize];
    Surface {
        pos: shading::pixel_position(&f.grid, frag.x as u32, frag.y as u32, frag.z),
        normal,
        albedo: Vec3::new(unorm8(a.x), unorm8(a.y), unorm8(a.z)),
        specular: mat.specular,
        roughness: mat.roughness,
    }
}

/// The buffers a transparent fragment reads and writes, in binding order after the vertex
/// stage's (see the entries).
pub struct TransparentBuffers<'a> {
    pub bounds: &'a [f32],
    pub page_base: &'a [u32],
    pub slot_rank: &'a [u32],
    pub unique: &'a [u32],
    pub cluster_counters: &'a [u32],
    pub counts: &'a [u32],
    pub offsets: &'a [u32],
    pub list: &'a [u32],
    pub lights: &'a [PointLight],
    pub materials: &'a [MaterialGpu],
}

/// Step 4 for one fragment: shade it over its cluster's list (`ALL_LIGHTS`: every light) and
/// insert it into its pixel's list. `primitive` is the draw's `PrimitiveId`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn transparent_fragment<const ALL_LIGHTS: bool>(
    p: &TransparentParams,
    b: &TransparentBuffers<'_>,
    frag: Vec4,
    in_normal: Vec3,
    front_facing: bool,
    texel: Vec3,
    primitive: u32,
    heads: &mut [u32],
    nodes: &mut [OitNode],
    oit_counters: &mut [u32],
) {
    let rgb = transparent_colour::<ALL_LIGHTS>(p, b, frag, in_normal, front_facing, texel, oit_counters);
    let f = &p.frame;
    let (px, py) = (frag.x as u32, frag.y as u32);
    let alpha = b.materials[p.draw.material as usize].opacity;
    let capacity = p.draw.capacity;
    let index = atomic_add(&mut oit_counters[OIT_COUNTER_NODES as usize], 1);
    let old = if oit::node_fits(index, capacity) { atomic_exchange(&mut heads[(py * f.grid.width + px) as usize], index) } else { OIT_END };
    let n = oit::insert_node(old, index, capacity, rgb, alpha, frag.z, p.draw.first_primitive.wrapping_add(primitive));
    if !n.overflow {
        nodes[index as usize] = n.node;
    }
}

/// The weighted blended variant of step 4 (McGuire & Bavoil 2013): the fragment's outputs into
/// the accumulation and revealage targets (`oit::weighted_fragment`, view depth `near / z_buf`);
/// counts the fragment.
#[inline]
pub fn weighted_transparent_fragment<const ALL_LIGHTS: bool>(
    p: &TransparentParams,
    b: &TransparentBuffers<'_>,
    frag: Vec4,
    in_normal: Vec3,
    front_facing: bool,
    texel: Vec3,
    oit_counters: &mut [u32],
) -> oit::WeightedFragment {
    let rgb = transparent_colour::<ALL_LIGHTS>(p, b, frag, in_normal, front_facing, texel, oit_counters);
    atomic_add(&mut oit_counters[OIT_COUNTER_NODES as usize], 1);
    let alpha = b.materials[p.draw.material as usize].opacity;
    oit::weighted_fragment(rgb, alpha, crate::reconstruct::distance_from_depth(p.frame.grid.near, frag.z))
}

/// Where a transparent fragment's light list lies, by the technique's lists (`p.draw.lists`): a
/// plain struct rather than an enum with fields (simple for the SPIR-V backend).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FragmentList {
    /// `LIST_RANGE`, `LIST_LINKED` or `LIST_NONE`.
    pub kind: u32,
    /// `LIST_RANGE`: the first entry of the index list; `LIST_LINKED`: the tile's head.
    pub first: u32,
    /// `LIST_RANGE`: entries.
    pub count: u32,
}

/// Entries `first..first + count` of the index list (page table, dense grid, tile arrays).
pub const LIST_RANGE: u32 = 0;
/// A tile's linked list from its head (`forward-plus --fp-lists linked`).
pub const LIST_LINKED: u32 = 1;
/// No list: the fragment's cluster was not marked (counted as `OIT_COUNTER_UNLISTED`), or the
/// frame's tile lists overflowed their buffer (it grows and the frame re-runs).
pub const LIST_NONE: u32 = 2;

impl FragmentList {
    const NONE: Self = Self { kind: LIST_NONE, first: 0, count: 0 };

    fn range(first: u32, count: u32) -> Self {
        Self { kind: LIST_RANGE, first, count }
    }
}

/// The list of the fragment at `(px, py)` with depth `z_buf`. The buffers mean, by `lists`:
/// page table — `page_base`, `slot_rank`, `unique`, the cluster counters, `counts`, `offsets`,
/// `list` as their names say; dense grid — `cluster_counters` the clusters' flags, `counts`,
/// `offsets`, `list` per dense cluster; tiles — `cluster_counters` Forward+'s counters (overflow
/// check against `light_capacity`), `counts` the tiles' `(offset, count)` pairs or heads, `list`
/// the indices or nodes.
#[inline]
pub fn fragment_list(p: &TransparentParams, b: &TransparentBuffers<'_>, px: u32, py: u32, z_buf: f32) -> FragmentList {
    let f = &p.frame;
    let g = &f.grid;
    let lists = p.draw.lists;
    if lists == TRANSPARENT_TILE_ARRAYS || lists == TRANSPARENT_TILE_LINKED {
        if b.cluster_counters[FP_COUNTER_REFS as usize] > f.light_capacity {
            return FragmentList::NONE;
        }
        let (tx, ty) = g.tile_of_pixel(px, py);
        let tile = ty * g.tiles_x + tx;
        return if lists == TRANSPARENT_TILE_ARRAYS {
            FragmentList::range(b.counts[2 * tile as usize], b.counts[2 * tile as usize + 1])
        } else {
            FragmentList { kind: LIST_LINKED, first: b.counts[tile as usize], count: 0 }
        };
    }
    let c = if lists == TRANSPARENT_DENSE_GRID {
        let c = dense_grid::pixel_cluster(g, b.bounds, px, py, z_buf);
        if c == dense_grid::NO_CLUSTER || b.cluster_counters[c as usize] == 0 {
            NO_CLUSTER
        } else {
            c
        }
    } else {
        let clusters = b.cluster_counters[COUNTER_UNIQUE_CLUSTERS as usize];
        fragment_cluster(g, b.bounds, b.page_base, b.slot_rank, b.unique, clusters, px, py, z_buf)
    };
    if c == NO_CLUSTER {
        FragmentList::NONE
    } else {
        FragmentList::range(b.offsets[c as usize], b.counts[c as usize])
    }
}

/// The tonemapped colour of a transparent fragment over its list ([`fragment_list`];
/// `ALL_LIGHTS`: every light); a fragment whose cluster has no list is counted
/// ([`OIT_COUNTER_UNLISTED`]; not a tile technique's overflowed frame, which re-runs) and lit by
/// no light.
#[inline]
pub fn transparent_colour<const ALL_LIGHTS: bool>(
    p: &TransparentParams,
    b: &TransparentBuffers<'_>,
    frag: Vec4,
    in_normal: Vec3,
    front_facing: bool,
    texel: Vec3,
    oit_counters: &mut [u32],
) -> Vec3 {
    let f = &p.frame;
    let (px, py) = (frag.x as u32, frag.y as u32);
    let surface = fragment_surface(p, b.materials, frag, in_normal, front_facing, texel);
    let mut sum = Vec3::ZERO;
    let count = if ALL_LIGHTS {
        shade_sum(f, &surface, b.lights, &shading::light_range(0, f.num_lights), &mut sum)
    } else {
        let list = b.list;
        let l = fragment_list(p, b, px, py, frag.z);
        if l.kind == LIST_RANGE {
            shade_sum(f, &surface, b.lights, &shading::index_range(l.first, l.count, move |t| list[t as usize]), &mut sum)
        } else if l.kind == LIST_LINKED {
            shade_sum(f, &surface, b.lights, &shading::linked_lights(l.first, list), &mut sum)
        } else {
            if p.draw.lists <= TRANSPARENT_DENSE_GRID {
                atomic_add(&mut oit_counters[OIT_COUNTER_UNLISTED as usize], 1);
            }
            0
        }
    };
    shading::lit_colour(f, sum, count)
}

/// Step 2: the cluster pre-pass of the transparent draws (both stages; [`mark_cluster`]).
#[spirv(fragment(early_fragment_tests))]
pub fn transparent_keys_fs(
    #[spirv(frag_coord)] frag: Vec4,
    #[spirv(push_constant)] p: &TransparentParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] bounds: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] marks: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] page_base: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] slots: &mut [u32],
) {
    mark_cluster(p, bounds, marks, page_base, slots, frag);
}

/// Declares one transparent fragment shader of each kind (its inputs, textures and texel; the
/// vertex shaders are the G-buffer's), each as a pair of entries over the fragment's cluster list
/// and over every light (`_all_lights`): the list pass (heads, nodes and OIT counters at 14–16,
/// textures from 17) and the weighted blended pass (OIT counters at 14, textures from 15; outputs
/// into the accumulation, location 0, and the revealage, location 1).
macro_rules! transparent_entries {
    (
        [$clustered:ident, $all:ident, $imp:ident],
        [$w_clustered:ident, $w_all:ident, $w_imp:ident],
        ($($input:ident: $input_ty:ty),*),
        ($($tex:ident: $binding:literal | $w_binding:literal),*),
        $texel:expr
    ) => {
        variant_entries! {
            [fragment(early_fragment_tests)] $clustered: "over the fragment's cluster list.", $all: "over every light (the brute-force reference).";
            /// Transparent pass (module docs, step 4).
            fn $imp<const ALL_LIGHTS: bool>(
                in_normal: Vec3,
                $($input: $input_ty,)*
                #[spirv(front_facing)] front_facing: bool,
                #[spirv(frag_coord)] frag: Vec4,
                #[spirv(primitive_id, flat)] primitive: u32,
                #[spirv(push_constant)] p: &TransparentParams,
                #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
                #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] bounds: &[f32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] page_base: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] slot_rank: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] unique: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] cluster_counters: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] counts: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] offsets: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] list: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] lights: &[PointLight],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] materials: &[MaterialGpu],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 14)] heads: &mut [u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 15)] nodes: &mut [OitNode],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 16)] oit_counters: &mut [u32],
                $(#[spirv(descriptor_set = 0, binding = $binding)] $tex: &Texture2d,)*
            ) {
                let p = &crate::light_types::specialise(p, light_types);
                let texel: Vec3 = $texel;
                let b = TransparentBuffers { bounds, page_base, slot_rank, unique, cluster_counters, counts, offsets, list, lights, materials };
                transparent_fragment::<ALL_LIGHTS>(p, &b, frag, in_normal, front_facing, texel, primitive, heads, nodes, oit_counters);
            }
        }

        variant_entries! {
            [fragment(early_fragment_tests)] $w_clustered: "over the fragment's cluster list.", $w_all: "over every light (the brute-force reference).";
            /// Weighted blended transparent pass (module docs; `oit::weighted_fragment`).
            fn $w_imp<const ALL_LIGHTS: bool>(
                in_normal: Vec3,
                $($input: $input_ty,)*
                #[spirv(front_facing)] front_facing: bool,
                #[spirv(frag_coord)] frag: Vec4,
                #[spirv(push_constant)] p: &TransparentParams,
                #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
                #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] bounds: &[f32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] page_base: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] slot_rank: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] unique: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] cluster_counters: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] counts: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] offsets: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] list: &[u32],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 12)] lights: &[PointLight],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 13)] materials: &[MaterialGpu],
                #[spirv(storage_buffer, descriptor_set = 0, binding = 14)] oit_counters: &mut [u32],
                $(#[spirv(descriptor_set = 0, binding = $w_binding)] $tex: &Texture2d,)*
                out_accum: &mut Vec4,
                out_revealage: &mut f32,
            ) {
                let p = &crate::light_types::specialise(p, light_types);
                let texel: Vec3 = $texel;
                let b = TransparentBuffers { bounds, page_base, slot_rank, unique, cluster_counters, counts, offsets, list, lights, materials };
                let w = weighted_transparent_fragment::<ALL_LIGHTS>(p, &b, frag, in_normal, front_facing, texel, oit_counters);
                *out_accum = w.accum;
                *out_revealage = w.alpha;
            }
        }
    };
}

transparent_entries!([transparent_fs, transparent_fs_all_lights, transparent_fs_impl], [weighted_fs, weighted_fs_all_lights, weighted_fs_impl], (), (), Vec3::ONE);
transparent_entries!(
    [transparent_fs_textured, transparent_fs_textured_all_lights, transparent_fs_textured_impl],
    [weighted_fs_textured, weighted_fs_textured_all_lights, weighted_fs_textured_impl],
    (in_uv: Vec2),
    (albedo_map: 17 | 15),
    sample_draw_uniform(albedo_map, in_uv).truncate()
);
transparent_entries!(
    [transparent_fs_masked, transparent_fs_masked_all_lights, transparent_fs_masked_impl],
    [weighted_fs_masked, weighted_fs_masked_all_lights, weighted_fs_masked_impl],
    (in_uv: Vec2),
    (albedo_map: 17 | 15, mask_map: 18 | 16),
    {
        if sample_draw_uniform(mask_map, in_uv).x < ALPHA_CUTOFF {
            spirv_std::arch::demote_to_helper_invocation();
        }
        sample_draw_uniform(albedo_map, in_uv).truncate()
    }
);

#[cfg(test)]
#[path = "raster_transparent_tests.rs"]
mod tests;
