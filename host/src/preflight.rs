//! What a frame and its lights need, against what the device has — checked before anything is
//! loaded or allocated, so that a request too large for the device is a one-line
//! [`BadInput`](crate::bad_input::BadInput) naming the flag (or the scene's light count) and the
//! limit, never an allocation failure halfway through a frame, a validation error or a lost
//! device.
//!
//! Limits checked (`vk::DeviceInfo` holds the device's):
//! - width and height: 1 ..= min(`cluster_key::MAX_DIMENSION`, `maxImageDimension2D`);
//! - tile size: 1 ..= `cluster_key::MAX_TILE_SIZE`, ≤ `tiled::MAX_TILED_TILE` for the tiled
//!   techniques and Forward+;
//! - the largest per-pixel buffer (the G-buffer normals: 4 or 16 bytes per pixel) within
//!   `maxStorageBufferRange`, and the G-buffer plus frame ([`frame_bytes_per_pixel`]) within the
//!   largest device-local heap;
//! - lights: 32 bytes each (16 with `--light-record compact`) within `maxStorageBufferRange`,
//!   at most `lights::MAX_LIGHTS`, and on
//!   lavapipe the loop limiter's bound of the technique ([`max_lights`]).
use crate::bail_input;
use crate::render::light_record::LightRecord;
use crate::render::Technique;
use crate::scene::lights::MAX_LIGHTS;
use crate::vk::DeviceInfo;
use anyhow::Result;
use shaders::cluster_key::{MAX_DIMENSION, MAX_TILE_SIZE};
use shaders::octahedral::Precision;

/// Bytes per pixel every technique allocates at least: the G-buffer's depth, normal and albedo
/// targets and their storage copies (4 + 4 or 16 + 4 bytes each), and the RGBA8 frame.
pub fn frame_bytes_per_pixel(precision: Precision) -> u64 {
    let gbuffer = 4 + 4 * precision.gbuffer_words() as u64 + 4;
    2 * gbuffer + 4
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
}

/// Checks `--width`, `--height` and `--tile-size` against the grid's and the device's limits.
pub fn check_frame(info: &DeviceInfo, width: u32, height: u32, tile_size: u32, precision: Precision) -> Result<()> {
    let max = MAX_DIMENSION.min(info.max_image_dimension_2d);
    for (flag, v) in [("--width", width), ("--height", height)] {
        if v == 0 || v > max {
            let why = if max < MAX_DIMENSION { format!("maxImageDimension2D of {}", info.name) } else { "the cluster grid's limit".into() };
            bail_input!("{flag} {v} is out of range: it must be in 1..={max} ({why})");
        }
    }
    if tile_size == 0 || tile_size > MAX_TILE_SIZE {
        bail_input!("--tile-size {tile_size} is out of range: it must be in 1..={MAX_TILE_SIZE} px");
    }
    let pixels = width as u64 * height as u64;
    let normals = pixels * 4 * precision.gbuffer_words() as u64;
    let range = info.max_storage_buffer_range as u64;
    if normals > range {
        bail_input!(
            "--width {width} --height {height}: the G-buffer normals need {} in one buffer; {} addresses at most {} per buffer (maxStorageBufferRange)",
            mib(normals),
            info.name,
            mib(range)
        );
    }
    let total = pixels * frame_bytes_per_pixel(precision);
    if info.device_local_bytes > 0 && total > info.device_local_bytes {
        bail_input!(
            "--width {width} --height {height}: the G-buffer and frame need {}; {}'s largest device-local heap holds {}",
            mib(total),
            info.name,
            mib(info.device_local_bytes)
        );
    }
    Ok(())
}

/// `--msaa N`: a count of `shaders::msaa::SAMPLE_COUNTS` that the device supports for the
/// G-buffer ([`DeviceInfo::msaa_sample_counts`]), a technique with an edge pass
/// ([`crate::render::Description::msaa`]), and `N` samples of every G-buffer buffer in one
/// binding and, with the frame, in the device's memory.
pub fn check_msaa(info: &DeviceInfo, technique: Technique, samples: u32, width: u32, height: u32, precision: Precision) -> Result<()> {
    if samples == 1 {
        return Ok(());
    }
    if !shaders::msaa::SAMPLE_COUNTS.contains(&samples) {
        bail_input!("--msaa {samples}: the sample count must be one of {:?}", shaders::msaa::SAMPLE_COUNTS);
    }
    if info.msaa_sample_counts & samples == 0 {
        let here: Vec<u32> = shaders::msaa::SAMPLE_COUNTS.into_iter().filter(|n| info.msaa_sample_counts & n != 0).collect();
        bail_input!("--msaa {samples}: {} renders and reads G-buffers of {here:?} samples per pixel only", info.name);
    }
    if !technique.description().msaa {
        let with: Vec<&str> = Technique::ALL.iter().filter(|t| t.description().msaa).map(|t| t.name()).collect();
        bail_input!("--msaa {samples}: {} shades once per pixel (it has no per-sample edge pass); with MSAA: {}", technique.name(), with.join(", "));
    }
    let pixels = width as u64 * height as u64;
    let normals = samples as u64 * pixels * 4 * precision.gbuffer_words() as u64;
    let range = info.max_storage_buffer_range as u64;
    if normals > range {
        bail_input!("--msaa {samples} at {width}x{height}: the G-buffer normals of every sample need {} in one buffer; {} addresses at most {} per buffer", mib(normals), info.name, mib(range));
    }
    let total = pixels * (samples as u64 * crate::render::msaa::bytes_per_sample(precision) + 4 + 4);
    if info.device_local_bytes > 0 && total > info.device_local_bytes {
        bail_input!("--msaa {samples} at {width}x{height}: the G-buffer of every sample needs {}; {}'s largest device-local heap holds {}", mib(total), info.name, mib(info.device_local_bytes));
    }
    Ok(())
}

/// `--tile-size` for a technique: at most its [`crate::render::Description::max_tile`] (the tiled
/// techniques and Forward+ cull tiles of at most `MAX_TILED_TILE` px).
pub fn check_tile_for(technique: Technique, tile_size: u32) -> Result<()> {
    match technique.description().max_tile {
        Some(max) if tile_size > max => bail_input!("--tile-size {tile_size} is out of range for {}: tiles of at most {max} px", technique.name()),
        _ => {}
    }
    Ok(())
}

/// Whether the device is lavapipe (llvmpipe), whose loop limiter bounds a shader's loops.
pub fn is_llvmpipe(info: &DeviceInfo) -> bool {
    info.driver_name.to_lowercase().contains("llvmpipe")
}

/// The most lights `technique` takes on this device in `record`s, and the limit that sets it.
pub fn max_lights(info: &DeviceInfo, technique: Technique, record: LightRecord, tile_size: u32) -> (u64, String) {
    // The light buffer's length is never read, so it takes the whole reported range; the
    // technique's own buffers per light stay below 2^31 bytes (`vk::device::MAX_BINDING_BYTES`).
    let range = info.reported_storage_buffer_range as u64;
    let more = match record {
        LightRecord::Full => "; --light-record compact holds twice as many",
        LightRecord::Compact => "",
    };
    let d = technique.description();
    let mut limits = vec![
        (MAX_LIGHTS as u64, "the renderer's limit (2^28 − 4 lights: 16-byte records in one binding of 4 GiB, the most maxStorageBufferRange can state)".to_string()),
        (record.max_lights_in(range), format!(
            "{}-byte lights in one buffer; {} addresses {} per buffer (maxStorageBufferRange){more}",
            record.bytes_per_light(),
            info.name,
            mib(range),
        )),
    ];
    if d.light_words > 0 {
        let own = info.max_storage_buffer_range as u64;
        limits.push((own / (4 * d.light_words as u64), format!("{} keeps {} bytes per light in buffers of at most {} (below 2 GiB)", d.name, 4 * d.light_words, mib(own))));
    }
    if is_llvmpipe(info) {
        let n = (technique.description().llvmpipe_lights)(tile_size.max(1));
        limits.push((n as u64, "lavapipe's loop limiter ends an invocation's loops after 65 535 iterations".to_string()));
    }
    limits.into_iter().min_by_key(|l| l.0).expect("at least one limit")
}

/// Checks `n` lights for `technique`; `what` names where the count came from (`--lights 5000`,
/// `scene x.toml's lights`).
pub fn check_lights(info: &DeviceInfo, technique: Technique, record: LightRecord, tile_size: u32, n: u64, what: &str) -> Result<()> {
    let (max, why) = max_lights(info, technique, record, tile_size);
    if n > max {
        bail_input!("{what}: {n} lights, but {} takes at most {max} here ({why})", technique.name());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(driver: &str, range: u32, image: u32, heap: u64) -> DeviceInfo {
        DeviceInfo {
            name: "test device".into(),
            kind: "discrete GPU",
            driver_name: driver.into(),
            driver_info: String::new(),
            api_version: "1.3".into(),
            vendor_id: 0x10de,
            subgroup_size: 32,
            min_subgroup_size: 32,
            max_subgroup_size: 32,
            full_subgroups: true,
            timestamp_period_ns: 1.0,
            timestamp_valid_bits: 64,
            async_timestamp_valid_bits: 0,
            timestamps_across_queues: false,
            calibrated_timestamps_ext: false,
            max_shared_memory_bytes: 48 << 10,
            max_storage_buffer_range: crate::vk::device::usable_storage_range(range),
            reported_storage_buffer_range: range,
            max_image_dimension_2d: image,
            device_local_bytes: heap,
            max_workgroup_invocations: 1024,
            graphics_family: 0,
            async_compute_family: None,
            kernel_statistics: false,
            msaa_sample_counts: 1 | 2 | 4 | 8,
        }
    }

    fn err(r: Result<()>) -> String {
        let e = r.unwrap_err();
        assert!(crate::bad_input::is_bad_input(&e), "{e:#}");
        format!("{e:#}")
    }

    #[test]
    fn frames_are_checked_against_the_grid_and_the_device() {
        let gpu = device("NVIDIA", u32::MAX, 32768, 80 << 30);
        check_frame(&gpu, 7680, 4320, 32, Precision::F32).unwrap();
        assert!(err(check_frame(&gpu, 0, 4320, 32, Precision::Oct16)).contains("--width 0 is out of range: it must be in 1..=32768 (the cluster grid's limit)"));
        assert!(err(check_frame(&gpu, 64, 32769, 32, Precision::Oct16)).starts_with("--height 32769 is out of range"));
        assert!(err(check_frame(&gpu, 64, 64, 0, Precision::Oct16)).contains("--tile-size 0 is out of range: it must be in 1..=1024"));
        assert!(err(check_frame(&gpu, 64, 64, 1025, Precision::Oct16)).contains("--tile-size 1025"));
        let small = device("llvmpipe", 128 << 20, 16384, 1 << 30);
        assert!(err(check_frame(&small, 16385, 64, 32, Precision::Oct16)).contains("maxImageDimension2D of test device"));
        // 4096 × 4096 × 4 B = 64 MiB of oct normals fit 128 MiB; float32's 256 MiB do not.
        check_frame(&small, 4096, 4096, 32, Precision::Oct16).unwrap();
        let e = err(check_frame(&small, 4096, 4096, 32, Precision::F32));
        assert!(e.contains("--width 4096 --height 4096: the G-buffer normals need 256.0 MiB") && e.contains("128.0 MiB"), "{e}");
        // The heap: 4096² px × 28 B/px = 448 MiB against a 256 MiB heap.
        let e = err(check_frame(&device("x", u32::MAX, 16384, 256 << 20), 4096, 4096, 32, Precision::Oct16));
        assert!(e.contains("448.0 MiB") && e.contains("device-local heap holds 256.0 MiB"), "{e}");
        assert!(err(check_tile_for(Technique::Tiled, 64)).contains("--tile-size 64 is out of range for tiled"));
        check_tile_for(Technique::ClusteredNaive, 64).unwrap();
    }

    #[test]
    fn light_limits_follow_the_device_and_the_technique() {
        // A GPU reporting 4 GiB − 1 per binding: the light buffer (whose length no kernel reads)
        // takes all of it, 2^27 − 1 lights of 32 B; one more is refused in one line before
        // anything is allocated.
        let gpu = device("NVIDIA", u32::MAX, 32768, 80 << 30);
        let (n, why) = max_lights(&gpu, Technique::Tiled, LightRecord::Full, 32);
        assert_eq!(n, (1 << 27) - 1, "{why}");
        check_lights(&gpu, Technique::ClusteredBvh, LightRecord::Full, 32, n, "--lights 134217727").unwrap();
        let e = err(check_lights(&gpu, Technique::ClusteredBvh, LightRecord::Full, 32, 1 << 27, "--lights 134217728"));
        assert!(e.starts_with("--lights 134217728: 134217728 lights, but clustered-bvh takes at most 134217727 here (32-byte lights in one buffer") && !e.contains('\n'), "{e}");
        assert!(e.contains("--light-record compact holds twice as many"), "{e}");
        // Compact records: 2^28 − 4 lights (a header record, two lights per 32 bytes, within
        // 4 GiB − 1), the renderer's limit too.
        let (n, why) = max_lights(&gpu, Technique::ClusteredBvh, LightRecord::Compact, 32);
        assert_eq!((n, n), (MAX_LIGHTS as u64, (1 << 28) - 4), "{why}");
        check_lights(&gpu, Technique::ClusteredBvh, LightRecord::Compact, 32, 250_000_000, "--lights 250000000").unwrap();
        let e = err(check_lights(&gpu, Technique::ClusteredBvh, LightRecord::Compact, 32, n + 1, "--lights 268435453"));
        assert!(e.starts_with("--lights 268435453: 268435453 lights, but clustered-bvh takes at most 268435452 here (the renderer's limit"), "{e}");
        // A technique's own buffers per light stay below 2^31 bytes: raster-tiled's 16-byte quads.
        let (n, why) = max_lights(&gpu, Technique::RasterTiled, LightRecord::Compact, 32);
        assert_eq!(n, ((1u64 << 31) - 1) / 16, "{why}");
        assert!(why.contains("raster-tiled keeps 16 bytes per light in buffers of at most 2048.0 MiB"), "{why}");
        // A device reporting exactly 2^31 bytes: the light buffer may take all of them (2^26
        // lights of 32 B, which read as none through the binding's length on an H200).
        let two = device("NVIDIA", 1 << 31, 32768, 80 << 30);
        assert_eq!(max_lights(&two, Technique::Tiled, LightRecord::Full, 32).0, 1 << 26);
        assert_eq!(max_lights(&two, Technique::ClusteredBvh, LightRecord::Compact, 32).0, (1 << 27) - 2);
        let lavapipe = device("llvmpipe", 128 << 20, 16384, 1 << 30);
        assert_eq!(max_lights(&lavapipe, Technique::ClusteredBvh, LightRecord::Full, 32).0, 400_000);
        assert_eq!(max_lights(&lavapipe, Technique::Tiled, LightRecord::Full, 32).0, 100_000);
        assert_eq!(max_lights(&lavapipe, Technique::ForwardPlus, LightRecord::Full, 16).0, 65_535);
        let tiny = device("x", 32 << 10, 16384, 1 << 30);
        assert_eq!(max_lights(&tiny, Technique::Deferred, LightRecord::Full, 32).0, 1024, "32 KiB of 32-byte lights");
        check_lights(&lavapipe, Technique::Deferred, LightRecord::Full, 32, 400_000, "--lights 400000").unwrap();
        let e = err(check_lights(&lavapipe, Technique::Deferred, LightRecord::Full, 32, 400_001, "--lights 400001"));
        assert!(e.starts_with("--lights 400001: 400001 lights, but deferred takes at most 400000 here (lavapipe's loop limiter"), "{e}");
    }
}
