//! Scenes the project builds itself, deterministically (a fixed-seed [`Pcg32`]), in metres.
//!
//! * [`city`]: a 24 × 24 grid of blocks, each split into 2 × 2 box buildings 2–40 m tall, 8 m
//!   streets between, a ground plane; the camera stands at eye height at the end of the central
//!   avenue looking down it (near 0.1, far 1000): a deep depth range, where screen tiles alone
//!   degrade because one tile spans buildings from 1 m to 500 m away.
//! * [`corridor`]: a 120 m corridor (floor, walls, ceiling, end walls, pillars and beams every
//!   6 m), the camera at one end looking down it.
//! * [`glass`]: the city with coloured glass panes of six transparent materials: shop windows
//!   before the facades along the central avenue, panes across it over the crossings, and a
//!   stack of [`GLASS_STACK_PANES`] parallel panes in it that puts that many transparent layers
//!   (twice as many surfaces) on the pixels looking through it (view `glass@stack`).
//! * [`nurbs`]: curved surfaces for the tessellation pass: the exact sphere, the exact torus and
//!   the 32-patch bicubic teapot of [`super::nurbs`] on a floor, the camera in front of them.
//!
//! Boxes have 24 vertices (flat normals per face) and counter-clockwise front faces seen from
//! outside (right-handed, y up); uvs are face-local metres.
use super::lights::Pcg32;
use super::nurbs::{self as patches, ScenePatch};
use super::{Camera, Material, Mesh, Scene};
use glam::Vec3;

/// The built-in scenes this module makes.
pub const NAMES: [&str; 4] = ["city", "corridor", "glass", "nurbs"];

/// An axis-aligned box, (min, max).
pub type BoxBounds = (Vec3, Vec3);

/// The six faces as (outward normal, u, v) with `u × v = normal`: corners listed
/// (−u−v, +u−v, +u+v, −u+v) are then counter-clockwise seen from outside.
const FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
];

/// Appends a box (24 vertices, 12 triangles) to `mesh`.
pub fn push_box(mesh: &mut Mesh, (min, max): BoxBounds) {
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    for (n, u, v) in FACES {
        let base = mesh.positions.len() as u32;
        let (hu, hv) = ((u * h).length(), (v * h).length());
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            mesh.positions.push((c + n * h + u * h * s + v * h * t).to_array());
            mesh.normals.push(n.to_array());
            mesh.uvs.push([(s + 1.0) * hu, (1.0 - t) * hv]);
        }
        mesh.indices.extend([0, 1, 2, 0, 2, 3].map(|k| base + k));
    }
}

/// Appends an upward-facing rectangle at height `y` (4 vertices, 2 triangles).
pub fn push_ground(mesh: &mut Mesh, min: [f32; 2], max: [f32; 2], y: f32) {
    let base = mesh.positions.len() as u32;
    // (x, z) corners counter-clockwise seen from above: −x+z, +x+z, +x−z, −x−z.
    for (x, z) in [(min[0], max[1]), (max[0], max[1]), (max[0], min[1]), (min[0], min[1])] {
        mesh.positions.push([x, y, z]);
        mesh.normals.push([0.0, 1.0, 0.0]);
        mesh.uvs.push([x - min[0], z - min[1]]);
    }
    mesh.indices.extend([0, 1, 2, 0, 2, 3].map(|k| base + k));
}

fn material(name: &str, albedo: [f32; 3], specular: f32, roughness: f32) -> Material {
    Material { specular, roughness, ..Material::diffuse(name, albedo) }
}

/// One mesh per material, boxes appended to the mesh of their material; empty meshes dropped.
fn meshes_from(materials: usize, boxes: &[(BoxBounds, u32)]) -> Vec<Mesh> {
    let mut meshes: Vec<Mesh> = (0..materials as u32).map(|material| Mesh { material, ..Mesh::default() }).collect();
    for &(b, m) in boxes {
        push_box(&mut meshes[m as usize], b);
    }
    meshes
}

/// Blocks per side of the city grid.
pub const CITY_BLOCKS: usize = 24;
/// Block edge and street width (m).
pub const CITY_BLOCK: f32 = 14.0;
pub const CITY_STREET: f32 = 8.0;

/// The city's buildings as (box, material), in a fixed order.
pub fn city_buildings() -> Vec<(BoxBounds, u32)> {
    let mut rng = Pcg32::new(0xC17E);
    let pitch = CITY_BLOCK + CITY_STREET;
    let x0 = -(CITY_BLOCKS as f32 * pitch - CITY_STREET) * 0.5;
    let lot = (CITY_BLOCK - 1.0) * 0.5; // 2 × 2 lots per block, 1 m apart
    let mut out = Vec::with_capacity(CITY_BLOCKS * CITY_BLOCKS * 4);
    for bz in 0..CITY_BLOCKS {
        for bx in 0..CITY_BLOCKS {
            for (lx, lz) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let x = x0 + bx as f32 * pitch + lx as f32 * (lot + 1.0);
                let z = x0 + bz as f32 * pitch + lz as f32 * (lot + 1.0);
                let u = rng.f32();
                let height = 2.0 + 38.0 * u * u; // mostly low, a few towers
                let inset = rng.range(0.0, 0.8); // ragged street fronts
                let material = 1 + rng.next_u32() % 5;
                out.push(((Vec3::new(x + inset, 0.0, z + inset), Vec3::new(x + lot - inset, height, z + lot - inset)), material));
            }
        }
    }
    out
}

/// The city (see the module docs): 2304 buildings, 6 materials (2 with specular).
pub fn city() -> Scene {
    let materials = vec![
        material("asphalt", [0.20, 0.20, 0.22], 0.0, 1.0),
        material("concrete", [0.60, 0.58, 0.55], 0.0, 1.0),
        material("brick", [0.55, 0.25, 0.18], 0.0, 1.0),
        material("sandstone", [0.76, 0.66, 0.48], 0.0, 1.0),
        material("glass", [0.30, 0.40, 0.50], 0.6, 0.15),
        material("metal", [0.55, 0.56, 0.58], 0.8, 0.35),
    ];
    let mut meshes = meshes_from(materials.len(), &city_buildings());
    let half = (CITY_BLOCKS as f32 * (CITY_BLOCK + CITY_STREET) - CITY_STREET) * 0.5;
    let edge = half + 20.0;
    push_ground(&mut meshes[0], [-edge, -edge], [edge, edge], 0.0);
    // The central avenue runs along z at x = 0 (between blocks 11 and 12).
    let camera = Camera {
        position: Vec3::new(0.0, 1.7, half + 10.0),
        target: Vec3::new(0.0, 3.0, -half),
        up: Vec3::Y,
        fov_y_degrees: 60.0,
        near: 0.1,
        far: 1000.0,
    };
    Scene::new("city", meshes, materials, vec![], camera)
}

/// The transparent materials of [`glass`]: (name, albedo, opacity), all with specular 0.5 and
/// roughness 0.1. (The city's own `glass` is an opaque facade material.)
pub const GLASS_PANES: [(&str, [f32; 3], f32); 6] = [
    ("pane red", [0.85, 0.15, 0.12], 0.35),
    ("pane amber", [0.95, 0.60, 0.10], 0.5),
    ("pane green", [0.20, 0.75, 0.30], 0.3),
    ("pane blue", [0.15, 0.35, 0.90], 0.45),
    ("pane clear", [0.90, 0.95, 1.00], 0.12),
    ("pane smoke", [0.25, 0.25, 0.28], 0.7),
];
/// Panes in the stack of [`glass`]: 0.02 m thick, 0.35 m apart, 6 × 6 m, across the central
/// avenue from z = 240 towards −z (the camera's side is +z).
pub const GLASS_STACK_PANES: usize = 24;
/// View `glass@stack` as (position, target, near, far): from the avenue's left half, through the
/// whole stack at a slant onto the facade of a 26 m building behind it.
pub const GLASS_STACK_VIEW: (Vec3, Vec3, f32, f32) = (Vec3::new(-2.2, 2.6, 246.0), Vec3::new(4.21, 2.0, 205.0), 0.1, 1000.0);

/// The panes of [`glass`] as (box, index into [`GLASS_PANES`]), in a fixed order: the stack,
/// the panes across the avenue, then the shop windows (0.3 m before each facade that faces the
/// avenue, up to 8 m high).
pub fn glass_panes() -> Vec<(BoxBounds, u32)> {
    let colours = GLASS_PANES.len() as u32;
    let b = |min: [f32; 3], max: [f32; 3]| (Vec3::from_array(min), Vec3::from_array(max));
    let mut panes = Vec::new();
    for k in 0..GLASS_STACK_PANES {
        let z = 240.0 - 0.35 * k as f32;
        panes.push((b([-3.0, 0.5, z - 0.01], [3.0, 6.5, z + 0.01]), k as u32 % colours));
    }
    // Over every second crossing of the avenue (the cross streets run at z = 194..202 − 44 j).
    for j in 0..10u32 {
        let z = 200.0 - 44.0 * j as f32;
        let y = 5.0 + 3.0 * (j % 3) as f32;
        let height = 4.0 + 2.0 * (j % 2) as f32;
        panes.push((b([-3.9, y, z - 0.025], [3.9, y + height, z + 0.025]), (j + 1) % colours));
    }
    // The avenue's building lines are x = ±4 (plus each lot's inset).
    for (k, ((lo, hi), _)) in city_buildings().into_iter().enumerate() {
        let (top, colour) = ((hi.y - 0.3).min(8.0), k as u32 % colours);
        if (4.0..5.0).contains(&lo.x) {
            panes.push((b([lo.x - 0.32, 0.3, lo.z + 0.4], [lo.x - 0.3, top, hi.z - 0.4]), colour));
        } else if (-5.0..=-4.0).contains(&hi.x) {
            panes.push((b([hi.x + 0.3, 0.3, lo.z + 0.4], [hi.x + 0.32, top, hi.z - 0.4]), colour));
        }
    }
    panes
}

/// The glass city (see the module docs): [`city`]'s geometry and materials, then the
/// [`GLASS_PANES`] materials with one mesh each. Camera: above the end of the central avenue,
/// looking down it over the stack (near 0.1, far 1000).
pub fn glass() -> Scene {
    let city = city();
    let first = city.materials.len() as u32;
    let mut materials = city.materials;
    materials.extend(GLASS_PANES.iter().map(|&(name, albedo, opacity)| Material { opacity, ..material(name, albedo, 0.5, 0.1) }));
    let mut meshes = city.meshes;
    meshes.extend(meshes_from(GLASS_PANES.len(), &glass_panes()).into_iter().map(|m| Mesh { material: m.material + first, ..m }));
    let camera = Camera { position: Vec3::new(-1.5, 7.0, 262.0), target: Vec3::new(1.0, 3.0, 190.0), ..city.camera };
    Scene::new("glass", meshes, materials, vec![], camera)
}

/// The NURBS scene (see the module docs): a 24 × 18 m floor, the teapot (3.15 m tall) at the
/// origin with its spout toward +x, the sphere (radius 1.3) to its left, the torus (radii 1.4 and
/// 0.45) lying on the floor to its right; 4 materials (3 with specular). Camera: 10.5 m in front,
/// 4.5 m up, looking at the teapot's middle (near 0.1, far 100).
pub fn nurbs() -> Scene {
    let materials = vec![
        material("floor", [0.45, 0.45, 0.42], 0.0, 1.0),
        material("porcelain", [0.85, 0.85, 0.80], 0.5, 0.3),
        material("red lacquer", [0.80, 0.18, 0.12], 0.3, 0.4),
        material("gold", [0.90, 0.65, 0.20], 0.8, 0.25),
    ];
    let mut floor = Mesh::default();
    push_ground(&mut floor, [-12.0, -8.0], [12.0, 10.0], 0.0);
    let camera = Camera { position: Vec3::new(0.0, 4.5, 11.0), target: Vec3::new(0.0, 1.2, 0.5), up: Vec3::Y, fov_y_degrees: 60.0, near: 0.1, far: 100.0 };
    let mut scene = Scene::new("nurbs", vec![floor], materials, vec![], camera);
    let patch = |name: String, patch: patches::NurbsPatch, material: u32| ScenePatch { name, patch: patches::NurbsPatch { material, ..patch }, level: None };
    let mut all = vec![
        patch("sphere".into(), patches::sphere(Vec3::new(-6.0, 1.3, 1.5), 1.3), 2),
        patch("torus".into(), patches::torus(Vec3::new(6.0, 0.45, 1.5), 1.4, 0.45), 3),
    ];
    all.extend(patches::teapot().into_iter().enumerate().map(|(k, p)| patch(format!("teapot[{k}]"), p, 1)));
    scene.add_nurbs(all);
    scene
}

/// Corridor length, width and height (m); pillars every [`CORRIDOR_BAY`] m.
pub const CORRIDOR_LENGTH: f32 = 120.0;
pub const CORRIDOR_WIDTH: f32 = 6.0;
pub const CORRIDOR_HEIGHT: f32 = 4.0;
pub const CORRIDOR_BAY: f32 = 6.0;

/// The corridor's parts as (box, material): the corridor runs from z = 0 to z = −length.
pub fn corridor_parts() -> Vec<(BoxBounds, u32)> {
    let (l, w, h, t) = (CORRIDOR_LENGTH, CORRIDOR_WIDTH * 0.5, CORRIDOR_HEIGHT, 0.2);
    let b = |min: [f32; 3], max: [f32; 3]| (Vec3::from_array(min), Vec3::from_array(max));
    let mut parts = vec![
        (b([-w - t, -t, -l - t], [w + t, 0.0, t]), 0),   // floor
        (b([-w - t, h, -l - t], [w + t, h + t, t]), 2),  // ceiling
        (b([-w - t, 0.0, -l], [-w, h, 0.0]), 1),         // left wall
        (b([w, 0.0, -l], [w + t, h, 0.0]), 1),           // right wall
        (b([-w - t, 0.0, -l - t], [w + t, h, -l]), 1),   // far end
        (b([-w - t, 0.0, 0.0], [w + t, h, t]), 1),       // near end, behind the camera
    ];
    let mut z = -CORRIDOR_BAY;
    while z > -l + 1.0 {
        parts.push((b([-w, 0.0, z - 0.3], [-w + 0.6, h, z + 0.3]), 3));
        parts.push((b([w - 0.6, 0.0, z - 0.3], [w, h, z + 0.3]), 3));
        parts.push((b([-w, h - 0.4, z - 0.2], [w, h, z + 0.2]), 4));
        z -= CORRIDOR_BAY;
    }
    parts
}

/// The corridor (see the module docs): 5 materials (floor and pillars with specular).
pub fn corridor() -> Scene {
    let materials = vec![
        material("floor tiles", [0.50, 0.45, 0.40], 0.3, 0.3),
        material("plaster", [0.75, 0.72, 0.68], 0.0, 1.0),
        material("ceiling", [0.80, 0.80, 0.80], 0.0, 1.0),
        material("marble", [0.85, 0.83, 0.80], 0.5, 0.2),
        material("wood", [0.40, 0.26, 0.13], 0.0, 1.0),
    ];
    let meshes = meshes_from(materials.len(), &corridor_parts());
    let camera = Camera {
        position: Vec3::new(0.0, 1.6, -1.0),
        target: Vec3::new(0.3, 1.5, -CORRIDOR_LENGTH),
        up: Vec3::Y,
        fov_y_degrees: 60.0,
        near: 0.1,
        far: 200.0,
    };
    Scene::new("corridor", meshes, materials, vec![], camera)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's geometric (CCW) normal agrees with its vertex normals.
    fn assert_ccw(scene: &Scene) {
        for (m, mesh) in scene.meshes.iter().enumerate() {
            for t in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(t);
                let n = (b - a).cross(c - a);
                assert!(n.length() > 0.0, "mesh {m} triangle {t} is degenerate");
                for &i in &mesh.indices[3 * t..3 * t + 3] {
                    assert!(n.dot(Vec3::from_array(mesh.normals[i as usize])) > 0.0, "mesh {m} triangle {t} winds clockwise");
                }
            }
        }
    }

    fn assert_finite(scene: &Scene) {
        scene.validate().unwrap();
        for mesh in &scene.meshes {
            assert!(mesh.positions.iter().chain(&mesh.normals).flatten().all(|v| v.is_finite()));
            assert!(mesh.uvs.iter().flatten().all(|v| v.is_finite()));
            assert!(mesh.normals.iter().all(|n| (Vec3::from_array(*n).length() - 1.0).abs() < 1e-5));
        }
    }

    #[test]
    fn boxes_face_outwards() {
        for (lo, hi) in [(Vec3::ZERO, Vec3::ONE), (Vec3::new(-3.0, 2.0, -40.0), Vec3::new(-1.0, 2.5, 7.0))] {
            let mut mesh = Mesh::default();
            push_box(&mut mesh, (lo, hi));
            assert_eq!((mesh.positions.len(), mesh.indices.len()), (24, 36));
            let centre = (lo + hi) * 0.5;
            for t in 0..12 {
                let [a, b, c] = mesh.triangle(t);
                let n = (b - a).cross(c - a);
                assert!(n.dot((a + b + c) / 3.0 - centre) > 0.0, "triangle {t} faces inwards");
            }
            assert!(mesh.positions.iter().all(|p| Vec3::from_array(*p).cmpge(lo).all() && Vec3::from_array(*p).cmple(hi).all()));
        }
    }

    #[test]
    fn every_city_and_corridor_box_faces_outwards() {
        for parts in [city_buildings(), corridor_parts()] {
            for (k, &(b, _)) in parts.iter().enumerate() {
                let mut mesh = Mesh::default();
                push_box(&mut mesh, b);
                let centre = (b.0 + b.1) * 0.5;
                for t in 0..12 {
                    let [p, q, r] = mesh.triangle(t);
                    assert!((q - p).cross(r - p).dot((p + q + r) / 3.0 - centre) > 0.0, "box {k} triangle {t}");
                }
            }
        }
    }

    #[test]
    fn city_is_deterministic_finite_and_deep() {
        let (a, b) = (city(), city());
        assert_eq!(a.meshes, b.meshes, "two loads give the same triangles");
        assert_eq!(a.triangle_count(), CITY_BLOCKS * CITY_BLOCKS * 4 * 12 + 2);
        assert_finite(&a);
        assert_ccw(&a);
        let (lo, hi) = a.bounds;
        assert!(lo.y == 0.0 && hi.y > 30.0 && hi.y <= 40.0, "{lo} {hi}");
        assert!(hi.x - lo.x > 500.0 && hi.z - lo.z > 500.0, "{lo} {hi}");
        let heights: Vec<f32> = city_buildings().iter().map(|(b, _)| b.1.y).collect();
        assert!(heights.iter().all(|&h| (2.0..=40.0).contains(&h)));
        assert!(heights.iter().any(|&h| h > 30.0) && heights.iter().filter(|&&h| h < 10.0).count() > heights.len() / 3);
        let c = a.camera;
        assert!(c.position.y < 2.0 && c.near == 0.1 && c.far >= 1000.0);
        assert!(c.target.distance(c.position) > 500.0, "looks down a long avenue");
        // The camera stands in the street: no building contains it or the avenue's axis.
        assert!(city_buildings().iter().all(|(b, _)| b.0.x > 1.0 || b.1.x < -1.0));
        assert!(a.effects.specular && !a.effects.textures && !a.effects.alpha_test);
        assert_eq!(a.effects.flags(), shaders::layout::EFFECT_SPECULAR);
    }

    #[test]
    fn nurbs_scene_holds_the_three_shapes_in_view() {
        let a = nurbs();
        assert_finite(&a);
        assert_ccw(&a);
        assert_eq!(a.nurbs.len(), 2 + 32, "sphere, torus and the teapot's 32 patches");
        assert!(a.nurbs.iter().all(|p| p.level.is_none() && p.level() == patches::DEFAULT_TESS_LEVEL));
        let (lo, hi) = a.bounds;
        // The sphere's control points reach x = −7.3, the torus's x = 7.85; the floor is wider.
        assert!(lo.x == -12.0 && hi.x == 12.0 && lo.y == 0.0 && hi.y >= 3.15, "{lo} {hi}");
        // Every control point lies inside the camera's view at 16:9 (so every surface does).
        let c = a.camera;
        let view = crate::render::ViewTransform::look_at(c.position.as_dvec3(), c.target.as_dvec3(), c.up.as_dvec3());
        let t = (0.5 * c.fov_y_degrees).to_radians().tan();
        for p in a.nurbs.iter().flat_map(|p| &p.patch.control_points) {
            let q = view.to_view(*p);
            assert!(-q.z > c.near && q.y.abs() < -q.z * t && q.x.abs() < -q.z * t * 16.0 / 9.0, "{p:?} is outside the view");
        }
        assert!(a.effects.specular);
    }

    #[test]
    fn corridor_is_deterministic_finite_and_closed() {
        let (a, b) = (corridor(), corridor());
        assert_eq!(a.meshes, b.meshes);
        assert_finite(&a);
        assert_ccw(&a);
        let (lo, hi) = a.bounds;
        assert!(hi.z - lo.z > CORRIDOR_LENGTH && hi.y > CORRIDOR_HEIGHT && lo.y < 0.0, "{lo} {hi}");
        let p = a.camera.position;
        assert!(p.cmpgt(lo).all() && p.cmplt(hi).all() && p.x.abs() < 1.0 && p.y > 0.5 && p.y < CORRIDOR_HEIGHT);
        assert!(a.triangle_count() > 100);
        a.camera.validate().unwrap();
    }
}
