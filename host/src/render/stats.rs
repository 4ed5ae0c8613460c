//! The `--stats` JSON: device, resolution, light count, the whole GPU frame over both queues and
//! per-pass GPU milliseconds with their queue (medians of the timed frames), bytes per buffer, unique clusters, lights per cluster and per pixel.
use super::reference::list_stats;
use super::{Frame, Settings};
use crate::vk::DeviceInfo;
use serde_json::{json, Value};

pub fn stats_json(device: &DeviceInfo, scene: &str, lights: usize, s: &Settings, frame: &Frame) -> Value {
    let mut lists = frame.readback.as_ref().map(list_stats).unwrap_or_default();
    if s.technique.description().cost == super::LightCost::EveryLightPerPixel {
        // Brute force evaluates every light at every pixel (and has no clusters).
        lists.mean_per_pixel = lights as f64;
        lists.max_per_pixel = lights as u32;
    }
    let passes: serde_json::Map<String, Value> = frame.timings.iter().map(|t| (t.name.clone(), json!(t.ms))).collect();
    let queues: serde_json::Map<String, Value> =
        frame.timings.iter().map(|t| (t.name.clone(), json!(if t.queue == crate::vk::Queue::Main { "main" } else { "async-compute" }))).collect();
    let g = &frame.gpu_frame;
    let buffers: serde_json::Map<String, Value> = frame.buffers.iter().map(|(n, b)| (n.clone(), json!(b))).collect();
    json!({
        "device": { "name": device.name, "kind": device.kind, "driver": format!("{} {}", device.driver_name, device.driver_info),
                    "vulkan": device.api_version, "subgroup_size": device.subgroup_size },
        "scene": scene,
        "technique": format!("{:?}", s.technique),
        // The per-tile list layout (`--fp-lists`) where the technique has one.
        "fp_lists": s.technique.reads(super::Knob::FpLists).then(|| s.fp_lists.name()),
        // How the clustered techniques found the unique clusters (`--unique-clusters`, or the
        // page table where the scene has transparent draws).
        "unique_clusters": s.technique.reads(super::Knob::UniqueClusters)
            .then(|| s.unique_clusters.for_frame(&frame.grid, frame.transparency.is_some()).name()),
        // The transparent pass, where the scene has transparent draws: the resolve (`--oit`),
        // fragments (the node counter), the most layers of a pixel, node-buffer bytes.
        "oit": frame.transparency.map(|_| s.oit.name()),
        "transparency": frame.transparency.map(|t| json!({
            "fragments": t.fragments, "max_layers": t.max_layers, "exact_fallback_pixels": t.fallbacks,
            "unlisted_fragments": t.unlisted, "node_bytes": t.node_bytes })),
        "resolution": [s.width, s.height],
        "tile_size": s.tile_size,
        // Bits per axis of the light BVH's Morton keys (`--morton-bits`) and the radix passes
        // sorting them, where the technique builds the hierarchy.
        "light_keys": s.technique.reads(super::Knob::LightHierarchy).then(|| {
            let bits = super::bvh::morton_bits(s.morton_bits);
            json!({ "morton_bits": bits, "radix_passes": shaders::radix::passes(3 * bits) })
        }),
        "slices": frame.grid.num_slices,
        "lights": lights,
        // How the light buffer stores them (`--light-record`), what it takes per light, and the
        // farthest a light moved in its record (view-space units).
        "light_record": { "record": s.light_record.name(), "record_bytes": s.light_record.bytes_per_light(),
                          "light_buffer_bytes": frame.buffers.iter().find(|b| b.0 == "lights").map(|b| b.1),
                          "max_position_error": frame.light_moved },
        // Each NURBS patch's tessellation level in the last frame (adaptive levels as the GPU
        // chose them; empty without patches).
        "tess_levels": frame.tess_levels,
        // MSAA (`--msaa` above 1): samples per pixel, the pixels shaded per sample, and the
        // bytes per sample of the multisampled targets and buffers (the G-buffer's,
        // `render::msaa::bytes_per_sample`, or the technique's own).
        "msaa": (frame.samples > 1).then(|| json!({
            "samples": frame.samples, "edge_pixels": frame.edge_pixels,
            "bytes_per_sample": frame.bytes_per_sample,
            "gbuffer_bytes": frame.buffers.iter().find(|b| b.0 == "gbuffer").map(|b| b.1) })),
        // Cube shadow maps, where lights cast shadows: casters, the largest face side, the
        // atlas's texels, those the last frame's faces took and how often the atlas halved every
        // face's side to hold them, the lookup's filter, what wrote the triangles (compute kernel
        // or draw), which faces get them and how many had receivers in the last frame, the
        // atlas's bytes, and the batches of 64 triangles the per-face cull drew of those it
        // tested (`render::shadow_maps`).
        "shadows": frame.shadows.map(|sh| json!({
            "casters": sh.casters, "resolution": sh.resolution,
            "atlas_texels": sh.atlas_texels, "atlas_used_texels": sh.atlas_used, "atlas_shift": sh.shift,
            "filter": format!("{:?}", s.shadow.filter).to_lowercase(),
            "raster": format!("{:?}", s.shadow.raster).to_lowercase(),
            "faces": format!("{:?}", s.shadow.faces).to_lowercase(), "faces_with_receivers": sh.faces_with_receivers,
            "map_bytes": frame.buffers.iter().find(|b| b.0 == "shadow maps").map(|b| b.1),
            "batches": sh.batches, "face_batches_drawn": sh.entries,
            "face_batches_tested": sh.batches as u64 * 6 * sh.casters as u64 })),
        "timed_frames": s.frames,
        "gpu_ms": {
            "passes": passes, "pass_queues": queues,
            // The whole GPU frame: first to last timestamp over both queues (render::frame_time).
            "frame": g.ms, "frame_min": g.min_ms, "frame_max": g.max_ms, "frame_without_raster": g.non_raster_ms,
            "main_queue": g.main_ms, "async_queue": g.async_ms, "overlap": g.overlap_ms,
            "frame_spans_queues": g.across_queues, "async_compute": frame.overlapped },
        "bytes": { "buffers": buffers, "total": frame.buffers.iter().map(|b| b.1).sum::<u64>(),
                   // Every buffer's bytes over the light count: per light where the lights dominate.
                   "per_light": (lights > 0).then(|| frame.buffers.iter().map(|b| b.1).sum::<u64>() as f64 / lights as f64) },
        "clusters": { "unique": frame.unique_clusters, "pages": frame.pages, "light_references": frame.light_refs, "regrowths": frame.regrowths },
        "lights_per_cluster": { "mean": lists.mean_per_cluster, "max": lists.max_per_cluster },
        "lights_per_pixel": { "mean": lists.mean_per_pixel, "max": lists.max_per_pixel },
    })
}
