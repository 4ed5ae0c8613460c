//! CPU tests of `morton`.
use super::*;

/// xorshift64* PRNG (no external crates).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn u32(&mut self) -> u32 {
        (self.next() >> 32) as u32
    }
    /// Uniform in [lo, hi).
    fn f32(&mut self, lo: f32, hi: f32) -> f32 {
        let t = (self.next() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * t
    }
}

/// Reference interleave: bit i of axis a goes to bit 3i + a.
fn ref_interleave(q: [u32; 3], bits: u32) -> u64 {
    let mut code = 0u64;
    for i in 0..bits {
        for (a, &v) in q.iter().enumerate() {
            code |= (((v >> i) & 1) as u64) << (3 * i + a as u32);
        }
    }
    code
}

fn next_down(x: f32) -> f32 {
    if x > 0.0 {
        f32::from_bits(x.to_bits() - 1)
    } else if x < 0.0 {
        f32::from_bits(x.to_bits() + 1)
    } else {
        -f32::from_bits(1)
    }
}

const LO: [f32; 3] = [-3.7, 0.25, -1200.0];
const HI: [f32; 3] = [12.9, 0.5, 35.5];

#[test]
fn layout_and_constants() {
    assert_eq!(core::mem::size_of::<MortonQuantizer>(), 24);
    assert_eq!(MAX_SCALE, 2f32.powi(126));
    assert_eq!(morton30([1, 0, 0]), 0b001);
    assert_eq!(morton30([0, 1, 0]), 0b010);
    assert_eq!(morton30([0, 0, 1]), 0b100);
    assert_eq!(morton30([2, 0, 0]), 0b001_000);
    assert_eq!(morton30([1023, 1023, 1023]), (1 << 30) - 1);
    assert_eq!(morton63([(1 << 21) - 1; 3]), (1u64 << 63) - 1);
    assert_eq!(morton63([1 << 20, 0, 0]), 1u64 << 60);
    assert_eq!(morton63([0, 0, 1 << 20]), 1u64 << 62);
    // Bits above the width are ignored.
    assert_eq!(morton30([1024 | 5, 0xffff_fc00, 0]), morton30([5, 0, 0]));
    assert_eq!(morton63([1 << 21 | 9, 0, 0]), morton63([9, 0, 0]));
}

#[test]
fn magic_numbers_match_reference() {
    for v in 0..1024u32 {
        assert_eq!(expand_bits_10(v) as u64, ref_interleave([v, 0, 0], 10));
        assert_eq!(compact_bits_10(expand_bits_10(v)), v);
        for a in 0..3 {
            let mut q = [0; 3];
            q[a] = v;
            assert_eq!(morton30(q) as u64, ref_interleave(q, 10), "axis {a} value {v}");
            assert_eq!(morton63(q), ref_interleave(q, 21));
        }
    }
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for _ in 0..200_000 {
        let q10 = [rng.u32() & 1023, rng.u32() & 1023, rng.u32() & 1023];
        let c30 = morton30(q10);
        assert_eq!(c30 as u64, ref_interleave(q10, 10));
        assert_eq!(morton30_decode(c30), q10);
        // morton63 of 10-bit cells equals morton30.
        assert_eq!(morton63(q10), c30 as u64);
        let m = (1 << 21) - 1;
        let q21 = [rng.u32() & m, rng.u32() & m, rng.u32() & m];
        let c63 = morton63(q21);
        assert_eq!(c63, ref_interleave(q21, 21));
        assert_eq!(morton63_decode(c63), q21);
        // The top 30 bits of a 63-bit code are the 30-bit code of the top 10 bits of each cell.
        assert_eq!(c63 >> 33, morton30([q21[0] >> 11, q21[1] >> 11, q21[2] >> 11]) as u64);
        let v = rng.next() & 0x1f_ffff;
        assert_eq!(expand_bits_21(v), ref_interleave([v as u32, 0, 0], 21));
        assert_eq!(compact_bits_21(expand_bits_21(v)), v);
    }
}

#[test]
fn bounds_map_to_first_and_last_cell() {
    for bits in [1u32, 5, MORTON30_BITS, MORTON63_BITS, 24] {
        let q = MortonQuantizer::new(LO, HI, bits);
        let max = (1u32 << bits) - 1;
        assert_eq!(q.quantize(LO, bits), [0; 3]);
        assert_eq!(q.quantize(HI, bits), [max; 3]);
        let below = [next_down(HI[0]), next_down(HI[1]), next_down(HI[2])];
        if bits <= MORTON63_BITS {
            assert_eq!(q.quantize(below, bits), [max; 3], "bits {bits}");
        } else {
            // 2^24 cells are about one ULP of the coordinates: the previous float may fall into
            // the previous cell.
            assert!(q.quantize(below, bits).iter().all(|&c| c >= max - 1));
        }
        // Outside: clamped.
        assert_eq!(q.quantize([LO[0] - 1.0, next_down(LO[1]), -1e30], bits), [0; 3]);
        assert_eq!(q.quantize([HI[0] + 1.0, 1e30, f32::MAX], bits), [max; 3]);
        assert_eq!(q.quantize([-f32::MAX, f32::MAX, 0.0], bits), [0, max, q.quantize([0.0; 3], bits)[2]]);
    }
    // Power-of-two box: scale 1, cell k is [k, k+1).
    let q = MortonQuantizer::new([0.0; 3], [1024.0; 3], 10);
    assert_eq!(q.scale, [1.0; 3]);
    for k in 1..1024u32 {
        let kf = k as f32;
        assert_eq!(q.quantize([kf, next_down(kf), kf + 0.5], 10), [k, k - 1, k]);
    }
    assert_eq!(q.quantize([-0.0, 0.0, 1e-45], 10), [0; 3]);
}

#[test]
fn degenerate_bounds() {
    let p = [0.3, 7.0, -2.0];
    // Zero size on one axis.
    let q = MortonQuantizer::new([0.0, 7.0, -5.0], [1.0, 7.0, 5.0], 10);
    assert_eq!(q.scale[1], 0.0);
    let c = q.quantize(p, 10);
    assert_eq!(c[1], 0);
    assert_eq!(c, [(0.3f32 * 1024.0) as u32, 0, (3.0f32 * 102.4) as u32]);
    assert_eq!(q.quantize([0.3, 1e30, -2.0], 10)[1], 0);
    // Zero size / inverted / NaN / infinite on all axes.
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let cases = [
        ([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]),
        ([1.0, 2.0, 3.0], [0.0, -2.0, 2.9]),
        ([nan, nan, nan], [nan, nan, nan]),
        ([nan, 0.0, -inf], [1.0, nan, 1.0]),
        ([-inf, -inf, 0.0], [inf, 0.0, inf]),
        ([-3e38, 0.0, 0.0], [3e38, 0.0, 0.0]), // extent overflows to inf
        ([0.0, 1.0, 5.0], [1e-37, 1.0, 5.0]), // scale > 2^126 / exactly empty
    ];
    for (lo, hi) in cases {
        for bits in [10, 21] {
            let q = MortonQuantizer::new(lo, hi, bits);
            assert_eq!(q.scale, [0.0; 3], "{lo:?} {hi:?}");
            assert!(q.min.iter().all(|m| m.is_finite()));
            for p in [p, [nan; 3], [inf; 3], [-inf; 3], [1e30, -1e30, 0.0], lo, hi] {
                assert_eq!(q.quantize(p, bits), [0; 3], "{lo:?} {hi:?} {p:?}");
            }
        }
    }
    // Small but resolvable extents are fine: one ULP of 1.0 split into 1024 cells.
    let q = MortonQuantizer::new([1.0; 3], [next_up(1.0); 3], 10);
    assert_eq!(q.scale, [1024.0 * 8_388_608.0; 3]);
    assert_eq!(q.quantize([1.0, next_up(1.0), 0.0], 10), [0, 1023, 0]);
    // bits = 0: one cell.
    let q = MortonQuantizer::new(LO, HI, 0);
    assert_eq!(q.quantize(HI, 0), [0; 3]);
}

fn next_up(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1) // positive x only
}

#[test]
fn nan_and_inf_positions() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let q = MortonQuantizer::new(LO, HI, 10);
    let mid = q.quantize([0.0, 0.4, 0.0], 10);
    assert_eq!(q.quantize([nan, 0.4, 0.0], 10), [0, mid[1], mid[2]]);
    assert_eq!(q.quantize([-nan, nan, nan], 10), [0; 3]);
    assert_eq!(q.quantize([inf, -inf, inf], 10), [1023, 0, 1023]);
    assert_eq!(q.morton30_of([inf; 3]), (1 << 30) - 1);
    assert_eq!(q.morton30_of([-inf; 3]), 0);
    assert_eq!(q.morton30_of([nan; 3]), 0);
    let q = MortonQuantizer::new(LO, HI, 21);
    assert_eq!(q.morton63_of([inf; 3]), (1 << 63) - 1);
    assert_eq!(q.morton63_of([nan, -inf, nan]), 0);
}

#[test]
fn monotone_along_each_axis() {
    let mut rng = Rng(12345);
    let q10 = MortonQuantizer::new(LO, HI, 10);
    let q21 = MortonQuantizer::new(LO, HI, 21);
    for _ in 0..200 {
        let base = [rng.f32(LO[0], HI[0]), rng.f32(LO[1], HI[1]), rng.f32(LO[2], HI[2])];
        for a in 0..3 {
            let (mut last30, mut last63) = (0u32, 0u64);
            let (mut last_q, mut distinct) = (0u32, 0);
            let n = 3000;
            for i in 0..=n {
                let mut p = base;
                // From below min to above max.
                let span = HI[a] - LO[a];
                p[a] = LO[a] - 0.1 * span + 1.2 * span * (i as f32 / n as f32);
                let (c30, c63) = (q10.morton30_of(p), q21.morton63_of(p));
                assert!(c30 >= last30 && c63 >= last63, "axis {a} step {i}");
                let cell = q10.quantize(p, 10)[a];
                assert!(cell >= last_q && cell <= last_q + 1 || i == 0);
                distinct += (cell != last_q) as u32;
                (last30, last63, last_q) = (c30, c63, cell);
            }
            assert_eq!(distinct, 1023, "every cell visited along axis {a}");
        }
    }
}

#[test]
fn morton63_refines_morton30() {
    // Quantizers from the same bounds: scale21 == 2^11·scale10 exactly, so the top 30 bits of the
    // 63-bit code are the 30-bit code, bit for bit.
    let mut rng = Rng(777);
    let q10 = MortonQuantizer::new(LO, HI, 10);
    let q21 = MortonQuantizer::new(LO, HI, 21);
    for a in 0..3 {
        assert_eq!(q21.scale[a], q10.scale[a] * 2048.0);
    }
    for _ in 0..1_000_000 {
        let p = [rng.f32(-5.0, 14.0), rng.f32(0.2, 0.6), rng.f32(-1300.0, 40.0)];
        assert_eq!(q21.morton63_of(p) >> 33, q10.morton30_of(p) as u64, "{p:?}");
        let c = q10.quantize(p, 10);
        let f = q21.quantize(p, 21);
        assert_eq!([f[0] >> 11, f[1] >> 11, f[2] >> 11], c);
    }
}
