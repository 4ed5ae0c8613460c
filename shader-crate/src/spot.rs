//! Spot lights: the cone's falloff and the cone tests that cull spot lights by their true shape.
//!
//! A spot light is a point light (`PointLight`: apex, range, colour) restricted to a cone about
//! its direction `d`: a point `p` at unit direction `l = (p − apex)/|p − apex|` receives the point
//! light's contribution times [`cone_falloff`] of `cos θ = l·d`, the glTF `KHR_lights_punctual`
//! rule: `saturate((cos θ − cos θ_outer) / (cos θ_inner − cos θ_outer))²`, exactly 0 outside the
//! outer cone. `θ_outer ≤ 90°` (glTF's limit: the lit set is convex).
//!
//! # Culling a cone (Wronski 2017, "Cull that cone!")
//!
//! The lit set is the sphere of the range cut by the cone. A bounding sphere `(c, r)` (a
//! cluster's box's, or a tile's) can meet it only if
//! 1. it meets the range sphere (the point light's test, done by the caller), and
//! 2. it meets the cone: with `v = c − apex`, `v₁ = v·d` (the distance along the axis) and
//!    `v₂ = |v − v₁·d|` (from the axis), the distance from `c` to the infinite cone (`θ < 90°`)
//!    is `v₂·cos θ − v₁·sin θ` where the closest point lies on the lateral surface, and `|v|`
//!    where it is the apex (`v₁·cos θ + v₂·sin θ < 0`: `c` more than `θ + 90°` from the axis);
//!    the sphere misses the cone when that distance exceeds `r`, or when `v₁ < −r` (entirely
//!    behind the apex's plane, which a cone of `θ = 90°` is bounded by), or when
//!    `v₁ > r + range` (beyond the range along the axis) — [`cone_meets_sphere`].
//!
//! The distance is exact for the infinite cone, so the cone part of the test is exact: a sphere
//! is rejected exactly when the cone of directions its centre sees it in (half-angle
//! `asin(r/|v|)`) misses the lit cone (`shadow::sphere_meets_widened_cone` is the same test for
//! the shadow passes); the range cut along the axis is conservative (the tests sample points in
//! each rejected sphere). Both comparisons carry a relative slack of [`CONE_TEST_SLACK`] of the
//! magnitudes involved so that rounding never culls a light that reaches a point of the
//! sphere.
//!
//! Cost per light–cluster pair: 2 dot products, a square root, 4 comparisons. Memory: none; the
//! light's direction and cone cosines come with it.
//!
//! Where it runs: every shading pass multiplies a spot's light by [`spot_factor`]
//! (`shading::shade_lights`); every technique culls spots with [`cone_meets_sphere`] after its
//! range test (`light_types::spot_may_meet`), against the bounding sphere of what it culls for:
//! the cluster's box (`clustered-naive`, `clustered-aabb`, and `clustered-bvh` at the BVH's
//! leaves — its nodes keep range spheres) or the tile's frustum slice (`tiled`, `tiled-2.5d`,
//! `forward-plus`: `tile_cull::TileFrustum::bounding_sphere`).
use glam::Vec3;
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

/// Relative slack of the cone tests (module docs).
pub const CONE_TEST_SLACK: f32 = 1.0 / 65_536.0;

/// A spot light's cone: unit axis, cosines of the inner and outer half-angles and the sine of
/// the outer one (`0 ≤ θ_inner ≤ θ_outer ≤ 90°`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub direction: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub sin_outer: f32,
}

impl Cone {
    /// The cone of half-angles `inner ≤ outer` (radians) about `direction` (unit).
    #[inline]
    pub fn new(direction: Vec3, inner: f32, outer: f32) -> Self {
        Self { direction, cos_inner: inner.cos(), cos_outer: outer.cos(), sin_outer: outer.sin() }
    }
}

/// The glTF spot falloff at `cos θ` (module docs): 1 inside the inner cone, 0 outside the outer
/// one, the square of a linear ramp between; a hard edge where the two cones coincide.
#[inline]
pub fn cone_falloff(cos_theta: f32, cone: &Cone) -> f32 {
    if !(cos_theta > cone.cos_outer) {
        return 0.0;
    }
    let span = cone.cos_inner - cone.cos_outer;
    let t = if span > 0.0 { (cos_theta - cone.cos_outer) / span } else { 1.0 };
    let t = if t < 1.0 { t } else { 1.0 };
    t * t
}

/// The falloff of a spot light with apex `apex` at point `p` ([`cone_falloff`] of the angle to
/// the axis; 1 at the apex itself, where the direction is undefined and the range test decides).
#[inline]
pub fn spot_factor(apex: Vec3, cone: &Cone, p: Vec3) -> f32 {
    let l = p - apex;
    let len = l.length();
    if !(len > 0.0) {
        return 1.0;
    }
    cone_falloff(l.dot(cone.direction) / len, cone)
}

/// Whether the sphere `(c, r)` may meet the cone of apex `apex` cut at `range` (module docs):
/// `false` only if no point of the sphere is lit. Conservative; NaN gives `true`.
#[inline]
pub fn cone_meets_sphere(apex: Vec3, cone: &Cone, range: f32, c: Vec3, r: f32) -> bool {
    let v = c - apex;
    let v1 = v.dot(cone.direction);
    let axial2 = v.length_squared() - v1 * v1;
    let v2 = if axial2 > 0.0 { axial2.sqrt() } else { 0.0 };
    let scale = v.length() + r + range;
    let slack = scale * CONE_TEST_SLACK;
    // Closest to the apex (only below 90°: a wider cone has no such region).
    let apex_closest = cone.cos_outer > 0.0 && v1 * cone.cos_outer + v2 * cone.sin_outer < 0.0;
    let distance = if apex_closest { v.length() } else { v2 * cone.cos_outer - v1 * cone.sin_outer };
    let outside = distance > r + slack;
    // Behind the apex's plane: outside a cone of at most 90° (a wider one, which only the
    // shadow passes' widened cones are, reaches behind it).
    let behind = cone.cos_outer >= 0.0 && v1 < -r - slack;
    let beyond = v1 > r + range + slack;
    !(outside || behind || beyond)
}

/// [`cone_meets_sphere`] for the box `[min, max]`, through its bounding sphere.
#[inline]
pub fn cone_meets_box(apex: Vec3, cone: &Cone, range: f32, min: Vec3, max: Vec3) -> bool {
    let c = (min + max) * 0.5;
    cone_meets_sphere(apex, cone, range, c, (max - min).length() * 0.5)
}

#[cfg(test)]
#[path = "spot_tests.rs"]
mod tests;
