//! Tiled deferred shading (`tiled`) and its 2.5D-culling variant (`tiled-2.5d`): one workgroup per
//! screen tile culls the lights and shades the tile's pixels in the same dispatch.
//!
//! # Steps (one workgroup of [`TILED_WORKGROUP`] invocations per `T × T` tile, `T` ≤ [`MAX_TILED_TILE`])
//!
//! 1. **Depth bounds** — each invocation reads the depth of its ≤ [`MAX_PIXELS_PER_INVOCATION`]
//!    pixels; a subgroup butterfly + workgroup memory reduce them to the tile's `[d_min, d_max]`
//!    (geometry pixels only; a tile of sky pixels culls nothing and shades background).
//! 2. **Frustum** — the tile's four side planes through the eye come from the projection: the
//!    tile's pixel edges have the integer NDC numerators of [`crate::reconstruct`], a side plane is
//!    `x = k·d` with `k = (n/H)·tan θ` (the pixel-position formula at an edge); near/far are
//!    `d_min`/`d_max` ([`tile_frustum`]).
//! 3. **2.5D mask** (`tiled-2.5d` only; Harada, Mckee, Yang 2012, "Forward+: A Step Toward Film-Style
//!    Shading in Real Time", GPU Pro 4, and Harada 2012, "A 2.5D Culling for Forward+", SIGGRAPH
//!    Asia technical briefs) — `[d_min, d_max]` is cut into 32 cells; the tile's mask has a bit
//!    per cell holding a pixel, a light's mask a bit per cell its depth range `[−c_z − r, −c_z + r]`
//!    meets ([`depth_cell`], [`light_depth_mask`]):
//!    ```text
//!      bit   0        1        2             31
//!          ┌────────┬────────┬────────┬ … ┬────────┐
//!          │ d_min  │        │        │   │  d_max │   cell b = [d_min + b·w, d_min + (b+1)·w),
//!          └────────┴────────┴────────┴ … ┴────────┘   w = (d_max − d_min)/32, last cell closed
//!      tile mask  = OR over geometry pixels of 1 << cell(d)
//!      light mask = bits cell(−c_z − r) ..= cell(−c_z + r)      keep iff tile & light ≠ 0
//!    ```
//! 4. **Culling** — the workgroup tests the lights in batches of [`CULL_BATCH`] (each invocation
//!    [`LIGHTS_PER_INVOCATION`] lights: sphere–plane tests [`sphere_in_tile`], then the mask) and
//!    appends the survivors, in index order, through a workgroup prefix sum to the tile-local list
//!    in workgroup memory (Olsson & Assarsson 2011, "Tiled Shading", JGT; Harada et al. 2012).
//! 5. **Shading** — every pixel sums [`lighting::shade`] over the list.
//!
//! **No capacity can be exceeded.** The list holds [`LIST_CAPACITY`] lights. A batch is started
//! only while it fits (`count + CULL_BATCH ≤ LIST_CAPACITY`); a full list is shaded (step 5
//! accumulates per pixel in registers), emptied, and culling resumes at the next batch: a tile
//! with more lights than the capacity takes several rounds, and no light is ever dropped.
//!
//! **Conservative.** A light that touches (`lighting::light_touches`) any pixel of the tile is
//! kept, on one machine and against a CPU check (see [`sphere_in_tile`] and [`depth_cell`]).
//!
//! **llvmpipe's loop limiter** (65 535 loop iterations per invocation): culling costs
//! `N / CULL_BATCH` batches of ≈ 20 iterations (the scan's shuffle loops included), shading
//! `P · (L/16 + rounds)` for `P` pixels per invocation and `L ≤ N` listed lights (16 lights per
//! iteration, straight-line): ≤ 41 k iterations for `N = 400 000`, `P = 1`; the host allows
//! `400 000 / P` lights on llvmpipe ([`max_lights_llvmpipe`]).
//!
//! **Memory**: no buffers beyond the G-buffer, the lights and the frame, plus one word per tile
//! (its light count, for statistics); workgroup memory [`TILED_SHARED_WORDS`] words (5 KiB).
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::scan::{workgroup_exclusive_scan, SCAN_SHARED_WORDS};
use crate::coop::gpu::GpuCoop;
use crate::{clustered, lighting, reconstruct};
use glam::Vec3;
use spirv_std::glam::UVec3;
use spirv_std::spirv;

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
/// Entries of the tile-local light list (workgroup memory); more lights take several rounds.
pub const LIST_CAPACITY: u32 = 1024;
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

/// Workgroup-memory layout (words): the scan's scratch, the reductions' scratch (min, max, mask per
/// subgroup), the light list.
pub const SHARED_REDUCE: u32 = SCAN_SHARED_WORDS as u32;
pub const SHARED_LIST: u32 = SHARED_REDUCE + 3 * MAX_SUBGROUPS;
pub const TILED_SHARED_WORDS: usize = (SHARED_LIST + LIST_CAPACITY) as usize;
const _: () = assert!(TILED_SHARED_WORDS * 4 <= 32 * 1024, "lavapipe has 32 KiB of workgroup memory");
const _: () = assert!(CULL_BATCH <= LIST_CAPACITY);

/// Marks a pixel slot outside the tile or the image.
pub const NO_PIXEL: u32 = u32::MAX;

/// Pixels per invocation for tile edge `t`.
#[inline]
pub fn pixels_per_invocation(t: u32) -> u32 {
    (t * t).div_ceil(TILED_WORKGROUP)
}

/// The most lights a tiled frame may have on llvmpipe (module docs).
#[inline]
pub fn max_lights_llvmpipe(tile_size: u32) -> u32 {
    clustered::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE / pixels_per_invocation(tile_size).max(1)
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

/// What one invocation produces: the colour of each of its pixel slots ([`NO_PIXEL`] where the
/// slot is outside the tile/image) and the tile's light count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileOutput {
    pub pixels: [u32; MAX_PIXELS_PER_INVOCATION as usize],
    pub colours: [u32; MAX_PIXELS_PER_INVOCATION as usize],
    pub tile_lights: u32,
    /// Rounds of culling + shading the tile took (1 unless the list filled up; 0 for a sky tile).
    pub rounds: u32,
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

/// Steps 1–5 for one invocation of tile `(tx, ty)` (module docs). Called by every invocation of
/// the workgroup (it synchronises).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn shade_tile<C: Coop, S: SharedU32 + ?Sized, const SPECULAR: bool>(
    c: &C,
    s: &mut S,
    p: &TiledParams,
    tx: u32,
    ty: u32,
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    bounds: &[f32],
) -> TileOutput {
    let fp = &p.frame;
    let g = &fp.grid;
    let li = c.local_index();
    let mut out = TileOutput { pixels: [NO_PIXEL; 4], colours: [clustered::BACKGROUND_RGBA8; 4], tile_lights: 0, rounds: 0 };
    // 1. My pixels and the tile's depth range (bits of positive floats order like the floats).
    let mut dist = [0.0f32; MAX_PIXELS_PER_INVOCATION as usize];
    let mut geo = [0u32; MAX_PIXELS_PER_INVOCATION as usize];
    let (mut lo, mut hi) = (f32::MAX.to_bits(), 0u32);
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = slot_pixel(g, tx, ty, li, slot);
        out.pixels[slot as usize] = i;
        if i != NO_PIXEL && !reconstruct::is_background(depth[i as usize]) {
            let d = reconstruct::distance_from_depth(g.near, depth[i as usize]);
            dist[slot as usize] = d;
            geo[slot as usize] = 1;
            lo = if d.to_bits() < lo { d.to_bits() } else { lo };
            hi = if d.to_bits() > hi { d.to_bits() } else { hi };
        }
        slot += 1;
    }
    let (lo, hi) = workgroup_min_max(c, s, lo, hi);
    let empty = lo > hi;
    let (d_min, d_max) = (f32::from_bits(lo), f32::from_bits(hi));
    // 2–3.
    let frustum = tile_frustum(g, tx, ty, d_min, d_max);
    let cells = depth_cells(d_min, d_max);
    let mut tile_mask = u32::MAX;
    if p.mode == MODE_TILED_25D && !empty {
        let mut mine = 0;
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            if geo[slot as usize] != 0 {
                mine |= 1u32 << depth_cell(&cells, dist[slot as usize]);
            }
            slot += 1;
        }
        tile_mask = workgroup_or(c, s, mine);
    }
    // 4–5 in rounds.
    let mut sums = [Vec3::ZERO; MAX_PIXELS_PER_INVOCATION as usize];
    let n = fp.num_lights;
    let mut next = if empty { n } else { 0 };
    while next < n {
        let mut count = 0;
        while next < n && count + CULL_BATCH <= LIST_CAPACITY {
            let first = next + li * LIGHTS_PER_INVOCATION;
            let a = first < n && keep_light(&frustum, &cells, tile_mask, p.mode, &lights[first as usize]);
            let b = first + 1 < n && keep_light(&frustum, &cells, tile_mask, p.mode, &lights[first as usize + 1]);
            let (prefix, total) = workgroup_exclusive_scan(c, s, a as u32 + b as u32);
            let mut w = SHARED_LIST + count + prefix;
            if a {
                s.store(w, first);
                w += 1;
            }
            if b {
                s.store(w, first + 1);
            }
            count += total;
            next += CULL_BATCH;
            c.workgroup_barrier();
        }
        out.tile_lights += count;
        out.rounds += 1;
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            let i = out.pixels[slot as usize];
            if geo[slot as usize] != 0 {
                let (pos, nrm, alb, m) = clustered::surface(fp, i, depth[i as usize], normals, albedo[i as usize]);
                let mat = materials[m as usize];
                let effects = if SPECULAR { EFFECT_SPECULAR } else { 0 };
                let mut sum = sums[slot as usize];
                let mut t = 0;
                while t < count {
                    unroll8!(u => {
                        if t + u < count {
                            let light = lights[s.load(SHARED_LIST + t + u) as usize];
                            sum += lighting::shade(pos, nrm, alb, mat.specular, mat.roughness, &light, effects);
                        }
                    });
                    unroll8!(u => {
                        if t + 8 + u < count {
                            let light = lights[s.load(SHARED_LIST + t + 8 + u) as usize];
                            sum += lighting::shade(pos, nrm, alb, mat.specular, mat.roughness, &light, effects);
                        }
                    });
                    t += 16;
                }
                sums[slot as usize] = sum;
            }
            slot += 1;
        }
        c.workgroup_barrier();
    }
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = out.pixels[slot as usize];
        if geo[slot as usize] != 0 {
            let (pos, nrm, _, _) = clustered::surface(fp, i, depth[i as usize], normals, albedo[i as usize]);
            out.colours[slot as usize] = clustered::output_colour(fp, bounds, i, pos, nrm, sums[slot as usize], out.tile_lights);
        }
        slot += 1;
    }
    out
}

/// Writes one invocation's pixels and (invocation 0) the tile's light count.
#[allow(clippy::too_many_arguments)]
#[inline]
fn run_entry<const SPECULAR: bool>(
    wg: UVec3,
    c: GpuCoop,
    p: &TiledParams,
    shared: &mut [u32; TILED_SHARED_WORDS],
    depth: &[f32],
    normals: &[u32],
    albedo: &[u32],
    lights: &[PointLight],
    materials: &[MaterialGpu],
    frame: &mut [u32],
    bounds: &[f32],
    tile_lights: &mut [u32],
) {
    let o = shade_tile::<_, _, SPECULAR>(&c, shared, p, wg.x, wg.y, depth, normals, albedo, lights, materials, bounds);
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = o.pixels[slot as usize];
        if i != NO_PIXEL {
            frame[i as usize] = o.colours[slot as usize];
        }
        slot += 1;
    }
    if c.local_index == 0 {
        tile_lights[(wg.y * p.frame.grid.tiles_x + wg.x) as usize] = o.tile_lights;
    }
}

/// Declares a tiled entry point (one workgroup per tile, `(wg.x, wg.y)` = tile).
macro_rules! tiled_entry {
    ($name:ident, $specular:expr) => {
        #[spirv(compute(threads(256)))]
        #[allow(clippy::too_many_arguments)]
        pub fn $name(
            #[spirv(workgroup_id)] wg: UVec3,
            #[spirv(local_invocation_index)] local_index: u32,
            #[spirv(subgroup_size)] subgroup_size: u32,
            #[spirv(subgroup_local_invocation_id)] lane: u32,
            #[spirv(subgroup_id)] subgroup_id: u32,
            #[spirv(num_subgroups)] num_subgroups: u32,
            #[spirv(push_constant)] p: &TiledParams,
            #[spirv(workgroup)] shared: &mut [u32; TILED_SHARED_WORDS],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] materials: &[MaterialGpu],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] frame: &mut [u32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] bounds: &[f32],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] tile_lights: &mut [u32],
        ) {
            let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
            run_entry::<$specular>(wg, c, p, shared, depth, normals, albedo, lights, materials, frame, bounds, tile_lights);
        }
    };
}
tiled_entry!(shade_tiled_diffuse, false);
tiled_entry!(shade_tiled_specular, true);

#[cfg(test)]
#[path = "tiled_tests.rs"]
pub(crate) mod tests;
