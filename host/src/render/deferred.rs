//! `deferred`: every light for every pixel after the G-buffer — the brute-force reference every
//! other technique is checked against; with shadow-casting lights, each one's share times its
//! visibility from the cube shadow maps (`shadow_maps.rs`). One kernel (`shade_deferred`); no buffers of its own but
//! those of the transparent pass (`transparent.rs`, every light for every transparent fragment
//! and the `--oit` resolve), for scenes with transparent draws.
use super::technique::{boxed, llvmpipe_chunked_lights, Description, FrameInputs, LightCost, LightingTechnique, TransparentDraws};
use super::transparent::{OpaqueDepth, Transparency, TransparencyStats};
use crate::gpu::{Gpu, LightCompute};
use crate::vk::{ImageUse, Recorder, VkResult};
use shaders::kernels;
use shaders::layout::FrameParams;
use anyhow::{Context as _, Result};

pub const DEFERRED: Description = Description {
    name: "deferred",
    summary: "Every light for every pixel: the correctness reference.",
    create: |gpu, f| boxed(Deferred::new(gpu, f)),
    transparent: TransparentDraws::Drawn,
    gbuffer: true,
    raster_passes: &[],
    cost: LightCost::EveryLightPerPixel,
    max_tile: None,
    llvmpipe_lights: llvmpipe_chunked_lights,
    knobs: &[],
    own_kernels: &[],
    own_raster: &[],
    msaa: true,
    light_words: 0,
    shadows: true,
};

pub struct Deferred {
    transparency: Option<Transparency>,
    /// The MSAA edge pass's pipelines (`--msaa` above 1): every sample of an edge pixel with
    /// every light.
    edges: Option<[LightCompute<FrameParams>; 2]>,
}

impl Deferred {
    pub fn new(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        Ok(Self {
            transparency: Transparency::new(f, gpu, None).context("creating the transparent pass")?,
            edges: super::msaa::edge_pipelines(gpu, f.msaa, kernels::SHADE_EDGES_DEFERRED),
        })
    }
}

impl LightingTechnique for Deferred {
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let (t, p) = (f.targets, &f.params);
        let [slots, maps] = f.shadow_buffers();
        rec.pass("shading", |rec| {
            rec.dispatch_linear(
                super::shading_pipeline(&gpu.kernels.shade_deferred, p)?,
                &[&t.depth_buf, &t.normal_buf, &t.albedo_buf, f.lights, f.materials, f.frame, f.bounds, slots, maps],
                p,
                p.count,
            )
        })?;
        if let (Some(m), Some(edges)) = (f.msaa, &self.edges) {
            m.record_edges(rec, edges, p, &[&t.depth_buf, &t.normal_buf, &t.albedo_buf, f.lights, f.materials, f.frame, f.bounds])?;
        }
        match &self.transparency {
            Some(tr) => tr.record_shade(rec, f, p, OpaqueDepth { image: &t.depth, from: ImageUse::CopySource }, None),
            None => Ok(()),
        }
    }

    fn grow_if_needed(&mut self, gpu: &Gpu) -> Result<Option<String>> {
        Transparency::grow(self.transparency.as_mut(), &gpu.ctx)
    }

    fn transparency(&self) -> Option<TransparencyStats> {
        self.transparency.as_ref().map(Transparency::stats)
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        self.transparency.iter().flat_map(Transparency::buffers).collect()
    }
}
