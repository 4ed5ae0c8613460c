//! CPU tests of `nurbs` against f64 references: the basis by the Cox–de Boor recursion of its
//! definition (eq. 2.5 and 2.9 of The NURBS Book), surfaces by summing every control point. Knot
//! spans, partition of unity, the exact sphere, derivatives against central differences,
//! clamped and unclamped knot vectors, degrees 1 and 5, degenerate normals and the winding of
//! tessellated grids.
use super::*;
use crate::test_support::Rng;
use core::f64::consts::FRAC_1_SQRT_2;

/// Knot vector and degree of one direction, in f64.
#[derive(Clone, Debug)]
struct Knots {
    p: usize,
    k: Vec<f64>,
}

impl Knots {
    fn size(&self) -> usize {
        self.k.len() - self.p - 1
    }
    fn domain(&self) -> (f64, f64) {
        (self.k[self.p], self.k[self.size()])
    }
    /// The span used at `u` (half-open, the domain's end belongs to the last non-empty span).
    fn span(&self, u: f64) -> usize {
        let (_, hi) = self.domain();
        if u >= hi {
            return (self.p..self.size()).rev().find(|&s| self.k[s] < hi).unwrap();
        }
        (self.p..self.size()).rev().find(|&s| self.k[s] <= u).unwrap_or(self.p)
    }
    /// `N_{i,p}(u)` by the recursion, with the span convention of `span`.
    fn n(&self, i: usize, p: usize, u: f64) -> f64 {
        if p == 0 {
            return if i == self.span(u) { 1.0 } else { 0.0 };
        }
        let k = &self.k;
        let a = if k[i + p] > k[i] { (u - k[i]) / (k[i + p] - k[i]) * self.n(i, p - 1, u) } else { 0.0 };
        let b = if k[i + p + 1] > k[i + 1] { (k[i + p + 1] - u) / (k[i + p + 1] - k[i + 1]) * self.n(i + 1, p - 1, u) } else { 0.0 };
        a + b
    }
    /// `N'_{i,p}(u)`, eq. (2.7).
    fn dn(&self, i: usize, u: f64) -> f64 {
        let (k, p) = (&self.k, self.p);
        let a = if k[i + p] > k[i] { p as f64 / (k[i + p] - k[i]) * self.n(i, p - 1, u) } else { 0.0 };
        let b = if k[i + p + 1] > k[i + 1] { p as f64 / (k[i + p + 1] - k[i + 1]) * self.n(i + 1, p - 1, u) } else { 0.0 };
        a - b
    }
    fn f32s(&self) -> Vec<f32> {
        self.k.iter().map(|&x| x as f32).collect()
    }
}

/// A rational surface in f64: Cartesian points and weights, u fastest.
#[derive(Clone, Debug)]
struct Surface {
    u: Knots,
    v: Knots,
    pts: Vec<[f64; 3]>,
    w: Vec<f64>,
}

/// A surface in the kernel's buffers, at non-zero offsets so the offsets are exercised.
struct Gpu {
    patch: NurbsPatchGpu,
    knots: Vec<f32>,
    cps: Vec<Vec4>,
}

impl Gpu {
    fn knot(&self) -> impl Fn(u32) -> f32 + Copy + '_ {
        move |i| self.knots[i as usize]
    }
    fn cp(&self) -> impl Fn(u32) -> Vec4 + Copy + '_ {
        move |i| self.cps[i as usize]
    }
    fn derivs(&self, u: f32, v: f32) -> SurfacePoint {
        surface_derivs(&self.patch, u, v, self.knot(), self.cp())
    }
    fn normal(&self, u: f32, v: f32) -> Vec3 {
        surface_normal(&self.patch, u, v, &self.derivs(u, v), self.knot(), self.cp())
    }
    fn vertex(&self, i: u32, j: u32, level: u32) -> NurbsVertex {
        tessellate_vertex(&self.patch, i, j, level, self.knot(), self.cp())
    }
    fn grid(&self, level: u32) -> Vec<NurbsVertex> {
        (0..vertex_count(level)).map(|k| vertex_grid(level, k)).map(|(i, j)| self.vertex(i, j, level)).collect()
    }
}

impl Surface {
    fn gpu(&self) -> Gpu {
        let mut knots = vec![-7.0f32; 3];
        let knot_offset_u = knots.len() as u32;
        knots.extend(self.u.f32s());
        let knot_offset_v = knots.len() as u32;
        knots.extend(self.v.f32s());
        let mut cps = vec![Vec4::splat(99.0); 2];
        let cp_offset = cps.len() as u32;
        cps.extend(self.pts.iter().zip(&self.w).map(|(p, &w)| Vec4::new((p[0] * w) as f32, (p[1] * w) as f32, (p[2] * w) as f32, w as f32)));
        let patch = NurbsPatchGpu {
            degree_u: self.u.p as u32,
            degree_v: self.v.p as u32,
            size_u: self.u.size() as u32,
            size_v: self.v.size() as u32,
            knot_offset_u,
            knot_offset_v,
            cp_offset,
            level: 8,
            vertex_offset: 0,
            index_offset: 0,
            material: 0,
            _pad: 0,
        };
        Gpu { patch, knots, cps }
    }

    /// The point at `(u, v)`, summing every control point.
    fn point(&self, u: f64, v: f64) -> [f64; 3] {
        let (nu, nv) = (self.u.size(), self.v.size());
        let (mut a, mut w) = ([0.0; 3], 0.0);
        for j in 0..nv {
            let bv = self.v.n(j, self.v.p, v);
            for i in 0..nu {
                let b = self.u.n(i, self.u.p, u) * bv * self.w[j * nu + i];
                w += b;
                for (ac, pc) in a.iter_mut().zip(self.pts[j * nu + i]) {
                    *ac += b * pc;
                }
            }
        }
        a.map(|x| x / w)
    }
}

fn uniform_clamped(p: usize, size: usize) -> Knots {
    let spans = size - p;
    let mut k = vec![0.0; p + 1];
    k.extend((1..spans).map(|s| s as f64 / spans as f64));
    k.extend(vec![1.0; p + 1]);
    Knots { p, k }
}

/// A random non-decreasing knot vector for `size` points, interior knots of multiplicity up to
/// `p` (the domain stays of non-zero length), clamped or not.
fn random_knots(rng: &mut Rng, p: usize, size: usize, clamped: bool) -> Knots {
    let m = size + p + 1;
    let mut k: Vec<f64> = (0..m).map(|_| rng.unit() as f64 * 4.0 - 1.0).collect();
    k.sort_by(f64::total_cmp);
    for i in 1..m {
        if rng.below(4) == 0 && i > p + 1 && i < size - 1 {
            let run = (1..p).take_while(|&r| k[i - r] == k[i - 1]).count() + 1;
            if run < p {
                k[i] = k[i - 1]; // a repeated interior knot, multiplicity ≤ p
            }
        }
    }
    if clamped {
        for i in 0..=p {
            k[i] = k[p];
            k[m - 1 - i] = k[m - 1 - p];
        }
    }
    let kn = Knots { p, k };
    assert!(kn.domain().0 < kn.domain().1);
    kn
}

fn random_surface(rng: &mut Rng, p: usize, q: usize, clamped: bool) -> Surface {
    let (nu, nv) = (p + 1 + rng.below(4) as usize, q + 1 + rng.below(4) as usize);
    let u = random_knots(rng, p, nu, clamped);
    let v = random_knots(rng, q, nv, clamped);
    let pts = (0..nu * nv).map(|k| [(k % nu) as f64 + rng.unit() as f64 * 0.5, (k / nu) as f64 + rng.unit() as f64 * 0.5, rng.unit() as f64 * 2.0]).collect();
    let w = (0..nu * nv).map(|_| 0.3 + 2.0 * rng.unit() as f64).collect();
    Surface { u, v, pts, w }
}

/// The exact unit sphere: a rational quadratic, 9 × 5 control points (full circle in u, the
/// half circle from the south to the north pole in v), normals `S_u × S_v` outward.
fn sphere() -> Surface {
    let r = FRAC_1_SQRT_2;
    let circle = [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (-1.0, 1.0), (-1.0, 0.0), (-1.0, -1.0), (0.0, -1.0), (1.0, -1.0), (1.0, 0.0)];
    let cw = [1.0, r, 1.0, r, 1.0, r, 1.0, r, 1.0];
    let profile = [(0.0, -1.0), (1.0, -1.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let pw = [1.0, r, 1.0, r, 1.0];
    let mut pts = vec![];
    let mut w = vec![];
    for (j, &(rad, y)) in profile.iter().enumerate() {
        for (i, &(x, z)) in circle.iter().enumerate() {
            pts.push([x * rad, y, -z * rad]);
            w.push(cw[i] * pw[j]);
        }
    }
    let u = Knots { p: 2, k: vec![0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0] };
    let v = Knots { p: 2, k: vec![0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0] };
    Surface { u, v, pts, w }
}

fn dist(a: Vec3, b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] as f64 - b[c]).powi(2)).sum::<f64>().sqrt()
}

/// Parameters to test in a knot vector: random ones, every knot of the domain, the span ends
/// and points just inside them.
fn parameters(k: &Knots, rng: &mut Rng) -> Vec<f64> {
    let (lo, hi) = k.domain();
    let mut us: Vec<f64> = (0..40).map(|_| lo + (hi - lo) * rng.unit() as f64).collect();
    for &x in &k.k[k.p..=k.size()] {
        us.push(x);
        us.extend([x - 1e-4, x + 1e-4].into_iter().filter(|y| (lo..=hi).contains(y)));
    }
    us
}

fn check_basis(k: &Knots, u64_: f64) {
    let kf = k.f32s();
    let knot = |i: u32| kf[i as usize];
    let u = u64_ as f32;
    let span = find_span(k.size() as u32, k.p as u32, u, knot) as usize;
    assert!(kf[span] < kf[span + 1], "empty span {span} at {u} in {:?}", k.k);
    assert!(kf[span] <= u && (u < kf[span + 1] || u >= kf[k.size()]), "span {span} at {u} in {:?}", k.k);
    let b = basis(span as u32, u, k.p as u32, knot);
    let (mut sum, mut dsum) = (0.0f64, 0.0f64);
    let u = u as f64; // the reference evaluates where the kernel did
    let scale = 1.0 + k.p as f64 / (k.k[span + 1] - k.k[span]);
    for r in 0..=k.p {
        let (n, d) = (b.n[r] as f64, b.d[r] as f64);
        assert!(n >= -1e-7, "N_{r} = {n} < 0 at u = {u}, knots {:?}", k.k);
        let i = span - k.p + r;
        assert!((n - k.n(i, k.p, u)).abs() < 2e-6, "N_{i} = {n} vs {} at u = {u}, knots {:?}", k.n(i, k.p, u), k.k);
        assert!((d - k.dn(i, u)).abs() < 2e-5 * scale, "N'_{i} = {d} vs {} at u = {u}, knots {:?}", k.dn(i, u), k.k);
        sum += n;
        dsum += d;
    }
    assert!((sum - 1.0).abs() < 1e-6, "Σ N = {sum} at u = {u}, knots {:?}", k.k);
    assert!(dsum.abs() < 1e-5 * scale, "Σ N' = {dsum} at u = {u}, knots {:?}", k.k);
    for r in k.p + 1..MAX_ORDER {
        assert_eq!((b.n[r], b.d[r]), (0.0, 0.0));
    }
}

#[test]
fn basis_partition_of_unity_random_knots_and_spans() {
    let mut rng = Rng(11);
    for trial in 0..300 {
        let p = 1 + trial % 5;
        let size = p + 1 + rng.below(6) as usize;
        let k = random_knots(&mut rng, p, size, trial % 2 == 0);
        for u in parameters(&k, &mut rng) {
            check_basis(&k, u);
        }
    }
}

#[test]
fn basis_with_repeated_interior_knots() {
    // Multiplicity 1, 2 and 3 (= p: the curve is C0 there) interior knots.
    let k = Knots { p: 3, k: vec![0.0, 0.0, 0.0, 0.0, 0.2, 0.4, 0.4, 0.6, 0.6, 0.6, 0.8, 1.0, 1.0, 1.0, 1.0] };
    let mut rng = Rng(5);
    for u in parameters(&k, &mut rng) {
        check_basis(&k, u);
    }
    // At a knot of multiplicity p the basis interpolates: one function is 1.
    let kf = k.f32s();
    let knot = |i: u32| kf[i as usize];
    let span = find_span(k.size() as u32, 3, 0.6, knot);
    assert_eq!(span, 9);
    let b = basis(span, 0.6, 3, knot);
    assert_eq!(b.n[0], 1.0, "{b:?}");
}

#[test]
fn find_span_ends_repeated_knots_and_bad_input() {
    let k: [f32; 10] = [0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 3.0, 4.0, 4.0, 4.0];
    let knot = |i: u32| k[i as usize];
    let (size, p) = (7, 2);
    let cases = [(0.0, 2), (0.5, 2), (1.0, 3), (1.5, 3), (2.0, 5), (2.5, 5), (3.0, 6), (3.99, 6), (4.0, 6), (9.0, 6), (-3.0, 2), (f32::NAN, 2), (f32::INFINITY, 6), (f32::NEG_INFINITY, 2)];
    for (u, want) in cases {
        assert_eq!(find_span(size, p, u, knot), want, "u = {u}");
    }
    // The domain's end repeated inside the vector: the last non-empty span.
    let k2: [f32; 8] = [0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 2.0];
    assert_eq!(find_span(5, 2, 2.0, |i| k2[i as usize]), 3);
    // A domain start shared with the next interior knot.
    let k3: [f32; 8] = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0];
    assert_eq!(find_span(5, 2, 0.0, |i| k3[i as usize]), 3);
}

#[test]
fn exact_sphere_points_at_radius_one() {
    let s = sphere();
    let g = s.gpu();
    let mut rng = Rng(3);
    let mut params: Vec<(f32, f32)> = (0..=64).flat_map(|i| (0..=64).map(move |j| (i as f32 / 64.0, j as f32 / 64.0))).collect();
    params.extend((0..2000).map(|_| (rng.unit(), rng.unit())));
    let mut worst = 0.0f64;
    for (u, v) in params {
        let p = g.derivs(u, v).s;
        let r = (0..3).map(|c| (p[c] as f64).powi(2)).sum::<f64>().sqrt();
        worst = worst.max((r - 1.0).abs());
        assert!(dist(p, s.point(u as f64, v as f64)) < 1e-6, "({u}, {v}): {p} vs {:?}", s.point(u as f64, v as f64));
    }
    assert!(worst < 1e-6, "largest radius error {worst}");
}

#[test]
fn exact_sphere_normals_radial_and_defined_at_the_poles() {
    let g = sphere().gpu();
    let level = 32;
    for vx in g.grid(level) {
        let n = vx.normal;
        assert!((n.length() - 1.0).abs() < 1e-6, "normal {n} not unit");
        let radial = vx.position.normalize();
        let pole = vx.uv.y == 0.0 || vx.uv.y == 1.0;
        // At the poles the limit ±S_uv × S_v is horizontal × horizontal: exactly vertical, so
        // the poles meet the same bound.
        assert!((n - radial).length() < 1e-5, "uv {}: normal {n} vs radial {radial} (pole {pole})", vx.uv);
    }
    // The poles themselves: S_u vanishes there and the fallback gives ±y.
    for u in [0.0, 0.1, 0.37, 0.5, 0.99, 1.0] {
        let south = g.derivs(u, 0.0);
        assert!(south.su.length() < 1e-5 * south.sv.length(), "S_u at the south pole {}", south.su);
        assert!((g.normal(u, 0.0) - Vec3::NEG_Y).length() < 1e-5, "south pole normal {}", g.normal(u, 0.0));
        assert!((g.normal(u, 1.0) - Vec3::Y).length() < 1e-5, "north pole normal {}", g.normal(u, 1.0));
    }
}

#[test]
fn derivatives_match_central_differences() {
    let mut rng = Rng(17);
    for trial in 0..200 {
        let (p, q) = (1 + trial % 5, 1 + (trial / 5) % 5);
        let s = random_surface(&mut rng, p, q, trial % 3 != 0);
        let g = s.gpu();
        let (u0, u1) = s.u.domain();
        let (v0, v1) = s.v.domain();
        for _ in 0..10 {
            let (u, v) = ((u0 + (u1 - u0) * rng.unit() as f64) as f32, (v0 + (v1 - v0) * rng.unit() as f64) as f32);
            let (u, v) = (u as f64, v as f64);
            let h = 1e-6 * (1.0 + (u1 - u0).max(v1 - v0));
            // Central differences need both sides in one span (derivatives jump at C0 knots).
            let same = |k: &Knots, x: f64| k.span(x - h) == k.span(x + h) && x - h > k.domain().0 && x + h < k.domain().1;
            if !same(&s.u, u) || !same(&s.v, v) {
                continue;
            }
            let d = g.derivs(u as f32, v as f32);
            let diff = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|c| (a[c] - b[c]) / (2.0 * h));
            let su = diff(s.point(u + h, v), s.point(u - h, v));
            let sv = diff(s.point(u, v + h), s.point(u, v - h));
            let scale = 1.0 + su.iter().chain(&sv).fold(0.0f64, |m, x| m.max(x.abs()));
            assert!(dist(d.s, s.point(u, v)) < 2e-5 * (1.0 + scale), "point at ({u}, {v}) of {s:?}");
            assert!(dist(d.su, su) < 2e-3 * scale, "S_u {} vs {su:?} at ({u}, {v}), trial {trial}", d.su);
            assert!(dist(d.sv, sv) < 2e-3 * scale, "S_v {} vs {sv:?} at ({u}, {v}), trial {trial}", d.sv);
            // The mixed derivative, on a wider stencil (still inside the span).
            let h2 = 1e-4 * (1.0 + (u1 - u0).max(v1 - v0));
            let inside = |k: &Knots, x: f64| k.span(x - h2) == k.span(x + h2) && x - h2 > k.domain().0 && x + h2 < k.domain().1;
            if inside(&s.u, u) && inside(&s.v, v) {
                let [a, b, c, e] = [s.point(u + h2, v + h2), s.point(u + h2, v - h2), s.point(u - h2, v + h2), s.point(u - h2, v - h2)];
                let suv = [0, 1, 2].map(|k| (a[k] - b[k] - c[k] + e[k]) / (4.0 * h2 * h2));
                let scale2 = 1.0 + suv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                assert!(dist(d.suv, suv) < 2e-3 * scale2 * scale, "S_uv {} vs {suv:?} at ({u}, {v}), trial {trial}", d.suv);
            }
        }
    }
}

#[test]
fn clamped_patch_interpolates_its_corners() {
    let mut rng = Rng(23);
    for trial in 0..50 {
        let s = random_surface(&mut rng, 1 + trial % 5, 1 + (trial / 5) % 5, true);
        let g = s.gpu();
        let (nu, nv) = (s.u.size(), s.v.size());
        let ((u0, u1), (v0, v1)) = (s.u.domain(), s.v.domain());
        for (u, v, c) in [(u0, v0, 0), (u1, v0, nu - 1), (u0, v1, (nv - 1) * nu), (u1, v1, nv * nu - 1)] {
            let p = g.derivs(u as f32, v as f32).s;
            assert!(dist(p, s.pts[c]) < 1e-5, "corner {c}: {p} vs {:?}", s.pts[c]);
        }
        // The tessellated grid's corners too.
        let level = 3;
        let corner = |i, j| g.vertex(i, j, level).position;
        assert!(dist(corner(0, 0), s.pts[0]) < 1e-5 && dist(corner(level, level), s.pts[nv * nu - 1]) < 1e-5);
    }
}

#[test]
fn unclamped_knots_evaluate_on_their_valid_domain_only() {
    // Uniform, unclamped: the domain is [u_p, u_{n+1}] = [2, 5] for 5 points of degree 2.
    let k = Knots { p: 2, k: (0..8).map(|x| x as f64).collect() };
    assert_eq!(k.domain(), (2.0, 5.0));
    let mut rng = Rng(8);
    for u in parameters(&k, &mut rng) {
        check_basis(&k, u);
    }
    let s = Surface { u: k.clone(), v: k, pts: (0..25).map(|i| [(i % 5) as f64, (i / 5) as f64, ((i * 7) % 3) as f64]).collect(), w: (0..25).map(|i| 1.0 + (i % 4) as f64 * 0.25).collect() };
    let g = s.gpu();
    assert_eq!(domain(&g.patch, g.knot()), [2.0, 5.0, 2.0, 5.0]);
    // The grid spans exactly the valid domain.
    let level = 6;
    for (idx, vx) in g.grid(level).iter().enumerate() {
        let (i, j) = vertex_grid(level, idx as u32);
        let (u, v) = (2.0 + 3.0 * i as f64 / level as f64, 2.0 + 3.0 * j as f64 / level as f64);
        assert!(dist(vx.position, s.point(u, v)) < 1e-5, "vertex ({i}, {j})");
    }
    // Outside the domain the parameters are clamped to it (never the partial sums outside).
    for (u, v, cu, cv) in [(0.5, 3.0, 2.0, 3.0), (6.5, 4.0, 5.0, 4.0), (3.0, -1.0, 3.0, 2.0), (f32::NAN, 3.0, 2.0, 3.0)] {
        let p = g.derivs(u, v).s;
        assert!(dist(p, s.point(cu, cv)) < 1e-5, "({u}, {v}) → {p}");
    }
}

#[test]
fn bilinear_patch_is_bilinear_interpolation() {
    let corners = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.5], [0.0, 1.0, 0.25], [2.0, 1.5, 1.0]];
    let s = Surface { u: Knots { p: 1, k: vec![0.0, 0.0, 1.0, 1.0] }, v: Knots { p: 1, k: vec![0.0, 0.0, 1.0, 1.0] }, pts: corners.to_vec(), w: vec![1.0; 4] };
    let g = s.gpu();
    let mut rng = Rng(2);
    for _ in 0..200 {
        let (u, v) = (rng.unit(), rng.unit());
        let d = g.derivs(u, v);
        let lerp = |c: usize| {
            let (a, b, cc, dd) = (corners[0][c], corners[1][c], corners[2][c], corners[3][c]);
            let (u, v) = (u as f64, v as f64);
            ((1.0 - u) * (1.0 - v) * a + u * (1.0 - v) * b + (1.0 - u) * v * cc + u * v * dd, (1.0 - v) * (b - a) + v * (dd - cc), (1.0 - u) * (cc - a) + u * (dd - b))
        };
        for c in 0..3 {
            let (p, pu, pv) = lerp(c);
            assert!((d.s[c] as f64 - p).abs() < 1e-6 && (d.su[c] as f64 - pu).abs() < 1e-5 && (d.sv[c] as f64 - pv).abs() < 1e-5, "({u}, {v}): {d:?}");
        }
    }
    // A planar bilinear patch: the normal is the plane's everywhere.
    let flat = Surface { pts: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], ..s };
    for vx in flat.gpu().grid(4) {
        assert!((vx.normal - Vec3::Z).length() < 1e-6, "{vx:?}");
    }
}

#[test]
fn degree_five_patches_match_the_reference() {
    let mut rng = Rng(31);
    for clamped in [true, false] {
        for _ in 0..20 {
            let s = random_surface(&mut rng, 5, 5, clamped);
            let g = s.gpu();
            let ((u0, u1), (v0, v1)) = (s.u.domain(), s.v.domain());
            for _ in 0..20 {
                let (u, v) = ((u0 + (u1 - u0) * rng.unit() as f64) as f32, (v0 + (v1 - v0) * rng.unit() as f64) as f32);
                let p = g.derivs(u, v).s;
                let r = s.point(u as f64, v as f64);
                assert!(dist(p, r) < 1e-4, "({u}, {v}): {p} vs {r:?}");
            }
        }
    }
    // A quintic Bézier patch reproduces a linear function exactly (linear precision).
    let s = Surface { u: uniform_clamped(5, 6), v: uniform_clamped(5, 6), pts: (0..36).map(|i| [(i % 6) as f64 / 5.0, (i / 6) as f64 / 5.0, 0.0]).collect(), w: vec![1.0; 36] };
    for vx in s.gpu().grid(7) {
        assert!((vx.position.truncate() - vx.uv).length() < 1e-6, "{vx:?}");
        assert!((vx.normal - Vec3::Z).length() < 1e-6);
    }
}

/// A cone: the v = 1 edge of control points collapses to the apex (the sphere's equator ring
/// at v = 0), normals up and out.
fn cone() -> Surface {
    let mut s = sphere();
    s.v = Knots { p: 1, k: vec![0.0, 0.0, 1.0, 1.0] };
    let (ring, w) = (s.pts[9 * 2..9 * 3].to_vec(), s.w[9 * 2..9 * 3].to_vec());
    s.pts = ring.iter().copied().chain(ring.iter().map(|_| [0.0, 1.0, 0.0])).collect();
    s.w = w.iter().chain(&w).copied().collect();
    s
}

#[test]
fn degenerate_normals_follow_the_fallback_rule() {
    // The cone's apex: S_u vanishes; the normal is that of the cone one step inward, whose
    // direction along the generator does not change: the cone's normal on that generator.
    let g = cone().gpu();
    for u in [0.0f32, 0.2, 0.5, 0.8] {
        let d = g.derivs(u, 1.0);
        assert!(d.su.length() < 1e-5 * d.sv.length(), "S_u at the apex {}", d.su);
        let apex = g.normal(u, 1.0);
        let inner = g.normal(u, 0.5);
        assert!((apex - inner).length() < 1e-5, "u {u}: apex {apex} vs {inner}");
        let out = Vec3::new(inner.x, 0.0, inner.z).normalize();
        assert!((apex - (out + Vec3::Y).normalize()).length() < 1e-5, "the 45° cone's normal: {apex}");
    }
    // A collapsed v edge (S_v vanishes) goes the other way: the sphere with u and v swapped.
    let mut s = sphere();
    let (nu, nv) = (s.u.size(), s.v.size());
    let idx = |i: usize, j: usize| j * nu + i;
    let pts = (0..nu * nv).map(|k| s.pts[idx(k / nv, k % nv)]).collect();
    let w = (0..nu * nv).map(|k| s.w[idx(k / nv, k % nv)]).collect();
    core::mem::swap(&mut s.u, &mut s.v);
    let t = Surface { pts, w, ..s }.gpu();
    for v in [0.0f32, 0.3, 1.0] {
        // Swapping the parameters flips S_u × S_v: the normals now point inward.
        assert!((t.normal(0.0, v) - Vec3::Y).length() < 1e-5, "{}", t.normal(0.0, v));
        assert!((t.normal(1.0, v) - Vec3::NEG_Y).length() < 1e-5);
    }
    // Parallel, non-vanishing derivatives at a corner (a cusp of a planar bilinear patch): the
    // normal one step inward, the plane's.
    let cusp = Surface { u: Knots { p: 1, k: vec![0.0, 0.0, 1.0, 1.0] }, v: Knots { p: 1, k: vec![0.0, 0.0, 1.0, 1.0] }, pts: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]], w: vec![1.0; 4] };
    let cg = cusp.gpu();
    let d = cg.derivs(0.0, 0.0);
    assert!(d.su.cross(d.sv).length() == 0.0 && d.su.length() > 0.5 && d.sv.length() > 0.5, "{d:?}");
    assert_eq!(cg.normal(0.0, 0.0), cg.normal(0.5, 0.5));
    assert!((cg.normal(0.5, 0.5) - Vec3::NEG_Z).length() < 1e-6, "{}", cg.normal(0.5, 0.5));
    // Collapsed to a point: no normal anywhere, +z.
    let mut p = sphere();
    p.pts.iter_mut().for_each(|x| *x = [1.0, 2.0, 3.0]);
    let pg = p.gpu();
    for vx in pg.grid(4) {
        assert_eq!(vx.normal, Vec3::Z);
        assert!(dist(vx.position, [1.0, 2.0, 3.0]) < 1e-6);
    }
}

#[test]
fn tessellated_grids_wind_counter_clockwise_with_their_normals() {
    let mut rng = Rng(41);
    let mut surfaces = vec![sphere(), cone()];
    surfaces.extend((0..20).map(|t| random_surface(&mut rng, 1 + t % 5, 1 + (t / 2) % 5, t % 2 == 0)));
    for (si, s) in surfaces.iter().enumerate() {
        let g = s.gpu();
        for level in [1, 2, 4, 5, 16] {
            let verts = g.grid(level);
            assert_eq!(verts.len() as u32, vertex_count(level));
            let (mut agree, mut total) = (0, 0);
            for q in 0..level * level {
                let t = tessellate_indices(level, q);
                assert!(t.iter().all(|&i| i < vertex_count(level)));
                for tri in [&t[0..3], &t[3..6]] {
                    let [a, b, c] = [0, 1, 2].map(|k| verts[tri[k] as usize]);
                    let n = (b.position - a.position).cross(c.position - a.position);
                    if n.length() < 1e-6 {
                        continue; // a pole's collapsed triangle
                    }
                    let avg = a.normal + b.normal + c.normal;
                    total += 1;
                    if n.dot(avg) > 0.0 {
                        agree += 1;
                    } else {
                        // The sphere and the cone agree everywhere from level 4 (at 1 and 2
                        // their triangles cut through the axis, perpendicular to the surface).
                        assert!(si >= 2 || level < 4, "surface {si}, level {level}, quad {q}: winding {n} vs normals {avg}");
                    }
                }
            }
            // Coarse grids of wavy random patches may fold; fine ones follow the surface.
            if level == 16 {
                assert!(agree * 100 >= total * 99, "surface {si}: {agree} of {total} triangles agree");
            }
        }
    }
}

#[test]
fn tessellated_indices_form_an_oriented_grid() {
    for level in [1u32, 2, 3, 8] {
        let mut edges = std::collections::HashMap::new();
        let mut used = vec![false; vertex_count(level) as usize];
        for q in 0..level * level {
            let t = tessellate_indices(level, q);
            for tri in [&t[0..3], &t[3..6]] {
                for k in 0..3 {
                    used[tri[k] as usize] = true;
                    *edges.entry((tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
                }
            }
        }
        assert!(used.iter().all(|&u| u));
        assert_eq!(edges.len() as u32, 3 * 2 * level * level);
        // Every directed edge once; an interior edge's reverse exists (consistent orientation).
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}→{b}");
            let (ia, ja, ib, jb) = (a % (level + 1), a / (level + 1), b % (level + 1), b / (level + 1));
            let boundary = (ia == ib && (ia == 0 || ia == level)) || (ja == jb && (ja == 0 || ja == level));
            assert!(boundary || edges.contains_key(&(b, a)), "interior edge {a}→{b} has no twin");
        }
        assert_eq!(index_count(level), 6 * level * level);
    }
    // Quad (0, 0) at level 2: (0, 1, 4) and (0, 4, 3), counter-clockwise with u right, v up.
    assert_eq!(tessellate_indices(2, 0), [0, 1, 4, 0, 4, 3]);
}
