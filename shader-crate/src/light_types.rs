//! Light types: point, spot and directional lights as the shading and culling kernels see them.
//!
//! # Layout: one light buffer, sections only where the scene calls for them
//!
//! Every punctual light (point or spot) is a [`PointLight`] (32 B: apex, range, colour,
//! intensity): the record every culling test and every light list knows. The light buffer holds
//! up to three sections, each 32-byte records read through the same `&[PointLight]` binding:
//!
//! ```text
//!  records 0 .. n          PointLight of every punctual light            (always)
//!  records n .. 2n         cone of light l at n + l (spot_record)        (EFFECT_SPOT only)
//!  records b .. b + k      directional lights (directional_record),      (EFFECT_DIRECTIONAL only)
//!                          b = n, or 2n with spots; k ≤ MAX_DIRECTIONAL_LIGHTS
//! ```
//!
//! Why one buffer and not a new binding: every kernel that shades or culls already binds the
//! light buffer, so the cone and directional records reach each of them (deferred, clustered,
//! tiled, Forward+, the transparent pass) without a descriptor change, and a scene without spot
//! or directional lights uploads, binds and reads nothing more than before. The section a kernel
//! reads is gated by an `EFFECT_*` bit, so a scene without spots runs no cone code and a scene
//! without directional lights no directional loop; `FrameParams` is unchanged (the directional
//! count rides in the effect word's bits [`DIRECTIONAL_COUNT_SHIFT`]`..`).
//!
//! # Specialised pipelines
//!
//! The light-type bits ([`LIGHT_TYPE_MASK`]: spot, directional and the directional count) do not
//! come from the push constants: every entry that shades or culls punctual lights takes them as
//! the specialization constant [`LIGHT_TYPES_SPEC_ID`] and overrides the frame's bits with it
//! ([`specialise`]). The host creates one pipeline per light-type mix a scene uses
//! ([`light_type_variant`]: at most [`LIGHT_TYPE_VARIANTS`]), from the module with the constant
//! frozen to the mix's bits (`host/src/vk/light_typed.rs`), so the driver compiles each with the
//! bits as constants: a scene without spots has no cone test and no cone falloff in its machine
//! code, a scene without directional lights no directional records, and one with two directional
//! lights exactly two. This is the specular variants' "simulate only what the scene calls for"
//! without an entry point per combination (that would be 10 × the shading entries of the module).
//!
//! A cone record ([`spot_record`]) is the view-space unit axis (where the light points), then
//! `cos θ_inner`, `cos θ_outer`, `sin θ_outer` in the record's `radius`, `colour[0]`, `colour[1]`.
//! In a scene that mixes points and spots a point light's cone record is the marker
//! [`point_record`] (`cos θ_outer = cos θ_inner = −2`): [`crate::spot::cone_falloff`] gives
//! exactly 1 for it (the shading multiplies by 1, bit-exact), and the culling tests skip lights
//! whose `cos θ_outer < −½` ([`is_point`]).
//!
//! A directional record ([`directional_record`]) is the view-space unit direction *towards* the
//! light, its intensity, its colour: irradiance `colour · intensity · n·l` everywhere, no range,
//! so no culling: every shading pass adds them once per pixel ([`crate::shading::shade_directional_lights`]).
use crate::compact_light::EFFECT_COMPACT_LIGHTS;
use crate::layout::{FrameParams, PointLight};
use crate::spot::{cone_meets_sphere, Cone};
use glam::Vec3;

/// The scene has spot lights: the light buffer holds the cone section; shading multiplies by the
/// cone falloff and the culling kernels test cones.
pub const EFFECT_SPOT: u32 = 64;
/// The scene has directional lights: the count is in the effect word's bits
/// [`DIRECTIONAL_COUNT_SHIFT`]`..` (at most [`MAX_DIRECTIONAL_LIGHTS`]).
pub const EFFECT_DIRECTIONAL: u32 = 128;
/// Accuracy study: spot lights are culled by their range sphere only (no cone test): the image
/// is the same, the lists longer.
pub const EFFECT_CULL_SPHERE_ONLY: u32 = 2048;
/// The scene has shadow-casting lights (`crate::shadow`): the shading loop multiplies each
/// light by its visibility from the frame's cube shadow maps.
pub const EFFECT_SHADOWS: u32 = 8192;
/// First bit of the directional-light count in the effect word (3 bits).
pub const DIRECTIONAL_COUNT_SHIFT: u32 = 8;
/// Most directional lights a scene may have (a small fixed loop in every shading pass).
pub const MAX_DIRECTIONAL_LIGHTS: u32 = 4;
// `shading::shade_directional_lights` is straight-line code for exactly this many.
const _: () = assert!(MAX_DIRECTIONAL_LIGHTS == 4);
/// `cos θ_outer` (and `cos θ_inner`) of a point light's cone record in a scene with spots.
pub const POINT_MARKER: f32 = -2.0;

/// Specialization-constant id of the light-type bits (module docs, "Specialised pipelines").
pub const LIGHT_TYPES_SPEC_ID: u32 = 0;
// The entries write the literal: `#[spirv(spec_constant(id = 0, default = 0))] light_types: u32`.
const _: () = assert!(LIGHT_TYPES_SPEC_ID == 0);
/// The effect bits a light-type specialization carries: [`EFFECT_SPOT`], [`EFFECT_DIRECTIONAL`]
/// and the directional count.
///
/// ```text
///  bit  6     EFFECT_SPOT
///  bit  7     EFFECT_DIRECTIONAL
///  bits 8–10  directional count (0 ..= MAX_DIRECTIONAL_LIGHTS)
///  bit  12    EFFECT_COMPACT_LIGHTS (compact_light: 16-byte point-light records)
///  bit  13    EFFECT_SHADOWS (shadow: cube shadow maps looked up per light)
/// ```
pub const LIGHT_TYPE_MASK: u32 = EFFECT_SPOT | EFFECT_DIRECTIONAL | (7 << DIRECTIONAL_COUNT_SHIFT) | EFFECT_COMPACT_LIGHTS | EFFECT_SHADOWS;
/// Distinct light-type specializations: spots or not × 0 ..= 4 directional lights × full or
/// compact records ([`crate::compact_light`]; compact records hold point lights only, so one
/// compact variant is ever created) × shadows or not.
pub const LIGHT_TYPE_VARIANTS: usize = 8 * (MAX_DIRECTIONAL_LIGHTS as usize + 1);

/// Index in `0..LIGHT_TYPE_VARIANTS` of the light-type mix of `effects` (the host's pipeline
/// cache key): `spot + 2 · directional count + 10 · compact + 20 · shadows`.
#[inline]
pub fn light_type_variant(effects: u32) -> usize {
    let compact = usize::from(effects & EFFECT_COMPACT_LIGHTS != 0);
    let shadows = usize::from(effects & EFFECT_SHADOWS != 0);
    usize::from(effects & EFFECT_SPOT != 0) + 2 * directional_count(effects) as usize + LIGHT_TYPE_VARIANTS / 4 * compact + LIGHT_TYPE_VARIANTS / 2 * shadows
}

/// Push constants that carry a [`FrameParams`]: what [`specialise`] rewrites.
pub trait CarriesFrame: Copy {
    fn frame_mut(&mut self) -> &mut FrameParams;
}

impl CarriesFrame for FrameParams {
    #[inline]
    fn frame_mut(&mut self) -> &mut FrameParams {
        self
    }
}

macro_rules! carries_frame {
    ($($t:ty),*) => {
        $(impl CarriesFrame for $t {
            #[inline]
            fn frame_mut(&mut self) -> &mut FrameParams {
                &mut self.frame
            }
        })*
    };
}
carries_frame!(crate::layout::TiledParams, crate::layout::BvhAssignParams, crate::layout::ForwardParams, crate::layout::TransparentParams);

/// `p` with its frame's light-type bits replaced by the entry's specialization constant
/// `light_types` (module docs): the first line of every light-typed entry, so the kernel never
/// reads the push constants' light-type bits.
#[inline]
pub fn specialise<P: CarriesFrame>(p: &P, light_types: u32) -> P {
    let mut q = *p;
    let f = q.frame_mut();
    f.effects = (f.effects & !LIGHT_TYPE_MASK) | (light_types & LIGHT_TYPE_MASK);
    q
}

/// The effect bits of a scene's light types: [`EFFECT_SPOT`] with spots, [`EFFECT_DIRECTIONAL`]
/// and the count with `directional` (≤ [`MAX_DIRECTIONAL_LIGHTS`]) directional lights.
#[inline]
pub const fn light_effects(spots: bool, directional: u32) -> u32 {
    let s = if spots { EFFECT_SPOT } else { 0 };
    let d = if directional > 0 { EFFECT_DIRECTIONAL | (directional << DIRECTIONAL_COUNT_SHIFT) } else { 0 };
    s | d
}

/// Directional lights of a frame (0 without [`EFFECT_DIRECTIONAL`]).
#[inline]
pub fn directional_count(effects: u32) -> u32 {
    if effects & EFFECT_DIRECTIONAL != 0 {
        let k = (effects >> DIRECTIONAL_COUNT_SHIFT) & 7;
        if k < MAX_DIRECTIONAL_LIGHTS {
            k
        } else {
            MAX_DIRECTIONAL_LIGHTS
        }
    } else {
        0
    }
}

/// Record index of the first directional light: after the punctual lights and their cones.
#[inline]
pub fn directional_base(effects: u32, num_lights: u32) -> u32 {
    if effects & EFFECT_SPOT != 0 {
        2 * num_lights
    } else {
        num_lights
    }
}

/// The cone of punctual light `l` (only with [`EFFECT_SPOT`]): record `num_lights + l`.
#[inline]
pub fn cone_of(lights: &[PointLight], num_lights: u32, l: u32) -> Cone {
    // In bounds: a spot scene's buffer holds a cone record per punctual light after them, and
    // callers pass `l < num_lights` (the binding's length is never read: `compact_light::light_at`).
    let r = crate::unchecked::at(lights, num_lights + l);
    Cone { direction: Vec3::from_array(r.position), cos_inner: r.radius, cos_outer: r.colour[0], sin_outer: r.colour[1] }
}

/// Whether a cone record is the point-light marker ([`point_record`]).
#[inline]
pub fn is_point(cone: &Cone) -> bool {
    cone.cos_outer < -0.5
}

/// Whether punctual light `light` (index `l`) may light a point of the sphere `(c, r)` by its
/// cone: with [`EFFECT_SPOT`] the cone test ([`cone_meets_sphere`]; point lights pass), else
/// `true`. The caller has tested the range sphere.
#[inline]
pub fn cone_may_meet(effects: u32, lights: &[PointLight], num_lights: u32, l: u32, light: &PointLight, c: Vec3, r: f32) -> bool {
    if effects & EFFECT_SPOT == 0 {
        return true;
    }
    let cone = cone_of(lights, num_lights, l);
    is_point(&cone) || cone_meets_sphere(Vec3::from_array(light.position), &cone, light.radius, c, r)
}

/// [`cone_may_meet`] for light index `l`, its record read only with [`EFFECT_SPOT`] and
/// without [`EFFECT_CULL_SPHERE_ONLY`] (the accuracy study's "sphere" culling of spots).
#[inline]
pub fn spot_may_meet(effects: u32, lights: &[PointLight], num_lights: u32, l: u32, c: Vec3, r: f32) -> bool {
    if effects & EFFECT_SPOT == 0 || effects & EFFECT_CULL_SPHERE_ONLY != 0 {
        return true;
    }
    // Spot scenes hold full records (`compact_light`): the record is the light.
    let light = crate::compact_light::light_at(lights, effects, num_lights, l);
    cone_may_meet(effects, lights, num_lights, l, &light, c, r)
}

/// The bounding sphere `(centre, radius)` of a box: what the cone tests take for a cluster.
#[inline]
pub fn box_sphere(min: Vec3, max: Vec3) -> (Vec3, f32) {
    ((min + max) * 0.5, (max - min).length() * 0.5)
}

/// The cone record of a spot light (module docs).
#[inline]
pub fn spot_record(cone: &Cone) -> PointLight {
    PointLight { position: cone.direction.to_array(), radius: cone.cos_inner, colour: [cone.cos_outer, cone.sin_outer, 0.0], intensity: 0.0 }
}

/// The cone record of a point light in a scene with spots: falloff 1, never culled by a cone.
#[inline]
pub fn point_record() -> PointLight {
    PointLight { position: [0.0, 0.0, -1.0], radius: POINT_MARKER, colour: [POINT_MARKER, 0.0, 0.0], intensity: 0.0 }
}

/// The record of a directional light: unit direction towards the light (view space), colour,
/// intensity.
#[inline]
pub fn directional_record(to_light: Vec3, colour: [f32; 3], intensity: f32) -> PointLight {
    PointLight { position: to_light.to_array(), radius: 0.0, colour, intensity }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spot::{cone_falloff, spot_factor};

    #[test]
    fn records_round_trip_and_the_point_marker_is_neutral() {
        let cone = Cone::new(Vec3::new(0.0, -1.0, 0.0), 0.2, 0.5);
        let lights = [PointLight { position: [1.0; 3], radius: 4.0, colour: [1.0; 3], intensity: 1.0 }; 2];
        let buf = [lights[0], lights[1], spot_record(&cone), point_record()];
        assert_eq!(cone_of(&buf, 2, 0), cone);
        let marker = cone_of(&buf, 2, 1);
        assert!(is_point(&marker) && !is_point(&cone));
        for c in [1.0, 0.3, 0.0, -0.7, -1.0] {
            assert_eq!(cone_falloff(c, &marker), 1.0, "cos θ = {c}");
        }
        assert_eq!(spot_factor(Vec3::ZERO, &marker, Vec3::new(0.0, 0.0, 5.0)), 1.0);
        let far = Vec3::new(0.0, 50.0, 0.0);
        assert!(cone_may_meet(0, &buf, 2, 0, &buf[0], far, 0.1), "without EFFECT_SPOT nothing is culled by a cone");
        assert!(!cone_may_meet(EFFECT_SPOT, &buf, 2, 0, &buf[0], far, 0.1), "behind the spot");
        assert!(cone_may_meet(EFFECT_SPOT, &buf, 2, 1, &buf[1], far, 0.1), "a point light in a scene with spots");
    }

    #[test]
    fn specialisation_replaces_the_frames_light_type_bits_only() {
        let mut p = crate::test_support::frame_params(crate::test_support::grid(64, 32, 16), 10);
        p.effects = crate::layout::EFFECT_SPECULAR | EFFECT_CULL_SPHERE_ONLY | light_effects(true, 3);
        let q = specialise(&p, light_effects(false, 1));
        assert_eq!(q.effects, crate::layout::EFFECT_SPECULAR | EFFECT_CULL_SPHERE_ONLY | light_effects(false, 1));
        assert_eq!(FrameParams { effects: p.effects, ..q }, p, "nothing else changes");
        assert_eq!(specialise(&p, 0).effects & LIGHT_TYPE_MASK, 0, "a point-light pipeline ignores the frame's bits");
        // Bits outside the mask in a specialization value do not leak into the frame.
        assert_eq!(specialise(&p, !0).effects & !LIGHT_TYPE_MASK, p.effects & !LIGHT_TYPE_MASK);
        let t = crate::layout::TiledParams { frame: p, mode: 1, _pad: [0; 3] };
        assert_eq!(specialise(&t, 0).frame.effects, p.effects & !LIGHT_TYPE_MASK);
        assert_eq!(specialise(&t, 0).mode, 1);
        // Every mix has its own variant.
        let mut seen = [false; LIGHT_TYPE_VARIANTS];
        for shadows in [0, EFFECT_SHADOWS] {
            for compact in [0, EFFECT_COMPACT_LIGHTS] {
                for spots in [false, true] {
                    for d in 0..=MAX_DIRECTIONAL_LIGHTS {
                        let v = light_type_variant(light_effects(spots, d) | compact | shadows);
                        assert!(!seen[v], "variant {v} twice");
                        seen[v] = true;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "every variant is some mix");
        assert_eq!(light_type_variant(crate::layout::EFFECT_SPECULAR), 0);
    }

    #[test]
    fn effect_bits_carry_the_directional_count() {
        assert_eq!(light_effects(false, 0), 0);
        assert_eq!(directional_count(light_effects(true, 3)), 3);
        assert_eq!(directional_count(light_effects(false, 0) | 1), 0);
        assert_eq!(directional_base(light_effects(true, 1), 10), 20);
        assert_eq!(directional_base(light_effects(false, 1), 10), 10);
        assert_eq!(light_effects(true, 0) & (crate::layout::EFFECT_SPECULAR | crate::layout::EFFECT_CULL_EXACT), 0, "no clash with the other bits");
    }
}
