//! The scene adapter: a loaded [`Scene`] as the renderer consumes it. Shared by `render`, `bench`
//! and the tests, so that each of them renders a scene the same way.
//!
//! 1. [`flatten`] merges the meshes into one vertex/index set with one draw per mesh, the
//!    materials into the G-buffer's material table (at most [`MAX_MATERIALS`]; each entry carries
//!    the material's opacity: draws below 1 go to the transparent pass), and marks the textures a draw samples —
//!    only where the scene's effects ask for them. Each NURBS patch gets a draw of its material
//!    too, whose index range the tessellation pass assigns (`render::nurbs`).
//! 2. [`scene_input`] borrows the flattened arrays, the lights, the textures and the NURBS
//!    patches (with their levels and draws) into a [`SceneInput`] with the camera.
//!
//! Memory: one copy of the scene's vertices and indices (the renderer uploads from it).
use super::{Scene, TextureKind};
use crate::render::nurbs::NurbsDraw;
use crate::render::{Draw, SceneInput, TextureData, ViewTransform};
use anyhow::{bail, Result};
use shaders::layout::{DrawParams, MaterialGpu, PointLight, MAX_MATERIALS};
use shaders::octahedral::Precision;

/// Merged geometry, materials and draws of a scene.
pub struct Flattened {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
    pub draws: Vec<Draw>,
    pub materials: Vec<MaterialGpu>,
    /// One draw per NURBS patch of the scene (in its order), its index range not yet assigned.
    pub nurbs_draws: Vec<Draw>,
}

/// Merges a scene's meshes into one vertex/index set with one draw per mesh; every draw encodes
/// its normals at `normal_precision` (the frame must read them at the same one).
pub fn flatten(scene: &Scene, normal_precision: Precision) -> Result<Flattened> {
    let mut f = Flattened { positions: vec![], normals: vec![], uvs: vec![], indices: vec![], draws: vec![], materials: vec![], nurbs_draws: vec![] };
    for m in &scene.materials {
        f.materials.push(MaterialGpu { specular: m.specular, roughness: m.roughness, opacity: m.opacity, _pad: 0.0 });
    }
    if f.materials.is_empty() {
        f.materials.push(MaterialGpu { specular: 0.0, roughness: 1.0, opacity: 1.0, _pad: 0.0 });
    }
    if f.materials.len() > MAX_MATERIALS as usize {
        bail!("scene {:?} has {} materials; the G-buffer addresses at most {MAX_MATERIALS}", scene.name, f.materials.len());
    }
    let vertices: usize = scene.meshes.iter().map(|m| m.positions.len()).sum();
    let indices: usize = scene.meshes.iter().map(|m| m.indices.len()).sum();
    if u32::try_from(vertices).is_err() || u32::try_from(indices).is_err() {
        bail!("scene {:?} has {vertices} vertices and {indices} indices; 32-bit indices address at most {}", scene.name, u32::MAX);
    }
    for mesh in &scene.meshes {
        let base = f.positions.len() as u32;
        let first_index = f.indices.len() as u32;
        f.positions.extend_from_slice(&mesh.positions);
        f.normals.extend_from_slice(&mesh.normals);
        f.uvs.extend_from_slice(&mesh.uvs);
        f.indices.extend(mesh.indices.iter().map(|i| i + base));
        f.draws.push(Draw { first_index, index_count: mesh.indices.len() as u32, ..draw_of(scene, mesh.material, f.materials.len(), normal_precision) });
    }
    f.nurbs_draws = scene.nurbs.iter().map(|p| draw_of(scene, p.patch.material, f.materials.len(), normal_precision)).collect();
    Ok(f)
}

/// A draw of material `material` (clamped to the `materials` of the table) with no index range
/// yet: its albedo, and its textures where the scene's effects call for them (no sampling
/// otherwise).
fn draw_of(scene: &Scene, material: u32, materials: usize, normal_precision: Precision) -> Draw {
    let material = (material as usize).min(materials - 1);
    let m = scene.materials.get(material);
    let albedo = m.map(|m| m.albedo).unwrap_or([0.8; 3]);
    let texture = |path: Option<&std::path::PathBuf>| path.and_then(|p| scene.textures.iter().position(|t| &t.path == p)).map(|i| i as u32);
    let albedo_texture = if scene.effects.textures { texture(m.and_then(|m| m.albedo_texture.as_ref())) } else { None };
    let mask_texture = if scene.effects.alpha_test { texture(m.and_then(|m| m.alpha_mask_texture.as_ref())) } else { None };
    Draw {
        first_index: 0,
        index_count: 0,
        params: DrawParams { albedo, material: material as u32, normal_precision: normal_precision.code(), _pad: [0; 3] },
        albedo_texture,
        mask_texture,
        indirect: None,
    }
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
        spots: &scene.spots,
        shadows: &scene.shadows,
        directional: &scene.directional,
        textures: scene
            .textures
            .iter()
            .map(|t| TextureData { width: t.width, height: t.height, rgba8: &t.rgba8, srgb: t.kind == TextureKind::Albedo })
            .collect(),
        view: ViewTransform::look_at(c.position.as_dvec3(), c.target.as_dvec3(), c.up.as_dvec3()),
        fov_y_radians: c.fov_y_degrees.to_radians(),
        near: c.near,
        far: c.far,
        effects: scene.effects.flags(),
        material_names: scene.materials.iter().map(|m| m.name.clone()).collect(),
        nurbs: scene.nurbs.iter().zip(&flat.nurbs_draws).map(|(p, &draw)| NurbsDraw { patch: &p.patch, level: p.level(), draw }).collect(),
        nurbs_tolerance: None,
    }
}
