//! OBJ/MTL files as common exporters write them: Latin-1 material names (older 3ds Max),
//! `newmtl` / `usemtl` with an empty name (Blender), UTF-16 with a byte-order mark (Windows
//! tools), a UTF-8 byte-order mark — each loaded as the UTF-8 original would be, errors still
//! naming file and line.
use super::tests::{assets, load_err, temp::TempDir};
use super::*;

const MTL: &[u8] = b"newmtl Mat\xE9riau\nKd 1 0 0\nnewmtl Mat\xE8re\nKd 0 1 0\nnewmtl\nKd 0 0 1\n";
const OBJ: &[u8] = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl Mat\xE9riau\nf 1 2 3\nusemtl Mat\xE8re\nf 1 3 2\nusemtl\nf 2 1 3\n";

fn utf16(bytes: &[u8], big_endian: bool) -> Vec<u8> {
    let text = text::name(bytes);
    let mut out: Vec<u8> = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
    for u in text.encode_utf16() {
        out.extend(if big_endian { u.to_be_bytes() } else { u.to_le_bytes() });
    }
    out
}

/// (material name, albedo) of each mesh of the loaded OBJ, in file order.
fn meshes_of(dir: &TempDir, obj: &[u8], mtl: &[u8]) -> Vec<(String, [f32; 3])> {
    std::fs::write(dir.0.join("m.mtl"), mtl).unwrap();
    let p = dir.0.join("s.obj");
    std::fs::write(&p, obj).unwrap();
    let s = Scene::load(p.to_str().unwrap(), &assets()).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s.meshes.iter().map(|m| &s.materials[m.material as usize]).map(|m| (m.name.clone(), m.albedo)).collect()
}

#[test]
fn latin1_and_empty_material_names_resolve() {
    let dir = TempDir::new("latin1");
    let got = meshes_of(&dir, OBJ, MTL);
    let want = [("Matériau", [1.0, 0.0, 0.0]), ("Matère", [0.0, 1.0, 0.0]), ("", [0.0, 0.0, 1.0])];
    assert_eq!(got, want.map(|(n, a)| (n.to_owned(), a)));
}

#[test]
fn utf16_and_utf8_byte_order_marks_load_like_utf8() {
    let dir = TempDir::new("utf16");
    let plain = meshes_of(&dir, OBJ, MTL);
    for big_endian in [false, true] {
        assert_eq!(meshes_of(&dir, &utf16(OBJ, big_endian), &utf16(MTL, big_endian)), plain, "UTF-16, big endian {big_endian}");
    }
    let bom = |b: &[u8]| [&[0xEF, 0xBB, 0xBF][..], b].concat();
    let utf8_obj = text::name(OBJ).into_bytes();
    assert_eq!(meshes_of(&dir, &bom(&utf8_obj), &bom(&text::name(MTL).into_bytes())), plain, "UTF-8 with a mark");
    // Errors in a UTF-16 file still name its line.
    let p = dir.0.join("bad.obj");
    std::fs::write(&p, utf16(b"v 0 0 0\r\nv 1 0 0\r\nv 0 zero 0\r\n", false)).unwrap();
    let e = load_err(&p);
    assert!(e.contains("bad.obj line 3: v: \"zero\" is not a number"), "{e}");
}
