//! `manylights bench`: every technique side by side, measured the same way.
//!
//! Steps:
//! 0. Warm the GPU up: every technique in turn for [`WARM_UP_SECONDS`], unrecorded (clocks).
//! 1. For each scene × resolution × light count × technique (the sweep), generate the lights
//!    (seeded, uniform in the scene; `--spot-fraction` of them spots, culled by cone, by range
//!    sphere or each way in turn: `--spot-culling`, `spots.rs`), render one warm-up frame and
//!    `--frames` timed frames, and keep each pass's GPU-timestamp median, min and max, the
//!    bytes of every buffer and the lights per pixel ([`run_config`]). A configuration that
//!    would take minutes per frame (brute force at 1M lights, per-cluster naive tests at 10M)
//!    is skipped with a note ([`skip_reason`]); one the device refuses (memory, lavapipe's loop
//!    limit) is recorded with the refusal — neither is ever timed out or dropped silently.
//! 2. Write `results.csv` (one row per configuration and stage, [`CSV_COLUMNS`]).
//! 3. Draw the plots (`plots.rs`): frame ms vs lights (log–log, one line per technique: Karas'
//!    Fig. 8) and stacked per-stage ms of the clustered techniques (Karas' Fig. 7).
//! 4. Write `results.md` (`report.rs`): device line and command line on top, the frame-time
//!    table, the speed-up table at 10k lights against each baseline (Karas' Table 1), the stage
//!    breakdown, the skips.
//!
//! The "frame" stage is the whole GPU frame: first to last timestamp over both queues
//! (`render::frame_time`; each pass row says its `queue`); "compute" is the frame without the
//! main queue's raster passes (each pass row says its `kind`), because a GPU may give raster work
//! only part of the chip (the H100 and H200 run it on 2 of their TPCs) — both are reported.
pub mod accuracy;
pub mod flythrough;
pub mod plots;
pub mod report;
pub mod spots;

use crate::gpu::Gpu;
use crate::render::{self, LightCost, Settings, Technique};
use crate::scene::flatten::flatten;
use crate::vk::Queue;
use crate::scene::Scene;
use anyhow::{bail, ensure, Context as _, Result};
use clap::{Args, ValueEnum};
use shaders::layout::View;
use shaders::octahedral::Precision;
use std::io::Write as _;
use std::path::PathBuf;

pub use spots::{present_series, with_spots, Series, SpotCulling};

/// Columns of `results.csv`.
pub const CSV_COLUMNS: [&str; 18] = [
    "scene", "technique", "width", "height", "lights", "frames", "stage", "queue", "kind", "median_ms", "min_ms", "max_ms", "bytes",
    "light_lists", "lights_per_list_mean", "lights_per_list_max", "spot_fraction", "spot_culling",
];

/// `queue` of a pass row: the queue it ran on (the "frame" and "compute" rows: `all`, both).
pub const QUEUE_MAIN: &str = "main";
pub const QUEUE_ASYNC: &str = "async-compute";
pub const QUEUE_ALL: &str = "all";
/// `kind` of a row: a raster pass, a compute pass (dispatches, copies), or a span of the whole
/// frame ("frame", "compute").
pub const KIND_RASTER: &str = "raster";
pub const KIND_COMPUTE: &str = "compute";
pub const KIND_SPAN: &str = "span";

/// Seconds every sweep spends warming the GPU up before its first recorded configuration.
pub const WARM_UP_SECONDS: f64 = 10.0;

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Light counts to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [1_000usize, 10_000, 50_000, 150_000, 1_000_000, 10_000_000])]
    pub lights: Vec<usize>,
    /// Techniques: `all` or a comma-separated list (`manylights render --help` names them).
    #[arg(long, default_value = "all")]
    pub techniques: String,
    /// Scenes (`city`, `sponza`, `corridor`, `glass`, `bunny` or a path; `name@view` for a named camera
    /// view, e.g. `city@corner`, `sponza@column` with large depth discontinuities), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = ["city".to_string(), "sponza".to_string(), "sponza@column".to_string()])]
    pub scenes: Vec<String>,
    #[arg(long, default_value_t = 1920)]
    pub width: u32,
    #[arg(long, default_value_t = 1080)]
    pub height: u32,
    /// Timed frames per configuration, after one warm-up frame.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Cluster / tile edge in pixels.
    #[arg(long, default_value_t = 32)]
    pub tile_size: u32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Share of the generated lights of every sweep point that are spot lights, in [0, 1]
    /// (`lights::spot_cones` with `--seed`, as `render --spot-fraction`).
    #[arg(long, default_value_t = 0.0, value_parser = crate::render_cmd::parse_fraction, allow_negative_numbers = true)]
    pub spot_fraction: f32,
    /// How the techniques cull spot lights: `cone` (cone after the range sphere), `sphere` (range
    /// sphere only), or `both` (each technique measured both ways). Needs `--spot-fraction` > 0
    /// for `sphere` and `both`.
    #[arg(long, value_enum, default_value_t = SpotCulling::Cone)]
    pub spot_culling: SpotCulling,
    /// Directory holding sponza/ and bunny/.
    #[arg(long, env = "MANYLIGHTS_ASSETS", default_value = "../shared/assets")]
    pub assets: PathBuf,
    /// Output directory (results.csv, results.md, plots).
    #[arg(long)]
    pub out: PathBuf,
    /// Instead of the sweep, run a study: `accuracy` (image error vs time per knob, at the light
    /// count closest to 10k; writes accuracy.csv, results.md and a Pareto plot per scene).
    #[arg(long, value_enum)]
    pub study: Option<Study>,
    /// The accuracy study's knobs to measure (comma-separated; default: every knob). Without the
    /// first four, no brute-force reference is rendered (`oit` alone on a scene with many
    /// transparent layers: brute force would shade every light for every transparent fragment).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = accuracy::Knob::ALL)]
    pub knobs: Vec<accuracy::Knob>,
    /// Camera bookmark `x,y,z,yaw,pitch[,fov]` (degrees; `render --camera`, the viewer's `C`
    /// key) for every scene of the sweep, instead of each scene's own camera.
    #[arg(long, value_parser = crate::scene::bookmark::parse_arg, allow_hyphen_values = true)]
    pub camera: Option<crate::scene::bookmark::Bookmark>,
    /// A camera path (one bookmark per line): each configuration also flies it, one frame per
    /// camera, and reports the frame time's median, 99th percentile and maximum
    /// (`flythrough.csv`, `results.md`).
    #[arg(long)]
    pub camera_path: Option<PathBuf>,
}

/// Loads scene `name` of the sweep, with `--camera` where given.
pub fn load_scene(name: &str, a: &BenchArgs) -> Result<Scene> {
    let mut scene = Scene::load(name, &a.assets).with_context(|| format!("loading scene {name:?}"))?;
    if let Some(b) = &a.camera {
        scene.camera = b.apply(&scene.camera);
        scene.camera.validate().with_context(|| format!("scene {name:?} with --camera {b}")).map_err(crate::bad_input::bad_input)?;
    }
    Ok(scene)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Study {
    Accuracy,
}

/// One measured stage of one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub scene: String,
    pub technique: Technique,
    pub width: u32,
    pub height: u32,
    pub lights: usize,
    pub frames: u32,
    pub stage: String,
    /// [`QUEUE_MAIN`], [`QUEUE_ASYNC`] or [`QUEUE_ALL`].
    pub queue: &'static str,
    /// [`KIND_RASTER`], [`KIND_COMPUTE`] or [`KIND_SPAN`].
    pub kind: &'static str,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub bytes: u64,
    /// Light lists the technique built: unique or active clusters, screen tiles, or 1 for brute
    /// force (one list of every light, shared by all pixels).
    pub light_lists: u32,
    /// Mean and longest list (false positives included: what shading evaluates per list).
    pub lights_per_list_mean: f64,
    pub lights_per_list_max: u32,
    /// Share of the generated lights that are spots (`--spot-fraction`).
    pub spot_fraction: f32,
    /// How the spots were culled: [`SpotCulling::Cone`] or [`SpotCulling::Sphere`] (cone
    /// without spots: there is nothing to cull by cone).
    pub spot_culling: SpotCulling,
}

/// A configuration that was not measured, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Skip {
    pub scene: String,
    pub technique: Technique,
    pub lights: usize,
    /// The spot culling of the configuration (`None`: skipped whatever the culling).
    pub culling: Option<SpotCulling>,
    pub why: String,
}

/// Everything one sweep measured.
#[derive(Clone, Debug, Default)]
pub struct Results {
    pub device: String,
    /// The device's queues share one timestamp time line, so "frame" spans both queues exactly
    /// (otherwise it is the longer queue's span, a lower bound).
    pub frame_spans_queues: bool,
    pub command: String,
    pub rows: Vec<Row>,
    pub skips: Vec<Skip>,
    /// Fly-throughs of `--camera-path`, one per configuration measured.
    pub flythrough: Vec<flythrough::FlyRow>,
}

/// The techniques named by `--techniques`.
pub fn parse_techniques(s: &str) -> Result<Vec<Technique>> {
    if s.trim() == "all" {
        return Ok(Technique::value_variants().to_vec());
    }
    s.split(',')
        .map(|t| {
            Technique::from_str(t.trim(), true)
                .map_err(|_| crate::bad_input::bad_input(anyhow::anyhow!("--techniques: unknown technique {t:?} (try `all`, or see `manylights render --help`)")))
        })
        .collect()
}

/// Why a configuration is not worth timing (minutes per configuration), from the tests it would
/// make per frame:
/// - `deferred` tests every light at every pixel: beyond 4·10^11 light–pixel pairs on a GPU
///   (1M lights at 1080p is 2·10^12: ≈ 2.6 s per frame on an H100, half a minute per
///   configuration), beyond 2·10^9 on a CPU driver;
/// - `clustered-naive` and `clustered-aabb` test every light against each cluster that holds
///   pixels, about one per [`PIXELS_PER_CLUSTER`] pixels (6 700–8 000 clusters at 1080p): beyond
///   [`CLUSTER_PAIRS_GPU`] light–cluster pairs on a GPU (10M lights at 1080p is 8·10^10: 6 s per
///   frame for the naive assignment, measured 0.63 s at 1M on an H100), beyond
///   [`CLUSTER_PAIRS_CPU`] on a CPU driver.
pub fn skip_reason(t: Technique, lights: usize, pixels: u64, cpu_driver: bool, transparent: bool) -> Option<String> {
    let pairs = lights as u64 * pixels;
    let limit: u64 = if cpu_driver { 2_000_000_000 } else { 400_000_000_000 };
    let cost = t.description().cost;
    if transparent && cost == LightCost::EveryLightPerPixel {
        // Brute force also shades every light for every transparent fragment, in a fragment
        // shader: count TRANSPARENT_LAYERS layers per pixel at FRAGMENT_COST times the cost.
        let fragment_pairs = pairs.saturating_mul(TRANSPARENT_LAYERS);
        let fragment_limit = limit / FRAGMENT_COST;
        if fragment_pairs > fragment_limit {
            return Some(format!(
                "brute force would shade about {fragment_pairs:.3e} light–fragment pairs of transparent surfaces per frame in a fragment shader (limit {fragment_limit:.0e}): minutes per run"
            ));
        }
    }
    let cluster_pairs = lights as u64 * (pixels / PIXELS_PER_CLUSTER).max(1);
    let cluster_limit = if cpu_driver { CLUSTER_PAIRS_CPU } else { CLUSTER_PAIRS_GPU };
    match cost {
        LightCost::EveryLightPerPixel if pairs > limit => {
            Some(format!("brute force would test {pairs:.3e} light–pixel pairs per frame (limit {limit:.0e}): minutes per run"))
        }
        LightCost::EveryLightPerCluster if cluster_pairs > cluster_limit => Some(format!(
            "every light against every cluster: about {cluster_pairs:.3e} light–cluster pairs per frame (limit {cluster_limit:.0e}): minutes per run"
        )),
        _ => None,
    }
}

/// Transparent layers per pixel [`skip_reason`] assumes for brute force in a transparent scene.
pub const TRANSPARENT_LAYERS: u64 = 4;
/// How much more a light costs in a fragment shader than in a compute kernel, for
/// [`skip_reason`]: Forward+ on the H200 (`docs/results/h200/README.md`) shades the same lights
/// about 50× slower in its fragment shader than the compute techniques do.
pub const FRAGMENT_COST: u64 = 50;

/// Pixels per cluster holding pixels, for [`skip_reason`]'s estimate (1080p Sponza and city: 6 700
/// – 8 000 unique clusters for 2.07M pixels).
pub const PIXELS_PER_CLUSTER: u64 = 256;
/// Light–cluster pairs per frame beyond which the per-cluster naive tests are not timed on a GPU.
pub const CLUSTER_PAIRS_GPU: u64 = 20_000_000_000;
/// The same on a CPU driver.
pub const CLUSTER_PAIRS_CPU: u64 = 100_000_000;

/// Renders one configuration (`n` generated lights, `--spot-fraction` of them spots culled the
/// `culling` way) and turns its passes into rows.
pub fn run_config(gpu: &Gpu, scene: &Scene, name: &str, t: Technique, n: usize, culling: SpotCulling, a: &BenchArgs) -> Result<Vec<Row>> {
    let (l, cones) = spots::generate(scene, n, a)?;
    let flat = flatten(scene, Precision::Oct16)?;
    let s = settings_of(a, t);
    let frame = render::render(gpu, &spots::input(scene, &flat, &l, &cones, culling), &s)?;
    run_rows(frame, name, t, n, culling, a)
}

/// The settings of a configuration of the sweep.
pub fn settings_of(a: &BenchArgs, t: Technique) -> Settings {
    Settings {
        width: a.width,
        height: a.height,
        tile_size: a.tile_size,
        technique: t,
        view: View::Shaded,
        normal_precision: Precision::Oct16,
        exposure: 1.0,
        frames: a.frames,
        read_back: true,
        bvh_branching: 0,
        morton_bits: 0,
        async_compute: true,
        sort: Default::default(),
        fp_lists: Default::default(),
        unique_clusters: Default::default(),
        oit: Default::default(),
        dispatch_times: false,
        msaa: 1,
        light_record: Default::default(),
        shadow: Default::default(),
    }
}

/// The rows of a configuration's measured frame.
fn run_rows(frame: render::Frame, name: &str, t: Technique, n: usize, culling: SpotCulling, a: &BenchArgs) -> Result<Vec<Row>> {
    ensure!(!frame.timings.is_empty(), "the device reports no GPU timestamps: nothing to measure");
    let bytes: u64 = frame.buffers.iter().map(|b| b.1).sum();
    let brute_force = t.description().cost == LightCost::EveryLightPerPixel;
    let light_lists = match t {
        _ if brute_force => 1,
        _ if frame.unique_clusters > 0 => frame.unique_clusters,
        _ => a.width.div_ceil(a.tile_size) * a.height.div_ceil(a.tile_size),
    };
    let (lights_per_list_mean, lights_per_list_max) = match (t, frame.readback.as_ref()) {
        _ if brute_force => (n as f64, n as u32),
        (_, Some(rb)) if !rb.counts.is_empty() => {
            let st = render::reference::list_stats(rb);
            (st.mean_per_cluster, st.max_per_cluster)
        }
        _ => (frame.light_refs as f64 / light_lists.max(1) as f64, frame.max_list),
    };
    let row = |stage: &str, queue: &'static str, kind: &'static str, median_ms: f64, min_ms: f64, max_ms: f64| Row {
        scene: name.to_string(),
        technique: t,
        width: a.width,
        height: a.height,
        lights: n,
        frames: a.frames,
        stage: stage.to_string(),
        queue,
        kind,
        median_ms,
        min_ms,
        max_ms,
        bytes,
        light_lists,
        lights_per_list_mean,
        lights_per_list_max,
        spot_fraction: a.spot_fraction,
        spot_culling: culling,
    };
    let mut rows: Vec<Row> = frame
        .timings
        .iter()
        .zip(&frame.timing_spread)
        .map(|(p, &(lo, hi))| {
            let queue = if p.queue == Queue::Main { QUEUE_MAIN } else { QUEUE_ASYNC };
            row(&p.name, queue, if p.raster { KIND_RASTER } else { KIND_COMPUTE }, p.ms, lo, hi)
        })
        .collect();
    // The whole GPU frame over both queues (render::frame_time), and the frame without its
    // raster passes: medians of the per-frame values, with their extremes.
    let g = &frame.gpu_frame;
    let frame_row = row("frame", QUEUE_ALL, KIND_SPAN, g.ms, g.min_ms, g.max_ms);
    let compute_row = row("compute", QUEUE_ALL, KIND_SPAN, g.non_raster_ms, g.non_raster_min_ms, g.non_raster_max_ms);
    rows.push(frame_row);
    rows.push(compute_row);
    Ok(rows)
}

/// The sweep (step 1); progress on stderr.
pub fn sweep(gpu: &Gpu, a: &BenchArgs, command: String) -> Result<Results> {
    let techniques = parse_techniques(&a.techniques)?;
    if a.lights.is_empty() || a.lights.contains(&0) {
        crate::bail_input!("--lights needs positive light counts");
    }
    if a.scenes.is_empty() {
        crate::bail_input!("--scenes is empty");
    }
    if a.frames == 0 {
        crate::bail_input!("--frames must be at least 1");
    }
    let cpu_driver = gpu.ctx.info.is_llvmpipe();
    let total = (a.scenes.len() * a.lights.len() * techniques.len()) as u64;
    let bar = indicatif::ProgressBar::new(total).with_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed} / ~{duration}]").unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut out = Results { device: gpu.ctx.info.line(), frame_spans_queues: gpu.ctx.info.timestamps_across_queues, command, ..Default::default() };
    let path = a.camera_path.as_deref().map(flythrough::load_path).transpose()?;
    // Warm-up: a GPU idle before the sweep starts at low clocks and ramps up over seconds; one
    // warm-up frame per configuration does not undo that for the first configurations. On a cold
    // H100, 2 s of deferred frames left Forward+'s first configuration (raster-bound) 2× slow,
    // and 1 s per technique still 1.3×. So the techniques take turns on the first scene and light
    // count for 10 s, unrecorded (not on lavapipe, whose times are not quoted anyway).
    let warm_up_seconds = if cpu_driver { 0.0 } else { WARM_UP_SECONDS };
    if let (Some(name), Some(&n)) = (a.scenes.first(), a.lights.first()) {
        let scene = load_scene(name, a)?;
        let warm = BenchArgs { frames: a.frames.max(10), ..a.clone() };
        let runnable: Vec<Technique> =
            techniques.iter().copied().filter(|&t| skip_reason(t, n, a.width as u64 * a.height as u64, cpu_driver, scene.has_transparency()).is_none()).collect();
        let start = std::time::Instant::now();
        'warm: while !runnable.is_empty() && start.elapsed().as_secs_f64() < warm_up_seconds {
            for &t in &runnable {
                if run_config(gpu, &scene, name, t, n, a.spot_culling.modes()[0], &warm).is_err() {
                    break 'warm; // the sweep records the error where it belongs
                }
            }
        }
    }
    for name in &a.scenes {
        let scene = load_scene(name, a)?;
        for &n in &a.lights {
            for &t in &techniques {
                bar.set_message(format!("{name} {t:?} {n} lights"));
                let pixels = a.width as u64 * a.height as u64;
                if let Some(why) = skip_reason(t, n, pixels, cpu_driver, scene.has_transparency()) {
                    out.skips.push(Skip { scene: name.clone(), technique: t, lights: n, culling: None, why });
                    bar.inc(1);
                    continue;
                }
                for &culling in a.spot_culling.modes() {
                    let skip = |why: String| Skip { scene: name.clone(), technique: t, lights: n, culling: Some(culling), why };
                    match run_config(gpu, &scene, name, t, n, culling, a) {
                        Ok(rows) => out.rows.extend(rows),
                        Err(e) => out.skips.push(skip(format!("{e:#}"))),
                    }
                    if let Some(cameras) = &path {
                        match flythrough::fly(gpu, &scene, name, Series { technique: t, culling }, n, a, cameras) {
                            Ok(row) => out.flythrough.push(row),
                            Err(e) => out.skips.push(skip(format!("fly-through: {e:#}"))),
                        }
                    }
                }
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    Ok(out)
}

/// `results.csv` (step 2).
pub fn write_csv(r: &Results, w: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(w, "{}", CSV_COLUMNS.join(","))?;
    for x in &r.rows {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{:.6},{:.6},{:.6},{},{},{:.4},{},{},{}",
            csv_field(&x.scene),
            technique_name(x.technique),
            x.width,
            x.height,
            x.lights,
            x.frames,
            csv_field(&x.stage),
            x.queue,
            x.kind,
            x.median_ms,
            x.min_ms,
            x.max_ms,
            x.bytes,
            x.light_lists,
            x.lights_per_list_mean,
            x.lights_per_list_max,
            x.spot_fraction,
            x.spot_culling.name()
        )?;
    }
    Ok(())
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Techniques that have rows, in the enum's order.
pub fn present_techniques(rows: &[&Row]) -> Vec<Technique> {
    Technique::value_variants().iter().copied().filter(|t| rows.iter().any(|x| x.technique == *t)).collect()
}

/// The technique's command-line name (`clustered-bvh`).
pub fn technique_name(t: Technique) -> String {
    t.name().to_string()
}

/// The command line as a user types it, for the results: the program as `manylights` (not the
/// path it was started from), arguments with spaces quoted.
fn command_line() -> String {
    let args = std::env::args().skip(1).map(|s| if s.contains(' ') { format!("'{s}'") } else { s });
    std::iter::once("manylights".to_string()).chain(args).collect::<Vec<_>>().join(" ")
}

/// `manylights bench`: sweep, CSV, plots, markdown.
pub fn run(gpu: &Gpu, a: &BenchArgs) -> Result<()> {
    spots::check_args(a)?;
    // The accuracy study's reference reads float32 normals: the widest G-buffer.
    let widest = if a.study.is_some() { Precision::F32 } else { Precision::Oct16 };
    crate::preflight::check_frame(&gpu.ctx.info, a.width, a.height, a.tile_size, widest)?;
    let command = command_line();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    if a.study == Some(Study::Accuracy) {
        let rows = accuracy::study(gpu, a)?;
        let csv = a.out.join("accuracy.csv");
        let mut f = std::io::BufWriter::new(std::fs::File::create(&csv).with_context(|| format!("creating {}", csv.display()))?);
        accuracy::write_csv(&rows, &mut f).and_then(|_| f.flush()).with_context(|| format!("writing {}", csv.display()))?;
        let plots = accuracy::pareto_plots(&rows, &a.out).context("drawing the Pareto plots")?;
        let md = a.out.join("results.md");
        std::fs::write(&md, accuracy::markdown(&rows, &gpu.ctx.info.line(), &command, &plots)).with_context(|| format!("writing {}", md.display()))?;
        eprintln!("wrote {}, {} and {} plot(s) in {}", csv.display(), md.display(), plots.len(), a.out.display());
        return Ok(());
    }
    let r = sweep(gpu, a, command)?;
    if r.rows.is_empty() {
        bail!("no configuration could be measured: {:?}", r.skips.iter().map(|s| &s.why).collect::<Vec<_>>());
    }
    let csv = a.out.join("results.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&csv).with_context(|| format!("creating {}", csv.display()))?);
    write_csv(&r, &mut f).and_then(|_| f.flush()).with_context(|| format!("writing {}", csv.display()))?;
    let plots = plots::draw_all(&r, &a.out).context("drawing the plots")?;
    let md = a.out.join("results.md");
    std::fs::write(&md, report::markdown(&r, &plots) + &flythrough::markdown(&r.flythrough)).with_context(|| format!("writing {}", md.display()))?;
    if !r.flythrough.is_empty() {
        let fly = a.out.join("flythrough.csv");
        let mut f = std::io::BufWriter::new(std::fs::File::create(&fly).with_context(|| format!("creating {}", fly.display()))?);
        flythrough::write_csv(&r.flythrough, &mut f).and_then(|_| f.flush()).with_context(|| format!("writing {}", fly.display()))?;
    }
    for s in &r.skips {
        let culling = s.culling.filter(|_| a.spot_fraction > 0.0).map(|c| format!(" ({} culling)", c.name())).unwrap_or_default();
        eprintln!("skipped {} {} {} lights{culling}: {}", s.scene, technique_name(s.technique), s.lights, s.why);
    }
    eprintln!("wrote {}, {} and {} plot(s) in {}", csv.display(), md.display(), plots.len(), a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the configurations that would take minutes are skipped: brute force from 1M lights at
    /// 1080p, the per-cluster naive tests at 10M; never the culling techniques.
    #[test]
    fn skips_what_would_take_minutes_only() {
        let hd = 1920 * 1080;
        let skipped = |t, n| skip_reason(t, n, hd, false, false).is_some();
        assert!(!skipped(Technique::Deferred, 100_000) && skipped(Technique::Deferred, 1_000_000));
        // Transparent surfaces: brute force shades them per fragment, so it stops far earlier.
        let transparent = |t, n| skip_reason(t, n, hd, false, true).is_some();
        assert!(!transparent(Technique::Deferred, 500) && transparent(Technique::Deferred, 10_000));
        assert!(!transparent(Technique::ClusteredBvh, 10_000_000));
        for t in [Technique::ClusteredNaive, Technique::ClusteredAabb] {
            assert!(!skipped(t, 1_000_000) && skipped(t, 10_000_000), "{t:?}");
        }
        for t in [Technique::ClusteredBvh, Technique::Tiled, Technique::Tiled25d, Technique::ForwardPlus] {
            assert!(!skipped(t, 10_000_000), "{t:?}");
        }
    }
}
