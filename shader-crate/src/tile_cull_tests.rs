//! CPU tests of `tile_cull`: the culling tests are conservative against brute force (random
//! tiles, spheres and pixels, thin and huge depth ranges) and the 2.5D bit math at its edges.
use super::*;
use crate::lighting::light_touches;
use crate::reconstruct::view_position;
use crate::test_support::{grid, Rng};

/// A random tile, depth range and pixel positions in it; lights around them, some touching.
/// Every light touching a sampled pixel must pass `sphere_in_tile` and the 2.5D mask test.
#[test]
fn culling_is_conservative_against_brute_force() {
    let mut rng = Rng(5);
    let mut culled = 0u64;
    let mut kept_touching = 0u64;
    for case in 0..3000 {
        let g = [grid(97, 61, 16), grid(1920, 1080, 32), grid(33, 17, 8), grid(1, 1, 16)][case % 4];
        let (tx, ty) = (rng.below(g.tiles_x), rng.below(g.tiles_y));
        let (x0, x1, y0, y1) = tile_rect(&g, tx, ty);
        // Depth ranges: ordinary, thin (min == max), and reaching MAX_DISTANCE.
        let d_a = 0.1 + 300.0 * rng.unit() * rng.unit();
        let (d_min, d_max) = match case % 3 {
            0 => (d_a, d_a + 50.0 * rng.unit()),
            1 => (d_a, d_a),
            _ => (d_a, reconstruct::MAX_DISTANCE),
        };
        let f = tile_frustum(&g, tx, ty, d_min, d_max);
        let cells = depth_cells(d_min, d_max);
        let pixels: Vec<Vec3> = (0..24)
            .map(|k| {
                let px = x0 + rng.below(x1 - x0);
                let py = y0 + rng.below(y1 - y0);
                let d = match k {
                    0 => d_min,
                    1 => d_max,
                    _ if case % 3 == 2 => d_min * (1.0 + 1e3 * rng.unit()),
                    _ => d_min + (d_max - d_min) * rng.unit(),
                };
                view_position(&g, px, py, d)
            })
            .collect();
        let tile_mask = pixels.iter().fold(0, |m, p| m | 1u32 << depth_cell(&cells, -p.z));
        for _ in 0..40 {
            let anchor = pixels[rng.below(pixels.len() as u32) as usize];
            let r = [0.0, 0.01, 1.0, 10.0, 1e4][rng.below(5) as usize] * (0.2 + rng.unit());
            let off = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * (3.0 * r + 1.0);
            let c = anchor + off;
            let light = PointLight { position: c.to_array(), radius: r, colour: [1.0; 3], intensity: 1.0 };
            let touches = pixels.iter().any(|p| light_touches(&light, *p));
            let keep = sphere_in_tile(&f, c, r);
            let keep25 = keep_light(&f, &cells, tile_mask, MODE_TILED_25D, &light);
            if touches {
                assert!(keep, "case {case}: light {light:?} touches a pixel of tile {f:?} but is culled");
                assert!(keep25, "case {case}: light {light:?} touches a pixel but the 2.5D masks miss (tile {tile_mask:#x})");
                kept_touching += 1;
            } else if !keep25 {
                culled += 1;
            }
        }
    }
    assert!(kept_touching > 10_000 && culled > 10_000, "the cases must exercise both outcomes: {kept_touching} kept, {culled} culled");
}

/// A light far outside a tile's frustum (beside it, behind the camera, beyond d_max) is culled.
#[test]
fn culling_rejects_lights_outside() {
    let g = grid(64, 64, 16);
    let f = tile_frustum(&g, 0, 0, 10.0, 20.0);
    let light = |p: [f32; 3], r: f32| (Vec3::from_array(p), r);
    let centre = view_position(&g, 8, 8, 15.0);
    for (c, r) in [light([centre.x, centre.y, 5.0], 1.0), light([centre.x, centre.y, -40.0], 5.0), light([50.0, centre.y, centre.z], 3.0), light([centre.x, -50.0, centre.z], 3.0)] {
        assert!(!sphere_in_tile(&f, c, r), "{c:?} r {r} should be culled by {f:?}");
    }
    assert!(sphere_in_tile(&f, centre, 0.5));
    assert!(sphere_in_tile(&f, view_position(&g, 8, 8, 9.5), 0.6), "reaches d_min");
    assert!(!sphere_in_tile(&f, view_position(&g, 8, 8, 9.3), 0.6), "stops short of d_min");
}

#[test]
fn depth_mask_bits_at_the_edges() {
    let cells = depth_cells(10.0, 42.0); // cells of width 1
    assert_eq!(depth_cell(&cells, 10.0), 0);
    assert_eq!(depth_cell(&cells, 10.999), 0);
    assert_eq!(depth_cell(&cells, 11.0), 1);
    assert_eq!(depth_cell(&cells, 41.0), 31);
    assert_eq!(depth_cell(&cells, 42.0), 31, "d_max is in the last cell");
    assert_eq!(depth_cell(&cells, 1e30), 31);
    assert_eq!(depth_cell(&cells, 9.0), 0);
    assert_eq!(depth_cell(&cells, -1e30), 0);
    assert_eq!(depth_cell(&cells, f32::NAN), 0);
    // A thin range is one cell.
    let thin = depth_cells(5.0, 5.0);
    assert_eq!(thin.inv_width, 0.0);
    assert_eq!(depth_cell(&thin, 5.0), 0);
    assert_eq!(cell_range_mask(0, 31), u32::MAX);
    assert_eq!(cell_range_mask(0, 0), 1);
    assert_eq!(cell_range_mask(31, 31), 1 << 31);
    assert_eq!(cell_range_mask(5, 7), 0b1110_0000);
    assert_eq!(cell_range_mask(7, 5), 0);
    // A light within one cell sets one bit; a light spanning the range sets all.
    let at = |d: f32| Vec3::new(0.0, 0.0, -d);
    assert_eq!(light_depth_mask(&cells, at(20.5), 0.25), 1 << 10);
    assert_eq!(light_depth_mask(&cells, at(26.0), 100.0), u32::MAX);
    assert_eq!(light_depth_mask(&cells, at(20.5), 1.0), 0b111 << 9);
    // Monotone in d over many random pairs.
    let mut rng = Rng(9);
    for _ in 0..100_000 {
        let c = depth_cells(rng.unit() * 100.0, 100.0 + rng.unit() * 1e5);
        let (a, b) = (rng.unit() * 2e5 - 1e4, rng.unit() * 2e5 - 1e4);
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        assert!(depth_cell(&c, lo) <= depth_cell(&c, hi));
    }
}
