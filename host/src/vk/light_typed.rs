//! Pipelines specialised by a frame's light types (`shaders::light_types`, "Specialised
//! pipelines"): an entry that shades or culls punctual lights gets one pipeline per light-type
//! mix a scene uses (at most `LIGHT_TYPE_VARIANTS`), each created the first time a frame needs
//! it and kept. The light-type bits are the module's specialization constant
//! `LIGHT_TYPES_SPEC_ID`, frozen into a module of their own per mix ([`LightTypedModules`],
//! `pipeline::freeze_spec_constant`; shared by every entry of the mix), so the driver compiles
//! each pipeline with those bits as constants: a scene of point lights runs pipelines with no
//! cone test and no directional loop in them.
use super::context::Context;
use super::error::VkResult;
use super::pipeline::{ComputePipeline, ShaderModule};
use super::raster::{Blend, DepthTest, GraphicsPipeline, TargetFormat};
use bytemuck::Pod;
use shaders::kernels::{Kernel, RasterKernel};
use shaders::light_types::{light_type_variant, LIGHT_TYPES_SPEC_ID, LIGHT_TYPE_MASK, LIGHT_TYPE_VARIANTS};
use std::sync::{Arc, OnceLock};

/// One SPIR-V module frozen to each light-type mix, each created on first use.
pub struct LightTypedModules {
    ctx: Context,
    name: &'static str,
    spirv: &'static [u8],
    modules: [OnceLock<ShaderModule>; LIGHT_TYPE_VARIANTS],
}

impl LightTypedModules {
    pub fn new(ctx: &Context, name: &'static str, spirv: &'static [u8]) -> Arc<Self> {
        Arc::new(Self { ctx: ctx.clone(), name, spirv, modules: std::array::from_fn(|_| OnceLock::new()) })
    }

    /// The light-type variants (`light_type_variant`) whose module a pipeline asked for so far.
    pub fn created(&self) -> impl Iterator<Item = usize> + '_ {
        self.modules.iter().enumerate().filter(|(_, m)| m.get().is_some()).map(|(v, _)| v)
    }

    /// The module for the light-type bits of `effects`.
    fn module(&self, effects: u32) -> VkResult<&ShaderModule> {
        let cell = &self.modules[light_type_variant(effects)];
        if let Some(m) = cell.get() {
            return Ok(m);
        }
        let m = ShaderModule::frozen(&self.ctx, self.name, self.spirv, LIGHT_TYPES_SPEC_ID, effects & LIGHT_TYPE_MASK)?;
        Ok(cell.get_or_init(|| m))
    }
}

type Make<T> = Box<dyn Fn(&ShaderModule) -> VkResult<T>>;

/// The pipelines of one entry point, one per light-type mix ([`LightTyped::get`]).
pub struct LightTyped<T> {
    modules: Arc<LightTypedModules>,
    make: Make<T>,
    variants: [OnceLock<T>; LIGHT_TYPE_VARIANTS],
}

impl<T> LightTyped<T> {
    fn with(modules: &Arc<LightTypedModules>, make: Make<T>) -> Self {
        Self { modules: modules.clone(), make, variants: std::array::from_fn(|_| OnceLock::new()) }
    }

    /// The pipeline for the light-type bits of a frame's `effects` (created on first use).
    pub fn get(&self, effects: u32) -> VkResult<&T> {
        let cell = &self.variants[light_type_variant(effects)];
        if let Some(p) = cell.get() {
            return Ok(p);
        }
        let made = (self.make)(self.modules.module(effects)?)?;
        Ok(cell.get_or_init(|| made))
    }
}

impl<P: Pod> LightTyped<ComputePipeline<P>> {
    pub fn compute(modules: &Arc<LightTypedModules>, kernel: Kernel<P>) -> Self {
        Self::with(modules, Box::new(move |m| ComputePipeline::new(&m.ctx, m, kernel)))
    }
}

impl<P: 'static> LightTyped<GraphicsPipeline<P>> {
    /// Pipelines drawing `kernel` into colour targets `colours` and a depth target (as
    /// [`GraphicsPipeline::blended`]).
    pub fn raster(modules: &Arc<LightTypedModules>, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest) -> Self {
        let colours = colours.to_vec();
        Self::with(modules, Box::new(move |m| GraphicsPipeline::blended(&m.ctx, m, kernel.fragment, kernel, &colours, depth)))
    }

    /// [`LightTyped::raster`] for targets of `samples` samples per pixel.
    pub fn raster_multisampled(modules: &Arc<LightTypedModules>, kernel: RasterKernel<P>, colours: &[(TargetFormat, Blend)], depth: DepthTest, samples: u32) -> Self {
        let colours = colours.to_vec();
        Self::with(modules, Box::new(move |m| GraphicsPipeline::blended_multisampled(&m.ctx, m, kernel.fragment, kernel, &colours, depth, samples)))
    }
}
