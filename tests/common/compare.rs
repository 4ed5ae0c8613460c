//! Comparing frames across techniques: every technique against a reference image, and a CPU
//! shading of a read-back G-buffer.
use super::pixels::worst_channel;
use super::render::{frame, label, runs, Run};
use host::gpu::Gpu;
use host::render::{reference, Frame, Settings, Technique};
use host::scene::Scene;
use shaders::layout::PointLight;

/// Largest per-channel difference (of 255) allowed between a technique and the reference.
pub const TOLERANCE: u32 = 1;

/// Renders `scene` with each of `techniques` (otherwise `s`; Forward+ with both layouts of its
/// tile lists: [`runs`]) and asserts every image within [`TOLERANCE`] of `reference`
/// ([`assert_runs_match`]).
pub fn assert_techniques_match(gpu: &Gpu, reference: &[u32], scene: &Scene, lights: &[PointLight], s: &Settings, techniques: &[Technique], what: &str) {
    assert_runs_match(gpu, reference, scene, lights, s, &runs(techniques), what);
}

/// Renders `scene` with each technique and list layout of `runs` (otherwise `s`) and asserts
/// every image within [`TOLERANCE`] of `reference`; with `s.read_back`, the clustered techniques'
/// lists are also checked against the CPU ([`reference::check`]). One frame is alive at a time
/// (8K frames).
pub fn assert_runs_match(gpu: &Gpu, reference: &[u32], scene: &Scene, lights: &[PointLight], s: &Settings, runs: &[Run], what: &str) {
    for &(technique, fp_lists) in runs {
        let run = Settings { technique, fp_lists, ..s.clone() };
        let f = frame(gpu, scene, lights, &run);
        let worst = worst_channel(reference, &f.pixels);
        assert!(worst <= TOLERANCE, "{what}, {}: differs from the reference by {worst}/255", label((technique, fp_lists)));
        if let Some(rb) = f.readback.as_ref().filter(|rb| !rb.keys.is_empty()) {
            reference::check(rb).unwrap_or_else(|e| panic!("{what}, {}: {e:#}", label((technique, fp_lists))));
        }
    }
    super::assert_clean(gpu);
}

/// Renders the brute-force reference (`deferred`) and asserts that every other technique (Forward+
/// with both list layouts) equals it ([`assert_techniques_match`]); returns the reference frame.
pub fn assert_every_technique_equals_deferred(gpu: &Gpu, scene: &Scene, lights: &[PointLight], s: &Settings, what: &str) -> Frame {
    let reference = frame(gpu, scene, lights, &Settings { technique: Technique::Deferred, ..s.clone() });
    let others: Vec<Technique> = Technique::ALL.iter().copied().filter(|&t| t != Technique::Deferred).collect();
    assert_techniques_match(gpu, &reference.pixels, scene, lights, s, &others, what);
    reference
}

/// Pixels showing geometry (reversed-Z depth above 0) in a read-back frame.
pub fn geometry_pixels(f: &Frame) -> usize {
    f.readback.as_ref().expect("a read-back frame").depth.iter().filter(|&&d| f32::from_bits(d) > 0.0).count()
}

/// The frame as the CPU shades it from its read-back G-buffer, without shadows
/// (`render::cpu_shading`): what every technique must show (within [`TOLERANCE`]).
pub fn cpu_shaded(scene: &Scene, f: &Frame, s: &Settings) -> Vec<u32> {
    host::render::cpu_shading::shade(scene, f, s, None).expect("the CPU shading of a read-back frame")
}
