use super::*;
use crate::shadow::{face_entry, face_texels, page_span, FaceMap, ALL_PAGES, NO_TEXEL, SHADOW_HEADER_WORDS};
use crate::shadow_receivers::NEEDED_WORDS;
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

/// Faces with levels and pages (`[level, pages, pages]` per face, `NEEDED_WORDS`) and an atlas:
/// the histogram step, then the allocation as the kernels run them (one invocation per face, in
/// any order).
fn allocate(needed: &[u32], cap: u32, texels: u32, order: &[u32]) -> (Vec<u32>, [u32; ARGS_WORDS as usize]) {
    let faces = needed.len() as u32 / NEEDED_WORDS;
    let p = AtlasParams { faces, cap, texels, pad: 0 };
    let mut args = [0u32; ARGS_WORDS as usize];
    for f in needed.chunks(NEEDED_WORDS as usize).filter(|f| f[0] != 0) {
        args[ARGS_LEVELS + f[0] as usize] += 1;
        args[ARGS_PAGES + f[0] as usize] += f[1].count_ones() + f[2].count_ones();
        args[ARGS_FACES] += 1;
    }
    let mut slots = vec![cap, 0, SHADOW_HEADER_WORDS, 0];
    slots.resize((SHADOW_HEADER_WORDS + faces * crate::shadow::FACE_WORDS) as usize, u32::MAX);
    let layout = atlas_layout(&args, cap, texels);
    (args[ARGS_SHIFT], args[ARGS_PAGED]) = (layout.0, layout.1 as u32);
    let mut used = 0u32;
    for &m in order {
        allocate_face(m, &p, layout, needed, &mut slots, &mut used);
    }
    args[ARGS_USED] = used;
    (slots, args)
}

/// A random page mask: none, one, a rectangle, scattered pages or all of them.
fn random_pages(rng: &mut Rng) -> [u32; 2] {
    match rng.below(5) {
        0 => [1 << rng.below(32), 0],
        1 => {
            let (i0, j0) = (rng.below(8), rng.below(8));
            crate::shadow_receivers::page_rect(i0, i0 + rng.below(8 - i0), j0, j0 + rng.below(8 - j0))
        }
        2 => [rng.below(u32::MAX) | 1, rng.below(u32::MAX)],
        _ => ALL_PAGES,
    }
}

/// Random faces and atlases: where the receivers' pages fit at the sides asked the atlas keeps
/// just those pages (and where they do not, they would not have fit); else every face whole at
/// the smallest shift that fits. Every face with a level gets its level's side after the shift
/// and texels of its own inside the atlas (no two overlap), faces without one get none; an atlas
/// of `MIN_SIDE²` per face always fits at some shift.
#[test]
fn the_atlas_gives_every_face_its_side_and_pages_without_overlap() {
    let mut rng = Rng(9);
    let (mut paged, mut whole) = (0, 0);
    for round in 0..600 {
        let faces = 1 + rng.below(400);
        let cap = [8, 100, 256, 4096][rng.below(4) as usize];
        let mut needed = vec![];
        for _ in 0..faces {
            let k = if rng.below(3) == 0 { 0 } else { 1 + rng.below(cap_level(cap)) };
            let pages = if k == 0 { [0, 0] } else { random_pages(&mut rng) };
            needed.extend([k, pages[0], pages[1]]);
        }
        let levels: Vec<(u32, [u32; 2])> = needed.chunks(3).map(|f| (f[0], [f[1], f[2]])).collect();
        let floor = MIN_SIDE.min(cap);
        let least = faces * floor * floor;
        let texels = if round % 3 == 0 { least } else { least + rng.below(faces * 256 * 256) };
        let mut order: Vec<u32> = (0..faces + 5).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i as u32 + 1) as usize);
        }
        let (slots, args) = allocate(&needed, cap, texels, &order);
        let shift = args[ARGS_SHIFT];
        let need_pages: u64 = levels.iter().filter(|f| f.0 != 0).map(|&(k, p)| (p[0].count_ones() + p[1].count_ones()) as u64 * (page_span(face_side(k, 0, cap)) as u64).pow(2)).sum();
        let need = |s: u32| levels.iter().filter(|f| f.0 != 0).map(|&(k, _)| (face_side(k, s, cap) as u64).pow(2)).sum::<u64>();
        let used: u64 = if args[ARGS_PAGED] == 1 {
            paged += 1;
            assert_eq!(shift, 0, "round {round}");
            assert!(need_pages <= texels as u64, "round {round}: pages need {need_pages} of {texels}");
            levels.iter().filter(|f| f.0 != 0).map(|&(k, p)| face_texels(face_side(k, 0, cap), p) as u64).sum()
        } else {
            whole += 1;
            assert!(need_pages > texels as u64, "round {round}: the pages fit, yet faces are whole");
            assert!(need(shift) <= texels as u64, "round {round}: shift {shift} needs {} of {texels}", need(shift));
            assert!(shift == 0 || need(shift - 1) > texels as u64, "round {round}: shift {shift} is not the least");
            need(shift)
        };
        assert_eq!(args[ARGS_USED] as u64, used, "round {round}");
        let mut spans = vec![];
        for (m, &(k, pages)) in levels.iter().enumerate() {
            let face = face_entry(&slots, m as u32);
            if k == 0 {
                assert_eq!(face, FaceMap { base: 0, res: 0, pages: [0, 0] });
            } else {
                assert_eq!(face.res, face_side(k, shift, cap));
                assert_eq!(face.pages, if args[ARGS_PAGED] == 1 { pages } else { ALL_PAGES });
                let n = face_texels(face.res, face.pages);
                assert!(face.base as u64 + n as u64 <= texels as u64);
                spans.push((face.base, face.base + n));
            }
        }
        spans.sort();
        assert!(spans.windows(2).all(|w| w[0].1 <= w[1].0), "round {round}: faces overlap");
    }
    assert!(paged > 100 && whole > 100, "{paged} paged, {whole} whole");
    // An atlas short of the levels asked halves every side until they fit (whole faces: their
    // pages at full size would need 2 · 128² · 4 + 8² texels).
    let all = [u32::MAX, u32::MAX];
    let (slots, args) = allocate(&[9, all[0], all[1], 9, all[0], all[1], 0, 0, 0, 3, 1, 0], 4096, 2 * 128 * 128 + 64, &[0, 1, 2, 3]);
    assert_eq!((args[ARGS_SHIFT], args[ARGS_PAGED]), (2, 0));
    assert_eq!(face_entry(&slots, 0).res, 128);
    assert_eq!(face_entry(&slots, 3).res, MIN_SIDE);
    assert_eq!(args[ARGS_FACES], 3);
    // With room for both at 256² (a shift of one for whole faces), a quarter of the first two
    // faces' pages fits at their full 512², paged.
    let texels = 2 * 256 * 256 + 64;
    let (_, args) = allocate(&[9, all[0], all[1], 9, all[0], all[1], 0, 0, 0, 3, 1, 0], 4096, texels, &[0, 1, 2, 3]);
    assert_eq!((args[ARGS_SHIFT], args[ARGS_PAGED]), (1, 0));
    let quarter = crate::shadow_receivers::page_rect(0, 3, 0, 3);
    let (slots, args) = allocate(&[9, quarter[0], quarter[1], 9, quarter[0], quarter[1], 0, 0, 0, 3, 1, 0], 4096, texels, &[0, 1, 2, 3]);
    assert_eq!((args[ARGS_SHIFT], args[ARGS_PAGED]), (0, 1));
    assert_eq!(face_entry(&slots, 0), FaceMap { base: face_entry(&slots, 0).base, res: 512, pages: quarter });
    assert_eq!(args[ARGS_USED], 2 * 16 * 64 * 64 + 1);
}

/// A face's texels in its pages, against the page rule computed apart: texel `(x, y)` is in page
/// `(⌊8x/res⌋, ⌊8y/res⌋)`; a present page's texels take distinct places in `base ..
/// base + face_texels`, an absent one's `NO_TEXEL`; a face of every page is row-major. Sides that
/// are and are not multiples of 8, down to sides below 8.
#[test]
fn a_face_maps_the_texels_of_its_pages_one_to_one() {
    let mut rng = Rng(33);
    for res in [1, 3, 8, 13, 64, 100, 128, 257] {
        for _ in 0..20 {
            let pages = random_pages(&mut rng);
            let face = FaceMap { base: 1000, res, pages };
            let n = face_texels(res, pages);
            let mut seen = vec![false; n as usize];
            for y in 0..res {
                for x in 0..res {
                    let page = 8 * (8 * y / res) + 8 * x / res;
                    let present = (if page < 32 { pages[0] >> page } else { pages[1] >> (page - 32) }) & 1 == 1;
                    let at = face.texel(x, y);
                    if !present {
                        assert_eq!(at, NO_TEXEL, "res {res}: texel ({x}, {y}) of absent page {page}");
                        continue;
                    }
                    if pages == ALL_PAGES {
                        assert_eq!(at, 1000 + y * res + x);
                    }
                    assert!((1000..1000 + n).contains(&at), "res {res}: texel ({x}, {y}) at {at} outside {n}");
                    assert!(!std::mem::replace(&mut seen[(at - 1000) as usize], true), "res {res}: ({x}, {y}) shares {at}");
                }
            }
        }
    }
}
