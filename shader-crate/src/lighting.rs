//! Light culling tests, attenuation, BRDF, tonemapping and output encoding of the clustered and
//! brute-force deferred passes.
//!
//! # Steps
//!
//! 1. **Assignment** (per unique cluster, [`crate::clustered`]): a light goes into a cluster's list
//!    iff its range sphere meets the cluster's view-space box ([`sphere_intersects_aabb`], Arvo
//!    1990, "A Simple Method for Box-Sphere Intersection Testing", Graphics Gems I; also
//!    Akenine-Möller et al., *Real-Time Rendering*, sphere/box intersection), the boxes being
//!    those of [`crate::cluster_bounds`] (Olsson, Billeter, Assarsson 2012, "Clustered Deferred and
//!    Forward Shading": clusters = screen tiles × exponential depth slices, §3.1).
//! 2. **Shading** (per pixel): the sum of [`shade`] over the cluster's lights. A light contributes
//!    exactly when [`light_touches`] the pixel's view position (`|p − c|² < r²`); otherwise
//!    [`shade`] returns exactly `0`.
//! 3. **Output**: [`tonemap`] (ACES fitted) and [`encode_srgb8`], or the lights-per-pixel
//!    [`heat_ramp`].
//!
//! # Lights: the host's contract
//!
//! Lights reach the GPU validated by the host (`render::lights_to_view`): finite view-space
//! position, colour and intensity `≥ 0` with every `colour·intensity ≤` [`MAX_EMISSION`] (else an
//! error), radius `0` or in `[`[`MIN_RADIUS`]`, `[`MAX_RADIUS`]`] = [2^-50, 2^60]` (clamped there, so
//! that `r²·2^-19` is a normal float and `r²` is finite). Larger radii are still handled with IEEE
//! semantics (CPU; tested with `1e30`): `r²` overflows to `+∞`, every light test is true and the
//! falloff becomes `1/(d² + 1)` — but a GPU may assume no `∞`, hence the host clamp.
//! Vulkan lets a compiler assume no NaN/∞ by default, so NaN handling on the GPU cannot be relied
//! on; the CPU functions nevertheless make NaN *conservative* where it is free: a NaN light
//! intersects every box (`!(d² > …)`) and contributes exactly 0 (`!(d² < r²)`).
//!
//! # Culling is conservative (sphere–box test vs `light_touches`)
//!
//! Claim: if `light_touches(light, p)` and `p` lies in box `b` (`b.min ≤ p ≤ b.max`), then
//! `sphere_intersects_aabb(c, r, b)`.
//! * **Same machine.** Per axis the box gap is `fl(min − c)` when `c < min` (else `fl(c − max)`,
//!   or 0), and `min ≤ p` gives `fl(min − c) ≤ fl(p − c)`: rounding is monotone. Squares of
//!   non-negatives and sums (same order `x² + y² + z²` in both functions, [`distance2`]) are
//!   monotone too, so `d²_box ≤ d²_point < r²`: no tolerance needed.
//! * **Across machines** (the host checks GPU lists against `light_touches` on the CPU, the GPU may
//!   fuse `a·b + c`): each computed squared distance is within `(1 ± 5.01u)` of its exact value
//!   (`u = 2^-24`: one subtraction, one square, two additions — or fewer roundings when fused;
//!   underflow/flush only shrinks the box gap, i.e. errs on the safe side), and the exact box gap
//!   is at most the exact point distance, so `d²_box,GPU ≤ d²_point,CPU·(1+5.01u)/(1−5u) <
//!   r²(1 + 10.1u)`. The test therefore accepts `d² ≤ r² + r²·2^-19` ([`SPHERE_TEST_SLACK`]
//!   `= 32u`, three times the requirement; computing the threshold costs ≤ 1u). Radius-0 lights
//!   still meet only boxes containing their centre (`r² = 0` ⇒ threshold 0).
//!
//! # Attenuation (Karis 2013, "Real Shading in Unreal Engine 4", SIGGRAPH course notes,
//! "inverse square falloff")
//!
//! `falloff(d) = saturate(1 − (d/r)⁴)² / (d² + 1)`, computed from `x = d²/r²` as
//! `max(1 − x², 0)² / (d² + 1)`. Units: 1 view-space unit = 1 m; the `+1` (m²) replaces the
//! singular `1/d²` of a point light near its source, so the falloff is `≤ 1` (1 at the light) and
//! follows `1/d²` for `d ≫ 1 m`: `intensity` acts as the radiant intensity. The window makes the
//! falloff reach 0 exactly at `d = r` with zero slope; **exactly** 0 for `d² ≥ r²` is enforced by
//! the explicit test `!(d² < r²)`, the same comparison as [`light_touches`] (a GPU division could
//! make `x = d²/r²` a hair below 1 at `d = r`). Inside, the falloff is continuous and
//! non-increasing in `d²` (every operation is monotone, see the tests).
//!
//! # BRDF: normalised Blinn-Phong
//!
//! Outgoing radiance towards the eye (normalisation factor `(s+8)/(8π)` of the Blinn-Phong lobe:
//! Akenine-Möller, Haines, Hoffman, *Real-Time Rendering*, 3rd ed., "BRDF models"):
//! ```text
//!   L = ( albedo/π + [EFFECT_SPECULAR] · specular · (s+8)/(8π) · max(n·h, 0)^s )
//!       · max(n·l, 0) · colour · intensity · falloff(|c − p|)
//!   s = 2/ρ² − 2,  ρ = roughness clamped to [0.03, 1] (s ∈ [0, 2220]),
//!   specular clamped to [0, 1]
//!   l = (c − p)/|c − p|,  v = −p/|p|,  h = (l + v)/|l + v|
//! ```
//! The `n·l` cosine multiplies both lobes (light below the surface never produces a highlight).
//! Degenerate geometry never yields NaN or ∞: `n` is normalised (zero → no light), a light at the
//! shaded point (`|c − p|² ≤ 10⁻³⁰`) takes `l = n`, a point at the eye (`|p|² ≤ 10⁻³⁰`) takes
//! `v = n` (a camera inside a light's range needs no special case), and `l + v ≈ 0` (light
//! exactly behind the view direction) drops the specular lobe. `max(n·h,0)^s` is evaluated only
//! for `n·h > 0` (`powf` of non-positive bases is undefined on GPUs), so `0^0` counts as 0 there.
//! Every factor is bounded (`falloff ≤ 1`, `n·l ≤ 1 + 3u`, the lobe `≤ (2228/8π)·(1+3u)^2220
//! < 89`), so the result is finite whenever the light's `colour·intensity` and the albedo are.
//!
//! # HDR overflow: bounded by the host contract, no clamp
//!
//! With `colour·intensity ≤` [`MAX_EMISSION`] `= 2^83` (host contract) one light's radiance is
//! at most `89.1·2^83 < 2^90 =` [`MAX_LIGHT_RADIANCE`] per channel (`falloff ≤ 1`, `n·l ≤ 1`,
//! albedo `≤ 1`, the lobe `< 89`), so nothing inside [`shade`] overflows and a sum of fewer than
//! `2^32` contributions stays `< 2^122`: no technique's per-pixel sum can reach `+∞` whatever its
//! order or list, since every one adds up [`shade`]'s results (a GPU may assume no `∞`, so none
//! must arise). The bound needs no per-light clamp in the light loop. `2^90` is far past the
//! tonemapper's saturation (`exposure·x ≥ 8` for any exposure `≥ 2^-87`), and `2^83 ≈ 10^25`
//! is far past any physical emitter in view-space units.
//!
//! # Tonemap and encoding
//!
//! [`tonemap`]: per channel, the ACES filmic curve as fitted by Narkowicz 2015 ("ACES Filmic Tone
//! Mapping Curve"): `f(x) = x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)` of `x = exposure·hdr`,
//! clamped to [0, 1] (monotone increasing on `x ≥ 0`; reaches 1 at `x ≈ 7.24`, so the input is
//! clamped to [0, 8] first and ∞ cannot produce ∞/∞). [`encode_srgb8`]: IEC 61966-2-1 sRGB
//! transfer function, 8 bits per channel rounded to nearest, `R | G<<8 | B<<16 | 255<<24`
//! (R in the low byte). Non-finite or out-of-range inputs are defined: NaN → 0 (detected on the
//! bit pattern), `≤ 0` and `−∞` → 0, `≥ 1` and `+∞` → 255.
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use crate::layout::{ClusterAabb, PointLight, EFFECT_INVERSE_SQUARE_CUT, EFFECT_SPECULAR};
use glam::Vec3;

/// Relative slack of [`sphere_intersects_aabb`]: `2^-19` (module docs).
pub const SPHERE_TEST_SLACK: f32 = 1.0 / 524_288.0;

/// Squared lengths at or below this are treated as zero when normalising (far above the denormal
/// range, so CPU and flushing GPUs agree; `sqrt` of it is `10⁻¹⁵`).
pub const MIN_LENGTH2: f32 = 1e-30;

/// `2^e` for a normal-range exponent, exactly.
const fn pow2(e: i32) -> f32 {
    f32::from_bits(((e + 127) as u32) << 23)
}

/// Largest `colour·intensity` (per channel) a light may have: [`shade`] stays finite below it
/// (module docs, "HDR overflow"). `2^83 ≈ 9.7·10^24`.
pub const MAX_EMISSION: f32 = pow2(83);

/// Bound on the radiance one light adds to a channel (module docs, "HDR overflow": [`shade`] stays
/// below it for lights within [`MAX_EMISSION`]): `2^90 ≈ 1.2·10^27`, so
/// that fewer than `2^32` lights cannot sum past `f32::MAX` (module docs, "HDR overflow").
pub const MAX_LIGHT_RADIANCE: f32 = pow2(90);

/// Radius range the kernels compute with (`r²·2^-19` normal, `r²` finite): `[2^-50, 2^60]`. The
/// host clamps larger radii to `MAX_RADIUS` and smaller non-zero ones to 0 (module docs).
pub const MAX_RADIUS: f32 = pow2(60);
pub const MIN_RADIUS: f32 = pow2(-50);

/// Roughness range of the BRDF (`s = 2/ρ² − 2` ∈ [0, 2220]).
pub const MIN_ROUGHNESS: f32 = 0.03;
pub const MAX_ROUGHNESS: f32 = 1.0;

const INV_PI: f32 = core::f32::consts::FRAC_1_PI;

/// `|a − b|²` as `dx² + dy² + dz²` (this order): the one squared distance of every light test.
#[inline]
pub fn distance2(a: Vec3, b: Vec3) -> f32 {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let dz = a.z - b.z;
    dx * dx + dy * dy + dz * dz
}

/// Distance from `c` to the interval `[lo, hi]` along one axis (0 inside).
#[inline]
fn axis_gap(c: f32, lo: f32, hi: f32) -> f32 {
    if c < lo {
        lo - c
    } else if c > hi {
        c - hi
    } else {
        0.0
    }
}

/// Arvo's test: does the sphere `(center, radius)` meet the closed box `b`? The squared distance
/// from the centre to the box is compared, inclusively, with `r²·(1 + 2^-19)` — conservative with
/// respect to [`light_touches`] for every point of the box, on one machine or across CPU/GPU
/// (module docs). Radius 0 meets only boxes containing the centre. NaN inputs give `true` on the
/// CPU (conservative); lights are validated on the host, so none reach the GPU.
#[inline]
pub fn sphere_intersects_aabb(center: Vec3, radius: f32, b: &ClusterAabb) -> bool {
    let gx = axis_gap(center.x, b.min[0], b.max[0]);
    let gy = axis_gap(center.y, b.min[1], b.max[1]);
    let gz = axis_gap(center.z, b.min[2], b.max[2]);
    let d2 = gx * gx + gy * gy + gz * gz;
    let r2 = radius * radius;
    !(d2 > r2 + r2 * SPHERE_TEST_SLACK)
}

/// Whether the light can contribute at `p`: `|p − c|² < r²`. [`shade`] is exactly 0 otherwise.
#[inline]
pub fn light_touches(light: &PointLight, p: Vec3) -> bool {
    in_range(Vec3::from_array(light.position), light.radius, p)
}

/// [`light_touches`] of a light with centre `c` and radius `r`.
#[inline]
pub fn in_range(c: Vec3, r: f32, p: Vec3) -> bool {
    distance2(p, c) < r * r
}

/// Karis' windowed inverse-square falloff `saturate(1 − (d/r)⁴)² / (d² + 1)` from `dist2 = d²`:
/// exactly 0 unless `dist2 < radius²` (so for `d ≥ r`, `r = 0` and NaN), in `[0, 1]` and finite
/// otherwise (also for `radius²` overflowing to ∞: then `1/(d² + 1)`).
#[inline]
pub fn attenuation(dist2: f32, radius: f32) -> f32 {
    let r2 = radius * radius;
    if !(dist2 < r2) {
        return 0.0;
    }
    let x = dist2 / r2;
    let w = 1.0 - x * x;
    let w = if w > 0.0 { w } else { 0.0 };
    w * w / (dist2 + 1.0)
}

/// Plain inverse square `1/(d² + 1)` cut to exactly 0 unless `dist2 < radius²`: with the radius
/// of [`cut_radius`] it drops every contribution below an intensity threshold ε (and only those).
#[inline]
pub fn inverse_square_cut(dist2: f32, radius: f32) -> f32 {
    if dist2 < radius * radius {
        1.0 / (dist2 + 1.0)
    } else {
        0.0
    }
}

/// Radius beyond which `intensity / (d² + 1) < epsilon`: `√(max(intensity/ε − 1, 0))`.
#[inline]
pub fn cut_radius(intensity: f32, epsilon: f32) -> f32 {
    let x = intensity / epsilon - 1.0;
    if x > 0.0 {
        x.sqrt()
    } else {
        0.0
    }
}

/// The falloff a frame uses: [`attenuation`] (Karis' window), or [`inverse_square_cut`] with
/// `effects & EFFECT_INVERSE_SQUARE_CUT`. Both are 0 unless `dist2 < radius²`.
#[inline]
pub fn falloff(dist2: f32, radius: f32, effects: u32) -> f32 {
    if effects & EFFECT_INVERSE_SQUARE_CUT != 0 {
        inverse_square_cut(dist2, radius)
    } else {
        attenuation(dist2, radius)
    }
}

/// `v / |v|`, or `fallback` when `|v|² ≤ MIN_LENGTH2` (or not a number).
#[inline]
fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let l2 = v.dot(v);
    if l2 > MIN_LENGTH2 {
        v * (1.0 / l2.sqrt())
    } else {
        fallback
    }
}

/// Blinn-Phong shininess `s = 2/ρ² − 2` of a roughness, `ρ` clamped to [0.03, 1] (NaN → 0.03).
#[inline]
pub fn shininess(roughness: f32) -> f32 {
    let r = if roughness > MIN_ROUGHNESS {
        if roughness < MAX_ROUGHNESS {
            roughness
        } else {
            MAX_ROUGHNESS
        }
    } else {
        MIN_ROUGHNESS
    };
    2.0 / (r * r) - 2.0
}

/// Radiance towards the eye from surface point `p` (view space) with normal `n`, lit by `light`:
/// normalised Blinn-Phong (module docs) times the light's colour, intensity and [`falloff`].
/// The specular lobe only with `effects & EFFECT_SPECULAR`. Exactly 0 when `!light_touches`;
/// finite for every finite input, including `p = 0`, `n = 0`, `p = c`, `r = 0`, `r = 1e30`;
/// each channel below [`MAX_LIGHT_RADIANCE`] for lights within [`MAX_EMISSION`] (module docs,
/// "HDR overflow").
#[inline]
pub fn shade(p: Vec3, n: Vec3, albedo: Vec3, specular: f32, roughness: f32, light: &PointLight, effects: u32) -> Vec3 {
    shade_variant::<true>(p, n, albedo, specular, roughness, light, effects)
}

/// [`shade`] as a compiled shading variant evaluates it: with `SPECULAR = false` the specular
/// lobe is not compiled at all (whatever `effects` says); with `true` it is [`shade`].
#[inline]
pub fn shade_variant<const SPECULAR: bool>(p: Vec3, n: Vec3, albedo: Vec3, specular: f32, roughness: f32, light: &PointLight, effects: u32) -> Vec3 {
    shade_unit_normal::<SPECULAR>(p, unit_normal(n), albedo, specular, roughness, light, effects)
}

/// The normal [`shade_variant`] shades with: `n / |n|`, or 0 for a zero or NaN normal.
#[inline]
pub fn unit_normal(n: Vec3) -> Vec3 {
    normalize_or(n, Vec3::ZERO)
}

/// [`shade_variant`] with the normal already through [`unit_normal`]: the light loops normalise
/// once per pixel, not once per light (same result).
#[inline]
pub fn shade_unit_normal<const SPECULAR: bool>(p: Vec3, n: Vec3, albedo: Vec3, specular: f32, roughness: f32, light: &PointLight, effects: u32) -> Vec3 {
    let emission = || (Vec3::from_array(light.colour), light.intensity);
    shade_sphere::<SPECULAR>(p, n, albedo, specular, roughness, Vec3::from_array(light.position), light.radius, effects, emission)
}

/// [`shade_unit_normal`] of a light at `c` of range `radius` whose colour and intensity
/// `emission` reads only where the light reaches `p` in front of the surface: the light loops
/// read a listed light's sphere first and the rest of its record only where it adds something
/// (`shading::shade_one`; the loop read records so when it met the 10k-light target, and the
/// state that copied each record whole first was 5 % slower on an H100, cause not isolated).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn shade_sphere<const SPECULAR: bool>(
    p: Vec3,
    n: Vec3,
    albedo: Vec3,
    specular: f32,
    roughness: f32,
    c: Vec3,
    radius: f32,
    effects: u32,
    emission: impl FnOnce() -> (Vec3, f32),
) -> Vec3 {
    let dist2 = distance2(p, c);
    // The cheap rejections first, each as exact as the full evaluation: out of range (both
    // falloffs are 0 unless `dist2 < radius²`), then behind the surface (`n·l ≤ 0`, with `n·l`
    // as `n·(c − p) / |c − p|`: the direction is normalised only where the specular lobe
    // needs it). Then the falloff.
    if !(dist2 < radius * radius) {
        return Vec3::ZERO;
    }
    let to_light = c - p;
    // `l` is read by the specular lobe only: the diffuse variant compiles it away.
    let (ndotl, l) = if dist2 > MIN_LENGTH2 {
        let inv_d = 1.0 / dist2.sqrt();
        (n.dot(to_light) * inv_d, to_light * inv_d)
    } else {
        // The light at the point: lit along the normal.
        (n.dot(n), n)
    };
    if !(ndotl > 0.0) {
        return Vec3::ZERO;
    }
    let att = falloff(dist2, radius, effects);
    let (colour, intensity) = emission();
    brdf_radiance::<SPECULAR>(p, n, l, ndotl, albedo, specular, roughness, att, intensity, colour, effects)
}

/// Radiance from `p` lit from the unit direction `to_light` (view space) with irradiance
/// `colour · intensity · n·l` and no falloff: a directional light. Same BRDF, clamp and variants
/// as [`shade_variant`]; `to_light` must be a unit vector (the host normalises it).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn shade_directional<const SPECULAR: bool>(p: Vec3, n: Vec3, albedo: Vec3, specular: f32, roughness: f32, to_light: Vec3, colour: Vec3, intensity: f32, effects: u32) -> Vec3 {
    let n = normalize_or(n, Vec3::ZERO);
    let ndotl = n.dot(to_light);
    if !(ndotl > 0.0) {
        return Vec3::ZERO;
    }
    brdf_radiance::<SPECULAR>(p, n, to_light, ndotl, albedo, specular, roughness, 1.0, intensity, colour, effects)
}

/// The BRDF part of [`shade_variant`] and [`shade_directional`]: unit normal `n`, unit direction
/// to the light `l` (read by the specular lobe only), `ndotl = n·l > 0`, attenuation `att`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn brdf_radiance<const SPECULAR: bool>(p: Vec3, n: Vec3, l: Vec3, ndotl: f32, albedo: Vec3, specular: f32, roughness: f32, att: f32, intensity: f32, colour: Vec3, effects: u32) -> Vec3 {
    let mut spec = 0.0;
    if SPECULAR && effects & EFFECT_SPECULAR != 0 && specular > 0.0 {
        let ks = if specular < 1.0 { specular } else { 1.0 };
        let v = normalize_or(-p, n);
        let hv = l + v;
        let hl2 = hv.dot(hv);
        if hl2 > MIN_LENGTH2 {
            let ndoth = n.dot(hv * (1.0 / hl2.sqrt()));
            if ndoth > 0.0 {
                let s = shininess(roughness);
                spec = ks * (s + 8.0) * (0.125 * INV_PI) * ndoth.powf(s);
            }
        }
    }
    let e = ndotl * att * intensity;
    (albedo * INV_PI + Vec3::splat(spec)) * colour * e
}

/// ACES fitted curve (Narkowicz 2015) of one channel, `x` clamped to [0, 8] (NaN → 0), result
/// clamped to [0, 1].
#[inline]
fn aces(x: f32) -> f32 {
    let x = if x > 0.0 {
        if x < 8.0 {
            x
        } else {
            8.0
        }
    } else {
        0.0
    };
    let y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    if y < 1.0 {
        y
    } else {
        1.0
    }
}

/// Display-referred linear RGB in [0, 1] of scene radiance: ACES fitted per channel of
/// `exposure · hdr` (module docs). NaN/negative → 0, ∞ → 1.
#[inline]
pub fn tonemap(hdr: Vec3, exposure: f32) -> Vec3 {
    Vec3::new(aces(hdr.x * exposure), aces(hdr.y * exposure), aces(hdr.z * exposure))
}

/// One channel: linear → sRGB-encoded 8-bit value (NaN → 0, clamped to [0, 1]).
#[inline]
fn srgb8(x: f32) -> u32 {
    // NaN test on the bits: a compiler assuming no NaN cannot remove it.
    if (x.to_bits() & 0x7fff_ffff) > 0x7f80_0000 {
        return 0;
    }
    let c = if x > 0.0 {
        if x < 1.0 {
            x
        } else {
            1.0
        }
    } else {
        0.0
    };
    let e = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    let q = (e * 255.0 + 0.5) as u32;
    if q < 255 {
        q
    } else {
        255
    }
}

/// Linear RGB → RGBA8 sRGB word, R in the low byte, alpha 255. NaN → 0, `≤ 0`/−∞ → 0,
/// `≥ 1`/+∞ → 255.
#[inline]
pub fn encode_srgb8(rgb: Vec3) -> u32 {
    srgb8(rgb.x) | (srgb8(rgb.y) << 8) | (srgb8(rgb.z) << 16) | 0xff00_0000
}

/// RGBA8 sRGB word → linear RGB (alpha ignored): the inverse of [`encode_srgb8`], whose encoding
/// gives every word's colour bytes back (the transparency resolve composites over the opaque
/// frame in linear colour).
#[inline]
pub fn decode_srgb8(word: u32) -> Vec3 {
    Vec3::new(srgb8_to_linear(word & 255), srgb8_to_linear((word >> 8) & 255), srgb8_to_linear((word >> 16) & 255))
}

/// One sRGB-encoded byte → linear.
#[inline]
fn srgb8_to_linear(b: u32) -> f32 {
    let e = b as f32 / 255.0;
    if e <= 0.040_45 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

/// Legend stop `s` (0..=6) of [`heat_ramp`].
#[inline]
fn heat_stop(s: u32) -> Vec3 {
    match s {
        0 => Vec3::new(0.0, 0.0, 0.0), // black
        1 => Vec3::new(0.0, 0.0, 1.0), // blue
        2 => Vec3::new(0.0, 1.0, 1.0), // cyan
        3 => Vec3::new(0.0, 1.0, 0.0), // green
        4 => Vec3::new(1.0, 1.0, 0.0), // yellow
        5 => Vec3::new(1.0, 0.0, 0.0), // red
        _ => Vec3::new(1.0, 1.0, 1.0), // white
    }
}

/// Colour of `count` lights per pixel in the heatmap view (linear RGB; primaries are unchanged by
/// the sRGB encoding). Legend, `t = count / max` piecewise linear between the stops
/// ```text
///   t:   0      1/6    2/6    3/6     4/6     5/6    1 (= max, and above)
///        black  blue   cyan   green   yellow  red    white
/// ```
/// `count = 0` is always black; `count ≥ max` (and any count > 0 when `max = 0`) is white.
#[inline]
pub fn heat_ramp(count: u32, max: u32) -> Vec3 {
    if count == 0 {
        return heat_stop(0);
    }
    if count >= max {
        return heat_stop(6);
    }
    let t = 6.0 * (count as f32 / max as f32);
    let s = t as u32; // 0..=5 (t < 6 as count < max; clamped below for safety)
    let s = if s < 5 { s } else { 5 };
    let f = t - s as f32;
    let f = if f > 0.0 {
        if f < 1.0 {
            f
        } else {
            1.0
        }
    } else {
        0.0
    };
    heat_stop(s) * (1.0 - f) + heat_stop(s + 1) * f
}

#[cfg(test)]
#[path = "lighting_tests.rs"]
mod tests;
