//! Camera-relative rendering: the world → view transform is applied on the CPU in f64, so a scene
//! far from the world origin renders as it would at the origin.
//!
//! A 4×4 f32 view matrix applied on the GPU cannot do this: its translation column is `−R·eye`,
//! rounded to f32, and `view · p` adds two large f32 numbers that cancel. At a world offset of
//! 10^7 m f32 values are spaced 1 m apart, so geometry and lights land up to a metre from where
//! they belong. Instead, per frame:
//! 1. **Lights**: view-space positions `R · (p − eye)` computed in f64 and rounded to f32 once
//!    ([`lights_to_view`]).
//! 2. **Geometry**: vertex positions uploaded as `p − eye` (f64 subtraction, one f32 rounding:
//!    [`ViewTransform::relative_positions`]), and the G-buffer camera's view matrix is the
//!    rotation `R` alone ([`ViewTransform::rotation`]): the vertex shader rotates small numbers.
//! 3. The rotation comes from the camera's eye, target and up in f64 ([`ViewTransform::look_at`]);
//!    it depends on `target − eye` only.
//!
//! Memory: one f32 copy of the positions on the host while uploading (12 B per vertex); nothing
//! more on the GPU.
//!
//! # Precision
//!
//! * **Translation invariance is exact.** The difference of two f32 values whose exponents differ
//!   by at most 29 is exact in f64 (24 + 29 = 53 bits), which holds for the coordinates of a scene
//!   and its camera. So translating scene, lights and camera by an offset that f32 represents
//!   exactly (every translated coordinate representable) hands the GPU bit-identical inputs, and
//!   the image is the same at any offset.
//! * **What remains is the f32 storage of world positions** (scenes, lights and cameras hold f32
//!   world coordinates). Near `|x|` they are spaced `2^(⌊log₂|x|⌋ − 23)` apart: 2^−7 m ≈ 7.8 mm
//!   at 10^5 m, 1 m at 10^7 m. Content placed at 10^7 m is on a 1 m grid before the renderer
//!   sees it, and no transform can undo that: keep coordinates below 2^17 m (131 km) for
//!   sub-centimetre detail, or rebase the world's origin near the camera.
//! * **Camera-relative f32** is not the limit: a point at distance `D` from the eye is rounded to
//!   within `D · 2^−24` per component (6 µm at 100 m, 60 µm at 1 km), a direction error of
//!   `≈ 10^−7` rad — 1/2700 of a pixel of a 60° frame 4320 pixels tall, far below the
//!   rasteriser's sub-pixel grid. Depth keeps the reversed-Z precision of the frame.
use super::light_contract;
use anyhow::{bail, Result};
use glam::{DMat3, DVec3, Mat4, Vec3};
use shaders::layout::PointLight;

/// World → view of a camera, kept in f64: the eye and the rotation `R` (right-handed, looking
/// down −z in view space, +y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewTransform {
    /// The camera position in world space.
    pub eye: DVec3,
    /// World → view rotation.
    pub rotation: DMat3,
}

impl ViewTransform {
    /// The look-at transform of a camera at `eye` looking at `target` (`up` need not be
    /// normalised; the camera must be valid: `target ≠ eye`, `up` not parallel to the view).
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> Self {
        Self { eye, rotation: glam::dcamera::rh::view::look_at_mat3(eye, target, up.normalize()) }
    }

    /// `p − eye`, computed in f64 and rounded to f32 once.
    pub fn relative(&self, p: [f32; 3]) -> Vec3 {
        (Vec3::from_array(p).as_dvec3() - self.eye).as_vec3()
    }

    /// `R · (p − eye)`: the view-space position of world point `p`, in f64, rounded once.
    pub fn to_view(&self, p: [f32; 3]) -> Vec3 {
        (self.rotation * (Vec3::from_array(p).as_dvec3() - self.eye)).as_vec3()
    }

    /// Vertex positions as the G-buffer pass takes them: relative to the eye.
    pub fn relative_positions(&self, positions: &[[f32; 3]]) -> Vec<[f32; 3]> {
        positions.iter().map(|&p| self.relative(p).to_array()).collect()
    }

    /// The view matrix of the G-buffer pass, whose vertices are
    /// [`relative_positions`](Self::relative_positions): the rotation alone, in f32.
    pub fn rotation(&self) -> Mat4 {
        Mat4::from_mat3(self.rotation.as_mat3())
    }
}

/// Lights as the shading kernels take them: view space ([`ViewTransform::to_view`]), checked
/// against the kernels' contract ([`light_contract::check`]: an error naming the light) and with
/// the radius they compute with ([`light_contract::kernel_radius`]).
pub fn lights_to_view(view: &ViewTransform, lights: &[PointLight]) -> Result<Vec<PointLight>> {
    lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            light_contract::check(i, l)?;
            let position = view.to_view(l.position);
            if !position.is_finite() {
                bail!("light {i} is too far from the camera for f32 view space: {l:?}");
            }
            Ok(PointLight { position: position.to_array(), radius: light_contract::kernel_radius(l.radius), ..*l })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(offset: DVec3) -> ViewTransform {
        ViewTransform::look_at(DVec3::new(3.0, 2.0, 10.0) + offset, DVec3::new(-4.0, 1.0, -20.0) + offset, DVec3::Y)
    }

    /// A scene translated by an f32-exact offset transforms bit-identically; f32 arithmetic
    /// (`view · p` with the translation in the matrix) does not.
    #[test]
    fn exact_offsets_transform_identically() {
        // Whole metres: exact at both offsets (f32 spacing at 10^7 m is 1 m).
        let points = [[1.0f32, 0.0, -7.0], [-30.0, 12.0, -100.0], [3.0, 2.0, 9.0]];
        let base = camera(DVec3::ZERO);
        for offset in [1e5, 1e7] {
            let moved = camera(DVec3::splat(offset));
            for p in points {
                let q = (Vec3::from_array(p).as_dvec3() + DVec3::splat(offset)).as_vec3().to_array();
                assert_eq!((Vec3::from_array(q).as_dvec3() - DVec3::splat(offset)).as_vec3().to_array(), p, "the offset must be exact for this test");
                assert_eq!(moved.to_view(q), base.to_view(p), "offset {offset}, point {p:?}");
                assert_eq!(moved.relative(q), base.relative(p), "offset {offset}, point {p:?}");
            }
            assert_eq!(moved.rotation(), base.rotation());
        }
        // The f32 matrix path at 10^7 m is off by about a metre.
        let (eye, target) = (Vec3::new(3.0, 2.0, 10.0) + Vec3::splat(1e7), Vec3::new(-4.0, 1.0, -20.0) + Vec3::splat(1e7));
        let view = glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y);
        let p = Vec3::new(1.0, 0.0, -7.0) + Vec3::splat(1e7);
        let err = (view.transform_point3(p) - base.to_view([1.0, 0.0, -7.0])).length();
        assert!(err > 0.05, "f32 view·p at 1e7 should be visibly wrong, error {err}");
    }

    #[test]
    fn lights_move_to_view_space_checked_and_clamped() {
        let v = camera(DVec3::ZERO);
        let l = |radius: f32, intensity: f32| PointLight { position: [0.0, 1.0, 0.0], radius, colour: [1.0, 0.5, 0.0], intensity };
        let out = lights_to_view(&v, &[l(1e30, 1.0), l(2.0, 3.0)]).unwrap();
        assert_eq!(out[0], PointLight { position: v.to_view([0.0, 1.0, 0.0]).to_array(), radius: shaders::lighting::MAX_RADIUS, ..l(1e30, 1.0) });
        assert_eq!(out[1].radius, 2.0);
        let err = lights_to_view(&v, &[l(1.0, 1.0), l(1.0, -1.0)]).unwrap_err().to_string();
        assert!(err.starts_with("light 1 has a negative"), "{err}");
        let far = PointLight { position: [f32::MAX, 0.0, 0.0], ..l(1.0, 1.0) };
        let behind = ViewTransform::look_at(DVec3::new(-f32::MAX as f64, 0.0, 0.0), DVec3::ZERO, DVec3::Y);
        assert!(lights_to_view(&behind, &[far]).unwrap_err().to_string().starts_with("light 0 is too far"));
    }
}
