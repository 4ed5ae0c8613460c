use super::*;
use crate::reconstruct::{distance_from_depth, is_background, view_position};
use crate::shadow::{cone_angle, cube_face, sphere_meets_widened_cone, FACES, NO_CONE};
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
            casters.extend_from_slice(&[c.x, c.y, c.z, 0.5 + 6.0 * rng.unit(), 0.0, 0.0, 0.0, NO_CONE]);
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
                let light = Vec3::new(casters[8 * c], casters[8 * c + 1], casters[8 * c + 2]);
                for _ in 0..2 {
                    let normal = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::Y);
                    if (light - pos).length() > casters[8 * c + 3] {
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
    let casters = [0.0, 0.0, 500.0, 10.0, 0.0, 0.0, 0.0, NO_CONE, inside.x, inside.y, inside.z, 0.5, 0.0, 0.0, 0.0, NO_CONE];
    let n = p.tiles_x * p.tiles_y;
    let mask = |c| mask_of((0..n).step_by(TILES_PER_INVOCATION as usize).fold(0, |m, first| merge(m, receiver_faces(&p, c, first, &tiles, &casters))));
    assert_eq!(mask(0), 0);
    assert_eq!(mask(1), 63);
}


/// The cone test against points: a sphere holding a point inside the cone always meets it; one
/// whose every point lies 0.05 rad or more outside never does; point lights meet everything.
#[test]
fn the_cone_test_keeps_every_sphere_that_reaches_into_the_cone() {
    let mut rng = Rng(31);
    let unit = |rng: &mut Rng| Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::X);
    let (mut met, mut missed) = (0, 0);
    for _ in 0..20_000 {
        let axis = unit(&mut rng);
        // Up to 3 rad: the shadow passes widen spot cones of up to 90° past it.
        let outer = 0.05 + 3.0 * rng.unit();
        let (d, r) = (unit(&mut rng) * (0.1 + 10.0 * rng.unit()), 3.0 * rng.unit() * rng.unit());
        let meets = sphere_meets_widened_cone(d, r, axis, cone_angle(outer.cos()).unwrap(), d.length() + r);
        assert!(cone_angle(NO_CONE).is_none() && cone_angle(f32::NAN).is_none(), "point lights take no cone test");
        // Points of the sphere: its centre and points towards the axis.
        let towards = (axis * d.length() - d).normalize_or(Vec3::ZERO);
        let angle = |q: Vec3| q.normalize().dot(axis).clamp(-1.0, 1.0).acos();
        for q in [d, d + towards * r * 0.999, d + unit(&mut rng) * r * rng.unit()] {
            if q.length() > 1e-4 && angle(q) < outer {
                assert!(meets, "{d} r {r}: a point at {} rad inside a cone of {outer}", angle(q));
            }
        }
        // Exact angular distance from the cone for a sphere not holding the apex.
        if d.length() > r {
            let gap = angle(d) - outer - (r / d.length()).asin();
            if gap > 0.05 {
                assert!(!meets, "{d} r {r}: {gap} rad outside the cone");
            }
        }
        met += usize::from(meets);
        missed += usize::from(!meets);
    }
    assert!(met > 2_000 && missed > 2_000, "{met} met, {missed} missed");
}

/// A spot light pointing down over the synthetic G-buffer keeps only faces its cone lights:
/// every lookup of a receiver inside the cone falls on a face with a level (faces of its cube
/// turned to the cone), and the spot keeps one face where the same light without a cone keeps
/// several.
#[test]
fn spot_lights_keep_only_the_faces_their_cone_lights() {
    let mut rng = Rng(17);
    let g = grid(130, 70, 16);
    let gb = gbuffer(&g, &mut rng);
    let p = params(g, 256, 2);
    let tiles = tiles_of(&p, &gb.depth);
    let n_tiles = p.tiles_x * p.tiles_y;
    let centre = view_position(&g, 65, 35, distance_from_depth(g.near, gb.depth[35 * 130 + 65]));
    // Half-way from the eye to the surface at the frame's centre, pointing at it.
    let light = centre * 0.5;
    let axis = (centre - light).normalize();
    let cos_outer = 0.3f32.cos();
    let casters = [light.x, light.y, light.z, 40.0, axis.x, axis.y, axis.z, cos_outer, light.x, light.y, light.z, 40.0, 0.0, 0.0, 0.0, NO_CONE];
    let levels: Vec<u32> = (0..2).map(|c| (0..n_tiles).step_by(TILES_PER_INVOCATION as usize).fold(0, |m, first| merge(m, receiver_faces(&p, c, first, &tiles, &casters)))).collect();
    let (spot, point) = (mask_of(levels[0]), mask_of(levels[1]));
    // The spot light's cube is turned to its cone (`CubeFrame`): a 17° cone on one face.
    let frame = crate::shadow::CubeFrame::of_cone(axis, cos_outer);
    assert!(spot == 1 << 4 && point.count_ones() > 1, "spot {spot:06b}, point {point:06b}");
    let mut inside = 0;
    for i in 0..(g.width * g.height) {
        let z = gb.depth[i as usize];
        if is_background(z) {
            continue;
        }
        let pos = view_position(&g, i % g.width, i / g.width, distance_from_depth(g.near, z));
        if (pos - light).normalize().dot(axis) <= cos_outer {
            continue;
        }
        inside += 1;
        let at = cube_face(frame.local(pos - light));
        let level = packed_level(levels[0], at);
        assert!(level != 0, "pixel {i} inside the cone on face {at} without a level");
        let normal = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::Y);
        let f = cube_face(frame.local(lookup(light, pos, normal, face_side(level, 0, 256))));
        assert!(spot & (1 << f) != 0, "pixel {i}'s lookup on face {f}, not in {spot:06b}");
    }
    assert!(inside > 200, "{inside} pixels inside the cone");
}

/// `pyramid_cos` against a dense sampling of the pyramid `|x| ≤ z, |y| ≤ z` (its interior on a
/// grid and its four sides finely): never below the best sampled direction, and within the
/// sampling's resolution of it.
#[test]
fn the_pyramid_cosine_is_the_best_direction_of_the_pyramid() {
    let mut rng = Rng(5);
    let n = 200;
    let samples: Vec<Vec3> = (0..=n).flat_map(|i| (0..=n).map(move |j| Vec3::new(2.0 * i as f32 / n as f32 - 1.0, 2.0 * j as f32 / n as f32 - 1.0, 1.0).normalize())).collect();
    for _ in 0..2_000 {
        let a = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::X);
        let got = pyramid_cos(a);
        let best = samples.iter().map(|p| a.dot(*p)).fold(-1.0f32, f32::max);
        assert!(got >= best - 1e-5, "{a}: {got} below a sampled {best}");
        assert!(got <= best + 2e-4, "{a}: {got} above every sample ({best})");
    }
}

/// `cone_faces` holds the face of every direction inside the cone, and leaves out faces the cone
/// misses: a cone of 40° down the −y axis meets that face alone; tilted 31° below +x, a cone of
/// 30° meets +x and −y, one of 40° also ±z (the edge `(1, −1, ±1)/√3` lies 37.7° off its axis).
#[test]
fn cone_faces_hold_every_direction_of_the_cone() {
    let mut rng = Rng(9);
    let unit = |rng: &mut Rng| Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize_or(Vec3::X);
    let mut partial = 0;
    for _ in 0..5_000 {
        let axis = unit(&mut rng);
        let angle = 0.02 + 1.6 * rng.unit();
        let mask = cone_faces(axis, angle);
        partial += usize::from(mask != 63);
        for _ in 0..50 {
            let d = unit(&mut rng);
            if d.dot(axis) > angle.cos() {
                assert!(mask & (1 << cube_face(d)) != 0, "axis {axis}, {angle} rad: {d} on face {} outside {mask:06b}", cube_face(d));
            }
        }
    }
    assert!(partial > 3_000, "{partial} cones left faces out");
    assert_eq!(cone_faces(Vec3::NEG_Y, 40f32.to_radians()), 1 << 3);
    let tilted = Vec3::new(1.0, -0.6, 0.0).normalize();
    assert_eq!(cone_faces(tilted, 30f32.to_radians()), (1 << 0) | (1 << 3));
    assert_eq!(cone_faces(tilted, 40f32.to_radians()), (1 << 0) | (1 << 3) | (1 << 4) | (1 << 5));
    assert_eq!(cone_faces(Vec3::X, 3.2), 63);
}
