//! Wavefront OBJ + MTL scenes: the files, their materials and textures (`wavefront.rs` parses
//! the text, so every error names the file and line).
//!
//! Material mapping: `Kd` → albedo; `map_Kd` → albedo texture; `Ks` → specular (its largest
//! component); `Ns` → roughness ([`roughness_from_ns`]); `map_d` → alpha mask (alpha-tested);
//! `d` / `Tr` → opacity ([`super::wavefront`] gives the rule, and [`MtlOptions`] the switch that
//! reads `d 0` as opaque: the built-in `sponza` sets it, [`builtin_mtl_options`]). A library
//! whose materials come out fully transparent is loaded with a warning that names the switch.
//! `map_Ka` and bump/normal maps are not used. Texture paths are relative to the MTL's directory;
//! backslashes are read as separators.
//!
//! Missing pieces are warnings, not errors: a material library that is not there (grey default
//! material), a texture that is missing or cannot be decoded (drawn untextured / opaque), a
//! `usemtl` naming no known material (the default material). A file that is there but malformed
//! is an error.
//!
//! Default camera ([`default_camera`]): [`Camera::framing`] from +z, a little above and to the
//! right (direction (0.35, 0.3, 1)), 60° vertical fov. Sponza and the bunny have their own.
use super::wavefront::{parse_mtl, parse_obj, MtlOptions};
use super::{Camera, Material, Scene, Texture, TextureKind};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use super::wavefront::{roughness_from_ns, texture_path};

/// How the built-in OBJ scene `name` reads its MTL: Sponza's `d 0` means opaque (its assets'
/// README: an artefact of the Crytek export on 22 of its 25 materials).
pub fn builtin_mtl_options(name: &str) -> MtlOptions {
    MtlOptions { d_zero_is_opaque: name == "sponza" }
}

/// Loads `assets_dir/<name>/<name>.obj` (`sponza` or `bunny`) with its own default camera,
/// reading its MTL with `mtl` (normally [`builtin_mtl_options`]).
pub fn load_builtin(name: &str, assets_dir: &Path, mtl: MtlOptions) -> Result<Scene> {
    let path = assets_dir.join(name).join(format!("{name}.obj"));
    if !path.is_file() {
        bail!(
            "the {name} scene was not found at {}; set the assets directory (the one holding {name}/) with --assets <dir> or MANYLIGHTS_ASSETS",
            path.display()
        );
    }
    let mut scene = load(&path, mtl)?;
    scene.name = name.to_owned();
    scene.camera = match name {
        "sponza" => sponza_camera(),
        _ => bunny_camera(scene.bounds),
    };
    Ok(scene)
}

/// Sponza (original Crytek units, ≈ 0.8 cm; floor at y ≈ 0, the court's long axis along x):
/// inside the court near its east end in front of the lion, at eye height (180 units ≈ 1.45 m),
/// looking west along the court and slightly up so the galleries show. Near 5, far 5000.
pub fn sponza_camera() -> Camera {
    Camera {
        position: Vec3::new(1150.0, 180.0, -40.0),
        target: Vec3::new(-1300.0, 400.0, -40.0),
        up: Vec3::Y,
        fov_y_degrees: 60.0,
        near: 5.0,
        far: 5000.0,
    }
}

/// The bunny: framed from its front-right, slightly above (direction (0.5, 0.3, 1)), 45° fov.
pub fn bunny_camera(bounds: (Vec3, Vec3)) -> Camera {
    Camera::framing(bounds, Vec3::new(0.5, 0.3, 1.0), 45.0)
}

/// The default camera of an OBJ without its own (see the module docs).
pub fn default_camera(bounds: (Vec3, Vec3)) -> Camera {
    Camera::framing(bounds, Vec3::new(0.35, 0.3, 1.0), 60.0)
}

/// Decodes a texture file; masks get their coverage in every channel (see [`TextureKind`]).
pub fn load_texture(path: &Path, kind: TextureKind) -> Result<Texture> {
    if !path.is_file() {
        bail!("{} is not a file", path.display());
    }
    let img = image::ImageReader::open(path)
        .with_context(|| format!("cannot open {}", path.display()))?
        .with_guessed_format()
        .with_context(|| format!("cannot read {}", path.display()))?
        .decode()
        .with_context(|| format!("cannot decode {}", path.display()))?;
    Ok(texture_of(path.to_owned(), img, kind))
}

/// A decoded image as a [`Texture`] of `kind`: colour as stored, or for a mask the coverage (its
/// alpha, else its luminance) in every channel (see [`TextureKind`]).
pub fn texture_of(path: PathBuf, img: image::DynamicImage, kind: TextureKind) -> Texture {
    let has_alpha = img.color().has_alpha();
    let (width, height) = (img.width(), img.height());
    let rgba8 = match kind {
        TextureKind::Albedo => img.into_rgba8().into_raw(),
        TextureKind::AlphaMask if has_alpha => img.into_rgba8().pixels().flat_map(|p| [p.0[3]; 4]).collect(),
        TextureKind::AlphaMask => img.into_luma8().into_raw().into_iter().flat_map(|c| [c; 4]).collect(),
    };
    Texture { path, kind, width, height, rgba8 }
}

/// Loads an OBJ file (and its MTL and textures, read with `mtl`) into a scene named after the
/// file.
pub fn load(path: &Path, mtl_options: MtlOptions) -> Result<Scene> {
    if !path.is_file() {
        bail!("scene file {} not found", path.display());
    }
    let text = std::fs::read(path).map_err(|e| anyhow!("cannot read scene file {}: {e}", path.display()))?;
    let obj = parse_obj(&text, path)?;
    let dir = path.parent().unwrap_or(Path::new("")).to_owned();

    let mut warnings = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    for lib in &obj.material_libraries {
        let mtl = dir.join(lib.replace('\\', "/"));
        // Only regular files: a device or a pipe named by the OBJ could be read forever.
        let read = if mtl.is_file() { std::fs::read(&mtl).map_err(|e| e.to_string()) } else { Err("not a file".into()) };
        match read {
            Ok(text) => {
                let lib = parse_mtl(&text, &mtl, mtl.parent().unwrap_or(&dir), mtl_options)?;
                warnings.extend(invisible_materials_warning(&mtl, &lib, mtl_options));
                materials.extend(lib);
            }
            Err(e) => warnings.push(format!("{}: material library {} not loaded ({e}); using a grey default material", path.display(), mtl.display())),
        }
    }
    let textures = load_textures(&mut materials, &mut warnings);

    let mut default_material = None;
    let mut meshes = Vec::with_capacity(obj.meshes.len());
    for m in obj.meshes {
        let known = m.material_name.as_ref().and_then(|name| materials.iter().position(|x| &x.name == name));
        let material = match known {
            Some(id) => id as u32,
            None => *default_material.get_or_insert_with(|| {
                materials.push(Material::diffuse("default", [0.8; 3]));
                materials.len() as u32 - 1
            }),
        };
        meshes.push(super::Mesh { material, ..m.mesh });
    }
    if materials.is_empty() {
        materials.push(Material::diffuse("default", [0.8; 3]));
    }
    let name = path.file_stem().map_or_else(|| "obj".to_owned(), |s| s.to_string_lossy().into_owned());
    let bounds = super::bounds_of(&meshes);
    let mut scene = Scene::new(&name, meshes, materials, textures, default_camera(bounds));
    scene.warnings = warnings;
    Ok(scene)
}

/// Most material names a warning quotes.
const QUOTED_NAMES: usize = 4;

/// A warning when materials of library `mtl` are fully transparent: usually an exporter's `d 0`
/// on opaque materials, which `mtl_d_zero_is_opaque` reads as opaque (not said when it is set:
/// then they came from `Tr 1`).
fn invisible_materials_warning(mtl: &Path, lib: &[Material], options: MtlOptions) -> Option<String> {
    let invisible: Vec<&str> = lib.iter().filter(|m| m.opacity == 0.0).map(|m| m.name.as_str()).collect();
    if invisible.is_empty() {
        return None;
    }
    let mut names = invisible.iter().take(QUOTED_NAMES).map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
    if invisible.len() > QUOTED_NAMES {
        names.push_str(", …");
    }
    let hint = if options.d_zero_is_opaque {
        String::new()
    } else {
        "; if the file means opaque by `d 0` (an exporter artefact, Crytek Sponza's among them), load it from a scene description with mtl_d_zero_is_opaque = true".to_owned()
    };
    Some(format!("{}: {} of {} materials have opacity 0 (d 0 or Tr 1: {names}) and will be invisible once transparency is rendered{hint}", mtl.display(), invisible.len(), lib.len()))
}

/// Decodes every distinct texture the materials name (in parallel). A texture that fails is
/// reported in `warnings` and its material path cleared.
fn load_textures(materials: &mut [Material], warnings: &mut Vec<String>) -> Vec<Texture> {
    let mut wanted: Vec<(PathBuf, TextureKind)> = Vec::new();
    for m in materials.iter() {
        let paths = [(&m.albedo_texture, TextureKind::Albedo), (&m.alpha_mask_texture, TextureKind::AlphaMask)];
        for (p, kind) in paths {
            if let Some(p) = p {
                if !wanted.iter().any(|(q, k)| q == p && *k == kind) {
                    wanted.push((p.clone(), kind));
                }
            }
        }
    }
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get()).min(8);
    let chunk = wanted.len().div_ceil(threads).max(1);
    let decoded: Vec<Result<Texture>> = std::thread::scope(|s| {
        let handles: Vec<_> = wanted
            .chunks(chunk)
            .map(|part| s.spawn(move || part.iter().map(|(p, k)| load_texture(p, *k)).collect::<Vec<_>>()))
            .collect();
        handles
            .into_iter()
            .zip(wanted.chunks(chunk))
            .flat_map(|(h, part)| h.join().unwrap_or_else(|_| part.iter().map(|(p, _)| Err(anyhow!("the decoder of {} panicked", p.display()))).collect()))
            .collect()
    });
    let mut textures = Vec::new();
    let mut failed: HashMap<(PathBuf, TextureKind), String> = HashMap::new();
    for ((path, kind), result) in wanted.into_iter().zip(decoded) {
        match result {
            Ok(t) => textures.push(t),
            Err(e) => {
                failed.insert((path, kind), format!("{e:#}"));
            }
        }
    }
    for m in materials.iter_mut() {
        let name = m.name.clone();
        let slots = [(&mut m.albedo_texture, TextureKind::Albedo), (&mut m.alpha_mask_texture, TextureKind::AlphaMask)];
        for (slot, kind) in slots {
            if let Some(why) = slot.as_ref().and_then(|p| failed.get(&(p.clone(), kind))) {
                let what = if kind == TextureKind::Albedo { "drawn untextured" } else { "drawn opaque" };
                warnings.push(format!("material {name}: texture not loaded ({why}); {what}"));
                *slot = None;
            }
        }
    }
    textures
}
