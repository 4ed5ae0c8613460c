//! Per-face culling of the shadow maps' draws (Olsson et al., "More Efficient Virtual Shadow
//! Maps for Many Lights", i3D 2014, §4.3 batches and per-face culling): the scene's opaque
//! triangles go in **batches** of [`BATCH_TRIANGLES`] consecutive ones, each bounded by a sphere;
//! a batch is drawn into a face of a caster's cube map only where its sphere meets that face's
//! pyramid within the light's radius ([`face_mask`]). A scene whose lights each reach a small part
//! of it rasterises that part per face, not the whole scene six times per caster.
//!
//! Steps (host: `render/shadow_maps.rs`; the maps themselves: `shadow`):
//! 1. **Cull** ([`shadow_cull`], one invocation per batch and caster, [`cull_batch`]): the batch's
//!    sphere moved into view space, tested against the caster's six faces (in its cube's axes,
//!    `shadow::CubeFrame`); each face it meets that has receivers on screen
//!    (`shadow_receivers`, run before; its side in the face table) takes an entry
//!    `(batch, map)` (`map = caster · 6 + face`) from a counter — for a spot light only where
//!    the sphere also meets the cone widened by the texels a lookup on that face can read
//!    ([`batch_meets_cone`]: occluders outside it shadow nothing the spot lights). Entries past
//!    the capacity are counted and not written.
//! 2. **Arguments** ([`shadow_draw_args`], one invocation, [`draw_args`]): the indirect draw's
//!    vertex count, `3 ·` [`BATCH_TRIANGLES`] per written entry.
//! 3. **Raster**, in a compute kernel (`shadow_raster`, `--shadow-raster compute`) or drawn
//!    (`--shadow-raster draw`: [`shadow_batch_vs`] + `shadow::shadow_distance_fs`): vertex `v` is corner
//!    `v % 3` of triangle `(v / 3) % BATCH_TRIANGLES` of entry `v / (3 · BATCH_TRIANGLES)`,
//!    pulled from the index and position buffers ([`batch_vertex`]); a batch's missing tail
//!    triangles, and triangles that cannot draw into the face ([`triangle_outside`]: beyond the
//!    radius, or outside a side plane of the face), are put behind the light (`w < 0`: clipped
//!    whole, never set up).
//!
//! **Capacity.** The host counts the entries with the same [`face_mask`] (without the cone test:
//! an upper bound) on spheres widened by [`CULL_MARGIN`] of their distance (`shadow_maps::ShadowMaps`), so rounding on the GPU cannot
//! add an entry the count left out; the frame loop still reads the counter back and fails
//! rather than drop triangles.
//!
//! **Memory:** [`BATCH_WORDS`]` · 4` = 32 B per batch (0.5 B per triangle), [`ENTRY_WORDS`]` · 4`
//! = 8 B per entry, [`ARGS_WORDS`]` · 4` B of arguments.
use crate::shadow::{face_axes, face_clip, CubeFrame, FACES};
use glam::{Mat4, Vec3, Vec4};
#[cfg(any(feature = "compute", feature = "graphics"))]
use spirv_std::spirv;

/// Triangles per batch (consecutive in a draw's indices; a draw's last batch may hold fewer).
pub const BATCH_TRIANGLES: u32 = 64;
/// Words of a batch: bounding-sphere centre (x, y, z) and radius as `f32` bits, its first index,
/// its triangle count, two words of padding.
pub const BATCH_WORDS: u32 = 8;
/// Words of an entry: batch, map (`caster · 6 + face`).
pub const ENTRY_WORDS: u32 = 2;
/// Words of the arguments: a `VkDrawIndirectCommand` (vertex count, instance count, first
/// vertex, first instance), the entries the cull counted ([`ARGS_COUNTED`]), then a
/// `VkDispatchIndirectCommand` of one workgroup per written entry ([`ARGS_DISPATCH`], for
/// `shadow_raster`), the faces with receivers ([`ARGS_FACES`]), the atlas's level histogram,
/// shift and texels taken (`shadow_atlas::ARGS_LEVELS`, `ARGS_SHIFT`, `ARGS_USED`).
pub const ARGS_WORDS: u32 = crate::shadow_atlas::ARGS_USED as u32 + 1;
/// Word of the arguments that counts entries (written or not).
pub const ARGS_COUNTED: usize = 4;
/// First word of the compute raster's dispatch arguments.
pub const ARGS_DISPATCH: u32 = 5;
/// Word of the arguments that counts the casters' faces with receivers (`shadow_atlas`).
pub const ARGS_FACES: usize = 8;
/// Invocations of a cull workgroup (batches along x, casters along y).
pub const CULL_WORKGROUP: u32 = 64;
/// The host's widening of a batch's sphere when it sizes the entries, relative to the sphere's
/// distance from the light plus both radii (module docs: above the GPU's rounding by orders).
pub const CULL_MARGIN: f32 = 1e-4;

/// The faces (bit `f` for face `f`) of a light of `light_radius` whose pyramid the sphere of
/// radius `r` at offset `d` from the light meets: none where the sphere lies beyond the light's
/// radius, all six where it holds the light, else each face whose four side planes (through the
/// light, `w = ±x` and `w = ±y` in the face's frame) leave the sphere on their inner side or
/// crossing them. Conservative: a sphere near a pyramid's edge, outside it, may pass.
#[inline]
pub fn face_mask(d: Vec3, r: f32, light_radius: f32) -> u32 {
    let dist2 = d.length_squared();
    let reach = r + light_radius;
    if dist2 > reach * reach {
        return 0;
    }
    if dist2 <= r * r {
        return (1 << FACES) - 1;
    }
    // A side plane's unit normal is (forward ∓ right) / √2: the sphere meets its inner side
    // where (w ∓ x) / √2 ≥ −r.
    let slack = r * core::f32::consts::SQRT_2;
    let mut mask = 0;
    let mut f = 0;
    while f < FACES {
        let (right, up, forward) = face_axes(f);
        let (w, x, y) = (d.dot(forward), d.dot(right), d.dot(up));
        if w - x >= -slack && w + x >= -slack && w - y >= -slack && w + y >= -slack {
            mask |= 1 << f;
        }
        f += 1;
    }
    mask
}

/// Push constants of the cull: batches, casters, entries the buffer holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ShadowCullParams {
    pub batches: u32,
    pub casters: u32,
    pub capacity: u32,
    pub pad: u32,
}
const _: () = assert!(core::mem::size_of::<ShadowCullParams>() == 16);

/// A batch's bounding sphere (the space of the position buffer) and radius.
#[inline]
pub fn batch_sphere(batches: &[u32], b: u32) -> (Vec3, f32) {
    let w = (b * BATCH_WORDS) as usize;
    (Vec3::new(f32::from_bits(batches[w]), f32::from_bits(batches[w + 1]), f32::from_bits(batches[w + 2])), f32::from_bits(batches[w + 3]))
}

/// Texels a lookup can read away from its receiver's own direction: the normal offset
/// (`shadow::NORMAL_OFFSET_TEXELS`, 1.5), the bilinear filter's neighbour (1) and half a texel
/// from the lookup point to a texel's centre.
pub const LOOKUP_SPREAD_TEXELS: f32 = 3.0;

/// Whether a batch's sphere (offset `d` from a spot light of `radius`, sphere radius `r`) may
/// hold an occluder that a receiver inside the cone (unit `axis`, outer half-angle `angle`,
/// `shadow::cone_angle`) looks up on a face of `side` texels: a point the spot lights lies in
/// its cone, the segment to it too, and its lookup reads texels at most
/// [`LOOKUP_SPREAD_TEXELS`] texels of angle (each at most `2 / side` radians) away; so the cone
/// widened by that angle (`shadow::sphere_meets_widened_cone`) holds every occluder a lookup can
/// see. Always for a point light (`angle` `None`).
#[inline]
pub fn batch_meets_cone(d: Vec3, r: f32, radius: f32, axis: Vec3, angle: Option<f32>, side: u32) -> bool {
    match angle {
        Some(a) => crate::shadow::sphere_meets_widened_cone(d, r, axis, a + 2.0 * LOOKUP_SPREAD_TEXELS / side as f32, radius),
        None => true,
    }
}

/// Step 1 for batch `b` and caster `c` (`casters`: caster records, `shadow::caster_record`;
/// `view`: the position buffer's space → view space, a rotation; `slots`: the face table,
/// `shadow::face_entry`, side 0 for a face without receivers): appends an entry per face met
/// that has receivers (for a spot light, only where the batch meets its cone widened by the
/// lookup's spread on that face, [`batch_meets_cone`]).
#[cfg(feature = "compute")]
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn cull_batch<A: crate::light_lists::AtomicAdd + ?Sized>(b: u32, c: u32, p: &ShadowCullParams, view: Mat4, batches: &[u32], casters: &[f32], slots: &[u32], entries: &mut [u32], counted: &mut A) {
    if b >= p.batches || c >= p.casters {
        return;
    }
    let (centre, r) = batch_sphere(batches, b);
    let k = (c * crate::shadow::CASTER_WORDS) as usize;
    let light = Vec3::new(casters[k], casters[k + 1], casters[k + 2]);
    let (axis, cos_outer) = (Vec3::new(casters[k + 4], casters[k + 5], casters[k + 6]), casters[k + 7]);
    let offset = (view * centre.extend(1.0)).truncate() - light;
    let mask = face_mask(CubeFrame::of_cone(axis, cos_outer).local(offset), r, casters[k + 3]);
    // The cone's half-angle once per batch and caster, its widening per face.
    let angle = crate::shadow::cone_angle(cos_outer);
    let mut f = 0;
    while f < FACES {
        let side = crate::shadow::face_entry(slots, c * FACES + f).1;
        if mask & (1 << f) != 0 && side != 0 && batch_meets_cone(offset, r, casters[k + 3], axis, angle, side) {
            let slot = counted.fetch_add(1);
            if slot < p.capacity {
                entries[(slot * ENTRY_WORDS) as usize] = b;
                entries[(slot * ENTRY_WORDS + 1) as usize] = c * FACES + f;
            }
        }
        f += 1;
    }
}

/// Step 2: the indirect draw of the entries written (at most `capacity`), and the compute
/// raster's dispatch of one workgroup per written entry (`indirect::dispatch_args`' grid).
#[inline]
pub fn draw_args(args: &mut [u32], capacity: u32) {
    let written = if args[ARGS_COUNTED] < capacity { args[ARGS_COUNTED] } else { capacity };
    args[0] = written * 3 * BATCH_TRIANGLES;
    args[1] = 1;
    args[2] = 0;
    args[3] = 0;
    let groups = crate::indirect::dispatch_args(written, 1);
    let d = ARGS_DISPATCH as usize;
    args[d] = groups[0];
    args[d + 1] = groups[1];
    args[d + 2] = groups[2];
}

/// Whether the triangle with corners at offsets `d0, d1, d2` from a light of `radius` can draw
/// nothing into face `f`: its plane passes farther than the radius from the light, or all three
/// corners lie outside one of the face pyramid's side planes (the clipper would remove it whole).
/// Conservative: a kept triangle may still draw nothing.
#[inline]
pub fn triangle_outside(d0: Vec3, d1: Vec3, d2: Vec3, f: u32, radius: f32) -> bool {
    let n = (d1 - d0).cross(d2 - d0);
    let n2 = n.length_squared();
    // Plane distance above the radius, with a margin for rounding (a degenerate triangle, n = 0,
    // draws nothing either way and is kept).
    let reach = radius * PLANE_MARGIN;
    if n2 > 0.0 && n.dot(d0) * n.dot(d0) > reach * reach * n2 {
        return true;
    }
    let (right, up, forward) = face_axes(f);
    let (w, x, y) = (Vec3::new(d0.dot(forward), d1.dot(forward), d2.dot(forward)), Vec3::new(d0.dot(right), d1.dot(right), d2.dot(right)), Vec3::new(d0.dot(up), d1.dot(up), d2.dot(up)));
    all_negative(w - x) || all_negative(w + x) || all_negative(w - y) || all_negative(w + y)
}

/// Whether all three components are below 0 (three corners outside one plane).
#[inline]
fn all_negative(s: Vec3) -> bool {
    s.x < 0.0 && s.y < 0.0 && s.z < 0.0
}

/// Offset from `light` of the vertex at index slot `slot`, in the cube's axes `frame`. (A
/// function, not a closure over the buffers: rust-gpu rejects closures that capture
/// storage-buffer slices.)
#[inline]
fn corner_offset(positions: &[f32], indices: &[u32], slot: usize, view: Mat4, light: Vec3, frame: &CubeFrame) -> Vec3 {
    let i = 3 * indices[slot] as usize;
    frame.local((view * Vec4::new(positions[i], positions[i + 1], positions[i + 2], 1.0)).truncate() - light)
}

/// The corners of the triangle whose indices start at slot `first` as offsets from caster `c`
/// (its record in `casters`), in its cube's axes ([`CubeFrame::of_caster`]): what the cull, the
/// draw and the compute raster place on its faces.
#[inline]
pub(crate) fn triangle_offsets(positions: &[f32], indices: &[u32], first: usize, view: Mat4, casters: &[f32], c: u32) -> (Vec3, Vec3, Vec3) {
    let k = (c * crate::shadow::CASTER_WORDS) as usize;
    let light = Vec3::new(casters[k], casters[k + 1], casters[k + 2]);
    let frame = CubeFrame::of_caster(casters, c);
    (corner_offset(positions, indices, first, view, light, &frame), corner_offset(positions, indices, first + 1, view, light, &frame), corner_offset(positions, indices, first + 2, view, light, &frame))
}

/// The plane-distance test's radius is widened by this factor (rounding of the cross product).
pub const PLANE_MARGIN: f32 = 1.001;

/// Step 3: the clip position, offset from the light, map and light radius of vertex `v`. Each
/// corner fetches its whole triangle and tests it ([`triangle_outside`]), so all three agree
/// and a triangle that cannot draw into the face is put behind the light (`w < 0`, clipped
/// whole) before the rasteriser sets it up: a batch's sphere bounds it coarsely.
#[inline]
pub fn batch_vertex(v: u32, positions: &[f32], indices: &[u32], view: Mat4, casters: &[f32], batches: &[u32], entries: &[u32]) -> (Vec4, Vec3, u32, f32) {
    let per_entry = 3 * BATCH_TRIANGLES;
    let (e, k) = (v / per_entry, v % per_entry);
    let (b, map) = (entries[(e * ENTRY_WORDS) as usize], entries[(e * ENTRY_WORDS + 1) as usize]);
    let w = (b * BATCH_WORDS) as usize;
    let c = (map / FACES * crate::shadow::CASTER_WORDS) as usize;
    let behind = (Vec4::new(0.0, 0.0, 0.0, -1.0), Vec3::ZERO, map, 0.0);
    if k / 3 >= batches[w + 5] {
        // Past the batch's last triangle.
        return behind;
    }
    let radius = casters[c + 3];
    let first = (batches[w + 4] + k - k % 3) as usize;
    let (d0, d1, d2) = triangle_offsets(positions, indices, first, view, casters, map / FACES);
    if triangle_outside(d0, d1, d2, map % FACES, radius) {
        return behind;
    }
    let d = match k % 3 {
        0 => d0,
        1 => d1,
        _ => d2,
    };
    (face_clip(d, map % FACES), d, map, radius)
}

/// Step 1: invocation (batch, caster) = (global x, workgroup y).
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
#[allow(clippy::too_many_arguments)]
pub fn shadow_cull(
    #[spirv(global_invocation_id)] id: glam::UVec3,
    #[spirv(push_constant)] p: &ShadowCullParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] camera: &crate::layout::RasterCamera,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] batches: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] casters: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] entries: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] args: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] slots: &[u32],
) {
    cull_batch(id.x, id.y, p, Mat4::from_cols_array_2d(&camera.view), batches, casters, slots, entries, &mut args[ARGS_COUNTED]);
}

/// Step 2: one invocation.
#[cfg(feature = "compute")]
#[spirv(compute(threads(1)))]
pub fn shadow_draw_args(#[spirv(push_constant)] p: &ShadowCullParams, #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] args: &mut [u32]) {
    draw_args(args, p.capacity);
}

/// Step 3, vertex stage: [`batch_vertex`], moved into the corner of the render area its face's
/// side takes (`shadow::face_area_clip`).
#[cfg(feature = "graphics")]
#[spirv(vertex)]
#[allow(clippy::too_many_arguments)]
pub fn shadow_batch_vs(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(push_constant)] p: &crate::shadow::ShadowParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] indices: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] camera: &crate::layout::RasterCamera,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] casters: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] batches: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 5)] entries: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 6)] slots: &[u32],
    #[spirv(position)] out_position: &mut Vec4,
    out_offset: &mut Vec3,
    #[spirv(flat)] out_base: &mut u32,
    #[spirv(flat)] out_res: &mut u32,
    #[spirv(flat)] out_radius: &mut f32,
) {
    let (clip, d, map, radius) = batch_vertex(vertex_index as u32, positions, indices, Mat4::from_cols_array_2d(&camera.view), casters, batches, entries);
    let (base, res) = crate::shadow::face_entry(slots, map);
    *out_position = crate::shadow::face_area_clip(clip, res, p.res);
    *out_offset = d;
    *out_base = base;
    *out_res = res;
    *out_radius = radius;
}

/// Typed handles (host side).
#[cfg(not(target_arch = "spirv"))]
pub mod handles {
    use super::ShadowCullParams;
    use crate::kernels::{Kernel, RasterKernel};
    use crate::shadow::ShadowParams;

    /// Step 1: camera, batches, caster records, entries, arguments, slots (the face table).
    pub const SHADOW_CULL: Kernel<ShadowCullParams> = Kernel::new("shadow_cull::shadow_cull", 6, [super::CULL_WORKGROUP, 1, 1], false);
    /// Step 2: arguments.
    pub const SHADOW_DRAW_ARGS: Kernel<ShadowCullParams> = Kernel::new("shadow_cull::shadow_draw_args", 1, [1, 1, 1], false);
    /// Step 3: positions, indices, camera, caster records, batches, entries, slots (vertex
    /// stage); the atlas (fragment stage).
    pub const SHADOW_BATCHES: RasterKernel<ShadowParams> = RasterKernel::with_vertex_buffers("shadow_cull::shadow_batch_vs", "shadow::shadow_distance_fs", 7, 1, 0);
}

#[cfg(test)]
#[path = "shadow_cull_tests.rs"]
pub(crate) mod tests;
