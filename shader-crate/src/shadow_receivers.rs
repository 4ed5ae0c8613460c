//! Which cube faces of each shadow-casting light have receivers on screen (Olsson et al., "More
//! Efficient Virtual Shadow Maps for Many Lights", i3D 2014, §4.1: only the faces the frame's
//! visible surfaces look up are rendered). A face no pixel of the frame looks up needs no
//! triangle: the batch cull (`shadow_cull`) sends batches only to faces with a level here, and
//! the atlas (`shadow_atlas`) gives each the resolution its receivers ask.
//!
//! Steps (host: `render/shadow_maps.rs`, before the cull):
//! 1. **Tiles** ([`shadow_receiver_tiles`], one invocation per tile of [`RECEIVER_TILE`]²
//!    pixels, [`tile_spheres`]): the boxes of the tile's surface points (the same
//!    `reconstruct::view_position` the shading uses) nearer and farther than their middle
//!    distance, as two spheres; none for background.
//! 2. **Faces** ([`shadow_receiver_faces`], one invocation per caster and run of
//!    [`TILES_PER_INVOCATION`] tiles, [`receiver_faces`]): each tile's sphere, widened by the
//!    lookup's normal offset ([`lookup_reach`]), through `shadow_cull::face_mask` against the
//!    caster (none where it lies outside a spot light's cone, `shadow::sphere_meets_widened_cone`, and only
//!    the faces the cone, widened by the lookup's offset, meets, [`spot_faces`]: a spot light
//!    takes only faces its cone lights, and its cube is turned to its cone,
//!    `shadow::CubeFrame`: one face for a cone of at most 42°, three up to 70°); each face met keeps the largest resolution level its
//!    receivers ask
//!    (`shadow_atlas::receiver_level`) in its word of `needed` (an atomic maximum; 0: none).
//!
//! **Conservative:** a pixel's lookup direction `pos + n·offset − light` lies within its tile's
//! widened sphere while its face has at least the side its tile asked (the atlas is not short),
//! and `face_mask` holds every face a point of the sphere within the light's radius lies in; a
//! pixel beyond the radius receives no light, so its face does not matter.
//!
//! **Memory:** 32 B per tile (8 160 tiles at 1080p: 261 KB), 4 B per caster face.
use crate::layout::ClusterGrid;
use crate::shadow::{cone_angle, sphere_meets_widened_cone, CubeFrame, CASTER_WORDS, CONE_MARGIN, FACES, NORMAL_OFFSET_TEXELS};
use crate::shadow_atlas::{face_side, receiver_level};
use crate::shadow_cull::{face_mask, CULL_MARGIN};
use glam::Vec3;
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;
#[cfg(feature = "compute")]
use spirv_std::spirv;

/// Tile edge in pixels.
pub const RECEIVER_TILE: u32 = 16;
/// Words per tile: two spheres' centre and radius (`f32`), radius −1 for none.
pub const TILE_WORDS: u32 = 8;
/// Tiles each invocation of step 2 tests against its caster.
pub const TILES_PER_INVOCATION: u32 = 32;
/// Invocations of a workgroup of either step.
pub const RECEIVER_WORKGROUP: u32 = 64;

/// Push constants of both steps.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ReceiverParams {
    pub grid: ClusterGrid,
    /// The largest face side (`--shadow-resolution`).
    pub res: u32,
    pub casters: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
}
const _: () = assert!(core::mem::size_of::<ReceiverParams>() == 80);

/// Step 1: the spheres around tile `(tx, ty)`'s surface points (`depth`: reversed-Z per pixel)
/// nearer and farther than the geometric middle of their distances (two layers: a column before
/// a wall is not one sphere across the gap), each `(centre, −1)` where it has none.
#[inline]
pub fn tile_spheres(p: &ReceiverParams, tx: u32, ty: u32, depth: &[f32]) -> [(Vec3, f32); 2] {
    let g = &p.grid;
    let y_end = if (ty + 1) * RECEIVER_TILE < g.height { (ty + 1) * RECEIVER_TILE } else { g.height };
    let x_end = if (tx + 1) * RECEIVER_TILE < g.width { (tx + 1) * RECEIVER_TILE } else { g.width };
    // Reversed Z: a larger value is nearer.
    let (mut z_lo, mut z_hi) = (f32::MAX, 0.0f32);
    let mut y = ty * RECEIVER_TILE;
    while y < y_end {
        let mut x = tx * RECEIVER_TILE;
        while x < x_end {
            let z = depth[(y * g.width + x) as usize];
            if !crate::reconstruct::is_background(z) {
                z_lo = z_lo.min(z);
                z_hi = z_hi.max(z);
            }
            x += 1;
        }
        y += 1;
    }
    // near / d is the depth value: the geometric middle of the distances is that of the values.
    let split = (z_lo * z_hi).sqrt();
    let (mut lo_near, mut hi_near) = (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
    let (mut lo_far, mut hi_far) = (lo_near, hi_near);
    y = ty * RECEIVER_TILE;
    while y < y_end {
        let mut x = tx * RECEIVER_TILE;
        while x < x_end {
            let z = depth[(y * g.width + x) as usize];
            if !crate::reconstruct::is_background(z) {
                let q = crate::reconstruct::view_position(g, x, y, crate::reconstruct::distance_from_depth(g.near, z));
                if z >= split {
                    lo_near = lo_near.min(q);
                    hi_near = hi_near.max(q);
                } else {
                    lo_far = lo_far.min(q);
                    hi_far = hi_far.max(q);
                }
            }
            x += 1;
        }
        y += 1;
    }
    [box_sphere(lo_near, hi_near), box_sphere(lo_far, hi_far)]
}

/// The sphere around a box (radius −1 for an empty one).
#[inline]
fn box_sphere(lo: Vec3, hi: Vec3) -> (Vec3, f32) {
    if lo.x <= hi.x {
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    } else {
        (Vec3::ZERO, -1.0)
    }
}

/// How far a lookup may land from a receiver at most `far` from the light on a face of `side`
/// texels: the normal offset of the bias rule (`shadow::cube_visibility`), plus a margin for
/// rounding.
#[inline]
pub fn lookup_reach(far: f32, side: u32) -> f32 {
    NORMAL_OFFSET_TEXELS * 2.0 * far / side as f32 + CULL_MARGIN * far
}

/// Bits per face of [`receiver_faces`]' levels.
pub const LEVEL_BITS: u32 = 4;

/// Level of face `f` in [`receiver_faces`]' packed levels (0: no receiver).
#[inline]
pub fn packed_level(levels: u32, f: u32) -> u32 {
    (levels >> (LEVEL_BITS * f)) & ((1 << LEVEL_BITS) - 1)
}

/// Step 2 for caster `c` and tiles `first..first + TILES_PER_INVOCATION`: the faces of the caster
/// any of those tiles' receivers look up, each with the largest level one of them asks
/// (`shadow_atlas::receiver_level`), packed [`LEVEL_BITS`] per face (face `f` at bit
/// `LEVEL_BITS · f`; 0: no receiver). A sphere is widened by the lookup's offset on a face of the
/// side its own level gives ([`lookup_reach`]): the face table gives each face at least that side
/// unless the atlas is short (`shadow::cube_visibility` then falls back to the receiver's face).
#[inline]
pub fn receiver_faces(p: &ReceiverParams, c: u32, first: u32, tiles: &[f32], casters: &[f32]) -> u32 {
    let k = (c * CASTER_WORDS) as usize;
    let (light, radius) = (Vec3::new(casters[k], casters[k + 1], casters[k + 2]), casters[k + 3]);
    let (axis, cos_outer) = (Vec3::new(casters[k + 4], casters[k + 5], casters[k + 6]), casters[k + 7]);
    let frame = CubeFrame::of_cone(axis, cos_outer);
    // The cone's half-angle once per caster and tile range (`None`: a point light).
    let angle = cone_angle(cos_outer);
    let local_axis = frame.local(axis);
    let n = p.tiles_x * p.tiles_y;
    let end = if first + TILES_PER_INVOCATION < n { first + TILES_PER_INVOCATION } else { n };
    let mut levels = 0;
    let mut t = 2 * first;
    while t < 2 * end {
        // Sphere `t` (two per tile).
        let w = (t * TILE_WORDS / 2) as usize;
        let r = tiles[w + 3];
        if r >= 0.0 {
            let centre = Vec3::new(tiles[w], tiles[w + 1], tiles[w + 2]);
            let d = centre - light;
            let far = d.length() + r;
            let g = &p.grid;
            let level = receiver_level(centre, r, light, g.near, g.height, g.tan_half_fov_y, p.res);
            let side = face_side(level, 0, p.res);
            let widened = r + lookup_reach(far, side);
            // The faces the light's cone allows: all for a point light; none for a receiver
            // outside a spot light's cone, which gets no light from it (the spot falloff ends at
            // the outer angle), so its faces need no texels.
            let cone = match angle {
                None => (1 << FACES) - 1,
                Some(a) if sphere_meets_widened_cone(d, widened, axis, a, far) => spot_faces(side, local_axis, a),
                Some(_) => 0,
            };
            let mask = if cone != 0 { face_mask(frame.local(d), widened, radius + CULL_MARGIN * far) & cone } else { 0 };
            let mut f = 0;
            while f < FACES {
                if mask & (1 << f) != 0 && packed_level(levels, f) < level {
                    levels = (levels & !(((1 << LEVEL_BITS) - 1) << (LEVEL_BITS * f))) | (level << (LEVEL_BITS * f));
                }
                f += 1;
            }
        }
        t += 1;
    }
    levels
}

/// The faces a receiver of a tile whose faces take `side` texels may look up through a spot
/// light's cone of unit `axis` (in the light's cube axes, `shadow::CubeFrame::local`) and outer
/// half-angle `angle` (`shadow::cone_angle`): [`cone_faces`] of the cone widened by the angle
/// the lookup's normal offset turns a direction. The offset is
/// [`NORMAL_OFFSET_TEXELS`] texels of `2ρ / side` at the receiver's distance `ρ` from the light
/// (`shadow::cube_visibility`, its own face having at least this side), so it turns the
/// direction by at most `asin(NORMAL_OFFSET_TEXELS · 2 / side)` whatever `ρ`. A point the spot
/// lights lies inside the cone; its lookup direction within that angle of it, so on one of
/// these faces.
#[inline]
pub fn spot_faces(side: u32, axis: Vec3, angle: f32) -> u32 {
    let s = NORMAL_OFFSET_TEXELS * 2.0 / side as f32;
    let widen = if s < 1.0 { s.asin() } else { core::f32::consts::PI };
    cone_faces(axis, angle + widen + CONE_MARGIN)
}

/// The faces (bit `f` for face `f`) whose pyramid meets the cone of unit `axis` and half-angle
/// `angle` (radians; all six from π on): face `f`
/// where the largest cosine between the axis and a direction of its pyramid ([`pyramid_cos`])
/// is at least `cos(angle)`.
#[inline]
pub fn cone_faces(axis: Vec3, angle: f32) -> u32 {
    if angle >= core::f32::consts::PI {
        return (1 << FACES) - 1;
    }
    let least = angle.cos();
    let mut mask = 0;
    let mut f = 0;
    while f < FACES {
        let (right, up, forward) = crate::shadow::face_axes(f);
        if pyramid_cos(Vec3::new(axis.dot(right), axis.dot(up), axis.dot(forward))) >= least {
            mask |= 1 << f;
        }
        f += 1;
    }
    mask
}

/// The largest `a · p` over unit directions `p` of the pyramid `|x| ≤ z, |y| ≤ z` for a unit
/// `a` (the cosine of the angle from `a` to the pyramid): 1 inside it, else the best of each
/// side's point nearest `a` (`a` projected on the side's plane, where that lands between the
/// side's edges: `|a'|`) and the four edges `(±1, ±1, 1)/√3`. A linear function's maximum on the
/// spherical square is inside it or on a side's arc, there at the projection or an end.
#[inline]
pub fn pyramid_cos(a: Vec3) -> f32 {
    if a.x.abs() <= a.z && a.y.abs() <= a.z {
        return 1.0;
    }
    let inv3 = 1.0 / 3.0f32.sqrt();
    let mut best = (a.x.abs() + a.y.abs() + a.z) * inv3;
    // Side x = s·z (s = ±1; the other coordinate free within ±z), then y = s·z.
    let mut k = 0;
    while k < 4 {
        let s = if k & 1 == 0 { 1.0 } else { -1.0 };
        let (along, other) = if k < 2 { (a.x, a.y) } else { (a.y, a.x) };
        // Projection onto the plane along = s·z: along and z both become (s·along + z) / 2.
        let z = 0.5 * (s * along + a.z);
        if z > 0.0 && other.abs() <= z {
            let c = (2.0 * z * z + other * other).sqrt();
            if c > best {
                best = c;
            }
        }
        k += 1;
    }
    best
}



/// `fetch_max` on a storage-buffer word: `OpAtomicUMax` (device scope, relaxed) on the GPU, a
/// plain maximum off it.
#[inline]
pub fn fetch_max(word: &mut u32, v: u32) -> u32 {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_u_max::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v)
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        let old = *word;
        *word = old.max(v);
        old
    }
}

/// Step 1: invocation = tile (linear, `tiles_x` per row).
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
pub fn shadow_receiver_tiles(
    #[spirv(global_invocation_id)] id: glam::UVec3,
    #[spirv(num_workgroups)] nwg: glam::UVec3,
    #[spirv(push_constant)] p: &ReceiverParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] depth: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] tiles: &mut [f32],
) {
    let t = id.y * nwg.x * RECEIVER_WORKGROUP + id.x;
    if t >= p.tiles_x * p.tiles_y {
        return;
    }
    let spheres = tile_spheres(p, t % p.tiles_x, t / p.tiles_x, depth);
    let w = (t * TILE_WORDS) as usize;
    let (near, far) = (spheres[0], spheres[1]);
    tiles[w] = near.0.x;
    tiles[w + 1] = near.0.y;
    tiles[w + 2] = near.0.z;
    tiles[w + 3] = near.1;
    tiles[w + 4] = far.0.x;
    tiles[w + 5] = far.0.y;
    tiles[w + 6] = far.0.z;
    tiles[w + 7] = far.1;
}

/// Step 2: invocation (run of tiles, caster) = (global x, workgroup y).
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
pub fn shadow_receiver_faces(
    #[spirv(global_invocation_id)] id: glam::UVec3,
    #[spirv(push_constant)] p: &ReceiverParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] tiles: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] casters: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] needed: &mut [u32],
) {
    let first = id.x * TILES_PER_INVOCATION;
    if first >= p.tiles_x * p.tiles_y || id.y >= p.casters {
        return;
    }
    let levels = receiver_faces(p, id.y, first, tiles, casters);
    let mut f = 0;
    while f < FACES {
        let level = packed_level(levels, f);
        if level != 0 {
            fetch_max(&mut needed[(id.y * FACES + f) as usize], level);
        }
        f += 1;
    }
}

/// Typed handles (host side).
#[cfg(not(target_arch = "spirv"))]
pub mod handles {
    use super::ReceiverParams;
    use crate::kernels::Kernel;

    /// Step 1: depth, tiles.
    pub const SHADOW_RECEIVER_TILES: Kernel<ReceiverParams> = Kernel::new("shadow_receivers::shadow_receiver_tiles", 2, [super::RECEIVER_WORKGROUP, 1, 1], false);
    /// Step 2: tiles, caster records, the faces' levels.
    pub const SHADOW_RECEIVER_FACES: Kernel<ReceiverParams> = Kernel::new("shadow_receivers::shadow_receiver_faces", 3, [super::RECEIVER_WORKGROUP, 1, 1], false);
}

#[cfg(test)]
#[path = "shadow_receivers_tests.rs"]
mod tests;
