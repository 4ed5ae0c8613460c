//! Clustered deferred end to end on the local device (lavapipe in CI), validation on:
//! the clustered image equals the brute-force deferred image (≤ 1/255 per channel after
//! tonemapping), the unique clusters (tile path and page table) equal the distinct keys, every pixel's list
//! holds every light touching it, and the hard cases stay finite and equal.
mod common;
use common::pixels::{lit, worst_channel};
use common::render::{asset_scene, city, frame, label, render_error, runs};
use common::scenes::hard_light_cases;
use host::gpu::Gpu;
use host::render::forward_plus::TileLists;
use host::render::sort::SortKind;
use host::render::transparent::OitVariant;
use host::render::clustered::UniqueClusters;
use host::render::{reference, Frame, Settings, Technique};
use host::scene::{lights, Directional, Scene};
use shaders::layout::PointLight;
use shaders::octahedral::Precision;

/// The test settings with the read-back the CPU checks need.
fn settings(w: u32, h: u32, technique: Technique) -> Settings {
    Settings { read_back: true, ..common::render::settings(w, h, technique) }
}

/// Renders with the reference and both clustered techniques (naive, and BVH at branchings 32 and
/// 64 with the radix light sort, 32 with the bitonic one; unique clusters found by tiles and by
/// the page table) and checks what the clustered pipeline guarantees (`reference::check`: the
/// unique clusters, complete light lists); returns the naive clustered frame (tile path).
fn assert_equal_to_reference(gpu: &Gpu, scene: &Scene, lights: &[PointLight], w: u32, h: u32, what: &str) -> Frame {
    assert_equal_to_reference_with(gpu, scene, lights, &settings(w, h, Technique::Deferred), what)
}

/// [`assert_equal_to_reference_with`] on a scene with transparent materials, plus the other
/// techniques with a transparent pass — `clustered-aabb` and `forward-plus` with both list
/// layouts — against the same reference (and every transparent fragment of `clustered-aabb`
/// found its cluster's list). Returns the naive clustered frame.
fn assert_transparent_equal_to_reference(gpu: &Gpu, scene: &Scene, lights: &[PointLight], base: &Settings, what: &str) -> Frame {
    assert!(scene.has_transparency(), "{what}: a scene with transparent materials");
    let naive = assert_equal_to_reference_with(gpu, scene, lights, base, what);
    let reference = frame(gpu, scene, lights, &Settings { technique: Technique::Deferred, ..base.clone() });
    for (technique, fp_lists) in [(Technique::ClusteredAabb, TileLists::Array), (Technique::ForwardPlus, TileLists::Linked), (Technique::ForwardPlus, TileLists::Array)] {
        let f = frame(gpu, scene, lights, &Settings { technique, fp_lists, ..base.clone() });
        let worst = worst_channel(&reference.pixels, &f.pixels);
        assert!(worst <= 1, "{what}, {technique:?} ({fp_lists:?} lists): differs from deferred by {worst}/255");
        let t = f.transparency.unwrap_or_else(|| panic!("{what}, {technique:?}: no transparent pass"));
        assert_eq!((t.fragments, t.unlisted), (reference.transparency.unwrap().fragments, 0), "{what}, {technique:?}: {t:?}");
    }
    common::assert_clean(gpu);
    naive
}

/// [`assert_equal_to_reference`] from settings `base` (its technique replaced by each run's).
fn assert_equal_to_reference_with(gpu: &Gpu, scene: &Scene, lights: &[PointLight], base: &Settings, what: &str) -> Frame {
    let settings = |_w: u32, _h: u32, technique: Technique| Settings { technique, ..base.clone() };
    let (w, h) = (base.width, base.height);
    let reference = frame(gpu, scene, lights, &settings(w, h, Technique::Deferred));
    let mut frames = Vec::new();
    let (tiles, pages) = (UniqueClusters::Tiles, UniqueClusters::PageTable);
    // (technique, branching, sort, unique clusters, Morton bits per axis; 0: the default)
    let runs = [
        (Technique::ClusteredNaive, 0, SortKind::Radix, tiles, 0),
        (Technique::ClusteredNaive, 0, SortKind::Radix, pages, 0),
        (Technique::ClusteredBvh, 32, SortKind::Radix, tiles, 0),
        (Technique::ClusteredBvh, 64, SortKind::Radix, pages, 0),
        (Technique::ClusteredBvh, 64, SortKind::Radix, tiles, 0),
        (Technique::ClusteredBvh, 32, SortKind::Bitonic, tiles, 0),
        (Technique::ClusteredBvh, 64, SortKind::Radix, tiles, 8),
        (Technique::ClusteredBvh, 64, SortKind::Radix, tiles, 2),
    ];
    for (technique, branching, sort, unique_clusters, morton_bits) in runs {
        let clustered = frame(gpu, scene, lights, &Settings { bvh_branching: branching, sort, unique_clusters, morton_bits, ..settings(w, h, technique) });
        let run = format!("{what}, {technique:?} (branching {branching}, {sort:?} sort, {unique_clusters:?}, Morton bits {morton_bits})");
        let worst = worst_channel(&reference.pixels, &clustered.pixels);
        assert!(worst <= 1, "{run}: differs from deferred by {worst}/255");
        reference::check(clustered.readback.as_ref().unwrap()).unwrap_or_else(|e| panic!("{run}: {e:#}"));
        frames.push(clustered);
    }
    // Both ways of finding the unique clusters give the same image.
    assert_eq!(frames[0].pixels, frames[1].pixels, "{what}: tile path and page table differ");
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
        // `--morton-bits` reaches the key kernel and the sort: 2 bits per axis (64 cells) order
        // the lights otherwise than 10, so the clusters list them in another order (the same
        // lights and image: `assert_equal_to_reference` runs both).
        let list = |morton_bits| {
            let s = Settings { morton_bits, bvh_branching: 64, sort: SortKind::Radix, read_back: true, ..common::render::settings(192, 108, Technique::ClusteredBvh) };
            frame(&gpu, &scene, &l, &s).readback.unwrap().list
        };
        assert_ne!(list(10), list(2), "city {n}: 2 and 10 Morton bits per axis list the lights in the same order");
        // `--light-order spatial` (`Scene::order_lights_spatially`): the same lights under other
        // indices: the same image within 1/255, and the same references once mapped back.
        let order = lights::spatial_order(&l);
        let mut spatial = scene.clone();
        spatial.lights = l.clone();
        spatial.order_lights_spatially();
        let s = Settings { bvh_branching: 64, sort: SortKind::Radix, read_back: true, ..common::render::settings(192, 108, Technique::ClusteredBvh) };
        let (given, moved) = (frame(&gpu, &scene, &l, &s), frame(&gpu, &scene, &spatial.lights, &s));
        let worst = worst_channel(&given.pixels, &moved.pixels);
        assert!(worst <= 1, "city {n}: the spatial order changes the image by {worst}/255");
        let (mut a, moved) = (given.readback.unwrap().list, moved.readback.unwrap().list);
        assert_ne!(a, moved, "city {n}: the spatial order lists the lights under the same indices");
        let mut b: Vec<u32> = moved.iter().map(|&k| order[k as usize]).collect();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "city {n}: the spatial order lists other lights");
        assert!(f.unique_clusters > 10 && f.light_refs > 0, "city {n}: {} clusters, {} refs", f.unique_clusters, f.light_refs);
        let lit = lit(&f.pixels);
        assert!(lit * 4 > f.pixels.len(), "city {n}: the frame should be mostly lit, {lit} of {} pixels", f.pixels.len());
    }
}

/// The glass scene through its stack (25 panes, 50 surfaces on the centre pixel): every technique
/// with a transparent pass, with `--oit exact`, equals the brute-force reference's transparent
/// pass (every light per fragment, exact OIT) within 1/255, and every transparent fragment found
/// its cluster's list (a fragment whose cluster the pre-pass did not mark is counted, and fails
/// here).
#[test]
fn glass_stack_equals_the_reference() {
    let gpu = common::gpu();
    let scene = Scene::load("glass@stack", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.has_transparency());
    let l = lights::uniform(&scene, 300, 29).unwrap();
    let s = Settings { oit: OitVariant::Exact, ..settings(96, 54, Technique::Deferred) };
    let f = assert_transparent_equal_to_reference(&gpu, &scene, &l, &s, "glass@stack");
    assert!(lit(&f.pixels) * 4 > f.pixels.len(), "glass@stack: the frame should be mostly lit");
    assert_transparent_fragments_listed(&f, "glass@stack");
}

/// Weighted blended OIT (`--oit weighted`, no lists): every technique with a transparent pass
/// equals the reference's weighted pass within 1/255 on the glass stack, and every fragment found its list.
#[test]
fn weighted_oit_equals_the_reference() {
    let gpu = common::gpu();
    let scene = Scene::load("glass@stack", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    let l = lights::uniform(&scene, 300, 29).unwrap();
    let s = Settings { oit: OitVariant::Weighted, ..settings(96, 54, Technique::Deferred) };
    let f = assert_transparent_equal_to_reference(&gpu, &scene, &l, &s, "glass@stack, weighted");
    let t = f.transparency.unwrap();
    assert!(t.fragments > 0 && t.unlisted == 0 && t.node_bytes == 0, "weighted: {t:?}");
}

/// The transparent pass ran, and every transparent fragment found its cluster's light list.
fn assert_transparent_fragments_listed(f: &Frame, what: &str) {
    let t = f.transparency.unwrap_or_else(|| panic!("{what}: no transparent pass"));
    assert!(t.fragments > 0 && t.max_layers > 0, "{what}: {t:?}");
    assert_eq!(t.unlisted, 0, "{what}: transparent fragments whose cluster has no light list: {t:?}");
    assert_eq!(t.fallbacks, 0, "{what}: pixels past the exact resolve's bound: {t:?}");
}

/// Sponza with translucent curtains (`assets/sponza-curtains.toml`), when the assets are present:
/// as the glass stack.
#[test]
fn sponza_curtains_equal_the_reference_when_present() {
    let gpu = common::gpu();
    if common::assets::asset("sponza").is_none() {
        return;
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/sponza-curtains.toml");
    let scene = Scene::load(path.to_str().unwrap(), &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(scene.has_transparency());
    let l = lights::uniform(&scene, 300, 5).unwrap();
    let s = Settings { oit: OitVariant::Exact, ..settings(96, 54, Technique::Deferred) };
    let f = assert_transparent_equal_to_reference(&gpu, &scene, &l, &s, "sponza-curtains");
    assert_transparent_fragments_listed(&f, "sponza-curtains");
}

/// The `--oit` knob reaches the resolve: on the glass stack (more than 8 layers on its centre
/// pixels) every variant gives another image; where no pixel has more than 8 layers (the glass
/// scene's street view with its shop windows only), `k8` equals `exact`.
#[test]
fn oit_variants_differ_and_k8_is_exact_up_to_8_layers() {
    let gpu = common::gpu();
    let dir = common::assets::dir();
    let stack = Scene::load("glass@stack", &dir).unwrap_or_else(|e| panic!("{e:#}"));
    let l = lights::uniform(&stack, 200, 3).unwrap();
    let images: Vec<(OitVariant, Frame)> =
        OitVariant::ALL.iter().map(|&oit| (oit, frame(&gpu, &stack, &l, &Settings { oit, ..settings(64, 36, Technique::ClusteredBvh) }))).collect();
    let layers = images[0].1.transparency.unwrap().max_layers;
    assert!(layers > 8, "glass@stack: the centre pixels hold {layers} layers, more than k = 8");
    for (i, (a, fa)) in images.iter().enumerate() {
        for (b, fb) in &images[i + 1..] {
            assert_ne!(fa.pixels, fb.pixels, "glass@stack: --oit {} and {} give one image", a.name(), b.name());
        }
    }
    let street = shop_windows_only(Scene::load("glass", &dir).unwrap_or_else(|e| panic!("{e:#}")));
    let l = lights::uniform(&street, 200, 3).unwrap();
    let exact = frame(&gpu, &street, &l, &Settings { oit: OitVariant::Exact, ..settings(64, 36, Technique::ClusteredBvh) });
    let t = exact.transparency.unwrap();
    assert!(t.max_layers > 1 && t.max_layers <= 8, "glass: {t:?}");
    let k8 = frame(&gpu, &street, &l, &Settings { oit: OitVariant::K8, ..settings(64, 36, Technique::ClusteredBvh) });
    assert_eq!(k8.pixels, exact.pixels, "glass: k8 differs from exact with at most {} layers", t.max_layers);
    common::assert_clean(&gpu);
}

/// The glass scene without the panes that cross the avenue (the stack among them): of its
/// transparent triangles, only those of the shop windows (thin in x, short of the stack).
fn shop_windows_only(mut scene: Scene) -> Scene {
    let transparent: Vec<bool> = scene.materials.iter().map(|m| m.is_transparent()).collect();
    for m in scene.meshes.iter_mut().filter(|m| transparent[m.material as usize]) {
        let p = &m.positions;
        let window = |t: &[u32]| {
            let xs = t.iter().map(|&i| p[i as usize][0]);
            let (lo, hi) = xs.fold((f32::MAX, f32::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
            hi - lo < 1.0 && lo.abs() > 3.5 && t.iter().all(|&i| p[i as usize][2] < 230.0)
        };
        m.indices = m.indices.chunks(3).filter(|t| window(t)).flatten().copied().collect();
    }
    scene
}

/// The heatmap view with transparent surfaces: each transparent fragment shows its own list's
/// length, composited like its shaded colour.
/// 1. Lights whose spheres hold the whole scene: every list of every technique holds all of them,
///    so every layer's colour is the ramp's colour of that count (below the ramp's top), and so is
///    their composite on every pixel with opaque geometry behind the glass (a fragment shown with
///    a shorter list, or none, would tint the pixel).
/// 2. Lights of the usual size: each technique's heatmap changes where the glass covers the frame
///    (pixels whose shaded colour the glass changes), and the clustered ones — lists per cluster:
///    the glass adds clusters and changes none — keep every pixel it does not cover.
#[test]
fn heatmap_shows_the_transparent_fragments_lists() {
    use shaders::layout::View;
    let gpu = common::gpu();
    let glass = Scene::load("glass@stack", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    let mut bare = glass.clone();
    let transparent: Vec<bool> = bare.materials.iter().map(|m| m.is_transparent()).collect();
    for m in bare.meshes.iter_mut().filter(|m| transparent[m.material as usize]) {
        m.indices.clear();
    }
    let techniques: Vec<Technique> = Technique::ALL.iter().copied().filter(|t| t.draws_transparency()).collect();
    let s = |technique, view| Settings { technique, view, oit: OitVariant::Exact, ..settings(64, 36, Technique::Deferred) };
    // 1.
    let mut huge = lights::uniform(&glass, 40, 3).unwrap();
    for l in &mut huge {
        l.radius = 1.0e5;
    }
    let all = shaders::lighting::encode_srgb8(shaders::lighting::heat_ramp(huge.len() as u32, host::render::HEAT_MAX));
    for &technique in &techniques {
        let heat = frame(&gpu, &glass, &huge, &s(technique, View::Heatmap));
        assert!(heat.transparency.unwrap().max_layers > 8, "{technique:?}: the stack's layers");
        let depth = &heat.readback.as_ref().unwrap().depth;
        let geometry: Vec<usize> = (0..depth.len()).filter(|&i| !shaders::reconstruct::is_background(f32::from_bits(depth[i]))).collect();
        assert!(geometry.len() * 2 > depth.len(), "{technique:?}: mostly geometry");
        let worst = geometry.iter().map(|&i| worst_channel(&[heat.pixels[i]], &[all])).max().unwrap();
        assert!(worst <= 1, "{technique:?}: a pixel's heat differs from {all:08x} (every light in every list) by {worst}/255");
    }
    // 2.
    let l = lights::uniform(&glass, 200, 3).unwrap();
    let shaded = frame(&gpu, &glass, &l, &s(Technique::Deferred, View::Shaded));
    let covered: Vec<bool> = shaded.pixels.iter().zip(&frame(&gpu, &bare, &l, &s(Technique::Deferred, View::Shaded)).pixels).map(|(a, b)| a != b).collect();
    assert!(covered.iter().filter(|&&c| c).count() * 4 > covered.len(), "glass@stack: the glass covers much of the frame");
    for &technique in &techniques {
        let with = frame(&gpu, &glass, &l, &s(technique, View::Heatmap));
        let without = frame(&gpu, &bare, &l, &s(technique, View::Heatmap));
        let changed: Vec<bool> = with.pixels.iter().zip(&without.pixels).map(|(a, b)| a != b).collect();
        assert!(changed.iter().zip(&covered).any(|(&c, &cov)| c && cov), "{technique:?}: the glass's lists do not show");
        if technique != Technique::ForwardPlus {
            let stray = changed.iter().zip(&covered).filter(|(&c, &cov)| c && !cov).count();
            assert_eq!(stray, 0, "{technique:?}: heatmap pixels the glass does not cover changed");
        }
    }
    common::assert_clean(&gpu);
}

/// Only what the scene calls for: a scene without transparent materials records no transparent
/// pass and allocates no OIT buffer (the stats file), one with them records both; the node
/// buffer grows when the frame's fragments do not fit.
#[test]
fn transparent_pass_only_where_the_scene_has_transparency() {
    let gpu = common::gpu();
    let stats = |scene: &Scene, l: &[PointLight], f: &Frame, s: &Settings| host::render::stats::stats_json(&gpu.ctx.info, &scene.name, l.len(), s, f);
    let s = Settings { read_back: true, ..settings(64, 36, Technique::ClusteredBvh) };
    let city = city();
    let l = lights::uniform(&city, 200, 3).unwrap();
    let f = frame(&gpu, &city, &l, &s);
    let j = stats(&city, &l, &f, &s);
    let passes = j["gpu_ms"]["passes"].as_object().unwrap();
    assert!(passes.keys().all(|p| p != "transparent" && p != "oit resolve"), "city: passes {:?}", passes.keys());
    let buffers = j["bytes"]["buffers"].as_object().unwrap();
    assert!(buffers.keys().all(|b| !b.starts_with("oit")), "city: buffers {:?}", buffers.keys());
    assert!(j["transparency"].is_null() && j["oit"].is_null(), "city: {j}");
    let glass = Scene::load("glass@stack", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    let l = lights::uniform(&glass, 200, 3).unwrap();
    let f = frame(&gpu, &glass, &l, &s);
    let j = stats(&glass, &l, &f, &s);
    let passes = j["gpu_ms"]["passes"].as_object().unwrap();
    assert!(passes.contains_key("transparent") && passes.contains_key("oit resolve"), "glass: passes {:?}", passes.keys());
    let t = f.transparency.unwrap();
    assert_eq!(j["bytes"]["buffers"]["oit nodes"].as_u64(), Some(t.node_bytes), "glass: {j}");
    assert_eq!(j["transparency"]["fragments"].as_u64(), Some(t.fragments as u64));
    assert_eq!(j["oit"], "k4", "the default resolve");
    assert!(16 * t.fragments as u64 <= t.node_bytes, "every fragment has a node: {t:?}");
    // 64×36 pixels start with 2 nodes each (4608); the stack needs more, so the buffer grew.
    assert!(f.regrowths >= 1 && t.fragments > 2 * 64 * 36, "glass@stack: {t:?}, {} regrowths", f.regrowths);
    common::assert_clean(&gpu);
}

/// Every registered technique either draws a transparent scene's transparent meshes or refuses
/// the scene: one that draws records a transparent pass whose fragments cover the panes (the
/// frame differs from the scene without them on the panes' pixels), one that refuses names itself
/// and the materials in one line instead of drawing them opaque or leaving them out.
#[test]
fn techniques_without_a_transparent_pass_refuse_transparent_scenes() {
    let gpu = common::gpu();
    let glass = Scene::load("glass", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    let mut bare = glass.clone();
    let transparent: Vec<bool> = bare.materials.iter().map(|m| m.is_transparent()).collect();
    for m in bare.meshes.iter_mut().filter(|m| transparent[m.material as usize]) {
        m.indices.clear();
    }
    let l = lights::uniform(&glass, 50, 3).unwrap();
    for &t in Technique::ALL {
        let s = settings(32, 18, t);
        if t.draws_transparency() {
            let f = frame(&gpu, &glass, &l, &s);
            let fragments = f.transparency.map_or(0, |tr| tr.fragments);
            assert!(fragments > 0, "{t:?}: draws transparency but its frame drew no transparent fragment");
            let without = frame(&gpu, &bare, &l, &s);
            assert!(worst_channel(&f.pixels, &without.pixels) > 8, "{t:?}: the panes do not show in the frame");
            continue;
        }
        let err = render_error(&gpu, &glass, &l, Precision::Oct16, &s);
        assert!(err.contains(t.name()) && err.contains("\"pane red\" (opacity 0.35)") && !err.contains('\n'), "{t:?}: {err}");
    }
    common::assert_clean(&gpu);
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

/// Spot and directional lights: every technique equals the brute-force reference within 1/255 on
/// the city with half of 300 lights spots (and the other half points in the same scene) and two
/// directional lights; the cones cut light (the frame differs from the same lights as points,
/// and is nowhere brighter) and the directional lights add light where the punctual ones do not
/// reach.
#[test]
fn spot_and_directional_lights_equal_the_reference() {
    let gpu = common::gpu();
    let base = city();
    let l = lights::uniform(&base, 300, 11).unwrap();
    let mut points = base.clone();
    points.lights = l.clone();
    let mut spots = base.clone();
    spots.add_lights(l.iter().copied().zip(lights::spot_cones(l.len(), 0.5, 11).unwrap()));
    let n_spots = spots.spots.iter().flatten().count();
    assert!(spots.spots.len() == l.len() && n_spots * 3 > l.len() && n_spots * 3 < 2 * l.len(), "about half the lights are spots: {n_spots}");
    let mut all = spots.clone();
    all.directional = vec![
        Directional { direction: glam::Vec3::new(0.3, -1.0, 0.2), colour: [1.0, 0.95, 0.9], intensity: 0.5 },
        Directional { direction: glam::Vec3::new(-0.5, -0.3, -1.0), colour: [0.3, 0.4, 1.0], intensity: 0.25 },
    ];
    let s = |(technique, fp_lists)| Settings { technique, fp_lists, ..common::render::settings(160, 90, technique) };
    let deferred = |scene: &Scene| frame(&gpu, scene, &scene.lights, &s((Technique::Deferred, TileLists::Array)));
    let (reference, point_frame, spot_frame) = (deferred(&all), deferred(&points), deferred(&spots));
    for run in runs(Technique::ALL) {
        for (scene, what, want) in [(&spots, "spot lights", &spot_frame), (&all, "spots and directional lights", &reference)] {
            let f = frame(&gpu, scene, &scene.lights, &s(run));
            let worst = worst_channel(&want.pixels, &f.pixels);
            assert!(worst <= 1, "{}, {what}: differs from deferred by {worst}/255", label(run));
        }
    }
    let luma = |p: u32| (p & 255) + ((p >> 8) & 255) + ((p >> 16) & 255);
    let darker = spot_frame.pixels.iter().zip(&point_frame.pixels).filter(|(a, b)| luma(**a) + 3 < luma(**b)).count();
    let brighter = spot_frame.pixels.iter().zip(&point_frame.pixels).filter(|(a, b)| luma(**a) > luma(**b) + 3).count();
    assert!(darker * 50 > spot_frame.pixels.len() && brighter == 0, "the cones cut light: {darker} pixels darker, {brighter} brighter");
    let (with_sun, without) = (lit(&reference.pixels), lit(&spot_frame.pixels));
    assert!(with_sun > without + reference.pixels.len() / 10, "directional lights light more of the frame: {with_sun} lit pixels, {without} without them");
    common::assert_clean(&gpu);
}

/// Spot lights culled by their cones in `clustered-naive` and `clustered-bvh` (every branching and
/// sort of [`assert_equal_to_reference`]; the other techniques in
/// `spot_and_directional_lights_equal_the_reference`): the frames equal the reference, every cluster list
/// equals the CPU's naive search with the cone test and holds every light whose cone reaches a
/// pixel of the cluster (`reference::check`), and the lists are shorter than the same lights'
/// as points, and so are the longest lists of `tiled` and `tiled-2.5d` and the references of
/// `clustered-aabb`.
#[test]
fn clustered_techniques_cull_spot_lights_by_their_cones() {
    let gpu = common::gpu();
    let base = city();
    let l = lights::uniform(&base, 1_000, 5).unwrap();
    let mut spots = base.clone();
    spots.add_lights(l.iter().copied().zip(lights::spot_cones(l.len(), 0.7, 5).unwrap()));
    let mut points = base.clone();
    points.lights = l.clone();
    let with_cones = assert_equal_to_reference(&gpu, &spots, &spots.lights, 160, 90, "spots");
    let as_points = frame(&gpu, &points, &points.lights, &settings(160, 90, Technique::ClusteredNaive));
    assert!(
        with_cones.light_refs * 10 < as_points.light_refs * 9,
        "cone culling: {} light references with spots, {} with the same lights as points",
        with_cones.light_refs,
        as_points.light_refs
    );
    // The tile and cluster-box techniques cull by cone too: their longest tile lists and the
    // cluster boxes' references shrink.
    for t in [Technique::Tiled, Technique::Tiled25d, Technique::ClusteredAabb] {
        let (a, b) = (frame(&gpu, &spots, &spots.lights, &settings(160, 90, t)), frame(&gpu, &points, &points.lights, &settings(160, 90, t)));
        let (a, b) = if t == Technique::ClusteredAabb { (a.light_refs, b.light_refs) } else { (a.max_list, b.max_list) };
        assert!(a < b, "{t:?}: {a} light references (longest list for tiles) with spots, {b} as points");
    }
}

/// Transparency against the closed form of "over", end to end on the GPU: a wall behind `n`
/// coincident panes of coverage α (one pane of α = ½; 50 of α = 0.1), both lit only by a
/// directional light travelling along the view axis, the panes filling the view. A pane's
/// colour is then the CPU's `shade_directional` of its material (albedo quantised to 8 bits, as
/// the pass does) tonemapped, `c`; the wall's `B` is read from the frame without the panes; every
/// pixel must be `c·(1 − (1 − α)^n) + B·(1 − α)^n` within 1/255 after the sRGB encoding, for every
/// technique that draws transparency, with the exact and the k-nearest resolves.
#[test]
fn coincident_panes_compose_to_the_closed_form() {
    use shaders::lighting::{decode_srgb8, encode_srgb8, shade_directional, tonemap};
    let gpu = common::gpu();
    let dir = common::temp::TempDir::new("closed-form-panes");
    let albedo = [0.6f32, 0.5, 0.4];
    let quad = |z: f32, s: f32, base: usize| format!("v {} {} {z}\nv {s} {} {z}\nv {s} {s} {z}\nv {} {s} {z}\nf {} {} {} {}\n", -s, -s, -s, -s, base + 1, base + 2, base + 3, base + 4);
    for (n, alpha) in [(1usize, 0.5f32), (50, 0.1)] {
        let mtl = format!("newmtl wall\nKd 0.5 0.5 0.5\nKs 0 0 0\nnewmtl pane\nKd {} {} {}\nKs 0 0 0\nd {alpha}\n", albedo[0], albedo[1], albedo[2]);
        dir.write("panes.mtl", &mtl);
        let mut obj = String::from("mtllib panes.mtl\nusemtl wall\n") + &quad(-10.0, 40.0, 0);
        let bare_obj = obj.clone();
        obj += "usemtl pane\n";
        for k in 0..n {
            obj += &quad(-5.0, 20.0, 4 * (k + 1));
        }
        dir.write("panes.obj", &obj);
        dir.write("wall.obj", &bare_obj);
        let toml = |geometry: &str| {
            format!(
                "geometry = \"{geometry}\"\n[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, -1]\nup = [0, 1, 0]\nfov_y = 60\nnear = 0.1\nfar = 100\n\
                 [[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\ncolour = [1, 0.9, 0.8]\nintensity = 2\n"
            )
        };
        let load = |name: &str, geometry: &str| Scene::load(dir.write(name, &toml(geometry)).to_str().unwrap(), &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
        let (panes, wall) = (load("panes.toml", "panes.obj"), load("wall.toml", "wall.obj"));
        assert!(panes.has_transparency() && !wall.has_transparency());
        // The pane's colour: the pass's surface (normal +z towards the camera, albedo in 8 bits).
        let q = albedo.map(shaders::raster::unorm8);
        let d = &panes.directional[0];
        let radiance = shade_directional::<false>(glam::Vec3::new(0.0, 0.0, -5.0), glam::Vec3::Z, glam::Vec3::from_array(q), 0.0, 0.5, -d.direction.normalize(), glam::Vec3::from_array(d.colour), d.intensity, 0);
        let c = tonemap(radiance, 1.0).to_array().map(f64::from);
        let t = (1.0 - alpha as f64).powi(n as i32);
        for &technique in Technique::ALL.iter().filter(|t| t.draws_transparency()) {
            for oit in [OitVariant::Exact, OitVariant::K4, OitVariant::K1] {
                let s = Settings { oit, ..settings(64, 36, technique) };
                let b = frame(&gpu, &wall, &wall.lights, &s).pixels;
                let got = frame(&gpu, &panes, &panes.lights, &s).pixels;
                let worst = b
                    .iter()
                    .zip(&got)
                    .map(|(&bw, &g)| {
                        let bl = decode_srgb8(bw).to_array().map(f64::from);
                        let want = encode_srgb8(glam::Vec3::from_array(core::array::from_fn(|k| (c[k] * (1.0 - t) + bl[k] * t) as f32)));
                        worst_channel(&[g], &[want])
                    })
                    .max()
                    .unwrap();
                assert!(worst <= 1, "{technique:?}, {oit:?}: {n} pane(s) of α {alpha} are {worst}/255 off the closed form");
            }
        }
    }
    common::assert_clean(&gpu);
}
