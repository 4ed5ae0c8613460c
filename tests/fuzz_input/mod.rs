//! Fuzz inputs: structure-aware mutations of seed files (see `tests/fuzz.rs`), as proptest
//! strategies. A mutation list shrinks to its fewest, simplest mutations.
use proptest::prelude::*;

/// Largest mutated input (bytes).
pub const MAX_INPUT: usize = 1 << 20;

/// Numbers that break loaders: non-finite, beyond f32, at integer boundaries, negative, tiny.
pub const NUMBERS: &[&str] = &[
    "nan", "NaN", "-nan", "inf", "-inf", "infinity", "1e30", "-1e30", "1e39", "-1e39", "3.4e38", "3.5e38", "1e-45", "1e-300", "-0", "0",
    "0.0", "1", "-1", "2", "3", "65535", "65536", "4000000000", "4294967296", "2147483647", "2147483648", "-2147483648", "-2147483649",
    "9223372036854775807", "9223372036854775808", "-9223372036854775808", "18446744073709551616", "67108865", "1e", "0x10", "1_000",
    "+5", ".5", "5.", "--1",
];

/// Format words, separators, odd bytes and paths (devices, missing files, escapes).
pub const TOKENS: &[&str] = &[
    "\n", "\r\n", "\r", " ", "\t", "#", "/", "//", "\\", "\0", "\u{feff}", "\u{ff}", "é", "v", "vt", "vn", "f", "o", "g", "s", "l",
    "usemtl", "mtllib", "newmtl", "Kd", "Ks", "Ns", "d", "Tr", "-halo", "illum", "map_Kd", "map_d", "-bm", "geometry", "name",
    "[camera]", "[lights]", "[[light]]", "[[material]]", "opacity", "albedo", "mtl_d_zero_is_opaque", "[effects]", "position",
    "target", "up", "fov_y", "near", "far", "count", "distribution", "seed", "radius", "intensity", "clusters", "offset", "colour",
    "specular", "textures", "alpha_test", "uniform", "hotspots", "surfaces", "city", "corridor", "glass", "nurbs", "sponza", "bunny", "=",
    "[[nurbs]]", "degree_u", "degree_v", "size_u", "size_v", "control_points", "weights", "knots_u", "knots_v", "level",
    "\"", "'", "[", "]", "{", "}", ",", "true", "/dev/zero", "/dev/urandom", "/proc/self/mem", "../", "missing.png", "missing.mtl",
    "../textures/albedo.png", "../textures/truncated.png", "../obj/cube.obj", "/dev/zero.obj", "../mtl/valid.mtl",
    "fuzz-input.obj", "fuzz-input.toml",
    // Light types in descriptions.
    "type", "\"point\"", "\"spot\"", "\"directional\"", "direction", "inner_angle", "outer_angle", "spot_fraction",
    // glTF: keys, enums and containers.
    "\"asset\"", "\"version\"", "\"2.0\"", "\"scene\"", "\"scenes\"", "\"nodes\"", "\"mesh\"", "\"meshes\"", "\"primitives\"",
    "\"attributes\"", "\"POSITION\"", "\"NORMAL\"", "\"TEXCOORD_0\"", "\"indices\"", "\"mode\"", "\"accessors\"",
    "\"bufferView\"", "\"bufferViews\"", "\"byteOffset\"", "\"byteLength\"", "\"byteStride\"", "\"componentType\"", "\"count\"",
    "\"VEC3\"", "\"SCALAR\"", "5126", "5123", "5125", "5121", "\"buffers\"", "\"uri\"", "\"data:application/octet-stream;base64,\"",
    "\"quad.bin\"", "\"matrix\"", "\"scale\"", "\"rotation\"", "\"translation\"", "\"children\"", "\"camera\"", "\"cameras\"",
    "\"yfov\"", "\"znear\"", "\"zfar\"", "\"materials\"", "\"alphaMode\"", "\"BLEND\"", "\"MASK\"", "\"alphaCutoff\"",
    "\"baseColorFactor\"", "\"extensions\"", "\"extensionsRequired\"", "\"KHR_lights_punctual\"", "\"light\"", "\"lights\"",
    "\"range\"", "\"spot\"", "\"innerConeAngle\"", "\"outerConeAngle\"", "\"KHR_draco_mesh_compression\"", "null", "glTF", "JSON", "BIN\0",
];

/// A choice among `len` things, shrinking towards the first.
#[derive(Clone, Copy, Debug)]
pub struct Pick(pub u64);

impl Pick {
    pub fn index(self, len: usize) -> usize {
        assert!(len > 0);
        ((len as u128 * self.0 as u128) >> 64) as usize
    }
}

pub fn pick() -> impl Strategy<Value = Pick> {
    any::<u64>().prop_map(Pick)
}

#[derive(Clone, Debug)]
pub enum Mutation {
    FlipBit(Pick, u8),
    SetByte(Pick, u8),
    InsertToken(Pick, Pick),
    ReplaceNumber(Pick, Pick),
    DeleteLine(Pick),
    DuplicateLine(Pick, u8),
    SwapLines(Pick, Pick),
    /// A line of another seed of the same kind, inserted before a line.
    SpliceLine(Pick, Pick, Pick),
    Truncate(Pick),
    LongWord(Pick, u16),
    Crlf,
    InsertBytes(Pick, Vec<u8>),
}

/// Byte spans of the number-like words (digits with signs, dots, exponents; `nan`, `inf`).
pub fn number_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let is_num = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E');
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if is_num(b[i]) || b[i..].starts_with(b"nan") || b[i..].starts_with(b"inf") {
            let start = i;
            while i < b.len() && (is_num(b[i]) || b[i].is_ascii_alphabetic()) {
                i += 1;
            }
            i = i.max(start + 1);
            if b[start..i].iter().any(|c| c.is_ascii_digit()) || b[start..i].starts_with(b"nan") || b[start..i].starts_with(b"inf") {
                spans.push((start, i));
            }
        } else {
            i += 1;
        }
    }
    spans
}

/// Line spans (each including its `\n`).
pub fn line_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            spans.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < b.len() {
        spans.push((start, b.len()));
    }
    spans
}

pub fn mutate(mut b: Vec<u8>, m: &Mutation, others: &[(String, Vec<u8>)]) -> Vec<u8> {
    let pos = |i: &Pick, len: usize| i.index(len + 1);
    match m {
        Mutation::FlipBit(i, bit) if !b.is_empty() => {
            let k = i.index(b.len());
            b[k] ^= 1 << (bit % 8);
        }
        Mutation::SetByte(i, v) if !b.is_empty() => {
            let k = i.index(b.len());
            b[k] = *v;
        }
        Mutation::InsertToken(i, t) => {
            let at = pos(i, b.len());
            b.splice(at..at, TOKENS[t.index(TOKENS.len())].bytes());
        }
        Mutation::ReplaceNumber(i, n) => {
            let spans = number_spans(&b);
            if !spans.is_empty() {
                let (s, e) = spans[i.index(spans.len())];
                b.splice(s..e, NUMBERS[n.index(NUMBERS.len())].bytes());
            }
        }
        Mutation::DeleteLine(i) => {
            let l = line_spans(&b);
            if !l.is_empty() {
                let (s, e) = l[i.index(l.len())];
                b.drain(s..e);
            }
        }
        Mutation::DuplicateLine(i, times) => {
            let l = line_spans(&b);
            if !l.is_empty() {
                let (s, e) = l[i.index(l.len())];
                let line = b[s..e].to_vec();
                for _ in 0..*times {
                    b.splice(e..e, line.iter().copied());
                }
            }
        }
        Mutation::SwapLines(i, j) => {
            let l = line_spans(&b);
            if l.len() >= 2 {
                let (a, c) = (l[i.index(l.len())], l[j.index(l.len())]);
                let (first, second) = if a.0 <= c.0 { (a, c) } else { (c, a) };
                if first != second {
                    let mut out = b[..first.0].to_vec();
                    out.extend_from_slice(&b[second.0..second.1]);
                    out.extend_from_slice(&b[first.1..second.0]);
                    out.extend_from_slice(&b[first.0..first.1]);
                    out.extend_from_slice(&b[second.1..]);
                    b = out;
                }
            }
        }
        Mutation::SpliceLine(seed, line, at) => {
            let other = &others[seed.index(others.len())].1;
            let l = line_spans(other);
            if !l.is_empty() {
                let (s, e) = l[line.index(l.len())];
                let lines = line_spans(&b);
                let at = if lines.is_empty() { 0 } else { lines[at.index(lines.len())].0 };
                b.splice(at..at, other[s..e].iter().copied());
            }
        }
        Mutation::Truncate(i) => {
            let k = pos(i, b.len());
            b.truncate(k);
        }
        Mutation::LongWord(i, len) => {
            let at = pos(i, b.len());
            let word = if len % 2 == 0 { b'9' } else { b'x' };
            b.splice(at..at, std::iter::repeat_n(word, *len as usize));
        }
        Mutation::Crlf => {
            b = b.iter().flat_map(|&c| if c == b'\n' { vec![b'\r', b'\n'] } else { vec![c] }).collect();
        }
        Mutation::InsertBytes(i, bytes) => {
            let at = pos(i, b.len());
            b.splice(at..at, bytes.iter().copied());
        }
        _ => {}
    }
    b.truncate(MAX_INPUT);
    b
}

pub fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => (pick(), any::<u8>()).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        1 => (pick(), any::<u8>()).prop_map(|(i, b)| Mutation::SetByte(i, b)),
        3 => (pick(), pick()).prop_map(|(i, t)| Mutation::InsertToken(i, t)),
        4 => (pick(), pick()).prop_map(|(i, n)| Mutation::ReplaceNumber(i, n)),
        1 => pick().prop_map(Mutation::DeleteLine),
        1 => (pick(), 1u8..40).prop_map(|(i, t)| Mutation::DuplicateLine(i, t)),
        1 => (pick(), pick()).prop_map(|(i, j)| Mutation::SwapLines(i, j)),
        2 => (pick(), pick(), pick()).prop_map(|(s, l, a)| Mutation::SpliceLine(s, l, a)),
        1 => pick().prop_map(Mutation::Truncate),
        1 => (pick(), 0u16..20000).prop_map(|(i, l)| Mutation::LongWord(i, l)),
        1 => Just(Mutation::Crlf),
        1 => (pick(), proptest::collection::vec(any::<u8>(), 1..16)).prop_map(|(i, b)| Mutation::InsertBytes(i, b)),
    ]
}

/// A fuzz input: a seed (a valid one, or any) with mutations, or arbitrary bytes.
#[derive(Clone, Debug)]
pub enum Input {
    Seed { valid_only: bool, seed: Pick, mutations: Vec<Mutation> },
    Raw(Vec<u8>),
}

pub fn input() -> impl Strategy<Value = Input> {
    let seed = |valid_only: bool, mutations: std::ops::Range<usize>| {
        (pick(), proptest::collection::vec(mutation(), mutations)).prop_map(move |(seed, mutations)| Input::Seed { valid_only, seed, mutations })
    };
    prop_oneof![
        5 => seed(true, 0..3),
        2 => seed(true, 3..10),
        2 => seed(false, 0..4),
        1 => proptest::collection::vec(any::<u8>(), 0..512).prop_map(Input::Raw),
    ]
}

pub fn bytes_of(input: &Input, seeds: &[(String, Vec<u8>)]) -> Vec<u8> {
    match input {
        Input::Raw(b) => b.clone(),
        Input::Seed { valid_only, seed, mutations } => {
            let pool: Vec<&(String, Vec<u8>)> = seeds.iter().filter(|s| !valid_only || !s.0.starts_with("bad-")).collect();
            mutations.iter().fold(pool[seed.index(pool.len())].1.clone(), |b, m| mutate(b, m, seeds))
        }
    }
}
