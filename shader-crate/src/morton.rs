//! 3D Morton codes for ordering lights (input of a Karras-style LBVH build), as pure functions
//! shared by the GPU kernels and the CPU tests.
//!
//! # Quantisation
//!
//! [`MortonQuantizer::new`] runs on the host: per axis it stores `min` and
//! `scale = 2^bits / (max - min)`, computed in `f32` with a (correctly rounded) CPU division. The
//! GPU then only evaluates `x = (p - min) · scale`: a subtraction and a multiplication, both
//! correctly rounded on Vulkan GPUs, and with no `a*b + c` that a driver could fuse into an fma,
//! so the CPU and the GPU compute bit-identical cells. `floor` is the truncating conversion of a
//! non-negative `x`, done only after clamping in float (`x as u32` of a negative, NaN or too large
//! float is undefined in SPIR-V even though Rust saturates on the CPU):
//!
//! ```text
//! q = 0                   if p is NaN, the axis is degenerate, x < 0 (below min) or p = -inf
//! q = 2^bits - 1          if x >= 2^bits (at or above max) or p = +inf
//! q = floor(x)            otherwise
//! ```
//!
//! The maximum corner `max` itself therefore lands in the last cell (clamped), as do points just
//! below it. A *degenerate* axis (`max - min <= 0`, any bound NaN or infinite, `max - min`
//! overflowing, `scale > 2^126`, i.e. an extent below ~2^(bits-126), or a denormal `scale`, only
//! possible for `bits <= 2` with an extent near `f32::MAX`) gets `scale = 0`: every
//! point quantises to cell 0 on that axis (a non-finite `min` is stored as 0). The `2^126` cap keeps
//! GPU denormal flushing harmless: a denormal `p - min` (< 2^-126) then gives `x < 1`, cell 0 on
//! both. The number of bits is not stored: build the quantizer with the same `bits` you pass to
//! [`MortonQuantizer::quantize`] — [`MORTON30_BITS`] (10) for [`MortonQuantizer::morton30_of`],
//! [`MORTON63_BITS`] (21) for [`MortonQuantizer::morton63_of`]. With a mismatch, a quantizer built
//! for more bits than used clamps most points to the last cell, one built for fewer bits uses only
//! the low cells. `bits` above [`MAX_BITS`] (24) are treated as 24 (`f32` cannot resolve more).
//!
//! Because `scale21 = 2^11 · scale10` exactly (same correctly rounded quotient, shifted exponent),
//! `(p - min)·scale21 = 2^11 · (p - min)·scale10` exactly, and so for quantizers built from the same
//! bounds `morton63_of(p) >> 33 == morton30_of(p) as u64` bit-exactly (tested).
//!
//! # Bit layout
//!
//! Bit `i` of each axis goes to bit `3i` (x), `3i + 1` (y), `3i + 2` (z), so sorting codes orders
//! points along a Z-order curve whose most significant split is on z:
//!
//! ```text
//! morton30 (u32):  31 30 | 29 28 27 | 26 25 24 | ... |  5  4  3 |  2  1  0
//!                   0  0 | z9 y9 x9 | z8 y8 x8 | ... | z1 y1 x1 | z0 y0 x0
//!
//! morton63 (u64):  63 | 62  61  60  | ... |  5  4  3 |  2  1  0
//!                   0 | z20 y20 x20 | ... | z1 y1 x1 | z0 y0 x0
//!
//! expand_bits_10:  v = .......... ........ ......98 76543210   (10 bits; higher bits ignored)
//!             ->   ..9..8..7..6..5..4..3..2..1..0               (bit i -> bit 3i)
//! ```

/// Bits per axis of [`morton30`].
pub const MORTON30_BITS: u32 = 10;
/// Bits per axis of [`morton63`].
pub const MORTON63_BITS: u32 = 21;
/// Largest supported bits per axis for quantisation (cells stay exact integers in `f32`).
pub const MAX_BITS: u32 = 24;

const ABS_MASK: u32 = 0x7fff_ffff;
const INF_BITS: u32 = 0x7f80_0000;
/// `2^126`: larger scales are treated as degenerate (see module docs).
const MAX_SCALE: f32 = 8.507_059e37;

/// Per-axis affine map of world positions to Morton cells: `cell = floor((p - min) · scale)`.
/// `#[repr(C)]`, 24 bytes, no padding.
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "spirv"), derive(Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct MortonQuantizer {
    /// Lower bounds (0 on a degenerate axis with non-finite bound).
    pub min: [f32; 3],
    /// `2^bits / (max - min)`, or 0 on a degenerate axis.
    pub scale: [f32; 3],
}

#[inline]
fn is_finite_bits(c: f32) -> bool {
    c.to_bits() & ABS_MASK < INF_BITS
}

/// `bits` clamped to [`MAX_BITS`].
#[inline]
const fn clamp_bits(bits: u32) -> u32 {
    if bits > MAX_BITS {
        MAX_BITS
    } else {
        bits
    }
}

/// `2^bits` as an exact `f32` (`bits` already clamped).
#[inline]
fn cells_f32(bits: u32) -> f32 {
    f32::from_bits((bits + 127) << 23)
}

/// (min, scale) of one axis.
#[inline]
#[allow(clippy::manual_range_contains)]
fn axis(lo: f32, hi: f32, cells: f32) -> (f32, f32) {
    let min = if is_finite_bits(lo) { lo } else { 0.0 };
    if is_finite_bits(lo) && is_finite_bits(hi) {
        let extent = hi - lo;
        if extent > 0.0 && is_finite_bits(extent) {
            let s = cells / extent;
            // Normal and at most 2^126 (a denormal scale could be flushed on the GPU).
            if s >= f32::MIN_POSITIVE && s <= MAX_SCALE {
                return (min, s);
            }
        }
    }
    (min, 0.0)
}

/// Cell of one coordinate (see the table in the module docs). `!(x >= 0.0)` is deliberate: it is
/// also true for NaN.
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn quantize_axis(p: f32, min: f32, scale: f32, cells: f32, max_cell: u32) -> u32 {
    let b = p.to_bits() & ABS_MASK;
    if b > INF_BITS || !(scale > 0.0) {
        return 0; // NaN position or degenerate axis
    }
    if b == INF_BITS {
        return if p > 0.0 { max_cell } else { 0 };
    }
    let x = (p - min) * scale; // exact same result on CPU and GPU
    if !(x >= 0.0) {
        0
    } else if x >= cells {
        max_cell
    } else {
        x as u32 // 0 <= x < 2^24: truncation == floor
    }
}

impl MortonQuantizer {
    /// Quantizer for the box `[bounds_min, bounds_max]` with `2^bits` cells per axis
    /// (`bits` clamped to [`MAX_BITS`]). Call on the host (it divides); degenerate axes get
    /// `scale = 0`.
    pub fn new(bounds_min: [f32; 3], bounds_max: [f32; 3], bits: u32) -> Self {
        let cells = cells_f32(clamp_bits(bits));
        let (x0, sx) = axis(bounds_min[0], bounds_max[0], cells);
        let (y0, sy) = axis(bounds_min[1], bounds_max[1], cells);
        let (z0, sz) = axis(bounds_min[2], bounds_max[2], cells);
        MortonQuantizer { min: [x0, y0, z0], scale: [sx, sy, sz] }
    }

    /// Cells `floor((p - min)·scale)` clamped to `[0, 2^bits - 1]` per axis; NaN → 0, `-inf` → 0,
    /// `+inf` → `2^bits - 1`; degenerate axis → 0. `bits` must be the value given to [`Self::new`].
    #[inline]
    pub fn quantize(&self, p: [f32; 3], bits: u32) -> [u32; 3] {
        let bits = clamp_bits(bits);
        let cells = cells_f32(bits);
        let max_cell = (1u32 << bits) - 1;
        [
            quantize_axis(p[0], self.min[0], self.scale[0], cells, max_cell),
            quantize_axis(p[1], self.min[1], self.scale[1], cells, max_cell),
            quantize_axis(p[2], self.min[2], self.scale[2], cells, max_cell),
        ]
    }

    /// 30-bit Morton code of `p`; the quantizer must have been built with [`MORTON30_BITS`].
    #[inline]
    pub fn morton30_of(&self, p: [f32; 3]) -> u32 {
        morton30(self.quantize(p, MORTON30_BITS))
    }

    /// 63-bit Morton code of `p`; the quantizer must have been built with [`MORTON63_BITS`].
    #[inline]
    pub fn morton63_of(&self, p: [f32; 3]) -> u64 {
        morton63(self.quantize(p, MORTON63_BITS))
    }
}

/// Spread the low 10 bits of `v` so that bit `i` moves to bit `3i` (higher bits of `v` ignored).
#[inline]
pub fn expand_bits_10(v: u32) -> u32 {
    let mut v = v & 0x0000_03ff;
    v = (v | (v << 16)) & 0x0300_00ff;
    v = (v | (v << 8)) & 0x0300_f00f;
    v = (v | (v << 4)) & 0x030c_30c3;
    v = (v | (v << 2)) & 0x0924_9249;
    v
}

/// Inverse of [`expand_bits_10`]: gather bits `0, 3, 6, …, 27` of `v` into bits `0..10`.
#[inline]
pub fn compact_bits_10(v: u32) -> u32 {
    let mut v = v & 0x0924_9249;
    v = (v | (v >> 2)) & 0x030c_30c3;
    v = (v | (v >> 4)) & 0x0300_f00f;
    v = (v | (v >> 8)) & 0x0300_00ff;
    v = (v | (v >> 16)) & 0x0000_03ff;
    v
}

/// Spread the low 21 bits of `v` so that bit `i` moves to bit `3i` (higher bits ignored).
#[inline]
pub fn expand_bits_21(v: u64) -> u64 {
    let mut v = v & 0x1f_ffff;
    v = (v | (v << 32)) & 0x001f_0000_0000_ffff;
    v = (v | (v << 16)) & 0x001f_0000_ff00_00ff;
    v = (v | (v << 8)) & 0x100f_00f0_0f00_f00f;
    v = (v | (v << 4)) & 0x10c3_0c30_c30c_30c3;
    v = (v | (v << 2)) & 0x1249_2492_4924_9249;
    v
}

/// Inverse of [`expand_bits_21`]: gather bits `0, 3, …, 60` of `v` into bits `0..21`.
#[inline]
pub fn compact_bits_21(v: u64) -> u64 {
    let mut v = v & 0x1249_2492_4924_9249;
    v = (v | (v >> 2)) & 0x10c3_0c30_c30c_30c3;
    v = (v | (v >> 4)) & 0x100f_00f0_0f00_f00f;
    v = (v | (v >> 8)) & 0x001f_0000_ff00_00ff;
    v = (v | (v >> 16)) & 0x001f_0000_0000_ffff;
    v = (v | (v >> 32)) & 0x1f_ffff;
    v
}

/// Interleave three 10-bit cells (x → bit 0, y → bit 1, z → bit 2 of each triple); only the low
/// 10 bits of each are used.
#[inline]
pub fn morton30(q: [u32; 3]) -> u32 {
    expand_bits_10(q[0]) | (expand_bits_10(q[1]) << 1) | (expand_bits_10(q[2]) << 2)
}

/// Interleave three 21-bit cells into 63 bits (same order as [`morton30`]).
#[inline]
pub fn morton63(q: [u32; 3]) -> u64 {
    expand_bits_21(q[0] as u64) | (expand_bits_21(q[1] as u64) << 1) | (expand_bits_21(q[2] as u64) << 2)
}

/// Cells of a 30-bit code (inverse of [`morton30`] for 10-bit inputs).
#[inline]
pub fn morton30_decode(code: u32) -> [u32; 3] {
    [compact_bits_10(code), compact_bits_10(code >> 1), compact_bits_10(code >> 2)]
}

/// Cells of a 63-bit code (inverse of [`morton63`] for 21-bit inputs).
#[inline]
pub fn morton63_decode(code: u64) -> [u32; 3] {
    [
        compact_bits_21(code) as u32,
        compact_bits_21(code >> 1) as u32,
        compact_bits_21(code >> 2) as u32,
    ]
}

#[cfg(test)]
#[path = "morton_tests.rs"]
mod tests;
