//! Lights that cast shadows: the inputs that mark them, the CPU ray-cast reference
//! (`render::cpu_shading`) held to a closed-form shadow, `deferred`'s cube shadow maps held to the
//! reference, and every technique (Forward+'s fragment shaders too) equal to `deferred` with them.
mod common;

use common::cli::{assert_refused, manylights_env, BAD_INPUT};
use common::compare::{assert_techniques_match, cpu_shaded};
use common::pixels::{channel_diff, worst_channel};
use common::render::{render_error, settings};
use common::temp::TempDir;
use glam::Vec3;
use host::render::cpu_shading::{shade, Shadows};
use host::render::clustered::UniqueClusters;
use host::render::shadow_maps::{ShadowFaces, ShadowFilter, ShadowRaster, ShadowSettings, ShadowStats};
use host::render::{self, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::Scene;
use shaders::lighting::{encode_srgb8, tonemap};
use shaders::octahedral::Precision;
use shaders::reconstruct::{distance_from_depth, is_background, view_position};

/// A 12 × 12 floor at y = 0 and a wall over it in the plane x = 0 (2 high, as long as the
/// floor), both facing up / towards −x and +x (two triangles each side).
const FLOOR_AND_WALL: &str = "\
v -6 0 -6\nv 6 0 -6\nv 6 0 6\nv -6 0 6\n\
v 0 0 -6\nv 0 0 6\nv 0 2 6\nv 0 2 -6\n\
f 1 4 3\nf 1 3 2\n\
f 5 6 7\nf 5 7 8\nf 5 8 7\nf 5 7 6\n";

/// One light at (−2, 1, 0) on the wall's −x side; the camera straight above the floor.
fn description(shadows: &str) -> String {
    description_at([-2.0, 1.0, 0.0], shadows)
}

/// [`description`] with the light at `light`.
fn description_at(light: [f32; 3], shadows: &str) -> String {
    format!(
        "geometry = \"floor.obj\"\n[camera]\nposition = [0, 14, 0.01]\ntarget = [0, 0, 0]\nfov_y = 60\nnear = 0.5\nfar = 40\n\
         [[light]]\nposition = {light:?}\nradius = 30\nintensity = 60\n{shadows}"
    )
}

/// An axis-aligned box's six faces (two triangles each, both windings: seen from in and out)
/// around `c` with half-size `h`, as OBJ lines numbered from vertex `first`.
fn obj_box(c: [f32; 3], h: f32, first: usize) -> String {
    let mut s = String::new();
    for i in 0..8 {
        let corner = [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32].map(|t| 2.0 * t - 1.0);
        s += &format!("v {} {} {}\n", c[0] + h * corner[0], c[1] + h * corner[1], c[2] + h * corner[2]);
    }
    for q in [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]] {
        let [a, b, c, d] = q.map(|k| first + k);
        s += &format!("f {a} {b} {c}\nf {a} {c} {d}\nf {a} {c} {b}\nf {a} {d} {c}\n");
    }
    s
}

fn scene(dir: &TempDir, shadows: &str) -> Scene {
    scene_of(dir, FLOOR_AND_WALL, &description(shadows))
}

fn scene_of(dir: &TempDir, obj: &str, description: &str) -> Scene {
    dir.write_bytes("floor.obj", obj.as_bytes());
    let path = dir.write_bytes("scene.toml", description.as_bytes());
    Scene::load(path.to_str().unwrap(), &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// The frame of `scene` rendered by `deferred` without shadows (read back), and its settings.
fn unshadowed_frame(gpu: &host::gpu::Gpu, scene: &Scene) -> (render::Frame, Settings, host::render::camera_relative::ViewTransform) {
    let s = Settings { read_back: true, ..settings(160, 120, Technique::Deferred) };
    let flat = flatten(scene, s.normal_precision).unwrap();
    let mut input = scene_input(scene, &flat, &scene.lights);
    input.shadows = &[];
    let f = render::render(gpu, &input, &s).unwrap_or_else(|e| panic!("{e:#}"));
    (f, s, input.view)
}

/// Every point of the floor beyond the wall (x > 0) is hidden from the light: the segment from
/// (−2, 1, 0) to (x, 0, z) crosses x = 0 at height 1 − 2/(x + 2), in (0, 1), and at |z| < 6,
/// inside the wall. The reference leaves those floor pixels unlit and shades the floor on the
/// light's side (x < 0) exactly as without shadows; without shadows the far side is lit, so the
/// test can tell.
#[test]
fn the_ray_cast_reference_shadows_the_floor_behind_a_wall() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-wall");
    let scene = scene(&dir, "shadows = true\n");
    assert_eq!(scene.shadows, vec![true]);
    let (f, s, view) = unshadowed_frame(&gpu, &scene);
    let shadows = Shadows::of_scene(&scene, &view);
    let reference = shade(&scene, &f, &s, Some(&shadows)).unwrap();
    let plain = cpu_shaded(&scene, &f, &s);
    let unlit = encode_srgb8(tonemap(Vec3::ZERO, s.exposure));
    let rb = f.readback.as_ref().unwrap();
    let g = &f.grid;
    let (mut behind, mut before) = (0, 0);
    for i in 0..rb.depth.len() {
        let depth = f32::from_bits(rb.depth[i]);
        if is_background(depth) {
            continue;
        }
        let p = view_position(g, i as u32 % g.width, i as u32 / g.width, distance_from_depth(g.near, depth));
        let world = view.eye + view.rotation.transpose() * p.as_dvec3();
        if world.y.abs() > 0.01 {
            continue; // the wall's top edge
        }
        // Clear of the wall's foot by more than the reconstruction and bias errors.
        if world.x > 0.2 {
            behind += 1;
            assert_eq!(reference[i], unlit, "floor pixel {i} at {world:?} is lit through the wall");
            assert_ne!(plain[i], unlit, "floor pixel {i} at {world:?} is unlit even without shadows");
        } else if world.x < -0.2 {
            before += 1;
            assert_eq!(reference[i], plain[i], "floor pixel {i} at {world:?} on the light's side differs from the unshadowed shading");
        }
    }
    assert!(behind > 3000 && before > 3000, "{behind} pixels behind the wall, {before} before it");
    common::assert_clean(&gpu);
}

/// With no light casting shadows the reference equals the unshadowed CPU shading everywhere,
/// and the scene's shadow flags stay empty: nothing for shadows is set up.
#[test]
fn without_casters_the_reference_is_the_plain_shading() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-none");
    let scene = scene(&dir, "");
    assert!(scene.shadows.is_empty(), "a scene without shadow-casting lights has no shadow flags");
    let (f, s, view) = unshadowed_frame(&gpu, &scene);
    let reference = shade(&scene, &f, &s, Some(&Shadows::of_scene(&scene, &view))).unwrap();
    assert_eq!(reference, cpu_shaded(&scene, &f, &s));
    common::assert_clean(&gpu);
}

/// The frame of `scene` rendered by `deferred` with its shadows (read back), the CPU's ray-cast
/// reference shaded from that frame's own G-buffer, and per pixel the ray-cast visibility of
/// the first 64 shadow-casting lights as bits (`None`: background).
fn shadowed_and_reference(gpu: &host::gpu::Gpu, scene: &Scene, shadow: ShadowSettings) -> (render::Frame, Vec<u32>, Vec<Option<u64>>) {
    let s = Settings { read_back: true, shadow, ..settings(160, 120, Technique::Deferred) };
    let flat = flatten(scene, s.normal_precision).unwrap();
    let input = scene_input(scene, &flat, &scene.lights);
    let f = render::render(gpu, &input, &s).unwrap_or_else(|e| panic!("{e:#}"));
    let shadows = Shadows::of_scene(scene, &input.view);
    let reference = shade(scene, &f, &s, Some(&shadows)).unwrap();
    let rb = f.readback.as_ref().unwrap();
    let g = &f.grid;
    let casters: Vec<usize> = (0..scene.lights.len()).filter(|&l| scene.shadows.get(l) == Some(&true)).take(64).collect();
    let visible = (0..rb.depth.len())
        .map(|i| {
            let depth = f32::from_bits(rb.depth[i]);
            (!is_background(depth)).then(|| {
                let p = view_position(g, i as u32 % g.width, i as u32 / g.width, distance_from_depth(g.near, depth));
                let n = Vec3::from_array(rb.normals[i]);
                casters.iter().enumerate().fold(0u64, |bits, (k, &l)| bits | (u64::from(shadows.lit(l, p, n, Vec3::from_array(rb.lights_view[l].position))) << k))
            })
        })
        .collect();
    (f, reference, visible)
}

/// Surface pixels at most `band` pixels (in x and y) from a surface pixel whose visibility differs: the edge band
/// where a shadow map of finite resolution may disagree with exact visibility.
fn edge_band(visible: &[Option<u64>], width: usize, band: usize) -> Vec<bool> {
    let height = visible.len() / width;
    (0..visible.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let near = |j: usize| visible[i].is_some() && visible[j].is_some() && visible[j] != visible[i];
            (y.saturating_sub(band)..(y + band + 1).min(height)).any(|v| (x.saturating_sub(band)..(x + band + 1).min(width)).any(|u| near(v * width + u)))
        })
        .collect()
}

/// The shadow edge's width in pixels (module docs of `shaders::shadow`: a texel at the default
/// 256² per face is about 0.3 of a pixel of this view at the floor, the bias rule moves the
/// receiver 1.5 texels, the bilinear filter blends 1 texel): two pixels hold them all.
const EDGE_BAND_PX: usize = 2;

/// `deferred` with `shadow` against the ray-cast reference: every pixel outside the edge band
/// within 1/255, the band a thin outline (both printed). Returns the pixels the first caster
/// leaves in shadow.
fn assert_matches_reference(gpu: &host::gpu::Gpu, scene: &Scene, shadow: ShadowSettings, what: &str) -> (usize, ShadowStats) {
    let (f, reference, visible) = shadowed_and_reference(gpu, scene, shadow);
    let band = edge_band(&visible, f.grid.width as usize, EDGE_BAND_PX);
    let (mut shadowed, mut in_band, mut off_in_band) = (0, 0, 0);
    for i in 0..reference.len() {
        shadowed += usize::from(visible[i].is_some_and(|v| v & 1 == 0));
        let off = channel_diff(f.pixels[i], reference[i]) > 1;
        if band[i] {
            in_band += 1;
            off_in_band += usize::from(off);
        } else {
            assert!(!off, "{what}: pixel {i} (visible {:?}) is {:08x} against the reference's {:08x}", visible[i], f.pixels[i], reference[i]);
        }
    }
    let share = in_band as f64 / reference.len() as f64;
    eprintln!("{what}: {shadowed} shadowed pixels; edge band {in_band} pixels ({:.2} %), {off_in_band} of them off by more than 1/255", 100.0 * share);
    // The band stays a thin outline (the test would hold nothing back were it the image).
    assert!(share < 0.1, "{what}: the edge band holds {:.1} % of the image", 100.0 * share);
    (shadowed, f.shadows.expect("the frame made shadow maps"))
}

/// Both ways of writing the maps' triangles (`--shadow-raster`).
const RASTERS: [ShadowRaster; 2] = [ShadowRaster::Compute, ShadowRaster::Draw];

/// `deferred` with cube shadow maps against the ray-cast reference on the floor behind a wall, at
/// both filters, the maps written by the compute rasteriser and by the draw.
#[test]
fn deferred_shadow_maps_match_the_ray_cast_reference() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-maps");
    let scene = scene(&dir, "shadows = true\n");
    for raster in RASTERS {
        for filter in [ShadowFilter::Nearest, ShadowFilter::Bilinear] {
            let (shadowed, _) = assert_matches_reference(&gpu, &scene, ShadowSettings { filter, raster, ..Default::default() }, &format!("{filter:?}, {raster:?}"));
            assert!(shadowed > 3000, "{shadowed} pixels in shadow");
        }
    }
    common::assert_clean(&gpu);
}

/// `--shadow-raster` reaches the frame: the compute rasteriser records the shadow pass without
/// raster work, the draw with it (the frame's pass timings say which), and `--stats` names it.
#[test]
fn the_shadow_raster_knob_picks_what_writes_the_maps() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-raster-knob");
    let scene = scene(&dir, "shadows = true\n");
    for (raster, drawn) in [(ShadowRaster::Compute, false), (ShadowRaster::Draw, true)] {
        let (f, _, _) = shadowed_and_reference(&gpu, &scene, ShadowSettings { raster, ..Default::default() });
        assert!(f.timings.iter().any(|t| t.name == "shadow maps"), "{raster:?}: no shadow pass");
        assert_eq!(f.is_raster("shadow maps"), drawn, "{raster:?}: the shadow pass {} raster work", if drawn { "records no" } else { "records" });
    }
    common::assert_clean(&gpu);
}

/// The hard cases against the ray-cast reference: a light inside a closed box (everything outside
/// dark), a light on the wall's plane and one on the floor (no surface through the light shadows
/// anything), a receiver a millimetre from the light (the floor under a light at 1 mm), and a
/// caster a tenth of a millimetre from the light (a small square right under it shadows nearly the
/// whole floor: no near plane drops it).
#[test]
fn hard_cases_match_the_ray_cast_reference() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-hard");
    let under = "v -2.1 0.9999 -0.1\nv -1.9 0.9999 -0.1\nv -1.9 0.9999 0.1\nv -2.1 0.9999 0.1\nf 9 10 11\nf 9 11 12\n";
    let cases: [(&str, String, [f32; 3], usize); 5] = [
        ("light inside a box", format!("{FLOOR_AND_WALL}{}", obj_box([-2.0, 1.0, 0.0], 0.5, 9)), [-2.0, 1.0, 0.0], 6000),
        ("light on the wall's plane", FLOOR_AND_WALL.to_string(), [0.0, 1.0, 0.0], 0),
        ("light on the floor", FLOOR_AND_WALL.to_string(), [-2.0, 0.0, 0.0], 0),
        ("receiver a millimetre from the light", FLOOR_AND_WALL.to_string(), [-2.0, 0.001, 0.0], 3000),
        ("caster a tenth of a millimetre from the light", format!("{FLOOR_AND_WALL}{under}"), [-2.0, 1.0, 0.0], 6000),
    ];
    for (what, obj, light, min_shadowed) in cases {
        let scene = scene_of(&dir, &obj, &description_at(light, "shadows = true\n"));
        for raster in RASTERS {
            let (shadowed, _) = assert_matches_reference(&gpu, &scene, ShadowSettings { raster, ..Default::default() }, &format!("{what}, {raster:?}"));
            assert!(shadowed >= min_shadowed, "{what}: {shadowed} pixels in shadow");
        }
    }
    common::assert_clean(&gpu);
}

/// Many batches and small lights: the per-face cull sends each caster only the batches near it
/// (at most a quarter of the batch-face pairs here; printed), and the frame still matches the
/// ray-cast reference on the city, 12 of 200 lights casting shadows — with both writers, and
/// with every face as well as only the faces with receivers (which must draw fewer).
#[test]
fn culled_shadow_maps_match_the_reference_on_the_city() {
    let gpu = common::gpu();
    let mut scene = common::render::city();
    scene.lights = host::scene::lights::uniform(&scene, 200, 7).unwrap();
    scene.spots.clear();
    scene.shadows = host::scene::lights::shadow_casters(200, 0.0625).unwrap();
    assert_eq!(scene.shadow_casters(), 12);
    let mut drawn = vec![];
    for (raster, faces) in [(ShadowRaster::Compute, ShadowFaces::Receivers), (ShadowRaster::Draw, ShadowFaces::Receivers), (ShadowRaster::Compute, ShadowFaces::All)] {
        let (_, sh) = assert_matches_reference(&gpu, &scene, ShadowSettings { raster, faces, ..Default::default() }, &format!("city, {raster:?}, {faces:?}"));
        let tested = sh.batches as u64 * 6 * sh.casters as u64;
        eprintln!("city ({faces:?}): {} batches, {} of {tested} batch-face pairs drawn, {} of {} faces with receivers", sh.batches, sh.entries, sh.faces_with_receivers, 6 * sh.casters);
        assert!(sh.batches > 20 && sh.entries > 0 && (sh.entries as u64) * 4 < tested, "{sh:?}");
        drawn.push((sh.entries, sh.faces_with_receivers));
    }
    // The receivers' faces reach the cull: fewer faces and fewer batch-face pairs than every face.
    assert_eq!(drawn[0], drawn[1]);
    assert!(drawn[0].0 < drawn[2].0 && drawn[0].1 < drawn[2].1 && drawn[2].1 == 6 * 12, "{drawn:?}");
    common::assert_clean(&gpu);
}

/// Every technique that renders shadows equals `deferred` with shadows within 1/255 on the wall
/// scene and on the city with 12 of 200 lights casting (both unique-cluster paths of the
/// clustered techniques, with read-back lists checked against the CPU).
#[test]
fn techniques_with_shadows_equal_deferred() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-techniques");
    let wall = scene(&dir, "shadows = true\n");
    let mut city = common::render::city();
    city.lights = host::scene::lights::uniform(&city, 200, 7).unwrap();
    city.spots.clear();
    city.shadows = host::scene::lights::shadow_casters(200, 0.0625).unwrap();
    let with: Vec<Technique> = Technique::ALL.iter().copied().filter(|&t| t != Technique::Deferred && t.description().shadows).collect();
    assert!(!with.is_empty());
    for (what, scene) in [("wall", &wall), ("city", &city)] {
        for unique_clusters in [UniqueClusters::Tiles, UniqueClusters::PageTable] {
            let s = Settings { read_back: true, unique_clusters, ..settings(160, 120, Technique::Deferred) };
            let reference = common::render::frame(&gpu, scene, &scene.lights, &s);
            assert!(reference.shadows.is_some());
            assert_techniques_match(&gpu, &reference.pixels, scene, &scene.lights, &s, &with, &format!("{what} ({} clusters)", unique_clusters.name()));
        }
    }
}

/// The atlas: each face gets the side its receivers ask (below the largest side here, so the
/// faces differ from one another and take less than room for all at the largest); an atlas one
/// texel short of that halves every side once (said in the frame's statistics) and the frame
/// still matches the reference; an atlas too small for every face at the least side is refused
/// in one line.
#[test]
fn faces_take_what_their_receivers_ask_and_a_short_atlas_halves_them() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-atlas");
    let lights: String = (0..5).map(|i| format!("[[light]]\nposition = [-2, 1, {}]\nradius = 30\nintensity = 12\nshadows = true\n", -3.0 + 1.5 * i as f32)).collect();
    let base = description_at([-2.0, 1.0, 0.0], "shadows = true\n");
    let scene = scene_of(&dir, FLOOR_AND_WALL, &format!("{base}{lights}"));
    let shadow = ShadowSettings { resolution: 4096, ..Default::default() };
    let (_, sh) = assert_matches_reference(&gpu, &scene, shadow, "atlas");
    let most = 6 * sh.casters as u64 * 4096 * 4096;
    eprintln!("atlas: {} faces with receivers took {} texels (room for all at 4096²: {most})", sh.faces_with_receivers, sh.atlas_used);
    assert!(sh.shift == 0 && sh.atlas_used > 0 && (sh.atlas_used as u64) * 16 < most, "{sh:?}");
    let short = ShadowSettings { atlas_bytes: Some(4 * sh.atlas_used as u64 - 4), ..shadow };
    let (_, halved) = assert_matches_reference(&gpu, &scene, short, "short atlas");
    assert_eq!((halved.shift, halved.faces_with_receivers), (1, sh.faces_with_receivers), "{halved:?}");
    assert!(halved.atlas_used <= halved.atlas_texels && halved.atlas_used * 3 < sh.atlas_used, "{halved:?}");
    let tiny = ShadowSettings { atlas_bytes: Some(1024), ..shadow };
    let e = render_error(&gpu, &scene, &scene.lights, Precision::Oct16, &Settings { shadow: tiny, ..settings(160, 120, Technique::Deferred) });
    assert!(e.contains("6 shadow-casting lights need a shadow atlas of at least 9 KiB") && !e.contains('\n'), "{e}");
    common::assert_clean(&gpu);
}

/// A spot light takes only the faces its cone lights, its cube turned to its cone
/// (`shadow::CubeFrame`): aimed past the wall and down with a 40° outer half-angle, one face
/// (fewer texels than the same light as a point light); aimed straight down from higher up, one
/// face; a 60° cone, wider than a face, at most the three faces around the corner it is centred
/// on. Every frame matches the ray-cast reference (which shades the cone's falloff and exact
/// visibility): the turned cube draws and looks up the same shadows.
#[test]
fn a_spot_light_takes_only_the_faces_its_cone_lights() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-spot");
    let point = scene_of(&dir, FLOOR_AND_WALL, &description("shadows = true\n"));
    let (_, all) = assert_matches_reference(&gpu, &point, ShadowSettings::default(), "point light");
    let spot = scene_of(&dir, FLOOR_AND_WALL, &description("shadows = true\ntype = \"spot\"\ndirection = [1, -0.6, 0]\nouter_angle = 40\n"));
    assert!(spot.spots.first().is_some_and(Option::is_some), "the light is a spot light");
    let (shadowed, cone) = assert_matches_reference(&gpu, &spot, ShadowSettings::default(), "spot light");
    eprintln!("faces with receivers: point light {}, spot light {}", all.faces_with_receivers, cone.faces_with_receivers);
    assert!(shadowed > 3000, "{shadowed} pixels in shadow");
    assert!(all.faces_with_receivers > 1, "{all:?}");
    assert_eq!(cone.faces_with_receivers, 1, "a 40° cone lies in one face of its turned cube: {cone:?} against {all:?}");
    assert!(cone.atlas_used < all.atlas_used, "{cone:?} against {all:?}");
    let wide = scene_of(&dir, FLOOR_AND_WALL, &description("shadows = true\ntype = \"spot\"\ndirection = [1, -0.6, 0.3]\nouter_angle = 60\n"));
    let (_, corner) = assert_matches_reference(&gpu, &wide, ShadowSettings::default(), "wide spot light");
    assert!((1..=3).contains(&corner.faces_with_receivers), "a 60° cone lies in the three faces around a corner: {corner:?}");
    // 6 m over the floor, aimed down one face's axis with a cone narrower than the face's 45°:
    // that face alone (the wall still shadows the floor behind it, 0 < x < 1, inside the cone).
    let down = scene_of(&dir, FLOOR_AND_WALL, &description_at([-2.0, 6.0, 0.0], "shadows = true\ntype = \"spot\"\ndirection = [0, -1, 0]\nouter_angle = 40\n"));
    let (_, one) = assert_matches_reference(&gpu, &down, ShadowSettings::default(), "spot light aimed down");
    assert_eq!(one.faces_with_receivers, 1, "{one:?}");
    common::assert_clean(&gpu);
}

/// A light over a bare floor casts shadows on nothing: the shadowed frame equals the unshadowed
/// one within 1/255 everywhere, grazing corners included (the bias rule keeps the floor from
/// shadowing itself).
#[test]
fn a_surface_never_shadows_itself() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-floor");
    dir.write_bytes("floor.obj", FLOOR_AND_WALL.lines().filter(|l| !l.starts_with("f 5")).collect::<Vec<_>>().join("\n").as_bytes());
    let path = dir.write_bytes("scene.toml", description("shadows = true\n").as_bytes());
    let scene = Scene::load(path.to_str().unwrap(), &common::assets::dir()).unwrap_or_else(|e| panic!("{e:#}"));
    let (plain, _, _) = unshadowed_frame(&gpu, &scene);
    for resolution in [16, 256, 1024] {
        let (f, _, _) = shadowed_and_reference(&gpu, &scene, ShadowSettings { resolution, ..Default::default() });
        let worst = worst_channel(&f.pixels, &plain.pixels);
        assert!(worst <= 1, "at {resolution}² per face the bare floor differs by {worst}/255 from its unshadowed frame");
    }
    common::assert_clean(&gpu);
}

/// Both knobs reach the kernel: a coarser map and the other filter each change the shadow's
/// edge.
#[test]
fn shadow_resolution_and_filter_change_the_image() {
    let gpu = common::gpu();
    let dir = TempDir::new("shadow-knobs");
    let scene = scene(&dir, "shadows = true\n");
    let at = |resolution, filter| shadowed_and_reference(&gpu, &scene, ShadowSettings { resolution, filter, ..Default::default() }).0.pixels;
    let changed = |a: &[u32], b: &[u32]| a.iter().zip(b).filter(|(a, b)| channel_diff(**a, **b) > 1).count();
    let coarse = at(32, ShadowFilter::Bilinear);
    let resolution = changed(&at(256, ShadowFilter::Bilinear), &coarse);
    let filter = changed(&at(32, ShadowFilter::Nearest), &coarse);
    eprintln!("pixels changed: {resolution} by 32² against 256² per face, {filter} by nearest against bilinear at 32²");
    assert!(resolution > 20, "--shadow-resolution changes {resolution} pixels");
    assert!(filter > 20, "--shadow-filter changes {filter} pixels");
    common::assert_clean(&gpu);
}

/// The command line: `deferred`, `tiled` and `forward-plus` render a description with a
/// shadow-casting light; `--shadow-reference` shades the ray-cast
/// reference; `--shadow-fraction` marks generated lights and `--shadows all` a scene's own; bad
/// knobs and what the reference cannot take are refused.
#[test]
fn render_draws_shadows_or_refuses_them() {
    let dir = TempDir::new("shadow-cli");
    let scene_path = {
        dir.write_bytes("floor.obj", FLOOR_AND_WALL.as_bytes());
        dir.write_bytes("scene.toml", description("shadows = true\n").as_bytes())
    };
    let out = dir.join("shadowed.png");
    let run = |technique: &str, extra: &[&str]| {
        let base = ["render", "--scene", scene_path.to_str().unwrap(), "--technique", technique, "--width", "64", "--height", "48", "--frames", "0", "--out", out.to_str().unwrap()];
        manylights_env(base.iter().copied().chain(extra.iter().copied()), &[])
    };
    let json = dir.join("stats.json");
    let r = run("deferred", &["--shadow-resolution", "64", "--shadow-filter", "nearest", "--stats", json.to_str().unwrap()]);
    assert!(r.ok, "{}", r.stderr);
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let sh = &stats["shadows"];
    assert_eq!((sh["casters"].as_u64(), sh["resolution"].as_u64(), sh["filter"].as_str(), sh["raster"].as_str(), sh["faces"].as_str()), (Some(1), Some(64), Some("nearest"), Some("compute"), Some("receivers")), "{sh}");
    assert!(sh["faces_with_receivers"].as_u64().is_some_and(|f| (1..=6).contains(&f)), "{sh}");
    assert_eq!(sh["map_bytes"].as_u64(), Some(6 * 64 * 64 * 4), "{sh}");
    assert!(stats["gpu_ms"]["passes"]["shadow maps"].as_f64().is_some(), "no shadow pass timed: {}", stats["gpu_ms"]["passes"]);
    // Without a caster the frame has no shadow pass, buffers or statistics.
    let plain = dir.write_bytes("plain.toml", description("").as_bytes());
    let args = ["render", "--scene", plain.to_str().unwrap(), "--width", "64", "--height", "48", "--frames", "0", "--out", out.to_str().unwrap(), "--stats", json.to_str().unwrap()];
    let r = manylights_env(args, &[]);
    assert!(r.ok, "{}", r.stderr);
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert!(stats["shadows"].is_null() && stats["gpu_ms"]["passes"]["shadow maps"].is_null(), "{stats}");
    assert!(!stats["bytes"]["buffers"].as_object().unwrap().keys().any(|k| k.contains("shadow")), "{}", stats["bytes"]["buffers"]);
    for technique in ["tiled", "forward-plus"] {
        let r = run(technique, &["--stats", json.to_str().unwrap()]);
        assert!(r.ok, "{technique}: {}", r.stderr);
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        assert_eq!(stats["shadows"]["casters"].as_u64(), Some(1), "{technique}: {}", stats["shadows"]);
        assert!(stats["gpu_ms"]["passes"]["shadow maps"].as_f64().is_some(), "{technique}: no shadow pass timed: {}", stats["gpu_ms"]["passes"]);
    }
    assert_refused(&run("deferred", &["--shadow-resolution", "0"]), "a zero resolution", BAD_INPUT, &["--shadow-resolution 0"]);
    assert_refused(&run("deferred", &["--msaa", "4"]), "shadows with MSAA", BAD_INPUT, &["--msaa 4", "shadows"]);
    let r = run("deferred", &["--shadow-reference"]);
    assert!(r.ok, "{}", r.stderr);
    assert!(r.stderr.contains("shadow reference: 1 of 1 lights cast shadows"), "{}", r.stderr);
    assert!(out.exists());
    assert_refused(&run("deferred", &["--shadow-fraction", "0.5"]), "--shadow-fraction with the scene's own lights", BAD_INPUT, &["--shadow-fraction applies to the --lights"]);
    // --shadows all marks the scene's own lights (here a description without `shadows = true`).
    let r = manylights_env(["render", "--scene", plain.to_str().unwrap(), "--shadows", "all", "--width", "64", "--height", "48", "--frames", "0", "--out", out.to_str().unwrap(), "--stats", json.to_str().unwrap()], &[]);
    assert!(r.ok, "{}", r.stderr);
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(stats["shadows"]["casters"].as_u64(), Some(1), "{}", stats["shadows"]);
    let both = ["render", "--scene", "city", "--lights", "40", "--shadow-fraction", "0.5", "--shadows", "all", "--width", "64", "--height", "48", "--frames", "0", "--out", out.to_str().unwrap()];
    assert_refused(&manylights_env(both, &[]), "--shadows all beside a fraction", BAD_INPUT, &["--shadows all and --shadow-fraction 0.5"]);
    let generated = |technique: &str, fraction: &str| {
        let args = ["render", "--scene", "city", "--technique", technique, "--lights", "40", "--shadow-fraction", fraction, "--width", "64", "--height", "48", "--frames", "0", "--out", out.to_str().unwrap()];
        manylights_env(args, &[])
    };
    let r = generated("deferred", "0.25");
    assert!(r.ok, "{}", r.stderr);
    let r = generated("forward-plus", "0.25");
    assert!(r.ok, "{}", r.stderr);
    assert_refused(&generated("deferred", "2"), "a fraction above 1", BAD_INPUT, &["not in [0, 1]"]);
}
