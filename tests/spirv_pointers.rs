//! Neither SPIR-V module carries a pointer through an `OpPhi` or `OpSelect` (directly, or inside
//! a struct or array) unless it declares a `VariablePointers` capability. Such a value is a
//! variable pointer; Vulkan drivers need not support it, `spirv-val` does not reject it, and a
//! compute module whose shading loops carried a list cursor holding a buffer slice (204 such phis)
//! crashed NVIDIA's pipeline compiler while lavapipe ran it. The loop now carries only integers
//! (`shaders::shading::LightList`); this test keeps it so for every kernel.
mod common;

use common::spirv::{instructions, words, MAGIC};
use std::collections::HashSet;

const OP_CAPABILITY: u32 = 17;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_SELECT: u32 = 169;
const OP_PHI: u32 = 245;
const CAPABILITY_VARIABLE_POINTERS_STORAGE_BUFFER: u32 = 4441;
const CAPABILITY_VARIABLE_POINTERS: u32 = 4442;

/// Result ids of the `OpPhi` / `OpSelect` instructions whose type is a pointer or holds one,
/// unless the module declares a variable-pointers capability.
fn variable_pointers(words: &[u32]) -> Vec<u32> {
    let inst = instructions(words);
    if inst.iter().any(|(op, o)| *op == OP_CAPABILITY && matches!(o[0], CAPABILITY_VARIABLE_POINTERS | CAPABILITY_VARIABLE_POINTERS_STORAGE_BUFFER)) {
        return vec![];
    }
    // Types are declared before use, so one pass finds every type that holds a pointer.
    let mut holds_pointer: HashSet<u32> = HashSet::new();
    for (op, o) in &inst {
        let members: &[u32] = match *op {
            OP_TYPE_POINTER => &[],
            OP_TYPE_STRUCT => &o[1..],
            OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY | OP_TYPE_VECTOR => &o[1..2],
            _ => continue,
        };
        if *op == OP_TYPE_POINTER || members.iter().any(|m| holds_pointer.contains(m)) {
            holds_pointer.insert(o[0]);
        }
    }
    inst.iter().filter(|(op, o)| matches!(*op, OP_PHI | OP_SELECT) && holds_pointer.contains(&o[0])).map(|(_, o)| o[1]).collect()
}


#[test]
fn no_module_carries_a_pointer_through_a_phi() {
    for (name, module) in [("compute", host::gpu::COMPUTE_SPV), ("raster", host::gpu::GRAPHICS_SPV)] {
        let found = variable_pointers(&words(module));
        assert!(found.is_empty(), "the {name} module carries pointers through {} phi/select instructions (first ids {:?})", found.len(), &found[..found.len().min(5)]);
    }
}

/// The scan finds a phi of a struct holding a pointer, and of a pointer, and accepts them once
/// the capability is declared.
#[test]
fn the_scan_finds_variable_pointers() {
    let inst = |op: u32, operands: &[u32]| -> Vec<u32> { [((operands.len() as u32 + 1) << 16) | op].into_iter().chain(operands.iter().copied()).collect() };
    let header = [MAGIC, 0x0001_0600, 0, 100, 0];
    let types = [inst(21, &[1, 32, 0]), inst(OP_TYPE_POINTER, &[2, 12, 1]), inst(OP_TYPE_STRUCT, &[3, 2, 1]), inst(OP_TYPE_STRUCT, &[4, 1, 1])];
    let module = |body: &[Vec<u32>], capability: u32| -> Vec<u32> {
        let mut w = header.to_vec();
        w.extend(inst(OP_CAPABILITY, &[capability]));
        types.iter().chain(body).for_each(|i| w.extend(i));
        w
    };
    let struct_phi = inst(OP_PHI, &[3, 10, 20, 21, 22, 23]);
    let pointer_select = inst(OP_SELECT, &[2, 11, 30, 31, 32]);
    let plain_phi = inst(OP_PHI, &[4, 12, 20, 21, 22, 23]);
    assert_eq!(variable_pointers(&module(&[struct_phi.clone(), pointer_select.clone(), plain_phi.clone()], 1)), vec![10, 11]);
    assert!(variable_pointers(&module(&[plain_phi], 1)).is_empty());
    assert!(variable_pointers(&module(&[struct_phi, pointer_select], CAPABILITY_VARIABLE_POINTERS)).is_empty());
}
