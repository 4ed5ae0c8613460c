//! The CPU's shading of a read-back frame, independent of every shading kernel: what each
//! technique must show, and, where lights cast shadows, the ray-cast shadow reference
//! (`render --shadow-reference`).
//!
//! Per pixel, from the frame's read-back G-buffer (depth, decoded normal, albedo and material)
//! and view-space lights: every light whose range touches the pixel's view-space position,
//! through `lighting::shade` and the output encoding in f32 like the kernels; a spot light's
//! times its cone falloff (`spot::spot_factor`); the scene's directional lights added
//! (`lighting::shade_directional`). With [`Shadows`], a light that casts shadows adds nothing
//! where a triangle of the scene lies strictly between the pixel and the light
//! ([`Occluders::blocked`], 64-bit floats): exact visibility per pixel and light.
//!
//! **Bias.** The receiver is reconstructed from the depth buffer, so it lies within depth and
//! normal quantisation of its surface, on either side. The segment starts at the receiver moved
//! along its G-buffer normal by [`SHADOW_BIAS`] times its distance to the eye; the light's end is
//! not moved (a light on a surface is not shadowed by it: `scene::raycast`).
//!
//! Cost: one segment test per pixel and touching shadow-casting light (a walk of the triangles'
//! hierarchy each), on every core of the machine.
use super::camera_relative::ViewTransform;
use super::{Frame, Settings};
use crate::scene::flatten::flatten;
use crate::scene::raycast::Occluders;
use crate::scene::Scene;
use anyhow::{Context as _, Result};
use glam::Vec3;
use shaders::layout::PointLight;

/// A receiver's offset along its normal, relative to its distance from the eye.
pub const SHADOW_BIAS: f32 = 1e-3;

/// The occluders of a frame's shadows, in the frame's view space, and which lights cast them.
pub struct Shadows<'a> {
    pub occluders: Occluders,
    /// Per light of the frame (its `lights_view` order), whether it casts shadows.
    pub casters: &'a [bool],
}

impl<'a> Shadows<'a> {
    /// The scene's triangles moved into the view space of `view` (as the lights are), and the
    /// scene's shadow flags.
    pub fn of_scene(scene: &'a Scene, view: &ViewTransform) -> Self {
        let triangles = scene.meshes.iter().flat_map(|m| m.indices.chunks_exact(3).map(move |t| [t[0], t[1], t[2]].map(|i| view.to_view(m.positions[i as usize]))));
        Shadows { occluders: Occluders::new(triangles), casters: &scene.shadows }
    }

    /// Whether light `i` at `light` reaches the receiver at `p` with normal `n` (view space).
    pub fn lit(&self, i: usize, p: Vec3, n: Vec3, light: Vec3) -> bool {
        if !self.casters.get(i).copied().unwrap_or(false) {
            return true;
        }
        let start = p.as_dvec3() + n.as_dvec3() * (SHADOW_BIAS * p.length()) as f64;
        !self.occluders.blocked(start, light.as_dvec3())
    }
}

/// The frame as the CPU shades it (module docs); `shadows`: the ray-cast visibility of lights
/// that cast shadows (`None`: every light reaches every pixel it touches). Needs a frame
/// rendered with `read_back`.
pub fn shade(scene: &Scene, f: &Frame, s: &Settings, shadows: Option<&Shadows>) -> Result<Vec<u32>> {
    use shaders::light_types::{cone_of, directional_base, light_effects};
    use shaders::lighting::{encode_srgb8, light_touches, shade, shade_directional, tonemap};
    use shaders::reconstruct::{distance_from_depth, is_background, view_position};
    let rb = f.readback.as_ref().context("the CPU shading needs a frame rendered with read_back")?;
    let materials = flatten(scene, s.normal_precision)?.materials;
    let effects = scene.effects.flags();
    let spots = scene.spots.iter().any(Option::is_some);
    let n_lights = rb.lights_view.len() as u32;
    let base = directional_base(light_effects(spots, scene.directional.len() as u32), n_lights) as usize;
    let directional = &rb.light_records[base..base + scene.directional.len()];
    let g = &f.grid;
    let pixel = |i: usize| -> u32 {
        let depth = f32::from_bits(rb.depth[i]);
        if is_background(depth) {
            return shaders::shading::BACKGROUND_RGBA8;
        }
        let p = view_position(g, i as u32 % g.width, i as u32 / g.width, distance_from_depth(g.near, depth));
        let n = Vec3::from_array(rb.normals[i]);
        let (albedo, m) = shaders::shading::gbuffer_albedo(rb.albedo[i]);
        let mat = materials[m as usize];
        let cone = |i: usize, l: &PointLight| if spots { shaders::spot::spot_factor(Vec3::from_array(l.position), &cone_of(&rb.light_records, n_lights, i as u32), p) } else { 1.0 };
        let lit = |i: usize, l: &PointLight| shadows.is_none_or(|sh| sh.lit(i, p, n, Vec3::from_array(l.position)));
        let punctual = rb.lights_view.iter().enumerate().filter(|(i, l)| light_touches(l, p) && lit(*i, l));
        let sum = punctual.fold(Vec3::ZERO, |sum, (i, l)| sum + shade(p, n, albedo, mat.specular, mat.roughness, l, effects) * cone(i, l));
        let sun = |d: &PointLight| {
            let (to_light, colour) = (Vec3::from_array(d.position), Vec3::from_array(d.colour));
            shade_directional::<true>(p, n, albedo, mat.specular, mat.roughness, to_light, colour, d.intensity, effects)
        };
        let sum = directional.iter().fold(sum, |sum, d| sum + sun(d));
        encode_srgb8(tonemap(sum, s.exposure))
    };
    // Rows split over the machine's cores.
    let n = rb.depth.len();
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(64);
    let chunk = n.div_ceil(threads).max(1);
    let mut out = vec![0u32; n];
    std::thread::scope(|scope| {
        for (c, part) in out.chunks_mut(chunk).enumerate() {
            let pixel = &pixel;
            scope.spawn(move || part.iter_mut().enumerate().for_each(|(j, o)| *o = pixel(c * chunk + j)));
        }
    });
    Ok(out)
}
