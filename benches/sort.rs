//! Key–value sorting of 30-bit keys (the light BVH's Morton keys), per input distribution:
//! - **uniform**: random 30-bit keys;
//! - **clustered**: 30-bit Morton codes of lights gathered around a few hotspots (long runs of
//!   nearby and equal keys, as a scene's light clusters give).
//!
//! Per distribution and size: the GPU radix sort (`host::render::sort`: both cross-tile variants
//! where the device runs both, else its own) and the bitonic sort (`host::render::bitonic`),
//! timed with GPU timestamps (`iter_custom`: batches of sorts recorded back to back, each of a GPU copy of the unsorted pairs made outside the timed pass,
//! so the GPU stays busy as in a frame — sorts separated by host uploads let its clocks drop and
//! measured several times slower than the same sort inside a frame); Rust's `sort_unstable_by_key` on the
//! CPU as an anchor; and the CPU versions of the kernels — the same functions in the lock-step
//! emulation (`shaders::radix::emulated`, `shaders::bitonic::emulated`: every invocation a
//! coroutine, switched at each shuffle, ballot and barrier), which measure the emulation, not a
//! CPU sort. Criterion reports each as keys/s (`thrpt`).
//!
//! First a summary table of every GPU sort on uniform keys: median GPU ms of 3 batches, keys/s and
//! wall-clock ms per sort (each sort's output checked: ordered keys, each with its input index),
//! and beside the radix and `auto` rows CUB's key–value sort (CuPy `argsort` + gather,
//! `benches/cub_sort.py`) where the device is an NVIDIA GPU with CuPy, with the ratio to CUB.
//!
//! `cargo bench -p host --bench sort`. Environment: `MANYLIGHTS_DEVICE`;
//! `MANYLIGHTS_BITONIC_KEEPS` (e.g. `1,2,4,8`: the bitonic sort again with each splitter keep,
//! beside the default); GPU sizes
//! `MANYLIGHTS_SORT_SIZES` (default 1k,64k,1M,4M,16M; sizes whose buffers exceed the device's
//! `maxStorageBufferRange` are skipped with a note); emulated sizes `MANYLIGHTS_SORT_CPU_SIZES`
//! (default 1k,64k,1M; a few µs per key) at subgroup width `MANYLIGHTS_SORT_CPU_WIDTH` (default
//! 8); `MANYLIGHTS_SORT_PARTS` (set: below each radix row, the GPU ms of each of its kernels,
//! fills and copies); `MANYLIGHTS_SORT_KEY_BITS` (default 30: the summary's keys are drawn that
//! wide and the radix sort orders that many bits, 8 per pass — 8, 16, 24 give one to three
//! passes; CuPy's `argsort` takes no bit range, so CUB's column stays the 30-bit sort). lavapipe's timestamps do not bracket
//! its work: quote GPU numbers from a real GPU only.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use host::gpu::Gpu;
use host::render::bitonic::BitonicSort;
use host::render::sort::{CrossTile, LightSorter, RadixSort, SortKind};
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

const GPU_SIZES: [usize; 5] = [1_000, 64_000, 1_000_000, 4_000_000, 16_000_000];

fn open_gpu() -> Gpu {
    Gpu::new(&ContextOptions { validation: false, device: std::env::var("MANYLIGHTS_DEVICE").ok(), ..Default::default() }).expect("a Vulkan device")
}

/// The GPU sizes that fit one storage-buffer binding of the device.
fn gpu_sizes(gpu: &Gpu) -> Vec<usize> {
    let max = gpu.ctx.info.max_storage_buffer_range as usize;
    env_sizes("MANYLIGHTS_SORT_SIZES", &GPU_SIZES)
        .into_iter()
        .filter(|&n| {
            let fits = 4 * n <= max;
            if !fits {
                eprintln!("{n} pairs: {} B per buffer exceed this device's {max} B per binding, skipped", 4 * n);
            }
            fits
        })
        .collect()
}

/// The sorts timed on the GPU: the device's radix variant for `n`, the other one too where the
/// device runs both, the bitonic sort (with each keep of `MANYLIGHTS_BITONIC_KEEPS` too) and the
/// light pipeline's default, which picks one of them by size (`SortKind::Auto`).
fn gpu_sorters(gpu: &Gpu, n: u32) -> Vec<(String, LightSorter)> {
    let radix = RadixSort::new(gpu, n).expect("radix sort buffers");
    let name = |c: CrossTile| format!("gpu radix {} (timestamps)", if c == CrossTile::Chained { "chained" } else { "reduce-then-scan" });
    let cross = radix.cross_tile();
    let mut v = vec![(name(cross), LightSorter::Radix(Box::new(radix)))];
    // The other variant where the device can run both.
    let other = if cross == CrossTile::Chained { CrossTile::ReduceThenScan } else { CrossTile::Chained };
    if let Ok(other) = RadixSort::with_cross_tile(gpu, n, other) {
        v.push((name(other.cross_tile()), LightSorter::Radix(Box::new(other))));
    }
    v.push(("gpu bitonic (timestamps)".into(), LightSorter::new(gpu, SortKind::Bitonic, n).expect("bitonic sort buffers")));
    v.push(("gpu auto (timestamps)".into(), LightSorter::new(gpu, SortKind::Auto, n).expect("light sort buffers")));
    for keep in env_sizes("MANYLIGHTS_BITONIC_KEEPS", &[]) {
        let sort = BitonicSort::with_keep(gpu, n, keep as u32).expect("bitonic sort buffers");
        v.push((format!("gpu bitonic keep {keep} (timestamps)"), LightSorter::Bitonic(Box::new(sort))));
    }
    v
}

/// Bits of a 30-bit Morton key (3 × `MORTON30_BITS`).
const KEY_BITS: u32 = 3 * MORTON30_BITS;

/// Bits of the keys the GPU sorts (`MANYLIGHTS_SORT_KEY_BITS`, default [`KEY_BITS`]).
fn key_bits() -> u32 {
    std::env::var("MANYLIGHTS_SORT_KEY_BITS").ok().and_then(|b| b.parse().ok()).unwrap_or(KEY_BITS)
}

/// Sorts timed back to back in one submission by [`Inputs::time`].
const BATCH: u32 = 8;

/// The unsorted pairs on the GPU (`src_*`, never sorted) and the buffers sorted in place.
struct Inputs {
    n: u32,
    /// Bits the sorts order by ([`key_bits`]).
    key_bits: u32,
    src_keys: Buffer,
    src_values: Buffer,
    keys: Buffer,
    values: Buffer,
}

impl Inputs {
    fn new(gpu: &Gpu, k: &[u32], values: &[u32]) -> Self {
        let ctx = &gpu.ctx;
        Self {
            n: k.len() as u32,
            key_bits: key_bits(),
            src_keys: Buffer::from_slice(ctx, "bench keys (unsorted)", k).expect("keys"),
            src_values: Buffer::from_slice(ctx, "bench values (unsorted)", values).expect("values"),
            keys: Buffer::from_slice(ctx, "bench keys", k).expect("keys"),
            values: Buffer::from_slice(ctx, "bench values", values).expect("values"),
        }
    }

    /// GPU milliseconds (timestamps) of each of [`BATCH`] sorts recorded back to back in one
    /// submission, each of a fresh copy of the unsorted pairs (the copies are outside the timed
    /// passes), and the submission's wall-clock milliseconds over [`BATCH`]. The GPU stays busy
    /// through the batch, as it does through a frame: single sorts separated by host uploads let
    /// it idle between them, and its clocks drop.
    fn time(&self, gpu: &Gpu, sorter: &LightSorter) -> (Vec<f64>, f64) {
        let mut prof = Profiler::new(&gpu.ctx, BATCH).expect("profiler");
        let bytes = 4 * self.n as u64;
        let wall = std::time::Instant::now();
        gpu.run(Some(&mut prof), |rec| {
            for _ in 0..BATCH {
                rec.copy(&self.src_keys, &self.keys, bytes)?;
                rec.copy(&self.src_values, &self.values, bytes)?;
                rec.pass("sort", |rec| sorter.record(gpu, rec, &self.keys, &self.values, self.n, self.key_bits))?;
            }
            Ok(())
        })
        .expect("sort");
        let wall_ms = wall.elapsed().as_secs_f64() * 1e3 / BATCH as f64;
        (prof.results().expect("timestamps").iter().filter(|t| !t.part).map(|t| t.ms).collect(), wall_ms)
    }

    /// Panics unless the last sort left `keys` ordered by their low [`key_bits`] bits with each
    /// value the input index of its key (a permutation): no time is reported for a wrong sort.
    fn check(&mut self, unsorted: &[u32], what: &str) {
        let n = self.n as usize;
        let (keys, values): (Vec<u32>, Vec<u32>) = (self.keys.read(n).expect("keys"), self.values.read(n).expect("values"));
        let mask = if self.key_bits >= 32 { u32::MAX } else { (1u32 << self.key_bits) - 1 };
        if let Some(i) = (1..n).find(|&i| keys[i - 1] & mask > keys[i] & mask) {
            panic!("{what}, {n} pairs: keys out of order at {i}");
        }
        let mut seen = vec![false; n];
        for (i, (&k, &v)) in keys.iter().zip(&values).enumerate() {
            let v = v as usize;
            assert!(v < n && !seen[v] && unsorted[v] == k, "{what}, {n} pairs: pair {i} ({k}, {v}) is not an input pair");
            seen[v] = true;
        }
    }

    /// GPU milliseconds per sort of each kind of command (every dispatch of a kernel, every fill,
    /// every copy inside the sort; `MANYLIGHTS_SORT_PARTS`): summed over a batch of [`BATCH`]
    /// sorts recorded with a timestamp around each command, divided by [`BATCH`].
    fn parts(&self, gpu: &Gpu, sorter: &LightSorter) -> Vec<(String, f64)> {
        let mut prof = Profiler::new(&gpu.ctx, BATCH * 24).expect("profiler").with_parts(true);
        let bytes = 4 * self.n as u64;
        gpu.run(Some(&mut prof), |rec| {
            for _ in 0..BATCH {
                rec.copy(&self.src_keys, &self.keys, bytes)?;
                rec.copy(&self.src_values, &self.values, bytes)?;
                rec.pass("sort", |rec| sorter.record(gpu, rec, &self.keys, &self.values, self.n, self.key_bits))?;
            }
            Ok(())
        })
        .expect("sort");
        let mut by_kind: Vec<(String, f64)> = Vec::new();
        for t in prof.results().expect("timestamps").into_iter().filter(|t| t.part) {
            // "sort · radix_chained #3" → "radix_chained"
            let kind = t.name.trim_start_matches("sort · ").split(" #").next().unwrap_or_default().to_owned();
            match by_kind.iter_mut().find(|e| e.0 == kind) {
                Some(e) => e.1 += t.ms / BATCH as f64,
                None => by_kind.push((kind, t.ms / BATCH as f64)),
            }
        }
        by_kind
    }
}

fn gpu_sort(c: &mut Criterion) {
    let gpu = open_gpu();
    eprintln!("device: {}", gpu.ctx.info.line());
    for (dist, make) in DISTRIBUTIONS {
        let mut g = c.benchmark_group(format!("key-value sort/{dist}"));
        g.sample_size(10);
        for n in gpu_sizes(&gpu) {
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
            let inputs = Inputs::new(&gpu, &k, &values);
            for (name, sorter) in gpu_sorters(&gpu, n as u32) {
                g.bench_function(BenchmarkId::new(name, n), |b| {
                    // Per iteration the median sort of a batch (the first sorts of a batch warm up).
                    b.iter_custom(|iters| (0..iters).map(|_| Duration::from_secs_f64(median(inputs.time(&gpu, &sorter).0) * 1e-3)).sum())
                });
            }
        }
        g.finish();
    }
}

/// CUB's key–value milliseconds per size from `benches/cub_sort.py` (NVIDIA with CuPy only).
fn cub_ms(gpu: &Gpu, sizes: &[usize]) -> Option<Vec<(usize, f64)>> {
    const NVIDIA: u32 = 0x10de;
    if gpu.ctx.info.vendor_id != NVIDIA {
        return None;
    }
    // From the checkout it was built in, else from the working directory (a copied binary).
    let built_in = concat!(env!("CARGO_MANIFEST_DIR"), "/../benches/cub_sort.py");
    let script = if std::path::Path::new(built_in).exists() { built_in } else { "benches/cub_sort.py" };
    let out = match std::process::Command::new("python3").arg(script).args(sizes.iter().map(|n| n.to_string())).output() {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).into_owned(),
        Ok(o) => {
            eprintln!("CUB reference unavailable: {script} failed: {}", String::from_utf8_lossy(&o.stderr).trim());
            return None;
        }
        Err(e) => {
            eprintln!("CUB reference unavailable: cannot run python3: {e}");
            return None;
        }
    };
    // "cupy 14.2.0 n=1000000: sort (keys) 0.090 ms, argsort+gather (key-value) 0.138 ms"
    let parse = |line: &str| -> Option<(usize, f64)> {
        let n = line.split("n=").nth(1)?.split(':').next()?.parse().ok()?;
        let ms = line.split("(key-value) ").nth(1)?.trim_end_matches(" ms").trim().parse().ok()?;
        Some((n, ms))
    };
    Some(out.lines().filter_map(parse).collect())
}

/// Median of `xs` (`render::frame_time::spread`, as the frame's medians).
fn median(xs: Vec<f64>) -> f64 {
    host::render::frame_time::spread(xs).expect("timed sorts").0
}

/// The summary (see the module doc), printed before the criterion groups: every GPU sort on
/// uniform keys, GPU medians of 3 batches of [`BATCH`] sorts and wall-clock per sort, CUB beside
/// the radix and `auto` rows.
fn radix_summary(_: &mut Criterion) {
    let gpu = open_gpu();
    let sizes = gpu_sizes(&gpu);
    let cub = cub_ms(&gpu, &sizes);
    println!("\nGPU sorts, uniform keys of {} bits, {}:", key_bits().min(30), gpu.ctx.info.line());
    if gpu.ctx.info.is_llvmpipe() {
        println!("(lavapipe: its timestamps do not bracket its work, so GPU ms and keys/s are not GPU times; wall ms compare the sorts roughly)");
    }
    println!("| pairs | sort | GPU ms | M keys/s | wall ms | CUB ms | / CUB |");
    println!("|---|---|---|---|---|---|---|");
    // Keys as wide as the bits sorted (a frame's Morton keys of `b` bits per axis stay below
    // 2^(3b)): the bitonic sort orders whole keys, the radix sort only the low `key_bits`.
    let mask = if key_bits() >= 32 { u32::MAX } else { (1u32 << key_bits()) - 1 };
    for n in sizes {
        let k: Vec<u32> = uniform(n).into_iter().map(|x| x & mask).collect();
        let values: Vec<u32> = (0..n as u32).collect();
        let mut inputs = Inputs::new(&gpu, &k, &values);
        let cub_n = cub.as_ref().and_then(|c| c.iter().find(|e| e.0 == n).map(|e| e.1));
        for (name, sorter) in gpu_sorters(&gpu, n as u32) {
            let runs: Vec<(Vec<f64>, f64)> = (0..3).map(|_| inputs.time(&gpu, &sorter)).collect();
            inputs.check(&k, &name);
            let gpu_ms = median(runs.iter().flat_map(|r| r.0.iter().copied()).collect());
            let wall_ms = median(runs.iter().map(|r| r.1).collect());
            let (cub_col, ratio) = match cub_n {
                Some(c) if !matches!(sorter, LightSorter::Bitonic(_)) => (format!("{c:.3}"), format!("{:.2}×", gpu_ms / c)),
                _ => ("—".into(), "—".into()),
            };
            let name = name.trim_start_matches("gpu ").trim_end_matches(" (timestamps)");
            println!("| {n} | {name} | {gpu_ms:.3} | {:.1} | {wall_ms:.2} | {cub_col} | {ratio} |", n as f64 / gpu_ms * 1e-3);
            if std::env::var_os("MANYLIGHTS_SORT_PARTS").is_some() && !matches!(sorter, LightSorter::Bitonic(_)) {
                let parts = inputs.parts(&gpu, &sorter);
                let line: Vec<String> = parts.iter().map(|(p, ms)| format!("{} {ms:.3}", p.trim_start_matches("sort · "))).collect();
                println!("|  | ↳ parts (GPU ms) | {} |  |  |  |  |", line.join(", "));
            }
        }
    }
}

fn emulated_sort(c: &mut Criterion) {
    let width: u32 = std::env::var("MANYLIGHTS_SORT_CPU_WIDTH").ok().and_then(|w| w.parse().ok()).unwrap_or(8);
    for (dist, make) in DISTRIBUTIONS {
        let mut g = c.benchmark_group(format!("key-value sort (CPU emulation, width {width})/{dist}"));
        g.sample_size(10).warm_up_time(Duration::from_millis(100)).measurement_time(Duration::from_secs(1));
        for n in env_sizes("MANYLIGHTS_SORT_CPU_SIZES", &[1_000, 64_000, 1_000_000]) {
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

// The summary first: a run cut short by a time limit still has the table with CUB beside it.
criterion_group!(benches, radix_summary, gpu_sort, emulated_sort);
criterion_main!(benches);
