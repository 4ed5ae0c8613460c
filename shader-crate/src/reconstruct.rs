//! View-space positions from the depth buffer: the one definition that the key, bounds, shading
//! passes and the CPU references share.
//!
//! # Conventions
//!
//! * View space is right-handed: camera at the origin looking down −z, y up, x right. The
//!   *distance* of a point is `d = −z`.
//! * Pixel `(px, py)` (row 0 at the top) has its centre at `(px + ½, py + ½)`, so
//!   `ndc_x = 2(px + ½)/W − 1` and `ndc_y = 1 − 2(py + ½)/H`.
//! * The depth buffer is reversed-Z with an infinite far plane: `z_buf = near / d` (1 on the near
//!   plane, → 0 at infinity; 0 is the cleared value = background). See [`crate::raster`].
//!
//! # Distance ([`distance_from_depth`])
//!
//! `d = near / z_buf`. A float `z_buf` has relative precision `2^-24` at every magnitude (down to
//! `2^-126`), so `d` is known to ~1 ULP at any distance — the reason for reversed-Z with floats.
//! Classification is done on the bit pattern ([`is_background`]): only positive *normal finite*
//! values are geometry; `0`, negatives, denormals, `±inf` and NaN are background. Treating
//! denormals as background makes CPU and GPU agree whether or not the GPU flushes them, and bit
//! tests cannot be folded away by a compiler that assumes no NaN (Vulkan's default float mode).
//! Results are clamped to [`MAX_DISTANCE`] `= 2^64` (only reachable for `z_buf < near·2^-64`,
//! i.e. nothing a rasteriser writes for a real scene), which keeps every position finite (below).
//!
//! # Position ([`view_position`])
//!
//! The reconstruction formula `(ndc_x·tan θ·aspect·d, ndc_y·tan θ·d, −d)` (θ half the vertical field of
//! view, `aspect = W/H`) is evaluated in an equivalent, cancellation-free form. With the integer
//! numerators
//! ```text
//!   n_x = 2·px + 1 − W   ( = ndc_x · W )         n_y = H − 2·py − 1   ( = ndc_y · H )
//! ```
//! we have `ndc_x·aspect = n_x / H` and `ndc_y = n_y / H`, so
//! ```text
//!   t = tan θ · d;    x = (n_x / H) · t;    y = (n_y / H) · t;    z = −d.
//! ```
//! The numerators are exact integers (|n| ≤ 2^16, exact in f32), so the subtraction `… − 1` of
//! the textbook form — which cancels catastrophically near the screen centre and makes the error
//! *absolute* instead of relative — never happens in floating point. Pixel edges use the same
//! function with even numerators `2e − W` / `H − 2e` ([`position_from_numerators`]), which is what
//! makes the cluster boxes provably conservative ([`crate::cluster_bounds`]).
//!
//! **Error.** With `u = 2^-24`: CPU (correctly rounded `/`, `·`): each of x, y is the exact value
//! times `(1+δ)`, `|δ| ≤ (1+u)³ − 1 < 3.001u`; a Vulkan GPU (division ≤ 2.5 ULP ≤ 5u relative,
//! products correctly rounded; there is no `a·b + c` to fuse): `|δ| ≤ (1+5u)(1+u)² − 1 < 7.001u`.
//! `n/H` is 0 or ≥ 2^-15 in magnitude (never denormal); only `t` and the final product can
//! underflow, adding an absolute error `≤ |n/H|·2^-126 + 2^-126 ≤ (2^15+1)·2^-126 < 2^-110` (also
//! with flush-to-zero). `z = −d` is exact.
//!
//! **Monotonicity.** Rounding to nearest is monotone, so on one machine the computed x is
//! non-decreasing in `n_x` for fixed `d ≥ 0` (`n ↦ fl(n/H)` monotone, `· t` with `t ≥ 0`
//! monotone), and monotone in `d` for fixed `n_x` (`t = fl(tan θ·d)` non-decreasing in `d`; the
//! product is non-decreasing in `t` if `n_x ≥ 0`, non-increasing otherwise). Likewise for y.
//!
//! **Range.** For any grid [`ClusterGrid::new`] accepts (`W, H ≤ 2^15`, field of view `< π` in
//! f32, so `tan θ < 2^25`) and `d ≤ 2^64`: `|x|, |y| ≤ 2^15·2^25·2^64 = 2^104` — finite.
use crate::layout::ClusterGrid;
use glam::Vec3;

/// Largest distance [`distance_from_depth`] returns for a geometry pixel (`2^64 ≈ 1.8e19`
/// units); the far side of the last slice's cluster box.
pub const MAX_DISTANCE: f32 = 18_446_744_073_709_551_616.0;

/// Bit pattern of `f32::MIN_POSITIVE` (smallest positive normal float).
const MIN_NORMAL_BITS: u32 = 0x0080_0000;
/// Bit pattern of `+inf` (every positive finite float has smaller bits).
const INF_BITS: u32 = 0x7f80_0000;

/// Whether a depth-buffer value shows no geometry: anything but a positive normal finite float
/// (`0` = cleared, negatives, denormals, `±inf`, NaN). Integer test on the bits, so CPU and GPU
/// agree regardless of denormal flushing or NaN assumptions.
#[inline]
pub fn is_background(z_buf: f32) -> bool {
    let b = z_buf.to_bits();
    !(b >= MIN_NORMAL_BITS && b < INF_BITS)
}

/// Distance `d = −z_view` of a reversed-Z, infinite-far depth value `z_buf = near / d`.
/// Background ([`is_background`]: `z_buf ≤ 0`, NaN, denormal, inf) → `f32::INFINITY`; geometry →
/// `near / z_buf` clamped to [`MAX_DISTANCE`] (finite, `≥ 0`). CPU: correctly rounded; GPU: within
/// 2.5 ULP of it (Vulkan `OpFDiv`), so the two differ by ≤ 3 ULP ≤ `6·2^-24` relative.
#[inline]
pub fn distance_from_depth(near: f32, z_buf: f32) -> f32 {
    if is_background(z_buf) {
        return f32::INFINITY;
    }
    let d = near / z_buf;
    if d < MAX_DISTANCE {
        d
    } else {
        MAX_DISTANCE
    }
}

/// `2·px + 1 − W`: the pixel centre's `ndc_x · W` as an exact integer.
#[inline]
pub fn pixel_numerator_x(grid: &ClusterGrid, px: u32) -> i32 {
    (px.wrapping_mul(2).wrapping_add(1) as i32).wrapping_sub(grid.width as i32)
}

/// `H − 2·py − 1`: the pixel centre's `ndc_y · H` as an exact integer.
#[inline]
pub fn pixel_numerator_y(grid: &ClusterGrid, py: u32) -> i32 {
    (grid.height as i32).wrapping_sub(py.wrapping_mul(2).wrapping_add(1) as i32)
}

/// The position formula on integer NDC numerators `n_x = ndc_x·W`, `n_y = ndc_y·H` (see the module
/// docs): `t = tan θ·d; (n_x/H · t, n_y/H · t, −d)`. Pixel centres have odd numerators, pixel
/// edges even ones; both go through this one function (same operations, same order).
#[inline]
pub fn position_from_numerators(grid: &ClusterGrid, nx: i32, ny: i32, d: f32) -> Vec3 {
    let h = grid.height as f32;
    let t = grid.tan_half_fov_y * d;
    Vec3::new((nx as f32 / h) * t, (ny as f32 / h) * t, -d)
}

/// View-space position of the centre of pixel `(px, py)` at distance `d` (≥ 0, finite: call it for
/// geometry pixels only — `d = ∞` gives non-finite coordinates). Equal to
/// `(ndc_x·tan θ·aspect·d, ndc_y·tan θ·d, −d)`; the single definition used by the shading passes
/// and the CPU references.
#[inline]
pub fn view_position(grid: &ClusterGrid, px: u32, py: u32, d: f32) -> Vec3 {
    position_from_numerators(grid, pixel_numerator_x(grid, px), pixel_numerator_y(grid, py), d)
}

/// View-space position of the framebuffer point `(px + ox/16, py + oy/16)` at distance `d`: a
/// sample location in sixteenths of a pixel (`crate::msaa::sample_location`). The formula of
/// [`position_from_numerators`] on the numerators `ndc_x·W = (32·px + 2·ox − 16·W) / 16` and
/// `ndc_y·H = (16·H − 32·py − 2·oy) / 16`, exact in `f32` (integers below 2^24 divided by a power
/// of two): at `(8, 8)`, the pixel centre, the same value as [`view_position`], bit for bit.
#[inline]
pub fn sample_position(grid: &ClusterGrid, px: u32, py: u32, ox: u32, oy: u32, d: f32) -> Vec3 {
    let sixteenths = |v: i32| v as f32 * (1.0 / 16.0);
    let nx = sixteenths((px as i32).wrapping_mul(32).wrapping_add(2 * ox as i32).wrapping_sub(16 * grid.width as i32));
    let ny = sixteenths((16 * grid.height as i32).wrapping_sub((py as i32).wrapping_mul(32)).wrapping_sub(2 * oy as i32));
    let h = grid.height as f32;
    let t = grid.tan_half_fov_y * d;
    Vec3::new((nx / h) * t, (ny / h) * t, -d)
}

#[cfg(test)]
#[path = "reconstruct_tests.rs"]
mod tests;
