//! The shadow atlas and its face table: each cube face of a shadow-casting light gets the
//! resolution its receivers need and a place in one shared atlas, every frame (Olsson et al.,
//! "More Efficient Virtual Shadow Maps for Many Lights", i3D 2014, §4.1–4.2: per-face resolution
//! from the projected size of the receivers, a physical pool shared by all lights). The
//! allocation unit is a whole face (no sparse pages inside a face).
//!
//! Steps (host: `render/shadow_maps.rs`):
//! 1. **Levels** (`shadow_receivers`, while it finds the faces with receivers): each receiver
//!    tile asks its faces for [`receiver_level`] — the power of two of texels per face side at
//!    which a texel at the face's centre spans at most `1 /` [`TEXELS_PER_PIXEL`] of the tile's
//!    nearest pixel — and each face keeps the largest asked (an atomic maximum; 0: no receiver).
//! 2. **Histogram** ([`shadow_face_levels`], an invocation per face): the faces counted per level.
//! 3. **Allocation** ([`shadow_face_alloc`], an invocation per face): every invocation finds the
//!    same [`atlas_shift`] from the histogram — the fewest halvings of every face's side that
//!    fit all faces in the atlas — and takes `side²` texels from the atlas's counter for its face;
//!    the face table holds `(first texel, side)` per face ([`crate::shadow::face_entry`]).
//!
//! **Bounded memory, nothing dropped.** The atlas holds [`MIN_SIDE`]² texels for every face of
//! every caster at least (the host sizes it so), so the shift always fits every face that has a
//! receiver: a frame whose faces ask for more than the atlas holds gets lower resolutions (the
//! shift, read back for `--stats` and a warning), never a face without texels.
//!
//! Level `k` stands for sides of `2^k` texels, capped at the requested largest side (which need
//! not be a power of two) and at least [`MIN_SIDE`] (or the cap, where smaller): [`face_side`].
//!
//! **Memory:** the atlas (4 B per texel), [`FACE_WORDS`](crate::shadow::FACE_WORDS) words per
//! face of the table, [`ARGS_LEVELS`]' counters.
#[cfg(feature = "compute")]
use crate::shadow::{FACE_WORDS, HEADER_TABLE};
use glam::Vec3;
#[cfg(feature = "compute")]
use spirv_std::spirv;

/// Texels across the footprint of one pixel that a face's resolution aims at (at the face's
/// centre; corner texels are smaller). Two keep the bias rule's offsets (1.5 and 1 texel,
/// `shadow`) and the bilinear filter's reach within about a pixel of the true shadow edge.
pub const TEXELS_PER_PIXEL: f32 = 2.0;
/// The smallest face side the atlas gives a face with receivers (where the cap allows).
pub const MIN_SIDE: u32 = 8;
/// Levels `0..LEVELS` (sides up to `2^(LEVELS − 1)` = 4096, `shadow_maps::MAX_RESOLUTION`).
pub const LEVELS: u32 = 13;
/// First word of the level histogram in the arguments (`shadow_cull::ARGS_WORDS`).
pub const ARGS_LEVELS: usize = 9;
/// Word of the arguments holding the frame's shift.
pub const ARGS_SHIFT: usize = ARGS_LEVELS + LEVELS as usize;
/// Word of the arguments holding the atlas's texels taken.
pub const ARGS_USED: usize = ARGS_SHIFT + 1;
/// Invocations of a workgroup of steps 2 and 3.
pub const ATLAS_WORKGROUP: u32 = 64;

/// Push constants of steps 2 and 3.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(not(target_arch = "spirv"), derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct AtlasParams {
    /// Faces in all (six per caster).
    pub faces: u32,
    /// The largest face side (`--shadow-resolution`).
    pub cap: u32,
    /// Texels of the atlas.
    pub texels: u32,
    pub pad: u32,
}
const _: () = assert!(core::mem::size_of::<AtlasParams>() == 16);

/// `⌈log2 x⌉` for `x ≥ 1` (0 below), at most `LEVELS − 1`.
#[inline]
pub fn level_of(x: f32) -> u32 {
    let mut k = 0;
    let mut side = 1.0;
    while side < x && k < LEVELS - 1 {
        side *= 2.0;
        k += 1;
    }
    k
}

/// The level of the smallest side that the cap `cap` needs at most (`⌈log2 cap⌉`).
#[inline]
pub fn cap_level(cap: u32) -> u32 {
    level_of(cap as f32)
}

/// Step 1: the level a receiver sphere (view-space `centre`, `radius`; the eye at the origin)
/// asks of a face of the light at `light`, for a frame of `height` pixels whose vertical field of
/// view has `tan(θ) = tan_half_fov_y`; at least 1 (a face with a receiver), at most the cap's.
///
/// A texel at the face's centre spans `2 · d / side` at distance `d` from the light; a pixel
/// spans `D · 2·tan θ / height` at distance `D` from the eye. The sphere's largest ratio `d / D`
/// is at most `(|centre − light| + radius) / max(|centre| − radius, near)`, so
/// `side ≥ TEXELS_PER_PIXEL · height · d / (D · tan θ)` holds for every point of it.
#[inline]
pub fn receiver_level(centre: Vec3, radius: f32, light: Vec3, near: f32, height: u32, tan_half_fov_y: f32, cap: u32) -> u32 {
    let d = (centre - light).length() + radius;
    let eye = centre.length() - radius;
    let eye = if eye > near { eye } else { near };
    let side = TEXELS_PER_PIXEL * height as f32 * d / (eye * tan_half_fov_y);
    let k = level_of(side);
    let top = cap_level(cap);
    let k = if k < top { k } else { top };
    if k < 1 {
        1
    } else {
        k
    }
}

/// Texels per side of a face of level `k` (≥ 1) after `shift` halvings: `2^(k − shift)` capped
/// at `cap`, at least [`MIN_SIDE`] (or `cap` where that is smaller).
#[inline]
pub fn face_side(k: u32, shift: u32, cap: u32) -> u32 {
    let side = if k > shift { 1u32 << (k - shift) } else { 1 };
    let side = if side < cap { side } else { cap };
    let floor = if MIN_SIDE < cap { MIN_SIDE } else { cap };
    if side > floor {
        side
    } else {
        floor
    }
}

/// Step 3's shift: the fewest halvings (at most `LEVELS − 1`) after which the faces counted per
/// level in `levels[ARGS_LEVELS..]` fit `texels`. The host's atlas holds every face at
/// [`MIN_SIDE`], which the largest shift reaches.
#[inline]
pub fn atlas_shift(args: &[u32], cap: u32, texels: u32) -> u32 {
    let mut shift = 0;
    while shift < LEVELS - 1 {
        let mut need = 0u64;
        let mut k = 1;
        while k < LEVELS {
            let side = face_side(k, shift, cap) as u64;
            need += args[ARGS_LEVELS + k as usize] as u64 * side * side;
            k += 1;
        }
        if need <= texels as u64 {
            return shift;
        }
        shift += 1;
    }
    shift
}

/// Step 3 for face `m`: its side and first texel (taken from `used`) into the face table at
/// `table` of `slots`; `(0, 0)` for a face without receivers.
#[cfg(feature = "compute")]
#[inline]
pub fn allocate_face<A: crate::light_lists::AtomicAdd + ?Sized>(m: u32, p: &AtlasParams, shift: u32, needed: &[u32], slots: &mut [u32], used: &mut A) {
    if m >= p.faces {
        return;
    }
    let k = needed[m as usize];
    let w = (slots[HEADER_TABLE] + m * FACE_WORDS) as usize;
    if k == 0 {
        slots[w] = 0;
        slots[w + 1] = 0;
    } else {
        let side = face_side(k, shift, p.cap);
        slots[w] = used.fetch_add(side * side);
        slots[w + 1] = side;
    }
}

/// Step 2: invocation = face (`caster · 6 + face`).
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
pub fn shadow_face_levels(
    #[spirv(global_invocation_id)] id: glam::UVec3,
    #[spirv(num_workgroups)] nwg: glam::UVec3,
    #[spirv(push_constant)] p: &AtlasParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] needed: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] args: &mut [u32],
) {
    let m = id.y * nwg.x * ATLAS_WORKGROUP + id.x;
    if m < p.faces && needed[m as usize] != 0 {
        let k = needed[m as usize] as usize;
        crate::light_lists::AtomicAdd::fetch_add(&mut args[ARGS_LEVELS + k], 1);
        crate::light_lists::AtomicAdd::fetch_add(&mut args[crate::shadow_cull::ARGS_FACES], 1);
    }
}

/// Step 3: invocation = face.
#[cfg(feature = "compute")]
#[spirv(compute(threads(64)))]
pub fn shadow_face_alloc(
    #[spirv(global_invocation_id)] id: glam::UVec3,
    #[spirv(num_workgroups)] nwg: glam::UVec3,
    #[spirv(push_constant)] p: &AtlasParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] needed: &[u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] args: &mut [u32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] slots: &mut [u32],
) {
    let m = id.y * nwg.x * ATLAS_WORKGROUP + id.x;
    let shift = atlas_shift(args, p.cap, p.texels);
    if m == 0 {
        args[ARGS_SHIFT] = shift;
    }
    allocate_face(m, p, shift, needed, slots, &mut args[ARGS_USED]);
}

/// Typed handles (host side).
#[cfg(not(target_arch = "spirv"))]
pub mod handles {
    use super::AtlasParams;
    use crate::kernels::Kernel;

    /// Step 2: needed levels, arguments.
    pub const SHADOW_FACE_LEVELS: Kernel<AtlasParams> = Kernel::new("shadow_atlas::shadow_face_levels", 2, [super::ATLAS_WORKGROUP, 1, 1], false);
    /// Step 3: needed levels, arguments, slots (the face table).
    pub const SHADOW_FACE_ALLOC: Kernel<AtlasParams> = Kernel::new("shadow_atlas::shadow_face_alloc", 3, [super::ATLAS_WORKGROUP, 1, 1], false);
}

#[cfg(test)]
#[path = "shadow_atlas_tests.rs"]
mod tests;
