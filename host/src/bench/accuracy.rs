//! `manylights bench --study accuracy`: what each accuracy knob costs in time.
//!
//! For every knob setting the frame is rendered with `clustered-bvh` and compared with a
//! brute-force (`deferred`) reference rendered with the most accurate setting of that knob:
//! PSNR over the 8-bit RGB image, the largest channel difference (in 1/255) and the share of
//! pixels that differ at all, next to the GPU time (frame, compute, assignment, shading) and the
//! lights per cluster. Knobs:
//! 1. **normal encoding** — octahedral 2×8 / 2×12 / 2×16 bits in a 4-byte target, and float32
//!    normals in a 16-byte target; the error is also measured on the normals themselves (angle to
//!    the reference frame's decoded normal per pixel). Reference: brute force with float32
//!    normals (the time column shows what the wider target costs).
//! 2. **falloff / cutoff** — Karis' window at the scene's radii, and the plain inverse square cut
//!    where a light's contribution drops below ε ∈ {1e-2, 1e-3, 1e-4} (`lighting::cut_radius`);
//!    reference: the uncut inverse square (every light reaches every pixel) by brute force.
//! 3. **tile size** — 16 / 32 / 64 px (the exponential depth slices follow from it, so this is
//!    also the slice count); reference: brute force. Lists are conservative, so only time and
//!    lights per cluster change.
//! 4. **culling test** — sphere–AABB, sphere–frustum planes and exact sphere–frustum
//!    (`shaders::cluster_test`), with `clustered-naive` (the test is all its assignment does):
//!    lights per cluster (the false positives) against assignment and shading time; reference:
//!    brute force. All three are conservative, so the image must not change. Spot lights: the
//!    same lights, half of them spots (`lights::spot_cones`), culled by cone and range sphere
//!    (the default) or by the range sphere alone (`EFFECT_CULL_SPHERE_ONLY`), each against
//!    brute force with those spots: the image is identical, the lists and times differ.
//! 5. **order-independent transparency** (scenes with transparent materials only, e.g.
//!    `glass@stack`) — `--oit` exact / k = 8, 4, 2, 1 / weighted blended, with `clustered-bvh`;
//!    reference: `clustered-bvh` with exact OIT, which the image tests hold equal to brute force
//!    within 1/255 — brute force would shade every light for every transparent fragment (10k
//!    lights × tens of layers per pixel at 1080p: minutes per frame). Its time is the
//!    transparent pass (raster) plus the resolve, so its Pareto plot is a separate one.
//! 6. **NURBS tessellation** (scenes with NURBS patches, e.g. `nurbs`) — fixed levels 4, 8, 16,
//!    32, 64 and adaptive tolerances of 2, 1, ½ and ¼ pixel (`--tess-error`), with
//!    `clustered-bvh`; reference: level 64. Besides the image error, the largest distance of the
//!    triangles from the exact surface (`scene::nurbs::tessellation_error`, f64, at each patch's
//!    level as the GPU chose it), timed by the tessellation pass plus the G-buffer (its own
//!    Pareto plot).
//! 7. **MSAA** — `--msaa` 1, 2, 4, 8 (the counts the device has) with `clustered-bvh`; reference:
//!    brute force at 16× the pixels (a 4 × 4 grid per pixel: square, so the frame keeps its
//!    aspect; more than the 8 samples of the finest setting) box-filtered in linear colour
//!    (`render::msaa::box_filter`), timed by the whole GPU frame (its own Pareto plot).
//! 8. **light record** — `--light-record` full (32 B per light) and compact (16 B:
//!    `shaders::compact_light`), with `clustered-bvh`; reference: brute force with full records.
//!    The compact rows' error is the quantisation of position, radius and colour; their time
//!    includes the decode at every light read (and the halved light buffer's bandwidth).
//! 9. **shadows** — cube shadow maps at 32², 128², 512² and 2048² per face (lower where the maps
//!    must degrade to fit), nearest and bilinear, with `clustered-bvh`, 10 % of the lights casting
//!    shadows, at most 64 (`SHADOW_SHARE`, `SHADOW_CASTERS`); reference: `deferred`'s frame shaded on the CPU with exact
//!    ray-cast visibility (`render::cpu_shading`), timed by the whole GPU frame (its own Pareto
//!    plot). Scenes with transparency or NURBS patches, which shadows refuse, get no rows.
use crate::render::shadow_maps::{ShadowFilter, ShadowSettings};
use super::{technique_name, BenchArgs};
use crate::gpu::Gpu;
use crate::render::light_record::LightRecord;
use crate::render::transparent::OitVariant;
use crate::render::{self, Frame, Settings, Technique};
use crate::scene::flatten::{flatten, scene_input};
use crate::scene::lights;
use crate::scene::nurbs::tessellation_error;
use anyhow::{Context as _, Result};
use plotters::prelude::*;
use shaders::layout::*;
use shaders::octahedral::Precision;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A knob of the study (`bench --knobs`), by its number in the module doc.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Knob {
    /// 1. normal encoding.
    Normals,
    /// 2. falloff / cutoff.
    Falloff,
    /// 3. tile size.
    TileSize,
    /// 4. culling test.
    Culling,
    /// 5. order-independent transparency (scenes with transparent materials).
    Oit,
    /// 6. NURBS tessellation (scenes with NURBS patches).
    Tessellation,
    /// 7. MSAA samples per pixel.
    Msaa,
    /// 8. light record (full or compact).
    LightRecord,
    /// 9. shadow-map resolution and filter (a share of the lights casting shadows).
    Shadows,
}

impl Knob {
    pub const ALL: [Knob; 9] = [Knob::Normals, Knob::Falloff, Knob::TileSize, Knob::Culling, Knob::Oit, Knob::Tessellation, Knob::Msaa, Knob::LightRecord, Knob::Shadows];
}

impl std::fmt::Display for Knob {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use clap::ValueEnum as _;
        f.write_str(self.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default().as_str())
    }
}

/// One knob setting, measured.
#[derive(Clone, Debug)]
pub struct AccuracyRow {
    pub scene: String,
    pub knob: &'static str,
    pub setting: String,
    pub psnr_db: f64,
    pub max_abs_255: u32,
    pub pixels_differing_pct: f64,
    /// (max, mean) angle in degrees to the reference normals (normal-encoding knob only).
    pub normal_error_deg: Option<(f64, f64)>,
    pub frame_ms: f64,
    pub compute_ms: f64,
    pub assignment_ms: f64,
    pub shading_ms: f64,
    /// The transparent pass plus its resolve (0 in scenes without transparency).
    pub transparent_ms: f64,
    pub lights_per_cluster: f64,
    /// Largest distance of the tessellated triangles from the exact surface (tessellation knob).
    pub geometric_error: Option<f64>,
    /// The tessellation pass plus the G-buffer (0 in scenes without NURBS patches).
    pub tessellation_ms: f64,
}

/// The tessellation knob's settings: fixed levels, then adaptive tolerances in pixels.
pub const TESS_LEVELS: [u32; 5] = [4, 8, 16, 32, 64];
pub const TESS_TOLERANCES: [f32; 4] = [2.0, 1.0, 0.5, 0.25];

/// The OIT knob's settings, most accurate first.
pub const OIT_SETTINGS: [(OitVariant, &str); 6] = [
    (OitVariant::Exact, "exact"),
    (OitVariant::K8, "k = 8"),
    (OitVariant::K4, "k = 4"),
    (OitVariant::K2, "k = 2"),
    (OitVariant::K1, "k = 1"),
    (OitVariant::Weighted, "weighted blended"),
];

/// Image error of `b` against `a` (RGBA8 words): (PSNR dB, max channel difference, % pixels
/// differing). PSNR is ∞ for identical images.
pub fn image_error(a: &[u32], b: &[u32]) -> (f64, u32, f64) {
    let (mut se, mut max, mut differing) = (0f64, 0u32, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        let mut any = false;
        for s in 0..3 {
            let d = ((x >> (8 * s)) & 255).abs_diff((y >> (8 * s)) & 255);
            se += (d * d) as f64;
            max = max.max(d);
            any |= d > 0;
        }
        differing += usize::from(any);
    }
    let mse = se / (3 * a.len().max(1)) as f64;
    let psnr = if mse == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() };
    (psnr, max, 100.0 * differing as f64 / a.len().max(1) as f64)
}

/// (max, mean) angle in degrees between the decoded normals of two frames, over pixels with
/// geometry (reversed-Z depth > 0) in both.
pub fn normal_error(reference: &Frame, f: &Frame) -> Option<(f64, f64)> {
    let (ra, fa) = (reference.readback.as_ref()?, f.readback.as_ref()?);
    let (mut max, mut sum, mut n) = (0f64, 0f64, 0usize);
    for i in 0..ra.normals.len().min(fa.normals.len()) {
        if f32::from_bits(ra.depth[i]) <= 0.0 || f32::from_bits(fa.depth[i]) <= 0.0 {
            continue;
        }
        let a = glam::Vec3::from_array(ra.normals[i]).as_dvec3();
        let b = glam::Vec3::from_array(fa.normals[i]).as_dvec3();
        // atan2(|a×b|, a·b): exact for equal vectors and accurate at small angles (acos is not).
        let angle = a.cross(b).length().atan2(a.dot(b)).to_degrees();
        max = max.max(angle);
        sum += angle;
        n += 1;
    }
    (n > 0).then(|| (max, sum / n as f64))
}

fn settings(a: &BenchArgs, technique: Technique, tile_size: u32, precision: Precision) -> Settings {
    Settings { tile_size, normal_precision: precision, ..super::settings_of(a, technique) }
}

fn pass(f: &Frame, name: &str) -> f64 {
    // `+ 0.0`: an empty float sum is −0.0, which the tables would print as "-0.000".
    f.timings.iter().filter(|t| t.name == name).map(|t| t.ms).sum::<f64>() + 0.0
}

/// Frame and compute ms as in the sweep: the whole GPU frame over both queues, and the frame
/// without its raster passes.
fn frame_ms(f: &Frame) -> (f64, f64) {
    (f.gpu_frame.ms, f.gpu_frame.non_raster_ms)
}

/// Runs the study on each scene of `a.scenes` at the light count closest to 10k in `a.lights`.
pub fn study(gpu: &Gpu, a: &BenchArgs) -> Result<Vec<AccuracyRow>> {
    let n = *a.lights.iter().min_by_key(|&&n| (n as i64 - 10_000).abs()).context("--lights is empty")?;
    let mut rows = Vec::new();
    let bar = indicatif::ProgressBar::new((a.scenes.len() * 36) as u64);
    for name in &a.scenes {
        let scene = super::load_scene(name, a)?;
        let base = lights::uniform(&scene, n, a.seed).context("generating lights")?;
        let flat = flatten(&scene, Precision::Oct16)?;
        let run = |ls: &[shaders::layout::PointLight], effects: u32, s: &Settings| -> Result<Frame> {
            let flat_p = if s.normal_precision == Precision::Oct16 { None } else { Some(flatten(&scene, s.normal_precision)?) };
            let mut input = scene_input(&scene, flat_p.as_ref().unwrap_or(&flat), ls);
            input.effects |= effects;
            bar.inc(1);
            render::render(gpu, &input, s)
        };
        let mut measure = |knob: &'static str, setting: String, reference: &Frame, f: &Frame, normals: Option<(f64, f64)>| {
            let (psnr_db, max_abs_255, pixels_differing_pct) = image_error(&reference.pixels, &f.pixels);
            let (frame, compute) = frame_ms(f);
            let lists = f.readback.as_ref().map(render::reference::list_stats).unwrap_or_default();
            rows.push(AccuracyRow {
                scene: name.clone(),
                knob,
                setting,
                psnr_db,
                max_abs_255,
                pixels_differing_pct,
                normal_error_deg: normals,
                frame_ms: frame,
                compute_ms: compute,
                assignment_ms: pass(f, "assignment") + pass(f, "morton keys") + pass(f, "light sort") + pass(f, "bvh build"),
                shading_ms: pass(f, "shading"),
                transparent_ms: pass(f, "transparent") + pass(f, "oit resolve"),
                lights_per_cluster: lists.mean_per_cluster,
                geometric_error: None,
                tessellation_ms: pass(f, "tessellation") + pass(f, "gbuffer"),
            });
        };
        let mut tess_errors = Vec::new();
        let wants = |k: Knob| a.knobs.contains(&k);
        // 1: reference = brute force, float32 normals, window falloff.
        if wants(Knob::Normals) {
            let exact = run(&base, 0, &settings(a, Technique::Deferred, a.tile_size, Precision::F32))?;
            for (p, label) in [(Precision::Oct8, "oct 2×8"), (Precision::Oct12, "oct 2×12"), (Precision::Oct16, "oct 2×16"), (Precision::F32, "float32")] {
                let f = run(&base, 0, &settings(a, Technique::ClusteredBvh, a.tile_size, p))?;
                measure("normal encoding", label.into(), &exact, &f, normal_error(&exact, &f));
            }
        }
        // 3 and 4: reference = brute force, 2×16-bit normals (as the rows), window falloff.
        if wants(Knob::Culling) || wants(Knob::TileSize) {
            let reference = run(&base, 0, &settings(a, Technique::Deferred, a.tile_size, Precision::Oct16))?;
            let culling: &[(u32, &str)] = if wants(Knob::Culling) { &[(0, "sphere–AABB"), (EFFECT_CULL_PLANES, "sphere–frustum planes"), (EFFECT_CULL_EXACT, "exact sphere–frustum")] } else { &[] };
            for &(effect, label) in culling {
                let f = run(&base, effect, &settings(a, Technique::ClusteredNaive, a.tile_size, Precision::Oct16))?;
                measure("culling test", format!("{label} (clustered-naive)"), &reference, &f, None);
            }
            if wants(Knob::Culling) {
                let cones = lights::spot_cones(base.len(), 0.5, a.seed).context("generating spot cones")?;
                let run_spots = |effects: u32, s: &Settings| -> Result<Frame> {
                    let mut input = scene_input(&scene, &flat, &base);
                    input.spots = &cones;
                    input.effects |= effects;
                    bar.inc(1);
                    render::render(gpu, &input, s)
                };
                let reference = run_spots(0, &settings(a, Technique::Deferred, a.tile_size, Precision::Oct16))?;
                let spot_tests = [(0, "spots: cone + sphere–AABB"), (shaders::light_types::EFFECT_CULL_SPHERE_ONLY, "spots: sphere–AABB only")];
                for (effect, label) in spot_tests {
                    let f = run_spots(effect, &settings(a, Technique::ClusteredNaive, a.tile_size, Precision::Oct16))?;
                    measure("culling test", format!("{label} (clustered-naive)"), &reference, &f, None);
                }
            }
            let tiles: &[u32] = if wants(Knob::TileSize) { &[16, 32, 64] } else { &[] };
            for &tile in tiles {
                let f = run(&base, 0, &settings(a, Technique::ClusteredBvh, tile, Precision::Oct16))?;
                measure("tile size", format!("{tile} px ({} slices)", f.grid.num_slices), &reference, &f, None);
            }
        }
        // 2: reference = brute force with the uncut inverse square.
        if wants(Knob::Falloff) {
            let uncut: Vec<_> = base.iter().map(|l| PointLight { radius: 1e30, ..*l }).collect();
            let s = settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16);
            let reference = run(&uncut, EFFECT_INVERSE_SQUARE_CUT, &settings(a, Technique::Deferred, a.tile_size, Precision::Oct16))?;
            let f = run(&base, 0, &s)?;
            measure("falloff", "Karis window (scene radii)".into(), &reference, &f, None);
            for eps in [1e-2f32, 1e-3, 1e-4] {
                let cut: Vec<_> = base
                    .iter()
                    .map(|l| PointLight { radius: shaders::lighting::cut_radius(l.intensity * l.colour.iter().fold(0f32, |m, &c| m.max(c)), eps), ..*l })
                    .collect();
                let f = run(&cut, EFFECT_INVERSE_SQUARE_CUT, &s)?;
                measure("falloff", format!("inverse square cut at ε = {eps:e}"), &reference, &f, None);
            }
        }
        // 5: reference = the exact setting itself (see the module doc).
        if wants(Knob::Oit) && scene.has_transparency() {
            let oit = |variant| Settings { oit: variant, ..settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16) };
            let frames: Vec<Frame> = OIT_SETTINGS.iter().map(|&(variant, _)| run(&base, 0, &oit(variant))).collect::<Result<_>>()?;
            for (f, (_, label)) in frames.iter().zip(OIT_SETTINGS) {
                measure(OIT_KNOB, label.into(), &frames[0], f, None);
            }
        }
        // 6: reference = the finest fixed level.
        if wants(Knob::Tessellation) && !scene.nurbs.is_empty() {
            let s = settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16);
            let tess = |level: Option<u32>, tolerance: Option<f32>| -> Result<Frame> {
                let mut at = scene.clone();
                if let Some(l) = level {
                    at.set_tess_level(l);
                }
                let mut input = scene_input(&at, &flat, &base);
                input.nurbs_tolerance = tolerance;
                bar.inc(1);
                render::render(gpu, &input, &s)
            };
            let finest = *TESS_LEVELS.last().unwrap_or(&64);
            let reference = tess(Some(finest), None)?;
            let error_at = |f: &Frame| scene.nurbs.iter().zip(&f.tess_levels).map(|(p, &l)| tessellation_error(&p.patch, l)).fold(0.0, f64::max);
            for level in TESS_LEVELS {
                let f = tess(Some(level), None)?;
                tess_errors.push(error_at(&f));
                measure(TESS_KNOB, format!("level {level}"), &reference, &f, None);
            }
            for tolerance in TESS_TOLERANCES {
                let f = tess(None, Some(tolerance))?;
                tess_errors.push(error_at(&f));
                measure(TESS_KNOB, format!("adaptive, {tolerance} px"), &reference, &f, None);
            }
        }
        // 7: reference = brute force at 16× the pixels, box-filtered.
        if wants(Knob::Msaa) {
            let (w, h) = (a.width, a.height);
            let (cols, rows_per_pixel) = MSAA_REFERENCE_GRID;
            let mut reference = run(&base, 0, &Settings { width: cols * w, height: rows_per_pixel * h, ..settings(a, Technique::Deferred, a.tile_size, Precision::Oct16) })?;
            reference.pixels = render::msaa::box_filter(&reference.pixels, w, h, MSAA_REFERENCE_GRID);
            let here = shaders::msaa::SAMPLE_COUNTS.into_iter().filter(|&n| gpu.ctx.info.msaa_sample_counts & n != 0);
            for samples in here {
                let f = run(&base, 0, &Settings { msaa: samples, ..settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16) })?;
                let edges = 100.0 * f.edge_pixels as f64 / (w as f64 * h as f64);
                measure(MSAA_KNOB, format!("{samples} × ({edges:.1} % edge pixels)"), &reference, &f, None);
            }
        }
        // 8: reference = brute force with full records.
        if wants(Knob::LightRecord) {
            let reference = run(&base, 0, &settings(a, Technique::Deferred, a.tile_size, Precision::Oct16))?;
            for record in [LightRecord::Full, LightRecord::Compact] {
                let f = run(&base, 0, &Settings { light_record: record, ..settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16) })?;
                measure(LIGHT_RECORD_KNOB, format!("{} ({} B per light)", record.name(), record.bytes_per_light()), &reference, &f, None);
            }
        }
        // 9: reference = deferred's frame shaded on the CPU with ray-cast shadows
        // (`render::cpu_shading`), `SHADOW_SHARE` of the lights casting.
        if wants(Knob::Shadows) && !scene.has_transparency() && scene.nurbs.is_empty() {
            let share = SHADOW_SHARE.min(SHADOW_CASTERS as f32 / base.len() as f32);
            let casters = lights::shadow_casters(base.len(), share)?;
            let run_shadowed = |shadowed: bool, s: &Settings| -> Result<Frame> {
                let mut input = scene_input(&scene, &flat, &base);
                input.shadows = if shadowed { &casters } else { &[] };
                bar.inc(1);
                render::render(gpu, &input, s)
            };
            let plain = Settings { read_back: true, ..settings(a, Technique::Deferred, a.tile_size, Precision::Oct16) };
            let mut reference = run_shadowed(false, &plain)?;
            let view = scene_input(&scene, &flat, &base).view;
            let mut shadows = render::cpu_shading::Shadows::of_scene(&scene, &view);
            shadows.casters = &casters;
            reference.pixels = render::cpu_shading::shade(&scene, &reference, &plain, Some(&shadows))?;
            for (resolution, filter) in SHADOW_SETTINGS {
                let shadow = ShadowSettings { resolution, filter, ..Default::default() };
                let f = run_shadowed(true, &Settings { shadow, ..settings(a, Technique::ClusteredBvh, a.tile_size, Precision::Oct16) })?;
                // The largest side; each face takes what its receivers ask up to it (`shadow_atlas`).
                measure(SHADOW_KNOB, format!("≤ {resolution}² per face, {}", format!("{filter:?}").to_lowercase()), &reference, &f, None);
            }
        }
        let tess_rows = rows.iter_mut().filter(|r| r.scene == *name && r.knob == TESS_KNOB);
        for (r, e) in tess_rows.zip(tess_errors) {
            r.geometric_error = Some(e);
        }
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// `accuracy.csv`.
pub fn write_csv(rows: &[AccuracyRow], w: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(w, "scene,knob,setting,psnr_db,max_abs_255,pixels_differing_pct,normal_max_deg,normal_mean_deg,frame_ms,compute_ms,assignment_ms,shading_ms,transparent_ms,lights_per_cluster,geometric_error,tessellation_gbuffer_ms")?;
    for r in rows {
        let (nmax, nmean) = r.normal_error_deg.map(|(a, b)| (format!("{a:.6}"), format!("{b:.6}"))).unwrap_or_default();
        writeln!(
            w,
            "{},{},\"{}\",{:.3},{},{:.4},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.3},{},{:.6}",
            r.scene,
            r.knob,
            r.setting,
            r.psnr_db,
            r.max_abs_255,
            r.pixels_differing_pct,
            nmax,
            nmean,
            r.frame_ms,
            r.compute_ms,
            r.assignment_ms,
            r.shading_ms,
            r.transparent_ms,
            r.lights_per_cluster,
            r.geometric_error.map(|e| format!("{e:.6e}")).unwrap_or_default(),
            r.tessellation_ms
        )?;
    }
    Ok(())
}

/// The markdown section (table per scene) and the Pareto plots' names.
pub fn markdown(rows: &[AccuracyRow], device: &str, command: &str, plots: &[PathBuf]) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# manylights accuracy vs time\n\n**Device:** {device}\n\nGenerated by:\n\n```\n{command}\n```\n");
    let _ = writeln!(
        md,
        "Each setting renders with `{}` and is compared with a brute-force reference at the knob's most accurate \
         setting (normal encoding: float32 normals, a 16-byte target; culling test, tile size: 2×16-bit normals and the \
         window falloff; falloff: the uncut inverse square). PSNR over 8-bit RGB (∞ = identical), max |Δ| in 1/255, \
         share of pixels with any channel differing. The culling tests run with `clustered-naive`, whose assignment is nothing but the test.\n",
        technique_name(Technique::ClusteredBvh)
    );
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let _ = writeln!(md, "## {scene}\n");
        let _ = writeln!(
            md,
            "| knob | setting | PSNR dB | max Δ/255 | pixels differing | normal error max / mean ° | geometric error | frame ms | compute ms | assignment ms | shading ms | transparent + resolve ms | tessellation + G-buffer ms | lights/cluster |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in rows.iter().filter(|r| r.scene == scene) {
            let ne = r.normal_error_deg.map(|(a, b)| format!("{a:.4} / {b:.4}")).unwrap_or_else(|| "–".into());
            let ge = r.geometric_error.map(|e| format!("{e:.3e}")).unwrap_or_else(|| "–".into());
            let _ = writeln!(
                md,
                "| {} | {} | {:.2} | {} | {:.3} % | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1} |",
                r.knob,
                r.setting,
                r.psnr_db,
                r.max_abs_255,
                r.pixels_differing_pct,
                ne,
                ge,
                r.frame_ms,
                r.compute_ms,
                r.assignment_ms,
                r.shading_ms,
                r.transparent_ms,
                r.tessellation_ms,
                r.lights_per_cluster
            );
        }
        let _ = writeln!(md);
    }
    for p in plots {
        let _ = writeln!(md, "![{0}]({0})\n", p.display());
    }
    md
}

/// The knobs timed by compute ms (one plot per scene), and the OIT knob, timed by its passes.
const COMPUTE_KNOBS: [&str; 5] = ["normal encoding", "culling test", "tile size", "falloff", LIGHT_RECORD_KNOB];
const LIGHT_RECORD_KNOB: &str = "light record";
const OIT_KNOB: &str = "transparency (OIT)";
const TESS_KNOB: &str = "tessellation";
const MSAA_KNOB: &str = "MSAA";
const SHADOW_KNOB: &str = "shadows";
/// The shadows knob's share of shadow-casting lights (at most [`SHADOW_CASTERS`] of them), and
/// its settings (coarsest first).
pub const SHADOW_SHARE: f32 = 0.1;
pub const SHADOW_CASTERS: usize = 64;
pub const SHADOW_SETTINGS: [(u32, ShadowFilter); 8] = [
    (32, ShadowFilter::Nearest),
    (32, ShadowFilter::Bilinear),
    (128, ShadowFilter::Nearest),
    (128, ShadowFilter::Bilinear),
    (512, ShadowFilter::Nearest),
    (512, ShadowFilter::Bilinear),
    (2048, ShadowFilter::Nearest),
    (2048, ShadowFilter::Bilinear),
];
/// The MSAA knob's reference: this many columns × rows of pixels per pixel (16× supersampling;
/// square, so the frame keeps its aspect).
pub const MSAA_REFERENCE_GRID: (u32, u32) = (4, 4);

/// Error (RMSE in 8-bit units, from the PSNR) vs time, one point per setting, the Pareto front
/// joined: per scene one plot of the compute-time knobs against compute ms and, where the scene
/// has transparency, one of the OIT knob against the transparent pass + resolve ms.
pub fn pareto_plots(rows: &[AccuracyRow], dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let slug = |s: &str| s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect::<String>();
    for scene in scenes {
        let of = |knobs: &[&str]| rows.iter().filter(|r| r.scene == scene && knobs.contains(&r.knob)).collect::<Vec<_>>();
        let compute = of(&COMPUTE_KNOBS);
        if !compute.is_empty() {
            let name = PathBuf::from(format!("pareto-{}.svg", slug(scene)));
            let title = format!("{scene}: image error vs compute time");
            plot(&compute, &COMPUTE_KNOBS, |r| r.compute_ms, "compute ms (median)", &title, &dir.join(&name))?;
            files.push(name);
        }
        let oit = of(&[OIT_KNOB]);
        if !oit.is_empty() {
            let name = PathBuf::from(format!("pareto-oit-{}.svg", slug(scene)));
            let title = format!("{scene}: OIT image error vs transparent pass + resolve time");
            plot(&oit, &[OIT_KNOB], |r| r.transparent_ms, "transparent pass + resolve ms (median)", &title, &dir.join(&name))?;
            files.push(name);
        }
        let tess = of(&[TESS_KNOB]);
        if !tess.is_empty() {
            let name = PathBuf::from(format!("pareto-tessellation-{}.svg", slug(scene)));
            let title = format!("{scene}: NURBS tessellation image error vs tessellation + G-buffer time");
            plot(&tess, &[TESS_KNOB], |r| r.tessellation_ms, "tessellation pass + G-buffer ms (median)", &title, &dir.join(&name))?;
            files.push(name);
        }
        let shadows = of(&[SHADOW_KNOB]);
        if !shadows.is_empty() {
            let name = PathBuf::from(format!("pareto-shadows-{}.svg", slug(scene)));
            let title = format!("{scene}: shadow-map image error (against ray-cast shadows) vs frame time");
            plot(&shadows, &[SHADOW_KNOB], |r| r.frame_ms, "GPU frame ms (median)", &title, &dir.join(&name))?;
            files.push(name);
        }
        let msaa = of(&[MSAA_KNOB]);
        if !msaa.is_empty() {
            let name = PathBuf::from(format!("pareto-msaa-{}.svg", slug(scene)));
            let title = format!("{scene}: MSAA image error (against 16× supersampling) vs frame time");
            plot(&msaa, &[MSAA_KNOB], |r| r.frame_ms, "GPU frame ms (median)", &title, &dir.join(&name))?;
            files.push(name);
        }
    }
    Ok(files)
}

fn plot(rows: &[&AccuracyRow], knobs: &[&str], time: impl Fn(&AccuracyRow) -> f64, x_desc: &str, title: &str, path: &Path) -> Result<()> {
    let pts: Vec<(&AccuracyRow, f64, f64)> = rows.iter().map(|r| (*r, time(r).max(1e-6), (255.0 * 10f64.powf(-r.psnr_db / 20.0)).max(1e-3))).collect();
    let root = SVGBackend::new(path, (960, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let (x0, x1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (y0, y1) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.2), b.max(p.2)));
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x0 * 0.8..x1 * 1.25).log_scale(), (y0 * 0.5..y1 * 2.0).log_scale())?;
    chart.configure_mesh().x_desc(x_desc).y_desc("RMSE (8-bit units; 0 drawn at 1e-3)").draw()?;
    let mut front: Vec<(f64, f64)> = pts.iter().filter(|p| !pts.iter().any(|q| q.1 <= p.1 && q.2 <= p.2 && (q.1 < p.1 || q.2 < p.2))).map(|p| (p.1, p.2)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart.draw_series(LineSeries::new(front, BLACK.stroke_width(1)))?.label("Pareto front").legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    for (i, knob) in knobs.iter().enumerate() {
        let colour = Palette99::pick(i).mix(1.0);
        let mine: Vec<_> = pts.iter().filter(|p| p.0.knob == *knob).collect();
        chart
            .draw_series(mine.iter().map(|p| Circle::new((p.1, p.2), 5, colour.filled())))?
            .label(*knob)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        chart.draw_series(mine.iter().map(|p| Text::new(p.0.setting.clone(), (p.1, p.2), ("sans-serif", 12))))?;
    }
    chart.configure_series_labels().position(SeriesLabelPosition::UpperRight).background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(())
}
