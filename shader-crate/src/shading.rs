//! Shading I/O shared by every technique: how a shading kernel finds its pixel, reads the
//! surface, walks a light list and writes the colour. Used by the brute-force reference
//! ([`crate::deferred`]), clustered naive/BVH ([`crate::clustered`]), tiled and 2.5D tiled
//! ([`crate::tiled`]), clustered-AABB ([`crate::clustered_aabb`]) and the Forward+ fragment
//! shader ([`crate::raster_forward`]); the linear non-shading kernels use [`linear_index`] too.
//!
//! * **Pixel** — [`linear_index`]: element of a 2D-folded linear dispatch; [`block_pixel`]: pixel
//!   of a dispatch of 32×8 blocks in 8×4 footprints (the cluster-list shading kernels).
//! * **Surface** — [`fetch_surface`]: depth → view position ([`pixel_position`]), the G-buffer
//!   normal at any precision ([`gbuffer_normal`]: 1 word per pixel octahedral, 4 words float32),
//!   albedo and material ([`gbuffer_albedo`]).
//! * **Light loop** — [`shade_lights`]: the sum of [`lighting::shade_variant`] over a
//!   [`LightList`] (a range of indices in a buffer or workgroup memory — a cluster's, a tiled
//!   tile's or a Forward+ tile's array —, [`light_range`]: all lights, or a Forward+ linked list), [`SHADE_LIGHTS_PER_ITERATION`] lights per loop iteration
//!   in the compute kernels, one in the Forward+ fragment shader. The effect bits it evaluates
//!   come from [`variant_effects`], the one place where a kernel's compile-time specular variant
//!   meets `FrameParams::effects`: every other bit (the falloff of `EFFECT_INVERSE_SQUARE_CUT`)
//!   reaches the shading unchanged. [`shade_gbuffer_pixel`]: fetch, loop and output of one
//!   G-buffer pixel (the clustered techniques).
//! * **Output** — [`BACKGROUND_RGBA8`], [`lit_colour`] (tonemap or heatmap), [`output_colour`]
//!   (also the debug views that need the slice bounds), packed as sRGB8.
//! * **Entries** — `variant_entries!` declares a shader's two variants of one compile-time flag:
//!   `specular_entries!` a kernel's `_diffuse` / `_specular` pair, the Forward+ fragment shaders
//!   their linked-list / array pair.
//!
//! **Variants.** A scene without specular materials runs the `_diffuse` kernels: with
//! `SPECULAR = false` the specular lobe is not in the compiled code (`shade_variant`), so such a
//! scene never runs it ("simulate only the effects a scene calls for"). The Forward+ fragment
//! shader selects the variant with a frame-uniform branch on the specular bit. The light types
//! (cone falloff, directional records) are specialised per pipeline instead: the entries take
//! them as a specialization constant (`light_types`, "Specialised pipelines"), so the driver
//! folds [`shade_lights`]' and [`shade_directional_lights`]' `EFFECT_SPOT` / `EFFECT_DIRECTIONAL`
//! branches away.
use crate::compact_light::{light_emission, light_sphere};
use crate::layout::*;
use crate::light_types::{cone_of, directional_base, directional_count, EFFECT_SHADOWS, EFFECT_SPOT};
use crate::shadow::{NoShadows, Shadowing, NO_CONE};
use crate::{lighting, octahedral, reconstruct, spot};
use spirv_std::glam::{UVec3, Vec3};

/// Colour of pixels that show no geometry.
pub const BACKGROUND_RGBA8: u32 = 0xff_20_18_18;

/// Workgroup size of every linear kernel.
pub const LINEAR_WORKGROUP: u32 = 256;

/// Lights the unrolled shading loop handles per loop iteration (straight-line): llvmpipe
/// (lavapipe) ends an invocation's loops after 65 535 iterations in all, so a compute kernel's
/// loop must not take one per light.
pub const SHADE_LIGHTS_PER_ITERATION: u32 = 16;

/// What [`LightList::step`] returns at the end of its list.
pub const NO_LIGHT: u32 = u32::MAX;
/// End of a Forward+ tile list (`heads` of an empty tile, `next` of the last node).
pub const NO_NODE: u32 = u32::MAX;

/// Element `(wg.y · num_wg.x + wg.x) · 256 + local` of a linear dispatch (domains larger than
/// 65 535 workgroups fold into 2D dispatches).
#[inline]
pub fn linear_index(wg: UVec3, num_wg: UVec3, local: u32) -> u32 {
    (wg.y * num_wg.x + wg.x) * LINEAR_WORKGROUP + local
}

/// Width in pixels of the block a cluster-list shading workgroup covers ([`block_pixel`]).
pub const BLOCK_WIDTH: u32 = 32;
/// Height of that block: the workgroup's [`LINEAR_WORKGROUP`] invocations.
pub const BLOCK_HEIGHT: u32 = LINEAR_WORKGROUP / BLOCK_WIDTH;
/// Width of the footprint of 32 consecutive invocations inside a block ([`block_pixel`]).
pub const FOOTPRINT_WIDTH: u32 = 8;
/// Height of that footprint.
pub const FOOTPRINT_HEIGHT: u32 = 4;
const FOOTPRINT: u32 = FOOTPRINT_WIDTH * FOOTPRINT_HEIGHT;
const _: () = assert!(
    BLOCK_WIDTH.is_multiple_of(FOOTPRINT_WIDTH) && BLOCK_HEIGHT.is_multiple_of(FOOTPRINT_HEIGHT) && FOOTPRINT == 32,
    "footprints of 32 invocations tile the block"
);
/// What [`block_pixel`] returns for an invocation outside the frame.
pub const NO_PIXEL: u32 = u32::MAX;

/// Pixel (row-major index) of invocation `local` of workgroup `wg` in a dispatch of
/// `BLOCK_WIDTH × BLOCK_HEIGHT` blocks, or [`NO_PIXEL`] past the frame's edge.
///
/// A block lies in one column of cluster tiles (32 px wide by default), so a workgroup's
/// subgroups walk the same few light lists and read the same lights, from the same SM's cache.
/// Inside it each run of 32 consecutive invocations (a subgroup of 32, or half of one of 64)
/// takes an 8 × 4 footprint instead of a 32-pixel row:
///
/// ```text
///  block 32 × 8:  x →  0       8       16      24      32
///                    ┌───────┬───────┬───────┬───────┐
///                    │ 0–31  │ 32–63 │ 64–95 │ 96–127│  y 0–3   (invocations; each
///                    ├───────┼───────┼───────┼───────┤           footprint row-major)
///                    │128–159│160–191│192–223│224–255│  y 4–7
///                    └───────┴───────┴───────┴───────┘
/// ```
///
/// The shading loop runs a light's full evaluation whenever any lane keeps it, so the lanes'
/// pixels should lie close together: on the H200 (Sponza 1080p, `clustered-bvh`) the footprint
/// took shading from 0.162 to 0.152 ms at 10k lights and from 0.379 to 0.343 at 1M against rows
/// of 32. Any mapping of invocations to lanes stays correct; this one only makes it faster.
#[inline]
pub fn block_pixel(wg: UVec3, local: u32, width: u32, height: u32) -> u32 {
    let (footprint, k) = (local / FOOTPRINT, local % FOOTPRINT);
    let per_row = BLOCK_WIDTH / FOOTPRINT_WIDTH;
    let x = wg.x * BLOCK_WIDTH + (footprint % per_row) * FOOTPRINT_WIDTH + k % FOOTPRINT_WIDTH;
    let y = wg.y * BLOCK_HEIGHT + (footprint / per_row) * FOOTPRINT_HEIGHT + k / FOOTPRINT_WIDTH;
    if x < width && y < height {
        y * width + x
    } else {
        NO_PIXEL
    }
}

/// Albedo and material index of a G-buffer albedo word (RGBA8 UNORM, material in alpha).
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

/// View-space position of pixel `(px, py)` whose depth-buffer value is `z_buf` (reversed Z): what
/// every technique shades, the deferred ones from the depth buffer, Forward+ from the fragment.
#[inline]
pub fn pixel_position(g: &ClusterGrid, px: u32, py: u32, z_buf: f32) -> Vec3 {
    reconstruct::view_position(g, px, py, reconstruct::distance_from_depth(g.near, z_buf))
}

/// The shading inputs of one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// View-space position.
    pub pos: Vec3,
    pub normal: Vec3,
    pub albedo: Vec3,
    pub specular: f32,
    pub roughness: f32,
}

/// The surface of geometry pixel `i` (depth-buffer value `z_buf`, G-buffer albedo word `albedo`).
#[inline]
pub fn fetch_surface(p: &FrameParams, i: u32, z_buf: f32, normals: &[u32], albedo: u32, materials: &[MaterialGpu]) -> Surface {
    let g = &p.grid;
    let (a, m) = gbuffer_albedo(albedo);
    let mat = materials[m as usize];
    Surface { pos: pixel_position(g, i % g.width, i / g.width, z_buf), normal: gbuffer_normal(p, normals, i), albedo: a, specular: mat.specular, roughness: mat.roughness }
}

/// The effect bits a shading variant evaluates: the frame's bits, with the specular bit that of
/// the compiled variant. The one place the two meet.
#[inline]
pub const fn variant_effects<const SPECULAR: bool>(frame_effects: u32) -> u32 {
    (frame_effects & !EFFECT_SPECULAR) | if SPECULAR { EFFECT_SPECULAR } else { 0 }
}

/// A light list as the shading loop walks it: [`start`](Self::start) is the first position,
/// [`step`](Self::step) gives the light at a position and the position after it, or [`NO_LIGHT`]
/// at the end. Positions are plain integers and the list itself never changes, so the loop
/// carries only integers: a reference carried around a loop (an `OpPhi` of a pointer, or of a
/// struct holding one) is a variable pointer, which SPIR-V for Vulkan needs a capability for and
/// drivers need not handle (a compute module with such phis crashed NVIDIA's pipeline compiler).
pub trait LightList {
    fn start(&self) -> u32;
    fn step(&self, pos: u32) -> (u32, u32);
    /// For lists whose entries can be read in any order (index ranges), the end position:
    /// entries `start()..end` are read through [`at`](Self::at) ahead of shading
    /// ([`shade_lights`]). `None` for lists that must be walked (linked lists).
    #[inline]
    fn end(&self) -> Option<u32> {
        None
    }
    /// The light at position `pos < end` of a random-access list.
    #[inline]
    fn at(&self, pos: u32) -> u32 {
        self.step(pos).0
    }
}

/// Entries `first..first + count` of a list of light indices, entry `t` being `at(t)`: a range of
/// a list buffer or of a workgroup-memory list.
pub struct IndexRange<F> {
    first: u32,
    end: u32,
    at: F,
}

/// The list of entries `first..first + count`, entry `t` being light `at(t)`.
#[inline]
pub fn index_range<F: Fn(u32) -> u32>(first: u32, count: u32, at: F) -> IndexRange<F> {
    IndexRange { first, end: first + count, at }
}

/// Entries `first..first + count` of the list buffer `list`, read without a bounds check on the
/// GPU ([`crate::unchecked`]): empty unless the range lies inside the buffer (a list the
/// assignment could not place this frame, whose buffer the host grows before it renders the
/// frame again), so every entry read is in bounds.
#[inline]
pub fn list_range(list: &[u32], first: u32, count: u32) -> IndexRange<impl Fn(u32) -> u32 + '_> {
    let len = list.len() as u32;
    let count = if count <= len && first <= len - count { count } else { 0 };
    index_range(first, count, move |t| crate::unchecked::at(list, t))
}

impl<F: Fn(u32) -> u32> LightList for IndexRange<F> {
    #[inline]
    fn start(&self) -> u32 {
        self.first
    }

    #[inline]
    fn step(&self, t: u32) -> (u32, u32) {
        if t < self.end {
            ((self.at)(t), t + 1)
        } else {
            (NO_LIGHT, t)
        }
    }

    #[inline]
    fn end(&self) -> Option<u32> {
        Some(self.end)
    }

    #[inline]
    fn at(&self, t: u32) -> u32 {
        (self.at)(t)
    }
}

/// Lights `first..first + count` themselves: the brute-force list (every light). Its own type,
/// not an [`IndexRange`] of `|t| t`: rust-gpu cannot address a zero-sized closure in a struct.
pub struct LightRange {
    first: u32,
    end: u32,
}

/// The list of lights `first..first + count`.
#[inline]
pub fn light_range(first: u32, count: u32) -> LightRange {
    LightRange { first, end: first + count }
}

impl LightList for LightRange {
    #[inline]
    fn start(&self) -> u32 {
        self.first
    }

    #[inline]
    fn step(&self, l: u32) -> (u32, u32) {
        if l < self.end {
            (l, l + 1)
        } else {
            (NO_LIGHT, l)
        }
    }

    #[inline]
    fn end(&self) -> Option<u32> {
        Some(self.end)
    }

    #[inline]
    fn at(&self, l: u32) -> u32 {
        l
    }
}

/// A Forward+ tile list: node `k` is `(light, next)` at words `2k`, `2k + 1`; [`NO_NODE`] ends it,
/// and so does a node that names itself as its next (never written; see its `step`).
/// The position is the node.
pub struct LinkedLights<'a> {
    head: u32,
    nodes: &'a [u32],
}

/// The linked list starting at node `head`.
#[inline]
pub fn linked_lights(head: u32, nodes: &[u32]) -> LinkedLights<'_> {
    LinkedLights { head, nodes }
}

impl LightList for LinkedLights<'_> {
    #[inline]
    fn start(&self) -> u32 {
        self.head
    }

    #[inline]
    fn step(&self, node: u32) -> (u32, u32) {
        if node == NO_NODE {
            return (NO_LIGHT, node);
        }
        let k = 2 * node as usize;
        let next = self.nodes[k + 1];
        // A node never follows itself: each push takes a fresh node and links it to the
        // previous head. An invocation that reads zeros — what lavapipe's fragment loop loads
        // for the lanes it carries with their mask off — sees node 0 follow itself: it ends
        // there instead of walking to the driver's loop limit (65 535 iterations per block).
        (self.nodes[k], if next == node { NO_NODE } else { next })
    }
}

/// The light loop of every technique: adds [`lighting::shade_variant`] of each light of `list`,
/// in list order, to `sum`, with the effects of [`variant_effects`]; returns the number of
/// lights walked. Accumulating into `sum` lets a list shaded in parts (tiled rounds) add its
/// lights in the order of one list.
///
/// `UNROLLED`: [`SHADE_LIGHTS_PER_ITERATION`] lights per loop iteration (straight-line), what the
/// compute kernels use to stay under llvmpipe's loop limiter with up to
/// `light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE` lights. Otherwise one light per iteration:
/// the Forward+ fragment shader (its frames are capped at `forward_plus::MAX_LIGHTS_LLVMPIPE` on
/// llvmpipe), where lavapipe runs an unrolled body two orders of magnitude slower. Unrolled
/// over a random-access list ([`LightList::end`]), the entries and lights are read in batches
/// ahead of shading ([`shade_range`]).
#[inline]
pub fn shade_lights<const SPECULAR: bool, const UNROLLED: bool, L: LightList>(
    s: &Surface,
    frame_effects: u32,
    num_lights: u32,
    lights: &[PointLight],
    list: &L,
    sum: &mut Vec3,
) -> u32 {
    shade_lights_with::<SPECULAR, UNROLLED, L, NoShadows>(s, frame_effects, num_lights, lights, list, &NoShadows, sum)
}

/// [`shade_lights`] with each light's radiance times its visibility from `shadows` where the
/// frame has shadow-casting lights ([`EFFECT_SHADOWS`]; `crate::shadow`).
#[inline]
pub fn shade_lights_with<const SPECULAR: bool, const UNROLLED: bool, L: LightList, S: Shadowing>(
    s: &Surface,
    frame_effects: u32,
    num_lights: u32,
    lights: &[PointLight],
    list: &L,
    shadows: &S,
    sum: &mut Vec3,
) -> u32 {
    let effects = variant_effects::<SPECULAR>(frame_effects);
    // The normal is normalised once here, not once per light (`lighting::shade_unit_normal`).
    let s = &Surface { normal: lighting::unit_normal(s.normal), ..*s };
    if UNROLLED {
        if let Some(end) = list.end() {
            return shade_range::<SPECULAR, L, S>(s, effects, num_lights, lights, list, end, shadows, sum);
        }
    }
    let mut walked = 0;
    let mut pos = list.start();
    let mut more = true;
    while more {
        if UNROLLED {
            unroll8!(_u => {
                if more {
                    more = shade_next::<SPECULAR, L, S>(s, effects, num_lights, lights, list, &mut pos, shadows, sum);
                    walked += more as u32;
                }
                if more {
                    more = shade_next::<SPECULAR, L, S>(s, effects, num_lights, lights, list, &mut pos, shadows, sum);
                    walked += more as u32;
                }
            });
        } else {
            more = shade_next::<SPECULAR, L, S>(s, effects, num_lights, lights, list, &mut pos, shadows, sum);
            walked += more as u32;
        }
    }
    walked
}

/// [`shade_lights`] over a random-access list (entries `start()..end`), one light after the
/// other, two per loop iteration: `N/2` iterations, under llvmpipe's loop limiter for
/// `light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE`. Reading lights ahead of shading (2, 4 or 8
/// entries and their lights loaded before any is shaded) keeps more loads in flight per
/// invocation but needs more registers, so fewer invocations run at once: on the H200 (Sponza
/// 1080p, `clustered-bvh` shading at 10k / 1M lights) 8 ahead took 0.243 / 0.611 ms, 4 ahead
/// 0.199 / 0.475, 2 ahead 0.185 / 0.431, one after the other 0.180 / 0.425.
#[inline]
#[allow(clippy::too_many_arguments)]
fn shade_range<const SPECULAR: bool, L: LightList, S: Shadowing>(s: &Surface, effects: u32, num_lights: u32, lights: &[PointLight], list: &L, end: u32, shadows: &S, sum: &mut Vec3) -> u32 {
    let first = list.start();
    if end <= first {
        return 0;
    }
    // A light index past the buffer (none is: lists hold indices of this frame's lights, and an
    // empty buffer has no list entries) reads the last light instead of leaving the buffer: one
    // minimum instead of a bounds check (`compact_light::light_at`, `crate::unchecked`).
    let mut t = first;
    while t < end {
        let l = list.at(t);
        *sum += shade_one::<SPECULAR, S>(s, effects, num_lights, lights, l, shadows);
        t += 1;
        if t < end {
            let l = list.at(t);
            *sum += shade_one::<SPECULAR, S>(s, effects, num_lights, lights, l, shadows);
            t += 1;
        }
    }
    end - first
}

/// The radiance of punctual light `l` at `s` (unit normal, [`shade_lights`]):
/// [`lighting::shade_variant`] of its record, read sphere first ([`lighting::shade_sphere`]),
/// times its cone falloff ([`spot::spot_factor`]) when the frame has spot lights
/// ([`EFFECT_SPOT`]; a point light's marker record gives exactly 1), times its visibility
/// where the frame has shadow-casting lights ([`EFFECT_SHADOWS`]; looked up only where the light
/// adds something).
#[inline]
fn shade_one<const SPECULAR: bool, S: Shadowing>(s: &Surface, effects: u32, num_lights: u32, lights: &[PointLight], l: u32, shadows: &S) -> Vec3 {
    let (c, radius) = light_sphere(lights, effects, num_lights, l);
    let emission = || light_emission(lights, effects, num_lights, l);
    let radiance = lighting::shade_sphere::<SPECULAR>(s.pos, s.normal, s.albedo, s.specular, s.roughness, c, radius, effects, emission);
    // The cone's axis and outer cosine also lay out the light's cube (`shadow::CubeFrame`; a
    // point light's marker record and a frame without spots give view space's axes).
    let (radiance, axis, cos_outer) = if effects & EFFECT_SPOT != 0 {
        let cone = cone_of(lights, num_lights, l);
        (radiance * spot::spot_factor(c, &cone, s.pos), cone.direction, cone.cos_outer)
    } else {
        (radiance, Vec3::ZERO, NO_CONE)
    };
    if effects & EFFECT_SHADOWS != 0 && radiance.max_element() > 0.0 {
        radiance * shadows.visibility(l, c, axis, cos_outer, s.pos, s.normal)
    } else {
        radiance
    }
}

/// One step of [`shade_lights`]: adds the radiance of the light at `pos` and advances `pos`;
/// false at the end of the list.
#[inline]
#[allow(clippy::too_many_arguments)]
fn shade_next<const SPECULAR: bool, L: LightList, S: Shadowing>(s: &Surface, effects: u32, num_lights: u32, lights: &[PointLight], list: &L, pos: &mut u32, shadows: &S, sum: &mut Vec3) -> bool {
    let (l, next) = list.step(*pos);
    if l == NO_LIGHT {
        return false;
    }
    *pos = next;
    *sum += shade_one::<SPECULAR, S>(s, effects, num_lights, lights, l, shadows);
    true
}

/// Adds the frame's directional lights (`light_types` module docs; none without
/// `EFFECT_DIRECTIONAL`) to `sum`: no list, no culling, once per shaded pixel or fragment, in
/// every technique after its light list.
#[inline]
pub fn shade_directional_lights<const SPECULAR: bool>(s: &Surface, frame_effects: u32, num_lights: u32, lights: &[PointLight], sum: &mut Vec3) {
    let effects = variant_effects::<SPECULAR>(frame_effects);
    let count = directional_count(effects);
    let base = directional_base(effects, num_lights);
    // Straight-line, no loop: after a Forward+ fragment's list walk a second loop lost lights
    // on lavapipe (the linked-list variant), and the count is at most 4 anyway. In bounds: the
    // buffer ends with the `count` directional records from `base`.
    if count > 0 {
        *sum += shade_directional_record::<SPECULAR>(s, effects, crate::unchecked::get(lights, base));
    }
    if count > 1 {
        *sum += shade_directional_record::<SPECULAR>(s, effects, crate::unchecked::get(lights, base + 1));
    }
    if count > 2 {
        *sum += shade_directional_record::<SPECULAR>(s, effects, crate::unchecked::get(lights, base + 2));
    }
    if count > 3 {
        *sum += shade_directional_record::<SPECULAR>(s, effects, crate::unchecked::get(lights, base + 3));
    }
}

/// The radiance of one directional record (`light_types::directional_record`) at `s`.
#[inline]
fn shade_directional_record<const SPECULAR: bool>(s: &Surface, effects: u32, d: &PointLight) -> Vec3 {
    lighting::shade_directional::<SPECULAR>(s.pos, s.normal, s.albedo, s.specular, s.roughness, Vec3::from_array(d.position), Vec3::from_array(d.colour), d.intensity, effects)
}

/// The colour of geometry pixel `i` of a deferred pass: its surface from the G-buffer, the sum
/// over `list` ([`shade_lights`], unrolled), [`output_colour`] with the list's length for the
/// heatmap. The whole per-pixel work of the clustered techniques once they have found the
/// pixel's list.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn shade_gbuffer_pixel<const SPECULAR: bool, L: LightList, S: Shadowing>(
    p: &FrameParams,
    bounds: &[f32],
    i: u32,
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    materials: &[MaterialGpu],
    lights: &[PointLight],
    list: &L,
    shadows: &S,
) -> u32 {
    let surface = fetch_surface(p, i, depth[i as usize], normals, albedo[i as usize], materials);
    let mut sum = Vec3::ZERO;
    let count = shade_lights_with::<SPECULAR, true, L, S>(&surface, p.effects, p.num_lights, lights, list, shadows, &mut sum);
    shade_directional_lights::<SPECULAR>(&surface, p.effects, p.num_lights, lights, &mut sum);
    output_colour(p, bounds, i, &surface, sum, count)
}

/// Display colour (linear RGB) of a shaded pixel in the views every technique has: the
/// tonemapped radiance, or the heatmap of the `lights` its list held.
#[inline]
pub fn lit_colour(p: &FrameParams, radiance: Vec3, lights: u32) -> Vec3 {
    if p.view == VIEW_HEATMAP {
        lighting::heat_ramp(lights, p.heat_max)
    } else {
        lighting::tonemap(radiance, p.exposure)
    }
}

/// Final colour of geometry pixel `i` of a deferred pass: [`lit_colour`], or one of the debug
/// views (`VIEW_CLUSTERS`, `VIEW_NORMALS`, `VIEW_DEPTH`), packed as sRGB8.
#[inline]
pub fn output_colour(p: &FrameParams, bounds: &[f32], i: u32, s: &Surface, radiance: Vec3, lights: u32) -> u32 {
    let g = &p.grid;
    let rgb = match p.view {
        VIEW_CLUSTERS => {
            let h = crate::debug_view::hash_u32(g.key(bounds, i % g.width, i / g.width, s.pos.z));
            Vec3::new((h & 255) as f32, ((h >> 8) & 255) as f32, ((h >> 16) & 255) as f32) * (1.0 / 255.0)
        }
        VIEW_NORMALS => s.normal * 0.5 + Vec3::splat(0.5),
        VIEW_DEPTH => crate::debug_view::ramp(g.slice_of_depth(bounds, -s.pos.z) as f32 / g.num_slices as f32),
        _ => lit_colour(p, radiance, lights),
    };
    lighting::encode_srgb8(rgb)
}

/// Declares a shader once and two entry points that differ in one compile-time flag: the
/// shader is written as `fn name<const FLAG: bool>(bindings) { body }` with its `#[spirv(...)]`
/// built-ins and bindings; the macro emits it as a plain function (attributes dropped) and the
/// entries `$off` / `$on` (each declared `#[spirv($entry)]`, documented by its literal) calling
/// it with `false` / `true`. The one macro behind every pair of variant entries:
/// `specular_entries!` (compute) and the Forward+ fragment shaders' list layouts.
macro_rules! variant_entries {
    (
        [$($entry:tt)+] $off:ident: $off_doc:literal, $on:ident: $on_doc:literal;
        $(#[$meta:meta])*
        fn $imp:ident<const $variant:ident: bool>($($(#[$attr:meta])* $arg:ident: $ty:ty),* $(,)?) $body:block
    ) => {
        $(#[$meta])*
        #[inline]
        #[allow(clippy::too_many_arguments)]
        fn $imp<const $variant: bool>($($arg: $ty),*) $body

        #[doc = concat!("[`", stringify!($imp), "`] ", $off_doc)]
        #[spirv($($entry)+)]
        #[allow(clippy::too_many_arguments)]
        pub fn $off($($(#[$attr])* $arg: $ty),*) {
            $imp::<false>($($arg),*);
        }

        #[doc = concat!("[`", stringify!($imp), "`] ", $on_doc)]
        #[spirv($($entry)+)]
        #[allow(clippy::too_many_arguments)]
        pub fn $on($($(#[$attr])* $arg: $ty),*) {
            $imp::<true>($($arg),*);
        }
    };
}
pub(crate) use variant_entries;

/// Declares a shading kernel once and its `_diffuse` and `_specular` compute entry points (256
/// invocations) through [`variant_entries`]: `fn name<const SPECULAR: bool>(bindings) { body }`.
/// One macro for every technique's shading kernels.
#[cfg(feature = "compute")]
macro_rules! specular_entries {
    ($diffuse:ident, $specular:ident; $($kernel:tt)+) => {
        $crate::shading::variant_entries! {
            [compute(threads(256))]
            $diffuse: "without the specular term (scenes without specular materials).",
            $specular: "with the specular term.";
            $($kernel)+
        }
    };
}
#[cfg(feature = "compute")]
pub(crate) use specular_entries;

#[cfg(test)]
#[path = "shading_tests.rs"]
mod tests;
