//! MSAA (`--msaa N`, `N` > 1): the G-buffer drawn at `N` samples per pixel, gathered into
//! per-sample planes of the G-buffer buffers with the edge pixels listed, and the edge pixels
//! shaded per sample by the technique (Lauritzen 2010; the steps, edge rule and sample locations
//! are in `shaders::msaa`).
//!
//! The frame loop owns a [`Multisampling`] when `N` > 1 and records its part inside the
//! G-buffer pass ([`Multisampling::record_gather`], in place of the copies of the targets into
//! the buffers); a technique whose [`super::Description::msaa`] is set reads it from
//! [`super::technique::FrameInputs::msaa`] and records its edge pass after its shading. With
//! `--msaa 1` none of this exists: no pipeline, no buffer, no pass.
//!
//! Memory per sample ([`bytes_per_sample`]): the targets' 24 B (the normal target is
//! `RGBA32_SFLOAT` at every precision) and the buffers' 12 B (24 with float32 normals), plus the
//! edge list of one word per pixel: 36 B per sample and 4 B per pixel at 2×16-bit normals.
use crate::gpu::{Gpu, LightCompute, ALBEDO_FORMAT};
use crate::vk::{Buffer, ComputePipeline, DepthTest, GraphicsPipeline, Image, ImageUse, LightTyped, Recorder, TargetFormat, VkResult};
use shaders::kernels::Kernel;
use shaders::kernels;
use shaders::layout::{DrawParams, FrameParams};
use shaders::msaa::{EDGE_ARGS_WORD, EDGE_HEADER_WORDS};
use shaders::octahedral::Precision;

/// The normal target of a multisampled G-buffer at every precision (`shaders::msaa::float_normal`:
/// integer targets need not multisample).
pub const NORMAL_FORMAT: TargetFormat = TargetFormat::Rgba32Float;

/// G-buffer bytes of one sample: the targets' (depth 4, normal 16, albedo 4) and the buffers'
/// (depth 4, normal words, albedo 4).
pub fn bytes_per_sample(precision: Precision) -> u64 {
    (4 + 16 + 4) + (4 + 4 * precision.gbuffer_words() as u64 + 4)
}

/// The pipelines and the edge list of a multisampled frame.
pub struct Multisampling {
    pub samples: u32,
    /// The G-buffer pipelines at `samples` samples, by draw variant (`gbuffer::Draw::variant`).
    pub gbuffer: [GraphicsPipeline<DrawParams>; 3],
    gather: ComputePipeline<FrameParams>,
    edge_args: ComputePipeline<()>,
    /// The edge list: `EDGE_HEADER_WORDS` words (count, the edge pass's indirect workgroup
    /// counts), then up to one pixel index per pixel.
    pub edges: Buffer,
}

impl Multisampling {
    /// The pipelines and edge list for `samples` samples per pixel of `pixels` pixels; `None` for
    /// one sample.
    pub fn new(gpu: &Gpu, samples: u32, pixels: u64) -> VkResult<Option<Self>> {
        if samples <= 1 {
            return Ok(None);
        }
        let ctx = &gpu.ctx;
        let colours = [NORMAL_FORMAT, ALBEDO_FORMAT];
        let handles = &kernels::GBUFFER_MS;
        let make = |h: shaders::kernels::RasterKernel<DrawParams>| GraphicsPipeline::multisampled(ctx, &gpu.graphics_module, h.fragment, h, &colours, DepthTest::NearestWrites, samples);
        let edge_words = EDGE_HEADER_WORDS as u64 + pixels;
        crate::vk::memory::check_range(ctx, "MSAA edge list", 4 * edge_words)?;
        Ok(Some(Self {
            samples,
            gbuffer: [make(handles[0])?, make(handles[1])?, make(handles[2])?],
            gather: ComputePipeline::new(ctx, &gpu.compute_module, kernels::MSAA_GATHER)?,
            edge_args: ComputePipeline::new(ctx, &gpu.compute_module, kernels::MSAA_EDGE_ARGS)?,
            edges: Buffer::storage(ctx, "MSAA edge list", 4 * edge_words)?,
        }))
    }

    /// After the multisampled G-buffer pass (`targets` in their target uses): every sample into
    /// the buffers' planes, the edge list and its indirect arguments (`shaders::msaa` steps 2–3).
    pub fn record_gather(&self, rec: &mut Recorder<'_>, targets: [(&Image, ImageUse); 3], buffers: [&Buffer; 3], p: &FrameParams) -> VkResult<()> {
        for (image, from) in targets {
            rec.transition(image, from, ImageUse::KernelRead);
        }
        rec.fill(&self.edges, 0);
        let [depth, normals, albedo] = buffers;
        let images = targets.map(|(i, _)| i);
        rec.dispatch_linear_reading(&self.gather, &[depth, normals, albedo, &self.edges], &images, p, p.count)?;
        rec.dispatch(&self.edge_args, &[&self.edges], &(), [1, 1, 1])
    }

    /// A technique's edge pass (`shaders::msaa` step 5): `pipes` (its `_diffuse` / `_specular`
    /// edge kernels) over the listed edge pixels, with `buffers` and then the edge list bound.
    pub fn record_edges(&self, rec: &mut Recorder<'_>, pipes: &[LightCompute<FrameParams>; 2], p: &FrameParams, buffers: &[&Buffer]) -> VkResult<()> {
        let bound: Vec<&Buffer> = buffers.iter().copied().chain([&self.edges]).collect();
        rec.pass("edge shading", |rec| rec.dispatch_indirect(super::shading_pipeline(pipes, p)?, &bound, p, &self.edges, EDGE_ARGS_WORD))
    }

    /// Edge pixels of the last frame.
    pub fn edge_pixels(&mut self) -> VkResult<u32> {
        Ok(self.edges.read::<u32>(1)?[0])
    }

    pub fn buffers(&self) -> Vec<(String, u64)> {
        vec![(self.edges.name.clone(), self.edges.size)]
    }
}

/// A technique's edge-pass pipelines for `handles` (its `_diffuse` / `_specular` edge kernels)
/// when the frame is multisampled (`msaa`), else none: nothing is created for one sample.
pub fn edge_pipelines(gpu: &Gpu, msaa: Option<&Multisampling>, handles: [Kernel<FrameParams>; 2]) -> Option<[LightCompute<FrameParams>; 2]> {
    msaa.map(|_| handles.map(|k| LightTyped::compute(&gpu.light_compute, k)))
}

/// `pixels` of a `(w·a) × (h·b)` frame box-filtered to `w × h`: the mean of each pixel's `a × b`
/// pixels in linear colour, encoded as sRGB8 as frames are (the supersampled reference MSAA is
/// measured against: `tests/msaa.rs`, the accuracy study).
pub fn box_filter(pixels: &[u32], w: u32, h: u32, (a, b): (u32, u32)) -> Vec<u32> {
    use shaders::lighting::{decode_srgb8, encode_srgb8};
    let wide = w * a;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sum = (0..a * b).map(|k| decode_srgb8(pixels[((y * b + k / a) * wide + x * a + k % a) as usize])).fold(glam::Vec3::ZERO, |s, c| s + c);
            encode_srgb8(sum / (a * b) as f32)
        })
        .collect()
}
