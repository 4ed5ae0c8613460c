//! Comparing frames across techniques: every technique against a reference image, and a CPU
//! shading of a read-back G-buffer.
use super::pixels::worst_channel;
use super::render::{frame, label, runs, Run};
use host::gpu::Gpu;
use host::render::{reference, Frame, Settings, Technique};
use host::scene::flatten::flatten;
use host::scene::Scene;
use shaders::layout::PointLight;

/// Largest per-channel difference (of 255) allowed between a technique and the reference.
pub const TOLERANCE: u32 = 1;

/// Renders `scene` with each of `techniques` (otherwise `s`; Forward+ with both layouts of its
/// tile lists: [`runs`]) and asserts every image within [`TOLERANCE`] of `reference`
/// ([`assert_runs_match`]).
pub fn assert_techniques_match(gpu: &Gpu, reference: &[u32], scene: &Scene, lights: &[PointLight], s: &Settings, techniques: &[Technique], what: &str) {
    assert_runs_match(gpu, reference, scene, lights, s, &runs(techniques), what);
}

/// Renders `scene` with each technique and list layout of `runs` (otherwise `s`) and asserts
/// every image within [`TOLERANCE`] of `reference`; with `s.read_back`, the clustered techniques'
/// lists are also checked against the CPU ([`reference::check`]). One frame is alive at a time
/// (8K frames).
pub fn assert_runs_match(gpu: &Gpu, reference: &[u32], scene: &Scene, lights: &[PointLight], s: &Settings, runs: &[Run], what: &str) {
    for &(technique, fp_lists) in runs {
        let run = Settings { technique, fp_lists, ..s.clone() };
        let f = frame(gpu, scene, lights, &run);
        let worst = worst_channel(reference, &f.pixels);
        assert!(worst <= TOLERANCE, "{what}, {}: differs from the reference by {worst}/255", label((technique, fp_lists)));
        if let Some(rb) = f.readback.as_ref().filter(|rb| !rb.keys.is_empty()) {
            reference::check(rb).unwrap_or_else(|e| panic!("{what}, {}: {e:#}", label((technique, fp_lists))));
        }
    }
    super::assert_clean(gpu);
}

/// Renders the brute-force reference (`deferred`) and asserts that every other technique (Forward+
/// with both list layouts) equals it ([`assert_techniques_match`]); returns the reference frame.
pub fn assert_every_technique_equals_deferred(gpu: &Gpu, scene: &Scene, lights: &[PointLight], s: &Settings, what: &str) -> Frame {
    let reference = frame(gpu, scene, lights, &Settings { technique: Technique::Deferred, ..s.clone() });
    let others: Vec<Technique> = Technique::ALL.iter().copied().filter(|&t| t != Technique::Deferred).collect();
    assert_techniques_match(gpu, &reference.pixels, scene, lights, s, &others, what);
    reference
}

/// Pixels showing geometry (reversed-Z depth above 0) in a read-back frame.
pub fn geometry_pixels(f: &Frame) -> usize {
    f.readback.as_ref().expect("a read-back frame").depth.iter().filter(|&&d| f32::from_bits(d) > 0.0).count()
}

/// The frame as the CPU shades it from the frame's read-back G-buffer (depth, decoded normals,
/// albedo and material) and view-space lights: every light that touches a pixel, through
/// `lighting::shade` and the output encoding, in f32 like the GPU; a spot light's times its cone
/// falloff (`spot::spot_factor`), and the scene's directional lights added
/// (`lighting::shade_directional`), from the light records the kernels read. What every
/// technique must show (within [`TOLERANCE`]).
pub fn cpu_shaded(scene: &Scene, f: &Frame, s: &Settings) -> Vec<u32> {
    use shaders::light_types::{cone_of, directional_base, light_effects};
    use shaders::lighting::{encode_srgb8, light_touches, shade, shade_directional, tonemap};
    use shaders::reconstruct::{distance_from_depth, is_background, view_position};
    let rb = f.readback.as_ref().expect("a read-back frame");
    let materials = flatten(scene, s.normal_precision).unwrap().materials;
    let effects = scene.effects.flags();
    let spots = scene.spots.iter().any(Option::is_some);
    let n_lights = rb.lights_view.len() as u32;
    let base = directional_base(light_effects(spots, scene.directional.len() as u32), n_lights) as usize;
    let directional = &rb.light_records[base..base + scene.directional.len()];
    let g = &f.grid;
    (0..rb.depth.len())
        .map(|i| {
            let depth = f32::from_bits(rb.depth[i]);
            if is_background(depth) {
                return shaders::shading::BACKGROUND_RGBA8;
            }
            let p = view_position(g, i as u32 % g.width, i as u32 / g.width, distance_from_depth(g.near, depth));
            let n = glam::Vec3::from_array(rb.normals[i]);
            let (albedo, m) = shaders::shading::gbuffer_albedo(rb.albedo[i]);
            let mat = materials[m as usize];
            let cone = |i: usize, l: &PointLight| if spots { shaders::spot::spot_factor(glam::Vec3::from_array(l.position), &cone_of(&rb.light_records, n_lights, i as u32), p) } else { 1.0 };
            let punctual = rb.lights_view.iter().enumerate().filter(|(_, l)| light_touches(l, p));
            let sum = punctual.fold(glam::Vec3::ZERO, |sum, (i, l)| sum + shade(p, n, albedo, mat.specular, mat.roughness, l, effects) * cone(i, l));
            let sun = |d: &PointLight| {
                let (to_light, colour) = (glam::Vec3::from_array(d.position), glam::Vec3::from_array(d.colour));
                shade_directional::<true>(p, n, albedo, mat.specular, mat.roughness, to_light, colour, d.intensity, effects)
            };
            let sum = directional.iter().fold(sum, |sum, d| sum + sun(d));
            encode_srgb8(tonemap(sum, s.exposure))
        })
        .collect()
}
