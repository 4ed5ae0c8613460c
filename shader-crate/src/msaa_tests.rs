//! CPU tests of `msaa`: sample locations, the sample position, the edge test, the albedo word and
//! the edge pixel's mean colour, each against a closed form.
use super::*;
use crate::layout::{ClusterGrid, FrameParams, MaterialGpu, VIEW_SHADED};

fn grid(w: u32, h: u32) -> ClusterGrid {
    ClusterGrid::new(w, h, 32, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).expect("valid grid")
}

fn frame(w: u32, h: u32) -> FrameParams {
    FrameParams {
        grid: grid(w, h),
        count: w * h,
        num_lights: 0,
        light_capacity: 0,
        effects: 0,
        normal_precision: PRECISION_F32,
        view: VIEW_SHADED,
        exposure: 1.0,
        heat_max: 64,
    }
}

#[test]
fn sample_locations_are_vulkans_standard_ones() {
    // Vulkan 1.3 §28.4, Table "Standard sample locations", in pixels.
    let spec: [&[(f32, f32)]; 4] = [
        &[(0.5, 0.5)],
        &[(0.75, 0.75), (0.25, 0.25)],
        &[(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)],
        &[(0.5625, 0.3125), (0.4375, 0.6875), (0.8125, 0.5625), (0.3125, 0.1875), (0.1875, 0.8125), (0.0625, 0.4375), (0.6875, 0.9375), (0.9375, 0.0625)],
    ];
    for (n, want) in SAMPLE_COUNTS.iter().zip(spec) {
        assert_eq!(want.len() as u32, *n);
        for (s, &(x, y)) in want.iter().enumerate() {
            let (ox, oy) = sample_location(*n, s as u32);
            assert_eq!((ox as f32 / 16.0, oy as f32 / 16.0), (x, y), "{n} samples, sample {s}");
        }
        // Each pattern is centred on the pixel centre.
        let (sx, sy) = (0..*n).map(|s| sample_location(*n, s)).fold((0, 0), |a, l| (a.0 + l.0, a.1 + l.1));
        assert_eq!((sx, sy), (8 * n, 8 * n), "{n} samples");
    }
    assert_eq!(*SAMPLE_COUNTS.iter().max().unwrap(), MAX_SAMPLES);
}

#[test]
fn sample_positions_lie_on_the_view_ray_of_their_framebuffer_point() {
    for (w, h) in [(1, 1), (7, 5), (1280, 720), (7680, 4320)] {
        let g = grid(w, h);
        for (px, py) in [(0, 0), (w - 1, h - 1), (w / 2, h / 3)] {
            for d in [0.1f32, 3.7, 900.0] {
                // At the centre, bit for bit the per-pixel position.
                assert_eq!(reconstruct::sample_position(&g, px, py, 8, 8, d), reconstruct::view_position(&g, px, py, d));
                for samples in SAMPLE_COUNTS {
                    for s in 0..samples {
                        let (ox, oy) = sample_location(samples, s);
                        let p = reconstruct::sample_position(&g, px, py, ox, oy, d);
                        // Closed form in f64: ndc of the point, times tan θ · d (aspect from W/H).
                        let (fx, fy) = (px as f64 + ox as f64 / 16.0, py as f64 + oy as f64 / 16.0);
                        let ndc = (2.0 * fx / w as f64 - 1.0, 1.0 - 2.0 * fy / h as f64);
                        let t = g.tan_half_fov_y as f64 * d as f64;
                        let want = (ndc.0 * t * w as f64 / h as f64, ndc.1 * t);
                        let tol = 1e-6 * t.max(1e-3) * (w as f64 / h as f64).max(1.0);
                        assert!((p.x as f64 - want.0).abs() <= tol && (p.y as f64 - want.1).abs() <= tol && p.z == -d, "{w}x{h} ({px},{py}) sample {s}/{samples}: {p:?} vs {want:?}");
                    }
                }
            }
        }
    }
}

fn key(depth: f32, normal: [f32; 3], albedo: u32) -> SampleKey {
    SampleKey { depth, normal: Vec3::from_array(normal), albedo, ray: Vec3::new(0.0, 0.0, -1.0) }
}

/// A sample of pixel `(px, py)` of `g` at location `s` of 4 on the plane `n·p = c` (view space).
fn on_plane(g: &ClusterGrid, px: u32, py: u32, s: u32, n: Vec3, c: f32, albedo: u32) -> SampleKey {
    let (ox, oy) = sample_location(4, s);
    let ray = reconstruct::sample_position(g, px, py, ox, oy, 1.0);
    let d = c / n.dot(ray);
    SampleKey { depth: g.near / d, normal: n, albedo, ray }
}

#[test]
fn edges_are_other_surfaces_and_only_those() {
    let near = 0.1;
    let z = |d: f32| near / d;
    let up = [0.0, 0.0, 1.0];
    let a = key(z(10.0), up, 0x01_80_80_80);
    // A plane facing the eye: another depth on the same ray within the tolerance is the same
    // surface, past it not, either way round.
    assert!(!differs(near, &a, &key(z(10.0 * (1.0 + 0.5 * EDGE_DEPTH_RELATIVE)), up, a.albedo)));
    assert!(!differs(near, &a, &a));
    assert!(differs(near, &a, &key(z(10.0 * (1.0 + 2.0 * EDGE_DEPTH_RELATIVE)), up, a.albedo)));
    assert!(differs(near, &key(z(10.0 * (1.0 + 2.0 * EDGE_DEPTH_RELATIVE)), up, a.albedo), &a));
    // Sky against geometry; sky against sky is no edge.
    assert!(differs(near, &a, &key(0.0, up, 0)));
    assert!(differs(near, &key(0.0, up, 0), &a));
    assert!(!differs(near, &key(0.0, up, 0), &key(0.0, [1.0, 0.0, 0.0], 7)));
    // Another material or albedo.
    assert!(differs(near, &a, &key(a.depth, up, 0x02_80_80_80)));
    assert!(differs(near, &a, &key(a.depth, up, 0x01_80_80_81)));
    // Normals: 1° apart is the same surface, 10° is not (threshold ≈ 5.7°).
    let tilt = |deg: f32| [deg.to_radians().sin(), 0.0, deg.to_radians().cos()];
    assert!(!differs(near, &a, &key(a.depth, tilt(1.0), a.albedo)));
    assert!(differs(near, &a, &key(a.depth, tilt(10.0), a.albedo)));
    assert!(differs(near, &a, &key(a.depth, [f32::NAN; 3], a.albedo)), "a NaN normal is an edge");
    // A floor seen at a grazing angle: its samples' distances differ by far more than the
    // tolerance, yet they lie on one plane: no edge. A parallel floor below it is one.
    let g = ClusterGrid::new(160, 90, 32, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).unwrap();
    let floor = Vec3::new(0.0, 1.0, 0.0);
    let (px, py) = (80, 46);
    let samples: Vec<SampleKey> = (0..4).map(|s| on_plane(&g, px, py, s, floor, -1.0, 7)).collect();
    let d = |k: &SampleKey| near / k.depth;
    let spread = samples.iter().map(d).fold(0.0f32, f32::max) / samples.iter().map(d).fold(f32::MAX, f32::min);
    assert!(spread > 1.0 + 4.0 * EDGE_DEPTH_RELATIVE, "the test floor should be steep in depth: ×{spread}");
    assert!(!is_edge(near, 4, |s| samples[s as usize]), "one plane, however slanted, is no edge");
    let lower = on_plane(&g, px, py, 1, floor, -1.1, 7);
    assert!(is_edge(near, 4, |s| if s == 1 { lower } else { samples[s as usize] }), "a parallel plane below is an edge");
    // A plane seen edge-on keeps no sample of another ray.
    let edge_on = SampleKey { normal: Vec3::new(1.0, 0.0, 0.0), ..a };
    assert!(differs(near, &edge_on, &SampleKey { ray: Vec3::new(0.01, 0.0, -1.0), ..edge_on }));
    // A pixel is an edge when any sample differs from sample 0, whatever the count.
    for samples in [2, 4, 8] {
        for odd in 1..samples {
            let k = |s: u32| if s == odd { key(0.0, up, 0) } else { a };
            assert!(is_edge(near, samples, k), "{samples} samples, sample {odd} sky");
        }
        assert!(!is_edge(near, samples, |_| a));
    }
    assert!(!is_edge(near, 1, |_| key(0.0, up, 0)), "one sample is never an edge");
}

#[test]
fn albedo_words_survive_the_unorm_target() {
    for c in 0..=255u32 {
        let word = c | ((255 - c) << 8) | (((c * 7) & 255) << 16) | (((c * 13) & 255) << 24);
        let texel = |shift: u32| ((word >> shift) & 255) as f32 / 255.0;
        assert_eq!(albedo_word(glam::Vec4::new(texel(0), texel(8), texel(16), texel(24))), word);
    }
}

#[test]
fn an_edge_pixel_is_the_mean_of_its_samples_colours() {
    let samples = 4;
    let mut p = frame(4, 2);
    p.grid.samples = samples as u32;
    let n = p.count as usize;
    let i = 5u32;
    let materials = [<MaterialGpu as bytemuck::Zeroable>::zeroed(); 2];
    let mut depth = vec![0.0f32; samples * n];
    let mut normals = vec![0u32; 4 * samples * n];
    let mut albedo = vec![0u32; samples * n];
    // Samples 0 and 2 see a surface at distance 2, samples 1 and 3 the sky.
    for s in [0usize, 2] {
        let e = s * n + i as usize;
        depth[e] = p.grid.near / 2.0;
        let one = 1.0f32.to_bits();
        normals[4 * e + 2] = one;
        albedo[e] = 0x01_ff_ff_ff;
    }
    let radiance = Vec3::new(0.25, 0.5, 1.0);
    let colour = shade_edge_pixel(&p, i, &[], &depth, &normals, &albedo, &materials, |_, _| (radiance, 0));
    let lit = lighting::decode_srgb8(lighting::encode_srgb8(lighting::tonemap(radiance, p.exposure)));
    let sky = lighting::decode_srgb8(shading::BACKGROUND_RGBA8);
    assert_eq!(colour, lighting::encode_srgb8((lit + sky) * 0.5));
    // Every sample on the surface: the single colour.
    let single = FrameParams { grid: ClusterGrid { samples: 1, ..p.grid }, ..p };
    let colour = shade_edge_pixel(&single, i, &[], &depth, &normals, &albedo, &materials, |_, _| (radiance, 0));
    assert_eq!(colour, lighting::encode_srgb8(lit));
    // The shading function sees each sample's own position.
    let seen = core::cell::RefCell::new(Vec::new());
    shade_edge_pixel(&p, i, &[], &depth, &normals, &albedo, &materials, |_, s| {
        seen.borrow_mut().push(s.pos);
        (radiance, 0)
    });
    let (px, py) = (i % p.grid.width, i / p.grid.width);
    let want: Vec<Vec3> = [0, 2]
        .iter()
        .map(|&s| {
            let (ox, oy) = sample_location(4, s);
            reconstruct::sample_position(&p.grid, px, py, ox, oy, 2.0)
        })
        .collect();
    assert_eq!(*seen.borrow(), want);
}

#[test]
fn normals_survive_the_float_target() {
    use crate::octahedral::{encode, Precision};
    let mut rng = crate::test_support::Rng(5);
    for precision in Precision::ALL {
        for k in 0..20_000 {
            let v = [rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0];
            let v = if k == 0 { [0.0, -0.0, 1.0] } else { v };
            let w = encode(v, precision);
            let back = normal_words(float_normal(w, precision.code()), precision.code());
            assert_eq!(back[..precision.gbuffer_words().min(3) as usize], w[..precision.gbuffer_words().min(3) as usize], "{precision:?} {v:?}");
        }
        // Every 16-bit half of an octahedral word is an integer a float holds exactly.
        if precision.gbuffer_words() == 1 {
            for w in [0u32, 1, 0xffff, 0x1_0000, 0xffff_ffff, 0x8000_8000] {
                assert_eq!(normal_words(float_normal([w, 0, 0], precision.code()), precision.code())[0], w);
            }
        }
    }
}
