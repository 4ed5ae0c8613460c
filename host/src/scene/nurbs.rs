//! NURBS patches: the host-side model of rational B-spline surfaces, their validation, their
//! packing into the tessellation pass's buffers, and built-in shapes (an exact sphere and torus,
//! and a teapot made of bicubic Bézier patches).
//!
//! A [`NurbsPatch`] keeps Cartesian control points and separate weights, as files and modelling
//! tools write them; [`NurbsBuffers::push`] converts them to the kernels' layout (homogeneous
//! points with premultiplied weights, `(w·x, w·y, w·z, w)`, and one shared knot buffer:
//! `shaders::nurbs` module docs) and assigns each patch its vertex and index ranges.
//!
//! A scene holds its patches as [`ScenePatch`]es (a name for messages, the patch, an optional
//! tessellation level): the procedural `nurbs` scene, and `[[nurbs]]` tables of a TOML
//! description. The renderer's tessellation pass (`render::nurbs`) packs them with
//! [`NurbsBuffers::push_relative`] (control points relative to the camera) and writes their grids
//! into the vertex streams and the index buffer on the GPU every frame; the raster passes then
//! draw them like any mesh, with the patch's material.
//!
//! Conventions as [`Mesh`](super::Mesh): right-handed, y up; a patch's front side is where
//! `S_u × S_v` points (counter-clockwise with u to the right and v up), outward for the built-ins.
use anyhow::{bail, Result};
use glam::{DVec3, Vec3};
use shaders::layout::NurbsPatchGpu;
use shaders::nurbs::{index_count, vertex_count, MAX_DEGREE};
use std::f32::consts::FRAC_1_SQRT_2;

/// A rational B-spline surface patch of degrees `(degree_u, degree_v)` over a
/// `size_u × size_v` control grid, u running fastest: point `(i, j)` is
/// `control_points[j·size_u + i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsPatch {
    /// 1..=`MAX_DEGREE` (5).
    pub degree_u: u32,
    pub degree_v: u32,
    /// Non-decreasing, `size_u + degree_u + 1` values; the patch covers `[knots_u[degree_u],
    /// knots_u[size_u]]` (clamped or not).
    pub knots_u: Vec<f32>,
    pub knots_v: Vec<f32>,
    /// Cartesian, `size_u · size_v` of them.
    pub control_points: Vec<[f32; 3]>,
    /// Positive and finite, one per control point (not premultiplied).
    pub weights: Vec<f32>,
    pub size_u: u32,
    pub size_v: u32,
    /// Index into the scene's materials.
    pub material: u32,
}

impl NurbsPatch {
    /// Checks everything the kernels rely on; the error is one line naming the patch and the field.
    /// Degrees and sizes first, then the lengths they imply (control points, weights, knots),
    /// then the values.
    pub fn validate(&self, name: &str) -> Result<()> {
        let dirs = [("u", self.degree_u, self.size_u, &self.knots_u), ("v", self.degree_v, self.size_v, &self.knots_v)];
        for (d, degree, size, _) in dirs {
            if degree == 0 || degree > MAX_DEGREE {
                bail!("NURBS patch {name:?}: degree_{d} is {degree}; it must be 1 to {MAX_DEGREE}");
            }
            if size <= degree {
                bail!("NURBS patch {name:?}: size_{d} is {size}; degree {degree} needs at least {} control points", degree + 1);
            }
        }
        let n = self.size_u as u64 * self.size_v as u64;
        if self.control_points.len() as u64 != n {
            bail!("NURBS patch {name:?}: control_points has {} points; size_u · size_v = {n} needed", self.control_points.len());
        }
        if self.weights.len() as u64 != n {
            bail!("NURBS patch {name:?}: weights has {} values; size_u · size_v = {n} needed", self.weights.len());
        }
        for (d, degree, size, knots) in dirs {
            let want = size as u64 + degree as u64 + 1;
            if knots.len() as u64 != want {
                bail!("NURBS patch {name:?}: knots_{d} has {} values; size_{d} + degree_{d} + 1 = {want} needed", knots.len());
            }
            if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
                bail!("NURBS patch {name:?}: knots_{d}[{i}] is {}, not finite", knots[i]);
            }
            if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
                bail!("NURBS patch {name:?}: knots_{d}[{i}] = {} is less than knots_{d}[{}] = {}: knot vectors must be non-decreasing", knots[i], i - 1, knots[i - 1]);
            }
            let (lo, hi) = (knots[degree as usize], knots[size as usize]);
            if hi <= lo {
                bail!("NURBS patch {name:?}: the {d} domain knots_{d}[{degree}..={size}] = [{lo}, {hi}] has zero length");
            }
        }
        if let Some(i) = self.control_points.iter().position(|p| !Vec3::from_array(*p).is_finite()) {
            bail!("NURBS patch {name:?}: control_points[{i}] = {:?} is not finite", self.control_points[i]);
        }
        if let Some(i) = self.weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            bail!("NURBS patch {name:?}: weights[{i}] = {}; weights must be positive and finite", self.weights[i]);
        }
        Ok(())
    }

    /// A polynomial patch (all weights 1) on clamped uniform knot vectors.
    pub fn polynomial(degree_u: u32, degree_v: u32, size_u: u32, size_v: u32, control_points: Vec<[f32; 3]>, material: u32) -> Self {
        let weights = vec![1.0; control_points.len()];
        Self { degree_u, degree_v, knots_u: clamped_uniform(degree_u, size_u), knots_v: clamped_uniform(degree_v, size_v), control_points, weights, size_u, size_v, material }
    }
}

/// Tessellation level of a patch that sets none (`render --tess-level` sets every patch's).
pub const DEFAULT_TESS_LEVEL: u32 = 16;
/// Largest tessellation level: `(256 + 1)²` = 66 049 vertices and 393 216 indices per patch.
pub const MAX_TESS_LEVEL: u32 = 256;

/// A patch of a scene: its name (for messages), the surface, and its tessellation level.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenePatch {
    pub name: String,
    pub patch: NurbsPatch,
    /// Quads along each parameter direction, 1..=[`MAX_TESS_LEVEL`]; `None`: [`DEFAULT_TESS_LEVEL`].
    pub level: Option<u32>,
}

impl ScenePatch {
    /// The patch's checks ([`NurbsPatch::validate`]), its level, and its material against the
    /// scene's `materials` materials; one line naming the patch and the field.
    pub fn validate(&self, materials: usize) -> Result<()> {
        let name = &self.name;
        self.patch.validate(name)?;
        if let Some(level) = self.level.filter(|l| !(1..=MAX_TESS_LEVEL).contains(l)) {
            bail!("NURBS patch {name:?}: level is {level}; it must be 1 to {MAX_TESS_LEVEL}");
        }
        if self.patch.material as usize >= materials {
            bail!("NURBS patch {name:?}: material is {}; the scene has {materials} materials", self.patch.material);
        }
        Ok(())
    }

    /// The level the patch is tessellated at.
    pub fn level(&self) -> u32 {
        self.level.unwrap_or(DEFAULT_TESS_LEVEL)
    }
}

/// A clamped knot vector with uniform interior knots on [0, 1] (`size + degree + 1` values).
pub fn clamped_uniform(degree: u32, size: u32) -> Vec<f32> {
    let spans = size - degree;
    let mut k = vec![0.0; degree as usize + 1];
    k.extend((1..spans).map(|s| s as f32 / spans as f32));
    k.extend(vec![1.0; degree as usize + 1]);
    k
}

/// Control point `p` of weight `w` made relative to `origin` and homogeneous:
/// `(w·(p − origin), w)`, computed in f64 and rounded to f32 ([`NurbsBuffers::push_relative`]).
pub fn relative_point(p: [f32; 3], w: f32, origin: DVec3) -> [f32; 4] {
    let q = (Vec3::from_array(p).as_dvec3() - origin) * w as f64;
    [q.x as f32, q.y as f32, q.z as f32, w]
}

/// Patches packed for the tessellation pass: headers, one knot buffer, one control-point buffer
/// (homogeneous, premultiplied weights), and the vertices and indices the grids will need.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NurbsBuffers {
    pub patches: Vec<NurbsPatchGpu>,
    pub knots: Vec<f32>,
    pub control_points: Vec<[f32; 4]>,
    /// The control points as the patches give them, `(Cartesian point, weight)` (world space):
    /// what [`relative_point`] makes `control_points` of, for any origin.
    pub world: Vec<([f32; 3], f32)>,
    /// The vertex streams' length: where the next patch's grid starts. Starts at 0, or where
    /// the grids follow other geometry (the renderer: after the meshes' vertices).
    pub vertices: u32,
    /// The index buffer's length, likewise.
    pub indices: u32,
}

impl NurbsBuffers {
    /// Appends a validated patch, tessellated at `level` (≥ 1) quads per side; returns its header.
    pub fn push(&mut self, patch: &NurbsPatch, level: u32) -> NurbsPatchGpu {
        self.push_relative(patch, level, DVec3::ZERO)
    }

    /// [`NurbsBuffers::push`] with the control points relative to `origin` (the camera: the
    /// renderer draws camera-relative, `render::camera_relative`): `(w·(x − c), w)` computed in
    /// f64 and rounded to f32. Exact for the homogeneous points: a rational surface is
    /// translated by translating its Cartesian control points. At `origin = 0` this is the f32
    /// product `w·x` itself (the product of two f32 is exact in f64).
    pub fn push_relative(&mut self, patch: &NurbsPatch, level: u32, origin: DVec3) -> NurbsPatchGpu {
        let level = level.max(1);
        let knot_offset_u = self.knots.len() as u32;
        self.knots.extend(&patch.knots_u);
        let knot_offset_v = self.knots.len() as u32;
        self.knots.extend(&patch.knots_v);
        let cp_offset = self.control_points.len() as u32;
        self.control_points.extend(patch.control_points.iter().zip(&patch.weights).map(|(p, &w)| relative_point(*p, w, origin)));
        self.world.extend(patch.control_points.iter().copied().zip(patch.weights.iter().copied()));
        let header = NurbsPatchGpu {
            degree_u: patch.degree_u,
            degree_v: patch.degree_v,
            size_u: patch.size_u,
            size_v: patch.size_v,
            knot_offset_u,
            knot_offset_v,
            cp_offset,
            level,
            vertex_offset: self.vertices,
            index_offset: self.indices,
            material: patch.material,
            _pad: 0,
        };
        self.vertices += vertex_count(level);
        self.indices += index_count(level);
        self.patches.push(header);
        header
    }
}

/// Control points of the unit circle as a rational quadratic, 9 points (the square's corners
/// and edge midpoints, counter-clockwise from (1, 0)), their weights, and its knot vector.
const CIRCLE: [[f32; 2]; 9] = [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, 0.0], [-1.0, -1.0], [0.0, -1.0], [1.0, -1.0], [1.0, 0.0]];
const CIRCLE_W: [f32; 9] = [1.0, FRAC_1_SQRT_2, 1.0, FRAC_1_SQRT_2, 1.0, FRAC_1_SQRT_2, 1.0, FRAC_1_SQRT_2, 1.0];
const CIRCLE_KNOTS: [f32; 12] = [0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0];

/// The surface of revolution about the y axis through `centre` of a rational profile in the
/// (radius, height) plane: control point `(i, j)` is profile point `j` turned by circle point
/// `i`, weight `w_i·w_j` (The NURBS Book, §8.5). The profile's knots run along v. The circle
/// turns from +x toward −z, so a profile traced counter-clockwise in (radius, height) gives
/// outward normals.
fn revolve(centre: Vec3, profile: &[[f32; 2]], profile_w: &[f32], knots_v: Vec<f32>, degree_v: u32) -> NurbsPatch {
    let mut control_points = vec![];
    let mut weights = vec![];
    for (p, pw) in profile.iter().zip(profile_w) {
        for (c, cw) in CIRCLE.iter().zip(CIRCLE_W) {
            control_points.push((centre + Vec3::new(p[0] * c[0], p[1], -p[0] * c[1])).to_array());
            weights.push(cw * pw);
        }
    }
    NurbsPatch { degree_u: 2, degree_v, knots_u: CIRCLE_KNOTS.to_vec(), knots_v, control_points, weights, size_u: 9, size_v: profile.len() as u32, material: 0 }
}

/// The exact sphere: rational quadratic, 9 × 5 control points (a full circle in u, the half
/// circle from the south to the north pole in v; the poles are collapsed edges).
pub fn sphere(centre: Vec3, radius: f32) -> NurbsPatch {
    let profile = [[0.0, -1.0], [1.0, -1.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[r, y]| [r * radius, y * radius]);
    let w = [1.0, FRAC_1_SQRT_2, 1.0, FRAC_1_SQRT_2, 1.0];
    revolve(centre, &profile, &w, vec![0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0], 2)
}

/// The exact torus about the y axis: rational quadratic, 9 × 9 control points, tube radius
/// `minor` around a circle of radius `major` (> `minor` for a ring torus).
pub fn torus(centre: Vec3, major: f32, minor: f32) -> NurbsPatch {
    let profile = CIRCLE.map(|[x, y]| [major + minor * x, minor * y]);
    revolve(centre, &profile, &CIRCLE_W, CIRCLE_KNOTS.to_vec(), 2)
}

/// `k` of the cubic Bézier quarter circle, `4/3·(√2 − 1)`: its midpoint is on the circle.
const QUARTER_K: f32 = 0.552_284_8;

/// The four cubic Bézier quarter circles of the unit circle in a plane (a, b), as 4 × 4 points.
fn quarter_circles() -> [[[f32; 2]; 4]; 4] {
    core::array::from_fn(|q| {
        let (a0, a1) = (q as f32 * std::f32::consts::FRAC_PI_2, (q + 1) as f32 * std::f32::consts::FRAC_PI_2);
        let (c0, c3) = ([a0.cos(), a0.sin()], [a1.cos(), a1.sin()]);
        let (t0, t3) = ([-a0.sin(), a0.cos()], [-a1.sin(), a1.cos()]);
        [c0, [c0[0] + QUARTER_K * t0[0], c0[1] + QUARTER_K * t0[1]], [c3[0] - QUARTER_K * t3[0], c3[1] - QUARTER_K * t3[1]], c3]
    })
}

/// Bicubic Bézier patches revolving a cubic profile segment (radius, height) about the y axis,
/// four quarters (the circle approximated by [`QUARTER_K`]; radial error under 0.03 %).
fn revolve_bezier(profile: [[f32; 2]; 4], out: &mut Vec<NurbsPatch>) {
    for q in quarter_circles() {
        let pts = profile.iter().flat_map(|p| q.map(|c| [p[0] * c[0], p[1], -p[0] * c[1]])).collect();
        out.push(NurbsPatch::polynomial(3, 3, 4, 4, pts, 0));
    }
}

/// Bicubic Bézier patches of a tube of radius `radius[j]` around a cubic path in the z = 0
/// plane (control points `path[j]`, along v), four quarters around it; open at both ends.
fn tube(path: [[f32; 2]; 4], radius: [f32; 4], out: &mut Vec<NurbsPatch>) {
    let p = path.map(|[x, y]| Vec3::new(x, y, 0.0));
    // N = z × T at each control point: (T, N, z) is right-handed and the quarters turn from N to
    // z, so S_u × S_v points away from the path.
    let normal = |j: usize| Vec3::Z.cross(p[(j + 1).min(3)] - p[j.saturating_sub(1)]).normalize();
    for q in quarter_circles() {
        let pts = (0..4).flat_map(|j| q.map(|c| (p[j] + radius[j] * (c[0] * normal(j) + c[1] * Vec3::Z)).to_array())).collect();
        out.push(NurbsPatch::polynomial(3, 3, 4, 4, pts, 0));
    }
}

/// A teapot in the style of Newell's: 32 bicubic Bézier patches (the body, rim, lid and knob as
/// six revolved profile segments, four patches each; a handle and a spout as tubes, four each).
/// The control points are this project's own (not Newell's data set); base at y = 0, about 3.2
/// units tall, the spout toward +x.
pub fn teapot() -> Vec<NurbsPatch> {
    // Traced counter-clockwise in (radius, height), from the bottom's centre to the knob's top.
    let profile: [[[f32; 2]; 4]; 6] = [
        [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.5, 0.0]],
        [[1.5, 0.0], [1.75, 0.0], [2.0, 0.3], [2.0, 0.9]],
        [[2.0, 0.9], [2.0, 1.5], [1.6, 2.0], [1.4, 2.25]],
        [[1.4, 2.25], [1.38, 2.32], [1.33, 2.38], [1.3, 2.4]],
        [[1.3, 2.4], [0.9, 2.45], [0.3, 2.6], [0.2, 2.9]],
        [[0.2, 2.9], [0.45, 3.0], [0.3, 3.15], [0.0, 3.15]],
    ];
    let mut out = vec![];
    for segment in profile {
        revolve_bezier(segment, &mut out);
    }
    tube([[-1.95, 1.9], [-2.9, 2.1], [-3.0, 1.0], [-1.95, 0.7]], [0.15; 4], &mut out);
    tube([[1.85, 0.8], [2.6, 1.2], [2.7, 2.0], [3.2, 2.3]], [0.35, 0.25, 0.18, 0.15], &mut out);
    out
}

#[cfg(test)]
#[path = "nurbs_tests.rs"]
mod tests;

/// The surface point of `patch` at `(u, v)` in f64 (The NURBS Book A2.1, A2.2 and A4.3 with
/// Cartesian points and weights): the exact surface the accuracy study measures tessellations
/// against. Parameters are clamped to the valid domain.
pub fn point_f64(patch: &NurbsPatch, u: f64, v: f64) -> DVec3 {
    let (su, nu) = basis_f64(&patch.knots_u, patch.degree_u as usize, patch.size_u as usize, u);
    let (sv, nv) = basis_f64(&patch.knots_v, patch.degree_v as usize, patch.size_v as usize, v);
    let (p, q) = (patch.degree_u as usize, patch.degree_v as usize);
    let (mut sum, mut w) = (DVec3::ZERO, 0.0);
    for (l, bv) in nv.iter().enumerate() {
        for (k, bu) in nu.iter().enumerate() {
            let idx = (sv - q + l) * patch.size_u as usize + (su - p + k);
            let wk = patch.weights[idx] as f64 * bu * bv;
            sum += Vec3::from_array(patch.control_points[idx]).as_dvec3() * wk;
            w += wk;
        }
    }
    sum / w
}

/// The valid parameter domain `[u_p, u_{n+1}] × [v_q, v_{m+1}]` of `patch`, in f64.
pub fn domain_f64(patch: &NurbsPatch) -> [f64; 4] {
    let (p, q) = (patch.degree_u as usize, patch.degree_v as usize);
    [patch.knots_u[p] as f64, patch.knots_u[patch.size_u as usize] as f64, patch.knots_v[q] as f64, patch.knots_v[patch.size_v as usize] as f64]
}

/// A2.1 and A2.2 in f64: the span of `t` (the last non-empty span at the domain's end) and the
/// `p + 1` basis functions that do not vanish there.
fn basis_f64(knots: &[f32], p: usize, size: usize, t: f64) -> (usize, Vec<f64>) {
    let k = |i: usize| knots[i] as f64;
    let (lo, hi) = (k(p), k(size));
    let t = t.clamp(lo, hi);
    let mut span = p;
    while span + 1 < size && k(span + 1) <= t && (t < hi || k(span + 1) < hi) {
        span += 1;
    }
    let (mut n, mut left, mut right) = (vec![0.0; p + 1], vec![0.0; p + 1], vec![0.0; p + 1]);
    n[0] = 1.0;
    for j in 1..=p {
        left[j] = t - k(span + 1 - j);
        right[j] = k(span + j) - t;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    (span, n)
}

/// The largest distance between `patch` tessellated at `level` (the renderer's grid and
/// triangles: `shaders::nurbs::tessellate_indices`) and the exact surface, in f64: sampled at
/// each triangle's centroid and edge midpoints, where a flat triangle strays furthest from a
/// smooth surface between its exact vertices.
pub fn tessellation_error(patch: &NurbsPatch, level: u32) -> f64 {
    let level = level.max(1) as usize;
    let [u0, u1, v0, v1] = domain_f64(patch);
    let param = |i: usize, j: usize| (u0 + (u1 - u0) * i as f64 / level as f64, v0 + (v1 - v0) * j as f64 / level as f64);
    let grid: Vec<(f64, f64, DVec3)> = (0..=level).flat_map(|j| (0..=level).map(move |i| (i, j))).map(|(i, j)| {
        let (u, v) = param(i, j);
        (u, v, point_f64(patch, u, v))
    }).collect();
    const SAMPLES: [[f64; 3]; 4] = [[1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]];
    let mut worst = 0f64;
    for quad in 0..(level * level) as u32 {
        let t = shaders::nurbs::tessellate_indices(level as u32, quad);
        for tri in [[t[0], t[1], t[2]], [t[3], t[4], t[5]]] {
            let [a, b, c] = tri.map(|i| grid[i as usize]);
            for w in SAMPLES {
                let (u, v) = (w[0] * a.0 + w[1] * b.0 + w[2] * c.0, w[0] * a.1 + w[1] * b.1 + w[2] * c.1);
                let flat = a.2 * w[0] + b.2 * w[1] + c.2 * w[2];
                worst = worst.max((point_f64(patch, u, v) - flat).length());
            }
        }
    }
    worst
}
