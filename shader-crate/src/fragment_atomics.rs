//! Atomics on storage-buffer words from fragment shaders (the raster module): queue-family scope
//! (the raster module has no device-scope capability), relaxed. Off the GPU plain operations, for
//! the CPU tests of the passes that use them.

/// `fetch_add` on a storage-buffer word.
#[inline]
pub fn atomic_add(word: &mut u32, v: u32) -> u32 {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_i_add::<u32, { spirv_std::memory::Scope::QueueFamily as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v)
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        let old = *word;
        *word = old.wrapping_add(v);
        old
    }
}

/// Exchange of a storage-buffer word.
#[inline]
pub fn atomic_exchange(word: &mut u32, v: u32) -> u32 {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_exchange::<u32, { spirv_std::memory::Scope::QueueFamily as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v)
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        core::mem::replace(word, v)
    }
}

/// Atomic max on a storage-buffer word.
#[inline]
pub fn atomic_max(word: &mut u32, v: u32) {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_u_max::<u32, { spirv_std::memory::Scope::QueueFamily as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v);
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        *word = (*word).max(v);
    }
}

/// Atomic minimum on a storage-buffer word.
#[inline]
pub fn atomic_min(word: &mut u32, v: u32) {
    #[cfg(target_arch = "spirv")]
    unsafe {
        spirv_std::arch::atomic_u_min::<u32, { spirv_std::memory::Scope::QueueFamily as u32 }, { spirv_std::memory::Semantics::NONE.bits() }>(word, v);
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        *word = (*word).min(v);
    }
}
