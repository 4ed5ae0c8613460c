//! NURBS surfaces end to end on the local device (lavapipe in CI), validation on: the `nurbs`
//! scene (the exact sphere, the torus and the teapot, tessellated by the compute pass each frame)
//! renders with every technique equal to the brute-force reference within 1/255, its patches
//! cover the pixels of their materials, the tessellation level reaches the pass, a scene without
//! patches records no tessellation pass and allocates none of its buffers, adaptive levels
//! (`--tess-error`) draw the same surfaces as a fine fixed level with every G-buffer technique
//! equal to the reference, and the command line renders `--scene nurbs` and refuses bad patches
//! with one line naming the patch and the field.
//! (The pass's buffers against the CPU kernel functions: `tests/gpu_parity.rs`.)
mod common;
use common::cli::{assert_one_line_error, manylights};
use common::compare::{assert_every_technique_equals_deferred, cpu_shaded, TOLERANCE};
use common::pixels::{lit, worst_channel};
use common::render::{city, frame, settings};
use common::temp::TempDir;
use host::gpu::Gpu;
use host::render::{self, Frame, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::{lights, Scene};
use shaders::layout::PointLight;

fn nurbs_scene() -> Scene {
    Scene::load("nurbs", &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// Pixels of each material (the G-buffer albedo word's alpha) in a read-back frame.
fn material_pixels(f: &Frame, materials: usize) -> Vec<usize> {
    let mut n = vec![0; materials];
    let rb = f.readback.as_ref().expect("a read-back frame");
    for (&a, &d) in rb.albedo.iter().zip(&rb.depth) {
        if f32::from_bits(d) > 0.0 {
            n[(a >> 24) as usize] += 1;
        }
    }
    n
}

/// Every technique (Forward+ with both list layouts, the clustered lists checked against the
/// CPU) equals the brute-force reference on the NURBS scene with many lights, and the reference
/// equals a CPU shading of its G-buffer; the sphere, the torus and the teapot each cover pixels.
#[test]
fn nurbs_scene_every_technique_equals_the_reference() {
    let gpu = common::gpu();
    let scene = nurbs_scene();
    for n in [2_000, 10_000] {
        let l = lights::uniform(&scene, n, 9).unwrap();
        let s = Settings { read_back: true, ..settings(160, 90, Technique::Deferred) };
        let what = format!("nurbs {n}");
        let reference = assert_every_technique_equals_deferred(&gpu, &scene, &l, &s, &what);
        assert!(lit(&reference.pixels) * 2 > reference.pixels.len(), "{what}: the frame should be mostly lit");
        let worst = worst_channel(&reference.pixels, &cpu_shaded(&scene, &reference, &s));
        assert!(worst <= TOLERANCE, "{what}: the reference differs from the CPU shading of its G-buffer by {worst}/255");
        let by_material = material_pixels(&reference, scene.materials.len());
        // floor, porcelain (teapot), red lacquer (sphere), gold (torus): each in view.
        assert!(by_material.iter().all(|&p| p > 150), "{what}: pixels per material {by_material:?}");
    }
    common::assert_clean(&gpu);
}

/// The level reaches the pass: a coarser tessellation gives another image (the sphere at level 2
/// is a few flat facets); the patches' own level is the default 16, and 16 set explicitly is the
/// same image.
#[test]
fn tessellation_level_reaches_the_pass() {
    let gpu = common::gpu();
    let mut scene = nurbs_scene();
    let l = lights::uniform(&scene, 500, 4).unwrap();
    let s = settings(96, 54, Technique::ClusteredBvh);
    let default = frame(&gpu, &scene, &l, &s);
    scene.set_tess_level(16);
    assert_eq!(frame(&gpu, &scene, &l, &s).pixels, default.pixels, "level 16 is the default");
    scene.set_tess_level(2);
    let coarse = frame(&gpu, &scene, &l, &s);
    assert!(worst_channel(&coarse.pixels, &default.pixels) > 16, "level 2 should look different from level 16");
    common::assert_clean(&gpu);
}

/// Only what the scene calls for: without patches no tessellation pass is recorded and none of
/// its buffers is allocated (its pipelines live in the pass, which is not created); with them,
/// the pass runs and its buffers are the packed patches.
#[test]
fn tessellation_pass_only_where_the_scene_has_patches() {
    let gpu = common::gpu();
    let stats = |scene: &Scene, l: &[PointLight], f: &Frame, s: &Settings| host::render::stats::stats_json(&gpu.ctx.info, &scene.name, l.len(), s, f);
    for technique in [Technique::ClusteredBvh, Technique::ForwardPlus] {
        let s = Settings { read_back: true, frames: 1, ..settings(64, 36, technique) };
        let city = city();
        assert!(city.nurbs.is_empty());
        let l = lights::uniform(&city, 200, 3).unwrap();
        let j = stats(&city, &l, &frame(&gpu, &city, &l, &s), &s);
        let passes = j["gpu_ms"]["passes"].as_object().unwrap();
        assert!(!passes.contains_key("tessellation"), "city, {technique:?}: passes {:?}", passes.keys());
        let buffers = j["bytes"]["buffers"].as_object().unwrap();
        assert!(buffers.keys().all(|b| !b.starts_with("nurbs")), "city, {technique:?}: buffers {:?}", buffers.keys());

        let scene = nurbs_scene();
        let l = lights::uniform(&scene, 200, 3).unwrap();
        let j = stats(&scene, &l, &frame(&gpu, &scene, &l, &s), &s);
        let passes = j["gpu_ms"]["passes"].as_object().unwrap();
        assert!(passes.contains_key("tessellation"), "nurbs, {technique:?}: passes {:?}", passes.keys());
        let b = &j["bytes"]["buffers"];
        assert_eq!(b["nurbs patches"].as_u64(), Some(48 * 34), "nurbs: {b}");
        let knots: usize = scene.nurbs.iter().map(|p| p.patch.knots_u.len() + p.patch.knots_v.len()).sum();
        let points: usize = scene.nurbs.iter().map(|p| p.patch.control_points.len()).sum();
        assert_eq!((b["nurbs knots"].as_u64(), b["nurbs control points"].as_u64()), (Some(4 * knots as u64), Some(16 * points as u64)), "nurbs: {b}");
    }
    common::assert_clean(&gpu);
}

/// `manylights render --scene nurbs` writes a picture (and the tessellation pass in its stats);
/// `--tess-level` out of range and a description with a bad patch are one-line errors with
/// status 2 naming the flag, or the file, the patch and the field.
#[test]
fn cli_renders_the_nurbs_scene_and_refuses_bad_patches() {
    let dir = TempDir::new("cli-nurbs");
    let (out, stats) = (dir.join("nurbs.png"), dir.join("stats.json"));
    let args = ["render", "--scene", "nurbs", "--lights", "300", "--width", "96", "--height", "54", "--frames", "0", "--tess-level", "8"];
    let r = manylights(args.iter().copied().chain(["--stats", stats.to_str().unwrap(), "--out", out.to_str().unwrap()]));
    assert!(r.ok, "render failed:\n{}", r.stderr);
    let img = image::open(&out).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (96, 54));
    let distinct: std::collections::HashSet<_> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 100, "a lit scene has many colours, got {}", distinct.len());
    let j: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(j["gpu_ms"]["passes"]["tessellation"].is_number(), "{j}");

    let o = out.to_str().unwrap();
    for level in ["0", "257"] {
        let r = manylights(["render", "--scene", "nurbs", "--tess-level", level, "--out", o]);
        assert_one_line_error(&r, &format!("--tess-level {level}"), &format!("'{level}'"));
    }
    let bad = dir.write(
        "bad.toml",
        "geometry = \"nurbs\"\n[[nurbs]]\ndegree_u = 1\ndegree_v = 1\nsize_u = 2\nsize_v = 2\n\
         control_points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\nweights = [1, 1, -2, 1]\nmaterial = \"gold\"\n",
    );
    let r = manylights(["render", "--scene", bad.to_str().unwrap(), "--lights", "10", "--out", o]);
    assert_one_line_error(&r, "a negative weight", "bad.toml: NURBS patch \"nurbs[0]\": weights[2] = -2; weights must be positive and finite");
}

/// A frame with adaptive NURBS levels within `tolerance` pixels.
fn adaptive(gpu: &Gpu, scene: &Scene, lights: &[PointLight], s: &Settings, tolerance: f32) -> anyhow::Result<Frame> {
    let flat = flatten(scene, s.normal_precision)?;
    let mut input = scene_input(scene, &flat, lights);
    input.nurbs_tolerance = Some(tolerance);
    render::render(gpu, &input, s)
}

/// Adaptive levels (the level kernel, indirect G-buffer draws): every technique that draws
/// through the G-buffer equals the reference with the same levels; the image is that of a fine
/// fixed tessellation (level 64, the adaptive maximum) but for silhouette pixels; Forward+ and
/// transparent patches refuse adaptive levels with one line.
#[test]
fn adaptive_levels_equal_the_reference_and_a_fine_tessellation() {
    let gpu = common::gpu();
    let mut scene = nurbs_scene();
    let l = lights::uniform(&scene, 2_000, 6).unwrap();
    let s = |t| Settings { read_back: true, ..settings(160, 90, t) };
    let reference = adaptive(&gpu, &scene, &l, &s(Technique::Deferred), 0.5).unwrap_or_else(|e| panic!("{e:#}"));
    for &t in Technique::ALL.iter().filter(|&&t| t != Technique::Deferred && t != Technique::ForwardPlus) {
        let f = adaptive(&gpu, &scene, &l, &s(t), 0.5).unwrap_or_else(|e| panic!("{t:?}: {e:#}"));
        let worst = worst_channel(&reference.pixels, &f.pixels);
        assert!(worst <= TOLERANCE, "adaptive levels, {t:?}: differs from deferred by {worst}/255");
    }
    let by_material = material_pixels(&reference, scene.materials.len());
    assert!(by_material.iter().all(|&p| p > 150), "adaptive: pixels per material {by_material:?}");
    scene.set_tess_level(64);
    let fine = frame(&gpu, &scene, &l, &s(Technique::Deferred));
    let differing = reference.pixels.iter().zip(&fine.pixels).filter(|(a, b)| common::pixels::channel_diff(**a, **b) > 8).count();
    assert!(differing * 50 < reference.pixels.len(), "adaptive levels differ from level 64 at {differing} of {} pixels", reference.pixels.len());
    let coarse = {
        scene.set_tess_level(2);
        frame(&gpu, &scene, &l, &s(Technique::Deferred))
    };
    let coarse_differing = coarse.pixels.iter().zip(&fine.pixels).filter(|(a, b)| common::pixels::channel_diff(**a, **b) > 8).count();
    assert!(coarse_differing > 2 * differing, "level 2 should differ from level 64 more than the adaptive levels do ({coarse_differing} vs {differing} pixels)");

    let e = format!("{:#}", adaptive(&gpu, &scene, &l, &s(Technique::ForwardPlus), 0.5).err().expect("forward+ refuses adaptive levels"));
    assert!(e.contains("--tess-error") && e.contains("forward-plus") && !e.contains('\n'), "{e}");
    let mut glassy = nurbs_scene();
    glassy.materials[3].opacity = 0.5;
    let e = format!("{:#}", adaptive(&gpu, &glassy, &l, &s(Technique::Deferred), 0.5).err().expect("transparent patches refuse adaptive levels"));
    assert!(e.contains("--tess-error") && e.contains("\"gold\"") && !e.contains('\n'), "{e}");
    if gpu.ctx.info.is_llvmpipe() {
        // A patch past the level kernel's loops on lavapipe is refused, not cut short.
        let (nu, nv) = (129u32, 125u32);
        let points = (0..nu * nv).map(|k| [(k % nu) as f32 * 0.01, 0.5, -((k / nu) as f32) * 0.01]).collect();
        let big = host::scene::nurbs::NurbsPatch::polynomial(1, 1, nu, nv, points, 0);
        let mut scene = nurbs_scene();
        scene.add_nurbs([host::scene::nurbs::ScenePatch { name: "big".into(), patch: big, level: None }]);
        let e = format!("{:#}", adaptive(&gpu, &scene, &l, &s(Technique::Deferred), 0.5).err().expect("too many control points for lavapipe's loops"));
        assert!(e.contains("16125 control points") && e.contains("16000") && !e.contains('\n'), "{e}");
    }
    common::assert_clean(&gpu);
}

/// `render --tess-error` renders the NURBS scene; a tolerance that is not a positive number and
/// `--technique forward-plus` with it are one-line errors with status 2.
#[test]
fn cli_adaptive_levels() {
    let dir = TempDir::new("cli-nurbs-adaptive");
    let out = dir.join("adaptive.png");
    let o = out.to_str().unwrap();
    let r = manylights(["render", "--scene", "nurbs", "--lights", "300", "--width", "96", "--height", "54", "--frames", "0", "--tess-error", "0.5", "--out", o]);
    assert!(r.ok, "render failed:\n{}", r.stderr);
    assert_eq!(image::open(&out).expect("a readable PNG").to_rgba8().dimensions(), (96, 54));
    for bad in ["0", "-1", "nan", "inf"] {
        let r = manylights(["render", "--scene", "nurbs", "--tess-error", bad, "--out", o]);
        assert_one_line_error(&r, &format!("--tess-error {bad}"), "--tess-error");
    }
    let r = manylights(["render", "--scene", "nurbs", "--technique", "forward-plus", "--tess-error", "1", "--out", o]);
    assert_one_line_error(&r, "forward-plus with --tess-error", "forward-plus");
}

/// A camera moved between frames (the viewer's `Renderer::set_view`): the patches' control
/// points follow the new eye, so the frame equals a fresh render from there, pixel for pixel.
#[test]
fn a_moved_camera_tessellates_relative_to_the_new_eye() {
    let gpu = common::gpu();
    let scene = nurbs_scene();
    let l = lights::uniform(&scene, 500, 4).unwrap();
    let s = settings(96, 54, Technique::ClusteredBvh);
    let flat = flatten(&scene, s.normal_precision).unwrap();
    let mut moved = scene.clone();
    moved.camera.position += glam::Vec3::new(1.5, 0.5, -2.0);
    let fresh = frame(&gpu, &moved, &l, &s);
    let mut r = render::renderer::Renderer::new(&gpu, &scene_input(&scene, &flat, &l), &s).unwrap();
    r.frame(&gpu).unwrap();
    let before = r.pixels().unwrap();
    r.set_view(&gpu, scene_input(&moved, &flat, &l).view, &flat.positions, &l).unwrap();
    r.frame(&gpu).unwrap();
    let after = r.pixels().unwrap();
    assert_ne!(before, fresh.pixels, "the move changes the frame");
    assert_eq!(after, fresh.pixels, "the moved renderer draws what a fresh render from there draws");
    common::assert_clean(&gpu);
}
