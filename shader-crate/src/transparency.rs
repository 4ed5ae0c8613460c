//! The resolves of the transparent pass (steps: [`crate::raster_transparent`]; algebra, order and
//! bounds: [`crate::oit`]): one invocation per pixel walks the pixel's list, composites it over
//! the opaque colour already in the frame (`oit::resolve` of the frame's variant), and clears
//! the head for the next frame. The weighted blended variant's resolve composites its two
//! targets instead ([`oit_resolve_weighted`]).
//!
//! Clearing the heads here costs one store to a word the resolve has just read (pixels with no
//! list skip it); a fill at the frame's start would be one more pass writing 4 B per pixel, and
//! a barrier. The heads are filled with `OIT_END` once, when they are allocated.
// Entry points take one parameter per built-in and binding.
#![allow(clippy::too_many_arguments)]

use crate::layout::*;
use crate::light_lists::AtomicAdd;
use crate::lighting;
use crate::oit;
use crate::shading::linear_index;
use spirv_std::glam::{UVec3, Vec4};
use spirv_std::spirv;

/// A resolved pixel: its new frame word and what the resolve saw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResolvedPixel {
    /// RGBA8 sRGB word of the composite.
    pub word: u32,
    pub layers: u32,
    pub fallback: bool,
}

/// The composite of the list at `head` over the opaque frame word `opaque` (sRGB8, decoded to
/// linear for the blend and encoded again).
#[inline]
pub fn resolve_pixel<F: Fn(u32) -> OitNode>(p: &OitParams, head: u32, opaque: u32, node_at: &F) -> ResolvedPixel {
    let r = oit::resolve(p, head, lighting::decode_srgb8(opaque), node_at);
    ResolvedPixel { word: lighting::encode_srgb8(r.rgb), layers: r.layers, fallback: r.fallback }
}

/// `max` on a storage-buffer word (device scope, relaxed); plain off the GPU.
#[inline]
fn atomic_max(word: &mut u32, v: u32) {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_u_max::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v);
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        *word = (*word).max(v);
    }
}

/// Resolve of one pixel (module docs): bindings heads, nodes, frame, the transparent pass's
/// counters (`OIT_COUNTER_*`: the most layers of a pixel, the exact resolve's fallbacks).
#[spirv(compute(threads(256)))]
pub fn oit_resolve(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &OitParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] heads: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] nodes: &[OitNode],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] frame: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] counters: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.width * p.height {
        return;
    }
    let head = heads[i as usize];
    if head == OIT_END {
        return;
    }
    heads[i as usize] = OIT_END;
    let r = resolve_pixel(p, head, frame[i as usize], &move |n: u32| nodes[n as usize]);
    frame[i as usize] = r.word;
    atomic_max(&mut counters[OIT_COUNTER_MAX_LAYERS as usize], r.layers);
    if r.fallback {
        counters[OIT_COUNTER_FALLBACKS as usize].fetch_add(1);
    }
}

/// The weighted blended composite of a pixel over the opaque frame word (`oit::weighted_resolve`):
/// `accum` and `revealage` as the weighted pass's targets hold them (a pixel no fragment reached:
/// 0 and 1, which gives the opaque word back).
#[inline]
pub fn resolve_weighted_pixel(accum: Vec4, revealage: f32, opaque: u32) -> u32 {
    lighting::encode_srgb8(oit::weighted_resolve(accum, revealage, lighting::decode_srgb8(opaque)))
}

/// Resolve of the weighted blended variant: bindings accumulation (4 floats per pixel),
/// revealage (1 per pixel), frame.
#[spirv(compute(threads(256)))]
pub fn oit_resolve_weighted(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &OitParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] accum: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] revealage: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] frame: &mut [u32],
) {
    let i = linear_index(wg, nwg, local);
    if i >= p.width * p.height {
        return;
    }
    let j = 4 * i as usize;
    let a = Vec4::new(accum[j], accum[j + 1], accum[j + 2], accum[j + 3]);
    frame[i as usize] = resolve_weighted_pixel(a, revealage[i as usize], frame[i as usize]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oit::{insert_node, premultiplied_rgba16};
    use glam::Vec3;

    /// A list built by the fragment shader's steps resolves over the decoded opaque colour and
    /// encodes back; an empty list gives the opaque word back unchanged.
    #[test]
    fn a_resolved_pixel_is_the_list_over_the_opaque_word() {
        let p = OitParams { capacity: 4, width: 1, height: 1, variant: OIT_EXACT, k: 4, near: 0.1, _pad: [0; 2] };
        let opaque = lighting::encode_srgb8(Vec3::new(0.2, 0.5, 0.9));
        let none = resolve_pixel(&p, OIT_END, opaque, &|_| unreachable!());
        assert_eq!((none.word, none.layers), (opaque, 0));
        let mut nodes = Vec::new();
        let mut head = OIT_END;
        for (i, (rgb, a, z)) in [(Vec3::X, 0.5, 0.3), (Vec3::Y, 0.25, 0.6)].into_iter().enumerate() {
            let n = insert_node(head, i as u32, p.capacity, rgb, a, z, i as u32);
            nodes.push(n.node);
            head = i as u32;
        }
        let r = resolve_pixel(&p, head, opaque, &|n| nodes[n as usize]);
        // Far (red, α ½) then near (green, α ¼) over the opaque colour.
        let b = lighting::decode_srgb8(opaque);
        let red = oit::over(premultiplied_rgba16(Vec3::X, 0.5), b);
        let want = oit::over(premultiplied_rgba16(Vec3::Y, 0.25), red);
        assert_eq!((r.word, r.layers, r.fallback), (lighting::encode_srgb8(want), 2, false));
    }

    #[test]
    fn a_weighted_pixel_no_fragment_reached_keeps_its_opaque_word() {
        for word in [0xff00_0000, 0xff12_3456, 0xffff_ffff, lighting::encode_srgb8(Vec3::new(0.2, 0.5, 0.9))] {
            assert_eq!(resolve_weighted_pixel(Vec4::ZERO, 1.0, word), word);
        }
        let f = oit::weighted_fragment(Vec3::X, 0.5, 3.0);
        let got = resolve_weighted_pixel(f.accum, 1.0 - f.alpha, 0xff00_0000);
        assert_eq!(got, lighting::encode_srgb8(oit::weighted_resolve(f.accum, 1.0 - f.alpha, Vec3::ZERO)));
        assert_ne!(got, 0xff00_0000, "one red layer over black shows");
    }
}
