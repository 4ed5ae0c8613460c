//! GPU-vs-CPU parity: every kernel runs on the device and is compared with the same pure
//! function run on the CPU. Integer outputs must be bit-equal; float outputs must lie within the
//! ULP bound stated next to each check (derived from Vulkan's precision rules). Used by the test
//! suite (on lavapipe) and by `manylights check` (on any device, e.g. an H100).
//!
//! Each check returns a [`Report`] or an error listing the first mismatches.
use crate::gpu::Gpu;
use crate::vk::Buffer;
use anyhow::{bail, ensure, Result};
use shaders::cluster_key::{slice_bounds, ClusterGrid};
use shaders::coop::cpu::{run_workgroups, Emulation};
use shaders::coop::Coop;
use shaders::layout::*;
use shaders::scan::{self, SCAN_SHARED_WORDS, SCAN_WORKGROUP};
use std::fmt;

mod octa;
pub use octa::{octahedral, octahedral_inputs};
mod morton;
pub use self::morton::morton_codes;
mod nurbs;
pub use self::nurbs::nurbs_tessellation;

/// Outcome of one parity check.
#[derive(Clone, Debug)]
pub struct Report {
    pub kernel: String,
    pub cases: usize,
    /// What was compared and how (exact / ULP bound / tie rule), with measured figures.
    pub detail: String,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ok  {:<28} {:>9} cases  {}", self.kernel, self.cases, self.detail)
    }
}

/// Runs every parity check.
pub fn run_all(gpu: &Gpu) -> Result<Vec<Report>> {
    let mut r = Vec::new();
    for p in shaders::octahedral::Precision::ALL {
        r.push(octahedral(gpu, p)?);
    }
    r.push(cluster_keys(gpu)?);
    r.push(morton_codes(gpu)?);
    r.push(workgroup_scan(gpu)?);
    r.push(nurbs_tessellation(gpu)?);
    Ok(r)
}

/// Distance in units in the last place between two finite floats (0 for +0/−0).
pub fn ulp_distance(a: f32, b: f32) -> u32 {
    let key = |x: f32| -> i64 {
        let bits = x.to_bits() as i32 as i64;
        if bits < 0 {
            i64::from(i32::MIN) - bits
        } else {
            bits
        }
    };
    (key(a) - key(b)).unsigned_abs().min(u32::MAX as u64) as u32
}

/// Formats up to 8 mismatches for an error message.
fn list<T: fmt::Debug>(bad: &[T]) -> String {
    let mut s: Vec<String> = bad.iter().take(8).map(|b| format!("  {b:?}")).collect();
    if bad.len() > 8 {
        s.push(format!("  … and {} more", bad.len() - 8));
    }
    s.join("\n")
}

/// The hard-case grids of the foundation kernels: 1×1, 33×17, 4K, 8K.
pub fn parity_grids() -> Vec<ClusterGrid> {
    [(1, 1), (33, 17), (3840, 2160), (7680, 4320)]
        .into_iter()
        .map(|(w, h)| ClusterGrid::new(w, h, 32, 0.1, 1000.0, 60f32.to_radians()).expect("valid grid"))
        .collect()
}

/// Samples for a grid: corners, last row/column, every slice boundary and its float neighbours,
/// near/far/beyond/behind/NaN/inf depths, and pseudo-random pixels at log-uniform depths.
pub fn key_samples(g: &ClusterGrid, bounds: &[f32]) -> Vec<KeySample> {
    let (w, h) = (g.width, g.height);
    let pixels = [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1), (w / 2, h / 2), (w + 7, h + 7)];
    let mut depths: Vec<f32> = vec![
        g.near, g.far, 2.0 * g.far, f32::MAX, f32::INFINITY, 0.0, -0.0, -1.0, f32::NEG_INFINITY, f32::NAN, 1e-30,
    ];
    for &b in bounds {
        depths.extend([b, f32::from_bits(b.to_bits() - 1), f32::from_bits(b.to_bits() + 1)]);
    }
    let mut s = Vec::new();
    for &(px, py) in &pixels {
        for &d in &depths {
            s.push(KeySample { px, py, view_z: -d, _pad: 0 });
        }
    }
    let mut x = 0x9e37_79b9u32;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        let px = x % w;
        let py = (x >> 7) % h;
        let t = (x >> 3) as f32 / (u32::MAX >> 3) as f32;
        let d = g.near * (g.far / g.near).powf(t * 1.1);
        s.push(KeySample { px, py, view_z: -d, _pad: 0 });
    }
    s
}

/// Cluster keys: bit-equal on every grid and sample.
pub fn cluster_keys(gpu: &Gpu) -> Result<Report> {
    let ctx = &gpu.ctx;
    let mut cases = 0;
    for grid in parity_grids() {
        let bounds = slice_bounds(&grid);
        let samples = key_samples(&grid, &bounds);
        let n = samples.len();
        let samples_buf = Buffer::from_slice(ctx, "key samples", &samples)?;
        let bounds_buf = Buffer::from_slice(ctx, "slice bounds", &bounds)?;
        let mut keys_buf = Buffer::storage(ctx, "keys", 4 * n as u64)?;
        let params = ClusterKeyParams { grid, count: n as u32, _pad: [0; 3] };
        gpu.run(None, |rec| {
            rec.dispatch_threads(&gpu.kernels.cluster_keys, &[&samples_buf, &bounds_buf, &keys_buf], &params, [n as u32, 1, 1])
        })?;
        let gpu_keys: Vec<u32> = keys_buf.read(n)?;
        let bad: Vec<_> = samples
            .iter()
            .zip(&gpu_keys)
            .map(|(s, &k)| (s, k, grid.key(&bounds, s.px, s.py, s.view_z)))
            .filter(|(_, gk, ck)| gk != ck)
            .map(|(s, gk, ck)| (s.px, s.py, s.view_z, grid.unpack(gk), grid.unpack(ck)))
            .collect();
        ensure!(
            bad.is_empty(),
            "cluster_keys {}x{}: {} of {n} keys differ (px, py, z, gpu ijk, cpu ijk):\n{}",
            grid.width,
            grid.height,
            bad.len(),
            list(&bad)
        );
        cases += n;
    }
    Ok(Report {
        kernel: "cluster_keys".into(),
        cases,
        detail: "bit-equal at 1x1, 33x17, 3840x2160, 7680x4320 (boundaries ±1 ulp, NaN/inf/behind/beyond)".into(),
    })
}

/// Workgroup scan: the GPU (at the device's subgroup width) equals a sequential scan, and the
/// same kernel code in the CPU emulation at that width.
pub fn workgroup_scan(gpu: &Gpu) -> Result<Report> {
    let ctx = &gpu.ctx;
    let wg = SCAN_WORKGROUP as usize;
    let width = ctx.info.subgroup_size;
    ensure!(
        SCAN_WORKGROUP.is_multiple_of(width) && (SCAN_WORKGROUP / width) as usize <= SCAN_SHARED_WORDS,
        "subgroup size {width} does not divide the scan workgroup {SCAN_WORKGROUP}"
    );
    let mut cases = 0;
    for n in [0usize, 1, 255, 256, 257, 1000, 40 * wg + 3] {
        let mut x = 12345u32 ^ n as u32;
        let input: Vec<u32> = (0..n)
            .map(|i| {
                x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                if i % 97 == 0 { u32::MAX - (x >> 8) } else { x >> 12 }
            })
            .collect();
        let groups = n.div_ceil(wg).max(1);
        let in_buf = Buffer::from_slice(ctx, "scan input", &input)?;
        let mut out_buf = Buffer::storage(ctx, "scan output", 4 * n as u64)?;
        let mut totals_buf = Buffer::storage(ctx, "scan totals", 4 * groups as u64)?;
        let params = ScanParams { count: n as u32, _pad: [0; 3] };
        gpu.run(None, |rec| {
            rec.dispatch(&gpu.kernels.workgroup_scan, &[&in_buf, &out_buf, &totals_buf], &params, [n.div_ceil(wg) as u32, 1, 1])
        })?;
        let out: Vec<u32> = out_buf.read(n)?;
        let totals: Vec<u32> = totals_buf.read(n.div_ceil(wg))?;
        for (g, chunk) in input.chunks(wg).enumerate() {
            let mut acc = 0u32;
            for (l, &v) in chunk.iter().enumerate() {
                let got = out[g * wg + l];
                if got != acc {
                    bail!("workgroup_scan n={n}: group {g} lane {l}: GPU {got}, sequential {acc}");
                }
                acc = acc.wrapping_add(v);
            }
            ensure!(totals[g] == acc, "workgroup_scan n={n}: group {g} total GPU {} != {acc}", totals[g]);
        }
        // The same kernel, emulated on the CPU at the device's width.
        if n == 1000 {
            let emu = Emulation { width, workgroup_size: SCAN_WORKGROUP, shared_words: SCAN_SHARED_WORDS };
            let cpu = run_workgroups(emu, groups as u32, |g, c, s| {
                let i = (g * SCAN_WORKGROUP + c.local_index()) as usize;
                scan::workgroup_exclusive_scan(c, s, input.get(i).copied().unwrap_or(0)).0
            });
            ensure!(cpu[..n] == out[..], "workgroup_scan: CPU emulation at width {width} differs from the GPU");
        }
        cases += n;
    }
    Ok(Report {
        kernel: "workgroup_scan".into(),
        cases,
        detail: format!("bit-equal to a sequential scan and to the CPU emulation, subgroup width {width}"),
    })
}
