//! Cube shadow maps: the shadows of the lights that cast them (`cast_shadows`), six faces per
//! shadow-casting light in the frame's view space, each face at the resolution its receivers
//! need in one shared atlas (`shadow_atlas`: Olsson et al.'s virtual cube shadow maps, with a
//! whole face as the unit of allocation).
//!
//! Steps (host: `render/shadow_maps.rs`):
//! 1. **Clear** every texel of the atlas to [`NO_OCCLUDER`].
//! 2. **Faces and atlas** (`shadow_receivers`: the faces the frame's pixels look up and the
//!    resolution each asks; `shadow_atlas`: each such face's side and first texel in the face
//!    table, [`face_entry`]).
//! 3. **Raster** (`shadow_cull`: batches of the scene's opaque triangles culled per face on the
//!    GPU; then `shadow_raster`'s compute kernel, or one indirect draw with fragments in
//!    [`shadow_distance_fs`]): each batch written into a face `f` of a caster ([`face_clip`]) of
//!    `res × res` texels, each covered texel keeping the distance from the light to the surface
//!    along the texel centre's ray with an atomic minimum on the float's bits (non-negative
//!    floats order as their bit patterns). No depth target is tested: the minimum is the depth
//!    test, and one dispatch or draw fills every face of every caster.
//! 4. **Lookup** ([`CubeShadows::visibility`], in the shading loop of every technique that
//!    renders shadows, `shading::shade_lights_with`): the receiver's face and texel, its distance
//!    compared with the stored one, one texel or the bilinear weights of four
//!    ([`SHADOW_FILTER_BILINEAR`], percentage-closer filtering).
//!
//! **Faces.** Face `f` looks along axis `f / 2` of the light's cube, towards `+` for even `f` and
//! `−` for odd ([`face_axes`]). A point light's cube is laid along view space's axes, a spot
//! light's is turned to its cone ([`CubeFrame`]: a cone of at most 42° centred on one face, a
//! wider one on the corner of three), and every offset from the light enters the face
//! functions in the cube's axes ([`CubeFrame::local`]). A direction `d` from the light belongs
//! to the face of its largest
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
//! **Memory:** the atlas (4 B per texel; `res² · 4` B per face in it: 4 KiB at 32, 256 KiB at
//! 256), [`SHADOW_HEADER_WORDS`] + 1 word per light (the slots), [`FACE_WORDS`] words per caster
//! face (the face table), 32 B per caster (its record).
use crate::layout::PointLight;
use glam::{Vec3, Vec4};
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;
#[cfg(feature = "graphics")]
use spirv_std::spirv;

/// Faces of a cube map.
pub const FACES: u32 = 6;
/// A texel no surface reached (the largest finite float's bits).
pub const NO_OCCLUDER: u32 = 0x7f7f_ffff;
/// The slot of a light that casts no shadow.
pub const NO_SHADOW: u32 = u32::MAX;
/// Words before the per-light slots in the slot buffer: `[largest res, filter, table, 0]`
/// (`table`: the word where the face table starts, after the slots; `shadow_atlas`).
pub const SHADOW_HEADER_WORDS: u32 = 4;
/// Header word holding the first word of the face table.
pub const HEADER_TABLE: usize = 2;
/// Words of a face's entry in the face table (`shadow_atlas`): its first texel in the atlas and
/// its texels per side (0: no pixel of the frame looks it up, so it holds no texel).
pub const FACE_WORDS: u32 = 2;
/// One texel per lookup (the nearest).
pub const SHADOW_FILTER_NEAREST: u32 = 0;
/// Four texels per lookup, weighted bilinearly (2 × 2 percentage-closer filtering).
pub const SHADOW_FILTER_BILINEAR: u32 = 1;
/// Words of a caster record: view-space position and radius, then a spot light's cone: its
/// axis (view space, unit) and the cosine of its outer half-angle ([`NO_CONE`] for a point
/// light).
pub const CASTER_WORDS: u32 = 8;
/// The cone word of a point light's record (below every cosine).
pub const NO_CONE: f32 = -2.0;
/// Margin in radians of the cone tests on spot lights' shadows (`shadow_receivers`,
/// `shadow_cull`), for rounding.
pub const CONE_MARGIN: f32 = 1e-3;

/// The receiver's offset along its normal, in texels at its distance (module docs).
pub const NORMAL_OFFSET_TEXELS: f32 = 1.5;
/// Distance tolerance of the comparison, in texels at the receiver's distance.
pub const DEPTH_BIAS_TEXELS: f32 = 1.0;

/// The outer half-angle of a caster record's cone word (`acos(cos_outer)`), or `None` for a point
/// light ([`NO_CONE`], or NaN): the shadow passes take it once per caster and widen it by the
/// angle their lookups reach ([`sphere_meets_widened_cone`], `shadow_receivers::spot_faces`).
#[inline]
pub fn cone_angle(cos_outer: f32) -> Option<f32> {
    if cos_outer >= -1.0 {
        Some(if cos_outer > 1.0 { 0.0 } else { cos_outer.acos() })
    } else {
        None
    }
}

/// Whether the sphere at offset `d` from a spot light, of radius `r`, may meet the light's cone
/// of unit `axis` and half-angle `angle` (radians; [`cone_angle`] widened by the caller) plus
/// [`CONE_MARGIN`] and cut at `range`: the one sphere–cone test of the shadow passes, the
/// spot lights' culling test (`spot::cone_meets_sphere`: the sphere's distance to the cone's
/// surface, `|d|·sin(a − angle)` for a centre at angle `a` from the axis, is its radius at
/// most; the same as `a ≤ angle + asin(r / |d|)`). A cone of half-angle `π` or more is every
/// direction: always.
#[inline]
pub fn sphere_meets_widened_cone(d: Vec3, r: f32, axis: Vec3, angle: f32, range: f32) -> bool {
    let angle = angle + CONE_MARGIN;
    if !(angle < core::f32::consts::PI) {
        return true;
    }
    let cone = crate::spot::Cone { direction: axis, cos_inner: 1.0, cos_outer: angle.cos(), sin_outer: angle.sin() };
    crate::spot::cone_meets_sphere(Vec3::ZERO, &cone, range, d, r)
}

/// Cosine of the widest outer half-angle (42°) whose cone a caster's [`CubeFrame`] centres on
/// one face: the face's pyramid holds every direction within 45° of its axis, and the 3° left
/// cover the lookup's offset angle, `asin(3 / side)`, on faces of 64² texels and more
/// (`shadow_receivers::spot_faces`).
pub const FACE_CONE_COS: f32 = 0.743_144_8;
/// `1/√2`, `1/√3`, `1/√6`: the rotation taking `+z` to the cube's corner `(1, 1, 1)/√3`.
const INV_SQRT2: f32 = core::f32::consts::FRAC_1_SQRT_2;
const INV_SQRT3: f32 = 0.577_350_26;
const INV_SQRT6: f32 = 0.408_248_3;

/// The axes a caster's cube is laid along (rows: the cube's x, y, z in view space). A point
/// light's cube uses view space's own axes; a spot light's is turned to its cone: a cone of at
/// most 42° ([`FACE_CONE_COS`]) about the centre of face 4 (`+z`), so one face holds it; a wider
/// one about the corner `(1, 1, 1)/√3` of faces 0, 2 and 4, which hold every direction within
/// 70.5° of it (the nearest direction of another face, `(1, 1, −1)/√3`, lies `acos(1/3)` away).
/// The raster, the cull, the receivers' faces and the lookup all see offsets through
/// [`CubeFrame::local`], built from the same record bits (`caster_record`, the cone record of
/// the light buffer: both from the one view-space axis and `cos(outer)`).
///
/// ```text
///  face-centred (outer ≤ 42°)      corner-centred (42° < outer)
///     cube z = axis                 cube (1,1,1)/√3 = axis
///       ┌─────┐                          ╱╲
///       │  ●  │  face 4               ╱ ● ╲   faces 0, 2, 4 meet at ●
///       └─────┘                        ╲  ╱
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeFrame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl CubeFrame {
    /// View space's own axes (point lights).
    pub const VIEW: CubeFrame = CubeFrame { x: Vec3::X, y: Vec3::Y, z: Vec3::Z };

    /// The frame of a light with cone `axis` (unit, view space) and outer cosine `cos_outer`:
    /// [`Self::VIEW`] where `cos_outer` is below −1 (a point light: [`NO_CONE`], the light
    /// buffer's point marker). The basis about the axis is Duff et al.'s ("Building an
    /// orthonormal basis, revisited", JCGT 2017): `(t, s, axis)` right-handed, continuous but
    /// for the sign of `axis.z`.
    #[inline]
    pub fn of_cone(axis: Vec3, cos_outer: f32) -> Self {
        if !(cos_outer >= -1.0) {
            return Self::VIEW;
        }
        let sign = if axis.z >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (sign + axis.z);
        let b = axis.x * axis.y * a;
        let t = Vec3::new(1.0 + sign * axis.x * axis.x * a, sign * b, -sign * axis.x);
        let s = Vec3::new(b, sign + axis.y * axis.y * a, -axis.y);
        if cos_outer >= FACE_CONE_COS {
            return CubeFrame { x: t, y: s, z: axis };
        }
        // Rows of C · (t, s, axis), C's columns (1, −1, 0)/√2, (1, 1, −2)/√6, (1, 1, 1)/√3.
        let (t2, s6, a3) = (t * INV_SQRT2, s * INV_SQRT6, axis * INV_SQRT3);
        CubeFrame { x: t2 + s6 + a3, y: s6 + a3 - t2, z: a3 - 2.0 * s6 }
    }

    /// The frame of caster `c`'s record ([`caster_record`]).
    #[inline]
    pub fn of_caster(casters: &[f32], c: u32) -> Self {
        let k = (c * CASTER_WORDS) as usize;
        Self::of_cone(Vec3::new(casters[k + 4], casters[k + 5], casters[k + 6]), casters[k + 7])
    }

    /// View-space offset `d` in the cube's axes.
    #[inline]
    pub fn local(&self, d: Vec3) -> Vec3 {
        Vec3::new(self.x.dot(d), self.y.dot(d), self.z.dot(d))
    }
}

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
    /// The share of light `l` (at `light`, view space; its cone's unit `axis` and outer cosine
    /// `cos_outer`, [`NO_CONE`] for a point light, lay out its cube: [`CubeFrame::of_cone`])
    /// that reaches `pos` with unit normal `normal`: 1 where nothing lies between, 0 in shadow.
    fn visibility(&self, l: u32, light: Vec3, axis: Vec3, cos_outer: f32, pos: Vec3, normal: Vec3) -> f32;
}

/// Every light reaches every point (the kernels of scenes without shadow-casting lights).
pub struct NoShadows;

impl Shadowing for NoShadows {
    #[inline]
    fn visibility(&self, _l: u32, _light: Vec3, _axis: Vec3, _cos_outer: f32, _pos: Vec3, _normal: Vec3) -> f32 {
        1.0
    }
}

/// The frame's cube shadow maps: `slots` = `[largest res, filter, table, 0]`, each light's slot
/// (or [`NO_SHADOW`]), then the face table ([`face_entry`]); `maps` = the atlas, each face
/// row-major at its entry's first texel (`f32` bits of distances).
pub struct CubeShadows<'a> {
    pub slots: &'a [u32],
    pub maps: &'a [u32],
}

impl Shadowing for CubeShadows<'_> {
    #[inline]
    fn visibility(&self, l: u32, light: Vec3, axis: Vec3, cos_outer: f32, pos: Vec3, normal: Vec3) -> f32 {
        let slot = self.slots[(SHADOW_HEADER_WORDS + l) as usize];
        if slot == NO_SHADOW {
            return 1.0;
        }
        // The frame only for a light that casts shadows (most lights of a list do not).
        cube_visibility(self.maps, self.slots, slot, self.slots[1], light, &CubeFrame::of_cone(axis, cos_outer), pos, normal)
    }
}

/// `(first texel, texels per side)` of map `map` (`slot · 6 + face`) in the face table of `slots`
/// (side 0: the face holds no texel).
#[inline]
pub fn face_entry(slots: &[u32], map: u32) -> (u32, u32) {
    let w = (slots[HEADER_TABLE] + map * FACE_WORDS) as usize;
    (slots[w], slots[w + 1])
}

/// [`CubeShadows::visibility`] of the map in slot `slot` with `filter`, the module docs' bias
/// rule: the texel size of the offset is that of the face the receiver lies in, the lookup that
/// of the face the offset point lies in. Where that face holds no texel (the offset crossed into
/// a face no receiver asked for, which only a short atlas allows: `shadow_receivers`), the
/// receiver's own face is looked up at its edge instead; where the receiver's own face holds none
/// (no lit receiver lies there), the light passes.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn cube_visibility(maps: &[u32], slots: &[u32], slot: u32, filter: u32, light: Vec3, frame: &CubeFrame, pos: Vec3, normal: Vec3) -> f32 {
    let to_light = light - pos;
    let at = cube_face(frame.local(-to_light));
    let (base_at, res_at) = face_entry(slots, slot * FACES + at);
    if res_at == 0 {
        return 1.0;
    }
    let texel = 2.0 * to_light.length() / res_at as f32;
    let n = if normal.dot(to_light) < 0.0 { -normal } else { normal };
    let d = pos + n * (NORMAL_OFFSET_TEXELS * texel) - light;
    let reach = d.length() - DEPTH_BIAS_TEXELS * texel;
    let d = frame.local(d);
    let f = cube_face(d);
    let (base, res) = face_entry(slots, slot * FACES + f);
    if res == 0 {
        return face_visibility(maps, base_at, res_at, filter, d, at, reach);
    }
    face_visibility(maps, base, res, filter, d, f, reach)
}

/// The lookup of direction `d` (in the cube's axes, [`CubeFrame::local`]) on face `f` (`res × res` texels from texel `base` of `maps`): lit
/// where the stored distance is at least `reach`, one texel or four bilinearly weighted.
#[inline]
pub fn face_visibility(maps: &[u32], base: u32, res: u32, filter: u32, d: Vec3, f: u32, reach: f32) -> f32 {
    let (x, y) = face_texel(d, f, res);
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

/// Clip position `clip` of a face of `res` texels per side moved into the `res × res` corner of a
/// render area of `area` texels per side (`res ≤ area`): the viewport maps the face's `[−1, 1]`
/// onto texels `0..res`, so the fragment at texel `(x, y)` of the area is texel `(x, y)` of the
/// face. The area clips the face's left and top sides; fragments past its right and bottom sides
/// lie outside the face's pyramid and store nothing ([`shadow_distance_fs`]).
#[inline]
pub fn face_area_clip(clip: Vec4, res: u32, area: u32) -> Vec4 {
    let k = res as f32 / area as f32;
    Vec4::new(clip.x * k + (k - 1.0) * clip.w, clip.y * k + (k - 1.0) * clip.w, clip.z, clip.w)
}

/// Record of a caster: view-space position and radius, and `cone` — a spot light's view-space
/// unit axis and the cosine of its outer half-angle, `None` for a point light.
#[inline]
pub fn caster_record(l: &PointLight, cone: Option<(Vec3, f32)>) -> [f32; CASTER_WORDS as usize] {
    let (axis, cos_outer) = match cone {
        Some(c) => c,
        None => (Vec3::ZERO, NO_CONE),
    };
    [l.position[0], l.position[1], l.position[2], l.radius, axis.x, axis.y, axis.z, cos_outer]
}

/// Push constants of the raster pass: the render area's side (the largest face side; each face
/// draws into the `res × res` corner of it, `shadow_cull::batch_vertex`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ShadowParams {
    /// Texels per side of the render area.
    pub res: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ShadowParams>() == 16);

/// Step 2, fragment stage: keeps the nearest distance at texel `⌊frag.xy⌋` of the face whose
/// `res × res` texels start at `base` (within the caster's radius; fragments past the face's
/// corner of the render area lie outside its pyramid and store nothing).
#[cfg(feature = "graphics")]
#[spirv(fragment)]
pub fn shadow_distance_fs(
    #[spirv(frag_coord)] frag: Vec4,
    in_offset: Vec3,
    #[spirv(flat)] in_base: u32,
    #[spirv(flat)] in_res: u32,
    #[spirv(flat)] in_radius: f32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] maps: &mut [u32],
) {
    let distance = in_offset.length();
    let (x, y) = (frag.x as u32, frag.y as u32);
    if distance <= in_radius && x < in_res && y < in_res {
        crate::fragment_atomics::atomic_min(&mut maps[(in_base + y * in_res + x) as usize], distance.to_bits());
    }
}

#[cfg(test)]
#[path = "shadow_tests.rs"]
pub(crate) mod tests;
