//! Building light lists on the GPU: what several techniques' list building shares. Used by
//! clustered-AABB ([`crate::clustered_aabb`]: active clusters, list reservation), Forward+
//! ([`crate::forward_plus`]: node allocation, linked-list push) and the loop limits of every
//! technique that loops over all lights (naive clustered, BVH walk, tiled).
//!
//! * [`AtomicAdd`], [`AtomicExchange`], [`AtomicMax`] — a storage-buffer word's atomics on the GPU (device
//!   scope, relaxed); a plain read-modify-write off the GPU, or `&AtomicU32` in the emulation.
//! * [`subgroup_reserve`] — subgroup-aggregated slot reservation: one atomic per subgroup.
//! * [`ListSink`] — where list building writes light indices (a storage buffer on the GPU, a
//!   recording buffer in the CPU tests).
//! * [`lights_meeting`] — the lights passing a test, in index order, [`LIGHTS_PER_ITERATION`] per
//!   loop iteration (naive clustered assignment; the brute-force heatmap).
//! * [`MAX_LIGHTS_PER_INVOCATION_LLVMPIPE`] — llvmpipe's loop limiter as a light count.
use crate::coop::{ballot_count, ballot_first, Coop};
use crate::layout::PointLight;
use crate::scan::subgroup_inclusive_scan;
use glam::Vec3;

/// Lights [`lights_meeting`] tests per loop iteration. llvmpipe (lavapipe) stops an invocation's
/// loops after 65 535 iterations in all (its loop limiter) and silently drops the rest;
/// straight-line unrolling by 8 lets one invocation visit [`MAX_LIGHTS_PER_INVOCATION_LLVMPIPE`]
/// lights there.
pub const LIGHTS_PER_ITERATION: u32 = 8;

/// The most lights one invocation may loop over on llvmpipe (the host refuses more there):
/// llvmpipe stops an invocation's loops after 65 535 iterations in all and silently drops the
/// rest. Naive loops take `N/8` iterations, a BVH walk that meets every light `N/8 + N/32 +
/// N/1024 + …` ≈ 0.157·N, the shading loop `N/16` (`N/8` over index ranges): all under 65 535
/// for N ≤ 400 000.
pub const MAX_LIGHTS_PER_INVOCATION_LLVMPIPE: u32 = 400_000;

/// Lights `0..n` that `keep(lights, index, light)`, in index order, [`LIGHTS_PER_ITERATION`] per
/// loop iteration: calls `emit(k, light)` for the `k`-th and returns the count. `keep` gets the
/// light buffer as an argument rather than capturing it: a closure that holds a slice keeps the
/// binding's length in its captures on the GPU (`tests/spirv_lengths.rs`).
#[inline]
pub fn lights_kept(effects: u32, n: u32, lights: &[PointLight], mut emit: impl FnMut(u32, u32), keep: impl Fn(&[PointLight], u32, &PointLight) -> bool) -> u32 {
    let mut found = 0;
    let mut base = 0;
    while base < n {
        unroll8!(u => {
            let l = base + u;
            if l < n {
                let light = crate::compact_light::light_at(lights, effects, n, l);
                if keep(lights, l, &light) {
                    emit(found, l);
                    found += 1;
                }
            }
        });
        base += LIGHTS_PER_ITERATION;
    }
    found
}

/// Lights `0..n` passing `test(centre, radius)` ([`lights_kept`]).
#[inline]
pub fn lights_meeting(effects: u32, n: u32, lights: &[PointLight], emit: impl FnMut(u32, u32), test: impl Fn(Vec3, f32) -> bool) -> u32 {
    lights_kept(effects, n, lights, emit, move |_, _, light| test(Vec3::from_array(light.position), light.radius))
}

/// [`lights_meeting`] in a frame with spot lights: a light passes `test` and its cone may meet
/// the sphere `(c, r)` bounding the region tested (`light_types::spot_may_meet`).
#[inline]
pub fn lights_meeting_spots(effects: u32, n: u32, lights: &[PointLight], emit: impl FnMut(u32, u32), test: impl Fn(Vec3, f32) -> bool, c: Vec3, r: f32) -> u32 {
    lights_kept(effects, n, lights, emit, move |lights, l, light| test(Vec3::from_array(light.position), light.radius) && crate::light_types::spot_may_meet(effects, lights, n, l, c, r))
}

/// A global counter that hands out slots (`fetch_add` returns the old value).
pub trait AtomicAdd {
    fn fetch_add(&mut self, v: u32) -> u32;
}

/// A storage-buffer word: `OpAtomicIAdd` (device scope, relaxed) on the GPU. Off the GPU a plain
/// add (sequential use only; the CPU emulation uses `&AtomicU32`).
impl AtomicAdd for u32 {
    #[inline]
    fn fetch_add(&mut self, v: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_i_add::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(self, v)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            let old = *self;
            *self = old.wrapping_add(v);
            old
        }
    }
}

#[cfg(not(target_arch = "spirv"))]
impl AtomicAdd for &std::sync::atomic::AtomicU32 {
    fn fetch_add(&mut self, v: u32) -> u32 {
        std::sync::atomic::AtomicU32::fetch_add(self, v, std::sync::atomic::Ordering::Relaxed)
    }
}

/// A word that can be swapped atomically (`OpAtomicExchange`, device scope, relaxed, on the GPU;
/// plain off the GPU, `&AtomicU32` in the emulation).
pub trait AtomicExchange {
    fn exchange(&mut self, v: u32) -> u32;
}

impl AtomicExchange for u32 {
    #[inline]
    fn exchange(&mut self, v: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_exchange::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(self, v)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            core::mem::replace(self, v)
        }
    }
}

#[cfg(not(target_arch = "spirv"))]
impl AtomicExchange for &std::sync::atomic::AtomicU32 {
    fn exchange(&mut self, v: u32) -> u32 {
        std::sync::atomic::AtomicU32::swap(self, v, std::sync::atomic::Ordering::Relaxed)
    }
}

/// A word that can be raised atomically (`OpAtomicUMax`, device scope, relaxed, on the GPU;
/// plain off the GPU).
pub trait AtomicMax {
    fn fetch_max(&mut self, v: u32) -> u32;
}

impl AtomicMax for u32 {
    #[inline]
    fn fetch_max(&mut self, v: u32) -> u32 {
        #[cfg(target_arch = "spirv")]
        unsafe {
            spirv_std::arch::atomic_u_max::<u32, { spirv_std::memory::Scope::Device as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(self, v)
        }
        #[cfg(not(target_arch = "spirv"))]
        {
            let old = *self;
            *self = old.max(v);
            old
        }
    }
}

/// Subgroup-aggregated reservation: every lane asks for `n` consecutive slots of `counter` and
/// gets the first. A ballot of the lanes that want any elects the lowest as leader; an inclusive
/// scan of `n` over the subgroup gives each lane its offset and the total; the leader alone does
/// one atomic add of the total; a shuffle broadcasts the base. A subgroup that wants nothing does
/// no atomic. Lanes asking for 0 get an unspecified slot. Subgroup-uniform control flow.
#[inline]
pub fn subgroup_reserve<C: Coop, A: AtomicAdd + ?Sized>(c: &C, counter: &mut A, n: u32) -> u32 {
    let want = c.ballot(n > 0);
    if ballot_count(want) == 0 {
        return 0;
    }
    let leader = ballot_first(want);
    let inclusive = subgroup_inclusive_scan(c, n);
    let total = c.shuffle(inclusive, c.subgroup_size() - 1);
    let mut base = 0;
    if c.lane() == leader {
        base = counter.fetch_add(total);
    }
    c.shuffle(base, leader).wrapping_add(inclusive - n)
}

/// Where list building writes light indices (a storage buffer on the GPU).
pub trait ListSink {
    fn put(&mut self, i: u32, light: u32);
}

impl ListSink for [u32] {
    #[inline]
    fn put(&mut self, i: u32, light: u32) {
        self[i as usize] = light;
    }
}

#[cfg(test)]
#[path = "light_lists_tests.rs"]
mod tests;
