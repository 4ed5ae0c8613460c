//! glTF 2.0 scenes (`.gltf` with external or embedded buffers, `.glb`) → meshes, materials,
//! textures, the first camera and the point lights of `KHR_lights_punctual`, through the `gltf`
//! crate's importer (which reads buffers and images, data URIs included).
//!
//! 1. **Nodes** of the default scene (or the first), depth first, each with its world transform
//!    (parent × local). Every triangle primitive of a node's mesh becomes one [`Mesh`]:
//!    positions by the transform, normals by its inverse transpose (face-averaged when the
//!    primitive has none), `TEXCOORD_0` as is (glTF's `(0, 0)` is the image's top-left texel,
//!    our convention), indices or `0..n`; a transform that mirrors (negative determinant) swaps
//!    each triangle's winding so front faces stay counter-clockwise.
//! 2. **Materials**: base-colour factor (linear RGB) → albedo, its texture → the albedo texture;
//!    `metallicFactor` → specular weight, `roughnessFactor` → roughness (at least 0.01); alpha
//!    mode `OPAQUE` → opacity 1, `MASK` → the alpha-test path (the base colour's alpha as the
//!    coverage mask, cut at 0.5; another `alphaCutoff` is read as 0.5 with a warning), `BLEND` →
//!    opacity = the base colour factor's alpha. A primitive without a material gets glTF's
//!    default (white, opaque).
//! 3. **Camera**: the first node with a perspective camera: position and −z / +y of its world
//!    transform, `yfov`, `znear`, `zfar` (or, infinite, 1000 × `znear` and at least past the
//!    scene). Without one: [`super::obj::default_camera`].
//! 4. **Lights** (`KHR_lights_punctual`): a point light → a [`PointLight`] at its node's origin,
//!    colour and intensity as given, radius = `range`; without a range, the distance where
//!    `intensity · max(colour) / d²` falls to 1/256 (`√(256 · intensity · max(colour))`), past
//!    which an unwindowed light would change no 8-bit pixel at exposure 1. A spot light is the
//!    same point light plus its cone ([`Spot`]): the node's −z axis, `innerConeAngle` and
//!    `outerConeAngle`; a directional light ([`Directional`]) the node's −z axis, colour and
//!    intensity. A cone out of glTF's range is an error naming the light.
//! 5. **Ignored with one warning line each**: skins, morph targets, animations, non-triangle
//!    primitives, orthographic cameras, extensions the importer does not know.
use super::{face_averaged_normals, Camera, Directional, Material, Mesh, Scene, Spot, Texture, TextureKind};
use anyhow::{anyhow, bail, Result};
use glam::{Mat3, Mat4, Vec3};
use shaders::layout::PointLight;
use std::path::{Path, PathBuf};

/// Falloff level below which a light without a range no longer counts (see step 4).
pub const RANGE_THRESHOLD: f32 = 1.0 / 256.0;
/// glTF's default alpha cutoff, and the one the alpha-test path cuts at (`TextureKind::AlphaMask`).
const ALPHA_CUTOFF: f32 = 0.5;

/// The radius of a point light without a `range` (step 4).
pub fn radius_without_range(intensity: f32, colour: [f32; 3]) -> f32 {
    (intensity * colour.into_iter().fold(0.0, f32::max) / RANGE_THRESHOLD).sqrt()
}

/// What the node walk gathers.
struct Gather<'a> {
    buffers: &'a [gltf::buffer::Data],
    meshes: Vec<Mesh>,
    lights: Vec<(PointLight, Option<Spot>)>,
    directional: Vec<Directional>,
    camera: Option<Camera>,
    warnings: Vec<String>,
    /// Material index per glTF material; the default material is the last.
    default_material: u32,
}

/// Loads a `.gltf` or `.glb` file.
pub fn load(path: &Path) -> Result<Scene> {
    if !path.is_file() {
        bail!("scene file {} not found", path.display());
    }
    let (doc, buffers, images) = gltf::import(path).map_err(|e| anyhow!("glTF file {}: {e}", path.display()))?;
    let mut warnings = Vec::new();
    let mut warn = |what: String| warnings.push(format!("{}: {what}", path.display()));
    if doc.skins().next().is_some() {
        warn("skins ignored".into());
    }
    if doc.animations().next().is_some() {
        warn("animations ignored".into());
    }
    for ext in doc.extensions_used() {
        if !matches!(ext, "KHR_lights_punctual" | "KHR_materials_emissive_strength" | "KHR_texture_transform") {
            warn(format!("extension {ext} ignored"));
        }
    }
    let (mut materials, textures) = materials_of(&doc, &images, path, &mut warn)?;
    let default_material = materials.len() as u32;
    materials.push(Material::diffuse("default", [1.0; 3]));

    let mut g = Gather { buffers: &buffers, meshes: Vec::new(), lights: Vec::new(), directional: Vec::new(), camera: None, warnings, default_material };
    let scene = doc.default_scene().or_else(|| doc.scenes().next()).ok_or_else(|| anyhow!("glTF file {} has no scene", path.display()))?;
    for node in scene.nodes() {
        visit(&mut g, &node, Mat4::IDENTITY, path)?;
    }
    let name = path.file_stem().map_or_else(|| "gltf".to_owned(), |s| s.to_string_lossy().into_owned());
    let bounds = super::bounds_of(&g.meshes);
    let camera = match g.camera {
        Some(mut c) => {
            // An infinite far plane: past the whole scene.
            if !c.far.is_finite() {
                let reach = (bounds.1 - bounds.0).length() + (c.position - 0.5 * (bounds.0 + bounds.1)).length();
                c.far = (1000.0 * c.near).max(2.0 * reach);
            }
            c
        }
        None => super::obj::default_camera(bounds),
    };
    let mut scene = Scene::new(&name, g.meshes, materials, textures, camera);
    scene.add_lights(g.lights);
    scene.directional = g.directional;
    scene.warnings = g.warnings;
    Ok(scene)
}

/// Step 1 (and 3, 4) for `node` under the world transform `parent`.
fn visit(g: &mut Gather<'_>, node: &gltf::Node<'_>, parent: Mat4, path: &Path) -> Result<()> {
    let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
    let label = |kind: &str, index: usize, name: Option<&str>| match name {
        Some(n) => format!("{kind} {index} ({n:?})"),
        None => format!("{kind} {index}"),
    };
    if let Some(mesh) = node.mesh() {
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
        for prim in mesh.primitives() {
            let what = format!("{}, primitive {}", label("mesh", mesh.index(), mesh.name()), prim.index());
            if prim.mode() != gltf::mesh::Mode::Triangles {
                g.warnings.push(format!("{}: {what}: {:?} primitives ignored (triangles only)", path.display(), prim.mode()));
                continue;
            }
            if prim.morph_targets().next().is_some() {
                g.warnings.push(format!("{}: {what}: morph targets ignored", path.display()));
            }
            let reader = prim.reader(|b| g.buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(positions) = reader.read_positions() else {
                g.warnings.push(format!("{}: {what}: no POSITION, ignored", path.display()));
                continue;
            };
            let positions: Vec<[f32; 3]> = positions.map(|p| world.transform_point3(Vec3::from_array(p)).to_array()).collect();
            let mut indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            indices.truncate(indices.len() / 3 * 3);
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                bail!("glTF file {}: {what}: index {bad} is out of range ({} vertices)", path.display(), positions.len());
            }
            if mirrored {
                indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
            }
            let normals = match reader.read_normals() {
                Some(n) => n.map(|n| (normal_matrix * Vec3::from_array(n)).normalize_or(Vec3::Y).to_array()).collect(),
                None => face_averaged_normals(&positions, &indices),
            };
            let uvs: Vec<[f32; 2]> = match reader.read_tex_coords(0) {
                Some(t) => t.into_f32().collect(),
                None => vec![[0.0; 2]; positions.len()],
            };
            if normals.len() != positions.len() || uvs.len() != positions.len() {
                bail!("glTF file {}: {what}: attribute counts differ from POSITION's {}", path.display(), positions.len());
            }
            let material = prim.material().index().map_or(g.default_material, |i| i as u32);
            g.meshes.push(Mesh { positions, normals, uvs, indices, material });
        }
    }
    let origin = world.transform_point3(Vec3::ZERO);
    if let (Some(cam), None) = (node.camera(), g.camera) {
        match cam.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
                let up = world.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
                let c = Camera { position: origin, target: origin + forward, up, fov_y_degrees: p.yfov().to_degrees(), near: p.znear(), far: p.zfar().unwrap_or(f32::INFINITY) };
                g.camera = Some(c);
            }
            gltf::camera::Projection::Orthographic(_) => g.warnings.push(format!("{}: {}: orthographic camera ignored", path.display(), label("camera", cam.index(), cam.name()))),
        }
    }
    if let Some(light) = node.light() {
        let what = label("light", light.index(), light.name());
        let (colour, intensity) = (light.color(), light.intensity());
        let forward = world.transform_vector3(Vec3::NEG_Z);
        let point = || PointLight { position: origin.to_array(), radius: light.range().unwrap_or_else(|| radius_without_range(intensity, colour)), colour, intensity };
        match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => g.lights.push((point(), None)),
            gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let spot = Spot { direction: forward, inner: inner_cone_angle, outer: outer_cone_angle };
                crate::render::light_types::check_spot(&format!("glTF file {}: {what}", path.display()), &spot)?;
                g.lights.push((point(), Some(spot)));
            }
            gltf::khr_lights_punctual::Kind::Directional => {
                let d = Directional { direction: forward, colour, intensity };
                crate::render::light_types::check_directional(&format!("glTF file {}: {what}", path.display()), &d)?;
                g.directional.push(d);
            }
        }
    }
    for child in node.children() {
        visit(g, &child, world, path)?;
    }
    Ok(())
}

/// Step 2: the document's materials in order, and the textures they name (decoded by the
/// importer; named `<file>#image<i>` for albedo and `<file>#image<i>-alpha` for coverage).
fn materials_of(doc: &gltf::Document, images: &[gltf::image::Data], path: &Path, warn: &mut impl FnMut(String)) -> Result<(Vec<Material>, Vec<Texture>)> {
    let mut materials = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    let mut texture = |image: usize, kind: TextureKind, warn: &mut dyn FnMut(String)| -> Option<PathBuf> {
        let suffix = if kind == TextureKind::AlphaMask { "-alpha" } else { "" };
        let name = PathBuf::from(format!("{}#image{image}{suffix}", path.display()));
        if textures.iter().any(|t| t.path == name) {
            return Some(name);
        }
        match images.get(image).map(dynamic_image) {
            Some(Ok(img)) => {
                textures.push(super::obj::texture_of(name.clone(), img, kind));
                Some(name)
            }
            Some(Err(e)) => {
                warn(format!("image {image}: {e}; material drawn without it"));
                None
            }
            None => None,
        }
    };
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, gr, b, a] = pbr.base_color_factor();
        let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_owned);
        let mut mat = Material::diffuse(&name, [r, gr, b].map(|c| c.clamp(0.0, 1.0)));
        mat.specular = pbr.metallic_factor().clamp(0.0, 1.0);
        mat.roughness = pbr.roughness_factor().clamp(0.01, 1.0);
        let image = pbr.base_color_texture().map(|t| t.texture().source().index());
        mat.albedo_texture = image.and_then(|i| texture(i, TextureKind::Albedo, warn));
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(ALPHA_CUTOFF);
                if cutoff != ALPHA_CUTOFF {
                    warn(format!("material {name:?}: alphaCutoff {cutoff} read as {ALPHA_CUTOFF}"));
                }
                mat.alpha_mask_texture = image.and_then(|i| texture(i, TextureKind::AlphaMask, warn));
            }
            gltf::material::AlphaMode::Blend => mat.opacity = a.clamp(0.0, 1.0),
        }
        materials.push(mat);
    }
    Ok((materials, textures))
}

/// The importer's decoded image as an `image` buffer (its bytes are the buffer's, native endian),
/// for [`super::obj::texture_of`]; float images are not supported.
fn dynamic_image(d: &gltf::image::Data) -> Result<image::DynamicImage> {
    use gltf::image::Format as F;
    use image::{DynamicImage as D, ImageBuffer};
    let (w, h, px) = (d.width, d.height, d.pixels.clone());
    let wide = || px.chunks_exact(2).map(|c| u16::from_ne_bytes([c[0], c[1]])).collect::<Vec<u16>>();
    let img = match d.format {
        F::R8 => ImageBuffer::from_raw(w, h, px).map(D::ImageLuma8),
        F::R8G8 => ImageBuffer::from_raw(w, h, px).map(D::ImageLumaA8),
        F::R8G8B8 => ImageBuffer::from_raw(w, h, px).map(D::ImageRgb8),
        F::R8G8B8A8 => ImageBuffer::from_raw(w, h, px).map(D::ImageRgba8),
        F::R16 => ImageBuffer::from_raw(w, h, wide()).map(D::ImageLuma16),
        F::R16G16 => ImageBuffer::from_raw(w, h, wide()).map(D::ImageLumaA16),
        F::R16G16B16 => ImageBuffer::from_raw(w, h, wide()).map(D::ImageRgb16),
        F::R16G16B16A16 => ImageBuffer::from_raw(w, h, wide()).map(D::ImageRgba16),
        other => bail!("{other:?} texels are not supported"),
    };
    img.ok_or_else(|| anyhow!("{}×{} {:?} image with {} bytes", w, h, d.format, d.pixels.len()))
}
