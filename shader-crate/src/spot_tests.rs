//! CPU tests of `spot`: the falloff's ends and ramp, and the cone tests — conservative against
//! points sampled in every sphere or box they reject, in f64, and tight enough to matter
//! (they reject most of what the range sphere alone keeps for narrow cones).
use super::*;
use crate::test_support::Rng;

fn unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Whether `p` is lit by the spot (apex, cone, range), in f64: inside the range and strictly
/// inside the outer cone.
fn lit(apex: Vec3, cone: &Cone, range: f32, p: Vec3) -> bool {
    let l = (p - apex).as_dvec3();
    let d = cone.direction.as_dvec3();
    let len = l.length();
    len < range as f64 && len > 0.0 && l.dot(d) / len > (cone.cos_outer as f64)
}

#[test]
fn the_falloff_is_one_inside_zero_outside_and_a_squared_ramp_between() {
    let cone = Cone::new(Vec3::NEG_Z, 20f32.to_radians(), 40f32.to_radians());
    assert_eq!(cone_falloff(1.0, &cone), 1.0);
    assert_eq!(cone_falloff(cone.cos_inner, &cone), 1.0);
    assert_eq!(cone_falloff(cone.cos_outer, &cone), 0.0);
    assert_eq!(cone_falloff(-1.0, &cone), 0.0);
    let mid = 0.5 * (cone.cos_inner + cone.cos_outer);
    assert!((cone_falloff(mid, &cone) - 0.25).abs() < 1e-6);
    let hard = Cone::new(Vec3::X, 0.3, 0.3);
    assert_eq!((cone_falloff(hard.cos_outer + 1e-6, &hard), cone_falloff(hard.cos_outer, &hard)), (1.0, 0.0), "equal cones: a hard edge");
    assert_eq!(spot_factor(Vec3::ZERO, &cone, Vec3::ZERO), 1.0, "the apex itself");
    assert_eq!(spot_factor(Vec3::ZERO, &cone, Vec3::new(0.0, 0.0, 3.0)), 0.0, "behind");
    assert_eq!(spot_factor(Vec3::ZERO, &cone, Vec3::new(0.0, 0.0, -3.0)), 1.0, "on the axis");
}

/// A sphere the test rejects holds no lit point: 2 000 random spots (half-angles up to 90°) ×
/// spheres around them, 64 points sampled in each rejected sphere (its centre, its surface
/// toward the apex and the axis, and random points).
#[test]
fn rejected_spheres_hold_no_lit_point() {
    let mut rng = Rng(41);
    let (mut rejected, mut tested) = (0, 0);
    for _ in 0..2000 {
        let apex = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 20.0 - 10.0;
        let outer = rng.unit() * 90f32.to_radians();
        let cone = Cone::new(unit(&mut rng), outer * rng.unit(), outer);
        let range = 0.5 + rng.unit() * 20.0;
        for _ in 0..20 {
            let c = apex + unit(&mut rng) * rng.unit() * (range * 1.5);
            let r = rng.unit() * range * 0.5;
            tested += 1;
            if cone_meets_sphere(apex, &cone, range, c, r) {
                continue;
            }
            rejected += 1;
            let mut points = vec![c, c + (apex - c).normalize_or_zero() * r];
            let foot = apex + cone.direction * (c - apex).dot(cone.direction);
            points.push(c + (foot - c).normalize_or_zero() * r);
            points.extend((0..61).map(|_| c + unit(&mut rng) * r * rng.unit().cbrt()));
            for p in points {
                assert!(!lit(apex, &cone, range, p), "apex {apex}, cone {cone:?}, range {range}: sphere ({c}, {r}) rejected but {p} is lit");
            }
        }
    }
    assert!(rejected * 4 > tested, "the test should reject a good share: {rejected} of {tested}");
}

/// Boxes through their bounding sphere: a rejected box holds no lit point (corners, centre and
/// random points), and for narrow cones (≤ 30°) the cone test rejects most boxes that the range
/// sphere alone keeps — what culling by the true shape buys.
#[test]
fn rejected_boxes_hold_no_lit_point_and_narrow_cones_cull_most_of_the_sphere() {
    let mut rng = Rng(43);
    let (mut sphere_kept, mut cone_kept) = (0, 0);
    for _ in 0..3000 {
        let apex = Vec3::ZERO;
        let outer = (5.0 + rng.unit() * 25.0).to_radians();
        let cone = Cone::new(unit(&mut rng), outer * 0.5, outer);
        let range = 10.0;
        let min = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 24.0 - 12.0;
        let max = min + Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 + 0.01;
        let gap = (apex.clamp(min, max) - apex).length();
        if gap >= range {
            continue;
        }
        sphere_kept += 1;
        if cone_meets_box(apex, &cone, range, min, max) {
            cone_kept += 1;
            continue;
        }
        for k in 0..72 {
            let t = if k < 8 {
                Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32)
            } else {
                Vec3::new(rng.unit(), rng.unit(), rng.unit())
            };
            let p = min + (max - min) * t;
            assert!(!lit(apex, &cone, range, p), "cone {cone:?}: box [{min}, {max}] rejected but {p} is lit");
        }
    }
    assert!(sphere_kept > 500, "enough boxes meet the range sphere: {sphere_kept}");
    assert!(cone_kept * 2 < sphere_kept, "narrow cones keep {cone_kept} of the {sphere_kept} boxes the sphere keeps");
}

/// A sphere that holds the apex, or a lit point on the axis, is always kept; NaN is kept.
#[test]
fn spheres_at_the_apex_and_on_the_axis_are_kept() {
    let cone = Cone::new(Vec3::Y, 0.1, 0.2);
    assert!(cone_meets_sphere(Vec3::ZERO, &cone, 5.0, Vec3::new(0.0, -0.5, 0.0), 0.6), "holds the apex");
    assert!(cone_meets_sphere(Vec3::ZERO, &cone, 5.0, Vec3::new(0.0, 4.9, 0.0), 0.0), "a point on the axis in range");
    assert!(!cone_meets_sphere(Vec3::ZERO, &cone, 5.0, Vec3::new(0.0, 5.5, 0.0), 0.1), "beyond the range");
    assert!(!cone_meets_sphere(Vec3::ZERO, &cone, 5.0, Vec3::new(3.0, 1.0, 0.0), 0.5), "beside the cone");
    assert!(cone_meets_sphere(Vec3::ZERO, &cone, 5.0, Vec3::new(f32::NAN, 1.0, 0.0), 0.5), "NaN is kept");
    let wide = Cone::new(Vec3::Y, 1.0, core::f32::consts::FRAC_PI_2);
    assert!(cone_meets_sphere(Vec3::ZERO, &wide, 5.0, Vec3::new(4.0, 0.0, 0.0), 0.01), "a 90° cone is a half-space: its rim plane is kept");
    assert!(!cone_meets_sphere(Vec3::ZERO, &wide, 5.0, Vec3::new(2.0, -1.0, 0.0), 0.5), "below a 90° cone's plane");
}

/// Points sampled in the box `[min, max]`: its corners, edge midpoints, centre and random points.
fn box_points(rng: &mut Rng, min: Vec3, max: Vec3) -> Vec<Vec3> {
    let mut t: Vec<Vec3> = (0..27).map(|k| Vec3::new((k % 3) as f32, ((k / 3) % 3) as f32, (k / 9) as f32) * 0.5).collect();
    t.extend((0..100).map(|_| Vec3::new(rng.unit(), rng.unit(), rng.unit())));
    t.into_iter().map(|t| min + (max - min) * t).collect()
}

/// Degenerate cones at the ends of the allowed range (the inputs refuse outer angles outside
/// (0°, 90°] and inner > outer — `scene` tests; these are the limits the kernels still see): an
/// outer angle of 1e-6 rad (a ray: nothing off the axis is lit, and the falloff never exceeds 1),
/// an inner angle equal to the outer (a hard edge), 0° inner, and exactly 90° (a half-space).
/// Each stays conservative on sampled boxes, never NaN, and its falloff stays in [0, 1].
#[test]
fn degenerate_cones_stay_conservative_and_bounded() {
    let mut rng = Rng(47);
    let half_pi = core::f32::consts::FRAC_PI_2;
    for (inner, outer, what) in [(0.0, 1e-6, "a ray"), (1e-6, 1e-6, "a ray, hard edge"), (0.0, half_pi, "0° inner, 90° outer"), (half_pi, half_pi, "90° hard edge"), (0.4, 0.4, "hard edge")] {
        let mut kept = 0;
        for _ in 0..400 {
            let cone = Cone::new(unit(&mut rng), inner, outer);
            assert!(cone.cos_outer.is_finite() && cone.sin_outer.is_finite(), "{what}: {cone:?}");
            let min = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 8.0 - 4.0;
            let max = min + Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 3.0 + 0.01;
            let range = 6.0;
            let points = box_points(&mut rng, min, max);
            for &p in &points {
                let f = spot_factor(Vec3::ZERO, &cone, p);
                assert!((0.0..=1.0).contains(&f), "{what}: falloff {f} at {p}");
            }
            if cone_meets_box(Vec3::ZERO, &cone, range, min, max) {
                kept += 1;
                continue;
            }
            for p in points {
                assert!(!lit(Vec3::ZERO, &cone, range, p), "{what}: box [{min}, {max}] rejected but {p} is lit ({cone:?})");
            }
        }
        assert!(kept > 0 && kept < 400, "{what}: the test decides both ways ({kept} of 400 kept)");
    }
    // A ray lights (almost) nothing off its axis: a box beside it is rejected, one on it kept.
    let ray = Cone::new(Vec3::X, 0.0, 1e-6);
    assert!(!cone_meets_box(Vec3::ZERO, &ray, 10.0, Vec3::new(1.0, 1.0, -0.5), Vec3::new(2.0, 2.0, 0.5)));
    assert!(cone_meets_box(Vec3::ZERO, &ray, 10.0, Vec3::new(1.0, -0.5, -0.5), Vec3::new(2.0, 0.5, 0.5)));
}

/// A spot whose apex is exactly a corner of a cluster's box (the real boxes of a cluster grid,
/// `cluster_bounds`), pointing in every direction: that cluster is always kept (the apex lies on
/// its bounding sphere, and a cone opening into the box lights it), and the clusters around it —
/// up to two steps away along each axis — are kept whenever one of their sampled points is lit
/// (conservative), while the cone test still rejects many of them.
#[test]
fn a_spot_at_a_cluster_corner_keeps_the_clusters_it_lights() {
    use crate::cluster_bounds::cluster_aabb_of_key;
    use crate::cluster_key::slice_bounds;
    let g = crate::test_support::grid(640, 360, 32);
    let bounds = slice_bounds(&g);
    let aabb = |i: u32, j: u32, k: u32| {
        let b = cluster_aabb_of_key(&g, &bounds, g.pack(i, j, k));
        (Vec3::from_array(b.min), Vec3::from_array(b.max))
    };
    let step = |rng: &mut Rng, v: u32, n: u32| (v as i32 + rng.below(5) as i32 - 2).clamp(0, n as i32 - 1) as u32;
    let mut rng = Rng(53);
    let (mut neighbours, mut rejected) = (0, 0);
    for _ in 0..300 {
        let (i, j, k) = (rng.below(g.tiles_x), rng.below(g.tiles_y), rng.below(g.num_slices));
        let (min, max) = aabb(i, j, k);
        let c = rng.below(8);
        let corner = Vec3::new(if c & 1 != 0 { max.x } else { min.x }, if c & 2 != 0 { max.y } else { min.y }, if c & 4 != 0 { max.z } else { min.z });
        let range = (max - min).length() * (1.0 + 2.0 * rng.unit());
        for _ in 0..8 {
            let outer = (1.0 + rng.unit() * 89.0).to_radians();
            let into = ((min + max) * 0.5 - corner).normalize();
            for dir in [into, -into, unit(&mut rng)] {
                let cone = Cone::new(dir, outer * rng.unit(), outer);
                assert!(cone_meets_box(corner, &cone, range, min, max), "cluster ({i}, {j}, {k}) with the apex at its corner {corner} rejected ({cone:?})");
                let (ni, nj, nk) = (step(&mut rng, i, g.tiles_x), step(&mut rng, j, g.tiles_y), step(&mut rng, k, g.num_slices));
                let (nmin, nmax) = aabb(ni, nj, nk);
                neighbours += 1;
                if cone_meets_box(corner, &cone, range, nmin, nmax) {
                    continue;
                }
                rejected += 1;
                for p in box_points(&mut rng, nmin, nmax) {
                    assert!(!lit(corner, &cone, range, p), "cluster ({ni}, {nj}, {nk}) rejected but {p} is lit by the spot at {corner} ({cone:?})");
                }
            }
        }
    }
    assert!(rejected * 5 > neighbours, "the cone test rejects a share of the neighbours: {rejected} of {neighbours}");
}
