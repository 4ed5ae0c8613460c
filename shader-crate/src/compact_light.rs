//! Compact light records: a point light in 16 bytes instead of 32, so that one storage binding
//! holds twice as many: 2^28 − 4 lights instead of 2^27 − 1 in the 4 GiB − 1 an NVIDIA GPU
//! binds (the light buffer takes the whole reported range: its length is never read,
//! [`light_at`]), 2^27 − 4 in a binding below 2^31 bytes.
//!
//! # Layout
//!
//! With [`EFFECT_COMPACT_LIGHTS`] the light buffer is still read through its `&[PointLight]`
//! binding (32-byte records), but holds a header and then two compact lights per record:
//!
//! ```text
//!  record 0                 header: position = origin o, colour = step s (view space, per axis)
//!  record 1 + l/2, half l%2 light l: 4 words (the record's position+radius words for even l,
//!                           its colour+intensity words for odd l)
//!
//!  word   bits 0–20                    bits 21–31
//!  w0     x: 21-bit fixed point        red mantissa   (11 bits)
//!  w1     y                            green mantissa (11 bits)
//!  w2     z                            blue mantissa  (11 bits)
//!  w3     bits 0–23: radius (f32 bits 7–30, rounded to nearest)   bits 24–31: shared exponent E
//! ```
//!
//! * position `= o + q · s` per axis, `q ∈ [0, 2^21 − 1]`, `s = extent / (2^21 − 1)` of the
//!   lights' view-space box: the error is at most `s/2` (plus the f32 rounding of the decode),
//!   i.e. `extent · 2.4·10⁻⁷`: 7 µm for lights spread over a 30 m atrium.
//! * radius: the f32's sign bit (always 0: radii are ≥ 0) and low 7 mantissa bits dropped:
//!   relative error ≤ 2^−17.
//! * colour: `colour · intensity` (what the shading multiplies, `lighting::brdf_radiance`) with a
//!   shared exponent (like Vulkan's `E5B9G9R9`, wider): channel `= m · 2^(E − 127 − 11)`, the
//!   largest channel's mantissa in `[1024, 2047]`: relative error ≤ 2^−11 of the largest channel.
//!   The decoded light has `intensity = 1`. `E = 0` is black.
//!
//! Spot and directional lights keep full records (their cone and directional sections follow
//! 32-byte point records, `light_types`): compact records hold point lights only, and the host
//! refuses `--light-record compact` for a scene with other types.
//!
//! # Cost
//!
//! Memory: 16 B per light instead of 32 (plus one 32-byte header). Time: a decode per light read
//! (three integer-to-float conversions and fused multiply-adds, one exponent shift), only in the
//! pipelines specialised with [`EFFECT_COMPACT_LIGHTS`] (a light-type bit, `light_types`): the
//! full-record pipelines have no decode in them.
use crate::layout::PointLight;
use glam::Vec3;

/// The light buffer holds compact records (module docs). A light-type bit: pipelines are
/// specialised on it (`light_types::LIGHT_TYPE_MASK`).
pub const EFFECT_COMPACT_LIGHTS: u32 = 4096;
/// Bits of each fixed-point coordinate.
pub const POSITION_BITS: u32 = 21;
/// Largest fixed-point coordinate, `2^21 − 1`.
pub const POSITION_MAX: u32 = (1 << POSITION_BITS) - 1;
/// Bits of each colour mantissa.
pub const MANTISSA_BITS: u32 = 11;
const MANTISSA_MAX: u32 = (1 << MANTISSA_BITS) - 1;
/// Low f32 bits the radius drops.
pub const RADIUS_DROPPED_BITS: u32 = 7;
const RADIUS_MASK: u32 = (1 << 24) - 1;
/// Compact lights one binding holds at most: `32 · (1 + ⌈n/2⌉) ≤ 2^32 − 1`, the largest
/// `maxStorageBufferRange` (a 32-bit limit) — on a device that reports it, for the light buffer
/// (its length is never read: [`light_at`]).
pub const MAX_COMPACT_LIGHTS: u32 = (1 << 28) - 4;
const _: () = assert!(32 * records_for(MAX_COMPACT_LIGHTS) as u64 <= u32::MAX as u64);
const _: () = assert!(32 * records_for(MAX_COMPACT_LIGHTS + 2) as u64 > u32::MAX as u64);

/// Records (32 B each) a buffer of `n` compact lights takes: the header and `⌈n/2⌉` (one for
/// no lights, so that a clamped read stays inside: [`compact_at`]).
#[inline]
pub const fn records_for(n: u32) -> u32 {
    1 + if n == 0 { 1 } else { n.div_ceil(2) }
}

/// The quantisation frame of a buffer's positions: origin and step per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: Vec3,
    pub step: Vec3,
}

impl Frame {
    /// The frame of positions inside `[lo, hi]` (finite, `lo ≤ hi`). A flat axis gets step 0.
    pub fn of_bounds(lo: Vec3, hi: Vec3) -> Self {
        Self { origin: lo, step: (hi - lo) / POSITION_MAX as f32 }
    }

    /// The header record.
    pub fn header(&self) -> PointLight {
        PointLight { position: self.origin.to_array(), radius: 0.0, colour: self.step.to_array(), intensity: 0.0 }
    }

    fn of_header(h: &PointLight) -> Self {
        Self { origin: Vec3::from_array(h.position), step: Vec3::from_array(h.colour) }
    }

    fn quantise(&self, v: f32, o: f32, s: f32) -> u32 {
        if s > 0.0 {
            let q = ((v - o) / s + 0.5).max(0.0);
            if q >= POSITION_MAX as f32 {
                POSITION_MAX
            } else {
                q as u32
            }
        } else {
            0
        }
    }
}

/// The four words of `light` in `frame` (a finite light: position in the frame's box, radius and
/// `colour · intensity` finite and ≥ 0).
pub fn encode(frame: &Frame, light: &PointLight) -> [u32; 4] {
    let p = light.position;
    let (o, s) = (frame.origin, frame.step);
    let q = [frame.quantise(p[0], o.x, s.x), frame.quantise(p[1], o.y, s.y), frame.quantise(p[2], o.z, s.z)];
    let (m, e) = encode_colour([light.colour[0] * light.intensity, light.colour[1] * light.intensity, light.colour[2] * light.intensity]);
    let r = encode_radius(light.radius);
    [q[0] | (m[0] << POSITION_BITS), q[1] | (m[1] << POSITION_BITS), q[2] | (m[2] << POSITION_BITS), r | (e << 24)]
}

/// 24 bits of a radius ≥ 0: f32 bits 7–30, rounded to nearest (ties up).
fn encode_radius(r: f32) -> u32 {
    let bits = r.max(0.0).to_bits();
    ((bits + (1 << (RADIUS_DROPPED_BITS - 1))) >> RADIUS_DROPPED_BITS).min(RADIUS_MASK)
}

/// `2^(e − 127)` for a biased exponent `e ∈ [1, 254]`, 0 for `e = 0`.
#[inline]
fn pow2_biased(e: u32) -> f32 {
    f32::from_bits(e << 23)
}

/// Shared-exponent mantissas and exponent of a colour ≥ 0 (module docs).
fn encode_colour(c: [f32; 3]) -> ([u32; 3], u32) {
    let c = [c[0].max(0.0), c[1].max(0.0), c[2].max(0.0)];
    let max = c[0].max(c[1]).max(c[2]);
    // The smallest E with max < 2^(E − 127): max / 2^(E−127) ∈ [½, 1), mantissa ∈ [1024, 2048).
    if max.is_nan() || max < pow2_biased(MANTISSA_BITS + 2) {
        // Below 2^(−114) (NaN impossible for a checked light): black.
        return ([0; 3], 0);
    }
    let mut e = ((max.to_bits() >> 23) & 0xff) + 1;
    let unit = |e: u32| pow2_biased(e - MANTISSA_BITS);
    let round = |v: f32, e: u32| (v / unit(e) + 0.5) as u32;
    if round(max, e) > MANTISSA_MAX {
        e += 1;
    }
    let e = e.min(254);
    ([round(c[0], e).min(MANTISSA_MAX), round(c[1], e).min(MANTISSA_MAX), round(c[2], e).min(MANTISSA_MAX)], e)
}

/// The light of four words in `frame`: what every kernel sees.
#[inline]
pub fn decode(frame: &Frame, w: [u32; 4]) -> PointLight {
    let q = |x: u32| (x & POSITION_MAX) as f32;
    let o = frame.origin;
    let s = frame.step;
    let e = w[3] >> 24;
    let unit = if e > MANTISSA_BITS { pow2_biased(e - MANTISSA_BITS) } else { 0.0 };
    let m = |x: u32| (x >> POSITION_BITS) as f32 * unit;
    PointLight {
        position: [o.x + q(w[0]) * s.x, o.y + q(w[1]) * s.y, o.z + q(w[2]) * s.z],
        radius: f32::from_bits((w[3] & RADIUS_MASK) << RADIUS_DROPPED_BITS),
        colour: [m(w[0]), m(w[1]), m(w[2])],
        intensity: 1.0,
    }
}

/// Light `l` of a compact buffer of `n` lights (an `l` from `n` on reads light `n − 1`, as the
/// full-record loops read their last light: `shading::shade_range`). The buffer's length is
/// never read (module docs: bindings past 2^31 bytes).
#[inline]
pub fn compact_at(lights: &[PointLight], n: u32, l: u32) -> PointLight {
    let l = if l < n { l } else { n.max(1) - 1 };
    // In bounds: a compact buffer of `n` lights holds its header and `records_for(n) − 1 ≥
    // 1 + l/2` records after it (`records_for` counts one for no lights).
    let header = crate::unchecked::get(lights, 0);
    let r = crate::unchecked::get(lights, 1 + (l >> 1));
    let w = if l & 1 == 0 {
        [r.position[0].to_bits(), r.position[1].to_bits(), r.position[2].to_bits(), r.radius.to_bits()]
    } else {
        [r.colour[0].to_bits(), r.colour[1].to_bits(), r.colour[2].to_bits(), r.intensity.to_bits()]
    };
    decode(&Frame::of_header(header), w)
}

/// Light `l` of the frame's `n` punctual lights as the kernels see it: its record, or with
/// [`EFFECT_COMPACT_LIGHTS`] its decoded compact record. `l` from `n` on reads light `n − 1`
/// (callers keep `l` below `n`; the clamp keeps a stray index inside the buffer, which holds at
/// least one record). No kernel reads the light buffer's length: a binding of 2^31 bytes or more
/// reads as empty through it on NVIDIA's driver (`docs/results/h200/light-buffer-boundary/`),
/// and the light buffer may pass 2 GiB (`vk::device::DeviceInfo::length_free_storage_range`;
/// `tests/spirv_lengths.rs` keeps every kernel so).
#[inline]
pub fn light_at(lights: &[PointLight], effects: u32, n: u32, l: u32) -> PointLight {
    if effects & EFFECT_COMPACT_LIGHTS != 0 {
        compact_at(lights, n, l)
    } else {
        *full_record(lights, n, l)
    }
}

/// The sphere of light `l` as [`light_at`] reads it: its position and radius, read before the
/// rest of its record (`shading::shade_one`): a listed light that does not reach the pixel
/// costs the 16 bytes of its sphere, not the 32 of its record (compact records are decoded
/// whole; the decode of [`light_emission`] reads the same words again, which the compiler merges).
#[inline]
pub fn light_sphere(lights: &[PointLight], effects: u32, n: u32, l: u32) -> (Vec3, f32) {
    if effects & EFFECT_COMPACT_LIGHTS != 0 {
        let d = compact_at(lights, n, l);
        (Vec3::from_array(d.position), d.radius)
    } else {
        let r = full_record(lights, n, l);
        (Vec3::from_array(r.position), r.radius)
    }
}

/// The colour and intensity of light `l` as [`light_at`] reads them.
#[inline]
pub fn light_emission(lights: &[PointLight], effects: u32, n: u32, l: u32) -> (Vec3, f32) {
    if effects & EFFECT_COMPACT_LIGHTS != 0 {
        let d = compact_at(lights, n, l);
        (Vec3::from_array(d.colour), d.intensity)
    } else {
        let r = full_record(lights, n, l);
        (Vec3::from_array(r.colour), r.intensity)
    }
}

/// Full record `l` of `n` in place (`l` from `n` on reads record `n − 1`; in bounds: the buffer
/// holds the `n` lights, one record for none).
#[inline]
fn full_record(lights: &[PointLight], n: u32, l: u32) -> &PointLight {
    crate::unchecked::get(lights, if l < n { l } else { n.max(1) - 1 })
}

/// Packs `lights` (all inside `frame`'s box) into a compact buffer: header, then two per record.
#[cfg(not(target_arch = "spirv"))]
pub fn pack(frame: &Frame, lights: &[PointLight]) -> Vec<PointLight> {
    let word = |w: u32| f32::from_bits(w);
    let mut out = Vec::with_capacity(records_for(lights.len() as u32) as usize);
    out.push(frame.header());
    if lights.is_empty() {
        out.push(frame.header());
    }
    for pair in lights.chunks(2) {
        let a = encode(frame, &pair[0]);
        let b = pair.get(1).map(|l| encode(frame, l)).unwrap_or([0; 4]);
        out.push(PointLight {
            position: [word(a[0]), word(a[1]), word(a[2])],
            radius: word(a[3]),
            colour: [word(b[0]), word(b[1]), word(b[2])],
            intensity: word(b[3]),
        });
    }
    out
}

/// The frame of `lights`' positions (their box; a point at the origin for no lights).
#[cfg(not(target_arch = "spirv"))]
pub fn frame_of(lights: &[PointLight]) -> Frame {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for l in lights {
        let p = Vec3::from_array(l.position);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lights.is_empty() {
        Frame::of_bounds(Vec3::ZERO, Vec3::ZERO)
    } else {
        Frame::of_bounds(lo, hi)
    }
}

/// What the kernels see of the `n` lights of a compact buffer: each light decoded (what the
/// host keeps for its CPU references and statistics).
#[cfg(not(target_arch = "spirv"))]
pub fn decoded(packed: &[PointLight], n: u32) -> Vec<PointLight> {
    (0..n).map(|l| compact_at(packed, n, l)).collect()
}

#[cfg(test)]
#[path = "compact_light_tests.rs"]
mod tests;
