//! Light–cluster tests beyond the sphere–AABB one, for the accuracy study ("what the culling test
//! costs"): the cluster as the frustum segment it is, tested against a light's sphere
//! 1. by its **six planes** ([`sphere_outside_planes`]; the classic test of tiled shading,
//!    Olsson & Assarsson 2011): a sphere is culled when it lies entirely outside one plane. It is
//!    conservative but keeps spheres near an edge or corner that miss the frustum;
//! 2. **exactly** ([`sphere_meets_frustum`]): the distance from the centre to the convex frustum
//!    segment is compared with the radius.
//!
//! # Geometry (same numerators and slice distances as `cluster_bounds`)
//!
//! With `d = −z` (view depth), tile columns `n_x ∈ [n_x0, n_x1]`, rows `n_y ∈ [n_y1, n_y0]` and
//! slice `[d0, d1]`, the cluster is `{(x, y, −d) : s_x0·d ≤ x ≤ s_x1·d, s_y1·d ≤ y ≤ s_y0·d,
//! d0 ≤ d ≤ d1}` with slopes `s = n·tan θ / H`: four side planes through the eye and two depth
//! planes. Its corners are `(s_x·d, s_y·d, −d)` over the 2×2×2 choices.
//!
//! # The exact test
//! Only the part of the frustum between the sphere's own depths `[−c_z − r, −c_z + r]` can meet
//! it, so `[d0, d1]` is first clipped to that slab (exact, and it keeps the last slice's
//! `d1 = 2^64` out of the arithmetic). If the centre lies inside all six planes the sphere meets
//! the cluster. Otherwise the closest point of the convex segment lies on its boundary: the
//! distance is the minimum over the faces whose plane projection of the centre falls inside the
//! face (inside the other five planes) and over the twelve edges (closest point on a segment;
//! the vertices are edge end points). Both tests compare with slack `2^-16` relative to the
//! magnitudes involved, so rounding never culls a light that touches a pixel of the cluster (the
//! sphere–AABB test pads its box for the same reason).
//!
//! Cost per light–cluster pair: planes ≈ 6 dot products; exact ≈ 6 plane tests + up to 6 face
//! checks + 12 segment distances. No memory.
use crate::cluster_bounds::slice_range;
use crate::cluster_key::ClusterGrid;
use spirv_std::glam::Vec3;
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

/// Relative slack of both tests (module docs).
pub const FRUSTUM_TEST_SLACK: f32 = 1.0 / 65_536.0;

/// Cluster `(i, j, k)` as a frustum segment: slopes and depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterFrustum {
    /// `x` slopes of the left and right side planes (`s_x0 < s_x1`).
    pub sx: [f32; 2],
    /// `y` slopes of the bottom and top side planes (`s_y1 < s_y0`, stored `[bottom, top]`).
    pub sy: [f32; 2],
    /// Depth range `[d0, d1]` (`d = −z`).
    pub d: [f32; 2],
}

/// The frustum segment of cluster `(i, j, k)` (clamped to the grid like `cluster_aabb`).
#[inline]
pub fn cluster_frustum(grid: &ClusterGrid, bounds: &[f32], i: u32, j: u32, k: u32) -> ClusterFrustum {
    let (d0, d1) = slice_range(grid, bounds, k);
    let i = if i < grid.tiles_x { i } else { grid.tiles_x - 1 };
    let j = if j < grid.tiles_y { j } else { grid.tiles_y - 1 };
    let x0 = i * grid.tile_size;
    let x1 = if x0 + grid.tile_size < grid.width { x0 + grid.tile_size } else { grid.width };
    let y0 = j * grid.tile_size;
    let y1 = if y0 + grid.tile_size < grid.height { y0 + grid.tile_size } else { grid.height };
    let (w, h) = (grid.width as i32, grid.height as i32);
    let s = grid.tan_half_fov_y / h as f32;
    let (nx0, nx1) = ((2 * x0 as i32 - w) as f32, (2 * x1 as i32 - w) as f32);
    let (ny0, ny1) = ((h - 2 * y0 as i32) as f32, (h - 2 * y1 as i32) as f32);
    ClusterFrustum { sx: [nx0 * s, nx1 * s], sy: [ny1 * s, ny0 * s], d: [d0, d1] }
}

/// Signed distances of `c` to the six planes, positive outside: left, right, bottom, top, near,
/// far (unit normals).
#[inline]
fn plane_distances(f: &ClusterFrustum, c: Vec3) -> [f32; 6] {
    let d = -c.z;
    let side = |s: f32, v: f32, outward_if_greater: bool| {
        let g = if outward_if_greater { v - s * d } else { s * d - v };
        g / (1.0 + s * s).sqrt()
    };
    [side(f.sx[0], c.x, false), side(f.sx[1], c.x, true), side(f.sy[0], c.y, false), side(f.sy[1], c.y, true), f.d[0] - d, d - f.d[1]]
}

/// Slack for a comparison involving `c` and `r`.
#[inline]
fn slack(c: Vec3, r: f32) -> f32 {
    FRUSTUM_TEST_SLACK * (c.x.abs() + c.y.abs() + c.z.abs() + r) + 1e-30
}

/// The six-plane test: `true` when the sphere lies entirely outside one plane (culled).
#[inline]
pub fn sphere_outside_planes(f: &ClusterFrustum, c: Vec3, r: f32) -> bool {
    let r = if r > 0.0 { r } else { 0.0 };
    let e = slack(c, r);
    let p = plane_distances(f, c);
    p[0] > r + e || p[1] > r + e || p[2] > r + e || p[3] > r + e || p[4] > r + e || p[5] > r + e
}

/// Squared distance from `c` to the segment `[a, b]`.
#[inline]
fn segment_distance2(c: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let l2 = ab.dot(ab);
    let t = if l2 > 0.0 { (c - a).dot(ab) / l2 } else { 0.0 };
    let t = if t < 0.0 { 0.0 } else if t > 1.0 { 1.0 } else { t };
    let q = a + ab * t - c;
    q.dot(q)
}

/// Corner `(xi, yi, di)` of a frustum segment.
#[inline]
fn corner(f: &ClusterFrustum, xi: usize, yi: usize, di: usize) -> Vec3 {
    let d = f.d[di];
    Vec3::new(f.sx[xi] * d, f.sy[yi] * d, -d)
}

/// The exact test (module docs): does the sphere `(c, r)` meet the cluster's frustum segment?
#[inline]
pub fn sphere_meets_frustum(f: &ClusterFrustum, c: Vec3, r: f32) -> bool {
    let r = if r > 0.0 { r } else { 0.0 };
    let e = slack(c, r);
    // Clip the depth range to the sphere's slab.
    let (lo, hi) = (-c.z - r - e, -c.z + r + e);
    let d0 = if f.d[0] > lo { f.d[0] } else { lo };
    let d1 = if f.d[1] < hi { f.d[1] } else { hi };
    if d0 > d1 {
        return false;
    }
    let d0 = if d0 > 0.0 { d0 } else { 0.0 };
    let g = ClusterFrustum { sx: f.sx, sy: f.sy, d: [d0, if d1 > d0 { d1 } else { d0 }] };
    let p = plane_distances(&g, c);
    if !outside_except(&p, 6, e) {
        return true; // inside every plane
    }
    let limit = (r + e) * (r + e);
    // Faces: project onto each plane the centre lies outside of; inside the face if the
    // projection lies inside the other five planes. Straight-line code, no loops: llvmpipe's
    // loop limiter counts every iteration of an invocation, and this runs once per light.
    let n = [
        Vec3::new(-1.0, 0.0, -g.sx[0]) / (1.0 + g.sx[0] * g.sx[0]).sqrt(),
        Vec3::new(1.0, 0.0, g.sx[1]) / (1.0 + g.sx[1] * g.sx[1]).sqrt(),
        Vec3::new(0.0, -1.0, -g.sy[0]) / (1.0 + g.sy[0] * g.sy[0]).sqrt(),
        Vec3::new(0.0, 1.0, g.sy[1]) / (1.0 + g.sy[1] * g.sy[1]).sqrt(),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let on_face = |face: usize| p[face] > 0.0 && p[face] * p[face] <= limit && !outside_except(&plane_distances(&g, c - n[face] * p[face]), face, e);
    if on_face(0) || on_face(1) || on_face(2) || on_face(3) || on_face(4) || on_face(5) {
        return true;
    }
    // Edges: 4 along depth, 4 on each depth face (the vertices are their end points).
    let k = |xi: usize, yi: usize, di: usize| corner(&g, xi, yi, di);
    let m = |a: f32, b: f32| if a < b { a } else { b };
    let depth_edges = m(
        m(segment_distance2(c, k(0, 0, 0), k(0, 0, 1)), segment_distance2(c, k(1, 0, 0), k(1, 0, 1))),
        m(segment_distance2(c, k(0, 1, 0), k(0, 1, 1)), segment_distance2(c, k(1, 1, 0), k(1, 1, 1))),
    );
    let face_edges = |di: usize| {
        m(
            m(segment_distance2(c, k(0, 0, di), k(1, 0, di)), segment_distance2(c, k(0, 1, di), k(1, 1, di))),
            m(segment_distance2(c, k(0, 0, di), k(0, 1, di)), segment_distance2(c, k(1, 0, di), k(1, 1, di))),
        )
    };
    m(depth_edges, m(face_edges(0), face_edges(1))) <= limit
}

/// Whether any signed distance but `skip` exceeds `e` (the point is outside that plane).
#[inline]
fn outside_except(q: &[f32; 6], skip: usize, e: f32) -> bool {
    (skip != 0 && q[0] > e) || (skip != 1 && q[1] > e) || (skip != 2 && q[2] > e) || (skip != 3 && q[3] > e) || (skip != 4 && q[4] > e) || (skip != 5 && q[5] > e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cluster_bounds::cluster_aabb;
    use crate::cluster_key::slice_bounds;
    use crate::lighting::sphere_intersects_aabb;
    use crate::reconstruct::view_position;

    /// Against dense samples of the cluster's pixel positions: no test culls a sphere containing
    /// a sample (conservative), the exact test keeps only spheres within a sample spacing of one,
    /// and exact ⊆ planes, exact ⊆ AABB.
    #[test]
    fn conservative_and_exact_against_sampled_clusters() {
        let grid = ClusterGrid::new(97, 61, 16, 0.5, 200.0, 1.0).unwrap();
        let bounds = slice_bounds(&grid);
        let mut x = 12345u32;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        let (mut kept_planes, mut kept_exact, mut kept_aabb) = (0, 0, 0);
        for (i, j, k) in [(0u32, 0u32, 0u32), (3, 2, 5), (6, 3, 12), (2, 1, grid.num_slices - 1), (1, 3, 1)] {
            let f = cluster_frustum(&grid, &bounds, i, j, k);
            let aabb = cluster_aabb(&grid, &bounds, i, j, k);
            // Samples: pixel centres of the tile at depths across the slice (the last slice up
            // to a finite depth).
            let (d0, d1) = (f.d[0], if f.d[1] > 1e4 { 400.0 } else { f.d[1] });
            let mut samples = Vec::new();
            for py in (j * 16..((j + 1) * 16).min(61)).step_by(3) {
                for px in (i * 16..((i + 1) * 16).min(97)).step_by(3) {
                    for t in 0..=8 {
                        samples.push(view_position(&grid, px, py, d0 + (d1 - d0) * t as f32 / 8.0));
                    }
                }
            }
            let centre = samples.iter().fold(Vec3::ZERO, |a, &s| a + s) / samples.len() as f32;
            let spread = samples.iter().map(|s| (*s - centre).length()).fold(0.0, f32::max);
            for _ in 0..3000 {
                let c = centre + Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * (4.0 * spread + 2.0);
                let r = rnd() * spread;
                let min_d = samples.iter().map(|s| (*s - c).length()).fold(f32::MAX, f32::min);
                let planes = !sphere_outside_planes(&f, c, r);
                let exact = sphere_meets_frustum(&f, c, r);
                let in_box = sphere_intersects_aabb(c, r, &aabb);
                if min_d < r {
                    assert!(planes && exact && in_box, "cluster {i},{j},{k}: a sphere containing a pixel sample is culled (planes {planes}, exact {exact})");
                }
                if exact {
                    assert!(planes, "exact ⊆ planes");
                    assert!(in_box, "exact ⊆ AABB");
                }
                kept_planes += usize::from(planes);
                kept_exact += usize::from(exact);
                kept_aabb += usize::from(in_box);
            }
        }
        // The tighter tests keep fewer spheres (the point of the study).
        assert!(kept_exact < kept_planes && kept_exact < kept_aabb, "exact {kept_exact}, planes {kept_planes}, aabb {kept_aabb}");
    }

    /// The exact test is exact: a sphere it keeps is within (radius + sampling spacing) of a
    /// point of the frustum, on a finely sampled cluster.
    #[test]
    fn exact_test_keeps_only_spheres_near_the_frustum() {
        let f = ClusterFrustum { sx: [-0.3, -0.1], sy: [0.05, 0.2], d: [4.0, 6.0] };
        let mut pts = Vec::new();
        let n = 24;
        for a in 0..=n {
            for b in 0..=n {
                for c in 0..=n {
                    let d = 4.0 + 2.0 * c as f32 / n as f32;
                    let x = (f.sx[0] + (f.sx[1] - f.sx[0]) * a as f32 / n as f32) * d;
                    let y = (f.sy[0] + (f.sy[1] - f.sy[0]) * b as f32 / n as f32) * d;
                    pts.push(Vec3::new(x, y, -d));
                }
            }
        }
        let spacing = 2.0 / n as f32 * 1.8;
        let mut s = 7u32;
        for _ in 0..1500 {
            let mut r = || {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 8) as f32 / (1u32 << 24) as f32
            };
            let c = Vec3::new(r() * 6.0 - 4.0, r() * 4.0 - 1.0, -(r() * 8.0 + 1.0));
            let rad = r() * 1.5;
            let min_d = pts.iter().map(|p| (*p - c).length()).fold(f32::MAX, f32::min);
            let exact = sphere_meets_frustum(&f, c, rad);
            if min_d <= rad {
                assert!(exact, "missed a sphere containing a frustum point: c={c:?} r={rad}");
            }
            if exact {
                assert!(min_d <= rad + spacing, "kept a sphere {min_d} from the frustum (r={rad})");
            }
        }
    }
}
