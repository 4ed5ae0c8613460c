use super::*;
use crate::test_support::Rng;

fn light(p: [f32; 3], radius: f32, colour: [f32; 3], intensity: f32) -> PointLight {
    PointLight { position: p, radius, colour, intensity }
}

fn random_lights(n: usize, seed: u64) -> Vec<PointLight> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let p = [rng.unit() * 40.0 - 20.0, rng.unit() * 15.0, -1.0 - rng.unit() * 60.0];
            let scale = 10f32.powf(rng.unit() * 8.0 - 4.0);
            light(p, 0.01 + rng.unit() * 30.0, [rng.unit(), rng.unit(), rng.unit()], scale)
        })
        .collect()
}

/// Every decoded light lies within the stated bounds of its original (module docs): position
/// within half a step (plus the decode's f32 rounding), radius within 2^−17 relative, each
/// channel of `colour · intensity` within 2^−11 of the largest channel.
#[test]
fn decoded_lights_are_within_the_stated_error() {
    for (n, seed) in [(1, 1), (2, 2), (3, 3), (1000, 4), (1001, 5)] {
        let lights = random_lights(n, seed);
        let frame = frame_of(&lights);
        let packed = pack(&frame, &lights);
        assert_eq!(packed.len() as u32, records_for(n as u32));
        for (l, a) in lights.iter().enumerate() {
            let b = compact_at(&packed, n as u32, l as u32);
            for k in 0..3 {
                let tol = frame.step[k] * 0.5 + 4.0 * f32::EPSILON * (frame.origin[k].abs() + 60.0);
                assert!((a.position[k] - b.position[k]).abs() <= tol, "light {l} axis {k}: {} vs {}", a.position[k], b.position[k]);
            }
            assert!((a.radius - b.radius).abs() <= a.radius * 2f32.powi(-17), "radius {} vs {}", a.radius, b.radius);
            let c: Vec<f32> = a.colour.iter().map(|c| c * a.intensity).collect();
            let max = c.iter().cloned().fold(0.0, f32::max);
            for k in 0..3 {
                assert!((c[k] - b.colour[k]).abs() <= max * 2f32.powi(-11) * 1.001, "colour {c:?} vs {:?}", b.colour);
            }
            assert_eq!(b.intensity, 1.0);
        }
    }
}

/// The bit layout of the module docs: light `l` is in record `1 + l/2`, the position+radius
/// words for even `l` and the colour+intensity words for odd `l`; x, y, z in the low 21 bits,
/// mantissas above them, the radius and exponent in word 3.
#[test]
fn records_follow_the_drawn_layout() {
    let frame = Frame { origin: Vec3::ZERO, step: Vec3::splat(1.0) };
    let a = light([5.0, 6.0, 7.0], 1.0, [1.0, 0.5, 0.0], 1.0);
    let b = light([1.0, 2.0, 3.0], 2.0, [0.0, 0.0, 0.25], 1.0);
    let packed = pack(&frame, &[a, b, a]);
    assert_eq!(packed.len(), 3);
    assert_eq!(packed[0], frame.header());
    let w = |r: &PointLight, odd: bool| {
        if odd {
            [r.colour[0].to_bits(), r.colour[1].to_bits(), r.colour[2].to_bits(), r.intensity.to_bits()]
        } else {
            [r.position[0].to_bits(), r.position[1].to_bits(), r.position[2].to_bits(), r.radius.to_bits()]
        }
    };
    let wa = w(&packed[1], false);
    assert_eq!([wa[0] & POSITION_MAX, wa[1] & POSITION_MAX, wa[2] & POSITION_MAX], [5, 6, 7]);
    // red 1.0 = 1024 · 2^(E − 138) with E = 128 (max 1.0 → [½, 1) of 2^(E−127)).
    assert_eq!(wa[3] >> 24, 128);
    assert_eq!([wa[0] >> POSITION_BITS, wa[1] >> POSITION_BITS, wa[2] >> POSITION_BITS], [1024, 512, 0]);
    assert_eq!((wa[3] & 0xff_ffff) << RADIUS_DROPPED_BITS, 1.0f32.to_bits());
    let wb = w(&packed[1], true);
    assert_eq!([wb[0] & POSITION_MAX, wb[1] & POSITION_MAX, wb[2] & POSITION_MAX], [1, 2, 3]);
    assert_eq!(wb[3] >> 24, 126);
    assert_eq!(wb[2] >> POSITION_BITS, 1024);
    // The third light's partner half is empty (black, radius 0).
    assert_eq!(w(&packed[2], true), [0; 4]);
    for (l, want) in [(0, a), (1, b), (2, a)] {
        assert_eq!(compact_at(&packed, 3, l), PointLight { colour: want.colour, intensity: 1.0, ..want });
    }
}

/// Edge cases: black lights, radius 0, all lights on one plane (a flat axis has step 0 and
/// decodes exactly), a colour whose largest mantissa rounds up to 2048 (the exponent grows),
/// and colours far apart in magnitude in one light.
#[test]
fn edge_cases_decode_as_documented() {
    let flat = [light([1.0, 2.0, -3.0], 0.0, [0.0; 3], 5.0), light([4.0, 2.0, -3.0], 3.0, [2047.9 / 1024.0, 0.0, 0.0], 1.0)];
    let frame = frame_of(&flat);
    assert_eq!(frame.step.y, 0.0);
    let packed = pack(&frame, &flat);
    let (a, b) = (compact_at(&packed, 2, 0), compact_at(&packed, 2, 1));
    assert_eq!((a.position, a.radius, a.colour), ([1.0, 2.0, -3.0], 0.0, [0.0; 3]));
    assert_eq!(b.position, [4.0, 2.0, -3.0]);
    assert!((b.colour[0] - 2.0).abs() < 1e-3 && b.colour[1] == 0.0, "{:?}", b.colour);
    let wide = light([0.0; 3], 1.0, [1e6, 1.0, 1e-6], 1.0);
    let d = compact_at(&pack(&frame_of(&[wide]), &[wide]), 1, 0);
    assert!((d.colour[0] - 1e6).abs() <= 1e6 * 2f32.powi(-11));
    assert!(d.colour[1] <= 1e6 * 2f32.powi(-11) && d.colour[2] <= 1e6 * 2f32.powi(-11));
    // Largest emission the host accepts (2^83 per channel) still encodes.
    let bright = light([0.0; 3], 1.0, [1.0; 3], 2f32.powi(83));
    assert_eq!(compact_at(&pack(&frame_of(&[bright]), &[bright]), 1, 0).colour, [2f32.powi(83); 3]);
}

/// The accessor reads records as they are without the compact bit, decodes with it, and an index
/// from the light count on reads the last light (never past the buffer, for any count: the CPU
/// build checks every index), also for no lights.
#[test]
fn light_at_follows_the_effect_bit() {
    for n in [1u32, 2, 5, 6] {
        let lights = random_lights(n as usize, 9);
        for l in 0..n {
            assert_eq!(light_at(&lights, 0, n, l), lights[l as usize]);
        }
        assert_eq!(light_at(&lights, 0, n, 99), lights[n as usize - 1]);
        let packed = pack(&frame_of(&lights), &lights);
        assert_eq!(packed.len() as u32, records_for(n));
        for l in 0..n {
            assert_eq!(light_at(&packed, EFFECT_COMPACT_LIGHTS, n, l), compact_at(&packed, n, l));
        }
        assert_eq!(light_at(&packed, EFFECT_COMPACT_LIGHTS, n, 99), compact_at(&packed, n, n - 1));
        assert_eq!(decoded(&packed, n), (0..n).map(|l| compact_at(&packed, n, l)).collect::<Vec<_>>());
    }
    let none = pack(&frame_of(&[]), &[]);
    assert_eq!(none.len() as u32, records_for(0));
    let _ = (light_at(&none, EFFECT_COMPACT_LIGHTS, 0, 0), light_at(&none, EFFECT_COMPACT_LIGHTS, 0, 7));
}

/// The largest compact buffer fits the largest binding Vulkan can state (4 GiB − 1); two lights
/// more (one record) would not.
#[test]
fn the_largest_compact_buffer_fits_one_binding() {
    assert!(32 * records_for(MAX_COMPACT_LIGHTS) as u64 <= u32::MAX as u64);
    assert!(32 * records_for(MAX_COMPACT_LIGHTS + 2) as u64 > u32::MAX as u64);
    assert_eq!(records_for(0), 2, "a record for no lights keeps clamped reads inside");
}
