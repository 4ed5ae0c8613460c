//! glTF 2.0 import, feature by feature: small files built in code (`common::gltf`), each loaded,
//! rendered on the local device (validation on) by every technique that accepts it and compared
//! with the brute-force reference (`deferred`) within 1/255, plus a check that fails when the
//! feature is ignored (a transform moves the mesh, a texture's colours show, the mask cuts out,
//! the camera changes the view, a cone bounds its spot, …). Then the features the importer skips
//! (one warning line each) and malformed files (one-line errors, no panic).
mod common;
use common::compare::assert_techniques_match;
use common::gltf::{light_node, rotation, Buffer, Builder};
use common::render::frame;
use common::temp::TempDir;
use glam::{Mat4, Quat, Vec3};
use host::render::{Frame, Settings, Technique};
use host::scene::{Camera, Scene};
use serde_json::json;
use std::path::Path;

const W: u32 = 64;
const H: u32 = 48;

/// The test settings (read-back on: depth says where geometry is).
fn settings(technique: Technique) -> Settings {
    Settings { read_back: true, ..common::render::settings(W, H, technique) }
}

fn load(p: &Path) -> Scene {
    Scene::load(p.to_str().unwrap(), &common::assets::dir()).unwrap_or_else(|e| panic!("{}: {e:#}", p.display()))
}

/// Loads `p` and checks it loads without warnings.
fn load_clean(p: &Path) -> Scene {
    let s = load(p);
    assert!(s.warnings.is_empty(), "{}: {:?}", p.display(), s.warnings);
    s
}

/// The error loading `p` gives: one line naming the file.
fn load_err(p: &Path) -> String {
    let e = match Scene::load(p.to_str().unwrap(), &common::assets::dir()) {
        Ok(_) => panic!("{} loaded; an error was expected", p.display()),
        Err(e) => format!("{e:#}"),
    };
    let name = p.file_name().unwrap().to_str().unwrap();
    assert!(e.contains(name) && !e.contains('\n'), "one line naming {name} expected: {e}");
    e
}

/// Renders `scene` (its own lights) with the reference and with every other technique that
/// accepts it (those with a transparent pass when it has transparent materials), asserting each
/// within 1/255 of the reference; returns the reference frame.
fn render_every_technique(gpu: &host::gpu::Gpu, scene: &Scene, what: &str) -> Frame {
    let reference = frame(gpu, scene, &scene.lights, &settings(Technique::Deferred));
    let others: Vec<Technique> = Technique::ALL.iter().copied().filter(|&t| t != Technique::Deferred && (t.draws_transparency() || !scene.has_transparency())).collect();
    assert!(others.len() >= 3, "{what}: techniques {others:?}");
    assert_techniques_match(gpu, &reference.pixels, scene, &scene.lights, &settings(Technique::Deferred), &others, what);
    reference
}

/// The pixel (column, row) where the camera sees the world point `p`.
fn pixel_of(c: &Camera, p: Vec3) -> (u32, u32) {
    let v = glam::camera::rh::view::look_at_mat4(c.position, c.target, c.up.normalize()).transform_point3(p);
    let t = (c.fov_y_degrees.to_radians() / 2.0).tan();
    let (x, y) = (v.x / -v.z / (t * W as f32 / H as f32), v.y / -v.z / t);
    assert!(v.z < 0.0 && x.abs() < 1.0 && y.abs() < 1.0, "{p} is outside the view");
    (((x * 0.5 + 0.5) * W as f32) as u32, ((0.5 - y * 0.5) * H as f32) as u32)
}

/// The frame's pixel showing `p`, as `[r, g, b]`.
fn rgb_at(f: &Frame, c: &Camera, p: Vec3) -> [u32; 3] {
    let (x, y) = pixel_of(c, p);
    let px = f.pixels[(y * W + x) as usize];
    [px & 255, (px >> 8) & 255, (px >> 16) & 255]
}

/// Whether the frame shows geometry (not background) where it sees `p`.
fn geometry_at(f: &Frame, c: &Camera, p: Vec3) -> bool {
    let (x, y) = pixel_of(c, p);
    f32::from_bits(f.readback.as_ref().unwrap().depth[(y * W + x) as usize]) > 0.0
}

/// A perspective camera node at `position` with `rotation`.
fn camera_node(b: &mut Builder, position: [f32; 3], rotation: [f32; 4], yfov: f32, znear: f32, zfar: f32) {
    let cam = b.push("cameras", json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": znear, "zfar": zfar, "aspectRatio": 1.333}}));
    b.root(json!({"camera": cam, "translation": position, "rotation": rotation}));
}

/// A diffuse (non-metallic) material of colour `rgba` and `mode`.
fn diffuse(b: &mut Builder, rgba: [f32; 4], extra: serde_json::Value) -> usize {
    let mut m = json!({"pbrMetallicRoughness": {"baseColorFactor": rgba, "metallicFactor": 0.0, "roughnessFactor": 1.0}});
    for (k, v) in extra.as_object().unwrap() {
        m[k] = v.clone();
    }
    b.material(m)
}

/// The camera the front-facing scenes use: at (0, 0, 4) looking down −z.
fn front_camera(b: &mut Builder) -> Camera {
    camera_node(b, [0.0, 0.0, 4.0], [0.0, 0.0, 0.0, 1.0], 0.8, 0.1, 100.0);
    Camera { position: Vec3::new(0.0, 0.0, 4.0), target: Vec3::new(0.0, 0.0, 3.0), up: Vec3::Y, fov_y_degrees: 0.8f32.to_degrees(), near: 0.1, far: 100.0 }
}

/// A white point light in front of the z = 0 plane, reaching all of what the front camera sees.
fn front_light(b: &mut Builder) {
    let l = b.light(json!({"type": "point", "intensity": 3.0, "range": 20.0}));
    b.root(light_node(l, json!({"translation": [0.0, 0.0, 1.5]})));
}

/// Nodes: a parent with translation, rotation and scale and a translated child holding a square,
/// and a node given by a matrix holding the same square: each square lands where its world
/// transform puts it (checked on the vertices, and in the image: geometry at each square's
/// centre, none at the origin where an untransformed square would be).
#[test]
fn node_transforms_place_the_meshes() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-nodes");
    let mut b = Builder::new();
    let cam = front_camera(&mut b);
    front_light(&mut b);
    let m = diffuse(&mut b, [0.8, 0.8, 0.8, 1.0], json!({}));
    let square = b.rectangle([0.0; 3], [0.2, 0.0, 0.0], [0.0, 0.2, 0.0], Some(m));
    let mesh = b.mesh(vec![square]);
    let turn = rotation([0.0, 0.0, 1.0], 0.5);
    let child = b.push("nodes", json!({"mesh": mesh, "translation": [0.3, 0.0, 0.0]}));
    b.root(json!({"translation": [-1.0, 0.4, 0.0], "rotation": turn, "scale": [1.5, 1.0, 1.0], "children": [child]}));
    let matrix = Mat4::from_translation(Vec3::new(1.0, -0.5, 0.0)) * Mat4::from_rotation_z(-0.3) * Mat4::from_scale(Vec3::new(1.0, 1.2, 1.0));
    b.root(json!({"mesh": mesh, "matrix": matrix.to_cols_array()}));
    let scene = load_clean(&b.write(dir.path(), "nodes.gltf", Buffer::External("nodes.bin")));
    let parent = Mat4::from_scale_rotation_translation(Vec3::new(1.5, 1.0, 1.0), Quat::from_array(turn), Vec3::new(-1.0, 0.4, 0.0));
    let worlds = [parent * Mat4::from_translation(Vec3::new(0.3, 0.0, 0.0)), matrix];
    assert_eq!(scene.meshes.len(), 2);
    let corners = [[-0.2, 0.2, 0.0], [0.2, 0.2, 0.0], [0.2, -0.2, 0.0], [-0.2, -0.2, 0.0]].map(Vec3::from_array);
    for (mesh, world) in scene.meshes.iter().zip(worlds) {
        for (p, c) in mesh.positions.iter().zip(corners) {
            assert!(Vec3::from_array(*p).distance(world.transform_point3(c)) < 1e-5, "{p:?} is not {}", world.transform_point3(c));
        }
    }
    let f = render_every_technique(&gpu, &scene, "node transforms");
    for world in worlds {
        assert!(geometry_at(&f, &cam, world.transform_point3(Vec3::ZERO)), "no geometry at {}", world.transform_point3(Vec3::ZERO));
    }
    assert!(!geometry_at(&f, &cam, Vec3::ZERO), "geometry at the origin: the transforms were not applied");
}

/// The base colour factor tints the surface: an orange square (no texture) shows red above
/// green and no blue on every lit pixel; a white one would be grey.
#[test]
fn base_colour_factor_tints_the_surface() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-factor");
    let mut b = Builder::new();
    let cam = front_camera(&mut b);
    front_light(&mut b);
    let m = diffuse(&mut b, [1.0, 0.3, 0.0, 1.0], json!({}));
    let square = b.rectangle([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Some(m));
    let mesh = b.mesh(vec![square]);
    b.root(json!({"mesh": mesh}));
    let scene = load_clean(&b.write(dir.path(), "factor.gltf", Buffer::External("factor.bin")));
    assert_eq!(scene.materials[0].albedo, [1.0, 0.3, 0.0]);
    let f = render_every_technique(&gpu, &scene, "base colour factor");
    for p in [Vec3::ZERO, Vec3::new(0.6, 0.6, 0.0), Vec3::new(-0.6, -0.5, 0.0)] {
        let [r, g, bl] = rgb_at(&f, &cam, p);
        assert!(r > 60 && g > 10 && r > g + 40 && bl == 0, "at {p}: {:?} is not orange", [r, g, bl]);
    }
}

/// A 2×2 base colour texture (embedded PNG: red, green / blue, white) shows its four colours
/// on the four quarters of a square whose factor is white.
#[test]
fn base_colour_texture_shows_its_texels() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-texture");
    let mut b = Builder::new();
    let cam = front_camera(&mut b);
    front_light(&mut b);
    let texels = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 255]];
    let img = image::RgbaImage::from_fn(2, 2, |x, y| image::Rgba(texels[(2 * y + x) as usize]));
    let t = b.texture(&img);
    let m = diffuse(&mut b, [1.0; 4], json!({}));
    b.json["materials"][m]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": t});
    let square = b.rectangle([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Some(m));
    let mesh = b.mesh(vec![square]);
    b.root(json!({"mesh": mesh}));
    let scene = load_clean(&b.write(dir.path(), "texture.gltf", Buffer::DataUri));
    assert!(scene.effects.textures && scene.materials[0].albedo_texture.is_some(), "{:?}", scene.materials[0]);
    let f = render_every_technique(&gpu, &scene, "base colour texture");
    // Quarter centres are texel centres: uv (0.25, 0.25) is the top-left texel.
    let quarters = [(Vec3::new(-0.5, 0.5, 0.0), 0), (Vec3::new(0.5, 0.5, 0.0), 1), (Vec3::new(-0.5, -0.5, 0.0), 2)];
    for (p, channel) in quarters {
        let c = rgb_at(&f, &cam, p);
        let others = (0..3).filter(|&k| k != channel).map(|k| c[k]).max().unwrap();
        // Not exactly 0: the pixel centre is not the texel centre, and filtering mixes in a little
        // of the neighbours.
        assert!(c[channel] > 80 && c[channel] > 8 * others, "at {p}: {c:?} is not the texel's colour (channel {channel})");
    }
    let white = rgb_at(&f, &cam, Vec3::new(0.5, -0.5, 0.0));
    assert!(white.iter().all(|&c| c > 80), "the white texel: {white:?}");
}

/// Alpha modes on a red square in front of a grey wall, its texture's left texel at alpha 0.3
/// and its right one opaque: `OPAQUE` draws both halves red; `MASK` (cutoff 0.5) cuts the left
/// half out, showing the wall exactly as without the square, while cutoff 0.2 keeps it; `BLEND`
/// (factor alpha 0.5) mixes the square with the wall.
#[test]
fn alpha_modes_opaque_mask_and_blend() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-alpha");
    let build = |mode: Option<serde_json::Value>, alpha: f32| {
        let mut b = Builder::new();
        front_camera(&mut b);
        front_light(&mut b);
        let grey = diffuse(&mut b, [0.5, 0.5, 0.5, 1.0], json!({}));
        let wall = b.rectangle([0.0, 0.0, -0.5], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], Some(grey));
        let mut prims = vec![wall];
        if let Some(extra) = mode {
            let img = image::RgbaImage::from_fn(2, 1, |x, _| image::Rgba([255, 255, 255, if x == 0 { 77 } else { 255 }]));
            let t = b.texture(&img);
            let red = diffuse(&mut b, [1.0, 0.0, 0.0, alpha], extra);
            b.json["materials"][red]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": t});
            prims.push(b.rectangle([0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.6, 0.0], Some(red)));
        }
        let mesh = b.mesh(prims);
        b.root(json!({"mesh": mesh}));
        b
    };
    let cam = front_camera(&mut Builder::new());
    let (left, right) = (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0));
    let cases = [
        ("wall only", None, 1.0),
        ("opaque", Some(json!({"alphaMode": "OPAQUE"})), 1.0),
        ("mask", Some(json!({"alphaMode": "MASK", "alphaCutoff": 0.5})), 1.0),
        ("mask at 0.2", Some(json!({"alphaMode": "MASK", "alphaCutoff": 0.2})), 1.0),
        ("blend", Some(json!({"alphaMode": "BLEND"})), 0.5),
    ];
    let mut frames = Vec::new();
    for (what, mode, alpha) in cases {
        let scene = load_clean(&build(mode, alpha).write(dir.path(), &format!("{}.gltf", what.replace(' ', "-")), Buffer::DataUri));
        assert_eq!(scene.has_transparency(), what == "blend", "{what}");
        assert_eq!(scene.effects.alpha_test, what == "mask", "{what}: alpha test (cutoff 0.2 keeps every texel)");
        let f = render_every_technique(&gpu, &scene, what);
        frames.push((rgb_at(&f, &cam, left), rgb_at(&f, &cam, right)));
    }
    let [(wall, _), (opaque_l, opaque_r), (mask_l, mask_r), (mask2_l, _), (blend_l, blend_r)] = frames[..] else { unreachable!() };
    let red = |c: [u32; 3]| c[0] > 60 && c[1] == 0 && c[2] == 0;
    assert!(wall[0] > 20 && wall[0] == wall[2], "the grey wall: {wall:?}");
    assert!(red(opaque_l) && red(opaque_r) && red(mask_r) && red(mask2_l), "red halves: {opaque_l:?} {opaque_r:?} {mask_r:?} {mask2_l:?}");
    assert!((0..3).all(|k| mask_l[k].abs_diff(wall[k]) <= 1), "the mask's cut-out half shows {mask_l:?}, not the wall {wall:?}");
    for c in [blend_l, blend_r] {
        assert!(c[0] > wall[0] && c[0] < opaque_r[0] && c[1] > 0 && c[1] < wall[1], "blend: {c:?} is not between the wall {wall:?} and red {opaque_r:?}");
    }
}

/// The first perspective camera: its node's position and orientation (a turned camera, up tilted
/// by a roll), `yfov`, `znear` and `zfar` reach the scene and the render (the cluster grid's
/// near, far and field of view; the image equals that camera's, differs from the default view);
/// a near plane past the wall clips it away.
#[test]
fn camera_position_orientation_fov_near_far() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-camera");
    let build = |znear: f32| {
        let mut b = Builder::new();
        let turn = Quat::from_rotation_y(0.3) * Quat::from_rotation_z(0.2);
        camera_node(&mut b, [1.5, 0.5, 4.0], turn.to_array(), 0.6, znear, 40.0);
        front_light(&mut b);
        let m = diffuse(&mut b, [0.8, 0.8, 0.8, 1.0], json!({}));
        let wall = b.rectangle([0.0; 3], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0], Some(m));
        let mesh = b.mesh(vec![wall]);
        b.root(json!({"mesh": mesh}));
        (b, turn)
    };
    let (b, turn) = build(0.25);
    let scene = load_clean(&b.write(dir.path(), "camera.gltf", Buffer::External("camera.bin")));
    let c = scene.camera;
    let (eye, forward, up) = (Vec3::new(1.5, 0.5, 4.0), turn * Vec3::NEG_Z, turn * Vec3::Y);
    assert!(c.position.distance(eye) < 1e-6 && (c.target - c.position).normalize().distance(forward) < 1e-5 && c.up.normalize().distance(up) < 1e-5, "{c:?}");
    assert!((c.fov_y_degrees - 0.6f32.to_degrees()).abs() < 1e-4 && c.near == 0.25 && c.far == 40.0, "{c:?}");
    let f = render_every_technique(&gpu, &scene, "glTF camera");
    assert!((f.grid.near, f.grid.far) == (0.25, 40.0) && (f.grid.tan_half_fov_y - 0.3f32.tan()).abs() < 1e-5, "grid {:?}", f.grid);
    let mut by_hand = scene.clone();
    by_hand.camera = Camera { position: eye, target: eye + forward, up, fov_y_degrees: 0.6f32.to_degrees(), near: 0.25, far: 40.0 };
    assert_eq!(frame(&gpu, &by_hand, &by_hand.lights, &settings(Technique::Deferred)).pixels, f.pixels, "the glTF camera's image is that camera's");
    let mut default = scene.clone();
    default.camera = host::scene::obj::default_camera(scene.bounds);
    assert_ne!(frame(&gpu, &default, &default.lights, &settings(Technique::Deferred)).pixels, f.pixels, "the camera changes the view");
    assert!(common::compare::geometry_pixels(&f) == (W * H) as usize, "the wall fills the view");
    // The wall is about 4 units away: a near plane at 6 leaves nothing in front of the camera.
    let clipped = load_clean(&build(6.0).0.write(dir.path(), "near.gltf", Buffer::External("near.bin")));
    assert_eq!(common::compare::geometry_pixels(&frame(&gpu, &clipped, &clipped.lights, &settings(Technique::Deferred))), 0, "znear 6 clips the wall");
}

/// A floor seen from above (camera 8 units up, looking down −y).
fn floor_scene(b: &mut Builder) -> Camera {
    camera_node(b, [0.0, 8.0, 0.0], rotation([1.0, 0.0, 0.0], -std::f32::consts::FRAC_PI_2), 1.0, 0.5, 50.0);
    let m = diffuse(b, [1.0; 4], json!({}));
    let floor = b.rectangle([0.0; 3], [5.0, 0.0, 0.0], [0.0, 0.0, -3.5], Some(m));
    let mesh = b.mesh(vec![floor]);
    b.root(json!({"mesh": mesh}));
    Camera { position: Vec3::new(0.0, 8.0, 0.0), target: Vec3::new(0.0, 7.0, 0.0), up: Vec3::NEG_Z, fov_y_degrees: 1.0f32.to_degrees(), near: 0.5, far: 50.0 }
}

/// Lit: a pixel brighter than black.
fn lit_at(f: &Frame, c: &Camera, p: Vec3) -> bool {
    rgb_at(f, c, p).iter().any(|&v| v > 0)
}

/// Point lights: one with `range` 1 lights the floor within 1 unit and nothing past it (its
/// radius is the range); one without a range gets the documented radius
/// `√(256 · intensity · max(colour))` and lights the floor 3 units away, not 8.
#[test]
fn point_lights_with_and_without_range() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-points");
    let mut b = Builder::new();
    let cam = floor_scene(&mut b);
    let ranged = b.light(json!({"type": "point", "intensity": 1.0, "range": 1.0, "color": [1.0, 0.5, 0.5]}));
    b.root(light_node(ranged, json!({"translation": [-3.0, 0.3, 0.0]})));
    let open = b.light(json!({"type": "point", "intensity": 0.2}));
    b.root(light_node(open, json!({"translation": [3.0, 1.0, 0.0]})));
    let scene = load_clean(&b.write(dir.path(), "points.gltf", Buffer::External("points.bin")));
    let radii: Vec<f32> = scene.lights.iter().map(|l| l.radius).collect();
    assert_eq!(radii, [1.0, (256.0f32 * 0.2).sqrt()]);
    assert_eq!((scene.lights[0].colour, scene.lights[0].intensity, scene.lights[0].position), ([1.0, 0.5, 0.5], 1.0, [-3.0, 0.3, 0.0]));
    let f = render_every_technique(&gpu, &scene, "point lights");
    assert!(lit_at(&f, &cam, Vec3::new(-3.0, 0.0, 0.5)), "inside the range");
    assert!(!lit_at(&f, &cam, Vec3::new(-4.5, 0.0, -1.2)), "past the range (1.9 units from the light)");
    assert!(lit_at(&f, &cam, Vec3::new(0.0, 0.0, 0.0)), "within the rule's radius (7.2) of the light without a range");
    assert!(!lit_at(&f, &cam, Vec3::new(-4.5, 0.0, 3.0)), "past both lights' radii");
}

/// A spot light 2 units above the floor, turned by its node to point down (−z → −y): the floor
/// is lit inside its outer cone and dark outside, and its direction is the node's.
#[test]
fn spot_light_lights_only_inside_its_cone() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-spot");
    let mut b = Builder::new();
    let cam = floor_scene(&mut b);
    let spot = b.light(json!({"type": "spot", "intensity": 4.0, "range": 10.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}}));
    b.root(light_node(spot, json!({"translation": [0.0, 2.0, 0.0], "rotation": rotation([1.0, 0.0, 0.0], -std::f32::consts::FRAC_PI_2)})));
    let scene = load_clean(&b.write(dir.path(), "spot.gltf", Buffer::Glb));
    let cone = scene.spots.iter().flatten().next().expect("a spot");
    assert!(cone.direction.normalize().distance(Vec3::NEG_Y) < 1e-5 && (cone.inner, cone.outer) == (0.2, 0.4), "{cone:?}");
    let f = render_every_technique(&gpu, &scene, "spot light");
    // tan(0.4) · 2 ≈ 0.85: the cone's footprint radius on the floor.
    assert!(lit_at(&f, &cam, Vec3::new(0.0, 0.0, 0.3)) && lit_at(&f, &cam, Vec3::new(0.5, 0.0, 0.0)), "inside the cone");
    for p in [Vec3::new(1.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.2), Vec3::new(-2.0, 0.0, 1.0)] {
        assert!(!lit_at(&f, &cam, p), "outside the cone at {p}: {:?}", rgb_at(&f, &cam, p));
    }
}

/// A directional light turned by its node to shine down (−z → −y): the floor, facing it, is lit;
/// a wall facing +z (edge-on to it) stays dark. Unturned (shining along −z) it would be the other
/// way round.
#[test]
fn directional_light_lights_surfaces_facing_it() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-sun");
    let mut b = Builder::new();
    camera_node(&mut b, [0.0, 2.0, 5.0], rotation([1.0, 0.0, 0.0], -0.3), 1.0, 0.1, 100.0);
    let cam = Camera { position: Vec3::new(0.0, 2.0, 5.0), target: Vec3::new(0.0, 2.0, 5.0) + Quat::from_rotation_x(-0.3) * Vec3::NEG_Z, up: Quat::from_rotation_x(-0.3) * Vec3::Y, fov_y_degrees: 1.0f32.to_degrees(), near: 0.1, far: 100.0 };
    let m = diffuse(&mut b, [1.0; 4], json!({}));
    let floor = b.rectangle([0.0; 3], [3.0, 0.0, 0.0], [0.0, 0.0, -3.0], Some(m));
    let wall = b.rectangle([0.0, 1.5, -2.0], [3.0, 0.0, 0.0], [0.0, 1.5, 0.0], Some(m));
    let mesh = b.mesh(vec![floor, wall]);
    b.root(json!({"mesh": mesh}));
    let sun = b.light(json!({"type": "directional", "intensity": 2.0, "color": [1.0, 0.9, 0.8]}));
    b.root(light_node(sun, json!({"rotation": rotation([1.0, 0.0, 0.0], -std::f32::consts::FRAC_PI_2)})));
    let scene = load_clean(&b.write(dir.path(), "sun.gltf", Buffer::DataUri));
    assert!(scene.lights.is_empty() && scene.directional.len() == 1 && scene.directional[0].direction.normalize().distance(Vec3::NEG_Y) < 1e-5, "{:?}", scene.directional);
    let f = render_every_technique(&gpu, &scene, "directional light");
    let floor = rgb_at(&f, &cam, Vec3::new(0.5, 0.0, 0.5));
    assert!(floor[0] > 100 && floor[0] > floor[2], "the floor faces the light: {floor:?}");
    let wall = Vec3::new(-0.5, 1.5, -2.0);
    assert!(geometry_at(&f, &cam, wall) && rgb_at(&f, &cam, wall) == [0; 3], "the wall is edge-on to the light: {:?}", rgb_at(&f, &cam, wall));
}

/// A document with a bit of everything (nodes, a textured and a plain material, a camera, a
/// point light and a spot): its buffer external, a data URI, or the `.glb` `BIN` chunk.
fn everything() -> Builder {
    let mut b = Builder::new();
    front_camera(&mut b);
    front_light(&mut b);
    let spot = b.light(json!({"type": "spot", "intensity": 2.0, "range": 6.0, "color": [0.3, 0.3, 1.0], "spot": {"outerConeAngle": 0.5}}));
    b.root(light_node(spot, json!({"translation": [0.8, 0.0, 2.0]})));
    let img = image::RgbaImage::from_fn(4, 4, |x, y| image::Rgba([60 * x as u8, 60 * y as u8, 200, 255]));
    let t = b.texture(&img);
    let textured = diffuse(&mut b, [1.0, 0.9, 0.8, 1.0], json!({}));
    b.json["materials"][textured]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": t});
    let plain = diffuse(&mut b, [0.2, 0.7, 0.3, 1.0], json!({}));
    let wall = b.rectangle([0.0, 0.0, -0.5], [2.5, 0.0, 0.0], [0.0, 2.0, 0.0], Some(plain));
    let square = b.rectangle([0.0; 3], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0], Some(textured));
    let (walls, squares) = (b.mesh(vec![wall]), b.mesh(vec![square]));
    b.root(json!({"mesh": walls}));
    let child = b.push("nodes", json!({"mesh": squares, "translation": [0.6, 0.0, 0.0]}));
    b.root(json!({"translation": [-0.3, 0.2, 0.0], "rotation": rotation([0.0, 1.0, 0.0], 0.4), "children": [child]}));
    b
}

/// The same scene from an external `.bin`, a data-URI buffer and a `.glb`: equal scenes (meshes,
/// materials, texels, camera, lights), each rendered by every technique within 1/255 of the
/// reference, and the three references equal.
#[test]
fn external_embedded_and_glb_buffers_load_alike() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-buffers");
    let b = everything();
    let files = [b.write(dir.path(), "external.gltf", Buffer::External("external.bin")), b.write(dir.path(), "embedded.gltf", Buffer::DataUri), b.write(dir.path(), "binary.glb", Buffer::Glb)];
    let plain = |s: &Scene| s.materials.iter().map(|m| (m.albedo, m.opacity, m.specular, m.roughness, m.albedo_texture.is_some())).collect::<Vec<_>>();
    let texels = |s: &Scene| s.textures.iter().map(|t| t.rgba8.clone()).collect::<Vec<_>>();
    let scenes: Vec<Scene> = files.iter().map(|p| load_clean(p)).collect();
    let first = &scenes[0];
    assert!(first.meshes.len() == 2 && first.lights.len() == 2 && first.spots.iter().flatten().count() == 1 && first.textures.len() == 1, "{first:?}");
    let mut reference: Option<Vec<u32>> = None;
    for (p, s) in files.iter().zip(&scenes) {
        assert_eq!((&s.meshes, plain(s), texels(s), &s.lights, &s.spots, s.camera), (&first.meshes, plain(first), texels(first), &first.lights, &first.spots, first.camera), "{}", p.display());
        let f = render_every_technique(&gpu, s, &p.display().to_string());
        assert_eq!(reference.get_or_insert_with(|| f.pixels.clone()), &f.pixels, "{}: another image", p.display());
    }
}

/// The PNG `manylights render` writes for `scene` with the reference technique at W×H, packed
/// like [`Frame::pixels`]; the run must print no warning.
fn cli_png(dir: &TempDir, scene: &Path, name: &str) -> Vec<u32> {
    let out = dir.join(name);
    let (w, h) = (W.to_string(), H.to_string());
    let args = ["render", "--scene", scene.to_str().unwrap(), "--technique", "deferred", "--width", &w, "--height", &h, "--tile-size", "32", "--frames", "0", "--out", out.to_str().unwrap()];
    let run = common::cli::manylights(args);
    assert!(run.ok && !run.stderr.contains("warning"), "{args:?}:\n{}", run.stderr);
    image::open(&out).unwrap().to_rgba8().pixels().map(|p| u32::from_le_bytes(p.0)).collect()
}

/// `--scene file.gltf`, `--scene file.glb` and a description's `geometry = "file.gltf"` load the
/// file: the binary's image equals the one rendered here from the loaded scene (camera and
/// lights from the file), and the description's scene is the file's.
#[test]
fn scene_flag_and_toml_geometry_load_gltf() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-cli");
    let b = everything();
    let gltf = b.write(dir.path(), "scene.gltf", Buffer::External("scene.bin"));
    let glb = b.write(dir.path(), "scene.glb", Buffer::Glb);
    let toml = dir.write("described.toml", "geometry = \"scene.gltf\"\n");
    let scene = load_clean(&gltf);
    let described = load_clean(&toml);
    assert_eq!((&described.meshes, &described.materials, &described.lights, &described.spots, described.camera), (&scene.meshes, &scene.materials, &scene.lights, &scene.spots, scene.camera));
    let here = frame(&gpu, &scene, &scene.lights, &settings(Technique::Deferred)).pixels;
    for (file, png) in [(&gltf, "gltf.png"), (&glb, "glb.png"), (&toml, "toml.png")] {
        let pixels = cli_png(&dir, file, png);
        assert_eq!(common::pixels::worst_channel(&here, &pixels), 0, "manylights render --scene {}", file.display());
    }
}

/// A lit square seen by the front camera: the base the unsupported and malformed files change.
/// Returns the builder and the square's primitive (JSON).
fn square_scene() -> (Builder, serde_json::Value) {
    let mut b = Builder::new();
    front_camera(&mut b);
    front_light(&mut b);
    let m = diffuse(&mut b, [0.8, 0.8, 0.8, 1.0], json!({}));
    let square = b.rectangle([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Some(m));
    (b, square)
}

/// A primitive compressed with `KHR_draco_mesh_compression`: its accessors have no buffer view;
/// the extension names a view of (here meaningless) compressed bytes.
fn draco_primitive(b: &mut Builder) -> serde_json::Value {
    b.uses("KHR_draco_mesh_compression");
    b.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let view = b.view(&[7; 16]);
    let p = b.push("accessors", json!({"componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]}));
    let i = b.push("accessors", json!({"componentType": 5123, "count": 6, "type": "SCALAR"}));
    json!({"attributes": {"POSITION": p}, "indices": i, "extensions": {"KHR_draco_mesh_compression": {"bufferView": view, "attributes": {"POSITION": 0}}}})
}

/// Skins, morph targets (on two primitives), animations and Draco-compressed primitives (with
/// the extension required) load, each with exactly one warning line naming the file and the
/// feature; the scene keeps every mesh it can draw and renders like every other. A file whose
/// only mesh is compressed is a one-line error saying so; the binary prints one warning line
/// per feature.
#[test]
fn unsupported_features_warn_once_each() {
    let gpu = common::gpu();
    let dir = TempDir::new("gltf-unsupported");
    let variant = |feature: &str| {
        let (mut b, square) = square_scene();
        let mut prims = vec![square.clone()];
        match feature {
            "skin" => {}
            "morph" => {
                let offsets = b.floats(&[0.0, 0.0, 0.1].repeat(4), 3, "VEC3");
                prims = vec![square.clone(), square.clone()];
                for p in &mut prims {
                    p["targets"] = json!([{"POSITION": offsets}]);
                }
            }
            "animation" => {
                let times = b.floats(&[0.0, 1.0], 1, "SCALAR");
                let moves = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], 3, "VEC3");
                b.push("animations", json!({"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}], "samplers": [{"input": times, "output": moves}]}));
            }
            "draco" => prims.push(draco_primitive(&mut b)),
            "only draco" => prims = vec![draco_primitive(&mut b)],
            _ => unreachable!(),
        }
        let mesh = b.mesh(prims);
        let node = b.root(json!({"mesh": mesh}));
        if feature == "skin" {
            let joint = b.push("nodes", json!({"translation": [0, 1, 0]}));
            b.push("skins", json!({"joints": [joint]}));
            b.json["nodes"][node]["skin"] = json!(0);
        }
        b.write(dir.path(), &format!("{}.gltf", feature.replace(' ', "-")), Buffer::External(&format!("{}.bin", feature.replace(' ', "-"))))
    };
    for (feature, needle, meshes) in [("skin", "skin", 1), ("morph", "morph targets of 2 primitive", 2), ("animation", "animation", 1), ("draco", "1 KHR_draco_mesh_compression primitive(s) skipped", 1)] {
        let p = variant(feature);
        let s = load(&p);
        assert_eq!(s.warnings.len(), 1, "{feature}: {:?}", s.warnings);
        assert!(s.warnings[0].contains(needle) && s.warnings[0].contains(p.to_str().unwrap()) && !s.warnings[0].contains('\n'), "{feature}: {:?}", s.warnings);
        assert_eq!(s.meshes.len(), meshes, "{feature}");
        if feature == "draco" {
            render_every_technique(&gpu, &s, "a file with a Draco primitive");
            let run = common::cli::manylights(["render", "--scene", p.to_str().unwrap(), "--width", "32", "--height", "24", "--frames", "0", "--out", dir.join("draco.png").to_str().unwrap()]);
            let warnings: Vec<&str> = run.stderr.lines().filter(|l| l.starts_with("warning: ")).collect();
            assert!(run.ok && warnings.len() == 1 && warnings[0].contains(needle), "manylights render --scene {}:\n{}", p.display(), run.stderr);
        }
    }
    let e = load_err(&variant("only draco"));
    assert!(e.contains("no triangle mesh") && e.contains("KHR_draco_mesh_compression"), "{e}");
}

/// Malformed files: each a one-line error naming the file and the problem (never a panic), from
/// `Scene::load` and from the binary (exit status 2).
#[test]
fn malformed_files_are_one_line_errors() {
    let dir = TempDir::new("gltf-malformed");
    let write = |name: &str, edit: &dyn Fn(&mut Builder)| {
        let (mut b, square) = square_scene();
        let mesh = b.mesh(vec![square]);
        b.root(json!({"mesh": mesh}));
        edit(&mut b);
        b.write(dir.path(), name, Buffer::External(&format!("{name}.bin")))
    };
    let glb = {
        let (mut b, square) = square_scene();
        let mesh = b.mesh(vec![square]);
        b.root(json!({"mesh": mesh}));
        common::gltf::glb(&b.text(Buffer::Glb), &b.bin)
    };
    let gone = write("gone.gltf", &|_| {});
    std::fs::remove_file(dir.join("gone.gltf.bin")).unwrap();
    let cases: Vec<(std::path::PathBuf, &[&str])> = vec![
        (write("count.gltf", &|b| b.json["accessors"][0]["count"] = json!(40)), &["accessor 0: count 40", "past the end of bufferView 0"]),
        (write("offset.gltf", &|b| b.json["accessors"][1]["byteOffset"] = json!(64)), &["accessor 1", "byteOffset 64", "past the end of bufferView 1"]),
        (write("view.gltf", &|b| b.json["bufferViews"][2]["byteLength"] = json!(4096)), &["bufferView 2", "past the end of buffer 0"]),
        (gone, &["buffer 0 (\"gone.gltf.bin\")"]),
        (dir.write("syntax.gltf", "{\"asset\": {\"version\": \"2.0\"},"), &["not valid JSON", "line 1"]),
        (dir.write("other.gltf", "{\"type\": \"FeatureCollection\", \"features\": []}"), &["not a glTF 2.0 document", "asset"]),
        (dir.write("array.gltf", "[1, 2, 3]"), &["not a glTF 2.0 document"]),
        (write("node.gltf", &|b| b.json["nodes"][2]["mesh"] = json!(7)), &["nodes[2].mesh", "out of bounds"]),
        (write("cycle.gltf", &|b| b.json["nodes"][2]["children"] = json!([2])), &["node 2 is its own ancestor"]),
        (write("attribute.gltf", &|b| b.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99)), &["attributes.POSITION", "accessor 99 is out of range"]),
        (write("type.gltf", &|b| b.json["accessors"][0]["componentType"] = json!(5123)), &["mesh 0, primitive 0", "Positions is accessor 0", "U16"]),
        (write("index.gltf", &|b| {
            let at = b.json["bufferViews"][3]["byteOffset"].as_u64().unwrap() as usize;
            b.bin[at..at + 2].copy_from_slice(&9u16.to_le_bytes());
        }), &["index 9 is out of range (4 vertices)"]),
        (dir.write_bytes("truncated.glb", &glb[..glb.len() / 2]), &["not a valid .glb container"]),
        (dir.write_bytes("header.glb", &glb[..10]), &["not a valid .glb container"]),
    ];
    for (p, needles) in &cases {
        let e = load_err(p);
        assert!(e.contains("glTF file") && needles.iter().all(|n| e.contains(n)), "{}: {e}\n(expected {needles:?})", p.display());
    }
    for (p, needles) in [&cases[0], &cases[7], &cases[12]] {
        let run = common::cli::manylights(["render", "--scene", p.to_str().unwrap(), "--out", dir.join("x.png").to_str().unwrap()]);
        common::cli::assert_refused(&run, &format!("--scene {}", p.display()), common::cli::BAD_INPUT, needles);
    }
}
