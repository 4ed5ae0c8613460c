//! CPU tests of `reconstruct`.
use super::*;

const FOV: f32 = core::f32::consts::FRAC_PI_3; // 60°

fn grid(w: u32, h: u32) -> ClusterGrid {
    ClusterGrid::new(w, h, 32, 0.1, 1000.0, FOV).expect("valid grid")
}

fn next_up(x: f32) -> f32 {
    assert!(x >= 0.0);
    f32::from_bits(x.to_bits() + 1)
}

#[test]
fn background_classification() {
    for z in [0.0, -0.0, -1.0, f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40, f32::from_bits(1)] {
        assert!(is_background(z), "{z:e}");
        assert_eq!(distance_from_depth(0.1, z), f32::INFINITY, "{z:e}");
    }
    for z in [f32::MIN_POSITIVE, 1e-30, 0.5, 1.0, 2.0, f32::MAX] {
        assert!(!is_background(z), "{z:e}");
        let d = distance_from_depth(0.1, z);
        assert!(d.is_finite() && d >= 0.0 && d <= MAX_DISTANCE, "{z:e} -> {d:e}");
    }
}

#[test]
fn max_distance_is_two_to_the_64() {
    assert_eq!(MAX_DISTANCE as f64, 2f64.powi(64));
    // Tiny depths clamp to it instead of overflowing.
    assert_eq!(distance_from_depth(100.0, f32::MIN_POSITIVE), MAX_DISTANCE);
    assert_eq!(distance_from_depth(1e30, 1e-3), MAX_DISTANCE);
}

#[test]
fn depth_distance_round_trip() {
    for near in [1e-3f32, 0.1, 1.0, 7.5] {
        assert_eq!(distance_from_depth(near, 1.0), near, "near plane");
        let mut d = near;
        while d < 1e9 {
            let z = near / d; // what the rasteriser stores
            let back = distance_from_depth(near, z);
            // Two correctly rounded divisions: |back/d − 1| ≤ 2u(1+u).
            let rel = ((back as f64) / (d as f64) - 1.0).abs();
            assert!(rel <= 2.0 * 2f64.powi(-24) * 1.000001, "near {near} d {d} -> {back} (rel {rel:e})");
            d *= 1.013;
        }
    }
}

#[test]
fn distance_is_monotone_in_depth() {
    let near = 0.1;
    let mut z = 1.0f32;
    let mut prev = distance_from_depth(near, z);
    while z > 1e-37 {
        z *= 0.9993;
        let d = distance_from_depth(near, z);
        assert!(d >= prev, "z {z:e}: {d} < {prev}");
        prev = d;
    }
    // Also across one-ULP steps near 1.
    let mut z = 1.0f32;
    let mut prev = distance_from_depth(near, z);
    for _ in 0..100_000 {
        z = f32::from_bits(z.to_bits() - 1);
        let d = distance_from_depth(near, z);
        assert!(d >= prev);
        prev = d;
    }
}

/// The reconstruction formula in f64: `(ndc_x·tanθ·aspect·d, ndc_y·tanθ·d, −d)`.
fn reference(g: &ClusterGrid, px: u32, py: u32, d: f32) -> [f64; 3] {
    let (w, h) = (g.width as f64, g.height as f64);
    let t = g.tan_half_fov_y as f64;
    let ndc_x = 2.0 * (px as f64 + 0.5) / w - 1.0;
    let ndc_y = 1.0 - 2.0 * (py as f64 + 0.5) / h;
    let d = d as f64;
    [ndc_x * t * (w / h) * d, ndc_y * t * d, -d]
}

#[test]
fn corner_pixels_at_known_distance() {
    for (w, h) in [(1, 1), (33, 17), (1920, 1080), (3840, 2160), (7680, 4320)] {
        let g = grid(w, h);
        let aspect = w as f64 / h as f64;
        let t = g.tan_half_fov_y as f64;
        for d in [0.1f32, 1.0, 10.0, 12345.0] {
            let (dd, u) = (d as f64, 2f64.powi(-24));
            let tl = view_position(&g, 0, 0, d);
            let br = view_position(&g, w - 1, h - 1, d);
            // Top-left is left (x < 0) and up (y > 0) by half a pixel less than the frustum edge.
            let ex = (1.0 / w as f64 - 1.0) * t * aspect * dd;
            let ey = (1.0 - 1.0 / h as f64) * t * dd;
            let tol = 4.0 * u * t * aspect.max(1.0) * dd;
            if w > 1 {
                assert!(tl.x < 0.0 && tl.y > 0.0);
            }
            assert!((tl.x as f64 - ex).abs() <= tol, "{w}x{h} d {d}: x {} vs {ex}", tl.x);
            assert!((tl.y as f64 - ey).abs() <= tol, "{w}x{h} d {d}: y {} vs {ey}", tl.y);
            assert_eq!(tl.z, -d);
            // Exact point symmetry: the numerators of opposite corners are negatives.
            assert_eq!((br.x, br.y, br.z), (-tl.x, -tl.y, -d));
            // The centre pixel of an odd dimension is on the axis exactly.
            if w % 2 == 1 {
                assert_eq!(view_position(&g, w / 2, 0, d).x, 0.0);
            }
            if h % 2 == 1 {
                assert_eq!(view_position(&g, 0, h / 2, d).y, 0.0);
            }
        }
    }
}

#[test]
fn matches_the_ndc_formula_and_primary_rays() {
    let mut s = 0x1234_5678_9abc_def0u64;
    let mut rnd = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 33) as u32
    };
    for (w, h) in [(33, 17), (1920, 1080), (7680, 4320), (5, 3000)] {
        let g = grid(w, h);
        let half_w = g.tan_half_fov_y as f64 * (w as f64 / h as f64).max(1.0);
        for _ in 0..20_000 {
            let (px, py) = (rnd() % w, rnd() % h);
            let d = 0.1 * 1.0001f32.powi((rnd() % 200_000) as i32);
            let p = view_position(&g, px, py, d);
            let r = reference(&g, px, py, d);
            // Relative error ≤ 3u of the coordinate (module docs); compare against the frustum
            // half-width as the f64 reference itself has cancellation in `… − 1`.
            for a in 0..2 {
                let err = (p.to_array()[a] as f64 - r[a]).abs();
                assert!(err <= 3.5 * 2f64.powi(-24) * half_w * d as f64, "{w}x{h} ({px},{py}) d {d}: {p:?} vs {r:?}");
            }
            assert_eq!(p.z as f64, r[2]);
        }
        // Same direction as the debug view's primary ray.
        let params = crate::layout::DebugViewParams { grid: g, view: 0, precision: 0, _pad: [0; 2] };
        for (px, py) in [(0, 0), (w - 1, h - 1), (w / 3, h / 2), (w / 2, 0)] {
            let dir = crate::debug_view::primary_ray(&params, px, py);
            let p = view_position(&g, px, py, 2.0).normalize();
            assert!((p - dir).length() < 1e-6, "{w}x{h} ({px},{py}): {p:?} vs {dir:?}");
        }
    }
}

#[test]
fn monotone_in_pixel_and_distance() {
    for (w, h) in [(33, 17), (1920, 1080)] {
        let g = grid(w, h);
        for d in [0.1f32, 0.37, 5.0, 999.0, 1e6, MAX_DISTANCE] {
            let mut prev = f32::NEG_INFINITY;
            for px in 0..w {
                let x = view_position(&g, px, 5 % h, d).x;
                assert!(x > prev, "x must increase with px");
                prev = x;
            }
            let mut prev = f32::INFINITY;
            for py in 0..h {
                let y = view_position(&g, 7 % w, py, d).y;
                assert!(y < prev, "y must decrease with py (row 0 at the top)");
                prev = y;
            }
        }
        for (px, py) in [(0, 0), (w - 1, h - 1), (w / 2, h / 2), (3, h - 2)] {
            let mut prev = view_position(&g, px, py, 0.0);
            assert_eq!(prev.to_array().map(|c| c.abs()), [0.0; 3]);
            let mut d = 1e-3f32;
            while d < 1e7 {
                let p = view_position(&g, px, py, d);
                assert!(p.x.abs() >= prev.x.abs() && p.y.abs() >= prev.y.abs() && p.z < prev.z);
                assert!(p.x * prev.x >= 0.0 && p.y * prev.y >= 0.0, "sign never flips");
                prev = p;
                d = next_up(d * 1.01);
            }
        }
    }
}

#[test]
fn positions_stay_finite_at_the_extremes() {
    // Widest aspect, widest field of view, farthest distance the depth buffer can produce.
    let g = ClusterGrid::new(32768, 2, 1024, 1e-3, 1e6, 3.1415925).expect("valid grid");
    for (px, py) in [(0, 0), (32767, 1), (16384, 0)] {
        let p = view_position(&g, px, py, MAX_DISTANCE);
        assert!(p.is_finite(), "{p:?}");
        assert!(p.x.abs() < 2f32.powi(105));
    }
}
