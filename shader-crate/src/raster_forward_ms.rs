//! Raster shaders of Forward+ with MSAA ([`crate::forward_msaa`] has the steps): the depth
//! pre-pass writing each sample's winning draw into a float target, and the forward pass whose
//! fragments shade the samples they own ([`crate::forward_msaa::visible_samples`]) and write
//! their colours, normal and albedo to exactly those samples (an output sample mask).
use crate::forward_msaa::{colour_texel, fragment_colours, sample_surface_position, visible_samples};
use crate::layout::*;
use crate::msaa::{albedo_word, float_normal, is_edge, normal_words, sample_key};
use crate::raster::{sample_draw_uniform, targets, Texture2d, ALPHA_CUTOFF};
use crate::raster_forward::{forward_surface, shade_tile};
use crate::shadow::NoShadows;
use crate::shading::{self, variant_entries, BACKGROUND_RGBA8};
use spirv_std::glam::{Vec2, Vec3, Vec4};
use spirv_std::spirv;

/// Step 1 of opaque draws: the triangle, as the draw's index ([`ForwardParams`]`::frame.count`)
/// and the primitive's, in floats.
#[spirv(fragment)]
pub fn depth_fs_ms(#[spirv(primitive_id, flat)] primitive: u32, #[spirv(push_constant)] p: &ForwardParams, out_winner: &mut Vec2) {
    *out_winner = winner(p, primitive);
}

/// The winner target's texel for primitive `primitive` of the draw ([`depth_fs_ms`]).
#[inline]
fn winner(p: &ForwardParams, primitive: u32) -> Vec2 {
    Vec2::new(p.frame.count as f32, primitive as f32)
}

/// Step 1 of alpha-tested draws: fragments below the mask's cut-off write nothing.
#[spirv(fragment)]
pub fn depth_fs_masked_ms(
    in_uv: Vec2,
    #[spirv(primitive_id, flat)] primitive: u32,
    #[spirv(push_constant)] p: &ForwardParams,
    #[spirv(descriptor_set = 0, binding = 5)] mask_map: &Texture2d,
    out_winner: &mut Vec2,
) {
    if sample_draw_uniform(mask_map, in_uv).x < ALPHA_CUTOFF {
        spirv_std::arch::demote_to_helper_invocation();
    }
    *out_winner = winner(p, primitive);
}

/// What one fragment of step 4 writes to its samples.
pub struct MsOutputs {
    /// [`crate::forward_msaa::colour_texel`]: edge colour and centre colour.
    pub colour: Vec4,
    /// The G-buffer's normal (`crate::msaa::float_normal`) and albedo for these samples.
    pub normal: Vec4,
    pub albedo: Vec4,
    /// The samples written (an output sample mask).
    pub mask: u32,
}

/// Step 4 for one fragment of primitive `primitive`: what it writes ([`MsOutputs`]). `covered` is
/// the rasteriser's coverage; `winners` and `depth` are the pre-pass's planes.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn forward_colour_ms<const ARRAY: bool>(
    frag: Vec4,
    primitive: u32,
    covered: u32,
    in_normal: Vec3,
    front_facing: bool,
    texel: Vec3,
    p: &ForwardParams,
    tiles: &[u32],
    entries: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    counters: &[u32],
    winners: &[u32],
    depth: &[f32],
) -> MsOutputs {
    let f = &p.frame;
    let g = f.grid;
    let (words, albedo) = targets(in_normal, front_facing, texel, &p.draw);
    let normal = float_normal(words, p.draw.normal_precision);
    // An overflowed frame is re-run with a larger buffer: draw nothing from a partial list.
    if counters[FP_COUNTER_REFS as usize] > f.light_capacity {
        let colour = colour_texel(crate::lighting::decode_srgb8(BACKGROUND_RGBA8), BACKGROUND_RGBA8);
        return MsOutputs { colour, normal, albedo, mask: covered };
    }
    let (px, py) = (frag.x as u32, frag.y as u32);
    let n = g.width * g.height;
    let i = py * g.width + px;
    let owned = visible_samples(g.samples, covered, (f.count, primitive), move |s| (winners[(2 * (s * n + i)) as usize], winners[(2 * (s * n + i) + 1) as usize]));
    let shade_at = move |pos: Vec3, lights: &[PointLight]| shade_tile::<ARRAY, _>(f, px, py, &forward_surface(in_normal, front_facing, texel, p, materials, pos), tiles, entries, lights, &NoShadows);
    // A pixel this fragment covers alone is an edge pixel where the edge rule says so of its
    // own samples (a surface seen edge-on): the keys the resolve will read back.
    let (precision, key_words, key_albedo) = (f.normal_precision, normal_words(normal, f.normal_precision), albedo_word(albedo));
    let alone_is_edge = move || is_edge(g.near, g.samples, move |s| sample_key(&g, precision, i, s, depth[(s * n + i) as usize], [key_words[0], key_words[1], key_words[2]], key_albedo));
    let (edge, centre) = fragment_colours(
        lights,
        g.samples,
        owned,
        alone_is_edge,
        move |lights| shade_at(shading::pixel_position(&g, px, py, depth[i as usize]), lights),
        move |lights, s| shade_at(sample_surface_position(&g, px, py, s, depth[(s * n + i) as usize]), lights),
    );
    MsOutputs { colour: colour_texel(edge, centre), normal, albedo, mask: owned }
}

variant_entries! {
    [fragment] forward_fs_ms: "over the linked lists (`--fp-lists linked`).", forward_fs_ms_array: "over the arrays (`--fp-lists array`).";
    /// Step 4 of untextured draws.
    fn forward_fs_ms_impl<const ARRAY: bool>(
        in_normal: Vec3,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(sample_mask, flat)] covered: [u32; 1],
        #[spirv(primitive_id, flat)] primitive: u32,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] depth: &[f32],
        out_colour: &mut Vec4,
        out_normal: &mut Vec4,
        out_albedo: &mut Vec4,
        #[spirv(sample_mask)] out_mask: &mut [u32; 1],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let o = forward_colour_ms::<ARRAY>(frag, primitive, covered[0], in_normal, front_facing, Vec3::ONE, p, tiles, entries, lights, materials, counters, winners, depth);
        (*out_colour, *out_normal, *out_albedo, *out_mask) = (o.colour, o.normal, o.albedo, [o.mask]);
    }
}

variant_entries! {
    [fragment] forward_fs_textured_ms: "over the linked lists (`--fp-lists linked`).", forward_fs_textured_ms_array: "over the arrays (`--fp-lists array`).";
    /// Step 4 of textured draws.
    fn forward_fs_textured_ms_impl<const ARRAY: bool>(
        in_normal: Vec3,
        in_uv: Vec2,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(sample_mask, flat)] covered: [u32; 1],
        #[spirv(primitive_id, flat)] primitive: u32,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] depth: &[f32],
        #[spirv(descriptor_set = 0, binding = 11)] albedo_map: &Texture2d,
        out_colour: &mut Vec4,
        out_normal: &mut Vec4,
        out_albedo: &mut Vec4,
        #[spirv(sample_mask)] out_mask: &mut [u32; 1],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let texel = sample_draw_uniform(albedo_map, in_uv).truncate();
        let o = forward_colour_ms::<ARRAY>(frag, primitive, covered[0], in_normal, front_facing, texel, p, tiles, entries, lights, materials, counters, winners, depth);
        (*out_colour, *out_normal, *out_albedo, *out_mask) = (o.colour, o.normal, o.albedo, [o.mask]);
    }
}

variant_entries! {
    [fragment] forward_fs_masked_ms: "over the linked lists (`--fp-lists linked`).", forward_fs_masked_ms_array: "over the arrays (`--fp-lists array`).";
    /// Step 4 of alpha-tested draws (the cut-out test at the pixel centre, as the pre-pass's).
    fn forward_fs_masked_ms_impl<const ARRAY: bool>(
        in_normal: Vec3,
        in_uv: Vec2,
        #[spirv(front_facing)] front_facing: bool,
        #[spirv(frag_coord)] frag: Vec4,
        #[spirv(sample_mask, flat)] covered: [u32; 1],
        #[spirv(primitive_id, flat)] primitive: u32,
        #[spirv(push_constant)] p: &ForwardParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] tiles: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] counters: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] winners: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] depth: &[f32],
        #[spirv(descriptor_set = 0, binding = 11)] albedo_map: &Texture2d,
        #[spirv(descriptor_set = 0, binding = 12)] mask_map: &Texture2d,
        out_colour: &mut Vec4,
        out_normal: &mut Vec4,
        out_albedo: &mut Vec4,
        #[spirv(sample_mask)] out_mask: &mut [u32; 1],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let texel = sample_draw_uniform(albedo_map, in_uv).truncate();
        if sample_draw_uniform(mask_map, in_uv).x < ALPHA_CUTOFF {
            spirv_std::arch::demote_to_helper_invocation();
        }
        let o = forward_colour_ms::<ARRAY>(frag, primitive, covered[0], in_normal, front_facing, texel, p, tiles, entries, lights, materials, counters, winners, depth);
        (*out_colour, *out_normal, *out_albedo, *out_mask) = (o.colour, o.normal, o.albedo, [o.mask]);
    }
}
