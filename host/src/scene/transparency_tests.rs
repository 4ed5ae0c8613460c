//! Transparency in scenes: MTL `d` / `Tr`, the Sponza rule, `[[material]]` overrides, the
//! `glass` scene (checked by casting rays through its triangles on the CPU),
//! `Scene::has_transparency` and the opacity in the flattened material table.
use super::tests::{assets, description_err, load_err, shared_assets, temp::TempDir};
use super::wavefront::{parse_mtl, MtlOptions};
use super::*;
use shaders::octahedral::Precision;

fn mtl(text: &str, options: MtlOptions) -> Result<Vec<Material>> {
    parse_mtl(text.as_bytes(), Path::new("m.mtl"), Path::new("d"), options)
}

fn opacities(text: &str, options: MtlOptions) -> Vec<f32> {
    mtl(text, options).unwrap().iter().map(|m| m.opacity).collect()
}

#[test]
fn mtl_d_is_opacity_and_tr_its_complement() {
    let spec = MtlOptions::default();
    assert_eq!(opacities("newmtl a\nKd 1 1 1\n", spec), [1.0], "no d, no Tr: opaque");
    assert_eq!(opacities("newmtl a\nd 0.25\n", spec), [0.25]);
    assert_eq!(opacities("newmtl a\nTr 0.25\n", spec), [0.75], "Tr alone: 1 − Tr");
    assert_eq!(opacities("newmtl a\nd -halo 0.6\n", spec), [0.6], "-halo is read as plain d");
    assert_eq!(opacities("newmtl a\nd 0.4\nTr 0.9\nnewmtl b\nTr 0.9\nd 0.4\n", spec), [0.4, 0.4], "d wins, before or after Tr");
    assert_eq!(opacities("newmtl a\nd 0.3\nd 0.8\nnewmtl b\nTr 0\n", spec), [0.8, 1.0], "the last d counts; Tr 0 is opaque");
    // `d 0` is fully transparent as the format says, opaque under the Sponza switch; `Tr 1` is
    // fully transparent either way.
    let text = "newmtl a\nd 0\nnewmtl b\nTr 1\nnewmtl c\nd 0.000000\nTr 1.000000\nnewmtl d\nd 1\n";
    assert_eq!(opacities(text, spec), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(opacities(text, MtlOptions { d_zero_is_opaque: true }), [1.0, 0.0, 1.0, 1.0]);
}

#[test]
fn bad_d_and_tr_name_the_file_and_line() {
    let e = |t: &str| format!("{:#}", mtl(t, MtlOptions::default()).unwrap_err());
    assert_eq!(e("newmtl a\nKd 1 1 1\nd 1.5\n"), "MTL file m.mtl line 3: d 1.5 is out of range: opacity must be in [0, 1]");
    assert_eq!(e("newmtl a\nTr -0.1\n"), "MTL file m.mtl line 2: Tr -0.1 is out of range: transparency must be in [0, 1]");
    assert_eq!(e("newmtl a\nd nan\n"), "MTL file m.mtl line 2: d: \"nan\" is not a finite 32-bit number");
    assert_eq!(e("newmtl a\nTr inf\n"), "MTL file m.mtl line 2: Tr: \"inf\" is not a finite 32-bit number");
    assert_eq!(e("newmtl a\nd 1e39\n"), "MTL file m.mtl line 2: d: \"1e39\" is not a finite 32-bit number");
    assert_eq!(e("newmtl a\nd -halo\n"), "MTL file m.mtl line 2: d needs 1 numbers, found 0");
    assert_eq!(e("newmtl a\nd half\n"), "MTL file m.mtl line 2: d: \"half\" is not a number");
    assert_eq!(e("Tr 0.5\n"), "MTL file m.mtl line 1: \"Tr\" before the first newmtl");
    // Through `Scene::load`: one line with the MTL's path and line, marked as bad input.
    let dir = TempDir::new("bad-opacity");
    let m = dir.write("m.mtl", "newmtl a\nd 2\n");
    let p = dir.write("o.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    assert_eq!(load_err(&p), format!("MTL file {} line 2: d 2 is out of range: opacity must be in [0, 1]", m.display()));
}

/// An OBJ whose MTL says `d 0`: transparent with a warning naming the switch by default, opaque
/// and silent from a description that sets it.
#[test]
fn d_zero_warns_and_the_description_switch_reads_it_as_opaque() {
    let dir = TempDir::new("d-zero");
    dir.write("m.mtl", "newmtl wall\nd 0.000000\nnewmtl veil\nd 0.5\n");
    let p = dir.write("o.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wall\nf 1 2 3\nusemtl veil\nf 1 3 2\n");
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert_eq!(s.materials.iter().map(|m| m.opacity).collect::<Vec<_>>(), [0.0, 0.5]);
    assert!(s.has_transparency());
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(w.contains("m.mtl") && w.contains("1 of 2 materials have opacity 0") && w.contains("\"wall\"") && w.contains("mtl_d_zero_is_opaque = true"), "{w}");
    let d = dir.write("d.toml", "geometry = \"o.obj\"\nmtl_d_zero_is_opaque = true\n");
    let s = Scene::load(d.to_str().unwrap(), &assets()).unwrap();
    assert_eq!(s.materials.iter().map(|m| m.opacity).collect::<Vec<_>>(), [1.0, 0.5]);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let e = description_err("geometry = \"city\"\nmtl_d_zero_is_opaque = true\n");
    assert!(e.contains("mtl_d_zero_is_opaque only applies to OBJ geometry"), "{e}");
}

#[test]
fn material_overrides_apply_by_name() {
    let dir = TempDir::new("overrides");
    let p = dir.write(
        "d.toml",
        "geometry = \"city\"\n[[material]]\nname = \"brick\"\nopacity = 0.4\n\
         [[material]]\nname = \"metal\"\nalbedo = [0.1, 0.2, 0.3]\n[[material]]\nname = \"brick\"\nalbedo = [1, 0, 0]\n",
    );
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    let by_name = |n: &str| s.materials.iter().find(|m| m.name == n).unwrap();
    assert_eq!((by_name("brick").opacity, by_name("brick").albedo), (0.4, [1.0, 0.0, 0.0]), "later tables add to earlier ones");
    assert_eq!((by_name("metal").opacity, by_name("metal").albedo), (1.0, [0.1, 0.2, 0.3]));
    assert_eq!(by_name("concrete"), &procedural::city().materials[1], "others untouched");
    assert!(s.has_transparency() && !procedural::city().has_transparency());
}

#[test]
fn material_overrides_reject_unknown_names_and_bad_values() {
    let table = |body: &str| description_err(&format!("geometry = \"city\"\n[[material]]\nname = \"brick\"\nopacity = 0.5\n[[material]]\n{body}\n"));
    let e = table("name = \"brik\"\nopacity = 0.5");
    assert!(e.contains("material[1].name = \"brik\" names no material of geometry \"city\"") && e.contains("\"asphalt\", \"concrete\", \"brick\""), "{e}");
    assert!(!e.contains('\n'));
    let cases = [
        ("name = \"brick\"\nopacity = 1.5", "material[1].opacity must be in [0, 1], got [1.5]"),
        ("name = \"brick\"\nopacity = -0.0001", "material[1].opacity must be in [0, 1]"),
        ("name = \"brick\"\nopacity = nan", "material[1].opacity must be finite, got [NaN]"),
        ("name = \"brick\"\nalbedo = [0.5, inf, 0.5]", "material[1].albedo must be finite"),
        ("name = \"brick\"\nalbedo = [0.5, 2, 0.5]", "material[1].albedo must be in [0, 1], got [0.5, 2.0, 0.5]"),
        ("name = \" \"", "material[1].name is empty"),
        ("name = \"brick\"\ntransparency = 0.5", "unknown field `transparency`"),
        ("opacity = 0.5", "missing field `name`"),
    ];
    for (body, expected) in cases {
        let e = table(body);
        assert!(e.contains(expected), "{body:?}: {e}");
    }
    // Past a few names, the list says how many there are.
    let dir = TempDir::new("many-materials");
    let names: String = (0..12).map(|i| format!("newmtl m{i}\n")).collect();
    dir.write("m.mtl", &names);
    dir.write("o.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m0\nf 1 2 3\n");
    let p = dir.write("d.toml", "geometry = \"o.obj\"\n[[material]]\nname = \"M0\"\n");
    let e = load_err(&p);
    assert!(e.contains("material[0].name = \"M0\" names no material of geometry \"o\"; it has \"m0\", \"m1\"") && e.contains(", … (12 in all)"), "{e}");
}

/// Everything a ray crosses: distance along the unit direction, the material, and whether the
/// triangle faces the ray (what a pass with back-face culling would keep).
#[derive(Clone, Copy, Debug)]
struct Hit {
    t: f64,
    material: u32,
    front: bool,
}

/// Every triangle of the scene on the ray (Möller–Trumbore, in f64), nearest first.
fn hits(scene: &Scene, origin: Vec3, dir: Vec3) -> Vec<Hit> {
    let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
    let mut out = Vec::new();
    for mesh in &scene.meshes {
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t).map(|v| v.as_dvec3());
            let (e1, e2) = (b - a, c - a);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = o - a;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            let dist = e2.dot(q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 1e-6 {
                out.push(Hit { t: dist, material: mesh.material, front: e1.cross(e2).dot(d) < 0.0 });
            }
        }
    }
    out.sort_by(|x, y| x.t.total_cmp(&y.t));
    out
}

/// What the ray sees: the transparent panes it crosses before its first opaque surface (front
/// faces, one per pane; a hit on the diagonal two triangles share counts once), the transparent
/// surfaces (front and back), and that opaque surface.
fn look_through(scene: &Scene, origin: Vec3, dir: Vec3) -> (usize, usize, Option<Hit>) {
    let transparent = |h: &Hit| scene.materials[h.material as usize].is_transparent();
    let all = hits(scene, origin, dir);
    let opaque = all.iter().find(|h| !transparent(h)).copied();
    let before: Vec<Hit> = all.into_iter().filter(|h| transparent(h) && opaque.is_none_or(|o| h.t < o.t)).collect();
    let mut fronts: Vec<f64> = before.iter().filter(|h| h.front).map(|h| h.t).collect();
    fronts.dedup_by(|a, b| (*a - *b).abs() < 1e-6 * b.max(1.0));
    (fronts.len(), before.len(), opaque)
}

/// The direction through the centre of pixel `(x, y)` of a `w × h` frame (rows top to bottom).
fn pixel_ray(c: &Camera, w: u32, h: u32, x: u32, y: u32) -> Vec3 {
    let forward = (c.target - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let tan = (c.fov_y_degrees.to_radians() * 0.5).tan();
    let sx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan * w as f32 / h as f32;
    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan;
    (forward + right * sx + up * sy).normalize()
}

#[test]
fn glass_has_coloured_panes_and_the_city() {
    let (s, again) = (procedural::glass(), procedural::glass());
    assert_eq!(s.meshes, again.meshes, "deterministic");
    s.validate().unwrap();
    let city = procedural::city();
    assert_eq!(&s.materials[..city.materials.len()], &city.materials[..], "the city's materials first");
    let transparent: Vec<&Material> = s.materials.iter().filter(|m| m.is_transparent()).collect();
    assert_eq!(transparent.len(), procedural::GLASS_PANES.len());
    let mut opacities: Vec<f32> = transparent.iter().map(|m| m.opacity).collect();
    opacities.sort_by(f32::total_cmp);
    opacities.dedup();
    assert!(opacities.len() >= 4 && opacities[0] > 0.0, "several opacities: {opacities:?}");
    assert!(s.has_transparency());
    let panes = procedural::glass_panes();
    assert_eq!(s.triangle_count(), city.triangle_count() + 12 * panes.len());
    assert_eq!(panes.len(), procedural::GLASS_STACK_PANES + 10 + 96, "the stack, the panes across the avenue, the shop windows");
    // Panes stand in the streets: none cuts into a building.
    for (k, (p, _)) in panes.iter().enumerate() {
        let inside = procedural::city_buildings().into_iter().any(|((lo, hi), _)| p.0.cmplt(hi).all() && p.1.cmpgt(lo).all());
        assert!(!inside, "pane {k} {p:?} overlaps a building");
    }
}

/// The ray through the centre pixel of `glass@stack` crosses the whole stack (at least 16
/// transparent panes, twice as many surfaces) and a shop window before it meets a building;
/// pixels around it cross at least 16 panes before an opaque surface too.
#[test]
fn glass_stack_view_puts_sixteen_layers_on_the_centre_pixel() {
    let s = Scene::load("glass@stack", Path::new("/nonexistent")).unwrap();
    let (w, h) = (1920, 1080);
    for (x, y) in [(w / 2, h / 2), (w / 2 - w / 20, h / 2), (w / 2 + w / 20, h / 2), (w / 2, h / 2 - h / 20), (w / 2, h / 2 + h / 20)] {
        let (panes, surfaces, opaque) = look_through(&s, s.camera.position, pixel_ray(&s.camera, w, h, x, y));
        assert!(panes >= 16 && surfaces >= 2 * panes, "pixel ({x}, {y}): {panes} panes, {surfaces} transparent surfaces");
        let opaque = opaque.unwrap_or_else(|| panic!("pixel ({x}, {y}) sees no opaque surface behind the panes"));
        if (x, y) == (w / 2, h / 2) {
            assert_eq!(panes, procedural::GLASS_STACK_PANES + 1, "the whole stack and a shop window");
            assert!((1..=5).contains(&opaque.material), "the centre ends on {:?}, not a building", s.materials[opaque.material as usize].name);
        }
    }
}

/// The default camera sees glass and buildings: on a 32 × 18 grid of rays, some first meet a
/// pane and more first meet a building.
#[test]
fn glass_default_view_sees_glass_and_the_city() {
    let s = procedural::glass();
    let (w, h) = (32, 18);
    let (mut glass, mut building) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            match hits(&s, s.camera.position, pixel_ray(&s.camera, w, h, x, y)).first() {
                Some(hit) if s.materials[hit.material as usize].is_transparent() => glass += 1,
                Some(hit) if (1..=5).contains(&hit.material) => building += 1,
                _ => {}
            }
        }
    }
    assert!(glass * 20 >= w * h && building * 4 >= w * h, "{glass} rays meet glass first, {building} a building, of {}", w * h);
}

#[test]
fn has_transparency_needs_a_mesh_that_uses_it() {
    for name in ["city", "corridor"] {
        assert!(!Scene::load(name, Path::new("/nonexistent")).unwrap().has_transparency(), "{name}");
    }
    assert!(Scene::load("glass", Path::new("/nonexistent")).unwrap().has_transparency());
    let mut s = procedural::city();
    s.materials.push(Material { opacity: 0.5, ..Material::diffuse("unused", [1.0; 3]) });
    assert!(!s.has_transparency(), "a transparent material no mesh uses");
    s.meshes.push(Mesh { material: s.materials.len() as u32 - 1, ..Mesh::default() });
    assert!(!s.has_transparency(), "a mesh without triangles");
    s.materials[1].opacity = 0.99;
    assert!(s.has_transparency());
    s.materials[1].opacity = 1.5;
    assert!(s.validate().unwrap_err().to_string().contains("opacity must be in [0, 1]"));
}

#[test]
fn flatten_carries_the_opacity() {
    let s = procedural::glass();
    let flat = flatten::flatten(&s, Precision::Oct16).unwrap();
    let gpu: Vec<f32> = flat.materials.iter().map(|m| m.opacity).collect();
    assert_eq!(gpu, s.materials.iter().map(|m| m.opacity).collect::<Vec<_>>());
    assert!(gpu.iter().any(|&o| o < 1.0));
}

/// Sponza's MTL says `d 0` on 22 opaque materials: the built-in reads them as opaque, and the
/// curtains variant makes exactly its three curtain materials translucent, in view of its camera.
#[test]
fn sponza_stays_opaque_and_its_curtains_variant_is_translucent() {
    let Some(dir) = shared_assets::asset("sponza") else { return };
    let path = dir.join("sponza.mtl");
    let text = std::fs::read(&path).unwrap();
    let as_written = parse_mtl(&text, &path, &dir, MtlOptions::default()).unwrap();
    assert_eq!(as_written.iter().filter(|m| m.opacity == 0.0).count(), 22, "d 0 as the format reads it");
    let s = Scene::load("sponza", &assets()).unwrap();
    assert!(s.materials.iter().all(|m| m.opacity == 1.0) && !s.has_transparency());
    assert!(!Scene::load("sponza@column", &assets()).unwrap().has_transparency());

    let curtains = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/sponza-curtains.toml"));
    let c = Scene::load(curtains.to_str().unwrap(), &assets()).unwrap();
    assert!(c.has_transparency() && c.warnings.is_empty());
    let mut translucent: Vec<(&str, f32)> = c.materials.iter().filter(|m| m.is_transparent()).map(|m| (m.name.as_str(), m.opacity)).collect();
    translucent.sort_by(|a, b| a.0.cmp(b.0));
    assert_eq!(translucent, [("fabric_c", 0.6), ("fabric_f", 0.55), ("fabric_g", 0.65)]);
    // The centre pixel looks through a curtain onto the arcade behind it.
    let (panes, _, opaque) = look_through(&c, c.camera.position, pixel_ray(&c.camera, 1920, 1080, 960, 540));
    assert!(panes >= 1 && opaque.is_some(), "{panes} curtain layers in front of {opaque:?}");
}
