//! CPU throughput of the foundation kernels (the same functions the GPU runs), as an anchor for
//! the GPU timings: `cargo bench -p host --bench kernels_cpu`. GPU timings come from
//! `manylights render --stats` (timestamps); the sort and BVH benches are `benches/sort.rs` and
//! `benches/bvh.rs`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use shaders::cluster_key::{slice_bounds, ClusterGrid};
use shaders::coop::cpu::{run_workgroups, Emulation};
use shaders::morton::{MortonQuantizer, MORTON30_BITS};
use shaders::octahedral::{decode, encode, fibonacci_sphere, Precision};
use shaders::scan::{workgroup_exclusive_scan, SCAN_SHARED_WORDS, SCAN_WORKGROUP};

const N: u32 = 1 << 16;

fn octahedral(c: &mut Criterion) {
    let dirs: Vec<[f32; 3]> = (0..N).map(|i| fibonacci_sphere(i, N)).collect();
    let mut g = c.benchmark_group("octahedral round trip");
    g.throughput(Throughput::Elements(N as u64));
    for p in Precision::ALL {
        g.bench_with_input(BenchmarkId::from_parameter(p.bits()), &p, |b, &p| {
            b.iter(|| dirs.iter().map(|d| decode(encode(*d, p), p)[2]).sum::<f32>())
        });
    }
    g.finish();
}

fn cluster_keys(c: &mut Criterion) {
    let grid = ClusterGrid::new(1920, 1080, 32, 0.1, 1000.0, 60f32.to_radians()).unwrap();
    let bounds = slice_bounds(&grid);
    let mut g = c.benchmark_group("cluster keys");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("1080p", |b| {
        b.iter(|| (0..N).map(|i| grid.key(&bounds, i % 1920, i / 1920 * 31, -0.1 * (1.0 + i as f32 * 0.15))).fold(0u32, |a, k| a ^ k))
    });
    g.finish();
}

fn morton(c: &mut Criterion) {
    let q = MortonQuantizer::new([-10.0; 3], [10.0; 3], MORTON30_BITS);
    let pts: Vec<[f32; 3]> = (0..N).map(|i| fibonacci_sphere(i, N).map(|x| x * 9.0)).collect();
    let mut g = c.benchmark_group("morton30");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("quantise + interleave", |b| b.iter(|| pts.iter().fold(0u32, |a, p| a ^ q.morton30_of(black_box(*p)))));
    g.finish();
}

/// The lock-step emulation is a test harness, not a fast path: this measures its overhead.
fn emulated_scan(c: &mut Criterion) {
    let mut g = c.benchmark_group("workgroup scan (CPU emulation, 1 workgroup)");
    g.sample_size(10);
    for width in [8, 32] {
        let emu = Emulation { width, workgroup_size: SCAN_WORKGROUP, shared_words: SCAN_SHARED_WORDS };
        g.bench_with_input(BenchmarkId::from_parameter(width), &emu, |b, &emu| {
            b.iter(|| run_workgroups(emu, 1, |_, c, s| workgroup_exclusive_scan(c, s, 1)))
        });
    }
    g.finish();
}

criterion_group!(benches, octahedral, cluster_keys, morton, emulated_scan);
criterion_main!(benches);
