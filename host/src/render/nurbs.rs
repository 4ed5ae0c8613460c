//! The NURBS tessellation pass: a scene's rational B-spline patches become triangles on the GPU
//! every frame, in the same vertex streams and index buffer as the meshes, so that every raster
//! pass (the G-buffer, Forward+'s depth and forward passes, the transparent pass) draws them as
//! ordinary draws with their material.
//!
//! Steps:
//! 1. **Packing** (host, once per render: [`upload_geometry`]): the patches are packed after the
//!    meshes' vertices and indices (`scene::nurbs::NurbsBuffers::push_relative`): a 48 B header
//!    per patch, the knots, and the control points as homogeneous points with premultiplied
//!    weights **relative to the camera**, `(w·(x − c), w)` in f64, rounded to f32 — the renderer
//!    draws camera-relative (`camera_relative.rs`), and translating the Cartesian control points
//!    translates a rational surface exactly. The geometry buffers are allocated with room for the
//!    grids (storage buffers; the index buffer is both), and each patch gets a draw of its index
//!    range.
//! 2. **Vertices** (compute, `shaders::tessellation::nurbs_vertices`): one invocation per grid
//!    vertex of every patch evaluates the surface and its normal at the vertex's parameters and
//!    writes position, normal and uv at the patch's `vertex_offset`.
//! 3. **Indices** (compute, `shaders::tessellation::nurbs_indices`): one invocation per quad
//!    writes its two counter-clockwise triangles, offset by the patch's first vertex, at the
//!    patch's `index_offset`.
//! 4. **Barrier**: the kernels' writes become visible to the vertex stage's storage reads and to
//!    index reads (`Recorder::draws_read_kernel_writes`), before the G-buffer pass.
//!
//! **Adaptive levels** (`render --tess-error PIXELS`, [`SceneInput::nurbs_tolerance`]): each
//! patch's slot holds its grid at [`ADAPTIVE_MAX_LEVEL`]; before step 2 a kernel
//! (`shaders::tessellation::nurbs_levels`, one invocation per patch) picks the level at which
//! the grid stays within the tolerance on screen from the patch's second-derivative control
//! points and its distance, writes it into the patch's header (steps 2–3 then fill only that
//! grid) and writes the patch's `VkDrawIndexedIndirectCommand`; the G-buffer draws the patches
//! indirectly (`Draw::indirect`). Forward+ (which reverses a CPU copy of the indices) and
//! transparent patches (the transparent pass draws index ranges) refuse adaptive levels.
//!
//! References: L. Piegl & W. Tiller, *The NURBS Book*, 2nd ed. (1997): A2.1 FindSpan, A2.2
//! BasisFuns, A2.3 DersBasisFuns, A3.6 SurfaceDerivsAlg1 on homogeneous points, A4.3/A4.4
//! rational surface points and derivatives (`shaders::nurbs` has where each one lives); the
//! compute-shader formulation of NURBS tessellation (one surface point per GPU thread, fixed-size
//! basis arrays, no recursion: the grids are written straight into the draw's buffers, no
//! tessellator stage).
//!
//! Forward+ draws the merged index list in reverse from a CPU copy (`FrameInputs::indices`); its
//! NURBS part comes from `shaders::tessellation::quad_indices`, the function the index kernel
//! runs ([`cpu_indices`]; `tests/gpu_parity.rs` compares the two).
//!
//! Memory: per patch the 48 B header, `4·(size_u + degree_u + 1 + size_v + degree_v + 1)` B of
//! knots and `16·size_u·size_v` B of control points (the `nurbs` scene: 34 patches, 13.7 KiB); per
//! grid vertex 32 B in the vertex streams (position 12, normal 12, uv 8), per quad 24 B of
//! indices (level 16: 9 248 B and 6 144 B per patch). A scene without patches allocates none of
//! it, records no pass and creates none of its pipelines. Adaptive levels: slots of
//! [`ADAPTIVE_MAX_LEVEL`] (135 200 B of vertices and 98 304 B of indices per patch) and 20 B of
//! draw arguments per patch.
use super::gbuffer::{Draw, Geometry};
use super::{SceneInput, Settings, Technique, ViewTransform};
use crate::gpu::Gpu;
use crate::scene::nurbs::{NurbsBuffers, NurbsPatch};
use crate::vk::{Buffer, ComputePipeline, Context, Recorder, ShaderModule, VkResult};
use anyhow::{bail, Result};
use shaders::kernels;
use shaders::layout::{TessLevelParams, TessellationParams};
use shaders::tessellation::DRAW_ARGS_WORDS;
use shaders::nurbs::{index_count, vertex_count};
use std::borrow::Cow;

/// A NURBS patch as the renderer draws it: the surface (world space), the level it is
/// tessellated at (≥ 1), and its draw (material, textures; the index range is assigned here).
#[derive(Clone, Copy, Debug)]
pub struct NurbsDraw<'a> {
    pub patch: &'a NurbsPatch,
    pub level: u32,
    pub draw: Draw,
}

/// The largest level adaptive tessellation picks: every patch's slot holds that grid.
pub const ADAPTIVE_MAX_LEVEL: u32 = 64;

/// The patches packed after `first_vertex` vertices and `first_index` indices, relative to the
/// camera, with each patch's draw over its index range; `adaptive`: every slot at
/// [`ADAPTIVE_MAX_LEVEL`] and every draw indirect (patch `k` draws arguments `k`).
pub fn pack(patches: &[NurbsDraw<'_>], view: &ViewTransform, first_vertex: u32, first_index: u32, adaptive: bool) -> Result<(NurbsBuffers, Vec<Draw>)> {
    let level_of = |p: &NurbsDraw<'_>| if adaptive { ADAPTIVE_MAX_LEVEL } else { p.level };
    let vertices: u64 = first_vertex as u64 + patches.iter().map(|p| vertex_count(level_of(p)) as u64).sum::<u64>();
    let indices: u64 = first_index as u64 + patches.iter().map(|p| index_count(level_of(p)) as u64).sum::<u64>();
    if vertices > u32::MAX as u64 || indices > u32::MAX as u64 {
        bail!("{} NURBS patches tessellate into {vertices} vertices and {indices} indices with the meshes; 32-bit indices address at most {}", patches.len(), u32::MAX);
    }
    let mut b = NurbsBuffers { vertices: first_vertex, indices: first_index, ..NurbsBuffers::default() };
    let draws = patches
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let h = b.push_relative(p.patch, level_of(p), view.eye);
            Draw { first_index: h.index_offset, index_count: index_count(h.level), indirect: adaptive.then_some(k as u32), ..p.draw }
        })
        .collect();
    Ok((b, draws))
}

/// The index list Forward+ reverses on the CPU: `mesh` followed by every quad's indices, from
/// the function the index kernel runs.
pub fn cpu_indices(mesh: &[u32], packed: &NurbsBuffers, params: &TessellationParams) -> Vec<u32> {
    let mut all = mesh.to_vec();
    all.resize(packed.indices as usize, 0);
    for q in 0..params.quad_count {
        let (_, first, six) = shaders::tessellation::quad_indices(&packed.patches, params, q);
        shaders::tessellation::store_quad(&mut all, first, &six);
    }
    all
}

/// The tessellation pass of a scene with NURBS patches (module docs).
pub struct Tessellation {
    vertices: ComputePipeline<TessellationParams>,
    indices: ComputePipeline<TessellationParams>,
    /// Adaptive levels: the level kernel and its parameters.
    levels: Option<(ComputePipeline<TessLevelParams>, TessLevelParams)>,
    headers: Buffer,
    knots: Buffer,
    control_points: Buffer,
    /// The control points in world space, `(point, weight)`: [`Tessellation::set_eye`] makes
    /// them relative to a new camera.
    world: Vec<([f32; 3], f32)>,
    params: TessellationParams,
}

impl Tessellation {
    /// Uploads packed patches (`first_vertex`, `first_index`: where their grids start) and
    /// creates the pass's pipelines; `levels`: adaptive levels with these parameters (the
    /// geometry to record into then has the draw arguments, [`Geometry::indirect_args`]).
    pub fn new(ctx: &Context, module: &ShaderModule, packed: &NurbsBuffers, first_vertex: u32, first_index: u32, levels: Option<TessLevelParams>) -> VkResult<Self> {
        Ok(Self {
            vertices: ComputePipeline::new(ctx, module, kernels::NURBS_VERTICES)?,
            indices: ComputePipeline::new(ctx, module, kernels::NURBS_INDICES)?,
            levels: levels.map(|l| Ok::<_, crate::vk::VkError>((ComputePipeline::new(ctx, module, kernels::NURBS_LEVELS)?, l))).transpose()?,
            headers: Buffer::from_slice(ctx, "nurbs patches", &packed.patches)?,
            knots: Buffer::from_slice(ctx, "nurbs knots", &packed.knots)?,
            control_points: Buffer::from_slice(ctx, "nurbs control points", &packed.control_points)?,
            world: packed.world.clone(),
            params: params(packed, first_vertex, first_index),
        })
    }

    /// Records the pass into `geometry`'s buffers: with adaptive levels the level kernel first,
    /// then steps 2–4.
    pub fn record(&self, rec: &mut Recorder<'_>, geometry: &Geometry) -> VkResult<()> {
        let p = &self.params;
        if let Some((pipe, l)) = &self.levels {
            let args = geometry.indirect_args.as_ref().ok_or_else(|| crate::vk::VkError::Kernel { entry: pipe.kernel.entry, what: "no draw-argument buffer in the geometry".into() })?;
            rec.dispatch_threads(pipe, &[&self.headers, &self.knots, &self.control_points, args], l, [l.patch_count, 1, 1])?;
        }
        let streams = [&self.headers, &self.knots, &self.control_points, &geometry.positions, &geometry.normals, &geometry.uvs];
        rec.dispatch_linear(&self.vertices, &streams, p, p.vertex_count)?;
        rec.dispatch_linear(&self.indices, &[&self.headers, &geometry.indices], p, p.quad_count)?;
        rec.draws_read_kernel_writes();
        Ok(())
    }

    /// The camera moved to `eye`: the control points are uploaded anew relative to it, as
    /// [`pack`] made them relative to the first one (the grids follow at the next frame).
    pub fn set_eye(&mut self, eye: glam::DVec3) -> VkResult<()> {
        let relative: Vec<[f32; 4]> = self.world.iter().map(|&(p, w)| crate::scene::nurbs::relative_point(p, w, eye)).collect();
        self.control_points.write(&relative)
    }

    /// Each patch's level in the headers (adaptive levels: as the level kernel last wrote them).
    pub fn levels(&mut self) -> VkResult<Vec<u32>> {
        let n = self.params.patch_count as usize;
        Ok(self.headers.read::<shaders::layout::NurbsPatchGpu>(n)?.iter().map(|h| h.level).collect())
    }

    /// The patches' headers on the GPU (adaptive levels: the level kernel writes their levels).
    pub fn headers_mut(&mut self) -> &mut Buffer {
        &mut self.headers
    }

    /// The pass's push constants: where its grids lie.
    pub fn params(&self) -> &TessellationParams {
        &self.params
    }

    /// Bytes per buffer of the pass (the grids themselves count as geometry).
    pub fn buffers(&self) -> Vec<(String, u64)> {
        [&self.headers, &self.knots, &self.control_points].iter().map(|b| (b.name.clone(), b.size)).collect()
    }
}

/// The push constants of packed patches whose grids start at `first_vertex` and `first_index`.
pub fn params(packed: &NurbsBuffers, first_vertex: u32, first_index: u32) -> TessellationParams {
    TessellationParams {
        patch_count: packed.patches.len() as u32,
        first_vertex,
        vertex_count: packed.vertices - first_vertex,
        first_index,
        quad_count: (packed.indices - first_index) / 6,
        _pad: [0; 3],
    }
}

/// The scene's geometry on the GPU (`positions`: camera-relative), with room for its NURBS
/// grids, the tessellation pass that writes them (`None` for a scene without patches), and the
/// merged index list on the CPU (Forward+'s copy; with adaptive levels, which Forward+ refuses,
/// the meshes' alone).
pub fn upload_geometry<'a>(gpu: &Gpu, scene: &SceneInput<'a>, positions: &[[f32; 3]], s: &Settings) -> Result<(Geometry, Option<Tessellation>, Cow<'a, [u32]>)> {
    let ctx = &gpu.ctx;
    let upload = |draws: &[Draw], extra| Geometry::upload_reserving(ctx, positions, scene.normals, scene.uvs, scene.indices, draws, &scene.materials, extra);
    if scene.nurbs.is_empty() {
        return Ok((upload(&scene.draws, [0, 0])?, None, Cow::Borrowed(scene.indices)));
    }
    let levels = scene.nurbs_tolerance.map(|tolerance| adaptive_params(scene, s, tolerance, ctx.info.is_llvmpipe())).transpose()?;
    let (first_vertex, first_index) = (u32::try_from(positions.len())?, u32::try_from(scene.indices.len())?);
    let (packed, nurbs_draws) = pack(&scene.nurbs, &scene.view, first_vertex, first_index, levels.is_some())?;
    let (vertices, indices) = (packed.vertices as u64, packed.indices as u64);
    crate::vk::memory::check_range(ctx, "vertex positions with the NURBS grids", 12 * vertices)?;
    crate::vk::memory::check_range(ctx, "indices with the NURBS grids", 4 * indices)?;
    let draws: Vec<Draw> = scene.draws.iter().chain(&nurbs_draws).copied().collect();
    let mut geometry = upload(&draws, [vertices - first_vertex as u64, indices - first_index as u64])?;
    let pass = Tessellation::new(ctx, &gpu.compute_module, &packed, first_vertex, first_index, levels)?;
    if levels.is_some() {
        geometry.indirect_args = Some(Buffer::storage(ctx, "nurbs draw arguments", 4 * DRAW_ARGS_WORDS as u64 * packed.patches.len() as u64)?);
        return Ok((geometry, Some(pass), Cow::Borrowed(scene.indices)));
    }
    let all = cpu_indices(scene.indices, &packed, pass.params());
    Ok((geometry, Some(pass), Cow::Owned(all)))
}

/// Whether `technique` can draw adaptive levels within `tolerance` pixels (`--tess-error`): a
/// positive tolerance, and a technique whose patches the G-buffer draws (not Forward+).
pub fn check_adaptive(technique: Technique, tolerance: f32) -> Result<()> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        bail!("--tess-error {tolerance}: the tolerance must be a positive number of pixels");
    }
    if !technique.description().gbuffer {
        bail!("--tess-error: {} draws NURBS patches from a CPU copy of the indices; adaptive levels are drawn by the G-buffer's indirect draws (use --tess-level, or another technique)", technique.name());
    }
    Ok(())
}

/// The level kernel's parameters for a frame of `s` (tolerance in pixels), after checking that
/// the frame can draw adaptive levels ([`check_adaptive`]; no transparent patch: the transparent
/// pass draws index ranges; on llvmpipe no patch past its loop limit).
fn adaptive_params(scene: &SceneInput<'_>, s: &Settings, tolerance: f32, llvmpipe: bool) -> Result<TessLevelParams> {
    check_adaptive(s.technique, tolerance)?;
    let limit = shaders::tessellation::MAX_ADAPTIVE_CONTROL_POINTS_LLVMPIPE;
    if let Some(p) = scene.nurbs.iter().find(|p| llvmpipe && p.patch.control_points.len() > limit as usize) {
        bail!(
            "--tess-error: a NURBS patch of {} control points: lavapipe's loop limiter ends a shader's loops after 65 535 iterations, so the level kernel takes patches of at most {limit} there (use --tess-level, or a GPU)",
            p.patch.control_points.len()
        );
    }
    if let Some(p) = scene.nurbs.iter().find(|p| super::gbuffer::is_transparent(&p.draw, &scene.materials)) {
        let name = scene.material_names.get(p.draw.params.material as usize).map_or("?", |n| n.as_str());
        bail!("--tess-error: a NURBS patch of transparent material {name:?}: the transparent pass draws fixed levels only (use --tess-level)");
    }
    Ok(TessLevelParams {
        patch_count: scene.nurbs.len() as u32,
        max_level: ADAPTIVE_MAX_LEVEL,
        pixel_scale: s.height as f32 / (2.0 * (0.5 * scene.fov_y_radians).tan()),
        tolerance,
        near: scene.near,
        _pad: [0; 3],
    })
}
