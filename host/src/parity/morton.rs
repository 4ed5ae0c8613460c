//! Morton-code parity: quantisation is `floor((p − min)·scale)` with the scale precomputed on the
//! host, i.e. one correctly rounded subtraction and one multiplication (no add to fuse), so
//! 30-bit and 63-bit codes must be bit-equal on every input.
use super::{list, Report};
use crate::gpu::Gpu;
use crate::vk::Buffer;
use anyhow::{ensure, Result};
use shaders::layout::MortonParams;
use shaders::morton::{MortonQuantizer, MORTON30_BITS, MORTON63_BITS};

/// Scene bounds used by the check: regular, flat on one axis, a single point, and NaN.
fn bounds() -> Vec<([f32; 3], [f32; 3])> {
    vec![
        ([-10.0, -5.0, -1.0], [10.0, 5.0, 30.0]),
        ([-10.0, 2.0, -1.0], [10.0, 2.0, 30.0]),
        ([1.0, 1.0, 1.0], [1.0, 1.0, 1.0]),
        ([f32::NAN, 0.0, 0.0], [1.0, f32::INFINITY, 1.0]),
        ([-1e30, -1e-30, 0.0], [1e30, 1e-30, 1e-6]),
    ]
}

/// Positions: the bounds' corners, just inside/outside them, NaN/inf, and pseudo-random points
/// spread over twice the bounds.
fn positions(min: [f32; 3], max: [f32; 3]) -> Vec<[f32; 3]> {
    let mut v = vec![min, max, [f32::NAN, 0.0, 0.0], [f32::INFINITY, f32::NEG_INFINITY, f32::NAN], [f32::MAX, -f32::MAX, 0.0]];
    let below = |x: f32| if x.is_finite() { x - x.abs().max(1.0) * 1e-3 } else { x };
    let above = |x: f32| if x.is_finite() { x + x.abs().max(1.0) * 1e-3 } else { x };
    v.push(min.map(below));
    v.push(max.map(above));
    v.push([0, 1, 2].map(|a| if max[a].is_finite() { f32::from_bits(max[a].to_bits().saturating_sub(1)) } else { 0.0 }));
    let mut x = 0x1234_5678u32;
    let mut r = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32 * 2.0 - 0.5
    };
    for _ in 0..10_000 {
        v.push([0, 1, 2].map(|a| {
            let (lo, hi) = (if min[a].is_finite() { min[a] } else { -1.0 }, if max[a].is_finite() { max[a] } else { 1.0 });
            lo + (hi - lo) * r()
        }));
    }
    v
}

pub fn morton_codes(gpu: &Gpu) -> Result<Report> {
    let ctx = &gpu.ctx;
    let mut cases = 0;
    for (min, max) in bounds() {
        let pos = positions(min, max);
        let n = pos.len();
        let params = MortonParams {
            q30: MortonQuantizer::new(min, max, MORTON30_BITS),
            q63: MortonQuantizer::new(min, max, MORTON63_BITS),
            count: n as u32,
            _pad: [0; 3],
        };
        let padded: Vec<[f32; 4]> = pos.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
        let in_buf = Buffer::from_slice(ctx, "positions", &padded)?;
        let mut c30 = Buffer::storage(ctx, "morton30", 4 * n as u64)?;
        let mut c63 = Buffer::storage(ctx, "morton63", 8 * n as u64)?;
        gpu.run(None, |rec| rec.dispatch_threads(&gpu.kernels.morton_codes, &[&in_buf, &c30, &c63], &params, [n as u32, 1, 1]))?;
        let g30: Vec<u32> = c30.read(n)?;
        let g63: Vec<[u32; 2]> = c63.read(n)?;
        let bad: Vec<_> = pos
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let (e30, e63) = (params.q30.morton30_of(*p), params.q63.morton63_of(*p));
                let got63 = g63[i][0] as u64 | (g63[i][1] as u64) << 32;
                (g30[i] != e30 || got63 != e63).then_some((i, *p, g30[i], e30, got63, e63))
            })
            .collect();
        ensure!(
            bad.is_empty(),
            "morton bounds {min:?}..{max:?}: {} of {n} codes differ (i, p, gpu30, cpu30, gpu63, cpu63):\n{}",
            bad.len(),
            list(&bad)
        );
        cases += n;
    }
    Ok(Report {
        kernel: "morton_codes".into(),
        cases,
        detail: "30-bit and 63-bit codes bit-equal (regular, flat, point and NaN bounds; outside/NaN/inf points)".into(),
    })
}
