//! Wavefront OBJ and MTL text → meshes and materials, with no file access (`obj.rs` reads the
//! files, resolves the material names and decodes the textures).
//!
//! Both parsers go line by line, so every error names the file and the line: `OBJ file
//! x.obj line 12: …`. Lines are bytes: a comment or a name may hold any bytes (names are read as
//! UTF-8, or as Latin-1 where they are not valid UTF-8: [`super::text::name`]), `\r\n` endings
//! and tabs are whitespace, and a number that is not valid UTF-8 is an error like any other
//! malformed number. Files with a byte-order mark (UTF-8, UTF-16 LE or BE) are decoded first
//! ([`super::text::decode`]). `newmtl` and `usemtl` may name the empty name (Blender writes it).
//!
//! OBJ statements read: `v x y z [w]` (w ignored), `vt u [v [w]]`, `vn x y z`, `f` with corners
//! `v`, `v/vt`, `v//vn` or `v/vt/vn` (1-based; negative = relative to the end; a corner may only
//! refer to an element defined on an earlier line), `o` / `g` (a new mesh), `usemtl` (a new mesh
//! when the material changes after faces), `mtllib` (the rest of the line is one file name,
//! spaces included). Other statements (`s`, `l`, `p`, curves, …) are ignored. Faces are
//! triangulated as fans; each distinct `(v, vt, vn)` corner becomes one vertex of its mesh.
//!
//! MTL statements read: `newmtl`, `Kd`, `Ks` (one value or three), `Ns`, `map_Kd`, `map_d`
//! (texture options such as `-bm 1` are skipped; the file name is the last word then), `d` and
//! `Tr`. Others (`Ka`, `Tf`, `illum`, bump maps, …) are ignored.
//!
//! Opacity ([`Material::opacity`]): `d v` (dissolve) is the opacity `v`; `d -halo v` is read as
//! `d v`. `Tr v` (transparency) is the opacity `1 − v`. When a material has both, `d` wins
//! wherever it appears, since exporters that write both do not always keep them consistent;
//! without either it is opaque. `d 0` is fully transparent as the format says, except under
//! [`MtlOptions::d_zero_is_opaque`]: many exporters (Crytek Sponza's, 22 of its 25 materials)
//! write `d 0` on opaque materials. `illum` cannot tell them apart (Sponza says `illum 2`
//! everywhere, as do files whose `d 0.5` is meant), so that reading is a switch of the file's
//! loader: the built-in `sponza` sets it, a scene description may (`mtl_d_zero_is_opaque`).
//!
//! Validation: every number must be finite (`1e39` overflows `f32` and is refused); colours must
//! be ≥ 0 and are clamped to 1; `Ns` must be ≥ 0; `d` and `Tr` must be in [0, 1]. Work is linear in the input's size whatever
//! its numbers say: an index is checked against what exists before anything is allocated for it.
use super::{face_averaged_normals, Material, Mesh};
use anyhow::{anyhow, Result};
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// How an MTL file's values are read where files disagree with the format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MtlOptions {
    /// Read `d 0` as opaque (an exporter artefact, see the module docs). `Tr 1` stays fully
    /// transparent.
    pub d_zero_is_opaque: bool,
}

/// Longest excerpt of an offending word quoted in an error.
const QUOTE_CHARS: usize = 32;

/// A mesh of an OBJ file, with the material its `usemtl` named (resolved by the caller).
#[derive(Clone, Debug, PartialEq)]
pub struct ObjMesh {
    /// `Mesh::material` is 0 until the caller resolves `material_name`.
    pub mesh: Mesh,
    pub material_name: Option<String>,
}

/// What an OBJ file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjFile {
    /// Meshes with at least one face, in file order.
    pub meshes: Vec<ObjMesh>,
    /// `mtllib` file names, as written (relative to the OBJ's directory).
    pub material_libraries: Vec<String>,
}

/// The words of a line, split at ASCII whitespace, comment (`#…`) removed.
fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    let code = line.split(|&b| b == b'#').next().unwrap_or(&[]);
    code.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty())
}

/// Everything after the first word of `line`, trimmed (a name or a file name: spaces allowed).
fn rest_of_line(line: &[u8]) -> String {
    let line = line.trim_ascii();
    let start = line.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(line.len());
    super::text::name(line[start..].trim_ascii())
}

/// A word as it appears in an error: escaped and cut to [`QUOTE_CHARS`].
fn quote(word: &[u8]) -> String {
    let text = String::from_utf8_lossy(word);
    let mut short: String = text.chars().take(QUOTE_CHARS).collect();
    if text.chars().count() > QUOTE_CHARS {
        short.push('…');
    }
    format!("{short:?}")
}

/// Reports errors as `<kind> file <path> line <n>: <message>`.
struct At<'a> {
    kind: &'static str,
    file: &'a Path,
    line: usize,
}

impl At<'_> {
    fn err(&self, msg: impl std::fmt::Display) -> anyhow::Error {
        anyhow!("{} file {} line {}: {msg}", self.kind, self.file.display(), self.line)
    }

    /// A finite `f32` (what: the statement, for the message).
    fn number(&self, word: &[u8], what: &str) -> Result<f32> {
        let v: f32 = std::str::from_utf8(word)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| self.err(format!("{what}: {} is not a number", quote(word))))?;
        if !v.is_finite() {
            return Err(self.err(format!("{what}: {} is not a finite 32-bit number", quote(word))));
        }
        Ok(v)
    }

    /// `min..=max` numbers after the keyword.
    fn numbers(&self, rest: impl Iterator<Item = impl AsRef<[u8]>>, what: &str, min: usize, max: usize) -> Result<Vec<f32>> {
        let mut out = Vec::with_capacity(max);
        for w in rest.take(max) {
            out.push(self.number(w.as_ref(), what)?);
        }
        if out.len() < min {
            return Err(self.err(format!("{what} needs {min} numbers, found {}", out.len())));
        }
        Ok(out)
    }

    /// A 1-based (or negative, relative) OBJ index into `len` elements of `what`.
    fn index(&self, word: &[u8], len: usize, what: &str) -> Result<usize> {
        let i: i64 = std::str::from_utf8(word)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| self.err(format!("face: {} is not a {what} index", quote(word))))?;
        let resolved = if i > 0 { Some(i - 1) } else if i < 0 { (len as i64).checked_add(i) } else { None };
        match resolved {
            Some(r) if r >= 0 && (r as u64) < len as u64 => Ok(r as usize),
            _ => Err(self.err(format!("face {what} index {i} is out of range: {len} defined before this line"))),
        }
    }
}

/// The mesh being assembled: one vertex per distinct `(v, vt, vn)` corner.
#[derive(Default)]
struct Builder {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    /// `None` where the corner had no normal.
    normals: Vec<Option<[f32; 3]>>,
    indices: Vec<u32>,
    corners: HashMap<(usize, Option<usize>, Option<usize>), u32>,
    material_name: Option<String>,
}

impl Builder {
    fn vertex(&mut self, key: (usize, Option<usize>, Option<usize>), obj: &Elements) -> u32 {
        *self.corners.entry(key).or_insert_with(|| {
            self.positions.push(obj.positions[key.0]);
            // OBJ's v grows upwards, Vulkan's downwards; a corner without one gets (0, 0).
            self.uvs.push(key.1.map_or([0.0; 2], |t| [obj.uvs[t][0], 1.0 - obj.uvs[t][1]]));
            self.normals.push(key.2.map(|n| obj.normals[n]));
            (self.positions.len() - 1) as u32
        })
    }

    /// The finished mesh: given normals renormalised; face-averaged ones where a corner had none
    /// or a degenerate one.
    fn finish(self) -> ObjMesh {
        let mut computed: Option<Vec<[f32; 3]>> = None;
        let normals = (0..self.positions.len())
            .map(|i| match self.normals[i].and_then(|n| super::unit_vector(Vec3::from_array(n))) {
                Some(n) => n.to_array(),
                None => computed.get_or_insert_with(|| face_averaged_normals(&self.positions, &self.indices))[i],
            })
            .collect();
        let mesh = Mesh { positions: self.positions, normals, uvs: self.uvs, indices: self.indices, material: 0 };
        ObjMesh { mesh, material_name: self.material_name }
    }
}

/// Vertex elements of the whole file (`v`, `vt`, `vn`), shared by its meshes.
#[derive(Default)]
struct Elements {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
}

/// Parses OBJ text; `file` names the source in errors.
pub fn parse_obj(text: &[u8], file: &Path) -> Result<ObjFile> {
    let text = super::text::decode(text);
    let mut out = ObjFile::default();
    let mut el = Elements::default();
    let mut mesh = Builder::default();
    let mut face: Vec<u32> = Vec::new();
    for (n, line) in text.split(|&b| b == b'\n').enumerate() {
        let at = At { kind: "OBJ", file, line: n + 1 };
        let mut w = words(line);
        let Some(keyword) = w.next() else { continue };
        match keyword {
            b"v" => {
                let v = at.numbers(w, "v", 3, 3)?;
                el.positions.push([v[0], v[1], v[2]]);
            }
            b"vt" => {
                let v = at.numbers(w, "vt", 1, 2)?;
                el.uvs.push([v[0], v.get(1).copied().unwrap_or(0.0)]);
            }
            b"vn" => {
                let v = at.numbers(w, "vn", 3, 3)?;
                el.normals.push([v[0], v[1], v[2]]);
            }
            b"f" => {
                face.clear();
                for corner in w {
                    let mut parts = corner.split(|&b| b == b'/');
                    let v = at.index(parts.next().unwrap_or(&[]), el.positions.len(), "position")?;
                    let t = match parts.next() {
                        Some(t) if !t.is_empty() => Some(at.index(t, el.uvs.len(), "texture coordinate")?),
                        _ => None,
                    };
                    let vn = match parts.next() {
                        Some(t) if !t.is_empty() => Some(at.index(t, el.normals.len(), "normal")?),
                        _ => None,
                    };
                    if parts.next().is_some() {
                        return Err(at.err(format!("face corner {} has more than v/vt/vn", quote(corner))));
                    }
                    if mesh.positions.len() >= u32::MAX as usize {
                        return Err(at.err("a mesh has more vertices than 32-bit indices address"));
                    }
                    face.push(mesh.vertex((v, t, vn), &el));
                }
                if face.len() < 3 {
                    return Err(at.err(format!("a face needs at least 3 corners, found {}", face.len())));
                }
                for k in 1..face.len() - 1 {
                    mesh.indices.extend([face[0], face[k], face[k + 1]]);
                }
            }
            b"o" | b"g" => {
                let material_name = mesh.material_name.clone();
                let done = std::mem::replace(&mut mesh, Builder { material_name, ..Default::default() });
                if !done.indices.is_empty() {
                    out.meshes.push(done.finish());
                }
            }
            b"usemtl" => {
                // An empty name is a name (Blender writes `newmtl` and `usemtl` without one).
                let name = rest_of_line(line);
                if mesh.material_name.as_deref() != Some(&name) && !mesh.indices.is_empty() {
                    let done = std::mem::take(&mut mesh);
                    out.meshes.push(done.finish());
                }
                mesh.material_name = Some(name);
            }
            b"mtllib" => {
                let name = rest_of_line(line);
                if name.is_empty() {
                    return Err(at.err("mtllib names no file"));
                }
                out.material_libraries.push(name);
            }
            _ => {}
        }
    }
    if !mesh.indices.is_empty() {
        out.meshes.push(mesh.finish());
    }
    Ok(out)
}

/// Roughness from a Blinn-Phong exponent: `roughness = √(2 / (Ns + 2))`, the Beckmann slope
/// α matching exponent `Ns` (Walter et al. 2007, eq. 4 inverted). `Ns` = 0 → 1 (matte),
/// `Ns` = 7.84 (Sponza) → 0.45, `Ns` = 1000 → 0.045. Negative or NaN `Ns` counts as 0.
pub fn roughness_from_ns(ns: f32) -> f32 {
    let ns = if ns > 0.0 { ns } else { 0.0 };
    (2.0 / (ns + 2.0)).sqrt()
}

/// A texture path from an MTL statement's words: options (`-bm 1 …`) dropped (the file is the
/// last word then), backslashes → `/`, relative to the MTL's directory.
pub fn texture_path(mtl_dir: &Path, raw: &str) -> PathBuf {
    let raw = raw.trim();
    let name = if raw.starts_with('-') { raw.split_whitespace().last().unwrap_or(raw) } else { raw };
    mtl_dir.join(name.replace('\\', "/"))
}

/// A colour statement (`Kd`, `Ks`): one grey value or three, each finite and ≥ 0, clamped to 1.
fn colour(at: &At<'_>, rest: impl Iterator<Item = impl AsRef<[u8]>>, what: &str) -> Result<[f32; 3]> {
    let v = at.numbers(rest, what, 1, 3)?;
    let c = match v[..] {
        [r, g, b] => [r, g, b],
        [grey] => [grey; 3],
        _ => return Err(at.err(format!("{what} needs 1 or 3 numbers, found {}", v.len()))),
    };
    if c.iter().any(|&x| x < 0.0) {
        return Err(at.err(format!("{what} {c:?} has a negative component")));
    }
    Ok(c.map(|x| x.min(1.0)))
}

/// A `d` or `Tr` value: one number in [0, 1], after an optional `-halo` (`d` only).
fn fraction<'w>(at: &At<'_>, mut rest: impl Iterator<Item = &'w [u8]>, what: &str, meaning: &str) -> Result<f32> {
    let mut first = rest.next();
    if what == "d" && first == Some(b"-halo".as_slice()) {
        first = rest.next();
    }
    let v = at.numbers(first.into_iter(), what, 1, 1)?[0];
    if !(0.0..=1.0).contains(&v) {
        return Err(at.err(format!("{what} {v} is out of range: {meaning} must be in [0, 1]")));
    }
    Ok(v)
}

/// The `d` and `Tr` values a material gave (the last of each), resolved once the file is read.
#[derive(Clone, Copy, Default)]
struct Opacity {
    d: Option<f32>,
    tr: Option<f32>,
}

impl Opacity {
    /// See the module docs: `d` wins over `Tr`; `d 0` is opaque under `d_zero_is_opaque`.
    fn resolve(self, options: MtlOptions) -> f32 {
        match (self.d, self.tr) {
            (Some(d), _) if d == 0.0 && options.d_zero_is_opaque => 1.0,
            (Some(d), _) => d,
            (None, Some(tr)) => 1.0 - tr,
            (None, None) => 1.0,
        }
    }
}

/// Parses MTL text into materials; texture paths are made relative to `dir` (the MTL's
/// directory); `file` names the source in errors.
pub fn parse_mtl(text: &[u8], file: &Path, dir: &Path, options: MtlOptions) -> Result<Vec<Material>> {
    let text = super::text::decode(text);
    let mut materials: Vec<Material> = Vec::new();
    let mut opacity: Vec<Opacity> = Vec::new();
    for (n, line) in text.split(|&b| b == b'\n').enumerate() {
        let at = At { kind: "MTL", file, line: n + 1 };
        let mut w = words(line);
        let Some(keyword) = w.next() else { continue };
        if keyword == b"newmtl" {
            let name = rest_of_line(line);
            materials.push(Material::diffuse(&name, [0.8; 3]));
            opacity.push(Opacity::default());
            continue;
        }
        if !matches!(keyword, b"Kd" | b"Ks" | b"Ns" | b"map_Kd" | b"map_d" | b"d" | b"Tr") {
            continue;
        }
        let (Some(m), Some(o)) = (materials.last_mut(), opacity.last_mut()) else {
            return Err(at.err(format!("{} before the first newmtl", quote(keyword))));
        };
        match keyword {
            b"d" => o.d = Some(fraction(&at, w, "d", "opacity")?),
            b"Tr" => o.tr = Some(fraction(&at, w, "Tr", "transparency")?),
            b"Kd" => m.albedo = colour(&at, w, "Kd")?,
            // Specular weight: the largest component of Ks.
            b"Ks" => m.specular = colour(&at, w, "Ks")?.into_iter().fold(0.0, f32::max),
            b"Ns" => {
                let ns = at.numbers(w, "Ns", 1, 1)?[0];
                if ns < 0.0 {
                    return Err(at.err(format!("Ns {ns} is negative")));
                }
                m.roughness = roughness_from_ns(ns);
            }
            _ => {
                let name = rest_of_line(line);
                if name.is_empty() {
                    return Err(at.err(format!("{} names no texture file", quote(keyword))));
                }
                let path = Some(texture_path(dir, &name));
                if keyword == b"map_Kd" {
                    m.albedo_texture = path;
                } else {
                    m.alpha_mask_texture = path;
                }
            }
        }
    }
    for (m, o) in materials.iter_mut().zip(opacity) {
        m.opacity = o.resolve(options);
    }
    Ok(materials)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(text: &str) -> Result<ObjFile> {
        parse_obj(text.as_bytes(), Path::new("t.obj"))
    }

    fn obj_err(text: &str) -> String {
        format!("{:#}", obj(text).unwrap_err())
    }

    #[test]
    fn faces_corners_and_meshes() {
        let f = obj("v 0 0 0\nv 1 0 0\r\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0.25\nvn 0 0 2\n\
                     o a\nf 1 2 3 4\nf -4 -2 -1\nusemtl m\nf 1/1/1 2/2/1 3//1\ng b\nf 1 2 3\n")
            .unwrap();
        assert_eq!(f.meshes.len(), 3, "a new material after faces and a new group each start a mesh");
        let a = &f.meshes[0];
        assert_eq!(a.mesh.indices, vec![0, 1, 2, 0, 2, 3, 0, 2, 3], "quad as a fan; relative indices reuse corners");
        assert_eq!(a.material_name, None);
        assert!(a.mesh.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]), "face-averaged");
        let m = &f.meshes[1];
        assert_eq!(m.material_name.as_deref(), Some("m"));
        assert_eq!(m.mesh.uvs, vec![[0.0, 1.0], [1.0, 0.75], [0.0, 0.0]], "v flipped; no vt → 0");
        assert!(m.mesh.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]), "vn renormalised");
        assert_eq!(f.meshes[2].material_name.as_deref(), Some("m"), "a group keeps the current material");
    }

    #[test]
    fn errors_name_the_file_and_line() {
        assert_eq!(obj_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 999\n"), "OBJ file t.obj line 4: face position index 999 is out of range: 3 defined before this line");
        assert!(obj_err("v 0 0 zero\n").starts_with("OBJ file t.obj line 1: v: \"zero\" is not a number"));
        assert!(obj_err("\n\nv 0 nan 0\n").starts_with("OBJ file t.obj line 3: v: \"nan\" is not a finite"));
        assert!(obj_err("v 0 1e39 0\n").contains("not a finite"));
        assert!(obj_err("v 0 0\n").contains("line 1: v needs 3 numbers, found 2"));
        assert!(obj_err("v 0 0 0\nf 1 1\n").contains("line 2: a face needs at least 3 corners, found 2"));
        assert!(obj_err("v 0 0 0\nf 1 1 2147483648\n").contains("index 2147483648 is out of range"));
        assert!(obj_err("v 0 0 0\nf 1 1 -9223372036854775808\n").contains("out of range"));
        assert!(obj_err("v 0 0 0\nf 1 0 1\n").contains("index 0 is out of range"));
        assert!(obj_err("v 0 0 0\nf 1/1 1 1\n").contains("texture coordinate index 1 is out of range: 0 defined"));
        assert!(obj_err("v 0 0 0\nf 1/\u{ff}/ 1 1\n").contains("is not a texture coordinate index"));
        assert!(obj_err("v 0 0 0\nvn 0 0 1\nf 1//1/1 1 1\n").contains("more than v/vt/vn"));
        let long = format!("v 0 0 {}\n", "9".repeat(100_000));
        let e = obj_err(&long);
        assert!(e.len() < 200, "a long word is cut in the message: {e}");
        // Non-UTF-8 in a comment and a name is fine; in a number it is an error.
        assert!(parse_obj(b"# \xff\xfe\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl \xff\nf 1 2 3\n", Path::new("t.obj")).is_ok());
        let e = format!("{:#}", parse_obj(b"v 0 \xff 0\n", Path::new("t.obj")).unwrap_err());
        assert!(e.contains("line 1") && e.contains("not a number"), "{e}");
    }

    #[test]
    fn mtl_values_are_checked() {
        let dir = Path::new("d");
        let mtl = |t: &str| parse_mtl(t.as_bytes(), Path::new("m.mtl"), dir, MtlOptions::default());
        let m = mtl("# c\nnewmtl a b\nKd 0.5\nKs 2 0.1 0\nNs 198\nmap_Kd -bm 1 tex\\a.png\nmap_d  mask.png \nd 0\n").unwrap();
        assert_eq!((m[0].name.as_str(), m[0].albedo, m[0].specular), ("a b", [0.5; 3], 1.0));
        assert!((m[0].roughness - 0.1).abs() < 1e-6);
        assert_eq!(m[0].albedo_texture.as_deref(), Some(Path::new("d/tex/a.png")));
        assert_eq!(m[0].alpha_mask_texture.as_deref(), Some(Path::new("d/mask.png")));
        let e = |t: &str| format!("{:#}", mtl(t).unwrap_err());
        assert_eq!(e("newmtl a\nKd 0 nan 0\n"), "MTL file m.mtl line 2: Kd: \"nan\" is not a finite 32-bit number");
        assert!(e("newmtl a\nKd 0 -1 0\n").contains("line 2: Kd [0.0, -1.0, 0.0] has a negative component"));
        assert!(e("newmtl a\nKd 0.5 0.5\n").contains("line 2: Kd needs 1 or 3 numbers, found 2"));
        assert!(e("newmtl a\nNs -3\n").contains("line 2: Ns -3 is negative"));
        assert!(e("newmtl a\nNs inf\n").contains("not a finite"));
        assert!(e("Kd 1 1 1\n").contains("line 1: \"Kd\" before the first newmtl"));
        assert!(e("newmtl a\nmap_Kd\n").contains("names no texture file"));
        assert_eq!(mtl("newmtl\n").unwrap()[0].name, "", "an empty name is a name");
    }
}
