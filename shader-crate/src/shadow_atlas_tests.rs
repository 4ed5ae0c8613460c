use super::*;
use crate::shadow::{face_entry, SHADOW_HEADER_WORDS};
use crate::shadow_cull::{ARGS_FACES, ARGS_WORDS};
use crate::test_support::Rng;

/// The level's side holds a texel of at most `1 / TEXELS_PER_PIXEL` of a pixel at every point of
/// the sphere (below the cap), measured at points drawn in it: texel `2 · |q − light| / side`
/// against the pixel `|q| · 2·tan θ / height`; the level is the smallest that does at the
/// sphere's worst point bound, so one level less can fail.
#[test]
fn a_receivers_level_gives_texels_no_larger_than_its_pixels() {
    let mut rng = Rng(21);
    let (height, tan, near) = (720, 0.577f32, 0.1);
    let mut capped = 0;
    for _ in 0..5_000 {
        let centre = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, -rng.unit()) * 40.0 - Vec3::Z * 0.2;
        let radius = 2.0 * rng.unit() * rng.unit();
        let light = centre + Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * 20.0;
        let cap = [64, 100, 4096][rng.below(3) as usize];
        let k = receiver_level(centre, radius, light, near, height, tan, cap);
        assert!(k >= 1 && k <= cap_level(cap), "level {k} for cap {cap}");
        let side = (1u32 << k).min(cap) as f32;
        if k == cap_level(cap) {
            capped += 1;
            continue;
        }
        for _ in 0..20 {
            let dir = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::X);
            let q = centre + dir * radius * rng.unit();
            let eye = q.length().max(near);
            let texel = 2.0 * (q - light).length() / side;
            let pixel = eye * 2.0 * tan / height as f32;
            assert!(texel <= pixel / TEXELS_PER_PIXEL * 1.0001, "level {k}: texel {texel} against pixel {pixel} at {q}");
        }
    }
    assert!(capped > 100 && capped < 4_900, "{capped} capped");
    // A sphere at the eye's distance from the light asks about TEXELS_PER_PIXEL · height / tan θ.
    let k = receiver_level(Vec3::new(0.0, 0.0, -10.0), 0.0, Vec3::new(0.0, 0.0, -20.0), near, height, tan, 4096);
    assert_eq!(k, level_of(TEXELS_PER_PIXEL * height as f32 / tan));
    assert_eq!(level_of(1.0), 0);
    assert_eq!(level_of(1.5), 1);
    assert_eq!(level_of(2.0), 1);
    assert_eq!(level_of(1e9), LEVELS - 1);
    assert_eq!(cap_level(100), 7);
}

#[test]
fn face_sides_follow_level_shift_and_cap() {
    assert_eq!(face_side(8, 0, 4096), 256);
    assert_eq!(face_side(8, 2, 4096), 64);
    assert_eq!(face_side(8, 7, 4096), MIN_SIDE);
    assert_eq!(face_side(12, 0, 100), 100);
    assert_eq!(face_side(1, 0, 4), 4);
    assert_eq!(face_side(3, 0, 1), 1);
}

/// Faces with levels and an atlas: the histogram step, then the allocation as the kernels run
/// them (one invocation per face, in any order).
fn allocate(needed: &[u32], cap: u32, texels: u32, order: &[u32]) -> (Vec<u32>, [u32; ARGS_WORDS as usize]) {
    let faces = needed.len() as u32;
    let p = AtlasParams { faces, cap, texels, pad: 0 };
    let mut args = [0u32; ARGS_WORDS as usize];
    for &k in needed.iter().filter(|&&k| k != 0) {
        args[ARGS_LEVELS + k as usize] += 1;
        args[ARGS_FACES] += 1;
    }
    let mut slots = vec![cap, 0, SHADOW_HEADER_WORDS, 0];
    slots.resize((SHADOW_HEADER_WORDS + faces * crate::shadow::FACE_WORDS) as usize, u32::MAX);
    let shift = atlas_shift(&args, cap, texels);
    args[ARGS_SHIFT] = shift;
    let mut used = 0u32;
    for &m in order {
        allocate_face(m, &p, shift, needed, &mut slots, &mut used);
    }
    args[ARGS_USED] = used;
    (slots, args)
}

/// Random faces and atlases: the shift is the smallest that fits, every face with a level gets
/// its level's side after the shift and texels of its own inside the atlas (no two overlap),
/// faces without one get none; an atlas of `MIN_SIDE²` per face always fits at some shift.
#[test]
fn the_atlas_gives_every_face_its_side_without_overlap() {
    let mut rng = Rng(9);
    for round in 0..300 {
        let faces = 1 + rng.below(400);
        let cap = [8, 100, 256, 4096][rng.below(4) as usize];
        let needed: Vec<u32> = (0..faces).map(|_| if rng.below(3) == 0 { 0 } else { 1 + rng.below(cap_level(cap)) }).collect();
        let floor = MIN_SIDE.min(cap);
        let least = faces * floor * floor;
        let texels = if round % 3 == 0 { least } else { least + rng.below(faces * 256 * 256) };
        let mut order: Vec<u32> = (0..faces + 5).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i as u32 + 1) as usize);
        }
        let (slots, args) = allocate(&needed, cap, texels, &order);
        let shift = args[ARGS_SHIFT];
        let need = |s: u32| needed.iter().filter(|&&k| k != 0).map(|&k| (face_side(k, s, cap) as u64).pow(2)).sum::<u64>();
        assert!(need(shift) <= texels as u64, "round {round}: shift {shift} needs {} of {texels}", need(shift));
        assert!(shift == 0 || need(shift - 1) > texels as u64, "round {round}: shift {shift} is not the least");
        assert_eq!(args[ARGS_USED] as u64, need(shift));
        let mut spans = vec![];
        for (m, &k) in needed.iter().enumerate() {
            let (base, side) = face_entry(&slots, m as u32);
            if k == 0 {
                assert_eq!((base, side), (0, 0));
            } else {
                assert_eq!(side, face_side(k, shift, cap));
                assert!(base as u64 + (side * side) as u64 <= texels as u64);
                spans.push((base, base + side * side));
            }
        }
        spans.sort();
        assert!(spans.windows(2).all(|w| w[0].1 <= w[1].0), "round {round}: faces overlap");
    }
    // An atlas short of the levels asked halves every side until they fit.
    let (slots, args) = allocate(&[9, 9, 0, 3], 4096, 2 * 128 * 128 + 64, &[0, 1, 2, 3]);
    assert_eq!(args[ARGS_SHIFT], 2);
    assert_eq!(face_entry(&slots, 0).1, 128);
    assert_eq!(face_entry(&slots, 3).1, MIN_SIDE);
    assert_eq!(args[ARGS_FACES], 3);
}
