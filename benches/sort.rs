//! Key–value sorting: the GPU radix sort (`host::render::sort`), timed with GPU timestamps
//! (`iter_custom`: the keys are re-uploaded before each run, outside the timed pass), next to
//! Rust's `sort_unstable_by_key` on the CPU in the same run as an anchor.
//!
//! `cargo bench -p host --bench sort` (device: `MANYLIGHTS_DEVICE`, sizes: `MANYLIGHTS_SORT_SIZES`,
//! default 1k,10k,100k,1M,16M). lavapipe's timestamps do not bracket its work: quote GPU numbers
//! from a real GPU only.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use host::gpu::Gpu;
use host::render::sort::RadixSort;
use host::vk::{Buffer, ContextOptions, Profiler};
use std::time::Duration;

fn sizes() -> Vec<usize> {
    std::env::var("MANYLIGHTS_SORT_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1_000, 10_000, 100_000, 1_000_000, 16_000_000])
}

fn keys(n: usize) -> Vec<u32> {
    let mut x = 0x9e37_79b9u32;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x >> 2 // 30-bit, like the Morton keys of the light BVH
        })
        .collect()
}

fn sort(c: &mut Criterion) {
    let gpu = Gpu::new(&ContextOptions { validation: false, device: std::env::var("MANYLIGHTS_DEVICE").ok() })
        .expect("a Vulkan device");
    eprintln!("device: {}", gpu.ctx.info.line());
    let mut g = c.benchmark_group("key-value sort");
    g.sample_size(10);
    for n in sizes() {
        let k = keys(n);
        let values: Vec<u32> = (0..n as u32).collect();
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new("cpu sort_unstable", n), &k, |b, k| {
            b.iter_batched(
                || k.iter().copied().zip(values.iter().copied()).collect::<Vec<(u32, u32)>>(),
                |mut kv| kv.sort_unstable_by_key(|e| e.0),
                criterion::BatchSize::LargeInput,
            )
        });
        let sorter = RadixSort::new(&gpu, n as u32).expect("sort buffers");
        let mut kb = Buffer::from_slice(&gpu.ctx, "bench keys", &k).expect("keys");
        let mut vb = Buffer::from_slice(&gpu.ctx, "bench values", &values).expect("values");
        g.bench_function(BenchmarkId::new("gpu radix (timestamps)", n), |b| {
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
    g.finish();
}

criterion_group!(benches, sort);
criterion_main!(benches);
