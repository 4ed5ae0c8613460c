//! CPU tests of `tiled`: the culling tests are conservative against brute force (random tiles,
//! spheres and pixels, thin and huge depth ranges), the 2.5D bit math at its edges, and the whole
//! cooperative tile kernel — in the lock-step emulation at subgroup widths 4…64 — gives exactly
//! the brute-force deferred image, also when a tile needs several rounds.
use super::*;
use crate::cluster_key::slice_bounds;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::lighting::light_touches;
use crate::octahedral::{encode, Precision};
use crate::reconstruct::view_position;

pub(crate) struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        // splitmix64
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn grid(w: u32, h: u32, t: u32) -> ClusterGrid {
    ClusterGrid::new(w, h, t, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).unwrap()
}

/// A random tile, depth range and pixel positions in it; lights around them, some touching.
/// Every light touching a sampled pixel must pass `sphere_in_tile` and the 2.5D mask test.
#[test]
fn culling_is_conservative_against_brute_force() {
    let mut rng = Rng(5);
    let mut culled = 0u64;
    let mut kept_touching = 0u64;
    for case in 0..3000 {
        let g = [grid(97, 61, 16), grid(1920, 1080, 32), grid(33, 17, 8), grid(1, 1, 16)][case % 4];
        let (tx, ty) = (rng.below(g.tiles_x), rng.below(g.tiles_y));
        let (x0, x1, y0, y1) = tile_rect(&g, tx, ty);
        // Depth ranges: ordinary, thin (min == max), and reaching MAX_DISTANCE.
        let d_a = 0.1 + 300.0 * rng.unit() * rng.unit();
        let (d_min, d_max) = match case % 3 {
            0 => (d_a, d_a + 50.0 * rng.unit()),
            1 => (d_a, d_a),
            _ => (d_a, reconstruct::MAX_DISTANCE),
        };
        let f = tile_frustum(&g, tx, ty, d_min, d_max);
        let cells = depth_cells(d_min, d_max);
        let pixels: Vec<Vec3> = (0..24)
            .map(|k| {
                let px = x0 + rng.below(x1 - x0);
                let py = y0 + rng.below(y1 - y0);
                let d = match k {
                    0 => d_min,
                    1 => d_max,
                    _ if case % 3 == 2 => d_min * (1.0 + 1e3 * rng.unit()),
                    _ => d_min + (d_max - d_min) * rng.unit(),
                };
                view_position(&g, px, py, d)
            })
            .collect();
        let tile_mask = pixels.iter().fold(0, |m, p| m | 1u32 << depth_cell(&cells, -p.z));
        for _ in 0..40 {
            let anchor = pixels[rng.below(pixels.len() as u32) as usize];
            let r = [0.0, 0.01, 1.0, 10.0, 1e4][rng.below(5) as usize] * (0.2 + rng.unit());
            let off = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * (3.0 * r + 1.0);
            let c = anchor + off;
            let light = PointLight { position: c.to_array(), radius: r, colour: [1.0; 3], intensity: 1.0 };
            let touches = pixels.iter().any(|p| light_touches(&light, *p));
            let keep = sphere_in_tile(&f, c, r);
            let keep25 = keep_light(&f, &cells, tile_mask, MODE_TILED_25D, &light);
            if touches {
                assert!(keep, "case {case}: light {light:?} touches a pixel of tile {f:?} but is culled");
                assert!(keep25, "case {case}: light {light:?} touches a pixel but the 2.5D masks miss (tile {tile_mask:#x})");
                kept_touching += 1;
            } else if !keep25 {
                culled += 1;
            }
        }
    }
    assert!(kept_touching > 10_000 && culled > 10_000, "the cases must exercise both outcomes: {kept_touching} kept, {culled} culled");
}

/// A light far outside a tile's frustum (beside it, behind the camera, beyond d_max) is culled.
#[test]
fn culling_rejects_lights_outside() {
    let g = grid(64, 64, 16);
    let f = tile_frustum(&g, 0, 0, 10.0, 20.0);
    let light = |p: [f32; 3], r: f32| (Vec3::from_array(p), r);
    let centre = view_position(&g, 8, 8, 15.0);
    for (c, r) in [light([centre.x, centre.y, 5.0], 1.0), light([centre.x, centre.y, -40.0], 5.0), light([50.0, centre.y, centre.z], 3.0), light([centre.x, -50.0, centre.z], 3.0)] {
        assert!(!sphere_in_tile(&f, c, r), "{c:?} r {r} should be culled by {f:?}");
    }
    assert!(sphere_in_tile(&f, centre, 0.5));
    assert!(sphere_in_tile(&f, view_position(&g, 8, 8, 9.5), 0.6), "reaches d_min");
    assert!(!sphere_in_tile(&f, view_position(&g, 8, 8, 9.3), 0.6), "stops short of d_min");
}

#[test]
fn depth_mask_bits_at_the_edges() {
    let cells = depth_cells(10.0, 42.0); // cells of width 1
    assert_eq!(depth_cell(&cells, 10.0), 0);
    assert_eq!(depth_cell(&cells, 10.999), 0);
    assert_eq!(depth_cell(&cells, 11.0), 1);
    assert_eq!(depth_cell(&cells, 41.0), 31);
    assert_eq!(depth_cell(&cells, 42.0), 31, "d_max is in the last cell");
    assert_eq!(depth_cell(&cells, 1e30), 31);
    assert_eq!(depth_cell(&cells, 9.0), 0);
    assert_eq!(depth_cell(&cells, -1e30), 0);
    assert_eq!(depth_cell(&cells, f32::NAN), 0);
    // A thin range is one cell.
    let thin = depth_cells(5.0, 5.0);
    assert_eq!(thin.inv_width, 0.0);
    assert_eq!(depth_cell(&thin, 5.0), 0);
    assert_eq!(cell_range_mask(0, 31), u32::MAX);
    assert_eq!(cell_range_mask(0, 0), 1);
    assert_eq!(cell_range_mask(31, 31), 1 << 31);
    assert_eq!(cell_range_mask(5, 7), 0b1110_0000);
    assert_eq!(cell_range_mask(7, 5), 0);
    // A light within one cell sets one bit; a light spanning the range sets all.
    let at = |d: f32| Vec3::new(0.0, 0.0, -d);
    assert_eq!(light_depth_mask(&cells, at(20.5), 0.25), 1 << 10);
    assert_eq!(light_depth_mask(&cells, at(26.0), 100.0), u32::MAX);
    assert_eq!(light_depth_mask(&cells, at(20.5), 1.0), 0b111 << 9);
    // Monotone in d over many random pairs.
    let mut rng = Rng(9);
    for _ in 0..100_000 {
        let c = depth_cells(rng.unit() * 100.0, 100.0 + rng.unit() * 1e5);
        let (a, b) = (rng.unit() * 2e5 - 1e4, rng.unit() * 2e5 - 1e4);
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        assert!(depth_cell(&c, lo) <= depth_cell(&c, hi));
    }
}

/// A synthetic G-buffer: a near wall over the left third, a far slope elsewhere, sky in a corner.
pub(crate) struct GBuffer {
    pub depth: Vec<f32>,
    pub normals: Vec<u32>,
    pub albedo: Vec<u32>,
}

pub(crate) fn gbuffer(g: &ClusterGrid, rng: &mut Rng) -> GBuffer {
    let n = (g.width * g.height) as usize;
    let mut gb = GBuffer { depth: vec![0.0; n], normals: vec![0; n], albedo: vec![0; n] };
    for i in 0..n {
        let (x, y) = (i as u32 % g.width, i as u32 / g.width);
        if x > g.width * 3 / 4 && y < g.height / 4 {
            continue; // sky
        }
        let d = if x < g.width / 3 { 1.5 + 0.01 * y as f32 } else { 40.0 + 2.0 * y as f32 + rng.unit() };
        gb.depth[i] = g.near / d;
        let nrm = [rng.unit() - 0.5, 0.5 + rng.unit(), rng.unit()];
        gb.normals[i] = encode(nrm, Precision::Oct16)[0];
        gb.albedo[i] = 0x00c0_8060 | ((i as u32 % 2) << 24);
    }
    gb
}

/// Lights near the geometry, plus a cluster of coincident ones (more than the list holds).
pub(crate) fn test_lights(g: &ClusterGrid, rng: &mut Rng, n: usize, coincident: usize) -> Vec<PointLight> {
    let mut v: Vec<PointLight> = (0..n)
        .map(|_| {
            let (px, py) = (rng.below(g.width), rng.below(g.height));
            let d = if rng.below(2) == 0 { 1.0 + rng.unit() } else { 30.0 + 60.0 * rng.unit() };
            let c = view_position(g, px, py, d) + Vec3::new(rng.unit(), rng.unit(), rng.unit()) - Vec3::splat(0.5);
            PointLight { position: c.to_array(), radius: 0.5 + 8.0 * rng.unit(), colour: [rng.unit(), 0.7, 0.4], intensity: 2.0 + rng.unit() }
        })
        .collect();
    let at = view_position(g, g.width / 2, g.height / 2, 45.0);
    v.extend((0..coincident).map(|_| PointLight { position: at.to_array(), radius: 30.0, colour: [0.3, 0.3, 0.3], intensity: 0.01 }));
    v
}

/// The brute-force deferred colour of pixel `i` (every light, index order).
pub(crate) fn reference_pixel(fp: &FrameParams, gb: &GBuffer, lights: &[PointLight], materials: &[MaterialGpu], bounds: &[f32], i: u32) -> u32 {
    let z = gb.depth[i as usize];
    if reconstruct::is_background(z) {
        return clustered::BACKGROUND_RGBA8;
    }
    let (pos, n, a, m) = clustered::surface(fp, i, z, &gb.normals, gb.albedo[i as usize]);
    let mat = materials[m as usize];
    let mut sum = Vec3::ZERO;
    for l in lights {
        if light_touches(l, pos) {
            sum += lighting::shade(pos, n, a, mat.specular, mat.roughness, l, EFFECT_SPECULAR);
        }
    }
    clustered::output_colour(fp, bounds, i, pos, n, sum, 0)
}

pub(crate) fn frame_params(g: ClusterGrid, num_lights: u32) -> FrameParams {
    FrameParams {
        grid: g,
        count: g.width * g.height,
        num_lights,
        light_capacity: 0,
        effects: EFFECT_SPECULAR,
        normal_precision: PRECISION_OCT16,
        view: VIEW_SHADED,
        exposure: 1.0,
        heat_max: 64,
    }
}

/// The emulated tile kernel equals brute-force deferred shading bit for bit (same shading
/// function, lights summed in index order), at every subgroup width, for both modes, for tiles
/// of 8, 16 and 32 px (1–4 pixels per invocation), and takes several rounds where a tile sees
/// more lights than [`LIST_CAPACITY`].
#[test]
fn emulated_tiles_equal_brute_force() {
    let materials = [MaterialGpu { specular: 0.0, roughness: 1.0, _pad: [0.0; 2] }, MaterialGpu { specular: 0.7, roughness: 0.3, _pad: [0.0; 2] }];
    for (w, h, t, width, mode) in [(40, 24, 16, 4, MODE_TILED), (40, 24, 16, 8, MODE_TILED_25D), (37, 20, 32, 16, MODE_TILED_25D), (20, 12, 8, 32, MODE_TILED), (33, 17, 16, 64, MODE_TILED_25D)] {
        let g = grid(w, h, t);
        let bounds = slice_bounds(&g);
        let mut rng = Rng(w as u64 * 7 + t as u64);
        let gb = gbuffer(&g, &mut rng);
        let lights = test_lights(&g, &mut rng, 300, 1500);
        let p = TiledParams { frame: frame_params(g, lights.len() as u32), mode, _pad: [0; 3] };
        let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: TILED_SHARED_WORDS };
        let out = run_workgroups(emu, g.tiles_x * g.tiles_y, |tile, c, s| {
            shade_tile::<_, _, true>(c, s, &p, tile % g.tiles_x, tile / g.tiles_x, &gb.depth, &gb.normals, &gb.albedo, &lights, &materials, &bounds)
        });
        let mut frame = vec![0u32; (w * h) as usize];
        let mut covered = 0;
        let mut max_rounds = 0;
        for o in &out {
            max_rounds = max_rounds.max(o.rounds);
            for (k, &i) in o.pixels.iter().enumerate() {
                if i != NO_PIXEL {
                    frame[i as usize] = o.colours[k];
                    covered += 1;
                }
            }
        }
        assert_eq!(covered, w * h, "every pixel is written exactly once");
        for i in 0..w * h {
            let want = reference_pixel(&p.frame, &gb, &lights, &materials, &bounds, i);
            assert_eq!(frame[i as usize], want, "{w}x{h} tile {t} width {width} mode {mode}: pixel {i}");
        }
        assert!(max_rounds >= 2, "1500 coincident lights exceed the {LIST_CAPACITY}-entry list: rounds {max_rounds}");
    }
}
