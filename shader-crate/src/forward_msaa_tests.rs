//! CPU tests of `forward_msaa`: the samples a fragment owns, its colours and the resolve, each
//! against a closed form.
use super::*;
use crate::lighting::{decode_srgb8, encode_srgb8};

#[test]
fn a_fragment_owns_the_covered_samples_the_pre_pass_gave_its_triangle() {
    let me = (3, 17);
    // Everything covered and won: every sample.
    assert_eq!(visible_samples(4, 0b1111, me, |_| me), 0b1111);
    // Coverage: only the covered ones.
    assert_eq!(visible_samples(4, 0b0101, me, |_| me), 0b0101);
    // Another draw wins sample 1 (a coplanar surface drawn first).
    assert_eq!(visible_samples(4, 0b1111, me, |s| if s == 1 { (2, 17) } else { me }), 0b1101);
    // Another triangle of the same draw wins sample 2 (nearer, or coplanar and drawn first).
    assert_eq!(visible_samples(4, 0b1111, me, |s| if s == 2 { (3, 18) } else { me }), 0b1011);
    // Sky samples (no draw) belong to no fragment.
    assert_eq!(visible_samples(8, 0xff, me, |s| if s == 0 { (NO_DRAW, NO_DRAW) } else { me }), 0xfe);
}

#[test]
fn a_whole_pixel_is_shaded_once_and_a_partial_one_per_sample() {
    let centre = 0xff_40_80_c0;
    let per_sample = |s: u32| [0xff_00_00_ff, 0xff_00_ff_00, 0xff_ff_00_00, 0xff_10_10_10][s as usize];
    // No sample (it writes none): the centre's colour for both.
    let (edge, c) = fragment_colours(&(), 4, 0, || panic!("owns no sample"), |_| centre, |_, _| panic!());
    assert_eq!((encode_srgb8(edge), c), (centre, centre));
    // Every sample: the centre's colour, exactly (decoded; the resolve encodes it back).
    for samples in [2, 4, 8] {
        let (edge, c) = fragment_colours(&(), samples, full_mask(samples), || false, |_| centre, |_, _| panic!("no sample is shaded alone"));
        assert_eq!((encode_srgb8(edge), c), (centre, centre), "{samples} samples");
    }
    // Every sample of a pixel the edge rule calls an edge (a surface seen edge-on): the mean of
    // the four, and the centre.
    let (c, centre_all) = fragment_colours(&(), 4, 0b1111, || true, |_| centre, |_, s| per_sample(s));
    let all = (0..4).map(|s| decode_srgb8(per_sample(s))).fold(Vec3::ZERO, |a, b| a + b) * 0.25;
    assert!((c - all).abs().max_element() < 1e-7);
    assert_eq!(centre_all, centre);
    // Samples 0 and 2 of 4: the mean of their two colours, linear, and (holding sample 0) the
    // centre colour.
    let (c02, centre02) = fragment_colours(&(), 4, 0b0101, || panic!("not alone"), |_| centre, |_, s| per_sample(s));
    let want = (decode_srgb8(per_sample(0)) + decode_srgb8(per_sample(2))) * 0.5;
    assert!((c02 - want).abs().max_element() < 1e-7);
    assert_eq!(centre02, centre);
    // Samples 1 and 3: no centre colour (never read: the resolve reads sample 0's).
    let (c13, centre13) = fragment_colours(&(), 4, 0b1010, || panic!("not alone"), |_| panic!("sample 0 is not its"), |_, s| per_sample(s));
    assert_eq!(centre13, 0);
    // Resolved as an edge pixel: the mean of all four samples' own colours.
    let resolved = crate::msaa::resolve(2.0 * c02 + 2.0 * c13, 4);
    let all = (0..4).map(|s| decode_srgb8(per_sample(s))).fold(Vec3::ZERO, |a, b| a + b);
    assert_eq!(resolved, crate::msaa::resolve(all, 4));
}

#[test]
fn colour_texels_keep_the_centre_word_exactly() {
    for word in [0xff_00_00_00u32, 0xff_ff_ff_ff, 0xff_20_18_18, 0xff_01_02_03, 0xff_fe_fd_fc] {
        let t = colour_texel(Vec3::new(0.25, 0.5, 1.0), word);
        assert_eq!(centre_of(t), word);
        assert_eq!(t.truncate(), Vec3::new(0.25, 0.5, 1.0));
    }
}

/// A sample key of a flat surface facing the viewer at distance 1, or of the sky.
fn key(albedo: u32, sky: bool) -> crate::msaa::SampleKey {
    // Reversed Z with the near plane at 0.1: depth 0.1 at distance 1; 0 is the sky.
    crate::msaa::SampleKey { depth: if sky { 0.0 } else { 0.1 }, normal: Vec3::Z, albedo, ray: Vec3::new(0.0, 0.0, -1.0) }
}

#[test]
fn the_resolve_keeps_the_centre_of_a_pixel_that_is_no_edge_and_averages_an_edge() {
    let centre = 0xff_40_80_c0;
    let edge_colour = |s: u32| Vec3::splat(0.1 * (s + 1) as f32);
    let texel = |s: u32| colour_texel(edge_colour(s), if s == 0 { centre } else { 0 });
    // One surface (two fragments of one smooth surface are no edge either): sample 0's centre
    // colour, whatever the samples' edge colours.
    assert_eq!(resolve_pixel(0.1, 4, |_| key(7, false), texel), (centre, false));
    // Another albedo at sample 3: an edge, the mean of the four edge colours.
    let (word, edge) = resolve_pixel(0.1, 4, |s| key(if s == 3 { 8 } else { 7 }, false), texel);
    assert!(edge);
    assert_eq!(word, crate::msaa::resolve((0..4).map(edge_colour).fold(Vec3::ZERO, |a, b| a + b), 4));
    // Sky at sample 0 and geometry elsewhere: an edge; sky everywhere: the background word the
    // target was cleared to.
    assert!(resolve_pixel(0.1, 4, |s| key(7, s == 0), texel).1);
    let bg = crate::shading::BACKGROUND_RGBA8;
    let cleared = |_| colour_texel(decode_srgb8(bg), bg);
    assert_eq!(resolve_pixel(0.1, 4, |_| key(0, true), cleared), (bg, false));
}

#[test]
fn winner_texels_hold_draw_indices_exactly() {
    for d in [0u32, 1, 2, 1000, MAX_DRAWS - 1] {
        assert_eq!(draw_of(d as f32), d);
    }
    assert_eq!(draw_of(-1.0), NO_DRAW);
    assert_eq!(full_mask(1), 1);
    assert_eq!(full_mask(8), 0xff);
}
