//! Brute-force deferred shading (`deferred`), the correctness reference of every technique: one
//! invocation per pixel sums every light of the frame over the G-buffer (no culling, no list).
//!
//! # Steps
//!
//! 1. **G-buffer** (raster, [`crate::raster`]): depth, normal, albedo + material per pixel.
//! 2. **Shading** — per pixel, [`shading::shade_lights_with`] over all lights in index order; a
//!    light that does not touch the pixel adds exactly 0 ([`crate::lighting`]), so the sum equals
//!    that over the touching lights. A shadow-casting light's share is its visibility from the
//!    frame's cube shadow maps ([`crate::shadow`]; the slot and map bindings alias other buffers
//!    when the scene has no such light, and the pipelines then hold no lookup).
//!
//! 3. **Edge shading** (`--msaa N`, [`crate::msaa`] step 5) — per edge pixel, every sample with
//!    every light ([`shade_edges_deferred_diffuse`] / `_specular`).
//!
//! **Cost**: `pixels × lights` light evaluations (the host skips it in benchmarks past a budget),
//! plus `edge pixels × N × lights` with MSAA.
//! **Memory**: nothing beyond the G-buffer, the lights and the frame.
use crate::layout::*;
use crate::light_lists::lights_meeting;
use crate::shading::{self, linear_index, specular_entries, BACKGROUND_RGBA8};
use crate::shadow::CubeShadows;
use crate::{lighting, msaa, reconstruct};
use spirv_std::glam::{UVec3, Vec3};
use spirv_std::spirv;

specular_entries! {
    shade_deferred_diffuse, shade_deferred_specular;
    /// Step 2 for pixel `i` of the linear dispatch (`_diffuse` / `_specular` variants).
    fn shade_deferred_impl<const SPECULAR: bool>(
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
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] shadow_slots: &[u32],
        #[spirv(storage_buffer, descriptor_set = 0, binding = 8)] shadow_maps: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let i = linear_index(wg, nwg, local);
        if i >= p.count {
            return;
        }
        let z = depth[i as usize];
        if reconstruct::is_background(z) {
            frame[i as usize] = BACKGROUND_RGBA8;
            return;
        }
        let surface = shading::fetch_surface(p, i, z, normals, albedo[i as usize], materials);
        let all_lights = shading::light_range(0, p.num_lights);
        let mut sum = Vec3::ZERO;
        let shadows = CubeShadows { slots: shadow_slots, maps: shadow_maps };
        shading::shade_lights_with::<SPECULAR, true, _, _>(&surface, p.effects, p.num_lights, lights, &all_lights, &shadows, &mut sum);
        shading::shade_directional_lights::<SPECULAR>(&surface, p.effects, p.num_lights, lights, &mut sum);
        // The heatmap shows the lights that touch the pixel (the frame-uniform view: no divergence).
        let touching = if p.view == VIEW_HEATMAP { lights_meeting(p.effects, p.num_lights, lights, |_, _| {}, |c, r| lighting::in_range(c, r, surface.pos)) } else { 0 };
        frame[i as usize] = shading::output_colour(p, bounds, i, &surface, sum, touching);
    }
}

specular_entries! {
    shade_edges_deferred_diffuse, shade_edges_deferred_specular;
    /// Step 3 for edge `slot` of the edge list (`msaa::EDGE_HEADER_WORDS` words, then pixels).
    fn shade_edges_deferred_impl<const SPECULAR: bool>(
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
        #[spirv(storage_buffer, descriptor_set = 0, binding = 7)] edges: &[u32],
    ) {
        let p = &crate::light_types::specialise(p, light_types);
        let slot = linear_index(wg, nwg, local);
        if slot >= edges[0] {
            return;
        }
        let i = edges[(msaa::EDGE_HEADER_WORDS + slot) as usize];
        // `move` over values: no pointer to this function's locals in the closure.
        let (effects, n, view) = (p.effects, p.num_lights, p.view);
        let shade = move |_: u32, surface: &shading::Surface| {
            let mut sum = Vec3::ZERO;
            shading::shade_lights::<SPECULAR, true, _>(surface, effects, n, lights, &shading::light_range(0, n), &mut sum);
            shading::shade_directional_lights::<SPECULAR>(surface, effects, n, lights, &mut sum);
            let pos = surface.pos;
            let touching = if view == VIEW_HEATMAP { lights_meeting(effects, n, lights, |_, _| {}, move |c, r| lighting::in_range(c, r, pos)) } else { 0 };
            (sum, touching)
        };
        frame[i as usize] = msaa::shade_edge_pixel(p, i, bounds, depth, normals, albedo, materials, shade);
    }
}
