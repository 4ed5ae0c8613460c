//! [`Coop`] on the GPU: each method is one SPIR-V instruction (spirv-std intrinsic).
//! Compiles on the CPU too (entry points are plain functions there) but must not be called there:
//! spirv-std's `gpu_only` intrinsics panic off the GPU.
use super::Coop;
use spirv_std::memory::Semantics;

/// Built-ins of one invocation, unpacked by the `#[spirv]` entry point.
#[derive(Clone, Copy)]
pub struct GpuCoop {
    pub subgroup_size: u32,
    pub lane: u32,
    pub subgroup_id: u32,
    pub num_subgroups: u32,
    pub local_index: u32,
}

impl Coop for GpuCoop {
    #[inline]
    fn subgroup_size(&self) -> u32 {
        self.subgroup_size
    }
    #[inline]
    fn lane(&self) -> u32 {
        self.lane
    }
    #[inline]
    fn subgroup_id(&self) -> u32 {
        self.subgroup_id
    }
    #[inline]
    fn num_subgroups(&self) -> u32 {
        self.num_subgroups
    }
    #[inline]
    fn local_index(&self) -> u32 {
        self.local_index
    }
    #[inline]
    fn shuffle(&self, v: u32, src: u32) -> u32 {
        spirv_std::arch::subgroup_shuffle(v, src)
    }
    #[inline]
    fn shuffle_xor(&self, v: u32, mask: u32) -> u32 {
        spirv_std::arch::subgroup_shuffle_xor(v, mask)
    }
    #[inline]
    fn ballot(&self, pred: bool) -> [u32; 4] {
        let m = spirv_std::arch::subgroup_ballot(pred);
        [m.x, m.y, m.z, m.w]
    }
    #[inline]
    fn workgroup_barrier(&self) {
        spirv_std::arch::workgroup_memory_barrier_with_group_sync();
    }
    #[inline]
    fn subgroup_barrier(&self) {
        subgroup_barrier_over::<{ Semantics::WORKGROUP_MEMORY.bits() | Semantics::ACQUIRE_RELEASE.bits() }>();
    }
    #[inline]
    fn subgroup_storage_barrier(&self) {
        subgroup_barrier_over::<{ Semantics::UNIFORM_MEMORY.bits() | Semantics::ACQUIRE_RELEASE.bits() }>();
    }
}

/// Control barrier over the subgroup with memory semantics `SEMANTICS` (acquire/release of
/// workgroup or of uniform memory): [`Coop::subgroup_barrier`] and
/// [`Coop::subgroup_storage_barrier`].
#[inline]
fn subgroup_barrier_over<const SEMANTICS: u32>() {
    use spirv_std::memory::Scope;
    spirv_std::arch::control_barrier::<{ Scope::Subgroup as u32 }, { Scope::Subgroup as u32 }, SEMANTICS>();
}
