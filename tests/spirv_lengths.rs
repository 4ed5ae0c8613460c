//! No kernel reads the length of the light buffer or of the light BVH's sorted spheres
//! (`OpArrayLength` on a binding named `lights` or `spheres`). NVIDIA's driver reads a binding of
//! 2^31 bytes or more as empty through its length (`docs/results/h200/light-buffer-boundary/`),
//! and these two buffers may take the device's whole `maxStorageBufferRange`
//! (`vk::Buffer::length_free`: up to 4 GiB − 1, 2^28 − 4 compact lights), so the kernels index
//! them by the frame's light count (`shaders::compact_light::light_at`, `shaders::unchecked`),
//! never by the binding's length. rust-gpu's checked `slice[i]` reads the length too, so this
//! test also catches a bounds-checked index into either buffer.
mod common;

use common::spirv::{instructions, string, words, MAGIC};
use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_ACCESS_CHAIN: u32 = 65;
const OP_IN_BOUNDS_ACCESS_CHAIN: u32 = 66;
const OP_ARRAY_LENGTH: u32 = 68;
const OP_COPY_OBJECT: u32 = 83;
const OP_COMPOSITE_CONSTRUCT: u32 = 80;

/// The bindings whose length no kernel may read.
const LENGTH_FREE: [&str; 2] = ["lights", "spheres"];

/// The names of the variables whose length the module reads: each `OpArrayLength` whose value
/// is used ([`live`]), its structure operand followed through access chains and copies to its
/// variable, named by `OpName` (`"?"` where it has none). Also the number of named variables.
fn lengths_read(words: &[u32]) -> (Vec<String>, usize) {
    let inst = instructions(words);
    let live = live(&inst);
    let names: HashMap<u32, String> = inst.iter().filter(|(op, _)| *op == OP_NAME).map(|(_, o)| (o[0], string(&o[1..]).0)).collect();
    // Result id → the pointer it was derived from.
    let base: HashMap<u32, u32> = inst
        .iter()
        .filter(|(op, _)| matches!(*op, OP_ACCESS_CHAIN | OP_IN_BOUNDS_ACCESS_CHAIN | OP_COPY_OBJECT))
        .map(|(_, o)| (o[1], o[2]))
        .collect();
    let root = |mut id: u32| {
        while let Some(&b) = base.get(&id) {
            id = b;
        }
        id
    };
    let read = inst.iter().filter(|(op, o)| *op == OP_ARRAY_LENGTH && live(o[1])).map(|(_, o)| names.get(&root(o[2])).cloned().unwrap_or_else(|| "?".into())).collect();
    (read, names.len())
}

/// Whether a result id's value is used: by any instruction but `OpCompositeConstruct`, or by a
/// composite that is itself used. rust-gpu builds each slice parameter as a (pointer, length)
/// pair at the entry, and spirv-opt may leave such a pair — or a closure's captures holding
/// one — built and never read; no driver computes a value nothing reads. Operands: from the
/// third word for instructions with a result type and id, every word of those without that
/// take values first (stores, copies, branches, returns, image writes), none of names and
/// decorations. Conservative: an operand word equal to the id counts as a use even where it is a
/// literal.
fn live(inst: &[(u32, &[u32])]) -> impl Fn(u32) -> bool {
    const OP_MEMBER_NAME: u32 = 6;
    const OP_DECORATE: u32 = 71;
    const OP_MEMBER_DECORATE: u32 = 72;
    const VALUES_FIRST: [u32; 6] = [62, 63, 99, 250, 251, 254]; // OpStore, OpCopyMemory, OpImageWrite, OpBranchConditional, OpSwitch, OpReturnValue
    // Id → the (opcode, result id) of each instruction with it among its operands.
    let mut users: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    for (op, o) in inst {
        let first = match *op {
            OP_NAME | OP_MEMBER_NAME | OP_DECORATE | OP_MEMBER_DECORATE => o.len(),
            op if VALUES_FIRST.contains(&op) => 0,
            _ => 2,
        };
        let result = if *op == OP_COMPOSITE_CONSTRUCT { o[1] } else { 0 };
        for &w in o.iter().skip(first) {
            users.entry(w).or_default().push((*op, result));
        }
    }
    move |id| {
        let mut todo = vec![id];
        let mut seen = std::collections::HashSet::new();
        while let Some(v) = todo.pop() {
            if !seen.insert(v) {
                continue;
            }
            for &(op, result) in users.get(&v).map(Vec::as_slice).unwrap_or(&[]) {
                if op != OP_COMPOSITE_CONSTRUCT {
                    return true;
                }
                todo.push(result);
            }
        }
        false
    }
}


#[test]
fn no_kernel_reads_the_length_of_the_light_buffers() {
    for (name, module) in [("compute", host::gpu::COMPUTE_SPV), ("raster", host::gpu::GRAPHICS_SPV)] {
        let w = words(module);
        let (read, named) = lengths_read(&w);
        let bad: Vec<&String> = read.iter().filter(|n| LENGTH_FREE.contains(&n.as_str())).collect();
        assert!(bad.is_empty(), "the {name} module reads the length of {} binding(s) that may pass 2^31 bytes: {:?}", bad.len(), &bad[..bad.len().min(8)]);
        // The scan sees the module: it names the light bindings and reads other lengths.
        assert!(named > 20 && instructions(&w).iter().any(|(op, o)| *op == OP_NAME && string(&o[1..]).0 == "lights"), "{name}: no binding named lights");
        if name == "compute" {
            assert!(read.iter().any(|n| n == "depth"), "compute: no length read of the depth buffer found ({} reads)", read.len());
        }
    }
}

/// The scan follows an access chain to its variable and names it, and counts a length that
/// reaches only composites nothing reads as unread (one read through a used composite counts).
#[test]
fn the_scan_names_the_variable_whose_length_is_read() {
    let inst = |op: u32, operands: &[u32]| -> Vec<u32> { [((operands.len() as u32 + 1) << 16) | op].into_iter().chain(operands.iter().copied()).collect() };
    let name = |id: u32, s: &str| {
        let mut bytes = s.as_bytes().to_vec();
        bytes.resize(s.len() / 4 * 4 + 4, 0);
        let mut o = vec![id];
        o.extend(bytes.chunks(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])));
        inst(OP_NAME, &o)
    };
    let mut w = vec![MAGIC, 0x0001_0600, 0, 100, 0];
    let used = |id: u32| inst(OP_COPY_OBJECT + 1000, &[2, id + 100, id]);
    let body = [
        name(10, "lights"),
        name(11, "depth"),
        name(13, "spheres"),
        inst(OP_ACCESS_CHAIN, &[1, 20, 10]),
        inst(OP_ARRAY_LENGTH, &[2, 21, 20, 0]),
        used(21),
        inst(OP_ARRAY_LENGTH, &[2, 22, 11, 0]),
        used(22),
        inst(OP_ARRAY_LENGTH, &[2, 23, 12, 0]),
        inst(OP_COMPOSITE_CONSTRUCT, &[3, 30, 23]),
        inst(OP_COMPOSITE_CONSTRUCT, &[3, 31, 30]),
        used(31),
        // A length of `spheres` built into a pair nothing reads.
        inst(OP_ARRAY_LENGTH, &[2, 24, 13, 0]),
        inst(OP_COMPOSITE_CONSTRUCT, &[3, 32, 24]),
    ];
    body.iter().for_each(|i| w.extend(i));
    assert_eq!(lengths_read(&w), (vec!["lights".to_string(), "depth".to_string(), "?".to_string()], 3));
}
