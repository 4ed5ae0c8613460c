//! Spot and directional lights at the hard angles, on the local device (lavapipe in CI),
//! validation on: spots pointing straight at the camera and away from it, one with its apex at
//! the eye, and one small enough to lie inside one cluster — every technique equals the
//! brute-force reference, which equals the CPU's shading of its G-buffer; and each scene creates
//! only the light-type pipelines it calls for (`shaders::light_types`, "Specialised pipelines").
mod common;
use common::compare::{assert_every_technique_equals_deferred, cpu_shaded, TOLERANCE};
use common::pixels::worst_channel;
use common::render::{city, frame};
use common::scenes::camera_frame;
use glam::Vec3;
use host::render::{Settings, Technique};
use host::scene::{lights, Directional, Scene, Spot};
use shaders::layout::PointLight;
use shaders::light_types::{light_effects, light_type_variant};
use std::collections::BTreeSet;

const W: u32 = 160;
const H: u32 = 90;

fn settings(technique: Technique) -> Settings {
    Settings { read_back: true, ..common::render::settings(W, H, technique) }
}

fn spot(position: Vec3, radius: f32, intensity: f32, direction: Vec3, inner_degrees: f32, outer_degrees: f32) -> (PointLight, Option<Spot>) {
    let light = PointLight { position: position.to_array(), radius, colour: [1.0, 0.9, 0.7], intensity };
    (light, Some(Spot { direction, inner: inner_degrees.to_radians(), outer: outer_degrees.to_radians() }))
}

/// Where a ray through the frame's vertical midline, `below` (tangent) under the view axis, meets
/// the city's ground plane `y = 0`.
fn ground_point(scene: &Scene, below: f32) -> Vec3 {
    let (eye, fwd, _, up) = camera_frame(scene);
    let ray = (fwd - up * below).normalize();
    assert!(ray.y < 0.0 && eye.y > 0.0, "the ray meets the ground in front of the camera");
    eye + ray * (-eye.y / ray.y)
}

/// Clusters (of `clustered-naive`, read back) whose list holds light `l`.
fn clusters_listing(f: &host::render::Frame, l: u32) -> usize {
    let rb = f.readback.as_ref().unwrap();
    (0..rb.unique.len()).filter(|&c| rb.list[rb.offsets[c] as usize..][..rb.counts[c] as usize].contains(&l)).count()
}

#[test]
fn spots_at_and_away_from_the_camera_and_inside_a_cluster_equal_the_reference() {
    let gpu = common::gpu();
    let base = city();
    let (eye, fwd, right, up) = camera_frame(&base);
    let diag = (base.bounds.1 - base.bounds.0).length();
    // How far the spots reach: a tenth of the city.
    let depth = 0.1 * diag;
    let cases: Vec<(&str, (PointLight, Option<Spot>))> = vec![
        // Halfway to the ground, pointing straight back at the eye.
        ("pointing at the camera", spot(eye + fwd * depth * 0.5, depth, 6.0, -fwd, 15.0, 35.0)),
        // Just in front of the eye, pointing where the camera looks.
        ("pointing away from the camera", spot(eye + fwd * depth * 0.05, depth * 1.5, 8.0, fwd, 5.0, 12.0)),
        // The apex at the eye itself (view-space origin), tilted off the axis.
        ("apex at the eye", spot(eye, depth * 1.5, 6.0, (fwd + right * 0.3 - up * 0.1).normalize(), 0.0, 20.0)),
    ];
    let mut scene = base.clone();
    scene.lights = lights::uniform(&base, 60, 3).unwrap();
    scene.add_lights(cases.iter().map(|(_, l)| *l));
    // A small spot just above the ground, pointing down: placed where `clustered-naive` lists
    // it in exactly one cluster (the first such point along the view axis).
    // Half a metre in a frame whose clusters are metres across (the ground 3–7 m from the eye).
    let small = 0.5;
    let mut listed = Vec::new();
    let inside = (0..12)
        .map(|k| 0.12 + 0.03 * k as f32)
        .find_map(|below| {
            let mut s = scene.clone();
            s.add_lights([spot(ground_point(&base, below) + Vec3::Y * small / 3.0, small, 2.0, Vec3::NEG_Y, 40.0, 70.0)]);
            let f = frame(&gpu, &s, &s.lights, &settings(Technique::ClusteredNaive));
            listed.push(clusters_listing(&f, s.lights.len() as u32 - 1));
            (listed.last() == Some(&1)).then_some(s)
        })
        .unwrap_or_else(|| panic!("no ground point whose cluster holds the small spot's whole sphere: clusters listing it {listed:?}"));
    let mut scene = inside;
    scene.directional = vec![Directional { direction: Vec3::new(0.2, -1.0, 0.4), colour: [0.6, 0.7, 1.0], intensity: 0.2 }];

    let reference = assert_every_technique_equals_deferred(&gpu, &scene, &scene.lights, &settings(Technique::Deferred), "hard-angle spots");
    let worst = worst_channel(&reference.pixels, &cpu_shaded(&scene, &reference, &settings(Technique::Deferred)));
    assert!(worst <= TOLERANCE, "deferred differs from the CPU's shading of its G-buffer by {worst}/255");

    // Each spot shows: without it the frame changes.
    let names = cases.iter().map(|(n, _)| *n).chain(["inside a cluster"]);
    for (name, l) in names.zip(scene.lights.len() - 4..) {
        let mut without = scene.clone();
        without.lights.remove(l);
        without.spots.remove(l);
        let f = frame(&gpu, &without, &without.lights, &settings(Technique::Deferred));
        let changed = f.pixels.iter().zip(&reference.pixels).filter(|(a, b)| a != b).count();
        assert!(changed > 0, "the spot {name} lights no pixel");
    }
    common::assert_clean(&gpu);
}

/// A scene of point lights creates only the point-light pipelines (variant 0: no cone test, no
/// directional records in their code); spots and two directional lights add exactly their
/// variant, one directional light without spots its own.
#[test]
fn scenes_create_only_the_light_type_pipelines_they_call_for() {
    let gpu = common::gpu();
    let base = city();
    let l = lights::uniform(&base, 200, 9).unwrap();
    let render_all = |scene: &Scene| {
        for &t in Technique::ALL {
            frame(&gpu, scene, &scene.lights, &settings(t));
        }
    };
    let mut points = base.clone();
    points.lights = l.clone();
    render_all(&points);
    assert_eq!(gpu.light_type_variants(), BTreeSet::from([0]), "point lights only");

    let mut spots = base.clone();
    spots.add_lights(l.iter().copied().zip(lights::spot_cones(l.len(), 0.5, 9).unwrap()));
    spots.directional = vec![
        Directional { direction: Vec3::new(0.3, -1.0, 0.2), colour: [1.0; 3], intensity: 0.3 },
        Directional { direction: Vec3::new(-0.3, -1.0, 0.1), colour: [1.0; 3], intensity: 0.2 },
    ];
    render_all(&spots);
    let with_spots = light_type_variant(light_effects(true, 2));
    assert_eq!(gpu.light_type_variants(), BTreeSet::from([0, with_spots]), "spots and two directional lights");

    let mut sun = points.clone();
    sun.directional = vec![spots.directional[0]];
    render_all(&sun);
    assert_eq!(gpu.light_type_variants(), BTreeSet::from([0, light_type_variant(light_effects(false, 1)), with_spots]));
    common::assert_clean(&gpu);
}


/// Cone culling strictly shortens every culling technique's lists on a scene built for it: spot
/// lights a metre above the avenue pointing straight up (30° cones, 8 m range). Their range
/// spheres reach the street and the façades around them, their cones only the sky, so every
/// technique that culls by cone (all but brute force) must list them in fewer tiles or clusters
/// than with range-sphere culling (`EFFECT_CULL_SPHERE_ONLY`, the bench's `--spot-culling
/// sphere`), and both images equal brute force.
#[test]
fn cone_culling_strictly_shortens_every_techniques_lists() {
    use host::render::LightCost;
    use host::scene::flatten::{flatten, scene_input};
    use shaders::light_types::EFFECT_CULL_SPHERE_ONLY;
    let gpu = common::gpu();
    let mut scene = city();
    let (_, fwd, right, _) = camera_frame(&scene);
    let ahead = ground_point(&scene, 0.2);
    scene.lights.clear();
    scene.spots.clear();
    scene.add_lights((0..24).map(|k| {
        let at = ahead + fwd * (3.0 * (k / 2) as f32 - 15.0) + right * if k % 2 == 0 { 1.5 } else { -1.5 } + Vec3::Y;
        spot(at, 8.0, 2.0, Vec3::Y, 20.0, 30.0)
    }));
    let render = |t: Technique, fp_lists, effects: u32| {
        let s = Settings { fp_lists, ..settings(t) };
        let flat = flatten(&scene, s.normal_precision).unwrap();
        let mut input = scene_input(&scene, &flat, &scene.lights);
        input.effects |= effects;
        host::render::render(&gpu, &input, &s).unwrap_or_else(|e| panic!("{t:?}: {e:#}"))
    };
    let reference = render(Technique::Deferred, Default::default(), 0).pixels;
    let culling: Vec<Technique> = Technique::ALL.iter().copied().filter(|t| t.description().cost != LightCost::EveryLightPerPixel).collect();
    for (t, fp_lists) in common::render::runs(&culling) {
        let what = common::render::label((t, fp_lists));
        let (cone, sphere) = (render(t, fp_lists, 0), render(t, fp_lists, EFFECT_CULL_SPHERE_ONLY));
        assert!(cone.light_refs > 0, "{what}: the spheres reach the street ({} references)", cone.light_refs);
        assert!(sphere.light_refs > cone.light_refs, "{what}: sphere-only culling lists {} light references, cone culling {}: the cone must cull", sphere.light_refs, cone.light_refs);
        for (how, f) in [("cone", &cone), ("sphere", &sphere)] {
            let worst = worst_channel(&reference, &f.pixels);
            assert!(worst <= TOLERANCE, "{what}, {how} culling: differs from deferred by {worst}/255");
        }
    }
    common::assert_clean(&gpu);
}
