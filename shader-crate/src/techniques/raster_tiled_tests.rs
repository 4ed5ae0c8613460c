//! CPU tests of `raster_tiled`: the quad of a light holds every tile the culling test can keep
//! (brute force over every tile, random lights and grids, lights crossing the near plane and
//! holding the eye), the quad's rasterisation covers exactly its tiles, the append never writes
//! past the capacity and counts what it could not store, and a frame's lists equal `tiled`'s
//! test applied tile by tile.
use super::*;
use crate::test_support::{grid, Rng};
use crate::tile_cull::{keep_light, tile_frustum, DepthCells, MODE_TILED};

/// A light around the view frustum: near the eye (some hold it), in front, behind, off to the
/// sides, tiny and huge radii.
fn random_light(rng: &mut Rng, g: &ClusterGrid) -> PointLight {
    let d = match rng.below(4) {
        0 => -2.0 + 4.0 * rng.unit(),
        1 => 0.1 + 5.0 * rng.unit(),
        _ => 1.0 + 300.0 * rng.unit(),
    };
    let spread = g.tan_half_fov_y * d.abs().max(1.0) * 2.5;
    let r = match rng.below(3) {
        0 => 0.01 + 0.5 * rng.unit(),
        1 => 1.0 + 20.0 * rng.unit(),
        _ => 50.0 + 500.0 * rng.unit(),
    };
    PointLight { position: [spread * (2.0 * rng.unit() - 1.0), spread * (2.0 * rng.unit() - 1.0), -d], radius: r, colour: [1.0; 3], intensity: 1.0 }
}

/// Every tile whose frustum (over the whole depth range the pixels can have) keeps the light lies
/// inside the light's quad: the raster pass can miss no tile the test would keep.
#[test]
fn the_quad_holds_every_tile_the_test_keeps() {
    let mut rng = Rng(31);
    let (mut inside, mut kept, mut total) = (0u64, 0u64, 0u64);
    let grids = [grid(1920, 1080, 16), grid(97, 61, 8), grid(33, 17, 32), grid(1, 1, 16), grid(640, 360, 24)];
    for case in 0..4000 {
        let g = grids[case % grids.len()];
        total += u64::from(g.tiles_x * g.tiles_y);
        let light = random_light(&mut rng, &g);
        let [tx0, ty0, tx1, ty1] = light_tiles(&g, &light);
        assert!(tx0 <= tx1 && ty0 <= ty1 && tx1 <= g.tiles_x && ty1 <= g.tiles_y, "{light:?}: rect {tx0} {ty0} {tx1} {ty1}");
        let cells = DepthCells { d_min: g.near, inv_width: 0.0 };
        for ty in 0..g.tiles_y {
            for tx in 0..g.tiles_x {
                let f = tile_frustum(&g, tx, ty, g.near, g.far);
                if keep_light(&f, &cells, u32::MAX, MODE_TILED, &light) {
                    kept += 1;
                    assert!(tx >= tx0 && tx < tx1 && ty >= ty0 && ty < ty1, "case {case}: tile ({tx}, {ty}) keeps {light:?} outside its quad {tx0}..{tx1} × {ty0}..{ty1}");
                }
                inside += u64::from(tx >= tx0 && tx < tx1 && ty >= ty0 && ty < ty1);
            }
        }
    }
    assert!(kept > 10_000, "the cases keep lights ({kept})");
    // Not every quad is the whole screen: the quads are tight enough to cull.
    assert!(inside * 2 < total, "quads cover {inside} of {total} tiles: too loose");
}

/// Lights wholly before the near plane have no tile; lights holding the eye have every tile.
#[test]
fn lights_behind_the_near_plane_and_around_the_eye() {
    let g = grid(320, 180, 16);
    let behind = PointLight { position: [0.0, 0.0, 5.0], radius: 1.0, colour: [1.0; 3], intensity: 1.0 };
    assert_eq!(light_tiles(&g, &behind), [0; 4]);
    let around = PointLight { position: [0.0, 0.0, 0.5], radius: 1.0, colour: [1.0; 3], intensity: 1.0 };
    assert_eq!(light_tiles(&g, &around), [0, 0, g.tiles_x, g.tiles_y]);
    let ahead = PointLight { position: [0.0, 0.0, -50.0], radius: 1.0, colour: [1.0; 3], intensity: 1.0 };
    let [x0, y0, x1, y1] = light_tiles(&g, &ahead);
    assert!(x0 > 0 && x1 < g.tiles_x && y0 > 0 && y1 < g.tiles_y && x0 < x1 && y0 < y1, "a small light ahead: a few central tiles");
    let nan = PointLight { position: [f32::NAN, 0.0, -5.0], radius: 1.0, colour: [1.0; 3], intensity: 1.0 };
    assert_eq!(light_tiles(&g, &nan), [0, 0, g.tiles_x, g.tiles_y], "out-of-contract input: every tile, never none");
}

/// The quad's two triangles cover exactly the centres of its tiles (the rasteriser's pixel-centre
/// rule on the tile target: a centre `t + 0.5` lies inside iff `t0 ≤ t < t1`).
#[test]
fn quads_cover_exactly_their_tiles() {
    let mut rng = Rng(7);
    let mut grids = 0;
    for _ in 0..2000 {
        // Grids the renderer accepts (a tile may not exceed what its slice count allows).
        let Ok(g) = ClusterGrid::new(1 + rng.below(4000), 1 + rng.below(3000), 1 + rng.below(64), 0.1, 1000.0, core::f32::consts::FRAC_PI_3) else { continue };
        grids += 1;
        let (x0, y0) = (rng.below(g.tiles_x), rng.below(g.tiles_y));
        let (x1, y1) = (x0 + 1 + rng.below(g.tiles_x - x0), y0 + 1 + rng.below(g.tiles_y - y0));
        let ndc = tiles_to_ndc(&g, [x0, y0, x1, y1]);
        let corners: Vec<Vec4> = (0..VERTICES_PER_LIGHT).map(|v| quad_corner(ndc, v)).collect();
        // Back to target pixels: the edges land on tile boundaries within far less than half a pixel.
        let px = |x: f32, n: u32| (x + 1.0) * 0.5 * n as f32;
        for (c, want) in corners.iter().zip([(x0, y0), (x1, y0), (x0, y1), (x0, y1), (x1, y0), (x1, y1)]) {
            assert!((px(c.x, g.tiles_x) - want.0 as f32).abs() < 0.01 && (px(c.y, g.tiles_y) - want.1 as f32).abs() < 0.01, "{c:?} vs {want:?}");
        }
        // The two triangles share the diagonal (1,0)–(0,1) and together are the rectangle.
        assert_eq!((corners[1], corners[2]), (corners[4], corners[3]));
    }
    assert!(grids > 1000, "{grids} grids tried");
}

/// The append stores up to the capacity, counts every light, and leaves other tiles alone.
#[test]
fn append_counts_past_the_capacity_without_writing_there() {
    let (tiles, capacity) = (3u32, 4u32);
    let mut counts = vec![0u32; tiles as usize];
    let mut lists = vec![u32::MAX; (tiles * capacity) as usize];
    let add = |w: &mut u32| {
        let old = *w;
        *w += 1;
        old
    };
    for l in 0..7 {
        append(&mut counts, &mut lists, capacity, 1, 100 + l, add);
    }
    assert_eq!(counts, [0, 7, 0]);
    assert_eq!(&lists[4..8], &[100, 101, 102, 103]);
    assert!(lists[..4].iter().chain(&lists[8..]).all(|&w| w == u32::MAX), "other tiles untouched");
}

/// `tile_keeps` over a frame is `tiled`'s test tile by tile: a tile without geometry keeps
/// nothing, every other tile exactly the lights `keep_light` keeps for its depth range.
#[test]
fn tile_keeps_is_the_tiled_test() {
    let mut rng = Rng(11);
    let g = grid(97, 61, 16);
    let lights: Vec<PointLight> = (0..300).map(|_| random_light(&mut rng, &g)).collect();
    let p = FrameParams { grid: g, count: g.width * g.height, num_lights: lights.len() as u32, light_capacity: 64, effects: 0, normal_precision: 0, view: 0, exposure: 1.0, heat_max: 64 };
    let mut depths = Vec::new();
    for t in 0..g.tiles_x * g.tiles_y {
        let words = if t.is_multiple_of(5) { EMPTY_TILE } else {
            let d = 0.5 + 100.0 * rng.unit();
            [d.to_bits(), (d + 30.0 * rng.unit()).to_bits()]
        };
        depths.extend(words);
    }
    let mut kept = 0;
    for ty in 0..g.tiles_y {
        for tx in 0..g.tiles_x {
            let t = ty * g.tiles_x + tx;
            let (lo, hi) = (f32::from_bits(depths[2 * t as usize]), f32::from_bits(depths[2 * t as usize + 1]));
            for (l, light) in lights.iter().enumerate() {
                let want = !t.is_multiple_of(5) && keep_light(&tile_frustum(&g, tx, ty, lo, hi), &DepthCells { d_min: lo, inv_width: 0.0 }, u32::MAX, MODE_TILED, light);
                assert_eq!(tile_keeps(&p, &depths, &lights, tx, ty, l as u32), want, "tile ({tx}, {ty}), light {l}");
                kept += usize::from(want);
            }
        }
    }
    assert!(kept > 100, "the frame keeps lights ({kept})");
    assert!(!tile_keeps(&p, &depths, &lights, g.tiles_x, 0, 0) && !tile_keeps(&p, &depths, &lights, 0, 0, lights.len() as u32), "out of range: nothing");
}

#[test]
fn pixels_map_to_their_tiles() {
    let g = grid(97, 61, 16);
    for i in 0..g.width * g.height {
        let (x, y) = (i % g.width, i / g.width);
        assert_eq!(tile_of_pixel(&g, i), (y / 16) * g.tiles_x + x / 16);
    }
}
