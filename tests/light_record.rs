//! Compact light records (`--light-record compact`, `shaders::compact_light`) on the local device
//! (lavapipe in CI), validation on: every technique equals brute force with the same records and
//! brute force equals the CPU's shading of the decoded lights; the record is a knob that reaches
//! the kernels (a far light coarsens the records' position grid, and every technique's image shows
//! it); compact frames create only the compact pipelines; scenes with spot or
//! directional lights are refused in one line.
mod common;
use common::compare::{assert_every_technique_equals_deferred, cpu_shaded, TOLERANCE};
use common::pixels::worst_channel;
use common::render::{city, frame, render_error};
use host::render::light_record::LightRecord;
use host::render::{Settings, Technique};
use host::scene::{lights, Directional};
use shaders::compact_light::EFFECT_COMPACT_LIGHTS;
use shaders::layout::PointLight;
use shaders::light_types::light_type_variant;
use shaders::octahedral::Precision;
use std::collections::BTreeSet;

const W: u32 = 160;
const H: u32 = 90;

fn settings(technique: Technique, record: LightRecord) -> Settings {
    Settings { read_back: true, light_record: record, ..common::render::settings(W, H, technique) }
}

#[test]
fn every_technique_with_compact_records_equals_the_reference() {
    let gpu = common::gpu();
    let mut scene = city();
    scene.lights = lights::uniform(&scene, 1500, 5).unwrap();
    let s = settings(Technique::Deferred, LightRecord::Compact);
    let reference = assert_every_technique_equals_deferred(&gpu, &scene, &scene.lights, &s, "compact records");
    // The read-back lights are the decoded ones (what the kernels saw), not the scene's.
    let rb = reference.readback.as_ref().unwrap();
    assert_ne!(rb.lights_view, frame(&gpu, &scene, &scene.lights, &settings(Technique::Deferred, LightRecord::Full)).readback.unwrap().lights_view);
    let worst = worst_channel(&reference.pixels, &cpu_shaded(&scene, &reference, &s));
    assert!(worst <= TOLERANCE, "deferred with compact records differs from the CPU's shading of the decoded lights by {worst}/255");
    // And from full records by no more than the quantisation: within 1/255 here.
    let full = frame(&gpu, &scene, &scene.lights, &settings(Technique::Deferred, LightRecord::Full));
    let worst = worst_channel(&reference.pixels, &full.pixels);
    assert!(worst <= 1, "compact records move the image by {worst}/255 against full records");
    common::assert_clean(&gpu);
}

/// 200 lights over the city and one far outside it (radius 1: it lights nothing). The far light
/// stretches the compact records' position grid to a step of ~2 % of the city's diagonal, so
/// every light the image shows moves by up to half a step: full and compact records render the
/// same scene visibly differently, through every technique — the record reaches each kernel that
/// reads lights (and each decodes the same positions: the first test holds them to `deferred`).
#[test]
fn the_light_record_reaches_every_kernel() {
    let gpu = common::gpu();
    let mut scene = city();
    let diag = (scene.bounds.1 - scene.bounds.0).length();
    let mut l = lights::uniform(&scene, 200, 4).unwrap();
    let far = scene.bounds.1 + glam::Vec3::splat(0.02 * diag * shaders::compact_light::POSITION_MAX as f32);
    l.push(PointLight { position: far.to_array(), radius: 1.0, colour: [1.0; 3], intensity: 1.0 });
    scene.lights = l;
    for &t in Technique::ALL {
        let full = frame(&gpu, &scene, &scene.lights, &settings(t, LightRecord::Full));
        let compact = frame(&gpu, &scene, &scene.lights, &settings(t, LightRecord::Compact));
        let (fl, cl) = (&full.readback.as_ref().unwrap().lights_view, &compact.readback.as_ref().unwrap().lights_view);
        let moved = fl.iter().zip(cl).map(|(a, b)| (glam::Vec3::from(a.position) - glam::Vec3::from(b.position)).length()).fold(0.0f32, f32::max);
        assert!(moved > 0.002 * diag && moved < 0.04 * diag, "{t:?}: decoded lights moved by up to {moved} (diagonal {diag})");
        assert_eq!((full.light_moved, compact.light_moved), (0.0, moved), "{t:?}: the frame reports how far the lights moved");
        let changed = full.pixels.iter().zip(&compact.pixels).filter(|(a, b)| a != b).count();
        assert!(changed > (W * H / 20) as usize, "{t:?}: full and compact records differ in only {changed} pixels");
    }
    common::assert_clean(&gpu);
}

/// Compact frames create the compact point-light pipelines only (the full-record variant 0 runs
/// no decode, the compact one no cone or directional code).
#[test]
fn compact_frames_create_only_the_compact_pipelines() {
    let gpu = common::gpu();
    let mut scene = city();
    scene.lights = lights::uniform(&scene, 200, 9).unwrap();
    for &t in Technique::ALL {
        frame(&gpu, &scene, &scene.lights, &settings(t, LightRecord::Compact));
    }
    assert_eq!(gpu.light_type_variants(), BTreeSet::from([light_type_variant(EFFECT_COMPACT_LIGHTS)]));
    common::assert_clean(&gpu);
}

#[test]
fn compact_records_refuse_spot_and_directional_lights_in_one_line() {
    let gpu = common::gpu();
    let base = city();
    let l = lights::uniform(&base, 50, 2).unwrap();
    let mut spots = base.clone();
    spots.add_lights(l.iter().copied().zip(lights::spot_cones(l.len(), 0.5, 2).unwrap()));
    let mut sun = base.clone();
    sun.lights = l.clone();
    sun.directional = vec![Directional { direction: glam::Vec3::NEG_Y, colour: [1.0; 3], intensity: 0.5 }];
    for scene in [&spots, &sun] {
        let e = render_error(&gpu, scene, &scene.lights, Precision::Oct16, &settings(Technique::ClusteredBvh, LightRecord::Compact));
        assert!(e.starts_with("--light-record compact holds point lights only") && !e.contains('\n'), "{e}");
    }
    common::assert_clean(&gpu);
}
