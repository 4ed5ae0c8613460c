//! Octahedral encode/decode parity.
//!
//! ## What may differ, and why (Vulkan 1.3 §"Precision and Operation of SPIR-V Instructions";
//! the derivations are in `shaders::octahedral`'s "CPU/GPU agreement")
//! * Encode: the only inexact GPU operation is the L1 normalisation `1/l1` (division: 2.5 ULP);
//!   sanitisation is bit-pattern logic and power-of-two scaling, folding is exact subtraction,
//!   quantisation multiplies by a constant and rounds without a fusable `a*b+c`. A GPU coordinate
//!   differs from the CPU's by ≤ 9u (u = 2^-24), so a code may differ by ±1 in a component only
//!   when its exact (f64) pre-rounding value `|c|·M` lies within `M · TIE_ULPS · u` of a `.5`
//!   boundary ([`TIE_ULPS`] = 9u plus 1u for this check's own f64→f32 reference). The check
//!   recomputes that value in f64 and allows nothing else.
//! * Decode (and the F32 "encoding", a normalisation): `p · 1/sqrt(dot)` with `p` identical on
//!   both sides. CPU relative error ≤ 4.5u; GPU ≤ 16.5u by the spec's minimum precisions (sqrt is
//!   inherited from `1/inversesqrt`), so a component differs by ≤ [`DECODE_ULPS`] = 21 ULP. The
//!   difference is a common scale, so the *directions* differ by ≤ 2u: [`DIRECTION_RAD`].
//!   Decode is compared on the GPU's own codes, so a tie in encode cannot leak into it.
use super::{list, ulp_distance, Report};
use crate::gpu::Gpu;
use crate::vk::Buffer;
use anyhow::{ensure, Result};
use shaders::layout::OctaParams;
use shaders::octahedral::{self, fibonacci_sphere, sanitize, Precision};

/// Distance (in u = 2^-24, times M) from a `.5` rounding boundary within which a ±1 code is allowed.
pub const TIE_ULPS: f64 = 10.0;
/// Bound on decoded components, GPU vs CPU (derivation in the module docs).
pub const DECODE_ULPS: u32 = 21;
/// Bound on the angle between GPU and CPU decodes of one code: 2u.
pub const DIRECTION_RAD: f64 = 2.0 / (1u64 << 24) as f64;
/// Well-spread directions in the parity input.
pub const FIBONACCI_DIRECTIONS: u32 = 1 << 18;

/// Hard cases followed by a spherical Fibonacci lattice.
pub fn octahedral_inputs() -> Vec<[f32; 3]> {
    let d = 1e-40f32; // denormal
    let mut v: Vec<[f32; 3]> = vec![
        [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0],
        [-0.0, -0.0, 1.0], [0.0, -0.0, -1.0], [-0.0, 0.0, -1.0], [-0.0, 1.0, -0.0], [-0.0, -0.0, -0.0],
        [d, 0.0, 1.0], [d, d, d], [-d, d, 0.0], [d, 2e-38, 0.0], [f32::MIN_POSITIVE, -f32::MIN_POSITIVE, 0.0],
        [f32::NAN, 0.0, 1.0], [0.0, f32::NAN, 0.0], [f32::NAN; 3], [f32::INFINITY, 0.0, 0.0],
        [f32::NEG_INFINITY, f32::INFINITY, 1.0], [f32::MAX, f32::MAX, -f32::MAX], [1e30, -2e30, 3e30],
        [1e-30, 2e-30, -3e-30], [3.0, 4.0, 12.0], [0.0, 0.0, 0.0],
    ];
    // −Z hemisphere seams: |x|+|y| = 1 on the equator and slightly below it, near corners too.
    for i in 0..64 {
        let t = i as f32 / 63.0;
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            for z in [0.0, -1e-7, -1e-3, -0.05] {
                v.push([sx * t, sy * (1.0 - t), z]);
            }
        }
    }
    v.extend((0..FIBONACCI_DIRECTIONS).map(|i| fibonacci_sphere(i, FIBONACCI_DIRECTIONS)));
    v
}

/// Exact (f64) octahedral coordinates of a sanitised direction, before quantisation.
fn project_f64(n: [f32; 3]) -> [f64; 2] {
    let [x, y, z] = sanitize(n).map(f64::from);
    let l1 = x.abs() + y.abs() + z.abs();
    let (u, v, w) = (x / l1, y / l1, z / l1);
    let sgn = |c: f64| if c >= 0.0 { 1.0 } else { -1.0 };
    if w < 0.0 {
        [(1.0 - v.abs()) * sgn(u), (1.0 - u.abs()) * sgn(v)]
    } else {
        [u, v]
    }
}

/// Components `(x, y)` of an oct code with `bits` (8, 12 or 16) per component, sign-extended.
fn components(w: u32, bits: u32) -> [i32; 2] {
    let mask = (1u32 << bits) - 1;
    let sext = |c: u32| ((c << (32 - bits)) as i32) >> (32 - bits);
    [sext(w & mask), sext((w >> bits) & mask)]
}

/// Parity of one precision.
pub fn octahedral(gpu: &Gpu, precision: Precision) -> Result<Report> {
    let inputs = octahedral_inputs();
    let n = inputs.len();
    let ctx = &gpu.ctx;
    let padded: Vec<[f32; 4]> = inputs.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
    let in_buf = Buffer::from_slice(ctx, "normals", &padded)?;
    let mut enc_buf = Buffer::storage(ctx, "encoded normals", 16 * n as u64)?;
    let mut dec_buf = Buffer::storage(ctx, "decoded normals", 16 * n as u64)?;
    let params = OctaParams { count: n as u32, precision: precision.code(), _pad: [0; 2] };
    gpu.run(None, |rec| {
        rec.dispatch_threads(&gpu.kernels.octa_roundtrip, &[&in_buf, &enc_buf, &dec_buf], &params, [n as u32, 1, 1])
    })?;
    let enc: Vec<[u32; 4]> = enc_buf.read(n)?;
    let dec: Vec<[f32; 4]> = dec_buf.read(n)?;

    let mut bad_encode = Vec::new();
    let mut bad_decode = Vec::new();
    let mut ties = 0usize;
    let mut max_decode_ulps = 0u32;
    let mut max_direction = 0f64;
    for (i, input) in inputs.iter().enumerate() {
        let cpu = octahedral::encode(*input, precision);
        let g = [enc[i][0], enc[i][1], enc[i][2]];
        if g != cpu {
            if precision == Precision::F32 {
                let worst = (0..3).map(|c| ulp_distance(f32::from_bits(g[c]), f32::from_bits(cpu[c]))).max().unwrap_or(0);
                if worst > DECODE_ULPS {
                    bad_encode.push((i, *input, g, cpu, worst));
                }
            } else {
                let bits = precision.bits();
                let m = ((1u32 << (bits - 1)) - 1) as f64;
                let exact = project_f64(*input);
                let (gc, cc) = (components(g[0], bits), components(cpu[0], bits));
                let tol = m * TIE_ULPS * f64::powi(2.0, -24);
                let explained = (0..2).all(|c| {
                    gc[c] == cc[c] || {
                        let x = (exact[c] * m).abs();
                        (gc[c] - cc[c]).abs() == 1 && ((x - x.floor()) - 0.5).abs() <= tol
                    }
                });
                if explained {
                    ties += 1;
                } else {
                    bad_encode.push((i, *input, g, cpu, 0));
                }
            }
        }
        // Decode of the GPU's own code, on the CPU.
        let cpu_dec = octahedral::decode(g, precision);
        let gpu_dec = [dec[i][0], dec[i][1], dec[i][2]];
        let finite = gpu_dec.iter().all(|c| c.is_finite());
        let worst = (0..3).map(|c| ulp_distance(gpu_dec[c], cpu_dec[c])).max().unwrap_or(0);
        max_decode_ulps = max_decode_ulps.max(worst);
        let (a, b) = (gpu_dec.map(f64::from), cpu_dec.map(f64::from));
        let (na, nb) = (a.iter().map(|x| x * x).sum::<f64>().sqrt(), b.iter().map(|x| x * x).sum::<f64>().sqrt());
        let d = |s: f64| (0..3).map(|c| (a[c] / na + s * b[c] / nb).powi(2)).sum::<f64>().sqrt();
        let direction = 2.0 * d(-1.0).atan2(d(1.0));
        max_direction = max_direction.max(direction);
        if !finite || worst > DECODE_ULPS || direction.is_nan() || direction > DIRECTION_RAD {
            bad_decode.push((i, *input, gpu_dec, cpu_dec, worst));
        }
    }
    ensure!(
        bad_encode.is_empty(),
        "octa {precision:?}: {} of {n} encodings differ beyond the tie rule (index, input, gpu, cpu, ulps):\n{}",
        bad_encode.len(),
        list(&bad_encode)
    );
    ensure!(
        bad_decode.is_empty(),
        "octa {precision:?}: {} of {n} decodes non-finite, > {DECODE_ULPS} ULP or > {DIRECTION_RAD:.2e} rad apart (index, input, gpu, cpu, ulps):\n{}",
        bad_decode.len(),
        list(&bad_decode)
    );
    Ok(Report {
        kernel: format!("octa_roundtrip {precision:?}"),
        cases: n,
        detail: format!(
            "encode bit-equal except {ties} rounding ties (±1 code within {TIE_ULPS}u·M of .5); decode max {max_decode_ulps} ULP (bound {DECODE_ULPS}), direction max {max_direction:.2e} rad (bound {DIRECTION_RAD:.2e})"
        ),
    })
}
