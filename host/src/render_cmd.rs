//! `manylights render`: load a scene, add lights, render with a technique, write PNG (+ stats).
use crate::gpu::Gpu;
use crate::render::{self, Draw, SceneInput, Settings, Technique, TextureData};
use crate::scene::{lights, Scene, TextureKind};
use anyhow::{bail, Context as _, Result};
use shaders::layout::{DrawParams, MaterialGpu, PointLight};
use std::path::PathBuf;

/// What the frame shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum View {
    Shaded,
    /// Lights evaluated per pixel on a colour ramp (0 black … 64+ white; legend below the frame).
    Heatmap,
    /// Cluster keys hashed to colours.
    Clusters,
    /// Decoded G-buffer normals.
    Normals,
    /// Exponential depth slices on a colour ramp.
    Depth,
}

impl View {
    pub fn code(self) -> u32 {
        use shaders::layout::*;
        match self {
            Self::Shaded => VIEW_SHADED,
            Self::Heatmap => VIEW_HEATMAP,
            Self::Clusters => VIEW_CLUSTERS,
            Self::Normals => VIEW_NORMALS,
            Self::Depth => VIEW_DEPTH,
        }
    }
}

/// Arguments of `render` (see `manylights render --help`).
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Built-in scene (city, corridor, sponza, bunny; `name@view` for a named camera view:
    /// city@corner, sponza@column), a .toml description or an .obj file.
    #[arg(long, default_value = "city")]
    pub scene: String,
    /// Point lights to generate (when the scene description does not give them).
    #[arg(long, default_value_t = 1000)]
    pub lights: u32,
    #[arg(long, value_enum, default_value_t = Technique::ClusteredNaive)]
    pub technique: Technique,
    #[command(flatten)]
    pub frame: crate::cli::FrameArgs,
    /// Write statistics (device, per-pass GPU ms, bytes, clusters, lights per cluster/pixel) here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Timed frames after the warm-up (per-pass median).
    #[arg(long, default_value_t = 5)]
    pub frames: u32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, value_enum, default_value_t = View::Shaded)]
    pub view: View,
    /// Encoding of the G-buffer normals: octahedral 2×8, 2×12 or 2×16 bits in a 32-bit target, or
    /// float32 components in a 128-bit one.
    #[arg(long, value_enum, default_value_t = NormalPrecision::Oct16)]
    pub normal_precision: NormalPrecision,
    /// Children per light-BVH node for `clustered-bvh`: 32 or 64 (default: the subgroup width,
    /// clamped to 32..=64).
    #[arg(long, value_parser = clap::builder::TypedValueParser::map(clap::builder::PossibleValuesParser::new(["32", "64"]), |s: String| s.parse::<u32>().unwrap_or(0)))]
    pub bvh_branching: Option<u32>,
    /// Keep the light sort + BVH build on the graphics queue instead of overlapping them with the
    /// G-buffer raster on the async-compute queue (devices without one always do).
    #[arg(long)]
    pub no_async_compute: bool,
    /// GPU sort of the lights' Morton keys for `clustered-bvh`.
    #[arg(long, value_enum, default_value_t = crate::render::sort::SortKind::Radix)]
    pub sort: crate::render::sort::SortKind,
    /// Animation time in seconds: lights move on small deterministic circles (`lights::animate`).
    #[arg(long)]
    pub time: Option<f32>,
    /// Directory holding sponza/ and bunny/.
    #[arg(long, env = "MANYLIGHTS_ASSETS", default_value = "../shared/assets")]
    pub assets: PathBuf,
}

/// G-buffer normal encodings (see `shaders::octahedral` for their error bounds).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum NormalPrecision {
    Oct8,
    Oct12,
    Oct16,
    /// Three float32 components (a 16-byte normal target): lossless, the accuracy reference.
    F32,
}

impl NormalPrecision {
    pub fn code(self) -> u32 {
        use shaders::layout::*;
        match self {
            Self::Oct8 => PRECISION_OCT8,
            Self::Oct12 => PRECISION_OCT12,
            Self::Oct16 => PRECISION_OCT16,
            Self::F32 => PRECISION_F32,
        }
    }
}

/// Merged geometry, materials and draws of a scene.
pub struct Flattened {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
    pub draws: Vec<Draw>,
    pub materials: Vec<MaterialGpu>,
}

/// Merges a scene's meshes into one vertex/index set with one draw per mesh.
pub fn flatten(scene: &Scene, normal_precision: u32) -> Result<Flattened> {
    let mut f = Flattened { positions: vec![], normals: vec![], uvs: vec![], indices: vec![], draws: vec![], materials: vec![] };
    for m in &scene.materials {
        f.materials.push(MaterialGpu { specular: m.specular, roughness: m.roughness, _pad: [0.0; 2] });
    }
    if f.materials.is_empty() {
        f.materials.push(MaterialGpu { specular: 0.0, roughness: 1.0, _pad: [0.0; 2] });
    }
    if f.materials.len() > shaders::layout::MAX_MATERIALS as usize {
        bail!("scene has {} materials; the G-buffer addresses at most {}", f.materials.len(), shaders::layout::MAX_MATERIALS);
    }
    for mesh in &scene.meshes {
        let base = f.positions.len() as u32;
        let first_index = f.indices.len() as u32;
        f.positions.extend_from_slice(&mesh.positions);
        f.normals.extend_from_slice(&mesh.normals);
        f.uvs.extend_from_slice(&mesh.uvs);
        f.indices.extend(mesh.indices.iter().map(|i| i + base));
        let material = (mesh.material as usize).min(f.materials.len() - 1);
        let m = scene.materials.get(material);
        let albedo = m.map(|m| m.albedo).unwrap_or([0.8; 3]);
        // Textures only where the scene's effects call for them (no sampling otherwise).
        let texture = |path: Option<&std::path::PathBuf>| {
            path.and_then(|p| scene.textures.iter().position(|t| &t.path == p)).map(|i| i as u32)
        };
        let albedo_texture = if scene.effects.textures { texture(m.and_then(|m| m.albedo_texture.as_ref())) } else { None };
        let mask_texture = if scene.effects.alpha_test { texture(m.and_then(|m| m.alpha_mask_texture.as_ref())) } else { None };
        f.draws.push(Draw {
            first_index,
            index_count: mesh.indices.len() as u32,
            params: DrawParams { albedo, material: material as u32, normal_precision, _pad: [0; 3] },
            albedo_texture,
            mask_texture,
        });
    }
    Ok(f)
}

/// The renderer's view of a scene and its lights.
pub fn scene_input<'a>(scene: &'a Scene, flat: &'a Flattened, lights: &'a [PointLight]) -> SceneInput<'a> {
    let c = &scene.camera;
    SceneInput {
        positions: &flat.positions,
        normals: &flat.normals,
        uvs: &flat.uvs,
        indices: &flat.indices,
        draws: flat.draws.clone(),
        materials: flat.materials.clone(),
        lights,
        textures: scene
            .textures
            .iter()
            .map(|t| TextureData { width: t.width, height: t.height, rgba8: &t.rgba8, srgb: t.kind == TextureKind::Albedo })
            .collect(),
        view: c.view(),
        fov_y_radians: c.fov_y_degrees.to_radians(),
        near: c.near,
        far: c.far,
        effects: scene.effects.flags(),
    }
}

/// Checks what can be checked before loading anything: sizes and whether the lights fit.
pub fn check_args(gpu: &Gpu, a: &RenderArgs) -> Result<()> {
    let max = shaders::cluster_key::MAX_DIMENSION;
    if a.frame.width == 0 || a.frame.height == 0 || a.frame.width > max || a.frame.height > max {
        bail!("--width {} --height {}: both must be in 1..={max}", a.frame.width, a.frame.height);
    }
    let bytes = a.lights as u64 * std::mem::size_of::<PointLight>() as u64;
    let limit = gpu.ctx.info.max_storage_buffer_range as u64;
    if bytes > limit {
        bail!(
            "--lights {} needs {} MiB for the light buffer; {} addresses at most {} MiB per buffer",
            a.lights,
            bytes >> 20,
            gpu.ctx.info.name,
            limit >> 20
        );
    }
    Ok(())
}

pub fn run(gpu: &Gpu, a: &RenderArgs) -> Result<()> {
    check_args(gpu, a)?;
    let mut scene = Scene::load(&a.scene, &a.assets).with_context(|| format!("loading scene {:?}", a.scene))?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if scene.lights.is_empty() {
        if a.lights == 0 {
            bail!("--lights 0: nothing to light (give at least 1, or lights in a scene description)");
        }
        scene.lights = lights::uniform(&scene, a.lights as usize, a.seed).context("generating lights")?;
    }
    if let Some(t) = a.time {
        if !t.is_finite() {
            bail!("--time {t} is not a finite number of seconds");
        }
        scene.lights = lights::animate(&scene.lights, t);
    }
    scene.validate().context("scene")?;
    let precision = a.normal_precision.code();
    let flat = flatten(&scene, precision)?;
    let input = scene_input(&scene, &flat, &scene.lights);
    let settings = Settings {
        width: a.frame.width,
        height: a.frame.height,
        tile_size: a.frame.tile_size,
        technique: a.technique,
        view: a.view.code(),
        normal_precision: precision,
        exposure: 1.0,
        frames: a.frames,
        read_back: a.stats.is_some(),
        bvh_branching: a.bvh_branching.unwrap_or(0),
        async_compute: !a.no_async_compute,
        sort: a.sort,
    };
    eprintln!("rendering {} ({} triangles, {} lights) at {}x{} with {:?}", scene.name, scene.triangle_count(), scene.lights.len(), a.frame.width, a.frame.height, a.technique);
    let mut frame = render::render(gpu, &input, &settings)?;
    if a.view == View::Heatmap && !render::legend::draw(&mut frame.pixels, a.frame.width, a.frame.height, render::HEAT_MAX) {
        eprintln!("note: the frame is too small for the heatmap legend (0 black … {}+ white)", render::HEAT_MAX);
    }
    crate::debug_frame::save_png(&a.frame.out, a.frame.width, a.frame.height, &frame.pixels)?;
    for t in &frame.timings {
        eprintln!("{:<12} {:9.3} ms (GPU, median of {})", t.name, t.ms, a.frames.max(1));
    }
    if let Some(path) = &a.stats {
        let json = render::stats::stats_json(&gpu.ctx.info, &scene.name, scene.lights.len(), &settings, &frame);
        std::fs::write(path, serde_json::to_string_pretty(&json)?).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    eprintln!("wrote {}", a.frame.out.display());
    Ok(())
}
