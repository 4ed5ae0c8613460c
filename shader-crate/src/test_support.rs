//! Fixtures shared by the CPU tests of several modules: a seeded generator, grids, a synthetic
//! G-buffer with lights around it, the brute-force reference pixel, frame parameters and a
//! counter that counts its atomics. Used by the tests of `tile_cull`, `tiled`, `forward_plus`,
//! `clustered_aabb`, `light_lists`, `shading` and `oit`.
use crate::layout::*;
use crate::light_lists::AtomicAdd;
use crate::lighting::{self, light_touches};
use crate::octahedral::{encode, Precision};
use crate::reconstruct::{self, view_position};
use crate::shading;
use glam::Vec3;
use std::sync::atomic::{AtomicU32, Ordering};

/// A seeded splitmix64 generator.
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

pub(crate) fn grid(w: u32, h: u32, t: u32) -> ClusterGrid {
    ClusterGrid::new(w, h, t, 0.1, 1000.0, core::f32::consts::FRAC_PI_3).unwrap()
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

/// The brute-force deferred colour of pixel `i` (every touching light, index order, the frame's
/// effects), computed with `lighting::shade` directly.
pub(crate) fn reference_pixel(fp: &FrameParams, gb: &GBuffer, lights: &[PointLight], materials: &[MaterialGpu], bounds: &[f32], i: u32) -> u32 {
    let z = gb.depth[i as usize];
    if reconstruct::is_background(z) {
        return shading::BACKGROUND_RGBA8;
    }
    let s = shading::fetch_surface(fp, i, z, &gb.normals, gb.albedo[i as usize], materials);
    let mut sum = Vec3::ZERO;
    for l in lights {
        if light_touches(l, s.pos) {
            sum += lighting::shade(s.pos, s.normal, s.albedo, s.specular, s.roughness, l, fp.effects);
        }
    }
    shading::output_colour(fp, bounds, i, &s, sum, 0)
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

/// An [`AtomicAdd`] that counts its atomic adds.
pub(crate) struct Counting<'a> {
    pub value: &'a AtomicU32,
    pub calls: &'a AtomicU32,
}

impl AtomicAdd for Counting<'_> {
    fn fetch_add(&mut self, v: u32) -> u32 {
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.value.fetch_add(v, Ordering::Relaxed)
    }
}
