//! CPU tests of the tessellation kernels: the patch search over ranges of every length, and the
//! whole pass run invocation by invocation over several patches at different levels and non-zero
//! stream offsets, against `nurbs::tessellate_vertex` / `tessellate_indices` called per patch.
use super::*;
use crate::nurbs::{index_count, vertex_count, vertex_grid};
use crate::test_support::Rng;
use glam::{Vec3, Vec4};

#[test]
fn patch_at_finds_the_range_of_every_element() {
    let mut rng = Rng(11);
    for count in 1..40u32 {
        let mut starts = vec![rng.below(5)];
        for _ in 1..count {
            let last = *starts.last().unwrap();
            starts.push(last + 1 + rng.below(9));
        }
        let end = starts.last().unwrap() + 1 + rng.below(9);
        for x in starts[0]..end {
            let k = patch_at(count, x, |k| starts[k as usize]) as usize;
            let next = starts.get(k + 1).copied().unwrap_or(end);
            assert!(starts[k] <= x && x < next, "count {count}, x {x}: patch {k} covers {}..{next}", starts[k]);
        }
    }
    assert_eq!(patch_at(1, 0, |_| 0), 0);
}

/// A random polynomial or rational patch of degrees `(p, q)` with clamped uniform knots.
fn random_patch(rng: &mut Rng, p: u32, q: u32, knots: &mut Vec<f32>, cps: &mut Vec<[f32; 4]>) -> NurbsPatchGpu {
    let (size_u, size_v) = (p + 1 + rng.below(3), q + 1 + rng.below(3));
    let mut push_knots = |degree: u32, size: u32| {
        let offset = knots.len() as u32;
        let spans = size - degree;
        knots.extend((0..=degree).map(|_| 0.0));
        knots.extend((1..spans).map(|s| s as f32 / spans as f32));
        knots.extend((0..=degree).map(|_| 1.0));
        offset
    };
    let (knot_offset_u, knot_offset_v) = (push_knots(p, size_u), push_knots(q, size_v));
    let cp_offset = cps.len() as u32;
    for j in 0..size_v {
        for i in 0..size_u {
            let w = 0.5 + rng.unit();
            let z = rng.unit() - 0.5;
            cps.push([i as f32 * w, j as f32 * w, z * w, w]);
        }
    }
    NurbsPatchGpu { degree_u: p, degree_v: q, size_u, size_v, knot_offset_u, knot_offset_v, cp_offset, level: 0, vertex_offset: 0, index_offset: 0, material: 0, _pad: 0 }
}

#[test]
fn the_pass_writes_every_patch_grid_where_its_header_says() {
    let mut rng = Rng(5);
    let (mut knots, mut cps) = (vec![-7.0], vec![[9.0; 4]]); // non-zero offsets
    let (first_vertex, first_index) = (37u32, 120u32);
    let (mut vertices, mut indices) = (first_vertex, first_index);
    let mut patches = Vec::new();
    for (k, (p, q, level)) in [(1, 1, 1), (3, 3, 4), (2, 5, 7), (5, 1, 2), (2, 2, 16)].into_iter().enumerate() {
        let mut h = random_patch(&mut rng, p, q, &mut knots, &mut cps);
        h.level = level;
        h.vertex_offset = vertices;
        h.index_offset = indices;
        h.material = k as u32;
        vertices += vertex_count(level);
        indices += index_count(level);
        patches.push(h);
    }
    let params = TessellationParams {
        patch_count: patches.len() as u32,
        first_vertex,
        vertex_count: vertices - first_vertex,
        first_index,
        quad_count: (indices - first_index) / 6,
        _pad: [0; 3],
    };
    let n = vertices as usize;
    let (mut positions, mut normals, mut uvs) = (vec![f32::NAN; 3 * n], vec![f32::NAN; 3 * n], vec![f32::NAN; 2 * n]);
    let mut index_buffer = vec![u32::MAX; indices as usize];
    for i in 0..params.vertex_count {
        let (in_grid, v, vertex) = grid_vertex(&patches, &params, &knots, &cps, i);
        assert!(in_grid, "fixed levels: every slot is a whole grid");
        store_vertex(&mut positions, &mut normals, &mut uvs, v, &vertex);
    }
    for q in 0..params.quad_count {
        let (in_grid, first, six) = quad_indices(&patches, &params, q);
        assert!(in_grid);
        store_quad(&mut index_buffer, first, &six);
    }
    // What lies before the pass's ranges is untouched.
    assert!(positions[..3 * first_vertex as usize].iter().all(|x| x.is_nan()));
    assert!(index_buffer[..first_index as usize].iter().all(|&x| x == u32::MAX));
    let knot = |k: u32| knots[k as usize];
    let cp = |k: u32| Vec4::from_array(cps[k as usize]);
    for h in &patches {
        for k in 0..vertex_count(h.level) {
            let (i, j) = vertex_grid(h.level, k);
            let want = nurbs::tessellate_vertex(h, i, j, h.level, knot, cp);
            let v = (h.vertex_offset + k) as usize;
            assert_eq!(&positions[3 * v..3 * v + 3], &want.position.to_array(), "patch {}, vertex {k}", h.material);
            assert_eq!(&normals[3 * v..3 * v + 3], &want.normal.to_array(), "patch {}, vertex {k}", h.material);
            assert_eq!(&uvs[2 * v..2 * v + 2], &want.uv.to_array(), "patch {}, vertex {k}", h.material);
        }
        for quad in 0..h.level * h.level {
            let want = nurbs::tessellate_indices(h.level, quad).map(|x| x + h.vertex_offset);
            let at = (h.index_offset + 6 * quad) as usize;
            assert_eq!(index_buffer[at..at + 6], want, "patch {}, quad {quad}", h.material);
        }
        // Each patch's indices address its own vertices only.
        let range = h.vertex_offset..h.vertex_offset + vertex_count(h.level);
        let own = &index_buffer[h.index_offset as usize..(h.index_offset + index_count(h.level)) as usize];
        assert!(own.iter().all(|x| range.contains(x)), "patch {}", h.material);
    }
}

/// With adaptive levels a patch's slot holds its grid at the largest level: only the current
/// level's vertices and quads are written, the rest of the slot stays as it was.
#[test]
fn slots_larger_than_the_grid_are_written_up_to_the_level() {
    let mut rng = Rng(8);
    let (mut knots, mut cps) = (vec![], vec![]);
    let max = 8;
    let mut patches = Vec::new();
    for (k, level) in [3u32, 8, 1].into_iter().enumerate() {
        let mut h = random_patch(&mut rng, 3, 2, &mut knots, &mut cps);
        h.level = level;
        h.vertex_offset = k as u32 * vertex_count(max);
        h.index_offset = k as u32 * index_count(max);
        patches.push(h);
    }
    let params = TessellationParams { patch_count: 3, first_vertex: 0, vertex_count: 3 * vertex_count(max), first_index: 0, quad_count: 3 * max * max, _pad: [0; 3] };
    let mut written = vec![false; params.vertex_count as usize];
    for i in 0..params.vertex_count {
        let (in_grid, v, _) = grid_vertex(&patches, &params, &knots, &cps, i);
        written[v as usize] = in_grid;
    }
    let mut quads = vec![false; params.quad_count as usize];
    for q in 0..params.quad_count {
        let (in_grid, first, six) = quad_indices(&patches, &params, q);
        quads[(first / 6) as usize] = in_grid;
        if in_grid {
            let h = patches.iter().rev().find(|h| h.index_offset <= first).unwrap();
            assert!(six.iter().all(|&x| x >= h.vertex_offset && x < h.vertex_offset + vertex_count(h.level)), "quad {q}: {six:?}");
        }
    }
    for (k, h) in patches.iter().enumerate() {
        let slot = |n: u32, i: u32| k * n as usize + i as usize;
        assert!((0..vertex_count(max)).all(|i| written[slot(vertex_count(max), i)] == (i < vertex_count(h.level))), "patch {k} vertices");
        assert!((0..max * max).all(|q| quads[slot(max * max, q)] == (q < h.level * h.level)), "patch {k} quads");
    }
}

/// A polynomial patch in the kernels' layout (weights 1), clamped uniform knots, at offset 0.
fn polynomial(p: u32, q: u32, nu: u32, nv: u32, pts: &[[f32; 3]]) -> (NurbsPatchGpu, Vec<f32>, Vec<[f32; 4]>) {
    let clamped = |d: u32, n: u32| -> Vec<f32> {
        let spans = n - d;
        (0..=d).map(|_| 0.0).chain((1..spans).map(|s| s as f32 / spans as f32)).chain((0..=d).map(|_| 1.0)).collect()
    };
    let mut knots = clamped(p, nu);
    let knot_offset_v = knots.len() as u32;
    knots.extend(clamped(q, nv));
    let cps = pts.iter().map(|a| [a[0], a[1], a[2], 1.0]).collect();
    let h = NurbsPatchGpu { degree_u: p, degree_v: q, size_u: nu, size_v: nv, knot_offset_u: 0, knot_offset_v, cp_offset: 0, level: 1, vertex_offset: 0, index_offset: 0, material: 0, _pad: 0 };
    (h, knots, cps)
}

#[test]
fn second_derivative_bounds_of_known_patches() {
    let bounds = |(h, k, c): &(NurbsPatchGpu, Vec<f32>, Vec<[f32; 4]>)| {
        second_derivative_bounds(h, |i| k[i as usize], |i| Vec4::from_array(c[i as usize]))
    };
    // A plane (bilinear in a parallelogram): no curvature.
    let flat = polynomial(1, 1, 2, 2, &[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 3.0, 0.0], [2.5, 3.0, 0.0]]);
    assert_eq!(bounds(&flat), (0.0, 0.0, 0.0));
    // A twisted bilinear patch: S_uv = P11 − P10 − P01 + P00.
    let twisted = polynomial(1, 1, 2, 2, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 2.0]]);
    assert_eq!(bounds(&twisted), (0.0, 2.0, 0.0));
    // A quadratic Bézier parabola along u (extruded along v): S_uu = 2·(P0 − 2·P1 + P2).
    let parabola = polynomial(2, 1, 3, 2, &[[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 2.0, 1.0], [2.0, 0.0, 1.0]]);
    let (uu, uv, vv) = bounds(&parabola);
    assert!((uu - 8.0).abs() < 1e-5 && uv == 0.0 && vv == 0.0, "{:?}", (uu, uv, vv));
}

/// On random bicubic patches (two spans per direction) at random distances: the grid at the
/// chosen level deviates from the surface by at most the tolerance (in the estimate's pixels,
/// the deviation measured inside each triangle); a smaller tolerance or a nearer patch never
/// gets a lower level; levels stay in 1..=max.
#[test]
fn adaptive_levels_keep_the_grid_within_the_tolerance() {
    let mut rng = Rng(21);
    let mut levels = Vec::new();
    for case in 0..40 {
        let (nu, nv) = (5, 5);
        let offset = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, -3.0 * 300f32.powf(rng.unit()));
        let pts: Vec<[f32; 3]> = (0..nu * nv)
            .map(|k| (offset + Vec3::new((k % nu) as f32 * 0.5, (k / nu) as f32 * 0.5, rng.unit() * 0.6)).to_array())
            .collect();
        let (h, knots, cps) = polynomial(3, 3, nu, nv, &pts);
        let knot = |i: u32| knots[i as usize];
        let cp = |i: u32| Vec4::from_array(cps[i as usize]);
        let params = |tolerance: f32| TessLevelParams { patch_count: 1, max_level: 64, pixel_scale: 600.0, tolerance, near: 0.1, _pad: [0; 3] };
        let tolerance = 0.25 + 2.0 * rng.unit();
        let level = adaptive_level(&h, &params(tolerance), knot, cp);
        assert!((1..=64).contains(&level), "case {case}: level {level}");
        levels.push(level);
        assert!(adaptive_level(&h, &params(tolerance * 0.5), knot, cp) >= level, "case {case}: a finer tolerance lowered the level");
        let nearer = TessLevelParams { pixel_scale: 1200.0, ..params(tolerance) };
        assert!(adaptive_level(&h, &nearer, knot, cp) >= level, "case {case}: a larger projection lowered the level");
        if level == 64 {
            continue;
        }
        // Distance used by the estimate: to the control points' bounding sphere.
        let c = pts.iter().map(|p| Vec3::from_array(*p)).sum::<Vec3>() / pts.len() as f32;
        let r = pts.iter().map(|p| (Vec3::from_array(*p) - c).length()).fold(0.0, f32::max);
        let d = (c.length() - r).max(0.1);
        let at = |u: f32, v: f32| nurbs::surface_point(&h, u, v, knot, cp);
        let step = 1.0 / level as f32;
        let mut worst = 0.0f32;
        for j in 0..level {
            for i in 0..level {
                let (u, v) = (i as f32 * step, j as f32 * step);
                let corner = [at(u, v), at(u + step, v), at(u + step, v + step), at(u, v + step)];
                // Both triangles (a, b, c) and (a, c, d), sampled at barycentric points.
                for (b, cc) in [(1usize, 2usize), (2, 3)] {
                    for (l1, l2) in [(0.25f32, 0.25f32), (0.5, 0.25), (0.25, 0.5), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                        let l0 = 1.0 - l1 - l2;
                        let uv_of = |k: usize| match k {
                            0 => (u, v),
                            1 => (u + step, v),
                            2 => (u + step, v + step),
                            _ => (u, v + step),
                        };
                        let ((u0, v0), (u1, v1), (u2, v2)) = (uv_of(0), uv_of(b), uv_of(cc));
                        let s = at(l0 * u0 + l1 * u1 + l2 * u2, l0 * v0 + l1 * v1 + l2 * v2);
                        let flat = corner[0] * l0 + corner[b] * l1 + corner[cc] * l2;
                        worst = worst.max((s - flat).length());
                    }
                }
            }
        }
        let px = worst * 600.0 / d;
        assert!(px <= tolerance * 1.001, "case {case}: level {level} leaves {px} px, tolerance {tolerance}");
    }
    // The cases span levels (not all clamped to either end).
    assert!(levels.iter().any(|&l| l <= 4) && levels.iter().any(|&l| (16..64).contains(&l)), "levels {levels:?}");
}
