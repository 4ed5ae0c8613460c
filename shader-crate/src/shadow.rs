//! Cube shadow maps: the shadows of the lights that cast them (`cast_shadows`), one map of six
//! `res × res` faces per shadow-casting light, in the frame's view space.
//!
//! Steps (host: `render/shadow_maps.rs`):
//! 1. **Clear** every texel to [`NO_OCCLUDER`].
//! 2. **Raster** (`shadow_receivers`: the faces the frame's pixels look up; `shadow_cull`:
//!    batches of the scene's opaque triangles culled per face on the GPU; then
//!    `shadow_raster`'s compute kernel, or one indirect draw with fragments in
//!    [`shadow_distance_fs`]): each batch written into a face `f` of a caster ([`face_clip`]) of
//!    `res × res` texels, each covered texel keeping the distance from the light to the surface
//!    along the texel centre's ray with an atomic minimum on the float's bits (non-negative
//!    floats order as their bit patterns). No depth target is tested: the minimum is the depth
//!    test, and one dispatch or draw fills every face of every caster.
//! 3. **Lookup** ([`CubeShadows::visibility`], in the shading loop of every technique that
//!    renders shadows, `shading::shade_lights_with`): the receiver's face and texel, its distance
//!    compared with the stored one, one texel or the bilinear weights of four
//!    ([`SHADOW_FILTER_BILINEAR`], percentage-closer filtering).
//!
//! **Faces.** Face `f` looks along axis `f / 2` of view space, towards `+` for even `f` and `−`
//! for odd ([`face_axes`]); a direction `d` from the light belongs to the face of its largest
//! component ([`cube_face`]), where `u = d·right / d·forward`, `v = d·up / d·forward` lie in
//! [−1, 1], and texel `(x, y) = ⌊((u, v) + 1) / 2 · res⌋`: the viewport transform of the clip
//! position `(d·right, d·up, ·, d·forward)` ([`face_clip`]), so the raster and the lookup agree
//! on every texel.
//!
//! **No near plane.** The clip depth is `w / 2`, inside `[0, w]` wherever `w ≥ 0`, so no caster
//! is clipped for being close to the light: only the face's pyramid `|x|, |y| ≤ w` bounds what
//! is drawn (its apex at the light), and a caster at any distance short of the light itself
//! casts its shadow. Distances are stored from the interpolated view-space offset, not from clip
//! depth, so nothing is lost to depth precision; fragments beyond the light's radius store
//! nothing (no receiver there is lit).
//!
//! **Bias rule.** A texel spans `w = 2 · dist / res` at distance `dist` (the face centre's texel;
//! corner texels are smaller). The receiver moves [`NORMAL_OFFSET_TEXELS`]` · w` along its normal
//! (turned towards the light) before the lookup, and counts as lit where its distance is at most
//! the stored one plus [`DEPTH_BIAS_TEXELS`]` · w`: a surface does not shadow itself at any angle
//! up to where its `n·l` falls below about `1 / (1 + NORMAL_OFFSET_TEXELS)` of grazing
//! (`shadow_tests.rs`), and a contact shadow starts at most about `NORMAL_OFFSET_TEXELS + 1`
//! texels late.
//!
//! **Memory:** `FACES · res² · 4` B per shadow-casting light (24 KiB at res 32, 1.5 MiB at 256),
//! [`SHADOW_HEADER_WORDS`] + 1 word per light (the slots), 16 B per caster (its record).
use crate::layout::PointLight;
use glam::{Vec3, Vec4};
#[cfg(feature = "graphics")]
use spirv_std::spirv;

/// Faces of a cube map.
pub const FACES: u32 = 6;
/// A texel no surface reached (the largest finite float's bits).
pub const NO_OCCLUDER: u32 = 0x7f7f_ffff;
/// The slot of a light that casts no shadow.
pub const NO_SHADOW: u32 = u32::MAX;
/// Words before the per-light slots in the slot buffer: `[res, filter, 0, 0]`.
pub const SHADOW_HEADER_WORDS: u32 = 4;
/// One texel per lookup (the nearest).
pub const SHADOW_FILTER_NEAREST: u32 = 0;
/// Four texels per lookup, weighted bilinearly (2 × 2 percentage-closer filtering).
pub const SHADOW_FILTER_BILINEAR: u32 = 1;
/// Words of a caster record: view-space position and radius.
pub const CASTER_WORDS: u32 = 4;
/// The receiver's offset along its normal, in texels at its distance (module docs).
pub const NORMAL_OFFSET_TEXELS: f32 = 1.5;
/// Distance tolerance of the comparison, in texels at the receiver's distance.
pub const DEPTH_BIAS_TEXELS: f32 = 1.0;

/// `(right, up, forward)` of face `f` (module docs): forward along axis `f / 2`, signed by `f`'s
/// parity; right and up the two following axes.
#[inline]
pub fn face_axes(f: u32) -> (Vec3, Vec3, Vec3) {
    let sign = if f & 1 == 0 { 1.0 } else { -1.0 };
    match f / 2 {
        0 => (Vec3::Y, Vec3::Z, Vec3::new(sign, 0.0, 0.0)),
        1 => (Vec3::Z, Vec3::X, Vec3::new(0.0, sign, 0.0)),
        _ => (Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, sign)),
    }
}

/// The face a direction `d` from the light belongs to: its largest component's axis and sign
/// (ties to the lower axis).
#[inline]
pub fn cube_face(d: Vec3) -> u32 {
    let a = d.abs();
    let (axis, c) = if a.x >= a.y && a.x >= a.z {
        (0, d.x)
    } else if a.y >= a.z {
        (1, d.y)
    } else {
        (2, d.z)
    };
    2 * axis + u32::from(c < 0.0)
}

/// Clip position of offset `d` (surface point − light) on face `f`: `(d·right, d·up, w / 2, w)`
/// with `w = d·forward` (module docs: no near plane).
#[inline]
pub fn face_clip(d: Vec3, f: u32) -> Vec4 {
    let (right, up, forward) = face_axes(f);
    let w = d.dot(forward);
    Vec4::new(d.dot(right), d.dot(up), 0.5 * w, w)
}

/// Continuous texel coordinates (`0..res` across the face) of direction `d` on face `f`.
#[inline]
pub fn face_texel(d: Vec3, f: u32, res: u32) -> (f32, f32) {
    let (right, up, forward) = face_axes(f);
    let z = d.dot(forward);
    let half = 0.5 * res as f32;
    ((d.dot(right) / z + 1.0) * half, (d.dot(up) / z + 1.0) * half)
}

/// Where the shading reads shadows from.
pub trait Shadowing {
    /// The share of light `l` (at `light`, view space) that reaches `pos` with unit normal
    /// `normal`: 1 where nothing lies between, 0 in shadow.
    fn visibility(&self, l: u32, light: Vec3, pos: Vec3, normal: Vec3) -> f32;
}

/// Every light reaches every point (the kernels of scenes without shadow-casting lights).
pub struct NoShadows;

impl Shadowing for NoShadows {
    #[inline]
    fn visibility(&self, _l: u32, _light: Vec3, _pos: Vec3, _normal: Vec3) -> f32 {
        1.0
    }
}

/// The frame's cube shadow maps: `slots` = `[res, filter, 0, 0]` then each light's slot (or
/// [`NO_SHADOW`]); `maps` = slot-major, face-major, row-major distances (`f32` bits).
pub struct CubeShadows<'a> {
    pub slots: &'a [u32],
    pub maps: &'a [u32],
}

impl Shadowing for CubeShadows<'_> {
    #[inline]
    fn visibility(&self, l: u32, light: Vec3, pos: Vec3, normal: Vec3) -> f32 {
        let slot = self.slots[(SHADOW_HEADER_WORDS + l) as usize];
        if slot == NO_SHADOW {
            return 1.0;
        }
        cube_visibility(self.maps, slot, self.slots[0], self.slots[1], light, pos, normal)
    }
}

/// [`CubeShadows::visibility`] of map `slot` (`res`, `filter`), the module docs' bias rule.
#[inline]
pub fn cube_visibility(maps: &[u32], slot: u32, res: u32, filter: u32, light: Vec3, pos: Vec3, normal: Vec3) -> f32 {
    let to_light = light - pos;
    let texel = 2.0 * to_light.length() / res as f32;
    let n = if normal.dot(to_light) < 0.0 { -normal } else { normal };
    let d = pos + n * (NORMAL_OFFSET_TEXELS * texel) - light;
    let reach = d.length() - DEPTH_BIAS_TEXELS * texel;
    let f = cube_face(d);
    let (x, y) = face_texel(d, f, res);
    let base = (slot * FACES + f) * res * res;
    if filter == SHADOW_FILTER_BILINEAR {
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (ix, iy) = (floor(fx), floor(fy));
        let (wx, wy) = (fx - ix as f32, fy - iy as f32);
        let top = texel_lit(maps, base, res, ix, iy, reach) * (1.0 - wx) + texel_lit(maps, base, res, ix + 1, iy, reach) * wx;
        let bottom = texel_lit(maps, base, res, ix, iy + 1, reach) * (1.0 - wx) + texel_lit(maps, base, res, ix + 1, iy + 1, reach) * wx;
        top * (1.0 - wy) + bottom * wy
    } else {
        texel_lit(maps, base, res, floor(x), floor(y), reach)
    }
}

/// 1 where texel `(tx, ty)` (clamped to the face) of the face map at `base` stores a distance of
/// at least `reach`, else 0. (A function, not a closure: rust-gpu cannot legalise a closure that
/// captures locals by reference.)
#[inline]
fn texel_lit(maps: &[u32], base: u32, res: u32, tx: i32, ty: i32, reach: f32) -> f32 {
    let last = res as i32 - 1;
    let (cx, cy) = (clamp(tx, last), clamp(ty, last));
    if reach <= f32::from_bits(maps[(base + cy * res + cx) as usize]) {
        1.0
    } else {
        0.0
    }
}

/// `⌊x⌋` as an integer (x well inside `i32`).
#[inline]
fn floor(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t - 1
    } else {
        t
    }
}

/// `t` clamped to `0..=last`, as an index.
#[inline]
fn clamp(t: i32, last: i32) -> u32 {
    (if t < 0 { 0 } else if t > last { last } else { t }) as u32
}

/// Record of a caster for the raster pass: view-space position and radius.
#[inline]
pub fn caster_record(l: &PointLight) -> [f32; 4] {
    [l.position[0], l.position[1], l.position[2], l.radius]
}

/// Push constants of the raster pass's fragment stage.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ShadowParams {
    /// Texels per face side.
    pub res: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ShadowParams>() == 16);

/// Step 2, fragment stage: keeps the nearest distance of face map `map` at texel `⌊frag.xy⌋`
/// (within the caster's radius).
#[cfg(feature = "graphics")]
#[spirv(fragment)]
pub fn shadow_distance_fs(
    #[spirv(frag_coord)] frag: Vec4,
    in_offset: Vec3,
    #[spirv(flat)] in_map: u32,
    #[spirv(flat)] in_radius: f32,
    #[spirv(push_constant)] p: &ShadowParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] maps: &mut [u32],
) {
    let distance = in_offset.length();
    if distance <= in_radius {
        let texel = (in_map * p.res + frag.y as u32) * p.res + frag.x as u32;
        crate::fragment_atomics::atomic_min(&mut maps[texel as usize], distance.to_bits());
    }
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
mod tests;
