//! Hard cases on every technique (`Technique::ALL`, so a new technique is covered
//! without a change; Forward+ with both layouts of its tile lists), on the local device
//! (lavapipe in CI) with validation on. Each image equals
//! the brute-force `deferred` reference within 1/255 per channel:
//! * the hard light cases (camera inside a light, lights behind the camera, near/far straddle,
//!   radii 0, huge and 1e30, coincident lights, no light) and a 7680×4320 frame;
//! * the scene, its lights and camera translated by 10^5 and 10^7 m (the image equals the
//!   untranslated one: the renderer draws camera-relative, `render::camera_relative`);
//! * degenerate and sliver triangles, geometry crossing the near plane;
//! * intensities at the largest emission the contract allows, alone and 2000 at one point
//!   (finite, saturated output, equal to a CPU shading of the read-back G-buffer;
//!   `shaders::lighting`, "HDR overflow"), and a brighter light refused.
mod common;
use common::compare::{assert_every_technique_equals_deferred, assert_runs_match, assert_techniques_match, cpu_shaded, geometry_pixels, TOLERANCE};
use common::pixels::{lit, worst_channel};
use common::render::{city, frame, runs, settings};
use common::scenes::{camera_frame, camera_in_box, degenerate_triangles, hard_light_cases, light, representable_at, translated, wall_through_near_plane, with_mesh};
use glam::DVec3;
use host::render::{self, Frame, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::{lights, Scene};
use shaders::layout::PointLight;

/// Frame size of the small cases, and the cluster/tile edge of every case (the CLI default).
const W: u32 = 128;
const H: u32 = 72;
const TILE: u32 = 32;

fn small(read_back: bool) -> Settings {
    Settings { read_back, tile_size: TILE, ..settings(W, H, Technique::Deferred) }
}

/// Pixels (of `f`, read back) at most `metres` from the eye.
fn pixels_nearer_than(f: &Frame, metres: f32) -> usize {
    let rb = f.readback.as_ref().unwrap();
    rb.depth.iter().filter(|&&d| f32::from_bits(d) > 0.0 && f.grid.near / f32::from_bits(d) <= metres).count()
}

/// Pixels that show geometry (not the background colour).
fn background_free(f: &Frame) -> usize {
    f.pixels.iter().filter(|&&p| p != shaders::shading::BACKGROUND_RGBA8).count()
}

#[test]
fn hard_light_cases_on_every_technique() {
    let gpu = common::gpu();
    let scene = city();
    for (what, l) in hard_light_cases(&scene) {
        assert_every_technique_equals_deferred(&gpu, &scene, &l, &small(false), what);
    }
}

/// The tile edge of technique `t` at 7680×4320 on a device addressing 128 MiB per binding:
/// [`TILE`], but 128 px for `clustered-aabb`, whose fixed grid of boxes (32 B per tile × slice)
/// would need 1.1 GB at 32 px (240 × 135 tiles × 1081 slices) and takes 18 MB at 128 px (60 × 34
/// tiles × 276 slices); the technique says so in a clear error otherwise.
fn tile_8k(t: Technique) -> u32 {
    match t {
        Technique::ClusteredAabb => 128,
        _ => TILE,
    }
}

/// `n` lights 0.5 m above the avenue 4–4 + 3n m ahead of the camera, alternating 1 m left and
/// right, radius 2.5 m: they light the street (where a ray meets nothing behind the ground) and
/// none of the façades 4 m aside.
fn street_lights(scene: &Scene, n: usize) -> Vec<PointLight> {
    let (eye, fwd, right, _) = camera_frame(scene);
    let ground = |p: glam::Vec3| glam::Vec3::new(p.x, 0.5, p.z);
    (0..n).map(|k| light(ground(eye + fwd * (4.0 + 3.0 * k as f32) + right * if k % 2 == 0 { 1.0 } else { -1.0 }), 2.5, 2.0)).collect()
}

/// 7680×4320 (33 M pixels; each G-buffer buffer 133 MB, just inside lavapipe's 128 MiB storage
/// range) on every technique, lit by 8 street lights (17 % of the pixels lit).
///
/// Cost on lavapipe with 2 cores, one frame at a time: the per-pixel passes dominate — deferred
/// takes 23 s of CPU with 8 lights over the avenue and 67 s with 64 uniform lights;
/// clustered-naive 50 s and clustered-aabb 42 s with those 8; 1.3–1.7 GB of host memory at the
/// peak. Forward+ with linked lists once took about 50 CPU seconds per 1000 pixels of width on
/// lavapipe (over 15 CPU minutes at 8K), which made this test render it without lights there:
/// the lanes lavapipe carries masked off through the fragment's list walk read zeros, and node 0
/// then led to itself until the driver's loop limit. A self-linked node now ends the walk
/// (`shaders::shading::LinkedLights`), and both layouts render the lit frame everywhere.
#[test]
fn frames_8k_on_every_technique() {
    let gpu = common::gpu();
    let scene = city();
    let street = street_lights(&scene, 8);
    let s = Settings { tile_size: TILE, ..settings(7680, 4320, Technique::Deferred) };
    let reference = frame(&gpu, &scene, &street, &s);
    assert_eq!(reference.pixels.len(), 7680 * 4320);
    assert!(background_free(&reference) * 2 > reference.pixels.len(), "8K: the frame should show the city");
    assert!(lit(&reference.pixels) * 10 > reference.pixels.len(), "8K: the lights should light the street");
    for run in runs(Technique::ALL).into_iter().filter(|&r| r.0 != Technique::Deferred) {
        assert_runs_match(&gpu, &reference.pixels, &scene, &street, &Settings { tile_size: tile_8k(run.0), ..s.clone() }, &[run], "8K, 8 lights");
    }
}

/// City and 1000 lights translated by 10^5 and 10^7 m along every axis. f32 world coordinates
/// are spaced 2^-7 m and 1 m apart there, so the untranslated scene is first snapped to what f32
/// can hold at the offset ([`representable_at`]); translating it is then exact, and every
/// technique's image of the far scene must equal the deferred image of the near one within
/// 1/255 (the renderer's inputs are bit-identical: `render::camera_relative`). With the f32 view
/// matrix on the GPU instead, the frame at 10^5 m already differs by 48/255.
#[test]
fn world_offsets_of_1e5_and_1e7() {
    let gpu = common::gpu();
    let scene = city();
    let l = lights::uniform(&scene, 1_000, 31).unwrap();
    for offset in [1e5, 1e7] {
        let o = DVec3::splat(offset);
        let (near, near_lights) = representable_at(&scene, &l, o);
        let (far, far_lights) = translated(&near, &near_lights, o);
        assert!(far.camera.position.x >= offset as f32 * 0.99, "the scene must be far away");
        let reference = frame(&gpu, &near, &near_lights, &small(true));
        assert!(geometry_pixels(&reference) * 2 > reference.pixels.len() && lit(&reference.pixels) * 4 > reference.pixels.len(), "offset {offset}: the near frame should show lit geometry");
        assert_techniques_match(&gpu, &reference.pixels, &far, &far_lights, &small(true), Technique::ALL, &format!("offset {offset} m"));
    }
}

/// Zero-area, repeated-index, collinear, edge-on, micro and sliver triangles in front of the
/// city's camera: no NaN/∞ (finite unit normals, the frame equals a CPU shading of its G-buffer),
/// no validation message, every technique equal to the reference; the slivers cover pixels.
#[test]
fn degenerate_and_sliver_triangles() {
    let gpu = common::gpu();
    let plain = city();
    let scene = degenerate_triangles(&plain).into_iter().fold(plain.clone(), |s, m| with_mesh(&s, m));
    let (eye, f, _, _) = camera_frame(&scene);
    let mut l = lights::uniform(&scene, 1_000, 37).unwrap();
    l.extend((0..40).map(|k| light(eye + f * (6.0 + 0.6 * k as f32), 4.0, 2.0)));
    let reference = assert_every_technique_equals_deferred(&gpu, &scene, &l, &small(true), "degenerate triangles");
    let rb = reference.readback.as_ref().unwrap();
    for (i, n) in rb.normals.iter().enumerate().filter(|(i, _)| f32::from_bits(rb.depth[*i]) > 0.0) {
        let len = glam::Vec3::from_array(*n).length();
        assert!(len.is_finite() && (len - 1.0).abs() < 1e-5, "pixel {i}: G-buffer normal {n:?}");
    }
    let worst = worst_channel(&reference.pixels, &cpu_shaded(&scene, &reference, &small(true)));
    assert!(worst <= TOLERANCE, "degenerate triangles: the GPU differs from the CPU shading by {worst}/255");
    let without = frame(&gpu, &plain, &l, &small(false));
    let covered = reference.pixels.iter().zip(&without.pixels).filter(|(a, b)| a != b).count();
    assert!(covered >= 20, "the slivers should cover pixels: {covered} differ from the plain city");
}

/// The camera inside a box whose walls cross the near plane, and a wall the near plane cuts
/// across the frame: every technique equals the reference, and the frames show geometry right at
/// the near plane.
#[test]
fn geometry_crossing_the_near_plane() {
    let gpu = common::gpu();
    let scene = city();
    let (boxed, box_lights) = camera_in_box(&scene);
    let f = assert_every_technique_equals_deferred(&gpu, &boxed, &box_lights, &small(true), "camera inside a box");
    assert_eq!(geometry_pixels(&f), f.pixels.len(), "the box fills the frame");
    assert!(pixels_nearer_than(&f, 0.3) > 0 && lit(&f.pixels) * 2 > f.pixels.len(), "the box walls should reach the near plane, lit");
    let walled = wall_through_near_plane(&scene);
    let (eye, fwd, right, _) = camera_frame(&walled);
    let mut l = lights::uniform(&scene, 1_000, 43).unwrap();
    // On the eye's side of the wall, 0.26 m from it (at 45°: 1 m aside per metre ahead).
    l.extend((0..60).map(|k| {
        let d = 0.3 + 0.5 * k as f32;
        light(eye + fwd * d + right * (d + 0.3), 3.0, 3.0)
    }));
    let f = assert_every_technique_equals_deferred(&gpu, &walled, &l, &small(true), "wall through the near plane");
    let near = walled.camera.near;
    assert!(pixels_nearer_than(&f, 2.0 * near) > 0 && pixels_nearer_than(&f, 1.0) * 5 > f.pixels.len(), "the wall should start at the near plane");
    assert!(lit(&f.pixels) * 4 > f.pixels.len(), "the frame should be lit");
}

/// Lights at `MAX_EMISSION` (the largest the contract allows), alone, 2000 at one point, and
/// among ordinary lights: every technique's output is finite and saturates the same way (no
/// black or NaN speckles) and equals the CPU shading of the reference's G-buffer; a light
/// brighter than `MAX_EMISSION` is a clear error.
#[test]
fn hdr_intensities_stay_finite_and_saturate_identically() {
    let gpu = common::gpu();
    let scene = city();
    let (eye, fwd, _, _) = camera_frame(&scene);
    let bright = |l: Vec<PointLight>, intensity: f32| -> Vec<PointLight> { l.into_iter().map(|l| PointLight { intensity, ..l }).collect() };
    let mut mixed = lights::uniform(&scene, 1_000, 47).unwrap();
    let top = shaders::lighting::MAX_EMISSION;
    mixed.extend(bright(lights::uniform(&scene, 100, 53).unwrap(), top));
    let cases: Vec<(&str, Vec<PointLight>)> = vec![
        ("intensity MAX_EMISSION", bright(lights::uniform(&scene, 300, 41).unwrap(), top)),
        ("2000 lights of MAX_EMISSION at one point", (0..2000).map(|_| light(eye + fwd * 25.0, 15.0, top)).collect()),
        ("ordinary and MAX_EMISSION lights", mixed),
    ];
    for (what, l) in &cases {
        assert!(l.iter().all(|l| l.colour.iter().fold(0.0f32, |m, &c| m.max(c)) * l.intensity <= shaders::lighting::MAX_EMISSION));
        let reference = assert_every_technique_equals_deferred(&gpu, &scene, l, &small(true), what);
        let worst = worst_channel(&reference.pixels, &cpu_shaded(&scene, &reference, &small(true)));
        assert!(worst <= TOLERANCE, "{what}: the GPU differs from the CPU shading by {worst}/255");
        let saturated = reference.pixels.iter().filter(|&&p| (0..3).any(|c| (p >> (8 * c)) & 255 == 255)).count();
        assert!(saturated * 100 > reference.pixels.len(), "{what}: the bright lights should saturate pixels ({saturated})");
    }
    // Brighter than the shading keeps finite: refused, naming the light.
    let mut l = lights::uniform(&scene, 10, 59).unwrap();
    l[7] = light(eye + fwd * 20.0, 5.0, shaders::lighting::MAX_EMISSION * 2.0);
    let flat = flatten(&scene, small(false).normal_precision).unwrap();
    for &t in Technique::ALL {
        let err = render::render(&gpu, &scene_input(&scene, &flat, &l), &Settings { technique: t, ..small(false) }).err().expect("a too bright light is an error");
        assert!(format!("{err:#}").starts_with("light 7 emits"), "{t:?}: {err:#}");
    }
    common::assert_clean(&gpu);
}
