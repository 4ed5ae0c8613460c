//! TOML scene descriptions: geometry plus an optional camera, lights, material and effect
//! overrides.
//!
//! ```toml
//! name = "my scene"               # optional: the file's stem otherwise
//! geometry = "city"               # city | corridor | glass | sponza | bunny | an .obj, .gltf or .glb path
//!                                 # (relative to this file)
//! mtl_d_zero_is_opaque = true     # OBJ geometry only, optional: read the MTL's `d 0` as opaque
//!                                 # (an exporter artefact; default true for sponza, else false)
//! [camera]                        # optional: the geometry's default camera otherwise
//! position = [0, 2, 0]
//! target = [0, 2, -10]
//! up = [0, 1, 0]                  # optional, default +y
//! fov_y = 60                      # degrees; optional, default 60
//! near = 0.1                      # optional, default: the geometry's
//! far = 1000                      # optional, default: the geometry's
//! [lights]                        # optional: no lights otherwise (the CLI then adds some)
//! count = 1000
//! distribution = "uniform"        # uniform | hotspots | surfaces
//! seed = 7                        # optional, default 1
//! radius = 5.0                    # optional: every light this radius (default: lights.rs rule)
//! intensity = 1.0                 # optional
//! clusters = 8                    # hotspots only, default 8
//! offset = 0.1                    # surfaces only: distance off the surface, default 0.5 % of
//!                                 # the scene diagonal
//! spot_fraction = 0.3             # optional, in [0, 1]: this share of the lights are spots
//!                                 # (lights::spot_cones), default 0
//! shadow_fraction = 0.1           # optional, in [0, 1]: this share of the lights cast shadows
//!                                 # (lights::shadow_casters), default 0
//! [[light]]                       # optional, repeatable: an explicit light (world space)
//! type = "point"                  # optional: point (default) | spot | directional
//! position = [0, 3, -10]          # point and spot
//! radius = 8                      # point and spot: the range
//! direction = [0, -1, 0]          # spot and directional: where the light points / travels
//! inner_angle = 20                # spot only: half-angles in degrees, 0 ≤ inner ≤ outer ≤ 90
//! outer_angle = 35                # (defaults 0 and 45, glTF's)
//! colour = [1, 0.8, 0.6]          # optional, default white
//! intensity = 20                  # optional, default: lights.rs rule for the radius (1 for
//!                                 # directional lights)
//! shadows = true                  # point and spot, optional: the light casts shadows
//! [[material]]                    # optional, repeatable: override a material of the geometry
//! name = "fabric_c"               # every material of that name (exact, case-sensitive)
//! opacity = 0.6                   # optional, in [0, 1] (1 opaque)
//! albedo = [0.8, 0.1, 0.1]        # optional, linear RGB in [0, 1] (replaces Kd; multiplies
//!                                 # the albedo texture where there is one)
//! [effects]                       # optional overrides of what the content implies
//! specular = false
//! textures = true
//! alpha_test = true
//! [[nurbs]]                       # optional, repeatable: a rational B-spline patch (world space)
//! degree_u = 2                    # 1 to 5
//! degree_v = 1
//! size_u = 3                      # control points along u (at least degree_u + 1)
//! size_v = 2
//! control_points = [[0, 0, 0], [1, 0, 1], [2, 0, 0], [0, 1, 0], [1, 1, 1], [2, 1, 0]]  # u fastest
//! weights = [1, 0.7071, 1, 1, 0.7071, 1]  # optional, positive, default 1 (polynomial)
//! knots_u = [0, 0, 0, 1, 1, 1]    # optional, size_u + degree_u + 1 non-decreasing values,
//! knots_v = [0, 0, 1, 1]          # default clamped uniform on [0, 1]
//! material = "concrete"           # a material of the geometry, by name
//! level = 24                      # optional tessellation level, 1 to 256 (quads per side;
//!                                 # `render --tess-level` overrides it, default 16)
//! ```
//! Unknown keys are errors (`deny_unknown_fields`); so are values out of range (negative
//! counts, fov outside (0, 180), NaN or infinite numbers, more than `lights::MAX_LIGHTS` lights
//! or `lights::MAX_HOTSPOT_CLUSTERS` clusters, opacity or albedo outside [0, 1]) and a
//! `[[material]]` name the geometry does not have (the error lists some it has). Material
//! overrides apply in file order once the geometry is loaded, then the `[[nurbs]]` patches are
//! added (named `nurbs[0]`, `nurbs[1]`, … in messages; a patch the kernels cannot evaluate —
//! a degree outside 1..=5, wrong lengths, decreasing or non-finite knots, a domain of zero
//! length, non-finite control points, weights not positive and finite, a level outside
//! 1..=256 — is refused naming the patch and the field: `NurbsPatch::validate`). Every error is
//! one line naming the file and the key (`light[2].radius` for the third `[[light]]`,
//! `material[1].name`), or the line and column of a syntax error.
use super::nurbs::{clamped_uniform, NurbsPatch, ScenePatch};
use super::wavefront::MtlOptions;
use super::{lights, Camera, Scene, BUILT_INS};
use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use serde::Deserialize;
use std::path::Path;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Description {
    pub name: Option<String>,
    pub geometry: String,
    /// How an OBJ geometry's MTL reads `d 0` ([`MtlOptions::d_zero_is_opaque`]); `None`: the
    /// geometry's default.
    pub mtl_d_zero_is_opaque: Option<bool>,
    pub camera: Option<CameraDesc>,
    pub lights: Option<LightsDesc>,
    /// Explicit lights (`[[light]]` tables), added after the generated ones.
    #[serde(default)]
    pub light: Vec<LightDesc>,
    /// Material overrides (`[[material]]` tables), applied in order after the geometry loads.
    #[serde(default)]
    pub material: Vec<MaterialDesc>,
    pub effects: Option<EffectsDesc>,
    /// NURBS patches (`[[nurbs]]` tables), added after the material overrides.
    #[serde(default)]
    pub nurbs: Vec<NurbsDesc>,
}

/// One rational B-spline patch (world space); checked by `NurbsPatch::validate` once its
/// material is found.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NurbsDesc {
    pub degree_u: u32,
    pub degree_v: u32,
    pub size_u: u32,
    pub size_v: u32,
    /// `size_u · size_v` Cartesian points, u fastest.
    pub control_points: Vec<[f32; 3]>,
    /// Default: every weight 1.
    pub weights: Option<Vec<f32>>,
    /// Default: clamped uniform on [0, 1] (`nurbs::clamped_uniform`).
    pub knots_u: Option<Vec<f32>>,
    pub knots_v: Option<Vec<f32>>,
    /// The name of a material of the geometry.
    pub material: String,
    pub level: Option<u32>,
}

impl NurbsDesc {
    /// The patch named `name`, of material index `material`, validated.
    fn patch(&self, name: String, material: u32, materials: usize) -> Result<ScenePatch> {
        // Default knots only where the degree and size allow them and the sizes match the control
        // points given (so a size is bounded by the file); otherwise validation names the field
        // at fault, which it checks before the knots.
        let consistent = self.size_u as u64 * self.size_v as u64 == self.control_points.len() as u64;
        let knots = |degree: u32, size: u32, given: &Option<Vec<f32>>| match given {
            Some(k) => k.clone(),
            None if consistent && (1..=shaders::nurbs::MAX_DEGREE).contains(&degree) && size > degree => clamped_uniform(degree, size),
            None => vec![],
        };
        let patch = NurbsPatch {
            degree_u: self.degree_u,
            degree_v: self.degree_v,
            knots_u: knots(self.degree_u, self.size_u, &self.knots_u),
            knots_v: knots(self.degree_v, self.size_v, &self.knots_v),
            control_points: self.control_points.clone(),
            weights: self.weights.clone().unwrap_or_else(|| vec![1.0; self.control_points.len()]),
            size_u: self.size_u,
            size_v: self.size_v,
            material,
        };
        let p = ScenePatch { name, patch, level: self.level };
        p.validate(materials)?;
        Ok(p)
    }
}

/// Overrides of the geometry's materials named `name`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    pub name: String,
    /// In [0, 1].
    pub opacity: Option<f32>,
    /// Linear RGB in [0, 1].
    pub albedo: Option<[f32; 3]>,
}

/// The `type` of a `[[light]]`.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    #[default]
    Point,
    Spot,
    Directional,
}

/// One explicit light (world space). Validated here (keys per type) and with the scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    #[serde(rename = "type", default)]
    pub kind: LightType,
    /// Point and spot lights.
    pub position: Option<[f32; 3]>,
    /// Point and spot lights.
    pub radius: Option<f32>,
    /// Spot and directional lights.
    pub direction: Option<[f32; 3]>,
    /// Spot lights, degrees (default 0).
    pub inner_angle: Option<f32>,
    /// Spot lights, degrees (default 45).
    pub outer_angle: Option<f32>,
    /// Linear RGB (default white).
    pub colour: Option<[f32; 3]>,
    /// Default: [`default_intensity`]`(radius)`.
    pub intensity: Option<f32>,
    /// Point and spot lights: casts shadows (default false).
    pub shadows: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub position: [f32; 3],
    pub target: [f32; 3],
    pub up: Option<[f32; 3]>,
    pub fov_y: Option<f32>,
    pub near: Option<f32>,
    pub far: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    Uniform,
    Hotspots,
    Surfaces,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightsDesc {
    pub count: usize,
    pub distribution: Distribution,
    pub seed: Option<u64>,
    pub radius: Option<f32>,
    pub intensity: Option<f32>,
    pub clusters: Option<usize>,
    pub offset: Option<f32>,
    /// Share of the generated lights that are spots, in [0, 1].
    pub spot_fraction: Option<f32>,
    /// Share of the generated lights that cast shadows, in [0, 1].
    pub shadow_fraction: Option<f32>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsDesc {
    pub specular: Option<bool>,
    pub textures: Option<bool>,
    pub alpha_test: Option<bool>,
}

impl Description {
    /// Lights the scene will have: `lights.count` plus the `[[light]]` tables.
    pub fn light_count(&self) -> usize {
        self.lights.as_ref().map_or(0, |l| l.count) + self.light.len()
    }
}

/// Parses a description (no file access); `file` only names the source in errors.
pub fn parse(text: &str, file: &Path) -> Result<Description> {
    let d: Description = toml::from_str(text).map_err(|e| anyhow!("scene description {}{}: {}", file.display(), locate(text, e.span()), e.message().trim()))?;
    check(&d).map_err(|e| anyhow!("scene description {}: {e}", file.display()))?;
    Ok(d)
}

/// Longest excerpt of the offending line quoted in a syntax error.
const QUOTE_CHARS: usize = 60;

/// ` line L, column C (`the line`)` for a byte span of `text` (empty without one).
fn locate(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    let Some(start) = span.map(|s| s.start.min(text.len())) else { return String::new() };
    let before = &text.as_bytes()[..start];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let column = String::from_utf8_lossy(&before[line_start..]).chars().count() + 1;
    let source = text[line_start..].lines().next().unwrap_or("").trim();
    let mut quoted: String = source.chars().take(QUOTE_CHARS).collect();
    if source.chars().count() > QUOTE_CHARS {
        quoted.push('…');
    }
    format!(" line {line}, column {column} (`{quoted}`)")
}

fn finite(key: &str, values: &[f32]) -> Result<()> {
    if values.iter().any(|v| !v.is_finite()) {
        bail!("{key} must be finite, got {values:?}");
    }
    Ok(())
}

/// Value checks serde cannot express; errors name the key.
fn check(d: &Description) -> Result<()> {
    if d.geometry.trim().is_empty() {
        bail!("geometry must name a built-in scene or an .obj file");
    }
    if let Some(c) = &d.camera {
        finite("camera.position", &c.position)?;
        finite("camera.target", &c.target)?;
        if let Some(up) = c.up {
            finite("camera.up", &up)?;
        }
        if let Some(fov) = c.fov_y {
            finite("camera.fov_y", &[fov])?;
            if !(fov > 0.0 && fov < 180.0) {
                bail!("camera.fov_y = {fov} is out of range: it must be in (0, 180) degrees");
            }
        }
        for (key, v) in [("camera.near", c.near), ("camera.far", c.far)] {
            if let Some(v) = v {
                finite(key, &[v])?;
                if v <= 0.0 {
                    bail!("{key} = {v} must be > 0");
                }
            }
        }
        if c.position == c.target {
            bail!("camera.position and camera.target are the same point {:?}", c.position);
        }
    }
    if let Some(l) = &d.lights {
        if l.count > lights::MAX_LIGHTS {
            bail!("lights.count = {} is more than the {} supported", l.count, lights::MAX_LIGHTS);
        }
        if l.count + d.light.len() > lights::MAX_LIGHTS {
            bail!("lights.count = {} and {} [[light]] tables make more than the {} lights supported", l.count, d.light.len(), lights::MAX_LIGHTS);
        }
        for (key, v) in [("lights.radius", l.radius), ("lights.intensity", l.intensity)] {
            if let Some(v) = v {
                finite(key, &[v])?;
                if v < 0.0 {
                    bail!("{key} = {v} must be ≥ 0");
                }
            }
        }
        if let Some(v) = l.offset {
            finite("lights.offset", &[v])?;
        }
        if let Some(c) = l.clusters.filter(|&c| c == 0 || c > lights::MAX_HOTSPOT_CLUSTERS) {
            bail!("lights.clusters = {c} is out of range: it must be in 1..={}", lights::MAX_HOTSPOT_CLUSTERS);
        }
        if l.clusters.is_some() && l.distribution != Distribution::Hotspots {
            bail!("lights.clusters only applies to distribution = \"hotspots\"");
        }
        for (key, f) in [("lights.spot_fraction", l.spot_fraction), ("lights.shadow_fraction", l.shadow_fraction)] {
            if let Some(f) = f.filter(|f| !(0.0..=1.0).contains(f)) {
                bail!("{key} = {f} must be in [0, 1]");
            }
        }
        if l.offset.is_some() && l.distribution != Distribution::Surfaces {
            bail!("lights.offset only applies to distribution = \"surfaces\"");
        }
    }
    let procedural = super::procedural::NAMES.contains(&d.geometry.trim().to_ascii_lowercase().as_str());
    if d.mtl_d_zero_is_opaque.is_some() && procedural {
        bail!("mtl_d_zero_is_opaque only applies to OBJ geometry (sponza, bunny or an .obj file), not geometry = {:?}", d.geometry.trim());
    }
    for (i, m) in d.material.iter().enumerate() {
        if m.name.trim().is_empty() {
            bail!("material[{i}].name is empty: it must name a material of the geometry");
        }
        let unit = |key: &str, values: &[f32]| -> Result<()> {
            finite(&format!("material[{i}].{key}"), values)?;
            if values.iter().any(|v| !(0.0..=1.0).contains(v)) {
                bail!("material[{i}].{key} must be in [0, 1], got {values:?}");
            }
            Ok(())
        };
        if let Some(v) = m.opacity {
            unit("opacity", &[v])?;
        }
        if let Some(c) = m.albedo {
            unit("albedo", &c)?;
        }
    }
    if d.light.len() > lights::MAX_LIGHTS {
        bail!("{} [[light]] tables are more than the {} lights supported", d.light.len(), lights::MAX_LIGHTS);
    }
    for (i, l) in d.light.iter().enumerate() {
        check_light_keys(i, l)?;
        if l.kind == LightType::Directional {
            continue;
        }
        let radius = l.radius.unwrap_or(0.0);
        let non_negative = |key: &str, values: &[f32]| -> Result<()> {
            finite(&format!("light[{i}].{key}"), values)?;
            if values.iter().any(|&v| v < 0.0) {
                bail!("light[{i}].{key} must be ≥ 0, got {values:?}");
            }
            Ok(())
        };
        non_negative("radius", &[radius])?;
        if let Some(c) = l.colour {
            non_negative("colour", &c)?;
        }
        match l.intensity {
            Some(v) => non_negative("intensity", &[v])?,
            None if !default_intensity(radius).is_finite() => {
                bail!("light[{i}].radius = {radius}: the default intensity for it overflows 32-bit floats; give light[{i}].intensity")
            }
            None => {}
        }
    }
    Ok(())
}

/// The keys a `[[light]]` of its type needs and allows, and their values (angles in range,
/// directions finite and non-zero); errors name `light[i].key`.
fn check_light_keys(i: usize, l: &LightDesc) -> Result<()> {
    let kind = match l.kind {
        LightType::Point => "point",
        LightType::Spot => "spot",
        LightType::Directional => "directional",
    };
    let punctual = l.kind != LightType::Directional;
    let present = [
        ("position", l.position.is_some(), punctual, punctual),
        ("radius", l.radius.is_some(), punctual, punctual),
        ("direction", l.direction.is_some(), l.kind != LightType::Point, l.kind != LightType::Point),
        ("inner_angle", l.inner_angle.is_some(), false, l.kind == LightType::Spot),
        ("outer_angle", l.outer_angle.is_some(), false, l.kind == LightType::Spot),
        ("shadows", l.shadows.is_some(), false, punctual),
    ];
    for (key, given, required, allowed) in present {
        if required && !given {
            bail!("light[{i}].{key} is missing: a {kind} light needs it");
        }
        if given && !allowed {
            bail!("light[{i}].{key} does not apply to a {kind} light (type = {kind:?})");
        }
    }
    if let Some(p) = l.position {
        finite(&format!("light[{i}].position"), &p)?;
    }
    if let Some(d) = l.direction {
        finite(&format!("light[{i}].direction"), &d)?;
        if Vec3::from_array(d).length_squared() == 0.0 || !Vec3::from_array(d).normalize_or_zero().is_finite() {
            bail!("light[{i}].direction = {d:?} has no direction (zero length)");
        }
    }
    if l.kind == LightType::Spot {
        let (inner, outer) = (l.inner_angle.unwrap_or(0.0), l.outer_angle.unwrap_or(45.0));
        finite(&format!("light[{i}].outer_angle"), &[outer])?;
        finite(&format!("light[{i}].inner_angle"), &[inner])?;
        if !(outer > 0.0 && outer <= 90.0) {
            bail!("light[{i}].outer_angle = {outer} is out of range: it must be in (0, 90] degrees");
        }
        if !(0.0..=outer).contains(&inner) {
            bail!("light[{i}].inner_angle = {inner} is out of range: it must be in [0, outer_angle = {outer}] degrees");
        }
    }
    if l.kind == LightType::Directional {
        if let Some(c) = l.colour {
            finite(&format!("light[{i}].colour"), &c)?;
            if c.iter().any(|&v| v < 0.0) {
                bail!("light[{i}].colour must be ≥ 0, got {c:?}");
            }
        }
        if let Some(v) = l.intensity {
            finite(&format!("light[{i}].intensity"), &[v])?;
            if v < 0.0 {
                bail!("light[{i}].intensity must be ≥ 0, got {v}");
            }
        }
    }
    Ok(())
}

/// Intensity of an explicit light that gives none: `lights::DEFAULT_INTENSITY ·
/// lights::radius_scaled_intensity(radius)`.
fn default_intensity(radius: f32) -> f32 {
    lights::DEFAULT_INTENSITY * lights::radius_scaled_intensity(radius)
}

/// Most material names an unknown-name error lists.
const LISTED_NAMES: usize = 8;

/// Applies the `[[material]]` tables in order; a name the scene lacks is an error naming the key
/// and listing some names it has.
fn apply_material_overrides(scene: &mut Scene, overrides: &[MaterialDesc]) -> Result<()> {
    for (i, o) in overrides.iter().enumerate() {
        let mut found = false;
        for m in scene.materials.iter_mut().filter(|m| m.name == o.name) {
            found = true;
            m.opacity = o.opacity.unwrap_or(m.opacity);
            m.albedo = o.albedo.unwrap_or(m.albedo);
        }
        if !found {
            bail!("material[{i}].name = {:?} names no material of geometry {:?}; it has {}", o.name, scene.name, material_list(scene));
        }
    }
    Ok(())
}

/// Some of the scene's material names, quoted, for an error about a name it lacks.
fn material_list(scene: &Scene) -> String {
    let mut known: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    known.dedup();
    let mut list = known.iter().take(LISTED_NAMES).map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
    if known.len() > LISTED_NAMES {
        list.push_str(&format!(", … ({} in all)", known.len()));
    }
    list
}

/// The `[[nurbs]]` tables as patches named `nurbs[i]`, each checked; a material name the scene
/// lacks is an error naming the key.
fn nurbs_patches(scene: &Scene, tables: &[NurbsDesc]) -> Result<Vec<ScenePatch>> {
    tables
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let Some(material) = scene.materials.iter().position(|m| m.name == t.material) else {
                bail!("nurbs[{i}].material = {:?} names no material of geometry {:?}; it has {}", t.material, scene.name, material_list(scene));
            };
            t.patch(format!("nurbs[{i}]"), material as u32, scene.materials.len())
        })
        .collect()
}

/// Loads a description file and builds its scene (geometry, camera, lights, effects).
pub fn load(path: &Path, assets_dir: &Path) -> Result<Scene> {
    if !path.is_file() {
        bail!("scene file {} not found", path.display());
    }
    let text = std::fs::read_to_string(path).map_err(|e| anyhow!("cannot read scene file {}: {e}", path.display()))?;
    let d = parse(&text, path)?;
    let at = |e: anyhow::Error| anyhow!("scene description {}: {e:#}", path.display());
    let geometry = d.geometry.trim();
    let mtl = d.mtl_d_zero_is_opaque.map(|d_zero_is_opaque| MtlOptions { d_zero_is_opaque });
    let mut scene = match geometry.to_ascii_lowercase().as_str() {
        g if BUILT_INS.contains(&g) => super::built_in(g, assets_dir, mtl).map_err(at)?,
        g if g.ends_with(".obj") => {
            let obj = path.parent().unwrap_or(Path::new("")).join(geometry);
            super::obj::load(&obj, mtl.unwrap_or_default()).map_err(at)?
        }
        g if g.ends_with(".gltf") || g.ends_with(".glb") => {
            if mtl.is_some() {
                return Err(at(anyhow!("mtl_d_zero_is_opaque only applies to OBJ geometry, not geometry = {geometry:?}")));
            }
            super::gltf::load(&path.parent().unwrap_or(Path::new("")).join(geometry)).map_err(at)?
        }
        _ => return Err(at(anyhow!("geometry = {geometry:?} is neither a built-in scene ({}) nor an .obj, .gltf or .glb file", BUILT_INS.join(", ")))),
    };
    apply_material_overrides(&mut scene, &d.material).map_err(at)?;
    let patches = nurbs_patches(&scene, &d.nurbs).map_err(at)?;
    scene.add_nurbs(patches);
    scene.name = d.name.clone().unwrap_or_else(|| path.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned()));
    if let Some(c) = &d.camera {
        let default = scene.camera;
        scene.camera = Camera {
            position: Vec3::from_array(c.position),
            target: Vec3::from_array(c.target),
            up: c.up.map_or(Vec3::Y, Vec3::from_array),
            fov_y_degrees: c.fov_y.unwrap_or(60.0),
            near: c.near.unwrap_or(default.near),
            far: c.far.unwrap_or(default.far),
        };
        scene.camera.validate().map_err(|e| at(anyhow!("[camera]: {e}")))?;
    }
    if let Some(l) = &d.lights {
        let seed = l.seed.unwrap_or(1);
        let mut generated = match l.distribution {
            Distribution::Uniform => lights::uniform(&scene, l.count, seed),
            Distribution::Hotspots => lights::hotspots(scene.bounds, l.count, seed, l.clusters.unwrap_or(8)),
            Distribution::Surfaces => {
                let offset = l.offset.unwrap_or(0.005 * (scene.bounds.1 - scene.bounds.0).length());
                lights::on_surfaces(&scene, l.count, seed, offset)
            }
        }
        .map_err(|e| at(anyhow!("[lights]: {e}")))?;
        for light in &mut generated {
            light.radius = l.radius.unwrap_or(light.radius);
            light.intensity = l.intensity.unwrap_or(light.intensity);
        }
        let cones = lights::spot_cones(generated.len(), l.spot_fraction.unwrap_or(0.0), seed).map_err(|e| at(anyhow!("[lights]: {e}")))?;
        // Every punctual light generated with spots: another count gets its cones alike.
        let listed = !scene.lights.is_empty() || d.light.iter().any(|l| l.kind != LightType::Directional);
        scene.spot_share = l.spot_fraction.filter(|&f| f > 0.0 && !listed).map(|fraction| lights::SpotShare { fraction, seed });
        // After the geometry's own lights (a glTF file's).
        let (n, first) = (generated.len(), scene.lights.len());
        scene.add_lights(generated.into_iter().zip(cones.into_iter().chain(std::iter::repeat(None)).take(n)));
        let casters = lights::shadow_casters(n, l.shadow_fraction.unwrap_or(0.0)).map_err(|e| at(anyhow!("[lights]: {e}")))?;
        for (i, _) in casters.iter().enumerate().filter(|(_, &c)| c) {
            scene.set_casts_shadows(first + i, true);
        }
    }
    for l in &d.light {
        let colour = l.colour.unwrap_or([1.0; 3]);
        let direction = l.direction.map(Vec3::from_array).unwrap_or(Vec3::NEG_Y);
        if l.kind == LightType::Directional {
            scene.directional.push(super::Directional { direction, colour, intensity: l.intensity.unwrap_or(1.0) });
            continue;
        }
        let radius = l.radius.unwrap_or(0.0);
        let light = shaders::layout::PointLight {
            position: l.position.unwrap_or_default(),
            radius,
            colour,
            intensity: l.intensity.unwrap_or_else(|| default_intensity(radius)),
        };
        let spot = (l.kind == LightType::Spot).then(|| super::Spot {
            direction,
            inner: l.inner_angle.unwrap_or(0.0).to_radians(),
            outer: l.outer_angle.unwrap_or(45.0).to_radians(),
        });
        scene.add_lights([(light, spot)]);
        if l.shadows == Some(true) {
            scene.set_casts_shadows(scene.lights.len() - 1, true);
        }
    }
    if scene.directional.len() > shaders::light_types::MAX_DIRECTIONAL_LIGHTS as usize {
        return Err(at(anyhow!(
            "{} directional lights: at most {} are supported (every shading pass loops over them)",
            scene.directional.len(),
            shaders::light_types::MAX_DIRECTIONAL_LIGHTS
        )));
    }
    if let Some(e) = &d.effects {
        scene.effects.specular = e.specular.unwrap_or(scene.effects.specular);
        scene.effects.textures = e.textures.unwrap_or(scene.effects.textures);
        scene.effects.alpha_test = e.alpha_test.unwrap_or(scene.effects.alpha_test);
    }
    Ok(scene)
}
