//! Clustered deferred end to end on the local device (lavapipe in CI), validation on:
//! the clustered image equals the brute-force deferred image (≤ 1/255 per channel after
//! tonemapping), the page-table compaction equals the sorted unique keys, every pixel's list
//! holds every light touching it, and the hard cases stay finite and equal.
mod common;
use common::pixels::{lit, worst_channel};
use common::render::{asset_scene, city, frame, render_error};
use common::scenes::hard_light_cases;
use host::gpu::Gpu;
use host::render::sort::SortKind;
use host::render::{reference, Frame, Settings, Technique};
use host::scene::{lights, Scene};
use shaders::layout::PointLight;
use shaders::octahedral::Precision;

/// The test settings with the read-back the CPU checks need.
fn settings(w: u32, h: u32, technique: Technique) -> Settings {
    Settings { read_back: true, ..common::render::settings(w, h, technique) }
}

/// Renders with the reference and both clustered techniques (naive, and BVH at branchings 32 and
/// 64 with the radix light sort, 32 with the bitonic one) and checks
/// what the clustered pipeline guarantees (`reference::check`: page-table compaction, complete
/// light lists); returns the naive clustered frame.
fn assert_equal_to_reference(gpu: &Gpu, scene: &Scene, lights: &[PointLight], w: u32, h: u32, what: &str) -> Frame {
    let reference = frame(gpu, scene, lights, &settings(w, h, Technique::Deferred));
    let mut frames = Vec::new();
    let runs = [
        (Technique::ClusteredNaive, 0, SortKind::Radix),
        (Technique::ClusteredBvh, 32, SortKind::Radix),
        (Technique::ClusteredBvh, 64, SortKind::Radix),
        (Technique::ClusteredBvh, 32, SortKind::Bitonic),
    ];
    for (technique, branching, sort) in runs {
        let clustered = frame(gpu, scene, lights, &Settings { bvh_branching: branching, sort, ..settings(w, h, technique) });
        let worst = worst_channel(&reference.pixels, &clustered.pixels);
        assert!(worst <= 1, "{what}, {technique:?} (branching {branching}, {sort:?} sort): differs from deferred by {worst}/255");
        reference::check(clustered.readback.as_ref().unwrap())
            .unwrap_or_else(|e| panic!("{what}, {technique:?} (branching {branching}, {sort:?} sort): {e:#}"));
        frames.push(clustered);
    }
    common::assert_clean(gpu);
    frames.swap_remove(0)
}

#[test]
fn city_1k_and_10k_lights_equal_the_reference() {
    let gpu = common::gpu();
    let scene = city();
    for n in [1_000, 10_000] {
        let l = lights::uniform(&scene, n, 7).unwrap();
        let f = assert_equal_to_reference(&gpu, &scene, &l, 192, 108, &format!("city {n}"));
        assert!(f.unique_clusters > 10 && f.light_refs > 0, "city {n}: {} clusters, {} refs", f.unique_clusters, f.light_refs);
        let lit = lit(&f.pixels);
        assert!(lit * 4 > f.pixels.len(), "city {n}: the frame should be mostly lit, {lit} of {} pixels", f.pixels.len());
    }
}

/// The glass scene through its stack (24 overlapping panes per pixel, drawn opaque until the
/// renderer has a transparent pass) renders like any other.
#[test]
fn glass_stack_equals_the_reference() {
    let gpu = common::gpu();
    let scene = Scene::load("glass@stack", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.has_transparency());
    let l = lights::uniform(&scene, 1_000, 29).unwrap();
    let f = assert_equal_to_reference(&gpu, &scene, &l, 96, 54, "glass@stack");
    assert!(lit(&f.pixels) * 4 > f.pixels.len(), "glass@stack: the frame should be mostly lit");
}

/// More lights than one lavapipe loop may iterate (65 535): the chunked light loops must still
/// visit every light (lavapipe's loop limiter once cut them off silently).
#[test]
fn seventy_thousand_lights_all_visited() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 70_000, 13).unwrap();
    assert_equal_to_reference(&gpu, &scene, &l, 48, 27, "city 70k");
}

/// The top of the light-count range the BVH is built for: 100 000 lights on city and Sponza, small
/// frames so the CPU references stay quick.
#[test]
fn hundred_thousand_lights_city_and_sponza() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 100_000, 19).unwrap();
    assert_equal_to_reference(&gpu, &scene, &l, 48, 27, "city 100k");
    if let Some(scene) = asset_scene("sponza") {
        let l = lights::uniform(&scene, 100_000, 23).unwrap();
        assert_equal_to_reference(&gpu, &scene, &l, 48, 27, "sponza 100k");
    }
}

/// Every G-buffer normal precision (float32 included: its 16-byte target and `_f32` fragment
/// variants) renders, every technique still equals deferred with it, and the read-back normals
/// are unit vectors within each encoding's proven bound of the float32 ones.
#[test]
fn normal_precisions() {
    use clap::ValueEnum;
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 500, 17).unwrap();
    let normals = |f: &Frame| f.readback.as_ref().unwrap().normals.clone();
    let depth = frame(&gpu, &scene, &l, &settings(64, 36, Technique::Deferred)).readback.unwrap().depth;
    let mut exact: Option<Vec<[f32; 3]>> = None;
    for precision in [Precision::F32, Precision::Oct8, Precision::Oct12, Precision::Oct16] {
        let s = |t| Settings { normal_precision: precision, ..settings(64, 36, t) };
        let reference = frame(&gpu, &scene, &l, &s(Technique::Deferred));
        for &t in Technique::value_variants() {
            let f = frame(&gpu, &scene, &l, &s(t));
            assert_eq!(f.pixels, reference.pixels, "precision {precision:?}, {t:?}");
        }
        let n = normals(&reference);
        assert_eq!(n.len(), 64 * 36, "precision {precision:?}: one normal per pixel");
        let bound = (precision.max_angular_error_bound() as f64).to_degrees();
        let exact = exact.get_or_insert_with(|| n.clone());
        let geometry: Vec<usize> = (0..n.len()).filter(|&i| f32::from_bits(depth[i]) > 0.0).collect();
        assert!(geometry.len() > 64 * 36 / 4, "the view must cover geometry");
        for i in geometry {
            let (a, b) = (glam::Vec3::from_array(n[i]).as_dvec3(), glam::Vec3::from_array(exact[i]).as_dvec3());
            assert!((a.length() - 1.0).abs() < 1e-5, "precision {precision:?}, pixel {i}: |n| = {}", a.length());
            let degrees = a.cross(b).length().atan2(a.dot(b)).to_degrees();
            // The bound plus the GPU's float32 rounding in the decode (≈2e-5°).
            assert!(degrees <= bound + 1e-4, "precision {precision:?}, pixel {i}: {degrees}° from float32 > bound {bound}°");
        }
    }
    // A scene flattened at one precision cannot be read at another.
    let err = render_error(&gpu, &scene, &l, Precision::Oct16, &Settings { normal_precision: Precision::F32, ..settings(64, 36, Technique::Deferred) });
    assert!(err.contains("precision"), "{err}");
    common::assert_clean(&gpu);
}

#[test]
fn page_table_compaction_at_odd_resolutions() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 300, 3).unwrap();
    for (w, h) in [(1, 1), (33, 17), (97, 61)] {
        assert_equal_to_reference(&gpu, &scene, &l, w, h, &format!("{w}x{h}"));
    }
}

/// The hard light cases (`common::scenes::hard_light_cases`; every technique's images are
/// compared in tests/hard_cases.rs): the clustered lists stay exact with every BVH variant.
#[test]
fn hard_cases_stay_finite_and_equal() {
    let gpu = common::gpu();
    let scene = city();
    for (what, l) in &hard_light_cases(&scene) {
        let f = assert_equal_to_reference(&gpu, &scene, l, 128, 72, what);
        if *what == "all lights at one point" {
            assert!(f.regrowths >= 1, "2000 coincident lights overflow the first light-list guess and must grow it");
        }
    }
}

/// A one-pixel frame (the 7680×4320 frame, on every technique, is in tests/hard_cases.rs).
#[test]
fn one_pixel_frame() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 64, 11).unwrap();
    assert_equal_to_reference(&gpu, &scene, &l, 1, 1, "1x1");
}

#[test]
fn bunny_and_sponza_when_present() {
    let gpu = common::gpu();
    for name in ["bunny", "sponza"] {
        let Some(scene) = asset_scene(name) else { continue };
        for n in [1_000, 10_000] {
            let l = lights::uniform(&scene, n, 5).unwrap();
            assert_equal_to_reference(&gpu, &scene, &l, 160, 90, &format!("{name} {n}"));
        }
    }
}
