//! Small glTF 2.0 files built in code: a [`Builder`] collects the JSON and one binary buffer,
//! then writes the document with the buffer as an external `.bin`, as a data URI, or as a `.glb`
//! ([`Buffer`]). Textures are PNGs embedded as data URIs.
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Where the binary buffer goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Buffer<'a> {
    /// A file beside the document, named so.
    External(&'a str),
    /// A `data:application/octet-stream;base64,` URI in the document.
    DataUri,
    /// The `BIN` chunk of a `.glb` container.
    Glb,
}

/// A glTF document under construction: `json` is its root object (edit it freely), `bin` its
/// one buffer (4-byte aligned views).
pub struct Builder {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Default for Builder {
    fn default() -> Self {
        Self::new()
    }
}

impl Builder {
    /// An empty document whose scene 0 has no nodes yet.
    pub fn new() -> Self {
        Self { json: json!({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}]}), bin: Vec::new() }
    }

    /// Appends `v` to the root array `key` (created when absent); returns its index.
    pub fn push(&mut self, key: &str, v: Value) -> usize {
        let array = self.json.as_object_mut().unwrap().entry(key).or_insert_with(|| json!([])).as_array_mut().unwrap();
        array.push(v);
        array.len() - 1
    }

    /// A buffer view of `bytes` (appended to the buffer at a 4-byte boundary).
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().div_ceil(4) * 4, 0);
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}))
    }

    /// A float accessor of `n`-component elements (`ty`: "SCALAR", "VEC2", "VEC3"), with the
    /// `min`/`max` glTF requires of positions.
    pub fn floats(&mut self, data: &[f32], n: usize, ty: &str) -> usize {
        let view = self.view(&data.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
        let (mut min, mut max) = (vec![f32::MAX; n], vec![f32::MIN; n]);
        for e in data.chunks(n) {
            for k in 0..n {
                (min[k], max[k]) = (min[k].min(e[k]), max[k].max(e[k]));
            }
        }
        self.push("accessors", json!({"bufferView": view, "componentType": 5126, "count": data.len() / n, "type": ty, "min": min, "max": max}))
    }

    /// A u16 index accessor.
    pub fn indices(&mut self, indices: &[u16]) -> usize {
        let view = self.view(&indices.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
        self.push("accessors", json!({"bufferView": view, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}))
    }

    /// A primitive (JSON) of triangles with these attributes.
    pub fn primitive(&mut self, positions: &[[f32; 3]], normals: &[[f32; 3]], uvs: &[[f32; 2]], indices: &[u16], material: Option<usize>) -> Value {
        let p = self.floats(positions.as_flattened(), 3, "VEC3");
        let n = self.floats(normals.as_flattened(), 3, "VEC3");
        let t = self.floats(uvs.as_flattened(), 2, "VEC2");
        let i = self.indices(indices);
        let mut prim = json!({"attributes": {"POSITION": p, "NORMAL": n, "TEXCOORD_0": t}, "indices": i});
        if let Some(m) = material {
            prim["material"] = json!(m);
        }
        prim
    }

    /// A rectangle primitive: `centre ± u ± v`, facing `u × v`, uv (0, 0) at `centre − u + v`
    /// (the top-left corner when u points right and v up) and (1, 1) at `centre + u − v`.
    pub fn rectangle(&mut self, centre: [f32; 3], u: [f32; 3], v: [f32; 3], material: Option<usize>) -> Value {
        let (c, u, v) = (glam::Vec3::from(centre), glam::Vec3::from(u), glam::Vec3::from(v));
        let corners = [c - u + v, c + u + v, c + u - v, c - u - v].map(|p| p.to_array());
        let n = u.cross(v).normalize().to_array();
        self.primitive(&corners, &[n; 4], &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], &[0, 3, 2, 0, 2, 1], material)
    }

    /// A mesh of these primitives; returns its index.
    pub fn mesh(&mut self, primitives: Vec<Value>) -> usize {
        self.push("meshes", json!({"primitives": primitives}))
    }

    /// A node (JSON object) added to the scene's root nodes; returns its index.
    pub fn root(&mut self, node: Value) -> usize {
        let i = self.push("nodes", node);
        self.json["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(i));
        i
    }

    /// A material (JSON); returns its index.
    pub fn material(&mut self, m: Value) -> usize {
        self.push("materials", m)
    }

    /// A texture of `img`, embedded as a PNG data URI; returns the texture's index.
    pub fn texture(&mut self, img: &image::RgbaImage) -> usize {
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
        let image = self.push("images", json!({"uri": format!("data:image/png;base64,{}", base64(&png))}));
        self.push("textures", json!({"source": image}))
    }

    /// A `KHR_lights_punctual` light (JSON); returns its index (a node names it with
    /// [`light_node`]).
    pub fn light(&mut self, light: Value) -> usize {
        self.uses("KHR_lights_punctual");
        let root = self.json.as_object_mut().unwrap();
        let lights = root.entry("extensions").or_insert_with(|| json!({})).as_object_mut().unwrap().entry("KHR_lights_punctual").or_insert_with(|| json!({"lights": []}));
        let list = lights["lights"].as_array_mut().unwrap();
        list.push(light);
        list.len() - 1
    }

    /// Lists `ext` in `extensionsUsed`.
    pub fn uses(&mut self, ext: &str) {
        let used = self.json.as_object_mut().unwrap().entry("extensionsUsed").or_insert_with(|| json!([])).as_array_mut().unwrap();
        if !used.iter().any(|e| e == ext) {
            used.push(json!(ext));
        }
    }

    /// The document's JSON text with its buffer described for `buffer`.
    pub fn text(&self, buffer: Buffer) -> String {
        let mut json = self.json.clone();
        let len = self.bin.len();
        json["buffers"] = match buffer {
            Buffer::External(name) => json!([{"byteLength": len, "uri": name}]),
            Buffer::DataUri => json!([{"byteLength": len, "uri": format!("data:application/octet-stream;base64,{}", base64(&self.bin))}]),
            Buffer::Glb => json!([{"byteLength": len}]),
        };
        serde_json::to_string_pretty(&json).unwrap()
    }

    /// Writes the document as `dir/name` (and the external buffer beside it); returns its path.
    pub fn write(&self, dir: &Path, name: &str, buffer: Buffer) -> PathBuf {
        let path = dir.join(name);
        let bytes = match buffer {
            Buffer::Glb => glb(&self.text(buffer), &self.bin),
            Buffer::External(bin) => {
                std::fs::write(dir.join(bin), &self.bin).unwrap();
                self.text(buffer).into_bytes()
            }
            Buffer::DataUri => self.text(buffer).into_bytes(),
        };
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
        path
    }
}

/// A node holding light `light`, placed by `transform` (JSON fields such as `"translation"`).
pub fn light_node(light: usize, mut transform: Value) -> Value {
    transform["extensions"] = json!({"KHR_lights_punctual": {"light": light}});
    transform
}

/// The unit quaternion `[x, y, z, w]` of a rotation by `radians` about `axis`.
pub fn rotation(axis: [f32; 3], radians: f32) -> [f32; 4] {
    glam::Quat::from_axis_angle(glam::Vec3::from(axis).normalize(), radians).to_array()
}

/// A `.glb` container of `json` and `bin` (each chunk padded to 4 bytes).
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    j.resize(j.len().div_ceil(4) * 4, b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().div_ceil(4) * 4, 0);
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    for w in [0x4654_6c67u32, 2, total as u32, j.len() as u32, 0x4e4f_534a] {
        out.extend(w.to_le_bytes());
    }
    out.extend(&j);
    out.extend([b.len() as u32, 0x004e_4942].iter().flat_map(|w| w.to_le_bytes()));
    out.extend(&b);
    out
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            out.push(if k <= c.len() { A[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' });
        }
    }
    out
}
