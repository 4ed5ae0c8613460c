use super::emulated::*;
use super::*;
use crate::sort_acceptance_tests::inputs;

const WIDTHS: [u32; 5] = [4, 8, 16, 32, 64];

/// Sorts `keys` (values = indices) in the emulation and compares with `sort`: keys equal, and
/// the (key, value) multiset equal.
fn check(width: u32, plan_width: u32, keys: &[u32], what: &str) -> u32 {
    check_keep(width, plan_width, SPLITTER_KEEP, keys, what)
}

/// [`check`] keeping every `keep`-th splitter sample.
fn check_keep(width: u32, plan_width: u32, keep: u32, keys: &[u32], what: &str) -> u32 {
    let values: Vec<u32> = (0..keys.len() as u32).collect();
    let (k, v, steps) = sort_emulated_with_keep(width, plan_width, keep, keys, &values);
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    expected.sort_unstable();
    let mut got: Vec<(u32, u32)> = k.iter().copied().zip(v).collect();
    let sorted_keys: Vec<u32> = expected.iter().map(|e| e.0).collect();
    assert_eq!(k, sorted_keys, "{what}, n = {}, width {width} (plan {plan_width}): keys", keys.len());
    got.sort_unstable();
    assert_eq!(got, expected, "{what}, n = {}, width {width}: key–value multiset", keys.len());
    steps
}

#[test]
fn block_sort_sorts_every_block_at_all_widths() {
    let m = BLOCK;
    for width in WIDTHS {
        for n in [1, 2, 3, 5, m - 1, m, m + 1, 3 * m + 5] {
            for (what, keys) in inputs(n as usize, n + width) {
                let values: Vec<u32> = (0..n).collect();
                let (k, v) = block_sort_emulated(width, &keys, &values);
                for (b, chunk) in k.chunks(m as usize).enumerate() {
                    assert!(chunk.windows(2).all(|w| w[0] <= w[1]), "{what}: block {b} at width {width}");
                }
                let mut got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
                let mut expected: Vec<(u32, u32)> = keys.into_iter().zip(values).collect();
                got.sort_unstable();
                expected.sort_unstable();
                assert_eq!(got, expected, "{what}, n = {n}, width {width}");
            }
        }
    }
}

/// A real key `u32::MAX` in a partial block is never mistaken for padding: its value survives.
#[test]
fn block_sort_keeps_real_max_keys_of_a_partial_block() {
    for width in [4, 32] {
        let keys: Vec<u32> = (0..300).map(|i| if i % 3 == 0 { u32::MAX } else { i * 7919 % 1000 }).collect();
        let values: Vec<u32> = (0..300).collect();
        let (k, v) = block_sort_emulated(width, &keys, &values);
        let mut got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
        let mut expected: Vec<(u32, u32)> = keys.into_iter().zip(values).collect();
        got.sort_unstable();
        expected.sort_unstable();
        assert_eq!(got, expected, "width {width}");
    }
}

/// The splitter pieces of every split level partition the merged run (∀a∈S_i, b∈S_j, i<j ⇒
/// a ≤ b), cover it exactly, and hold at most `(k+2)·g − 2` elements — duplicates included.
#[test]
fn splitter_pieces_partition_each_pair_within_the_bound() {
    let mut split_levels = 0;
    for (n, min_width, keep) in [(9000u32, 4u32, SPLITTER_KEEP), (4099, 8, SPLITTER_KEEP), (20_000, 8, SPLITTER_KEEP), (40_000, 32, SPLITTER_KEEP), (5000, 4, 1), (4099, 8, 2), (9000, 32, 4)] {
        for (what, keys) in inputs(n as usize, n) {
            // Sorted runs of every level: sort each run of the input.
            let (_, levels) = plan_with_keep(n, min_width, keep);
            for lv in levels.iter().filter(|lv| lv.split()) {
                split_levels += 1;
                let mut k = keys.clone();
                for run in k.chunks_mut(lv.run as usize) {
                    run.sort_unstable();
                }
                let boundaries = splitters_emulated(&k, lv);
                let bound = (lv.keep + 2) * lv.stride - 2;
                for pair in 0..lv.pairs() {
                    let (base, a, b) = lv.pair(pair);
                    let ctx = format!("{what}, n = {n}, run {}, pair {pair}", lv.run);
                    let mut prev: Option<Piece> = None;
                    let mut covered = 0;
                    let mut prev_max: Option<u32> = None;
                    for q in 0..lv.pieces_per_pair() {
                        let index = pair * lv.pieces_per_pair() + q;
                        let Some(p) = piece_of(lv, &boundaries, index) else {
                            assert!(q >= lv.pair_pieces(a, b), "{ctx}: piece {q} missing");
                            continue;
                        };
                        let len = (p.a1 - p.a0) + (p.b1 - p.b0);
                        assert!(len <= bound, "{ctx}: piece {q} has {len} > {bound} elements");
                        assert!(p.a0 <= p.a1 && p.b0 <= p.b1, "{ctx}: piece {q} reversed");
                        if let Some(pp) = prev {
                            assert_eq!((pp.a1, pp.b1), (p.a0, p.b0), "{ctx}: pieces {} and {q} not adjacent", q - 1);
                        } else {
                            assert_eq!((p.a0, p.b0, p.out0), (base, base + a, base), "{ctx}: first piece");
                        }
                        assert_eq!(p.out0, base + covered, "{ctx}: piece {q} output start");
                        let elems = k[p.a0 as usize..p.a1 as usize].iter().chain(&k[p.b0 as usize..p.b1 as usize]);
                        let (lo, hi) = elems.fold((u32::MAX, 0), |(lo, hi), &x| (lo.min(x), hi.max(x)));
                        if len > 0 {
                            if let Some(m) = prev_max {
                                assert!(m <= lo, "{ctx}: piece {q} has {lo} below the previous piece's {m}");
                            }
                            prev_max = Some(prev_max.map_or(hi, |m| m.max(hi)));
                        }
                        covered += len;
                        prev = Some(p);
                    }
                    let last = prev.expect("a pair has at least one piece");
                    assert_eq!((last.a1, last.b1), (base + a, base + a + b), "{ctx}: last piece ends short");
                    assert_eq!(covered, a + b, "{ctx}: coverage");
                }
            }
        }
    }
    assert!(split_levels > 20, "the cases must reach split levels ({split_levels})");
}

/// Every splitter keep (the host may pick it per device and size) sorts, and no subgroup merges
/// more than `keep + 2` steps (a piece holds at most `(k+2)·g − 2` elements, `g` one step).
#[test]
fn every_splitter_keep_sorts_within_its_step_bound() {
    for keep in [1, 2, 4] {
        for width in [4, 8, 32] {
            let piece = (keep * sample_stride(width)) as usize;
            let block = BLOCK as usize;
            for n in [100, 2 * block + 1, 5 * block + 3 * piece + 7] {
                for (what, keys) in inputs(n, n as u32) {
                    let steps = check_keep(width, width, keep, &keys, what);
                    assert!(steps <= keep + 2, "{what}, n = {n}, width {width}, keep {keep}: {steps} merge steps");
                }
            }
        }
    }
}

/// The measured rule: keep 1 at 64k pairs, 4 at 1M, 8 from 4M on (W = 32); powers of two.
#[test]
fn splitter_keep_grows_with_the_input() {
    assert_eq!([64_000, 1_000_000, 4_000_000, 16_000_000].map(|n| splitter_keep(n, 32)), [1, 4, 8, 8]);
    for w in [4, 8, 16, 32, 64] {
        let mut last = 0;
        for n in (0..32).map(|b| 1u32 << b) {
            let k = splitter_keep(n, w);
            assert!(k.is_power_of_two() && k <= SPLITTER_KEEP && k >= last, "n = {n}, width {w}: keep {k}");
            last = k;
        }
    }
}

// The acceptance matrix (lengths × shapes × widths 4–64, 2^20 included) is
// `crate::sort_acceptance_tests`, shared with the radix sort.

/// A driver may run a kernel with a wider subgroup than the plan's narrowest one: same result.
#[test]
fn wider_subgroup_than_planned_sorts_too() {
    for (width, plan_width) in [(8, 4), (32, 8), (64, 16)] {
        for n in [1u32, 100, 1000, 3 * 1024 + 7] {
            for (what, keys) in inputs(n as usize, n) {
                // Splitter levels (n > 16·plan width) with all shapes at the narrow pair.
                if width == 8 || what == "random" {
                    check(width, plan_width, &keys, what);
                }
            }
        }
    }
}
