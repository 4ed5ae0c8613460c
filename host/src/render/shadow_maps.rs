//! Cube shadow maps for the lights that cast shadows (face layout, bias rule and memory:
//! `shaders::shadow`; batches and per-face culling: `shaders::shadow_cull`). Made only for scenes
//! with such lights; the frame records one pass ("shadow maps") after the G-buffer:
//!
//! 1. the maps cleared to "no occluder" and the draw's arguments to zero;
//! 2. the faces with receivers (`shaders::shadow_receivers`, [`ShadowFaces::Receivers`]): the
//!    G-buffer's tiles of 16² pixels as two spheres each, tested against every caster's faces;
//!    each face the frame's pixels look up keeps the resolution level they ask;
//! 3. the atlas (`shaders::shadow_atlas`): the faces counted per level, then each given its side
//!    (halved as often as the atlas needs) and its first texel in the face table;
//! 4. the cull kernel: every batch of 64 opaque triangles against every caster's six faces,
//!    an entry per face with receivers its bounding sphere meets within the light's radius;
//! 5. the arguments kernel, then every entry's triangles into its face: by default one indirect
//!    dispatch of the compute rasteriser (`shaders::shadow_raster`, a workgroup per entry), or
//!    with [`ShadowRaster::Draw`] one indirect draw through the fixed-function rasteriser (the
//!    two write the same texels; `docs/results/h200/shadows/` measures them side by side).
//!
//! Techniques that render shadows bind [`ShadowMaps::slots`] and [`ShadowMaps::maps`] beside
//! their lights (`FrameInputs::shadow_buffers`).
//!
//! Each face gets the side its receivers ask, at most [`ShadowSettings::resolution`], in one
//! atlas shared by all casters ([`ShadowSettings::atlas_bytes`]; by default room for every face at
//! the largest side, within the device's largest storage binding). A frame whose faces ask for
//! more than the atlas holds halves every side until they fit, and `--stats` and `render` say so
//! ([`ShadowStats::shift`]); no caster or face is dropped.
//!
//! Memory: the atlas (`shaders::shadow`), 12 B per opaque triangle (its indices in the batches'
//! order, [`shadow_triangles`]), 32 B per batch (0.5 B per triangle), 8 B per entry
//! (counted on the host when the lights or the camera move: [`count_entries`], an upper bound
//! that ignores the receivers), 16 B per caster record, 4 B per caster face of levels and 8 B of
//! face table, 32 B per 16² pixels of receiver tiles.
use super::gbuffer::{Draw, Geometry};
use crate::gpu::Gpu;
use crate::vk::{Attachment, Binding, Buffer, ComputePipeline, Context, GraphicsPipeline, Image, ImageUse, Load, Recorder, TargetFormat, VkResult};
use anyhow::{bail, Context as _, Result};
use glam::{Mat4, Vec3};
use shaders::layout::PointLight;
use shaders::shadow_raster::ShadowRasterParams;
use shaders::shadow::{caster_record, CubeFrame, ShadowParams, CASTER_WORDS, FACES, FACE_WORDS, NO_OCCLUDER, NO_SHADOW, SHADOW_FILTER_BILINEAR, SHADOW_FILTER_NEAREST, SHADOW_HEADER_WORDS};
use shaders::shadow_atlas::{cap_level, handles as atlas_handles, AtlasParams, ARGS_SHIFT, ARGS_USED, MIN_SIDE};
use shaders::layout::ClusterGrid;
use shaders::shadow_receivers::{handles as receiver_handles, ReceiverParams, RECEIVER_TILE, RECEIVER_WORKGROUP, TILES_PER_INVOCATION, TILE_WORDS};
use shaders::shadow_cull::{face_mask, handles, ShadowCullParams, ARGS_COUNTED, ARGS_DISPATCH, ARGS_FACES, ARGS_WORDS, BATCH_TRIANGLES, BATCH_WORDS, CULL_MARGIN, CULL_WORKGROUP, ENTRY_WORDS};

/// Texels per face side unless `--shadow-resolution` says otherwise.
pub const DEFAULT_RESOLUTION: u32 = 256;
/// The largest face side accepted.
pub const MAX_RESOLUTION: u32 = 4096;
/// The most shadow-casting lights: the cull dispatches one row of workgroups per caster.
pub const MAX_CASTERS: usize = shaders::indirect::MAX_GROUPS_PER_AXIS as usize;

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
    /// Only faces that pixels of the frame look up (`shaders::shadow_receivers`), each at the
    /// side its receivers ask.
    #[default]
    Receivers,
    /// Every face a batch's sphere meets within the light's radius, each at the largest side.
    All,
}

/// The shadow maps' knobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowSettings {
    /// The largest side of a face in texels (each face gets what its receivers ask, up to this).
    pub resolution: u32,
    /// Bytes of the atlas the faces share (`--shadow-atlas`); `None`: room for every face at
    /// [`Self::resolution`], within the device's largest storage binding.
    pub atlas_bytes: Option<u64>,
    pub filter: ShadowFilter,
    pub raster: ShadowRaster,
    pub faces: ShadowFaces,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { resolution: DEFAULT_RESOLUTION, atlas_bytes: None, filter: ShadowFilter::default(), raster: ShadowRaster::default(), faces: ShadowFaces::default() }
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
    /// The largest side of a face.
    pub resolution: u32,
    /// Texels of the atlas, those the last frame's faces took, and how often the atlas halved
    /// every face's side in it (0: each face had the side its receivers asked).
    pub atlas_texels: u32,
    pub atlas_used: u32,
    pub shift: u32,
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
    levels_pipe: ComputePipeline<AtlasParams>,
    alloc_pipe: ComputePipeline<AtlasParams>,
    cull: ComputePipeline<ShadowCullParams>,
    args_pipe: ComputePipeline<ShadowCullParams>,
    /// The receivers' tiles and faces (`None`: every face, [`ShadowFaces::All`]).
    receivers: Option<Receivers>,
    /// Per caster face, the level its receivers ask (`shaders::shadow_atlas`; 0: none; every
    /// face at the largest side with [`ShadowFaces::All`]).
    needed: Buffer,
    /// What writes the entries' triangles: the compute rasteriser, or the draw and its render area
    /// (the largest side squared, never tested or written).
    writer: Writer,
    settings: ShadowSettings,
    /// Texels of the atlas, and the last frame's texels taken and shift.
    atlas_texels: u32,
    used: u32,
    shift: u32,
    /// Light index of each caster, in slot order.
    casters: Vec<u32>,
    /// `[largest side, filter, table, 0]`, each light's slot or `NO_SHADOW`, then the face table
    /// (`shaders::shadow::face_entry`, written by the atlas's allocation every frame).
    pub slots: Buffer,
    /// Each caster's view-space position and radius (cull and raster).
    records: Buffer,
    records_cpu: Vec<[f32; CASTER_WORDS as usize]>,
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
    /// The atlas: each face's distances, row-major from its first texel.
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
    pub fn new(gpu: &Gpu, positions: &[[f32; 3]], indices: &[u32], draws: &[Draw], rotation: Mat4, casters: &[bool], lights_view: &[PointLight], cones: &[Option<(Vec3, f32)>], settings: ShadowSettings, frame: (u32, u32)) -> Result<Option<Self>> {
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
        let atlas_texels = atlas_texels(ctx, &settings, list.len())?;
        let faces = FACES as usize * list.len();
        let table = SHADOW_HEADER_WORDS + lights_view.len() as u32;
        let mut slots = vec![settings.resolution, settings.filter.code(), table, 0];
        slots.extend(std::iter::repeat_n(NO_SHADOW, lights_view.len()));
        for (slot, &l) in list.iter().enumerate() {
            slots[(SHADOW_HEADER_WORDS + l) as usize] = slot as u32;
        }
        slots.extend(std::iter::repeat_n(0, FACE_WORDS as usize * faces));
        let order = shadow_triangles(positions, indices, draws);
        let (batch_words, spheres) = batches(positions, &order);
        let records_cpu = records(&list, lights_view, cones);
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
            Some(_) => Buffer::storage(ctx, "shadow face levels", 4 * faces as u64)?,
            None => Buffer::from_slice(ctx, "shadow face levels", &vec![cap_level(settings.resolution).max(1); faces])?,
        };
        let maps = Self {
            levels_pipe: ComputePipeline::new(ctx, &gpu.compute_module, atlas_handles::SHADOW_FACE_LEVELS)?,
            alloc_pipe: ComputePipeline::new(ctx, &gpu.compute_module, atlas_handles::SHADOW_FACE_ALLOC)?,
            cull: ComputePipeline::new(ctx, &gpu.compute_module, handles::SHADOW_CULL)?,
            args_pipe: ComputePipeline::new(ctx, &gpu.compute_module, handles::SHADOW_DRAW_ARGS)?,
            writer,
            receivers,
            needed,
            faces: 0,
            settings,
            atlas_texels,
            used: 0,
            shift: 0,
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
            maps: Buffer::storage(ctx, "shadow maps", 4 * atlas_texels as u64).context("allocating the shadow atlas")?,
        };
        Ok(Some(maps))
    }

    /// Uploads the casters' records anew (the lights or the camera moved) and grows the entries
    /// to the new count where it passed them.
    pub fn lights_moved(&mut self, ctx: &Context, lights_view: &[PointLight], cones: &[Option<(Vec3, f32)>]) -> Result<()> {
        if let Some(&l) = self.casters.iter().find(|&&l| l as usize >= lights_view.len()) {
            bail!("shadow-casting light {l} is past the {} lights of the frame", lights_view.len());
        }
        self.records_cpu = records(&self.casters, lights_view, cones);
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
        (self.counted, self.faces, self.used, self.shift) = (args[ARGS_COUNTED], args[ARGS_FACES], args[ARGS_USED], args[ARGS_SHIFT]);
        if args[ARGS_COUNTED] > self.capacity {
            bail!("the shadow cull counted {} entries against the {} the host counted: shadow-map triangles would be missing", args[ARGS_COUNTED], self.capacity);
        }
        Ok(())
    }

    /// Shadow-casting lights.
    pub fn casters(&self) -> usize {
        self.casters.len()
    }

    /// The settings drawn.
    pub fn settings(&self) -> ShadowSettings {
        self.settings
    }

    /// What `--stats` reports.
    pub fn stats(&self) -> ShadowStats {
        ShadowStats {
            casters: self.casters.len(),
            resolution: self.settings.resolution,
            atlas_texels: self.atlas_texels,
            atlas_used: self.used,
            shift: self.shift,
            entries: self.counted,
            batches: self.spheres.len(),
            faces_with_receivers: self.faces,
        }
    }

    /// Records the pass: clear, the faces with receivers and their levels (from the G-buffer's
    /// reversed-Z `depth` over `grid`), the atlas, cull, arguments, then every entry's triangles
    /// into the atlas (one indirect dispatch or one indirect draw).
    pub fn record(&self, rec: &mut Recorder<'_>, geometry: &Geometry, camera: &Buffer, depth: &Buffer, grid: ClusterGrid) -> VkResult<()> {
        rec.fill(&self.maps, NO_OCCLUDER);
        rec.fill(&self.args, 0);
        let casters = self.casters.len() as u32;
        if let Some(r) = &self.receivers {
            rec.fill(&self.needed, 0);
            let p = ReceiverParams { grid, res: self.settings.resolution, casters, tiles_x: grid.width.div_ceil(RECEIVER_TILE), tiles_y: grid.height.div_ceil(RECEIVER_TILE) };
            let tiles = p.tiles_x * p.tiles_y;
            rec.dispatch_linear(&r.tiles_pipe, &[depth, &r.tiles], &p, tiles)?;
            rec.dispatch(&r.faces_pipe, &[&r.tiles, &self.records, &self.needed], &p, [tiles.div_ceil(TILES_PER_INVOCATION * RECEIVER_WORKGROUP), casters, 1])?;
        }
        let atlas = AtlasParams { faces: FACES * casters, cap: self.settings.resolution, texels: self.atlas_texels, pad: 0 };
        rec.dispatch_linear(&self.levels_pipe, &[&self.needed, &self.args], &atlas, atlas.faces)?;
        rec.dispatch_linear(&self.alloc_pipe, &[&self.needed, &self.args, &self.slots], &atlas, atlas.faces)?;
        let batches = self.spheres.len() as u32;
        let p = ShadowCullParams { batches, casters, capacity: self.capacity, pad: 0 };
        rec.dispatch(&self.cull, &[camera, &self.batches, &self.records, &self.entries, &self.args, &self.slots], &p, [batches.div_ceil(CULL_WORKGROUP), p.casters, 1])?;
        rec.dispatch(&self.args_pipe, &[&self.args], &p, [1, 1, 1])?;
        match &self.writer {
            Writer::Compute(raster) => {
                let params = ShadowRasterParams { capacity: self.capacity, pad: [0; 3] };
                let buffers = [&geometry.positions, &self.indices, camera, &self.records, &self.batches, &self.entries, &self.args, &self.slots, &self.maps];
                rec.dispatch_indirect(raster, &buffers, &params, &self.args, ARGS_DISPATCH)?;
            }
            Writer::Draw { pipe, area } => {
                rec.draws_read_kernel_writes();
                rec.fragments_read_earlier_writes();
                rec.transition(area, ImageUse::Undefined, ImageUse::DepthTarget);
                rec.begin_drawing(&[], Attachment { image: area, load: Load::ClearDepth(0.0) });
                let bindings = [&geometry.positions, &self.indices, camera, &self.records, &self.batches, &self.entries, &self.slots, &self.maps].map(Binding::Buffer);
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

/// Texels of the atlas: [`ShadowSettings::atlas_bytes`] / 4, or by default room for every face
/// at the largest side within the device's largest storage binding; refused in one line where it
/// cannot hold every face at [`MIN_SIDE`] (the least the atlas's shift reaches) or a requested
/// size passes the binding.
fn atlas_texels(ctx: &Context, settings: &ShadowSettings, casters: usize) -> Result<u32> {
    let faces = FACES as u64 * casters as u64;
    let side = |s: u32| s as u64 * s as u64;
    let (least, most) = (faces * side(MIN_SIDE.min(settings.resolution)), faces * side(settings.resolution));
    let binding = ctx.info.max_storage_buffer_range as u64 / 4;
    let texels = match settings.atlas_bytes {
        Some(bytes) => {
            if bytes / 4 > binding {
                bail!("--shadow-atlas {} MiB: the device's largest storage binding holds {} MiB", bytes >> 20, (4 * binding) >> 20);
            }
            (bytes / 4).min(most)
        }
        None => most.min(binding),
    };
    if texels < least {
        bail!("{casters} shadow-casting lights need a shadow atlas of at least {} KiB ({}² texels for each of their {faces} faces); it has {} KiB", (4 * least) >> 10, MIN_SIDE.min(settings.resolution), (4 * texels) >> 10);
    }
    Ok(texels as u32)
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

/// The entries the cull can write for these casters: [`face_mask`] on each batch's sphere (in
/// the caster's cube axes)
/// widened by `CULL_MARGIN` of its distance and both radii, so that the GPU's unwidened test in
/// its own rounding never finds more.
pub fn count_entries(spheres: &[[f32; 4]], rotation: Mat4, records: &[[f32; CASTER_WORDS as usize]]) -> u64 {
    let view: Vec<(Vec3, f32)> = spheres.iter().map(|s| (rotation.transform_point3(Vec3::new(s[0], s[1], s[2])), s[3])).collect();
    let count_for = |records: &[[f32; CASTER_WORDS as usize]]| -> u64 {
        let mut n = 0u64;
        for rec in records {
            let (light, radius) = (Vec3::new(rec[0], rec[1], rec[2]), rec[3]);
            let frame = CubeFrame::of_cone(Vec3::new(rec[4], rec[5], rec[6]), rec[7]);
            for &(c, r) in &view {
                let d = c - light;
                let widened = r + CULL_MARGIN * (d.length() + r + radius);
                n += face_mask(frame.local(d), widened, radius).count_ones() as u64;
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
fn entry_capacity(ctx: &Context, spheres: &[[f32; 4]], rotation: Mat4, records: &[[f32; CASTER_WORDS as usize]]) -> Result<u32> {
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

/// The records of `casters` (`shaders::shadow::caster_record`), each with its light's view-space
/// cone where it is a spot light (`cones`: one per light, or none for a scene of point lights).
fn records(casters: &[u32], lights_view: &[PointLight], cones: &[Option<(Vec3, f32)>]) -> Vec<[f32; CASTER_WORDS as usize]> {
    casters.iter().map(|&l| caster_record(&lights_view[l as usize], cones.get(l as usize).copied().flatten())).collect()
}
