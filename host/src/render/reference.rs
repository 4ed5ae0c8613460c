//! CPU references for a clustered frame, computed from its read-back data:
//! * keys recomputed from the G-buffer depth must equal the GPU's bit for bit;
//! * the unique-cluster list must hold the distinct keys, each once, in any order (the page
//!   table sorts them, the tile path groups them by tile; with transparent draws: hold them, the
//!   transparent fragments' clusters beside them);
//! * every pixel's cluster list must contain every light whose range touches the pixel's
//!   view-space position (`lighting::light_touches`) — conservative culling, no dropped light;
//! * every cluster's list must equal, as a set, the CPU's naive search for lights meeting its box
//!   (`clustered::for_each_cluster_light`), so no light is lost even where no pixel would show it.
//!
//! It also computes the statistics of the stats file (lights per cluster / per pixel).
use super::Readback;
use anyhow::{ensure, Result};
use glam::Vec3;
use shaders::clustered::for_each_cluster_light;
use shaders::lighting::light_touches;
use shaders::page_table::{pixel_key, unique_keys_reference, INVALID_KEY};
use shaders::reconstruct::{distance_from_depth, view_position};

/// Lights-per-cluster and lights-per-pixel figures of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ListStats {
    pub mean_per_cluster: f64,
    pub max_per_cluster: u32,
    pub mean_per_pixel: f64,
    pub max_per_pixel: u32,
}

/// Index of each valid pixel's cluster in `rb.unique` (None for background pixels).
pub fn pixel_clusters(rb: &Readback) -> Vec<Option<usize>> {
    let index: std::collections::HashMap<u32, usize> = rb.unique.iter().enumerate().map(|(c, &k)| (k, c)).collect();
    rb.keys.iter().map(|&k| if k == INVALID_KEY { None } else { index.get(&k).copied() }).collect()
}

pub fn list_stats(rb: &Readback) -> ListStats {
    let mut s = ListStats::default();
    if !rb.counts.is_empty() {
        s.mean_per_cluster = rb.counts.iter().map(|&c| c as f64).sum::<f64>() / rb.counts.len() as f64;
        s.max_per_cluster = rb.counts.iter().copied().max().unwrap_or(0);
    }
    let per_pixel: Vec<u32> = pixel_clusters(rb).into_iter().flatten().map(|c| rb.counts[c]).collect();
    if !per_pixel.is_empty() {
        s.mean_per_pixel = per_pixel.iter().map(|&c| c as f64).sum::<f64>() / per_pixel.len() as f64;
        s.max_per_pixel = per_pixel.iter().copied().max().unwrap_or(0);
    }
    s
}

/// Frame parameters the CPU cluster searches need: the frame's grid and light count (default
/// AABB test, no other effect).
pub fn cpu_params(rb: &Readback) -> shaders::layout::FrameParams {
    shaders::layout::FrameParams {
        grid: rb.grid,
        count: 0,
        num_lights: rb.lights_view.len() as u32,
        light_capacity: 0,
        effects: rb.light_effects,
        normal_precision: 0,
        view: 0,
        exposure: 1.0,
        heat_max: 0,
    }
}

/// Whether light `l`'s cone reaches `p` (a point light's always does; `spot::spot_factor > 0`).
fn lit_by_cone(rb: &Readback, l: usize, p: Vec3) -> bool {
    if rb.light_effects & shaders::light_types::EFFECT_SPOT == 0 {
        return true;
    }
    let cone = shaders::light_types::cone_of(&rb.light_records, rb.lights_view.len() as u32, l as u32);
    shaders::light_types::is_point(&cone) || shaders::spot::spot_factor(Vec3::from_array(rb.lights_view[l].position), &cone, p) > 0.0
}

/// All three checks; an error names the first violations.
pub fn check(rb: &Readback) -> Result<()> {
    let g = &rb.grid;
    let n = (g.width * g.height) as usize;
    let depth = |i: usize| f32::from_bits(rb.depth[i]);
    let cpu_keys: Vec<u32> = (0..n).map(|i| pixel_key(g, &rb.bounds, i as u32 % g.width, i as u32 / g.width, depth(i))).collect();
    let bad_keys: Vec<usize> = (0..n).filter(|&i| cpu_keys[i] != rb.keys[i]).take(5).collect();
    ensure!(bad_keys.is_empty(), "GPU cluster keys differ from the CPU's at pixels {bad_keys:?}");
    let expected = unique_keys_reference(&cpu_keys);
    // Transparent fragments add clusters of their own: the opaque pixels' are then a subset.
    let mut sorted = rb.unique.clone();
    sorted.sort_unstable();
    let unique_ok = if rb.transparent {
        sorted.windows(2).all(|w| w[0] < w[1]) && expected.iter().all(|k| sorted.binary_search(k).is_ok())
    } else {
        expected == sorted
    };
    ensure!(
        unique_ok,
        "unique clusters: GPU has {}, CPU reference {} (first GPU {:?}, CPU {:?})",
        rb.unique.len(),
        expected.len(),
        rb.unique.iter().take(4).collect::<Vec<_>>(),
        expected.iter().take(4).collect::<Vec<_>>()
    );
    let params = cpu_params(rb);
    // Every cluster's list, as a set, equals the CPU's naive search (whatever order the technique
    // produced: index order for naive, Morton order for the BVH).
    let mut bad_lists = Vec::new();
    let mut sorted_lists = Vec::with_capacity(rb.unique.len());
    for (c, &key) in rb.unique.iter().enumerate() {
        let mut expected = Vec::new();
        for_each_cluster_light(&params, &rb.bounds, &rb.light_records, key, |_, l| expected.push(l));
        let mut got = rb.list[rb.offsets[c] as usize..(rb.offsets[c] + rb.counts[c]) as usize].to_vec();
        got.sort_unstable();
        if got != expected && bad_lists.len() < 5 {
            bad_lists.push((c, got.len(), expected.len()));
        }
        sorted_lists.push(got);
    }
    ensure!(bad_lists.is_empty(), "cluster light lists differ from the CPU's naive lists (cluster, gpu len, cpu len): {bad_lists:?}");
    let clusters = pixel_clusters(rb);
    let mut missing = Vec::new();
    for (i, cluster) in clusters.iter().enumerate() {
        let Some(c) = *cluster else { continue };
        let list = &sorted_lists[c];
        ensure!(list.windows(2).all(|w| w[0] < w[1]), "cluster {c}'s list repeats a light");
        let (px, py) = (i as u32 % g.width, i as u32 / g.width);
        let p: Vec3 = view_position(g, px, py, distance_from_depth(g.near, depth(i)));
        for (l, light) in rb.lights_view.iter().enumerate() {
            if light_touches(light, p) && lit_by_cone(rb, l, p) && list.binary_search(&(l as u32)).is_err() {
                missing.push((px, py, l));
                if missing.len() >= 5 {
                    break;
                }
            }
        }
        if missing.len() >= 5 {
            break;
        }
    }
    ensure!(missing.is_empty(), "lights touching a pixel are missing from its cluster list (px, py, light): {missing:?}");
    Ok(())
}
