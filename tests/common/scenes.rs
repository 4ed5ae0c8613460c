//! Scenes and lights of the hard-case tests: the hard light cases, and what the
//! built-in scenes lack — degenerate and sliver triangles, geometry crossing the near plane, and
//! translations far from the world origin.
use glam::{DVec3, Vec3};
use host::scene::procedural::push_box;
use host::scene::{bounds_of, Mesh, Scene};
use shaders::layout::PointLight;

/// A light of warm white colour.
pub fn light(position: Vec3, radius: f32, intensity: f32) -> PointLight {
    PointLight { position: position.to_array(), radius, colour: [1.0, 0.9, 0.8], intensity }
}

/// The camera's orthonormal frame: (eye, forward, right, up).
pub fn camera_frame(scene: &Scene) -> (Vec3, Vec3, Vec3, Vec3) {
    let c = &scene.camera;
    let forward = (c.target - c.position).normalize();
    let right = forward.cross(c.up).normalize();
    (c.position, forward, right, right.cross(forward))
}

/// The hard light cases around `scene`'s camera, as (name, lights): the camera inside a light,
/// lights behind the camera, a light straddling the near plane, one beyond the far plane, radii
/// 0, ten times the scene and `1e30`, 2000 and 10 000 coincident lights (more than the first
/// light-list guesses), and no light.
pub fn hard_light_cases(scene: &Scene) -> Vec<(&'static str, Vec<PointLight>)> {
    let (eye, fwd, _, _) = camera_frame(scene);
    let at = |t: f32| eye + fwd * t;
    let diag = (scene.bounds.1 - scene.bounds.0).length();
    vec![
        ("camera inside a light", vec![light(eye, 30.0, 20.0)]),
        ("lights behind the camera", (0..50).map(|i| light(at(-5.0), 2.0 + i as f32 * 0.1, 20.0)).collect()),
        ("straddling the near plane", vec![light(at(scene.camera.near), 3.0, 20.0)]),
        ("beyond the far plane", vec![light(at(scene.camera.far * 1.5), scene.camera.far, 20.0)]),
        ("zero radius", vec![light(at(10.0), 0.0, 20.0), light(at(20.0), 0.0, 20.0)]),
        ("radius larger than the scene", vec![light(at(30.0), 10.0 * diag, 20.0)]),
        ("radius 1e30", vec![light(at(30.0), 1e30, 20.0)]),
        ("all lights at one point", (0..2000).map(|_| light(at(25.0), 15.0, 20.0)).collect()),
        ("10k lights at one point", (0..10_000).map(|_| light(at(40.0), 4.0, 20.0)).collect()),
        ("zero lights", vec![]),
    ]
}

/// `scene` and `lights` with every world position (vertices, lights, the camera's position and
/// target) replaced by `f` of it; bounds recomputed.
fn map_positions(scene: &Scene, lights: &[PointLight], f: impl Fn([f32; 3]) -> [f32; 3]) -> (Scene, Vec<PointLight>) {
    let mut s = scene.clone();
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| *p = f(*p));
    }
    s.bounds = bounds_of(&s.meshes);
    s.camera.position = Vec3::from_array(f(s.camera.position.to_array()));
    s.camera.target = Vec3::from_array(f(s.camera.target.to_array()));
    (s, lights.iter().map(|l| PointLight { position: f(l.position), ..*l }).collect())
}

/// `scene` and `lights` translated by `offset`, each coordinate computed in f64 and stored in f32
/// (what f32 world coordinates keep there: a 1 m grid at 10^7 m).
pub fn translated(scene: &Scene, lights: &[PointLight], offset: DVec3) -> (Scene, Vec<PointLight>) {
    map_positions(scene, lights, |p| (Vec3::from_array(p).as_dvec3() + offset).as_vec3().to_array())
}

/// The content of `scene` and `lights` that f32 world coordinates can hold at `offset`: translated
/// there and back (both exact), so that translating the result by `offset` is exact.
pub fn representable_at(scene: &Scene, lights: &[PointLight], offset: DVec3) -> (Scene, Vec<PointLight>) {
    let (far, far_lights) = translated(scene, lights, offset);
    let (near, near_lights) = translated(&far, &far_lights, -offset);
    let (again, again_lights) = translated(&near, &near_lights, offset);
    assert!(again.meshes == far.meshes && again.camera == far.camera && again_lights == far_lights, "the translation by {offset} is not exact");
    (near, near_lights)
}

/// `scene` plus `mesh` (its material index must exist).
pub fn with_mesh(scene: &Scene, mesh: Mesh) -> Scene {
    assert!((mesh.material as usize) < scene.materials.len() && mesh.positions.len() == mesh.normals.len());
    let mut s = scene.clone();
    s.meshes.push(Mesh { uvs: vec![[0.0; 2]; mesh.positions.len()], ..mesh });
    s.bounds = bounds_of(&s.meshes);
    s.validate().unwrap();
    s
}

/// Appends triangle `(a, b, c)` with one normal for all three corners.
fn push_triangle(mesh: &mut Mesh, [a, b, c]: [Vec3; 3], normal: Vec3) {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([a, b, c].map(|p| p.to_array()));
    mesh.normals.extend([normal.to_array(); 3]);
    mesh.indices.extend([base, base + 1, base + 2]);
}

/// Degenerate and sliver triangles 6–30 m in front of `scene`'s camera (material 1, diffuse, and
/// 4, specular): zero-area (one point thrice), a repeated index, collinear corners, triangles
/// edge-on to the eye (their plane contains it), zero normals, micro-triangles, and 120 slivers
/// and needles from 10^-7 m to 1 m wide across the view (the wider ones cover pixel centres).
pub fn degenerate_triangles(scene: &Scene) -> Vec<Mesh> {
    let (eye, f, r, u) = camera_frame(scene);
    let at = |d: f32, x: f32, y: f32| eye + f * d + r * x + u * y;
    let mut plain = Mesh { material: 1, ..Mesh::default() };
    let facing = -f;
    // One point thrice, and a repeated index.
    push_triangle(&mut plain, [at(10.0, 0.0, 0.0); 3], facing);
    let base = plain.positions.len() as u32;
    plain.positions.extend([at(12.0, -1.0, 0.0), at(12.0, 1.0, 0.5)].map(|p| p.to_array()));
    plain.normals.extend([facing.to_array(); 2]);
    plain.indices.extend([base, base, base + 1, base + 1, base, base + 1]);
    // Collinear corners, along and across the view.
    push_triangle(&mut plain, [at(8.0, -2.0, 0.0), at(8.0, 0.0, 0.5), at(8.0, 2.0, 1.0)], facing);
    push_triangle(&mut plain, [at(6.0, 1.0, 0.2), at(12.0, 1.0, 0.2), at(24.0, 1.0, 0.2)], u);
    // Edge-on: every corner on a plane through the eye.
    let (d1, d2) = (f + r * 0.3, f + r * 0.3 + u * 0.2);
    push_triangle(&mut plain, [eye + d1 * 8.0, eye + d1 * 20.0, eye + d2 * 14.0], r);
    push_triangle(&mut plain, [eye + d1 * 8.0, eye + d2 * 14.0, eye + d2 * 30.0], -r);
    // Micro-triangles, and a sliver with zero normals.
    for k in 0..8 {
        let p = at(9.0 + k as f32, -1.5 + 0.4 * k as f32, -0.5);
        push_triangle(&mut plain, [p, p + r * 1e-6, p + u * 1e-6], facing);
    }
    push_triangle(&mut plain, [at(15.0, -4.0, 0.3), at(15.0, 4.0, 0.3), at(15.0, 4.0, 0.3 + 1e-3)], Vec3::ZERO);
    let mut shiny = Mesh { material: 4, ..Mesh::default() };
    for k in 0..120 {
        let t = k as f32 / 120.0;
        let width = 1e-7 * 10f32.powf(7.0 * t); // 1e-7 … 1 m
        let d = 6.0 + 24.0 * t;
        let (a, b) = if k % 2 == 0 { (at(d, -6.0, -1.0 + 2.0 * t), at(d, 6.0, 1.0 - 2.0 * t)) } else { (at(d, -0.2 * d, -0.05 * d), at(d + 10.0, 0.2 * d, 0.05 * d)) };
        let across = (b - a).cross(f).normalize_or(u);
        let mesh = if k % 3 == 0 { &mut plain } else { &mut shiny };
        push_triangle(mesh, [a, b, b + across * width], facing);
    }
    vec![plain, shiny]
}

/// `scene` with the camera inside a small box (0.7–0.9 m from the eye in front, 0.3–0.6 m to
/// the sides): its side walls run from behind the eye to beyond the near plane, so every one of
/// their triangles is clipped by it. Also the lights to see it by (inside the box).
pub fn camera_in_box(scene: &Scene) -> (Scene, Vec<PointLight>) {
    let (eye, f, r, u) = camera_frame(scene);
    let mut mesh = Mesh { material: 3, ..Mesh::default() };
    push_box(&mut mesh, (eye - Vec3::new(0.3, 0.4, 0.7), eye + Vec3::new(0.6, 0.5, 0.9)));
    let lights = (0..24).map(|k| light(eye + f * 0.3 + r * (0.05 * (k % 6) as f32 - 0.1) + u * (0.1 * (k / 6) as f32 - 0.2), 0.8, 0.3)).collect();
    (with_mesh(scene, mesh), lights)
}

/// `scene` with a 400 m × 60 m wall at 45° to the view direction through a point of the near
/// plane right of the centre (`0.3·near` aside): it passes half `near` from the eye, and the near
/// plane cuts it, so the right third of the frame shows it from the near plane to the horizon.
pub fn wall_through_near_plane(scene: &Scene) -> Scene {
    let (eye, f, r, u) = camera_frame(scene);
    let near = scene.camera.near;
    let along = (f + r).normalize();
    let normal = along.cross(u).normalize();
    let corner = |s: f32, t: f32| eye + f * near + r * (0.3 * near) + along * s + u * t;
    let mut mesh = Mesh { material: 2, ..Mesh::default() };
    push_triangle(&mut mesh, [corner(-200.0, -30.0), corner(200.0, -30.0), corner(200.0, 30.0)], normal);
    push_triangle(&mut mesh, [corner(-200.0, -30.0), corner(200.0, 30.0), corner(-200.0, 30.0)], normal);
    with_mesh(scene, mesh)
}
