//! The frame's effect bits reach the shading of every technique on the local device (lavapipe in
//! CI), validation on. With `EFFECT_INVERSE_SQUARE_CUT` (the accuracy study's falloff rows) every
//! technique must shade with the plain inverse square cut at each light's radius, not with Karis'
//! window: its image differs from the window image on a meaningful share of the pixels, and both
//! images equal a CPU shading of the read-back G-buffer (every light, `lighting::shade` with the
//! frame's effect bits) within 1/255 — for the `_diffuse` and the `_specular` shading variants
//! (Forward+ with both layouts of its tile lists).
mod common;
use host::gpu::Gpu;
use host::render::{self, Frame, Readback, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::{lights, Effects, Scene};
use shaders::layout::{PointLight, View, EFFECT_INVERSE_SQUARE_CUT, EFFECT_SPECULAR};
use shaders::octahedral::Precision;
use shaders::lighting::{cut_radius, encode_srgb8, shade, tonemap};
use shaders::raster::unorm8;
use shaders::reconstruct::{distance_from_depth, is_background, view_position};
use shaders::shading::BACKGROUND_RGBA8;

/// The intensity threshold of the cut (one of the accuracy study's ε).
const EPSILON: f32 = 1e-2;
const WIDTH: u32 = 160;
const HEIGHT: u32 = 90;
const LIGHTS: usize = 1_000;
/// The one material of the test scene: every pixel's albedo and BRDF are known to the CPU check.
const ALBEDO: [f32; 3] = [0.8, 0.6, 0.4];
const ROUGHNESS: f32 = 0.4;

/// `city` with every material made the same (`specular` 0: the scene runs the `_diffuse` kernels).
fn city(specular: f32) -> Scene {
    let mut scene = Scene::load("city", &common::assets::dir()).unwrap();
    for m in &mut scene.materials {
        (m.albedo, m.specular, m.roughness, m.albedo_texture, m.alpha_mask_texture) = (ALBEDO, specular, ROUGHNESS, None, None);
    }
    scene.effects = Effects::from_materials(&scene.materials);
    assert_eq!(scene.effects.specular, specular > 0.0);
    scene
}

/// Uniform lights with the accuracy study's cut radius at [`EPSILON`]: `intensity·max(colour) /
/// (d² + 1) ≥ ε` inside.
fn cut_lights(scene: &Scene) -> Vec<PointLight> {
    lights::uniform(scene, LIGHTS, 31)
        .unwrap()
        .into_iter()
        .map(|l| PointLight { radius: cut_radius(l.intensity * l.colour.iter().fold(0f32, |m, &c| m.max(c)), EPSILON), ..l })
        .collect()
}

fn settings(technique: Technique, read_back: bool) -> Settings {
    Settings {
        bvh_branching: 0,
        morton_bits: 0,
        async_compute: true,
        sort: Default::default(),
        fp_lists: Default::default(),
        unique_clusters: Default::default(),
        oit: Default::default(),
        dispatch_times: false,
        msaa: 1,
        light_record: Default::default(),
        shadow: Default::default(),
        width: WIDTH,
        height: HEIGHT,
        tile_size: 16,
        technique,
        view: View::Shaded,
        normal_precision: Precision::Oct16,
        exposure: 1.0,
        frames: 0,
        read_back,
    }
}

fn frame(gpu: &Gpu, scene: &Scene, lights: &[PointLight], effects: u32, s: &Settings) -> Frame {
    let flat = flatten(scene, s.normal_precision).unwrap();
    let mut input = scene_input(scene, &flat, lights);
    input.effects |= effects;
    render::render(gpu, &input, s).unwrap_or_else(|e| panic!("{:?}: {e:#}", s.technique))
}

/// The CPU's image of the read-back G-buffer: every light, `lighting::shade` with `effects`.
fn cpu_image(rb: &Readback, specular: f32, effects: u32) -> Vec<u32> {
    let g = &rb.grid;
    let albedo = glam::Vec3::from_array(ALBEDO.map(unorm8));
    (0..(g.width * g.height) as usize)
        .map(|i| {
            let z = f32::from_bits(rb.depth[i]);
            if is_background(z) {
                return BACKGROUND_RGBA8;
            }
            let p = view_position(g, i as u32 % g.width, i as u32 / g.width, distance_from_depth(g.near, z));
            let n = glam::Vec3::from_array(rb.normals[i]);
            let sum = rb.lights_view.iter().fold(glam::Vec3::ZERO, |s, l| s + shade(p, n, albedo, specular, ROUGHNESS, l, effects));
            encode_srgb8(tonemap(sum, 1.0))
        })
        .collect()
}

fn channel_diff(a: u32, b: u32) -> u32 {
    (0..4).map(|s| ((a >> (8 * s)) & 255).abs_diff((b >> (8 * s)) & 255)).max().unwrap()
}

/// Pixels where the two images differ by more than 1/255 in some channel.
fn differing(a: &[u32], b: &[u32]) -> usize {
    a.iter().zip(b).filter(|(a, b)| channel_diff(**a, **b) > 1).count()
}

/// For one scene variant: every technique's cut image differs from its window image where the
/// falloffs differ, and both equal the CPU shading within 1/255.
fn assert_cut_reaches_every_technique(gpu: &Gpu, specular: f32) {
    let scene = city(specular);
    let lights = cut_lights(&scene);
    let spec_bit = if specular > 0.0 { EFFECT_SPECULAR } else { 0 };
    let rb = frame(gpu, &scene, &lights, 0, &settings(Technique::Deferred, true)).readback.unwrap();
    let cpu_window = cpu_image(&rb, specular, spec_bit);
    let cpu_cut = cpu_image(&rb, specular, spec_bit | EFFECT_INVERSE_SQUARE_CUT);
    let geometry = cpu_cut.iter().filter(|&&p| p != BACKGROUND_RGBA8).count();
    let expected = differing(&cpu_cut, &cpu_window);
    assert!(expected * 5 > geometry, "specular {specular}: the falloffs should differ on a fifth of the {geometry} geometry pixels, they differ on {expected}");
    for (t, fp_lists) in common::render::runs(Technique::ALL) {
        let s = Settings { fp_lists, ..settings(t, false) };
        let t = common::render::label((t, fp_lists));
        let window = frame(gpu, &scene, &lights, 0, &s).pixels;
        let cut = frame(gpu, &scene, &lights, EFFECT_INVERSE_SQUARE_CUT, &s).pixels;
        let changed = differing(&cut, &window);
        assert!(changed * 5 > geometry, "{t}, specular {specular}: the inverse-square cut changes {changed} of {geometry} pixels (CPU: {expected})");
        for (what, gpu_image, cpu) in [("cut", &cut, &cpu_cut), ("window", &window, &cpu_window)] {
            let bad: Vec<(usize, u32, u32)> = (0..cpu.len()).filter(|&i| channel_diff(gpu_image[i], cpu[i]) > 1).map(|i| (i, gpu_image[i], cpu[i])).take(5).collect();
            assert!(bad.is_empty(), "{t}, specular {specular}, {what}: pixels differ from the CPU shading by more than 1/255 (pixel, GPU, CPU): {bad:x?}");
        }
    }
    common::assert_clean(gpu);
}

#[test]
fn inverse_square_cut_reaches_every_diffuse_technique() {
    assert_cut_reaches_every_technique(&common::gpu(), 0.0);
}

#[test]
fn inverse_square_cut_reaches_every_specular_technique() {
    assert_cut_reaches_every_technique(&common::gpu(), 0.5);
}

/// The accuracy study's culling knobs strictly change `clustered-naive`'s lists on lights chosen
/// for it: from 4000 candidate lights of 1.5 m, the CPU picks (with the kernels' own tests over
/// the frame's unique clusters) lights that the frustum planes cull from a cluster whose box keeps
/// them, and lights that the exact test culls from a cluster whose planes keep them (spheres by
/// an edge or a corner). Rendered alone, those lights must give strictly fewer references with
/// `EFFECT_CULL_PLANES` than with the box, and strictly fewer with `EFFECT_CULL_EXACT` than with
/// the planes; the images stay within 1/255 of each other (every test is conservative).
#[test]
fn culling_tests_strictly_narrow_the_lists() {
    use shaders::cluster_bounds::cluster_aabb_of_key;
    use shaders::cluster_test::{cluster_frustum, sphere_meets_frustum, sphere_outside_planes};
    use shaders::layout::{EFFECT_CULL_EXACT, EFFECT_CULL_PLANES};
    use shaders::lighting::sphere_intersects_aabb;
    let gpu = common::gpu();
    let scene = city(0.0);
    let candidates: Vec<PointLight> = lights::uniform(&scene, 4000, 57).unwrap().into_iter().map(|l| PointLight { radius: 1.5, ..l }).collect();
    let s = settings(Technique::ClusteredNaive, true);
    let rb = frame(&gpu, &scene, &candidates, 0, &s).readback.unwrap();
    let g = &rb.grid;
    // Per candidate: clusters whose box, planes and exact test keep it.
    let kept = |l: &PointLight| -> [usize; 3] {
        let c = glam::Vec3::from_array(l.position);
        let mut n = [0; 3];
        for &key in &rb.unique {
            let (i, j, k) = g.unpack(key);
            let f = cluster_frustum(g, &rb.bounds, i, j, k);
            n[0] += usize::from(sphere_intersects_aabb(c, l.radius, &cluster_aabb_of_key(g, &rb.bounds, key)));
            n[1] += usize::from(!sphere_outside_planes(&f, c, l.radius));
            n[2] += usize::from(sphere_meets_frustum(&f, c, l.radius));
        }
        n
    };
    let counts: Vec<[usize; 3]> = rb.lights_view.iter().map(kept).collect();
    let planes_cull: Vec<usize> = (0..counts.len()).filter(|&l| counts[l][1] < counts[l][0]).take(40).collect();
    let exact_cull: Vec<usize> = (0..counts.len()).filter(|&l| counts[l][2] < counts[l][1]).take(40).collect();
    assert!(!planes_cull.is_empty() && !exact_cull.is_empty(), "the candidates hold lights each finer test culls: {} and {}", planes_cull.len(), exact_cull.len());
    let chosen: Vec<PointLight> = planes_cull.iter().chain(&exact_cull).map(|&l| candidates[l]).collect();
    let [aabb, planes, exact] = [0, EFFECT_CULL_PLANES, EFFECT_CULL_EXACT].map(|e| frame(&gpu, &scene, &chosen, e, &settings(Technique::ClusteredNaive, false)));
    assert!(planes.light_refs < aabb.light_refs, "EFFECT_CULL_PLANES must cull lights the box keeps: {} references against {}", planes.light_refs, aabb.light_refs);
    assert!(exact.light_refs < planes.light_refs, "EFFECT_CULL_EXACT must cull lights the planes keep: {} references against {}", exact.light_refs, planes.light_refs);
    for (what, f) in [("planes", &planes), ("exact", &exact)] {
        assert!(differing(&f.pixels, &aabb.pixels) == 0, "{what}: the image must not change (the tests are conservative)");
    }
    common::assert_clean(&gpu);
}
