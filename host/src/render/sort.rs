//! GPU key–value radix sort (`shaders::radix`): 8-bit digits, histogram → scan → stable scatter
//! per pass, ping-ponging between the caller's buffers and scratch buffers. An even number of
//! passes is always run (an extra pass over zero digits is the identity), so the result ends in
//! the caller's buffers. Scratch: 8 B per element + `4 · 256 · ⌈n/256⌉` B of counts (×2) + scan.
use super::scan::DeviceScan;
use crate::vk::fold;
use crate::gpu::Gpu;
use crate::vk::{Buffer, Recorder, VkResult};
use shaders::layout::RadixParams;
use shaders::radix::{passes, RADIX, RADIX_BITS, RADIX_TILE};

pub struct RadixSort {
    pub capacity: u32,
    keys_tmp: Buffer,
    values_tmp: Buffer,
    hist: Buffer,
    starts: Buffer,
    scan: DeviceScan,
}

impl RadixSort {
    pub fn new(gpu: &Gpu, capacity: u32) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        let groups = capacity.div_ceil(RADIX_TILE).max(1);
        let counts = RADIX * groups;
        Ok(Self {
            capacity,
            keys_tmp: Buffer::storage(ctx, "sort keys (scratch)", 4 * capacity as u64)?,
            values_tmp: Buffer::storage(ctx, "sort values (scratch)", 4 * capacity as u64)?,
            hist: Buffer::storage(ctx, "sort histogram", 4 * counts as u64)?,
            starts: Buffer::storage(ctx, "sort digit starts", 4 * counts as u64)?,
            scan: DeviceScan::new(gpu, "sort", counts)?,
        })
    }

    /// Records a stable sort of `keys[..n]` (values follow) for keys below `2^key_bits`.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, keys: &Buffer, values: &Buffer, n: u32, key_bits: u32) -> VkResult<()> {
        assert!(n <= self.capacity, "sorting {n} keys with a plan for {}", self.capacity);
        if n <= 1 {
            return Ok(());
        }
        let groups = n.div_ceil(RADIX_TILE);
        let k = &gpu.kernels;
        let total_passes = passes(key_bits.min(32)).next_multiple_of(2);
        for pass in 0..total_passes {
            let (src_k, src_v, dst_k, dst_v) = if pass % 2 == 0 {
                (keys, values, &self.keys_tmp, &self.values_tmp)
            } else {
                (&self.keys_tmp, &self.values_tmp, keys, values)
            };
            // At most 4 passes (32-bit keys): shifts 0, 8, 16, 24.
            let p = RadixParams { count: n, shift: pass * RADIX_BITS, groups, _pad: 0 };
            rec.dispatch(&k.radix_histogram, &[src_k, &self.hist], &p, fold(groups))?;
            self.scan.record(gpu, rec, &self.hist, &self.starts, RADIX * groups, None)?;
            rec.dispatch(&k.radix_scatter, &[src_k, src_v, &self.starts, dst_k, dst_v], &p, fold(groups))?;
        }
        Ok(())
    }
}

/// Which GPU sort orders the lights' Morton keys (`render --sort`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SortKind {
    /// LSD radix sort ([`RadixSort`]), stable.
    #[default]
    Radix,
    /// Bitonic-warp merge sort ([`super::bitonic::BitonicSort`]).
    Bitonic,
}

/// The light sort of `clustered-bvh`: one of the two GPU key–value sorts, same interface.
pub enum LightSorter {
    Radix(Box<RadixSort>),
    Bitonic(Box<super::bitonic::BitonicSort>),
}

impl LightSorter {
    pub fn new(gpu: &Gpu, kind: SortKind, capacity: u32) -> VkResult<Self> {
        Ok(match kind {
            SortKind::Radix => Self::Radix(Box::new(RadixSort::new(gpu, capacity)?)),
            SortKind::Bitonic => Self::Bitonic(Box::new(super::bitonic::BitonicSort::new(gpu, capacity)?)),
        })
    }

    /// Records a sort of `keys[..n]` (values follow) for keys below `2^key_bits`.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, keys: &Buffer, values: &Buffer, n: u32, key_bits: u32) -> VkResult<()> {
        match self {
            Self::Radix(s) => s.record(gpu, rec, keys, values, n, key_bits),
            Self::Bitonic(s) => s.record(gpu, rec, keys, values, n, key_bits),
        }
    }
}
