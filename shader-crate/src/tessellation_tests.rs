//! CPU tests of the tessellation kernels: the patch search over ranges of every length, and the
//! whole pass run invocation by invocation over several patches at different levels and non-zero
//! stream offsets, against `nurbs::tessellate_vertex` / `tessellate_indices` called per patch.
use super::*;
use crate::nurbs::{index_count, vertex_count, vertex_grid};
use crate::test_support::Rng;
use glam::Vec4;

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
        let (v, vertex) = grid_vertex(&patches, &params, &knots, &cps, i);
        store_vertex(&mut positions, &mut normals, &mut uvs, v, &vertex);
    }
    for q in 0..params.quad_count {
        let (first, six) = quad_indices(&patches, &params, q);
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
