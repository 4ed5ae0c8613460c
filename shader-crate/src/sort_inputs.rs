//! Inputs of the sort acceptance matrix, shared by the CPU emulation tests
//! (`sort_acceptance_tests.rs`) and the GPU tests (`tests/sort.rs`).

fn xorshift(seed: u32) -> impl FnMut() -> u32 {
    let mut x = seed | 1;
    move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    }
}

/// The five input shapes of the sort acceptance matrix, each `n` keys: all equal, already sorted,
/// reverse sorted, few distinct values (4) and random (seeded; with a real `0xFFFF_FFFF`, the
/// bitonic sort's padding key, in the middle).
pub fn shapes(n: usize, seed: u32) -> Vec<(&'static str, Vec<u32>)> {
    let mut rnd = xorshift(seed);
    let mut random: Vec<u32> = (0..n).map(|_| rnd()).collect();
    if n > 2 {
        random[n / 2] = u32::MAX;
    }
    vec![
        ("all equal", vec![0xdead_beef; n]),
        ("sorted", (0..n as u32).map(|i| i.wrapping_mul(3)).collect()),
        ("reverse", (0..n as u32).rev().collect()),
        ("few distinct", (0..n).map(|_| rnd() % 4).collect()),
        ("random", random),
    ]
}
