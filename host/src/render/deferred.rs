//! `deferred`: every light for every pixel after the G-buffer — the brute-force reference every
//! other technique is checked against. One kernel (`shade_deferred`); no buffers of its own.
use super::technique::{FrameInputs, LightingTechnique};
use crate::gpu::Gpu;
use crate::vk::{Recorder, VkResult};
use anyhow::Result;

pub struct Deferred;

impl Deferred {
    pub fn new(_gpu: &Gpu, _f: &FrameInputs<'_>) -> Result<Self> {
        Ok(Self)
    }
}

impl LightingTechnique for Deferred {
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let (t, p) = (f.targets, &f.params);
        rec.pass("shading", |rec| {
            rec.dispatch_linear(
                &gpu.kernels.shade_deferred[super::specular_variant(p)],
                &[&t.depth_buf, &t.normal_buf, &t.albedo_buf, f.lights, f.materials, f.frame, f.bounds],
                p,
                p.count,
            )
        })
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        Vec::new()
    }
}
