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
//!    mode `OPAQUE` → opacity 1, `MASK` → the alpha-test path (coverage = the base colour
//!    texture's alpha × the factor's alpha, kept where it reaches `alphaCutoff`, default 0.5;
//!    without a texture, the factor's alpha alone), `BLEND` → opacity = the base colour factor's
//!    alpha. A primitive without a material gets glTF's
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
//!    intensity. A cone out of glTF's range is an error naming the light. A point or spot light
//!    whose `extras` hold `"shadows": true` casts shadows (`--shadows all` marks every one); on a
//!    directional light, or with a value other than a boolean, it is an error naming the light.
//! 5. **Ignored with one warning line each** (per file and feature): skins, morph targets,
//!    animations, orthographic cameras, extensions the importer does not know, images that do
//!    not decode; non-triangle primitives (one line each). Primitives compressed with
//!    `KHR_draco_mesh_compression` (allowed in `extensionsRequired`) are skipped with one line;
//!    a file left with no triangle mesh is an error.
//! 6. **Errors** are one line naming the file and what is wrong: not JSON, JSON that is not
//!    glTF, a broken `.glb` container, the `gltf` crate's validation (index out of range, …:
//!    its first problem and how many more), a buffer that cannot be read or is shorter than its
//!    `byteLength`, a buffer view past its buffer, an accessor past its view, attributes of the
//!    wrong type, vertex indices past the vertices, cones out of range. They are checked before
//!    the crate reads the data (it would index past them); a panic it raises anyway becomes an
//!    error too.
use super::{face_averaged_normals, unit_vector, Camera, Directional, Material, Mesh, Scene, Spot, Texture, TextureKind};
use anyhow::{anyhow, bail, Result};
use glam::{Mat3, Mat4, Vec3};
use shaders::layout::PointLight;
use std::path::{Path, PathBuf};

/// Falloff level below which a light without a range no longer counts (see step 4).
pub const RANGE_THRESHOLD: f32 = 1.0 / 256.0;
/// glTF's default alpha cutoff.
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
    /// Indices into `lights` of those whose `extras` mark them as casting shadows (step 4).
    casters: Vec<usize>,
    directional: Vec<Directional>,
    camera: Option<Camera>,
    warnings: Vec<String>,
    /// Material index per glTF material; the default material is the last.
    default_material: u32,
    /// Whether the file uses Draco, and how many primitives it compressed (skipped).
    draco: bool,
    skipped_draco: usize,
    /// Primitives whose morph targets were ignored.
    morphed: usize,
    /// The document's node count: a deeper walk has met a cycle.
    nodes: usize,
}

/// The extension of Draco-compressed primitives, which this importer cannot decode (step 5).
const DRACO: &str = "KHR_draco_mesh_compression";
/// Extensions read (or harmless to ignore) without a warning.
const KNOWN_EXTENSIONS: [&str; 3] = ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"];

/// The light's `extras` (step 4): `{"shadows": true}` marks it as casting shadows; absent extras,
/// an object without the key or `false` leave it unshadowed; anything else is an error.
fn shadow_flag(extras: Option<&str>) -> Result<bool, String> {
    let Some(raw) = extras else { return Ok(false) };
    let value: serde_json::Value = serde_json::from_str(raw).map_err(|e| format!("not JSON ({e})"))?;
    match value.get("shadows") {
        None => Ok(false),
        Some(serde_json::Value::Bool(b)) => Ok(*b),
        Some(other) => Err(format!("\"shadows\" must be true or false, not {other}")),
    }
}

/// Loads a `.gltf` or `.glb` file. Every error is one line naming the file (step 6).
pub fn load(path: &Path) -> Result<Scene> {
    if !path.is_file() {
        bail!("scene file {} not found", path.display());
    }
    // The checks of `import` keep the `gltf` crate from indexing past its arrays; should one be
    // missed, its panic still becomes an error here, not an abort.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load_checked(path)));
    loaded.unwrap_or_else(|panic| {
        let what = panic.downcast_ref::<String>().map(String::as_str).or_else(|| panic.downcast_ref::<&str>().copied()).unwrap_or("unknown failure");
        Err(anyhow!("glTF file {}: the importer failed: {}", path.display(), one_line(what)))
    })
}

/// A `uri` without a scheme is a relative path whose percent-encoding the glTF crate decodes
/// and unwraps as UTF-8: one whose `%XX` bytes are not UTF-8 (`q%AD.bin`) is refused here.
fn relative_uri_decodes(uri: &str) -> Result<(), String> {
    if uri.contains(':') {
        return Ok(());
    }
    let (b, mut out, mut k) = (uri.as_bytes(), Vec::with_capacity(uri.len()), 0);
    while k < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (b[k], b.get(k + 1).copied().and_then(hex), b.get(k + 2).copied().and_then(hex)) {
            (b'%', Some(hi), Some(lo)) => {
                out.push((hi * 16 + lo) as u8);
                k += 3;
            }
            (c, _, _) => {
                out.push(c);
                k += 1;
            }
        }
    }
    String::from_utf8(out).map(|_| ()).map_err(|_| format!("{uri:?} percent-decodes to bytes that are not UTF-8"))
}

/// `text` on one line: its lines joined by "; ".
fn one_line(text: &str) -> String {
    text.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join("; ")
}

/// The document, its buffers and its images (`None`: an image that failed, with a warning),
/// checked so that reading them cannot index past an array or a buffer (step 6).
/// Bytes of a `.glb` header: magic, version, total length.
const GLB_HEADER_BYTES: u32 = 12;

type Imported = (gltf::Document, Vec<gltf::buffer::Data>, Vec<Option<gltf::image::Data>>);

fn import(path: &Path, warn: &mut impl FnMut(String)) -> Result<Imported, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read it: {e}"))?;
    // A `.glb` header's total length below the header's own 12 bytes makes the crate subtract
    // past zero: refused here, as the container error it is.
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)).map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]])) {
        if length < GLB_HEADER_BYTES {
            return Err(format!("not a valid .glb container: its header gives a total length of {length} bytes, less than the {GLB_HEADER_BYTES}-byte header"));
        }
    }
    let gltf::Gltf { document: doc, mut blob } = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| match e {
        gltf::Error::Deserialize(e) if e.is_data() => format!("not a glTF 2.0 document: {}", one_line(&e.to_string())),
        gltf::Error::Deserialize(e) => format!("not valid JSON: {}", one_line(&e.to_string())),
        gltf::Error::Binary(e) => format!("not a valid .glb container: {}", one_line(&e.to_string())),
        e => one_line(&e.to_string()),
    })?;
    let json = doc.as_json();
    // The crate's own validation indexes `accessors` with a primitive's POSITION unchecked.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some((semantic, index)) = prim.attributes.iter().find(|(_, i)| i.value() >= json.accessors.len()) {
                let name = match semantic {
                    gltf::json::validation::Checked::Valid(s) => s.to_string(),
                    gltf::json::validation::Checked::Invalid => "?".into(),
                };
                return Err(format!("meshes[{m}].primitives[{p}].attributes.{name}: accessor {} is out of range ({} accessors)", index.value(), json.accessors.len()));
            }
        }
    }
    use gltf::json::validation::Validate;
    let mut problems = Vec::new();
    json.validate(json, gltf::json::Path::new, &mut |at, error| problems.push(format!("{}: {error}", at())));
    // Draco may be required (its primitives are skipped), and its accessors have no data of
    // their own (no bufferView).
    let draco = json.extensions_used.iter().chain(&json.extensions_required).any(|e| e == DRACO);
    problems.retain(|p| !(p.starts_with("extensionsRequired") && p.contains(&format!("\"{DRACO}\""))));
    problems.retain(|p| !(draco && p.starts_with("accessors[") && p.ends_with("].bufferView: Missing data")));
    if let Some(first) = problems.first() {
        let more = match problems.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        return Err(format!("invalid glTF: {}{more}", one_line(first)));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for b in doc.buffers() {
        let what = match b.source() {
            gltf::buffer::Source::Uri(u) if !u.starts_with("data:") => format!("buffer {} ({u:?})", b.index()),
            _ => format!("buffer {}", b.index()),
        };
        if let gltf::buffer::Source::Uri(u) = b.source() {
            relative_uri_decodes(u).map_err(|e| format!("buffers[{}].uri: {e}", b.index()))?;
        }
        let data = gltf::buffer::Data::from_source_and_blob(b.source(), Some(base), &mut blob).map_err(|e| format!("{what}: {}", one_line(&e.to_string())))?;
        if data.len() < b.length() {
            return Err(format!("{what}: byteLength is {} but it holds {} bytes", b.length(), data.len()));
        }
        buffers.push(data);
    }
    check_views(&doc, &buffers)?;
    let images = doc
        .images()
        .map(|i| {
            // `source()` takes a `bufferView` first and unwraps its `mimeType`, else unwraps a
            // `uri`: an image whose chosen source lacks them has nothing to read.
            let j = &json.images[i.index()];
            let source = match (&j.buffer_view, &j.mime_type, &j.uri) {
                (None, _, Some(u)) => relative_uri_decodes(u).map(|()| i.source()).map_err(|e| format!("its uri: {e}")),
                (Some(_), Some(_), _) => Ok(i.source()),
                (Some(_), None, _) => Err("a bufferView without a mimeType".to_string()),
                (None, _, None) => Err("neither a uri nor a bufferView".to_string()),
            };
            match source.and_then(|s| gltf::image::Data::from_source(s, Some(base), &buffers).map_err(|e| one_line(&e.to_string()))) {
                Ok(d) => Some(d),
                Err(e) => {
                    warn(format!("image {}: {e}; materials drawn without it", i.index()));
                    None
                }
            }
        })
        .collect();
    Ok((doc, buffers, images))
}

/// Every buffer view inside its buffer, and every accessor's elements inside its view.
fn check_views(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    for v in doc.views() {
        let (end, len) = (v.offset().checked_add(v.length()), buffers[v.buffer().index()].len());
        if end.is_none_or(|end| end > len) {
            return Err(format!("bufferView {}: bytes {}..{} lie past the end of buffer {} ({len} bytes)", v.index(), v.offset(), v.offset().saturating_add(v.length()), v.buffer().index()));
        }
    }
    for a in doc.accessors() {
        let what = format!("accessor {}", a.index());
        if a.count() == 0 {
            return Err(format!("{what}: count is 0 (at least 1 expected)"));
        }
        let Some(v) = a.view() else { continue };
        let stride = v.stride().unwrap_or(a.size());
        if stride < a.size() {
            return Err(format!("{what}: bufferView {} has byteStride {stride}, less than the {}-byte element", v.index(), a.size()));
        }
        let need = (a.count() - 1).checked_mul(stride).and_then(|n| n.checked_add(a.offset() + a.size()));
        if need.is_none_or(|need| need > v.length()) {
            return Err(format!(
                "{what}: count {} × stride {stride} from byteOffset {} lies past the end of bufferView {} ({} bytes)",
                a.count(),
                a.offset(),
                v.index(),
                v.length()
            ));
        }
    }
    Ok(())
}

/// Steps 1–5 on a file that exists.
fn load_checked(path: &Path) -> Result<Scene> {
    let mut warnings = Vec::new();
    let mut warn = |what: String| warnings.push(format!("{}: {what}", path.display()));
    let (doc, buffers, images) = import(path, &mut warn).map_err(|e| anyhow!("glTF file {}: {e}", path.display()))?;
    if doc.skins().next().is_some() {
        warn(format!("{} skin(s) ignored (meshes drawn in their bind pose)", doc.skins().count()));
    }
    if doc.animations().next().is_some() {
        warn(format!("{} animation(s) ignored (nodes drawn at rest)", doc.animations().count()));
    }
    for ext in doc.extensions_used() {
        if !KNOWN_EXTENSIONS.contains(&ext) && ext != DRACO {
            warn(format!("extension {ext} ignored"));
        }
    }
    let (mut materials, textures) = materials_of(&doc, &images, path, &mut warn)?;
    let default_material = materials.len() as u32;
    materials.push(Material::diffuse("default", [1.0; 3]));

    let draco = doc.extensions_used().any(|e| e == DRACO) || doc.extensions_required().any(|e| e == DRACO);
    let mut g = Gather { buffers: &buffers, meshes: Vec::new(), lights: Vec::new(), casters: Vec::new(), directional: Vec::new(), camera: None, warnings, default_material, draco, skipped_draco: 0, morphed: 0, nodes: doc.nodes().count() };
    let scene = doc.default_scene().or_else(|| doc.scenes().next()).ok_or_else(|| anyhow!("glTF file {}: scenes: the document lists no scene to draw", path.display()))?;
    for node in scene.nodes() {
        visit(&mut g, &node, Mat4::IDENTITY, 0, path)?;
    }
    if g.morphed > 0 {
        g.warnings.push(format!("{}: morph targets of {} primitive(s) ignored (base shapes drawn)", path.display(), g.morphed));
    }
    if g.skipped_draco > 0 {
        let left = if g.meshes.is_empty() { "" } else { "; the rest loaded" };
        g.warnings.push(format!("{}: {} {DRACO} primitive(s) skipped: compressed meshes cannot be decoded{left}", path.display(), g.skipped_draco));
    }
    if g.meshes.is_empty() {
        let why = if g.skipped_draco > 0 { format!(" (all {} are {DRACO}-compressed, which cannot be decoded)", g.skipped_draco) } else { String::new() };
        bail!("glTF file {}: no triangle mesh to draw in its scene{why}", path.display());
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
    for i in g.casters {
        scene.set_casts_shadows(i, true);
    }
    scene.directional = g.directional;
    scene.warnings = g.warnings;
    Ok(scene)
}

/// Step 1 (and 3, 4) for `node` under the world transform `parent`, `depth` nodes down.
fn visit(g: &mut Gather<'_>, node: &gltf::Node<'_>, parent: Mat4, depth: usize, path: &Path) -> Result<()> {
    if depth >= g.nodes {
        bail!("glTF file {}: node {} is its own ancestor (the node hierarchy has a cycle)", path.display(), node.index());
    }
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
            let position = prim.get(&gltf::Semantic::Positions);
            // Draco's accessors hold no data of their own (no bufferView).
            if g.draco && position.as_ref().is_some_and(|a| a.view().is_none() && a.sparse().is_none()) {
                g.skipped_draco += 1;
                continue;
            }
            g.morphed += usize::from(prim.morph_targets().next().is_some());
            check_attributes(&prim).map_err(|e| anyhow!("glTF file {}: {what}: {e}", path.display()))?;
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
                Some(n) => n.map(|n| unit_vector(normal_matrix * Vec3::from_array(n)).unwrap_or(Vec3::Y).to_array()).collect(),
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
        let shadows = shadow_flag(light.extras().as_deref().map(|r| r.get()))
            .map_err(|e| anyhow!("glTF file {}: {what}: extras: {e}", path.display()))?;
        let point = || PointLight { position: origin.to_array(), radius: light.range().unwrap_or_else(|| radius_without_range(intensity, colour)), colour, intensity };
        match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => g.lights.push((point(), None)),
            gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let spot = Spot { direction: forward, inner: inner_cone_angle, outer: outer_cone_angle };
                crate::render::light_types::check_spot(&format!("glTF file {}: {what}", path.display()), &spot)?;
                g.lights.push((point(), Some(spot)));
            }
            gltf::khr_lights_punctual::Kind::Directional => {
                if shadows {
                    bail!("glTF file {}: {what}: extras: \"shadows\": directional lights cast no shadows here (point and spot lights do)", path.display());
                }
                let d = Directional { direction: forward, colour, intensity };
                crate::render::light_types::check_directional(&format!("glTF file {}: {what}", path.display()), &d)?;
                g.directional.push(d);
            }
        }
        // Only a point or spot light gets here with the flag (a directional one was refused).
        if shadows {
            g.casters.push(g.lights.len() - 1);
        }
    }
    for child in node.children() {
        visit(g, &child, world, depth + 1, path)?;
    }
    Ok(())
}

/// The attributes read have the types the reader reads them as (another type would be misread).
fn check_attributes(prim: &gltf::Primitive<'_>) -> Result<(), String> {
    use gltf::accessor::{DataType as T, Dimensions as D};
    use gltf::Semantic as S;
    for (semantic, a) in prim.attributes() {
        let (dims, types): (D, &[T]) = match semantic {
            S::Positions | S::Normals => (D::Vec3, &[T::F32]),
            S::TexCoords(0) => (D::Vec2, &[T::F32, T::U8, T::U16]),
            _ => continue,
        };
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            return Err(format!("{semantic:?} is accessor {} of {:?} {:?}; {dims:?} of {types:?} expected", a.index(), a.dimensions(), a.data_type()));
        }
    }
    if let Some(a) = prim.indices() {
        if a.dimensions() != D::Scalar || !matches!(a.data_type(), T::U8 | T::U16 | T::U32) {
            return Err(format!("indices are accessor {} of {:?} {:?}; SCALAR U8, U16 or U32 expected", a.index(), a.dimensions(), a.data_type()));
        }
    }
    Ok(())
}

/// Step 2: the document's materials in order, and the textures they name: `<file>#image<i>` for
/// an albedo, `<file>#image<i>-alpha<a>-cut<c>` for a coverage mask (texture alpha × factor
/// alpha `a` against the cutoff `c`, stored as 0 or 255 so that the alpha test's fixed cut
/// keeps exactly the texels at or above `c`), `<file>#material<m>-alpha` for a mask without a
/// texture whose factor alpha lies below its cutoff (the whole material cut out).
fn materials_of(doc: &gltf::Document, images: &[Option<gltf::image::Data>], path: &Path, warn: &mut impl FnMut(String)) -> Result<(Vec<Material>, Vec<Texture>)> {
    let mut materials = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    let decoded: Vec<Option<image::RgbaImage>> = images
        .iter()
        .enumerate()
        .map(|(i, d)| match d.as_ref().map(dynamic_image)? {
            Ok(img) => Some(img.into_rgba8()),
            Err(e) => {
                warn(format!("image {i}: {e}; materials drawn without it"));
                None
            }
        })
        .collect();
    let named = |suffix: String| PathBuf::from(format!("{}#{suffix}", path.display()));
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, gr, b, a] = pbr.base_color_factor();
        let index = m.index().unwrap_or(0);
        let name = m.name().map_or_else(|| format!("material {index}"), str::to_owned);
        let mut mat = Material::diffuse(&name, [r, gr, b].map(|c| c.clamp(0.0, 1.0)));
        mat.specular = pbr.metallic_factor().clamp(0.0, 1.0);
        mat.roughness = pbr.roughness_factor().clamp(0.01, 1.0);
        let image = pbr.base_color_texture().map(|t| t.texture().source().index());
        let img = image.and_then(|i| Some((i, decoded.get(i)?.as_ref()?)));
        if let Some((i, img)) = img {
            let name = named(format!("image{i}"));
            if !textures.iter().any(|t| t.path == name) {
                textures.push(super::obj::texture_of(name.clone(), image::DynamicImage::ImageRgba8(img.clone()), TextureKind::Albedo));
            }
            mat.albedo_texture = Some(name);
        }
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(ALPHA_CUTOFF);
                let alpha = a.clamp(0.0, 1.0);
                let (name, width, height, coverage): (PathBuf, u32, u32, Vec<f32>) = match img {
                    Some((i, img)) => (named(format!("image{i}-alpha{alpha}-cut{cutoff}")), img.width(), img.height(), img.pixels().map(|p| f32::from(p.0[3]) / 255.0 * alpha).collect()),
                    None => (named(format!("material{index}-alpha")), 1, 1, vec![alpha]),
                };
                if coverage.iter().any(|&c| c < cutoff) {
                    if !textures.iter().any(|t| t.path == name) {
                        let rgba8 = coverage.iter().flat_map(|&c| [if c >= cutoff { 255 } else { 0 }; 4]).collect();
                        textures.push(Texture { path: name.clone(), kind: TextureKind::AlphaMask, width, height, rgba8 });
                    }
                    mat.alpha_mask_texture = Some(name);
                }
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
