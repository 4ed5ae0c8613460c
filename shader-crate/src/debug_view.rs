//! Debug frames of an analytic scene: the first real picture the renderer makes, and a visual
//! check of the foundation kernels (normal encoding, cluster keys, exponential slices).
//!
//! Scene (view space, camera at the origin looking down −z, y up): a ground plane at
//! `y = −GROUND_DEPTH_BELOW_EYE` and rows of spheres receding to 300 units — a deep depth range, so
//! many exponential slices are visible. Each pixel casts one primary ray analytically (no
//! geometry buffers), then:
//! * [`VIEW_NORMALS`] — view-space normal after an encode/decode round trip at the chosen
//!   precision, shown as `0.5·n + 0.5`;
//! * [`VIEW_OCTA_ERROR`] — angular error of that round trip, relative to the precision's proven
//!   bound (black = 0, white = the bound; red would mean the bound is violated);
//! * [`VIEW_CLUSTERS`] — the cluster key hashed to a colour, lit by `n·l` so geometry stays legible;
//! * [`VIEW_SLICES`] — the depth slice `k / S` on a colour ramp.
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use crate::layout::DebugViewParams;
use crate::octahedral;
use glam::{vec3, Vec3};

// The frame's view codes (`layout::View`): one code space for every kernel.
pub const VIEW_NORMALS: u32 = crate::layout::VIEW_NORMALS;
pub const VIEW_OCTA_ERROR: u32 = crate::layout::VIEW_OCTA_ERROR;
pub const VIEW_CLUSTERS: u32 = crate::layout::VIEW_CLUSTERS;
pub const VIEW_SLICES: u32 = crate::layout::VIEW_DEPTH;

const GROUND_DEPTH_BELOW_EYE: f32 = 1.5;
const SPHERE_ROWS: u32 = 14;
const SPHERE_COLS: u32 = 7;
const BACKGROUND: u32 = 0xff_20_18_18; // ABGR in memory order RGBA

/// Packs linear [0,1] RGB into RGBA8 (R in the low byte).
#[inline]
pub fn pack_rgba8(c: Vec3) -> u32 {
    let q = |x: f32| -> u32 {
        let v = if x > 0.0 { if x < 1.0 { x } else { 1.0 } } else { 0.0 };
        (v * 255.0 + 0.5) as u32
    };
    q(c.x) | (q(c.y) << 8) | (q(c.z) << 16) | 0xff00_0000
}

/// Primary-ray hit: distance along the ray and the surface normal.
#[derive(Clone, Copy)]
pub struct Hit {
    pub t: f32,
    pub normal: Vec3,
}

/// Sphere `s` of the grid: centre and radius.
#[inline]
fn sphere(s: u32) -> (Vec3, f32) {
    let row = s / SPHERE_COLS;
    let col = s % SPHERE_COLS;
    let z = -4.0 - 1.6 * (row * row) as f32;
    let r = 0.45 + 0.12 * (row as f32);
    let x = (col as f32 - 0.5 * (SPHERE_COLS - 1) as f32) * (1.2 + 0.55 * row as f32);
    (vec3(x, -GROUND_DEPTH_BELOW_EYE + r, z), r)
}

/// Nearest intersection of the ray `t·dir` (`dir` normalised) with the scene.
pub fn trace(dir: Vec3) -> Option<Hit> {
    let mut best = Hit { t: f32::INFINITY, normal: Vec3::Y };
    if dir.y < 0.0 {
        let t = -GROUND_DEPTH_BELOW_EYE / dir.y;
        if t < 400.0 {
            best = Hit { t, normal: Vec3::Y };
        }
    }
    let mut s = 0;
    while s < SPHERE_ROWS * SPHERE_COLS {
        let (c, r) = sphere(s);
        let b = dir.dot(c);
        let disc = b * b - (c.length_squared() - r * r);
        if disc >= 0.0 {
            let t = b - disc.sqrt();
            if t > 0.0 && t < best.t {
                best = Hit { t, normal: (dir * t - c) / r };
            }
        }
        s += 1;
    }
    if best.t < f32::INFINITY {
        Some(best)
    } else {
        None
    }
}

/// View-space ray direction through the centre of pixel `(px, py)` (row 0 at the top).
#[inline]
pub fn primary_ray(p: &DebugViewParams, px: u32, py: u32) -> Vec3 {
    let g = &p.grid;
    let aspect = g.width as f32 / g.height as f32;
    let x = (2.0 * (px as f32 + 0.5) / g.width as f32 - 1.0) * g.tan_half_fov_y * aspect;
    let y = (1.0 - 2.0 * (py as f32 + 0.5) / g.height as f32) * g.tan_half_fov_y;
    vec3(x, y, -1.0).normalize()
}

/// Angle between two unit vectors, accurate for tiny angles: `2·atan2(|a−b|, |a+b|)`.
#[inline]
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    2.0 * (a - b).length().atan2((a + b).length())
}

/// Cheap integer hash (for key colours).
#[inline]
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// Blue → green → yellow → red ramp for `t ∈ [0, 1]`.
#[inline]
pub fn ramp(t: f32) -> Vec3 {
    let t = if t > 0.0 { if t < 1.0 { t } else { 1.0 } } else { 0.0 };
    let r = (1.5 - (4.0 * t - 3.0).abs()).max(0.0).min(1.0);
    let gr = (1.5 - (4.0 * t - 2.0).abs()).max(0.0).min(1.0);
    let b = (1.5 - (4.0 * t - 1.0).abs()).max(0.0).min(1.0);
    vec3(r, gr, b)
}

/// Colour of one pixel of the debug frame.
pub fn shade_pixel(p: &DebugViewParams, bounds: &[f32], px: u32, py: u32) -> u32 {
    let dir = primary_ray(p, px, py);
    let hit = match trace(dir) {
        Some(h) => h,
        None => return BACKGROUND,
    };
    let n = hit.normal.normalize();
    let view_z = dir.z * hit.t;
    let precision = octahedral::Precision::from_u32(p.precision);
    let decoded = Vec3::from_array(octahedral::decode(octahedral::encode(n.to_array(), precision), precision));
    let light = vec3(0.4, 0.8, 0.45).normalize();
    let lit = 0.25 + 0.75 * n.dot(light).max(0.0);
    let g = &p.grid;
    let rgb = match p.view {
        VIEW_NORMALS => decoded * 0.5 + Vec3::splat(0.5),
        VIEW_OCTA_ERROR => {
            let e = angle_between(n, decoded) / precision.max_angular_error_bound();
            if e > 1.0 {
                vec3(1.0, 0.0, 0.0)
            } else {
                Vec3::splat(e.sqrt())
            }
        }
        VIEW_CLUSTERS => {
            let h = hash_u32(g.key(bounds, px, py, view_z));
            let c = vec3((h & 255) as f32, ((h >> 8) & 255) as f32, ((h >> 16) & 255) as f32) / 255.0;
            (c * 0.7 + Vec3::splat(0.3)) * lit
        }
        _ => {
            let k = g.slice_of_depth(bounds, -view_z);
            ramp(k as f32 / g.num_slices as f32) * lit
        }
    };
    pack_rgba8(rgb)
}
