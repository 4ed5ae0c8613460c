//! CPU tests of `lighting`.
use super::*;
use crate::cluster_bounds::cluster_aabb;
use crate::cluster_key::{slice_bounds, ClusterGrid};
use crate::layout::EFFECT_TEXTURES;
use crate::reconstruct::{distance_from_depth, view_position};
use glam::vec3;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    fn vec(&mut self, s: f32) -> Vec3 {
        vec3(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
}

fn light(c: Vec3, r: f32, intensity: f32) -> PointLight {
    PointLight { position: c.to_array(), radius: r, colour: [1.0, 0.9, 0.8], intensity }
}

fn next_up(x: f32) -> f32 {
    assert!(x >= 0.0);
    f32::from_bits(x.to_bits() + 1)
}

fn next_down(x: f32) -> f32 {
    assert!(x > 0.0);
    f32::from_bits(x.to_bits() - 1)
}

fn aabb(min: Vec3, max: Vec3) -> ClusterAabb {
    ClusterAabb { min: min.to_array(), _pad0: 0.0, max: max.to_array(), _pad1: 0.0 }
}

// ─── attenuation ────────────────────────────────────────────────────────────────────────────

#[test]
fn attenuation_is_exactly_zero_at_and_beyond_the_radius() {
    for r in [1e-3f32, 0.5, 1.0, 3.0, 7.7, 100.0, 1e6] {
        let r2 = r * r;
        for d2 in [r2, next_up(r2), r2 * 1.0001, r2 * 4.0, 1e30, f32::MAX, f32::INFINITY, f32::NAN] {
            assert_eq!(attenuation(d2, r).to_bits(), 0, "r {r} d2 {d2}");
        }
        // Just inside: positive and tiny (the window ends with zero slope).
        let a = attenuation(next_down(r2), r);
        assert!(a > 0.0 && a < 1e-12, "r {r}: {a:e}");
    }
    // Radius 0: nothing, not even at the light.
    assert_eq!(attenuation(0.0, 0.0).to_bits(), 0);
    assert_eq!(attenuation(1e-30, 0.0).to_bits(), 0);
    assert_eq!(attenuation(0.0, f32::NAN).to_bits(), 0);
    // Radius² underflows to 0: also nothing (and consistent with light_touches).
    assert_eq!(attenuation(0.0, 1e-30), 0.0);
    assert!(!light_touches(&light(Vec3::ZERO, 1e-30, 1.0), Vec3::ZERO));
}

#[test]
fn attenuation_is_continuous_and_monotone_inside() {
    for r in [0.25f32, 1.0, 5.0, 40.0, 1e4] {
        let r2 = r * r;
        assert_eq!(attenuation(0.0, r), 1.0);
        let n = 100_000;
        let mut prev = attenuation(0.0, r);
        for s in 1..=n {
            let d2 = r2 * s as f32 / n as f32;
            let a = attenuation(d2, r);
            assert!(a <= prev, "r {r} d2 {d2}: {a} > {prev}");
            // Continuity: steps of r²/1e5 in d² change the falloff by a bounded amount
            // (|d/dd² falloff| ≤ 1 + 4/r²).
            assert!(prev - a <= (1.0 + 4.0 / r2) * (r2 / n as f32) * 1.01 + 1e-7, "jump at d2 {d2}");
            assert!((0.0..=1.0).contains(&a));
            prev = a;
        }
        assert_eq!(prev, 0.0, "reaches exactly 0 at d = r");
        // Against the closed form in f64.
        for s in 0..1000 {
            let d2 = r2 * s as f32 / 1000.0;
            let x = d2 as f64 / r2 as f64;
            let expected = (1.0 - x * x).max(0.0).powi(2) / (d2 as f64 + 1.0);
            // `1 − x²` cancels near the radius: the error is absolute, a few u of the window.
            let err = (attenuation(d2, r) as f64 - expected).abs();
            assert!(err <= 1e-6 / (d2 as f64 + 1.0), "r {r} d2 {d2}: err {err:e}");
        }
    }
}

#[test]
fn attenuation_with_huge_radius_is_inverse_square() {
    for d2 in [0.0f32, 1.0, 99.0, 1e20] {
        let a = attenuation(d2, 1e30);
        assert!(a.is_finite());
        assert_eq!(a, 1.0 / (d2 + 1.0));
    }
}

#[test]
fn inverse_square_cut_drops_exactly_what_is_below_epsilon() {
    for intensity in [0.5f32, 1.0, 40.0, 1e4] {
        for eps in [1e-2f32, 1e-3, 1e-4] {
            let r = cut_radius(intensity, eps);
            assert!(r.is_finite() && r >= 0.0);
            // Inside the radius the plain inverse square is kept, beyond it the contribution is
            // below ε (up to f32 rounding of the radius itself: 1e-5 relative).
            for t in [0.0f32, 0.5, 0.99, 0.9999] {
                let d2 = (t * r) * (t * r);
                assert_eq!(inverse_square_cut(d2, r), 1.0 / (d2 + 1.0));
                assert!(intensity * inverse_square_cut(d2, r) >= eps * (1.0 - 1e-5), "I={intensity} ε={eps} t={t}");
            }
            for t in [1.0f32, 1.0001, 3.0] {
                let d2 = (t * r) * (t * r);
                assert_eq!(inverse_square_cut(d2, r), 0.0);
                assert!(intensity / (d2 + 1.0) <= eps * (1.0 + 1e-5), "I={intensity} ε={eps} t={t}");
            }
            assert_eq!(falloff(4.0, r, EFFECT_INVERSE_SQUARE_CUT), inverse_square_cut(4.0, r));
            assert_eq!(falloff(4.0, r, 0), attenuation(4.0, r));
        }
    }
    assert_eq!(cut_radius(1e-3, 1e-2), 0.0, "a light dimmer than ε everywhere has radius 0");
}

// ─── light_touches ⇒ shade, exact zero ─────────────────────────────────────────────────────

#[test]
fn shade_is_exactly_zero_unless_the_light_touches() {
    let mut rng = Rng(1);
    let n = vec3(0.0, 0.0, 1.0);
    for it in 0..200_000 {
        let c = rng.vec(10.0);
        let r = match it % 5 {
            0 => 0.0,
            1 => rng.range(0.0, 0.1),
            _ => rng.range(0.0, 8.0),
        };
        // Points on the sphere surface (the boundary), inside and outside.
        let dir = rng.vec(1.0).normalize_or(Vec3::X);
        let p = match it % 3 {
            0 => c + dir * r,
            1 => c + dir * next_up(r),
            _ => c + rng.vec(10.0),
        };
        let l = light(c, r, rng.range(0.0, 100.0));
        let s = shade(p, n, vec3(0.8, 0.5, 0.2), 0.5, 0.3, &l, EFFECT_SPECULAR);
        assert!(s.is_finite());
        if !light_touches(&l, p) {
            assert_eq!(s.to_array().map(f32::to_bits), [0; 3], "{l:?} at {p:?}");
            assert_eq!(attenuation(distance2(p, c), r).to_bits(), 0);
        }
    }
}

#[test]
fn shade_is_finite_in_the_hard_cases() {
    let albedo = vec3(0.9, 0.6, 0.3);
    let n = vec3(0.0, 1.0, 0.0);
    let mut cases: Vec<(Vec3, Vec3, PointLight)> = vec![
        // Camera inside a light (point at the eye, light around it).
        (Vec3::ZERO, n, light(vec3(0.0, 0.5, 0.0), 10.0, 5.0)),
        (Vec3::ZERO, n, light(Vec3::ZERO, 10.0, 5.0)),
        // Light exactly at the shaded point.
        (vec3(1.0, -2.0, -3.0), n, light(vec3(1.0, -2.0, -3.0), 1.0, 5.0)),
        (vec3(1e-20, 0.0, -1e-20), n, light(Vec3::ZERO, 1.0, 5.0)),
        // Zero normal.
        (vec3(0.0, 0.0, -5.0), Vec3::ZERO, light(vec3(0.0, 1.0, -5.0), 3.0, 5.0)),
        // Unnormalised normal.
        (vec3(0.0, 0.0, -5.0), n * 1e6, light(vec3(0.0, 1.0, -5.0), 3.0, 5.0)),
        (vec3(0.0, 0.0, -5.0), n * 1e-25, light(vec3(0.0, 1.0, -5.0), 3.0, 5.0)),
        // Huge radius, near and far.
        (vec3(0.0, 0.0, -5.0), n, light(vec3(0.0, 1.0, -5.0), 1e30, 5.0)),
        (vec3(0.0, 0.0, -1e15), n, light(vec3(0.0, 1e15, -5.0), 1e30, 5.0)),
        (vec3(3e18, 0.0, -1e19), n, light(vec3(0.0, 1e19, 0.0), f32::MAX, 5.0)),
        // Radius 0 and intensity 0.
        (vec3(0.0, 0.0, -5.0), n, light(vec3(0.0, 0.0, -5.0), 0.0, 5.0)),
        (vec3(0.0, 0.0, -5.0), n, light(vec3(0.0, 1.0, -5.0), 3.0, 0.0)),
        // Light exactly opposite the view direction (l = −v): no half vector.
        (vec3(0.0, 0.0, -5.0), vec3(0.0, 0.0, -1.0), light(vec3(0.0, 0.0, -6.0), 3.0, 5.0)),
        // Grazing light, light below the surface.
        (vec3(0.0, 0.0, -5.0), n, light(vec3(1.0, 0.0, -5.0), 3.0, 5.0)),
        (vec3(0.0, 0.0, -5.0), n, light(vec3(0.0, -1.0, -5.0), 3.0, 5.0)),
    ];
    let mut rng = Rng(5);
    for _ in 0..2000 {
        let c = rng.vec(1.0);
        cases.push((c + rng.vec(1e-6), rng.vec(1.0), light(c, rng.range(0.0, 2.0), 1.0)));
    }
    for (p, nn, l) in cases {
        for effects in [0, EFFECT_SPECULAR, EFFECT_SPECULAR | EFFECT_TEXTURES] {
            for (ks, rough) in [(0.5, 0.0), (1.0, 0.03), (0.04, 1.0), (2.0, f32::NAN), (f32::NAN, 0.5), (1.0, 1e-30)] {
                let s = shade(p, nn, albedo, ks, rough, &l, effects);
                assert!(s.is_finite() && s.min_element() >= 0.0, "p {p:?} n {nn:?} {l:?} fx {effects} ks {ks} rough {rough}: {s:?}");
                if l.intensity == 0.0 || l.radius == 0.0 {
                    assert_eq!(s, Vec3::ZERO);
                }
            }
        }
    }
}

#[test]
fn shade_values() {
    let albedo = vec3(0.9, 0.6, 0.3);
    let n = vec3(0.0, 0.0, 1.0);
    let p = vec3(0.0, 0.0, -5.0);
    // Light 2 units straight above the surface, along the normal, towards the camera.
    let l = light(vec3(0.0, 0.0, -3.0), 4.0, 3.0);
    let att = attenuation(4.0, 4.0);
    let expected = albedo / core::f32::consts::PI * Vec3::from_array(l.colour) * (3.0 * att);
    let diffuse = shade(p, n, albedo, 0.5, 0.5, &l, 0);
    assert!((diffuse - expected).abs().max_element() < 1e-6, "{diffuse:?} vs {expected:?}");
    // Mirror configuration: l = v = h = n, so the specular lobe is at its peak (s+8)/(8π).
    let s = shininess(0.5);
    assert_eq!(s, 6.0);
    let with_spec = shade(p, n, albedo, 0.5, 0.5, &l, EFFECT_SPECULAR);
    let peak = 0.5 * (s + 8.0) / (8.0 * core::f32::consts::PI);
    let expected_spec = Vec3::from_array(l.colour) * (3.0 * att * peak);
    assert!((with_spec - diffuse - expected_spec).abs().max_element() < 1e-5, "{with_spec:?}");
    // Roughness clamps.
    assert_eq!(shininess(1.0), 0.0);
    assert_eq!(shininess(7.0), 0.0);
    assert_eq!(shininess(0.0), shininess(MIN_ROUGHNESS));
    assert_eq!(shininess(f32::NAN), shininess(MIN_ROUGHNESS));
    assert!((shininess(MIN_ROUGHNESS) - 2220.222).abs() < 0.01);
}

/// The HDR bound (module docs, "HDR overflow"): at the largest emission and the specular peak
/// one light stays finite and below `MAX_LIGHT_RADIANCE` with no clamp; `2^32` such lights cannot
/// reach `f32::MAX`; their sum still tonemaps to white.
#[test]
fn hdr_contributions_stay_bounded_and_sums_stay_finite() {
    assert_eq!((MAX_EMISSION, MAX_LIGHT_RADIANCE), (2f32.powi(83), 2f32.powi(90)));
    assert_eq!((MAX_RADIUS, MIN_RADIUS), (2f32.powi(60), 2f32.powi(-50)));
    let n = vec3(0.0, 0.0, 1.0);
    let p = vec3(0.0, 0.0, -5.0);
    // Mirror configuration at the sharpest lobe (roughness 0.03): the largest factor of `shade`.
    let peak = |intensity: f32| shade(p, n, Vec3::ONE, 1.0, MIN_ROUGHNESS, &light(vec3(0.0, 0.0, -4.999), 4.0, intensity), EFFECT_SPECULAR);
    let top = peak(MAX_EMISSION);
    assert!(top.is_finite() && top.max_element() < MAX_LIGHT_RADIANCE, "{top}");
    // The bound in f64: the largest factor of `shade` times the largest emission.
    let bound = (1.0 / core::f64::consts::PI + 2228.2 / (8.0 * core::f64::consts::PI)) * MAX_EMISSION as f64 * (1.0 + 1e-5);
    assert!(bound < MAX_LIGHT_RADIANCE as f64, "{bound:e}");
    // The peak is no clamp: it scales with the emission (within rounding).
    let half = peak(MAX_EMISSION * 0.5);
    assert!((top.x / half.x - 2.0).abs() < 1e-5, "{top} / {half}");
    // Sums of up to 2^32 bounded contributions stay far below f32::MAX.
    assert!((MAX_LIGHT_RADIANCE as f64) * 2f64.powi(32) <= 2f64.powi(122));
    let mut sum = Vec3::ZERO;
    for _ in 0..100_000 {
        sum += top;
    }
    assert!(sum.is_finite() && sum.min_element() >= top.min_element());
    assert_eq!(encode_srgb8(tonemap(sum, 1.0)), 0xffff_ffff);
    // The bound is past saturation for any exposure ≥ 2^-87.
    assert_eq!(tonemap(Vec3::splat(MAX_LIGHT_RADIANCE), 2f32.powi(-87)), Vec3::ONE);
}

// ─── sphere vs box ─────────────────────────────────────────────────────────────────────────

/// Random box (sometimes degenerate) and a sample of its points: corners, face centres, a
/// lattice, and the point closest to `c` (the decisive one).
fn box_samples(min: Vec3, max: Vec3, c: Vec3) -> Vec<Vec3> {
    let mut v = vec![c.clamp(min, max)];
    let n = 6;
    for a in 0..=n {
        for b in 0..=n {
            for e in 0..=n {
                let t = vec3(a as f32, b as f32, e as f32) / n as f32;
                v.push((min + (max - min) * t).clamp(min, max));
            }
        }
    }
    v
}

#[test]
fn sphere_box_is_conservative_against_brute_force() {
    let mut rng = Rng(11);
    for it in 0..40_000 {
        let a = rng.vec(10.0);
        let ext = if it % 7 == 0 { Vec3::ZERO } else { rng.vec(3.0).abs() };
        let (min, max) = (a, a + ext);
        let b = aabb(min, max);
        let c = rng.vec(15.0);
        let r = if it % 9 == 0 { 0.0 } else { rng.range(0.0, 8.0) };
        let hit = sphere_intersects_aabb(c, r, &b);
        let l = light(c, r, 1.0);
        let samples = box_samples(min, max, c);
        if samples.iter().any(|&p| light_touches(&l, p)) {
            assert!(hit, "{l:?} touches a point of {b:?} but the test says no");
        }
        // Not loose beyond the documented slack: the exact (f64) box distance decides.
        let q = c.clamp(min, max) - c;
        let dist2 = (q.x as f64).powi(2) + (q.y as f64).powi(2) + (q.z as f64).powi(2);
        let r2 = (r as f64).powi(2);
        if dist2 > r2 * (1.0 + 1e-5) {
            assert!(!hit, "{l:?} vs {b:?}: box distance² {dist2} > r² {r2}");
        }
        if dist2 < r2 * (1.0 - 1e-5) {
            assert!(hit);
        }
    }
}

#[test]
fn zero_radius_meets_only_boxes_containing_the_centre() {
    let b = aabb(vec3(-1.0, -1.0, -1.0), vec3(1.0, 1.0, 1.0));
    for c in [Vec3::ZERO, vec3(1.0, 1.0, 1.0), vec3(-1.0, 0.5, 1.0)] {
        assert!(sphere_intersects_aabb(c, 0.0, &b));
    }
    for c in [vec3(next_up(1.0), 0.0, 0.0), vec3(0.0, -1.000_001, 0.0), vec3(5.0, 5.0, 5.0)] {
        assert!(!sphere_intersects_aabb(c, 0.0, &b), "{c:?}");
    }
    // Inclusive at exact tangency.
    assert!(sphere_intersects_aabb(vec3(3.0, 0.0, 0.0), 2.0, &b));
    assert!(!sphere_intersects_aabb(vec3(3.0, 0.0, 0.0), 1.99, &b));
    // Huge radii meet everything; NaN is conservative on the CPU.
    assert!(sphere_intersects_aabb(vec3(1e19, -1e19, 0.0), 1e30, &b));
    assert!(sphere_intersects_aabb(vec3(f32::NAN, 0.0, 0.0), 1.0, &b));
    assert!(sphere_intersects_aabb(Vec3::ZERO, f32::NAN, &b));
}

/// A light touching a point intersects every box that contains the point — also boxes whose
/// face passes exactly through the point, and with the light at the edge of its range.
#[test]
fn touching_implies_intersecting_every_containing_box() {
    let mut rng = Rng(23);
    for it in 0..200_000 {
        let p = rng.vec(50.0);
        let c = p + rng.vec(5.0);
        // Smallest radius for which the light touches p.
        let r = next_up(distance2(p, c).sqrt());
        let r = if light_touches(&light(c, r, 1.0), p) { r } else { next_up(r) };
        let l = light(c, r, 1.0);
        assert!(light_touches(&l, p));
        let lo = p - rng.vec(2.0).abs();
        let hi = p + rng.vec(2.0).abs();
        // Put p on a face or corner of the box in some cases.
        let (lo, hi) = match it % 4 {
            0 => (p, hi),
            1 => (lo, p),
            2 => (vec3(p.x, lo.y, p.z), vec3(hi.x, p.y, hi.z)),
            _ => (lo, hi),
        };
        assert!(sphere_intersects_aabb(c, r, &aabb(lo, hi)), "{l:?} touches {p:?} in [{lo:?}, {hi:?}]");
    }
}

/// End to end, as the host's reference check does it: every light touching a pixel's
/// reconstructed position intersects the box of the pixel's cluster.
#[test]
fn lights_touching_a_pixel_meet_its_cluster() {
    let mut rng = Rng(31);
    for (w, h, t) in [(33, 17, 32), (1920, 1080, 32), (7680, 4320, 32)] {
        let g = ClusterGrid::new(w, h, t, 0.1, 500.0, 1.0).unwrap();
        let b = slice_bounds(&g);
        for it in 0..50_000 {
            let (px, py) = (rng.below(w), rng.below(h));
            let z_buf = if it % 10 == 0 { 1.0 } else { rng.unit().powi(3) };
            if crate::reconstruct::is_background(z_buf) {
                continue;
            }
            let d = distance_from_depth(g.near, z_buf);
            let p = view_position(&g, px, py, d);
            // A light whose sphere just reaches p, from a random direction.
            let c = p + rng.vec(3.0);
            let r = next_up(distance2(p, c).sqrt());
            let r = if light_touches(&light(c, r, 1.0), p) { r } else { next_up(r) };
            let (i, j) = g.tile_of_pixel(px, py);
            let k = g.slice_of_depth(&b, d);
            let bx = cluster_aabb(&g, &b, i, j, k);
            assert!(sphere_intersects_aabb(c, r, &bx), "{w}x{h} ({px},{py}) d {d}: light {c:?} r {r} misses {bx:?}");
            assert!(shade(p, vec3(0.0, 1.0, 0.0), Vec3::ONE, 1.0, 0.2, &light(c, r, 1.0), EFFECT_SPECULAR).is_finite());
        }
    }
}

// ─── tonemap, encoding, heat ramp ──────────────────────────────────────────────────────────

#[test]
fn tonemap_is_bounded_and_monotone() {
    assert_eq!(tonemap(Vec3::ZERO, 1.0), Vec3::ZERO);
    assert_eq!(tonemap(Vec3::splat(f32::INFINITY), 1.0), Vec3::ONE);
    assert_eq!(tonemap(vec3(f32::NAN, -1.0, f32::NEG_INFINITY), 1.0), Vec3::ZERO);
    assert_eq!(tonemap(Vec3::ONE, f32::NAN), Vec3::ZERO);
    assert_eq!(tonemap(Vec3::splat(7.3), 1.0), Vec3::ONE);
    let mut prev = 0.0;
    let mut x = 1e-6f32;
    while x < 100.0 {
        let y = tonemap(Vec3::splat(x), 1.0).x;
        assert!(y >= prev && (0.0..=1.0).contains(&y), "x {x}: {y}");
        prev = y;
        x *= 1.001;
    }
    // Exposure scales the input.
    assert_eq!(tonemap(Vec3::splat(0.5), 2.0), tonemap(Vec3::splat(1.0), 1.0));
    // Mid grey 0.18 maps to ≈ 0.27 (Narkowicz's curve).
    assert!((tonemap(Vec3::splat(0.18), 1.0).x - 0.267).abs() < 0.01);
}

#[test]
fn srgb8_encoding() {
    let px = |r: f32, g: f32, b: f32| encode_srgb8(vec3(r, g, b));
    assert_eq!(px(0.0, 0.0, 0.0), 0xff00_0000);
    assert_eq!(px(1.0, 1.0, 1.0), 0xffff_ffff);
    assert_eq!(px(1.0, 0.0, 0.0), 0xff00_00ff, "R in the low byte");
    assert_eq!(px(0.0, 0.0, 1.0), 0xffff_0000);
    // sRGB(0.5) = 0.7354 → 188; sRGB(0.0031308) = 0.04045 → 10; linear segment.
    assert_eq!(px(0.5, 0.0, 0.0) & 0xff, 188);
    assert_eq!(px(0.003_130_8, 0.0, 0.0) & 0xff, 10);
    assert_eq!(px(0.001, 0.0, 0.0) & 0xff, 3);
    // Non-finite and out-of-range inputs are defined.
    assert_eq!(px(f32::NAN, -f32::NAN, f32::NAN), 0xff00_0000);
    assert_eq!(px(f32::INFINITY, f32::NEG_INFINITY, -5.0), 0xff00_00ff);
    assert_eq!(px(1e30, 2.0, -0.0), 0xff00_ffff);
    // Monotone, every code reachable.
    let mut seen = [false; 256];
    let mut prev = 0;
    for s in 0..=100_000 {
        let q = px(s as f32 / 100_000.0, 0.0, 0.0) & 0xff;
        assert!(q >= prev);
        seen[q as usize] = true;
        prev = q;
    }
    assert!(seen.iter().all(|&s| s));
}

#[test]
fn heat_ramp_legend() {
    assert_eq!(heat_ramp(0, 10), Vec3::ZERO);
    assert_eq!(heat_ramp(0, 0), Vec3::ZERO);
    assert_eq!(heat_ramp(10, 10), Vec3::ONE);
    assert_eq!(heat_ramp(1000, 10), Vec3::ONE);
    assert_eq!(heat_ramp(1, 0), Vec3::ONE);
    let stops = [Vec3::ZERO, Vec3::Z, vec3(0.0, 1.0, 1.0), Vec3::Y, vec3(1.0, 1.0, 0.0), Vec3::X, Vec3::ONE];
    for (s, &c) in stops.iter().enumerate() {
        assert!((heat_ramp(s as u32, 6) - c).abs().max_element() < 1e-6, "stop {s}");
        assert!((heat_ramp(2 * s as u32, 12) - c).abs().max_element() < 1e-6, "stop {s}");
    }
    // Halfway between blue and cyan.
    assert!((heat_ramp(9, 36) - vec3(0.0, 0.5, 1.0)).abs().max_element() < 1e-6);
    for max in [1, 7, 64, 1000, u32::MAX] {
        for count in [1, 2, max / 3, max / 2, max.saturating_sub(1)] {
            let c = heat_ramp(count, max);
            assert!(c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= 1.0);
        }
    }
}

/// The cross-machine margin of the sphere test (module docs): for every radius of the host's
/// contract, the threshold exceeds `r²(1 + 10.1u)` (GPU box distance vs CPU point distance).
#[test]
fn sphere_slack_covers_cross_machine_rounding() {
    let u = 2f64.powi(-24);
    assert_eq!(SPHERE_TEST_SLACK as f64, 2f64.powi(-19));
    let mut r = 2f32.powi(-50);
    while r <= 2f32.powi(60) {
        for rr in [r, r * 1.1, r * 1.37, r * 1.999] {
            let r2 = rr * rr;
            let thr = (r2 + r2 * SPHERE_TEST_SLACK) as f64;
            assert!(thr >= r2 as f64 * (1.0 + 20.0 * u), "r {rr:e}");
            // A box gap computed 10.1u (in d²) above a point distance just below r² still passes.
            let gap = ((next_down(r2) as f64 * (1.0 + 10.1 * u)).sqrt() * (1.0 + u)) as f32;
            let b = aabb(vec3(gap, -1.0, -1.0), vec3(f32::MAX, 1.0, 1.0));
            assert!(sphere_intersects_aabb(Vec3::ZERO, rr, &b), "r {rr:e}");
        }
        r *= 2.0;
    }
}

#[test]
fn srgb8_decode_is_the_inverse_of_the_encoding() {
    for b in 0..256u32 {
        let word = b | ((255 - b) << 8) | ((b * 7 % 256) << 16) | 0xff00_0000;
        let linear = decode_srgb8(word);
        assert!(linear.cmpge(Vec3::ZERO).all() && linear.cmple(Vec3::ONE).all(), "{word:#x} → {linear}");
        assert_eq!(encode_srgb8(linear), word, "byte {b}");
    }
}
