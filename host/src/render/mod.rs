//! Rendering a frame: upload the scene, then run one lighting technique through the frame loop.
//!
//! Every technique has one shape ([`technique::LightingTechnique`]: create → record → grow →
//! report) and lives in its own file: `deferred.rs` (the brute-force reference), `clustered.rs`
//! (`clustered-naive`, `clustered-bvh` with `bvh.rs`, `sort.rs`, `bitonic.rs`, `scan.rs`),
//! `tiled.rs` (`tiled`, `tiled-2.5d`), `clustered_aabb.rs`, `forward_plus.rs`, `raster_tiled.rs`;
//! `transparent.rs` is the transparent pass the techniques whose [`Description::transparent`] is
//! `Drawn` add for scenes with transparent materials (the others refuse such scenes in one line).
//! The frame loop ([`render`], a loop over the per-frame [`Renderer`] of `renderer.rs`, which the
//! viewer drives too) owns what they share: uploads, the G-buffer pass (`gbuffer.rs`, recorded once per
//! frame for every technique that uses it), the async-compute overlap, the warm-up and timed
//! frames, growth and re-run (at most [`technique::MAX_REGROWTHS`] times; a frame never drops a
//! light), per-pass medians and the read-back for CPU checks.
//!
//! Every technique draws camera-relative: lights are moved to view space and vertices to the eye
//! in f64 on the CPU, so scenes far from the world origin render as at the origin
//! (`camera_relative.rs`, with the precision that remains; `light_contract.rs` checks each light
//! against what the kernels assume).
//!
//! ## How to add a technique
//! (The README's "Adding a technique" has the steps with the shader side.)
//! 1. Write `render/<name>.rs`: a `pub const` [`Description`] (name, summary, constructor,
//!    transparency, G-buffer use, raster passes, light cost, tile and lavapipe limits, knobs, own
//!    kernels), a struct with a constructor `fn(&Gpu, &FrameInputs) -> Result<Self>` (allocate,
//!    create its pipelines, check limits) and an `impl LightingTechnique` (at least `record` and
//!    `buffers`; `grow_if_needed`, `stats` and `record_async` where it has them). It records
//!    through `vk::Recorder` (dispatches, raster passes) and holds no `unsafe` or Vulkan types.
//! 2. Register it with one line in the `techniques!` list below: `[module] Variant =>
//!    module::DESCRIPTION` (the brackets declare the module). The CLI (`--technique`),
//!    `manylights bench` (`--techniques all`), the viewer, the preflight checks and the tests
//!    that iterate [`Technique::ALL`] pick it up from there.
pub mod bitonic;
pub mod bvh;
pub mod camera_relative;
pub mod clustered;
pub mod clustered_aabb;
pub mod cpu_shading;
pub mod deferred;
pub mod forward_plus;
pub mod frame_time;
pub mod gbuffer;
pub mod legend;
pub mod light_contract;
pub mod light_record;
pub mod light_types;
pub mod msaa;
pub mod nurbs;
pub mod reference;
pub mod shadow_maps;
pub mod renderer;
pub mod sort;
pub mod stats;
pub mod technique;
pub mod tiled;
pub mod transparent;

use crate::gpu::Gpu;
use crate::vk::PassTiming;
use anyhow::Result;
pub use gbuffer::{Draw, TextureData};
pub use camera_relative::{lights_to_view, ViewTransform};
pub use renderer::{FrameTimes, Renderer};
use shaders::cluster_key::ClusterGrid;
use shaders::layout::*;
pub use technique::{Description, Knob, LightCost, TransparentDraws};
use technique::{FrameInputs, LightingTechnique};
use shaders::octahedral::Precision;

/// Declares [`Technique`] from one line per technique: `Variant => module::DESCRIPTION`, or
/// `[module] Variant => module::DESCRIPTION` for a technique in a module of its own, which the line
/// then declares too. Everything else about a technique is its [`Description`].
macro_rules! techniques {
    ($( $([$module:ident])? $variant:ident => $description:path, )*) => {
        $( $(pub mod $module;)? )*

        /// Lighting technique: one per registered [`Description`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Technique {
            $( $variant, )*
        }

        impl Technique {
            /// Every technique, in registration order (the bench's sweep, the viewer's number keys).
            pub const ALL: &'static [Technique] = &[$(Technique::$variant),*];

            /// What the program knows of the technique.
            pub fn description(self) -> &'static Description {
                match self { $(Self::$variant => &$description,)* }
            }
        }
    };
}

techniques! {
    Deferred => deferred::DEFERRED,
    ClusteredNaive => clustered::CLUSTERED_NAIVE,
    ClusteredBvh => clustered::CLUSTERED_BVH,
    Tiled => tiled::TILED,
    Tiled25d => tiled::TILED_25D,
    ClusteredAabb => clustered_aabb::CLUSTERED_AABB,
    ForwardPlus => forward_plus::FORWARD_PLUS,
    [raster_tiled] RasterTiled => raster_tiled::RASTER_TILED,
}

impl Technique {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        self.description().name
    }

    /// Whether the technique draws transparent materials (the transparent pass of
    /// `transparent.rs`); the others refuse scenes that have them.
    pub fn draws_transparency(self) -> bool {
        self.description().transparent == TransparentDraws::Drawn
    }

    /// Whether the technique reads setting `knob`.
    pub fn reads(self, knob: Knob) -> bool {
        self.description().knobs.contains(&knob)
    }

    /// Creates the technique for a frame.
    fn create(self, gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Box<dyn LightingTechnique>> {
        (self.description().create)(gpu, f)
    }
}

impl clap::ValueEnum for Technique {
    fn value_variants<'a>() -> &'a [Self] {
        Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description().summary))
    }
}

/// Scene data as the renderer consumes it (world space; lights are checked by
/// [`lights_to_view`]).
pub struct SceneInput<'a> {
    pub positions: &'a [[f32; 3]],
    pub normals: &'a [[f32; 3]],
    pub uvs: &'a [[f32; 2]],
    pub indices: &'a [u32],
    pub draws: Vec<Draw>,
    pub materials: Vec<MaterialGpu>,
    pub lights: &'a [PointLight],
    /// Per light, its cone if it is a spot light; empty when no light is (`light_types`).
    pub spots: &'a [Option<light_types::Spot>],
    /// Per light, whether it casts shadows; empty when none does. No technique renders shadows
    /// yet: the renderer refuses a frame with a shadow-casting light in one line
    /// (`cpu_shading` shades its ray-cast reference).
    pub shadows: &'a [bool],
    /// Directional lights (at most `shaders::light_types::MAX_DIRECTIONAL_LIGHTS`).
    pub directional: &'a [light_types::Directional],
    /// Textures the draws index (`Draw::albedo_texture` / `mask_texture`).
    pub textures: Vec<TextureData<'a>>,
    /// World → view, in f64: the renderer draws camera-relative ([`camera_relative`]).
    pub view: ViewTransform,
    pub fov_y_radians: f32,
    pub near: f32,
    pub far: f32,
    pub effects: u32,
    /// Material names (by material index; may be shorter than `materials`), for messages.
    pub material_names: Vec<String>,
    /// NURBS patches, tessellated on the GPU each frame into the geometry buffers ([`nurbs`]).
    pub nurbs: Vec<nurbs::NurbsDraw<'a>>,
    /// Adaptive NURBS levels within this many pixels of the surface (`None`: each patch's level).
    pub nurbs_tolerance: Option<f32>,
}

/// How to render.
#[derive(Clone, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub tile_size: u32,
    pub technique: Technique,
    /// One of `View::FRAME`.
    pub view: View,
    /// Encoding of the G-buffer normals (the draws' `DrawParams::normal_precision` must match).
    pub normal_precision: Precision,
    pub exposure: f32,
    /// Timed frames after the warm-up frame (0: render once, untimed beyond it).
    pub frames: u32,
    /// Keep the cluster data for CPU checks and statistics.
    pub read_back: bool,
    /// Children per light-BVH node (32 or 64); 0: the device default
    /// ([`bvh::LightBvh::default_branching`]).
    pub bvh_branching: u32,
    /// Bits per axis of the light BVH's Morton keys (1..=10, `bvh::LightBvh::morton_bits`); 0:
    /// [`bvh::DEFAULT_MORTON_BITS`].
    pub morton_bits: u32,
    /// Run the light sort + BVH build on the async-compute queue when the device has one.
    pub async_compute: bool,
    /// GPU sort of the lights' Morton keys (`clustered-bvh`).
    pub sort: sort::SortKind,
    /// Layout of the per-tile light lists (`forward-plus`).
    pub fp_lists: forward_plus::TileLists,
    /// How `clustered-naive` and `clustered-bvh` find the frame's unique clusters.
    pub unique_clusters: clustered::UniqueClusters,
    /// How transparent fragments are resolved (`--oit`; scenes with transparent materials).
    pub oit: transparent::OitVariant,
    /// Also time every dispatch, fill and copy inside each pass (`--dispatch-times`).
    pub dispatch_times: bool,
    /// Samples per pixel of the G-buffer (`--msaa`; 1: no multisampling, nothing of `msaa.rs`).
    pub msaa: u32,
    /// How the light buffer stores point lights (`--light-record`).
    pub light_record: light_record::LightRecord,
    /// The cube shadow maps' resolution and filter (`--shadow-resolution`, `--shadow-filter`;
    /// read only where lights cast shadows).
    pub shadow: shadow_maps::ShadowSettings,
}

/// GPU results kept for checks and statistics.
pub struct Readback {
    /// Reversed-Z depth bits per pixel.
    pub depth: Vec<u32>,
    /// Decoded G-buffer normal per pixel (as the shading passes read it).
    pub normals: Vec<[f32; 3]>,
    /// G-buffer albedo word per pixel (RGBA8 albedo, material index in alpha).
    pub albedo: Vec<u32>,
    pub keys: Vec<u32>,
    pub unique: Vec<u32>,
    pub counts: Vec<u32>,
    pub offsets: Vec<u32>,
    pub list: Vec<u32>,
    pub lights_view: Vec<PointLight>,
    /// The light buffer as the kernels read it (`lights_view`, then cone and directional
    /// records where the scene has them: `shaders::light_types`).
    pub light_records: Vec<PointLight>,
    /// The frame's light-type bits (`EFFECT_SPOT`, `EFFECT_CULL_SPHERE_ONLY`) the culling used.
    pub light_effects: u32,
    pub grid: ClusterGrid,
    pub bounds: Vec<f32>,
    /// Each screen tile's light list as the GPU stored it (`forward-plus`; empty otherwise).
    pub tile_lists: Vec<Vec<u32>>,
    /// The scene has transparent draws: their fragments add clusters of their own, so the unique
    /// clusters hold the opaque pixels' and more.
    pub transparent: bool,
}

/// A rendered frame.
pub struct Frame {
    pub pixels: Vec<u32>,
    /// The whole GPU frame over both queues (first to last timestamp), medians over the timed
    /// frames ([`frame_time`]).
    pub gpu_frame: frame_time::FrameTime,
    /// Median GPU milliseconds per pass over the timed frames (or of the single frame).
    pub timings: Vec<PassTiming>,
    /// (min, max) GPU milliseconds of each pass of `timings` over the timed frames.
    pub timing_spread: Vec<(f64, f64)>,
    pub unique_clusters: u32,
    pub light_refs: u32,
    pub pages: u32,
    /// Times a buffer had to grow and the frame re-run.
    pub regrowths: u32,
    /// Longest light list of one tile or cluster (tiled and clustered-aabb; 0 otherwise). A tiled
    /// list longer than `shaders::tiled::LIST_CAPACITY` was culled and shaded in several rounds.
    pub max_list: u32,
    pub buffers: Vec<(String, u64)>,
    pub readback: Option<Readback>,
    pub grid: ClusterGrid,
    /// The technique's light-only passes (`clustered-bvh`: light sort and BVH build) ran on the
    /// async-compute queue, overlapping the G-buffer raster ([`Frame::gpu_frame`] spans both).
    pub overlapped: bool,
    /// The transparent pass of the last frame (`None`: the scene has no transparent draws).
    pub transparency: Option<transparent::TransparencyStats>,
    /// Each NURBS patch's tessellation level in the last frame, in the scene's order (adaptive
    /// levels as the GPU chose them; empty without patches).
    pub tess_levels: Vec<u32>,
    /// Samples per pixel (`Settings::msaa`).
    pub samples: u32,
    /// Pixels the last frame shaded per sample (MSAA edge pixels; 0 with one sample).
    pub edge_pixels: u32,
    /// Bytes per sample of the frame's multisampled targets and buffers (`--stats`).
    pub bytes_per_sample: u64,
    /// The farthest a light moved in the light buffer's records (view space; 0 for full records,
    /// at most half a grid step's diagonal for compact ones: `light_record::light_buffer`).
    pub light_moved: f32,
    /// The frame's shadow maps (`None`: no light casts shadows, none were made).
    pub shadows: Option<shadow_maps::ShadowStats>,
}

impl Frame {
    /// Whether pass `name` recorded raster work (the G-buffer, Forward+'s depth pre-pass and
    /// forward pass): only part of a GPU may run raster work, so raster and compute are reported
    /// apart.
    pub fn is_raster(&self, name: &str) -> bool {
        self.timings.iter().any(|t| t.name == name && t.raster)
    }
}

/// Which shading variant a frame runs: 1 (with the specular term) only if the scene has specular
/// materials.
pub fn specular_variant(p: &FrameParams) -> usize {
    usize::from(p.effects & EFFECT_SPECULAR != 0)
}

/// The pipeline of a frame's shading kernel: its specular variant ([`specular_variant`]) for the
/// frame's light types (`vk::light_typed`).
pub fn shading_pipeline<'g, P: bytemuck::Pod>(variants: &'g [crate::gpu::LightCompute<P>; 2], p: &FrameParams) -> crate::vk::VkResult<&'g crate::vk::ComputePipeline<P>> {
    variants[specular_variant(p)].get(p.effects)
}

/// Lights per pixel at the top of the heatmap ramp.
pub const HEAT_MAX: u32 = 64;

/// Renders one frame (plus `settings.frames` timed repetitions): a loop over
/// [`Renderer::frame`] (`renderer.rs`), the first frame a warm-up unless it is the only one.
pub fn render(gpu: &Gpu, scene: &SceneInput<'_>, s: &Settings) -> Result<Frame> {
    let mut renderer = Renderer::new(gpu, scene, s)?;
    let mut timed = Vec::new();
    for f in 0..=s.frames {
        let times = renderer.frame(gpu)?;
        if f > 0 || s.frames == 0 {
            timed.push(times);
        }
    }
    renderer.into_report(&timed, s.read_back)
}

/// Per-pass median over frames, and the (min, max) beside it (passes matched by position).
fn median_timings(all: &[Vec<PassTiming>]) -> (Vec<PassTiming>, Vec<(f64, f64)>) {
    let Some(first) = all.first() else { return (Vec::new(), Vec::new()) };
    first
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // The first frame has pass i, so the spread is of at least one value.
            let (ms, lo, hi) = frame_time::spread(all.iter().filter_map(|f| f.get(i).map(|t| t.ms))).unwrap_or_default();
            (PassTiming { ms, ..p.clone() }, (lo, hi))
        })
        .unzip()
}
