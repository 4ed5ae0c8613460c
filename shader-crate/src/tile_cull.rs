//! Tile culling shared by the tiled techniques: one workgroup of [`TILED_WORKGROUP`] invocations
//! per `T × T` screen tile (`T` ≤ [`MAX_TILED_TILE`]) bounds the tile's depth and tests lights
//! against it. Used by tiled and 2.5D tiled shading ([`crate::tiled`]: culls into a
//! workgroup-memory list and shades) and Forward+ ([`crate::forward_plus`]: culls into per-tile
//! linked lists).
//!
//! # Steps ([`tile_bounds`], then [`TileCull::keeps`] per light)
//!
//! 1. **Depth bounds** — each invocation reads the depth of its ≤ [`MAX_PIXELS_PER_INVOCATION`]
//!    pixels ([`slot_pixel`]); a subgroup butterfly + workgroup memory reduce them to the tile's
//!    `[d_min, d_max]` ([`workgroup_min_max`]; geometry pixels only: a tile of sky pixels is
//!    empty and culls nothing).
//! 2. **Frustum** — the tile's four side planes through the eye come from the projection: the
//!    tile's pixel edges have the integer NDC numerators of [`crate::reconstruct`], a side plane is
//!    `x = k·d` with `k = (n/H)·tan θ` (the pixel-position formula at an edge); near/far are
//!    `d_min`/`d_max` ([`tile_frustum`]).
//! 3. **2.5D mask** (`MODE_TILED_25D` only; Harada, Mckee, Yang 2012, "Forward+: A Step Toward
//!    Film-Style Shading in Real Time", GPU Pro 4, and Harada 2012, "A 2.5D Culling for
//!    Forward+", SIGGRAPH Asia technical briefs) — `[d_min, d_max]` is cut into 32 cells; the
//!    tile's mask has a bit per cell holding a pixel ([`workgroup_or`]), a light's mask a bit per
//!    cell its depth range `[−c_z − r, −c_z + r]` meets ([`depth_cell`], [`light_depth_mask`]):
//!    ```text
//!      bit   0        1        2             31
//!          ┌────────┬────────┬────────┬ … ┬────────┐
//!          │ d_min  │        │        │   │  d_max │   cell b = [d_min + b·w, d_min + (b+1)·w),
//!          └────────┴────────┴────────┴ … ┴────────┘   w = (d_max − d_min)/32, last cell closed
//!      tile mask  = OR over geometry pixels of 1 << cell(d)
//!      light mask = bits cell(−c_z − r) ..= cell(−c_z + r)      keep iff tile & light ≠ 0
//!    ```
//! 4. **Light test** — sphere–plane tests ([`sphere_in_tile`]), then the mask ([`keep_light`]),
//!    [`LIGHTS_PER_INVOCATION`] lights per invocation per batch ([`TileCull::keeps_pair`]).
//!
//! **Conservative.** A light that touches (`lighting::light_touches`) any pixel of the tile is
//! kept, on one machine and against a CPU check (see [`sphere_in_tile`] and [`depth_cell`]).
//!
//! **Memory**: no buffers; workgroup memory [`TILE_CULL_SHARED_WORDS`] words (the scan's scratch,
//! which the tiled list building uses, then min, max and mask per subgroup: 1 KiB).
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use crate::compact_light::light_at;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::reconstruct;
use crate::scan::{workgroup_exclusive_scan, SCAN_SHARED_WORDS};
use glam::Vec3;

/// Invocations per workgroup (16 × 16).
pub const TILED_WORKGROUP: u32 = 256;
/// Largest tile edge: `32² / 256 = 4` pixels per invocation.
pub const MAX_TILED_TILE: u32 = 32;
/// Pixels one invocation handles at most (`⌈T² / 256⌉`).
pub const MAX_PIXELS_PER_INVOCATION: u32 = 4;
/// Lights each invocation tests per batch.
pub const LIGHTS_PER_INVOCATION: u32 = 2;
/// Lights tested per batch by the workgroup.
pub const CULL_BATCH: u32 = TILED_WORKGROUP * LIGHTS_PER_INVOCATION;
/// Depth cells of the 2.5D mask (bits of a `u32`).
pub const DEPTH_CELLS: u32 = 32;
/// Relative slack of the culling tests, `2^-16` (≥ 8× the rounding error bound, see
/// [`sphere_in_tile`]).
pub const CULL_SLACK: f32 = 1.0 / 65_536.0;
/// Absolute slack (covers underflow), `2^-100`.
pub const CULL_ABS_SLACK: f32 = 7.888_609e-31;
/// Subgroups per workgroup at the smallest supported width (4).
const MAX_SUBGROUPS: u32 = TILED_WORKGROUP / 4;

/// `TiledParams::mode`: plain tiled culling, or with the 2.5D depth mask.
pub const MODE_TILED: u32 = 0;
pub const MODE_TILED_25D: u32 = 1;

/// Workgroup-memory layout (words): the scan's scratch (used by the tiled list building), then the
/// reductions' scratch (min, max, mask per subgroup). Kernels append their own words after
/// [`TILE_CULL_SHARED_WORDS`].
pub const SHARED_REDUCE: u32 = SCAN_SHARED_WORDS as u32;
pub const TILE_CULL_SHARED_WORDS: u32 = SHARED_REDUCE + 3 * MAX_SUBGROUPS;

/// Marks a pixel slot outside the tile or the image.
pub const NO_PIXEL: u32 = u32::MAX;

/// Pixels per invocation for tile edge `t`.
#[inline]
pub fn pixels_per_invocation(t: u32) -> u32 {
    (t * t).div_ceil(TILED_WORKGROUP)
}

/// Pixel rectangle `[x0, x1) × [y0, y1)` of tile `(tx, ty)` (the last ones may be partial).
#[inline]
pub fn tile_rect(g: &ClusterGrid, tx: u32, ty: u32) -> (u32, u32, u32, u32) {
    let x0 = tx * g.tile_size;
    let y0 = ty * g.tile_size;
    let x1 = if x0 + g.tile_size < g.width { x0 + g.tile_size } else { g.width };
    let y1 = if y0 + g.tile_size < g.height { y0 + g.tile_size } else { g.height };
    (x0, x1, y0, y1)
}

/// A tile's view frustum: side planes `x = k·d`, `y = k·d` (`d = −z`) and the depth range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileFrustum {
    pub k_left: f32,
    pub k_right: f32,
    pub k_bottom: f32,
    pub k_top: f32,
    pub d_min: f32,
    pub d_max: f32,
}

impl TileFrustum {
    /// A sphere holding the frustum slice (the sphere of its view-space bounding box): what the
    /// spot lights' cone test takes for a tile.
    #[inline]
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (n, f) = (self.d_min, self.d_max);
        // Both slopes at both distances: whatever their signs and order.
        let x = [self.k_left * n, self.k_left * f, self.k_right * n, self.k_right * f];
        let y = [self.k_bottom * n, self.k_bottom * f, self.k_top * n, self.k_top * f];
        let min = Vec3::new(x[0].min(x[1]).min(x[2].min(x[3])), y[0].min(y[1]).min(y[2].min(y[3])), -f);
        let max = Vec3::new(x[0].max(x[1]).max(x[2].max(x[3])), y[0].max(y[1]).max(y[2].max(y[3])), -n);
        crate::light_types::box_sphere(min, max)
    }
}

/// The frustum of tile `(tx, ty)` between distances `d_min ≤ d_max`: the side slopes are the
/// pixel-position formula `x = (n_x/H)·tan θ·d` at the tile's edge numerators `2·x0 − W`,
/// `2·x1 − W`, `H − 2·y1`, `H − 2·y0` (see [`crate::cluster_bounds`]).
#[inline]
pub fn tile_frustum(g: &ClusterGrid, tx: u32, ty: u32, d_min: f32, d_max: f32) -> TileFrustum {
    let (x0, x1, y0, y1) = tile_rect(g, tx, ty);
    let (w, h) = (g.width as i32, g.height as i32);
    let hf = g.height as f32;
    let slope = |n: i32| (n as f32 / hf) * g.tan_half_fov_y;
    TileFrustum {
        k_left: slope(2 * x0 as i32 - w),
        k_right: slope(2 * x1 as i32 - w),
        k_bottom: slope(h - 2 * y1 as i32),
        k_top: slope(h - 2 * y0 as i32),
        d_min,
        d_max,
    }
}

/// The radius the culling tests use: `r + ε·(r + |c_x| + |c_y| + |c_z|) + τ` ([`CULL_SLACK`],
/// [`CULL_ABS_SLACK`]).
#[inline]
pub fn padded_radius(c: Vec3, r: f32) -> f32 {
    r + CULL_SLACK * (r + c.x.abs() + c.y.abs() + c.z.abs()) + CULL_ABS_SLACK
}

/// Whether a side plane `e ≥ 0` (inside) can be reached from a sphere with signed plane value `e`
/// (`e / √(1 + k²)` is the centre's distance) and padded radius `rr`.
#[inline]
fn side_reaches(e: f32, k: f32, rr: f32) -> bool {
    !(e + rr * (1.0 + k * k).sqrt() < 0.0)
}

/// Sphere–frustum test (four side planes through the eye plus the depth slab), conservative: if
/// the light touches a pixel of the tile whose distance lies in `[d_min, d_max]`, it is kept.
///
/// Why: for the pixel's computed position `p̂` with `|p̂ − c|² < r²` (computed), the exact
/// position of the same pixel centre at the same distance lies strictly inside the exact frustum
/// and within `13u·|p|` of `p̂` (`u = 2^-24`, GPU division ≤ 2.5 ULP; `reconstruct`, "Error"), so
/// the exact signed distance of `c` to each side plane is `≥ −(r + 16u·(r + |c|))`; the computed
/// plane value `e` (slope `k` within 6u, one product and one difference) adds `≤ 8u·|c|₁·√(1+k²)`
/// and `√(1+k²)` is computed within `10u`. The padded radius adds `2^-16·(r + |c|₁) = 256u·(…)`,
/// more than 8× the `≈ 30u·(r + |c|₁)` needed. The slab: the pixel's `z = −d` is exact, so
/// `|d − d_c| < r(1 + 3u)`; `d_min`/`d_max` are widened by `2^-16` relative for a CPU check whose
/// distances differ by ≤ 3 ULP.
#[inline]
pub fn sphere_in_tile(f: &TileFrustum, c: Vec3, r: f32) -> bool {
    let rr = padded_radius(c, r);
    let dc = -c.z;
    if dc + rr < f.d_min - CULL_SLACK * f.d_min || dc - rr > f.d_max + CULL_SLACK * f.d_max {
        return false;
    }
    side_reaches(c.x - f.k_left * dc, f.k_left, rr)
        && side_reaches(f.k_right * dc - c.x, f.k_right, rr)
        && side_reaches(c.y - f.k_bottom * dc, f.k_bottom, rr)
        && side_reaches(f.k_top * dc - c.y, f.k_top, rr)
}

/// The 2.5D cells of a tile's depth range: `cell(d) = ⌊(d − d_min)·inv_width⌋` clamped to 0..=31.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthCells {
    pub d_min: f32,
    /// `32 / (d_max − d_min)`, or 0 for a range too thin to split (then every depth is cell 0).
    pub inv_width: f32,
}

/// Cells of `[d_min, d_max]` (module docs, step 3). A range thinner than `10⁻⁶·d_max` is one cell
/// (keeps `inv_width` finite).
#[inline]
pub fn depth_cells(d_min: f32, d_max: f32) -> DepthCells {
    let span = d_max - d_min;
    let inv_width = if span > 1e-6 * d_max { DEPTH_CELLS as f32 / span } else { 0.0 };
    DepthCells { d_min, inv_width }
}

/// Cell of distance `d`: non-decreasing in `d` (a correctly rounded difference, a product with a
/// non-negative constant, a clamped truncation), so a depth between two others lies in a cell
/// between theirs — which is what makes the mask test exact without padding (same kernel, same
/// `DepthCells`). Below `d_min` (or NaN) → 0; at or beyond the last cell → 31.
#[inline]
pub fn depth_cell(cells: &DepthCells, d: f32) -> u32 {
    let t = (d - cells.d_min) * cells.inv_width;
    if !(t > 0.0) {
        0
    } else if t >= (DEPTH_CELLS - 1) as f32 {
        DEPTH_CELLS - 1
    } else {
        t as u32
    }
}

/// Bits `a..=b` (`a ≤ b ≤ 31`; empty when `a > b`).
#[inline]
pub fn cell_range_mask(a: u32, b: u32) -> u32 {
    if a > b || b >= DEPTH_CELLS {
        return 0;
    }
    (u32::MAX >> (DEPTH_CELLS - 1 - b)) & (u32::MAX << a)
}

/// The light's 2.5D mask: the cells its padded depth range `[d_c − rr, d_c + rr]` meets.
#[inline]
pub fn light_depth_mask(cells: &DepthCells, c: Vec3, r: f32) -> u32 {
    let rr = padded_radius(c, r);
    let dc = -c.z;
    cell_range_mask(depth_cell(cells, dc - rr), depth_cell(cells, dc + rr))
}

/// Whether the tile keeps `light` (frustum test, then the 2.5D mask when `tile_mask` is not all
/// ones).
#[inline]
pub fn keep_light(f: &TileFrustum, cells: &DepthCells, tile_mask: u32, mode: u32, light: &PointLight) -> bool {
    let c = Vec3::from_array(light.position);
    sphere_in_tile(f, c, light.radius) && (mode != MODE_TILED_25D || light_depth_mask(cells, c, light.radius) & tile_mask != 0)
}

/// Minimum and maximum over the workgroup (every invocation gets both). Uniform control flow.
#[inline]
pub fn workgroup_min_max<C: Coop, S: SharedU32 + ?Sized>(c: &C, s: &mut S, lo: u32, hi: u32) -> (u32, u32) {
    let (mut lo, mut hi) = (lo, hi);
    let mut d = 1;
    while d < c.subgroup_size() {
        let (a, b) = (c.shuffle_xor(lo, d), c.shuffle_xor(hi, d));
        lo = if a < lo { a } else { lo };
        hi = if b > hi { b } else { hi };
        d *= 2;
    }
    if c.lane() == 0 {
        s.store(SHARED_REDUCE + c.subgroup_id(), lo);
        s.store(SHARED_REDUCE + MAX_SUBGROUPS + c.subgroup_id(), hi);
    }
    c.workgroup_barrier();
    let mut g = 0;
    while g < c.num_subgroups() {
        let (a, b) = (s.load(SHARED_REDUCE + g), s.load(SHARED_REDUCE + MAX_SUBGROUPS + g));
        lo = if a < lo { a } else { lo };
        hi = if b > hi { b } else { hi };
        g += 1;
    }
    (lo, hi)
}

/// Bitwise OR over the workgroup. Uniform control flow.
#[inline]
pub fn workgroup_or<C: Coop, S: SharedU32 + ?Sized>(c: &C, s: &mut S, v: u32) -> u32 {
    let mut v = v;
    let mut d = 1;
    while d < c.subgroup_size() {
        v |= c.shuffle_xor(v, d);
        d *= 2;
    }
    if c.lane() == 0 {
        s.store(SHARED_REDUCE + 2 * MAX_SUBGROUPS + c.subgroup_id(), v);
    }
    c.workgroup_barrier();
    let mut g = 0;
    while g < c.num_subgroups() {
        v |= s.load(SHARED_REDUCE + 2 * MAX_SUBGROUPS + g);
        g += 1;
    }
    v
}

/// Pixel index of slot `slot` of invocation `li` in tile `(tx, ty)`, or [`NO_PIXEL`].
#[inline]
pub fn slot_pixel(g: &ClusterGrid, tx: u32, ty: u32, li: u32, slot: u32) -> u32 {
    let t = g.tile_size;
    let q = li + slot * TILED_WORKGROUP;
    if slot >= MAX_PIXELS_PER_INVOCATION || q >= t * t {
        return NO_PIXEL;
    }
    let (x, y) = (tx * t + q % t, ty * t + q / t);
    if x < g.width && y < g.height {
        y * g.width + x
    } else {
        NO_PIXEL
    }
}


/// One invocation's pixel slots of a tile (step 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TilePixels {
    /// Pixel index per slot, [`NO_PIXEL`] outside the tile or the image.
    pub pixels: [u32; MAX_PIXELS_PER_INVOCATION as usize],
    /// Distance of each geometry pixel (0 elsewhere).
    pub dist: [f32; MAX_PIXELS_PER_INVOCATION as usize],
    /// 1 where the slot holds a geometry pixel.
    pub geo: [u32; MAX_PIXELS_PER_INVOCATION as usize],
}

/// What the tile tests lights with (steps 2–3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileCull {
    pub frustum: TileFrustum,
    pub cells: DepthCells,
    /// The tile's 2.5D mask (all ones unless `mode` is `MODE_TILED_25D`).
    pub mask: u32,
    pub mode: u32,
    /// No geometry pixel: the tile keeps no light.
    pub empty: bool,
}

impl TileCull {
    /// Whether the tile keeps `light` ([`keep_light`]).
    #[inline]
    pub fn keeps(&self, light: &PointLight) -> bool {
        keep_light(&self.frustum, &self.cells, self.mask, self.mode, light)
    }

    /// Step 4 for one invocation: whether the tile keeps lights `first` and `first + 1` (each
    /// only if below `n`). With spot lights (`effects & EFFECT_SPOT`) a light is kept only if
    /// its cone may also meet the sphere bounding the tile's frustum slice
    /// ([`TileFrustum::bounding_sphere`], `light_types::spot_may_meet`).
    #[inline]
    pub fn keeps_pair(&self, lights: &[PointLight], n: u32, first: u32, effects: u32) -> (bool, bool) {
        let a = first < n && self.keeps(&light_at(lights, effects, n, first));
        let b = first + 1 < n && self.keeps(&light_at(lights, effects, n, first + 1));
        if effects & crate::light_types::EFFECT_SPOT == 0 || n == 0 {
            return (a, b);
        }
        // The cone record is read and tested only for lights the tile keeps by range.
        let (c0, r0) = self.frustum.bounding_sphere();
        let ca = a && crate::light_types::spot_may_meet(effects, lights, n, first, c0, r0);
        let cb = b && crate::light_types::spot_may_meet(effects, lights, n, first + 1, c0, r0);
        (ca, cb)
    }
}

/// One batch of step 4 compacted over the workgroup ([`TileCull::keep_batch`]): which of its two
/// lights an invocation keeps, and their places among the batch's survivors in light-index order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeptPair {
    /// The invocation's first light (the second is `first + 1`).
    pub first: u32,
    pub a: bool,
    pub b: bool,
    /// Survivors of the batch before this invocation's (an exclusive prefix sum).
    pub rank: u32,
    /// Survivors of the whole batch.
    pub total: u32,
}

impl KeptPair {
    /// Calls `put(k, light)` for each kept light, `k` being its place among the batch's survivors.
    #[inline]
    pub fn emit(&self, mut put: impl FnMut(u32, u32)) {
        if self.a {
            put(self.rank, self.first);
        }
        if self.b {
            put(self.rank + self.a as u32, self.first + 1);
        }
    }
}

impl TileCull {
    /// Step 4 for the batch of [`CULL_BATCH`] lights from `next`: [`Self::keeps_pair`], ranked
    /// over the workgroup by a prefix sum (the scan's workgroup-memory words). Uniform control
    /// flow; a caller puts a workgroup barrier between two batches (the scan's scratch).
    #[inline]
    pub fn keep_batch<C: Coop, S: SharedU32 + ?Sized>(&self, c: &C, s: &mut S, lights: &[PointLight], n: u32, next: u32, effects: u32) -> KeptPair {
        let first = next + c.local_index() * LIGHTS_PER_INVOCATION;
        let (a, b) = self.keeps_pair(lights, n, first, effects);
        let (rank, total) = workgroup_exclusive_scan(c, s, a as u32 + b as u32);
        KeptPair { first, a, b, rank, total }
    }
}

/// A tile depth range that widens nothing: `(lo, hi)` bits of view distances, `lo > hi`.
pub const NO_WIDENING: (u32, u32) = (f32::MAX.to_bits(), 0);

/// The view-distance range (`(lo, hi)` bits) of a tile's transparent fragments from its
/// `TILE_DEPTH_WORDS` (`!min`, `max`, both kept by atomic max from 0): [`NO_WIDENING`] for a
/// tile no transparent fragment reached.
#[inline]
pub fn tile_widening(words: &[u32], tile: u32) -> (u32, u32) {
    let w = (TILE_DEPTH_WORDS * tile) as usize;
    let lo = !words[w];
    (if lo < NO_WIDENING.0 { lo } else { NO_WIDENING.0 }, words[w + 1])
}

/// Steps 1–3 for one invocation of tile `(tx, ty)` (module docs): its pixels, and the tile's
/// depth bounds, frustum and (`mode == MODE_TILED_25D`) 2.5D mask. The bounds also span `widen`
/// (view-distance bits, [`tile_widening`]: Forward+'s transparent fragments; [`NO_WIDENING`]
/// otherwise), and a widened tile's 2.5D mask keeps every cell (the mask knows opaque pixels
/// only). With a multisampled G-buffer (`ClusterGrid::samples` above 1, `crate::msaa`) the bounds
/// and the mask span every sample of the tile's pixels (planes `s·n + i` of `depth`), so the list
/// serves the edge pixels' samples too; `TilePixels` is sample 0's. Called by every invocation of
/// the workgroup (it synchronises).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn tile_bounds<C: Coop, S: SharedU32 + ?Sized>(c: &C, s: &mut S, g: &ClusterGrid, tx: u32, ty: u32, mode: u32, depth: &[f32], widen: (u32, u32)) -> (TilePixels, TileCull) {
    let li = c.local_index();
    let mut px = TilePixels { pixels: [NO_PIXEL; 4], dist: [0.0; 4], geo: [0; 4] };
    // Bits of positive floats order like the floats.
    let (mut lo, mut hi) = widen;
    let plane = g.width * g.height;
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = slot_pixel(g, tx, ty, li, slot);
        px.pixels[slot as usize] = i;
        if i != NO_PIXEL && !reconstruct::is_background(depth[i as usize]) {
            let d = reconstruct::distance_from_depth(g.near, depth[i as usize]);
            px.dist[slot as usize] = d;
            px.geo[slot as usize] = 1;
            lo = if d.to_bits() < lo { d.to_bits() } else { lo };
            hi = if d.to_bits() > hi { d.to_bits() } else { hi };
        }
        let mut sample = 1;
        while i != NO_PIXEL && sample < g.samples {
            let z = depth[(sample * plane + i) as usize];
            if !reconstruct::is_background(z) {
                let d = reconstruct::distance_from_depth(g.near, z).to_bits();
                lo = if d < lo { d } else { lo };
                hi = if d > hi { d } else { hi };
            }
            sample += 1;
        }
        slot += 1;
    }
    let (lo, hi) = workgroup_min_max(c, s, lo, hi);
    let empty = lo > hi;
    let (d_min, d_max) = (f32::from_bits(lo), f32::from_bits(hi));
    let cells = depth_cells(d_min, d_max);
    let mut mask = u32::MAX;
    if mode == MODE_TILED_25D && !empty && widen.0 > widen.1 {
        let mut mine = 0;
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            let i = px.pixels[slot as usize];
            if px.geo[slot as usize] != 0 {
                mine |= 1u32 << depth_cell(&cells, px.dist[slot as usize]);
            }
            let mut sample = 1;
            while i != NO_PIXEL && sample < g.samples {
                let z = depth[(sample * plane + i) as usize];
                if !reconstruct::is_background(z) {
                    mine |= 1u32 << depth_cell(&cells, reconstruct::distance_from_depth(g.near, z));
                }
                sample += 1;
            }
            slot += 1;
        }
        mask = workgroup_or(c, s, mine);
    }
    (px, TileCull { frustum: tile_frustum(g, tx, ty, d_min, d_max), cells, mask, mode, empty })
}

#[cfg(test)]
#[path = "tile_cull_tests.rs"]
mod tests;
