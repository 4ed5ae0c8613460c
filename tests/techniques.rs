//! Every registered technique but `deferred` and the two that read `--unique-clusters` (those
//! run with each of its values in `tests/render.rs`) — `tiled`, `tiled-2.5d`, `clustered-aabb`,
//! `forward-plus` with both layouts of its tile lists (`--fp-lists linked|array`) and any technique
//! registered later — on the local device (lavapipe in CI),
//! validation on: each image equals the brute-force `deferred` reference (≤ 1/255 per channel
//! after tonemapping) on city and Sponza at 1k and 10k lights, on a view with a large depth
//! discontinuity, and when a fixed capacity overflows (2000 coincident lights: the tiled list
//! takes several rounds, the clustered and Forward+ list buffers grow and the frame re-runs, a
//! Forward+ tile array outgrows its culling workgroup's staging list); Forward+'s two layouts
//! give the same image and hold the same lists per tile.
mod common;
use common::pixels::{lit, worst_channel};
use common::render::{asset_scene, city, frame, label, render_error, runs, Run};
use host::gpu::Gpu;
use host::render::forward_plus::TileLists;
use host::render::{Frame, Knob, Settings, Technique};
use std::collections::BTreeSet;
use host::scene::{lights, view_camera, Scene};
use shaders::layout::{PointLight, View};
use shaders::octahedral::Precision;

/// Every technique of this file (module docs), from the registry; Forward+ with each layout of
/// its tile lists.
fn runs_here() -> Vec<Run> {
    let here: Vec<Technique> = Technique::ALL.iter().copied().filter(|&t| t != Technique::Deferred && !t.reads(Knob::UniqueClusters)).collect();
    runs(&here)
}

/// The test settings with `tile_size` px tiles.
fn settings(w: u32, h: u32, technique: Technique, tile_size: u32) -> Settings {
    Settings { tile_size, ..common::render::settings(w, h, technique) }
}

/// [`settings`] of a run.
fn run_settings(w: u32, h: u32, (technique, fp_lists): Run, tile_size: u32) -> Settings {
    Settings { fp_lists, ..settings(w, h, technique, tile_size) }
}


/// Renders the reference and every run (16 px tiles, the tiled default of the papers) and
/// asserts equality; returns the frames in [`runs_here`] order.
fn assert_equal_to_reference(gpu: &Gpu, scene: &Scene, lights: &[PointLight], w: u32, h: u32, what: &str) -> Vec<Frame> {
    assert_equal_for(gpu, scene, lights, w, h, what, &runs_here())
}

/// As [`assert_equal_to_reference`] for the given runs; where both Forward+ layouts ran, their
/// images also agree within 1/255 (the array sums a tile's lights in index order, the linked list
/// in the order its atomics ran).
fn assert_equal_for(gpu: &Gpu, scene: &Scene, lights: &[PointLight], w: u32, h: u32, what: &str, runs: &[Run]) -> Vec<Frame> {
    let reference = frame(gpu, scene, lights, &settings(w, h, Technique::Deferred, 16));
    let lit = lit(&reference.pixels);
    assert!(lit * 10 > reference.pixels.len(), "{what}: the reference should be lit ({lit} of {} pixels)", reference.pixels.len());
    let frames: Vec<Frame> = runs
        .iter()
        .map(|&run| {
            let f = frame(gpu, scene, lights, &run_settings(w, h, run, 16));
            let worst = worst_channel(&reference.pixels, &f.pixels);
            assert!(worst <= 1, "{what}, {}: differs from deferred by {worst}/255", label(run));
            f
        })
        .collect();
    let forward = |lists| runs.iter().position(|&r| r == (Technique::ForwardPlus, lists)).map(|i| &frames[i]);
    if let (Some(linked), Some(array)) = (forward(TileLists::Linked), forward(TileLists::Array)) {
        let worst = worst_channel(&linked.pixels, &array.pixels);
        assert!(worst <= 1, "{what}: forward+ with array lists differs from linked lists by {worst}/255");
    }
    common::assert_clean(gpu);
    frames
}

/// City at 1k and 10k lights; the lists must cull (fewer references than tiles × lights).
#[test]
fn city_1k_and_10k_lights_equal_the_reference() {
    let gpu = common::gpu();
    let scene = city();
    for n in [1_000, 10_000] {
        let l = lights::uniform(&scene, n, 7).unwrap();
        for (run, f) in runs_here().into_iter().zip(assert_equal_to_reference(&gpu, &scene, &l, 160, 90, &format!("city {n}"))) {
            let tiles = 10 * 6;
            assert!(f.light_refs > 0 && (f.light_refs as usize) < tiles * n / 2, "city {n}, {}: {} light references", label(run), f.light_refs);
        }
    }
}

#[test]
fn sponza_1k_and_10k_lights_equal_the_reference() {
    let Some(scene) = asset_scene("sponza") else { return };
    let gpu = common::gpu();
    for n in [1_000, 10_000] {
        let l = lights::uniform(&scene, n, 5).unwrap();
        assert_equal_to_reference(&gpu, &scene, &l, 160, 90, &format!("sponza {n}"));
    }
}

/// The widest ratio of far to near depth within one 16 px tile of a frame's depth buffer.
fn widest_tile_depth_ratio(depth: &[u32], w: u32, h: u32) -> f32 {
    let mut widest = 0.0f32;
    for ty in 0..h / 16 {
        for tx in 0..w / 16 {
            let z: Vec<f32> = (0..256).map(|q| f32::from_bits(depth[((ty * 16 + q / 16) * w + tx * 16 + q % 16) as usize])).filter(|&z| z > 0.0).collect();
            // Reversed-Z: distance ratio far/near = z_max / z_min.
            if let (Some(lo), Some(hi)) = (z.iter().cloned().reduce(f32::min), z.iter().cloned().reduce(f32::max)) {
                widest = widest.max(hi / lo);
            }
        }
    }
    widest
}

/// Equality on a view whose tiles span near and far geometry (checked: some 16 px tile spans a
/// 20× depth ratio); the 2.5D mask culls at least as much as the frustum alone there.
fn assert_discontinuity_view(gpu: &Gpu, scene: &Scene, l: &[PointLight], what: &str) {
    let (w, h) = (160, 90);
    let frames = assert_equal_to_reference(gpu, scene, l, w, h, what);
    let depth = frame(gpu, scene, l, &Settings { read_back: true, ..settings(w, h, Technique::Deferred, 16) }).readback.unwrap().depth;
    let widest = widest_tile_depth_ratio(&depth, w, h);
    assert!(widest > 20.0, "{what}: some tile should span a 20x depth ratio, the widest spans {widest}");
    assert!(frames[1].light_refs <= frames[0].light_refs, "{what}: 2.5D keeps {} refs, tiled {}", frames[1].light_refs, frames[0].light_refs);
}

#[test]
fn depth_discontinuity_views_equal_the_reference() {
    let gpu = common::gpu();
    let mut scene = city();
    scene.camera = view_camera("city", "corner").unwrap();
    // Lights along the avenue and around the corner, plus uniform ones.
    let mut l = lights::uniform(&scene, 3_000, 21).unwrap();
    l.extend((0..200).map(|i| PointLight {
        position: [3.0 + (i % 10) as f32 * 1.5, 0.5 + (i % 3) as f32, 8.0 - (i / 10) as f32 * 6.0],
        radius: 6.0,
        colour: [1.0, 0.8, 0.6],
        intensity: 3.0,
    }));
    assert_discontinuity_view(&gpu, &scene, &l, "city corner");
    let Some(mut sponza) = asset_scene("sponza") else { return };
    sponza.camera = view_camera("sponza", "column").unwrap();
    let l = lights::uniform(&sponza, 10_000, 23).unwrap();
    assert_discontinuity_view(&gpu, &sponza, &l, "sponza column");
}

/// 2000 lights at one point: more than a tile list holds (several rounds), more references than
/// the clustered and Forward+ lists' first guess (they grow and the frame re-runs), and more
/// than a Forward+ culling workgroup stages before it reserves its tile's array (the lights past
/// the stage are culled a second time).
#[test]
fn coincident_lights_overflow_and_stay_exact() {
    let gpu = common::gpu();
    let scene = city();
    let fwd = (scene.camera.target - scene.camera.position).normalize();
    let at = (scene.camera.position + fwd * 25.0).to_array();
    let l: Vec<PointLight> = (0..2000).map(|_| PointLight { position: at, radius: 15.0, colour: [1.0, 0.9, 0.8], intensity: 0.05 }).collect();
    let frames = assert_equal_to_reference(&gpu, &scene, &l, 128, 72, "2000 coincident lights");
    for (run, f) in runs_here().into_iter().zip(&frames) {
        let t = label(run);
        match run.0 {
            Technique::Tiled | Technique::Tiled25d => assert!(
                f.max_list > shaders::tiled::LIST_CAPACITY,
                "{t}: the longest tile list ({}) should exceed the {}-entry workgroup list",
                f.max_list,
                shaders::tiled::LIST_CAPACITY
            ),
            _ => assert!(f.regrowths >= 1, "{t}: the light list should have grown"),
        }
        if run.0 == Technique::ForwardPlus {
            let stage = shaders::forward_plus::STAGE_CAPACITY;
            assert!(f.max_list > stage, "{t}: the longest tile list ({}) should exceed the {stage}-entry staging list", f.max_list);
        }
    }
}

/// Tile sizes 8 and 32 (1 and 4 pixels per invocation) and odd resolutions with partial tiles.
#[test]
fn tile_sizes_and_odd_resolutions() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 500, 3).unwrap();
    for (w, h, tile) in [(97, 61, 8), (97, 61, 32), (33, 17, 16), (1, 1, 16)] {
        let reference = frame(&gpu, &scene, &l, &settings(w, h, Technique::Deferred, tile));
        for run in runs_here() {
            let f = frame(&gpu, &scene, &l, &run_settings(w, h, run, tile));
            let worst = worst_channel(&reference.pixels, &f.pixels);
            assert!(worst <= 1, "{w}x{h}, {tile} px tiles, {}: differs from deferred by {worst}/255", label(run));
        }
    }
    common::assert_clean(&gpu);
}

/// More lights than one lavapipe loop may iterate (65 535): the batched culling and the 16-wide
/// light loops must still visit every light (lavapipe's loop limiter drops the rest silently).
/// Forward+ shades its lists one light per iteration, so lavapipe refuses it such a frame (with
/// either layout).
#[test]
fn seventy_thousand_lights_all_visited() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 70_000, 13).unwrap();
    let llvmpipe = gpu.ctx.info.is_llvmpipe();
    let runs: Vec<Run> = runs_here().into_iter().filter(|&(t, _)| !(llvmpipe && t == Technique::ForwardPlus)).collect();
    assert_equal_for(&gpu, &scene, &l, 48, 27, "city 70k", &runs);
    if llvmpipe {
        for lists in TileLists::ALL {
            let err = render_error(&gpu, &scene, &l, Precision::Oct16, &run_settings(48, 27, (Technique::ForwardPlus, lists), 16));
            assert!(err.contains("65535"), "forward+ ({} lists) must refuse 70k lights on lavapipe: {err}", lists.name());
        }
    }
}

/// The heatmap view: clustered-aabb's lists are those of clustered-naive (same boxes, same test),
/// and forward+'s lists (linked or arrays) those of tiled (same depth bounds and frustum test), so
/// those heatmaps agree pixel for pixel; a tiled heatmap is constant over each tile's geometry.
#[test]
fn heatmaps() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 2_000, 29).unwrap();
    let (w, h) = (96, 54);
    let heat = |t, tile| frame(&gpu, &scene, &l, &Settings { view: View::Heatmap, ..settings(w, h, t, tile) }).pixels;
    assert_eq!(heat(Technique::ClusteredAabb, 32), heat(Technique::ClusteredNaive, 32), "clustered-aabb and clustered-naive heatmaps");
    let tiled = heat(Technique::Tiled, 16);
    for lists in TileLists::ALL {
        let forward = frame(&gpu, &scene, &l, &Settings { view: View::Heatmap, ..run_settings(w, h, (Technique::ForwardPlus, lists), 16) }).pixels;
        assert_eq!(forward, tiled, "forward+ ({} lists) and tiled heatmaps", lists.name());
    }
    let background = shaders::shading::BACKGROUND_RGBA8;
    for t in [Technique::Tiled, Technique::Tiled25d] {
        let px = heat(t, 16);
        assert!(px.iter().any(|&p| p != background && p & 0x00ff_ffff != 0), "{t:?}: the heatmap shows lights");
        for ty in 0..h.div_ceil(16) {
            for tx in 0..w / 16 {
                let tile: Vec<u32> =
                    (0..256).map(|q| (ty * 16 + q / 16, tx * 16 + q % 16)).filter(|&(y, _)| y < h).map(|(y, x)| px[(y * w + x) as usize]).filter(|&p| p != background).collect();
                assert!(tile.windows(2).all(|p| p[0] == p[1]), "{t:?}: tile ({tx}, {ty}) has several counts");
            }
        }
    }
    common::assert_clean(&gpu);
}

/// `--fp-lists` takes effect: the two layouts allocate different buffers (heads and nodes, or
/// ranges and indices) and the stats name the layout; the arrays read back from the GPU hold, per
/// tile, the very lights the linked lists walked from the GPU hold (as sets), in index order, and
/// their references add up to the counter's.
#[test]
fn forward_plus_arrays_hold_the_linked_lists_per_tile() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 1_000, 41).unwrap();
    let (w, h) = (96u32, 54u32);
    let tiles = w.div_ceil(16) * h.div_ceil(16);
    let run = |lists| {
        let s = Settings { read_back: true, ..run_settings(w, h, (Technique::ForwardPlus, lists), 16) };
        let f = frame(&gpu, &scene, &l, &s);
        let stats = host::render::stats::stats_json(&gpu.ctx.info, "city", l.len(), &s, &f);
        assert_eq!(stats["fp_lists"], lists.name(), "the stats name the layout");
        f
    };
    let (linked, array) = (run(TileLists::Linked), run(TileLists::Array));
    let buffers = |f: &Frame| f.buffers.iter().map(|b| b.0.clone()).collect::<BTreeSet<String>>();
    let (linked_buffers, array_buffers) = (buffers(&linked), buffers(&array));
    for (buffers, has, lacks) in [(&linked_buffers, ["tile list heads", "light list nodes"], ["tile light ranges", "tile light indices"]), (&array_buffers, ["tile light ranges", "tile light indices"], ["tile list heads", "light list nodes"])] {
        for b in has {
            assert!(buffers.contains(b), "{b:?} should be among {buffers:?}");
        }
        for b in lacks {
            assert!(!buffers.contains(b), "{b:?} should not be among {buffers:?}");
        }
    }
    let lists = |f: &Frame| f.readback.as_ref().unwrap().tile_lists.clone();
    let (walked, arrays) = (lists(&linked), lists(&array));
    assert_eq!((walked.len(), arrays.len()), (tiles as usize, tiles as usize), "one list per tile");
    assert_eq!(linked.light_refs, array.light_refs, "both layouts reference as many lights");
    for (f, l) in [(&linked, &walked), (&array, &arrays)] {
        assert_eq!(l.iter().map(|t| t.len() as u32).sum::<u32>(), f.light_refs, "the lists hold every reference the counter counted");
        assert_eq!(l.iter().map(|t| t.len() as u32).max(), Some(f.max_list));
    }
    assert!(arrays.iter().filter(|t| t.len() > 1).count() * 2 > tiles as usize, "most tiles should list several lights");
    for (t, (walked, array)) in walked.iter().zip(&arrays).enumerate() {
        assert!(array.windows(2).all(|p| p[0] < p[1]), "tile {t}: the array is in index order, each light once: {array:?}");
        let mut sorted = walked.clone();
        sorted.sort_unstable();
        assert_eq!(&sorted, array, "tile {t}: the array holds the linked list's lights");
    }
    let worst = worst_channel(&linked.pixels, &array.pixels);
    assert!(worst <= 1, "the layouts' images differ by {worst}/255");
    common::assert_clean(&gpu);
}
