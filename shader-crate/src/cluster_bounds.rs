//! View-space bounding boxes of clusters for light assignment — the *implicit* bounds that the
//! cluster key defines (tile × slice), as opposed to explicit bounds reduced from the samples
//! (Olsson, Billeter, Assarsson 2012, "Clustered Deferred and Forward Shading") — provably
//! containing every position [`crate::reconstruct::view_position`] can give a pixel of the
//! cluster.
//!
//! # The box
//!
//! Cluster `(i, j, k)` is the part of tile `(i, j)`'s frustum between the distances of slice `k`.
//! The tile covers pixel columns `x0 = i·T … x1 = min((i+1)·T, W)` and rows `y0 = j·T …
//! y1 = min((j+1)·T, H)` (`T` = tile size; the last column/row of tiles may be partial). Its edges
//! have the integer NDC numerators (see [`crate::reconstruct`])
//! ```text
//!   n_x ∈ {2·x0 − W, 2·x1 − W},      n_y ∈ {H − 2·y0, H − 2·y1}
//! ```
//! and the slice spans distances `[d0, d1]` ([`slice_range`]). The box is the AABB of the 8
//! corners `position_from_numerators(n_x, n_y, d)` — the same function, with the same operations in
//! the same order, as the pixel positions. The tile's side planes are not axis-aligned (a corner
//! tile's frustum widens with `d`), hence min/max over all corners; x depends only on `(n_x, d)`
//! and y only on `(n_y, d)`, so the 8 corners have 4 distinct x and 4 distinct y values.
//!
//! # First and last slice (documented clamping of `slice_of_depth`)
//!
//! [`ClusterGrid::slice_of_depth`] puts `d ≤ near` into slice 0 and `d ≥ bounds[S−1]` (also
//! beyond `far`: the far plane is at infinity) into slice `S − 1`. So slice 0's box starts at
//! `d0 = 0` (points in front of the near plane are clipped by the rasteriser and never occur, but
//! the box does not rely on it; the cost is that slice-0 boxes reach the eye, which only matters
//! for lights within about `bounds[1]` of the camera), and the last slice's box ends at
//! `d1 = MAX_DISTANCE = 2^64`, the largest distance [`crate::reconstruct::distance_from_depth`]
//! returns. Every bound is clamped to `≤ 2^64`, which keeps all corner coordinates below `2^104`
//! (finite: no `inf`/NaN ever reaches the sphere test, nor `0·∞` on the optical axis as a far
//! distance of `f32::MAX` or ∞ would give).
//!
//! # Why the box is conservative
//!
//! Claim: for every pixel centre `(px, py)` of the tile (inside the image) and every distance
//! `d ∈ [0, 2^64]` with `slice_of_depth(bounds, d) == k`, `view_position(px, py, d)` lies in
//! [`cluster_aabb`]`(i, j, k)` — even when the box is computed on the GPU and the point on the CPU,
//! or vice versa, and even for `d` up to `η = 2^-20` (relative) outside the slice.
//!
//! 1. **Domain.** `slice_of_depth` compares `d` exactly against the same `bounds` table, so
//!    `d ∈ [d0, d1]` (with the clamps above). Pixel centres have numerators
//!    `n_x = 2px + 1 − W ∈ [2·x0 + 1 − W, 2·x1 − 1 − W] ⊂ [2·x0 − W, 2·x1 − W]`; likewise `n_y`.
//! 2. **Exact arithmetic.** `X(n, d) = n·d·tanθ/H` is bilinear in `(n, d)`, so over the rectangle
//!    `[n_lo, n_hi] × [d0, d1]` its minimum `m` and maximum `M` are attained at the corners;
//!    `Z = −d` lies in `[−d1, −d0]`. With the tolerance `d ∈ [d0(1−η), d1(1+η)]` the corner
//!    values scale by `1 ± η`, so `X ≥ m − η|m|` and `X ≤ M + η|M|` (`v ↦ v ∓ η|v|` is increasing).
//! 3. **Same machine, no padding needed.** Rounding to nearest is monotone, and the computed
//!    coordinate is monotone in `n` and in `d` (see `reconstruct`, "Monotonicity"); the pixel and
//!    the corners use the same function, so the computed pixel coordinate lies between the
//!    computed corner coordinates *exactly*. The tests check this unpadded containment on the CPU.
//! 4. **Across machines / compilations**, monotonicity is not guaranteed (GPU division is not
//!    correctly rounded, and the box kernel and the shading kernel are compiled separately). Then
//!    only the error bounds hold: with `u = 2^-24`, each computed coordinate is the exact one times
//!    `(1+δ)`, `|δ| ≤ ε_g = 7.001u` (GPU; CPU `3.001u`), plus an absolute underflow term
//!    `α < 2^-110` (`reconstruct`, "Error"). For the lower face (the upper is symmetric):
//!    the point satisfies `x̂ ≥ f(m) − α` with `f(v) = v − (ε_g + η + ε_g·η)|v|`, and the computed
//!    minimum corner satisfies `m̂ ≤ m + ε_g|m| + α`. The padded face is
//!    `fl(m̂ − fl(ρ|m̂| + τ))`; its three roundings cost `≤ 2u` relative (`ρ` is a power of two, so
//!    `ρ|m̂|` is exact unless it underflows, which `τ` absorbs). It is below `f(m) − α` as soon as
//!    ```text
//!      ρ ≥ ε_g + ε_g + η + 2u + O(u²) = (7.001 + 7.001 + 16 + 2)u ≈ 32.01u,   τ ≥ 2α + …
//!    ```
//!    (for `m ≥ 0`: `m̂(1−ρ)(1+u) ≤ m(1+ε_g)(1−ρ)(1+u) ≤ m(1−ε_g−η)` by the above; for `m < 0`:
//!    `−|m̂|(1+ρ)(1−u) ≤ −|m|(1−ε_g)(1+ρ)(1−u) ≤ −|m|(1+ε_g+η)` likewise; `m = 0` is covered by
//!    `τ`). We pad by [`BOX_REL_PAD`] `ρ = 2^-18 = 64u` (twice the requirement) plus
//!    [`BOX_ABS_PAD`] `τ = 2^-100` (≥ 2^9·2α); both are negligible for culling (`3.8e-6` relative).
//!    `η = 2^-20 = 16u` covers the ≤ 3-ULP (`6u`) CPU/GPU difference of `distance_from_depth`, so
//!    even a pixel that the two machines put in adjacent slices lies in both slices' boxes.
//! 5. z: `−d` and the bounds are exact, so the z faces contain the point by step 1; they are padded
//!    the same way, which provides the `η` tolerance.
//!
//! Adjacent clusters share their edge numerators / slice bounds, so their (unpadded) boxes touch or
//! overlap: the boxes leave no gaps.
//!
//! # Cost
//!
//! A box is 32 B ([`ClusterAabb`]) per cluster. The assignment kernels recompute it from the key,
//! the grid and the `bounds` table (4·(S+1) B) instead of storing it; storing boxes would cost
//! 32 B per unique cluster (e.g. 1920×1080, 32 px tiles, 276 slices: at most
//! `min(60·34·276, pixels) = 563 040` clusters → ≤ 18 MB; typical frames touch a few 10⁴ → ~1 MB).
use crate::layout::{ClusterAabb, ClusterGrid};
use crate::reconstruct::{position_from_numerators, MAX_DISTANCE};

/// Relative padding of every box face: `2^-18` (see the module docs, step 4).
pub const BOX_REL_PAD: f32 = 1.0 / 262_144.0;
/// Absolute padding of every box face: `2^-100` (covers underflow; see step 4).
pub const BOX_ABS_PAD: f32 = 7.888_609e-31;

/// Distances `[d0, d1]` covered by slice `k`'s box (`k` clamped to the grid): `[bounds[k],
/// bounds[k+1]]`, except that slice 0 starts at 0 and the last slice ends at
/// [`MAX_DISTANCE`]; both clamped to `≤ MAX_DISTANCE`.
#[inline]
pub fn slice_range(grid: &ClusterGrid, bounds: &[f32], k: u32) -> (f32, f32) {
    let last = if grid.num_slices > 0 { grid.num_slices - 1 } else { 0 };
    let k = if k < last { k } else { last };
    let d0 = if k == 0 { 0.0 } else { bounds[k as usize] };
    let d1 = if k == last { MAX_DISTANCE } else { bounds[k as usize + 1] };
    (min_f(d0, MAX_DISTANCE), min_f(d1, MAX_DISTANCE))
}

#[inline]
fn min_f(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

#[inline]
fn max_f(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[inline]
fn min4(a: f32, b: f32, c: f32, d: f32) -> f32 {
    min_f(min_f(a, b), min_f(c, d))
}

#[inline]
fn max4(a: f32, b: f32, c: f32, d: f32) -> f32 {
    max_f(max_f(a, b), max_f(c, d))
}

/// The unpadded box: exact min/max of the 8 computed corners (module docs, "The box").
/// `i`, `j`, `k` are clamped to the grid.
#[inline]
pub fn cluster_corner_bounds(grid: &ClusterGrid, bounds: &[f32], i: u32, j: u32, k: u32) -> ([f32; 3], [f32; 3]) {
    let (d0, d1) = slice_range(grid, bounds, k);
    let i = if i < grid.tiles_x { i } else { grid.tiles_x - 1 };
    let j = if j < grid.tiles_y { j } else { grid.tiles_y - 1 };
    let x0 = i * grid.tile_size;
    let x1 = if x0 + grid.tile_size < grid.width { x0 + grid.tile_size } else { grid.width };
    let y0 = j * grid.tile_size;
    let y1 = if y0 + grid.tile_size < grid.height { y0 + grid.tile_size } else { grid.height };
    let (w, h) = (grid.width as i32, grid.height as i32);
    // Edge numerators: n_x = 2e − W (left, right), n_y = H − 2e (top row edge, bottom row edge).
    let (nx0, nx1) = (2 * x0 as i32 - w, 2 * x1 as i32 - w);
    let (ny0, ny1) = (h - 2 * y0 as i32, h - 2 * y1 as i32);
    // Corners (nx, ny, d): x depends on (nx, d) only, y on (ny, d) only.
    let a = position_from_numerators(grid, nx0, ny0, d0);
    let b = position_from_numerators(grid, nx1, ny1, d0);
    let c = position_from_numerators(grid, nx0, ny0, d1);
    let e = position_from_numerators(grid, nx1, ny1, d1);
    (
        [min4(a.x, b.x, c.x, e.x), min4(a.y, b.y, c.y, e.y), min_f(-d0, -d1)],
        [max4(a.x, b.x, c.x, e.x), max4(a.y, b.y, c.y, e.y), max_f(-d0, -d1)],
    )
}

/// Lower face moved outwards by `ρ|v| + τ`.
#[inline]
fn pad_down(v: f32) -> f32 {
    v - (BOX_REL_PAD * v.abs() + BOX_ABS_PAD)
}

/// Upper face moved outwards by `ρ|v| + τ`.
#[inline]
fn pad_up(v: f32) -> f32 {
    v + (BOX_REL_PAD * v.abs() + BOX_ABS_PAD)
}

/// View-space AABB of cluster `(i, j, k)`: the corner box of [`cluster_corner_bounds`], every
/// face padded outwards by [`BOX_REL_PAD`]`·|face| + `[`BOX_ABS_PAD`]. Conservative for every
/// [`view_position`](crate::reconstruct::view_position) of the cluster's pixels, across CPU and
/// GPU (module docs). All coordinates are finite.
#[inline]
pub fn cluster_aabb(grid: &ClusterGrid, bounds: &[f32], i: u32, j: u32, k: u32) -> ClusterAabb {
    let (lo, hi) = cluster_corner_bounds(grid, bounds, i, j, k);
    ClusterAabb {
        min: [pad_down(lo[0]), pad_down(lo[1]), pad_down(lo[2])],
        _pad0: 0.0,
        max: [pad_up(hi[0]), pad_up(hi[1]), pad_up(hi[2])],
        _pad1: 0.0,
    }
}

/// [`cluster_aabb`] of the cluster with key `key` (`grid.unpack`): the box both clustered light
/// searches (naive and BVH) test against.
#[inline]
pub fn cluster_aabb_of_key(grid: &ClusterGrid, bounds: &[f32], key: u32) -> ClusterAabb {
    let (i, j, k) = grid.unpack(key);
    cluster_aabb(grid, bounds, i, j, k)
}

#[cfg(test)]
#[path = "cluster_bounds_tests.rs"]
mod tests;
