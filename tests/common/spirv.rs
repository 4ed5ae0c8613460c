//! SPIR-V modules read for tests (SPIR-V specification §2.3 physical layout, §3 opcodes): a
//! module's words and instructions, and its entry points — name, execution model, local size,
//! and the descriptor bindings of the storage buffers in each entry's interface (since SPIR-V 1.4
//! the interface lists every global variable the entry uses).
use std::collections::HashMap;

pub const MAGIC: u32 = 0x0723_0203;
const OP_ENTRY_POINT: u32 = 15;
const OP_EXECUTION_MODE: u32 = 16;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const MODE_LOCAL_SIZE: u32 = 17;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
const STORAGE_CLASS_STORAGE_BUFFER: u32 = 12;

/// Execution models.
pub const VERTEX: u32 = 0;
pub const FRAGMENT: u32 = 4;
pub const GL_COMPUTE: u32 = 5;

#[derive(Debug)]
pub struct EntryPoint {
    pub name: String,
    pub model: u32,
    /// `LocalSize` (compute entries).
    pub local_size: Option<[u32; 3]>,
    /// `(set, binding)` of every storage buffer the entry uses, sorted.
    pub storage_buffers: Vec<(u32, u32)>,
}

/// The little-endian words of a module's bytes.
pub fn words(module: &[u8]) -> Vec<u32> {
    assert!(module.len().is_multiple_of(4) && module.len() >= 20, "not a SPIR-V module ({} bytes)", module.len());
    module.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

/// The instructions of a module as `(opcode, operands)`; panics on a malformed module.
pub fn instructions(words: &[u32]) -> Vec<(u32, &[u32])> {
    assert!(words.len() >= 5 && words[0] == MAGIC, "not a SPIR-V module");
    let mut out = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        assert!(count > 0 && at + count <= words.len(), "truncated instruction at word {at}");
        out.push((words[at] & 0xffff, &words[at + 1..at + count]));
        at += count;
    }
    out
}

/// Every entry point of `module`; panics on a malformed module.
pub fn entry_points(module: &[u8]) -> Vec<EntryPoint> {
    let words = words(module);
    let mut entries: Vec<(u32, EntryPoint, Vec<u32>)> = Vec::new();
    let mut local_size: HashMap<u32, [u32; 3]> = HashMap::new();
    let mut storage_buffers: Vec<u32> = Vec::new();
    let (mut sets, mut bindings): (HashMap<u32, u32>, HashMap<u32, u32>) = Default::default();
    for (opcode, ops) in instructions(&words) {
        match opcode {
            OP_ENTRY_POINT => {
                let (name, rest) = string(&ops[2..]);
                entries.push((ops[1], EntryPoint { name, model: ops[0], local_size: None, storage_buffers: vec![] }, rest.to_vec()));
            }
            OP_EXECUTION_MODE if ops[1] == MODE_LOCAL_SIZE => {
                local_size.insert(ops[0], [ops[2], ops[3], ops[4]]);
            }
            OP_VARIABLE if ops[2] == STORAGE_CLASS_STORAGE_BUFFER => storage_buffers.push(ops[1]),
            OP_DECORATE if ops[1] == DECORATION_DESCRIPTOR_SET => {
                sets.insert(ops[0], ops[2]);
            }
            OP_DECORATE if ops[1] == DECORATION_BINDING => {
                bindings.insert(ops[0], ops[2]);
            }
            _ => {}
        }
    }
    entries
        .into_iter()
        .map(|(function, mut e, interface)| {
            e.local_size = local_size.get(&function).copied();
            e.storage_buffers = interface
                .iter()
                .filter(|id| storage_buffers.contains(id))
                .map(|id| {
                    let undecorated = |what| panic!("{}: storage buffer %{id} has no {what}", e.name);
                    (*sets.get(id).unwrap_or_else(|| undecorated("descriptor set")), *bindings.get(id).unwrap_or_else(|| undecorated("binding")))
                })
                .collect();
            e.storage_buffers.sort_unstable();
            e
        })
        .collect()
}

/// A literal string (UTF-8, NUL-terminated, padded to whole words) and the words after it.
pub fn string(words: &[u32]) -> (String, &[u32]) {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let len = bytes.iter().position(|&b| b == 0).expect("unterminated SPIR-V string");
    (String::from_utf8(bytes[..len].to_vec()).expect("UTF-8 SPIR-V string"), &words[len / 4 + 1..])
}
