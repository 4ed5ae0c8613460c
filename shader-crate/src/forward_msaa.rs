//! Forward+ with MSAA (`forward-plus --msaa N`): a multisampled forward pass whose pixels are
//! classified and resolved by the deferred techniques' rule ([`crate::msaa`]): a pixel that is no
//! edge keeps one shading at its centre, an edge pixel the mean of its samples shaded each at its
//! own location — the same image as `deferred --msaa N`, without a G-buffer pass.
//!
//! # Steps
//!
//! 1. **Depth pre-pass at `N` samples** (raster, `raster_forward_ms::depth_fs*_ms`): depth per
//!    sample and, per sample, the triangle that wins it — its draw and its primitive in the draw,
//!    in an `RG32_SFLOAT` target (integer targets need not multisample; integers below 2^24 are
//!    exact in a float).
//! 2. **Gather** ([`forward_gather`], one invocation per pixel): both targets into per-sample
//!    planes of buffers (sample `s` of pixel `i` at `s·n + i`), the layout of a multisampled
//!    G-buffer's depth, so the culling's tile bounds span every sample as the deferred
//!    techniques' do (`tile_cull::tile_bounds`).
//! 3. **Culling**: Forward+'s, unchanged.
//! 4. **Forward pass at `N` samples** (raster, `raster_forward_ms::forward_fs*_ms`): the fragment
//!    runs once per pixel and primitive, at the pixel centre (as the G-buffer's does), the draws
//!    in the pre-pass's order. Its samples ([`visible_samples`]) are those the pre-pass gave to
//!    its triangle: exactly where the G-buffer would hold its surface. It writes to them ([`fragment_colours`]): the **edge colour**, the mean of the
//!    display colours of its samples shaded each at the sample's own location and depth
//!    ([`sample_surface_position`]), as the deferred edge pass shades them; the **centre
//!    colour** (the fragment holding sample 0 only), its surface shaded once at sample 0's depth
//!    on the pixel-centre ray, as the deferred techniques shade a pixel that is no edge; and the
//!    normal and albedo the G-buffer would hold for those samples (`raster::targets`).
//! 5. **Resolve** ([`forward_resolve`] → [`resolve_pixel`], one invocation per pixel): the pixel
//!    classified by [`crate::msaa::is_edge`] over its samples' depths, normals and albedo — the
//!    deferred rule on the deferred values. No edge: sample 0's centre colour. Edge: the mean of
//!    the samples' edge colours, which (each fragment wrote its mean to each of its samples) is
//!    the mean over the samples of each one's own colour: the deferred edge pixel's value.
//!    Edge pixels are counted (`--stats`' `edge_pixels`, equal to the deferred techniques').
//!
//! A fragment holding every sample of its pixel shades once (unless the edge rule calls its own
//! samples an edge: a surface seen edge-on, whose samples leave its plane's tolerance); one
//! holding some shades each of them and, if it holds sample 0, the centre too: per fragment at
//! most `N` + 1 shadings, only on edge pixels.
//!
//! **Memory** (`n` pixels, per sample): the depth target 4 B, the winner target 8 B, the colour
//! target 16 B (`RGBA32_SFLOAT`: the linear edge colour and the centre colour's word), the
//! normal target 16 B, the albedo target 4 B, the depth plane 4 B and the winner plane 8 B:
//! 60 B per sample ([`BYTES_PER_SAMPLE`]), plus one word counting edge pixels. Scenes of
//! [`MAX_DRAWS`] draws or a draw of as many triangles are refused with `--msaa`.
use crate::layout::*;
use crate::reconstruct;
use glam::{Vec3, Vec4};
#[cfg(feature = "compute")]
use crate::shading::linear_index;
#[cfg(feature = "compute")]
use spirv_std::glam::{IVec2, UVec3};
#[cfg(feature = "compute")]
use spirv_std::image::{sample_with, ImageWithMethods};
#[cfg(feature = "compute")]
use spirv_std::spirv;

/// The samples (a mask, bit `s`) a fragment of triangle `me` (its draw and its primitive in the
/// draw) owns: those it covers (`covered`, the rasteriser's coverage) that the pre-pass gave to
/// the same triangle (`winner(s)`). The pre-pass ran the same draws in the same order with the
/// same depth test as the G-buffer pass, so these are exactly the samples where the G-buffer
/// holds this triangle's surface — ties between coplanar triangles included, which a depth
/// comparison could not settle.
#[inline]
pub fn visible_samples(samples: u32, covered: u32, me: (u32, u32), winner: impl Fn(u32) -> (u32, u32)) -> u32 {
    let mut owned = 0;
    let mut s = 0;
    while s < samples {
        if covered & (1 << s) != 0 && winner(s) == me {
            owned |= 1 << s;
        }
        s += 1;
    }
    owned
}

/// Every sample of `samples`.
#[inline]
pub fn full_mask(samples: u32) -> u32 {
    if samples >= 32 { u32::MAX } else { (1u32 << samples) - 1 }
}

/// View-space position of sample `s` of pixel `(px, py)` at reversed-Z depth `z_buf` (its own
/// location: what the deferred edge pass shades, `msaa::sample_surface`).
#[inline]
pub fn sample_surface_position(g: &ClusterGrid, px: u32, py: u32, s: u32, z_buf: f32) -> Vec3 {
    let (ox, oy) = crate::msaa::sample_location(g.samples, s);
    reconstruct::sample_position(g, px, py, ox, oy, reconstruct::distance_from_depth(g.near, z_buf))
}

/// Step 4's colours for a fragment owning the samples `owned` ([`visible_samples`]):
/// `(edge, centre)`. `edge` (linear display colour) is the mean of `at_sample(s)` (sRGB8) over
/// them — or the centre's colour where it owns none (it writes nothing then) or every sample of
/// a pixel that is no edge (`alone_is_edge()`: the edge rule over its own samples; the resolve
/// then reads the centre). `centre` is `centre()` (sRGB8, sample 0's depth at the pixel centre)
/// for the fragment owning sample 0, else 0: the resolve reads it from sample 0 alone. Both
/// shading closures get `data` (the light buffer) as an argument rather than capturing it: a
/// closure holding a slice keeps the binding's length in its captures (`tests/spirv_lengths.rs`).
#[inline]
pub fn fragment_colours<T: ?Sized>(data: &T, samples: u32, owned: u32, alone_is_edge: impl Fn() -> bool, centre: impl Fn(&T) -> u32, at_sample: impl Fn(&T, u32) -> u32) -> (Vec3, u32) {
    if owned == 0 || (owned == full_mask(samples) && !alone_is_edge()) {
        let c = centre(data);
        return (crate::lighting::decode_srgb8(c), c);
    }
    let c = if owned & 1 != 0 { centre(data) } else { 0 };
    let mut sum = Vec3::ZERO;
    let mut count = 0u32;
    let mut s = 0;
    while s < samples {
        if owned & (1 << s) != 0 {
            sum += crate::lighting::decode_srgb8(at_sample(data, s));
            count += 1;
        }
        s += 1;
    }
    (sum * (1.0 / count.max(1) as f32), c)
}

/// The colour target's texel for an edge colour and a centre colour: the edge colour in RGB, the
/// centre colour's three bytes as an integer in alpha (below 2^24: exact in a float).
#[inline]
pub fn colour_texel(edge: Vec3, centre: u32) -> Vec4 {
    edge.extend((centre & 0xff_ffff) as f32)
}

/// The centre colour (sRGB8 word) a [`colour_texel`] holds.
#[inline]
pub fn centre_of(texel: Vec4) -> u32 {
    (texel.w as u32 & 0xff_ffff) | 0xff00_0000
}

/// Step 5 for a pixel of `samples` samples whose classification keys are `key(s)` and colour
/// texels `texel(s)` ([`colour_texel`]): the frame's sRGB8 word, and whether it is an edge pixel
/// (`near`: the near plane, [`crate::msaa::is_edge`]).
#[inline]
pub fn resolve_pixel(near: f32, samples: u32, key: impl Fn(u32) -> crate::msaa::SampleKey, texel: impl Fn(u32) -> Vec4) -> (u32, bool) {
    if !crate::msaa::is_edge(near, samples, key) {
        return (centre_of(texel(0)), false);
    }
    let mut sum = Vec3::ZERO;
    let mut s = 0;
    while s < samples {
        sum += texel(s).truncate();
        s += 1;
    }
    (crate::msaa::resolve(sum, samples), true)
}

/// Bytes per sample of a multisampled frame (module docs, "Memory").
pub const BYTES_PER_SAMPLE: u64 = 4 + 8 + 16 + 16 + 4 + 4 + 8;

/// A multisampled float target read texel by texel.
#[cfg(feature = "compute")]
pub type SamplesF32 = crate::msaa::SamplesF32;

#[cfg(feature = "compute")]
/// Step 2 for pixel `i`: its samples' depths and winning triangles (draw, primitive: two words
/// per sample) into their planes.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn forward_gather(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &mut [f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] winners: &mut [u32],
    #[spirv(descriptor_set = 0, binding = 2)] depth_samples: &SamplesF32,
    #[spirv(descriptor_set = 0, binding = 3)] winner_samples: &SamplesF32,
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let at = IVec2::new((i % p.grid.width) as i32, (i / p.grid.width) as i32);
    let mut s = 0;
    while s < p.grid.samples {
        let e = (s * p.count + i) as usize;
        let z: Vec4 = depth_samples.fetch_with(at, sample_with::sample_index(s as i32));
        let w: Vec4 = winner_samples.fetch_with(at, sample_with::sample_index(s as i32));
        depth[e] = z.x;
        winners[2 * e] = draw_of(w.x);
        winners[2 * e + 1] = draw_of(w.y);
        s += 1;
    }
}

/// The draw index or primitive index a winner target's channel holds (cleared to -1: no draw,
/// [`NO_DRAW`]).
#[inline]
pub fn draw_of(texel: f32) -> u32 {
    if texel < 0.0 { NO_DRAW } else { texel as u32 }
}

/// A pixel sample no draw won (the sky).
pub const NO_DRAW: u32 = u32::MAX;

/// Draws, and triangles in a draw, the winner target holds exactly (integers of a 32-bit float).
pub const MAX_DRAWS: u32 = 1 << 24;

#[cfg(feature = "compute")]
/// Step 5 for pixel `i`: classified as the deferred techniques classify it, resolved into the
/// frame; an edge pixel adds one to `edges[0]`.
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn forward_resolve(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] frame: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] edges: &mut [u32],
    #[spirv(descriptor_set = 0, binding = 3)] colour_samples: &SamplesF32,
    #[spirv(descriptor_set = 0, binding = 4)] normal_samples: &SamplesF32,
    #[spirv(descriptor_set = 0, binding = 5)] albedo_samples: &SamplesF32,
) {
    use crate::light_lists::AtomicAdd;
    use crate::msaa::{albedo_word, normal_words, sample_key};
    let i = linear_index(wg, nwg, local);
    if i >= p.count {
        return;
    }
    let g = p.grid;
    let (count, precision) = (p.count, p.normal_precision);
    let at = IVec2::new((i % g.width) as i32, (i / g.width) as i32);
    // The texels first: a closure may not hold an image (a struct of opaque types is not valid
    // SPIR-V for Vulkan).
    let mut colours = [Vec4::ZERO; crate::msaa::MAX_SAMPLES as usize];
    let mut normals = [Vec4::ZERO; crate::msaa::MAX_SAMPLES as usize];
    let mut albedo = [Vec4::ZERO; crate::msaa::MAX_SAMPLES as usize];
    let mut s = 0;
    while s < g.samples {
        colours[s as usize] = colour_samples.fetch_with(at, sample_with::sample_index(s as i32));
        normals[s as usize] = normal_samples.fetch_with(at, sample_with::sample_index(s as i32));
        albedo[s as usize] = albedo_samples.fetch_with(at, sample_with::sample_index(s as i32));
        s += 1;
    }
    let key = move |s: u32| {
        let w = normal_words(normals[s as usize], precision);
        sample_key(&g, precision, i, s, depth[(s * count + i) as usize], [w[0], w[1], w[2]], albedo_word(albedo[s as usize]))
    };
    let (word, edge) = resolve_pixel(g.near, g.samples, key, move |s| colours[s as usize]);
    frame[i as usize] = word;
    if edge {
        edges[0].fetch_add(1);
    }
}

#[cfg(test)]
#[path = "forward_msaa_tests.rs"]
mod tests;
