//! The NURBS tessellation pass's kernels: every patch's grid written into the flat vertex
//! streams and the index buffer that the raster passes pull from (`raster::gbuffer_vs`).
//!
//! Steps (one frame; `host::render::nurbs` records them):
//! 0. With adaptive levels only, [`nurbs_levels`]: one invocation per patch picks the level at
//!    which its grid stays within a pixel tolerance of the surface on screen
//!    ([`adaptive_level`]: the second-derivative control points of The NURBS Book A3.3/A3.7
//!    bound the triangles' deviation, scaled by the patch's distance), stores it in the patch's
//!    header and writes the patch's indirect draw arguments ([`draw_args`]). Each patch's slot
//!    in the streams holds its grid at the largest level; the vertex and index steps skip what
//!    lies past the current one.
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
//! homogeneous control points of each patch) and the outputs (32 B per vertex, 24 B per quad;
//! adaptive levels: 20 B of draw arguments per patch);
//! per invocation the registers of [`nurbs`] (about 250 B of basis rows and scratch).
use crate::layout::{NurbsPatchGpu, TessLevelParams, TessellationParams};
use crate::nurbs::{self, NurbsVertex};
use crate::shading::linear_index;
use spirv_std::glam::{UVec3, Vec2, Vec3, Vec4};
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;
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

/// Vertex `i` of the pass (`0 ≤ i < p.vertex_count`): whether it is a vertex of its patch's grid
/// at the patch's current level (with adaptive levels a patch's slot holds the grid of its
/// largest level; the rest of it is not drawn), its place in the vertex streams and the
/// tessellated vertex there.
#[inline]
pub fn grid_vertex(patches: &[NurbsPatchGpu], p: &TessellationParams, knots: &[f32], control_points: &[[f32; 4]], i: u32) -> (bool, u32, NurbsVertex) {
    let v = p.first_vertex + i;
    let patch = patches[patch_at(p.patch_count, v, move |k| patches[k as usize].vertex_offset) as usize];
    let level = if patch.level == 0 { 1 } else { patch.level };
    let local = v - patch.vertex_offset;
    if local >= nurbs::vertex_count(level) {
        return (false, v, NurbsVertex { position: Vec3::ZERO, normal: Vec3::Z, uv: Vec2::ZERO });
    }
    let (gi, gj) = nurbs::vertex_grid(level, local);
    let knot = move |k: u32| knots[k as usize];
    let cp = move |k: u32| Vec4::from_array(control_points[k as usize]);
    (true, v, nurbs::tessellate_vertex(&patch, gi, gj, level, knot, cp))
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

/// Quad `q` of the pass (`0 ≤ q < p.quad_count`): whether it is a quad of its patch's grid at
/// the current level (as [`grid_vertex`]), the position of its first index in the index buffer
/// and its six indices (vertex numbers of the whole streams).
#[inline]
pub fn quad_indices(patches: &[NurbsPatchGpu], p: &TessellationParams, q: u32) -> (bool, u32, [u32; 6]) {
    let first = p.first_index + 6 * q;
    let patch = patches[patch_at(p.patch_count, first, move |k| patches[k as usize].index_offset) as usize];
    let local = (first - patch.index_offset) / 6;
    let level = if patch.level == 0 { 1 } else { patch.level };
    if local >= level * level {
        return (false, first, [0; 6]);
    }
    let six = nurbs::tessellate_indices(level, local);
    let o = patch.vertex_offset;
    (true, first, [six[0] + o, six[1] + o, six[2] + o, six[3] + o, six[4] + o, six[5] + o])
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

/// `a / b`, or 0 where `b` is not positive (a repeated knot: that term of A3.3 vanishes).
#[inline]
fn over(a: f32, b: f32) -> f32 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// Bounds of a patch's second partial derivatives `(|S_uu|, |S_uv|, |S_vv|)` over its whole
/// parameter range, in position units per squared parameter unit: the largest second-derivative
/// control point of each kind (The NURBS Book A3.3 CurveDerivCpts along u and v and A3.7
/// SurfaceDerivCpts for the mixed one, `k = 2` / `k = l = 1`), which bound the derivative by the
/// convex-hull property. Computed from the Cartesian control points `(x, y, z, w)/w`: exact for
/// polynomial patches (all weights equal), an estimate for rational ones.
#[inline]
pub fn second_derivative_bounds(patch: &NurbsPatchGpu, knot: impl Fn(u32) -> f32 + Copy, cp: impl Fn(u32) -> Vec4 + Copy) -> (f32, f32, f32) {
    let (p, q) = (patch.degree_u, patch.degree_v);
    let (nu, nv) = (patch.size_u, patch.size_v);
    let ku = move |i: u32| knot(patch.knot_offset_u + i);
    let kv = move |j: u32| knot(patch.knot_offset_v + j);
    let point = move |i: u32, j: u32| {
        let h = cp(patch.cp_offset + j * nu + i);
        h.truncate() / h.w
    };
    // First-derivative control points along u (A3.3, k = 1) and along v.
    let du = move |i: u32, j: u32| (point(i + 1, j) - point(i, j)) * over(p as f32, ku(i + p + 1) - ku(i + 1));
    let dv = move |i: u32, j: u32| (point(i, j + 1) - point(i, j)) * over(q as f32, kv(j + q + 1) - kv(j + 1));
    let (mut uu, mut uv, mut vv) = (0.0f32, 0.0f32, 0.0f32);
    let mut j = 0;
    while j < nv {
        let mut i = 0;
        while i < nu {
            if p >= 2 && i + 2 < nu {
                let d2 = (du(i + 1, j) - du(i, j)) * over((p - 1) as f32, ku(i + p + 1) - ku(i + 2));
                uu = uu.max(d2.length());
            }
            if q >= 2 && j + 2 < nv {
                let d2 = (dv(i, j + 1) - dv(i, j)) * over((q - 1) as f32, kv(j + q + 1) - kv(j + 2));
                vv = vv.max(d2.length());
            }
            if i + 1 < nu && j + 1 < nv {
                let d2 = (du(i, j + 1) - du(i, j)) * over(q as f32, kv(j + q + 1) - kv(j + 1));
                uv = uv.max(d2.length());
            }
            i += 1;
        }
        j += 1;
    }
    (uu, uv, vv)
}

/// The level at which a patch's grid stays within `p.tolerance` pixels of the surface: the
/// linear interpolation over a triangle of parameter legs `h_u = D_u/L`, `h_v = D_v/L` (`D`: the
/// domain's lengths) is off by at most `(h_u²·|S_uu| + 2·h_u·h_v·|S_uv| + h_v²·|S_vv|)/8`
/// ([`second_derivative_bounds`]); a length `e` at distance `d` from the eye covers about
/// `e · p.pixel_scale / d` pixels, `d` the distance to the control points' bounding sphere (the
/// surface lies in their convex hull; at least `p.near`). So
/// `L = ⌈√(pixel_scale/d · (D_u²·|S_uu| + 2·D_u·D_v·|S_uv| + D_v²·|S_vv|) / (8·tolerance))⌉`,
/// clamped to `1..=p.max_level` (a NaN to `max_level`). Control points are camera-relative.
#[inline]
pub fn adaptive_level(patch: &NurbsPatchGpu, p: &TessLevelParams, knot: impl Fn(u32) -> f32 + Copy, cp: impl Fn(u32) -> Vec4 + Copy) -> u32 {
    let n = patch.size_u * patch.size_v;
    let mut centre = Vec3::ZERO;
    let mut k = 0;
    while k < n {
        let h = cp(patch.cp_offset + k);
        centre += h.truncate() / h.w;
        k += 1;
    }
    centre /= n as f32;
    let mut radius = 0.0f32;
    k = 0;
    while k < n {
        let h = cp(patch.cp_offset + k);
        radius = radius.max((h.truncate() / h.w - centre).length());
        k += 1;
    }
    let d = centre.length() - radius;
    let d = if d > p.near { d } else { p.near };
    let [u0, u1, v0, v1] = nurbs::domain(patch, knot);
    let (lu, lv) = (u1 - u0, v1 - v0);
    let (uu, uv, vv) = second_derivative_bounds(patch, knot, cp);
    let error_px = p.pixel_scale / d * (lu * lu * uu + 2.0 * lu * lv * uv + lv * lv * vv) / 8.0;
    let level = (error_px / p.tolerance).sqrt().ceil();
    if !(level < p.max_level as f32) {
        p.max_level
    } else if level < 1.0 {
        1
    } else {
        level as u32
    }
}

/// The `VkDrawIndexedIndirectCommand` of a patch's grid at `level`: index count, one instance,
/// its first index, vertex offset 0 (the indices address the whole streams), first instance 0.
#[inline]
pub const fn draw_args(patch: &NurbsPatchGpu, level: u32) -> [u32; 5] {
    [nurbs::index_count(level), 1, patch.index_offset, 0, 0]
}

/// The most control points of one patch [`adaptive_level`] may loop over on llvmpipe, whose loop
/// limiter stops an invocation's loops after 65 535 iterations in all and silently drops the
/// rest: its loops take `3·n + size_v ≤ 4·n` iterations for `n` control points (the host refuses
/// adaptive levels for larger patches there).
pub const MAX_ADAPTIVE_CONTROL_POINTS_LLVMPIPE: u32 = 16_000;

/// Words of one patch's indirect draw arguments.
pub const DRAW_ARGS_WORDS: u32 = 5;

/// Step 0 of adaptive tessellation: one invocation per patch sets its level in its header and
/// writes its indirect draw arguments.
#[spirv(compute(threads(64)))]
pub fn nurbs_levels(
    #[spirv(global_invocation_id)] gid: UVec3,
    #[spirv(push_constant)] p: &TessLevelParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] patches: &mut [NurbsPatchGpu],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] knots: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] control_points: &[[f32; 4]],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] args: &mut [u32],
) {
    let k = gid.x;
    if k < p.patch_count {
        let patch = patches[k as usize];
        let level = adaptive_level(&patch, p, move |i| knots[i as usize], move |i| Vec4::from_array(control_points[i as usize]));
        patches[k as usize].level = level;
        store_args(args, k, &draw_args(&patch, level));
    }
}

/// Writes patch `k`'s draw arguments (words `5k..5k + 5`).
#[inline]
pub fn store_args(args: &mut [u32], k: u32, a: &[u32; 5]) {
    let o = (DRAW_ARGS_WORDS * k) as usize;
    args[o] = a[0];
    args[o + 1] = a[1];
    args[o + 2] = a[2];
    args[o + 3] = a[3];
    args[o + 4] = a[4];
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
        let (in_grid, v, vertex) = grid_vertex(patches, p, knots, control_points, i);
        if in_grid {
            store_vertex(positions, normals, uvs, v, &vertex);
        }
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
        let (in_grid, first, six) = quad_indices(patches, p, q);
        if in_grid {
            store_quad(indices, first, &six);
        }
    }
}

#[cfg(test)]
#[path = "tessellation_tests.rs"]
mod tests;
