//! Loading tests: descriptions, OBJ files (written to a temporary directory), the shipped example
//! descriptions, and Sponza / the bunny from the shared assets (skipped with a note when absent,
//! failing when `MANYLIGHTS_REQUIRE_ASSETS` is set: `tests/common/assets.rs`).
use super::*;
use shaders::layout::{EFFECT_ALPHA_TEST, EFFECT_SPECULAR, EFFECT_TEXTURES};
use std::time::Instant;

// The integration tests' helpers for the shared assets and temporary directories.
#[path = "../../../tests/common/assets.rs"]
pub(super) mod shared_assets;
#[path = "../../../tests/common/temp.rs"]
pub(super) mod temp;
use temp::TempDir;

pub(super) fn assets() -> PathBuf {
    shared_assets::dir()
}

pub(super) fn load_err(spec: &Path) -> String {
    format!("{:#}", Scene::load(spec.to_str().unwrap(), &assets()).unwrap_err())
}

#[test]
fn built_ins_load_and_unknown_names_are_refused() {
    for name in ["city", "corridor", "glass", "CITY"] {
        let s = Scene::load(name, Path::new("/nonexistent")).unwrap();
        assert!(s.triangle_count() > 0 && s.lights.is_empty() && s.warnings.is_empty());
    }
    let e = format!("{:#}", Scene::load("cty", &assets()).unwrap_err());
    assert!(e.contains("unknown scene \"cty\"") && e.contains("city, corridor, glass, nurbs, sponza, bunny"), "{e}");
}

#[test]
fn missing_files_are_named() {
    for f in ["/x/y.obj", "/x/y.toml"] {
        let e = load_err(Path::new(f));
        assert_eq!(e, format!("scene file {f} not found"));
    }
    let e = format!("{:#}", Scene::load("sponza", Path::new("/no/assets")).unwrap_err());
    assert!(e.contains("/no/assets/sponza/sponza.obj") && e.contains("--assets <dir>") && e.contains("MANYLIGHTS_ASSETS"), "{e}");
}

#[test]
fn malformed_obj_names_the_file_and_the_problem() {
    let dir = TempDir::new("bad-obj");
    let p = dir.write("broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 999\n");
    let e = load_err(&p);
    assert_eq!(e, format!("OBJ file {} line 4: face position index 999 is out of range: 3 defined before this line", p.display()));
    let p = dir.write("junk.obj", "v 0 0 zero\n");
    let e = load_err(&p);
    assert!(e.contains("junk.obj line 1: v: \"zero\" is not a number"), "{e}");
    // A malformed MTL that is there is an error naming its line (a missing one is a warning).
    dir.write("m.mtl", "newmtl a\nKd 0.5 nan 0.5\n");
    let p = dir.write("uses-mtl.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    let e = load_err(&p);
    assert!(e.contains("m.mtl line 2: Kd: \"nan\" is not a finite"), "{e}");
    // Finite coordinates whose extent overflows f32: refused with the scene named.
    let p = dir.write("huge.obj", "v -3e38 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n");
    let e = load_err(&p);
    assert!(e.contains("huge.obj") && e.contains("extent is not finite"), "{e}");
    // Every load error is bad input, on one line.
    let e = Scene::load(p.to_str().unwrap(), &assets()).unwrap_err();
    assert!(crate::bad_input::is_bad_input(&e) && !format!("{e:#}").contains('\n'));
}

#[test]
fn obj_materials_textures_and_missing_pieces() {
    let dir = TempDir::new("obj");
    let mut img = image::RgbaImage::new(4, 2);
    img.put_pixel(1, 0, image::Rgba([10, 20, 30, 40]));
    std::fs::create_dir_all(dir.0.join("tex")).unwrap();
    img.save(dir.0.join("tex").join("albedo.png")).unwrap();
    image::GrayImage::from_pixel(2, 2, image::Luma([200])).save(dir.0.join("tex").join("mask.png")).unwrap();
    dir.write(
        "m.mtl",
        "newmtl shiny\nKd 0.5 0.25 1\nKs 0.1 0.4 0.2\nNs 198\nd 0\nmap_Kd tex\\albedo.png\n\
         newmtl leaf\nKd 1 1 1\nmap_Kd tex/missing.tga\nmap_d tex/mask.png\n",
    );
    // Two triangles of `shiny` without normals or uvs, a quad of `leaf` with uvs, no material
    // on the last one.
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               o a\nusemtl shiny\nf 1 2 3\nf 1 3 4\no b\nusemtl leaf\nf 1/1 2/2 3/3 4/4\no c\nusemtl nothing\nf 1 3 4\n";
    let p = dir.write("scene.obj", obj);
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert_eq!(s.name, "scene");
    assert_eq!(s.triangle_count(), 5);
    let shiny = &s.materials[s.meshes[0].material as usize];
    assert_eq!((shiny.name.as_str(), shiny.albedo, shiny.specular), ("shiny", [0.5, 0.25, 1.0], 0.4));
    assert!((shiny.roughness - 0.1).abs() < 1e-6, "Ns 198 → √(2/200) = 0.1: {}", shiny.roughness);
    assert_eq!(shiny.albedo_texture.as_deref(), Some(dir.0.join("tex/albedo.png").as_path()), "backslash read as a separator");
    let t = s.texture(shiny.albedo_texture.as_ref().unwrap()).unwrap();
    assert_eq!((t.width, t.height, t.kind, &t.rgba8[4..8]), (4, 2, TextureKind::Albedo, &[10u8, 20, 30, 40][..]));
    let leaf = &s.materials[s.meshes[1].material as usize];
    assert_eq!(leaf.albedo_texture, None, "the missing texture is dropped");
    let mask = s.texture(leaf.alpha_mask_texture.as_ref().unwrap()).unwrap();
    assert_eq!((mask.kind, &mask.rgba8[..4]), (TextureKind::AlphaMask, &[200u8; 4][..]));
    assert_eq!((shiny.opacity, leaf.opacity), (0.0, 1.0), "d 0: fully transparent, as the format says");
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("m.mtl") && s.warnings[0].contains("\"shiny\"") && s.warnings[0].contains("mtl_d_zero_is_opaque"), "{:?}", s.warnings);
    assert!(s.warnings[1].contains("leaf") && s.warnings[1].contains("missing.tga"), "{:?}", s.warnings);
    assert_eq!(s.meshes[2].material as usize, s.materials.len() - 1, "unknown usemtl → default material");
    // Normals: face-averaged (+z) where absent; uvs flipped (OBJ v up → Vulkan v down) or zero.
    assert!(s.meshes.iter().all(|m| m.normals.iter().all(|n| *n == [0.0, 0.0, 1.0])));
    assert!(s.meshes[0].uvs.iter().all(|uv| *uv == [0.0, 0.0]));
    let m = &s.meshes[1];
    let uv_of = |pos: [f32; 3]| m.uvs[m.positions.iter().position(|p| *p == pos).unwrap()];
    assert_eq!((uv_of([0.0, 0.0, 0.0]), uv_of([1.0, 1.0, 0.0])), ([0.0, 1.0], [1.0, 0.0]));
    assert_eq!(s.effects, Effects { specular: true, textures: true, alpha_test: true });
    assert_eq!(s.effects.flags(), EFFECT_SPECULAR | EFFECT_TEXTURES | EFFECT_ALPHA_TEST);
    // The default camera sees the whole thing from +z.
    let c = s.camera;
    c.validate().unwrap();
    assert!(c.position.z > 1.0 && c.near < c.position.z - 0.1 && c.far > c.position.length() + 1.0);

    // Without its MTL: one default material and a warning, no failure.
    std::fs::remove_file(dir.0.join("m.mtl")).unwrap();
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert_eq!(s.materials.len(), 1);
    assert!(s.warnings.len() == 1 && s.warnings[0].contains("material library"), "{:?}", s.warnings);
    assert!(s.meshes.iter().all(|m| m.material == 0));
}

#[test]
fn validate_names_the_bad_item() {
    let mut s = procedural::corridor();
    s.validate().unwrap();
    s.meshes[2].positions[5][1] = f32::NAN;
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("mesh 2 vertex 5"), "{e}");
    let mut s = procedural::corridor();
    s.lights = lights::uniform(&s, 10, 1).unwrap();
    s.lights[3].radius = 0.0;
    s.validate().unwrap();
    s.lights[4].radius = -1.0;
    assert!(s.validate().unwrap_err().to_string().contains("light 4 has a negative radius"));
    s.lights[4].radius = 1.0;
    s.lights[7].position[2] = f32::INFINITY;
    assert!(s.validate().unwrap_err().to_string().contains("light 7"));
    let mut s = procedural::corridor();
    s.camera.far = s.camera.near;
    assert!(s.validate().unwrap_err().to_string().contains("far plane"));
}

pub(super) fn description_err(text: &str) -> String {
    let dir = TempDir::new("desc");
    let p = dir.write("bad.toml", text);
    let e = load_err(&p);
    assert!(e.contains(&p.display().to_string()), "error must name the file: {e}");
    e
}

#[test]
fn descriptions_load_and_reject_bad_input() {
    let dir = TempDir::new("desc-ok");
    let obj = dir.write("geo/tri.obj", "v 0 0 0\nv 4 0 0\nv 0 4 0\nf 1 2 3\n");
    assert!(obj.exists());
    let p = dir.write(
        "d.toml",
        "geometry = \"geo/tri.obj\"\n[camera]\nposition = [0, 1, 10]\ntarget = [0, 1, 0]\nnear = 0.5\nfar = 50\n\
         [lights]\ncount = 20\ndistribution = \"surfaces\"\noffset = 0.25\n[effects]\nspecular = true\n",
    );
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert_eq!((s.name.as_str(), s.lights.len(), s.triangle_count()), ("d", 20, 1));
    assert_eq!((s.camera.position, s.camera.near, s.camera.far, s.camera.fov_y_degrees), (Vec3::new(0.0, 1.0, 10.0), 0.5, 50.0, 60.0));
    assert!(s.lights.iter().all(|l| (l.position[2] - 0.25).abs() < 1e-6), "0.25 off the z = 0 triangle");
    assert!(s.effects.specular && !s.effects.textures);

    let e = description_err("geometry = \"city\"\ncolour = 3\n");
    assert!(e.contains("unknown field `colour`"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"uniform\"\nradus = 2\n");
    assert!(e.contains("unknown field `radus`"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = -1\ndistribution = \"uniform\"\n");
    assert!(e.contains("count = -1") && e.contains("invalid value"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"everywhere\"\n");
    assert!(e.contains("everywhere") && e.contains("uniform"), "{e}");
    let e = description_err("geometry = \"city\"\n[camera]\nposition = [0, 1, 0]\ntarget = [0, 1, -1]\nfov_y = 500\n");
    assert!(e.contains("camera.fov_y = 500") && e.contains("(0, 180)"), "{e}");
    let e = description_err("geometry = \"city\"\n[camera]\nposition = [0, nan, 0]\ntarget = [0, 1, -1]\n");
    assert!(e.contains("camera.position must be finite"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"uniform\"\nradius = nan\n");
    assert!(e.contains("lights.radius must be finite"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 268435453\ndistribution = \"uniform\"\n");
    assert!(e.contains("lights.count") && e.contains("more than"), "{e}");
    let e = description_err("geometry = \"castle\"\n");
    assert!(e.contains("geometry = \"castle\""), "{e}");
    let e = description_err("geometry = \"missing.obj\"\n");
    assert!(e.contains("missing.obj not found"), "{e}");
    let e = description_err("geometry = \"city\"\n[camera]\nposition = [0, 1, 0]\ntarget = [0, 1, -1]\nup = [0, 0, -1]\n");
    assert!(e.contains("[camera]") && e.contains("parallel"), "{e}");
    let e = description_err("name = \"x\"\n");
    assert!(e.contains("missing field `geometry`"), "{e}");

    // Syntax errors: one line with the line, column and source line.
    let e = description_err("geometry = \"city\"\n[camera]\nposition = [0, 1,\n");
    assert!(e.contains("line 4, column 1") && !e.contains('\n'), "{e}");
    let e = description_err("geometry = \"city\"\nx = 1\nbrightness = 3\n");
    assert!(e.contains("line 2, column 1 (`x = 1`): unknown field `x`"), "{e}");
    // Explicit lights: every value finite and ≥ 0, and a default intensity that fits f32.
    let light = |body: &str| description_err(&format!("geometry = \"city\"\n[[light]]\nposition = [0, 1, 0]\nradius = 1\n[[light]]\n{body}\n"));
    let e = light("position = [0, inf, 0]\nradius = 1");
    assert!(e.contains("light[1].position must be finite"), "{e}");
    let e = light("position = [0, 1, 0]\nradius = -2");
    assert!(e.contains("light[1].radius must be ≥ 0"), "{e}");
    let e = light("position = [0, 1, 0]\nradius = 1\ncolour = [1, -1, 1]");
    assert!(e.contains("light[1].colour must be ≥ 0"), "{e}");
    let e = light("position = [0, 1, 0]\nradius = 1\nintensity = nan");
    assert!(e.contains("light[1].intensity must be finite"), "{e}");
    let e = light("position = [0, 1, 0]\nradius = 1e30");
    assert!(e.contains("light[1].radius = 1000000000000000000000000000000") && e.contains("give light[1].intensity"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"hotspots\"\nclusters = 100000000\n");
    assert!(e.contains("lights.clusters = 100000000 is out of range"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 4000000000\ndistribution = \"uniform\"\n");
    assert!(e.contains("lights.count = 4000000000 is more than the 268435452 supported"), "{e}");
}

#[test]
fn shipped_example_descriptions_load() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets"));
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            found.push(p.file_name().unwrap().to_string_lossy().into_owned());
            let geometry = description::parse(&std::fs::read_to_string(&p).unwrap(), &p).unwrap().geometry;
            if ["sponza", "bunny"].contains(&geometry.as_str()) && shared_assets::asset(&geometry).is_none() {
                continue;
            }
            let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap_or_else(|e| panic!("{}: {e:#}", p.display()));
            assert!(!s.lights.is_empty() && s.warnings.is_empty(), "{}", p.display());
            let again = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
            assert_eq!(s.lights, again.lights, "{}: lights are seeded", p.display());
        }
    }
    found.sort();
    assert_eq!(found, ["city-1k.toml", "corridor-hotspots.toml", "corridor-surfaces.toml", "nurbs-wave.toml", "sponza-curtains.toml"], "example descriptions in assets/");
    let h = Scene::load(dir.join("corridor-hotspots.toml").to_str().unwrap(), &assets()).unwrap();
    assert!(!h.effects.specular && h.camera.fov_y_degrees == 70.0 && h.lights.len() == 4000);
}

/// Distance from `p` to triangle `abc` (Ericson, Real-Time Collision Detection §5.1.5), in f64:
/// the corridor's 120 m sliver triangles defeat f32 barycentrics.
fn dist_to_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> f64 {
    let [p, a, b, c] = [p, a, b, c].map(|v| v.as_dvec3());
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (p - (a + ab * (d1 / (d1 - d3)))).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (p - (a + ac * (d2 / (d2 - d6)))).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    (p - (a + ab * (vb * denom) + ac * (vc * denom))).length()
}

#[test]
fn surface_lights_lie_offset_from_a_triangle() {
    let s = procedural::corridor();
    let offset = 0.3;
    let l = lights::on_surfaces(&s, 300, 9, offset).unwrap();
    assert_eq!(l, lights::on_surfaces(&s, 300, 9, offset).unwrap());
    for (i, light) in l.iter().enumerate() {
        let p = Vec3::from_array(light.position);
        let nearest = s
            .meshes
            .iter()
            .flat_map(|m| (0..m.triangle_count()).map(move |t| m.triangle(t)))
            .map(|t| dist_to_triangle(p, t))
            .fold(f64::INFINITY, f64::min);
        assert!(nearest <= offset as f64 + 1e-4, "light {i} is {nearest} from the nearest triangle");
    }
    // Area-weighted: the floor (6.4 × 120.4 m of a few thousand m²) gets a fair share.
    let on_floor = l.iter().filter(|l| (l.position[1] - offset).abs() < 1e-4).count();
    assert!(on_floor > 20, "{on_floor} of 300 lights on the floor");
    assert!(lights::on_surfaces(&Scene::new("empty", vec![], vec![], vec![], s.camera), 1, 1, 0.1).is_err());
}

#[test]
fn sponza_when_present() {
    if shared_assets::asset("sponza").is_none() {
        return;
    }
    let t0 = Instant::now();
    let s = Scene::load("sponza", &assets()).unwrap();
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let texels: usize = s.textures.iter().map(|t| t.rgba8.len() / 4).sum();
    eprintln!(
        "sponza: {} triangles, {} meshes, {} materials, {} textures ({texels} texels), {} warnings, loaded in {ms:.0} ms",
        s.triangle_count(),
        s.meshes.len(),
        s.materials.len(),
        s.textures.len(),
        s.warnings.len()
    );
    for w in &s.warnings {
        eprintln!("  warning: {w}");
    }
    assert_eq!(s.triangle_count(), 262_267);
    assert_eq!((s.meshes.len(), s.materials.len()), (25, 25));
    assert_eq!(s.materials.iter().filter(|m| m.albedo_texture.is_some()).count(), 24);
    assert_eq!(s.materials.iter().filter(|m| m.alpha_mask_texture.is_some()).count(), 3);
    assert_eq!(s.textures.len(), 24 + 3, "24 distinct diffuse maps and 3 masks");
    assert!(s.warnings.is_empty());
    assert_eq!(s.effects, Effects { specular: false, textures: true, alpha_test: true }, "Sponza's Ks is 0 everywhere");
    let (lo, hi) = s.bounds;
    assert!((lo.x + 1920.0).abs() < 2.0 && (hi.y - 1428.75).abs() < 2.0, "{lo} {hi}");
    let c = s.camera;
    c.validate().unwrap();
    assert!(c.position.cmpgt(lo).all() && c.position.cmplt(hi).all(), "camera inside the atrium: {c:?}");
    assert!((c.target - c.position).normalize().x < -0.9, "looking along the long axis");
    let l = lights::uniform(&s, 10_000, 1).unwrap();
    assert!(l.iter().all(|l| l.radius > 0.0));
}

#[test]
fn bunny_when_present() {
    if shared_assets::asset("bunny").is_none() {
        return;
    }
    let t0 = Instant::now();
    let s = Scene::load("bunny", &assets()).unwrap();
    eprintln!("bunny: {} triangles, loaded in {:.0} ms", s.triangle_count(), t0.elapsed().as_secs_f64() * 1e3);
    assert_eq!(s.triangle_count(), 69_451);
    assert_eq!((s.materials.len(), s.textures.len(), s.effects.flags()), (1, 0, 0));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Face-averaged normals point away from the centre on most of the (closed-ish) surface.
    let m = &s.meshes[0];
    let centre = (s.bounds.0 + s.bounds.1) * 0.5;
    let outward = m.positions.iter().zip(&m.normals).filter(|(p, n)| (Vec3::from_array(**p) - centre).dot(Vec3::from_array(**n)) > 0.0).count();
    assert!(outward * 10 > m.positions.len() * 8, "{outward} of {} normals outward", m.positions.len());
    let c = s.camera;
    c.validate().unwrap();
    let d = c.position.distance(centre);
    assert!(c.near < d - 0.08 && c.far > d + 0.08 && d < 1.0, "{c:?}");
}

#[test]
fn named_views_set_the_camera_and_unknown_ones_are_named_errors() {
    let s = Scene::load("city@corner", Path::new(".")).unwrap();
    assert_eq!(s.name, "city@corner");
    assert_eq!(s.camera.position, view_camera("city", "corner").unwrap().position);
    let e = format!("{:#}", Scene::load("city@nowhere", Path::new(".")).unwrap_err());
    assert!(e.contains("unknown view \"nowhere\"") && e.contains("sponza@column"), "{e}");
    // '@' in a path is not a view.
    let e = format!("{:#}", Scene::load("no@such.obj", Path::new(".")).unwrap_err());
    assert!(!e.contains("unknown view"), "{e}");
}

/// `[[light]] type = …`: point, spot and directional lights with their keys; `[lights]
/// spot_fraction`; the keys a type needs or does not take, and angles out of range, are one-line
/// errors naming `light[i].key`.
#[test]
fn descriptions_with_light_types() {
    let dir = TempDir::new("desc-types");
    let p = dir.write(
        "t.toml",
        "geometry = \"city\"\n[lights]\ncount = 200\ndistribution = \"uniform\"\nspot_fraction = 0.5\n\
         [[light]]\nposition = [0, 3, 0]\nradius = 5\n\
         [[light]]\ntype = \"spot\"\nposition = [0, 3, 0]\nradius = 8\ndirection = [0, -1, 0]\ninner_angle = 20\nouter_angle = 35\n\
         [[light]]\ntype = \"directional\"\ndirection = [1, -1, 0]\nintensity = 2\n",
    );
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert_eq!((s.lights.len(), s.spots.len(), s.directional.len()), (202, 202, 1));
    let generated = s.spots[..200].iter().flatten().count();
    assert!((60..140).contains(&generated), "about half of the generated lights are spots: {generated}");
    assert_eq!(s.spots[200], None);
    let spot = s.spots[201].unwrap();
    assert_eq!((spot.direction, spot.inner, spot.outer), (Vec3::NEG_Y, 20f32.to_radians(), 35f32.to_radians()));
    assert_eq!((s.directional[0].direction, s.directional[0].intensity, s.directional[0].colour), (Vec3::new(1.0, -1.0, 0.0), 2.0, [1.0; 3]));
    // Without spots, no cone section at all.
    let p = dir.write("points.toml", "geometry = \"city\"\n[[light]]\nposition = [0, 3, 0]\nradius = 5\n");
    assert!(Scene::load(p.to_str().unwrap(), &assets()).unwrap().spots.is_empty());

    let light = |body: &str| description_err(&format!("geometry = \"city\"\n[[light]]\nposition = [0, 1, 0]\nradius = 1\n[[light]]\n{body}\n"));
    let spot = "type = \"spot\"\nposition = [0, 1, 0]\nradius = 4\ndirection = [0, -1, 0]";
    for (body, wanted) in [
        (format!("{spot}\nouter_angle = 95"), "light[1].outer_angle = 95 is out of range"),
        // The degenerate ends: a 0° cone lights nothing, a 180° one is no cone (the cone test
        // assumes at most 90°).
        (format!("{spot}\nouter_angle = 0"), "light[1].outer_angle = 0 is out of range: it must be in (0, 90] degrees"),
        (format!("{spot}\nouter_angle = 180"), "light[1].outer_angle = 180 is out of range"),
        (format!("{spot}\nouter_angle = 20\ninner_angle = -1"), "light[1].inner_angle = -1 is out of range"),
        (format!("{spot}\nouter_angle = 30\ninner_angle = 40"), "light[1].inner_angle = 40 is out of range"),
        (format!("{spot}\nouter_angle = nan"), "light[1].outer_angle must be finite"),
        ("type = \"spot\"\nposition = [0, 1, 0]\nradius = 4\ndirection = [0, 0, 0]".into(), "light[1].direction = [0.0, 0.0, 0.0] has no direction"),
        ("type = \"spot\"\nposition = [0, 1, 0]\nradius = 4".into(), "light[1].direction is missing"),
        ("type = \"directional\"\ndirection = [0, -1, 0]\nradius = 3".into(), "light[1].radius does not apply to a directional light"),
        ("position = [0, 1, 0]\nradius = 1\nouter_angle = 10".into(), "light[1].outer_angle does not apply to a point light"),
        ("type = \"directional\"\ndirection = [0, inf, 0]".into(), "light[1].direction must be finite"),
        ("type = \"area\"\nposition = [0, 1, 0]\nradius = 1".into(), "unknown variant `area`"),
    ] {
        let e = light(&body);
        assert!(e.contains(wanted) && !e.contains('\n'), "{body}: {e}");
    }
    let e = description_err(&format!("geometry = \"city\"\n{}", "[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n".repeat(5)));
    assert!(e.contains("5 directional lights: at most 4"), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"uniform\"\nspot_fraction = 1.5\n");
    assert!(e.contains("lights.spot_fraction = 1.5 must be in [0, 1]"), "{e}");
}

/// A description whose punctual lights are all generated with `[lights] spot_fraction` keeps
/// its share and seed (another count gets its cones alike: the viewer's + / −); lights listed
/// one by one, or no spots, leave none.
#[test]
fn descriptions_keep_the_spot_share_of_generated_lights() {
    let dir = TempDir::new("desc-share");
    let generated = "geometry = \"city\"\n[lights]\ncount = 50\ndistribution = \"uniform\"\nseed = 7\nspot_fraction = 0.5\n";
    let load = |name: &str, text: &str| Scene::load(dir.write(name, text).to_str().unwrap(), &assets()).unwrap();
    let s = load("share.toml", generated);
    let share = s.spot_share.expect("a spot share");
    assert_eq!((share.fraction, share.seed), (0.5, 7));
    assert_eq!(share.cones(s.lights.len()).unwrap(), s.spots, "the share gives the scene's own cones back");
    let directional = format!("{generated}[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n");
    assert_eq!(load("dir.toml", &directional).spot_share, Some(share), "a directional light is no punctual light");
    let listed = format!("{generated}[[light]]\nposition = [0, 3, 0]\nradius = 5\n");
    assert_eq!(load("listed.toml", &listed).spot_share, None, "a listed light");
    assert_eq!(load("points.toml", &generated.replace("spot_fraction = 0.5\n", "")).spot_share, None, "no spots");
}

/// Unit vectors from vectors whose squared length leaves f32's normal range: tiny (squares
/// subnormal) and huge (squares infinite) components give unit length; zero, ∞ and NaN give none.
#[test]
fn unit_vectors_survive_tiny_and_huge_components() {
    use super::unit_vector;
    use glam::Vec3;
    for scale in [1e-30f32, 1e-20, 1e-19, 3e-23, 1.0, 1e19, 1e20, 1e30, 1e37] {
        for v in [Vec3::new(0.0, -1.0, -1.0), Vec3::new(1.0, 2.0, 3.0), Vec3::new(-7.0, 0.0, 0.0)] {
            let u = unit_vector(v * scale).unwrap_or_else(|| panic!("{v} × {scale:e}: no unit vector"));
            assert!((u.length() - 1.0).abs() < 1e-6, "{v} × {scale:e}: length {}", u.length());
            assert!((u - v.normalize()).length() < 1e-6, "{v} × {scale:e}: direction {u}");
        }
    }
    for v in [Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::new(f32::NAN, 1.0, 0.0), Vec3::new(1.0, f32::NEG_INFINITY, 1.0)] {
        assert_eq!(unit_vector(v), None, "{v}");
    }
}

/// `[[light]] shadows = true` and `[lights] shadow_fraction` mark the lights that cast shadows
/// (evenly spread, `⌊n·fraction⌋` of them); a scene without any keeps no flags; directional
/// lights and fractions out of range are one-line errors.
#[test]
fn descriptions_with_shadow_casting_lights() {
    let dir = TempDir::new("desc-shadows");
    let p = dir.write(
        "s.toml",
        "geometry = \"city\"\n[lights]\ncount = 8\ndistribution = \"uniform\"\nshadow_fraction = 0.25\n\
         [[light]]\nposition = [0, 3, 0]\nradius = 5\n\
         [[light]]\nposition = [0, 3, 0]\nradius = 5\nshadows = true\n\
         [[light]]\nposition = [0, 3, 0]\nradius = 5\nshadows = false\n",
    );
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    let flags: Vec<usize> = s.shadows.iter().enumerate().filter(|(_, &c)| c).map(|(i, _)| i).collect();
    assert_eq!((s.shadows.len(), flags), (11, vec![3, 7, 9]));
    assert_eq!(s.shadow_casters(), 3);
    let p = dir.write("none.toml", "geometry = \"city\"\n[lights]\ncount = 8\ndistribution = \"uniform\"\n[[light]]\nposition = [0, 3, 0]\nradius = 5\nshadows = false\n");
    assert!(Scene::load(p.to_str().unwrap(), &assets()).unwrap().shadows.is_empty(), "no shadow flags without a caster");
    let e = description_err("geometry = \"city\"\n[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nshadows = true\n");
    assert!(e.contains("light[0].shadows does not apply to a directional light") && !e.contains('\n'), "{e}");
    let e = description_err("geometry = \"city\"\n[lights]\ncount = 5\ndistribution = \"uniform\"\nshadow_fraction = -0.5\n");
    assert!(e.contains("lights.shadow_fraction = -0.5 must be in [0, 1]"), "{e}");
    for (n, f, casters) in [(0, 0.5, 0), (7, 0.0, 0), (7, 1.0, 7), (10, 0.3, 3), (3, 0.5, 1)] {
        assert_eq!(lights::shadow_casters(n, f).unwrap().iter().filter(|&&c| c).count(), casters, "{n} lights, fraction {f}");
    }
    assert!(lights::shadow_casters(3, 1.5).is_err());
}

/// `--light-order spatial`: a permutation of the lights whose Morton codes (interleaved here bit
/// by bit, not by the shader crate's spreading) never decrease, ties in the given order, each
/// light keeping its cone and shadow flag; consecutive lights end up far closer in space.
#[test]
fn spatial_order_follows_the_morton_curve_and_keeps_each_lights_flags() {
    let mut s = Scene::load("city", &assets()).unwrap();
    let mut ls = lights::uniform(&s, 5000, 3).unwrap();
    ls[17] = ls[4000]; // an equal key: the tie keeps 17 before 4000
    let cones = lights::spot_cones(ls.len(), 0.5, 3).unwrap();
    s.add_lights(ls.iter().copied().zip(cones.iter().copied()));
    for i in (0..ls.len()).step_by(7) {
        s.set_casts_shadows(i, true);
    }
    let before = s.clone();
    let order = lights::spatial_order(&s.lights);
    let mut seen = vec![false; ls.len()];
    order.iter().for_each(|&i| seen[i as usize] = true);
    assert!(seen.iter().all(|&b| b) && order.len() == ls.len(), "a permutation");
    let (lo, hi) = s.lights.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), l| (lo.min(l.position.into()), hi.max(l.position.into())));
    let key = |p: [f32; 3]| {
        let cell = |a: usize| (((p[a] - lo[a]) / (hi[a] - lo[a]) * 1024.0) as u32).min(1023);
        (0..10).fold(0u32, |k, b| k | ((cell(0) >> b & 1) << (3 * b)) | ((cell(1) >> b & 1) << (3 * b + 1)) | ((cell(2) >> b & 1) << (3 * b + 2)))
    };
    let keys: Vec<u32> = order.iter().map(|&i| key(s.lights[i as usize].position)).collect();
    let out_of_order = keys.windows(2).filter(|w| w[0] > w[1]).count();
    // The shader crate quantises with a precomputed scale: a light on a cell boundary may land
    // one cell over; a handful of the 5 000, never a systematic reversal.
    assert!(out_of_order <= 5, "{out_of_order} lights out of Morton order");
    let at = |i: u32| order.iter().position(|&o| o == i).unwrap();
    assert!(at(17) + 1 == at(4000), "equal keys keep their given order");
    s.order_lights_spatially();
    for (k, &i) in order.iter().enumerate() {
        let i = i as usize;
        assert_eq!((s.lights[k], s.spots[k], s.shadows[k]), (before.lights[i], before.spots[i], before.shadows[i]), "light {k} (was {i})");
    }
    let step = |l: &[PointLight]| l.windows(2).map(|w| (Vec3::from(w[0].position) - Vec3::from(w[1].position)).length()).sum::<f32>();
    assert!(step(&s.lights) * 5.0 < step(&before.lights), "consecutive lights closer: {} against {}", step(&s.lights), step(&before.lights));
}
