//! NURBS tessellation parity: the tessellation pass (`render::nurbs`) runs on the device over
//! patches packed after a prefix of other geometry, and its vertex streams and index buffer are
//! read back and compared with the same functions run on the CPU
//! (`shaders::tessellation::grid_vertex`, i.e. `nurbs::tessellate_vertex`, and `quad_indices`,
//! i.e. `nurbs::tessellate_indices` plus the patch's first vertex).
//!
//! Bounds (see [`POSITION_ULPS`], [`NORMAL_ULPS`], [`UV_ULPS`]): indices are integers and must
//! be equal. The floats run the same sequence of operations on both sides; they may differ where
//! Vulkan lets the device differ from IEEE round-to-nearest: a division within 2.5 ULP (the
//! Cox–de Boor table's and the quotient rule's), `inversesqrt` within 2 ULP (`normalize`), and a
//! multiply–add that the driver contracts into a fused one (one rounding less).
use super::{list, Report};
use crate::gpu::Gpu;
use crate::render::gbuffer::Geometry;
use crate::render::nurbs::{params, Tessellation};
use crate::scene::nurbs::{sphere, teapot, torus, NurbsBuffers, NurbsPatch};
use anyhow::{ensure, Result};
use glam::Vec3;
use shaders::layout::NurbsPatchGpu;
use shaders::tessellation::{grid_vertex, quad_indices};

/// Positions: the bound is `POSITION_ULPS · ρ` ULP of the patch's scale `M` (the largest
/// Cartesian control-point coordinate; ρ: largest over smallest weight). The point is
/// `Σ N_i(u) N_j(v) w_ij P_ij / Σ N_i N_j w_ij` with `N ≥ 0` and `Σ N = 1`. The basis values of
/// degree `p` pass through `p` levels of the Cox–de Boor table, each a division (the device's
/// within 2.5 ULP, the CPU's within 0.5) and a multiply–add (≤ 1 ULP apart when contracted),
/// and the `(p+1)(q+1)` products and sums add a rounding per term: for `p, q ≤ 5` under
/// 2·(4·5) + 2·36 ≈ 110 roundings of ε = 2⁻²⁴ relative to `Σ |N N w P| ≤ max w · M`, i.e.
/// 55 ULP of `max w · M`; the division by `w ≥ min w` turns that into 55·ρ ULP of `M`, here
/// rounded up to 64·ρ.
pub const POSITION_ULPS: f32 = 64.0;
/// Normals: ULPs of 1 (2⁻²³) per component. The normal is `normalize(S_u × S_v)`; each partial
/// derivative carries the position's error divided by its length over the domain, which is
/// amplified where `|S_u|` shrinks toward a collapsed edge (next to a pole `|S_u|` is about
/// `1/level` of the domain's): the position's 64·ρ ULP (ρ ≤ 2 for the test patches) times the
/// grids' finest level of 64: 8192 ULP of 1, about 1e-3 per component (under 0.1° of
/// direction).
pub const NORMAL_ULPS: f32 = 8192.0;
/// uvs: `i · (1/level)`, one division (2.5 ULP) and one product: 4 ULP.
pub const UV_ULPS: u32 = 4;

/// The test patches: the exact sphere (collapsed poles) and torus, the teapot's 32 bicubic
/// patches (collapsed at the bottom's and the knob's centres), a polynomial quintic and a
/// rational (5, 2) patch, and an unclamped cubic, with their levels (1 to 64).
fn patches() -> Vec<(NurbsPatch, u32)> {
    let mut x = 0x2545_f491u32;
    let mut r = move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32
    };
    let mut grid = |nu: u32, nv: u32, scale: f32| -> Vec<[f32; 3]> {
        (0..nu * nv).map(|k| [(k % nu) as f32 * scale, (k / nu) as f32 * scale, (r() - 0.5) * scale]).collect()
    };
    let quintic = NurbsPatch::polynomial(5, 5, 6, 7, grid(6, 7, 3.0), 0);
    let mut rational = NurbsPatch::polynomial(5, 2, 7, 4, grid(7, 4, 0.25), 0);
    rational.weights = (0..28).map(|k| 0.5 + (k % 5) as f32 * 0.25).collect();
    let mut unclamped = NurbsPatch::polynomial(3, 3, 5, 5, grid(5, 5, 1.0), 0);
    unclamped.knots_u = vec![-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    unclamped.knots_v = vec![0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0];
    let mut out = vec![(sphere(Vec3::new(1.0, -2.0, 0.5), 2.5), 64), (sphere(Vec3::ZERO, 1.0), 1), (torus(Vec3::new(0.0, 1.0, -4.0), 3.0, 0.8), 16)];
    out.extend(teapot().into_iter().enumerate().map(|(k, p)| (p, 2 + k as u32 % 7)));
    out.extend([(quintic, 10), (rational, 13), (unclamped, 9)]);
    out
}

/// Largest Cartesian control-point coordinate and largest over smallest weight of a patch.
fn scale(p: &NurbsPatch) -> (f32, f32) {
    let m = p.control_points.iter().flatten().fold(0f32, |m, c| m.max(c.abs()));
    let (lo, hi) = p.weights.iter().fold((f32::MAX, 0f32), |(lo, hi), &w| (lo.min(w), hi.max(w)));
    (m, hi / lo)
}

/// The spacing of f32 values at `x` (the ULP of `|x|`, at least the smallest normal's).
fn ulp_of(x: f32) -> f32 {
    let e = x.abs().max(f32::MIN_POSITIVE).log2().floor();
    2f32.powf(e - 23.0)
}

pub fn nurbs_tessellation(gpu: &Gpu) -> Result<Report> {
    let ctx = &gpu.ctx;
    let patches = patches();
    // Grids after 5 vertices and 12 indices of other geometry, which must stay as they are.
    let (first_vertex, first_index) = (5u32, 12u32);
    let mut packed = NurbsBuffers { vertices: first_vertex, indices: first_index, ..NurbsBuffers::default() };
    for (p, level) in &patches {
        p.validate("parity patch")?;
        packed.push(p, *level);
    }
    let prefix_positions = [[7.0f32; 3]; 5];
    let prefix_indices: Vec<u32> = (0..first_index).map(|i| 1000 + i).collect();
    let extra = [(packed.vertices - first_vertex) as u64, (packed.indices - first_index) as u64];
    let mut geometry = Geometry::upload_reserving(ctx, &prefix_positions, &prefix_positions, &[[7.0; 2]; 5], &prefix_indices, &[], &[], extra)?;
    let pass = Tessellation::new(ctx, &packed, first_vertex, first_index)?;
    gpu.run(None, |rec| pass.record(rec, &geometry))?;
    let n = packed.vertices as usize;
    let positions: Vec<[f32; 3]> = geometry.positions.read(n)?;
    let normals: Vec<[f32; 3]> = geometry.normals.read(n)?;
    let uvs: Vec<[f32; 2]> = geometry.uvs.read(n)?;
    let indices: Vec<u32> = geometry.indices.read(packed.indices as usize)?;
    ensure!(positions[..5] == prefix_positions && uvs[..5] == [[7.0; 2]; 5], "the pass wrote over the vertices before its range");
    ensure!(indices[..first_index as usize] == prefix_indices[..], "the pass wrote over the indices before its range");

    let p = params(&packed, first_vertex, first_index);
    let knots = &packed.knots;
    let cps = &packed.control_points;
    let (mut worst_pos, mut worst_normal, mut worst_uv) = (0f32, 0f32, 0u32);
    let mut bad = Vec::new();
    for i in 0..p.vertex_count {
        let (v, cpu) = grid_vertex(&packed.patches, &p, knots, cps, i);
        let k = packed.patches.iter().rposition(|h: &NurbsPatchGpu| h.vertex_offset <= v).unwrap_or(0);
        let (m, rho) = scale(&patches[k].0);
        let v = v as usize;
        let pos = (0..3).map(|a| (positions[v][a] - cpu.position[a]).abs() / ulp_of(m) / rho.max(1.0)).fold(0f32, f32::max);
        let nrm = (0..3).map(|a| (normals[v][a] - cpu.normal[a]).abs() / f32::EPSILON).fold(0f32, f32::max);
        let uv = (0..2).map(|a| super::ulp_distance(uvs[v][a], cpu.uv[a])).max().unwrap_or(0);
        // NaN compares false: a NaN is reported as a mismatch.
        if !(pos <= POSITION_ULPS && nrm <= NORMAL_ULPS && uv <= UV_ULPS) {
            bad.push((k, v, positions[v], cpu.position, normals[v], cpu.normal, uvs[v], cpu.uv));
        }
        worst_pos = worst_pos.max(pos);
        worst_normal = worst_normal.max(nrm);
        worst_uv = worst_uv.max(uv);
    }
    ensure!(
        bad.is_empty(),
        "nurbs_tessellation: {} of {} vertices beyond {POSITION_ULPS}·ρ ULP (positions) / {NORMAL_ULPS} (normals) / {UV_ULPS} (uvs) \
         (patch, vertex, gpu position, cpu, gpu normal, cpu, gpu uv, cpu):\n{}",
        bad.len(),
        p.vertex_count,
        list(&bad)
    );
    let mut wrong = Vec::new();
    for q in 0..p.quad_count {
        let (first, six) = quad_indices(&packed.patches, &p, q);
        let got = &indices[first as usize..first as usize + 6];
        if got != six {
            wrong.push((q, got.to_vec(), six));
        }
    }
    ensure!(wrong.is_empty(), "nurbs_tessellation: {} of {} quads' indices differ (quad, gpu, cpu):\n{}", wrong.len(), p.quad_count, list(&wrong));
    Ok(Report {
        kernel: "nurbs_tessellation".into(),
        cases: (p.vertex_count + p.quad_count) as usize,
        detail: format!(
            "{} patches; indices equal; worst position {worst_pos:.1}·ρ ULP of the patch scale (bound {POSITION_ULPS}·ρ), normal {worst_normal:.1} ULP of 1 \
             (bound {NORMAL_ULPS}), uv {worst_uv} ULP (bound {UV_ULPS})",
            patches.len()
        ),
    })
}
