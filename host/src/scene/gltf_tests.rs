//! glTF import: a small document written to a temporary directory — external and embedded
//! buffers, `.glb`, node transforms (a mirrored one), materials of every alpha mode, a texture,
//! a camera, point lights with and without a range — and the refusals.
use super::gltf::radius_without_range;
use super::tests::{assets, load_err, temp::TempDir};
use super::*;

/// The glTF builders of the integration tests (`.glb` containers, base64).
#[path = "../../../tests/common/gltf.rs"]
#[allow(dead_code)]
mod builder;
use builder::{base64, glb};

/// One triangle: positions (36 B) then u16 indices (6 B, padded to 8).
fn triangle_bin() -> Vec<u8> {
    let mut b: Vec<u8> = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    b.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    b.extend([0, 0]);
    b
}

/// The document: `uri` names the buffer (a file, a data URI, or none for `.glb`); `light`
/// is the extra light's JSON.
fn document(uri: Option<&str>, light: &str) -> String {
    let buffer = match uri {
        Some(u) => format!(r#"{{"byteLength": 44, "uri": "{u}"}}"#),
        None => r#"{"byteLength": 44}"#.to_owned(),
    };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "point", "color": [1, 0.5, 0.25], "intensity": 4, "range": 7, "name": "lamp"}},
    {{"type": "point", "intensity": 2}},
    {light}
  ]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 3, 4]}}],
  "nodes": [
    {{"translation": [10, 0, 0], "children": [1, 2]}},
    {{"mesh": 0}},
    {{"mesh": 0, "scale": [-1, 1, 1]}},
    {{"camera": 0, "translation": [0, 1, 5]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [1, 2, 3], "children": [5]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 1}}}}, "translation": [0, 0, 1]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1, "zfar": 100}}}}],
  "meshes": [{{"primitives": [
    {{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}},
    {{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 1}},
    {{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 2}},
    {{"attributes": {{"POSITION": 0}}, "indices": 1}}
  ]}}],
  "materials": [
    {{"name": "glass", "alphaMode": "BLEND", "pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.4, 0.6, 0.4], "metallicFactor": 0, "roughnessFactor": 0.5}}}},
    {{"name": "leaf", "alphaMode": "MASK", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0.5}}}},
    {{"name": "plain"}}
  ],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "leaf.png"}}],
  "buffers": [{buffer}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}}"#
    )
}

const POINT: &str = r#"{"type": "point", "intensity": 1, "range": 1}"#;

fn write_leaf(dir: &TempDir) {
    let mut img = image::RgbaImage::from_pixel(2, 2, image::Rgba([20, 200, 40, 255]));
    img.put_pixel(1, 1, image::Rgba([20, 200, 40, 0]));
    img.save(dir.0.join("leaf.png")).unwrap();
}

fn load(p: &Path) -> Scene {
    Scene::load(p.to_str().unwrap(), &assets()).unwrap()
}

#[test]
fn gltf_meshes_materials_camera_and_lights() {
    let dir = TempDir::new("gltf");
    write_leaf(&dir);
    std::fs::write(dir.0.join("tri.bin"), triangle_bin()).unwrap();
    let p = dir.write("scene.gltf", &document(Some("tri.bin"), POINT));
    let s = load(&p);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Two nodes × four primitives; translated by 10 along x, the second mirrored.
    assert_eq!(s.meshes.len(), 8);
    assert_eq!(s.meshes[0].positions, [[10.0, 0.0, 0.0], [11.0, 0.0, 0.0], [10.0, 1.0, 0.0]]);
    assert_eq!(s.meshes[4].positions, [[10.0, 0.0, 0.0], [9.0, 0.0, 0.0], [10.0, 1.0, 0.0]]);
    for m in &s.meshes {
        // The winding (kept or swapped) and the normals agree: front faces point along +z.
        let [a, b, c] = m.triangle(0);
        assert!((b - a).cross(c - a).z > 0.0 && m.normals.iter().all(|n| n[2] > 0.99), "{m:?}");
    }
    let names: Vec<&str> = s.meshes[..4].iter().map(|m| s.materials[m.material as usize].name.as_str()).collect();
    assert_eq!(names, ["glass", "leaf", "plain", "default"]);
    let (glass, leaf) = (&s.materials[0], &s.materials[1]);
    assert_eq!((glass.albedo, glass.opacity, glass.roughness, glass.specular), ([0.2, 0.4, 0.6], 0.4, 0.5, 0.0));
    assert!(s.has_transparency() && s.effects.alpha_test && s.effects.textures);
    assert_eq!((leaf.specular, leaf.opacity), (0.5, 1.0));
    let albedo = s.texture(leaf.albedo_texture.as_ref().unwrap()).unwrap();
    let mask = s.texture(leaf.alpha_mask_texture.as_ref().unwrap()).unwrap();
    assert_eq!((&albedo.rgba8[..4], &mask.rgba8[12..16]), (&[20, 200, 40, 255][..], &[0u8; 4][..]));
    let c = s.camera;
    assert_eq!((c.position, c.target, c.near, c.far), (Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 4.0), 0.1, 100.0));
    assert!((c.fov_y_degrees - 0.8f32.to_degrees()).abs() < 1e-4);
    // Lights: node 4 (range 7), its child (no range: the 1/256 rule), the extra light is unused.
    assert_eq!(s.lights.len(), 2);
    assert_eq!((s.lights[0].position, s.lights[0].radius, s.lights[0].colour, s.lights[0].intensity), ([1.0, 2.0, 3.0], 7.0, [1.0, 0.5, 0.25], 4.0));
    assert_eq!((s.lights[1].position, s.lights[1].radius), ([1.0, 2.0, 4.0], radius_without_range(2.0, [1.0; 3])));
    assert!((radius_without_range(2.0, [1.0; 3]) - 512f32.sqrt()).abs() < 1e-4);

    // The same document with the buffer embedded, and as a .glb: the same scene.
    let embedded = dir.write("embedded.gltf", &document(Some(&format!("data:application/octet-stream;base64,{}", base64(&triangle_bin()))), POINT));
    let g = dir.0.join("scene.glb");
    std::fs::write(&g, glb(&document(None, POINT), &triangle_bin())).unwrap();
    // Materials compared without their texture names (named after the file).
    let plain = |s: &Scene| s.materials.iter().map(|m| (m.name.clone(), m.albedo, m.opacity, m.specular, m.roughness, m.albedo_texture.is_some())).collect::<Vec<_>>();
    for other in [embedded, g] {
        let o = load(&other);
        assert_eq!((&o.meshes, plain(&o), &o.lights, o.camera), (&s.meshes, plain(&s), &s.lights, s.camera), "{}", other.display());
        assert_eq!(o.textures.iter().map(|t| &t.rgba8).collect::<Vec<_>>(), s.textures.iter().map(|t| &t.rgba8).collect::<Vec<_>>());
    }
}

#[test]
fn gltf_refusals_name_the_file_and_what() {
    let dir = TempDir::new("gltf-bad");
    write_leaf(&dir);
    std::fs::write(dir.0.join("tri.bin"), triangle_bin()).unwrap();
    // A spot light is used by no node here; a node that uses one loads it as a spot (the
    // node's −z axis, its cone angles), and a cone past 90° is refused, naming the light.
    let spot = r#"{"type": "spot", "name": "torch", "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}}"#;
    let text = document(Some("tri.bin"), spot).replace(r#""light": 1}}"#, r#""light": 2}}"#);
    let s = load(&dir.write("spot.gltf", &text));
    let cone = s.spots.iter().flatten().next().unwrap_or_else(|| panic!("no spot in {:?}", s.spots));
    assert_eq!((cone.inner, cone.outer, s.spots.len(), s.lights.len()), (0.25, 0.5, s.lights.len(), 2));
    let wide = text.replace(r#""outerConeAngle": 0.5"#, r#""outerConeAngle": 2.0"#);
    let e = load_err(&dir.write("wide.gltf", &wide));
    assert!(e.contains("wide.gltf") && e.contains("light 2 (\"torch\"): outer_angle") && !e.contains('\n'), "{e}");
    let sun = r#"{"type": "directional", "name": "sun", "intensity": 3}"#;
    let s = load(&dir.write("sun.gltf", &document(Some("tri.bin"), sun).replace(r#""light": 1}}"#, r#""light": 2}}"#)));
    assert_eq!((s.directional.len(), s.directional[0].intensity), (1, 3.0));
    let p = dir.write("broken.gltf", "{\"asset\": ");
    let e = load_err(&p);
    assert!(e.contains("glTF file") && e.contains("broken.gltf"), "{e}");
    let e = load_err(&dir.0.join("missing.glb"));
    assert!(e.contains("missing.glb not found"), "{e}");
    let p = dir.write("nobin.gltf", &document(Some("absent.bin"), POINT));
    let e = load_err(&p);
    assert!(e.contains("nobin.gltf") && !e.contains('\n'), "{e}");
}

/// A light's `extras` `{"shadows": true}` marks it as casting shadows: only that light, a point
/// or a spot; `false`, other keys or no extras leave lights unshadowed (and the scene allocates
/// nothing for shadows); a non-boolean value or a shadowed directional light is refused in one line.
#[test]
fn gltf_light_extras_mark_shadow_casters() {
    let dir = TempDir::new("gltf-shadows");
    write_leaf(&dir);
    std::fs::write(dir.0.join("tri.bin"), triangle_bin()).unwrap();
    let with = |name: &str, light: &str| dir.write(name, &document(Some("tri.bin"), light).replace(r#""light": 1}}"#, r#""light": 2}}"#));
    let spot = |extras: &str| format!(r#"{{"type": "spot", "name": "torch", "spot": {{"outerConeAngle": 0.5}}, "extras": {extras}}}"#);
    let s = load(&with("casts.gltf", &spot(r#"{"shadows": true, "note": 1}"#)));
    assert_eq!((s.shadows.as_slice(), s.shadow_casters()), (&[false, true][..], 1));
    assert!(s.spots[1].is_some());
    let point = r#"{"type": "point", "intensity": 2, "extras": {"shadows": true}}"#;
    assert_eq!(load(&with("point.gltf", point)).shadows, [false, true]);
    for (name, extras) in [("off.gltf", r#"{"shadows": false}"#), ("other.gltf", r#"{"owner": "x"}"#), ("null.gltf", "null")] {
        let s = load(&with(name, &spot(extras)));
        assert_eq!(s.shadow_casters(), 0, "{name}");
    }
    assert!(load(&with("none.gltf", POINT)).shadows.is_empty());
    let e = load_err(&with("word.gltf", &spot(r#"{"shadows": "yes"}"#)));
    assert!(e.contains("word.gltf") && e.contains("light 2 (\"torch\")") && e.contains(r#""shadows" must be true or false, not "yes""#) && !e.contains('\n'), "{e}");
    let sun = r#"{"type": "directional", "name": "sun", "extras": {"shadows": true}}"#;
    let e = load_err(&with("sun.gltf", sun));
    assert!(e.contains("sun.gltf") && e.contains("directional lights cast no shadows") && !e.contains('\n'), "{e}");
}

/// `MASK` without a texture: the factor's alpha alone against `alphaCutoff` — below it the whole
/// material is cut out (a 1×1 mask of 0), at or above it nothing is.
#[test]
fn gltf_mask_without_texture_cuts_by_the_factor_alpha() {
    let dir = TempDir::new("gltf-mask");
    write_leaf(&dir);
    std::fs::write(dir.0.join("tri.bin"), triangle_bin()).unwrap();
    for (alpha, cutoff, cut) in [(0.3, 0.5, true), (0.3, 0.25, false), (0.5, 0.5, false)] {
        let plain = format!(r#"{{"name": "plain", "alphaMode": "MASK", "alphaCutoff": {cutoff}, "pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, {alpha}]}}}}"#);
        let s = load(&dir.write("mask.gltf", &document(Some("tri.bin"), POINT).replace(r#"{"name": "plain"}"#, &plain)));
        let mask = s.materials[2].alpha_mask_texture.as_ref().map(|p| s.texture(p).unwrap());
        assert_eq!(mask.map(|t| (t.width, t.height, t.rgba8.clone())), cut.then(|| (1, 1, vec![0; 4])), "alpha {alpha}, cutoff {cutoff}");
    }
}
