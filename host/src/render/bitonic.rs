//! GPU key–value bitonic-warp merge sort (`shaders::bitonic`, Ye et al. 2010): a block sort of
//! `BLOCK` = 1 024 elements per workgroup (registers, shuffles and workgroup memory), then one
//! merge level per doubling of the run length — a splitter dispatch where
//! a pair of runs spans several pieces, and a warp-merge dispatch — ping-ponging between the
//! caller's buffers and scratch buffers. The block sort runs in place or into the scratch pair so
//! that the last level writes the caller's buffers. Not stable.
//!
//! Plan: sample stride `2·W_min`, with `W_min` the device's smallest subgroup width (its only
//! width on NVIDIA and lavapipe), and every `keep`-th sample a splitter; the merge dispatches give
//! each piece a subgroup and cover the *largest* width (`Recorder::dispatch_subgroups`), so the
//! result does not depend on the width the driver picks.
//!
//! Memory (scratch): 8 B per element (keys + values) and 8 B per piece of boundaries, sized for
//! the largest level at `capacity` (≈ n/16 B at W = 8, n/64 B at W = 32).
use crate::vk::fold;
use crate::gpu::Gpu;
use crate::vk::{Buffer, Recorder, VkError, VkResult};
use shaders::bitonic::{level, level_count, splitter_keep, Level, BLOCK, SPLITTER_WORKGROUP};
use shaders::layout::BitonicParams;

pub struct BitonicSort {
    pub capacity: u32,
    /// Subgroup width the plan assumes (the device's smallest).
    pub min_width: u32,
    /// Every `keep`-th splitter sample bounds a piece (`shaders::bitonic::Level::keep`).
    pub keep: u32,
    keys_tmp: Buffer,
    values_tmp: Buffer,
    boundaries: Buffer,
}

/// The merge levels of a sort of `n` elements for a device whose narrowest subgroup is
/// `min_width` lanes, keeping every `keep`-th splitter sample (the plan
/// `shaders::bitonic::emulated::plan_with_keep` tests).
pub fn levels(n: u32, min_width: u32, keep: u32) -> Vec<Level> {
    (0..level_count(n, BLOCK)).map(|l| level(n, min_width, l, keep)).collect()
}

fn params(lv: &Level, in_place: bool) -> BitonicParams {
    BitonicParams { count: lv.n, run: lv.run, stride: lv.stride, keep: lv.keep, in_place: in_place as u32, _pad: [0; 3] }
}

impl BitonicSort {
    /// A sort for up to `capacity` pairs whose splitter keep suits `capacity`
    /// (`shaders::bitonic::splitter_keep`).
    pub fn new(gpu: &Gpu, capacity: u32) -> VkResult<Self> {
        let min_width = gpu.ctx.info.min_subgroup_size.max(1);
        Self::with_keep(gpu, capacity, splitter_keep(capacity, min_width))
    }

    /// A sort keeping every `keep`-th splitter sample (≥ 1): smaller pieces, more of them.
    pub fn with_keep(gpu: &Gpu, capacity: u32, keep: u32) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let keep = keep.max(1);
        let min_width = ctx.info.min_subgroup_size.max(1);
        let pieces = levels(capacity, min_width, keep).iter().filter(|l| l.split()).map(Level::pieces).max().unwrap_or(1);
        Ok(Self {
            capacity,
            min_width,
            keep,
            keys_tmp: Buffer::storage(ctx, "bitonic keys (scratch)", 4 * capacity.max(1) as u64)?,
            values_tmp: Buffer::storage(ctx, "bitonic values (scratch)", 4 * capacity.max(1) as u64)?,
            boundaries: Buffer::storage(ctx, "bitonic piece boundaries", 8 * pieces as u64)?,
        })
    }

    /// Bytes of scratch memory.
    pub fn bytes(&self) -> u64 {
        self.keys_tmp.size + self.values_tmp.size + self.boundaries.size
    }

    /// Records a sort of `keys[..n]` (values follow). `key_bits` is accepted for the same shape
    /// as `RadixSort::record`; a comparison sort does not need it.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, keys: &Buffer, values: &Buffer, n: u32, _key_bits: u32) -> VkResult<()> {
        if n > self.capacity {
            return Err(VkError::Kernel { entry: "bitonic sort", what: format!("sorting {n} pairs with buffers for {}", self.capacity) });
        }
        if n <= 1 {
            return Ok(());
        }
        let k = &gpu.kernels;
        let levels = levels(n, self.min_width, self.keep);
        // An even number of levels ends where the block sort wrote: in place, then.
        let in_place = levels.len().is_multiple_of(2);
        let first = Level { n, run: BLOCK, stride: 0, keep: 0 };
        let buffers = [keys, values, &self.keys_tmp, &self.values_tmp];
        rec.dispatch(&k.bitonic_block_sort, &buffers, &params(&first, in_place), fold(n.div_ceil(BLOCK)))?;
        let (mut src, mut dst) = if in_place { ((keys, values), (&self.keys_tmp, &self.values_tmp)) } else { ((&self.keys_tmp, &self.values_tmp), (keys, values)) };
        for lv in &levels {
            let p = params(lv, false);
            if lv.split() {
                rec.dispatch(&k.bitonic_splitters, &[src.0, &self.boundaries], &p, fold(lv.slots().div_ceil(SPLITTER_WORKGROUP)))?;
            }
            rec.dispatch_subgroups(&k.bitonic_merge, &[src.0, src.1, &self.boundaries, dst.0, dst.1], &p, lv.pieces())?;
            (src, dst) = (dst, src);
        }
        debug_assert!(std::ptr::eq(src.0, keys));
        Ok(())
    }
}
