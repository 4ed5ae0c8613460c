//! Device-wide exclusive prefix sum (reduce-then-scan over workgroup scans).
//!
//! Level 0 scans `n` elements in workgroups of 256 (`workgroup_scan`, cooperative), writing one
//! total per workgroup; the totals are scanned the same way (recursively) and added back
//! (`scan_add_offsets`). Levels: ⌈log₂₅₆ n⌉ — 3 for 16 M elements.
//! Memory: `2 × 4 B × (n/256 + n/256² + …)` for the totals and their scans.
//! The grand total can be stored into a counter slot (`scan_store_total`), so later kernels
//! read it without a round trip to the host.
use crate::gpu::Gpu;
use crate::vk::{fold, Buffer, Recorder, VkResult};
use shaders::layout::{CountedTotalParams, IndirectParams, ScanFixParams, ScanParams};
use shaders::scan::SCAN_WORKGROUP;

struct Level {
    totals: Buffer,
    scanned: Buffer,
    /// Elements this level scans at capacity (`⌈capacity / 256^level⌉`).
    capacity: u32,
}

/// Scratch buffers for scanning up to `capacity` elements.
pub struct DeviceScan {
    levels: Vec<Level>,
    /// Indirect dispatch arguments of a counted scan, one triple per level.
    args: Buffer,
    pub capacity: u32,
}

/// A count the GPU knows: `counters[counter] · scale` elements (e.g. allocated pages × slots per
/// page).
#[derive(Clone, Copy, Debug)]
pub struct Counted {
    pub counter: u32,
    pub scale: u32,
}

impl DeviceScan {
    pub fn new(gpu: &Gpu, name: &str, capacity: u32) -> VkResult<Self> {
        let mut levels = Vec::new();
        let mut n = capacity.max(1);
        loop {
            let groups = n.div_ceil(SCAN_WORKGROUP);
            let g = fold(groups);
            let slots = (g[0] * g[1]) as u64;
            levels.push(Level {
                totals: Buffer::storage(&gpu.ctx, &format!("{name} scan totals L{}", levels.len()), 4 * slots)?,
                scanned: Buffer::storage(&gpu.ctx, &format!("{name} scan offsets L{}", levels.len()), 4 * slots)?,
                capacity: n,
            });
            if groups <= 1 {
                break;
            }
            n = groups;
        }
        let args = Buffer::storage(&gpu.ctx, &format!("{name} scan dispatch"), 4 * 3 * levels.len() as u64)?;
        Ok(Self { levels, args, capacity })
    }

    /// Bytes of scratch memory.
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.totals.size + l.scanned.size).sum::<u64>() + self.args.size
    }

    /// Records `output[..n] = exclusive_scan(input[..n])` for the `n` elements the GPU counted
    /// (`n ≤ capacity`), and with `total` `counters[total] = Σ input[..n]`. Every level is
    /// dispatched indirectly for `n`: level `l` (its workgroup scan and the addition of its
    /// offsets) takes `⌈n / 256^(l+1)⌉` workgroups, so the work follows the count, not the
    /// capacity. Elements past `n` (in the last workgroup of a level) may be stale: they follow
    /// every counted element, so no counted prefix depends on them; the total is therefore the
    /// last prefix plus the last element (`scan_counted_total`), not the top level's sum.
    #[allow(clippy::too_many_arguments)]
    pub fn record_counted(&self, gpu: &Gpu, rec: &mut Recorder<'_>, input: &Buffer, output: &Buffer, counters: &Buffer, n: Counted, total: Option<u32>) -> VkResult<()> {
        let k = &gpu.kernels;
        let p = IndirectParams {
            counter: n.counter,
            scale: n.scale,
            items_per_group: SCAN_WORKGROUP,
            growth: SCAN_WORKGROUP,
            offset: 0,
            levels: self.levels.len() as u32,
            _pad: [0; 2],
        };
        rec.indirect_args(&k.indirect_args, counters, &self.args, &p)?;
        self.record_counted_level(gpu, rec, 0, input, output)?;
        if let Some(slot) = total {
            let t = CountedTotalParams { count: n.counter, scale: n.scale, total: slot, capacity: self.capacity };
            rec.dispatch(&k.scan_counted_total, &[input, output, counters], &t, [1, 1, 1])?;
        }
        Ok(())
    }

    fn record_counted_level(&self, gpu: &Gpu, rec: &mut Recorder<'_>, level: usize, input: &Buffer, output: &Buffer) -> VkResult<()> {
        let (l, k, offset) = (&self.levels[level], &gpu.kernels, 3 * level as u32);
        let p = ScanParams { count: l.capacity, _pad: [0; 3] };
        rec.dispatch_indirect(&k.workgroup_scan, &[input, output, &l.totals], &p, &self.args, offset)?;
        if level + 1 < self.levels.len() {
            self.record_counted_level(gpu, rec, level + 1, &l.totals, &l.scanned)?;
            let fix = ScanFixParams { count: l.capacity, slot: 0, _pad: [0; 2] };
            // One workgroup of 256 per 256 elements of this level: the same triple.
            rec.dispatch_indirect(&k.scan_add_offsets, &[&l.scanned, output], &fix, &self.args, offset)?;
        }
        Ok(())
    }

    /// Records `output = exclusive_scan(input[..n])` and, with `total`, `counters[slot] = Σ input`.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, input: &Buffer, output: &Buffer, n: u32, total: Option<(&Buffer, u32)>) -> VkResult<()> {
        assert!(n <= self.capacity, "scan of {n} elements exceeds its plan ({})", self.capacity);
        self.record_level(gpu, rec, 0, input, output, n)?;
        if let Some((counters, slot)) = total {
            // The top level of *this* scan: the first level whose input fits in one workgroup.
            let mut m = n.max(1);
            let mut level = 0;
            while m > SCAN_WORKGROUP {
                m = m.div_ceil(SCAN_WORKGROUP);
                level += 1;
            }
            let p = ScanFixParams { count: 1, slot, _pad: [0; 2] };
            rec.dispatch(&gpu.kernels.scan_store_total, &[&self.levels[level].totals, counters], &p, [1, 1, 1])?;
        }
        Ok(())
    }

    fn record_level(&self, gpu: &Gpu, rec: &mut Recorder<'_>, level: usize, input: &Buffer, output: &Buffer, n: u32) -> VkResult<()> {
        let l = &self.levels[level];
        let groups = n.max(1).div_ceil(SCAN_WORKGROUP);
        let p = ScanParams { count: n, _pad: [0; 3] };
        rec.dispatch(&gpu.kernels.workgroup_scan, &[input, output, &l.totals], &p, fold(groups))?;
        if groups > 1 {
            self.record_level(gpu, rec, level + 1, &l.totals, &l.scanned, groups)?;
            let fix = ScanFixParams { count: n, slot: 0, _pad: [0; 2] };
            rec.dispatch(&gpu.kernels.scan_add_offsets, &[&l.scanned, output], &fix, fold(n.div_ceil(256)))?;
        }
        Ok(())
    }
}
