//! GPU radix sort (key–value, stable) on the local device, validation on: the output equals a
//! stable sort of the input for every length from one tile to two tiles + 1, the special
//! lengths, and 2^20 (+17), on all-equal, sorted, reverse, few-distinct and random keys.
mod common;
use host::gpu::Gpu;
use host::render::sort::RadixSort;
use host::vk::Buffer;

fn inputs(n: usize, seed: u32) -> Vec<(&'static str, Vec<u32>)> {
    let mut x = seed | 1;
    let mut rnd = move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    vec![
        ("all equal", vec![0xdead_beef; n]),
        ("sorted", (0..n as u32).map(|i| i.wrapping_mul(3)).collect()),
        ("reverse", (0..n as u32).rev().collect()),
        ("few distinct", (0..n).map(|_| rnd() % 4).collect()),
        ("random", (0..n).map(|_| rnd()).collect()),
    ]
}

fn check(gpu: &Gpu, sorter: &RadixSort, keys: &[u32], what: &str) {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let mut kb = Buffer::from_slice(&gpu.ctx, "keys", keys).unwrap();
    let mut vb = Buffer::from_slice(&gpu.ctx, "values", &values).unwrap();
    gpu.run(None, |rec| sorter.record(gpu, rec, &kb, &vb, n as u32, 32)).unwrap();
    let (k, v): (Vec<u32>, Vec<u32>) = (kb.read(n).unwrap(), vb.read(n).unwrap());
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    expected.sort_by_key(|e| e.0);
    let got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
    if got != expected {
        let first = got.iter().zip(&expected).position(|(a, b)| a != b);
        panic!("{what} (n = {n}): first difference at {first:?}");
    }
}

#[test]
fn small_and_partial_tile_lengths() {
    let gpu = common::gpu();
    let sorter = RadixSort::new(&gpu, 1024).unwrap();
    let mut lengths: Vec<usize> = vec![0, 1, 2, 3, 127, 128, 129];
    lengths.extend(256..=513); // every size from one tile to two tiles + 1
    for n in lengths {
        for (what, keys) in inputs(n, n as u32 + 1) {
            if n > 3 && n < 256 && what != "random" {
                continue; // the shapes matter for the boundary lengths, not every small one
            }
            check(&gpu, &sorter, &keys, what);
        }
    }
    common::assert_clean(&gpu);
}

#[test]
fn a_million_keys() {
    let gpu = common::gpu();
    let n = (1 << 20) + 17;
    let sorter = RadixSort::new(&gpu, n as u32).unwrap();
    for (what, keys) in inputs(n, 99) {
        check(&gpu, &sorter, &keys, what);
        check(&gpu, &sorter, &keys[..1 << 20], what);
    }
    common::assert_clean(&gpu);
}
