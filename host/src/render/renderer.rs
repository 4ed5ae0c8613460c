//! The per-frame renderer shared by `render` (a loop of warm-up and timed frames) and the
//! interactive viewer (one frame per displayed frame): it owns what a frame reads — the uploaded
//! scene, the G-buffer targets, the lights, the output frame — and the lighting technique, and
//! [`Renderer::frame`] records and runs one frame of every pass (async work, G-buffer, the
//! technique's passes), growing buffers and re-running the frame when the technique asks.
//!
//! Between frames the viewer moves the camera ([`Renderer::set_view`]: vertices and lights are
//! re-uploaded camera-relative, `camera_relative.rs`), replaces the lights
//! ([`Renderer::set_lights`]) or changes the technique or the view ([`Renderer::set_settings`]:
//! the technique is created anew). A new frame size is a new renderer.
use super::technique::{ClusterLists, Description, FrameInputs, LightingTechnique, ListStats, MAX_REGROWTHS};
use super::Technique;
use super::light_types::{self, light_records};
use super::shadow_maps::ShadowMaps;
use shaders::light_types as light_types_bits;
use super::{frame_time, gbuffer, lights_to_view, transparent, Frame, Readback, SceneInput, Settings, ViewTransform, HEAT_MAX};
use crate::gpu::Gpu;
use crate::vk::{Buffer, PassTiming, Profiler, Queue};
use anyhow::{bail, Context as _, Result};
use shaders::cluster_key::{slice_bounds, ClusterGrid};
use shaders::layout::*;
use shaders::octahedral::Precision;

/// One frame's GPU times.
#[derive(Clone, Debug, Default)]
pub struct FrameTimes {
    /// Every timed pass of the frame (async-compute queue first), in recording order.
    pub passes: Vec<PassTiming>,
    /// The whole frame over both queues (`None` where the device has no timestamps).
    pub sample: Option<frame_time::FrameSample>,
}

/// Everything a frame reads but the technique.
struct Resources {
    settings: Settings,
    params: FrameParams,
    grid: ClusterGrid,
    view: ViewTransform,
    fov_y_radians: f32,
    near: f32,
    geometry: gbuffer::Geometry,
    /// The NURBS tessellation pass (scenes with patches), recorded before the G-buffer.
    tessellation: Option<super::nurbs::Tessellation>,
    indices: Vec<u32>,
    textures: gbuffer::Textures,
    camera: Buffer,
    targets: gbuffer::Targets,
    /// The multisampled frame's pipelines and edge list (`--msaa` above 1; `msaa.rs`).
    msaa: Option<super::msaa::Multisampling>,
    lights: Buffer,
    lights_view: Vec<PointLight>,
    /// The farthest a light moved in the light buffer's records (`light_record::light_buffer`).
    light_moved: f32,
    /// World-space cones and directional lights: re-transformed with the lights each frame.
    spots: Vec<Option<light_types::Spot>>,
    directional: Vec<light_types::Directional>,
    materials_cpu: Vec<MaterialGpu>,
    material_names: Vec<String>,
    materials: Buffer,
    bounds: Vec<f32>,
    bounds_buf: Buffer,
    frame: Buffer,
    /// The device compares timestamps across queues (`DeviceInfo::timestamps_across_queues`).
    across_queues: bool,
    /// The cube shadow maps (scenes with shadow-casting lights; `shadow_maps.rs`).
    shadows: Option<ShadowMaps>,
}

impl Resources {
    fn inputs(&self) -> FrameInputs<'_> {
        FrameInputs {
            params: self.params,
            settings: &self.settings,
            geometry: &self.geometry,
            indices: &self.indices,
            textures: &self.textures,
            camera: &self.camera,
            targets: &self.targets,
            msaa: self.msaa.as_ref(),
            lights: &self.lights,
            lights_view: &self.lights_view,
            materials: &self.materials,
            bounds: &self.bounds_buf,
            frame: &self.frame,
            shadows: self.shadows.as_ref(),
        }
    }

    /// The buffers the frame loop owns, by name and bytes.
    fn buffers(&self) -> Vec<(String, u64)> {
        let mut v = vec![
            ("geometry".into(), self.geometry.bytes()),
            ("textures".into(), self.textures.bytes()),
            ("gbuffer".into(), self.targets.bytes()),
            ("lights".into(), self.lights.size),
            ("frame".into(), self.frame.size),
        ];
        v.extend(self.tessellation.iter().flat_map(|t| t.buffers()));
        v.extend(self.msaa.iter().flat_map(|m| m.buffers()));
        v.extend(self.shadows.iter().flat_map(|m| m.buffers()));
        v
    }

    /// Creates the technique of `settings` (refusing scenes with transparent materials where it
    /// has no transparent pass).
    fn technique(&self, gpu: &Gpu) -> Result<Box<dyn LightingTechnique>> {
        let s = &self.settings;
        if !self.geometry.transparent.is_empty() && !s.technique.draws_transparency() {
            bail!("{}", transparent::refusal(s.technique, &self.geometry.transparent, &self.material_names, &self.materials_cpu));
        }
        if s.msaa > 1 && !s.technique.description().msaa {
            // The preflight's refusal (`preflight::check_msaa`), for a technique changed later.
            bail!("--msaa {}: {} shades once per pixel (it has no per-sample edge pass)", s.msaa, s.technique.name());
        }
        if let Some(sh) = &self.shadows {
            refuse_shadows(s.technique.description(), sh.casters(), self.lights_view.len())?;
        }
        s.technique.create(gpu, &self.inputs())
    }
}

/// Refuses, in one line naming the registered techniques that render shadows, a technique
/// described by `d` that renders none where `casters` of the frame's `lights` cast them.
fn refuse_shadows(d: &Description, casters: usize, lights: usize) -> Result<()> {
    if casters == 0 || d.shadows {
        return Ok(());
    }
    let with: Vec<&str> = Technique::ALL.iter().filter(|t| t.description().shadows).map(|t| t.name()).collect();
    bail!("{casters} of {lights} lights cast shadows, but {} renders no shadows (techniques that do: {})", d.name, with.join(", "))
}

/// Refuses, in one line, scenes with shadow-casting lights that the technique or the shadow
/// maps would render wrongly: the technique must render shadows, and the maps they shade one sample per pixel, read full light records, draw the meshes' opaque
/// triangles (not tessellated NURBS grids), and the transparent pass shades without them.
pub fn check_shadow_scene(scene: &SceneInput<'_>, s: &Settings) -> Result<()> {
    let casters = scene.shadows.iter().filter(|&&c| c).count();
    if casters == 0 {
        return Ok(());
    }
    let n = scene.lights.len();
    refuse_shadows(s.technique.description(), casters, n)?;
    super::shadow_maps::check_resolution(s.shadow.resolution)?;
    super::shadow_maps::check_casters(casters)?;
    if s.msaa > 1 {
        bail!("--msaa {}: {casters} of {n} lights cast shadows, and shadows are shaded once per pixel: render them at --msaa 1", s.msaa);
    }
    if s.light_record != super::light_record::LightRecord::Full {
        bail!("--light-record compact: {casters} of {n} lights cast shadows, and the shadow maps take full light records");
    }
    if scene.draws.iter().any(|d| gbuffer::is_transparent(d, &scene.materials)) {
        bail!("{casters} of {n} lights cast shadows, but the scene has transparent materials, which are shaded without shadows");
    }
    if scene.draws.iter().any(|d| d.indirect.is_some()) || !scene.nurbs.is_empty() {
        bail!("{casters} of {n} lights cast shadows, but the scene has NURBS patches, which the shadow maps do not draw");
    }
    Ok(())
}

/// Timed scopes per submission with `Settings::dispatch_times`: the passes and every dispatch,
/// fill and copy inside them (the longest chain, `clustered-bvh` with transparency, records
/// about 40).
const MAX_TIMED_COMMANDS: u32 = 128;

/// What a technique reports after its last frame.
struct TechReport {
    lists: ListStats,
    transparency: Option<transparent::TransparencyStats>,
    buffers: Vec<(String, u64)>,
    cluster_lists: Option<ClusterLists>,
    tile_lists: Vec<Vec<u32>>,
    msaa_bytes_per_sample: Option<u64>,
    msaa_edge_pixels: Option<u32>,
}

fn tech_report(tech: &mut dyn LightingTechnique, read_back: bool) -> Result<TechReport> {
    Ok(TechReport {
        lists: tech.stats()?,
        transparency: tech.transparency(),
        buffers: tech.buffers(),
        cluster_lists: if read_back { tech.cluster_lists()? } else { None },
        tile_lists: if read_back { tech.tile_lists()?.unwrap_or_default() } else { Vec::new() },
        msaa_bytes_per_sample: tech.msaa_bytes_per_sample(),
        msaa_edge_pixels: tech.msaa_edge_pixels()?,
    })
}

/// The uploaded scene, the frame's targets and a lighting technique (see the module doc).
pub struct Renderer {
    res: Resources,
    tech: Box<dyn LightingTechnique>,
    profiler: Profiler,
    async_profiler: Profiler,
    /// Whether the technique's async work runs on the async-compute queue.
    overlapped: bool,
    /// Times a buffer had to grow and a frame re-run, over every frame so far.
    pub regrowths: u32,
}

impl Renderer {
    /// Checks the scene and settings, uploads the scene and creates the technique.
    pub fn new(gpu: &Gpu, scene: &SceneInput<'_>, s: &Settings) -> Result<Self> {
        let grid = ClusterGrid::new(s.width, s.height, s.tile_size, scene.near, scene.far, scene.fov_y_radians).context("cluster grid")?;
        let grid = ClusterGrid { samples: s.msaa.max(1), ..grid };
        check_shadow_scene(scene, s)?;
        if scene.materials.is_empty() || scene.materials.len() > MAX_MATERIALS as usize {
            bail!("{} materials: the G-buffer addresses 1..={MAX_MATERIALS}", scene.materials.len());
        }
        if let Some(d) = scene.draws.iter().find(|d| d.params.normal_precision != s.normal_precision.code()) {
            bail!(
                "a draw encodes normals at precision {:?} but the frame reads them at {:?}: flatten the scene at the frame's precision",
                Precision::from_u32(d.params.normal_precision),
                s.normal_precision
            );
        }
        check_view(s)?;
        let ctx = &gpu.ctx;
        check_light_count(gpu, scene.lights.len())?;
        crate::preflight::check_msaa(&ctx.info, s.technique, s.msaa, s.width, s.height, s.normal_precision)?;
        let per_sample = (s.technique.description().llvmpipe_lights)(s.tile_size.max(1)) / s.msaa.max(1);
        if ctx.info.is_llvmpipe() && s.msaa > 1 && scene.lights.len() > per_sample as usize {
            bail!("{} lights at --msaa {}: an edge pixel's invocation visits its lights once per sample, and lavapipe's loop limiter allows {per_sample} lights per sample here", scene.lights.len(), s.msaa);
        }
        if s.msaa > 1 && scene.draws.iter().any(|d| gbuffer::is_transparent(d, &scene.materials)) {
            bail!("--msaa {}: transparent materials are drawn once per pixel over the opaque frame, not per sample: render scenes with transparency at --msaa 1", s.msaa);
        }
        let n = s.width * s.height;
        let (records, lights_view, light_moved) = super::light_record::light_buffer(s.light_record, &scene.view, lights_to_view(&scene.view, scene.lights)?, scene.spots, scene.directional)?;
        let positions = scene.view.relative_positions(scene.positions);
        let (geometry, tessellation, indices) = super::nurbs::upload_geometry(gpu, scene, &positions, s).context("uploading geometry")?;
        let aspect = s.width as f32 / s.height as f32;
        let camera = Buffer::from_slice(ctx, "camera", &[gbuffer::raster_camera(scene.view.rotation(), scene.fov_y_radians, aspect, scene.near)])?;
        // A technique without the G-buffer pass (Forward+) multisamples its own targets: the
        // G-buffer's then stay one-sample, and only its depth buffer holds a plane per sample.
        let gbuffer_samples = if s.technique.description().gbuffer { s.msaa } else { 1 };
        let targets = gbuffer::Targets::new(ctx, s.width, s.height, s.normal_precision.code(), gbuffer_samples, s.msaa).context("allocating the G-buffer")?;
        let msaa = super::msaa::Multisampling::new(gpu, gbuffer_samples, n as u64).context("creating the MSAA passes")?;
        let textures = gbuffer::Textures::upload(ctx, &scene.textures).context("uploading textures")?;
        let lights = Buffer::length_free_from_slice(ctx, "lights", &records).context("allocating the light buffer")?;
        let materials = Buffer::from_slice(ctx, "materials", &scene.materials)?;
        let bounds = slice_bounds(&grid);
        let bounds_buf = Buffer::from_slice(ctx, "slice bounds", &bounds)?;
        let frame = Buffer::storage(ctx, "frame", 4 * n as u64).context("allocating the frame")?;
        let cones = light_types::view_cones(&scene.view, scene.spots, lights_view.len());
        let shadows = ShadowMaps::new(gpu, &positions, &indices, &geometry.draws, scene.view.rotation(), scene.shadows, &lights_view, &cones, s.shadow, (s.width, s.height))?;
        let shadow_effect = if shadows.is_some() { light_types_bits::EFFECT_SHADOWS } else { 0 };
        let params = FrameParams {
            grid,
            count: n,
            num_lights: scene.lights.len() as u32,
            light_capacity: 0,
            effects: scene.effects | light_types::light_effects(scene.spots, scene.directional)? | s.light_record.effects() | shadow_effect,
            normal_precision: s.normal_precision.code(),
            view: s.view.code(),
            exposure: s.exposure,
            heat_max: HEAT_MAX,
        };
        let res = Resources {
            settings: s.clone(),
            params,
            grid,
            view: scene.view,
            fov_y_radians: scene.fov_y_radians,
            near: scene.near,
            geometry,
            tessellation,
            indices: indices.into_owned(),
            textures,
            camera,
            targets,
            msaa,
            lights,
            lights_view,
            light_moved,
            spots: scene.spots.to_vec(),
            directional: scene.directional.to_vec(),
            materials_cpu: scene.materials.clone(),
            material_names: scene.material_names.clone(),
            materials,
            bounds,
            bounds_buf,
            frame,
            across_queues: ctx.info.timestamps_across_queues,
            shadows,
        };
        let tech = res.technique(gpu)?;
        // Room for every pass, and with `dispatch_times` for every command inside them.
        let (parts, passes) = (s.dispatch_times, if s.dispatch_times { MAX_TIMED_COMMANDS } else { 16 });
        let overlapped = tech.has_async_work() && s.async_compute && ctx.async_compute_queue.is_some();
        Ok(Self { res, tech, profiler: Profiler::new(ctx, passes)?.with_parts(parts), async_profiler: Profiler::new_async(ctx, passes)?.with_parts(parts), overlapped, regrowths: 0 })
    }

    /// The settings frames are rendered with.
    pub fn settings(&self) -> &Settings {
        &self.res.settings
    }

    /// The cluster grid of the frame.
    pub fn grid(&self) -> ClusterGrid {
        self.res.grid
    }

    /// The output frame: one packed RGBA8 word per pixel, rows top to bottom (what the viewer
    /// copies to its window).
    pub fn frame_buffer(&self) -> &Buffer {
        &self.res.frame
    }

    /// Whether the technique's light-only passes run on the async-compute queue.
    pub fn overlapped(&self) -> bool {
        self.overlapped
    }

    /// Renders one frame: the async work, the G-buffer and the technique's passes; when a buffer
    /// was too small, grows it and renders the frame again (at most [`MAX_REGROWTHS`] times).
    pub fn frame(&mut self, gpu: &Gpu) -> Result<FrameTimes> {
        let (res, tech) = (&self.res, &mut self.tech);
        let inputs = res.inputs();
        let mut regrowths = 0;
        loop {
            gpu.ctx.run_overlapped(
                self.overlapped,
                Some(&mut self.profiler),
                Some(&mut self.async_profiler),
                |rec| tech.record_async(gpu, rec, &inputs),
                |rec| {
                    if let Some(t) = &res.tessellation {
                        rec.pass("tessellation", |rec| t.record(rec, &res.geometry))?;
                    }
                    // Without the G-buffer pass the technique records the shadow maps itself,
                    // after the pass that gives it depths (`FrameInputs::record_shadow_maps`).
                    if res.settings.technique.description().gbuffer {
                        rec.pass("gbuffer", |rec| gbuffer::record(gpu, rec, &res.geometry, &res.textures, &res.camera, &res.targets, res.msaa.as_ref(), &res.params))?;
                        inputs.record_shadow_maps(rec)?;
                    }
                    Ok(())
                },
                |rec| tech.record(gpu, rec, &inputs),
            )?;
            match tech.grow_if_needed(gpu)? {
                Some(grown) => {
                    regrowths += 1;
                    self.regrowths += 1;
                    if regrowths > MAX_REGROWTHS {
                        bail!("{}: buffers keep growing ({grown}): giving up", res.settings.technique.name());
                    }
                }
                None => break,
            }
        }
        // A technique that takes a scene with transparent draws must have drawn them: one that
        // recorded no transparent pass would have left the glass out of the frame unseen.
        if !res.geometry.transparent.is_empty() && tech.transparency().is_none() {
            bail!("{} recorded no transparent pass for a scene with transparent draws: their surfaces would be missing from the frame", res.settings.technique.name());
        }
        let ((mut passes, async_span), (main_passes, main_span)) = (self.async_profiler.results_and_span()?, self.profiler.results_and_span()?);
        passes.extend(main_passes);
        let raster_ms = passes.iter().filter(|p| p.raster && p.queue == Queue::Main).map(|p| p.ms).sum();
        let sample = frame_time::sample(main_span, async_span, gpu.ctx.info.timestamps_across_queues, raster_ms);
        if let Some(sh) = &mut self.res.shadows {
            sh.check_entries()?;
        }
        Ok(FrameTimes { passes, sample })
    }

    /// Moves the camera: vertices and lights are uploaded anew relative to `view`'s eye
    /// (`world_positions` and `world_lights` as in the [`SceneInput`] the renderer was made from).
    pub fn set_view(&mut self, gpu: &Gpu, view: ViewTransform, world_positions: &[[f32; 3]], world_lights: &[PointLight]) -> Result<()> {
        let r = &mut self.res;
        r.view = view;
        let relative = view.relative_positions(world_positions);
        r.geometry.positions.write(&relative).context("uploading vertices")?;
        if let Some(t) = &mut r.tessellation {
            t.set_eye(view.eye).context("uploading the NURBS control points")?;
        }
        let aspect = r.settings.width as f32 / r.settings.height as f32;
        r.camera.write(&[gbuffer::raster_camera(view.rotation(), r.fov_y_radians, aspect, r.near)])?;
        if let Some(sh) = &mut r.shadows {
            sh.view_moved(&relative, view.rotation())?;
        }
        let spots = r.spots.clone();
        self.set_lights(gpu, world_lights, &spots)
    }

    /// Replaces the lights (world space, seen from the current view) and their cones (`spots`:
    /// one per light, `None` for a point light, or empty without spot lights). A different
    /// count, or spots where there were none (or none where there were), reallocates the light
    /// buffer and creates the technique anew; on an error the renderer keeps its lights and
    /// technique.
    pub fn set_lights(&mut self, gpu: &Gpu, world_lights: &[PointLight], spots: &[Option<light_types::Spot>]) -> Result<()> {
        let (records, lights_view, light_moved) = super::light_record::light_buffer(self.res.settings.light_record, &self.res.view, lights_to_view(&self.res.view, world_lights)?, spots, &self.res.directional)?;
        let effects = (self.res.params.effects & !shaders::light_types::EFFECT_SPOT) | light_types::light_effects(spots, &self.res.directional)?;
        if let Some(sh) = &mut self.res.shadows {
            // The shadow flags belong to the lights the renderer was made with.
            if lights_view.len() != self.res.lights_view.len() {
                let n = self.res.lights_view.len();
                bail!("{} lights in place of {}: the scene's lights cast shadows, and their flags are per light", lights_view.len(), n);
            }
            sh.lights_moved(&gpu.ctx, &lights_view, &light_types::view_cones(&self.res.view, spots, lights_view.len()))?;
        }
        if lights_view.len() == self.res.lights_view.len() && effects == self.res.params.effects {
            self.res.lights.write(&records).context("uploading lights")?;
            self.res.lights_view = lights_view;
            self.res.light_moved = light_moved;
            self.res.spots.clear();
            self.res.spots.extend_from_slice(spots);
            self.tech.lights_moved(&self.res.inputs());
            return Ok(());
        }
        check_light_count(gpu, lights_view.len())?;
        let lights = Buffer::length_free_from_slice(&gpu.ctx, "lights", &records).context("allocating the light buffer")?;
        let old_lights = std::mem::replace(&mut self.res.lights, lights);
        let old_view = std::mem::replace(&mut self.res.lights_view, lights_view);
        let old_count = std::mem::replace(&mut self.res.params.num_lights, world_lights.len() as u32);
        let old_effects = std::mem::replace(&mut self.res.params.effects, effects);
        let old_spots = std::mem::replace(&mut self.res.spots, spots.to_vec());
        let old_moved = std::mem::replace(&mut self.res.light_moved, light_moved);
        if let Err(e) = self.replace_technique(gpu) {
            self.res.lights = old_lights;
            self.res.lights_view = old_view;
            self.res.light_moved = old_moved;
            self.res.params.num_lights = old_count;
            self.res.params.effects = old_effects;
            self.res.spots = old_spots;
            return Err(e);
        }
        Ok(())
    }

    /// Changes the technique, the view or other settings of the same frame size, tiles and
    /// normal encoding: the technique is created anew. On an error the renderer keeps its
    /// settings and technique.
    pub fn set_settings(&mut self, gpu: &Gpu, s: &Settings) -> Result<()> {
        let old = &self.res.settings;
        if (s.width, s.height, s.tile_size, s.normal_precision, s.msaa) != (old.width, old.height, old.tile_size, old.normal_precision, old.msaa) {
            bail!("a new frame size, tile size, normal encoding or sample count needs a new renderer");
        }
        check_view(s)?;
        let old = std::mem::replace(&mut self.res.settings, s.clone());
        let (old_view, old_exposure) = (self.res.params.view, self.res.params.exposure);
        (self.res.params.view, self.res.params.exposure) = (s.view.code(), s.exposure);
        if let Err(e) = self.replace_technique(gpu) {
            self.res.settings = old;
            (self.res.params.view, self.res.params.exposure) = (old_view, old_exposure);
            return Err(e);
        }
        Ok(())
    }

    fn replace_technique(&mut self, gpu: &Gpu) -> Result<()> {
        let tech = self.res.technique(gpu)?;
        let s = &self.res.settings;
        self.overlapped = tech.has_async_work() && s.async_compute && gpu.ctx.async_compute_queue.is_some();
        self.tech = tech;
        Ok(())
    }

    /// The light lists of the last frame; with `longest`, the longest list of the clustered
    /// techniques too, read back from their lists (the others count theirs on the GPU).
    pub fn list_stats(&mut self, longest: bool) -> Result<ListStats> {
        let mut s = self.tech.stats()?;
        if longest && s.max_list == 0 {
            if let Some(c) = self.tech.cluster_lists()? {
                s.max_list = c.counts.iter().copied().max().unwrap_or(0);
            }
        }
        Ok(s)
    }

    /// The last frame's pixels (packed RGBA8 words, rows top to bottom).
    pub fn pixels(&mut self) -> Result<Vec<u32>> {
        let n = self.res.params.count as usize;
        Ok(self.res.frame.read(n)?)
    }

    /// The last frame as [`super::render`] reports it, with the given per-frame times (medians
    /// over them) and, with `read_back`, the G-buffer and light lists for checks and statistics.
    pub fn report(&mut self, times: &[FrameTimes], read_back: bool) -> Result<Frame> {
        let r = tech_report(self.tech.as_mut(), read_back)?;
        let overlapped = self.overlapped;
        finish(&mut self.res, r, times, self.regrowths, overlapped, read_back)
    }

    /// [`Renderer::report`] that frees the technique's buffers before reading the frame back
    /// (the largest frames hold little else).
    pub fn into_report(self, times: &[FrameTimes], read_back: bool) -> Result<Frame> {
        let Renderer { mut res, mut tech, overlapped, regrowths, .. } = self;
        let r = tech_report(tech.as_mut(), read_back)?;
        drop(tech);
        finish(&mut res, r, times, regrowths, overlapped, read_back)
    }
}

fn finish(res: &mut Resources, r: TechReport, times: &[FrameTimes], regrowths: u32, overlapped: bool, read_back: bool) -> Result<Frame> {
    let n = res.params.count as usize;
    let mut buffers = res.buffers();
    buffers.extend(r.buffers);
    let pixels: Vec<u32> = res.frame.read(n)?;
    let readback = if read_back {
        let t = &mut res.targets;
        let depth: Vec<u32> = t.depth_buf.read(n)?;
        let precision = res.settings.normal_precision;
        let words: Vec<u32> = t.normal_buf.read(precision.gbuffer_words() as usize * n)?;
        let normals = words
            .chunks(precision.gbuffer_words() as usize)
            .map(|w| shaders::octahedral::decode([w[0], w.get(1).copied().unwrap_or(0), w.get(2).copied().unwrap_or(0)], precision))
            .collect();
        let albedo: Vec<u32> = t.albedo_buf.read(n)?;
        let c = r.cluster_lists.unwrap_or(ClusterLists { keys: vec![], unique: vec![], counts: vec![], offsets: vec![], list: vec![] });
        Some(Readback {
            depth,
            normals,
            albedo,
            keys: c.keys,
            unique: c.unique,
            counts: c.counts,
            offsets: c.offsets,
            list: c.list,
            lights_view: res.lights_view.clone(),
            light_records: light_records(&res.view, &res.lights_view, &res.spots, &res.directional)?,
            light_effects: res.params.effects & (shaders::light_types::EFFECT_SPOT | shaders::light_types::EFFECT_CULL_SPHERE_ONLY),
            grid: res.grid,
            bounds: res.bounds.clone(),
            tile_lists: r.tile_lists,
            transparent: !res.geometry.transparent.is_empty(),
        })
    } else {
        None
    };
    let passes: Vec<Vec<PassTiming>> = times.iter().map(|t| t.passes.clone()).collect();
    let samples: Vec<frame_time::FrameSample> = times.iter().filter_map(|t| t.sample).collect();
    let (timings, timing_spread) = super::median_timings(&passes);
    Ok(Frame {
        pixels,
        gpu_frame: frame_time::median(&samples, res.across_queues),
        timings,
        timing_spread,
        unique_clusters: r.lists.clusters,
        light_refs: r.lists.light_refs,
        pages: r.lists.pages,
        regrowths,
        max_list: r.lists.max_list,
        buffers,
        readback,
        grid: res.grid,
        overlapped,
        transparency: r.transparency,
        tess_levels: match &mut res.tessellation {
            Some(t) => t.levels()?,
            None => Vec::new(),
        },
        samples: res.grid.samples,
        light_moved: res.light_moved,
        shadows: res.shadows.as_ref().map(|m| m.stats()),
        bytes_per_sample: r.msaa_bytes_per_sample.unwrap_or_else(|| super::msaa::bytes_per_sample(res.settings.normal_precision)),
        edge_pixels: match (&mut res.msaa, r.msaa_edge_pixels) {
            (_, Some(n)) => n,
            (Some(m), None) => m.edge_pixels()?,
            (None, None) => 0,
        },
    })
}

fn check_view(s: &Settings) -> Result<()> {
    if !View::FRAME.contains(&s.view) {
        bail!("view {:?} is not a view of a rendered frame (one of {:?})", s.view, View::FRAME);
    }
    Ok(())
}

/// Lavapipe's loop limiter bounds the lights one invocation visits.
fn check_light_count(gpu: &Gpu, lights: usize) -> Result<()> {
    let max = shaders::light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE;
    if gpu.ctx.info.is_llvmpipe() && lights > max as usize {
        bail!(
            "{lights} lights: lavapipe's loop limiter ends a shader's loops after 65 535 iterations, so one invocation \
             can visit at most {max} lights there (use fewer lights or a GPU)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every registered technique renders shadows, so no frame reaches the refusal; a technique
    /// registered without them must still be refused in one line that names it and the ones
    /// that do, and only where a light casts shadows.
    #[test]
    fn a_technique_without_shadows_is_refused_in_one_line() {
        let without = Description { name: "no-shadows", shadows: false, ..*Technique::ALL[0].description() };
        let e = refuse_shadows(&without, 3, 10).expect_err("refused").to_string();
        assert!(!e.contains('\n'), "one line: {e}");
        assert!(e.starts_with("3 of 10 lights cast shadows, but no-shadows renders no shadows (techniques that do: "), "{e}");
        for t in Technique::ALL.iter().filter(|t| t.description().shadows) {
            assert!(e.contains(t.name()), "{e} names {}", t.name());
        }
        refuse_shadows(&without, 0, 10).expect("no casters: nothing to refuse");
        for t in Technique::ALL {
            assert_eq!(refuse_shadows(t.description(), 3, 10).is_ok(), t.description().shadows, "{}", t.name());
        }
    }
}
