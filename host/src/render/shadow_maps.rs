//! Cube shadow maps for the lights that cast shadows (face layout, bias rule and memory:
//! `shaders::shadow`; batches and per-face culling: `shaders::shadow_cull`). Made only for scenes
//! with such lights; the frame records one pass ("shadow maps") after the G-buffer:
//!
//! 1. the maps cleared to "no occluder" and the draw's arguments to zero;
//! 2. the faces with receivers (`shaders::shadow_receivers`, [`ShadowFaces::Receivers`]): the
//!    G-buffer's tiles of 16² pixels as two spheres each, tested against every caster's faces;
//!    each caster keeps the faces the frame's pixels look up;
//! 3. the cull kernel: every batch of 64 opaque triangles against every caster's six faces,
//!    an entry per face with receivers its bounding sphere meets within the light's radius;
//! 4. the arguments kernel, then every entry's triangles into its face: by default one indirect
//!    dispatch of the compute rasteriser (`shaders::shadow_raster`, a workgroup per entry), or
//!    with [`ShadowRaster::Draw`] one indirect draw through the fixed-function rasteriser (the
//!    two write the same texels; `docs/results/h200/shadows/` measures them side by side).
//!
//! Techniques that render shadows bind [`ShadowMaps::slots`] and [`ShadowMaps::maps`] beside
//! their lights (`FrameInputs::shadow_buffers`).
//!
//! Every shadow-casting light gets a whole map at [`ShadowSettings::resolution`]: Olsson et al.'s
//! virtual cube shadow maps without their page table (no per-face resolution choice). Where the
//! maps would pass the device's largest storage binding, the resolution halves until they fit,
//! and `--stats` and `render` say so ([`ShadowStats::degraded_from`]); no caster is dropped.
//!
//! Memory: the maps (`shaders::shadow`), 12 B per opaque triangle (its indices in the batches'
//! order, [`shadow_triangles`]), 32 B per batch (0.5 B per triangle), 8 B per entry
//! (counted on the host when the lights or the camera move: [`count_entries`], an upper bound
//! that ignores the receivers), 16 B per caster record and 4 B per caster of faces with
//! receivers, 32 B per 16² pixels of receiver tiles.
use super::gbuffer::{Draw, Geometry};
use crate::gpu::Gpu;
use crate::vk::{Attachment, Binding, Buffer, ComputePipeline, Context, GraphicsPipeline, Image, ImageUse, Load, Recorder, TargetFormat, VkResult};
use anyhow::{bail, Context as _, Result};
use glam::{Mat4, Vec3};
use shaders::layout::PointLight;
use shaders::shadow_raster::ShadowRasterParams;
use shaders::shadow::{caster_record, ShadowParams, FACES, NO_OCCLUDER, NO_SHADOW, SHADOW_FILTER_BILINEAR, SHADOW_FILTER_NEAREST, SHADOW_HEADER_WORDS};
use shaders::layout::ClusterGrid;
use shaders::shadow_receivers::{handles as receiver_handles, ReceiverParams, RECEIVER_TILE, RECEIVER_WORKGROUP, TILES_PER_INVOCATION, TILE_WORDS};
use shaders::shadow_cull::{face_mask, handles, ShadowCullParams, ARGS_COUNTED, ARGS_DISPATCH, ARGS_FACES, ARGS_WORDS, BATCH_TRIANGLES, BATCH_WORDS, CULL_MARGIN, CULL_WORKGROUP, ENTRY_WORDS};

/// Texels per face side unless `--shadow-resolution` says otherwise.
pub const DEFAULT_RESOLUTION: u32 = 256;
/// The largest face side accepted.
pub const MAX_RESOLUTION: u32 = 4096;
/// The most shadow-casting lights: the cull dispatches one row of workgroups per caster.
pub const MAX_CASTERS: usize = shaders::indirect::MAX_GROUPS_PER_AXIS as usize;
/// The smallest face side the maps degrade to where the requested one does not fit.
pub const MIN_DEGRADED_RESOLUTION: u32 = 8;

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

/// What writes the culled triangles into the maps (`--shadow-raster`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ShadowRaster {
    /// A compute kernel, a workgroup per culled batch and face (`shaders::shadow_raster`).
    #[default]
    Compute,
    /// One indirect draw through the fixed-function rasteriser (`shaders::shadow_cull`).
    Draw,
}

/// Which faces of the casters' cube maps get triangles (`--shadow-faces`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ShadowFaces {
    /// Only faces that pixels of the frame look up (`shaders::shadow_receivers`).
    #[default]
    Receivers,
    /// Every face a batch's sphere meets within the light's radius.
    All,
}

/// The shadow maps' knobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowSettings {
    /// Texels per face side.
    pub resolution: u32,
    pub filter: ShadowFilter,
    pub raster: ShadowRaster,
    pub faces: ShadowFaces,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { resolution: DEFAULT_RESOLUTION, filter: ShadowFilter::default(), raster: ShadowRaster::default(), faces: ShadowFaces::default() }
    }
}

/// Checks `--shadow-resolution`.
pub fn check_resolution(res: u32) -> Result<()> {
    if res == 0 || res > MAX_RESOLUTION {
        bail!("--shadow-resolution {res}: texels per cube face side must be in 1..={MAX_RESOLUTION}");
    }
    Ok(())
}

/// What `--stats` reports of the shadow maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowStats {
    pub casters: usize,
    /// Texels per face side drawn, and the requested side where that had to be lower.
    pub resolution: u32,
    pub degraded_from: Option<u32>,
    /// Batches of triangles the batches' cull sent to faces in the last frame, and the triangles
    /// of the scene's opaque draws per face at most (batches × 64 × 6 per caster).
    pub entries: u32,
    pub batches: usize,
    /// Faces of the casters that pixels of the last frame looked up (all six per caster with
    /// [`ShadowFaces::All`]).
    pub faces_with_receivers: u32,
}

/// Checks the number of shadow-casting lights against [`MAX_CASTERS`].
pub fn check_casters(casters: usize) -> Result<()> {
    if casters > MAX_CASTERS {
        bail!("{casters} lights cast shadows: the shadow maps take at most {MAX_CASTERS}");
    }
    Ok(())
}

/// The frame's cube shadow maps.
pub struct ShadowMaps {
    cull: ComputePipeline<ShadowCullParams>,
    args_pipe: ComputePipeline<ShadowCullParams>,
    /// The receivers' tiles and faces (`None`: every face, [`ShadowFaces::All`]).
    receivers: Option<Receivers>,
    /// Per caster, the faces with receivers (all six set with [`ShadowFaces::All`]).
    needed: Buffer,
    /// What writes the entries' triangles: the compute rasteriser, or the draw and its render area
    /// (`res × res`, never tested or written).
    writer: Writer,
    /// The resolution drawn (the requested one, or lower where it did not fit) and the filter.
    settings: ShadowSettings,
    /// The requested resolution where the maps had to drop below it.
    degraded_from: Option<u32>,
    /// Light index of each caster, in slot order.
    casters: Vec<u32>,
    /// `[res, filter, 0, 0]`, then each light's slot or `NO_SHADOW`.
    pub slots: Buffer,
    /// Each caster's view-space position and radius (cull and raster).
    records: Buffer,
    records_cpu: Vec<[f32; 4]>,
    /// The batches (`shaders::shadow_cull::BATCH_WORDS` each) and their spheres on the host, in
    /// the position buffer's space (relative to the eye).
    batches: Buffer,
    spheres: Vec<[f32; 4]>,
    /// The opaque triangles' indices in the batches' order ([`shadow_triangles`]), on the GPU and
    /// the host.
    indices: Buffer,
    order: Vec<u32>,
    /// The view's rotation (position-buffer space → view space).
    rotation: Mat4,
    /// Entries of the last count, and their buffer.
    capacity: u32,
    /// Entries the last frame's cull counted, and the faces with receivers it found.
    counted: u32,
    faces: u32,
    entries: Buffer,
    /// The indirect draw's arguments and the entries counted (`shaders::shadow_cull::ARGS_WORDS`).
    args: Buffer,
    /// Slot-major, face-major, row-major distances.
    pub maps: Buffer,
}

/// [`ShadowFaces::Receivers`]' pipelines and the G-buffer's tiles (`shaders::shadow_receivers`).
struct Receivers {
    tiles_pipe: ComputePipeline<ReceiverParams>,
    faces_pipe: ComputePipeline<ReceiverParams>,
    tiles: Buffer,
}

/// [`ShadowRaster`]'s pipelines.
enum Writer {
    Compute(ComputePipeline<ShadowRasterParams>),
    Draw { pipe: GraphicsPipeline<ShadowParams>, area: Image },
}

impl ShadowMaps {
    /// The maps of the lights `casters` marks (one flag per light of `lights_view`), drawing the
    /// opaque `draws` of `indices` over `positions` (the position buffer's contents; `rotation`
    /// takes them to view space); `None` where no light casts shadows (nothing is made).
    #[allow(clippy::too_many_arguments)]
    pub fn new(gpu: &Gpu, positions: &[[f32; 3]], indices: &[u32], draws: &[Draw], rotation: Mat4, casters: &[bool], lights_view: &[PointLight], settings: ShadowSettings, frame: (u32, u32)) -> Result<Option<Self>> {
        let ctx = &gpu.ctx;
        check_resolution(settings.resolution)?;
        let list: Vec<u32> = casters.iter().enumerate().filter(|(_, &c)| c).map(|(i, _)| i as u32).collect();
        if list.is_empty() {
            return Ok(None);
        }
        if casters.len() != lights_view.len() {
            bail!("{} shadow flags for {} lights", casters.len(), lights_view.len());
        }
        check_casters(list.len())?;
        let (resolution, bytes) = fitting_resolution(ctx, settings.resolution, list.len())?;
        let degraded_from = (resolution != settings.resolution).then_some(settings.resolution);
        let settings = ShadowSettings { resolution, ..settings };
        let mut slots = vec![settings.resolution, settings.filter.code(), 0, 0];
        slots.extend(std::iter::repeat_n(NO_SHADOW, lights_view.len()));
        for (slot, &l) in list.iter().enumerate() {
            slots[(SHADOW_HEADER_WORDS + l) as usize] = slot as u32;
        }
        let order = shadow_triangles(positions, indices, draws);
        let (batch_words, spheres) = batches(positions, &order);
        let records_cpu = records(&list, lights_view);
        let capacity = entry_capacity(ctx, &spheres, rotation, &records_cpu)?;
        let writer = match settings.raster {
            ShadowRaster::Compute => Writer::Compute(ComputePipeline::new(ctx, &gpu.compute_module, shaders::shadow_raster::handles::SHADOW_RASTER)?),
            ShadowRaster::Draw => Writer::Draw {
                pipe: GraphicsPipeline::new(ctx, &gpu.graphics_module, "shadow maps", handles::SHADOW_BATCHES, &[], crate::vk::DepthTest::Off)?,
                area: Image::target(ctx, "shadow map area", settings.resolution, settings.resolution, TargetFormat::Depth32)?,
            },
        };
        let receivers = match settings.faces {
            ShadowFaces::Receivers => {
                let tiles = frame.0.div_ceil(RECEIVER_TILE) as u64 * frame.1.div_ceil(RECEIVER_TILE) as u64;
                Some(Receivers {
                    tiles_pipe: ComputePipeline::new(ctx, &gpu.compute_module, receiver_handles::SHADOW_RECEIVER_TILES)?,
                    faces_pipe: ComputePipeline::new(ctx, &gpu.compute_module, receiver_handles::SHADOW_RECEIVER_FACES)?,
                    tiles: Buffer::storage(ctx, "shadow receiver tiles", 4 * TILE_WORDS as u64 * tiles)?,
                })
            }
            ShadowFaces::All => None,
        };
        let needed = match receivers {
            Some(_) => Buffer::storage(ctx, "shadow faces with receivers", 4 * list.len() as u64)?,
            None => Buffer::from_slice(ctx, "shadow faces with receivers", &vec![(1u32 << FACES) - 1; list.len()])?,
        };
        let maps = Self {
            cull: ComputePipeline::new(ctx, &gpu.compute_module, handles::SHADOW_CULL)?,
            args_pipe: ComputePipeline::new(ctx, &gpu.compute_module, handles::SHADOW_DRAW_ARGS)?,
            writer,
            receivers,
            needed,
            faces: 0,
            settings,
            degraded_from,
            records: Buffer::from_slice(ctx, "shadow caster records", &records_cpu)?,
            records_cpu,
            casters: list,
            slots: Buffer::from_slice(ctx, "shadow slots", &slots)?,
            batches: Buffer::from_slice(ctx, "shadow batches", &batch_words)?,
            indices: Buffer::from_slice(ctx, "shadow batch indices", &order)?,
            order,
            spheres,
            rotation,
            capacity,
            counted: 0,
            entries: entry_buffer(ctx, capacity)?,
            args: Buffer::storage(ctx, "shadow draw arguments", 4 * ARGS_WORDS as u64)?,
            maps: Buffer::storage(ctx, "shadow maps", bytes).context("allocating the shadow maps")?,
        };
        Ok(Some(maps))
    }

    /// Uploads the casters' records anew (the lights or the camera moved) and grows the entries
    /// to the new count where it passed them.
    pub fn lights_moved(&mut self, ctx: &Context, lights_view: &[PointLight]) -> Result<()> {
        if let Some(&l) = self.casters.iter().find(|&&l| l as usize >= lights_view.len()) {
            bail!("shadow-casting light {l} is past the {} lights of the frame", lights_view.len());
        }
        self.records_cpu = records(&self.casters, lights_view);
        self.records.write(&self.records_cpu).context("uploading the shadow casters")?;
        self.recount(ctx)
    }

    /// The position buffer's contents moved (the eye moved) and the view turned: the batches'
    /// spheres anew (the same triangles in each). The caller moves the lights next
    /// ([`ShadowMaps::lights_moved`]).
    pub fn view_moved(&mut self, positions: &[[f32; 3]], rotation: Mat4) -> Result<()> {
        let (words, spheres) = batches(positions, &self.order);
        self.batches.write(&words).context("uploading the shadow batches")?;
        (self.spheres, self.rotation) = (spheres, rotation);
        Ok(())
    }

    fn recount(&mut self, ctx: &Context) -> Result<()> {
        let capacity = entry_capacity(ctx, &self.spheres, self.rotation, &self.records_cpu)?;
        if capacity > self.capacity {
            self.entries = entry_buffer(ctx, capacity)?;
            self.capacity = capacity;
        }
        Ok(())
    }

    /// Fails where the last frame's cull counted more entries than it could write (which the
    /// host's widened count rules out): triangles would be missing from the maps.
    pub fn check_entries(&mut self) -> Result<()> {
        let args: Vec<u32> = self.args.read(ARGS_WORDS as usize)?;
        self.counted = args[ARGS_COUNTED];
        self.faces = if self.receivers.is_some() { args[ARGS_FACES] } else { FACES * self.casters.len() as u32 };
        if args[ARGS_COUNTED] > self.capacity {
            bail!("the shadow cull counted {} entries against the {} the host counted: shadow-map triangles would be missing", args[ARGS_COUNTED], self.capacity);
        }
        Ok(())
    }

    /// Shadow-casting lights.
    pub fn casters(&self) -> usize {
        self.casters.len()
    }

    /// The settings drawn (the resolution possibly below the requested one).
    pub fn settings(&self) -> ShadowSettings {
        self.settings
    }

    /// What `--stats` reports.
    pub fn stats(&self) -> ShadowStats {
        ShadowStats { casters: self.casters.len(), resolution: self.settings.resolution, degraded_from: self.degraded_from, entries: self.counted, batches: self.spheres.len(), faces_with_receivers: self.faces }
    }

    /// Records the pass: clear, the faces with receivers (from the G-buffer's reversed-Z `depth`
    /// over `grid`), cull, arguments, then every entry's triangles into the maps (one indirect
    /// dispatch or one indirect draw).
    pub fn record(&self, rec: &mut Recorder<'_>, geometry: &Geometry, camera: &Buffer, depth: &Buffer, grid: ClusterGrid) -> VkResult<()> {
        rec.fill(&self.maps, NO_OCCLUDER);
        rec.fill(&self.args, 0);
        let casters = self.casters.len() as u32;
        if let Some(r) = &self.receivers {
            rec.fill(&self.needed, 0);
            let p = ReceiverParams { grid, res: self.settings.resolution, casters, tiles_x: grid.width.div_ceil(RECEIVER_TILE), tiles_y: grid.height.div_ceil(RECEIVER_TILE) };
            let tiles = p.tiles_x * p.tiles_y;
            rec.dispatch_linear(&r.tiles_pipe, &[depth, &r.tiles], &p, tiles)?;
            rec.dispatch(&r.faces_pipe, &[&r.tiles, &self.records, &self.needed, &self.args], &p, [tiles.div_ceil(TILES_PER_INVOCATION * RECEIVER_WORKGROUP), casters, 1])?;
        }
        let batches = self.spheres.len() as u32;
        let p = ShadowCullParams { batches, casters, capacity: self.capacity, pad: 0 };
        rec.dispatch(&self.cull, &[camera, &self.batches, &self.records, &self.entries, &self.args, &self.needed], &p, [batches.div_ceil(CULL_WORKGROUP), p.casters, 1])?;
        rec.dispatch(&self.args_pipe, &[&self.args], &p, [1, 1, 1])?;
        match &self.writer {
            Writer::Compute(raster) => {
                let params = ShadowRasterParams { res: self.settings.resolution, capacity: self.capacity, pad: [0; 2] };
                let buffers = [&geometry.positions, &self.indices, camera, &self.records, &self.batches, &self.entries, &self.args, &self.maps];
                rec.dispatch_indirect(raster, &buffers, &params, &self.args, ARGS_DISPATCH)?;
            }
            Writer::Draw { pipe, area } => {
                rec.draws_read_kernel_writes();
                rec.fragments_read_earlier_writes();
                rec.transition(area, ImageUse::Undefined, ImageUse::DepthTarget);
                rec.begin_drawing(&[], Attachment { image: area, load: Load::ClearDepth(0.0) });
                let bindings = [&geometry.positions, &self.indices, camera, &self.records, &self.batches, &self.entries, &self.maps].map(Binding::Buffer);
                let params = ShadowParams { res: self.settings.resolution, pad: [0; 3] };
                rec.draw_indirect(pipe, &bindings, &params, &self.args)?;
                rec.end_rendering();
                rec.kernels_read_fragment_writes();
            }
        }
        Ok(())
    }

    /// The buffers, by name and bytes.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        let tiles = self.receivers.as_ref().map(|r| &r.tiles);
        [&self.slots, &self.records, &self.batches, &self.indices, &self.entries, &self.args, &self.needed, &self.maps].into_iter().chain(tiles).map(|b| (b.name.clone(), b.size)).collect()
    }
}

/// The largest resolution at most `requested` (halving) whose maps for `casters` fit one storage
/// binding, and their bytes; an error where not even [`MIN_DEGRADED_RESOLUTION`] fits.
fn fitting_resolution(ctx: &Context, requested: u32, casters: usize) -> Result<(u32, u64)> {
    let bytes = |res: u32| 4 * FACES as u64 * res as u64 * res as u64 * casters as u64;
    let mut res = requested;
    while crate::vk::memory::check_range(ctx, "shadow maps", bytes(res)).is_err() && res > MIN_DEGRADED_RESOLUTION {
        res = (res / 2).max(MIN_DEGRADED_RESOLUTION);
    }
    crate::vk::memory::check_range(ctx, "shadow maps", bytes(res)).with_context(|| format!("{casters} shadow-casting lights: even at {res}² texels per face their maps pass the device's largest storage binding"))?;
    Ok((res, bytes(res)))
}

/// The opaque draws' triangles (the indices of each, three per triangle) in the Morton order of
/// their centroids over the scene's box: consecutive triangles lie near each other wherever the
/// meshes' own order scatters them, so each batch of [`BATCH_TRIANGLES`] has a small sphere.
/// (Alpha-tested triangles occlude whole, as in the draw order.)
fn shadow_triangles(positions: &[[f32; 3]], indices: &[u32], draws: &[Draw]) -> Vec<u32> {
    let tris: Vec<[u32; 3]> = draws.iter().filter(|d| d.indirect.is_none()).flat_map(|d| indices[d.first_index as usize..(d.first_index + d.index_count) as usize].chunks_exact(3).map(|t| [t[0], t[1], t[2]])).collect();
    let centroids: Vec<Vec3> = tris.iter().map(|t| t.iter().fold(Vec3::ZERO, |c, &i| c + Vec3::from_array(positions[i as usize])) / 3.0).collect();
    let (lo, hi) = centroids.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &c| (lo.min(c), hi.max(c)));
    let q = shaders::morton::MortonQuantizer::new(lo.to_array(), hi.to_array(), shaders::morton::MORTON30_BITS);
    let mut keyed: Vec<(u32, usize)> = centroids.iter().enumerate().map(|(k, c)| (q.morton30_of(c.to_array()), k)).collect();
    keyed.sort_unstable();
    keyed.into_iter().flat_map(|(_, k)| tris[k]).collect()
}

/// Batches of [`BATCH_TRIANGLES`] consecutive triangles of `order` (`shaders::shadow_cull`): the
/// batch words and each batch's bounding sphere (box centre, half diagonal).
fn batches(positions: &[[f32; 3]], order: &[u32]) -> (Vec<u32>, Vec<[f32; 4]>) {
    let (mut words, mut spheres) = (vec![], vec![]);
    let triangles = (order.len() / 3) as u32;
    for first in (0..triangles).step_by(BATCH_TRIANGLES as usize) {
        let count = BATCH_TRIANGLES.min(triangles - first);
        let start = 3 * first as usize;
        let corners = order[start..start + 3 * count as usize].iter().map(|&i| Vec3::from_array(positions[i as usize]));
        let (lo, hi) = corners.fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        words.extend_from_slice(&[c.x.to_bits(), c.y.to_bits(), c.z.to_bits(), r.to_bits(), start as u32, count, 0, 0]);
        spheres.push([c.x, c.y, c.z, r]);
    }
    debug_assert_eq!(words.len(), spheres.len() * BATCH_WORDS as usize);
    (words, spheres)
}

/// The entries the cull can write for these casters: [`face_mask`] on each batch's sphere
/// widened by `CULL_MARGIN` of its distance and both radii, so that the GPU's unwidened test in
/// its own rounding never finds more.
pub fn count_entries(spheres: &[[f32; 4]], rotation: Mat4, records: &[[f32; 4]]) -> u64 {
    let view: Vec<(Vec3, f32)> = spheres.iter().map(|s| (rotation.transform_point3(Vec3::new(s[0], s[1], s[2])), s[3])).collect();
    let count_for = |records: &[[f32; 4]]| -> u64 {
        let mut n = 0u64;
        for rec in records {
            let (light, radius) = (Vec3::new(rec[0], rec[1], rec[2]), rec[3]);
            for &(c, r) in &view {
                let d = c - light;
                let widened = r + CULL_MARGIN * (d.length() + r + radius);
                n += face_mask(d, widened, radius).count_ones() as u64;
            }
        }
        n
    };
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(16);
    let chunk = records.len().div_ceil(threads).max(1);
    std::thread::scope(|s| records.chunks(chunk).map(|c| s.spawn(move || count_for(c))).collect::<Vec<_>>().into_iter().fold(0u64, |a, h| a.saturating_add(h.join().unwrap_or(u64::MAX))))
}

/// [`count_entries`] as a buffer capacity: at least one entry, and refused in one line where the
/// entries pass a storage binding or the draw's vertex count.
fn entry_capacity(ctx: &Context, spheres: &[[f32; 4]], rotation: Mat4, records: &[[f32; 4]]) -> Result<u32> {
    let n = count_entries(spheres, rotation, records).max(1);
    let most = (u32::MAX / (3 * BATCH_TRIANGLES)) as u64;
    if n > most {
        bail!("the shadow maps would draw {n} batches of triangles, more than one indirect draw's {most}: fewer shadow-casting lights or smaller radii");
    }
    crate::vk::memory::check_range(ctx, "shadow draw entries", 4 * ENTRY_WORDS as u64 * n)?;
    Ok(n as u32)
}

fn entry_buffer(ctx: &Context, capacity: u32) -> Result<Buffer> {
    Buffer::storage(ctx, "shadow draw entries", 4 * ENTRY_WORDS as u64 * capacity as u64).context("allocating the shadow draw entries")
}

/// The raster pass's records of `casters` (`shaders::shadow::caster_record`).
fn records(casters: &[u32], lights_view: &[PointLight]) -> Vec<[f32; 4]> {
    casters.iter().map(|&l| caster_record(&lights_view[l as usize])).collect()
}
