//! Light assignment: BVH (Morton keys + radix sort + build + traversal) against the naive
//! all-lights search, timed with the renderer's own GPU timestamps (`iter_custom` sums the
//! passes of interest over rendered frames) on `city` at 1280×720.
//!
//! `cargo bench -p host --bench bvh` (device: `MANYLIGHTS_DEVICE`; light counts:
//! `MANYLIGHTS_BVH_LIGHTS`, default 1k,10k,100k,1M — sizes over lavapipe's per-invocation light
//! limit are skipped there). Quote GPU numbers from a real GPU only.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use host::gpu::Gpu;
use host::render::{self, Settings, Technique};
use host::render_cmd::{flatten, scene_input};
use host::scene::{lights, Scene};
use host::vk::ContextOptions;
use shaders::layout::{PRECISION_OCT16, VIEW_SHADED};
use std::time::Duration;

/// Passes that make up a technique's light assignment.
fn assignment_passes(t: Technique) -> &'static [&'static str] {
    match t {
        Technique::ClusteredBvh => &["light sort", "bvh build", "assignment"],
        _ => &["assignment"],
    }
}

fn bvh(c: &mut Criterion) {
    let gpu = Gpu::new(&ContextOptions { validation: false, device: std::env::var("MANYLIGHTS_DEVICE").ok() }).expect("a Vulkan device");
    eprintln!("device: {}", gpu.ctx.info.line());
    let llvmpipe = gpu.ctx.info.driver_name.to_lowercase().contains("llvmpipe");
    let counts: Vec<usize> = std::env::var("MANYLIGHTS_BVH_LIGHTS")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1_000, 10_000, 100_000, 1_000_000]);
    let scene = Scene::load("city", std::path::Path::new(".")).expect("city");
    let flat = flatten(&scene, PRECISION_OCT16).expect("flatten");
    let mut g = c.benchmark_group("light assignment (city 1280x720)");
    g.sample_size(10);
    for n in counts {
        if llvmpipe && n > shaders::clustered::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE as usize {
            eprintln!("{n} lights: over lavapipe's loop limit, skipped");
            continue;
        }
        let l = lights::uniform(&scene, n, 3).expect("lights");
        for t in [Technique::ClusteredBvh, Technique::ClusteredNaive] {
            let s = Settings {
                width: 1280,
                height: 720,
                tile_size: 32,
                technique: t,
                view: VIEW_SHADED,
                normal_precision: PRECISION_OCT16,
                exposure: 1.0,
                frames: 1,
                read_back: false,
                bvh_branching: 0,
                async_compute: true,
            };
            g.bench_function(BenchmarkId::new(format!("{t:?}"), n), |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        let f = render::render(&gpu, &scene_input(&scene, &flat, &l), &s).expect("frame");
                        let ms: f64 = f.timings.iter().filter(|p| assignment_passes(t).contains(&p.name.as_str())).map(|p| p.ms).sum();
                        total += Duration::from_secs_f64(ms * 1e-3);
                    }
                    total
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bvh);
criterion_main!(benches);
