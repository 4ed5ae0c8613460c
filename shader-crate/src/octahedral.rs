//! Octahedral unit-vector encoding (Cigolle, Donow, Evangelakos, Mara, McGuire, Meyer 2014,
//! "A Survey of Efficient Representations for Independent Unit Vectors", JCGT 3(2)), plus an
//! `f32` passthrough, as pure functions shared by the GPU kernels and the CPU tests.
//!
//! # The map
//!
//! A direction `n` is L1-normalised, `p = n / (|x| + |y| + |z|)`, which puts it on the octahedron
//! `|x| + |y| + |z| = 1`. The upper half (`z >= 0`) projects straight down onto the diamond
//! `|u| + |v| <= 1`: `(u, v) = (p.x, p.y)`. The lower half is folded outwards over the diamond's
//! edges (the diagonals of the square): `(u, v) = ((1 - |p.y|)·sx, (1 - |p.x|)·sy)`, which fills the
//! four corner triangles of the square `[-1, 1]²`. Decoding inverts this: `p = (u, v, 1-|u|-|v|)`,
//! and if `p.z < 0`, `(p.x, p.y) = ((1 - |v|)·su, (1 - |u|)·sv)`; then `n = p / |p|₂`.
//!
//! ```text
//!              v
//!   (-1,1) +---------+---------+ (1,1)   corners (±1,±1): -Z
//!          |  -Z   / | \   -Z  |
//!          |     /  +Y   \     |         diamond |u|+|v| <= 1: z >= 0
//!          |   /     |     \   |         (centre +Z, vertices ±X, ±Y)
//!   (-1,0) +-X------+Z------X+-+ (1,0)
//!          |   \     |     /   |         4 corner triangles: z < 0 (folded)
//!          |     \  -Y   /     |
//!          |  -Z   \ | /   -Z  |         edges glued in mirror pairs:
//!  (-1,-1) +---------+---------+ (1,-1)  (u, 1) ~ (-u, 1), (1, v) ~ (1, -v)
//!                                  u
//! ```
//!
//! Signs follow `s(c) = if c >= 0.0 { 1.0 } else { -1.0 }`, so `-0.0` counts as positive: the
//! result never depends on the sign of a zero (GPUs may ignore signed zeros by default).
//!
//! # Precisions and bit layouts
//!
//! Every precision encodes to [`EncodedNormal`] = `[u32; 3]`. The octahedral ones use word 0 only
//! (words 1 and 2 are zero); `F32` stores the bit patterns of the three components of the
//! sanitised, normalised vector. `b`-bit snorm: `M = 2^(b-1) - 1`, `q = s(c)·floor'(|c|·M)` with
//! round-half-away-from-zero (`floor'` = round half up of the non-negative product), stored as
//! two's complement in `b` bits. Decoding: sign-extend, `c = q · (1/M)` (constant reciprocal,
//! never a division), clamped to `[-1, 1]` (`q = -M-1` would give `c < -1`).
//!
//! ```text
//! OCT8   31                 16 15        8 7         0     2 bytes/pixel packed
//!        +--------------------+-----------+-----------+    (R16_UINT / RG8_SNORM texel)
//!        |     0 (unused)     |  y  (s8)  |  x  (s8)  |
//!        +--------------------+-----------+-----------+
//! OCT12  31        24 23            12 11             0     3 bytes/pixel packed
//!        +-----------+----------------+----------------+    (4 in an R32 texel: 8 spare bits)
//!        | 0 (unused)|    y  (s12)    |    x  (s12)    |
//!        +-----------+----------------+----------------+
//! OCT16  31                       16 15                0     4 bytes/pixel
//!        +---------------------------+-----------------+    (R32_UINT / RG16_SNORM texel)
//!        |          y  (s16)         |     x  (s16)    |
//!        +---------------------------+-----------------+
//! F32    word 0 = x.to_bits(), word 1 = y.to_bits(),        12 bytes/pixel
//!        word 2 = z.to_bits()                               (16 in an RGBA32F texel)
//! ```
//!
//! At 1920×1080 that is 4.1 MB (OCT8), 6.2 MB (OCT12), 8.3 MB (OCT16) and 24.9 MB (F32).
//! Other `bits` arguments of [`encode_oct`] / [`decode_oct`] are rounded up to the next of
//! 8, 12, 16 (and anything above 16 means 16), see [`oct_bits`].
//!
//! # Sanitisation (shared by all precisions, [`sanitize`])
//!
//! All classification is done on bit patterns (integer ops), which GPU compilers cannot fold
//! away under the default Vulkan "may assume no NaN/Inf" float rules, and which see a denormal
//! whether or not the GPU would flush it.
//! 1. Any NaN component → the default direction `+Z = (0, 0, 1)`.
//! 2. Any ±inf component → the direction is the sum of the signed infinite axes: inf components
//!    become ±1, finite ones 0 (so `(inf, -inf, 5)` → `(1, -1, 0)`).
//! 3. Flush-to-zero: any component with `|c| < f32::MIN_POSITIVE` (zero or denormal; tested as
//!    "exponent field is 0", equivalent to `c.abs() < f32::MIN_POSITIVE`) becomes `+0.0`, so the CPU
//!    and a denormal-flushing GPU agree. Consequently denormal components are ignored by design:
//!    all-denormal → `+Z`, and e.g. `(2e-38, 1e-40, 0)` encodes as `+X`.
//! 4. All zero → `+Z`.
//! 5. Exact power-of-two rescale: with `m = max |c|` and `e` its unbiased exponent (from the bits),
//!    every component is multiplied by `2^-e` (in two steps `2^k1 · 2^k2`, each a normal float),
//!    putting `m` into `[1, 2)`: the L1 sum then lies in `[1, 6)` and can neither overflow nor
//!    underflow. Multiplying by a power of two is exact on CPU and GPU except for results that
//!    become denormal; those (components below `2^-126·m`, far below any quantisation step) are
//!    flushed to `+0.0` again. The two steps have the same sign, so a denormal intermediate is only
//!    ever produced on the way down and ends flushed on both CPU and GPU.
//!
//! # CPU/GPU agreement
//!
//! Vulkan: add/sub/mul correctly rounded (round-to-nearest-even on all current GPUs), `a*b+c` may
//! be fused, division 2.5 ULP, `sqrt` inherited from `1/inversesqrt` (2 ULP + 2.5 ULP),
//! denormals may be flushed on any operation.
//! * Encode: sanitisation is exact; the L1 sum is adds only (identical); the only inexact GPU op is
//!   `inv = 1.0 / l1` (≤ 2.5 ULP vs CPU's 0.5). Folds use `1 - |c|` and a select on the sign (no
//!   multiply); the fold decision uses the sign of the sanitised `z` (exact), not of `z·inv`
//!   (which may underflow and be flushed). Rounding is `f = floor(t); if t >= f + 0.5 { f + 1 }`
//!   with `t = |c|·M`: no `a*b+c` pattern the GPU could fuse, and no double rounding of `t + 0.5`.
//!   Hence GPU `c` differs from CPU `c` by at most ≈ 8u+1u (u = 2^-24; 6u from the division
//!   difference, 2u from the product roundings, ≤ 1u from the fold subtraction), and a code can
//!   differ by ±1 only when the CPU's `t` lies within `≈ 9u·M` (≈ 10 ULP of `t`) of a `.5`
//!   rounding boundary. For `F32` the encoded components differ by at most 21 ULP (see decode).
//! * Decode: everything up to the dot product is sign-extension, a multiply by a constant and
//!   subtractions: identical. `n = p · (1/sqrt(dot))`: CPU relative error ≤ 3u (dot, with or
//!   without fma, positive terms) / 2 + u (sqrt) + u (div) + u (mul) = 4.5u; GPU per the spec
//!   minimums ≤ 1.5u + 4u (inversesqrt) + 5u (1/x in sqrt) + 5u (div) + u (mul) = 16.5u. As
//!   `ULP(c) >= u·|c|`, a component differs by **at most 21 ULP** (≤ 11 ULP if the driver turns
//!   `1/sqrt` into one `inversesqrt`, or on hardware with ≤ 1 ULP sqrt/rcp). The error is almost
//!   entirely a common scale factor: the *directions* of CPU and GPU results differ by ≤ 2u
//!   (≈ 1.2e-7 rad), and since `p` is identical on both, GPU decoding is as accurate as the CPU.
//!
//! # Angular error bound ([`max_angular_error_bound`])
//!
//! Let `a` be the exact square point of the input direction and `b` the point that decoding uses.
//! Rounding to the nearest multiple of `1/M` (the grid includes ±1) moves each coordinate by at
//! most `h = 1/(2M)`; float error adds at most `ε = 1e-6` per coordinate (encode: ≤ 9u from
//! the L1 sum, the (GPU, 2.5 ULP) division, the product and the fold; rounding of `t = |c|·M`:
//! ≤ u·M in `t`, i.e. ≤ u; decode `q·(1/M)`: ≤ 2u; total 12u < 7.2e-7). So
//! `|a - b|∞ <= δ = h + ε`.
//!
//! The decode map `F(u, v) = p` is continuous and, on each of its 8 triangles (4 quadrants ×
//! diamond/corner), linear: `dp = (du, dv, -su·du - sv·dv)` inside the diamond and a signed
//! permutation of the first two entries in the corners, so
//! `|dp|₂ <= sqrt(du² + dv² + (|du| + |dv|)²) <= √6 · max(|du|, |dv|)`.
//! Normalisation `N(p) = p/|p|₂` has derivative `(I - n nᵀ)/|p|₂`, of norm `1/|p|₂ <= √3` on the
//! octahedron (`|p|₂ >= |p|₁/√3 = 1/√3`). The square is convex, so the segment `a → b` stays in it,
//! and its image `N(F(segment))` is a curve on the sphere from the true to the decoded direction
//! of length `<= √3 · √6 · δ = 3√2·δ`; the angle (geodesic distance) is at most that length.
//! The bound is attained to first order at the face centres `(±1/3, ±1/3, ±1/3)` for a diagonal
//! error `(h, h)`, so it cannot be improved by more than the float slack.
//! Decode-side float error: `1 - |u| - |v|` and the folds add ≤ 2u per coordinate of `p`
//! (angle ≤ √3·|Δp|₂ ≤ 6u) and the final products ≤ u (angle ≤ u): < 1e-6 in total. Hence
//!
//! `θ_max <= 3√2 · (1/(2M) + 1e-6) + 1e-6`   (radians)
//!
//! | precision | M     | bound (rad) | bound (deg) |
//! |-----------|-------|-------------|-------------|
//! | OCT8      | 127   | 1.6710e-2   | 0.9574      |
//! | OCT12     | 2047  | 1.0416e-3   | 0.05968     |
//! | OCT16     | 32767 | 6.9979e-5   | 0.004010    |
//!
//! `F32`: sanitisation is exact, `1/sqrt(dot)` only scales all components alike, and each final
//! product `v_i·inv` has relative error ≤ u, so `|d - s·v| <= u·|s·v|` and `sin θ <= u`; flushing
//! output components below 2^-126 adds < 2^-125. Hence `θ <= 2^-24·(1 + 1e-7) + 2^-125`; the
//! function returns `2u = 2^-23 ≈ 1.19e-7` rad (the 21-ULP CPU/GPU length difference is a common
//! scale and does not change this). All bounds assume normal (non-denormal) input components.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

/// Encoded normal: word 0 holds an octahedral code (words 1, 2 zero), or the three `f32` bit
/// patterns for [`Precision::F32`].
pub type EncodedNormal = [u32; 3];

/// `Precision::Oct8 as u32`.
pub const OCT8: u32 = crate::layout::PRECISION_OCT8;
/// `Precision::Oct12 as u32`.
pub const OCT12: u32 = crate::layout::PRECISION_OCT12;
/// `Precision::Oct16 as u32`.
pub const OCT16: u32 = crate::layout::PRECISION_OCT16;
/// `Precision::F32 as u32`.
pub const F32: u32 = crate::layout::PRECISION_F32;

/// The default direction for NaN or all-zero input.
pub const DEFAULT_DIRECTION: [f32; 3] = [0.0, 0.0, 1.0];

/// Storage precision of a normal.
#[derive(Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug))]
#[repr(u32)]
pub enum Precision {
    /// 2 × 8-bit snorm, low 16 bits of word 0.
    Oct8 = OCT8,
    /// 2 × 12-bit snorm, low 24 bits of word 0.
    Oct12 = OCT12,
    /// 2 × 16-bit snorm, all 32 bits of word 0.
    Oct16 = OCT16,
    /// Three `f32` bit patterns (sanitised and normalised).
    F32 = F32,
}

impl Precision {
    /// All precisions, lowest first.
    pub const ALL: [Precision; 4] = [Precision::Oct8, Precision::Oct12, Precision::Oct16, Precision::F32];

    /// `0 → Oct8, 1 → Oct12, 2 → Oct16`, anything else → `F32` (lossless fallback).
    #[inline]
    pub const fn from_u32(v: u32) -> Precision {
        match v {
            OCT8 => Precision::Oct8,
            OCT12 => Precision::Oct12,
            OCT16 => Precision::Oct16,
            _ => Precision::F32,
        }
    }

    /// The kernel constant (`layout::PRECISION_*`), as `FrameParams`/`DrawParams` carry it.
    #[inline]
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// Bits per component: 8, 12, 16 or 32.
    #[inline]
    pub const fn bits(self) -> u32 {
        match self {
            Precision::Oct8 => 8,
            Precision::Oct12 => 12,
            Precision::Oct16 => 16,
            Precision::F32 => 32,
        }
    }

    /// Packed storage cost per pixel in bytes (2, 3, 4, 12).
    #[inline]
    pub const fn bytes_per_pixel(self) -> u32 {
        match self {
            Precision::Oct8 => 2,
            Precision::Oct12 => 3,
            Precision::Oct16 => 4,
            Precision::F32 => 12,
        }
    }

    /// Words per pixel of the G-buffer's normal target: 1 (`R32_UINT`, an octahedral code) or 4
    /// for `F32` (`R32G32B32A32_UINT`: the three bit patterns and a zero; no 96-bit colour
    /// format is renderable).
    #[inline]
    pub const fn gbuffer_words(self) -> u32 {
        match self {
            Precision::F32 => 4,
            _ => 1,
        }
    }

    /// [`max_angular_error_bound`]`(self.bits())`.
    #[inline]
    pub const fn max_angular_error_bound(self) -> f32 {
        max_angular_error_bound(self.bits())
    }
}

/// `1/M` for M = 127, 2047, 32767, evaluated at compile time (correctly rounded).
const INV_M8: f32 = 1.0 / 127.0;
const INV_M12: f32 = 1.0 / 2047.0;
const INV_M16: f32 = 1.0 / 32767.0;

const ABS_MASK: u32 = 0x7fff_ffff;
const EXP_MASK: u32 = 0x7f80_0000;
const INF_BITS: u32 = 0x7f80_0000;

/// Supported snorm width for a requested `bits`: `<= 8 → 8`, `<= 12 → 12`, otherwise 16.
#[inline]
pub const fn oct_bits(bits: u32) -> u32 {
    if bits <= 8 {
        8
    } else if bits <= 12 {
        12
    } else {
        16
    }
}

/// `M = 2^(b-1) - 1` as `f32`, for `b = oct_bits(bits)`.
#[inline]
const fn snorm_max(bits: u32) -> f32 {
    let b = oct_bits(bits);
    if b == 8 {
        127.0
    } else if b == 12 {
        2047.0
    } else {
        32767.0
    }
}

/// `1/M` (a compile-time constant per width, never a runtime division).
#[inline]
const fn snorm_inv_max(bits: u32) -> f32 {
    let b = oct_bits(bits);
    if b == 8 {
        INV_M8
    } else if b == 12 {
        INV_M12
    } else {
        INV_M16
    }
}

/// Proven upper bound (radians) of the angle between a direction with normal components and its
/// decoded encoding: `3√2·(1/(2M) + 1e-6) + 1e-6` for `bits <= 16` (rounded up to 8/12/16 as in
/// [`oct_bits`]), and `2^-23` for `bits > 16` (`F32`). Derivation in the module docs.
pub const fn max_angular_error_bound(bits: u32) -> f32 {
    if bits > 16 {
        return f32::EPSILON; // 2^-23 >= 2^-24·(1+1e-7) + 2^-125
    }
    let h = 0.5 * snorm_inv_max(bits); // 1/(2M), division-free (same value on CPU and GPU)
    3.0 * core::f32::consts::SQRT_2 * (h + 1.0e-6) + 1.0e-6
}

/// `+0.0` if `c` is zero or denormal (exponent field 0), else `c`. Works on the bit pattern, so it
/// gives the same answer whether or not the hardware flushed `c`.
#[inline]
fn flush(c: f32) -> f32 {
    if c.to_bits() & EXP_MASK == 0 {
        0.0
    } else {
        c
    }
}

/// `2^k` for `k` in `[-126, 127]`, exactly.
#[inline]
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// `±1.0` for an infinite `c` (given its bits), else `0.0`.
#[inline]
fn inf_axis(bits: u32) -> f32 {
    if bits & ABS_MASK == INF_BITS {
        if bits >> 31 == 0 {
            1.0
        } else {
            -1.0
        }
    } else {
        0.0
    }
}

/// Sanitised direction (see module docs): NaN/zero/all-denormal → `+Z`; infinities → sum of the
/// signed infinite axes; denormal components → `+0.0`; otherwise the input exactly rescaled by a
/// power of two so that the largest magnitude lies in `[1, 2)`. Not normalised.
pub fn sanitize(n: [f32; 3]) -> [f32; 3] {
    let b = [n[0].to_bits(), n[1].to_bits(), n[2].to_bits()];
    let a = [b[0] & ABS_MASK, b[1] & ABS_MASK, b[2] & ABS_MASK];
    if a[0] > INF_BITS || a[1] > INF_BITS || a[2] > INF_BITS {
        return DEFAULT_DIRECTION;
    }
    if a[0] == INF_BITS || a[1] == INF_BITS || a[2] == INF_BITS {
        return [inf_axis(b[0]), inf_axis(b[1]), inf_axis(b[2])];
    }
    // Magnitude bits of non-negative floats order like the floats; zero/denormal count as 0.
    let m0 = if a[0] & EXP_MASK == 0 { 0 } else { a[0] };
    let m1 = if a[1] & EXP_MASK == 0 { 0 } else { a[1] };
    let m2 = if a[2] & EXP_MASK == 0 { 0 } else { a[2] };
    let m = if m0 > m1 { m0 } else { m1 };
    let m = if m > m2 { m } else { m2 };
    if m == 0 {
        return DEFAULT_DIRECTION;
    }
    // m = 1.f · 2^e with e = (m >> 23) - 127 in [-126, 127]; scale by 2^k, k = -e in [-127, 126],
    // split as k1 + k2 (same signs, each in [-64, 63]) so both factors are normal floats.
    let k = 127 - (m >> 23) as i32;
    let k1 = k >> 1; // floor(k/2): k1 and k - k1 have the sign of k (or are 0)
    let s1 = pow2(k1);
    let s2 = pow2(k - k1);
    [
        flush(flush(n[0]) * s1 * s2),
        flush(flush(n[1]) * s1 * s2),
        flush(flush(n[2]) * s1 * s2),
    ]
}

/// `v · (1/sqrt(v·v))` (the module docs bound the CPU/GPU difference).
#[inline]
fn normalize3(x: f32, y: f32, z: f32) -> [f32; 3] {
    let dot = x * x + y * y + z * z;
    let inv = 1.0 / dot.sqrt();
    [x * inv, y * inv, z * inv]
}

/// `(1 - |other|)` with the sign of `sign_src` (`-0.0` counts as positive), without a multiply.
#[inline]
fn fold_coord(other: f32, sign_src: f32) -> f32 {
    let a = 1.0 - other.abs();
    if sign_src >= 0.0 {
        a
    } else {
        -a
    }
}

/// Unquantised octahedral square coordinates `(u, v)` in `[-1, 1]²` of a (sanitised) direction.
pub fn oct_project(n: [f32; 3]) -> [f32; 2] {
    let v = sanitize(n);
    let l1 = v[0].abs() + v[1].abs() + v[2].abs(); // in [1, 6): adds only, exact on GPU too
    let inv = 1.0 / l1; // the single inexact GPU operation of the encode path
    project_with_inv(v, inv)
}

/// The rest of [`oct_project`] for a sanitised `v` and `inv ≈ 1/|v|₁` (split out so the tests can
/// emulate a GPU division that is off by a few ULP).
#[inline]
fn project_with_inv(v: [f32; 3], inv: f32) -> [f32; 2] {
    let px = v[0] * inv;
    let py = v[1] * inv;
    // Decide and sign with the sanitised values (exact), not with px/py/pz (may underflow).
    if v[2] < 0.0 {
        [fold_coord(py, v[0]), fold_coord(px, v[1])]
    } else {
        [px, py]
    }
}

/// Inverse of [`oct_project`]: the unit direction of square point `(u, v)` (clamped to `[-1,1]²`).
pub fn oct_unproject(uv: [f32; 2]) -> [f32; 3] {
    let u = clamp_unit(uv[0]);
    let v = clamp_unit(uv[1]);
    let z = 1.0 - u.abs() - v.abs();
    if z < 0.0 {
        normalize3(fold_coord(v, u), fold_coord(u, v), z)
    } else {
        normalize3(u, v, z)
    }
}

/// Clamp to `[-1, 1]` with explicit compares (NaN → 0).
#[inline]
fn clamp_unit(c: f32) -> f32 {
    if c > 1.0 {
        1.0
    } else if c < -1.0 {
        -1.0
    } else if c >= -1.0 {
        c
    } else {
        0.0
    }
}

/// `b`-bit snorm code of `c` (clamped to `[-1, 1]`), round half away from zero, as an `i32`
/// in `[-M, M]`. `b = oct_bits(bits)`.
#[inline]
pub fn snorm_encode(c: f32, bits: u32) -> i32 {
    let a = clamp_unit(c).abs();
    let t = a * snorm_max(bits); // correctly rounded on CPU and GPU; t in [0, M]
    let f = t.floor();
    // Exact round-half-up of t: no `t + 0.5` (double rounding, and fusable into an fma).
    let r = if t >= f + 0.5 { f + 1.0 } else { f };
    let q = r as i32;
    if c >= 0.0 {
        q
    } else {
        -q
    }
}

/// Value of `b`-bit snorm code `q`: `q · (1/M)` clamped to `[-1, 1]`.
#[inline]
pub fn snorm_decode(q: i32, bits: u32) -> f32 {
    clamp_unit(q as f32 * snorm_inv_max(bits))
}

/// Sign-extend the low `b` bits of `w` (`b` in 8..=16).
#[inline]
fn sign_extend(w: u32, b: u32) -> i32 {
    let sh = 32 - b;
    ((w << sh) as i32) >> sh
}

/// Octahedral code of `n` with `bits` per component (8, 12, 16; see [`oct_bits`]):
/// `x` in bits `0..b`, `y` in bits `b..2b`.
pub fn encode_oct(n: [f32; 3], bits: u32) -> u32 {
    let b = oct_bits(bits);
    let mask = (1u32 << b) - 1;
    let uv = oct_project(n);
    let qx = snorm_encode(uv[0], b) as u32 & mask;
    let qy = snorm_encode(uv[1], b) as u32 & mask;
    qx | (qy << b)
}

/// Unit direction of octahedral code `w` with `bits` per component (see [`encode_oct`]).
pub fn decode_oct(w: u32, bits: u32) -> [f32; 3] {
    let b = oct_bits(bits);
    let u = snorm_decode(sign_extend(w, b), b);
    let v = snorm_decode(sign_extend(w >> b, b), b);
    oct_unproject([u, v])
}

/// Sanitised and normalised `n` (the values stored by [`Precision::F32`]); output components
/// that would be denormal are flushed to `+0.0`.
pub fn encode_f32(n: [f32; 3]) -> [f32; 3] {
    let v = sanitize(n);
    let r = normalize3(v[0], v[1], v[2]); // dot in [1, 12): no overflow, no underflow
    [flush(r[0]), flush(r[1]), flush(r[2])]
}

/// Encode `n` (any finite or non-finite vector; see the sanitisation rules) at `precision`.
pub fn encode(n: [f32; 3], precision: Precision) -> EncodedNormal {
    match precision {
        Precision::Oct8 => [encode_oct(n, 8), 0, 0],
        Precision::Oct12 => [encode_oct(n, 12), 0, 0],
        Precision::Oct16 => [encode_oct(n, 16), 0, 0],
        Precision::F32 => {
            let r = encode_f32(n);
            [r[0].to_bits(), r[1].to_bits(), r[2].to_bits()]
        }
    }
}

/// Decode words produced by [`encode`] with the same `precision`. `F32` returns the stored floats.
pub fn decode(words: EncodedNormal, precision: Precision) -> [f32; 3] {
    match precision {
        Precision::Oct8 => decode_oct(words[0], 8),
        Precision::Oct12 => decode_oct(words[0], 12),
        Precision::Oct16 => decode_oct(words[0], 16),
        Precision::F32 => [f32::from_bits(words[0]), f32::from_bits(words[1]), f32::from_bits(words[2])],
    }
}

/// Point `i` of an `n`-point spherical Fibonacci lattice (`z = 1 - (2i+1)/n`, azimuth
/// `2π·frac(i·φ⁻¹)` from a 0.32 fixed-point product, so it stays accurate for large `i`).
/// `n = 0` is treated as 1. Only `f32` math, usable on the GPU, but *not* bit-identical between
/// CPU and GPU (Vulkan `sin`/`cos` are only accurate to 2^-11 absolute, `sqrt` and `/` are
/// approximate): a parity test must feed the same generated floats to both sides.
pub fn fibonacci_sphere(i: u32, n: u32) -> [f32; 3] {
    let nf = if n == 0 { 1.0 } else { n as f32 };
    let z = 1.0 - (2.0 * i as f32 + 1.0) / nf;
    let r2 = 1.0 - z * z;
    let r = if r2 > 0.0 { r2.sqrt() } else { 0.0 };
    // frac(i / golden ratio) in 0.32 fixed point; 0x9E3779B9 = round(2^32 / φ).
    let frac = (i.wrapping_mul(0x9E37_79B9) >> 8) as f32 * (1.0 / 16_777_216.0);
    let phi = frac * (2.0 * core::f32::consts::PI);
    [r * phi.cos(), r * phi.sin(), z]
}

#[cfg(test)]
#[path = "octahedral_tests.rs"]
mod tests;
