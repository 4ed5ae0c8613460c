//! The NURBS tessellation pass's kernels: every patch's grid written into the flat vertex
//! streams and the index buffer that the raster passes pull from (`raster::gbuffer_vs`).
//!
//! Steps (one frame; `host::render::nurbs` records them):
//! 1. [`nurbs_vertices`]: one invocation per grid vertex of every patch. The invocation finds its
//!    patch by a binary search over the headers' vertex offsets ([`patch_at`]), evaluates the
//!    surface point and its normal at the vertex's parameters ([`nurbs::tessellate_vertex`]:
//!    The NURBS Book A2.1 FindSpan, A2.2/A2.3 basis functions and derivatives, A3.6 + A4.4
//!    rational derivatives, [`nurbs`] module docs) and writes position, normal and uv at the
//!    vertex's place in the streams ([`store_vertex`]).
//! 2. [`nurbs_indices`]: one invocation per quad of every patch writes its two counter-clockwise
//!    triangles ([`nurbs::tessellate_indices`]), offset by the patch's first vertex, at the
//!    quad's place in the index buffer ([`quad_indices`]).
//!
//! Both are independent of each other; the host orders them before the raster passes' vertex
//! and index reads. The per-invocation evaluation is the compute-shader formulation of NURBS
//! tessellation: no recursion, fixed-size basis arrays, one surface point per thread.
//!
//! Memory: nothing of their own beyond the inputs (the 48 B header, the knots and the 16 B
//! homogeneous control points of each patch) and the outputs (32 B per vertex, 24 B per quad);
//! per invocation the registers of [`nurbs`] (about 250 B of basis rows and scratch).
use crate::layout::{NurbsPatchGpu, TessellationParams};
use crate::nurbs::{self, NurbsVertex};
use crate::shading::linear_index;
use spirv_std::glam::{UVec3, Vec4};
use spirv_std::spirv;

/// Search steps of [`patch_at`]: enough for 2^32 patches.
const MAX_SEARCH_STEPS: u32 = 33;

/// The last of `count` ranges, sorted by their starts `start(k)`, that starts at or before `x`
/// (0 when none does): the patch that holds element `x` when the ranges tile the elements.
#[inline]
pub fn patch_at(count: u32, x: u32, start: impl Fn(u32) -> u32) -> u32 {
    // Invariant: the answer lies in [lo, hi).
    let (mut lo, mut hi) = (0u32, count);
    let mut steps = 0;
    while hi > lo + 1 && steps < MAX_SEARCH_STEPS {
        let mid = lo + (hi - lo) / 2;
        if start(mid) <= x {
            lo = mid;
        } else {
            hi = mid;
        }
        steps += 1;
    }
    lo
}

/// Vertex `i` of the pass (`0 ≤ i < p.vertex_count`): its place in the vertex streams and the
/// tessellated vertex there.
#[inline]
pub fn grid_vertex(patches: &[NurbsPatchGpu], p: &TessellationParams, knots: &[f32], control_points: &[[f32; 4]], i: u32) -> (u32, NurbsVertex) {
    let v = p.first_vertex + i;
    let patch = patches[patch_at(p.patch_count, v, move |k| patches[k as usize].vertex_offset) as usize];
    let level = if patch.level == 0 { 1 } else { patch.level };
    let (gi, gj) = nurbs::vertex_grid(level, v - patch.vertex_offset);
    let knot = move |k: u32| knots[k as usize];
    let cp = move |k: u32| Vec4::from_array(control_points[k as usize]);
    (v, nurbs::tessellate_vertex(&patch, gi, gj, level, knot, cp))
}

/// Writes vertex `v` into the flat streams: `positions[3v..3v + 3]`, `normals[3v..3v + 3]`,
/// `uvs[2v..2v + 2]`.
#[inline]
pub fn store_vertex(positions: &mut [f32], normals: &mut [f32], uvs: &mut [f32], v: u32, vertex: &NurbsVertex) {
    let (a, b) = (3 * v as usize, 2 * v as usize);
    positions[a] = vertex.position.x;
    positions[a + 1] = vertex.position.y;
    positions[a + 2] = vertex.position.z;
    normals[a] = vertex.normal.x;
    normals[a + 1] = vertex.normal.y;
    normals[a + 2] = vertex.normal.z;
    uvs[b] = vertex.uv.x;
    uvs[b + 1] = vertex.uv.y;
}

/// Quad `q` of the pass (`0 ≤ q < p.quad_count`): the position of its first index in the index
/// buffer and its six indices (vertex numbers of the whole streams).
#[inline]
pub fn quad_indices(patches: &[NurbsPatchGpu], p: &TessellationParams, q: u32) -> (u32, [u32; 6]) {
    let first = p.first_index + 6 * q;
    let patch = patches[patch_at(p.patch_count, first, move |k| patches[k as usize].index_offset) as usize];
    let local = nurbs::tessellate_indices(patch.level, (first - patch.index_offset) / 6);
    let o = patch.vertex_offset;
    (first, [local[0] + o, local[1] + o, local[2] + o, local[3] + o, local[4] + o, local[5] + o])
}

/// Writes a quad's six indices from position `first` of the index buffer.
#[inline]
pub fn store_quad(indices: &mut [u32], first: u32, six: &[u32; 6]) {
    let f = first as usize;
    indices[f] = six[0];
    indices[f + 1] = six[1];
    indices[f + 2] = six[2];
    indices[f + 3] = six[3];
    indices[f + 4] = six[4];
    indices[f + 5] = six[5];
}

/// Step 1: one invocation per grid vertex (linear, 2D-folded dispatch).
#[spirv(compute(threads(256)))]
#[allow(clippy::too_many_arguments)]
pub fn nurbs_vertices(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &TessellationParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] patches: &[NurbsPatchGpu],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] knots: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] control_points: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] positions: &mut [f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] normals: &mut [f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] uvs: &mut [f32],
) {
    let i = linear_index(wg, nwg, local);
    if i < p.vertex_count {
        let (v, vertex) = grid_vertex(patches, p, knots, control_points, i);
        store_vertex(positions, normals, uvs, v, &vertex);
    }
}

/// Step 2: one invocation per quad (linear, 2D-folded dispatch).
#[spirv(compute(threads(256)))]
pub fn nurbs_indices(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &TessellationParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] patches: &[NurbsPatchGpu],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] indices: &mut [u32],
) {
    let q = linear_index(wg, nwg, local);
    if q < p.quad_count {
        let (first, six) = quad_indices(patches, p, q);
        store_quad(indices, first, &six);
    }
}

#[cfg(test)]
#[path = "tessellation_tests.rs"]
mod tests;
