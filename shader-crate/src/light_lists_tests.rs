//! CPU tests of `light_lists`: the subgroup-aggregated reservation is disjoint, dense and does
//! one atomic per subgroup that wants anything, at widths 4…64; the naive search loop emits
//! exactly the lights passing its test, in index order.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::test_support::{Counting, Rng};
use std::sync::atomic::{AtomicU32, Ordering};

const WIDTHS: [u32; 5] = [4, 8, 16, 32, 64];

#[test]
fn subgroup_reserve_is_dense_disjoint_and_one_atomic_per_subgroup() {
    for width in WIDTHS {
        let mut rng = Rng(width as u64);
        // Whole subgroups that want nothing (the second), lanes asking 0, 1 or many.
        let wants: Vec<u32> = (0..256u32)
            .map(|i| if (i / width) == 1 { 0 } else { [0, 1, 1, 5, 200][rng.below(5) as usize] })
            .collect();
        let (value, calls) = (AtomicU32::new(7), AtomicU32::new(0));
        let emu = Emulation { width, workgroup_size: 256, shared_words: 0 };
        let got = run_workgroups(emu, 1, |_, c, _| {
            let mut counter = Counting { value: &value, calls: &calls };
            subgroup_reserve(c, &mut counter, wants[c.local_index() as usize])
        });
        let total: u32 = wants.iter().sum();
        assert_eq!(value.load(Ordering::Relaxed), 7 + total, "width {width}");
        let subgroups_wanting = (0..256 / width).filter(|g| wants[(g * width) as usize..((g + 1) * width) as usize].iter().any(|&n| n > 0)).count();
        assert_eq!(calls.load(Ordering::Relaxed) as usize, subgroups_wanting, "width {width}: one atomic per subgroup that wants slots");
        let mut ranges: Vec<(u32, u32)> = got.iter().zip(&wants).filter(|(_, &n)| n > 0).map(|(&s, &n)| (s, s + n)).collect();
        ranges.sort_unstable();
        assert_eq!(ranges.first().unwrap().0, 7);
        assert_eq!(ranges.last().unwrap().1, 7 + total);
        assert!(ranges.windows(2).all(|w| w[0].1 == w[1].0), "width {width}: slots are dense and disjoint");
    }
}

#[test]
fn lights_meeting_emits_the_passing_lights_in_order() {
    let mut rng = Rng(23);
    for n in [0u32, 1, 7, 8, 9, 100] {
        let lights: Vec<PointLight> = (0..n).map(|_| PointLight { position: [rng.unit(), 0.0, 0.0], radius: rng.unit(), colour: [1.0; 3], intensity: 1.0 }).collect();
        let expected: Vec<(u32, u32)> = (0..n).filter(|&l| lights[l as usize].position[0] < lights[l as usize].radius).enumerate().map(|(k, l)| (k as u32, l)).collect();
        let mut got = Vec::new();
        let count = lights_meeting(0, n, &lights, |k, l| got.push((k, l)), |c, r| c.x < r);
        assert_eq!(got, expected, "{n} lights");
        assert_eq!(count as usize, expected.len());
    }
}
