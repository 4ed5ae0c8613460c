//! MSAA with per-sample shading of edge pixels (`--msaa N`): Lauritzen, "Deferred Rendering for
//! Current and Future Rendering Pipelines" (SIGGRAPH 2010 course *Beyond Programmable Shading*,
//! "Tiled deferred shading with MSAA": classify each pixel, shade the ordinary ones once and
//! the edge pixels once per sample in a second loop over a compact list).
//!
//! # Steps
//!
//! 1. **G-buffer at `N` samples** (raster): the fragment shader runs once per pixel and
//!    primitive (at the pixel centre) and its normal and albedo go to every sample the
//!    primitive covers; depth is per sample.
//! 2. **Gather** ([`msaa_gather`], one invocation per pixel): the `N` samples of the three
//!    targets (sampled images) go to the G-buffer buffers, sample `s` of pixel `i` at entry
//!    `s·n + i` (`n` pixels): plane 0 is the per-pixel G-buffer every technique reads, so a
//!    technique's passes run unchanged on sample 0. The pixel is classified ([`is_edge`]) and an
//!    edge pixel appended to the edge list.
//! 3. **Edge arguments** ([`msaa_edge_args`], one invocation): the workgroups of step 5.
//! 4. **The technique's passes** shade every pixel once: sample 0's surface at the pixel centre.
//! 5. **Edge shading** (the technique's `shade_edges_*`, one invocation per edge pixel,
//!    [`shade_edge_pixel`]): every sample's surface at its own location ([`sample_location`]),
//!    shaded with the technique's light list for that sample; the mean of the samples' display
//!    colours (linear, after tonemapping) replaces the pixel. Sky samples count as the
//!    background colour.
//!
//! **Edges** ([`is_edge`]): a sample whose geometry or sky state, albedo word or material
//! differs from sample 0's, whose normal turns more than `acos(`[`EDGE_NORMAL_COS`]`)` from it,
//! or whose distance is off the plane of sample 0 (its position and normal, continued to the
//! sample's view ray) by more than [`EDGE_DEPTH_RELATIVE`] of the nearer of the two. Samples of
//! one primitive share normal and albedo (step 1) and lie on its plane, so a slanted floor is no
//! edge however fast its depth changes; a parallel surface behind another is.
//!
//! **Memory** (`n` pixels): the G-buffer targets and buffers `N` times (12 B per sample, 24 B
//! with float32 normals, each as a target and as a buffer), the edge list `4·n + 16` B. With
//! `N = 1` none of this exists: the G-buffer is copied as before and no pass of this module runs.
use crate::layout::*;
use crate::shading::Surface;
use crate::{lighting, octahedral, reconstruct, shading};
use glam::{Vec3, Vec4};
#[cfg(feature = "compute")]
use crate::light_lists::AtomicAdd;
#[cfg(feature = "compute")]
use crate::shading::linear_index;
#[cfg(feature = "compute")]
use spirv_std::glam::{IVec2, UVec3};
#[cfg(feature = "compute")]
use spirv_std::image::{sample_with, ImageWithMethods};
#[cfg(feature = "compute")]
use spirv_std::{spirv, Image};

/// Sample counts `--msaa` takes (a device may support fewer).
pub const SAMPLE_COUNTS: [u32; 4] = [1, 2, 4, 8];
/// The largest of [`SAMPLE_COUNTS`].
pub const MAX_SAMPLES: u32 = 8;

/// Vulkan's standard sample locations (`standardSampleLocations`; Vulkan 1.3 §28.4,
/// "Multisampling") for 1, 2, 4 and 8 samples, in sixteenths of a pixel from its top-left
/// corner: sample `s` is byte `s % 4` of word `s / 4` of the pattern, `x | y << 4`. Packed in
/// 32-bit integers, not arrays: a choice between constant arrays compiles to a choice between
/// pointers, which SPIR-V for Vulkan does not have, and the raster module has no 64-bit integers.
const LOCATIONS_1: u32 = 0x88;
const LOCATIONS_2: u32 = 0x44_cc;
const LOCATIONS_4: u32 = 0xea_a2_6e_26;
const LOCATIONS_8: [u32; 2] = [0x35_9d_b7_59, 0x1f_fb_71_d3];

/// Location of sample `s` of `samples` ([`SAMPLE_COUNTS`]) in sixteenths of a pixel, `(x, y)`
/// from the pixel's top-left corner (y down, as the framebuffer's rows). Any other count gets the
/// pixel centre.
#[inline]
pub fn sample_location(samples: u32, s: u32) -> (u32, u32) {
    let (pattern, index) = match samples {
        2 => (LOCATIONS_2, s & 1),
        4 => (LOCATIONS_4, s & 3),
        8 => (if s & 4 == 0 { LOCATIONS_8[0] } else { LOCATIONS_8[1] }, s & 3),
        _ => (LOCATIONS_1, 0),
    };
    let byte = (pattern >> (8 * index)) & 0xff;
    (byte & 15, byte >> 4)
}

/// A sample's distance differs by more than this fraction of the nearer one: an edge.
pub const EDGE_DEPTH_RELATIVE: f32 = 0.01;
/// A sample's normal makes an angle with sample 0's whose cosine is below this (about 5.7°): an
/// edge.
pub const EDGE_NORMAL_COS: f32 = 0.995;

/// Words before the edge list's entries: the count, then the edge pass's indirect workgroup
/// counts `[x, y, z]`.
pub const EDGE_HEADER_WORDS: u32 = 4;
/// Word of the first indirect workgroup count.
pub const EDGE_ARGS_WORD: u32 = 1;

/// What [`is_edge`] compares of one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleKey {
    /// Reversed-Z depth-buffer value.
    pub depth: f32,
    /// View-space normal.
    pub normal: Vec3,
    /// G-buffer albedo word (colour and material).
    pub albedo: u32,
    /// The view-space point of the sample's location at distance 1 (its view ray, `z = −1`).
    pub ray: Vec3,
}

/// Whether sample `b` belongs to another surface than sample `a` (module docs, "Edges").
#[inline]
pub fn differs(near: f32, a: &SampleKey, b: &SampleKey) -> bool {
    let (sky_a, sky_b) = (reconstruct::is_background(a.depth), reconstruct::is_background(b.depth));
    if sky_a || sky_b {
        return sky_a != sky_b;
    }
    if a.albedo != b.albedo {
        return true;
    }
    let n = lighting::unit_normal(a.normal);
    // NaN-safe: a normal that does not compare as close is an edge.
    let close = n.dot(lighting::unit_normal(b.normal)) >= EDGE_NORMAL_COS;
    // Sample `a`'s plane (point `ray_a·d_a`, normal `n`) meets `b`'s ray at `d = n·p_a / n·ray_b`.
    let (da, db) = (reconstruct::distance_from_depth(near, a.depth), reconstruct::distance_from_depth(near, b.depth));
    let (along_a, along_b) = (n.dot(a.ray) * da, n.dot(b.ray));
    // `b` on the plane: `|d_b·(n·ray_b) − n·p_a| ≤ t·min(d_b, d)·|n·ray_b|`, divided out; a plane
    // seen edge-on (`n·ray_b` = 0) keeps no sample but its own.
    let off = db * along_b - along_a;
    let off = if off < 0.0 { -off } else { off };
    let slope = if along_b < 0.0 { -along_b } else { along_b };
    let predicted = if slope > 0.0 { along_a / along_b } else { f32::INFINITY };
    let nearer = if db < predicted { db } else { predicted };
    let on_plane = off <= EDGE_DEPTH_RELATIVE * nearer * slope;
    !(on_plane && close)
}

/// Whether a pixel whose samples are `key(0..samples)` is an edge pixel: any sample
/// [`differs`] from sample 0.
#[inline]
pub fn is_edge(near: f32, samples: u32, key: impl Fn(u32) -> SampleKey) -> bool {
    let first = key(0);
    let mut edge = false;
    let mut s = 1;
    while s < samples {
        edge = edge || differs(near, &first, &key(s));
        s += 1;
    }
    edge
}

/// The surface of sample `s` of geometry pixel `i` (entry `s·n + i` of the G-buffer buffers,
/// `n` = `p.count`) at the sample's location.
#[inline]
pub fn sample_surface(p: &FrameParams, i: u32, s: u32, depth: &[f32], normals: &[u32], albedo: &[u32], materials: &[MaterialGpu]) -> Surface {
    let e = s * p.count + i;
    let mut surface = shading::fetch_surface(p, e, depth[e as usize], normals, albedo[e as usize], materials);
    let g = &p.grid;
    let (ox, oy) = sample_location(g.samples, s);
    let d = reconstruct::distance_from_depth(g.near, depth[e as usize]);
    surface.pos = reconstruct::sample_position(g, i % g.width, i / g.width, ox, oy, d);
    surface
}

/// Step 5 for edge pixel `i`: the mean display colour of its samples, packed as sRGB8.
/// `shade(s, surface)` is the technique's radiance at sample `s`'s surface (its light list's sum
/// and the directional lights) and the list's length for the heatmap.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn shade_edge_pixel(
    p: &FrameParams,
    i: u32,
    bounds: &[f32],
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    materials: &[MaterialGpu],
    shade: impl Fn(u32, &Surface) -> (Vec3, u32),
) -> u32 {
    let samples = p.grid.samples;
    let mut sum = Vec3::ZERO;
    let mut s = 0;
    while s < samples {
        sum += if is_sky(p, i, s, depth) {
            background()
        } else {
            let surface = sample_surface(p, i, s, depth, normals, albedo, materials);
            let (radiance, lights) = shade(s, &surface);
            sample_colour(p, bounds, i, &surface, radiance, lights)
        };
        s += 1;
    }
    resolve(sum, samples)
}

/// Whether sample `s` of pixel `i` shows no geometry.
#[inline]
pub fn is_sky(p: &FrameParams, i: u32, s: u32, depth: &[f32]) -> bool {
    reconstruct::is_background(depth[(s * p.count + i) as usize])
}

/// The background's display colour, linear (a sky sample's share of an edge pixel).
#[inline]
pub fn background() -> Vec3 {
    lighting::decode_srgb8(shading::BACKGROUND_RGBA8)
}

/// A shaded sample's display colour, linear: `shading::output_colour` decoded (so the mean of
/// the samples is taken over what one-sample frames show).
#[inline]
pub fn sample_colour(p: &FrameParams, bounds: &[f32], i: u32, surface: &Surface, radiance: Vec3, lights: u32) -> Vec3 {
    lighting::decode_srgb8(shading::output_colour(p, bounds, i, surface, radiance, lights))
}

/// The pixel of `samples` samples whose display colours add up to `sum`: their mean, sRGB8.
#[inline]
pub fn resolve(sum: Vec3, samples: u32) -> u32 {
    lighting::encode_srgb8(sum * (1.0 / samples.max(1) as f32))
}

/// Whether pixel `i` of a multisampled G-buffer's planes is an edge pixel ([`is_edge`]).
#[inline]
pub fn pixel_is_edge(p: &FrameParams, i: u32, depth: &[f32], normals: &[u32], albedo: &[u32]) -> bool {
    let g = p.grid;
    let words = octahedral::Precision::from_u32(p.normal_precision).gbuffer_words();
    // `move`: the closure holds values, not pointers to this function's locals (a struct of
    // such pointers is not valid SPIR-V for Vulkan).
    let (count, precision) = (p.count, p.normal_precision);
    let key = move |s: u32| {
        let e = s * count + i;
        let w = if words == 4 { [normals[4 * e as usize], normals[4 * e as usize + 1], normals[4 * e as usize + 2]] } else { [normals[e as usize], 0, 0] };
        sample_key(&g, precision, i, s, depth[e as usize], w, albedo[e as usize])
    };
    is_edge(g.near, g.samples, key)
}

/// What [`is_edge`] compares of sample `s` of pixel `i`, from its G-buffer values: the
/// reversed-Z `depth`, the normal's `words` at `precision` (`PRECISION_*`) and the albedo word.
#[inline]
pub fn sample_key(g: &ClusterGrid, precision: u32, i: u32, s: u32, depth: f32, words: [u32; 3], albedo: u32) -> SampleKey {
    let (ox, oy) = sample_location(g.samples, s);
    let ray = reconstruct::sample_position(g, i % g.width, i / g.width, ox, oy, 1.0);
    SampleKey { depth, normal: decoded_normal(precision, words), albedo, ray }
}

/// The G-buffer albedo word of a fetched `RGBA8_UNORM` texel (the inverse of the target's
/// conversion: `c / 255` back to `c`, exactly).
#[inline]
pub fn albedo_word(texel: Vec4) -> u32 {
    let b = |c: f32| ((c * 255.0 + 0.5) as u32).min(255);
    b(texel.x) | (b(texel.y) << 8) | (b(texel.z) << 16) | (b(texel.w) << 24)
}

/// The normal of a multisampled G-buffer, whose normal target is `RGBA32_SFLOAT` for every
/// precision (integer targets need not multisample: lavapipe's `framebufferIntegerColorSampleCounts`
/// is 1): an octahedral word as its two 16-bit halves (integers, stored exactly), or the float32
/// normal's three components as values (stored unchanged, except that a target may flush a
/// subnormal component to zero). [`normal_words`] is the inverse.
#[inline]
pub fn float_normal(words: [u32; 3], precision: u32) -> Vec4 {
    if octahedral::Precision::from_u32(precision).gbuffer_words() == 4 {
        Vec4::new(f32::from_bits(words[0]), f32::from_bits(words[1]), f32::from_bits(words[2]), 0.0)
    } else {
        Vec4::new((words[0] & 0xffff) as f32, (words[0] >> 16) as f32, 0.0, 0.0)
    }
}

/// The G-buffer words of a [`float_normal`] texel (the fourth word of float32 normals is 0).
#[inline]
pub fn normal_words(texel: Vec4, precision: u32) -> [u32; 4] {
    if octahedral::Precision::from_u32(precision).gbuffer_words() == 4 {
        [texel.x.to_bits(), texel.y.to_bits(), texel.z.to_bits(), 0]
    } else {
        [(texel.x as u32 & 0xffff) | ((texel.y as u32 & 0xffff) << 16), 0, 0, 0]
    }
}

/// The normal [`is_edge`] compares: the G-buffer words decoded at precision `precision`
/// (`PRECISION_*`).
#[inline]
pub fn decoded_normal(precision: u32, words: [u32; 3]) -> Vec3 {
    Vec3::from_array(octahedral::decode(words, octahedral::Precision::from_u32(precision)))
}

/// A multisampled float target read texel by texel (depth, normals, albedo).
#[cfg(feature = "compute")]
pub type SamplesF32 = Image!(2D, type = f32, sampled, multisampled);

#[cfg(feature = "compute")]
/// Step 2 for pixel `i` of the linear dispatch.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn msaa_gather(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &mut [f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] edges: &mut [u32],
    #[spirv(descriptor_set = 0, binding = 4)] depth_samples: &SamplesF32,
    #[spirv(descriptor_set = 0, binding = 5)] normal_samples: &SamplesF32,
    #[spirv(descriptor_set = 0, binding = 6)] albedo_samples: &SamplesF32,
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let g = &p.grid;
    let at = IVec2::new((i % g.width) as i32, (i / g.width) as i32);
    let words = octahedral::Precision::from_u32(p.normal_precision).gbuffer_words();
    let mut s = 0;
    while s < p.grid.samples {
        let e = (s * p.count + i) as usize;
        let z: Vec4 = depth_samples.fetch_with(at, sample_with::sample_index(s as i32));
        let t: Vec4 = normal_samples.fetch_with(at, sample_with::sample_index(s as i32));
        let a: Vec4 = albedo_samples.fetch_with(at, sample_with::sample_index(s as i32));
        depth[e] = z.x;
        albedo[e] = albedo_word(a);
        let n = normal_words(t, p.normal_precision);
        if words == 4 {
            normals[4 * e] = n[0];
            normals[4 * e + 1] = n[1];
            normals[4 * e + 2] = n[2];
            normals[4 * e + 3] = n[3];
        } else {
            normals[e] = n[0];
        }
        s += 1;
    }
    if pixel_is_edge(p, i, depth, normals, albedo) {
        let slot = edges[0].fetch_add(1);
        edges[(EDGE_HEADER_WORDS + slot) as usize] = i;
    }
}

#[cfg(feature = "compute")]
/// Step 3: the edge pass's workgroups from the edge count.
#[spirv(compute(threads(1)))]
pub fn msaa_edge_args(#[spirv(storage_buffer, descriptor_set = 0, binding = 0)] edges: &mut [u32]) {
    let [x, y, z] = crate::indirect::dispatch_args(edges[0], shading::LINEAR_WORKGROUP);
    edges[EDGE_ARGS_WORD as usize] = x;
    edges[EDGE_ARGS_WORD as usize + 1] = y;
    edges[EDGE_ARGS_WORD as usize + 2] = z;
}

#[cfg(test)]
#[path = "msaa_tests.rs"]
mod tests;
