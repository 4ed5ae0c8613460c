//! Cooperative-kernel abstraction: one kernel source for the GPU and for `cargo test`.
//!
//! A *cooperative* kernel is one whose invocations talk to each other: subgroup shuffles and
//! ballots, workgroup memory, workgroup barriers. Such code cannot be unit-tested by calling it
//! once per invocation, so every cooperative kernel here is written against two small traits:
//!
//! * [`Coop`] — the invocation's place in its subgroup/workgroup and the subgroup/workgroup
//!   operations. [`gpu::GpuCoop`] maps them 1:1 to SPIR-V (`OpGroupNonUniform*`,
//!   `OpControlBarrier`); [`cpu`] emulates a workgroup with one coroutine per invocation run in
//!   lock-step at every collective operation, with the subgroup width as a parameter (4…64), so
//!   the same kernel is tested at widths the local GPU does not have.
//! * [`SharedU32`] — workgroup memory as an array of `u32`. On the GPU it is the
//!   `#[spirv(workgroup)] &mut [u32; N]` entry parameter itself; on the CPU a handle over
//!   cells shared by the emulated invocations of one workgroup.
//!
//! Rules a cooperative kernel follows (they are also the GPU's rules):
//! 1. Subgroup operations are called in subgroup-uniform control flow: every lane of the subgroup
//!    reaches the same call (the CPU emulation detects a violation and fails the test with a
//!    message naming the subgroup).
//! 2. `workgroup_barrier` is called in workgroup-uniform control flow.
//! 3. Lane numbering comes from the built-ins (`lane()`, `subgroup_id()`), never from
//!    `local_index % width`: Vulkan does not promise that mapping.
//! 4. The workgroup size is a multiple of the subgroup size (the host requests full subgroups).

pub mod gpu;

#[cfg(not(target_arch = "spirv"))]
pub mod cpu;

/// The item (block, piece, cluster, leaf node) of a kernel that gives each item its own
/// subgroup: workgroup index · subgroups per workgroup + subgroup id, the numbering
/// `Recorder::dispatch_subgroups` dispatches for.
#[inline]
pub fn subgroup_item<C: Coop>(c: &C, wg: spirv_std::glam::UVec3, nwg: spirv_std::glam::UVec3) -> u32 {
    (wg.y * nwg.x + wg.x) * c.num_subgroups() + c.subgroup_id()
}

/// Subgroup and workgroup operations of one invocation.
pub trait Coop {
    /// Invocations per subgroup (the SPIR-V `SubgroupSize` built-in).
    fn subgroup_size(&self) -> u32;
    /// This invocation's lane in its subgroup (`SubgroupLocalInvocationId`).
    fn lane(&self) -> u32;
    /// This invocation's subgroup within the workgroup (`SubgroupId`).
    fn subgroup_id(&self) -> u32;
    /// Subgroups in the workgroup (`NumSubgroups`).
    fn num_subgroups(&self) -> u32;
    /// `LocalInvocationIndex`.
    fn local_index(&self) -> u32;
    /// Value of `v` held by lane `src` (must be `< subgroup_size`).
    fn shuffle(&self, v: u32, src: u32) -> u32;
    /// Value of `v` held by lane `lane() ^ mask`.
    fn shuffle_xor(&self, v: u32, mask: u32) -> u32;
    /// Bit `l` of the result is set when lane `l` passed `true` (128 bits: up to 128 lanes).
    fn ballot(&self, pred: bool) -> [u32; 4];
    /// Control barrier + workgroup-memory acquire/release over the whole workgroup.
    fn workgroup_barrier(&self);
    /// Control barrier + workgroup-memory acquire/release over the subgroup: one lane's
    /// workgroup-memory stores before it are seen by the subgroup's other lanes after it (a
    /// shuffle or ballot alone does not order memory).
    fn subgroup_barrier(&self);
    /// The same over storage buffers: one lane's storage-buffer stores before it are seen by
    /// the subgroup's other lanes after it.
    fn subgroup_storage_barrier(&self);
}

/// Workgroup memory seen as `u32` words.
pub trait SharedU32 {
    fn load(&self, i: u32) -> u32;
    fn store(&mut self, i: u32, v: u32);
    /// Adds `v` to word `i` atomically (workgroup scope, relaxed) and returns the old value.
    fn atomic_add(&mut self, i: u32, v: u32) -> u32;
    /// Sets the bits of `v` in word `i` atomically (workgroup scope, relaxed).
    fn atomic_or(&mut self, i: u32, v: u32);
}

impl<const N: usize> SharedU32 for [u32; N] {
    #[inline]
    fn load(&self, i: u32) -> u32 {
        self[i as usize]
    }
    #[inline]
    fn store(&mut self, i: u32, v: u32) {
        self[i as usize] = v;
    }
    /// `OpAtomicIAdd` on the GPU; a plain read-modify-write off it (one thread owns the array).
    #[inline]
    fn atomic_add(&mut self, i: u32, v: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_i_add::<u32, { spirv_std::memory::Scope::Workgroup as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(
                &mut self[i as usize],
                v,
            )
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            let old = self[i as usize];
            self[i as usize] = old.wrapping_add(v);
            old
        }
    }
    /// `OpAtomicOr` on the GPU; a plain read-modify-write off it.
    #[inline]
    fn atomic_or(&mut self, i: u32, v: u32) {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_or::<u32, { spirv_std::memory::Scope::Workgroup as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(&mut self[i as usize], v);
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            self[i as usize] |= v;
        }
    }
}

/// Number of set bits among the lanes below `lane` in a ballot (the "exclusive bit count" used to
/// give each voting lane a dense slot).
#[inline]
pub fn ballot_rank(mask: [u32; 4], lane: u32) -> u32 {
    let mut n = 0;
    unroll4!(w => {
        let lo = w * 32;
        let bits = if lane >= lo + 32 {
            mask[w as usize]
        } else if lane > lo {
            mask[w as usize] & ((1u32 << (lane - lo)) - 1)
        } else {
            0
        };
        n += bits.count_ones();
    });
    n
}

/// The ballot mask of every lane of a subgroup of `width` lanes.
#[inline]
pub fn subgroup_lanes(width: u32) -> [u32; 4] {
    let mut m = [0u32; 4];
    unroll4!(w => {
        let lo = w * 32;
        m[w as usize] = if width >= lo + 32 {
            u32::MAX
        } else if width > lo {
            (1u32 << (width - lo)) - 1
        } else {
            0
        };
    });
    m
}

/// The lowest lane set in a ballot (128 for an empty one).
#[inline]
pub fn ballot_first(mask: [u32; 4]) -> u32 {
    if mask[0] != 0 {
        mask[0].trailing_zeros()
    } else if mask[1] != 0 {
        32 + mask[1].trailing_zeros()
    } else if mask[2] != 0 {
        64 + mask[2].trailing_zeros()
    } else if mask[3] != 0 {
        96 + mask[3].trailing_zeros()
    } else {
        128
    }
}

/// Total set bits of a ballot.
#[inline]
pub fn ballot_count(mask: [u32; 4]) -> u32 {
    mask[0].count_ones() + mask[1].count_ones() + mask[2].count_ones() + mask[3].count_ones()
}
