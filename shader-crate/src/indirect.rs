//! Workgroup counts of a dispatch, on the host and on the GPU from a counter.
//!
//! A pass over work whose size only the GPU knows (the unique clusters of a frame) is dispatched
//! indirectly: the kernel that counts it also writes `VkDispatchIndirectCommand` arguments
//! ([`dispatch_args`]), so the pass launches workgroups for the real work instead of the
//! buffer's capacity. Both sides fold large counts into a 2D grid the same way ([`fold`]); kernels
//! linearise `wg.y · num_wg.x + wg.x` and return past their item count.

/// Workgroups per dispatch axis (Vulkan guarantees 65 535).
pub const MAX_GROUPS_PER_AXIS: u32 = 65_535;

/// `groups` workgroups as a 2D grid whose linear index covers them all (at least one workgroup).
#[inline]
pub fn fold(groups: u32) -> [u32; 3] {
    let gx = if groups < 1 { 1 } else if groups > MAX_GROUPS_PER_AXIS { MAX_GROUPS_PER_AXIS } else { groups };
    let gy = groups.div_ceil(gx);
    [gx, if gy < 1 { 1 } else { gy }, 1]
}

/// Indirect dispatch arguments for `items` items of `items_per_group` per workgroup: no workgroup
/// for no item, else [`fold`] of the workgroups needed.
#[inline]
pub fn dispatch_args(items: u32, items_per_group: u32) -> [u32; 3] {
    if items == 0 {
        return [0, 1, 1];
    }
    fold(items.div_ceil(if items_per_group < 1 { 1 } else { items_per_group }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_cover_the_items_and_no_more_than_a_row_extra() {
        for per_group in [1, 2, 8, 64, 256] {
            for items in [1u32, 2, 255, 256, 257, 65_535 * 8, 65_535 * 8 + 1, 33_554_432, u32::MAX / 2] {
                let [x, y, z] = dispatch_args(items, per_group);
                let groups = items.div_ceil(per_group) as u64;
                let covered = x as u64 * y as u64;
                assert!(z == 1 && x <= MAX_GROUPS_PER_AXIS && y <= MAX_GROUPS_PER_AXIS, "{items}/{per_group}: {x}×{y}×{z}");
                assert!(covered >= groups && covered < groups + x as u64, "{items}/{per_group}: {x}×{y} for {groups} groups");
            }
        }
        assert_eq!(dispatch_args(0, 4), [0, 1, 1]);
        assert_eq!(fold(0), [1, 1, 1]);
    }
}
