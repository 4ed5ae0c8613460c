use super::*;
use crate::shadow::{cube_face, CASTER_WORDS, NO_CONE, SHADOW_HEADER_WORDS};
use crate::test_support::Rng;

/// The batch words (`BATCH_WORDS` each) of `n_tris` triangles stored corner after corner in
/// `positions` and indexed in order: batches of [`BATCH_TRIANGLES`], each bounded by its box's
/// sphere, the last one partial.
pub(crate) fn batch_words(positions: &[f32], n_tris: u32) -> Vec<u32> {
    let mut batches = vec![];
    for first in (0..n_tris).step_by(BATCH_TRIANGLES as usize) {
        let count = BATCH_TRIANGLES.min(n_tris - first);
        let pts: Vec<Vec3> = (3 * first..3 * (first + count)).map(|i| crate::raster::fetch3(positions, i as usize)).collect();
        let (lo, hi) = pts.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        batches.extend_from_slice(&[c.x.to_bits(), c.y.to_bits(), c.z.to_bits(), r.to_bits(), 3 * first, count, 0, 0]);
    }
    batches
}

fn range(rng: &mut Rng, a: f32, b: f32) -> f32 {
    a + (b - a) * rng.unit()
}

fn random_in_ball(rng: &mut Rng, r: f32) -> Vec3 {
    loop {
        let p = Vec3::new(range(rng, -1.0, 1.0), range(rng, -1.0, 1.0), range(rng, -1.0, 1.0));
        if p.length_squared() <= 1.0 {
            return p * r;
        }
    }
}

/// Every point of a sphere within the light's radius lies in a face the mask holds
/// (conservative), on random spheres and lights.
#[test]
fn the_face_mask_holds_every_face_the_sphere_reaches() {
    let mut rng = Rng(3);
    let mut partial = 0;
    for _ in 0..3000 {
        let d = Vec3::new(range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0));
        let (r, radius) = (range(&mut rng, 0.05, 2.0), range(&mut rng, 0.5, 8.0));
        let mask = face_mask(d, r, radius);
        partial += usize::from(mask != 0 && mask != 63);
        for _ in 0..200 {
            let p = d + random_in_ball(&mut rng, r);
            if p.length() <= radius && p.length() > 1e-6 {
                let f = cube_face(p);
                assert!(mask & (1 << f) != 0, "sphere at {d} (r {r}, light radius {radius}): {p} on face {f} outside mask {mask:06b}");
            }
        }
    }
    assert!(partial > 500, "{partial} spheres met some faces but not all");
}

/// Closed cases: beyond the radius none; holding the light all six; far along +x only face 0;
/// on the diagonal between +x and +y, both faces and no other.
#[test]
fn the_face_mask_in_closed_cases() {
    assert_eq!(face_mask(Vec3::new(10.0, 0.0, 0.0), 1.0, 8.0), 0);
    assert_eq!(face_mask(Vec3::new(10.0, 0.0, 0.0), 1.0, 9.5), 1);
    assert_eq!(face_mask(Vec3::new(0.3, 0.2, 0.0), 0.5, 1.0), 63);
    assert_eq!(face_mask(Vec3::new(0.0, 0.0, -5.0), 0.5, 10.0), 1 << 5);
    assert_eq!(face_mask(Vec3::new(3.0, 3.0, 0.0), 0.2, 10.0), 0b101);
}

/// A small scene in batches, culled for every caster, the entries drawn on the CPU: every
/// triangle corner a caster's face sees within its radius is drawn into that face by some entry
/// (the whole triangle pulled by `batch_vertex` matches the index buffer); tail triangles are
/// put behind the light; a capacity below the count writes that many and counts them all.
#[test]
fn culled_batches_draw_every_triangle_a_face_sees() {
    let mut rng = Rng(5);
    // Small triangles in clumps of 64 (a clump per batch, as a mesh's consecutive triangles are
    // near each other) across a 20-unit box: 12 batches, the last one partial.
    let n_tris = 12 * BATCH_TRIANGLES - 20;
    let mut positions = vec![];
    let mut clump = Vec3::ZERO;
    for t in 0..n_tris {
        if t % BATCH_TRIANGLES == 0 {
            clump = Vec3::new(range(&mut rng, -10.0, 10.0), range(&mut rng, -10.0, 10.0), range(&mut rng, -10.0, 10.0));
        }
        let c = clump + random_in_ball(&mut rng, 1.5);
        for _ in 0..3 {
            let p = c + random_in_ball(&mut rng, 0.6);
            positions.extend_from_slice(&[p.x, p.y, p.z]);
        }
    }
    let indices: Vec<u32> = (0..3 * n_tris).collect();
    let n_batches = n_tris.div_ceil(BATCH_TRIANGLES);
    let batches = batch_words(&positions, n_tris);
    // A rotation as the camera's view.
    let view = Mat4::from_rotation_y(0.7) * Mat4::from_rotation_x(-0.3);
    let lights: Vec<(Vec3, f32)> = (0..6).map(|_| (Vec3::new(range(&mut rng, -8.0, 8.0), range(&mut rng, -8.0, 8.0), range(&mut rng, -8.0, 8.0)), range(&mut rng, 2.0, 7.0))).collect();
    // Every other caster a spot light (cones of 20° to 80°, about random axes): its cube is
    // turned to its cone (`CubeFrame`), the cull's faces and the draw's with it.
    let cones: Vec<(Vec3, f32)> = (0..lights.len())
        .map(|l| match l % 2 {
            0 => (Vec3::ZERO, NO_CONE),
            _ => (random_in_ball(&mut rng, 1.0).normalize_or(Vec3::Y), range(&mut rng, 20.0, 80.0).to_radians().cos()),
        })
        .collect();
    let casters: Vec<f32> = lights.iter().zip(&cones).flat_map(|((p, r), (a, c))| [p.x, p.y, p.z, *r, a.x, a.y, a.z, *c]).collect();
    assert_eq!(casters.len() as u32, CASTER_WORDS * lights.len() as u32);
    // The face table: every face of 7 casters (one past the last) at 64² texels.
    const SIDE: u32 = 64;
    let slots: Vec<u32> = [vec![SIDE, 0, SHADOW_HEADER_WORDS, 0], (0..7 * FACES).flat_map(|m| [m * SIDE * SIDE, SIDE]).collect()].concat();
    let run_with = |capacity: u32, casters: &[f32]| {
        let p = ShadowCullParams { batches: n_batches, casters: lights.len() as u32, capacity, pad: 0 };
        let mut entries = vec![u32::MAX; (ENTRY_WORDS * capacity) as usize];
        let mut args = [0u32; ARGS_WORDS as usize];
        for c in 0..p.casters + 1 {
            for b in 0..n_batches + 3 {
                cull_batch(b, c, &p, view, &batches, casters, &slots, &mut entries, &mut args[ARGS_COUNTED]);
            }
        }
        draw_args(&mut args, capacity);
        (entries, args)
    };
    let run = |capacity: u32| run_with(capacity, &casters);
    let (entries, args) = run(10_000);
    // The same lights without cones send batches to more faces: the cone cull drops those
    // outside the spot lights' cones.
    let points: Vec<f32> = casters.chunks(CASTER_WORDS as usize).flat_map(|r| [r[0], r[1], r[2], r[3], 0.0, 0.0, 0.0, NO_CONE]).collect();
    let uncut = run_with(10_000, &points).1[ARGS_COUNTED];
    assert!(args[ARGS_COUNTED] < uncut, "{} entries with cones, {uncut} without", args[ARGS_COUNTED]);
    let counted = args[ARGS_COUNTED];
    assert!(counted > 10 && counted < 6 * n_batches * lights.len() as u32, "{counted} entries");
    assert_eq!(args[..4], [counted * 3 * BATCH_TRIANGLES, 1, 0, 0]);
    // Draw: (triangle, map) pairs the entries rasterise.
    let mut drawn = std::collections::HashSet::new();
    let mut culled = 0;
    for v in (0..args[0]).step_by(3) {
        let (clip, _, map, radius) = batch_vertex(v, &positions, &indices, view, &casters, &batches, &entries);
        let e = v / (3 * BATCH_TRIANGLES);
        let b = entries[(e * ENTRY_WORDS) as usize];
        let local = (v % (3 * BATCH_TRIANGLES)) / 3;
        let tri = b * BATCH_TRIANGLES + local;
        if local >= batches[(b * BATCH_WORDS + 5) as usize] {
            assert!(clip.w < 0.0, "tail vertex {v} not behind the light");
            continue;
        }
        // The triangle's three corners agree on whether it is culled (put behind the light with
        // radius 0; a kept triangle's corner may lie behind the face's plane too).
        let culled_at = |u: u32| {
            let (clip, _, _, radius) = batch_vertex(u, &positions, &indices, view, &casters, &batches, &entries);
            radius == 0.0 && clip == Vec4::new(0.0, 0.0, 0.0, -1.0)
        };
        let cull = culled_at(v);
        assert!(culled_at(v + 1) == cull && culled_at(v + 2) == cull, "triangle {tri}'s corners disagree on its cull");
        if cull {
            culled += 1;
            continue;
        }
        assert_eq!(radius, lights[(map / FACES) as usize].1);
        drawn.insert((tri, map));
    }
    let mut seen = 0;
    for t in 0..n_tris {
        for (l, &(light, radius)) in lights.iter().enumerate() {
            for k in 0..3 {
                let d = (view * crate::raster::fetch3(&positions, (3 * t + k) as usize).extend(1.0)).truncate() - light;
                // A spot light needs the corners inside its cone (a lookup outside it finds no
                // light to shadow).
                let in_cone = cones[l].1 < -1.0 || d.normalize().dot(cones[l].0) >= cones[l].1;
                if d.length() <= radius && in_cone {
                    seen += 1;
                    let map = l as u32 * FACES + cube_face(crate::shadow::CubeFrame::of_cone(cones[l].0, cones[l].1).local(d));
                    assert!(drawn.contains(&(t, map)), "triangle {t} corner {k} seen by face {map} is not drawn there");
                }
            }
        }
    }
    assert!(seen > 50, "{seen} corners seen");
    assert!(culled > drawn.len() / 4, "{culled} triangles culled, {} drawn: the per-triangle test culls next to nothing", drawn.len());
    // A capacity below the count: every entry counted, only the capacity's worth written.
    let (short, args) = run(counted / 2);
    assert_eq!(args[ARGS_COUNTED], counted);
    assert_eq!(args[0], counted / 2 * 3 * BATCH_TRIANGLES);
    assert!(short.iter().all(|&w| w != u32::MAX));
}

/// The per-triangle test never culls a triangle with a point inside the face's pyramid within the
/// radius (points sampled over random triangles), and culls ones wholly beyond the radius or
/// behind a side plane.
#[test]
fn the_triangle_test_keeps_every_triangle_that_reaches_the_face() {
    let mut rng = Rng(9);
    let (mut kept, mut culled) = (0, 0);
    for _ in 0..4000 {
        let c = Vec3::new(range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0), range(&mut rng, -6.0, 6.0));
        let s = range(&mut rng, 0.1, 4.0);
        let (d0, d1, d2) = (c + random_in_ball(&mut rng, s), c + random_in_ball(&mut rng, s), c + random_in_ball(&mut rng, s));
        let radius = range(&mut rng, 1.0, 6.0);
        for f in 0..FACES {
            let out = triangle_outside(d0, d1, d2, f, radius);
            if out {
                culled += 1;
            } else {
                kept += 1;
            }
            for _ in 0..60 {
                let (a, b) = (rng.unit(), rng.unit());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let p = d0 + (d1 - d0) * a + (d2 - d0) * b;
                if p.length() <= radius && p.length() > 1e-4 && cube_face(p) == f {
                    assert!(!out, "triangle {d0} {d1} {d2} culled from face {f} though {p} lies in it within radius {radius}");
                }
            }
        }
    }
    assert!(kept > 2000 && culled > 2000, "{kept} kept, {culled} culled");
}
