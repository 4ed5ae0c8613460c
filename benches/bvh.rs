//! Light assignment: BVH (Morton keys + sort + build + subgroup traversal) against the naive
//! all-lights search, for uniform and clustered (hotspot) light distributions, on `city` at
//! 1280×720.
//!
//! * **GPU** — timed with the renderer's own GPU timestamps (`iter_custom` sums the passes of
//!   interest over rendered frames; the light sort and build run on the graphics queue here,
//!   `async_compute: false`, so their time is not hidden behind the raster).
//! * **CPU** — the same kernels' functions run one after the other on one core over the frame's
//!   unique clusters (read back from the GPU frame): Morton keys + `sort_unstable` + node boxes +
//!   one walk per cluster, against the naive search per cluster (`clustered::for_each_cluster_light`).
//!   The clusters come from one read-back frame with 1k lights (they do not depend on the
//!   lights), so every size runs on any device. CPU sizes: `MANYLIGHTS_BVH_CPU_LIGHTS` (default
//!   1k,10k,100k,1M); the naive CPU search runs up to `MANYLIGHTS_BVH_CPU_NAIVE_MAX` lights
//!   (default 100k: at 1M it takes about a minute per iteration), larger sizes print a skip.
//!
//! `cargo bench -p host --bench bvh` (device: `MANYLIGHTS_DEVICE`; GPU light counts:
//! `MANYLIGHTS_BVH_LIGHTS`, default 1k,10k,100k,1M — sizes over lavapipe's per-invocation light
//! limit are skipped there). Quote GPU numbers from a real GPU only.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use host::gpu::Gpu;
use host::render::{self, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::{lights, Scene};
use host::vk::ContextOptions;
use shaders::layout::{PointLight, View};
use shaders::octahedral::Precision;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Passes that make up a technique's light assignment.
fn assignment_passes(t: Technique) -> &'static [&'static str] {
    match t {
        Technique::ClusteredBvh => &["morton keys", "light sort", "bvh build", "assignment"],
        _ => &["assignment"],
    }
}

fn sizes(var: &str, default: &[usize]) -> Vec<usize> {
    std::env::var(var).ok().map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect()).unwrap_or_else(|| default.to_vec())
}

fn settings(technique: Technique, read_back: bool) -> Settings {
    Settings {
        width: 1280,
        height: 720,
        tile_size: 32,
        technique,
        view: View::Shaded,
        normal_precision: Precision::Oct16,
        exposure: 1.0,
        frames: 1,
        read_back,
        bvh_branching: 0,
        morton_bits: 0,
        async_compute: false,
        sort: Default::default(),
        fp_lists: Default::default(),
        unique_clusters: Default::default(),
        oit: Default::default(),
        dispatch_times: false,
        msaa: 1,
        light_record: Default::default(),
        shadow: Default::default(),
    }
}

/// The two light distributions: uniform in the scene's bounds, and 8 hotspots.
fn distributions(scene: &Scene, n: usize) -> [(&'static str, Vec<PointLight>); 2] {
    [
        ("uniform", lights::uniform(scene, n, 3).expect("uniform lights")),
        ("clustered", lights::hotspots(scene.bounds, n, 3, 8).expect("hotspot lights")),
    ]
}

fn bvh(c: &mut Criterion) {
    let gpu = Gpu::new(&ContextOptions { validation: false, device: std::env::var("MANYLIGHTS_DEVICE").ok(), ..Default::default() }).expect("a Vulkan device");
    eprintln!("device: {}", gpu.ctx.info.line());
    let llvmpipe = gpu.ctx.info.is_llvmpipe();
    let scene = Scene::load("city", std::path::Path::new(".")).expect("city");
    let flat = flatten(&scene, Precision::Oct16).expect("flatten");
    let mut g = c.benchmark_group("light assignment (city 1280x720)");
    g.sample_size(10);
    for n in sizes("MANYLIGHTS_BVH_LIGHTS", &[1_000, 10_000, 100_000, 1_000_000]) {
        if llvmpipe && n > shaders::light_lists::MAX_LIGHTS_PER_INVOCATION_LLVMPIPE as usize {
            eprintln!("{n} lights: over lavapipe's loop limit, skipped");
            continue;
        }
        for (dist, l) in distributions(&scene, n) {
            for t in [Technique::ClusteredBvh, Technique::ClusteredNaive] {
                let s = settings(t, false);
                g.bench_function(BenchmarkId::new(format!("gpu {t:?} {dist}"), n), |b| {
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
    }
    // The frame's unique clusters do not depend on the lights: read them back once, from a
    // frame with few lights (lavapipe refuses frames over its per-invocation light limit, the
    // CPU versions have none).
    let few = lights::uniform(&scene, 1_000, 3).expect("uniform lights");
    let input = scene_input(&scene, &flat, &few);
    let f = render::render(&gpu, &input, &settings(Technique::ClusteredNaive, true)).expect("frame");
    let rb = f.readback.expect("read back");
    let naive_max = sizes("MANYLIGHTS_BVH_CPU_NAIVE_MAX", &[100_000])[0];
    for n in sizes("MANYLIGHTS_BVH_CPU_LIGHTS", &[1_000, 10_000, 100_000, 1_000_000]) {
        for (dist, l) in distributions(&scene, n) {
            let lights_view = render::lights_to_view(&input.view, &l).expect("lights within the shading contract");
            let p = shaders::layout::FrameParams { num_lights: n as u32, ..render::reference::cpu_params(&rb) };
            let branching = 32;
            g.bench_function(BenchmarkId::new(format!("cpu bvh {dist}"), n), |b| {
                b.iter_custom(|iters| {
                    let start = Instant::now();
                    for _ in 0..iters {
                        let (order, spheres, nodes) = render::bvh::build_cpu(&lights_view, branching);
                        let mut refs = 0u64;
                        for &key in &rb.unique {
                            let cluster = shaders::cluster_bounds::cluster_aabb_of_key(&p.grid, &rb.bounds, key);
                            refs += shaders::light_bvh::for_each_bvh_light(&nodes, &spheres, &order, p.num_lights, branching, &cluster, |_, _| {}) as u64;
                        }
                        black_box(refs);
                    }
                    start.elapsed()
                })
            });
            if n > naive_max {
                eprintln!("cpu naive {dist}/{n}: skipped (over MANYLIGHTS_BVH_CPU_NAIVE_MAX = {naive_max}; about a minute per iteration)");
                continue;
            }
            g.bench_function(BenchmarkId::new(format!("cpu naive {dist}"), n), |b| {
                b.iter_custom(|iters| {
                    let start = Instant::now();
                    for _ in 0..iters {
                        let mut refs = 0u64;
                        for &key in &rb.unique {
                            refs += shaders::clustered::for_each_cluster_light(&p, &rb.bounds, &lights_view, key, |_, _| {}) as u64;
                        }
                        black_box(refs);
                    }
                    start.elapsed()
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bvh);
criterion_main!(benches);
