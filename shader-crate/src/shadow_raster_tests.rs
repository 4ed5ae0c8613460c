use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::shadow::{cube_face, NO_OCCLUDER, SHADOW_HEADER_WORDS};
use crate::shadow_cull::tests::batch_words;
use crate::shadow_cull::{cull_batch, draw_args, ShadowCullParams, ARGS_DISPATCH, ARGS_WORDS};
use crate::test_support::Rng;
use core::sync::atomic::{AtomicU32, Ordering};

fn range(rng: &mut Rng, a: f32, b: f32) -> f32 {
    a + (b - a) * rng.unit()
}

fn random_vec(rng: &mut Rng, r: f32) -> Vec3 {
    Vec3::new(range(rng, -r, r), range(rng, -r, r), range(rng, -r, r))
}

/// Where the ray from the light along `p` (face frame) meets the triangle `v0 v1 v2` (face
/// frame), in 64-bit floats: `Some((distance from the light, cosine of the ray to the normal))`
/// or `None`; and how far (in radians) the ray passes outside the band the inside tests'
/// tolerance may decide either way around the nearest edge plane (twice [`EDGE_TOLERANCE`]`·|v_j|·|v_k|
/// / |v_j × v_k|`: negative within it).
fn exact(p: Vec3, v: [Vec3; 3]) -> (Option<(f64, f64)>, f64) {
    let p = p.as_dvec3().normalize();
    let v = v.map(|c| c.as_dvec3());
    let det = v[0].dot(v[1].cross(v[2]));
    let mut margin = f64::MAX;
    let mut inside = true;
    for i in 0..3 {
        let (a, b) = (v[(i + 1) % 3], v[(i + 2) % 3]);
        let e = a.cross(b) * det.signum();
        let s = p.dot(e) / e.length();
        let band = 2.0 * EDGE_TOLERANCE as f64 * a.length() * b.length() / e.length();
        margin = margin.min(s.abs() - band);
        inside &= s >= 0.0;
    }
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let t = n.dot(v[0]) / n.dot(p);
    (if inside && t > 0.0 { Some((t, n.normalize().dot(p).abs())) } else { None }, margin)
}

/// Every texel of random triangles (in front of the light, across its plane, around it, near
/// it, far away) against the exact ray–triangle test: covered exactly where the exact test
/// says, except texels whose ray passes within 10⁻⁶ radians of the tolerance's band around an edge
/// plane; the same distance
/// to 10⁻⁵ relative (plus the corners' rounding); every covered texel inside the triangle's box; the radius respected.
#[test]
fn texels_equal_the_exact_ray_test_and_stay_in_the_box() {
    let mut rng = Rng(21);
    let res = 48;
    let (mut covered, mut crossing, mut checked) = (0, 0, 0);
    for i in 0..1500 {
        let (c, s) = match i % 4 {
            0 => (random_vec(&mut rng, 6.0), range(&mut rng, 0.2, 3.0)),
            1 => (random_vec(&mut rng, 1.0), range(&mut rng, 1.0, 6.0)),
            2 => (random_vec(&mut rng, 0.05), range(&mut rng, 0.01, 0.2)),
            _ => (random_vec(&mut rng, 60.0), range(&mut rng, 1.0, 40.0)),
        };
        let d = [c + random_vec(&mut rng, s), c + random_vec(&mut rng, s), c + random_vec(&mut rng, s)];
        let radius = range(&mut rng, 0.5, 100.0);
        for f in 0..FACES {
            let t = face_triangle(d[0], d[1], d[2], f, res, radius);
            let v = [to_face(d[0], f), to_face(d[1], f), to_face(d[2], f)];
            crossing += usize::from(t.texels() > 0 && v.iter().any(|c| c.z <= 0.0));
            for y in 0..res {
                for x in 0..res {
                    let p = texel_ray(x, y, res);
                    let got = if t.texels() == 0 { -1.0 } else { texel_distance(&t, x, y, res) };
                    let (want, margin) = exact(p, v);
                    let want = want.filter(|&(w, _)| w <= radius as f64);
                    if margin < 1e-6 || want.is_some_and(|(w, _)| (w - radius as f64).abs() < 1e-4 * w) {
                        continue;
                    }
                    checked += 1;
                    match want {
                        Some((w, cos)) => {
                            covered += 1;
                            assert!(got >= 0.0, "triangle {d:?} face {f}: texel ({x}, {y}) missed (exact distance {w})");
                            // Rounding of the corners' coordinates (a few ulps of the largest) carries
                            // into the plane's offset, and along a grazing ray by 1 / cos: a triangle
                            // near the light is off by more than 10⁻⁵ of its distance, still far
                            // below the bias rule's texel.
                            let far = v.iter().map(|c| c.length()).fold(0.0f32, f32::max) as f64;
                            assert!(((got as f64) - w).abs() <= 1e-5 * w + 4e-6 * far / cos, "triangle {d:?} face {f}: texel ({x}, {y}) at {got}, exactly {w}");
                            assert!((t.lo_x..=t.hi_x).contains(&x) && (t.lo_y..=t.hi_y).contains(&y), "triangle {d:?} face {f}: texel ({x}, {y}) outside the box {t:?}");
                        }
                        None => assert!(got < 0.0, "triangle {d:?} face {f}: texel ({x}, {y}) covered at {got}, the exact ray misses"),
                    }
                }
            }
        }
    }
    assert!(covered > 100_000 && crossing > 200 && checked > 10_000_000, "{covered} covered texels, {crossing} triangles across the light's plane, {checked} checked");
}

/// A closed box around the light, its six sides in jittered grids of triangles (every edge shared
/// by two triangles, none axis-aligned): every texel of every face is covered, at the distance of
/// the side its ray meets. A floor split the same way: every texel whose ray meets it inside its
/// border is covered. No texel leaks between triangles.
#[test]
fn meshes_leave_no_texel_between_their_triangles() {
    let mut rng = Rng(8);
    let (n, res) = (7usize, 40);
    // Side `s` of the cube [-1, 1]³ (offset by the light at the origin + a shift) as a grid.
    let shift = Vec3::new(0.13, -0.21, 0.07);
    let mut tris = vec![];
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut grid = vec![vec![Vec3::ZERO; n + 1]; n + 1];
            for (i, row) in grid.iter_mut().enumerate() {
                for (j, p) in row.iter_mut().enumerate() {
                    let interior = |k: usize| k > 0 && k < n;
                    let jit = |rng: &mut Rng, k: usize| if interior(k) { range(rng, -0.3, 0.3) / n as f32 } else { 0.0 };
                    let (a, b) = (-1.0 + 2.0 * i as f32 / n as f32 + jit(&mut rng, i), -1.0 + 2.0 * j as f32 / n as f32 + jit(&mut rng, j));
                    let mut q = [0.0; 3];
                    q[axis] = sign;
                    q[(axis + 1) % 3] = a;
                    q[(axis + 2) % 3] = b;
                    *p = Vec3::from_array(q) + shift;
                }
            }
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (grid[i][j], grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1]);
                    if (i + j) % 2 == 0 {
                        tris.extend([[a, b, c], [a, c, d]]);
                    } else {
                        tris.extend([[a, b, d], [b, c, d]]);
                    }
                }
            }
        }
    }
    for f in 0..FACES {
        let mut map = vec![NO_OCCLUDER; (res * res) as usize];
        for t in &tris {
            let ft = face_triangle(t[0], t[1], t[2], f, res, 10.0);
            raster_texels(&ft, 0, 1, 0, res, &mut map[..]);
        }
        for y in 0..res {
            for x in 0..res {
                let got = f32::from_bits(map[(y * res + x) as usize]);
                // The side the ray meets: the largest of its components relative to the shifted box.
                let p = texel_ray(x, y, res);
                let (right, up, forward) = face_axes(f);
                let dir = (right * p.x + up * p.y + forward * p.z).normalize();
                let t = [0, 1, 2].map(|a| {
                    let c = dir[a];
                    let wall = if c > 0.0 { 1.0 + shift[a] } else { -1.0 + shift[a] };
                    if c == 0.0 { f32::MAX } else { wall / c }
                });
                let want = t.into_iter().filter(|&t| t > 0.0).fold(f32::MAX, f32::min);
                assert!(got != f32::from_bits(NO_OCCLUDER), "face {f} texel ({x}, {y}) leaks: no side of the box covers it");
                // Jittered interior vertices stay on their side's plane: the distance is the wall's.
                assert!((got - want).abs() <= 1e-5 * want, "face {f} texel ({x}, {y}) at {got}, the wall at {want}");
            }
        }
    }
}

/// A small scene's batches culled for a few casters (`shadow_cull`) and rasterised by the
/// emulated kernel at subgroup widths 4 to 64 into faces of six sides in one atlas: the maps
/// equal those of the triangles drawn one
/// at a time over every texel of their faces (no box), with large triangles (shared by the
/// workgroup) and small ones (one invocation each) both present; entries past the written ones
/// and the dispatch's grid as `draw_args` writes it.
#[test]
fn emulated_kernel_equals_every_texel_of_every_culled_triangle() {
    let mut rng = Rng(44);
    let n_tris = 3 * BATCH_TRIANGLES - 11;
    let mut positions = vec![];
    for t in 0..n_tris {
        // Mostly small triangles, every ninth a large one (a floor tile near the lights).
        let (c, s) = if t % 9 == 0 { (random_vec(&mut rng, 2.0), 3.0) } else { (random_vec(&mut rng, 4.0), 0.4) };
        for _ in 0..3 {
            let p = c + random_vec(&mut rng, s);
            positions.extend_from_slice(&[p.x, p.y, p.z]);
        }
    }
    let indices: Vec<u32> = (0..3 * n_tris).collect();
    let n_batches = n_tris.div_ceil(BATCH_TRIANGLES);
    let batches = batch_words(&positions, n_tris);
    let view = Mat4::from_rotation_z(0.4) * Mat4::from_rotation_x(1.1);
    let lights: Vec<(Vec3, f32)> = (0..4).map(|_| (random_vec(&mut rng, 3.0), range(&mut rng, 3.0, 9.0))).collect();
    // Casters 1 and 3 spot lights (their cubes turned to cones of 30° and 60°).
    let cone = |l: usize| match l {
        1 => (Vec3::new(0.2, -1.0, 0.3).normalize(), 30.0f32.to_radians().cos()),
        3 => (Vec3::new(-0.7, 0.1, 0.7).normalize(), 60.0f32.to_radians().cos()),
        _ => (Vec3::ZERO, crate::shadow::NO_CONE),
    };
    let casters: Vec<f32> = lights.iter().enumerate().flat_map(|(l, (p, r))| [p.x, p.y, p.z, *r, cone(l).0.x, cone(l).0.y, cone(l).0.z, cone(l).1]).collect();
    // The face table: sides from 5 to 40 texels, the faces one after another in the atlas.
    let maps_n = lights.len() as u32 * FACES;
    let mut slots = vec![40, 0, SHADOW_HEADER_WORDS, 0];
    let mut texels = 0;
    for m in 0..maps_n {
        let side = [24, 8, 5, 40, 16, 33][(m % 6) as usize];
        slots.extend([texels, side]);
        texels += side * side;
    }
    let texels = texels as usize;
    let cull = ShadowCullParams { batches: n_batches, casters: lights.len() as u32, capacity: 1000, pad: 0 };
    let mut entries = vec![0u32; (ENTRY_WORDS * cull.capacity) as usize];
    let mut args = [0u32; ARGS_WORDS as usize];
    for c in 0..cull.casters {
        for b in 0..n_batches {
            cull_batch(b, c, &cull, view, &batches, &casters, &slots, &mut entries, &mut args[ARGS_COUNTED]);
        }
    }
    draw_args(&mut args, cull.capacity);
    let written = args[ARGS_COUNTED];
    let d = ARGS_DISPATCH as usize;
    assert!(written > 10 && args[d] * args[d + 1] >= written && args[d + 2] == 1, "{written} entries, dispatch {:?}", &args[d..d + 3]);
    // Reference: each entry's triangles over every texel of their face.
    let mut want = vec![NO_OCCLUDER; texels];
    let (mut large, mut small) = (0, 0);
    for e in 0..written {
        let (b, map) = (entries[(e * ENTRY_WORDS) as usize], entries[(e * ENTRY_WORDS + 1) as usize]);
        for k in 0..BATCH_TRIANGLES {
            let (base, res) = face_entry(&slots, map);
            let t = entry_triangle(k, b, map, res, view, &positions, &indices, &casters, &batches);
            match t.texels() {
                0 => continue,
                n if n > SMALL_TEXELS => large += 1,
                _ => small += 1,
            }
            let whole = FaceTriangle { lo_x: 0, lo_y: 0, hi_x: res - 1, hi_y: res - 1, ..t };
            raster_texels(&whole, 0, 1, base, res, &mut want[..]);
        }
    }
    assert!(large > 20 && small > 200, "{large} large and {small} small triangles");
    assert!(want.iter().filter(|&&w| w != NO_OCCLUDER).count() > texels / 20, "the maps are nearly empty");
    let p = ShadowRasterParams { capacity: cull.capacity, pad: [0; 3] };
    for width in [4, 8, 16, 32, 64] {
        let maps: Vec<AtomicU32> = (0..texels).map(|_| AtomicU32::new(NO_OCCLUDER)).collect();
        let emu = Emulation { width, workgroup_size: RASTER_WORKGROUP, shared_words: QUEUE_WORDS };
        // Two workgroups more than the entries (a grid's last row): they return.
        run_workgroups(emu, written + 2, |e, c, s| {
            let mut m: &[AtomicU32] = &maps;
            raster_entry(c, s, e, &p, view, &positions, &indices, &casters, &batches, &entries, &args, &slots, &mut m);
        });
        let got: Vec<u32> = maps.iter().map(|m| m.load(Ordering::Relaxed)).collect();
        let off = got.iter().zip(&want).filter(|(g, w)| g != w).count();
        assert_eq!(off, 0, "width {width}: {off} texels differ from every triangle drawn over its whole face");
    }
}

/// The kernel's texels agree with the lookup's: a triangle covering texel `(x, y)` of face `f`
/// covers the direction the lookup maps to that texel and face.
#[test]
fn texel_rays_are_the_lookups_texels() {
    for res in [1, 7, 32, 256] {
        for f in 0..FACES {
            for (x, y) in [(0, 0), (res - 1, 0), (res / 2, res / 3), (res - 1, res - 1)] {
                let p = texel_ray(x, y, res);
                let (right, up, forward) = face_axes(f);
                let d = right * p.x + up * p.y + forward * p.z;
                assert_eq!(cube_face(d * 3.0), f, "res {res} texel ({x}, {y}) of face {f}");
                let (tx, ty) = crate::shadow::face_texel(d, f, res);
                assert_eq!((tx as u32, ty as u32), (x, y), "res {res} face {f}");
            }
        }
    }
}

/// A spot light's turned cube (`shadow::CubeFrame`) is the same for the raster and the lookup:
/// a square across the cone, drawn through the caster's record (`entry_triangle`) into every
/// face, shadows exactly the receivers whose ray from the light crosses it (an exact test in
/// 64-bit floats; receivers within two texels' angle of the square's edges are left out), for a
/// cone centred on a face (30°) and one centred on a corner (55°). The same maps looked up
/// through view space's axes instead get many wrong, so the frame is what makes them agree.
#[test]
fn a_turned_cube_draws_and_looks_up_the_same_shadows() {
    use crate::shadow::{cube_visibility, CubeFrame, SHADOW_FILTER_NEAREST};
    const RES: u32 = 64;
    let light = Vec3::new(1.0, 4.0, -2.0);
    let axis = Vec3::new(0.3, -1.0, 0.2).normalize();
    let (t, s) = (axis.any_orthonormal_vector(), axis.cross(axis.any_orthonormal_vector()));
    // The square, 1.5 from the light across the axis, half-side H (about 17° off the axis).
    const H: f32 = 0.45;
    let centre = light + axis * 1.5;
    let corners = [centre - H * t - H * s, centre + H * t - H * s, centre + H * t + H * s, centre - H * t + H * s];
    let tris = [[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]];
    let positions: Vec<f32> = tris.iter().flatten().flat_map(|v| v.to_array()).collect();
    let indices: Vec<u32> = (0..6).collect();
    let batches = batch_words(&positions, 2);
    let slots: Vec<u32> = [vec![RES, SHADOW_FILTER_NEAREST, SHADOW_HEADER_WORDS + 1, 0, 0], (0..FACES).flat_map(|f| [f * RES * RES, RES]).collect()].concat();
    for outer_deg in [30.0f32, 55.0] {
        let cos_outer = outer_deg.to_radians().cos();
        let casters = [light.x, light.y, light.z, 10.0, axis.x, axis.y, axis.z, cos_outer];
        let mut maps = vec![NO_OCCLUDER; (FACES * RES * RES) as usize];
        for f in 0..FACES {
            for k in 0..2 {
                let tri = entry_triangle(k, 0, f, RES, Mat4::IDENTITY, &positions, &indices, &casters, &batches);
                let whole = FaceTriangle { lo_x: 0, lo_y: 0, hi_x: RES - 1, hi_y: RES - 1, ..tri };
                raster_texels(&whole, 0, 1, f * RES * RES, RES, &mut maps[..]);
            }
        }
        let frame = CubeFrame::of_cone(axis, cos_outer);
        let mut rng = Rng(0xc0de);
        let (mut checked, mut shadowed, mut wrong_in_view_axes) = (0, 0, 0);
        for _ in 0..8000 {
            let dir = (axis + random_vec(&mut rng, 0.7)).normalize();
            if dir.dot(axis) < cos_outer {
                continue;
            }
            let p = light + dir * 3.0;
            // The ray's crossing of the square's plane, in the square's axes (64-bit floats).
            let (d, a, tt, ss) = (dir.as_dvec3(), axis.as_dvec3(), t.as_dvec3(), s.as_dvec3());
            let hit = d * (1.5 / d.dot(a));
            let (u, v) = (hit.dot(tt).abs(), hit.dot(ss).abs());
            // Two texels' angle at the square's distance, at a face's centre (corner texels are
            // smaller): 2 · 2 · 1.5 / RES, widened for the plane's obliquity.
            let band = 4.0 * 1.5 / RES as f64 * 1.5;
            let h = H as f64;
            if (u - h).abs() < band || (v - h).abs() < band {
                continue;
            }
            let inside = u < h && v < h;
            let n = -dir;
            let lit = cube_visibility(&maps, &slots, 0, SHADOW_FILTER_NEAREST, light, &frame, p, n);
            assert_eq!(lit, if inside { 0.0 } else { 1.0 }, "{outer_deg}°: receiver along {dir:?} (square at ({u:.3}, {v:.3}))");
            checked += 1;
            shadowed += inside as u32;
            wrong_in_view_axes += (cube_visibility(&maps, &slots, 0, SHADOW_FILTER_NEAREST, light, &CubeFrame::VIEW, p, n) != lit) as u32;
        }
        assert!(checked > 1000 && shadowed > 200 && checked - shadowed > 100, "{outer_deg}°: {checked} receivers, {shadowed} shadowed");
        assert!(wrong_in_view_axes > checked / 10, "{outer_deg}°: view space's axes got only {wrong_in_view_axes} of {checked} wrong");
    }
}
