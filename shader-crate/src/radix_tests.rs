//! Unit tests of the radix sort's parts; the whole acceptance matrix is in
//! `sort_acceptance_tests.rs`.
use super::emulated::{sort_emulated_with, Path};
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::sort_inputs::shapes;

const WIDTHS: [u32; 5] = [4, 8, 16, 32, 64];

/// Keys masked to `key_bits`, values = input index; the result must equal a stable sort.
fn check(width: u32, keys: &[u32], key_bits: u32, path: Path, what: &str) {
    let mask = if key_bits >= 32 { u32::MAX } else { (1u32 << key_bits) - 1 };
    let keys: Vec<u32> = keys.iter().map(|k| k & mask).collect();
    let values: Vec<u32> = (0..keys.len() as u32).collect();
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
    expected.sort_by_key(|e| e.0);
    let (k, v) = sort_emulated_with(width, &keys, &values, key_bits, path);
    let got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
    if let Some(i) = (0..got.len()).find(|&i| got[i] != expected[i]) {
        panic!("{what}, n = {}, {key_bits} bits, {path:?}, width {width}: first difference at {i}: {:?} instead of {:?}", keys.len(), got[i], expected[i]);
    }
}

#[test]
fn passes_cover_exactly_the_key_bits() {
    assert_eq!(passes(0), 0);
    assert_eq!(passes(1), 1);
    assert_eq!(passes(8), 1);
    assert_eq!(passes(9), 2);
    assert_eq!(passes(30), 4);
    assert_eq!(passes(32), 4);
    assert_eq!(passes(40), 4, "keys have 32 bits");
    let digits: Vec<(u32, u32)> = (0..passes(30)).map(|p| pass_digit(p, 30)).collect();
    assert_eq!(digits, [(0, 8), (8, 8), (16, 8), (24, 6)]);
    assert_eq!(digit(0xABCD_EF12, 8, 8), 0xEF);
    assert_eq!(digit(u32::MAX, 24, 6), 63, "the padding key has the largest digit");
}

/// The invocations' slots cover the tile exactly once at every width, and the chunks of one
/// rank row are consecutive.
#[test]
fn slots_cover_the_tile_once() {
    for width in [1, 2, 4, 8, 16, 32, 64, 128] {
        let emu = Emulation { width, workgroup_size: SORT_WORKGROUP, shared_words: 0 };
        let out = run_workgroups(emu, 1, |_, c, _| {
            let s = Slots::of(c);
            ((0..KEYS_PER_INVOCATION).map(|j| s.item(j)).collect::<Vec<_>>(), s)
        });
        let mut seen = vec![0u32; RADIX_TILE as usize];
        for (items, s) in &out {
            assert!(s.rows <= RANK_ROWS && s.rows * s.rounds * width == SORT_WORKGROUP, "width {width}: {s:?}");
            let chunk = items[0] / (width * KEYS_PER_INVOCATION);
            assert_eq!(chunk, s.row * s.rounds + s.round, "width {width}");
            items.iter().for_each(|&i| seen[i as usize] += 1);
        }
        assert!(seen.iter().all(|&n| n == 1), "width {width}: some slot is not covered exactly once");
    }
}

/// Stable for every key width (1–32 bits: odd and even pass counts, a narrower last digit) on
/// both paths, several tiles with a partial last one.
#[test]
fn sorts_every_key_width_stably() {
    let n = 3 * RADIX_TILE as usize + 5;
    for width in [4, 32] {
        for key_bits in [1, 5, 8, 9, 16, 24, 30, 32] {
            for (what, keys) in shapes(n, key_bits ^ width) {
                check(width, &keys, key_bits, Path::Auto, what);
                check(width, &keys[..RADIX_TILE as usize - 3], key_bits, Path::Auto, what);
            }
        }
    }
}

/// The tile path also sorts inputs of less than one tile (the host sends those to one
/// workgroup, so the acceptance matrix does not reach them there).
#[test]
fn tile_path_sorts_partial_single_tiles() {
    for width in WIDTHS {
        for n in [2, 3, 255, 256, 257, 1000, RADIX_TILE as usize - 1, RADIX_TILE as usize] {
            for (what, keys) in shapes(n, n as u32 + width) {
                check(width, &keys, 32, Path::Tiles, what);
            }
        }
    }
}

/// One workgroup's global histogram counts every pass's digits of its keys.
#[test]
fn global_histogram_counts_every_digit() {
    let keys: Vec<u32> = shapes(HISTOGRAM_KEYS as usize + 77, 5).pop().unwrap().1;
    for width in WIDTHS {
        let emu = Emulation { width, workgroup_size: SORT_WORKGROUP, shared_words: HISTOGRAM_SHARED_WORDS };
        let rows = run_workgroups(emu, 2, |g, c, s| {
            let base = g * HISTOGRAM_KEYS;
            global_histogram(c, s, (keys.len() as u32 - base).min(HISTOGRAM_KEYS), 30, |i| keys[(base + i) as usize])
        });
        for pass in 0..passes(30) {
            let (shift, bits) = pass_digit(pass, 30);
            let mut expected = vec![0u32; RADIX as usize];
            keys.iter().for_each(|&k| expected[digit(k, shift, bits) as usize] += 1);
            let got: Vec<u32> = (0..RADIX as usize).map(|d| rows[d][pass as usize] + rows[RADIX as usize + d][pass as usize]).collect();
            assert_eq!(got, expected, "width {width}, pass {pass}");
        }
    }
}

/// Small inputs scan their tile counts in one spine workgroup, large ones in up to 256, none
/// past its share.
#[test]
fn spine_splits_by_size() {
    assert_eq!(spine_digits(1), RADIX);
    assert_eq!(spine_digits(3), RADIX);
    assert_eq!(spine_digits(512), 16);
    assert_eq!(spine_digits(8192), 1);
    assert_eq!(spine_digits(100_000), 1);
    for tiles in [1, 2, 31, 32, 33, 512, 513, 8192] {
        let d = spine_digits(tiles);
        assert!(d.is_power_of_two() && RADIX.is_multiple_of(d));
        assert!(d == 1 || d * tiles <= SPINE_COUNTS, "{tiles} tiles: {d} digits per workgroup");
    }
}
