//! Rendering a frame: G-buffer, then either brute-force deferred shading or the clustered chain.
//!
//! Clustered deferred (Olsson et al. 2012; Karas' Vulkan design), one kernel per step:
//! 1. **G-buffer** (raster) → depth | normal | albedo buffer (`gbuffer.rs`).
//! 2. **keys** — cluster key per pixel (`clustered::pixel_keys`).
//! 3. **page table** — mark pages → scan (allocate) → record → store slots → scan → compact
//!    into the sorted unique-cluster list (`page_table`), all sized from the resolution.
//! 4. **assignment** — per unique cluster, its lights (naive: every light against the cluster's
//!    AABB), as counts → scan → fill; offsets + counts give each cluster's list.
//! 5. **shading** — per pixel: key → page → slot → cluster → list → lights.
//!
//! The baselines of issue 5 live in their own files, one match arm each: `tiled.rs` (`tiled`,
//! `tiled-2.5d`), `clustered_aabb.rs`, `forward_plus.rs`.
//!
//! Capacities that depend on the view (pages touched, light references) are GPU counters read
//! back after the frame; if one exceeded its buffer, the buffer grows and the frame re-runs — a
//! frame never drops a light. Memory per buffer is reported in [`Frame::buffers`].
pub mod bitonic;
pub mod bvh;
pub mod clustered_aabb;
pub mod forward_plus;
pub mod gbuffer;
pub mod legend;
pub mod reference;
pub mod resources;
pub mod scan;
pub mod sort;
pub mod stats;
pub mod tiled;

use crate::gpu::Gpu;
use crate::vk::{Buffer, PassTiming, Profiler};
use anyhow::{bail, Context as _, Result};
use glam::Mat4;
pub use gbuffer::{Draw, TextureData};
use resources::{ClusterBuffers, Capacities};
use shaders::cluster_key::{slice_bounds, ClusterGrid};
use shaders::layout::*;

/// Lighting technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Technique {
    /// Every light for every pixel: the correctness reference.
    Deferred,
    /// Clustered deferred with unique clusters and naive (all-lights) assignment.
    ClusteredNaive,
    /// Clustered deferred with lights Morton-sorted (GPU radix sort) into a 32-ary BVH that each
    /// unique cluster traverses.
    ClusteredBvh,
    /// Tiled deferred (Olsson & Assarsson 2011; Harada et al. 2012): per screen tile, depth bounds,
    /// frustum culling into a workgroup-memory list, shading in the same dispatch (`tiled.rs`).
    Tiled,
    /// `tiled` plus Harada's 2.5D culling: a 32-cell depth mask per tile against each light's.
    #[value(name = "tiled-2.5d")]
    Tiled25d,
    /// Clustered deferred on a fixed grid with precomputed cluster boxes: active clusters from
    /// depth, staged sphere–box assignment with subgroup-aggregated atomics (`clustered_aabb.rs`).
    ClusteredAabb,
    /// Forward+ (Harada et al. 2012): depth pre-pass, tiled culling into per-tile linked lists,
    /// forward raster shading with depth test EQUAL (`forward_plus.rs`).
    ForwardPlus,
}

/// Scene data as the renderer consumes it (world space; lights validated).
pub struct SceneInput<'a> {
    pub positions: &'a [[f32; 3]],
    pub normals: &'a [[f32; 3]],
    pub uvs: &'a [[f32; 2]],
    pub indices: &'a [u32],
    pub draws: Vec<Draw>,
    pub materials: Vec<MaterialGpu>,
    pub lights: &'a [PointLight],
    /// Textures the draws index (`Draw::albedo_texture` / `mask_texture`).
    pub textures: Vec<TextureData<'a>>,
    pub view: Mat4,
    pub fov_y_radians: f32,
    pub near: f32,
    pub far: f32,
    pub effects: u32,
}

/// How to render.
#[derive(Clone, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub tile_size: u32,
    pub technique: Technique,
    /// `VIEW_SHADED` or `VIEW_HEATMAP`.
    pub view: u32,
    pub normal_precision: u32,
    pub exposure: f32,
    /// Timed frames after the warm-up frame (0: render once, untimed beyond it).
    pub frames: u32,
    /// Keep the cluster data for CPU checks and statistics.
    pub read_back: bool,
    /// Children per light-BVH node (32 or 64); 0: the device default
    /// ([`bvh::LightBvh::default_branching`]).
    pub bvh_branching: u32,
    /// Run the light sort + BVH build on the async-compute queue when the device has one.
    pub async_compute: bool,
    /// GPU sort of the lights' Morton keys (`clustered-bvh`).
    pub sort: sort::SortKind,
}

/// GPU results kept for checks and statistics.
pub struct Readback {
    /// Reversed-Z depth bits per pixel.
    pub depth: Vec<u32>,
    /// Decoded G-buffer normal per pixel (as the shading passes read it).
    pub normals: Vec<[f32; 3]>,
    pub keys: Vec<u32>,
    pub unique: Vec<u32>,
    pub counts: Vec<u32>,
    pub offsets: Vec<u32>,
    pub list: Vec<u32>,
    pub lights_view: Vec<PointLight>,
    pub grid: ClusterGrid,
    pub bounds: Vec<f32>,
}

/// A rendered frame.
pub struct Frame {
    pub pixels: Vec<u32>,
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
    /// The light sort and BVH build ran on the async-compute queue, overlapping the G-buffer
    /// raster ([`ASYNC_PASSES`]); the main queue's passes then account for the frame's time.
    pub overlapped: bool,
}

impl Frame {
    /// Whether pass `name` ran on the main queue (every pass, except the [`ASYNC_PASSES`] of an
    /// overlapped frame): the main queue's passes, waits included, make up the frame's time.
    pub fn on_main_queue(&self, name: &str) -> bool {
        !(self.overlapped && ASYNC_PASSES.contains(&name))
    }
}

/// Passes that run on the async-compute queue when the frame is overlapped.
pub const ASYNC_PASSES: [&str; 3] = ["morton keys", "light sort", "bvh build"];

/// Which shading variant a frame runs: 1 (with the specular term) only if the scene has specular
/// materials.
pub fn specular_variant(p: &FrameParams) -> usize {
    usize::from(p.effects & EFFECT_SPECULAR != 0)
}

/// Lights per pixel at the top of the heatmap ramp.
pub const HEAT_MAX: u32 = 64;

/// Lights in view space.
pub fn lights_to_view(view: Mat4, lights: &[PointLight]) -> Vec<PointLight> {
    lights
        .iter()
        .map(|l| PointLight { position: view.transform_point3(l.position.into()).to_array(), ..*l })
        .collect()
}

/// Renders one frame (plus `settings.frames` timed repetitions).
pub fn render(gpu: &Gpu, scene: &SceneInput<'_>, s: &Settings) -> Result<Frame> {
    let grid = ClusterGrid::new(s.width, s.height, s.tile_size, scene.near, scene.far, scene.fov_y_radians).context("cluster grid")?;
    if scene.materials.is_empty() || scene.materials.len() > MAX_MATERIALS as usize {
        bail!("{} materials: the G-buffer addresses 1..={MAX_MATERIALS}", scene.materials.len());
    }
    if let Some(d) = scene.draws.iter().find(|d| d.params.normal_precision != s.normal_precision) {
        bail!(
            "a draw encodes normals at precision {} but the frame reads them at {}: flatten the scene at the frame's precision",
            d.params.normal_precision,
            s.normal_precision
        );
    }
    let ctx = &gpu.ctx;
    let max_lights = shaders::light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE;
    if ctx.info.driver_name.to_lowercase().contains("llvmpipe") && scene.lights.len() > max_lights as usize {
        bail!(
            "{} lights: lavapipe's loop limiter ends a shader's loops after 65 535 iterations, so one invocation \
             can visit at most {max_lights} lights there (use fewer lights or a GPU)",
            scene.lights.len()
        );
    }
    let n = s.width * s.height;
    let geometry = gbuffer::Geometry::upload(ctx, scene.positions, scene.normals, scene.uvs, scene.indices, scene.draws.clone())
        .context("uploading geometry")?;
    let camera = Buffer::from_slice(ctx, "camera", &[gbuffer::raster_camera(scene.view, scene.fov_y_radians, s.width as f32 / s.height as f32, scene.near)])?;
    let targets = gbuffer::Targets::new(ctx, s.width, s.height, s.normal_precision).context("allocating the G-buffer")?;
    let textures = gbuffer::Textures::upload(ctx, &scene.textures).context("uploading textures")?;
    let lights_view = lights_to_view(scene.view, scene.lights);
    let lights = Buffer::from_slice(ctx, "lights", &lights_view).context("allocating the light buffer")?;
    let materials = Buffer::from_slice(ctx, "materials", &scene.materials)?;
    let bounds = slice_bounds(&grid);
    let bounds_buf = Buffer::from_slice(ctx, "slice bounds", &bounds)?;
    let mut frame_buf = Buffer::storage(ctx, "frame", 4 * n as u64).context("allocating the frame")?;
    let params = FrameParams {
        grid,
        count: n,
        num_lights: scene.lights.len() as u32,
        light_capacity: 0,
        effects: scene.effects,
        normal_precision: s.normal_precision,
        view: s.view,
        exposure: s.exposure,
        heat_max: HEAT_MAX,
    };
    let mut buffers: Vec<(String, u64)> = vec![
        ("geometry".into(), geometry.bytes()),
        ("textures".into(), textures.bytes()),
        ("gbuffer".into(), targets.bytes()),
        ("lights".into(), lights.size),
        ("frame".into(), frame_buf.size),
    ];
    let mut profiler = Profiler::new(ctx, 16)?;
    let mut regrowths = 0;
    let (mut unique_clusters, mut light_refs, mut pages, mut max_list) = (0, 0, 0, 0);
    let mut timings_all: Vec<Vec<PassTiming>> = Vec::new();
    let mut cluster = None;
    let mut overlapped = false;
    match s.technique {
        Technique::Deferred => {
            for f in 0..=s.frames {
                gpu.run(Some(&mut profiler), |rec| {
                    rec.pass("gbuffer", |rec| gbuffer::record(gpu, rec, &geometry, &textures, &camera, &targets))?;
                    rec.pass("shading", |rec| {
                        rec.dispatch_linear(&gpu.kernels.shade_deferred[specular_variant(&params)], &[&targets.depth_buf, &targets.normal_buf, &targets.albedo_buf, &lights, &materials, &frame_buf, &bounds_buf], &params, n)
                    })
                })?;
                if f > 0 || s.frames == 0 {
                    timings_all.push(profiler.results()?);
                }
            }
        }
        Technique::Tiled | Technique::Tiled25d => {
            let mut t = tiled::Tiled::new(gpu, &params, s.technique == Technique::Tiled25d)?;
            for f in 0..=s.frames {
                gpu.run(Some(&mut profiler), |rec| {
                    rec.pass("gbuffer", |rec| gbuffer::record(gpu, rec, &geometry, &textures, &camera, &targets))?;
                    t.record(gpu, rec, &targets, &lights, &materials, &frame_buf, &bounds_buf)
                })?;
                if f > 0 || s.frames == 0 {
                    timings_all.push(profiler.results()?);
                }
            }
            (light_refs, max_list) = t.list_totals()?;
            buffers.extend(t.sizes());
        }
        Technique::ClusteredAabb => {
            let gbuf = |rec: &mut crate::vk::Recorder<'_>| rec.pass("gbuffer", |rec| gbuffer::record(gpu, rec, &geometry, &textures, &camera, &targets));
            let o = clustered_aabb::run(gpu, &params, s.frames, &mut profiler, &gbuf, &targets, &bounds_buf, &lights, &materials, &frame_buf)?;
            (timings_all, unique_clusters, light_refs, max_list, regrowths) = (o.timings, o.active, o.refs, o.max_list, o.regrowths);
            buffers.extend(o.buffers);
        }
        Technique::ForwardPlus => {
            let sc = forward_plus::SceneGpu { geometry: &geometry, indices: scene.indices, textures: &textures, camera: &camera, lights: &lights, materials: &materials };
            let o = forward_plus::run(gpu, &params, s.frames, &mut profiler, &sc, &targets, &frame_buf)?;
            (timings_all, light_refs, max_list, regrowths) = (o.timings, o.refs, o.max_list, o.regrowths);
            buffers.extend(o.buffers);
        }
        Technique::ClusteredNaive | Technique::ClusteredBvh => {
            let bvh = match s.technique {
                Technique::ClusteredBvh => {
                    let b = match s.bvh_branching {
                        0 => bvh::LightBvh::default_branching(ctx.info.subgroup_size),
                        b if shaders::light_bvh::valid_branching(b) => b,
                        b => bail!("BVH branching {b}: 32 or 64"),
                    };
                    Some(bvh::LightBvh::new(gpu, &lights_view, b, s.sort).context("allocating the light BVH")?)
                }
                _ => None,
            };
            if let Some(b) = &bvh {
                buffers.push(("light bvh".into(), b.bytes()));
            }
            overlapped = bvh.is_some() && s.async_compute && ctx.async_compute_queue.is_some();
            let mut async_profiler = crate::vk::Profiler::new_async(ctx, 4)?;
            let mut caps = Capacities::initial(&grid, scene.lights.len() as u32);
            let mut cb = ClusterBuffers::new(gpu, &grid, caps)?;
            let mut f = 0;
            while f <= s.frames {
                let mut p = params;
                p.light_capacity = caps.light_refs;
                // The light sort + BVH build depend on the lights only: on the async-compute queue
                // they overlap the G-buffer raster (the assignment waits for them).
                gpu.run_overlapped(
                    overlapped,
                    Some(&mut profiler),
                    Some(&mut async_profiler),
                    |rec| bvh.as_ref().map_or(Ok(()), |b| b.record(gpu, rec, &lights)),
                    |rec| {
                        rec.pass("gbuffer", |rec| gbuffer::record(gpu, rec, &geometry, &textures, &camera, &targets))?;
                        cb.record(gpu, rec, &p, &targets, &bounds_buf, &lights, &materials, &frame_buf, bvh.as_ref())
                    },
                )?;
                let c: Vec<u32> = cb.counters.read(COUNTERS as usize)?;
                (unique_clusters, light_refs, pages) =
                    (c[COUNTER_UNIQUE_CLUSTERS as usize], c[COUNTER_LIGHT_REFS as usize], c[COUNTER_PAGES as usize]);
                if let Some(grown) = caps.grown(pages, light_refs) {
                    regrowths += 1;
                    if regrowths > 8 {
                        bail!("cluster buffers keep growing ({grown:?}): giving up");
                    }
                    caps = grown;
                    cb = ClusterBuffers::new(gpu, &grid, caps).with_context(|| {
                        format!("growing the cluster buffers to {} pages and {} light references", caps.pages, caps.light_refs)
                    })?;
                    continue; // re-run this frame
                }
                if f > 0 || s.frames == 0 {
                    let mut t = async_profiler.results()?;
                    t.extend(profiler.results()?);
                    timings_all.push(t);
                }
                f += 1;
            }
            buffers.extend(cb.sizes());
            cluster = Some(cb);
        }
    }
    let pixels: Vec<u32> = frame_buf.read(n as usize)?;
    let readback = if s.read_back {
        let mut depth = targets.depth_buf;
        let gbuffer: Vec<u32> = depth.read(n as usize)?;
        let precision = shaders::octahedral::Precision::from_u32(s.normal_precision);
        let mut normal_buf = targets.normal_buf;
        let words: Vec<u32> = normal_buf.read((precision.gbuffer_words() * n) as usize)?;
        let normals = words
            .chunks(precision.gbuffer_words() as usize)
            .map(|w| shaders::octahedral::decode([w[0], w.get(1).copied().unwrap_or(0), w.get(2).copied().unwrap_or(0)], precision))
            .collect();
        let mut rb = match cluster.as_mut() {
            Some(cb) => cb.read_back(gbuffer, unique_clusters, light_refs, lights_view.clone(), grid, bounds.clone())?,
            None => Readback { depth: gbuffer, normals: vec![], keys: vec![], unique: vec![], counts: vec![], offsets: vec![], list: vec![], lights_view, grid, bounds },
        };
        rb.normals = normals;
        Some(rb)
    } else {
        None
    };
    let (timings, timing_spread) = median_timings(&timings_all);
    Ok(Frame { pixels, timings, timing_spread, unique_clusters, light_refs, pages, regrowths, max_list, buffers, readback, grid, overlapped })
}

/// Per-pass median over frames, and the (min, max) beside it (passes matched by position).
fn median_timings(all: &[Vec<PassTiming>]) -> (Vec<PassTiming>, Vec<(f64, f64)>) {
    let Some(first) = all.first() else { return (Vec::new(), Vec::new()) };
    first
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut v: Vec<f64> = all.iter().filter_map(|f| f.get(i).map(|t| t.ms)).collect();
            v.sort_by(|a, b| a.total_cmp(b));
            (PassTiming { name: p.name.clone(), ms: v[v.len() / 2] }, (v[0], v[v.len() - 1]))
        })
        .unzip()
}
