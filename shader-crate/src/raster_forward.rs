//! Raster shaders of Forward+ ([`crate::forward_plus`] has the algorithm): the depth pre-pass and
//! the forward shading pass, the latter in two variants of its tile lists (`render --fp-lists`):
//! `forward_fs*` walk the linked lists, `forward_fs*_array` read `(offset, count)` and a
//! contiguous index range. Every vertex shader computes its position with the one function
//! [`clip_position`], and the forward pass reuses the G-buffer vertex shaders ([`crate::raster`]),
//! so the depths agree with the pre-pass (the forward pass tests EQUAL) and with the G-buffer of
//! the deferred techniques (the tests compare the images).
//!
//! The forward fragment shades with exactly the deferred inputs: the position from the pixel
//! centre and the fragment's depth through [`shading::pixel_position`] (what the deferred passes
//! compute from the depth buffer), the normal encoded and decoded at the G-buffer precision, the
//! albedo quantised to 8 bits as the `RGBA8_UNORM` G-buffer target stores it, and the light loop
//! and output of every technique ([`crate::shading`]) — so the image equals the deferred
//! reference, not just a similar forward rendering.
use crate::layout::*;
use crate::octahedral::{self, Precision};
use crate::raster::{clip_position, encode_gbuffer_normal, sample_draw_uniform, unorm8, Texture2d, ALPHA_CUTOFF};
use crate::lighting;
use crate::shading::{self, variant_entries, LightList, Surface, BACKGROUND_RGBA8};
use crate::shadow::{CubeShadows, Shadowing};
use spirv_std::glam::{Vec2, Vec3, Vec4};
use spirv_std::spirv;

/// Depth pre-pass vertex shader: the position only ([`clip_position`], as every vertex shader).
#[spirv(vertex)]
pub fn depth_vs(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] camera: &RasterCamera,
    #[spirv(position)] out_position: &mut Vec4,
) {
    *out_position = clip_position(positions, camera, vertex_index as usize);
}

/// Depth pre-pass vertex shader of alpha-tested draws: position and texture coordinate.
#[spirv(vertex)]
pub fn depth_vs_uv(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] uvs: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] camera: &RasterCamera,
    #[spirv(position)] out_position: &mut Vec4,
    out_uv: &mut Vec2,
) {
    let i = vertex_index as usize;
    *out_position = clip_position(positions, camera, i);
    *out_uv = Vec2::new(uvs[2 * i], uvs[2 * i + 1]);
}

/// Depth pre-pass of opaque draws: depth, and the index of the draw that wins the pixel
/// ([`ForwardParams`]`::frame.count`). With the G-buffer's test (GREATER) the first-drawn of
/// coplanar surfaces wins, as in the G-buffer; the forward pass shades only that draw's fragment
/// (EQUAL alone would let the last coplanar one overwrite it).
#[spirv(fragment)]
pub fn depth_fs(#[spirv(push_constant)] p: &ForwardParams, out_draw: &mut u32) {
    *out_draw = p.frame.count;
}

/// Depth pre-pass of alpha-tested draws: fragments below the mask's cut-off write nothing.
#[spirv(fragment)]
pub fn depth_fs_masked(in_uv: Vec2, #[spirv(push_constant)] p: &ForwardParams, #[spirv(descriptor_set = 0, binding = 5)] mask_map: &Texture2d, out_draw: &mut u32) {
    if sample_draw_uniform(mask_map, in_uv).x < ALPHA_CUTOFF {
        spirv_std::arch::demote_to_helper_invocation();
    }
    *out_draw = p.frame.count;
}

/// Coplanar fragments of other draws than the pre-pass's winner (`winners`: its per-pixel draw
/// index) are demoted, so exactly the fragment the G-buffer would keep is shaded.
#[inline]
fn demote_unless_winner(frag: Vec4, p: &ForwardParams, winners: &[u32]) {
    let (px, py) = (frag.x as u32, frag.y as u32);
    if winners[(py * p.frame.grid.width + px) as usize] != p.frame.count {
        spirv_std::arch::demote_to_helper_invocation();
    }
}

/// The sum over `list` at `surface` and its output colour: the light loop of every technique,
/// one light per iteration, with the variant the frame-uniform specular bit picks (no specular
/// code for scenes without specular materials), each shadow-casting light times its visibility
/// from `shadows` (`EFFECT_SHADOWS`, `crate::shadow`).
#[inline]
pub(crate) fn shade_list<L: LightList, S: Shadowing>(f: &FrameParams, surface: &Surface, lights: &[PointLight], list: &L, shadows: &S) -> u32 {
    let mut sum = Vec3::ZERO;
    let count = if f.effects & EFFECT_SPECULAR != 0 {
        let count = shading::shade_lights_with::<true, false, _, S>(surface, f.effects, f.num_lights, lights, list, shadows, &mut sum);
        shading::shade_directional_lights::<true>(surface, f.effects, f.num_lights, lights, &mut sum);
        count
    } else {
        let count = shading::shade_lights_with::<false, false, _, S>(surface, f.effects, f.num_lights, lights, list, shadows, &mut sum);
        shading::shade_directional_lights::<false>(surface, f.effects, f.num_lights, lights, &mut sum);
        count
    };
    lighting::encode_srgb8(shading::lit_colour(f, sum, count))
}

/// The surface a forward fragment shades at view-space position `pos`: the normal the deferred
/// passes would read back from the G-buffer (any precision), the albedo as the `RGBA8_UNORM`
/// target stores it, and the draw's material.
#[inline]
pub(crate) fn forward_surface(in_normal: Vec3, front_facing: bool, texel: Vec3, p: &ForwardParams, materials: &[MaterialGpu], pos: Vec3) -> Surface {
    let facing = if front_facing { in_normal } else { -in_normal };
    let normal = Vec3::from_array(octahedral::decode(encode_gbuffer_normal(facing, p.draw.normal_precision), Precision::from_u32(p.frame.normal_precision)));
    let a = Vec3::from_array(p.draw.albedo) * texel;
    let mat = materials[p.draw.material as usize];
    Surface { pos, normal, albedo: Vec3::new(unorm8(a.x), unorm8(a.y), unorm8(a.z)), specular: mat.specular, roughness: mat.roughness }
}

/// `surface` shaded over the list of the tile holding pixel `(px, py)`, as sRGB8. `ARRAY` picks
/// the list layout (`render --fp-lists`): `false` linked lists (`tiles` = heads, `entries` =
/// nodes), `true` arrays (`tiles` = `(offset, count)` pairs, `entries` = light indices).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn shade_tile<const ARRAY: bool, S: Shadowing>(f: &FrameParams, px: u32, py: u32, surface: &Surface, tiles: &[u32], entries: &[u32], lights: &[PointLight], shadows: &S) -> u32 {
    let (tx, ty) = f.grid.tile_of_pixel(px, py);
    let tile = (ty * f.grid.tiles_x + tx) as usize;
    if ARRAY {
        shade_list(f, surface, lights, &shading::index_range(tiles[2 * tile], tiles[2 * tile + 1], |t| entries[t as usize]), shadows)
    } else {
        shade_list(f, surface, lights, &shading::linked_lights(tiles[tile], entries), shadows)
    }
}

/// The forward shading of one fragment (module docs): its surface at the pixel centre and the
/// fragment's depth, shaded over its tile's list ([`shade_tile`]) with the frame's cube shadow
/// maps (bound as `slots` and `maps` after the lists; the pipelines of frames without
/// shadow-casting lights hold no lookup). Views: the shaded image and the heatmap (lights in the
/// tile's list); the other debug views show the shaded image.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn forward_colour<const ARRAY: bool>(
    frag: Vec4,
    in_normal: Vec3,
    front_facing: bool,
    texel: Vec3,
    p: &ForwardParams,
    tiles: &[u32],
    entries: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    counters: &[u32],
    shadows: &CubeShadows<'_>,
) -> u32 {
    let f = &p.frame;
    // An overflowed frame is re-run with a larger buffer: draw nothing from a partial list.
    if counters[FP_COUNTER_REFS as usize] > f.light_capacity {
        return BACKGROUND_RGBA8;
    }
    let (px, py) = (frag.x as u32, frag.y as u32);
    let surface = forward_surface(in_normal, front_facing, texel, p, materials, shading::pixel_position(&f.grid, px, py, frag.z));
    shade_tile::<ARRAY, _>(f, px, py, &surface, tiles, entries, lights, shadows)
}

variant_entries! {
    [fragment] forward_fs: "over the linked lists (`--fp-lists linked`).", forward_fs_array: "over the arrays (`--fp-lists array`).";
    /// Forward pass of untextured draws.
    fn forward_fs_impl<const ARRAY: bool>(
        in_normal: Vec3,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] shadow_maps: &[u32],
        out_colour: &mut u32,
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        demote_unless_winner(frag, p, winners);
        *out_colour = forward_colour::<ARRAY>(frag, in_normal, front_facing, Vec3::ONE, p, tiles, entries, lights, materials, counters, &CubeShadows { slots: shadow_slots, maps: shadow_maps });
    }
}

variant_entries! {
    [fragment] forward_fs_textured: "over the linked lists (`--fp-lists linked`).", forward_fs_textured_array: "over the arrays (`--fp-lists array`).";
    /// Forward pass of textured draws.
    fn forward_fs_textured_impl<const ARRAY: bool>(
        in_normal: Vec3,
        in_uv: Vec2,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] shadow_maps: &[u32],
        #[spirv(descriptor_set = 0, binding = 12)] albedo_map: &Texture2d,
        out_colour: &mut u32,
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        demote_unless_winner(frag, p, winners);
        let texel = sample_draw_uniform(albedo_map, in_uv).truncate();
        *out_colour = forward_colour::<ARRAY>(frag, in_normal, front_facing, texel, p, tiles, entries, lights, materials, counters, &CubeShadows { slots: shadow_slots, maps: shadow_maps });
    }
}

variant_entries! {
    [fragment] forward_fs_masked: "over the linked lists (`--fp-lists linked`).", forward_fs_masked_array: "over the arrays (`--fp-lists array`).";
    /// Forward pass of alpha-tested draws (cut-out fragments also fail the EQUAL test; demoted
    /// all the same, as in the pre-pass).
    fn forward_fs_masked_impl<const ARRAY: bool>(
        in_normal: Vec3,
        in_uv: Vec2,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 11)] shadow_maps: &[u32],
        #[spirv(descriptor_set = 0, binding = 12)] albedo_map: &Texture2d,
        #[spirv(descriptor_set = 0, binding = 13)] mask_map: &Texture2d,
        out_colour: &mut u32,
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        demote_unless_winner(frag, p, winners);
        if sample_draw_uniform(mask_map, in_uv).x < ALPHA_CUTOFF {
            spirv_std::arch::demote_to_helper_invocation();
        }
        let texel = sample_draw_uniform(albedo_map, in_uv).truncate();
        *out_colour = forward_colour::<ARRAY>(frag, in_normal, front_facing, texel, p, tiles, entries, lights, materials, counters, &CubeShadows { slots: shadow_slots, maps: shadow_maps });
    }
}
