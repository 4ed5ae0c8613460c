//! GPU-vs-CPU parity of every foundation kernel, on the local Vulkan device (lavapipe in CI),
//! with validation on. The comparison rules (bit-equal / ULP bounds / tie rule) live in
//! `host::parity` and are shared with `manylights check`.
mod common;
use common::pixels::channel_diff;
use host::debug_frame::{self, FrameSpec};
use shaders::layout::View;
use shaders::octahedral::Precision;
use host::parity;

fn check(f: impl FnOnce(&host::gpu::Gpu) -> anyhow::Result<parity::Report>) {
    let gpu = common::gpu();
    let report = f(&gpu).unwrap_or_else(|e| panic!("{e:#}"));
    println!("{} [{}]", report, gpu.ctx.info.line());
    common::assert_clean(&gpu);
}

#[test]
fn octahedral_oct8() {
    check(|g| parity::octahedral(g, Precision::Oct8));
}

#[test]
fn octahedral_oct12() {
    check(|g| parity::octahedral(g, Precision::Oct12));
}

#[test]
fn octahedral_oct16() {
    check(|g| parity::octahedral(g, Precision::Oct16));
}

#[test]
fn octahedral_f32() {
    check(|g| parity::octahedral(g, Precision::F32));
}

#[test]
fn cluster_keys() {
    check(parity::cluster_keys);
}

#[test]
fn morton_codes() {
    check(parity::morton_codes);
}

#[test]
fn workgroup_scan_at_device_width() {
    check(parity::workgroup_scan);
}

/// The NURBS tessellation pass: vertex streams within the documented ULP bounds of the CPU
/// kernel functions, indices equal (`host::parity::nurbs_tessellation`).
#[test]
fn nurbs_tessellation() {
    check(parity::nurbs_tessellation);
}

/// The debug frame (all kernels' functions composed) matches its CPU rendering: identical except
/// for pixels where GPU `sqrt`/division rounding flips a silhouette or an 8-bit colour step.
/// The octa-error view is the amplified difference of two rounding errors (a 1e-4 rad angle over
/// its bound), so there the check is what the view is for: no pixel, on either side, shows an
/// error above the proven bound (pure red).
#[test]
fn debug_frame_matches_cpu() {
    let gpu = common::gpu();
    for view in View::DEBUG {
        for precision in [Precision::Oct8, Precision::Oct12, Precision::Oct16] {
            let spec = FrameSpec { width: 97, height: 61, tile_size: 16, near: 0.1, far: 500.0, fov_y_degrees: 60.0, view, precision };
            let (g, _) = debug_frame::render_gpu(&gpu, &spec).unwrap();
            let c = debug_frame::render_cpu(&spec).unwrap();
            let background = g.iter().filter(|&&p| p == 0xff20_1818).count();
            assert!(background > 0 && background < g.len(), "{view:?}: frame must show both scene and background");
            if view == View::OctaError {
                const RED: u32 = 0xff00_00ff;
                assert!(!g.contains(&RED) && !c.contains(&RED), "{precision:?}: an encoding error exceeds the proven bound");
                continue;
            }
            assert_eq!(g.len(), c.len(), "{view:?}: GPU and CPU frames of different sizes");
            let differing = g.iter().zip(&c).filter(|(a, b)| channel_diff(**a, **b) > 1).count();
            assert!(differing * 200 <= g.len(), "{view:?}: {differing} of {} pixels differ by more than 1/255", g.len());
        }
    }
    common::assert_clean(&gpu);
}
