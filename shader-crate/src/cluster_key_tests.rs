//! CPU tests of the cluster-key functions, hard cases included (1×1 and 8K grids, near/far planes).
use super::*;

const FOV: f32 = core::f32::consts::FRAC_PI_3; // 60°

fn grid(w: u32, h: u32) -> ClusterGrid {
    ClusterGrid::new(w, h, 32, 0.1, 1000.0, FOV).expect("valid grid")
}

fn next_down(x: f32) -> f32 {
    assert!(x > 0.0);
    f32::from_bits(x.to_bits() - 1)
}

#[test]
fn bits_for_counts() {
    assert_eq!([bits_for(0), bits_for(1), bits_for(2), bits_for(3), bits_for(4)], [0, 0, 1, 2, 2]);
    assert_eq!([bits_for(120), bits_for(128), bits_for(129), bits_for(240)], [7, 7, 8, 8]);
}

#[test]
fn seed_layout_at_4k_is_7_plus_7() {
    let g = grid(3840, 2160);
    assert_eq!((g.tiles_x, g.tiles_y), (120, 68));
    assert_eq!((g.bits_i, g.bits_j), (7, 7));
    assert!(g.bits_i + g.bits_j + g.bits_k <= 32);
}

#[test]
fn resolutions_and_last_row_column() {
    for (w, h, tiles) in [(1, 1, (1, 1)), (33, 17, (2, 1)), (3840, 2160, (120, 68)), (7680, 4320, (240, 135))] {
        let g = grid(w, h);
        let b = slice_bounds(&g);
        assert_eq!((g.tiles_x, g.tiles_y), tiles, "{w}x{h}");
        // Last column / row / corner land in the last (partial) tile, never beyond.
        assert_eq!(g.tile_of_pixel(w - 1, 0), (tiles.0 - 1, 0));
        assert_eq!(g.tile_of_pixel(0, h - 1), (0, tiles.1 - 1));
        assert_eq!(g.tile_of_pixel(w - 1, h - 1), (tiles.0 - 1, tiles.1 - 1));
        // Out-of-image pixels are clamped.
        assert_eq!(g.tile_of_pixel(w + 100, h + 100), (tiles.0 - 1, tiles.1 - 1));
        // Keys of the four corners at the nearest and farthest slice round-trip.
        let last_k = g.num_slices - 1;
        for (px, py) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
            for (z, k) in [(-0.1, 0), (-1000.0, last_k)] {
                let key = g.key(&b, px, py, z);
                let (i, j) = g.tile_of_pixel(px, py);
                assert_eq!(g.unpack(key), (i, j, k), "{w}x{h} pixel ({px},{py}) z={z}");
            }
        }
        assert!(g.key_space() <= 1u64 << 32);
    }
}

#[test]
fn pack_is_injective_on_a_small_grid() {
    let g = ClusterGrid::new(200, 100, 16, 0.5, 50.0, FOV).unwrap();
    let mut seen = std::collections::HashSet::new();
    for k in 0..g.num_slices {
        for j in 0..g.tiles_y {
            for i in 0..g.tiles_x {
                let key = g.pack(i, j, k);
                assert_eq!(g.unpack(key), (i, j, k));
                assert!(seen.insert(key), "duplicate key {key:#x}");
            }
        }
    }
}

#[test]
fn depth_edge_cases() {
    let g = grid(1920, 1080);
    let b = slice_bounds(&g);
    let last = g.num_slices - 1;
    let s = |z: f32| g.slice_of_depth(&b, -z);
    assert_eq!(s(-g.near), 0, "exactly at near");
    assert_eq!(s(-next_down(g.near)), 0, "just in front of near");
    assert_eq!(s(0.0), 0, "at the eye");
    assert_eq!(s(-0.0), 0, "negative zero");
    assert_eq!(s(5.0), 0, "behind the camera");
    assert_eq!(s(f32::INFINITY), 0, "infinitely behind");
    assert_eq!(s(f32::NAN), 0, "NaN");
    assert_eq!(s(-next_down(g.far)), last, "just inside far");
    assert_eq!(s(-g.far), last, "at far");
    assert_eq!(s(-2.0 * g.far), last, "beyond far");
    assert_eq!(s(-f32::MAX), last, "huge depth");
    assert_eq!(s(f32::NEG_INFINITY), last, "infinitely far");
    // The last slice really contains far.
    assert!(b[last as usize] <= g.far && g.far <= b[last as usize + 1]);
}

/// A point on a boundary lands in exactly one slice, and the key function agrees with the bound
/// function everywhere.
#[test]
fn slice_boundaries_agree_with_bounds() {
    for (w, h) in [(1, 1), (33, 17), (1920, 1080), (7680, 4320)] {
        let g = grid(w, h);
        let b = slice_bounds(&g);
        assert_eq!(b.len() as u32, g.num_slices + 1);
        assert_eq!(b[0], g.near);
        for k in 0..g.num_slices {
            assert_eq!(g.slice_of_depth(&b, b[k as usize]), k, "{w}x{h}: boundary of slice {k}");
            if k > 0 {
                assert_eq!(g.slice_of_depth(&b, next_down(b[k as usize])), k - 1, "{w}x{h}: below boundary {k}");
            }
        }
        // Dense sweep: the slice interval contains the depth; the log guess is off by at most 1.
        let mut d = g.near;
        let mut max_guess_error = 0;
        while d < g.far {
            let k = g.slice_of_depth(&b, d);
            assert!(b[k as usize] <= d && d < b[k as usize + 1], "{w}x{h}: d={d} k={k}");
            max_guess_error = max_guess_error.max(g.slice_guess(d).abs_diff(k));
            d *= 1.000_37;
        }
        assert!(max_guess_error <= 1, "log guess off by {max_guess_error}");
    }
}

#[test]
fn invalid_grids_are_errors() {
    let e = |r: Result<ClusterGrid, GridError>| r.expect_err("must be rejected").to_string();
    assert!(e(ClusterGrid::new(0, 10, 32, 0.1, 10.0, FOV)).contains("resolution 0x10"));
    assert!(e(ClusterGrid::new(10, 0, 32, 0.1, 10.0, FOV)).contains("resolution"));
    assert!(e(ClusterGrid::new(10, 10, 0, 0.1, 10.0, FOV)).contains("tile size 0"));
    assert!(e(ClusterGrid::new(10, 10, 32, 0.0, 10.0, FOV)).contains("depth range"));
    assert!(e(ClusterGrid::new(10, 10, 32, 1.0, 1.0, FOV)).contains("depth range"));
    assert!(e(ClusterGrid::new(10, 10, 32, f32::NAN, 1.0, FOV)).contains("depth range"));
    assert!(e(ClusterGrid::new(10, 10, 32, 0.1, f32::INFINITY, FOV)).contains("depth range"));
    assert!(e(ClusterGrid::new(10, 10, 32, 0.1, 10.0, 0.0)).contains("field of view"));
    assert!(e(ClusterGrid::new(10, 10, 32, 0.1, 10.0, f32::NAN)).contains("field of view"));
    assert!(e(ClusterGrid::new(10, 10, 32, 0.1, 10.0, 4.0)).contains("field of view"));
    // 1 px tiles at 32768² need 15 + 15 bits for (i, j): no room left for 28 slices (5 bits).
    assert!(e(ClusterGrid::new(32768, 32768, 1, 0.1, 0.1001, FOV)).contains("15+15+5 bits > 32"));
    // … and with a deep range the slice count itself is refused first.
    assert!(e(ClusterGrid::new(32768, 32768, 1, 0.1, 1000.0, FOV)).contains("slices"));
    assert!(e(ClusterGrid::new(1000, 1000, 1, 1e-30, 1e30, 0.001)).contains("slices"));
}
