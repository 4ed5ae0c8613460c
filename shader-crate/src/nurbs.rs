//! NURBS surfaces: rational B-spline patches evaluated and tessellated on the GPU. Pure functions,
//! f32, no recursion, no allocation, bounded loops: a compute entry calls them per vertex and per
//! quad, and the CPU tests call the very same functions.
//!
//! References: Piegl & Tiller, *The NURBS Book*, 2nd ed., Springer 1997. Implemented here:
//! * **A2.1 FindSpan** — [`find_span`]: binary search of the knot span, with the end case
//!   `u = u_{n+1}` (the last knot of the valid domain) mapped to the last non-empty span.
//! * **A2.2 BasisFuns** — the triangular Cox–de Boor table of [`basis`], without recursion.
//! * **A2.3 DersBasisFuns** for first derivatives (`n = 1`): [`basis`] keeps the degree `p − 1`
//!   row of that table and applies eq. (2.7), `N'_{i,p} = p·N_{i,p−1}/(u_{i+p} − u_i)
//!   − p·N_{i+1,p−1}/(u_{i+p+1} − u_{i+1})`.
//! * **A3.6 SurfaceDerivsAlg1** on homogeneous control points (first derivatives in u and in v,
//!   and the mixed `∂²/∂u∂v`) followed by **A4.4 RatSurfaceDerivs** (the quotient rule of eq.
//!   (4.20)): with `A(u,v) = Σ N_i N_j w_ij P_ij`, `w(u,v) = Σ N_i N_j w_ij`, the point is
//!   `S = A/w`, `S_u = (A_u − w_u·S)/w`, `S_v = (A_v − w_v·S)/w`, and
//!   `S_uv = (A_uv − w_u·S_v − w_v·S_u − w_uv·S)/w` — [`surface_derivs`]. **A4.3 SurfacePoint**
//!   is its first part.
//!
//! # Conventions
//!
//! A patch of degrees `(p, q)` has `size_u × size_v` control points (`n + 1 = size_u`), knot
//! vectors of `size_u + p + 1` and `size_v + q + 1` non-decreasing values, and is valid on the
//! domain `[u_p, u_{n+1}] × [v_q, v_{m+1}]` (`u_{n+1} = u_{m_u − p}` with `m_u` the last knot
//! index). Clamped or not, only that domain is evaluated: parameters outside are clamped to it.
//! Control point `(i, j)` (i along u) is element `cp_offset + j·size_u + i` of the control-point
//! buffer: u runs fastest.
//!
//! **Weights are premultiplied**: a control point is stored homogeneous, `(w·x, w·y, w·z, w)`
//! (16 B), which is what A3.6 sums — the kernel never multiplies by the weight. The host model
//! (`host::scene::nurbs`) keeps Cartesian points and weights and converts on upload. Weights are
//! positive (the host refuses others), so `w(u,v) > 0` on the whole domain.
//!
//! # Normals, and where `S_u × S_v` degenerates
//!
//! The normal is `normalize(S_u × S_v)`, pointing to the side from which increasing u then v turn
//! counter-clockwise. Where a whole edge of control points collapses to one point (the poles of
//! the sphere, a cone's apex) one partial derivative vanishes there. The rule ([`surface_normal`]):
//! 1. `S_u` is *vanished* when `|S_u| ≤ ε·|S_v|` (ε = [`DEGENERATE_EPS`]) or when it is under
//!    the f32 noise of a zero, [`DEGENERATE_NOISE`]` · |S|` (both scaled to the whole domain),
//!    and likewise `S_v`;
//! 2. along a collapsed edge `v = v_0` (`S_u ≡ 0` there) `S_u(u, v_0 + t) = t·S_uv + O(t²)`, so
//!    the normals next to the edge tend to `±S_uv × S_v`: a vanished `S_u` is replaced by `S_uv`,
//!    negated when the point lies in the upper half of the v domain (the neighbours are then at
//!    `v − t`), and a vanished `S_v` by `±S_uv` the same way in u. This is the exact limit (the
//!    normal that the surrounding vertices converge to), computed without cancellation: `S_uv`
//!    comes from A4.4 with `k = 2` in the same pass over the control points. For the sphere's
//!    poles it gives `∓y` exactly;
//! 3. if `S_u × S_v` is still degenerate (`|S_u × S_v| ≤ ε·|S_u|·|S_v|`: parallel derivatives, a
//!    cusp, or `S_uv` vanishing too), the whole normal is taken one step inward in both
//!    directions, at `(u ± δ, v ± δ)` toward the middle of the domain, δ = [`INWARD_STEP`] × the
//!    domain's length;
//! 4. if that degenerates too (a patch collapsed to a curve or a point has no normal), `+z`:
//!    finite and unit, never a NaN in the G-buffer.
//!
//! # Tessellation
//!
//! A patch at level `L` is a uniform `(L + 1) × (L + 1)` grid of vertices over its valid domain
//! ([`tessellate_vertex`]; the last row and column use the domain end exactly) and `L²` quads of
//! two counter-clockwise triangles ([`tessellate_indices`]): with u to the right and v up, seen
//! from the side the normal points to, so the triangle winding and the normals agree.
//!
//! The tessellation pass ([`crate::tessellation`], recorded by `host::render::nurbs`): one
//! compute dispatch over every patch's vertices writes positions, normals and uvs into the flat
//! `f32` vertex streams the G-buffer pass pulls from (`raster::gbuffer_vs`), at
//! `NurbsPatchGpu::vertex_offset`, and one over every patch's quads writes the index buffer at
//! `index_offset` (indices plus the patch's `vertex_offset`); the raster passes then draw the
//! patches as ordinary meshes.
//!
//! # Memory
//!
//! Per patch: the 48 B [`NurbsPatchGpu`] header, `4·(size_u + p + 1 + size_v + q + 1)` B of
//! knots and `16·size_u·size_v` B of control points (the sphere: 48 + 4·20 + 16·45 = 848 B).
//! Per vertex written: 32 B (position 12, normal 12, uv 8); per quad: 24 B of indices. Per
//! invocation, in registers or function memory: two basis rows and two derivative rows of
//! [`MAX_ORDER`] f32 (96 B), the Cox–de Boor scratch (`left`, `right` and the degree `p − 1`
//! row: 72 B per direction).
pub use crate::layout::NurbsPatchGpu;
use glam::{Vec2, Vec3, Vec4};

/// Largest degree the kernels evaluate (quintic); the host refuses higher ones.
pub const MAX_DEGREE: u32 = 5;
/// Basis functions non-zero on one span: `p + 1` at most.
pub const MAX_ORDER: usize = MAX_DEGREE as usize + 1;
/// Relative size under which a partial derivative or the cross product counts as vanished.
pub const DEGENERATE_EPS: f32 = 1e-4;
/// Relative f32 rounding noise of a derivative that vanishes exactly: under `DEGENERATE_NOISE ·
/// |S|` (derivatives scaled to the whole domain) it counts as zero.
pub const DEGENERATE_NOISE: f32 = 1e-5;
/// Inward step of the degenerate-normal rule, as a fraction of the domain's length.
pub const INWARD_STEP: f32 = 1.0 / 1024.0;
/// Iterations [`find_span`]'s binary search may take: enough for 2^32 knots.
const MAX_SEARCH_STEPS: u32 = 33;

/// Basis functions `N_{span−p+r, p}(u)` and their first derivatives, `r = 0..=p` (zero past `p`).
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug, PartialEq))]
pub struct Basis {
    pub n: [f32; MAX_ORDER],
    pub d: [f32; MAX_ORDER],
}

/// A point of a surface, its first partial derivatives and the mixed second derivative
/// (Cartesian, after the quotient rule).
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug, PartialEq))]
pub struct SurfacePoint {
    pub s: Vec3,
    pub su: Vec3,
    pub sv: Vec3,
    /// `S_uv`: what the normal's limit at a collapsed edge needs (module docs).
    pub suv: Vec3,
}

/// A tessellated vertex: position, unit normal, and uv in [0, 1]² over the valid domain (u along
/// the first texture axis; `(0, 0)` at `(u_p, v_q)`).
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug, PartialEq))]
pub struct NurbsVertex {
    pub position: Vec3,
    pub normal: Vec3,
    pub uv: Vec2,
}

/// A2.1 FindSpan: the span index `s` in `[p, n]` with `u_s ≤ u < u_{s+1}` for the knot vector
/// `knot(0..=n+p+1)` of `n + 1 = size` control points. At the domain's ends, where the half-open
/// rule finds no span or an empty one, it returns the first (`u ≤ u_p`, and NaN) or the last
/// (`u ≥ u_{n+1}`) span of non-zero length: repeated knots are skipped, so the span found is
/// never empty when the domain has non-zero length.
#[inline]
pub fn find_span(size: u32, p: u32, u: f32, knot: impl Fn(u32) -> f32) -> u32 {
    let n = size - 1;
    if !(u > knot(p)) {
        let mut s = p;
        let mut steps = 0;
        while s < n && !(knot(s + 1) > knot(p)) && steps < MAX_SEARCH_STEPS * 8 {
            s += 1;
            steps += 1;
        }
        return s;
    }
    if !(u < knot(n + 1)) {
        // The end case: clamped vectors repeat u_{n+1} up to the last knot.
        let mut s = n;
        let mut steps = 0;
        while s > p && !(knot(s) < knot(n + 1)) && steps < MAX_SEARCH_STEPS * 8 {
            s -= 1;
            steps += 1;
        }
        return s;
    }
    // Invariant: knot(low) ≤ u < knot(high).
    let mut low = p;
    let mut high = n + 1;
    let mut steps = 0;
    while high - low > 1 && steps < MAX_SEARCH_STEPS {
        let mid = (low + high) / 2;
        if u < knot(mid) {
            high = mid;
        } else {
            low = mid;
        }
        steps += 1;
    }
    low
}

/// A2.2 BasisFuns and A2.3 DersBasisFuns (first derivatives): the `p + 1` basis functions of
/// degree `p` non-zero on span `span` at `u`, and their derivatives. Needs `u_span < u_{span+1}`
/// (what [`find_span`] returns on a domain of non-zero length); then no denominator is zero.
#[inline]
pub fn basis(span: u32, u: f32, p: u32, knot: impl Fn(u32) -> f32) -> Basis {
    let mut n = [0.0f32; MAX_ORDER];
    let mut low = [0.0f32; MAX_ORDER]; // the degree p − 1 row
    let mut left = [0.0f32; MAX_ORDER];
    let mut right = [0.0f32; MAX_ORDER];
    n[0] = 1.0;
    low[0] = 1.0;
    let mut j = 1;
    while j <= p && j <= MAX_DEGREE {
        left[j as usize] = u - knot(span + 1 - j);
        right[j as usize] = knot(span + j) - u;
        let mut saved = 0.0;
        let mut r = 0;
        while r < j {
            let temp = n[r as usize] / (right[(r + 1) as usize] + left[(j - r) as usize]);
            n[r as usize] = saved + right[(r + 1) as usize] * temp;
            saved = left[(j - r) as usize] * temp;
            r += 1;
        }
        n[j as usize] = saved;
        if j + 1 == p {
            low = n;
        }
        j += 1;
    }
    // Eq. (2.7) on the degree p − 1 row: N_{span−p+r, p−1} is low[r − 1] (zero outside 1..=p).
    let mut d = [0.0f32; MAX_ORDER];
    if p > 0 {
        let pf = p as f32;
        let mut r = 0;
        while r <= p && r <= MAX_DEGREE {
            let i = span + r - p; // the function's index
            let mut v = 0.0;
            if r >= 1 {
                v += pf * low[(r - 1) as usize] / (knot(i + p) - knot(i));
            }
            if r < p {
                v -= pf * low[r as usize] / (knot(i + p + 1) - knot(i + 1));
            }
            d[r as usize] = v;
            r += 1;
        }
    }
    Basis { n, d }
}

/// The patch's valid parameter domain: `(u_p, u_{n+1}, v_q, v_{m+1})`.
#[inline]
pub fn domain(patch: &NurbsPatchGpu, knot: impl Fn(u32) -> f32) -> [f32; 4] {
    [
        knot(patch.knot_offset_u + patch.degree_u),
        knot(patch.knot_offset_u + patch.size_u),
        knot(patch.knot_offset_v + patch.degree_v),
        knot(patch.knot_offset_v + patch.size_v),
    ]
}

/// A3.6 (order 1) on homogeneous control points, then A4.4 (k = 1): the point and its first
/// partial derivatives at `(u, v)`, clamped to the valid domain. `knot(i)` reads the knot buffer,
/// `cp(i)` the control-point buffer (`(w·x, w·y, w·z, w)`, module docs).
#[inline]
pub fn surface_derivs(patch: &NurbsPatchGpu, u: f32, v: f32, knot: impl Fn(u32) -> f32, cp: impl Fn(u32) -> Vec4) -> SurfacePoint {
    let (p, q) = (patch.degree_u, patch.degree_v);
    let ku = |i: u32| knot(patch.knot_offset_u + i);
    let kv = |i: u32| knot(patch.knot_offset_v + i);
    let su = find_span(patch.size_u, p, u, ku);
    let sv = find_span(patch.size_v, q, v, kv);
    let u = clamp_to(u, ku(p), ku(patch.size_u));
    let v = clamp_to(v, kv(q), kv(patch.size_v));
    let bu = basis(su, u, p, ku);
    let bv = basis(sv, v, q, kv);
    let mut a = Vec4::ZERO;
    let mut au = Vec4::ZERO;
    let mut av = Vec4::ZERO;
    let mut auv = Vec4::ZERO;
    let mut l = 0;
    while l <= q && l <= MAX_DEGREE {
        let row = patch.cp_offset + (sv - q + l) * patch.size_u + (su - p);
        let mut t = Vec4::ZERO;
        let mut tu = Vec4::ZERO;
        let mut k = 0;
        while k <= p && k <= MAX_DEGREE {
            let pw = cp(row + k);
            t += pw * bu.n[k as usize];
            tu += pw * bu.d[k as usize];
            k += 1;
        }
        a += t * bv.n[l as usize];
        au += tu * bv.n[l as usize];
        av += t * bv.d[l as usize];
        auv += tu * bv.d[l as usize];
        l += 1;
    }
    let inv_w = 1.0 / a.w;
    let s = a.truncate() * inv_w;
    let su = (au.truncate() - s * au.w) * inv_w;
    let sv = (av.truncate() - s * av.w) * inv_w;
    // A4.4 for k = 2, the mixed term: S_uv = (A_uv − w_u·S_v − w_v·S_u − w_uv·S) / w.
    let suv = (auv.truncate() - sv * au.w - su * av.w - s * auv.w) * inv_w;
    SurfacePoint { s, su, sv, suv }
}

/// A4.3 SurfacePoint: the Cartesian point at `(u, v)`.
#[inline]
pub fn surface_point(patch: &NurbsPatchGpu, u: f32, v: f32, knot: impl Fn(u32) -> f32, cp: impl Fn(u32) -> Vec4) -> Vec3 {
    surface_derivs(patch, u, v, knot, cp).s
}

/// `x` clamped to `[lo, hi]`, NaN → `lo`.
#[inline]
fn clamp_to(x: f32, lo: f32, hi: f32) -> f32 {
    if !(x > lo) {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `x` moved by `step` toward the middle of `[lo, hi]`.
#[inline]
fn inward(x: f32, lo: f32, hi: f32, step: f32) -> f32 {
    if x < 0.5 * (lo + hi) {
        x + step
    } else {
        x - step
    }
}

/// Whether `a` vanishes next to `b`: `|a| ≤ max(ε·|b|, floor)` (both zero counts as vanished).
#[inline]
fn vanished(a: Vec3, b: Vec3, floor: f32) -> bool {
    let a2 = a.length_squared();
    a2 <= DEGENERATE_EPS * DEGENERATE_EPS * b.length_squared() || a2 <= floor * floor
}

/// Whether `a × b` gives no direction: a factor at or under `floor`, or `|a × b| ≤ ε·|a|·|b|`
/// (parallel factors).
#[inline]
fn degenerate_cross(a: Vec3, b: Vec3, floor: f32) -> bool {
    let c2 = a.cross(b).length_squared();
    let f2 = floor * floor;
    !(a.length_squared() > f2) || !(b.length_squared() > f2) || !(c2 > DEGENERATE_EPS * DEGENERATE_EPS * a.length_squared() * b.length_squared()) || !(c2 > 0.0)
}

/// The unit normal at an evaluated point `d` of `(u, v)`, with the degenerate-normal rule of the
/// module docs (the mixed derivative's limit, one step inward, then `+z`). The tests run in
/// position units: derivatives times the domain's lengths (which does not turn the normal),
/// against `floor` = [`DEGENERATE_NOISE`]` · |S|`, the f32 rounding noise of a vanished one.
#[inline]
pub fn surface_normal(patch: &NurbsPatchGpu, u: f32, v: f32, d: &SurfacePoint, knot: impl Fn(u32) -> f32 + Copy, cp: impl Fn(u32) -> Vec4 + Copy) -> Vec3 {
    let [u0, u1, v0, v1] = domain(patch, knot);
    let (u, v) = (clamp_to(u, u0, u1), clamp_to(v, v0, v1));
    let (lu, lv) = (u1 - u0, v1 - v0);
    let floor = DEGENERATE_NOISE * d.s.length();
    let mut su = d.su * lu;
    let mut sv = d.sv * lv;
    let suv = d.suv * (lu * lv);
    // Inward in v from the lower half is +v: S_u(u, v + t) ≈ t·S_uv there, −t·S_uv from the upper.
    if vanished(su, sv, floor) {
        su = if v < 0.5 * (v0 + v1) { suv } else { -suv };
    } else if vanished(sv, su, floor) {
        sv = if u < 0.5 * (u0 + u1) { suv } else { -suv };
    }
    if degenerate_cross(su, sv, floor) {
        let e = surface_derivs(patch, inward(u, u0, u1, INWARD_STEP * lu), inward(v, v0, v1, INWARD_STEP * lv), knot, cp);
        su = e.su * lu;
        sv = e.sv * lv;
        if degenerate_cross(su, sv, floor) {
            return Vec3::Z;
        }
    }
    su.cross(sv).normalize()
}

/// Parameter of grid line `i` of `level` over `[lo, hi]`; the last line is `hi` exactly.
#[inline]
pub fn grid_parameter(i: u32, level: u32, lo: f32, hi: f32) -> f32 {
    if i >= level {
        hi
    } else {
        lo + (hi - lo) * (i as f32 / level as f32)
    }
}

/// Vertices of a patch tessellated at `level` (≥ 1): `(level + 1)²`.
#[inline]
pub const fn vertex_count(level: u32) -> u32 {
    (level + 1) * (level + 1)
}

/// Indices of a patch tessellated at `level`: six per quad, `6·level²`.
#[inline]
pub const fn index_count(level: u32) -> u32 {
    6 * level * level
}

/// Grid coordinates `(i, j)` of the patch's vertex `k` (`k = j·(level + 1) + i`, i along u).
#[inline]
pub const fn vertex_grid(level: u32, k: u32) -> (u32, u32) {
    (k % (level + 1), k / (level + 1))
}

/// Grid vertex `(i, j)`, `0 ≤ i, j ≤ level`, of a patch tessellated at `level`: uniform in the
/// parameters over the valid domain. Called once per vertex by the tessellation pass.
#[inline]
pub fn tessellate_vertex(patch: &NurbsPatchGpu, i: u32, j: u32, level: u32, knot: impl Fn(u32) -> f32 + Copy, cp: impl Fn(u32) -> Vec4 + Copy) -> NurbsVertex {
    let level = if level == 0 { 1 } else { level };
    let [u0, u1, v0, v1] = domain(patch, knot);
    let u = grid_parameter(i, level, u0, u1);
    let v = grid_parameter(j, level, v0, v1);
    let d = surface_derivs(patch, u, v, knot, cp);
    let normal = surface_normal(patch, u, v, &d, knot, cp);
    let inv = 1.0 / level as f32;
    let uv = Vec2::new(if i >= level { 1.0 } else { i as f32 * inv }, if j >= level { 1.0 } else { j as f32 * inv });
    NurbsVertex { position: d.s, normal, uv }
}

/// The two counter-clockwise triangles of quad `quad` (`quad = j·level + i`) of a patch at
/// `level`, as vertex numbers of that patch (`j·(level + 1) + i`): `(a, b, c)` and `(a, c, d)`
/// with `a = (i, j)`, `b = (i+1, j)`, `c = (i+1, j+1)`, `d = (i, j+1)`.
#[inline]
pub fn tessellate_indices(level: u32, quad: u32) -> [u32; 6] {
    let level = if level == 0 { 1 } else { level };
    let (i, j) = (quad % level, quad / level);
    let a = j * (level + 1) + i;
    let b = a + 1;
    let d = a + level + 1;
    let c = d + 1;
    [a, b, c, a, c, d]
}

#[cfg(test)]
#[path = "nurbs_tests.rs"]
mod tests;
