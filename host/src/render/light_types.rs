//! Spot and directional lights on the host: their world-space description ([`Spot`],
//! [`Directional`]), the checks that name a bad light and field, and the light buffer the kernels
//! read ([`light_records`]: the layout of `shaders::light_types` — punctual lights, then the cone
//! section only when the scene has spots, then the directional section only when it has
//! directional lights) with the effect bits that gate each section ([`light_effects`]).
//!
//! Directions go to view space each frame with the positions (rotated in f64, normalised,
//! rounded once), so a moving camera moves every light type alike.
use super::ViewTransform;
use anyhow::{bail, Result};
use glam::Vec3;
use shaders::layout::PointLight;
use shaders::light_types::{directional_record, point_record, spot_record, MAX_DIRECTIONAL_LIGHTS};
use shaders::spot::Cone;

/// A spot light's cone (world space): the point light of the same index is its apex, range,
/// colour and intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// Where the light points (any length > 0).
    pub direction: Vec3,
    /// Half-angle of full intensity, radians, `0 ≤ inner ≤ outer`.
    pub inner: f32,
    /// Half-angle where the light ends, radians, `0 < outer ≤ π/2`.
    pub outer: f32,
}

/// A directional light (world space): no position, no range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Directional {
    /// Where the light travels (any length > 0): surfaces facing `−direction` are lit.
    pub direction: Vec3,
    /// Linear RGB.
    pub colour: [f32; 3],
    pub intensity: f32,
}

/// A unit vector or an error naming `what`'s field `field`.
fn unit(what: &str, field: &str, v: Vec3) -> Result<Vec3> {
    if !v.is_finite() {
        bail!("{what}: {field} = {:?} is not finite", v.to_array());
    }
    let n = v.normalize_or_zero();
    if n == Vec3::ZERO || !n.is_finite() {
        bail!("{what}: {field} = {:?} has no direction (zero length)", v.to_array());
    }
    Ok(n)
}

/// Checks spot `what` (e.g. `light 3`): a direction, `0 ≤ inner ≤ outer ≤ 90°`, `outer > 0`.
pub fn check_spot(what: &str, s: &Spot) -> Result<()> {
    unit(what, "direction", s.direction)?;
    let deg = |r: f32| r.to_degrees();
    if !(s.outer.is_finite() && s.outer > 0.0 && s.outer <= std::f32::consts::FRAC_PI_2 * (1.0 + 1e-6)) {
        bail!("{what}: outer_angle = {}° must be in (0, 90] degrees", deg(s.outer));
    }
    if !(s.inner.is_finite() && s.inner >= 0.0 && s.inner <= s.outer) {
        bail!("{what}: inner_angle = {}° must be in [0, outer_angle = {}°] degrees", deg(s.inner), deg(s.outer));
    }
    Ok(())
}

/// Checks directional light `what`: a direction, finite colour and intensity `≥ 0`.
pub fn check_directional(what: &str, d: &Directional) -> Result<()> {
    unit(what, "direction", d.direction)?;
    if !d.colour.iter().all(|c| c.is_finite() && *c >= 0.0) {
        bail!("{what}: colour = {:?} must be finite and ≥ 0", d.colour);
    }
    if !(d.intensity.is_finite() && d.intensity >= 0.0) {
        bail!("{what}: intensity = {} must be finite and ≥ 0", d.intensity);
    }
    Ok(())
}

/// The `EFFECT_SPOT` / `EFFECT_DIRECTIONAL` bits (and count) of a scene: spot bits only if some
/// light is a spot; an error beyond [`MAX_DIRECTIONAL_LIGHTS`] directional lights.
pub fn light_effects(spots: &[Option<Spot>], directional: &[Directional]) -> Result<u32> {
    if directional.len() > MAX_DIRECTIONAL_LIGHTS as usize {
        bail!("{} directional lights: every shading pass loops over them, at most {MAX_DIRECTIONAL_LIGHTS} are supported", directional.len());
    }
    Ok(shaders::light_types::light_effects(spots.iter().any(Option::is_some), directional.len() as u32))
}

/// Each light's cone in view space for the shadow maps' caster records: the unit axis and the
/// cosine of the outer half-angle of a spot light, `None` for a point light (and for every light
/// of a scene without spot lights).
pub fn view_cones(view: &ViewTransform, spots: &[Option<Spot>], lights: usize) -> Vec<Option<(Vec3, f32)>> {
    let rotate = |v: Vec3| (view.rotation * v.as_dvec3()).normalize().as_vec3();
    (0..lights).map(|i| spots.get(i).copied().flatten().map(|s| (rotate(s.direction), s.outer.cos()))).collect()
}

/// The GPU light buffer: `lights_view` (the punctual lights in view space), then with spots one
/// cone record per light (a point light's marker for the others), then the directional lights;
/// checks every spot and directional light (errors name the light and field).
pub fn light_records(view: &ViewTransform, lights_view: &[PointLight], spots: &[Option<Spot>], directional: &[Directional]) -> Result<Vec<PointLight>> {
    let effects = light_effects(spots, directional)?;
    let with_spots = effects & shaders::light_types::EFFECT_SPOT != 0;
    if with_spots && spots.len() != lights_view.len() {
        bail!("{} spot records for {} lights: a scene with spot lights gives one (or none, for a point light) per light", spots.len(), lights_view.len());
    }
    let rotate = |v: Vec3| (view.rotation * v.as_dvec3()).normalize().as_vec3();
    let mut out = lights_view.to_vec();
    if with_spots {
        out.reserve(lights_view.len() + directional.len());
        for (i, s) in spots.iter().enumerate() {
            out.push(match s {
                Some(s) => {
                    check_spot(&format!("light {i} (spot)"), s)?;
                    spot_record(&Cone::new(rotate(s.direction), s.inner, s.outer))
                }
                None => point_record(),
            });
        }
    }
    for (i, d) in directional.iter().enumerate() {
        check_directional(&format!("directional light {i}"), d)?;
        out.push(directional_record(-rotate(d.direction), d.colour, d.intensity));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn records_follow_the_layout_and_bad_lights_are_named() {
        let view = ViewTransform::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y);
        let l = PointLight { position: [0.0; 3], radius: 3.0, colour: [1.0; 3], intensity: 1.0 };
        let spot = Spot { direction: Vec3::new(0.0, -2.0, 0.0), inner: 0.2, outer: 0.6 };
        let sun = Directional { direction: Vec3::new(0.0, -1.0, 0.0), colour: [1.0; 3], intensity: 2.0 };
        let r = light_records(&view, &[l, l], &[Some(spot), None], &[sun]).unwrap();
        assert_eq!(r.len(), 5);
        assert_eq!(r[2].position, [0.0, -1.0, 0.0]);
        assert_eq!(r[3], point_record());
        assert_eq!((r[4].position, r[4].intensity), ([0.0, 1.0, 0.0], 2.0), "towards the light");
        assert_eq!(light_records(&view, &[l, l], &[None, None], &[]).unwrap().len(), 2, "no cone section without spots");
        let err = |spots: &[Option<Spot>], dirs: &[Directional]| light_records(&view, &[l, l], spots, dirs).unwrap_err().to_string();
        assert!(err(&[None, Some(Spot { outer: 2.0, ..spot })], &[]).starts_with("light 1 (spot): outer_angle"));
        assert!(err(&[Some(Spot { inner: 0.7, ..spot }), None], &[]).starts_with("light 0 (spot): inner_angle"));
        assert!(err(&[Some(Spot { direction: Vec3::ZERO, ..spot }), None], &[]).contains("direction"));
        assert!(err(&[Some(Spot { inner: f32::NAN, ..spot }), None], &[]).contains("inner_angle"));
        assert!(err(&[], &[Directional { direction: Vec3::NAN, ..sun }]).starts_with("directional light 0: direction"));
        assert!(err(&[], &[sun; 5]).contains("at most 4"));
    }
}
