//! Rendering a scene for a test: settings, one frame, the scenes the tests use.
use super::assets;
use host::gpu::Gpu;
use host::render::forward_plus::TileLists;
use host::render::{self, Frame, Knob, Settings, Technique};
use host::scene::flatten::{flatten, scene_input};
use host::scene::Scene;
use shaders::layout::{PointLight, View};
use shaders::octahedral::Precision;

/// One untimed frame (`frames: 0`) at `width`×`height`: 32 px tiles, octahedral 2×16 normals,
/// the shaded view, no read-back. Tests change fields with `..settings(..)`.
pub fn settings(width: u32, height: u32, technique: Technique) -> Settings {
    Settings {
        width,
        height,
        tile_size: 32,
        technique,
        view: View::Shaded,
        normal_precision: Precision::Oct16,
        exposure: 1.0,
        frames: 0,
        read_back: false,
        bvh_branching: 0,
        morton_bits: 0,
        async_compute: true,
        sort: Default::default(),
        fp_lists: Default::default(),
        unique_clusters: Default::default(),
        oit: Default::default(),
        dispatch_times: false,
        msaa: 1,
        light_record: Default::default(),
        shadow: Default::default(),
    }
}

/// A technique and the layout of its tile lists (`--fp-lists`; only techniques with
/// [`Knob::FpLists`] read it).
pub type Run = (Technique, TileLists);

/// What a test renders for `techniques`: those that read `--fp-lists` with both layouts of their
/// tile lists, every other technique once (with the default layout, which it ignores).
pub fn runs(techniques: &[Technique]) -> Vec<Run> {
    techniques
        .iter()
        .flat_map(|&t| {
            let layouts: &[TileLists] = if t.reads(Knob::FpLists) { &TileLists::ALL } else { &[TileLists::Linked] };
            layouts.iter().map(move |&l| (t, l))
        })
        .collect()
}

/// A run's technique and (for Forward+) list layout, for messages.
pub fn label((technique, lists): Run) -> String {
    match technique.reads(Knob::FpLists) {
        true => format!("{technique:?} ({} lists)", lists.name()),
        false => format!("{technique:?}"),
    }
}

/// Renders `scene` with `lights`; panics with the technique and the error.
pub fn frame(gpu: &Gpu, scene: &Scene, lights: &[PointLight], s: &Settings) -> Frame {
    let flat = flatten(scene, s.normal_precision).unwrap_or_else(|e| panic!("{e:#}"));
    render::render(gpu, &scene_input(scene, &flat, lights), s).unwrap_or_else(|e| panic!("{}: {e:#}", label((s.technique, s.fp_lists))))
}

/// The error `render` answers for `scene` flattened at normal precision `flattened_at` and
/// rendered with `s`; panics when it renders.
pub fn render_error(gpu: &Gpu, scene: &Scene, lights: &[PointLight], flattened_at: Precision, s: &Settings) -> String {
    let flat = flatten(scene, flattened_at).unwrap_or_else(|e| panic!("{e:#}"));
    match render::render(gpu, &scene_input(scene, &flat, lights), s) {
        Ok(_) => panic!("{:?} at {}x{} with {} lights rendered; an error was expected", s.technique, s.width, s.height, lights.len()),
        Err(e) => format!("{e:#}"),
    }
}

/// The procedural city.
pub fn city() -> Scene {
    Scene::load("city", &assets::dir()).unwrap_or_else(|e| panic!("{e:#}"))
}

/// A scene from the shared assets (`sponza`, `bunny`), or `None` when it is absent and not
/// required (see [`assets::asset`]).
pub fn asset_scene(name: &str) -> Option<Scene> {
    assets::asset(name)?;
    Some(Scene::load(name, &assets::dir()).unwrap_or_else(|e| panic!("{e:#}")))
}
