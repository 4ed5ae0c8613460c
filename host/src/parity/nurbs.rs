//! NURBS tessellation parity: the tessellation pass (`render::nurbs`) runs on the device over
//! patches packed after a prefix of other geometry, and its vertex streams and index buffer are
//! read back and compared with the same functions run on the CPU
//! (`shaders::tessellation::grid_vertex`, i.e. `nurbs::tessellate_vertex`, and `quad_indices`,
//! i.e. `nurbs::tessellate_indices` plus the patch's first vertex), at fixed levels and at the
//! adaptive levels the level kernel picks (those against `tessellation::adaptive_level`).
//!
//! Bounds (see [`POSITION_ULPS`], [`NORMAL_ULPS`], [`UV_ULPS`]): indices are integers and must
//! be equal. The floats run the same sequence of operations on both sides; they may differ where
//! Vulkan lets the device differ from IEEE round-to-nearest: a division within 2.5 ULP (the
//! Cox–de Boor table's and the quotient rule's), `inversesqrt` within 2 ULP (`normalize`), and a
//! multiply–add that the driver contracts into a fused one (one rounding less).
use super::{list, Report};
use crate::gpu::Gpu;
use crate::render::gbuffer::Geometry;
use crate::render::nurbs::{params, Tessellation, ADAPTIVE_MAX_LEVEL};
use crate::vk::Buffer;
use crate::scene::nurbs::{sphere, teapot, torus, NurbsBuffers, NurbsPatch};
use anyhow::{ensure, Result};
use glam::{DVec3, Vec3, Vec4};
use shaders::layout::{NurbsPatchGpu, TessLevelParams};
use shaders::tessellation::{adaptive_level, draw_args, grid_vertex, quad_indices, DRAW_ARGS_WORDS};

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
/// rational (5, 2) patch, an unclamped cubic, a sphere 400 units away and a flat square, with
/// their fixed levels (1 to 64).
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
    let plane = NurbsPatch::polynomial(1, 1, 2, 2, vec![[-5.0, 0.0, 5.0], [5.0, 0.0, 5.0], [-5.0, 0.0, -5.0], [5.0, 0.0, -5.0]], 0);
    out.extend([(quintic, 10), (rational, 13), (unclamped, 9), (sphere(Vec3::new(0.0, 0.0, -400.0), 1.0), 5), (plane, 3)]);
    out
}

/// Largest Cartesian control-point coordinate `M` and largest over smallest weight ρ of packed
/// patch `h`.
fn scale(b: &NurbsBuffers, h: &NurbsPatchGpu) -> (f32, f32) {
    let cps = &b.control_points[h.cp_offset as usize..(h.cp_offset + h.size_u * h.size_v) as usize];
    let m = cps.iter().flat_map(|c| [c[0] / c[3], c[1] / c[3], c[2] / c[3]]).fold(0f32, |m, x| m.max(x.abs()));
    let (lo, hi) = cps.iter().fold((f32::MAX, 0f32), |(lo, hi), c| (lo.min(c[3]), hi.max(c[3])));
    (m, hi / lo)
}

/// The spacing of f32 values at `x` (the ULP of `|x|`, at least the smallest normal's).
fn ulp_of(x: f32) -> f32 {
    let e = x.abs().max(f32::MIN_POSITIVE).log2().floor();
    2f32.powf(e - 23.0)
}

/// What the pass wrote, read back.
struct Written {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
    /// Adaptive levels: each patch's header and draw arguments after the frame.
    headers: Vec<NurbsPatchGpu>,
    args: Vec<u32>,
}

/// Runs the pass over `packed` (grids after 5 vertices and 12 indices of other geometry, which
/// must stay as they are) and reads back what it wrote.
fn run(gpu: &Gpu, packed: &NurbsBuffers, levels: Option<TessLevelParams>) -> Result<Written> {
    let ctx = &gpu.ctx;
    let (first_vertex, first_index) = (FIRST_VERTEX, FIRST_INDEX);
    let prefix_positions = [[7.0f32; 3]; FIRST_VERTEX as usize];
    let prefix_indices: Vec<u32> = (0..first_index).map(|i| 1000 + i).collect();
    let extra = [(packed.vertices - first_vertex) as u64, (packed.indices - first_index) as u64];
    let mut geometry = Geometry::upload_reserving(ctx, &prefix_positions, &prefix_positions, &[[7.0; 2]; 5], &prefix_indices, &[], &[], extra)?;
    let n = packed.patches.len();
    if levels.is_some() {
        geometry.indirect_args = Some(Buffer::storage(ctx, "nurbs draw arguments", 4 * DRAW_ARGS_WORDS as u64 * n as u64)?);
    }
    let mut pass = Tessellation::new(ctx, &gpu.compute_module, packed, first_vertex, first_index, levels)?;
    gpu.run(None, |rec| pass.record(rec, &geometry))?;
    let v = packed.vertices as usize;
    let w = Written {
        positions: geometry.positions.read(v)?,
        normals: geometry.normals.read(v)?,
        uvs: geometry.uvs.read(v)?,
        indices: geometry.indices.read(packed.indices as usize)?,
        headers: pass.headers_mut().read(n)?,
        args: match geometry.indirect_args.as_mut() {
            Some(a) => a.read(DRAW_ARGS_WORDS as usize * n)?,
            None => vec![],
        },
    };
    ensure!(w.positions[..5] == prefix_positions && w.uvs[..5] == [[7.0; 2]; 5], "the pass wrote over the vertices before its range");
    ensure!(w.indices[..first_index as usize] == prefix_indices[..], "the pass wrote over the indices before its range");
    Ok(w)
}

const FIRST_VERTEX: u32 = 5;
const FIRST_INDEX: u32 = 12;

/// Compares the grids the pass wrote for the patches of `headers` (their levels) with the CPU's;
/// returns the worst position, normal and uv differences and the vertices and quads compared.
fn compare(packed: &NurbsBuffers, headers: &[NurbsPatchGpu], w: &Written, what: &str) -> Result<(f32, f32, u32, u32, u32)> {
    let p = params(packed, FIRST_VERTEX, FIRST_INDEX);
    let (knots, cps) = (&packed.knots, &packed.control_points);
    let (mut worst_pos, mut worst_normal, mut worst_uv, mut vertices, mut quads) = (0f32, 0f32, 0u32, 0u32, 0u32);
    let mut bad = Vec::new();
    for i in 0..p.vertex_count {
        let (in_grid, v, cpu) = grid_vertex(headers, &p, knots, cps, i);
        if !in_grid {
            continue;
        }
        vertices += 1;
        let k = headers.iter().rposition(|h| h.vertex_offset <= v).unwrap_or(0);
        let (m, rho) = scale(packed, &headers[k]);
        let v = v as usize;
        let pos = (0..3).map(|a| (w.positions[v][a] - cpu.position[a]).abs() / ulp_of(m) / rho.max(1.0)).fold(0f32, f32::max);
        let nrm = (0..3).map(|a| (w.normals[v][a] - cpu.normal[a]).abs() / f32::EPSILON).fold(0f32, f32::max);
        let uv = (0..2).map(|a| super::ulp_distance(w.uvs[v][a], cpu.uv[a])).max().unwrap_or(0);
        // NaN compares false: a NaN is reported as a mismatch.
        if !(pos <= POSITION_ULPS && nrm <= NORMAL_ULPS && uv <= UV_ULPS) {
            bad.push((k, v, w.positions[v], cpu.position, w.normals[v], cpu.normal, w.uvs[v], cpu.uv));
        }
        worst_pos = worst_pos.max(pos);
        worst_normal = worst_normal.max(nrm);
        worst_uv = worst_uv.max(uv);
    }
    ensure!(
        bad.is_empty(),
        "nurbs_tessellation ({what}): {} of {vertices} vertices beyond {POSITION_ULPS}·ρ ULP (positions) / {NORMAL_ULPS} (normals) / {UV_ULPS} (uvs) \
         (patch, vertex, gpu position, cpu, gpu normal, cpu, gpu uv, cpu):\n{}",
        bad.len(),
        list(&bad)
    );
    let mut wrong = Vec::new();
    for q in 0..p.quad_count {
        let (in_grid, first, six) = quad_indices(headers, &p, q);
        if !in_grid {
            continue;
        }
        quads += 1;
        let got = &w.indices[first as usize..first as usize + 6];
        if got != six {
            wrong.push((q, got.to_vec(), six));
        }
    }
    ensure!(wrong.is_empty(), "nurbs_tessellation ({what}): {} of {quads} quads' indices differ (quad, gpu, cpu):\n{}", wrong.len(), list(&wrong));
    Ok((worst_pos, worst_normal, worst_uv, vertices, quads))
}

/// Fixed levels, then adaptive levels (patches relative to a camera, levels and draw arguments
/// against `tessellation::adaptive_level` / `draw_args`; a level may be one off only where the
/// CPU's own level changes within 0.1 % of the tolerance, a rounding tie of the `⌈⌉`).
pub fn nurbs_tessellation(gpu: &Gpu) -> Result<Report> {
    let patches = patches();
    let pack = |origin: DVec3, adaptive: bool| -> Result<NurbsBuffers> {
        let mut b = NurbsBuffers { vertices: FIRST_VERTEX, indices: FIRST_INDEX, ..NurbsBuffers::default() };
        for (p, level) in &patches {
            p.validate("parity patch")?;
            b.push_relative(p, if adaptive { ADAPTIVE_MAX_LEVEL } else { *level }, origin);
        }
        Ok(b)
    };
    let fixed = pack(DVec3::ZERO, false)?;
    let w = run(gpu, &fixed, None)?;
    let (pos, nrm, uv, mut vertices, mut quads) = compare(&fixed, &fixed.patches, &w, "fixed levels")?;

    let adaptive = pack(DVec3::new(2.0, 3.0, 14.0), true)?;
    let l = TessLevelParams { patch_count: patches.len() as u32, max_level: ADAPTIVE_MAX_LEVEL, pixel_scale: 300.0, tolerance: 0.5, near: 0.1, _pad: [0; 3] };
    let w = run(gpu, &adaptive, Some(l))?;
    let (knots, cps) = (&adaptive.knots, &adaptive.control_points);
    let level_at = |h: &NurbsPatchGpu, tolerance: f32| {
        adaptive_level(h, &TessLevelParams { tolerance, ..l }, |i| knots[i as usize], |i| Vec4::from_array(cps[i as usize]))
    };
    let mut seen = std::collections::BTreeSet::new();
    for (k, (h, g)) in adaptive.patches.iter().zip(&w.headers).enumerate() {
        let cpu = level_at(h, l.tolerance);
        let tie = [l.tolerance * (1.0 - 1e-3), l.tolerance * (1.0 + 1e-3)].map(|t| level_at(h, t));
        ensure!(
            g.level == cpu || tie.contains(&g.level),
            "nurbs_levels: patch {k}: GPU level {}, CPU {cpu} (within 0.1 % of the tolerance: {tie:?})",
            g.level
        );
        let args = &w.args[(DRAW_ARGS_WORDS as usize) * k..(DRAW_ARGS_WORDS as usize) * (k + 1)];
        ensure!(args == draw_args(h, g.level), "nurbs_levels: patch {k}: draw arguments {args:?}, want {:?}", draw_args(h, g.level));
        ensure!(NurbsPatchGpu { level: h.level, ..*g } == *h, "nurbs_levels: patch {k}: the header changed beyond its level");
        seen.insert(g.level);
    }
    ensure!(
        seen.len() >= 4 && seen.contains(&1) && seen.contains(&ADAPTIVE_MAX_LEVEL),
        "nurbs_levels: the test patches should take several levels, 1 (the flat square) and the largest among them: {seen:?}"
    );
    let (apos, anrm, auv, av, aq) = compare(&adaptive, &w.headers, &w, "adaptive levels")?;
    vertices += av;
    quads += aq;
    Ok(Report {
        kernel: "nurbs_tessellation".into(),
        cases: (vertices + quads) as usize + patches.len(),
        detail: format!(
            "{} patches, fixed and adaptive levels ({} distinct); indices equal, levels equal or a tie; worst position {:.1}·ρ ULP of the patch scale \
             (bound {POSITION_ULPS}·ρ), normal {:.1} ULP of 1 (bound {NORMAL_ULPS}), uv {} ULP (bound {UV_ULPS})",
            patches.len(),
            seen.len(),
            pos.max(apos),
            nrm.max(anrm),
            uv.max(auv)
        ),
    })
}
