//! G-buffer pass (vertex + fragment), the only raster work of the deferred pipelines.
//!
//! * Vertex pulling: positions, normals and uvs are flat `f32` storage buffers indexed by
//!   `VertexIndex` (the index buffer and `vertexOffset` of the draw give it), so the pipeline has
//!   no vertex-input state and one merged buffer set serves every mesh.
//! * Reversed-Z with an infinite far plane: stored depth `= near / d` (1 at the near plane, 0 at
//!   infinity; cleared to 0, test GREATER). Distances reconstruct as `near / depth`
//!   (`reconstruct::distance_from_depth`), with float precision where it matters (far away).
//! * Targets (each copied into its own storage buffer after the pass): `R32_UINT` view-space normal, octahedral at the draw's precision (2×8 / 2×12 /
//!   2×16 bit, `octahedral`); `RGBA8_UNORM` linear albedo with the material index in alpha
//!   (`index / 255`), whose specular/roughness the shading pass reads from a material buffer.
//!   8 + 4 bytes per pixel beside the 4-byte depth.
use crate::layout::{DrawParams, RasterCamera};
use crate::octahedral::{self, Precision};
use spirv_std::glam::{Mat4, Vec3, Vec4};
use spirv_std::spirv;

/// Reads element `i` of a flat `[x, y, z, x, y, z, …]` buffer.
#[inline]
pub fn fetch3(buf: &[f32], i: usize) -> Vec3 {
    Vec3::new(buf[3 * i], buf[3 * i + 1], buf[3 * i + 2])
}

/// View-space normal → G-buffer word. A zero or NaN normal encodes as +Z (facing the camera).
#[inline]
pub fn encode_gbuffer_normal(n_view: Vec3, precision: u32) -> u32 {
    octahedral::encode(n_view.to_array(), Precision::from_u32(precision))[0]
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
    let proj = Mat4::from_cols_array_2d(&camera.proj);
    let p_view = view * fetch3(positions, i).extend(1.0);
    *out_position = proj * p_view;
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
    // Two-sided surfaces: the normal faces the side being seen.
    let n = if front_facing { in_normal } else { -in_normal };
    *out_normal = encode_gbuffer_normal(n, draw.normal_precision);
    *out_albedo = Vec3::from_array(draw.albedo).extend(draw.material as f32 / 255.0);
}
