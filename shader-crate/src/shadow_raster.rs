//! Cube shadow maps rasterised in a compute kernel: the culled batches' triangles (`shadow_cull`)
//! written into their faces without the fixed-function rasteriser, whose throughput is a few
//! units on a compute GPU (the H100/H200 raster with 2 of their TPCs: a 1 000-caster frame spent
//! 77 of its 82 ms in the draw).
//!
//! Steps (one workgroup of [`RASTER_WORKGROUP`] invocations per cull entry `(batch, map)`, the
//! dispatch's size written by `shadow_cull::draw_args`; [`raster_entry`]):
//! 1. **Set-up**: invocation `t` takes triangle `t` of the batch: its corners relative to the
//!    light, in the frame of face `map % 6` at the side the face table gives it
//!    (`shadow_atlas`; [`face_triangle`]): culled as in the draw path
//!    (`shadow_cull::triangle_outside`) and where its plane passes through the light (seen edge on,
//!    it covers no texel centre); else its three edge planes through the light, its plane, and
//!    the texels its projection onto the face can reach ([`FaceTriangle`]'s box).
//! 2. **Small triangles** (a box of at most [`SMALL_TEXELS`] texels): the invocation tests every
//!    texel of its box itself. **Large ones** are queued in workgroup memory.
//! 3. After a barrier, the workgroup takes the queued triangles one after another, each
//!    invocation testing every [`RASTER_WORKGROUP`]-th texel of the triangle's box.
//!
//! **Coverage** ([`texel_distance`]): texel `(x, y)` of face `f` stands for the ray from the light
//! through its centre, direction `p = (u, v, 1)` in the face's frame with
//! `(u, v) = ((2x + 1) / res − 1, (2y + 1) / res − 1)`: the texel the draw path's rasteriser
//! covers with the fragment at that centre (`shadow::face_clip` and the viewport transform). The
//! ray meets the triangle where it lies on the inner side of the three planes through the light
//! and an edge (`p · (v_j × v_k)` of the sign of `det = v_0 · (v_1 × v_2)`: homogeneous
//! rasterisation, Olano and Greer 1997, which needs no clipping at the light's plane), at
//! distance `|p| · det / (p · n)` with `n` the triangle's normal: the distance the draw path
//! interpolates at the fragment. Each inside test accepts `p · e ≥ −`[`EDGE_TOLERANCE`]`·|p|·|v_j|·|v_k|`
//! (`e = v_j × v_k`), far above the rounding of the products, so a texel centre on an edge two
//! triangles share is covered by both or one of them, never by neither (no light leaks through a
//! closed mesh); the edge moves out by `10⁻⁵·|v_j|·|v_k| / |e|` radians, about 10⁻⁵ of its
//! corners' distance from the light in the scene's units (`shadow_raster_tests.rs` holds every
//! other texel to the exact ray test). Texels at most the light's
//! radius away keep the smallest distance (atomic minimum of the float bits, as the draw path).
//!
//! **Box** ([`FaceTriangle`]): where every corner lies in front of the light's plane (`w > 0`),
//! the box of the projected corners; else the box of what lies in front: corners with `w > 0`,
//! the points where edges cross the pyramid's four side planes in front of the light, and the
//! face's corners whose rays meet the triangle. Either box is clamped to the face; it only bounds
//! the coverage test.
//!
//! **Memory:** [`QUEUE_WORDS`] words of workgroup memory; no buffer of its own.
use crate::coop::{Coop, SharedU32};
use crate::shadow::{face_axes, face_entry, CASTER_WORDS, FACES};
use crate::shadow_cull::{triangle_offsets, triangle_outside, ARGS_COUNTED, BATCH_TRIANGLES, BATCH_WORDS, ENTRY_WORDS};
use glam::{Mat4, Vec3};
#[cfg(feature = "compute")]
use spirv_std::spirv;

/// Invocations per workgroup: one per triangle of a batch.
pub const RASTER_WORKGROUP: u32 = BATCH_TRIANGLES;
/// The most texels of a box one invocation tests on its own (step 2); larger boxes are shared by
/// the workgroup (step 3).
pub const SMALL_TEXELS: u32 = 32;
/// Workgroup memory: the queue's length, then its triangles.
pub const QUEUE_WORDS: usize = 1 + BATCH_TRIANGLES as usize;
/// Relative tolerance of the inside tests (module docs).
pub const EDGE_TOLERANCE: f32 = 1e-5;

/// Push constants: entries the buffer holds (each face's side and place come from the face
/// table, `shadow_atlas`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ShadowRasterParams {
    pub capacity: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<ShadowRasterParams>() == 16);

/// A triangle set up for one face (step 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceTriangle {
    /// Normals of the planes through the light and each edge, signed so that the triangle lies
    /// on their non-negative side, and each one's tolerance (per unit of `|p|`).
    pub e0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    pub tol: Vec3,
    /// The triangle's plane: `n · q = nd` (same sign as `det`).
    pub n: Vec3,
    pub nd: f32,
    /// Texels `lo..=hi` (inclusive) its projection may cover; `lo > hi` where none.
    pub lo_x: u32,
    pub lo_y: u32,
    pub hi_x: u32,
    pub hi_y: u32,
    /// The light's radius.
    pub radius: f32,
}

impl FaceTriangle {
    /// A triangle that covers nothing.
    pub const NONE: Self = Self { e0: Vec3::ZERO, e1: Vec3::ZERO, e2: Vec3::ZERO, tol: Vec3::ZERO, n: Vec3::ZERO, nd: 0.0, lo_x: 1, lo_y: 1, hi_x: 0, hi_y: 0, radius: 0.0 };

    /// Texels in its box.
    #[inline]
    pub fn texels(&self) -> u32 {
        if self.lo_x > self.hi_x || self.lo_y > self.hi_y {
            0
        } else {
            (self.hi_x - self.lo_x + 1) * (self.hi_y - self.lo_y + 1)
        }
    }

    /// Whether direction `p` (face frame) lies within the three edge planes (with tolerance).
    #[inline]
    pub fn holds(&self, p: Vec3) -> bool {
        let len = p.length();
        p.dot(self.e0) >= -self.tol.x * len && p.dot(self.e1) >= -self.tol.y * len && p.dot(self.e2) >= -self.tol.z * len
    }
}

/// Offset `d` (view space) in the frame of face `f`: `(d·right, d·up, d·forward)` = `(x, y, w)`.
#[inline]
pub fn to_face(d: Vec3, f: u32) -> Vec3 {
    let (right, up, forward) = face_axes(f);
    Vec3::new(d.dot(right), d.dot(up), d.dot(forward))
}

/// Step 1 for the triangle with corners at view-space offsets `d0, d1, d2` from a light of
/// `radius`, on face `f` of `res × res` texels.
#[inline]
pub fn face_triangle(d0: Vec3, d1: Vec3, d2: Vec3, f: u32, res: u32, radius: f32) -> FaceTriangle {
    if triangle_outside(d0, d1, d2, f, radius) {
        return FaceTriangle::NONE;
    }
    let (v0, v1, v2) = (to_face(d0, f), to_face(d1, f), to_face(d2, f));
    let n = (v1 - v0).cross(v2 - v0);
    let nd = n.dot(v0);
    let (l0, l1, l2) = (v0.length(), v1.length(), v2.length());
    // Seen edge on (its plane through the light, or no area): no texel centre's ray meets it.
    let far = if l0 > l1 { if l0 > l2 { l0 } else { l2 } } else if l1 > l2 { l1 } else { l2 };
    let faces_light = nd.abs() > EDGE_TOLERANCE * n.length() * far;
    if !faces_light {
        return FaceTriangle::NONE;
    }
    let s = if nd > 0.0 { 1.0 } else { -1.0 };
    let mut t = FaceTriangle {
        e0: v1.cross(v2) * s,
        e1: v2.cross(v0) * s,
        e2: v0.cross(v1) * s,
        tol: Vec3::new(l1 * l2, l2 * l0, l0 * l1) * EDGE_TOLERANCE,
        n: n * s,
        nd: nd * s,
        lo_x: 1,
        lo_y: 1,
        hi_x: 0,
        hi_y: 0,
        radius,
    };
    let mut b = Bounds::EMPTY;
    if v0.z > 0.0 && v1.z > 0.0 && v2.z > 0.0 {
        b.add(v0);
        b.add(v1);
        b.add(v2);
    } else {
        b.add_front(v0);
        b.add_front(v1);
        b.add_front(v2);
        b.add_crossings(v0, v1);
        b.add_crossings(v1, v2);
        b.add_crossings(v2, v0);
        b.add_face_corner(&t, -1.0, -1.0);
        b.add_face_corner(&t, 1.0, -1.0);
        b.add_face_corner(&t, -1.0, 1.0);
        b.add_face_corner(&t, 1.0, 1.0);
    }
    if b.lo_u <= b.hi_u && b.lo_v <= b.hi_v {
        let half = 0.5 * res as f32;
        // Texel x's centre is at u = (2x + 1) / res − 1: the centres within [lo, hi] (one more
        // texel on each side against rounding, clamped to the face).
        t.lo_x = texel_floor((clamp1(b.lo_u) + 1.0) * half - 1.5, res);
        t.lo_y = texel_floor((clamp1(b.lo_v) + 1.0) * half - 1.5, res);
        t.hi_x = texel_floor((clamp1(b.hi_u) + 1.0) * half + 0.5, res);
        t.hi_y = texel_floor((clamp1(b.hi_v) + 1.0) * half + 0.5, res);
    }
    t
}

/// `⌊x⌋` clamped to `0..res` (x within `[−2, res + 1]`).
#[inline]
fn texel_floor(x: f32, res: u32) -> u32 {
    if x <= 0.0 {
        0
    } else {
        let t = x as u32;
        if t >= res {
            res - 1
        } else {
            t
        }
    }
}

/// `x` clamped to `[−1, 1]` (the face).
#[inline]
fn clamp1(x: f32) -> f32 {
    if x < -1.0 {
        -1.0
    } else if x > 1.0 {
        1.0
    } else {
        x
    }
}

/// A box on the face in `(u, v)`.
struct Bounds {
    lo_u: f32,
    lo_v: f32,
    hi_u: f32,
    hi_v: f32,
}

impl Bounds {
    const EMPTY: Self = Self { lo_u: f32::MAX, lo_v: f32::MAX, hi_u: -f32::MAX, hi_v: -f32::MAX };

    /// The projection of `q` (face frame, `w > 0`), clamped to a little past the face.
    #[inline]
    fn add(&mut self, q: Vec3) {
        let (u, v) = (clamp2(q.x / q.z), clamp2(q.y / q.z));
        self.add_uv(u, v);
    }

    #[inline]
    fn add_uv(&mut self, u: f32, v: f32) {
        if u < self.lo_u {
            self.lo_u = u;
        }
        if u > self.hi_u {
            self.hi_u = u;
        }
        if v < self.lo_v {
            self.lo_v = v;
        }
        if v > self.hi_v {
            self.hi_v = v;
        }
    }

    /// `q` where it lies in front of the light's plane.
    #[inline]
    fn add_front(&mut self, q: Vec3) {
        if q.z > 0.0 {
            self.add(q);
        }
    }

    /// Where edge `a → b` crosses each side plane of the face's pyramid (`w = ±x`, `w = ±y`) in
    /// front of the light.
    #[inline]
    fn add_crossings(&mut self, a: Vec3, b: Vec3) {
        self.add_crossing(a, b, a.z - a.x, b.z - b.x);
        self.add_crossing(a, b, a.z + a.x, b.z + b.x);
        self.add_crossing(a, b, a.z - a.y, b.z - b.y);
        self.add_crossing(a, b, a.z + a.y, b.z + b.y);
    }

    #[inline]
    fn add_crossing(&mut self, a: Vec3, b: Vec3, pa: f32, pb: f32) {
        if (pa < 0.0) != (pb < 0.0) {
            let q = a + (b - a) * (pa / (pa - pb));
            self.add_front(q);
        }
    }

    /// Face corner `(u, v)` where its ray meets the triangle.
    #[inline]
    fn add_face_corner(&mut self, t: &FaceTriangle, u: f32, v: f32) {
        if t.holds(Vec3::new(u, v, 1.0)) {
            self.add_uv(u, v);
        }
    }
}

/// `x` clamped to `[−2, 2]` (past the face, finite).
#[inline]
fn clamp2(x: f32) -> f32 {
    let inside = x >= -2.0;
    if !inside {
        // Below the face, or NaN.
        -2.0
    } else if x > 2.0 {
        2.0
    } else {
        x
    }
}

/// The direction of texel `(x, y)`'s centre on a face of `res × res` texels (face frame).
#[inline]
pub fn texel_ray(x: u32, y: u32, res: u32) -> Vec3 {
    let inv = 1.0 / res as f32;
    Vec3::new((2 * x + 1) as f32 * inv - 1.0, (2 * y + 1) as f32 * inv - 1.0, 1.0)
}

/// The distance from the light to where texel `(x, y)`'s ray meets triangle `t`, or a negative
/// number where it misses it or meets it beyond the light's radius.
#[inline]
pub fn texel_distance(t: &FaceTriangle, x: u32, y: u32, res: u32) -> f32 {
    let p = texel_ray(x, y, res);
    if !t.holds(p) {
        return -1.0;
    }
    let pn = p.dot(t.n);
    let ahead = pn > 0.0;
    if !ahead {
        return -1.0;
    }
    let distance = p.length() * (t.nd / pn);
    if distance <= t.radius {
        distance
    } else {
        -1.0
    }
}

/// Where the kernel keeps a texel's smallest value.
pub trait MinStore {
    /// `word[i] = min(word[i], v)`, atomically.
    fn min_at(&mut self, i: u32, v: u32);
}

/// A storage buffer: `OpAtomicUMin` (device scope, relaxed) on the GPU, a plain minimum off it.
impl MinStore for [u32] {
    #[inline]
    fn min_at(&mut self, i: u32, v: u32) {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_u_min::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(&mut self[i as usize], v);
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            if v < self[i as usize] {
                self[i as usize] = v;
            }
        }
    }
}

/// The CPU emulation's maps, shared by the emulated invocations.
#[cfg(not(target_arch = "spirv"))]
impl MinStore for &[core::sync::atomic::AtomicU32] {
    fn min_at(&mut self, i: u32, v: u32) {
        self[i as usize].fetch_min(v, core::sync::atomic::Ordering::Relaxed);
    }
}

/// Tests texels `from, from + step, …` of triangle `t`'s box and keeps each covered one's
/// distance in the face of `res × res` texels from texel `base` of `maps`.
#[inline]
fn raster_texels<M: MinStore + ?Sized>(t: &FaceTriangle, from: u32, step: u32, base: u32, res: u32, maps: &mut M) {
    let n = t.texels();
    let w = if n == 0 { 1 } else { t.hi_x - t.lo_x + 1 };
    let mut i = from;
    while i < n {
        let (x, y) = (t.lo_x + i % w, t.lo_y + i / w);
        let distance = texel_distance(t, x, y, res);
        if distance >= 0.0 {
            maps.min_at(base + y * res + x, distance.to_bits());
        }
        i += step;
    }
}

/// Triangle `k` of batch `b` set up for `map` (`None` past the batch's triangles).
#[inline]
#[allow(clippy::too_many_arguments)]
fn entry_triangle(k: u32, b: u32, map: u32, res: u32, view: Mat4, positions: &[f32], indices: &[u32], casters: &[f32], batches: &[u32]) -> FaceTriangle {
    let w = (b * BATCH_WORDS) as usize;
    if k >= batches[w + 5] {
        return FaceTriangle::NONE;
    }
    let first = (batches[w + 4] + 3 * k) as usize;
    let (d0, d1, d2) = triangle_offsets(positions, indices, first, view, casters, map / FACES);
    face_triangle(d0, d1, d2, map % FACES, res, casters[(map / FACES * CASTER_WORDS + 3) as usize])
}

/// Steps 1–3 for entry `e` (workgroup-uniform; past the written entries the workgroup returns).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn raster_entry<C: Coop, S: SharedU32 + ?Sized, M: MinStore + ?Sized>(
    c: &C,
    shared: &mut S,
    e: u32,
    p: &ShadowRasterParams,
    view: Mat4,
    positions: &[f32],
    indices: &[u32],
    casters: &[f32],
    batches: &[u32],
    entries: &[u32],
    args: &[u32],
    slots: &[u32],
    maps: &mut M,
) {
    let written = if args[ARGS_COUNTED] < p.capacity { args[ARGS_COUNTED] } else { p.capacity };
    if e >= written {
        return;
    }
    let t = c.local_index();
    if t == 0 {
        shared.store(0, 0);
    }
    c.workgroup_barrier();
    let (b, map) = (entries[(e * ENTRY_WORDS) as usize], entries[(e * ENTRY_WORDS + 1) as usize]);
    let (base, res) = face_entry(slots, map);
    let tri = entry_triangle(t, b, map, res, view, positions, indices, casters, batches);
    let n = tri.texels();
    if n > SMALL_TEXELS {
        let slot = shared.atomic_add(0, 1);
        shared.store(1 + slot, t);
    } else if n > 0 {
        raster_texels(&tri, 0, 1, base, res, maps);
    }
    c.workgroup_barrier();
    let queued = shared.load(0);
    let mut q = 0;
    while q < queued {
        let big = entry_triangle(shared.load(1 + q), b, map, res, view, positions, indices, casters, batches);
        raster_texels(&big, t, RASTER_WORKGROUP, base, res, maps);
        q += 1;
    }
}

/// Steps 1–3: workgroup `(wg.y · num_wg.x + wg.x)` = entry.
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
#[allow(clippy::too_many_arguments)]
pub fn shadow_raster(
    #[spirv(workgroup_id)] wg: glam::UVec3,
    #[spirv(num_workgroups)] nwg: glam::UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &ShadowRasterParams,
    #[spirv(workgroup)] shared: &mut [u32; QUEUE_WORDS],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] indices: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] camera: &crate::layout::RasterCamera,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] casters: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] batches: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] args: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] slots: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] maps: &mut [u32],
) {
    let c = crate::coop::gpu::GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let e = wg.y * nwg.x + wg.x;
    raster_entry(&c, shared, e, p, Mat4::from_cols_array_2d(&camera.view), positions, indices, casters, batches, entries, args, slots, maps);
}

/// Typed handles (host side).
#[cfg(not(target_arch = "spirv"))]
pub mod handles {
    use super::ShadowRasterParams;
    use crate::kernels::Kernel;

    /// Positions, indices, camera, caster records, batches, entries, arguments, slots (the face
    /// table), the atlas.
    pub const SHADOW_RASTER: Kernel<ShadowRasterParams> = Kernel::new("shadow_raster::shadow_raster", 9, [super::RASTER_WORKGROUP, 1, 1], true);
}

#[cfg(test)]
#[path = "shadow_raster_tests.rs"]
mod tests;
