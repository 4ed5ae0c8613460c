//! Device-wide exclusive prefix sum (reduce-then-scan over workgroup scans).
//!
//! Level 0 scans `n` elements in workgroups of 256 (`workgroup_scan`, cooperative), writing one
//! total per workgroup; the totals are scanned the same way (recursively) and added back
//! (`scan_add_offsets`). Levels: ⌈log₂₅₆ n⌉ — 3 for 16 M elements.
//! Memory: `2 × 4 B × (n/256 + n/256² + …)` for the totals and their scans.
//! The grand total can be stored into a counter slot (`scan_store_total`), so later kernels
//! read it without a round trip to the host.
use crate::gpu::Gpu;
use crate::vk::{fold, Buffer, ComputePipeline, Recorder, VkResult};
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

/// The elements of a level: known to the host, or counted by the GPU (indirect dispatches).
#[derive(Clone, Copy, Debug)]
enum Extent {
    Host(u32),
    Counted,
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
        self.record_level(gpu, rec, 0, input, output, Extent::Counted)?;
        if let Some(slot) = total {
            let t = CountedTotalParams { count: n.counter, scale: n.scale, total: slot, capacity: self.capacity };
            rec.dispatch(&k.scan_counted_total, &[input, output, counters], &t, [1, 1, 1])?;
        }
        Ok(())
    }

    /// Records `output = exclusive_scan(input[..n])` and, with `total`, `counters[slot] = Σ input`.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, input: &Buffer, output: &Buffer, n: u32, total: Option<(&Buffer, u32)>) -> VkResult<()> {
        assert!(n <= self.capacity, "scan of {n} elements exceeds its plan ({})", self.capacity);
        self.record_level(gpu, rec, 0, input, output, Extent::Host(n))?;
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

    /// Level `level`: its workgroup scan, the levels above it, and the addition of their offsets.
    fn record_level(&self, gpu: &Gpu, rec: &mut Recorder<'_>, level: usize, input: &Buffer, output: &Buffer, extent: Extent) -> VkResult<()> {
        let (l, k) = (&self.levels[level], &gpu.kernels);
        // One workgroup of 256 per 256 elements, for the scan and for the addition alike.
        let (count, groups, above) = match extent {
            Extent::Host(n) => {
                let groups = n.max(1).div_ceil(SCAN_WORKGROUP);
                (n, Some(groups), (groups > 1).then_some(Extent::Host(groups)))
            }
            Extent::Counted => (l.capacity, None, (level + 1 < self.levels.len()).then_some(Extent::Counted)),
        };
        let p = ScanParams { count, _pad: [0; 3] };
        self.dispatch_level(rec, &k.workgroup_scan, &[input, output, &l.totals], &p, level, groups)?;
        if let Some(above) = above {
            self.record_level(gpu, rec, level + 1, &l.totals, &l.scanned, above)?;
            let fix = ScanFixParams { count, slot: 0, _pad: [0; 2] };
            self.dispatch_level(rec, &k.scan_add_offsets, &[&l.scanned, output], &fix, level, groups)?;
        }
        Ok(())
    }

    /// Dispatches `groups` workgroups, or with `None` the counted level's indirect triple.
    fn dispatch_level<P: bytemuck::Pod>(&self, rec: &mut Recorder<'_>, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P, level: usize, groups: Option<u32>) -> VkResult<()> {
        match groups {
            Some(g) => rec.dispatch(pipe, buffers, params, fold(g)),
            None => rec.dispatch_indirect(pipe, buffers, params, &self.args, 3 * level as u32),
        }
    }
}
