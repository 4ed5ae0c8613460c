//! Tiled deferred shading (`tiled`) and its 2.5D-culling variant (`tiled-2.5d`): one workgroup per
//! screen tile culls the lights and shades the tile's pixels in the same dispatch.
//!
//! # Steps (one workgroup of [`TILED_WORKGROUP`] invocations per `T × T` tile, `T` ≤ [`MAX_TILED_TILE`])
//!
//! 1–3. **Depth bounds, frustum, 2.5D mask** (`tiled-2.5d` only) — [`crate::tile_cull`] (Harada,
//!    Mckee, Yang 2012; Harada 2012), shared with Forward+.
//! 4. **Culling** — the workgroup tests the lights in batches of [`CULL_BATCH`] (each invocation
//!    [`LIGHTS_PER_INVOCATION`] lights: [`TileCull::keep_batch`]) and appends the survivors, in
//!    index order, through a workgroup prefix sum to the tile-local list in workgroup memory
//!    (Olsson & Assarsson 2011, "Tiled Shading", JGT; Harada et al. 2012).
//! 5. **Shading** — every pixel sums its lights over the list ([`shading::shade_lights_with`],
//!    each light times its visibility from the cube shadow maps where lights cast shadows); with
//!    MSAA (Lauritzen 2010, [`crate::msaa`]) an edge pixel sums them for each of its samples at
//!    the sample's location and takes the mean colour, in the same rounds (the bounds of steps 1–3
//!    span every sample).
//!
//! **No capacity can be exceeded.** The list holds [`LIST_CAPACITY`] lights. A batch is started
//! only while it fits (`count + CULL_BATCH ≤ LIST_CAPACITY`); a full list is shaded (step 5
//! accumulates per pixel in registers), emptied, and culling resumes at the next batch: a tile
//! with more lights than the capacity takes several rounds, and no light is ever dropped.
//!
//! **Conservative.** A light that touches (`lighting::light_touches`) any pixel of the tile is
//! kept ([`crate::tile_cull`]).
//!
//! **llvmpipe's loop limiter** (65 535 loop iterations per invocation): culling costs
//! `N / CULL_BATCH` batches of ≈ 20 iterations (the scan's shuffle loops included), shading
//! `P · (L/16 + rounds)` for `P` pixels per invocation and `L ≤ N` listed lights (16 lights per
//! iteration, straight-line): ≤ 41 k iterations for `N = 400 000`, `P = 1`; the host allows
//! `400 000 / P` lights on llvmpipe ([`max_lights_llvmpipe`]).
//!
//! **Memory**: no buffers beyond the G-buffer, the lights and the frame, plus one word per tile
//! (its light count, for statistics); workgroup memory [`TILED_SHARED_WORDS`] words (5 KiB).
use crate::coop::gpu::GpuCoop;
use crate::coop::{Coop, SharedU32};
use crate::layout::*;
use crate::light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE;
use crate::msaa::{self, MAX_SAMPLES};
use crate::shading::{self, specular_entries, BACKGROUND_RGBA8};
use crate::shadow::{CubeShadows, Shadowing};
use crate::tile_cull::*;
use glam::Vec3;
use spirv_std::glam::UVec3;
use spirv_std::spirv;

/// Entries of the tile-local light list (workgroup memory); more lights take several rounds.
pub const LIST_CAPACITY: u32 = 1024;

/// Workgroup-memory layout (words): the tile culling's words ([`TILE_CULL_SHARED_WORDS`]: the
/// scan's scratch and the reductions'), then the light list.
pub const SHARED_LIST: u32 = TILE_CULL_SHARED_WORDS;
pub const TILED_SHARED_WORDS: usize = (SHARED_LIST + LIST_CAPACITY) as usize;
const _: () = assert!(TILED_SHARED_WORDS * 4 <= 32 * 1024, "lavapipe has 32 KiB of workgroup memory");
const _: () = assert!(CULL_BATCH <= LIST_CAPACITY);

/// The most lights a tiled frame may have on llvmpipe (module docs).
#[inline]
pub fn max_lights_llvmpipe(tile_size: u32) -> u32 {
    MAX_LIGHTS_PER_INVOCATION_LLVMPIPE / pixels_per_invocation(tile_size).max(1)
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

/// Steps 1–5 for one invocation of tile `(tx, ty)` (module docs). Called by every invocation of
/// the workgroup (it synchronises).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn shade_tile<C: Coop, S: SharedU32 + ?Sized, const SPECULAR: bool, V: Shadowing>(
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
    shadows: &V,
) -> TileOutput {
    let fp = &p.frame;
    // 1–3.
    let (px, cull) = tile_bounds(c, s, &fp.grid, tx, ty, p.mode, depth, NO_WIDENING);
    let mut out = TileOutput { pixels: px.pixels, colours: [BACKGROUND_RGBA8; 4], tile_lights: 0, rounds: 0 };
    // MSAA (`crate::msaa`): an edge pixel's every sample is shaded, at its own location, with the
    // tile's list (its bounds span every sample); its sums take `MAX_SAMPLES` slots.
    let samples = fp.grid.samples;
    // 1 for an edge pixel (a `u32`: rust-gpu cannot fill a bool array).
    let mut edge = [0u32; MAX_PIXELS_PER_INVOCATION as usize];
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = px.pixels[slot as usize];
        edge[slot as usize] = (samples > 1 && i != NO_PIXEL && msaa::pixel_is_edge(fp, i, depth, normals, albedo)) as u32;
        slot += 1;
    }
    // 4–5 in rounds; each sum carries over from round to round (lights in index order).
    let mut sums = [Vec3::ZERO; (MAX_PIXELS_PER_INVOCATION * MAX_SAMPLES) as usize];
    let n = fp.num_lights;
    let mut next = if cull.empty { n } else { 0 };
    while next < n {
        let mut count = 0;
        while next < n && count + CULL_BATCH <= LIST_CAPACITY {
            let kept = cull.keep_batch(c, s, lights, n, next, fp.effects);
            kept.emit(|k, light| s.store(SHARED_LIST + count + k, light));
            count += kept.total;
            next += CULL_BATCH;
            c.workgroup_barrier();
        }
        out.tile_lights += count;
        out.rounds += 1;
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            let i = px.pixels[slot as usize];
            let list = &*s;
            let tile_list = shading::index_range(0, count, |t| list.load(SHARED_LIST + t));
            let first = slot * MAX_SAMPLES;
            if edge[slot as usize] != 0 {
                let mut sample = 0;
                while sample < samples {
                    if !msaa::is_sky(fp, i, sample, depth) {
                        let surface = msaa::sample_surface(fp, i, sample, depth, normals, albedo, materials);
                        shading::shade_lights_with::<SPECULAR, true, _, _>(&surface, fp.effects, fp.num_lights, lights, &tile_list, shadows, &mut sums[(first + sample) as usize]);
                    }
                    sample += 1;
                }
            } else if px.geo[slot as usize] != 0 {
                let surface = shading::fetch_surface(fp, i, depth[i as usize], normals, albedo[i as usize], materials);
                shading::shade_lights_with::<SPECULAR, true, _, _>(&surface, fp.effects, fp.num_lights, lights, &tile_list, shadows, &mut sums[first as usize]);
            }
            slot += 1;
        }
        c.workgroup_barrier();
    }
    let mut slot = 0;
    while slot < MAX_PIXELS_PER_INVOCATION {
        let i = px.pixels[slot as usize];
        let first = slot * MAX_SAMPLES;
        if edge[slot as usize] != 0 {
            let mut mean = Vec3::ZERO;
            let mut sample = 0;
            while sample < samples {
                mean += if msaa::is_sky(fp, i, sample, depth) {
                    msaa::background()
                } else {
                    let surface = msaa::sample_surface(fp, i, sample, depth, normals, albedo, materials);
                    let mut sum = sums[(first + sample) as usize];
                    shading::shade_directional_lights::<SPECULAR>(&surface, fp.effects, fp.num_lights, lights, &mut sum);
                    msaa::sample_colour(fp, bounds, i, &surface, sum, out.tile_lights)
                };
                sample += 1;
            }
            out.colours[slot as usize] = msaa::resolve(mean, samples);
        } else if px.geo[slot as usize] != 0 {
            let surface = shading::fetch_surface(fp, i, depth[i as usize], normals, albedo[i as usize], materials);
            let mut sum = sums[first as usize];
            shading::shade_directional_lights::<SPECULAR>(&surface, fp.effects, fp.num_lights, lights, &mut sum);
            out.colours[slot as usize] = shading::output_colour(fp, bounds, i, &surface, sum, out.tile_lights);
        }
        slot += 1;
    }
    out
}

specular_entries! {
    shade_tiled_diffuse, shade_tiled_specular;
    /// One workgroup per tile, `(wg.x, wg.y)` = tile: writes the invocation's pixels and (invocation
    /// 0) the tile's light count.
    fn shade_tiled_impl<const SPECULAR: bool>(
        #[spirv(workgroup_id)] wg: UVec3,
        #[spirv(local_invocation_index)] local_index: u32,
        #[spirv(subgroup_size)] subgroup_size: u32,
        #[spirv(subgroup_local_invocation_id)] lane: u32,
        #[spirv(subgroup_id)] subgroup_id: u32,
        #[spirv(num_subgroups)] num_subgroups: u32,
        #[spirv(push_constant)] p: &TiledParams,
        #[spirv(spec_constant(id = 0, default = 0))] light_types: u32,
        #[spirv(workgroup)] shared: &mut [u32; TILED_SHARED_WORDS],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] albedo: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] lights: &[PointLight],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] materials: &[MaterialGpu],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] frame: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] bounds: &[f32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] tile_lights: &mut [u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 9)] shadow_maps: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let c = GpuCoop { subgroup_size, lane, subgroup_id, num_subgroups, local_index };
        let shadows = CubeShadows { slots: shadow_slots, maps: shadow_maps };
        let o = shade_tile::<_, _, SPECULAR, _>(&c, shared, p, wg.x, wg.y, depth, normals, albedo, lights, materials, bounds, &shadows);
        let mut slot = 0;
        while slot < MAX_PIXELS_PER_INVOCATION {
            let i = o.pixels[slot as usize];
            if i != NO_PIXEL {
                frame[i as usize] = o.colours[slot as usize];
            }
            slot += 1;
        }
        if local_index == 0 {
            tile_lights[(wg.y * p.frame.grid.tiles_x + wg.x) as usize] = o.tile_lights;
        }
    }
}

#[cfg(test)]
#[path = "tiled_tests.rs"]
pub(crate) mod tests;
