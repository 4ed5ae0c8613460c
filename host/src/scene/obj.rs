//! Wavefront OBJ + MTL through `tobj` (`single_index`, `triangulate`).
//!
//! Material mapping: `Kd` → albedo; `map_Kd` → albedo texture; `Ks` → specular (its largest
//! component); `Ns` → roughness ([`roughness_from_ns`]); `map_d` → alpha mask (alpha-tested).
//! `d` (dissolve) is ignored: everything without a `map_d` is opaque — Crytek Sponza's MTL has
//! `d 0` on its opaque materials. `map_Ka` and bump/normal maps are not used. Texture paths are
//! relative to the MTL's directory; backslashes are read as separators.
//!
//! Default camera ([`default_camera`]): [`Camera::framing`] from +z, a little above and to the
//! right (direction (0.35, 0.3, 1)), 60° vertical fov. Sponza and the bunny have their own.
use super::{face_averaged_normals, Camera, Material, Mesh, Scene, Texture, TextureKind};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::Vec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// Roughness from a Blinn-Phong exponent: `roughness = √(2 / (Ns + 2))`, the Beckmann slope
/// α matching exponent `Ns` (Walter et al. 2007, eq. 4 inverted). `Ns` = 0 → 1 (matte),
/// `Ns` = 7.84 (Sponza) → 0.45, `Ns` = 1000 → 0.045. Negative or NaN `Ns` counts as 0.
pub fn roughness_from_ns(ns: f32) -> f32 {
    let ns = if ns > 0.0 { ns } else { 0.0 };
    (2.0 / (ns + 2.0)).sqrt()
}

/// Loads `assets_dir/<name>/<name>.obj` (`sponza` or `bunny`) with its own default camera.
pub fn load_builtin(name: &str, assets_dir: &Path) -> Result<Scene> {
    let path = assets_dir.join(name).join(format!("{name}.obj"));
    if !path.is_file() {
        bail!(
            "the {name} scene was not found at {}; set the assets directory (the one holding {name}/) with --assets <dir> or MANYLIGHTS_ASSETS",
            path.display()
        );
    }
    let mut scene = load(&path)?;
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

/// A texture path from an MTL statement: options (`-bm 1 …`) dropped, backslashes → `/`,
/// relative to the MTL's directory.
fn texture_path(mtl_dir: &Path, raw: &str) -> PathBuf {
    let raw = raw.trim();
    let name = if raw.starts_with('-') { raw.split_whitespace().last().unwrap_or(raw) } else { raw };
    mtl_dir.join(name.replace('\\', "/"))
}

/// Decodes a texture file; masks get their coverage in every channel (see [`TextureKind`]).
pub fn load_texture(path: &Path, kind: TextureKind) -> Result<Texture> {
    let img = image::ImageReader::open(path)
        .with_context(|| format!("cannot open {}", path.display()))?
        .with_guessed_format()
        .with_context(|| format!("cannot read {}", path.display()))?
        .decode()
        .with_context(|| format!("cannot decode {}", path.display()))?;
    let has_alpha = img.color().has_alpha();
    let (width, height) = (img.width(), img.height());
    let rgba8 = match kind {
        TextureKind::Albedo => img.into_rgba8().into_raw(),
        TextureKind::AlphaMask if has_alpha => img.into_rgba8().pixels().flat_map(|p| [p.0[3]; 4]).collect(),
        TextureKind::AlphaMask => img.into_luma8().into_raw().into_iter().flat_map(|c| [c; 4]).collect(),
    };
    Ok(Texture { path: path.to_owned(), kind, width, height, rgba8 })
}

/// Loads an OBJ file (and its MTL and textures) into a scene named after the file.
pub fn load(path: &Path) -> Result<Scene> {
    if !path.is_file() {
        bail!("scene file {} not found", path.display());
    }
    let file = std::fs::File::open(path).with_context(|| format!("cannot open scene file {}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("")).to_owned();
    let mtl_dirs = RefCell::new(Vec::new());
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    let (models, materials) = tobj::load_obj_buf(&mut BufReader::new(file), &opts, |mtl| {
        let full = dir.join(mtl);
        mtl_dirs.borrow_mut().push(full.parent().unwrap_or(&dir).to_owned());
        tobj::load_mtl(&full)
    })
    .map_err(|e| anyhow!("scene file {} is not a valid OBJ file: {e}", path.display()))?;
    let mtl_dir = mtl_dirs.into_inner().into_iter().next().unwrap_or_else(|| dir.clone());

    let mut warnings = Vec::new();
    let mtl_materials = materials.unwrap_or_else(|e| {
        warnings.push(format!("{}: material library not loaded ({e}); using a grey default material", path.display()));
        Vec::new()
    });
    let mut materials: Vec<Material> = mtl_materials
        .iter()
        .map(|m| Material {
            name: m.name.clone(),
            albedo: m.diffuse.unwrap_or([0.8; 3]),
            albedo_texture: m.diffuse_texture.as_deref().map(|t| texture_path(&mtl_dir, t)),
            specular: m.specular.map_or(0.0, |s| s.into_iter().fold(0.0, f32::max)).clamp(0.0, 1.0),
            roughness: roughness_from_ns(m.shininess.unwrap_or(0.0)),
            alpha_mask_texture: m.dissolve_texture.as_deref().map(|t| texture_path(&mtl_dir, t)),
        })
        .collect();
    let textures = load_textures(&mut materials, &mut warnings);

    let mut default_material = None;
    let mut meshes = Vec::with_capacity(models.len());
    for model in models {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let material = match m.material_id.filter(|&id| id < materials.len()) {
            Some(id) => id as u32,
            None => *default_material.get_or_insert_with(|| {
                materials.push(Material::diffuse("default", [0.8; 3]));
                materials.len() as u32 - 1
            }),
        };
        meshes.push(mesh_from(m, material));
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

/// Converts one tobj mesh: normals renormalised (or face-averaged when absent or degenerate),
/// uvs flipped to Vulkan's convention (or zero when absent).
fn mesh_from(m: tobj::Mesh, material: u32) -> Mesh {
    let positions: Vec<[f32; 3]> = m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    let n = positions.len();
    let computed = || face_averaged_normals(&positions, &m.indices);
    let normals = if m.normals.len() == 3 * n {
        let mut fallback: Option<Vec<[f32; 3]>> = None;
        m.normals
            .chunks_exact(3)
            .enumerate()
            .map(|(i, v)| match Vec3::new(v[0], v[1], v[2]).try_normalize() {
                Some(v) => v.to_array(),
                None => fallback.get_or_insert_with(computed)[i],
            })
            .collect()
    } else {
        computed()
    };
    let uvs = if m.texcoords.len() == 2 * n { m.texcoords.chunks_exact(2).map(|t| [t[0], 1.0 - t[1]]).collect() } else { vec![[0.0; 2]; n] };
    Mesh { positions, normals, uvs, indices: m.indices, material }
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
        handles.into_iter().flat_map(|h| h.join().expect("texture decoding thread panicked")).collect()
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
