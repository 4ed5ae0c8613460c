//! The ray-cast reference against closed-form visibility: a square occluder's shadow on a floor
//! (a scaled square), a closed box around a light, lights and receivers on surfaces, shared edges,
//! axis-parallel and zero-length segments; and the hierarchy's walk against testing every
//! triangle, on random triangle soups.
use super::*;
use glam::Vec3;

fn square(z: f32, r: f32) -> [[Vec3; 3]; 2] {
    let (a, b, c, d) = (Vec3::new(-r, -r, z), Vec3::new(r, -r, z), Vec3::new(r, r, z), Vec3::new(-r, r, z));
    [[a, b, c], [a, c, d]]
}

/// The 12 triangles of the box `[lo, hi]`.
fn closed_box(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: u32| Vec3::new(if i & 1 == 0 { lo.x } else { hi.x }, if i & 2 == 0 { lo.y } else { hi.y }, if i & 4 == 0 { lo.z } else { hi.z });
    let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    faces.iter().flat_map(|f| [[c(f[0]), c(f[1]), c(f[2])], [c(f[0]), c(f[2]), c(f[3])]]).collect()
}

/// A square of half-width 1 at height `h` over a floor, a light at height `l` above its centre:
/// a floor point `(x, y, 0)` is in shadow exactly when its projection from the light onto the
/// square's plane, `(x, y) · (l − h) / l`, lies in the square. Every floor point of a grid that is
/// not within 1e-6 of the shadow's border must agree.
#[test]
fn a_square_casts_its_scaled_square_on_the_floor() {
    let (h, l) = (1.5f64, 4.0f64);
    let occ = Occluders::new(square(h as f32, 1.0).into_iter().chain(square(0.0, 100.0)));
    assert_eq!(occ.triangle_count(), 4);
    let light = DVec3::new(0.0, 0.0, l);
    let (mut shadowed, mut lit) = (0, 0);
    for i in -60..=60 {
        for j in -60..=60 {
            let (x, y) = (i as f64 * 0.0371, j as f64 * 0.0413);
            let m = x.abs().max(y.abs()) * (l - h) / l;
            if (m - 1.0).abs() < 1e-6 {
                continue;
            }
            let expected = m < 1.0;
            assert_eq!(occ.blocked(DVec3::new(x, y, 0.0), light), expected, "floor point ({x}, {y})");
            if expected { shadowed += 1 } else { lit += 1 }
        }
    }
    assert!(shadowed > 1000 && lit > 1000, "the grid covers both: {shadowed} shadowed, {lit} lit");
}

/// A light inside a closed box reaches every point inside and none outside.
#[test]
fn a_closed_box_hides_its_light_from_everything_outside() {
    let occ = Occluders::new(closed_box(Vec3::splat(-1.0), Vec3::new(2.0, 1.0, 3.0)));
    let light = DVec3::new(0.3, -0.2, 0.9);
    for k in 0..500 {
        let f = k as f64;
        let dir = DVec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).sin() * 0.9).normalize();
        assert!(!occ.blocked(light, light + dir * 0.5), "inside, direction {dir}");
        assert!(occ.blocked(light, light + dir * 10.0), "outside, direction {dir}");
        assert!(occ.blocked(light + dir * 10.0, light), "the test is symmetric");
    }
}

/// A light on a surface is not hidden by that surface (it lies at the segment's end), and a
/// receiver on a surface is not hidden by its own surface; the far side of a box still is.
#[test]
fn end_points_on_surfaces_are_not_hidden_by_them() {
    let occ = Occluders::new(closed_box(Vec3::ZERO, Vec3::ONE));
    let on_top = DVec3::new(0.5, 0.5, 1.0);
    assert!(!occ.blocked(on_top, DVec3::new(0.2, 0.9, 5.0)), "above the top face");
    assert!(!occ.blocked(DVec3::new(0.2, 0.9, 5.0), on_top), "and back");
    assert!(occ.blocked(on_top, DVec3::new(0.5, 0.5, -4.0)), "through the bottom face");
    assert!(!occ.blocked(on_top, DVec3::new(0.1, 0.7, 1.0)), "along the top face itself (in its plane)");
    assert!(!occ.blocked(on_top, DVec3::new(0.4, 0.6, 0.0)), "to a point on the bottom face, inside");
}

/// A segment through the shared edge of two triangles, or a corner, is blocked; one just
/// outside the square is not. Axis-parallel and zero-length segments take the slab test's
/// parallel branch.
#[test]
fn shared_edges_corners_and_axis_parallel_segments() {
    let occ = Occluders::new(square(0.0, 1.0));
    let up = DVec3::new(0.0, 0.0, 1.0);
    for p in [DVec3::new(0.25, 0.25, 0.0), DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::ZERO] {
        assert!(occ.blocked(p - up, p + up), "through {p} (vertical)");
        assert!(occ.blocked(p - up + DVec3::new(0.5, 0.0, 0.0), p + up - DVec3::new(0.5, 0.0, 0.0)), "through {p} (oblique)");
    }
    assert!(!occ.blocked(DVec3::new(1.0 + 1e-9, 0.0, -1.0), DVec3::new(1.0 + 1e-9, 0.0, 1.0)), "beside the edge");
    assert!(!occ.blocked(DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, -0.5)), "short of the square");
    assert!(!occ.blocked(DVec3::ZERO, DVec3::ZERO), "zero length");
    assert!(!occ.blocked(DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, 1.0)), "zero length, off the square");
}

#[test]
fn degenerate_triangles_hide_nothing_and_no_triangles_hide_nothing() {
    let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
    let point = [Vec3::Y; 3];
    let occ = Occluders::new([line, point]);
    assert_eq!(occ.triangle_count(), 0);
    assert!(!occ.blocked(DVec3::new(1.0, 0.0, -1.0), DVec3::new(1.0, 0.0, 1.0)));
    assert!(!Occluders::new([]).blocked(DVec3::ZERO, DVec3::ONE));
}

/// xorshift64*, for reproducible soups without a dependency.
struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
    }
    fn point(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.unit(), self.unit(), self.unit()) * scale
    }
}

/// The walk finds a blocker exactly when testing every triangle does, on soups of small and
/// large, clustered and spread triangles (leaves of every size up to `LEAF_TRIANGLES`).
#[test]
fn the_hierarchy_agrees_with_testing_every_triangle() {
    for (seed, n, size) in [(1u64, 1usize, 3.0f32), (2, 5, 2.0), (3, 37, 1.0), (4, 500, 0.6), (5, 3000, 0.15)] {
        let mut r = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
        let tris: Vec<[Vec3; 3]> = (0..n)
            .map(|_| {
                let c = r.point(10.0);
                [c + r.point(size) - Vec3::splat(size / 2.0), c + r.point(size) - Vec3::splat(size / 2.0), c + r.point(size) - Vec3::splat(size / 2.0)]
            })
            .collect();
        let occ = Occluders::new(tris);
        let (mut hits, total) = (0, 4000);
        for _ in 0..total {
            let (a, b) = (r.point(12.0).as_dvec3() - 1.0, r.point(12.0).as_dvec3() - 1.0);
            let expected = occ.blocked_brute_force(a, b);
            assert_eq!(occ.blocked(a, b), expected, "seed {seed}: segment {a} → {b}");
            hits += expected as u32;
        }
        if n >= 37 {
            assert!(hits > 0 && hits < total, "seed {seed}: {hits} of {total} blocked: the soup must test both outcomes");
        }
    }
}

/// The city's triangles: the hierarchy agrees with brute force from lights above the roofs to
/// points of the ground, and at least 5 % of those points are in shadow and 5 % are not.
#[test]
fn city_shadows_agree_with_brute_force() {
    let scene = super::super::Scene::load("city", std::path::Path::new(".")).unwrap();
    let occ = Occluders::of_scene(&scene);
    assert_eq!(occ.triangle_count(), scene.meshes.iter().map(|m| m.triangle_count()).sum::<usize>());
    let (lo, hi) = (scene.bounds.0.as_dvec3(), scene.bounds.1.as_dvec3());
    let mut r = Rng(77);
    let mut blocked = 0;
    for _ in 0..3000 {
        // Two to six times the tallest roof up (a point inside the bounds is often inside a
        // building, and the narrow streets are mostly hidden from lights just above the roofs).
        let t = DVec3::new(r.unit() as f64, 2.0 + 4.0 * r.unit() as f64, r.unit() as f64);
        let light = lo + (hi - lo) * t;
        let ground = DVec3::new(lo.x + (hi.x - lo.x) * r.unit() as f64, lo.y + 1e-3, lo.z + (hi.z - lo.z) * r.unit() as f64);
        let b = occ.blocked(ground, light);
        assert_eq!(b, occ.blocked_brute_force(ground, light));
        blocked += b as u32;
    }
    assert!(blocked > 150 && blocked < 2850, "{blocked} of 3000 ground points hidden");
}
