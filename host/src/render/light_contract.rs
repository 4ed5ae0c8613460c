//! What a light must satisfy before the shading kernels see it (`shaders::lighting`, "Lights: the
//! host's contract"): finite values, colour, intensity and radius `≥ 0`, and every
//! `colour · intensity ≤` [`MAX_EMISSION`] — checked by [`check`] with an error naming the light —
//! and a radius in the range the kernels compute with ([`kernel_radius`]). Scene validation and
//! [`super::lights_to_view`] (every frame) both apply it.
use anyhow::{bail, Result};
use shaders::layout::PointLight;
use shaders::lighting::{MAX_EMISSION, MAX_RADIUS, MIN_RADIUS};

/// Checks light `index` against the contract; the error is one line naming the light.
pub fn check(index: usize, l: &PointLight) -> Result<()> {
    let values = l.position.iter().chain(&l.colour).chain([&l.radius, &l.intensity]);
    if values.into_iter().any(|v| !v.is_finite()) {
        bail!("light {index} has a non-finite value: {l:?}");
    }
    if l.radius < 0.0 {
        bail!("light {index} has a negative radius {}", l.radius);
    }
    if l.intensity < 0.0 || l.colour.iter().any(|&c| c < 0.0) {
        bail!("light {index} has a negative colour or intensity: {l:?}");
    }
    let emission = l.colour.iter().fold(0.0f32, |m, &c| m.max(c)) as f64 * l.intensity as f64;
    if emission > MAX_EMISSION as f64 {
        bail!("light {index} emits colour × intensity = {emission:e}, more than the {MAX_EMISSION:e} the shading keeps finite: {l:?}");
    }
    Ok(())
}

/// The radius the kernels compute with: above [`MAX_RADIUS`] (2^60) clamped to it — the light
/// reaches everything either way —, below [`MIN_RADIUS`] (2^-50) 0 — a light reaching no farther
/// than 2^-50 lights nothing either way.
pub fn kernel_radius(radius: f32) -> f32 {
    if radius > MAX_RADIUS {
        MAX_RADIUS
    } else if radius < MIN_RADIUS {
        0.0
    } else {
        radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_name_the_light_and_radii_clamp() {
        let l = |radius: f32, intensity: f32| PointLight { position: [0.0, 1.0, 0.0], radius, colour: [1.0, 0.5, 0.0], intensity };
        assert!(check(0, &l(3.0, MAX_EMISSION)).is_ok());
        let err = |l: PointLight| check(4, &l).unwrap_err().to_string();
        assert!(err(l(1.0, MAX_EMISSION * 2.0)).starts_with("light 4 emits"));
        assert!(err(l(f32::NAN, 1.0)).starts_with("light 4 has a non-finite"));
        assert!(err(l(-1.0, 1.0)).starts_with("light 4 has a negative radius"));
        assert!(err(l(1.0, -1.0)).starts_with("light 4 has a negative colour"));
        assert_eq!([1e30, 1e-20, 3.0, 0.0].map(kernel_radius), [MAX_RADIUS, 0.0, 3.0, 0.0]);
    }
}
