//! Cube shadow maps for the lights that cast shadows (steps, face layout, bias rule and memory:
//! `shaders::shadow`). Made only for scenes with such lights; the frame records one raster pass
//! ("shadow maps") after the G-buffer: the maps cleared, then the scene's opaque draws instanced
//! six times per shadow-casting light. Techniques that render shadows bind [`ShadowMaps::slots`]
//! and [`ShadowMaps::maps`] beside their lights (`FrameInputs::shadow_buffers`).
//!
//! Every shadow-casting light gets a full map at [`ShadowSettings::resolution`]: this is the
//! plain form of the virtual cube shadow maps of Olsson et al. (no per-face culling, no page
//! table), the reference their resolution choices are measured against.
use super::gbuffer::Geometry;
use crate::vk::{Attachment, Binding, Buffer, Context, GraphicsPipeline, Image, ImageUse, Load, Recorder, TargetFormat, VkResult};
use anyhow::{bail, Context as _, Result};
use shaders::layout::PointLight;
use shaders::shadow::{caster_record, handles, ShadowParams, FACES, NO_OCCLUDER, NO_SHADOW, SHADOW_FILTER_BILINEAR, SHADOW_FILTER_NEAREST, SHADOW_HEADER_WORDS};

/// Texels per face side unless `--shadow-resolution` says otherwise.
pub const DEFAULT_RESOLUTION: u32 = 256;
/// The largest face side accepted.
pub const MAX_RESOLUTION: u32 = 4096;

/// How the lookup filters (`--shadow-filter`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ShadowFilter {
    /// One texel: hard edges, stair-stepped at the map's resolution.
    Nearest,
    /// 2 × 2 percentage-closer filtering, bilinearly weighted.
    #[default]
    Bilinear,
}

impl ShadowFilter {
    fn code(self) -> u32 {
        match self {
            ShadowFilter::Nearest => SHADOW_FILTER_NEAREST,
            ShadowFilter::Bilinear => SHADOW_FILTER_BILINEAR,
        }
    }
}

/// The shadow maps' knobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowSettings {
    /// Texels per face side.
    pub resolution: u32,
    pub filter: ShadowFilter,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { resolution: DEFAULT_RESOLUTION, filter: ShadowFilter::default() }
    }
}

/// Checks `--shadow-resolution`.
pub fn check_resolution(res: u32) -> Result<()> {
    if res == 0 || res > MAX_RESOLUTION {
        bail!("--shadow-resolution {res}: texels per cube face side must be in 1..={MAX_RESOLUTION}");
    }
    Ok(())
}

/// The frame's cube shadow maps.
pub struct ShadowMaps {
    pipe: GraphicsPipeline<ShadowParams>,
    settings: ShadowSettings,
    /// Light index of each caster, in slot order.
    casters: Vec<u32>,
    /// `[res, filter, 0, 0]`, then each light's slot or `NO_SHADOW`.
    pub slots: Buffer,
    /// Each caster's view-space position and radius (the raster pass's vertex stage).
    records: Buffer,
    /// Slot-major, face-major, row-major distances.
    pub maps: Buffer,
    /// The raster pass's render area (`res × res`, never tested or written).
    area: Image,
}

impl ShadowMaps {
    /// The maps of the lights `casters` marks (one flag per light of `lights_view`); `None`
    /// where none casts shadows (nothing is made).
    pub fn new(ctx: &Context, module: &crate::vk::ShaderModule, casters: &[bool], lights_view: &[PointLight], settings: ShadowSettings) -> Result<Option<Self>> {
        check_resolution(settings.resolution)?;
        let list: Vec<u32> = casters.iter().enumerate().filter(|(_, &c)| c).map(|(i, _)| i as u32).collect();
        if list.is_empty() {
            return Ok(None);
        }
        if casters.len() != lights_view.len() {
            bail!("{} shadow flags for {} lights", casters.len(), lights_view.len());
        }
        let res = settings.resolution as u64;
        let bytes = 4 * FACES as u64 * res * res * list.len() as u64;
        crate::vk::memory::check_range(ctx, "shadow maps", bytes).with_context(|| format!("{} shadow-casting lights at {res}² texels per face: lower --shadow-resolution", list.len()))?;
        let mut slots = vec![settings.resolution, settings.filter.code(), 0, 0];
        slots.extend(std::iter::repeat_n(NO_SHADOW, lights_view.len()));
        for (slot, &l) in list.iter().enumerate() {
            slots[(SHADOW_HEADER_WORDS + l) as usize] = slot as u32;
        }
        let maps = Self {
            pipe: GraphicsPipeline::new(ctx, module, "shadow maps", handles::SHADOW_DISTANCES, &[], crate::vk::DepthTest::Off)?,
            settings,
            records: Buffer::from_slice(ctx, "shadow caster records", &records(&list, lights_view))?,
            casters: list,
            slots: Buffer::from_slice(ctx, "shadow slots", &slots)?,
            maps: Buffer::storage(ctx, "shadow maps", bytes).context("allocating the shadow maps")?,
            area: Image::target(ctx, "shadow map area", settings.resolution, settings.resolution, TargetFormat::Depth32)?,
        };
        Ok(Some(maps))
    }

    /// Uploads the casters' records anew (the lights or the camera moved).
    pub fn lights_moved(&mut self, lights_view: &[PointLight]) -> Result<()> {
        if let Some(&l) = self.casters.iter().find(|&&l| l as usize >= lights_view.len()) {
            bail!("shadow-casting light {l} is past the {} lights of the frame", lights_view.len());
        }
        self.records.write(&records(&self.casters, lights_view)).context("uploading the shadow casters")?;
        Ok(())
    }

    /// Shadow-casting lights.
    pub fn casters(&self) -> usize {
        self.casters.len()
    }

    pub fn settings(&self) -> ShadowSettings {
        self.settings
    }

    /// Records the pass: clear, then every opaque draw once per face of every caster.
    pub fn record(&self, rec: &mut Recorder<'_>, geometry: &Geometry, camera: &Buffer) -> VkResult<()> {
        rec.fill(&self.maps, NO_OCCLUDER);
        rec.fragments_read_earlier_writes();
        rec.transition(&self.area, ImageUse::Undefined, ImageUse::DepthTarget);
        rec.begin_rendering(&[], Attachment { image: &self.area, load: Load::ClearDepth(0.0) }, &geometry.indices);
        let bindings = [&geometry.positions, camera, &self.records, &self.maps].map(Binding::Buffer);
        let params = ShadowParams { res: self.settings.resolution, pad: [0; 3] };
        let instances = FACES * self.casters.len() as u32;
        for d in geometry.draws.iter().filter(|d| d.index_count > 0) {
            rec.draw_indexed_instanced(&self.pipe, &bindings, &params, d.first_index, d.index_count, instances)?;
        }
        rec.end_rendering();
        rec.kernels_read_fragment_writes();
        Ok(())
    }

    /// The buffers, by name and bytes.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        [&self.slots, &self.records, &self.maps].iter().map(|b| (b.name.clone(), b.size)).collect()
    }
}

/// The raster pass's records of `casters` (`shaders::shadow::caster_record`).
fn records(casters: &[u32], lights_view: &[PointLight]) -> Vec<[f32; 4]> {
    casters.iter().map(|&l| caster_record(&lights_view[l as usize])).collect()
}
