//! CPU tests of `cluster_bounds`: every reconstructed pixel position lies in its own cluster's box.
use super::*;
use crate::cluster_key::slice_bounds;
use crate::reconstruct::{pixel_numerator_x, pixel_numerator_y, view_position};

const U: f64 = 1.0 / 16_777_216.0; // 2^-24

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // splitmix64
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Grids under test: odd sizes, partial tiles, 8K, 1-pixel tiles, extreme fields of view.
fn grids() -> Vec<ClusterGrid> {
    let fov = core::f32::consts::FRAC_PI_3;
    [
        (33, 17, 32, 0.1, 1000.0, fov),
        (1, 1, 1, 0.1, 10.0, fov),
        (100, 37, 7, 0.05, 300.0, 1.2),
        (1920, 1080, 32, 0.1, 1000.0, fov),
        (3840, 2160, 32, 0.1, 1000.0, fov),
        (7680, 4320, 32, 0.1, 1000.0, fov),
        (1280, 720, 16, 1.0, 1e5, 0.01),
        (640, 480, 64, 1e-3, 1e7, 3.0),
        (32768, 2, 1024, 1e-3, 1e6, 3.141_592_5),
    ]
    .iter()
    .map(|&(w, h, t, n, f, fov)| ClusterGrid::new(w, h, t, n, f, fov).expect("valid grid"))
    .collect()
}

fn inside(p: [f32; 3], lo: [f32; 3], hi: [f32; 3]) -> bool {
    (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a])
}

fn next_up(x: f32) -> f32 {
    if x == 0.0 {
        f32::from_bits(1)
    } else if x > 0.0 {
        f32::from_bits(x.to_bits() + 1)
    } else {
        f32::from_bits(x.to_bits() - 1)
    }
}

fn next_down(x: f32) -> f32 {
    -next_up(-x)
}

/// Distances to try for slice `k`: its bounds, one ULP inside, random values in between; for the
/// first/last slice also the clamped ranges (0, below near, beyond far, the maximum distance).
fn distances(g: &ClusterGrid, b: &[f32], rng: &mut Rng) -> Vec<f32> {
    let mut v = vec![0.0, 1e-30, g.near * 0.5, next_down(g.near), g.near, g.far, g.far * 3.0, 1e12, MAX_DISTANCE];
    for _ in 0..64 {
        let k = rng.below(g.num_slices) as usize;
        v.push(b[k]);
        v.push(next_down(b[k + 1]));
        let t = rng.unit();
        v.push((b[k] as f64 * (b[k + 1] as f64 / b[k] as f64).powf(t)) as f32);
    }
    v
}

#[test]
fn pad_constants() {
    assert_eq!(BOX_REL_PAD as f64, 2f64.powi(-18));
    assert_eq!(BOX_ABS_PAD as f64, 2f64.powi(-100));
}

/// The property the renderer relies on (module docs, claim), on the CPU: the padded box contains
/// the pixel, and so does the *unpadded* corner box (step 3: monotone rounding, same function).
#[test]
fn reconstructed_positions_lie_in_their_cluster() {
    let mut rng = Rng(7);
    for g in grids() {
        let b = slice_bounds(&g);
        let ds = distances(&g, &b, &mut rng);
        let mut checked = 0u32;
        for _ in 0..3000 {
            let (px, py) = (rng.below(g.width), rng.below(g.height));
            // Also the first and last pixel of a tile (closest to the tile's edges).
            let (px, py) = match rng.below(4) {
                0 => (px - px % g.tile_size, py - py % g.tile_size),
                1 => ((px | (g.tile_size - 1)).min(g.width - 1), (py | (g.tile_size - 1)).min(g.height - 1)),
                _ => (px, py),
            };
            for &d in &ds {
                let p = view_position(&g, px, py, d).to_array();
                let (i, j) = g.tile_of_pixel(px, py);
                let k = g.slice_of_depth(&b, d);
                let aabb = cluster_aabb(&g, &b, i, j, k);
                assert!(inside(p, aabb.min, aabb.max), "{g:?} pixel ({px},{py}) d {d}: {p:?} not in {aabb:?}");
                let (lo, hi) = cluster_corner_bounds(&g, &b, i, j, k);
                assert!(inside(p, lo, hi), "unpadded: {g:?} pixel ({px},{py}) d {d}: {p:?} not in {lo:?}..{hi:?}");
                checked += 1;
            }
        }
        assert!(checked > 0);
    }
}

/// Every pixel of a small grid with partial tiles, every slice, both ends of each slice.
#[test]
fn exhaustive_small_grid() {
    for (w, h, t) in [(33, 17, 32), (35, 19, 8), (7, 5, 3)] {
        let g = ClusterGrid::new(w, h, t, 0.1, 50.0, 1.0).unwrap();
        let b = slice_bounds(&g);
        for k in 0..g.num_slices as usize {
            for d in [b[k], next_down(b[k + 1]), 0.5 * (b[k] + b[k + 1])] {
                for py in 0..h {
                    for px in 0..w {
                        let p = view_position(&g, px, py, d).to_array();
                        let (i, j) = g.tile_of_pixel(px, py);
                        assert_eq!(g.slice_of_depth(&b, d), k as u32);
                        let (lo, hi) = cluster_corner_bounds(&g, &b, i, j, k as u32);
                        assert!(inside(p, lo, hi), "{w}x{h}/{t} ({px},{py}) k {k} d {d}");
                    }
                }
            }
        }
    }
}

/// Step 4 of the proof, simulated adversarially: the point computed by "another machine" with
/// every coordinate pushed outwards by 7u (GPU bound) plus one extra ULP, at a distance up to
/// η = 2^-20 outside the slice; the box computed by a machine whose corners are pushed inwards by
/// the same amount, then padded. The point must still be inside.
#[test]
fn padding_covers_cross_machine_rounding() {
    let eps = 7.001 * U;
    let eta = 2f64.powi(-20);
    let mut rng = Rng(99);
    for g in grids() {
        let b = slice_bounds(&g);
        let tan = g.tan_half_fov_y as f64;
        let h = g.height as f64;
        // Exact coordinate of numerator n at distance d.
        let exact = |n: i32, d: f64| n as f64 * d * tan / h;
        for _ in 0..20_000 {
            let (px, py) = (rng.below(g.width), rng.below(g.height));
            let k = rng.below(g.num_slices);
            let (d0, d1) = slice_range(&g, &b, k);
            let (d0, d1) = (d0 as f64, d1 as f64);
            let d = match rng.below(3) {
                0 => d0 * (1.0 - eta),
                1 => d1 * (1.0 + eta),
                _ => d0 + (d1 - d0) * rng.unit(),
            };
            let (i, j) = g.tile_of_pixel(px, py);
            // Exact corner extents.
            let x0 = i * g.tile_size;
            let x1 = (x0 + g.tile_size).min(g.width);
            let y0 = j * g.tile_size;
            let y1 = (y0 + g.tile_size).min(g.height);
            let (w, hh) = (g.width as i32, g.height as i32);
            let nxs = [2 * x0 as i32 - w, 2 * x1 as i32 - w];
            let nys = [hh - 2 * y0 as i32, hh - 2 * y1 as i32];
            let xs: Vec<f64> = nxs.iter().flat_map(|&n| [exact(n, d0), exact(n, d1)]).collect();
            let ys: Vec<f64> = nys.iter().flat_map(|&n| [exact(n, d0), exact(n, d1)]).collect();
            let lo_x = xs.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi_x = xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let lo_y = ys.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi_y = ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            // Adversarial rounding: corners inwards, point outwards, each by eps then one more ULP.
            let inward_lo = |v: f64| next_up((v + eps * v.abs()) as f32);
            let inward_hi = |v: f64| next_down((v - eps * v.abs()) as f32);
            let lo = [pad_down(inward_lo(lo_x)), pad_down(inward_lo(lo_y)), pad_down(inward_lo(-d1))];
            let hi = [pad_up(inward_hi(hi_x)), pad_up(inward_hi(hi_y)), pad_up(inward_hi(-d0))];
            let px_exact = exact(pixel_numerator_x(&g, px), d);
            let py_exact = exact(pixel_numerator_y(&g, py), d);
            for (sx, sy, sz) in [(1.0, 1.0, 1.0), (-1.0, -1.0, -1.0), (1.0, -1.0, 1.0), (-1.0, 1.0, -1.0)] {
                let out = |v: f64, s: f64| {
                    let f = (v + s * eps * v.abs()) as f32;
                    if s > 0.0 {
                        next_up(f)
                    } else {
                        next_down(f)
                    }
                };
                let p = [out(px_exact, sx), out(py_exact, sy), out(-d, sz)];
                assert!(inside(p, lo, hi), "{g:?} ({px},{py}) k {k} d {d}: {p:?} not in {lo:?}..{hi:?}");
            }
        }
    }
}

#[test]
fn adjacent_boxes_touch_or_overlap() {
    let mut rng = Rng(3);
    for g in grids() {
        let b = slice_bounds(&g);
        for _ in 0..5000 {
            let (i, j, k) = (rng.below(g.tiles_x), rng.below(g.tiles_y), rng.below(g.num_slices));
            let a = cluster_aabb(&g, &b, i, j, k);
            let (alo, ahi) = cluster_corner_bounds(&g, &b, i, j, k);
            assert!((0..3).all(|c| a.min[c] < alo[c] && ahi[c] < a.max[c]), "padding moves every face outwards");
            if i + 1 < g.tiles_x {
                // Tile to the right: shares the edge column.
                let r = cluster_aabb(&g, &b, i + 1, j, k);
                assert!(r.min[0] <= a.max[0]);
                let (rlo, _) = cluster_corner_bounds(&g, &b, i + 1, j, k);
                assert!(rlo[0] <= ahi[0]);
            }
            if j + 1 < g.tiles_y {
                // Tile below (row j+1 is further down: smaller y).
                let r = cluster_aabb(&g, &b, i, j + 1, k);
                assert!(r.max[1] >= a.min[1]);
                let (_, rhi) = cluster_corner_bounds(&g, &b, i, j + 1, k);
                assert!(rhi[1] >= alo[1]);
            }
            if k + 1 < g.num_slices {
                // Next slice is farther (more negative z); unpadded faces coincide exactly.
                let r = cluster_aabb(&g, &b, i, j, k + 1);
                assert!(r.max[2] >= a.min[2]);
                let (_, rhi) = cluster_corner_bounds(&g, &b, i, j, k + 1);
                assert_eq!(rhi[2], alo[2]);
                assert_eq!(alo[2], -b[k as usize + 1]);
            }
        }
    }
}

#[test]
fn first_and_last_slice() {
    for g in grids() {
        let b = slice_bounds(&g);
        let last = g.num_slices - 1;
        assert_eq!(slice_range(&g, &b, 0).0, 0.0);
        assert_eq!(slice_range(&g, &b, last).1, MAX_DISTANCE);
        // Out-of-range k clamps to the last slice.
        assert_eq!(slice_range(&g, &b, last + 5), slice_range(&g, &b, last));
        for (i, j) in [(0, 0), (g.tiles_x - 1, g.tiles_y - 1), (g.tiles_x / 2, g.tiles_y / 2)] {
            let first = cluster_aabb(&g, &b, i, j, 0);
            assert!(first.max[2] >= 0.0, "slice 0 reaches the eye");
            let far = cluster_aabb(&g, &b, i, j, last);
            assert!(far.min[2] <= -MAX_DISTANCE);
            for a in [first, far] {
                assert!(a.min.iter().chain(a.max.iter()).all(|c| c.is_finite()), "{g:?}: {a:?}");
            }
            // Points in front of the near plane and beyond far are inside.
            for (px, py) in [(i * g.tile_size, j * g.tile_size), ((i * g.tile_size + g.tile_size - 1).min(g.width - 1), (j * g.tile_size).min(g.height - 1))] {
                for d in [0.0, 1e-20, g.near * 0.25] {
                    assert_eq!(g.slice_of_depth(&b, d), 0);
                    assert!(inside(view_position(&g, px, py, d).to_array(), first.min, first.max));
                }
                for d in [b[last as usize], g.far, g.far * 1e3, MAX_DISTANCE] {
                    assert_eq!(g.slice_of_depth(&b, d), last);
                    assert!(inside(view_position(&g, px, py, d).to_array(), far.min, far.max));
                }
            }
        }
        // Out-of-range tiles clamp (keys can address more tiles than exist).
        assert_eq!(cluster_aabb(&g, &b, g.tiles_x + 3, 0, 0), cluster_aabb(&g, &b, g.tiles_x - 1, 0, 0));
    }
}

#[test]
fn every_box_is_finite_and_ordered() {
    for g in grids() {
        let b = slice_bounds(&g);
        let step = (g.tiles_x * g.tiles_y * g.num_slices / 20_000).max(1);
        let mut c = 0;
        while c < g.tiles_x * g.tiles_y * g.num_slices {
            let (i, j, k) = (c % g.tiles_x, (c / g.tiles_x) % g.tiles_y, c / (g.tiles_x * g.tiles_y));
            let a = cluster_aabb(&g, &b, i, j, k);
            for ax in 0..3 {
                assert!(a.min[ax].is_finite() && a.max[ax].is_finite() && a.min[ax] < a.max[ax], "{g:?} ({i},{j},{k}): {a:?}");
            }
            c += step;
        }
    }
}
