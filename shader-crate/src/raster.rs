//! G-buffer pass (vertex + fragment), the only raster work of the deferred pipelines.
//!
//! * Vertex pulling: positions, normals and uvs are flat `f32` storage buffers indexed by
//!   `VertexIndex` (the index buffer and `vertexOffset` of the draw give it), so the pipeline has
//!   no vertex-input state and one merged buffer set serves every mesh.
//! * Reversed-Z with an infinite far plane: stored depth `= near / d` (1 at the near plane, 0 at
//!   infinity; cleared to 0, test GREATER). Distances reconstruct as `near / depth`
//!   (`reconstruct::distance_from_depth`), with float precision where it matters (far away).
//! * Targets (each copied into its own storage buffer after the pass): the view-space normal at
//!   the draw's precision (`octahedral`): `R32_UINT` holding a 2×8 / 2×12 / 2×16-bit octahedral
//!   code, or `R32G32B32A32_UINT` holding three float32 bit patterns (the `_f32` fragment
//!   variants, the accuracy study's lossless reference); `RGBA8_UNORM` linear albedo with the
//!   material index in alpha (`index / 255`), whose specular/roughness the shading pass reads
//!   from a material buffer. 4 (or 16) + 4 bytes per pixel beside the 4-byte depth, each once
//!   as a target and once as a buffer.
use crate::layout::{DrawParams, RasterCamera};
use crate::msaa::float_normal;
use crate::octahedral::{self, Precision};
use spirv_std::glam::{Mat4, UVec4, Vec2, Vec3, Vec4};
use spirv_std::image::SampledImage;
use spirv_std::Image;
use spirv_std::spirv;

/// Reads element `i` of a flat `[x, y, z, x, y, z, …]` buffer.
#[inline]
pub fn fetch3(buf: &[f32], i: usize) -> Vec3 {
    Vec3::new(buf[3 * i], buf[3 * i + 1], buf[3 * i + 2])
}

/// View-space normal → G-buffer words (word 0 alone for the octahedral precisions). A zero or
/// NaN normal encodes as +Z (facing the camera).
#[inline]
pub fn encode_gbuffer_normal(n_view: Vec3, precision: u32) -> [u32; 3] {
    octahedral::encode(n_view.to_array(), Precision::from_u32(precision))
}

/// A combined image sampler of 2D float colour data.
pub type Texture2d = SampledImage<Image!(2D, type = f32, sampled)>;

/// Samples a texture that is the same for every invocation of the draw (bound per draw with
/// push descriptors). spirv-std's `sample` decorates its operands `NonUniform`, which needs the
/// `ShaderNonUniform` capability lavapipe lacks; a draw-uniform texture needs no such thing.
#[cfg(target_arch = "spirv")]
#[inline]
pub fn sample_draw_uniform(texture: &Texture2d, uv: Vec2) -> Vec4 {
    let mut result = Vec4::ZERO;
    // SAFETY: one OpImageSampleImplicitLod on a valid combined image sampler, in a fragment shader.
    unsafe {
        core::arch::asm!(
            "%sampled = OpLoad typeof*{1} {1}",
            "%coord = OpLoad typeof*{2} {2}",
            "%result = OpImageSampleImplicitLod typeof*{0} %sampled %coord",
            "OpStore {0} %result",
            in(reg) &mut result,
            in(reg) texture,
            in(reg) &uv,
        );
    }
    result
}

/// Off the GPU there is no texture unit: the CPU references never rasterise.
#[cfg(not(target_arch = "spirv"))]
pub fn sample_draw_uniform(_texture: &Texture2d, _uv: Vec2) -> Vec4 {
    unimplemented!("texture sampling runs on the GPU only")
}

/// Alpha-mask coverage below which a fragment is cut out.
pub const ALPHA_CUTOFF: f32 = 0.5;

/// Clip-space position of vertex `i`: `proj · (view · p)`. The one definition every vertex shader
/// uses, so a depth pre-pass and a later pass produce the same depths (Forward+ tests EQUAL).
#[inline]
pub fn clip_position(positions: &[f32], camera: &RasterCamera, i: usize) -> Vec4 {
    let view = Mat4::from_cols_array_2d(&camera.view);
    let proj = Mat4::from_cols_array_2d(&camera.proj);
    proj * (view * fetch3(positions, i).extend(1.0))
}

#[spirv(vertex)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_vs(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] uvs: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] camera: &RasterCamera,
    #[spirv(position)] out_position: &mut Vec4,
    out_normal: &mut Vec3,
) {
    let i = vertex_index as usize;
    let view = Mat4::from_cols_array_2d(&camera.view);
    *out_position = clip_position(positions, camera, i);
    *out_normal = (view * fetch3(normals, i).extend(0.0)).truncate();
    // uvs (binding 2) are bound for the textured variant; the untextured one reads none.
    let _ = uvs;
}

#[spirv(fragment)]
pub fn gbuffer_fs(
    in_normal: Vec3,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    out_normal: &mut u32,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, Vec3::ONE, draw);
    (*out_normal, *out_albedo) = (n[0], a);
}

/// [`gbuffer_fs`] writing a float32 normal (`R32G32B32A32_UINT` target).
#[spirv(fragment)]
pub fn gbuffer_fs_f32(
    in_normal: Vec3,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    out_normal: &mut UVec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, Vec3::ONE, draw);
    (*out_normal, *out_albedo) = (wide_normal(n), a);
}

/// [`gbuffer_fs`] for the multisampled G-buffer (`--msaa`): the normal as `crate::msaa::float_normal`
/// (an `RGBA32_SFLOAT` target at any precision).
#[spirv(fragment)]
pub fn gbuffer_fs_ms(
    in_normal: Vec3,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    out_normal: &mut Vec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, Vec3::ONE, draw);
    (*out_normal, *out_albedo) = (float_normal(n, draw.normal_precision), a);
}

/// [`gbuffer_fs_textured`] for the multisampled G-buffer.
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_textured_ms(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    out_normal: &mut Vec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, sample_draw_uniform(albedo_map, in_uv).truncate(), draw);
    (*out_normal, *out_albedo) = (float_normal(n, draw.normal_precision), a);
}

/// [`gbuffer_fs_masked`] for the multisampled G-buffer.
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_masked_ms(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    #[spirv(descriptor_set = 0, binding = 5)] mask_map: &Texture2d,
    out_normal: &mut Vec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, masked_texel(albedo_map, mask_map, in_uv), draw);
    (*out_normal, *out_albedo) = (float_normal(n, draw.normal_precision), a);
}

/// The G-buffer values every fragment variant writes: the normal facing the viewed side,
/// encoded at the draw's precision; albedo = material colour × `texel`, with the material index
/// in alpha.
#[inline]
pub fn targets(in_normal: Vec3, front_facing: bool, texel: Vec3, draw: &DrawParams) -> ([u32; 3], Vec4) {
    // Two-sided surfaces: the normal faces the side being seen.
    let n = if front_facing { in_normal } else { -in_normal };
    // Quantised here, exactly (round to nearest): the UNORM8 target then stores `k/255`, which
    // every rounding mode Vulkan allows converts back to `k`, so Forward+ (which computes the same
    // `unorm8`) sees the albedo the deferred passes read, on any driver.
    let a = Vec3::from_array(draw.albedo) * texel;
    (encode_gbuffer_normal(n, draw.normal_precision), Vec4::new(unorm8(a.x), unorm8(a.y), unorm8(a.z), draw.material as f32 / 255.0))
}

/// The four words of the float32 normal target.
#[inline]
pub fn wide_normal(w: [u32; 3]) -> UVec4 {
    UVec4::new(w[0], w[1], w[2], 0)
}

/// A channel as the `UNORM8` G-buffer stores and the shading passes decode it: clamped to
/// [0, 1], rounded to the nearest `k/255`.
#[inline]
pub fn unorm8(x: f32) -> f32 {
    let c = if x > 0.0 {
        if x < 1.0 {
            x
        } else {
            1.0
        }
    } else {
        0.0
    };
    ((c * 255.0 + 0.5) as u32) as f32 * (1.0 / 255.0)
}

/// The vertex shader of textured draws: as [`gbuffer_vs`] plus the texture coordinate.
#[spirv(vertex)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_vs_uv(
    #[spirv(vertex_index)] vertex_index: i32,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] positions: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] normals: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] uvs: &[f32],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] camera: &RasterCamera,
    #[spirv(position)] out_position: &mut Vec4,
    out_normal: &mut Vec3,
    out_uv: &mut Vec2,
) {
    gbuffer_vs(vertex_index, positions, normals, uvs, camera, out_position, out_normal);
    let i = vertex_index as usize;
    *out_uv = Vec2::new(uvs[2 * i], uvs[2 * i + 1]);
}

/// Textured draws: albedo = material colour × texture (sRGB image: sampled as linear).
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_textured(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    out_normal: &mut u32,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, sample_draw_uniform(albedo_map, in_uv).truncate(), draw);
    (*out_normal, *out_albedo) = (n[0], a);
}

/// [`gbuffer_fs_textured`] writing a float32 normal.
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_textured_f32(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    out_normal: &mut UVec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, sample_draw_uniform(albedo_map, in_uv).truncate(), draw);
    (*out_normal, *out_albedo) = (wide_normal(n), a);
}

/// Alpha-tested textured draws (Sponza's foliage and chains): fragments whose mask coverage is
/// below [`ALPHA_CUTOFF`] are demoted to helpers, so they write neither depth nor targets.
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_masked(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    #[spirv(descriptor_set = 0, binding = 5)] mask_map: &Texture2d,
    out_normal: &mut u32,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, masked_texel(albedo_map, mask_map, in_uv), draw);
    (*out_normal, *out_albedo) = (n[0], a);
}

/// [`gbuffer_fs_masked`] writing a float32 normal.
#[spirv(fragment)]
#[allow(clippy::too_many_arguments)]
pub fn gbuffer_fs_masked_f32(
    in_normal: Vec3,
    in_uv: Vec2,
    #[spirv(front_facing)] front_facing: bool,
    #[spirv(push_constant)] draw: &DrawParams,
    #[spirv(descriptor_set = 0, binding = 4)] albedo_map: &Texture2d,
    #[spirv(descriptor_set = 0, binding = 5)] mask_map: &Texture2d,
    out_normal: &mut UVec4,
    out_albedo: &mut Vec4,
) {
    let (n, a) = targets(in_normal, front_facing, masked_texel(albedo_map, mask_map, in_uv), draw);
    (*out_normal, *out_albedo) = (wide_normal(n), a);
}

/// The albedo texel of an alpha-tested fragment; fragments whose mask coverage is below
/// [`ALPHA_CUTOFF`] are demoted to helpers first.
#[inline]
fn masked_texel(albedo_map: &Texture2d, mask_map: &Texture2d, uv: Vec2) -> Vec3 {
    if sample_draw_uniform(mask_map, uv).x < ALPHA_CUTOFF {
        spirv_std::arch::demote_to_helper_invocation();
    }
    sample_draw_uniform(albedo_map, uv).truncate()
}
