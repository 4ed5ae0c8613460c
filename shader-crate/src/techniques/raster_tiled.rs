//! Raster-based tiled light assignment (`raster-tiled`): the light lists of the screen tiles are
//! built by the rasteriser. Each light is drawn as a quad over the tiles it may touch into a
//! framebuffer of one pixel per tile; each fragment tests its light against its tile and appends
//! the light to the tile's list with an atomic; the shading is a per-pixel loop over the tile's
//! list, as in tiled deferred shading.
//!
//! After Douda's thesis ("Rendering of many lights", Czech Technical University, §4, "Deferred
//! Tiled" on rasterisation: light volumes drawn into a tile-resolution target, each fragment
//! appending its light to a per-tile list in a storage buffer) and Olsson & Assarsson 2011
//! ("Tiled Shading", JGT) for the tiles and their depth bounds.
//!
//! # Steps (after the G-buffer)
//!
//! 1. **Tile depth bounds** ([`tile_depths`], one workgroup of 256 per tile): the tile's
//!    `[d_min, d_max]` over its geometry pixels (`tile_cull::tile_bounds`, as `tiled`), stored as
//!    [`DEPTH_BOUND_WORDS`] words; the tile's list count is zeroed.
//! 2. **Light quads** ([`light_rects`], one invocation per light): the range of tiles the light's
//!    sphere may cover on screen, from the tangent planes through the eye ([`light_tiles`]), as a
//!    quad in the tile target's NDC ([`RECT_WORDS`] floats per light). Every tile whose centre
//!    lies inside the quad is a tile of the range, and no other: the quad's edges lie on tile
//!    boundaries, so no conservative rasterisation is needed.
//! 3. **Raster** ([`light_rect_vs`] + [`append_light_fs`]): [`VERTICES_PER_LIGHT`] vertices per
//!    light, no depth test, a `tiles_x × tiles_y` target; each fragment (one per tile of the quad)
//!    tests its light against its tile ([`tile_keeps`]: the tile's frustum and depth range as
//!    `tiled`, the cone for spot lights) and, if kept, appends the light with an atomic add
//!    ([`append`]: entries past `FrameParams::light_capacity` are counted, not stored).
//! 4. **Shading** (`shade_raster_tiled_diffuse` / `_specular`, one invocation per pixel): the
//!    pixel's tile's list through `shading::shade_gbuffer_pixel`.
//! 5. **Edge shading** (MSAA only, `crate::msaa`; `shade_edges_raster_tiled_*`): each edge
//!    pixel's samples with its tile's list; step 1's bounds span every sample.
//!
//! **No light is dropped.** A tile whose count passed the capacity makes the host grow the lists
//! to the longest count + 25 % and render the frame again.
//!
//! **Conservative.** The quad of step 2 holds every tile whose side planes the padded sphere can
//! reach (exact tangent slopes for a radius [`RECT_RADIUS_GROWTH`] larger than the culling
//! test's, widened by [`RECT_MARGIN_PX`]); the test of step 3 is `tile_cull::sphere_in_tile`,
//! which keeps every light that touches a pixel of the tile.
//!
//! **Memory**: [`DEPTH_BOUND_WORDS`] + 1 words per tile (depth bounds, count), `capacity` words
//! per tile (lists), [`RECT_WORDS`] words per light (quads); the target (one 32-bit depth word
//! per tile).
use crate::layout::*;
use crate::tile_cull::{padded_radius, sphere_in_tile, tile_frustum};
use glam::{Vec3, Vec4};
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;
#[cfg(feature = "compute")]
use crate::coop::gpu::GpuCoop;
#[cfg(feature = "compute")]
use crate::shading::{self, linear_index, specular_entries, BACKGROUND_RGBA8};
#[cfg(feature = "compute")]
use crate::tile_cull::{tile_bounds, MODE_TILED, NO_WIDENING, TILE_CULL_SHARED_WORDS};
#[cfg(feature = "compute")]
use spirv_std::glam::UVec3;
#[cfg(any(feature = "compute", feature = "graphics"))]
use spirv_std::spirv;
#[cfg(feature = "graphics")]
use crate::fragment_atomics::atomic_add;

/// Words of a light's quad: NDC `[x0, y0, x1, y1]` of the tile target.
pub const RECT_WORDS: u32 = 4;
/// Vertices drawn per light (two triangles).
pub const VERTICES_PER_LIGHT: u32 = 6;
/// Pixels the tile range of step 2 is widened by on every side (covers the rounding of the
/// tangent slopes, well under 0.1 px at 32 k pixels).
pub const RECT_MARGIN_PX: f32 = 1.0;
/// Relative growth of the padded radius the quad is computed for.
pub const RECT_RADIUS_GROWTH: f32 = 1.0 / 1024.0;
/// Words of a tile's depth bounds: the bits of `d_min` and `d_max` (`d_min > d_max`: a tile
/// without geometry, which keeps no light).
pub const DEPTH_BOUND_WORDS: u32 = 2;
/// Depth-bound words of a tile without geometry.
pub const EMPTY_TILE: [u32; 2] = [1, 0];

/// Step 2: the tiles `[tx0, tx1) × [ty0, ty1)` light `light` may touch (`tx0 == tx1`: none).
///
/// In the `(x, d)` plane (`d = −z`), the lines `x = k·d` tangent to the circle of centre
/// `(c_x, d_c)` and radius `r` have slopes `k = (c_x·d_c ± r·√(c_x² + d_c² − r²)) / (d_c² − r²)`
/// (for `d_c > r`); a tile's side test (`sphere_in_tile`) passes exactly for the tiles whose
/// slope interval meets `[k_min, k_max]`. A pixel column at slope `k` is
/// `x = (k·H / tan θ + W) / 2` (`tile_cull::tile_frustum`'s slope formula inverted), a row
/// `y = (H − k·H / tan θ) / 2`. A sphere that reaches the eye plane (`d_c ≤ r`) may cover every
/// tile; one wholly before the near plane none.
#[inline]
pub fn light_tiles(g: &ClusterGrid, light: &PointLight) -> [u32; 4] {
    let c = Vec3::from_array(light.position);
    let r = padded_radius(c, light.radius) * (1.0 + RECT_RADIUS_GROWTH);
    let d = -c.z;
    let all = [0, 0, g.tiles_x, g.tiles_y];
    if d + r < g.near * (1.0 - RECT_RADIUS_GROWTH) {
        return [0; 4];
    }
    if !(d > r) {
        return all;
    }
    let (w, h) = (g.width as f32, g.height as f32);
    let scale = h / g.tan_half_fov_y;
    let dd = d * d - r * r;
    // Pixel interval of one axis (centre offset `a`; `flip` for rows, counted from the top).
    let span = |a: f32, flip: bool| -> (f32, f32) {
        let root = (a * a + dd).sqrt();
        let (k0, k1) = ((a * d - r * root) / dd, (a * d + r * root) / dd);
        let (p0, p1) = if flip { ((h - k1 * scale) * 0.5, (h - k0 * scale) * 0.5) } else { ((k0 * scale + w) * 0.5, (k1 * scale + w) * 0.5) };
        (p0 - RECT_MARGIN_PX, p1 + RECT_MARGIN_PX)
    };
    let (x0, x1) = span(c.x, false);
    let (y0, y1) = span(c.y, true);
    if !(x1 >= x0 && y1 >= y0) {
        // NaN (out-of-contract input): every tile, never none.
        return all;
    }
    let ts = g.tile_size as f32;
    let tile = |p: f32, n: u32| -> u32 {
        let t = p / ts;
        if !(t > 0.0) {
            0
        } else if t >= n as f32 {
            n
        } else {
            t as u32
        }
    };
    let (tx0, ty0) = (tile(x0, g.tiles_x), tile(y0, g.tiles_y));
    // `⌊x1 / ts⌋ + 1`: the tile holding `x1` is in.
    let (tx1, ty1) = (tile(x1 + ts, g.tiles_x), tile(y1 + ts, g.tiles_y));
    if tx0 >= tx1 || ty0 >= ty1 {
        return [0; 4];
    }
    [tx0, ty0, tx1, ty1]
}

/// Step 2's quad in the tile target's NDC (`x = 2·t / tiles − 1`; row 0 of the target, at NDC
/// `y = −1`, is the top row of tiles, as in the image).
#[inline]
pub fn tiles_to_ndc(g: &ClusterGrid, t: [u32; 4]) -> [f32; 4] {
    let (nx, ny) = (2.0 / g.tiles_x as f32, 2.0 / g.tiles_y as f32);
    [t[0] as f32 * nx - 1.0, t[1] as f32 * ny - 1.0, t[2] as f32 * nx - 1.0, t[3] as f32 * ny - 1.0]
}

/// Step 3, vertex `v`'s corner of its light's quad (`rect` = NDC `[x0, y0, x1, y1]`): two
/// triangles `(0,0) (1,0) (0,1)` and `(0,1) (1,0) (1,1)`.
#[inline]
pub fn quad_corner(rect: [f32; 4], v: u32) -> Vec4 {
    let corner = v % VERTICES_PER_LIGHT;
    let right = corner == 1 || corner == 4 || corner == 5;
    let down = corner == 2 || corner == 3 || corner == 5;
    Vec4::new(if right { rect[2] } else { rect[0] }, if down { rect[3] } else { rect[1] }, 0.0, 1.0)
}

/// Step 3's test: whether tile `(tx, ty)` keeps light `l` — its depth bounds (`tile_depths`,
/// [`DEPTH_BOUND_WORDS`] per tile), its frustum and the light's sphere (`sphere_in_tile`), and
/// for a spot light its cone against the sphere bounding the tile's frustum slice (as `tiled`).
#[inline]
pub fn tile_keeps(p: &FrameParams, tile_depths: &[u32], lights: &[PointLight], tx: u32, ty: u32, l: u32) -> bool {
    let g = &p.grid;
    if tx >= g.tiles_x || ty >= g.tiles_y || l >= p.num_lights {
        return false;
    }
    let t = (ty * g.tiles_x + tx) * DEPTH_BOUND_WORDS;
    let (lo, hi) = (tile_depths[t as usize], tile_depths[t as usize + 1]);
    if lo > hi {
        return false;
    }
    let f = tile_frustum(g, tx, ty, f32::from_bits(lo), f32::from_bits(hi));
    let light = &crate::compact_light::light_at(lights, p.effects, p.num_lights, l);
    if !sphere_in_tile(&f, Vec3::from_array(light.position), light.radius) {
        return false;
    }
    let (c, r) = f.bounding_sphere();
    crate::light_types::spot_may_meet(p.effects, lights, p.num_lights, l, c, r)
}

/// Step 3's append: light `l` to tile `t`'s list (`capacity` entries per tile), through
/// `reserve` (an atomic add on the tile's count, returning the count before). Entries past the
/// capacity are counted and not stored (the host grows the lists and renders again).
#[inline]
pub fn append(counts: &mut [u32], lists: &mut [u32], capacity: u32, t: u32, l: u32, reserve: impl Fn(&mut u32) -> u32) {
    let slot = reserve(&mut counts[t as usize]);
    if slot < capacity {
        lists[(t * capacity + slot) as usize] = l;
    }
}

/// Tile of pixel `i` (row-major pixels, row-major tiles).
#[inline]
pub fn tile_of_pixel(g: &ClusterGrid, i: u32) -> u32 {
    (i / g.width / g.tile_size) * g.tiles_x + (i % g.width) / g.tile_size
}

/// Step 1: one workgroup per tile `(wg.x, wg.y)`.
#[cfg(feature = "compute")]
#[allow(clippy::too_many_arguments)]
#[spirv(compute(threads(256)))]
pub fn tile_depths(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(local_invocation_index)] local_index: u32,
    #[spirv(subgroup_size)] subgroup_size: u32,
    #[spirv(subgroup_local_invocation_id)] lane: u32,
    #[spirv(subgroup_id)] subgroup_id: u32,
    #[spirv(num_subgroups)] num_subgroups: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(workgroup)] shared: &mut [u32; TILE_CULL_SHARED_WORDS as usize],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] tile_depths: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] counts: &mut [u32],
) {
    let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
    let (_, cull) = tile_bounds(&c, shared, &p.grid, wg.x, wg.y, MODE_TILED, depth, NO_WIDENING);
    if local_index == 0 {
        let t = wg.y * p.grid.tiles_x + wg.x;
        let words = if cull.empty { EMPTY_TILE } else { [cull.frustum.d_min.to_bits(), cull.frustum.d_max.to_bits()] };
        tile_depths[(t * DEPTH_BOUND_WORDS) as usize] = words[0];
        tile_depths[(t * DEPTH_BOUND_WORDS + 1) as usize] = words[1];
        counts[t as usize] = 0;
    }
}

/// Step 2: one invocation per light (`p.count` = lights).
#[cfg(feature = "compute")]
#[spirv(compute(threads(256)))]
pub fn light_rects(
    #[spirv(workgroup_id)] wg: UVec3,
    #[spirv(num_workgroups)] nwg: UVec3,
    #[spirv(local_invocation_index)] local: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] rects: &mut [f32],
) {
    let l = linear_index(wg, nwg, local);
    if l >= p.count {
        return;
    }
    let t = light_tiles(&p.grid, &crate::compact_light::light_at(lights, light_types, p.count, l));
    let ndc = if t[0] == t[2] { [0.0; 4] } else { tiles_to_ndc(&p.grid, t) };
    let mut k = 0;
    while k < RECT_WORDS {
        rects[(l * RECT_WORDS + k) as usize] = ndc[k as usize];
        k += 1;
    }
}

#[cfg(feature = "compute")]
specular_entries! {
    shade_raster_tiled_diffuse, shade_raster_tiled_specular;
    /// Step 4 for pixel `i` of the linear dispatch.
    fn shade_raster_tiled_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(num_workgroups)] nwg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lists: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 10)] shadow_maps: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let i = linear_index(wg, nwg, local);
        if i >= p.count {
            return;
        }
        if crate::reconstruct::is_background(depth[i as usize]) {
            frame[i as usize] = BACKGROUND_RGBA8;
            return;
        }
        let t = tile_of_pixel(&p.grid, i);
        let n = counts[t as usize];
        let list = shading::list_range(lists, t * p.light_capacity, if n < p.light_capacity { n } else { p.light_capacity });
        let shadows = crate::shadow::CubeShadows { slots: shadow_slots, maps: shadow_maps };
        frame[i as usize] = shading::shade_gbuffer_pixel::<SPECULAR, _, _>(p, bounds, i, depth, normals, albedo, materials, lights, &list, &shadows);
    }
}

#[cfg(feature = "compute")]
specular_entries! {
    shade_edges_raster_tiled_diffuse, shade_edges_raster_tiled_specular;
    /// Step 5 with MSAA (`crate::msaa`): edge `slot` of the edge list, every sample with its
    /// tile's list (whose depth bounds spanned every sample).
    fn shade_edges_raster_tiled_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(num_workgroups)] nwg: UVec3,
        #[spirv(local_invocation_index)] local: u32,
        #[spirv(push_constant)] p: &FrameParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] counts: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] lists: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] edges: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let slot = linear_index(wg, nwg, local);
        if slot >= edges[0] {
            return;
        }
        let i = edges[(crate::msaa::EDGE_HEADER_WORDS + slot) as usize];
        let t = tile_of_pixel(&p.grid, i);
        let n = counts[t as usize];
        // `move` over values: no pointer to this function's locals in the closure.
        let (first, len, effects, num_lights) = (t * p.light_capacity, if n < p.light_capacity { n } else { p.light_capacity }, p.effects, p.num_lights);
        let shade = move |_: u32, surface: &shading::Surface| {
            let mut sum = Vec3::ZERO;
            let count = shading::shade_lights::<SPECULAR, true, _>(surface, effects, num_lights, lights, &shading::list_range(lists, first, len), &mut sum);
            shading::shade_directional_lights::<SPECULAR>(surface, effects, num_lights, lights, &mut sum);
            (sum, count)
        };
        frame[i as usize] = crate::msaa::shade_edge_pixel(p, i, bounds, depth, normals, albedo, materials, shade);
    }
}

/// Step 3, vertex stage: vertex `v` is corner `v % 6` of light `v / 6`'s quad.
#[cfg(feature = "graphics")]
#[spirv(vertex)]
pub fn light_rect_vs(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] rects: &[f32],
    #[spirv(position)] out_position: &mut Vec4,
) {
    let v = vertex_index as u32;
    let base = (v / VERTICES_PER_LIGHT * RECT_WORDS) as usize;
    *out_position = quad_corner([rects[base], rects[base + 1], rects[base + 2], rects[base + 3]], v);
}

/// Step 3, fragment stage: the fragment of tile `⌊frag.xy⌋` for light `primitive / 2`.
#[cfg(feature = "graphics")]
#[allow(clippy::too_many_arguments)]
#[spirv(fragment)]
pub fn append_light_fs(
    #[spirv(frag_coord)] frag: Vec4,
    #[spirv(primitive_id, flat)] primitive: u32,
    #[spirv(push_constant)] p: &FrameParams,
    #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] tile_depths: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] lights: &[PointLight],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] counts: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] lists: &mut [u32],
) {
    let p = &crate::light_types::specialise(p, light_types);
    let (tx, ty, l) = (frag.x as u32, frag.y as u32, primitive / 2);
    if tile_keeps(p, tile_depths, lights, tx, ty, l) {
        append(counts, lists, p.light_capacity, ty * p.grid.tiles_x + tx, l, |w| atomic_add(w, 1));
    }
}

/// Typed handles of the kernels above (host side): what `render/raster_tiled.rs` creates its
/// pipelines from and registers for `tests/spirv_val.rs`.
#[cfg(not(target_arch = "spirv"))]
pub mod handles {
    use crate::kernels::{Kernel, RasterKernel};
    use crate::layout::FrameParams;

    /// Step 1: depth, tile depths, counts; cooperative (subgroup reductions).
    pub const TILE_DEPTHS: Kernel<FrameParams> = Kernel::new("raster_tiled::tile_depths", 3, [256, 1, 1], true);
    /// Step 2: lights, quads.
    pub const LIGHT_RECTS: Kernel<FrameParams> = Kernel::new("raster_tiled::light_rects", 2, [256, 1, 1], false);
    /// Step 4 `[diffuse only, with specular]`: the G-buffer (3), lights, materials, frame,
    /// bounds, counts, lists, the shadow slots and maps.
    pub const SHADE: [Kernel<FrameParams>; 2] = [
        Kernel::new("raster_tiled::shade_raster_tiled_diffuse", 11, [256, 1, 1], false),
        Kernel::new("raster_tiled::shade_raster_tiled_specular", 11, [256, 1, 1], false),
    ];
    /// Step 5 (MSAA) `[diffuse only, with specular]`: as [`SHADE`] without the shadows (frames
    /// with shadows are shaded once per pixel), and the edge list.
    pub const SHADE_EDGES: [Kernel<FrameParams>; 2] = [
        Kernel::new("raster_tiled::shade_edges_raster_tiled_diffuse", 10, [256, 1, 1], false),
        Kernel::new("raster_tiled::shade_edges_raster_tiled_specular", 10, [256, 1, 1], false),
    ];
    /// Step 3: quads (vertex stage); tile depths, lights, counts, lists (fragment stage).
    pub const APPEND: RasterKernel<FrameParams> = RasterKernel::with_vertex_buffers("raster_tiled::light_rect_vs", "raster_tiled::append_light_fs", 1, 4, 0);

    /// Every compute handle, erased.
    pub const COMPUTE: &[Kernel<()>] = &[TILE_DEPTHS.erased(), LIGHT_RECTS.erased(), SHADE[0].erased(), SHADE[1].erased(), SHADE_EDGES[0].erased(), SHADE_EDGES[1].erased()];
    /// Every raster handle, erased.
    pub const RASTER: &[RasterKernel<()>] = &[APPEND.erased()];
}

#[cfg(test)]
#[path = "raster_tiled_tests.rs"]
mod tests;
