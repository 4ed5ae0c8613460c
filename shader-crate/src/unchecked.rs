//! Element access for the hot loops: no bounds check in the compiled kernels, a checked index on
//! the CPU.
//!
//! rust-gpu compiles `slice[i]` to a compare and a branch out of the invocation per access,
//! and the driver keeps them. In the loops that run per light or per BVH node they were a
//! measurable share of the work: on the H200 (Sponza 1080p, `clustered-bvh`, 10k lights) the
//! assignment went from 0.073 to 0.066 ms (64 → 48 registers) without the checks of the node
//! loads and from 0.079 to 0.074 without those of the leaf's spheres and light indices, and the
//! shading from 0.153 to 0.146 without those of the list entry and its light.
//!
//! Every caller states why its index is in bounds (an `In bounds` comment at the call, or a
//! guard: [`crate::shading::list_range`] is empty unless its range lies inside the buffer, and
//! the light loop reads `min(l, len − 1)`). The CPU build of the same functions — what every
//! unit test and CPU reference runs — keeps the check, so an index out of bounds is a test
//! failure there, never undefined behaviour.

/// `s[i]`, unchecked on the GPU. The caller guarantees `i < s.len()`.
#[inline]
pub fn at<T: Copy>(s: &[T], i: u32) -> T {
    #[cfg(target_arch = "spirv")]
    {
        // SAFETY: the caller guarantees `i < s.len()` (module docs); the CPU build checks it.
        unsafe { *spirv_std::arch::IndexUnchecked::index_unchecked(s, i as usize) }
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        s[i as usize]
    }
}

/// `&s[i]`, unchecked on the GPU. The caller guarantees `i < s.len()`.
#[inline]
pub fn get<T>(s: &[T], i: u32) -> &T {
    #[cfg(target_arch = "spirv")]
    {
        // SAFETY: as in `at`.
        unsafe { spirv_std::arch::IndexUnchecked::index_unchecked(s, i as usize) }
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        &s[i as usize]
    }
}

/// `s[i] = v`, unchecked on the GPU. The caller guarantees `i < s.len()`.
#[inline]
pub fn set<T>(s: &mut [T], i: u32, v: T) {
    #[cfg(target_arch = "spirv")]
    {
        // SAFETY: as in `at`.
        unsafe { *spirv_std::arch::IndexUnchecked::index_unchecked_mut(s, i as usize) = v }
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        s[i as usize] = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// In bounds both read the element; out of bounds the CPU build panics (the check the
    /// GPU build leaves out is kept for every test).
    #[test]
    fn reads_in_bounds_and_the_cpu_build_checks() {
        let v = [1u32, 2, 3];
        assert_eq!((at(&v, 0), at(&v, 2), *get(&v, 1)), (1, 3, 2));
        assert!(std::panic::catch_unwind(|| at(&v, 3)).is_err());
        assert!(std::panic::catch_unwind(|| *get(&v, u32::MAX)).is_err());
    }
}
