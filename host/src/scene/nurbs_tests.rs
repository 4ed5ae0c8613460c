//! Tests of the NURBS model: every validation error names the patch and the field on one line;
//! the built-ins validate and evaluate through the shader crate's functions (the sphere at its
//! radius, the torus around its tube circle, the teapot's patches joined without gaps).
use super::*;
use shaders::nurbs::{surface_derivs, tessellate_vertex, vertex_grid, NurbsVertex};

fn vec4(p: [f32; 4]) -> glam::Vec4 {
    glam::Vec4::from_array(p)
}

/// The grid of `patch` at `level`, evaluated as the tessellation pass will.
fn grid(patch: &NurbsPatch, level: u32) -> Vec<NurbsVertex> {
    let mut b = NurbsBuffers::default();
    b.knots.push(-1.0); // non-zero offsets
    b.control_points.push([9.0; 4]);
    let h = b.push(patch, level);
    let knot = |i: u32| b.knots[i as usize];
    let cp = |i: u32| vec4(b.control_points[i as usize]);
    (0..vertex_count(level)).map(|k| vertex_grid(level, k)).map(|(i, j)| tessellate_vertex(&h, i, j, level, knot, cp)).collect()
}

fn bilinear() -> NurbsPatch {
    NurbsPatch::polynomial(1, 1, 2, 2, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], 0)
}

/// Applies `edit` to a valid patch and returns the validation error.
fn error(edit: impl FnOnce(&mut NurbsPatch)) -> String {
    let mut p = sphere(Vec3::ZERO, 1.0);
    edit(&mut p);
    format!("{:#}", p.validate("dome").unwrap_err())
}

#[test]
fn validation_errors_name_the_patch_and_the_field() {
    type Edit = Box<dyn FnOnce(&mut NurbsPatch)>;
    let cases: Vec<(Edit, &str)> = vec![
        (Box::new(|p| p.degree_u = 0), "degree_u is 0"),
        (Box::new(|p| p.degree_v = 6), "degree_v is 6"),
        (Box::new(|p| p.knots_u.push(1.0)), "knots_u has 13 values"),
        (Box::new(|p| { p.knots_v.pop(); }), "knots_v has 7 values"),
        (Box::new(|p| p.knots_u[4] = 0.2), "knots_u[4] = 0.2 is less than knots_u[3] = 0.25"),
        (Box::new(|p| p.knots_u[3] = -0.1), "knots_u[3] = -0.1 is less than knots_u[2] = 0"),
        (Box::new(|p| p.knots_v[3] = f32::NAN), "knots_v[3] is NaN"),
        (Box::new(|p| p.knots_v = vec![0.0; 8]), "v domain knots_v[2..=5] = [0, 0] has zero length"),
        (Box::new(|p| { p.control_points.pop(); }), "control_points has 44 points"),
        (Box::new(|p| { p.weights.pop(); }), "weights has 44 values"),
        (Box::new(|p| p.control_points[7][1] = f32::NAN), "control_points[7] = ["),
        (Box::new(|p| p.control_points[8][2] = f32::INFINITY), "control_points[8] = [0.0, -1.0, inf] is not finite"),
        (Box::new(|p| p.weights[3] = 0.0), "weights[3] = 0; weights must be positive"),
        (Box::new(|p| p.weights[4] = -0.5), "weights[4] = -0.5"),
        (Box::new(|p| p.weights[5] = f32::NAN), "weights[5] = NaN"),
        (Box::new(|p| p.weights[6] = f32::INFINITY), "weights[6] = inf"),
        (Box::new(|p| p.size_v = 2), "size_v is 2; degree 2 needs at least 3"),
    ];
    for (edit, want) in cases {
        let e = error(edit);
        assert!(e.starts_with("NURBS patch \"dome\": "), "{e}");
        assert!(e.contains(want), "{e:?} lacks {want:?}");
        assert!(!e.contains('\n'), "{e}");
    }
    // Unclamped knot vectors are fine; so are repeated knots outside the domain.
    let mut p = bilinear();
    p.knots_u = vec![-1.0, 0.0, 1.0, 2.0];
    p.knots_v = vec![0.0, 0.0, 1.0, 1.0];
    p.validate("flat").unwrap();
    p.knots_u = vec![0.0, 0.5, 0.5, 2.0];
    assert!(format!("{:#}", p.validate("flat").unwrap_err()).contains("u domain knots_u[1..=2] = [0.5, 0.5] has zero length"));
}

#[test]
fn built_ins_validate() {
    sphere(Vec3::new(1.0, 2.0, 3.0), 0.5).validate("sphere").unwrap();
    torus(Vec3::ZERO, 2.0, 0.5).validate("torus").unwrap();
    bilinear().validate("bilinear").unwrap();
    let t = teapot();
    assert_eq!(t.len(), 32);
    for (i, p) in t.iter().enumerate() {
        p.validate(&format!("teapot {i}")).unwrap();
        assert_eq!((p.degree_u, p.degree_v, p.size_u, p.size_v), (3, 3, 4, 4), "bicubic Bézier");
    }
}

#[test]
fn sphere_evaluates_at_its_radius_with_radial_normals() {
    let (c, r) = (Vec3::new(1.0, -2.0, 0.5), 2.5);
    for v in grid(&sphere(c, r), 24) {
        let d = v.position - c;
        assert!((d.length() / r - 1.0).abs() < 1e-6, "{v:?} at radius {}", d.length());
        assert!((v.normal - d.normalize()).length() < 1e-5, "{v:?}");
    }
    // Off the grid too, through the evaluation itself.
    let mut b = NurbsBuffers::default();
    let h = b.push(&sphere(c, r), 4);
    for k in 0..500 {
        let (u, v) = ((k as f32 * 0.618_034).fract(), (k as f32 * 0.414_213_57).fract());
        let s = surface_derivs(&h, u, v, |i| b.knots[i as usize], |i| vec4(b.control_points[i as usize])).s;
        assert!(((s - c).length() / r - 1.0).abs() < 1e-6, "({u}, {v}): {s}");
    }
}

#[test]
fn torus_evaluates_around_its_tube_circle() {
    let (c, big, small) = (Vec3::new(0.0, 1.0, 0.0), 2.0, 0.5);
    for v in grid(&torus(c, big, small), 24) {
        let d = v.position - c;
        let ring = Vec3::new(d.x, 0.0, d.z).normalize() * big; // nearest point of the tube circle
        let off = d - ring;
        assert!((off.length() / small - 1.0).abs() < 1e-5, "{v:?}: {} from the tube circle", off.length());
        assert!((v.normal - off.normalize()).length() < 1e-4, "{v:?}");
    }
}

#[test]
fn teapot_patches_evaluate_and_join() {
    let patches = teapot();
    let level = 8;
    let grids: Vec<_> = patches.iter().map(|p| grid(p, level)).collect();
    for (i, g) in grids.iter().enumerate() {
        for v in g {
            assert!(v.position.is_finite() && (v.normal.length() - 1.0).abs() < 1e-5, "patch {i}: {v:?}");
        }
        // A Bézier patch interpolates its corner control points.
        let p = &patches[i].control_points;
        assert!((g[0].position - Vec3::from(p[0])).length() < 1e-5 && (g[g.len() - 1].position - Vec3::from(p[15])).length() < 1e-5);
    }
    // The revolved body is closed around: each quarter's last column is the next one's first,
    // and each profile segment's top row the next segment's bottom row.
    let n = level as usize + 1;
    let col = |g: &Vec<NurbsVertex>, i: usize| (0..n).map(|j| g[j * n + i].position).collect::<Vec<_>>();
    let row = |g: &Vec<NurbsVertex>, j: usize| (0..n).map(|i| g[j * n + i].position).collect::<Vec<_>>();
    let close = |a: Vec<Vec3>, b: Vec<Vec3>| a.iter().zip(&b).all(|(x, y)| (*x - *y).length() < 1e-5);
    for s in 0..6 {
        for q in 0..4 {
            let (a, b) = (&grids[4 * s + q], &grids[4 * s + (q + 1) % 4]);
            assert!(close(col(a, n - 1), col(b, 0)), "segment {s}, quarter {q}");
            if s < 5 {
                assert!(close(row(a, n - 1), row(&grids[4 * (s + 1) + q], 0)), "segment {s} to {}", s + 1);
            }
        }
    }
    // The body's outside faces away from the axis at its widest.
    let side = &grids[4][(n - 1) * n + n / 2];
    assert!(Vec3::new(side.position.x, 0.0, side.position.z).dot(side.normal) > 0.0, "{side:?}");
}

#[test]
fn buffers_pack_patches_with_premultiplied_weights() {
    let mut b = NurbsBuffers::default();
    let s = sphere(Vec3::ZERO, 1.0);
    let h0 = b.push(&bilinear(), 2);
    let h1 = b.push(&s, 5);
    assert_eq!((h0.knot_offset_u, h0.knot_offset_v, h0.cp_offset, h0.vertex_offset, h0.index_offset), (0, 4, 0, 0, 0));
    assert_eq!((h1.knot_offset_u, h1.knot_offset_v, h1.cp_offset, h1.vertex_offset, h1.index_offset), (8, 20, 4, 9, 24));
    assert_eq!((b.vertices, b.indices, b.knots.len(), b.control_points.len()), (9 + 36, 24 + 150, 28, 49));
    let (p, w) = (s.control_points[1], s.weights[1]);
    assert_eq!(b.control_points[4 + 1], [p[0] * w, p[1] * w, p[2] * w, w]);
    assert_eq!(b.patches, vec![h0, h1]);
}

/// Packed relative to a camera far from the origin, a patch evaluates to its world-space points
/// minus the camera, as the renderer draws (camera-relative).
#[test]
fn relative_packing_translates_the_surface() {
    let (c, r) = (Vec3::new(1.0e5 + 3.0, 20.0, -1.0e5), 2.0);
    let eye = glam::DVec3::new(1.0e5, 18.5, -1.0e5 + 9.0);
    let mut b = NurbsBuffers::default();
    let h = b.push_relative(&sphere(c, r), 8, eye);
    let centre = (c.as_dvec3() - eye).as_vec3();
    let knot = |i: u32| b.knots[i as usize];
    let cp = |i: u32| vec4(b.control_points[i as usize]);
    for k in 0..vertex_count(8) {
        let (i, j) = vertex_grid(8, k);
        let v = tessellate_vertex(&h, i, j, 8, knot, cp);
        let d = v.position - centre;
        // Near the camera f32 keeps the radius to 1e-6 (world-space f32 at 1e5 m would not).
        assert!((d.length() / r - 1.0).abs() < 1e-6, "{v:?}: radius {}", d.length());
    }
    // At the origin it is the plain packing, bit for bit.
    let (mut a, mut z) = (NurbsBuffers::default(), NurbsBuffers::default());
    a.push(&sphere(c, r), 3);
    z.push_relative(&sphere(c, r), 3, glam::DVec3::ZERO);
    assert_eq!(a, z);
}

/// `[[nurbs]]` tables of a description: a patch loads with its defaults (clamped uniform knots,
/// weights 1, the default level), grows the bounds and takes its material by name; bad input is
/// one line naming the file, the patch and the field.
#[test]
fn description_patches_load_and_bad_ones_are_named() {
    use super::super::tests::{assets, description_err, temp::TempDir};
    use super::super::Scene;
    let table = |body: &str| format!("geometry = \"nurbs\"\n[[nurbs]]\ndegree_u = 1\ndegree_v = 1\nsize_u = 2\nsize_v = 2\ncontrol_points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\nmaterial = \"gold\"\n[[nurbs]]\n{body}\n");
    let good = "degree_u = 2\ndegree_v = 1\nsize_u = 3\nsize_v = 2\ncontrol_points = [[0, 0, 0], [1, 0, 1], [2, 0, 0], [0, 30, 0], [1, 30, 1], [2, 30, 0]]\nweights = [1, 0.5, 1, 1, 0.5, 1]\nmaterial = \"floor\"\nlevel = 3";
    let dir = TempDir::new("nurbs-desc");
    let p = dir.write("n.toml", &table(good));
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(s.nurbs.len(), 34 + 2, "the scene's patches, then the tables'");
    let (a, b) = (&s.nurbs[34], &s.nurbs[35]);
    assert_eq!((a.name.as_str(), a.level, a.level(), a.patch.material), ("nurbs[0]", None, DEFAULT_TESS_LEVEL, 3));
    assert_eq!((a.patch.knots_u.as_slice(), a.patch.weights.as_slice()), (&[0.0, 0.0, 1.0, 1.0][..], &[1.0; 4][..]));
    assert_eq!((b.name.as_str(), b.level, b.patch.material, b.patch.knots_u.len()), ("nurbs[1]", Some(3), 0, 6));
    assert_eq!(s.bounds.1.y, 30.0, "the bounds hold the control points");
    let cases = [
        (good.replace("degree_u = 2", "degree_u = 0"), "degree_u is 0"),
        (good.replace("degree_v = 1", "degree_v = 6"), "degree_v is 6"),
        (good.replace("weights = [1, 0.5, 1, 1, 0.5, 1]", "weights = [1, 0.5, 1, 1, 0, 1]"), "weights[4] = 0; weights must be positive"),
        (good.replace("weights = [1, 0.5, 1, 1, 0.5, 1]", "weights = [1, 0.5, 1, 1, -0.5, 1]"), "weights[4] = -0.5"),
        (good.replace("weights = [1, 0.5, 1, 1, 0.5, 1]", "weights = [1, 0.5, 1]"), "weights has 3 values; size_u · size_v = 6 needed"),
        (good.replace("[1, 30, 1]", "[1, nan, 1]"), "control_points[4] = [1.0, NaN, 1.0] is not finite"),
        (good.replace("[2, 30, 0]]", "[2, 30, 0], [3, 30, 0]]"), "control_points has 7 points; size_u · size_v = 6 needed"),
        (format!("{good}\nknots_u = [0, 0, 0, 1, 0.5, 1]"), "knots_u[4] = 0.5 is less than knots_u[3] = 1: knot vectors must be non-decreasing"),
        (format!("{good}\nknots_v = [0, 0, 1]"), "knots_v has 3 values; size_v + degree_v + 1 = 4 needed"),
        (format!("{good}\nknots_v = [0, 0, 0, 0]"), "v domain knots_v[1..=2] = [0, 0] has zero length"),
        (good.replace("size_u = 3", "size_u = 2"), "size_u is 2; degree 2 needs at least 3"),
        (good.replace("level = 3", "level = 0"), "level is 0; it must be 1 to 256"),
        (good.replace("level = 3", "level = 257"), "level is 257"),
        // Sizes that do not match the points: no default knots are built for them.
        (good.replace("size_u = 3", "size_u = 4000000000"), "control_points has 6 points; size_u · size_v = 8000000000 needed"),
    ];
    for (body, want) in cases {
        let e = description_err(&table(&body));
        assert!(e.contains("NURBS patch \"nurbs[1]\": ") && e.contains(want) && !e.contains('\n'), "{want:?}: {e}");
    }
    let e = description_err(&table(&good.replace("\"floor\"", "\"chrome\"")));
    assert!(e.contains("nurbs[1].material = \"chrome\" names no material of geometry") && e.contains("\"gold\""), "{e}");
    let e = description_err(&table(&format!("{good}\nknot_u = [0, 1]")));
    assert!(e.contains("unknown field `knot_u`") && !e.contains('\n'), "{e}");
}

/// The f64 evaluator: the exact sphere's points at radius 1 to 1e-12 (the f32 data's rounding of
/// √½ aside: weights and points are f32, so 1e-7), the f32 kernel's grid within f32 rounding of
/// it, and the tessellation error: 0 for a flat patch, falling about fourfold per doubled level
/// on the sphere, within 1 % of the analytic sagitta of its equator (a chord of angle 2π/L
/// strays `1 − cos(π/L)` from the circle).
#[test]
fn the_f64_surface_and_the_tessellation_error() {
    let s = sphere(Vec3::ZERO, 1.0);
    let [u0, u1, v0, v1] = domain_f64(&s);
    for k in 0..200 {
        let (u, v) = (u0 + (u1 - u0) * (k as f64 * 0.618).fract(), v0 + (v1 - v0) * (k as f64 * 0.377).fract());
        let r = point_f64(&s, u, v).length();
        assert!((r - 1.0).abs() < 1e-6, "sphere at ({u}, {v}): radius {r}");
    }
    for (v, p) in grid(&s, 8).iter().enumerate() {
        let (i, j) = (v % 9, v / 9);
        let exact = point_f64(&s, u0 + (u1 - u0) * i as f64 / 8.0, v0 + (v1 - v0) * j as f64 / 8.0);
        assert!((p.position.as_dvec3() - exact).length() < 1e-5, "vertex ({i}, {j})");
    }
    assert!(tessellation_error(&bilinear(), 4) < 1e-6, "a flat patch has no tessellation error");
    let e: Vec<f64> = [4, 8, 16, 32].iter().map(|&l| tessellation_error(&s, l)).collect();
    for w in e.windows(2) {
        assert!(w[1] < w[0] / 3.0 && w[1] > w[0] / 5.0, "errors {e:?} should fall about fourfold per doubled level");
    }
    // At level 16 the quads' diagonals stray a little more than the equator's chords.
    let sagitta = 1.0 - (std::f64::consts::PI / 16.0).cos();
    assert!(e[2] >= sagitta * 0.99, "level 16: {} against the equator's sagitta {sagitta}", e[2]);
}
