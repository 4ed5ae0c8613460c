//! Key–value sorting of 30-bit keys (the light BVH's Morton keys), per input distribution:
//! - **uniform**: random 30-bit keys;
//! - **clustered**: 30-bit Morton codes of lights gathered around a few hotspots (long runs of
//!   nearby and equal keys, as a scene's light clusters give).
//!
//! Per distribution and size: the GPU radix and bitonic sorts (`host::render::sort`,
//! `host::render::bitonic`), timed with GPU timestamps (`iter_custom`: the keys are re-uploaded
//! before each run, outside the timed pass); Rust's `sort_unstable_by_key` on the CPU as an
//! anchor; and the CPU versions of the kernels — the same functions in the lock-step emulation
//! (`shaders::radix::pass_emulated`, `shaders::bitonic::emulated::sort_emulated`: every
//! invocation a coroutine, switched at each shuffle, ballot and barrier), which measure the
//! emulation, not a CPU sort.
//!
//! `cargo bench -p host --bench sort`. Environment: `MANYLIGHTS_DEVICE`; GPU sizes
//! `MANYLIGHTS_SORT_SIZES` (default 1k,10k,100k,1M,16M); emulated sizes
//! `MANYLIGHTS_SORT_CPU_SIZES` (default 1k,10k,100k,1M; a few µs per key) at
//! subgroup width `MANYLIGHTS_SORT_CPU_WIDTH` (default 8). lavapipe's timestamps do not bracket
//! its work: quote GPU numbers from a real GPU only.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use host::gpu::Gpu;
use host::render::sort::{LightSorter, SortKind};
use host::vk::{Buffer, ContextOptions, Profiler};
use shaders::morton::{MortonQuantizer, MORTON30_BITS};
use std::time::Duration;

fn env_sizes(var: &str, default: &[usize]) -> Vec<usize> {
    std::env::var(var)
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

fn xorshift(seed: u32) -> impl FnMut() -> u32 {
    let mut x = seed;
    move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    }
}

/// Random 30-bit keys.
fn uniform(n: usize) -> Vec<u32> {
    let mut rnd = xorshift(0x9e37_79b9);
    (0..n).map(|_| rnd() >> 2).collect()
}

/// Morton codes of `n` lights around 6 hotspots in a unit cube (each light within ±2% of its
/// hotspot per axis), quantised over the cube.
fn clustered(n: usize) -> Vec<u32> {
    let mut rnd = xorshift(0x2545_f491);
    let mut unit = move || (rnd() >> 8) as f32 / (1u32 << 24) as f32;
    let hotspots: Vec<[f32; 3]> = (0..6).map(|_| [0.1 + 0.8 * unit(), 0.1 + 0.8 * unit(), 0.1 + 0.8 * unit()]).collect();
    let q = MortonQuantizer::new([0.0; 3], [1.0; 3], MORTON30_BITS);
    (0..n)
        .map(|i| {
            let h = hotspots[i % hotspots.len()];
            q.morton30_of([h[0] + 0.04 * (unit() - 0.5), h[1] + 0.04 * (unit() - 0.5), h[2] + 0.04 * (unit() - 0.5)])
        })
        .collect()
}

type Distribution = (&'static str, fn(usize) -> Vec<u32>);
const DISTRIBUTIONS: [Distribution; 2] = [("uniform", uniform), ("clustered", clustered)];

fn gpu_sort(c: &mut Criterion) {
    let gpu = Gpu::new(&ContextOptions { validation: false, device: std::env::var("MANYLIGHTS_DEVICE").ok() })
        .expect("a Vulkan device");
    eprintln!("device: {}", gpu.ctx.info.line());
    for (dist, make) in DISTRIBUTIONS {
        let mut g = c.benchmark_group(format!("key-value sort/{dist}"));
        g.sample_size(10);
        for n in env_sizes("MANYLIGHTS_SORT_SIZES", &[1_000, 10_000, 100_000, 1_000_000, 16_000_000]) {
            let k = make(n);
            let values: Vec<u32> = (0..n as u32).collect();
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::new("cpu sort_unstable", n), &k, |b, k| {
                b.iter_batched(
                    || k.iter().copied().zip(values.iter().copied()).collect::<Vec<(u32, u32)>>(),
                    |mut kv| kv.sort_unstable_by_key(|e| e.0),
                    criterion::BatchSize::LargeInput,
                )
            });
            let mut kb = Buffer::from_slice(&gpu.ctx, "bench keys", &k).expect("keys");
            let mut vb = Buffer::from_slice(&gpu.ctx, "bench values", &values).expect("values");
            for (name, kind) in [("gpu radix (timestamps)", SortKind::Radix), ("gpu bitonic (timestamps)", SortKind::Bitonic)] {
                let sorter = LightSorter::new(&gpu, kind, n as u32).expect("sort buffers");
                g.bench_function(BenchmarkId::new(name, n), |b| {
                    b.iter_custom(|iters| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iters {
                            kb.write(&k).expect("re-upload keys");
                            vb.write(&values).expect("re-upload values");
                            let mut prof = Profiler::new(&gpu.ctx, 1).expect("profiler");
                            gpu.run(Some(&mut prof), |rec| rec.pass("sort", |rec| sorter.record(&gpu, rec, &kb, &vb, n as u32, 30)))
                                .expect("sort");
                            let ms = prof.results().expect("timestamps").first().map_or(0.0, |t| t.ms);
                            total += Duration::from_secs_f64(ms * 1e-3);
                        }
                        total
                    })
                });
            }
        }
        g.finish();
    }
}

fn emulated_sort(c: &mut Criterion) {
    let width: u32 = std::env::var("MANYLIGHTS_SORT_CPU_WIDTH").ok().and_then(|w| w.parse().ok()).unwrap_or(8);
    for (dist, make) in DISTRIBUTIONS {
        let mut g = c.benchmark_group(format!("key-value sort (CPU emulation, width {width})/{dist}"));
        g.sample_size(10).warm_up_time(Duration::from_millis(100)).measurement_time(Duration::from_secs(1));
        for n in env_sizes("MANYLIGHTS_SORT_CPU_SIZES", &[1_000, 10_000, 100_000, 1_000_000]) {
            let k = make(n);
            let values: Vec<u32> = (0..n as u32).collect();
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::new("emulated radix", n), &k, |b, k| {
                b.iter(|| shaders::radix::emulated::sort_emulated_with(width, k, &values, 30, shaders::radix::emulated::Path::Auto))
            });
            g.bench_with_input(BenchmarkId::new("emulated bitonic", n), &k, |b, k| {
                b.iter(|| shaders::bitonic::emulated::sort_emulated(width, width, k, &values))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, gpu_sort, emulated_sort);
criterion_main!(benches);
