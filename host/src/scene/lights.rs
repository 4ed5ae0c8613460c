//! Point-light generators. Every generator is seeded and deterministic: the same arguments give
//! bit-identical lights on every platform (a local PCG32, no `rand` crate).
//!
//! Default radius ([`default_radius`]): `r₀ = 1.5 · ∛(V / n)`, where `V` is the volume of the
//! bounds with each extent clamped to at least 1 % of the diagonal (flat scenes keep a volume).
//! `∛(V/n)` is the mean spacing of `n` uniform lights, so a point sees on average
//! `n · 4/3·π·E[r³] / V ≈ 17` lights for radii uniform in `[0.5, 1.5]·r₀` whatever `n` is: more
//! lights means smaller lights, and the work per pixel stays comparable across light counts.
//! Intensity is [`DEFAULT_INTENSITY`] × [`radius_scaled_intensity`] (equal brightness at half
//! range whatever the radius); colours are random saturated hues.
use super::{Scene, Spot};
use anyhow::{bail, ensure, Result};
use glam::Vec3;
use shaders::layout::PointLight;

/// Most lights a generator makes, a scene holds and the renderer takes: 2^27 − 4 lights are
/// 2 GiB of 16-byte compact records (`shaders::compact_light`; full 32-byte records hold half,
/// `preflight::max_lights`).
pub const MAX_LIGHTS: usize = shaders::compact_light::MAX_COMPACT_LIGHTS as usize;
/// Intensity of generated lights unless told otherwise.
pub const DEFAULT_INTENSITY: f32 = 0.15;
/// Most centres [`hotspots`] takes (more would only cost memory: each centre is one cluster).
pub const MAX_HOTSPOT_CLUSTERS: usize = 1 << 16;
/// Fraction of the lights that [`hotspots`] puts around its centres (the rest are uniform).
pub const HOTSPOT_FRACTION: f32 = 0.9;

/// PCG32 (XSH-RR, O'Neill 2014): a small, seedable, portable generator.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MUL: u64 = 6364136223846793005;

    pub fn new(seed: u64) -> Self {
        let mut r = Self { state: 0, inc: (0xda3e_39cb_94b9_5bdb_u64 << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1) (24 bits).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.f32(); // (0, 1]
        let u2 = self.f32();
        (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
    }

    /// Uniform point in the box.
    pub fn in_box(&mut self, (lo, hi): (Vec3, Vec3)) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }
}

/// A saturated colour: random hue, saturation in [0.7, 1], value 1.
pub fn saturated_colour(rng: &mut Pcg32) -> [f32; 3] {
    let h = rng.f32() * 6.0;
    let s = rng.range(0.7, 1.0);
    let f = h - h.floor();
    let (p, q, t) = (1.0 - s, 1.0 - s * f, 1.0 - s * (1.0 - f));
    match h as u32 {
        0 => [1.0, t, p],
        1 => [q, 1.0, p],
        2 => [p, 1.0, t],
        3 => [p, q, 1.0],
        4 => [t, p, 1.0],
        _ => [1.0, p, q],
    }
}

/// Intensity that makes a light of range `radius` as bright at half its range as a unit light
/// at distance 0: with attenuation `window(d/r)/(d² + 1)` (`shaders::lighting`), a light's
/// irradiance at `d = r/2` is `I·0.88/(r²/4 + 1)`; `I = (r²/4 + 1)/0.88` keeps it ≈ 1 for every
/// radius, so scenes stay lit whatever their scale and light count.
pub fn radius_scaled_intensity(radius: f32) -> f32 {
    (0.25 * radius * radius + 1.0) / 0.88
}

/// The module's default radius `r₀` for `n` lights in `bounds` (see the module docs).
pub fn default_radius(bounds: (Vec3, Vec3), n: usize) -> f32 {
    let ext = (bounds.1 - bounds.0).abs();
    let diag = ext.length();
    if !diag.is_finite() || diag <= 0.0 {
        return 1.0;
    }
    let e = ext.max(Vec3::splat(0.01 * diag));
    let volume = e.x as f64 * e.y as f64 * e.z as f64;
    (1.5 * (volume / n.max(1) as f64).cbrt()) as f32
}

fn check(n: usize, bounds: (Vec3, Vec3)) -> Result<()> {
    if n > MAX_LIGHTS {
        bail!("{n} lights requested, more than the {MAX_LIGHTS} supported (4 GiB of compact records)");
    }
    ensure!(bounds.0.is_finite() && bounds.1.is_finite() && (bounds.1 - bounds.0).is_finite(), "light bounds {bounds:?} are not finite in 32-bit floats");
    ensure!(bounds.0.cmple(bounds.1).all(), "light bounds {bounds:?} have a minimum above the maximum");
    Ok(())
}

/// `lights`, or an error naming the first one with a non-finite value: a scene whose extent (or
/// surface offset) is near the `f32` range gives positions, radii or intensities beyond it.
fn finite(lights: Vec<PointLight>) -> Result<Vec<PointLight>> {
    let bad = |l: &PointLight| !l.position.iter().chain(&l.colour).chain([&l.radius, &l.intensity]).all(|v| v.is_finite());
    if let Some(i) = lights.iter().position(bad) {
        bail!("generated light {i} is not finite ({:?}): the scene's extent or the surface offset is too large for 32-bit floats", lights[i]);
    }
    Ok(lights)
}

/// `n` lights uniform in the scene's bounds, radii uniform in `[0.5, 1.5]·r₀`
/// ([`default_radius`]), intensity [`DEFAULT_INTENSITY`].
pub fn uniform(scene: &Scene, n: usize, seed: u64) -> Result<Vec<PointLight>> {
    let r0 = default_radius(scene.bounds, n);
    uniform_in(scene.bounds, n, seed, (0.5 * r0, 1.5 * r0), DEFAULT_INTENSITY)
}

/// `n` lights uniform in `bounds`, radii uniform in `radius_range` (min, max); each light's
/// intensity is `intensity ·` [`radius_scaled_intensity`]`(radius)`.
pub fn uniform_in(bounds: (Vec3, Vec3), n: usize, seed: u64, radius_range: (f32, f32), intensity: f32) -> Result<Vec<PointLight>> {
    check(n, bounds)?;
    let (r_lo, r_hi) = radius_range;
    ensure!(r_lo.is_finite() && r_hi.is_finite() && 0.0 <= r_lo && r_lo <= r_hi, "light radius range {radius_range:?} must be finite with 0 ≤ min ≤ max");
    ensure!(intensity.is_finite() && intensity >= 0.0, "light intensity {intensity} must be finite and ≥ 0");
    let mut rng = Pcg32::new(seed);
    finite((0..n)
        .map(|_| {
            let p = rng.in_box(bounds);
            let radius = rng.range(r_lo, r_hi);
            PointLight { position: p.to_array(), radius, colour: saturated_colour(&mut rng), intensity: intensity * radius_scaled_intensity(radius) }
        })
        .collect())
}

/// `n` lights, [`HOTSPOT_FRACTION`] of them normally distributed (σ = 4 % of the diagonal,
/// clamped to the bounds) around `clusters` centres uniform in the middle 80 % of `bounds`, the
/// rest uniform. Radii uniform in `[0.25, 0.75]·r₀`: the crowded regions stay crowded.
pub fn hotspots(bounds: (Vec3, Vec3), n: usize, seed: u64, clusters: usize) -> Result<Vec<PointLight>> {
    check(n, bounds)?;
    ensure!((1..=MAX_HOTSPOT_CLUSTERS).contains(&clusters), "hotspot lights need 1..={MAX_HOTSPOT_CLUSTERS} clusters, got {clusters}");
    let mut rng = Pcg32::new(seed);
    let margin = (bounds.1 - bounds.0) * 0.1;
    let centres: Vec<Vec3> = (0..clusters).map(|_| rng.in_box((bounds.0 + margin, bounds.1 - margin))).collect();
    let sigma = 0.04 * (bounds.1 - bounds.0).length();
    let r0 = default_radius(bounds, n);
    finite((0..n)
        .map(|_| {
            let p = if rng.f32() < HOTSPOT_FRACTION {
                let c = centres[(rng.next_u32() as usize) % clusters];
                let offset = Vec3::new(rng.normal(), rng.normal(), rng.normal()) * sigma;
                (c + offset).clamp(bounds.0, bounds.1)
            } else {
                rng.in_box(bounds)
            };
            let radius = rng.range(0.25 * r0, 0.75 * r0);
            PointLight { position: p.to_array(), radius, colour: saturated_colour(&mut rng), intensity: DEFAULT_INTENSITY * radius_scaled_intensity(radius) }
        })
        .collect())
}

/// `n` lights on the scene's surfaces: triangles chosen with probability proportional to their
/// area, a uniform point on the triangle, pushed `offset` along its (geometric, CCW) normal.
/// Radii uniform in `[0.25, 0.75]·r₀` (surface lights sit close to what they light).
pub fn on_surfaces(scene: &Scene, n: usize, seed: u64, offset: f32) -> Result<Vec<PointLight>> {
    check(n, scene.bounds)?;
    ensure!(offset.is_finite(), "surface light offset {offset} is not finite");
    // Cumulative area over every triangle of every mesh, in f64 (Sponza has 262k triangles).
    let mut cdf = Vec::with_capacity(scene.triangle_count());
    let mut tris = Vec::with_capacity(scene.triangle_count());
    let mut total = 0.0f64;
    for (m, mesh) in scene.meshes.iter().enumerate() {
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let area = 0.5 * (b - a).cross(c - a).length() as f64;
            if area > 0.0 && area.is_finite() {
                total += area;
                cdf.push(total);
                tris.push((m, t));
            }
        }
    }
    if n > 0 && tris.is_empty() {
        bail!("scene {:?} has no triangle with a non-zero area to put lights on", scene.name);
    }
    let r0 = default_radius(scene.bounds, n);
    let mut rng = Pcg32::new(seed);
    finite((0..n)
        .map(|_| {
            let x = (rng.f32() as f64 * total).min(total);
            let k = cdf.partition_point(|&c| c <= x).min(tris.len() - 1);
            let (m, t) = tris[k];
            let [a, b, c] = scene.meshes[m].triangle(t);
            let (u, v) = (rng.f32().sqrt(), rng.f32());
            let p = a * (1.0 - u) + b * (u * (1.0 - v)) + c * (u * v);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            let radius = rng.range(0.25 * r0, 0.75 * r0);
            PointLight { position: (p + normal * offset).to_array(), radius, colour: saturated_colour(&mut rng), intensity: DEFAULT_INTENSITY * radius_scaled_intensity(radius) }
        })
        .collect())
}

/// Half-angles of generated spot lights: outer uniform in this range (degrees), inner a uniform
/// fraction [`SPOT_INNER_FRACTION`] of it.
pub const SPOT_OUTER_DEGREES: (f32, f32) = (20.0, 60.0);
pub const SPOT_INNER_FRACTION: (f32, f32) = (0.3, 0.9);

/// How generated lights got their spots: the share that are spots and the seed of the cones
/// ([`spot_cones`]), kept so that another count of lights gets its cones alike (the viewer's
/// `+` / `−`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotShare {
    pub fraction: f32,
    pub seed: u64,
}

impl SpotShare {
    /// The cones of `n` lights generated with this share ([`spot_cones`]).
    pub fn cones(&self, n: usize) -> Result<Vec<Option<Spot>>> {
        spot_cones(n, self.fraction, self.seed)
    }
}

/// Cones for `n` generated lights: each light is a spot with probability `fraction` (seeded, its
/// own stream: the lights themselves do not change with the fraction), pointing mostly down
/// (`−y` plus a random tilt up to ≈ 45°), half-angles [`SPOT_OUTER_DEGREES`]. Empty for
/// `fraction = 0` (a scene without spots).
pub fn spot_cones(n: usize, fraction: f32, seed: u64) -> Result<Vec<Option<Spot>>> {
    ensure!(fraction.is_finite() && (0.0..=1.0).contains(&fraction), "spot fraction {fraction} must be in [0, 1]");
    if fraction == 0.0 {
        return Ok(vec![]);
    }
    let mut rng = Pcg32::new(seed ^ 0x5907_5907_a11c_e5e5);
    Ok((0..n)
        .map(|_| {
            let tilt = Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0));
            let outer = rng.range(SPOT_OUTER_DEGREES.0, SPOT_OUTER_DEGREES.1).to_radians();
            let inner = outer * rng.range(SPOT_INNER_FRACTION.0, SPOT_INNER_FRACTION.1);
            (rng.f32() < fraction).then(|| Spot { direction: (Vec3::NEG_Y + tilt).normalize(), inner, outer })
        })
        .collect())
}

/// Light `i` at time `t` (seconds) moves on a horizontal circle (xz plane) around its base
/// position: circle radius `0.1 · light radius`, one turn every `4 + (i mod 7)` seconds, phase
/// `i · 2.39996` rad (golden angle), clockwise for odd `i`. At `t = 0` every light is displaced
/// by its circle radius along its phase direction; the motion is periodic and deterministic.
pub fn animate(base: &[PointLight], t: f32) -> Vec<PointLight> {
    base.iter()
        .enumerate()
        .map(|(i, l)| {
            let period = 4.0 + (i % 7) as f32;
            let sign = if i % 2 == 1 { -1.0 } else { 1.0 };
            let angle = i as f32 * 2.399_963 + sign * std::f32::consts::TAU * t / period;
            let r = 0.1 * l.radius;
            let mut out = *l;
            out.position[0] += r * angle.cos();
            out.position[2] += r * angle.sin();
            out
        })
        .collect()
}

/// Which of `n` lights cast shadows for a share `fraction` in [0, 1]: light `i` does where
/// `⌊(i + 1)·fraction⌋ > ⌊i·fraction⌋`, so `⌊n·fraction⌋` casters spread evenly over the
/// lights (every light at 1, none at 0).
pub fn shadow_casters(n: usize, fraction: f32) -> Result<Vec<bool>> {
    ensure!((0.0..=1.0).contains(&fraction), "shadow fraction {fraction} must be in [0, 1]");
    // The fraction as written (the f32's shortest decimal: 0.08, not 0.0799999982), so that
    // 200 lights at 0.08 give 16 casters.
    let f: f64 = fraction.to_string().parse().unwrap_or(fraction as f64);
    Ok((0..n).map(|i| ((i + 1) as f64 * f).floor() > (i as f64 * f).floor()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b() -> (Vec3, Vec3) {
        (Vec3::new(-10.0, 0.0, -50.0), Vec3::new(30.0, 8.0, 5.0))
    }

    fn inside(p: [f32; 3], (lo, hi): (Vec3, Vec3)) -> bool {
        let p = Vec3::from_array(p);
        p.cmpge(lo).all() && p.cmple(hi).all()
    }

    #[test]
    fn uniform_is_inside_the_bounds_and_seeded() {
        let a = uniform_in(b(), 5000, 7, (1.0, 2.0), 3.0).unwrap();
        assert_eq!(a.len(), 5000);
        assert!(a.iter().all(|l| inside(l.position, b()) && (1.0..=2.0).contains(&l.radius) && l.intensity == 3.0 * radius_scaled_intensity(l.radius)));
        assert_eq!(a, uniform_in(b(), 5000, 7, (1.0, 2.0), 3.0).unwrap(), "same seed, same lights");
        assert_ne!(a, uniform_in(b(), 5000, 8, (1.0, 2.0), 3.0).unwrap(), "another seed, other lights");
        // Spread: every eighth of the box gets some lights.
        let c = (b().0 + b().1) * 0.5;
        let mut octants = [0; 8];
        for l in &a {
            let p = Vec3::from_array(l.position);
            octants[(p.x > c.x) as usize + 2 * (p.y > c.y) as usize + 4 * (p.z > c.z) as usize] += 1;
        }
        assert!(octants.iter().all(|&o| o > 500), "{octants:?}");
        // Saturated, non-negative colours.
        assert!(a.iter().all(|l| l.colour.iter().all(|&c| (0.0..=1.0).contains(&c)) && l.colour.iter().cloned().fold(0.0, f32::max) == 1.0));
    }

    #[test]
    fn hotspots_cluster() {
        let cube = (Vec3::splat(-50.0), Vec3::splat(50.0));
        // Share of the lights in the 50 fullest of 10 × 10 × 10 cells.
        let crowding = |lights: &[PointLight]| {
            let mut cells = std::collections::HashMap::new();
            for l in lights {
                let q = ((Vec3::from_array(l.position) - cube.0) / 10.0).floor().min(Vec3::splat(9.0));
                *cells.entry((q.x as i32, q.y as i32, q.z as i32)).or_insert(0usize) += 1;
            }
            let mut counts: Vec<usize> = cells.into_values().collect();
            counts.sort_unstable_by(|a, b| b.cmp(a));
            counts.iter().take(50).sum::<usize>() as f32 / lights.len() as f32
        };
        let h = hotspots(cube, 4000, 3, 4).unwrap();
        assert!(h.iter().all(|l| inside(l.position, cube)));
        assert_eq!(h, hotspots(cube, 4000, 3, 4).unwrap());
        assert!(hotspots(b(), 500, 3, 2).unwrap().iter().all(|l| inside(l.position, b())));
        let u = uniform_in(cube, 4000, 3, (1.0, 1.0), 1.0).unwrap();
        let (ch, cu) = (crowding(&h), crowding(&u));
        assert!(ch > 0.5 && cu < 0.15, "the 5 % fullest cells hold {ch} of the hotspot lights, {cu} of uniform ones");
    }

    #[test]
    fn limits_and_degenerate_inputs() {
        let e = uniform_in(b(), MAX_LIGHTS + 1, 1, (1.0, 1.0), 1.0).unwrap_err().to_string();
        assert!(e.contains("more than"), "{e}");
        assert!(uniform_in(b(), 0, 1, (1.0, 1.0), 1.0).unwrap().is_empty());
        assert!(uniform_in(b(), 1, 1, (2.0, 1.0), 1.0).is_err());
        assert!(hotspots(b(), 10, 1, 0).is_err());
        assert!(hotspots(b(), 10, 1, MAX_HOTSPOT_CLUSTERS + 1).unwrap_err().to_string().contains("clusters"));
        // Found by fuzzing: inverted bounds put lights outside them.
        let e = uniform_in((Vec3::ONE, Vec3::ZERO), 1, 1, (1.0, 1.0), 1.0).unwrap_err().to_string();
        assert!(e.contains("minimum above the maximum"), "{e}");
        // An extent past f32 (finite corners), and radii whose intensity overflows.
        assert!(uniform_in((Vec3::splat(-3e38), Vec3::splat(3e38)), 1, 1, (1.0, 1.0), 1.0).is_err());
        let e = uniform_in(b(), 3, 1, (1e30, 1e30), 1.0).unwrap_err().to_string();
        assert!(e.contains("generated light 0 is not finite"), "{e}");
        let point = (Vec3::ONE, Vec3::ONE);
        assert!(uniform_in(point, 10, 1, (1.0, 1.0), 1.0).unwrap().iter().all(|l| l.position == [1.0; 3]));
        assert_eq!(default_radius(point, 10), 1.0);
        // More lights → smaller lights (r ∝ n^(-1/3)).
        let (r1, r8) = (default_radius(b(), 1000), default_radius(b(), 8000));
        assert!((r1 / r8 - 2.0).abs() < 1e-3, "{r1} {r8}");
    }

    #[test]
    fn animation_is_periodic_and_small() {
        let base = uniform_in(b(), 50, 2, (1.0, 2.0), 1.0).unwrap();
        let a0 = animate(&base, 0.0);
        assert_eq!(a0, animate(&base, 0.0));
        let period = 2520.0; // lcm(4..=10): a multiple of every period
        for (i, (l, m)) in base.iter().zip(animate(&base, 1.3)).enumerate() {
            let d = Vec3::from_array(l.position).distance(Vec3::from_array(m.position));
            assert!((d - 0.1 * l.radius).abs() < 1e-4, "light {i} is {d} from its base");
            assert_eq!(l.position[1], m.position[1]);
        }
        for (a, c) in a0.iter().zip(animate(&base, period)) {
            assert!(Vec3::from_array(a.position).distance(Vec3::from_array(c.position)) < 1e-2);
        }
    }

    #[test]
    fn shadow_casters_are_the_share_spread_evenly() {
        assert!(shadow_casters(40, 0.0).unwrap().iter().all(|&c| !c));
        assert!(shadow_casters(40, 1.0).unwrap().iter().all(|&c| c));
        let quarter = shadow_casters(40, 0.25).unwrap();
        assert_eq!(quarter.iter().filter(|&&c| c).count(), 10);
        // One caster in every run of four lights.
        assert!(quarter.chunks(4).all(|c| c.iter().filter(|&&c| c).count() == 1), "{quarter:?}");
        assert_eq!(shadow_casters(7, 0.5).unwrap().iter().filter(|&&c| c).count(), 3);
        assert_eq!(shadow_casters(200, 0.08).unwrap().iter().filter(|&&c| c).count(), 16, "0.08 as written, not as its f32");
        assert!(shadow_casters(3, 1.5).is_err() && shadow_casters(3, f32::NAN).is_err());
    }
}

/// The order the light buffer stores a scene's lights in (`--light-order`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LightOrder {
    /// As the description lists them or the generator made them.
    Given,
    /// In the Morton order of their world positions ([`spatial_order`]).
    #[default]
    Spatial,
}

impl LightOrder {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Given => "given",
            Self::Spatial => "spatial",
        }
    }
}

/// The box of the lights' positions, `(min, max)` per axis (`[0; 3], [1; 3]` for no lights):
/// what the Morton quantisers of [`spatial_order`] and the light BVH (`render::bvh`) span.
pub fn position_bounds(lights: &[PointLight]) -> ([f32; 3], [f32; 3]) {
    if lights.is_empty() {
        return ([0.0; 3], [1.0; 3]);
    }
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for l in lights {
        for a in 0..3 {
            lo[a] = lo[a].min(l.position[a]);
            hi[a] = hi[a].max(l.position[a]);
        }
    }
    (lo, hi)
}

/// Radix digit of [`spatial_order`]'s host sort: three passes of 10 bits order the 30-bit keys.
const SPATIAL_DIGIT_BITS: u32 = 10;

/// The storage order along the Morton curve of the lights' positions (`--light-order spatial`,
/// [`Scene::order_lights_spatially`]): `order[k]` is the light with the k-th smallest 30-bit
/// Morton code in the box of all light positions, ties in the given order (a stable LSD radix
/// sort, three passes of [`SPATIAL_DIGIT_BITS`]; 16 B per light while it runs).
///
/// Why: the light BVH sorts the lights by the Morton code of their *view-space* positions every
/// frame and gathers each light's sphere by its sorted index. The view transform is rigid, so
/// lights adjacent in that order are near each other in space, and with the buffer in world
/// Morton order near each other in memory too: the gather reads a few pages per workgroup
/// instead of a random page per light, and so do the shading's reads of a cluster's lights.
pub fn spatial_order(lights: &[PointLight]) -> Vec<u32> {
    let n = lights.len();
    let (lo, hi) = position_bounds(lights);
    let q = shaders::morton::MortonQuantizer::new(lo, hi, shaders::morton::MORTON30_BITS);
    // Key in the high word, index in the low one: the sort moves one u64 per light.
    let mut pairs: Vec<u64> = lights.iter().enumerate().map(|(i, l)| ((q.morton30_of(l.position) as u64) << 32) | i as u64).collect();
    let mut out = vec![0u64; n];
    let digits = 1usize << SPATIAL_DIGIT_BITS;
    for pass in 0..(3 * shaders::morton::MORTON30_BITS).div_ceil(SPATIAL_DIGIT_BITS) {
        let shift = 32 + pass * SPATIAL_DIGIT_BITS;
        let digit = |p: u64| ((p >> shift) as usize) & (digits - 1);
        let mut start = vec![0usize; digits + 1];
        for &p in &pairs {
            start[digit(p) + 1] += 1;
        }
        for d in 0..digits {
            start[d + 1] += start[d];
        }
        for &p in &pairs {
            let d = digit(p);
            out[start[d]] = p;
            start[d] += 1;
        }
        std::mem::swap(&mut pairs, &mut out);
    }
    pairs.into_iter().map(|p| p as u32).collect()
}

/// `v` in `order` (`v[order[k]]` at `k`); an empty `v` (a scene without spots or casters) stays
/// empty.
pub fn permuted<T: Copy>(v: &[T], order: &[u32]) -> Vec<T> {
    if v.is_empty() {
        return vec![];
    }
    order.iter().map(|&i| v[i as usize]).collect()
}
