//! The one shape of a lighting technique, and what every technique reads.
//!
//! Life cycle, driven by the frame loop in [`super::render`]:
//! 1. **create** for the frame's size, scene and settings (`Technique::create`, the registry in
//!    `render/mod.rs`): allocate, check limits, precompute what depends on the grid only;
//! 2. per frame, **record**: [`LightingTechnique::record_async`] on the async-compute queue
//!    (work that depends on the lights only), then — after the G-buffer pass, which the frame loop
//!    records once when [`Description::gbuffer`] — [`LightingTechnique::record`] on the
//!    main queue;
//! 3. after the frame, **grow**: [`LightingTechnique::grow_if_needed`] reads the GPU counters
//!    back; a view-dependent buffer that was too small is grown and the frame loop re-runs the
//!    frame (at most [`MAX_REGROWTHS`] times), so no frame ever drops a light;
//! 4. **report**: [`LightingTechnique::stats`] (light lists of the last frame),
//!    [`LightingTechnique::buffers`] (bytes per buffer) and, for CPU checks,
//!    [`LightingTechnique::cluster_lists`] and [`LightingTechnique::tile_lists`].
use super::gbuffer::{Draw, Geometry, Targets, Textures};
use super::Settings;
use crate::gpu::Gpu;
use crate::vk::{Binding, Buffer, Recorder, VkResult};
use anyhow::Result;
use shaders::kernels::{Kernel, RasterKernel};
use shaders::layout::{FrameParams, PointLight};

/// Regrowths of a frame's buffers after which the frame loop gives up (each grows a buffer to
/// what the frame needed + 25 %, so one is enough unless the need itself keeps changing).
pub const MAX_REGROWTHS: u32 = 8;

/// First capacity of a light-reference list: 8 references per light, at least 4096 and at
/// most 2^24 (the need is read back after the first frame; more grows).
pub fn initial_list_capacity(lights: u32) -> u32 {
    lights.saturating_mul(8).clamp(4096, 1 << 24)
}

/// The capacity for a frame that needed `need` entries: the need + 25 %, so a view that moves a
/// little does not regrow at once.
pub fn grown_capacity(need: u32) -> u32 {
    need.saturating_add(need / 4)
}

/// What grew after a frame, of two buffers' growths (`"a, b"` when both grew).
pub fn grew_together(a: Option<String>, b: Option<String>) -> Option<String> {
    match (a, b) {
        (Some(a), Some(b)) => Some(format!("{a}, {b}")),
        (a, b) => a.or(b),
    }
}

/// Everything a technique can read: the frame's parameters and the GPU buffers the frame loop
/// uploads and allocates once per render.
pub struct FrameInputs<'a> {
    /// The frame's parameters (`light_capacity` 0: each technique sets its own).
    pub params: FrameParams,
    pub settings: &'a Settings,
    pub geometry: &'a Geometry,
    /// The merged index list on the CPU (Forward+ draws it in reverse order).
    pub indices: &'a [u32],
    pub textures: &'a Textures,
    pub camera: &'a Buffer,
    /// G-buffer targets and their buffer copies.
    pub targets: &'a Targets,
    /// The multisampled frame's edge list and passes (`--msaa` above 1, `msaa.rs`): a technique
    /// whose `Description::msaa` is set shades the listed edge pixels per sample.
    pub msaa: Option<&'a super::msaa::Multisampling>,
    /// View-space lights, on the GPU and (for host-side builds) on the CPU.
    pub lights: &'a Buffer,
    pub lights_view: &'a [PointLight],
    pub materials: &'a Buffer,
    /// The exponential depth-slice table of the cluster grid.
    pub bounds: &'a Buffer,
    /// The output frame (one packed RGBA8 word per pixel).
    pub frame: &'a Buffer,
    /// The cube shadow maps (scenes with shadow-casting lights only).
    pub shadows: Option<&'a super::shadow_maps::ShadowMaps>,
}

impl FrameInputs<'_> {
    /// The shadow slots and maps a shading kernel binds after its own buffers
    /// (`shaders::shadow::CubeShadows`); without shadow-casting lights, the light buffer twice in
    /// their place (the pipelines then hold no lookup, and nothing is allocated for them).
    pub fn shadow_buffers(&self) -> [&Buffer; 2] {
        match self.shadows {
            Some(s) => [&s.slots, &s.maps],
            None => [self.lights, self.lights],
        }
    }

    /// Records the cube shadow maps' pass (scenes with shadow-casting lights; nothing without)
    /// from the depths in `targets.depth_buf`: the frame loop records it after the G-buffer, and
    /// a technique without the G-buffer pass ([`Description::gbuffer`] false) once it has put its
    /// own depths there, before its shading reads [`FrameInputs::shadow_buffers`].
    pub fn record_shadow_maps(&self, rec: &mut Recorder<'_>) -> VkResult<()> {
        match self.shadows {
            Some(sh) => rec.pass("shadow maps", |rec| sh.record(rec, self.geometry, self.camera, &self.targets.depth_buf, self.params.grid)),
            None => Ok(()),
        }
    }

    /// The bindings of a draw of a raster pass: the vertex stage's storage buffers, `extra`
    /// storage buffers of the fragment stage, then the draw's `textures` (0, 1 or 2).
    pub fn draw_bindings<'b>(&'b self, extra: &[&'b Buffer], draw: &Draw, textures: usize) -> Vec<Binding<'b>> {
        self.geometry
            .vertex_bindings(self.camera)
            .chain(extra.iter().map(|b| Binding::Buffer(b)))
            .chain(self.textures.bindings_of(draw, textures))
            .collect()
    }
}

/// The light lists of the last frame (0 where a technique has no such thing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ListStats {
    /// Clusters that held pixels (unique or active clusters).
    pub clusters: u32,
    /// Light references of all lists together.
    pub light_refs: u32,
    /// Pages of the virtual page table touched.
    pub pages: u32,
    /// The longest list of one tile or cluster (tiled, forward+ and clustered-aabb).
    pub max_list: u32,
}

/// Per-cluster light lists read back for CPU checks (the clustered techniques).
pub struct ClusterLists {
    pub keys: Vec<u32>,
    pub unique: Vec<u32>,
    pub counts: Vec<u32>,
    pub offsets: Vec<u32>,
    pub list: Vec<u32>,
}

/// Everything the program knows of a technique besides its passes: one `const` beside the
/// technique's own code, registered with one line in `render/mod.rs` (`techniques!`). The CLI,
/// the viewer, the preflight checks, the bench and the tests read a technique only through this.
pub struct Description {
    /// The command-line name (`--technique`, `--techniques`, the viewer's overlay).
    pub name: &'static str,
    /// One line: what the technique does and after whom (`--help`, the README's table).
    pub summary: &'static str,
    /// Creates the technique for a frame (allocate, check limits).
    pub create: fn(&Gpu, &FrameInputs<'_>) -> Result<Box<dyn LightingTechnique>>,
    /// How it meets a scene with transparent draws. No default: a technique says which.
    pub transparent: TransparentDraws,
    /// Whether the frame loop records the G-buffer pass before [`LightingTechnique::record`]
    /// (Forward+ rasterises its own depth pre-pass instead, and so cannot draw adaptive NURBS
    /// levels, which only the G-buffer's indirect draws take).
    pub gbuffer: bool,
    /// Its passes (by their timing names) that rasterise, beside the G-buffer: only part of a GPU
    /// runs raster work, so the timings report raster and compute apart (`tests/bench.rs` checks
    /// the recorder marks exactly these and the G-buffer as raster).
    pub raster_passes: &'static [&'static str],
    /// How its light tests grow with the frame (the bench's skip rule, `--stats`' lists).
    pub cost: LightCost,
    /// The largest `--tile-size` it takes (`None`: any the grid takes).
    pub max_tile: Option<u32>,
    /// The most lights one frame may have on lavapipe, whose loop limiter ends an invocation's
    /// loops after 65 535 iterations, for a tile size.
    pub llvmpipe_lights: fn(u32) -> u32,
    /// The settings beyond the common ones that reach its kernels (`--stats` reports them, the
    /// tests run each value).
    pub knobs: &'static [Knob],
    /// Compute and raster entry points of pipelines the technique creates itself (not in
    /// `gpu::Kernels`): `tests/spirv_val.rs` checks them against the modules.
    pub own_kernels: &'static [Kernel<()>],
    pub own_raster: &'static [RasterKernel<()>],
    /// Whether it shades the edge pixels of a multisampled G-buffer per sample (`--msaa N`,
    /// `render/msaa.rs`: [`FrameInputs::msaa`] is then set and its `record` adds the edge pass);
    /// `--msaa` above 1 is refused in one line for the others.
    pub msaa: bool,
    /// 32-bit words per light of the largest buffer it keeps per light besides the light buffer
    /// (bound whole, so below 2^31 bytes: the preflight's light limit names it); 0 for none.
    pub light_words: u32,
    /// Whether its shading multiplies each shadow-casting light by its visibility from the
    /// frame's cube shadow maps (`shadow_maps.rs`; it binds [`FrameInputs::shadow_buffers`],
    /// and without the G-buffer pass records the maps itself, [`FrameInputs::record_shadow_maps`]);
    /// scenes with shadow-casting lights are refused in one line for the others.
    pub shadows: bool,
}

/// How a technique meets a scene with transparent draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransparentDraws {
    /// It records the transparent pass (`transparent.rs`): the frame loop fails a frame of a
    /// transparent scene whose technique reports no transparent pass.
    Drawn,
    /// It refuses such scenes with one line naming itself and the materials.
    Refused,
}

/// How many light tests a technique makes per frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightCost {
    /// Every light at every pixel (brute force).
    EveryLightPerPixel,
    /// Every light against every cluster that holds pixels.
    EveryLightPerCluster,
    /// Lights culled by a hierarchy, per tile or by rasterisation: about the lights that touch.
    Culled,
}

/// A setting of [`super::Settings`] only some techniques read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    /// `--fp-lists`: the layout of Forward+'s per-tile lists.
    FpLists,
    /// `--unique-clusters`: how the clustered techniques find the frame's clusters.
    UniqueClusters,
    /// `--sort`, `--bvh-branching` and `--morton-bits`: the light sort and hierarchy.
    LightHierarchy,
}

/// A technique's constructor result as [`Description::create`] returns it.
pub fn boxed<T: LightingTechnique + 'static>(t: Result<T>) -> Result<Box<dyn LightingTechnique>> {
    Ok(Box::new(t?))
}

/// [`Description::llvmpipe_lights`] of a technique whose loops visit a light per iteration in
/// chunks (`shaders::light_lists`).
pub fn llvmpipe_chunked_lights(_tile_size: u32) -> u32 {
    shaders::light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE
}

/// One lighting technique (see the module doc for the life cycle).
pub trait LightingTechnique {
    /// Whether [`Self::record_async`] records any work.
    fn has_async_work(&self) -> bool {
        false
    }

    /// Records the passes that depend on the lights only; they run on the async-compute queue
    /// (overlapping the G-buffer raster) where the device has one, else first on the main queue.
    fn record_async(&self, _gpu: &Gpu, _rec: &mut Recorder<'_>, _f: &FrameInputs<'_>) -> VkResult<()> {
        Ok(())
    }

    /// Between frames, the same lights moved in view space (the viewer's camera or animation;
    /// `f.lights_view` holds them): a technique that precomputed something from their positions
    /// updates it.
    fn lights_moved(&mut self, _f: &FrameInputs<'_>) {}

    /// Records the technique's passes on the main queue (after the G-buffer pass).
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()>;

    /// After a frame: reads its counters back and, when a view-dependent buffer was too small,
    /// grows it and says what grew (the frame loop then re-runs the frame).
    fn grow_if_needed(&mut self, _gpu: &Gpu) -> Result<Option<String>> {
        Ok(None)
    }

    /// The light lists of the last frame.
    fn stats(&mut self) -> Result<ListStats> {
        Ok(ListStats::default())
    }

    /// Bytes per sample of the targets and buffers it multisamples itself (`None`: the
    /// G-buffer's, `msaa::bytes_per_sample`).
    fn msaa_bytes_per_sample(&self) -> Option<u64> {
        None
    }

    /// Edge pixels of the last frame where it classifies them itself (`None`: the multisampled
    /// G-buffer's edge list counts them, `msaa.rs`).
    fn msaa_edge_pixels(&mut self) -> VkResult<Option<u32>> {
        Ok(None)
    }

    /// What the transparent pass of the last frame did (`None`: the frame had none).
    fn transparency(&self) -> Option<super::transparent::TransparencyStats> {
        None
    }

    /// Bytes of each buffer the technique owns.
    fn buffers(&self) -> Vec<(String, u64)>;

    /// The per-cluster lists of the last frame, for CPU checks (`None`: not a clustered technique).
    fn cluster_lists(&mut self) -> Result<Option<ClusterLists>> {
        Ok(None)
    }

    /// Each screen tile's light list of the last frame as the GPU stored it (tiles row by row),
    /// for CPU checks (`None`: the technique keeps no per-tile lists in memory).
    fn tile_lists(&mut self) -> Result<Option<Vec<Vec<u32>>>> {
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::super::Technique;
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn the_registry_lists_every_technique_once_under_its_command_line_name() {
        assert_eq!(Technique::ALL, Technique::value_variants(), "ALL is the registration order of every variant");
        let names: Vec<&str> = Technique::ALL.iter().map(|t| t.name()).collect();
        for (t, name) in Technique::ALL.iter().zip(&names) {
            assert_eq!(Technique::from_str(name, false), Ok(*t), "{name} parses back to {t:?}");
            assert_eq!(t.to_possible_value().map(|v| v.get_name().to_string()).as_deref(), Some(*name));
        }
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "names are unique: {names:?}");
        assert_eq!(Technique::ALL[0], Technique::Deferred, "the reference comes first (viewer key 1, the bench's first row)");
        assert!(Technique::ALL.len() <= 9, "every technique has a viewer number key 1–9");
        for t in Technique::ALL {
            let d = t.description();
            assert!(d.name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '.'), "{}: a command-line name", d.name);
            assert!(d.summary.ends_with('.') && !d.summary.contains('\n'), "{}: a one-line summary", d.name);
            if let Some(max) = d.max_tile {
                assert!((1..=shaders::cluster_key::MAX_TILE_SIZE).contains(&max), "{}: max tile {max}", d.name);
            }
            assert!((d.llvmpipe_lights)(32) > 0, "{}: takes lights on lavapipe", d.name);
        }
    }

    #[test]
    fn list_capacities_start_bounded_and_grow_past_the_need() {
        assert_eq!(initial_list_capacity(0), 4096);
        assert_eq!(initial_list_capacity(1000), 8000);
        assert_eq!(initial_list_capacity(u32::MAX), 1 << 24, "no overflow, capped");
        for need in [0, 1, 4, 1000, 1 << 24, u32::MAX / 2, u32::MAX] {
            let g = grown_capacity(need);
            assert!(g >= need, "grown capacity {g} holds the need {need}");
            assert!(need < 4 || g > need || need == u32::MAX, "grows by a quarter: {need} → {g}");
        }
    }
}
