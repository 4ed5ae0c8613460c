//! `manylights render`: load a scene, add lights, render with a technique, write PNG (+ stats).
//!
//! Steps: check the flags against the device (`preflight`), load the scene (`scene`), generate
//! lights if it has none, check its lights and textures against the device, adapt it to the
//! renderer (`scene::flatten`), render, write the PNG and the statistics. Bad input — a flag out
//! of range, a scene file missing or malformed, more lights than the device takes — is a
//! one-line `BadInput` (exit status 2).
use crate::args::{check_output_dir, frame_view_parser, precision_parser, FrameArgs};
use crate::bail_input;
use crate::bad_input::bad_input;
use crate::gpu::Gpu;
use crate::preflight;
use crate::render::{self, Settings, Technique};
use crate::scene::flatten::{flatten, scene_input};
use crate::scene::{description, lights, Scene};
use anyhow::{Context as _, Result};
use shaders::layout::View;
use shaders::octahedral::Precision;
use std::path::PathBuf;

/// Most timed frames `--frames` takes.
pub const MAX_FRAMES: u32 = 100_000;

/// Arguments of `render` (see `manylights render --help`).
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Built-in scene (city, corridor, glass, nurbs, sponza, bunny; `name@view` for a named camera view:
    /// city@corner, sponza@column, glass@stack), a .toml description, or an .obj, .gltf or .glb file.
    #[arg(long, default_value = "city")]
    pub scene: String,
    /// Point lights to generate (when the scene description does not give them).
    #[arg(long, default_value_t = 1000)]
    pub lights: u32,
    #[arg(long, value_enum, default_value_t = Technique::ClusteredNaive)]
    pub technique: Technique,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Write statistics (device, per-pass GPU ms, bytes, clusters, lights per cluster/pixel) here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Timed frames after the warm-up (per-pass median).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=MAX_FRAMES as i64))]
    pub frames: u32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Share of the `--lights` that are spot lights (random cones pointing mostly down,
    /// `lights::spot_cones`), in [0, 1]; scene descriptions use `[lights] spot_fraction`.
    #[arg(long, default_value_t = 0.0, value_parser = parse_fraction, allow_negative_numbers = true)]
    pub spot_fraction: f32,
    /// Share of the `--lights` that cast shadows (spread evenly, `lights::shadow_casters`), in
    /// [0, 1]; scene descriptions use `[lights] shadow_fraction` or `shadows = true` per light.
    /// Techniques that render shadows (cube shadow maps) draw them; the others refuse.
    #[arg(long, default_value_t = 0.0, value_parser = parse_fraction, allow_negative_numbers = true)]
    pub shadow_fraction: f32,
    /// `--shadows all`: every point and spot light of the scene casts shadows — its own lights
    /// (a description's or a glTF file's) as well as generated ones; the default, `listed`,
    /// keeps what the scene and `--shadow-fraction` say.
    #[arg(long, value_enum, default_value_t = ShadowCasters::Listed)]
    pub shadows: ShadowCasters,
    /// The largest side, in texels, of a face of a shadow-casting light's cube shadow map
    /// (1..=4096): each face gets the side its receivers ask (about two texels across a pixel's
    /// footprint), up to this.
    #[arg(long, default_value_t = crate::render::shadow_maps::DEFAULT_RESOLUTION)]
    pub shadow_resolution: u32,
    /// MiB of the shadow atlas all faces share; default: room for every face at
    /// `--shadow-resolution`, within the device's largest storage binding. Faces that ask for more
    /// than it holds are all halved until they fit (said in a warning and `--stats`).
    #[arg(long, value_name = "MIB")]
    pub shadow_atlas: Option<u64>,
    /// How the shadow lookup filters: `nearest` (one texel) or `bilinear` (2 × 2 percentage-closer
    /// filtering).
    #[arg(long, value_enum, default_value_t = crate::render::shadow_maps::ShadowFilter::Bilinear)]
    pub shadow_filter: crate::render::shadow_maps::ShadowFilter,
    /// What writes the shadow maps' triangles: `compute` (a compute kernel per culled batch and
    /// face) or `draw` (one indirect draw through the fixed-function rasteriser). Same texels.
    #[arg(long, value_enum, default_value_t = crate::render::shadow_maps::ShadowRaster::Compute)]
    pub shadow_raster: crate::render::shadow_maps::ShadowRaster,
    /// Which cube faces of the casters get triangles: `receivers` (only faces the frame's pixels
    /// look up, found from the G-buffer, each at the side its receivers ask) or `all` (every face
    /// a batch meets, each at `--shadow-resolution`).
    #[arg(long, value_enum, default_value_t = crate::render::shadow_maps::ShadowFaces::Receivers)]
    pub shadow_faces: crate::render::shadow_maps::ShadowFaces,
    /// Shade the frame on the CPU from the technique's read-back G-buffer, with exact ray-cast
    /// shadows for the lights that cast them (`render::cpu_shading`: the reference shadowed
    /// techniques are held to). Not with MSAA, NURBS patches, transparent materials or a debug
    /// view; alpha-tested triangles occlude whole.
    #[arg(long)]
    pub shadow_reference: bool,
    /// What the frame shows.
    #[arg(long, value_parser = frame_view_parser(), default_value = "shaded")]
    pub view: View,
    /// Encoding of the G-buffer normals: octahedral 2×8, 2×12 or 2×16 bits in a 32-bit target, or
    /// float32 components in a 128-bit one.
    #[arg(long, value_parser = precision_parser(), default_value = "oct16")]
    pub normal_precision: Precision,
    /// Children per light-BVH node for `clustered-bvh`: 32 or 64 (default: the subgroup width,
    /// clamped to 32..=64).
    #[arg(long, value_parser = clap::builder::TypedValueParser::map(clap::builder::PossibleValuesParser::new(["32", "64"]), |s: String| s.parse::<u32>().unwrap_or(0)))]
    pub bvh_branching: Option<u32>,
    /// Bits per axis of the light BVH's Morton keys for `clustered-bvh` (1..=10, default 10):
    /// the radix sort orders three times as many bits, one pass per 8 (8 bits per axis: 24-bit
    /// keys in three passes instead of four). Coarser keys leave lights of one cell in index
    /// order: looser leaf boxes, same lights found.
    #[arg(long)]
    pub morton_bits: Option<u32>,
    /// Keep the light sort + BVH build on the graphics queue instead of overlapping them with the
    /// G-buffer raster on the async-compute queue (devices without one always do).
    #[arg(long)]
    pub no_async_compute: bool,
    /// GPU sort of the lights' Morton keys for `clustered-bvh`: `auto` takes the bitonic sort up
    /// to 32 768 lights (faster there on the H200) and the radix sort above.
    #[arg(long, value_enum, default_value_t = crate::render::sort::SortKind::Auto)]
    pub sort: crate::render::sort::SortKind,
    /// Layout of the per-tile light lists for `forward-plus`: `linked` lists built with atomics
    /// (each fragment walks its tile's list), or contiguous `array`s the culling writes (each
    /// fragment reads its tile's offset, count and index range; faster on the H200 and on
    /// lavapipe).
    #[arg(long, value_enum, default_value_t = crate::render::forward_plus::TileLists::Array)]
    pub fp_lists: crate::render::forward_plus::TileLists,
    /// How `clustered-naive` and `clustered-bvh` find the frame's unique clusters: `tiles` (one
    /// workgroup per screen tile, one dispatch) or Karas' `page-table` (five dispatches; what
    /// scenes with transparent draws always use).
    #[arg(long, value_enum, default_value_t = crate::render::clustered::UniqueClusters::Tiles)]
    pub unique_clusters: crate::render::clustered::UniqueClusters,
    /// How the transparent pass resolves each pixel's fragments (scenes with transparent
    /// materials): `exact` (every layer sorted), the `k1`/`k2`/`k4`/`k8` nearest sorted over an
    /// order-independent average of the rest, or `weighted` blended OIT (no lists, no sorting).
    #[arg(long, value_enum, default_value_t = crate::render::transparent::OitVariant::K4)]
    pub oit: crate::render::transparent::OitVariant,
    /// Camera bookmark `x,y,z,yaw,pitch[,fov]` (degrees; the viewer's `C` key prints it): replaces
    /// the scene's camera position and direction.
    #[arg(long, value_parser = crate::scene::bookmark::parse_arg, allow_hyphen_values = true)]
    pub camera: Option<crate::scene::bookmark::Bookmark>,
    /// Tessellation level of every NURBS patch: quads along each parameter direction (default:
    /// each patch's own `level`, else 16).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=crate::scene::nurbs::MAX_TESS_LEVEL as i64))]
    pub tess_level: Option<u32>,
    /// Adaptive NURBS tessellation: each patch's level picked on the GPU every frame so that its
    /// triangles stay within this many pixels of the surface (levels 1 to 64; not with
    /// forward-plus, nor with transparent patches).
    #[arg(long, allow_negative_numbers = true)]
    pub tess_error: Option<f32>,
    /// Animation time in seconds: lights move on small deterministic circles (`lights::animate`).
    #[arg(long)]
    pub time: Option<f32>,
    /// Also time every dispatch, fill and copy inside each pass (listed as `pass · kernel`
    /// beneath the passes, and in `--stats`): where a pass's time goes.
    #[arg(long)]
    pub dispatch_times: bool,
    /// Samples per pixel of the G-buffer: 1 (no MSAA), 2, 4 or 8 (where the device has them).
    /// Edge pixels (samples of other surfaces, `shaders::msaa`) are shaded per sample, the others
    /// once; techniques without a per-sample edge pass refuse more than 1.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub msaa: u32,
    /// How the light buffer stores point lights: `full` 32-byte records (exact; at most
    /// 2^26 − 1 lights), or `compact` 16-byte ones (fixed-point position in the lights' box,
    /// 24-bit radius, shared-exponent colour; up to 2^27 − 4 lights; point lights only).
    #[arg(long, value_enum, default_value_t = crate::render::light_record::LightRecord::Full)]
    pub light_record: crate::render::light_record::LightRecord,
    /// The order the light buffer stores the scene's lights in: `spatial` (the Morton order of
    /// their world positions, `lights::spatial_order`: neighbours in space are neighbours in
    /// memory, the same image; 250M lights on an H100 in 34 ms instead of 68), or `given` (the
    /// description's or the generator's).
    #[arg(long, value_enum, default_value_t = lights::LightOrder::Spatial)]
    pub light_order: lights::LightOrder,
    /// Directory holding sponza/ and bunny/.
    #[arg(long, env = "MANYLIGHTS_ASSETS", default_value = "../shared/assets")]
    pub assets: PathBuf,
}

impl RenderArgs {
    /// The renderer's settings from the flags: `frames` timed frames, `read_back` for the stats.
    pub fn settings(&self, frames: u32, read_back: bool) -> Settings {
        Settings {
            width: self.frame.width,
            height: self.frame.height,
            tile_size: self.frame.tile_size,
            technique: self.technique,
            view: self.view,
            normal_precision: self.normal_precision,
            exposure: 1.0,
            frames,
            read_back,
            bvh_branching: self.bvh_branching.unwrap_or(0),
            morton_bits: self.morton_bits.unwrap_or(0),
            async_compute: !self.no_async_compute,
            sort: self.sort,
            fp_lists: self.fp_lists,
            unique_clusters: self.unique_clusters,
            oit: self.oit,
            dispatch_times: self.dispatch_times,
            msaa: self.msaa,
            light_record: self.light_record,
            shadow: crate::render::shadow_maps::ShadowSettings { resolution: self.shadow_resolution, atlas_bytes: self.shadow_atlas.map(|m| m.saturating_mul(1 << 20)), filter: self.shadow_filter, raster: self.shadow_raster, faces: self.shadow_faces },
        }
    }
}

/// Checks what can be checked before loading anything: the frame's size and tile against the
/// grid's and the device's limits, `--lights` against what the technique takes on the device,
/// and the output's directory.
pub fn check_args(gpu: &Gpu, a: &RenderArgs) -> Result<()> {
    let info = &gpu.ctx.info;
    let f = &a.frame;
    preflight::check_frame(info, f.width, f.height, f.tile_size, a.normal_precision)?;
    preflight::check_tile_for(a.technique, f.tile_size)?;
    preflight::check_msaa(info, a.technique, a.msaa, f.width, f.height, a.normal_precision)?;
    preflight::check_lights(info, a.technique, a.light_record, f.tile_size, a.lights as u64, &format!("--lights {}", a.lights))?;
    check_output_dir("--out", &f.out)?;
    if let Some(stats) = &a.stats {
        check_output_dir("--stats", stats)?;
    }
    if let Some(t) = a.time.filter(|t| !t.is_finite()) {
        bail_input!("--time {t} is not a finite number of seconds");
    }
    if let Some(e) = a.tess_error {
        render::nurbs::check_adaptive(a.technique, e).map_err(bad_input)?;
    }
    Ok(())
}

/// Checks a loaded scene against the device: its light count (from a description) and its
/// textures' sizes.
fn check_scene(gpu: &Gpu, a: &RenderArgs, scene: &Scene) -> Result<()> {
    let info = &gpu.ctx.info;
    let what = format!("scene {:?}", a.scene);
    preflight::check_lights(info, a.technique, a.light_record, a.frame.tile_size, scene.lights.len() as u64, &what)?;
    let max = info.max_image_dimension_2d;
    if let Some(t) = scene.textures.iter().find(|t| t.width > max || t.height > max) {
        bail_input!("{what}: texture {} is {}x{}; {} takes textures of at most {max}x{max} (maxImageDimension2D)", t.path.display(), t.width, t.height, info.name);
    }
    Ok(())
}

/// A description's light count against the device, before its lights are generated (a file
/// asking for 60 million lights is refused at once, not after building them).
fn check_description(gpu: &Gpu, a: &RenderArgs) -> Result<()> {
    let path = std::path::Path::new(&a.scene);
    if !a.scene.to_ascii_lowercase().ends_with(".toml") || !path.is_file() {
        return Ok(());
    }
    // A file that does not parse is reported by `Scene::load`, with its line.
    let parsed = std::fs::read_to_string(path).map_err(anyhow::Error::from).and_then(|text| description::parse(&text, path));
    match parsed {
        Ok(d) => preflight::check_lights(&gpu.ctx.info, a.technique, a.light_record, a.frame.tile_size, d.light_count() as u64, &format!("scene {:?}", a.scene)),
        Err(_) => Ok(()),
    }
}

/// Which lights cast shadows (`--shadows`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ShadowCasters {
    /// Those the scene marks, and the `--shadow-fraction` of generated lights.
    #[default]
    Listed,
    /// Every point and spot light.
    All,
}

/// `--shadows all`: marks every light of `scene` as a caster; refused in one line beside a
/// `--shadow-fraction`, which it would override.
pub fn apply_shadow_casters(scene: &mut Scene, a: &RenderArgs) -> Result<()> {
    if a.shadows == ShadowCasters::All {
        if a.shadow_fraction > 0.0 {
            bail_input!("--shadows all and --shadow-fraction {}: every light casts with the first, a share with the second; give one", a.shadow_fraction);
        }
        for i in 0..scene.lights.len() {
            scene.set_casts_shadows(i, true);
        }
    }
    Ok(())
}

pub fn run(gpu: &Gpu, a: &RenderArgs) -> Result<()> {
    check_args(gpu, a)?;
    check_description(gpu, a)?;
    // Its errors name the file (and line or key) already.
    let mut scene = Scene::load(&a.scene, &a.assets)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(b) = &a.camera {
        scene.camera = b.apply(&scene.camera);
    }
    if scene.lights.is_empty() {
        if a.lights == 0 {
            bail_input!("--lights 0: nothing to light (give at least 1, or lights in a scene description)");
        }
        let generated = lights::uniform(&scene, a.lights as usize, a.seed).with_context(|| format!("generating --lights {} in scene {:?}", a.lights, a.scene)).map_err(bad_input)?;
        let cones = lights::spot_cones(generated.len(), a.spot_fraction, a.seed).map_err(bad_input)?;
        let n = generated.len();
        scene.add_lights(generated.into_iter().zip(cones.into_iter().chain(std::iter::repeat(None)).take(n)));
        for (i, _) in lights::shadow_casters(n, a.shadow_fraction).map_err(bad_input)?.iter().enumerate().filter(|(_, &c)| c) {
            scene.set_casts_shadows(i, true);
        }
    } else if a.spot_fraction > 0.0 {
        bail_input!("--spot-fraction applies to the --lights the command generates; this scene has its own lights (use [lights] spot_fraction in its description)");
    } else if a.shadow_fraction > 0.0 {
        bail_input!("--shadow-fraction applies to the --lights the command generates; this scene has its own lights (use [lights] shadow_fraction or shadows = true in its description, or --shadows all)");
    }
    apply_shadow_casters(&mut scene, a)?;
    // Ordered before the animation, which moves each light by its index (as the viewer does).
    if a.light_order == lights::LightOrder::Spatial {
        scene.order_lights_spatially();
    }
    if let Some(t) = a.time {
        scene.lights = lights::animate(&scene.lights, t);
    }
    if let Some(level) = a.tess_level {
        scene.set_tess_level(level);
    }
    scene.validate().with_context(|| format!("scene {:?}", a.scene)).map_err(bad_input)?;
    check_scene(gpu, a, &scene)?;
    check_shadows(a, &scene)?;
    let flat = flatten(&scene, a.normal_precision).map_err(bad_input)?;
    let mut input = scene_input(&scene, &flat, &scene.lights);
    input.nurbs_tolerance = a.tess_error;
    // The reference shades on the CPU: the GPU frame renders without shadows and is read back.
    if a.shadow_reference {
        input.shadows = &[];
    }
    let settings = a.settings(a.frames, a.stats.is_some() || a.shadow_reference);
    render::renderer::check_shadow_scene(&input, &settings).map_err(bad_input)?;
    let patches = if scene.nurbs.is_empty() { String::new() } else { format!(", {} NURBS patches", scene.nurbs.len()) };
    eprintln!("rendering {} ({} triangles{patches}, {} lights) at {}x{} with {:?}", scene.name, scene.triangle_count(), scene.lights.len(), a.frame.width, a.frame.height, a.technique);
    let mut frame = render::render(gpu, &input, &settings)?;
    // Compact records quantise positions in the lights' box: say so where that moves a light by
    // more than 1 % of the smallest radius (lights spread far beyond the scene).
    let smallest = scene.lights.iter().map(|l| l.radius).fold(f32::INFINITY, f32::min);
    if frame.light_moved > 0.01 * smallest {
        eprintln!("warning: compact light records move lights by up to {:.3e} (the smallest light radius is {smallest:.3e}): the lights span a large box; --light-record full keeps them exact", frame.light_moved);
    }
    if let Some(sh) = frame.shadows {
        if sh.shift > 0 {
            eprintln!("warning: the shadow atlas ({} MiB) could not hold the sides the faces asked: every side divided by {} (--shadow-atlas raises it)", (4 * sh.atlas_texels as u64) >> 20, 1u32 << sh.shift);
        }
    }
    if a.shadow_reference {
        let start = std::time::Instant::now();
        let shadows = render::cpu_shading::Shadows::of_scene(&scene, &input.view);
        frame.pixels = render::cpu_shading::shade(&scene, &frame, &settings, Some(&shadows))?;
        eprintln!(
            "shadow reference: {} of {} lights cast shadows, {} occluding triangles, shaded on the CPU in {:.1} s",
            scene.shadow_casters(),
            scene.lights.len(),
            shadows.occluders.triangle_count(),
            start.elapsed().as_secs_f64()
        );
    }
    if a.view == View::Heatmap && !render::legend::draw(&mut frame.pixels, a.frame.width, a.frame.height, render::HEAT_MAX) {
        eprintln!("note: the frame is too small for the heatmap legend (0 black … {}+ white)", render::HEAT_MAX);
    }
    crate::debug_frame::save_png(&a.frame.out, a.frame.width, a.frame.height, &frame.pixels)?;
    let queue = |t: &crate::vk::PassTiming| if t.queue == crate::vk::Queue::Main { "" } else { ", async-compute queue" };
    for t in &frame.timings {
        match t.part {
            false => eprintln!("{:<12} {:9.3} ms (GPU, median of {}{})", t.name, t.ms, a.frames.max(1), queue(t)),
            true => eprintln!("  {:<40} {:9.3} ms", t.name, t.ms),
        }
    }
    let g = &frame.gpu_frame;
    if g.timed {
        let bound = if g.across_queues { "" } else { " (at least: this device's queues keep separate time lines)" };
        eprintln!("{:<12} {:9.3} ms (GPU, first to last timestamp over both queues{bound})", "frame", g.ms);
        if g.async_ms > 0.0 {
            eprintln!("{:<12} {:9.3} ms main queue, {:.3} ms async-compute queue, {:.3} ms overlapped", "", g.main_ms, g.async_ms, g.overlap_ms);
        }
    }
    if let Some(path) = &a.stats {
        let mut json = render::stats::stats_json(&gpu.ctx.info, &scene.name, scene.lights.len(), &settings, &frame);
        json["light_order"] = serde_json::json!(a.light_order.name());
        std::fs::write(path, serde_json::to_string_pretty(&json)?).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    eprintln!("wrote {}", a.frame.out.display());
    Ok(())
}

/// `--shadow-reference` takes what its ray cast and read-back G-buffer hold; alpha-tested
/// triangles cast whole shadows (neither the shadow maps nor the ray cast read textures).
fn check_shadows(a: &RenderArgs, scene: &Scene) -> Result<()> {
    if scene.shadow_casters() > 0 && scene.effects.alpha_test {
        eprintln!("warning: alpha-tested triangles cast whole shadows (the shadow maps and the ray cast read no textures)");
    }
    if !a.shadow_reference {
        return Ok(());
    }
    let refuse = [
        (a.msaa > 1, "--msaa above 1 (the reference shades one sample per pixel)"),
        (a.view != View::Shaded, "a --view other than shaded"),
        (!scene.nurbs.is_empty(), "NURBS patches (the ray cast takes the scene's triangles only)"),
        (scene.has_transparency(), "transparent materials (the ray cast treats every triangle as opaque)"),
    ];
    if let Some((_, what)) = refuse.iter().find(|r| r.0) {
        bail_input!("--shadow-reference does not take {what}");
    }
    Ok(())
}

/// A value in [0, 1] (`--spot-fraction`, `--shadow-fraction`).
pub fn parse_fraction(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        Ok(v) => Err(format!("{v} is not in [0, 1]")),
        Err(e) => Err(e.to_string()),
    }
}
