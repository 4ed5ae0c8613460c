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
