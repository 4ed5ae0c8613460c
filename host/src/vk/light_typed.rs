//! Pipelines specialised by a frame's light types (`shaders::light_types`, "Specialised
//! pipelines"): an entry that shades or culls punctual lights gets one pipeline per light-type
//! mix a scene uses (at most `LIGHT_TYPE_VARIANTS`), each created the first time a frame needs
//! it and kept, with the light-type bits as the specialization constant `LIGHT_TYPES_SPEC_ID`.
//! The driver compiles each with those bits folded: a scene of point lights runs pipelines with
//! no cone test and no directional loop in them.
use super::error::VkResult;
use super::pipeline::{ComputePipeline, ShaderModule};
use super::raster::{Blend, DepthTest, GraphicsPipeline, TargetFormat};
use bytemuck::Pod;
use shaders::kernels::{Kernel, RasterKernel};
use shaders::light_types::{light_type_variant, LIGHT_TYPES_SPEC_ID, LIGHT_TYPE_MASK, LIGHT_TYPE_VARIANTS};
use std::sync::{Arc, OnceLock};

type Make<T> = Box<dyn Fn(&ShaderModule, u32) -> VkResult<T>>;

/// The pipelines of one entry point, one per light-type mix ([`LightTyped::get`]).
pub struct LightTyped<T> {
    module: Arc<ShaderModule>,
    make: Make<T>,
    variants: [OnceLock<T>; LIGHT_TYPE_VARIANTS],
}

impl<T> LightTyped<T> {
    fn with(module: &Arc<ShaderModule>, make: Make<T>) -> Self {
        Self { module: module.clone(), make, variants: std::array::from_fn(|_| OnceLock::new()) }
    }

    /// The pipeline for the light-type bits of a frame's `effects` (created on first use).
    pub fn get(&self, effects: u32) -> VkResult<&T> {
        let cell = &self.variants[light_type_variant(effects)];
        if let Some(p) = cell.get() {
            return Ok(p);
        }
        let made = (self.make)(&self.module, effects & LIGHT_TYPE_MASK)?;
        Ok(cell.get_or_init(|| made))
    }

    /// The variants (`light_types::light_type_variant`) created so far.
    pub fn created(&self) -> Vec<usize> {
        (0..LIGHT_TYPE_VARIANTS).filter(|&v| self.variants[v].get().is_some()).collect()
    }
}

impl<P: Pod> LightTyped<ComputePipeline<P>> {
    pub fn compute(module: &Arc<ShaderModule>, kernel: Kernel<P>) -> Self {
        Self::with(module, Box::new(move |m, bits| ComputePipeline::specialised(&m.ctx, m, kernel, &[(LIGHT_TYPES_SPEC_ID, bits)])))
    }
}

impl<P: 'static> LightTyped<GraphicsPipeline<P>> {
    /// Pipelines drawing `kernel` into colour targets `colours` and a depth target (as
    /// [`GraphicsPipeline::blended`]).
    pub fn raster(module: &Arc<ShaderModule>, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest) -> Self {
        let colours = colours.to_vec();
        Self::with(
            module,
            Box::new(move |m, bits| GraphicsPipeline::specialised(&m.ctx, m, kernel.fragment, kernel, &colours, depth, &[(LIGHT_TYPES_SPEC_ID, bits)])),
        )
    }
}
