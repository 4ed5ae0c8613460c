//! Subgroup and workgroup prefix sums (the building block of stream compaction: unique-cluster
//! compaction, light-list allocation).
//!
//! Steps of [`workgroup_exclusive_scan`] (one workgroup of `W·G` invocations, subgroup width `W`):
//! 1. each subgroup computes an inclusive scan of its lanes' values with `log2 W` shuffle steps
//!    (Hillis–Steele: lane `l` adds the value `d` lanes below, `d = 1, 2, 4, …`);
//! 2. the last lane of each subgroup stores the subgroup total into workgroup memory `[sg]`;
//! 3. barrier; subgroup 0 scans those `G` totals in chunks of `W` (carrying the running total),
//!    turning `[sg]` into inclusive subgroup offsets;
//! 4. barrier; each invocation adds the offsets of the subgroups before it.
//!
//! Cost: `log2 W` shuffles + `ceil(G/W)·log2 W` shuffles in subgroup 0, two workgroup barriers.
//! Workgroup memory: `G` words (`G = workgroup size / subgroup width`: 32 words at 256/8 on lavapipe,
//! 8 at 256/32 on NVIDIA; [`SCAN_SHARED_WORDS`] covers widths down to 4).
//! Sums wrap modulo 2^32 (callers scan counts that are far below that).
use crate::coop::{Coop, SharedU32};

/// Workgroup size of the scan kernels.
pub const SCAN_WORKGROUP: u32 = 256;
/// Workgroup memory words the scan needs at the smallest supported subgroup width (4).
pub const SCAN_SHARED_WORDS: usize = (SCAN_WORKGROUP / 4) as usize;

/// Inclusive prefix sum over the lanes of the subgroup.
#[inline]
pub fn subgroup_inclusive_scan<C: Coop>(c: &C, value: u32) -> u32 {
    let lane = c.lane();
    let mut x = value;
    let mut d = 1;
    while d < c.subgroup_size() {
        let src = if lane >= d { lane - d } else { lane };
        let t = c.shuffle(x, src);
        if lane >= d {
            x = x.wrapping_add(t);
        }
        d *= 2;
    }
    x
}

/// Exclusive prefix sum over the whole workgroup; returns `(exclusive prefix, workgroup total)`.
/// Must be called by every invocation of the workgroup (uniform control flow).
#[inline]
pub fn workgroup_exclusive_scan<C: Coop, S: SharedU32 + ?Sized>(
    c: &C,
    shared: &mut S,
    value: u32,
) -> (u32, u32) {
    workgroup_exclusive_scan_at(c, shared, 0, value)
}

/// [`workgroup_exclusive_scan`] using workgroup-memory words `at..at + SCAN_SHARED_WORDS`. A
/// caller scanning twice in a row puts a workgroup barrier between the calls (the second call's
/// first stores would race with the first call's last loads).
#[inline]
pub fn workgroup_exclusive_scan_at<C: Coop, S: SharedU32 + ?Sized>(
    c: &C,
    shared: &mut S,
    at: u32,
    value: u32,
) -> (u32, u32) {
    let width = c.subgroup_size();
    let sg = c.subgroup_id();
    let groups = c.num_subgroups();
    // 1–2.
    let inclusive = subgroup_inclusive_scan(c, value);
    if c.lane() == width - 1 {
        shared.store(at + sg, inclusive);
    }
    c.workgroup_barrier();
    // 3. Subgroup 0 scans the subgroup totals, W at a time.
    if sg == 0 {
        let mut carry = 0u32;
        let mut base = 0;
        while base < groups {
            let i = base + c.lane();
            let v = if i < groups { shared.load(at + i) } else { 0 };
            let s = subgroup_inclusive_scan(c, v).wrapping_add(carry);
            if i < groups {
                shared.store(at + i, s);
            }
            carry = c.shuffle(s, width - 1);
            base += width;
        }
    }
    c.workgroup_barrier();
    // 4.
    let before = if sg > 0 { shared.load(at + sg - 1) } else { 0 };
    let total = shared.load(at + groups - 1);
    (before.wrapping_add(inclusive).wrapping_sub(value), total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coop::cpu::{run_workgroups, Emulation};

    /// The emulated scan equals a sequential scan, per workgroup, at every width 4…64.
    #[test]
    fn workgroup_scan_matches_sequential_at_all_widths() {
        let n = 3 * SCAN_WORKGROUP as usize;
        let input: Vec<u32> = (0..n as u32).map(|i| i.wrapping_mul(2_654_435_761) >> 22).collect();
        for width in [4, 8, 16, 32, 64] {
            let emu = Emulation { width, workgroup_size: SCAN_WORKGROUP, shared_words: SCAN_SHARED_WORDS };
            let out = run_workgroups(emu, 3, |g, c, s| {
                let i = (g * SCAN_WORKGROUP + c.local_index()) as usize;
                workgroup_exclusive_scan(c, s, input[i])
            });
            for (g, chunk) in input.chunks(SCAN_WORKGROUP as usize).enumerate() {
                let mut acc = 0u32;
                let total: u32 = chunk.iter().sum();
                for (l, v) in chunk.iter().enumerate() {
                    let (excl, tot) = out[g * SCAN_WORKGROUP as usize + l];
                    assert_eq!(excl, acc, "width {width}, group {g}, lane {l}");
                    assert_eq!(tot, total, "width {width}, group {g}");
                    acc += v;
                }
            }
        }
    }

    /// Wrap-around is modular, as on the GPU.
    #[test]
    fn subgroup_scan_wraps() {
        let emu = Emulation { width: 8, workgroup_size: 8, shared_words: 0 };
        let out = run_workgroups(emu, 1, |_, c, _| subgroup_inclusive_scan(c, u32::MAX));
        for (l, v) in out.iter().enumerate() {
            assert_eq!(*v, u32::MAX.wrapping_mul(l as u32 + 1));
        }
    }

    /// A kernel whose lanes diverge around a shuffle fails loudly instead of hanging.
    #[test]
    #[should_panic(expected = "bails out")]
    fn divergent_shuffle_is_reported() {
        let emu = Emulation { width: 4, workgroup_size: 4, shared_words: 0 };
        run_workgroups(emu, 1, |_, c, _| {
            if c.lane() == 0 {
                panic!("lane 0 bails out before the shuffle: the others must not wait forever");
            }
            c.shuffle(1, 0)
        });
    }
}
