//! Spot lights in the sweep: `--spot-fraction F` makes that share of every sweep point's
//! generated lights spots (`lights::spot_cones`, seeded with `--seed` as `render
//! --spot-fraction`), and `--spot-culling cone|sphere|both` says how the techniques cull them:
//! by cone after the range sphere (every technique's default), by the range sphere alone
//! (`EFFECT_CULL_SPHERE_ONLY`: the image is the same, the lists longer), or each technique both
//! ways. Every row carries the fraction and the culling; the plots and tables keep cone and
//! sphere rows apart ([`super::Series`]), and `results.md` gets a table of lights per list and
//! light-list / shading ms per culling ([`markdown`]).
use super::{technique_name, BenchArgs, Row, Technique};
use crate::bail_input;
use crate::render::SceneInput;
use crate::scene::flatten::{scene_input, Flattened};
use crate::scene::{lights, Scene, Spot};
use anyhow::{Context as _, Result};
use clap::ValueEnum;
use shaders::layout::PointLight;
use std::fmt::Write as _;

/// How the techniques cull spot lights (`bench --spot-culling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum SpotCulling {
    /// Cone after the range sphere (the renderer's default).
    #[default]
    Cone,
    /// The range sphere alone (`EFFECT_CULL_SPHERE_ONLY`).
    Sphere,
    /// Each technique measured both ways, cone first.
    Both,
}

impl SpotCulling {
    /// The ways each configuration is measured.
    pub fn modes(self) -> &'static [SpotCulling] {
        match self {
            SpotCulling::Cone => &[SpotCulling::Cone],
            SpotCulling::Sphere => &[SpotCulling::Sphere],
            SpotCulling::Both => &[SpotCulling::Cone, SpotCulling::Sphere],
        }
    }

    /// The command-line name, also the CSV's `spot_culling`.
    pub fn name(self) -> &'static str {
        match self {
            SpotCulling::Cone => "cone",
            SpotCulling::Sphere => "sphere",
            SpotCulling::Both => "both",
        }
    }

    /// The effect bits of a measured way.
    pub fn effects(self) -> u32 {
        match self {
            SpotCulling::Sphere => shaders::light_types::EFFECT_CULL_SPHERE_ONLY,
            _ => 0,
        }
    }
}

impl Row {
    /// The plot line and table column the row belongs to.
    pub fn series(&self) -> Series {
        Series { technique: self.technique, culling: self.spot_culling }
    }
}

/// A line of the plots and a column of the tables: a technique, and how it culled spot lights
/// (the rows of `--spot-culling both` are never merged).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Series {
    pub technique: Technique,
    pub culling: SpotCulling,
}

impl Series {
    /// The technique's name, with the spot culling where the rows have spot lights
    /// (`clustered-bvh (sphere)`).
    pub fn name(&self, with_spots: bool) -> String {
        match with_spots {
            true => format!("{} ({})", technique_name(self.technique), self.culling.name()),
            false => technique_name(self.technique),
        }
    }
}

/// Series that have rows: techniques in the enum's order, each with cone culling first.
pub fn present_series(rows: &[&Row]) -> Vec<Series> {
    Technique::value_variants()
        .iter()
        .flat_map(|&technique| [SpotCulling::Cone, SpotCulling::Sphere].map(|culling| Series { technique, culling }))
        .filter(|s| rows.iter().any(|x| x.series() == *s))
        .collect()
}

/// Whether any of the rows has spot lights (the series then name their culling).
pub fn with_spots(rows: &[&Row]) -> bool {
    rows.iter().any(|x| x.spot_fraction > 0.0)
}

/// Refuses a spot culling without spots to cull, and spot flags with the accuracy study (its
/// culling knob makes its own spots).
pub fn check_args(a: &BenchArgs) -> Result<()> {
    if !(a.spot_fraction.is_finite() && (0.0..=1.0).contains(&a.spot_fraction)) {
        bail_input!("--spot-fraction {}: expected a share in [0, 1]", a.spot_fraction);
    }
    if a.study.is_some() && (a.spot_fraction > 0.0 || a.spot_culling != SpotCulling::Cone) {
        bail_input!("--spot-fraction and --spot-culling apply to the sweep; the accuracy study's culling knob makes half its lights spots itself");
    }
    if a.spot_fraction == 0.0 && a.spot_culling != SpotCulling::Cone {
        bail_input!("--spot-culling {}: there are no spot lights to cull (give --spot-fraction F with F > 0)", a.spot_culling.name());
    }
    Ok(())
}

/// A sweep point's lights: `n` uniform in the scene (seeded), and the cones of the
/// `--spot-fraction` of them that are spots (empty without spots). The scene's own lights and
/// cones are not used.
pub fn generate(scene: &Scene, n: usize, a: &BenchArgs) -> Result<(Vec<PointLight>, Vec<Option<Spot>>)> {
    let l = lights::uniform(scene, n, a.seed).context("generating lights")?;
    let cones = lights::spot_cones(l.len(), a.spot_fraction, a.seed).context("generating spot cones")?;
    Ok((l, cones))
}

/// The renderer's input for a sweep point: the scene with `l` and `cones`, culled the `culling`
/// way.
pub fn input<'a>(scene: &'a Scene, flat: &'a Flattened, l: &'a [PointLight], cones: &'a [Option<Spot>], culling: SpotCulling) -> SceneInput<'a> {
    let mut input = scene_input(scene, flat, l);
    input.spots = cones;
    input.effects |= culling.effects();
    input
}

/// A share as a percentage to a tenth (0.3 → "30", 0.125 → "12.5").
pub fn percent(fraction: f32) -> String {
    format!("{}", (f64::from(fraction) * 1000.0).round() / 10.0)
}

/// Median ms of the stages named `stages` of one configuration, summed (`None` without any).
fn stage_ms(rows: &[&Row], x: &Row, stages: &[&str]) -> Option<f64> {
    let of = |r: &&&Row| r.series() == x.series() && r.lights == x.lights && stages.contains(&r.stage.as_str());
    let v: Vec<f64> = rows.iter().filter(of).map(|r| r.median_ms).collect();
    (!v.is_empty()).then(|| v.iter().sum())
}

/// Light-list stages: the clustered assignment and Forward+'s culling (the tiled techniques cull
/// and shade in one pass, reported under shading).
pub const LIST_STAGES: [&str; 2] = ["assignment", "culling"];
/// Shading stages.
pub const SHADING_STAGES: [&str; 2] = ["shading", "culling + shading"];

/// The spot table of a scene's rows in `results.md` (empty without spot lights): per light count
/// and series, the light lists, lights per list (mean, max), light-list and shading ms and the
/// frame.
pub fn markdown(rows: &[&Row]) -> String {
    let mut md = String::new();
    let Some(fraction) = rows.iter().map(|r| r.spot_fraction).find(|&f| f > 0.0) else {
        return md;
    };
    let _ = writeln!(
        md,
        "\n### Spot lights ({} % of the lights): lights per list and ms, cone vs range-sphere culling\n",
        percent(fraction)
    );
    let _ = writeln!(
        md,
        "*cone*: spots culled by their cone after the range sphere; *sphere*: by the range sphere only. \
         Light lists: {} ms; shading: {} ms (the tiled techniques cull and shade in one pass).\n",
        LIST_STAGES.join(" / "),
        SHADING_STAGES.join(" / ")
    );
    let _ = writeln!(md, "| lights | technique | culling | light lists | lights per list mean | max | light lists ms | shading ms | frame ms |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
    let mut lights: Vec<usize> = rows.iter().map(|r| r.lights).collect();
    lights.sort_unstable();
    lights.dedup();
    let cell = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |v| format!("{v:.3}"));
    for n in lights {
        for s in present_series(rows) {
            let Some(x) = rows.iter().find(|r| r.series() == s && r.lights == n && r.stage == "frame") else {
                continue;
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.2} | {} | {} | {} | {:.3} |",
                super::plots::short(n),
                technique_name(s.technique),
                s.culling.name(),
                x.light_lists,
                x.lights_per_list_mean,
                x.lights_per_list_max,
                cell(stage_ms(rows, x, &LIST_STAGES)),
                cell(stage_ms(rows, x, &SHADING_STAGES)),
                x.median_ms
            );
        }
    }
    md
}
