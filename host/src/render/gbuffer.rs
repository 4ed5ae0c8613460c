//! G-buffer pass: rasterise the scene (rust-gpu `raster::gbuffer_vs/fs`) into depth, normal and
//! albedo targets, then copy each into a storage buffer that every compute pass and CPU reference
//! reads (one buffer each: at 7680×4320 a word per pixel is 133 MB, just inside lavapipe's
//! 128 MiB storage-buffer range).
//!
//! The normal target is one word per pixel (`R32_UINT`, an octahedral code) or, with float32
//! normals, four (`R32G32B32A32_UINT`: three bit patterns and a pad; the `_f32` fragment
//! variants write it). Memory: targets 4 + 4 (16) + 4 B/px, plus the same again as buffers:
//! 24 MB at 1080p in all, 49 MB with float32 normals.
use crate::gpu::{normal_target, Gpu, ALBEDO_FORMAT, NORMAL_FORMATS};
use crate::vk::image::upload_rgba8;
use crate::vk::{Attachment, Binding, Buffer, Context, Image, ImageUse, Load, Recorder, Sampler, TargetFormat, VkResult};
use super::msaa::Multisampling;
use shaders::layout::{DrawParams, FrameParams, MaterialGpu, RasterCamera};
use shaders::octahedral::Precision;

/// One draw: a range of the merged index buffer, its material and its textures (indices into
/// the scene's texture list).
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub params: DrawParams,
    pub albedo_texture: Option<u32>,
    pub mask_texture: Option<u32>,
    /// Drawn with the arguments a kernel wrote, number `k` of [`Geometry::indirect_args`]
    /// (adaptive NURBS levels: the G-buffer draws the current grid; `first_index` and
    /// `index_count` then span the patch's whole slot).
    pub indirect: Option<u32>,
}

impl Draw {
    /// Index into the raster handles' variants (`shaders::kernels::GBUFFER`): plain, textured,
    /// alpha-tested.
    pub fn variant(&self) -> usize {
        match (self.albedo_texture, self.mask_texture) {
            (_, Some(_)) => 2,
            (Some(_), None) => 1,
            (None, None) => 0,
        }
    }
}

/// Whether a draw's material lets light through (opacity below 1; a missing material is opaque).
pub fn is_transparent(d: &Draw, materials: &[MaterialGpu]) -> bool {
    materials.get(d.params.material as usize).is_some_and(|m| m.opacity < 1.0)
}

/// Texels of one texture, as the scene loaded them.
#[derive(Clone, Copy, Debug)]
pub struct TextureData<'a> {
    pub width: u32,
    pub height: u32,
    pub rgba8: &'a [u8],
    /// Colour data stored in sRGB (sampled as linear); masks are linear.
    pub srgb: bool,
}

/// The scene's textures on the GPU, a white fallback and the sampler.
pub struct Textures {
    images: Vec<Image>,
    white: Image,
    sampler: Sampler,
}

impl Textures {
    pub fn upload(ctx: &Context, textures: &[TextureData<'_>]) -> VkResult<Self> {
        let images = textures
            .iter()
            .enumerate()
            .map(|(i, t)| {
                upload_rgba8(ctx, &format!("texture {i}"), t.width, t.height, t.srgb, t.rgba8)
            })
            .collect::<VkResult<Vec<_>>>()?;
        let white = upload_rgba8(ctx, "white texture", 1, 1, false, &[255; 4])?;
        Ok(Self { images, white, sampler: Sampler::linear_repeat(ctx)? })
    }

    /// The binding of texture `index` (the white texture for none).
    pub fn binding(&self, index: Option<u32>) -> Binding<'_> {
        Binding::Texture(index.and_then(|i| self.images.get(i as usize)).unwrap_or(&self.white), &self.sampler)
    }

    /// The bindings of a draw of `variant` (0: none; 1: albedo; 2: albedo and mask).
    pub fn bindings_of<'a>(&'a self, draw: &Draw, variant: usize) -> impl Iterator<Item = Binding<'a>> {
        [self.binding(draw.albedo_texture), self.binding(draw.mask_texture)].into_iter().take(variant)
    }

    pub fn bytes(&self) -> u64 {
        self.images.iter().map(|i| 4 * i.extent.width as u64 * i.extent.height as u64).sum()
    }
}

/// Scene geometry on the GPU (merged buffers; world space).
pub struct Geometry {
    pub positions: Buffer,
    pub normals: Buffer,
    pub uvs: Buffer,
    pub indices: Buffer,
    /// Draws of opaque materials (opacity 1): the G-buffer's.
    pub draws: Vec<Draw>,
    /// Draws of transparent materials (opacity below 1), in scene order: the transparent pass's.
    pub transparent: Vec<Draw>,
    /// Indirect draw arguments of the draws that have them ([`Draw::indirect`]), written by
    /// kernels each frame (`nurbs.rs`, adaptive levels); `None` without such draws.
    pub indirect_args: Option<Buffer>,
}

impl Geometry {
    /// Uploads the merged buffers and splits `draws` by their material's opacity (`materials`).
    pub fn upload(ctx: &Context, positions: &[[f32; 3]], normals: &[[f32; 3]], uvs: &[[f32; 2]], indices: &[u32], draws: &[Draw], materials: &[MaterialGpu]) -> VkResult<Self> {
        Self::upload_reserving(ctx, positions, normals, uvs, indices, draws, materials, [0, 0])
    }

    /// [`Geometry::upload`] with room for `extra[0]` more vertices and `extra[1]` more indices
    /// after the uploaded ones, which kernels write (the NURBS tessellation pass, `nurbs.rs`).
    #[allow(clippy::too_many_arguments)]
    pub fn upload_reserving(
        ctx: &Context,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        uvs: &[[f32; 2]],
        indices: &[u32],
        draws: &[Draw],
        materials: &[MaterialGpu],
        extra: [u64; 2],
    ) -> VkResult<Self> {
        let (transparent, draws) = draws.iter().copied().filter(|d| d.index_count > 0).partition(|d| is_transparent(d, materials));
        Ok(Self {
            positions: Buffer::from_slice_reserving(ctx, "positions", positions, extra[0])?,
            normals: Buffer::from_slice_reserving(ctx, "normals", normals, extra[0])?,
            uvs: Buffer::from_slice_reserving(ctx, "uvs", uvs, extra[0])?,
            indices: Buffer::indices_reserving(ctx, "indices", indices, extra[1])?,
            draws,
            transparent,
            indirect_args: None,
        })
    }

    pub fn bytes(&self) -> u64 {
        self.positions.size + self.normals.size + self.uvs.size + self.indices.size + self.indirect_args.as_ref().map_or(0, |b| b.size)
    }

    /// The vertex stage's storage buffers of every raster pass: positions, normals, uvs, camera.
    pub fn vertex_bindings<'a>(&'a self, camera: &'a Buffer) -> impl Iterator<Item = Binding<'a>> {
        [&self.positions, &self.normals, &self.uvs, camera].into_iter().map(Binding::Buffer)
    }
}

/// Render targets and their buffer copy.
pub struct Targets {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the targets (`--msaa`): with more than one, the buffers hold one
    /// plane of `width × height` entries per sample, sample `s` of pixel `i` at `s·n + i`
    /// (`shaders::msaa`), plane 0 being what a one-sample frame holds.
    pub samples: u32,
    /// The opaque depth target; the transparent pass tests against it.
    pub depth: Image,
    normal: Image,
    albedo: Image,
    /// Reversed-Z depth (`f32`), one word per pixel and sample.
    pub depth_buf: Buffer,
    /// View-space normal: one word per pixel and sample (octahedral) or four (float32).
    pub normal_buf: Buffer,
    /// Index into [`NORMAL_FORMATS`].
    pub normal_target: usize,
    /// RGBA8 albedo + material index, one word per pixel and sample.
    pub albedo_buf: Buffer,
}

impl Targets {
    /// Targets for `width × height` pixels of `samples` samples and normals at `precision`
    /// (`PRECISION_*`).
    ///
    /// `depth_planes` (at least `samples`) sizes the depth buffer alone: a technique that
    /// multisamples targets of its own (Forward+) keeps a plane per sample there.
    pub fn new(ctx: &Context, width: u32, height: u32, precision: u32, samples: u32, depth_planes: u32) -> VkResult<Self> {
        let n = width as u64 * height as u64 * samples.max(1) as u64;
        let depth_n = width as u64 * height as u64 * depth_planes.max(samples).max(1) as u64;
        let normal_target = normal_target(precision);
        let normal_words = Precision::from_u32(precision).gbuffer_words() as u64;
        crate::vk::memory::check_range(ctx, "G-buffer", 4 * depth_n)?;
        crate::vk::memory::check_range(ctx, "G-buffer normals", 4 * normal_words * n)?;
        let target = |name: &str, format: TargetFormat| match samples {
            0 | 1 => Image::target(ctx, name, width, height, format),
            _ => Image::multisampled_target(ctx, name, width, height, format, samples),
        };
        let normal_format = if samples > 1 { super::msaa::NORMAL_FORMAT } else { NORMAL_FORMATS[normal_target] };
        Ok(Self {
            width,
            height,
            samples: samples.max(1),
            depth: target("gbuffer depth", TargetFormat::Depth32)?,
            normal: target("gbuffer normal", normal_format)?,
            albedo: target("gbuffer albedo", ALBEDO_FORMAT)?,
            depth_buf: Buffer::storage(ctx, "gbuffer depth", 4 * depth_n)?,
            normal_buf: Buffer::storage(ctx, "gbuffer normals", 4 * normal_words * n)?,
            normal_target,
            albedo_buf: Buffer::storage(ctx, "gbuffer albedo", 4 * n)?,
        })
    }

    pub fn bytes(&self) -> u64 {
        let buffers = self.depth_buf.size + self.normal_buf.size + self.albedo_buf.size;
        // One sample: the targets hold what their buffers hold. More: `msaa::bytes_per_sample`.
        match self.samples {
            // The targets hold one plane of what the buffers hold (whose depth may hold more).
            1 => buffers + self.width as u64 * self.height as u64 * 4 + self.normal_buf.size + self.albedo_buf.size,
            n => buffers + n as u64 * self.width as u64 * self.height as u64 * (4 + 16 + 4),
        }
    }
}

/// Records the G-buffer pass and the copies into the targets' buffers, or with `msaa` the
/// multisampled pass and its gather (`msaa.rs`); `p` is the frame's parameters.
#[allow(clippy::too_many_arguments)]
pub fn record(gpu: &Gpu, rec: &mut Recorder<'_>, geo: &Geometry, textures: &Textures, camera: &Buffer, t: &Targets, msaa: Option<&Multisampling>, p: &FrameParams) -> VkResult<()> {
    for img in [&t.normal, &t.albedo] {
        rec.transition(img, ImageUse::Undefined, ImageUse::ColourTarget);
    }
    rec.transition(&t.depth, ImageUse::Undefined, ImageUse::DepthTarget);
    let colours = [
        Attachment { image: &t.normal, load: Load::ClearU32([0; 4]) },
        Attachment { image: &t.albedo, load: Load::ClearF32([0.0; 4]) },
    ];
    rec.begin_rendering(&colours, Attachment { image: &t.depth, load: Load::ClearDepth(0.0) }, &geo.indices);
    for draw in geo.draws.iter().filter(|d| d.index_count > 0) {
        let variant = draw.variant();
        let bindings: Vec<Binding<'_>> = geo.vertex_bindings(camera).chain(textures.bindings_of(draw, variant)).collect();
        let pipe = match msaa {
            Some(m) => &m.gbuffer[variant],
            None => &gpu.raster.gbuffer[t.normal_target][variant],
        };
        match (draw.indirect, &geo.indirect_args) {
            (Some(k), Some(args)) => rec.draw_indexed_indirect(pipe, &bindings, &draw.params, args, k)?,
            _ => rec.draw_indexed(pipe, &bindings, &draw.params, draw.first_index, draw.index_count)?,
        }
    }
    rec.end_rendering();
    if let Some(m) = msaa {
        let targets = [(&t.depth, ImageUse::DepthTarget), (&t.normal, ImageUse::ColourTarget), (&t.albedo, ImageUse::ColourTarget)];
        return m.record_gather(rec, targets, [&t.depth_buf, &t.normal_buf, &t.albedo_buf], p);
    }
    for img in [&t.normal, &t.albedo] {
        rec.transition(img, ImageUse::ColourTarget, ImageUse::CopySource);
    }
    rec.transition(&t.depth, ImageUse::DepthTarget, ImageUse::CopySource);
    rec.copy_to_buffers(&[(&t.depth, &t.depth_buf), (&t.normal, &t.normal_buf), (&t.albedo, &t.albedo_buf)]);
    Ok(())
}

/// Reversed-Z, infinite-far projection with Vulkan's y-down clip space:
/// `clip = (f/a·x, −f·y, near, −z)`, so the stored depth is `near / d`.
pub fn projection(fov_y_radians: f32, aspect: f32, near: f32) -> glam::Mat4 {
    let f = 1.0 / (0.5 * fov_y_radians).tan();
    glam::Mat4::from_cols(
        glam::Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, -f, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, 0.0, -1.0),
        glam::Vec4::new(0.0, 0.0, near, 0.0),
    )
}

/// The camera block of the G-buffer pass.
pub fn raster_camera(view: glam::Mat4, fov_y_radians: f32, aspect: f32, near: f32) -> RasterCamera {
    RasterCamera { view: view.to_cols_array_2d(), proj: projection(fov_y_radians, aspect, near).to_cols_array_2d() }
}
