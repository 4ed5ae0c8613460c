//! The whole radix sort on the CPU: the kernel functions of [`super`] in the lock-step emulation
//! of [`crate::coop::cpu`] at any subgroup width, dispatched as the host records them
//! (`host/src/render/sort.rs`): the single-workgroup path for one tile, otherwise the global
//! histogram and, per pass, upsweep, spine and downsweep. Reference for the acceptance matrix
//! (`sort_acceptance_tests.rs`) and the CPU version of the kernels in `benches/sort.rs`.
use super::*;
use crate::coop::cpu::{run_workgroups, Emulation};
use std::sync::atomic::{AtomicU32, Ordering};

/// Which dispatches sort the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// What the host picks: one workgroup for one tile ([`fits_one_tile`]), tiles otherwise.
    Auto,
    /// The tile passes whatever the length (for tests of one partial tile on that path).
    Tiles,
}

fn tile_emulation(width: u32, shared_words: usize) -> Emulation {
    Emulation { width, workgroup_size: SORT_WORKGROUP, shared_words }
}

/// Output buffers written by many emulated workgroups at once; each slot must be written once.
pub(crate) struct Out {
    keys: Vec<AtomicU32>,
    values: Vec<AtomicU32>,
    writes: Vec<AtomicU32>,
}

impl Out {
    pub(crate) fn new(n: usize) -> Self {
        let zeros = || (0..n).map(|_| AtomicU32::new(0)).collect();
        Self { keys: zeros(), values: zeros(), writes: zeros() }
    }

    pub(crate) fn write(&self, i: u32, key: u32, value: u32) {
        let i = i as usize;
        assert!(i < self.keys.len(), "destination {i} past the end ({})", self.keys.len());
        self.keys[i].store(key, Ordering::Relaxed);
        self.values[i].store(value, Ordering::Relaxed);
        self.writes[i].fetch_add(1, Ordering::Relaxed);
    }

    /// The written keys and values; panics unless every slot was written exactly once.
    pub(crate) fn finish(self) -> (Vec<u32>, Vec<u32>) {
        if let Some(i) = self.writes.iter().position(|w| w.load(Ordering::Relaxed) != 1) {
            panic!("slot {i} written {} times", self.writes[i].load(Ordering::Relaxed));
        }
        let plain = |v: Vec<AtomicU32>| v.into_iter().map(AtomicU32::into_inner).collect();
        (plain(self.keys), plain(self.values))
    }
}

/// Step 1: the global histogram of every pass, `hist[pass · 256 + digit]`.
pub(crate) fn global_histogram_emulated(width: u32, keys: &[u32], key_bits: u32) -> Vec<u32> {
    let n = keys.len() as u32;
    let groups = n.div_ceil(HISTOGRAM_KEYS);
    let rows = run_workgroups(tile_emulation(width, HISTOGRAM_SHARED_WORDS), groups, |g, c, s| {
        let base = g * HISTOGRAM_KEYS;
        global_histogram(c, s, (n - base).min(HISTOGRAM_KEYS), key_bits, |i| keys[(base + i) as usize])
    });
    let mut hist = vec![0u32; (MAX_PASSES * RADIX) as usize];
    for (i, counts) in rows.iter().enumerate() {
        for (pass, &count) in counts.iter().enumerate() {
            hist[pass * RADIX as usize + i % RADIX as usize] += count;
        }
    }
    hist
}

/// Sorts `keys` (below `2^key_bits`; `values` follow) at subgroup width `width` along `path`.
pub fn sort_emulated_with(width: u32, keys: &[u32], values: &[u32], key_bits: u32, path: Path) -> (Vec<u32>, Vec<u32>) {
    assert_eq!(keys.len(), values.len(), "one value per key");
    let n = keys.len() as u32;
    if n <= 1 || passes(key_bits) == 0 {
        return (keys.to_vec(), values.to_vec());
    }
    if path == Path::Auto && fits_one_tile(n) {
        let out = Out::new(n as usize);
        run_workgroups(tile_emulation(width, RADIX_SHARED_WORDS), 1, |_, c, s| {
            let slots = Slots::of(c);
            let k = load_items(slots, n, u32::MAX, |i| keys[i as usize]);
            let v = load_items(slots, n, 0, |i| values[i as usize]);
            let (k, v) = sort_tile(c, s, slots, k, v, key_bits);
            // The GPU stores keys and values apart; here both at once, from the same slots.
            store_items(slots, n, &k, |i, key| out.write(i, key, v[((i - slots.first) / slots.stride) as usize]));
        });
        return out.finish();
    }
    let tiles = n.div_ceil(RADIX_TILE);
    let tile_len = |t: u32| (n - t * RADIX_TILE).min(RADIX_TILE);
    let hist = global_histogram_emulated(width, keys, key_bits);
    let (mut k, mut v) = (keys.to_vec(), values.to_vec());
    for pass in 0..passes(key_bits) {
        let (shift, bits) = pass_digit(pass, key_bits);
        // 2.1 Tile counts, digit-major.
        let up = run_workgroups(tile_emulation(width, UPSWEEP_SHARED_WORDS), tiles, |t, c, s| {
            let base = t * RADIX_TILE;
            upsweep_tile(c, s, tile_len(t), shift, bits, |i| k[(base + i) as usize])
        });
        let mut counts = vec![0u32; (RADIX * tiles) as usize];
        for (i, &count) in up.iter().enumerate() {
            let (t, d) = (i / RADIX as usize, i % RADIX as usize);
            counts[d * tiles as usize + t] = count;
        }
        // 2.2 Starts of every (digit, tile).
        let starts = Out::new((RADIX * tiles) as usize);
        let bins = &hist[(pass * RADIX) as usize..];
        let digits = spine_digits(tiles);
        run_workgroups(tile_emulation(width, crate::scan::SCAN_SHARED_WORDS), RADIX / digits, |g, c, s| {
            spine(c, s, g * digits, digits, tiles, |e| bins[e as usize], |i| counts[i as usize], |i, start| starts.write(i, start, 0));
        });
        let starts = starts.finish().0;
        // 2.3 Rank, reorder, write.
        let out = Out::new(n as usize);
        run_workgroups(tile_emulation(width, RADIX_SHARED_WORDS), tiles, |t, c, s| {
            let base = t * RADIX_TILE;
            let start = starts[(c.local_index() * tiles + t) as usize];
            let (k, v) = (&k, &v);
            downsweep_tile(c, s, tile_len(t), start, (shift, bits), |i| k[(base + i) as usize], |i| v[(base + i) as usize], |d, key, value| {
                out.write(d, key, value)
            });
        });
        (k, v) = out.finish();
    }
    (k, v)
}

/// The sort of 32-bit keys at subgroup width `width`, as the host runs it.
pub fn sort_emulated(width: u32, keys: &[u32], values: &[u32]) -> (Vec<u32>, Vec<u32>) {
    sort_emulated_with(width, keys, values, 32, Path::Auto)
}
