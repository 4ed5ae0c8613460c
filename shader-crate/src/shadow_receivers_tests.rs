use super::*;
use crate::reconstruct::{distance_from_depth, is_background, view_position};
use crate::shadow::{cube_face, FACES};
use crate::test_support::{gbuffer, grid, Rng};

fn params(g: ClusterGrid, res: u32, casters: u32) -> ReceiverParams {
    ReceiverParams { grid: g, res, casters, tiles_x: g.width.div_ceil(RECEIVER_TILE), tiles_y: g.height.div_ceil(RECEIVER_TILE) }
}

fn tiles_of(p: &ReceiverParams, depth: &[f32]) -> Vec<f32> {
    let mut tiles = vec![];
    for t in 0..p.tiles_x * p.tiles_y {
        for (c, r) in tile_spheres(p, t % p.tiles_x, t / p.tiles_x, depth) {
            tiles.extend_from_slice(&[c.x, c.y, c.z, r]);
        }
    }
    tiles
}

/// Per face the larger of two packed levels.
fn merge(a: u32, b: u32) -> u32 {
    (0..FACES).fold(0, |m, f| m | (packed_level(a, f).max(packed_level(b, f)) << (LEVEL_BITS * f)))
}

/// The faces with a level.
fn mask_of(levels: u32) -> u32 {
    (0..FACES).filter(|&f| packed_level(levels, f) != 0).fold(0, |m, f| m | 1 << f)
}

/// The lookup direction of `shadow::cube_visibility` for a receiver at `pos` with normal `n`.
fn lookup(light: Vec3, pos: Vec3, normal: Vec3, res: u32) -> Vec3 {
    let to_light = light - pos;
    let texel = 2.0 * to_light.length() / res as f32;
    let n = if normal.dot(to_light) < 0.0 { -normal } else { normal };
    pos + n * (NORMAL_OFFSET_TEXELS * texel) - light
}

/// On a synthetic G-buffer (a near wall, a far slope, sky; partial tiles at the right and bottom
/// edges) with lights near the surfaces: every surface point lies in one of its tile's spheres, a tile of
/// sky has none, and every pixel's lookup within a light's radius, with any normal, at the side
/// the atlas gives the receiver's face (its tiles' largest level, `shadow_atlas`), falls on a face
/// with a level; at most 256² per face the levels leave a quarter of the faces out.
#[test]
fn every_lookup_within_the_radius_falls_on_a_needed_face() {
    let mut rng = Rng(12);
    let g = grid(130, 70, 16);
    let gb = gbuffer(&g, &mut rng);
    for res in [8, 256] {
        let mut casters = vec![];
        for _ in 0..60 {
            let (px, py) = (rng.below(g.width), rng.below(g.height));
            let d = if rng.below(2) == 0 { 1.0 + rng.unit() } else { 30.0 + 60.0 * rng.unit() };
            let c = view_position(&g, px, py, d) + Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - Vec3::ONE;
            casters.extend_from_slice(&[c.x, c.y, c.z, 0.5 + 6.0 * rng.unit()]);
        }
        let p = params(g, res, 60);
        let tiles = tiles_of(&p, &gb.depth);
        let n_tiles = p.tiles_x * p.tiles_y;
        assert_eq!((p.tiles_x, p.tiles_y), (9, 5));
        let levels: Vec<u32> = (0..p.casters).map(|c| (0..n_tiles).step_by(TILES_PER_INVOCATION as usize).fold(0, |m, first| merge(m, receiver_faces(&p, c, first, &tiles, &casters)))).collect();
        // One run per tile gives the same levels.
        for c in 0..p.casters {
            let single = (0..n_tiles).fold(0, |m, t| {
                let one = ReceiverParams { tiles_x: 1, tiles_y: t + 1, ..p };
                merge(m, receiver_faces(&one, c, t, &tiles, &casters))
            });
            assert_eq!(single, levels[c as usize], "caster {c}");
        }
        let masks: Vec<u32> = levels.iter().map(|&l| mask_of(l)).collect();
        let mut seen = 0;
        for i in 0..(g.width * g.height) {
            let (x, y) = (i % g.width, i / g.width);
            let t = (y / RECEIVER_TILE) * p.tiles_x + x / RECEIVER_TILE;
            let z = gb.depth[i as usize];
            if is_background(z) {
                continue;
            }
            let pos = view_position(&g, x, y, distance_from_depth(g.near, z));
            let within = |k: u32| {
                let w = (t * TILE_WORDS + 4 * k) as usize;
                let (centre, r) = (Vec3::new(tiles[w], tiles[w + 1], tiles[w + 2]), tiles[w + 3]);
                r >= 0.0 && (pos - centre).length() <= r * (1.0 + 1e-6) + 1e-6
            };
            assert!(within(0) || within(1), "pixel ({x}, {y}) outside its tile's spheres");
            for c in 0..p.casters as usize {
                let light = Vec3::new(casters[4 * c], casters[4 * c + 1], casters[4 * c + 2]);
                for _ in 0..2 {
                    let normal = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::Y);
                    if (light - pos).length() > casters[4 * c + 3] {
                        continue;
                    }
                    let at = cube_face(pos - light);
                    let level = packed_level(levels[c], at);
                    assert!(level != 0, "res {res}: pixel ({x}, {y})'s own face {at} of caster {c} has no level");
                    let d = lookup(light, pos, normal, face_side(level, 0, res));
                    if d.length() > 1e-6 {
                        seen += 1;
                        let f = cube_face(d);
                        assert!(masks[c] & (1 << f) != 0, "res {res}: pixel ({x}, {y}) looks caster {c} up on face {f}, not in its mask {:06b}", masks[c]);
                    }
                }
            }
        }
        // A tile of sky has no sphere.
        let sky = (0..n_tiles).filter(|&t| tiles[(t * TILE_WORDS + 3) as usize] < 0.0 && tiles[(t * TILE_WORDS + 7) as usize] < 0.0).count();
        let kept: u32 = masks.iter().map(|m| m.count_ones()).sum();
        eprintln!("res {res}: {seen} lookups, {sky} tiles of sky, {kept} of {} faces kept", FACES * p.casters);
        assert!(seen > 1000 && sky >= 1, "{seen} lookups, {sky} sky tiles");
        // At 8² the normal offset (1.5 texels of a quarter of the distance) widens every sphere
        // past most faces; at 256² the masks cull.
        assert!(kept > 0 && (res < 256 || kept < FACES * p.casters * 3 / 4), "res {res}: {kept} faces kept");
    }
}

/// A caster whose sphere reaches no tile's receivers keeps no face; one inside a tile's box
/// keeps all six.
#[test]
fn casters_far_from_every_receiver_keep_no_face() {
    let mut rng = Rng(2);
    let g = grid(40, 30, 16);
    let gb = gbuffer(&g, &mut rng);
    let p = params(g, 64, 2);
    let tiles = tiles_of(&p, &gb.depth);
    let inside = view_position(&g, 5, 5, distance_from_depth(g.near, gb.depth[5 * 40 + 5]));
    let casters = [0.0, 0.0, 500.0, 10.0, inside.x, inside.y, inside.z, 0.5];
    let n = p.tiles_x * p.tiles_y;
    let mask = |c| mask_of((0..n).step_by(TILES_PER_INVOCATION as usize).fold(0, |m, first| merge(m, receiver_faces(&p, c, first, &tiles, &casters))));
    assert_eq!(mask(0), 0);
    assert_eq!(mask(1), 63);
}

