//! CPU tests of `octahedral` (run with `cargo test --release -- --nocapture` for the table).
use super::*;

const OCTS: [Precision; 3] = [Precision::Oct8, Precision::Oct12, Precision::Oct16];
const U: f64 = 1.0 / 16_777_216.0; // 2^-24

fn to64(v: [f32; 3]) -> [f64; 3] {
    [v[0] as f64, v[1] as f64, v[2] as f64]
}

fn norm64(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn unit64(v: [f64; 3]) -> [f64; 3] {
    let l = norm64(v);
    [v[0] / l, v[1] / l, v[2] / l]
}

/// Angle between two directions, accurate for tiny angles: 2·atan2(|a-b|, |a+b|) of unit vectors.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (unit64(a), unit64(b));
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let s = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
    2.0 * norm64(d).atan2(norm64(s))
}

fn is_finite3(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

/// Decoded vector is finite and unit length within 5u (CPU decode: ≤ 4.5u, see module docs).
fn assert_unit(v: [f32; 3], what: &str) {
    assert!(is_finite3(v), "{what}: non-finite {v:?}");
    let l = norm64(to64(v));
    assert!((l - 1.0).abs() <= 5.0 * U, "{what}: length {l} of {v:?}");
}

/// Encode `n` at `p`, decode, check finite/unit and the angle to `expect` against the bound.
fn check_dir(n: [f32; 3], expect: [f64; 3], p: Precision) -> f64 {
    let d = decode(encode(n, p), p);
    assert_unit(d, &format!("{p:?} {n:?}"));
    let a = angle(expect, to64(d));
    let bound = p.max_angular_error_bound() as f64;
    assert!(a <= bound, "{p:?} {n:?}: angle {a} > bound {bound} (decoded {d:?})");
    a
}

/// Sign-extended (qx, qy) of an oct word.
fn codes(w: u32, b: u32) -> (i32, i32) {
    (sign_extend(w, b), sign_extend(w >> b, b))
}

#[test]
fn axes_round_trip_exactly() {
    // Exact because M·fl(1/M) == 1 for M = 127, 2047, 32767 (checked below), 1 - 1 - 0 = 0 and
    // 1/sqrt(1) = 1 on the CPU; on a GPU, `1/sqrt(1)` need not be exactly 1 (see module docs).
    for b in [8u32, 12, 16] {
        assert_eq!(snorm_decode((1 << (b - 1)) - 1, b), 1.0);
        assert_eq!(snorm_decode(-((1 << (b - 1)) - 1), b), -1.0);
    }
    let axes = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0f32]];
    for p in Precision::ALL {
        for a in axes {
            assert_eq!(decode(encode(a, p), p), a, "{p:?} axis {a:?}");
            assert_eq!(decode(encode([a[0] * 3.5, a[1] * 3.5, a[2] * 3.5], p), p), a, "{p:?} 3.5·{a:?}");
        }
    }
}

#[test]
fn bit_layouts() {
    // +X: (u, v) = (1, 0). -X: (-1, 0). -Z: folded to the corner (1, 1). -Y: (0, -1).
    assert_eq!(encode([1.0, 0.0, 0.0], Precision::Oct8), [0x0000_007f, 0, 0]);
    assert_eq!(encode([-1.0, 0.0, 0.0], Precision::Oct8), [0x0000_0081, 0, 0]);
    assert_eq!(encode([0.0, -1.0, 0.0], Precision::Oct8), [0x0000_8100, 0, 0]);
    assert_eq!(encode([0.0, 0.0, -1.0], Precision::Oct8), [0x0000_7f7f, 0, 0]);
    assert_eq!(encode([0.0, 0.0, -1.0], Precision::Oct12), [0x007f_f7ff, 0, 0]);
    assert_eq!(encode([0.0, -1.0, 0.0], Precision::Oct12), [0x0080_1000, 0, 0]);
    assert_eq!(encode([0.0, 0.0, -1.0], Precision::Oct16), [0x7fff_7fff, 0, 0]);
    assert_eq!(encode([-1.0, 0.0, 0.0], Precision::Oct16), [0x0000_8001, 0, 0]);
    assert_eq!(encode([0.0, 0.0, 2.0], Precision::F32), [0, 0, 1.0f32.to_bits()]);
    // Only the low 16 / 24 bits are used; words 1, 2 are zero.
    for i in 0..4096 {
        let n = fibonacci_sphere(i, 4096);
        assert_eq!(encode(n, Precision::Oct8)[0] >> 16, 0);
        assert_eq!(encode(n, Precision::Oct12)[0] >> 24, 0);
        for p in OCTS {
            assert_eq!(&encode(n, p)[1..], &[0, 0]);
        }
    }
    // Round half away from zero; -M-1 clamps to -1; unsupported widths round up.
    assert_eq!((snorm_encode(0.5, 8), snorm_encode(-0.5, 8)), (64, -64)); // 63.5 -> 64
    assert_eq!((snorm_encode(0.5, 12), snorm_encode(-0.5, 12)), (1024, -1024));
    assert_eq!((snorm_encode(2.0, 16), snorm_encode(-7.0, 16)), (32767, -32767));
    assert_eq!(snorm_decode(-128, 8), -1.0);
    assert_eq!(snorm_decode(-32768, 16), -1.0);
    assert_eq!((oct_bits(0), oct_bits(8), oct_bits(9), oct_bits(12), oct_bits(13), oct_bits(99)), (8, 8, 12, 12, 16, 16));
    for p in Precision::ALL {
        assert_eq!(Precision::from_u32(p as u32), p);
    }
    assert_eq!(Precision::from_u32(77), Precision::F32);
}

#[test]
fn every_code_decodes_to_a_unit_vector() {
    // Exhaustive for 8 and 12 bits (including the -M-1 codes and unused high bits ignored),
    // a strided sample of 16 bits.
    for w in 0..(1u32 << 16) {
        assert_unit(decode_oct(w | 0xabcd_0000, 8), "oct8");
    }
    for w in 0..(1u32 << 24) {
        assert_unit(decode_oct(w | 0x5a00_0000, 12), "oct12");
    }
    for w in (0..u32::MAX).step_by(251) {
        assert_unit(decode_oct(w, 16), "oct16");
    }
}

#[test]
fn lower_hemisphere_seams() {
    let mut n_checked = 0;
    let mut dirs: Vec<[f32; 3]> = Vec::new();
    let k = 720;
    for j in 0..k {
        let phi = j as f64 * core::f64::consts::TAU / k as f64;
        // z = 0 equator (|x| + |y| = 1 after L1 normalisation), slightly below, and near -Z
        // (the square's corners).
        for z in [0.0, -1e-30, -1e-7, -1e-5, -1e-3, -0.01, -0.5, -0.99, -1.0 + 1e-5, -1.0 + 1e-7] {
            let r = (1.0f64 - z * z).sqrt();
            dirs.push([(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]);
        }
        // The square's border: the x = 0 and y = 0 great circles in the lower hemisphere,
        // with both signs of zero and tiny offsets of either sign.
        let (c, s) = ((phi / 2.0).cos() as f32, -(phi / 2.0).sin() as f32);
        for e in [0.0f32, -0.0, 1e-30, -1e-30, 1e-7, -1e-7, 1e-3, -1e-3] {
            dirs.extend([[e, c, s], [c, e, s], [e, -c, s], [-c, e, s]]);
        }
    }
    // Near the diamond's vertices (±1,0), (0,±1) = ±X, ±Y and along the fold diagonals.
    for e in [0.0f32, 1e-7, 1e-4, 1e-2] {
        for sx in [1.0f32, -1.0] {
            for sz in [1.0f32, -1.0] {
                dirs.extend([[sx, e, sz * e], [sx, -e, sz * e], [e, sx, sz * e], [-e, sx, sz * e]]);
                dirs.extend([[sx * 0.5, 0.5, sz * e], [0.5, sx * 0.5, sz * e], [sx * 0.5, -0.5, sz * e]]);
            }
        }
    }
    for n in dirs {
        let expect = to64(n);
        for p in Precision::ALL {
            check_dir(n, expect, p);
            n_checked += 1;
        }
    }
    assert!(n_checked > 50_000);
}

#[test]
fn signed_zeros_do_not_matter() {
    let pairs = [
        ([-0.0, -0.0, 1.0f32], [0.0, 0.0, 1.0f32]),
        ([0.0, -0.0, -1.0], [0.0, 0.0, -1.0]),
        ([-0.0, 0.0, -1.0], [0.0, 0.0, -1.0]),
        ([-0.0, -0.0, -1.0], [0.0, 0.0, -1.0]),
        ([-0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
        ([1.0, -0.0, -0.0], [1.0, 0.0, 0.0]),
        ([-1.0, -0.0, -0.0], [-1.0, 0.0, 0.0]),
        ([0.6, -0.0, -0.8], [0.6, 0.0, -0.8]),
        ([-0.0, -0.6, -0.8], [0.0, -0.6, -0.8]),
        ([-0.0, -0.0, -0.0], [0.0, 0.0, 0.0]),
    ];
    for (a, b) in pairs {
        for p in Precision::ALL {
            assert_eq!(encode(a, p), encode(b, p), "{p:?} {a:?} vs {b:?}");
        }
    }
}

#[test]
fn denormals_are_flushed() {
    let pairs = [
        ([1e-40, 0.6, 0.8f32], [0.0, 0.6, 0.8f32]),
        ([-1e-45, 1.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.3, -1e-39, -0.7], [0.3, 0.0, -0.7]),
        ([2e-38, 1e-40, 0.0], [1.0, 0.0, 0.0]), // documented: denormal components are ignored
        ([-2e-38, 0.0, -1e-44], [-1.0, 0.0, 0.0]),
        ([1.2e-38, -2.4e-38, 1.1e-38], [1.2e-38, -2.4e-38, 0.0]), // 1.1e-38 < MIN_POSITIVE
        ([1e-40, -1e-45, 1e-39], [0.0, 0.0, 1.0]), // all denormal -> +Z
        ([-1e-40, -1e-40, -1e-40], [0.0, 0.0, 1.0]),
        ([1e-40, 0.0, -0.0], [0.0, 0.0, 1.0]),
    ];
    for (a, b) in pairs {
        for p in Precision::ALL {
            assert_eq!(encode(a, p), encode(b, p), "{p:?} {a:?} vs {b:?}");
            let d = decode(encode(a, p), p);
            assert!(is_finite3(d));
        }
    }
    // Components that become denormal only after the rescale are flushed too (2^-130 relative).
    let tiny = f32::from_bits(0x00c0_0000 | (20 << 23)); // 1.5·2^-107
    for p in Precision::ALL {
        assert_eq!(encode([1e20, tiny, -1e20], p), encode([1.0, 0.0, -1.0], p));
    }
    assert_eq!(sanitize([1e20, tiny, -1e20])[1].to_bits(), 0);
}

#[test]
fn scale_invariance() {
    let base: [[f32; 3]; 6] = [
        [0.267_261_24, -0.534_522_5, 0.801_783_7],
        [-0.6, 0.0, -0.8],
        [0.123, 0.456, -0.881],
        [-0.57735, -0.57735, 0.57735],
        [0.9, -0.3, -0.316_227_8],
        [3.0, -5.0, 7.0], // not unit; all |c| >= 1 so it also survives a MIN_POSITIVE scale
    ];
    let pow2_scales = [f32::MIN_POSITIVE, 2f32.powi(-100), 2f32.powi(-10), 2f32.powi(100)];
    let other_scales = [1e-30f32, 1e-3, 7.5, 1e30, f32::MAX, 0.99 * f32::MAX / 7.0];
    for n in base {
        for p in Precision::ALL {
            let reference = encode(n, p);
            for s in pow2_scales {
                if s == f32::MIN_POSITIVE && n[0].abs() < 1.0 {
                    continue; // would be denormal: covered below
                }
                // Exact: a power-of-two scale of normal floats is undone exactly by sanitize.
                assert_eq!(encode([n[0] * s, n[1] * s, n[2] * s], p), reference, "{p:?} {n:?}·{s}");
            }
            for s in other_scales {
                if n[2] * s == f32::INFINITY {
                    continue; // (3,-5,7)·MAX overflows: that is the ±inf rule, tested elsewhere
                }
                // Inexact: n·s is rounded (relative change ≤ 2^-24 per component), which can move a
                // value sitting within a few ULP of a .5 rounding boundary to the next code.
                let w = encode([n[0] * s, n[1] * s, n[2] * s], p);
                if p == Precision::F32 {
                    for c in 0..3 {
                        let d = (f32::from_bits(w[c]) - f32::from_bits(reference[c])).abs();
                        assert!(d <= 4.0 * U as f32, "{n:?}·{s}: {w:?} vs {reference:?}");
                    }
                } else {
                    let b = p.bits();
                    let (a, r) = (codes(w[0], b), codes(reference[0], b));
                    assert!((a.0 - r.0).abs() <= 1 && (a.1 - r.1).abs() <= 1, "{p:?} {n:?}·{s}: {a:?} vs {r:?}");
                }
            }
        }
    }
    // A unit vector times MIN_POSITIVE has denormal components: flushed, so it becomes +Z.
    for p in Precision::ALL {
        let s = f32::MIN_POSITIVE;
        assert_eq!(decode(encode([0.6 * s, 0.8 * s, 0.0], p), p), [0.0, 0.0, 1.0]);
        // The largest finite inputs do not overflow the L1 sum.
        assert_eq!(encode([f32::MAX, -f32::MAX, f32::MAX], p)[0], encode([1.0, -1.0, 1.0], p)[0]);
    }
}

#[test]
fn nan_and_inf() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    for p in Precision::ALL {
        for v in [[nan, 0.0, 0.0], [0.3, nan, -0.2], [1.0, 1.0, nan], [nan, nan, nan], [inf, nan, 0.0], [-nan, 1.0, 1.0]] {
            assert_eq!(decode(encode(v, p), p), [0.0, 0.0, 1.0], "{p:?} {v:?}");
        }
        let cases = [
            ([inf, 0.0, 0.0], [1.0, 0.0, 0.0]),
            ([-inf, 5.0, -3.0], [-1.0, 0.0, 0.0]),
            ([1e30, 2.0, -inf], [0.0, 0.0, -1.0]),
            ([inf, -inf, 1.0], [1.0, -1.0, 0.0]),
            ([inf, inf, inf], [1.0, 1.0, 1.0]),
            ([-inf, -inf, -inf], [-1.0, -1.0, -1.0]),
            ([0.0, inf, -inf], [0.0, 1.0, -1.0]),
        ];
        for (v, expect) in cases {
            check_dir(v, to64(expect), p);
        }
    }
}

#[test]
fn bound_values() {
    let table = [(8, 1.6710e-2), (12, 1.0416e-3), (16, 6.9979e-5)];
    for (b, v) in table {
        let got = max_angular_error_bound(b) as f64;
        assert!((got - v).abs() < 1e-4 * v, "bits {b}: {got} vs doc {v}");
    }
    assert_eq!(max_angular_error_bound(32), 2f32.powi(-23));
    assert_eq!(Precision::Oct12.max_angular_error_bound(), max_angular_error_bound(12));
    // The rounded-up widths share bounds.
    assert_eq!(max_angular_error_bound(10), max_angular_error_bound(12));
}

#[test]
fn error_study() {
    const N: u32 = 1 << 20;
    let mut max = [0.0f64; 4];
    let mut sum = [0.0f64; 4];
    let mut max_len_err = [0.0f64; 4];
    for i in 0..N {
        let n = fibonacci_sphere(i, N);
        assert!(is_finite3(n));
        let l = norm64(to64(n));
        assert!((l - 1.0).abs() < 1e-6, "fibonacci point {i} length {l}");
        let exact = to64(n);
        for (k, p) in Precision::ALL.into_iter().enumerate() {
            let d = decode(encode(n, p), p);
            assert!(is_finite3(d), "{p:?} {n:?}");
            let len_err = (norm64(to64(d)) - 1.0).abs();
            max_len_err[k] = max_len_err[k].max(len_err);
            let a = angle(exact, to64(d));
            max[k] = max[k].max(a);
            sum[k] += a;
        }
    }
    println!();
    println!("octahedral error study: {N} spherical-Fibonacci directions");
    println!("precision  B/px      max (deg)      mean (deg)     bound (deg)   max/bound  max |len-1|");
    for (k, p) in Precision::ALL.into_iter().enumerate() {
        let bound = p.max_angular_error_bound() as f64;
        println!(
            "{:<9} {:>4}  {:>13.6e}  {:>13.6e}  {:>13.6e}  {:>9.4}  {:>9.2e}",
            format!("{p:?}"),
            p.bytes_per_pixel(),
            max[k].to_degrees(),
            (sum[k] / N as f64).to_degrees(),
            bound.to_degrees(),
            max[k] / bound,
            max_len_err[k],
        );
        assert!(max[k] <= bound, "{p:?}: max error {} rad > bound {bound}", max[k]);
        assert!(max_len_err[k] <= 5.0 * U, "{p:?}: length error {}", max_len_err[k]);
    }
}

#[test]
fn inexact_gpu_division_moves_codes_by_at_most_one() {
    // Emulate a GPU whose `1.0 / l1` is off by up to ±5 ULP (the spec allows 2.5): codes differ
    // from the CPU's by at most one step, and the decoded direction stays within the bound.
    const N: u32 = 1 << 16;
    let mut changed = [0u32; 3];
    for i in 0..N {
        let n = fibonacci_sphere(i, N);
        let v = sanitize(n);
        let inv = 1.0 / (v[0].abs() + v[1].abs() + v[2].abs());
        for (k, b) in [8u32, 12, 16].into_iter().enumerate() {
            let reference = encode_oct(n, b);
            let (rx, ry) = codes(reference, b);
            for d in [-5i32, -2, -1, 1, 2, 5] {
                let inv_gpu = f32::from_bits((inv.to_bits() as i32 + d) as u32);
                let uv = project_with_inv(v, inv_gpu);
                let (qx, qy) = (snorm_encode(uv[0], b), snorm_encode(uv[1], b));
                assert!((qx - rx).abs() <= 1 && (qy - ry).abs() <= 1, "{n:?} bits {b} ulp {d}");
                changed[k] += ((qx, qy) != (rx, ry)) as u32;
                let w = (qx as u32 & ((1 << b) - 1)) | ((qy as u32 & ((1 << b) - 1)) << b);
                let a = angle(to64(n), to64(decode_oct(w, b)));
                assert!(a <= max_angular_error_bound(b) as f64);
            }
        }
    }
    println!("\n±1..5-ULP division: codes changed in {changed:?} of {} encodes (8/12/16 bits)", 6 * N);
}

/// The shading passes' G-buffer fetch (`shading::gbuffer_normal`): one word per pixel for the
/// octahedral codes, four (three bit patterns and a pad) for float32, each pixel decoding to
/// exactly what its own encoding decodes to.
#[test]
fn gbuffer_normal_fetch_uses_each_precisions_stride() {
    use crate::shading::gbuffer_normal;
    use crate::layout::FrameParams;
    let dirs = [[0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [-0.48, 0.6, 0.64], [0.3, 0.3, -0.905_538_5]];
    for p in Precision::ALL {
        let mut buf = Vec::new();
        for d in dirs {
            let w = encode(d, p);
            buf.extend_from_slice(&[w[0], w[1], w[2], 0][..p.gbuffer_words() as usize]);
        }
        assert_eq!(buf.len(), dirs.len() * p.gbuffer_words() as usize);
        let fp = FrameParams { normal_precision: p as u32, ..bytemuck::Zeroable::zeroed() };
        for (i, d) in dirs.iter().enumerate() {
            assert_eq!(gbuffer_normal(&fp, &buf, i as u32).to_array(), decode(encode(*d, p), p), "{p:?}, pixel {i}");
        }
    }
}
