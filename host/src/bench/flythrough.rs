//! `manylights bench --camera-path FILE`: each configuration also flies a camera path, one frame
//! per camera, and reports the frame time's median, 99th percentile and maximum over the path
//! (`flythrough.csv`, a table in `results.md`), as interactive demos are measured: the frames a
//! user sees, not one view's best case.
//!
//! The path file holds one camera bookmark per line, in the format of `render --camera` and the
//! viewer's `C` key (`x,y,z,yaw,pitch[,fov]`, degrees); blank lines and `#` comments are
//! skipped. The configuration's renderer is created once at the first camera; one warm-up frame,
//! then every camera of the path in order ([`crate::render::Renderer::set_view`]: vertices and
//! lights move relative to the new eye, NURBS patches are tessellated anew).
use super::{settings_of, spots, technique_name, BenchArgs, Series, SpotCulling};
use crate::bad_input::bad_input;
use crate::gpu::Gpu;
use crate::render::{Renderer, Technique};
use crate::scene::bookmark::Bookmark;
use crate::scene::flatten::flatten;
use crate::scene::Scene;
use anyhow::{bail, Context as _, Result};
use shaders::octahedral::Precision;
use std::path::Path;

/// One configuration's fly-through.
#[derive(Clone, Debug, PartialEq)]
pub struct FlyRow {
    pub scene: String,
    pub technique: Technique,
    pub lights: usize,
    /// Share of the lights that are spots, and how they were culled (`--spot-fraction`,
    /// `--spot-culling`).
    pub spot_fraction: f32,
    pub spot_culling: SpotCulling,
    /// Frames timed: the path's cameras.
    pub frames: usize,
    pub median_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

/// The cameras of a path file (module docs); a malformed line is bad input naming the file and
/// line.
pub fn load_path(path: &Path) -> Result<Vec<Bookmark>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("--camera-path {}: cannot read it", path.display())).map_err(bad_input)?;
    let mut cameras = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let b = Bookmark::parse(line).with_context(|| format!("{}:{}", path.display(), i + 1)).map_err(bad_input)?;
        cameras.push(b);
    }
    if cameras.is_empty() {
        return Err(bad_input(anyhow::anyhow!("{}: no camera in the path (one `x,y,z,yaw,pitch[,fov]` per line)", path.display())));
    }
    Ok(cameras)
}

/// The value at quantile `q` of sorted `v` (nearest rank: the smallest value with at least `q`
/// of the values at or below it).
pub fn nearest_rank(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// Flies `cameras` through `scene` with `n` lights and the technique of `series`, which culls
/// their spots its way (module docs).
pub fn fly(gpu: &Gpu, scene: &Scene, name: &str, series: Series, n: usize, a: &BenchArgs, cameras: &[Bookmark]) -> Result<FlyRow> {
    let Series { technique: t, culling } = series;
    let (l, cones) = spots::generate(scene, n, a)?;
    let flat = flatten(scene, Precision::Oct16)?;
    let s = crate::render::Settings { read_back: false, frames: 0, ..settings_of(a, t) };
    let at = |b: &Bookmark| {
        let mut sc = scene.clone();
        sc.camera = b.apply(&scene.camera);
        sc
    };
    let first = at(&cameras[0]);
    let mut r = Renderer::new(gpu, &spots::input(&first, &flat, &l, &cones, culling), &s)?;
    r.frame(gpu)?;
    let mut ms = Vec::with_capacity(cameras.len());
    for b in cameras {
        let view = spots::input(&at(b), &flat, &l, &cones, culling).view;
        r.set_view(gpu, view, &flat.positions, &l)?;
        match r.frame(gpu)?.sample {
            Some(sample) => ms.push(sample.frame_ms),
            None => bail!("the device reports no GPU timestamps: nothing to measure"),
        }
    }
    ms.sort_by(f64::total_cmp);
    Ok(FlyRow {
        scene: name.to_string(),
        technique: t,
        lights: n,
        spot_fraction: a.spot_fraction,
        spot_culling: culling,
        frames: ms.len(),
        median_ms: nearest_rank(&ms, 0.5),
        p99_ms: nearest_rank(&ms, 0.99),
        max_ms: ms.last().copied().unwrap_or(0.0),
    })
}

/// `flythrough.csv`.
pub fn write_csv(rows: &[FlyRow], w: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(w, "scene,technique,lights,frames,median_ms,p99_ms,max_ms,spot_fraction,spot_culling")?;
    for r in rows {
        let (t, culling) = (technique_name(r.technique), r.spot_culling.name());
        writeln!(w, "{},{t},{},{},{:.6},{:.6},{:.6},{},{culling}", r.scene, r.lights, r.frames, r.median_ms, r.p99_ms, r.max_ms, r.spot_fraction)?;
    }
    Ok(())
}

/// The fly-through table of `results.md` (empty without rows).
pub fn markdown(rows: &[FlyRow]) -> String {
    use std::fmt::Write as _;
    let mut md = String::new();
    if rows.is_empty() {
        return md;
    }
    let _ = writeln!(md, "## Fly-through (`--camera-path`)\n\nWhole GPU frame over the path, one frame per camera.\n");
    let _ = writeln!(md, "| scene | technique | lights | frames | median ms | 99th percentile ms | max ms |\n|---|---|---|---|---|---|---|");
    for r in rows {
        let t = match r.spot_fraction > 0.0 {
            true => format!("{} ({}, {} % spots)", technique_name(r.technique), r.spot_culling.name(), spots::percent(r.spot_fraction)),
            false => technique_name(r.technique),
        };
        let _ = writeln!(md, "| {} | {t} | {} | {} | {:.3} | {:.3} | {:.3} |", r.scene, r.lights, r.frames, r.median_ms, r.p99_ms, r.max_ms);
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_quantiles() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!((nearest_rank(&v, 0.5), nearest_rank(&v, 0.99), nearest_rank(&v, 1.0)), (50.0, 99.0, 100.0));
        assert_eq!((nearest_rank(&[3.0], 0.99), nearest_rank(&[], 0.5)), (3.0, 0.0));
        assert_eq!(nearest_rank(&[1.0, 2.0, 3.0], 0.99), 3.0, "three frames: the 99th percentile is the slowest");
    }

    #[test]
    fn path_files_skip_comments_and_name_bad_lines() {
        let dir = std::env::temp_dir().join(format!("manylights-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.txt");
        std::fs::write(&good, "# a path\n0,1.6,8,0,0\n\n1,1.6,7,10,-5,60  # turning\n").unwrap();
        let cams = load_path(&good).unwrap();
        assert_eq!(cams.len(), 2);
        assert_eq!(cams[1].fov_y_degrees, Some(60.0));
        let bad = dir.join("bad.txt");
        std::fs::write(&bad, "0,1.6,8,0,0\n0,1.6\n").unwrap();
        let e = format!("{:#}", load_path(&bad).unwrap_err());
        assert!(e.contains("bad.txt:2") && !e.contains('\n'), "{e}");
        let empty = dir.join("empty.txt");
        std::fs::write(&empty, "# nothing\n").unwrap();
        assert!(format!("{:#}", load_path(&empty).unwrap_err()).contains("no camera"));
        assert!(load_path(&dir.join("missing.txt")).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
