//! CPU tests of `tiled`: the whole cooperative tile kernel — in the lock-step emulation at
//! subgroup widths 4…64 — gives exactly the brute-force deferred image, also when a tile needs
//! several rounds.
use super::*;
use crate::cluster_key::slice_bounds;
use crate::coop::cpu::{run_workgroups, Emulation};
use crate::test_support::{frame_params, gbuffer, grid, reference_pixel, test_lights, Rng};

/// The emulated tile kernel equals brute-force deferred shading bit for bit (same shading
/// function, lights summed in index order), at every subgroup width, for both modes, for tiles
/// of 8, 16 and 32 px (1–4 pixels per invocation), and takes several rounds where a tile sees
/// more lights than [`LIST_CAPACITY`].
#[test]
fn emulated_tiles_equal_brute_force() {
    let materials = [MaterialGpu { specular: 0.0, roughness: 1.0, opacity: 1.0, _pad: 0.0 }, MaterialGpu { specular: 0.7, roughness: 0.3, opacity: 1.0, _pad: 0.0 }];
    for (w, h, t, width, mode) in [(40, 24, 16, 4, MODE_TILED), (40, 24, 16, 8, MODE_TILED_25D), (37, 20, 32, 16, MODE_TILED_25D), (20, 12, 8, 32, MODE_TILED), (33, 17, 16, 64, MODE_TILED_25D)] {
        let g = grid(w, h, t);
        let bounds = slice_bounds(&g);
        let mut rng = Rng(w as u64 * 7 + t as u64);
        let gb = gbuffer(&g, &mut rng);
        let lights = test_lights(&g, &mut rng, 300, 1500);
        let p = TiledParams { frame: frame_params(g, lights.len() as u32), mode, _pad: [0; 3] };
        let emu = Emulation { width, workgroup_size: TILED_WORKGROUP, shared_words: TILED_SHARED_WORDS };
        let out = run_workgroups(emu, g.tiles_x * g.tiles_y, |tile, c, s| {
            shade_tile::<_, _, true, _>(c, s, &p, tile % g.tiles_x, tile / g.tiles_x, &gb.depth, &gb.normals, &gb.albedo, &lights, &materials, &bounds, &crate::shadow::NoShadows)
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
