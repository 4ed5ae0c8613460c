use super::*;
use crate::test_support::Rng;

/// A uniform float in `[a, b)`.
fn range(rng: &mut Rng, a: f32, b: f32) -> f32 {
    a + (b - a) * rng.unit()
}

/// Texels per face side of the maps built here.
const RES: u32 = 64;

/// The face table of `lights` lights whose slots follow the header: light `l` casts shadows
/// from slot `slots[l]` (or not, [`NO_SHADOW`]); every slot's six faces of `res` texels lie one
/// after another from texel 0 of the atlas, slot-major.
pub(crate) fn uniform_slots(res: u32, filter: u32, slots: &[u32]) -> Vec<u32> {
    let table = SHADOW_HEADER_WORDS + slots.len() as u32;
    let mut s = vec![res, filter, table, 0];
    s.extend_from_slice(slots);
    let maps = slots.iter().filter(|&&m| m != NO_SHADOW).count() as u32;
    for m in 0..maps * FACES {
        s.extend([m * res * res, res]);
    }
    s
}

/// A cube map of `RES` built independently of the raster pass: each texel holds the distance
/// along its centre's ray to the nearest of `hit`'s surfaces (`hit(origin, dir)` → distance or
/// infinity), as the raster pass stores the surface at the texel's centre.
fn cube_map(light: Vec3, hit: impl Fn(Vec3, Vec3) -> f32) -> Vec<u32> {
    cube_map_of(light, RES, &hit)
}

/// [`cube_map`] with faces of `res` texels per side.
fn cube_map_of(light: Vec3, res: u32, hit: &dyn Fn(Vec3, Vec3) -> f32) -> Vec<u32> {
    let mut map = vec![NO_OCCLUDER; (FACES * res * res) as usize];
    for f in 0..FACES {
        let (right, up, forward) = face_axes(f);
        for y in 0..res {
            for x in 0..res {
                let u = (x as f32 + 0.5) / res as f32 * 2.0 - 1.0;
                let v = (y as f32 + 0.5) / res as f32 * 2.0 - 1.0;
                let dir = (forward + right * u + up * v).normalize();
                let t = hit(light, dir);
                if t.is_finite() {
                    map[((f * res + y) * res + x) as usize] = t.to_bits();
                }
            }
        }
    }
    map
}

/// Distance along `dir` from `o` to the plane `y = h` (infinity when parallel or behind).
fn plane_y(o: Vec3, dir: Vec3, h: f32) -> f32 {
    let t = (h - o.y) / dir.y;
    if t > 0.0 && t.is_finite() {
        t
    } else {
        f32::INFINITY
    }
}

/// Distance along `dir` to the square `|x|, |z| ≤ half` at `y = h`.
fn square_y(o: Vec3, dir: Vec3, h: f32, half: f32) -> f32 {
    let t = plane_y(o, dir, h);
    let p = o + dir * t;
    if t.is_finite() && p.x.abs() <= half && p.z.abs() <= half {
        t
    } else {
        f32::INFINITY
    }
}

#[test]
fn the_raster_clip_position_and_the_lookup_agree_on_every_texel() {
    let mut rng = Rng(7);
    for _ in 0..20_000 {
        let d = Vec3::new(range(&mut rng, -5.0, 5.0), range(&mut rng, -5.0, 5.0), range(&mut rng, -5.0, 5.0));
        let f = cube_face(d);
        let (_, _, forward) = face_axes(f);
        let z = d.dot(forward);
        assert!(z > 0.0 && z >= d.abs().max_element() * 0.999_999, "{d}: face {f} is not the largest axis");
        let clip = face_clip(d, f);
        assert!(clip.x.abs() <= clip.w * 1.000_001 && clip.y.abs() <= clip.w * 1.000_001, "{d}: outside its face's frustum");
        assert!(clip.z >= 0.0 && clip.z <= clip.w, "{d}: clipped by depth ({clip})");
        // The viewport transform of the clip position is the lookup's texel position.
        let (x, y) = face_texel(d, f, RES);
        let viewport = ((clip.x / clip.w + 1.0) * 0.5 * RES as f32, (clip.y / clip.w + 1.0) * 0.5 * RES as f32);
        assert!((viewport.0 - x).abs() < 1e-3 && (viewport.1 - y).abs() < 1e-3, "{d}: {viewport:?} against {:?}", (x, y));
        // A smaller face in the corner of a larger render area: the same texel.
        for (res, area) in [(8, 64), (32, 256), (RES, RES)] {
            let (x, y) = face_texel(d, f, res);
            let c = face_area_clip(clip, res, area);
            let viewport = ((c.x / c.w + 1.0) * 0.5 * area as f32, (c.y / c.w + 1.0) * 0.5 * area as f32);
            assert!((viewport.0 - x).abs() < 1e-3 && (viewport.1 - y).abs() < 1e-3, "{d} at {res} of {area}: {viewport:?} against {:?}", (x, y));
        }
    }
    // No near plane: a point a hair in front of the light stays inside the depth range; one
    // behind the face's plane is outside its pyramid.
    let near = face_clip(Vec3::new(1e-6, 0.0, 0.0), 0);
    assert!(near.z >= 0.0 && near.z <= near.w);
    let behind = face_clip(Vec3::new(-1e-3, 0.0, 0.0), 0);
    assert!(behind.w < 0.0 && behind.z < 0.0);
}

#[test]
fn every_face_is_an_orthonormal_frame_looking_along_its_axis() {
    for f in 0..FACES {
        let (r, u, fw) = face_axes(f);
        assert!(r.dot(u).abs() < 1e-6 && r.dot(fw).abs() < 1e-6 && u.dot(fw).abs() < 1e-6);
        assert_eq!(cube_face(fw), f, "face {f}'s forward belongs to it");
    }
}

/// A light 3 above an infinite floor, a square occluder of half-size 1 at height 1.5: the floor's
/// umbra is the square scaled by 3 / 1.5 = 2 (|x|, |z| ≤ 2). The lookup leaves the floor lit
/// everywhere outside it (no self-shadowing) as far as the light's `n·l` is not grazing, and
/// unlit well inside it; the same for both filters.
#[test]
fn a_square_shadows_exactly_its_projection_on_a_floor() {
    let light = Vec3::new(0.0, 3.0, 0.0);
    let map = cube_map(light, |o, d| plane_y(o, d, 0.0).min(square_y(o, d, 1.5, 1.0)));
    let up = Vec3::Y;
    for filter in [SHADOW_FILTER_NEAREST, SHADOW_FILTER_BILINEAR] {
        let (mut lit, mut dark) = (0, 0);
        for i in 0..=160 {
            for k in 0..=160 {
                let p = Vec3::new(-8.0 + 0.1 * i as f32, 0.0, -8.0 + 0.1 * k as f32);
                let v = cube_visibility(&map, &uniform_slots(RES, filter, &[0]), 0, filter, light, &CubeFrame::VIEW, p, up);
                // The edge band: texels of the occluder's edge seen from the light, plus the
                // bias rule's offset (module docs), both a few texels at the floor.
                let texel = 2.0 * (light - p).length() / RES as f32;
                let band = 4.0 * texel;
                let inside = p.x.abs().max(p.z.abs());
                let n_dot_l = up.dot((light - p).normalize());
                if inside > 2.0 + band && n_dot_l > 0.3 {
                    assert_eq!(v, 1.0, "filter {filter}: floor at {p} shadows itself");
                    lit += 1;
                } else if inside < 2.0 - band {
                    assert_eq!(v, 0.0, "filter {filter}: {p} in the umbra is lit");
                    dark += 1;
                }
            }
        }
        assert!(lit > 10_000 && dark > 800, "{lit} lit and {dark} dark points checked");
    }
}

/// Receivers of every orientation facing the light: a plane through a random point, tilted
/// anywhere up to 75° from the light's direction, never shadows itself.
#[test]
fn tilted_planes_do_not_shadow_themselves() {
    let mut rng = Rng(11);
    for _ in 0..2000 {
        let light = Vec3::new(range(&mut rng, -1.0, 1.0), range(&mut rng, -1.0, 1.0), range(&mut rng, -1.0, 1.0));
        let p = light + Vec3::new(range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0));
        let to_light = (light - p).normalize();
        // A normal at most 75° from the light's direction.
        let side = to_light.any_orthonormal_vector();
        let angle = range(&mut rng, 0.0, 75f32.to_radians());
        let n = (to_light * angle.cos() + side * angle.sin()).normalize();
        let map = cube_map(light, |o, d| {
            let denom = d.dot(n);
            let t = (p - o).dot(n) / denom;
            if t > 0.0 && t.is_finite() {
                t
            } else {
                f32::INFINITY
            }
        });
        for filter in [SHADOW_FILTER_NEAREST, SHADOW_FILTER_BILINEAR] {
            let v = cube_visibility(&map, &uniform_slots(RES, filter, &[0]), 0, filter, light, &CubeFrame::VIEW, p, n);
            assert_eq!(v, 1.0, "a plane {:.0}° from the light at distance {:.2} shadows itself (filter {filter})", angle.to_degrees(), (light - p).length());
        }
    }
}

#[test]
fn lights_without_a_slot_and_no_shadows_reach_everything() {
    let slots = uniform_slots(16, SHADOW_FILTER_NEAREST, &[NO_SHADOW, 0]);
    // Slot 0's map says "occluded right at the light" everywhere.
    let maps = vec![0f32.to_bits(); (FACES * 16 * 16) as usize];
    let s = CubeShadows { slots: &slots, maps: &maps };
    let (light, p, n) = (Vec3::ZERO, Vec3::new(0.0, -2.0, 0.0), Vec3::Y);
    assert_eq!(s.visibility(0, light, Vec3::ZERO, NO_CONE, p, n), 1.0, "light 0 casts no shadow");
    assert_eq!(s.visibility(1, light, Vec3::ZERO, NO_CONE, p, n), 0.0, "light 1's map occludes");
    assert_eq!(NoShadows.visibility(1, light, Vec3::ZERO, NO_CONE, p, n), 1.0);
}

/// The bilinear filter weighs the four texels around the lookup: half-way across a shadow edge
/// it gives ½, and it varies monotonically across it.
#[test]
fn the_bilinear_filter_blends_across_an_edge() {
    let light = Vec3::new(0.0, 3.0, 0.0);
    // A half-plane occluder x ≤ 0 at height 1.5: the floor's shadow edge is x = 0.
    let map = cube_map(light, |o, d| {
        let t = plane_y(o, d, 1.5);
        if t.is_finite() && (o + d * t).x <= 0.0 {
            t
        } else {
            plane_y(o, d, 0.0)
        }
    });
    let mut last = 0.0;
    let mut partial = 0;
    for i in 0..=200 {
        let p = Vec3::new(-0.5 + 0.005 * i as f32, 0.0, 0.3);
        let v = cube_visibility(&map, &uniform_slots(RES, SHADOW_FILTER_BILINEAR, &[0]), 0, SHADOW_FILTER_BILINEAR, light, &CubeFrame::VIEW, p, Vec3::Y);
        assert!(v >= last - 1e-6, "visibility falls from {last} to {v} at {p}");
        partial += usize::from(v > 0.0 && v < 1.0);
        last = v;
    }
    assert_eq!(last, 1.0);
    assert!(partial >= 5, "{partial} points in the filtered edge");
}

/// Faces of different sides in one atlas: each lookup reads its own face at its own side, the
/// same as a map of that side alone; a face without texels lets the light through where the
/// receiver lies in it, and is replaced by the receiver's face where only the offset reaches it.
#[test]
fn faces_of_different_sides_look_up_their_own_texels() {
    let light = Vec3::new(0.0, 3.0, 0.0);
    let hit = |o: Vec3, d: Vec3| square_y(o, d, 1.5, 0.5).min(plane_y(o, d, 0.0));
    let sides = [16u32, 8, 32, 64, 16, 8];
    // The atlas: face f of side sides[f], one after another; and each side's uniform map.
    let mut atlas = vec![];
    let mut slots = vec![64, SHADOW_FILTER_NEAREST, SHADOW_HEADER_WORDS + 1, 0, 0];
    for (f, &side) in sides.iter().enumerate() {
        let whole = cube_map_of(light, side, &hit);
        slots.extend([atlas.len() as u32, side]);
        atlas.extend_from_slice(&whole[f * (side * side) as usize..(f + 1) * (side * side) as usize]);
    }
    let mut rng = Rng(3);
    for _ in 0..2_000 {
        let p = Vec3::new(range(&mut rng, -4.0, 4.0), 0.0, range(&mut rng, -4.0, 4.0));
        let got = cube_visibility(&atlas, &slots, 0, SHADOW_FILTER_NEAREST, light, &CubeFrame::VIEW, p, Vec3::Y);
        let at = cube_face(p - light);
        let side = sides[at as usize];
        let want = cube_visibility(&cube_map_of(light, side, &hit), &uniform_slots(side, SHADOW_FILTER_NEAREST, &[0]), 0, SHADOW_FILTER_NEAREST, light, &CubeFrame::VIEW, p, Vec3::Y);
        // Near a seam the offset may cross into a face of another side: skip those points.
        let texel = 2.0 * (light - p).length() / side as f32;
        if cube_face(p + Vec3::Y * (NORMAL_OFFSET_TEXELS * texel) - light) == at {
            assert_eq!(got, want, "{p} on face {at} of side {side}");
        }
    }
    // Face 3 (−y, towards the floor) without texels: the floor below the light is lit.
    let mut bare = slots.clone();
    let w = (SHADOW_HEADER_WORDS + 1 + 3 * FACE_WORDS) as usize;
    bare[w + 1] = 0;
    assert_eq!(cube_visibility(&atlas, &bare, 0, SHADOW_FILTER_NEAREST, light, &CubeFrame::VIEW, Vec3::new(0.1, 0.0, 0.1), Vec3::Y), 1.0);
    assert_eq!(cube_visibility(&atlas, &slots, 0, SHADOW_FILTER_NEAREST, light, &CubeFrame::VIEW, Vec3::new(0.1, 0.0, 0.1), Vec3::Y), 0.0, "under the square");
}

/// A spot light's cube frame: orthonormal and right-handed for axes all over the sphere (the
/// poles and the basis's seam at `z = 0` included); a cone of at most 42° about the centre of
/// face 4, which alone holds it widened up to 45° (`shadow_receivers::cone_faces`); a wider one
/// about the corner `(1, 1, 1)/√3`, whose three faces hold it up to `acos(1/3)` ≈ 70.5°; a point light keeps view
/// space's axes.
#[test]
fn a_spot_lights_cube_is_turned_to_its_cone() {
    use crate::shadow_receivers::cone_faces;
    let corner = Vec3::ONE / 3.0f32.sqrt();
    let mut rng = Rng(0x5eed_f4ce);
    let mut axes: Vec<Vec3> = (0..2000).map(|_| Vec3::new(range(&mut rng, -1.0, 1.0), range(&mut rng, -1.0, 1.0), range(&mut rng, -1.0, 1.0))).filter(|v| v.length() > 0.1).map(Vec3::normalize).collect();
    axes.extend([Vec3::Z, -Vec3::Z, Vec3::X, -Vec3::Y, Vec3::new(0.6, 0.8, 0.0), Vec3::new(0.0, 0.0, -1.0 + 1e-7).normalize()]);
    for axis in axes {
        for (outer_deg, centre, faces) in [(20.0f32, Vec3::Z, 1u32 << 4), (42.0, Vec3::Z, 1 << 4), (43.0, corner, 0b01_0101), (60.0, corner, 0b01_0101)] {
            let outer = outer_deg.to_radians();
            let f = CubeFrame::of_cone(axis, outer.cos());
            for (a, b) in [(f.x, f.y), (f.y, f.z), (f.x, f.z)] {
                assert!(a.dot(b).abs() < 1e-5, "{axis:?}: rows not orthogonal");
            }
            for r in [f.x, f.y, f.z] {
                assert!((r.length() - 1.0).abs() < 1e-5, "{axis:?}: a row of length {}", r.length());
            }
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5, "{axis:?}: left-handed");
            let local = f.local(axis);
            assert!((local - centre).length() < 1e-5, "{axis:?} at {outer_deg}°: the axis lands at {local:?}");
            // Widened to just short of what the faces hold: 45° for one face, acos(1/3) for three.
            let widened = if outer_deg <= 42.0 { 44.9f32.to_radians() } else { (1.0f32 / 3.0).acos() - 1e-3 };
            assert_eq!(cone_faces(local, widened), faces, "{axis:?}, {outer_deg}° widened to {}°", widened.to_degrees());
        }
    }
    assert_eq!(CubeFrame::of_cone(Vec3::ZERO, NO_CONE), CubeFrame::VIEW);
    assert_eq!(CubeFrame::of_cone(Vec3::new(0.0, 0.0, -1.0), crate::light_types::POINT_MARKER), CubeFrame::VIEW, "the light buffer's point marker");
}
