//! SVG plots of a sweep (plotters' SVG backend: no system fonts needed, viewable on GitHub).
//! * `frame-vs-lights-<scene>.svg` / `compute-vs-lights-<scene>.svg` — ms vs lights, log–log,
//!   one line per technique (Karas' Fig. 8); with spot lights one per technique and spot
//!   culling (`clustered-bvh (cone)`, `clustered-bvh (sphere)`: `--spot-culling both` draws
//!   both, never merged);
//! * `stages-<scene>.svg` — per-stage ms stacked, one bar per clustered technique (and spot
//!   culling) and light count (Karas' Fig. 7).
use super::{technique_name, with_spots, Results, Row, Series};
use anyhow::Result;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

const SIZE: (u32, u32) = (960, 600);

/// File-name-safe form of a scene name.
fn slug(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '-' }).collect()
}

fn scenes(r: &Results) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for row in &r.rows {
        if !v.contains(&row.scene) {
            v.push(row.scene.clone());
        }
    }
    v
}

/// Draws every plot into `dir`; returns the files (relative names).
pub fn draw_all(r: &Results, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for scene in scenes(r) {
        for stage in ["frame", "compute"] {
            let name = PathBuf::from(format!("{stage}-vs-lights-{}.svg", slug(&scene)));
            if lines(r, &scene, stage, &dir.join(&name))? {
                files.push(name);
            }
        }
        let name = PathBuf::from(format!("stages-{}.svg", slug(&scene)));
        if stacked(r, &scene, &dir.join(&name))? {
            files.push(name);
        }
    }
    Ok(files)
}

/// ms of `stage` vs lights, one line per technique; false when there is nothing to draw.
fn lines(r: &Results, scene: &str, stage: &str, path: &Path) -> Result<bool> {
    let rows: Vec<&Row> = r.rows.iter().filter(|x| x.scene == scene && x.stage == stage && x.median_ms > 0.0).collect();
    if rows.is_empty() {
        return Ok(false);
    }
    let (x0, x1) = rows.iter().fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x.lights as f64), b.max(x.lights as f64)));
    let (y0, y1) = rows.iter().fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x.median_ms), b.max(x.median_ms)));
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let res = format!("{}×{}", rows[0].width, rows[0].height);
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{scene} {res}: {stage} GPU ms vs lights"), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x0 * 0.8..x1 * 1.25).log_scale(), (y0 * 0.7..y1 * 1.4).log_scale())?;
    chart.configure_mesh().x_desc("lights").y_desc(format!("{stage} ms (median)")).draw()?;
    let series = super::present_series(&rows);
    let spots = with_spots(&rows);
    for (i, t) in series.iter().enumerate() {
        let colour = Palette99::pick(i).mix(1.0);
        let mut pts: Vec<(f64, f64)> = rows.iter().filter(|x| x.series() == *t).map(|x| (x.lights as f64, x.median_ms)).collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
            .label(t.name(spots))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))?;
    }
    chart.configure_series_labels().position(SeriesLabelPosition::UpperLeft).background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(true)
}

/// Stacked per-stage bars of the clustered techniques; false when there are none.
fn stacked(r: &Results, scene: &str, path: &Path) -> Result<bool> {
    let clustered = |x: &&Row| x.scene == scene && technique_name(x.technique).starts_with("clustered");
    let rows: Vec<&Row> = r.rows.iter().filter(clustered).collect();
    // Bars: (technique and spot culling, lights) in sweep order; stages in first-seen order.
    let mut bars: Vec<(Series, usize)> = Vec::new();
    let mut stages: Vec<String> = Vec::new();
    for x in &rows {
        if x.stage == "frame" || x.stage == "compute" {
            continue;
        }
        if !bars.contains(&(x.series(), x.lights)) {
            bars.push((x.series(), x.lights));
        }
        if !stages.contains(&x.stage) {
            stages.push(x.stage.clone());
        }
    }
    if bars.is_empty() {
        return Ok(false);
    }
    bars.sort_by_key(|b| (technique_name(b.0.technique), b.1, b.0.culling.name()));
    let stage_ms = |b: &(Series, usize), s: &str| rows.iter().find(|x| x.series() == b.0 && x.lights == b.1 && x.stage == s).map(|x| x.median_ms).unwrap_or(0.0);
    let spots = with_spots(&rows);
    let top = bars.iter().map(|b| stages.iter().map(|s| stage_ms(b, s)).sum::<f64>()).fold(0.0, f64::max);
    let root = SVGBackend::new(path, (SIZE.0.max(60 * bars.len() as u32 + 200), SIZE.1)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{scene}: GPU ms per stage (median), clustered techniques"), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(90)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..bars.len() as f64, 0f64..top * 1.15)?;
    let labels: Vec<String> = bars
        .iter()
        .map(|b| {
            let culling = if spots { format!(" {}", b.0.culling.name()) } else { String::new() };
            format!("{} {}{culling}", technique_name(b.0.technique).trim_start_matches("clustered-"), short(b.1))
        })
        .collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(bars.len() * 2 + 1)
        .x_label_formatter(&|x| {
            let i = x.floor() as usize;
            if (x - i as f64 - 0.5).abs() < 0.01 { labels.get(i).cloned().unwrap_or_default() } else { String::new() }
        })
        .y_desc("ms")
        .draw()?;
    for (si, s) in stages.iter().enumerate() {
        let colour = Palette99::pick(si).mix(0.9);
        let rects: Vec<Rectangle<(f64, f64)>> = bars
            .iter()
            .enumerate()
            .map(|(bi, b)| {
                let below: f64 = stages[..si].iter().map(|p| stage_ms(b, p)).sum();
                Rectangle::new([(bi as f64 + 0.15, below), (bi as f64 + 0.85, below + stage_ms(b, s))], colour.filled())
            })
            .collect();
        chart
            .draw_series(rects)?
            .label(s.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.filled()));
    }
    chart.configure_series_labels().position(SeriesLabelPosition::UpperLeft).background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(true)
}

/// 1000 → "1k", 1000000 → "1M".
pub fn short(n: usize) -> String {
    match n {
        n if n >= 1_000_000 && n % 1_000_000 == 0 => format!("{}M", n / 1_000_000),
        n if n >= 1_000 && n % 1_000 == 0 => format!("{}k", n / 1_000),
        n => n.to_string(),
    }
}
