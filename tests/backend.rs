//! Vulkan backend pieces not covered by the kernel parity tests: images, the timestamp profiler,
//! device selection.
mod common;
use ash::vk;
use host::vk::{Buffer, ContextOptions, Image, Profiler, VkError};

#[test]
fn image_clear_and_read_back() {
    let gpu = common::gpu();
    let (w, h) = (37u32, 23u32);
    let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::STORAGE;
    let img = Image::new_2d(&gpu.ctx, "test image", w, h, vk::Format::R8G8B8A8_UINT, usage).unwrap();
    let mut out = Buffer::storage(&gpu.ctx, "image read-back", (w * h * 4) as u64).unwrap();
    gpu.ctx
        .submit_and_wait(|cmd| {
            let d = &gpu.ctx.device;
            img.transition(
                cmd,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::AccessFlags::empty(),
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            );
            // An integer format: the cleared bytes are exact on every device (a UNORM 0.5 may become 127 or 128).
            let colour = vk::ClearColorValue { uint32: [255, 128, 0, 255] };
            unsafe { d.cmd_clear_color_image(cmd, img.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &colour, &[img.range()]) };
            img.transition(
                cmd,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1))
                .image_extent(vk::Extent3D { width: w, height: h, depth: 1 });
            unsafe { d.cmd_copy_image_to_buffer(cmd, img.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, out.raw, &[region]) };
            host::vk::memory::barrier(&gpu.ctx, cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
            Ok(())
        })
        .unwrap();
    let px: Vec<u32> = out.read((w * h) as usize).unwrap();
    assert!(px.iter().all(|&p| p == 0xff00_80ff), "every pixel is the clear colour, got {:#x}", px[0]);
    let zero = Image::new_2d(&gpu.ctx, "empty", 0, 4, vk::Format::R8G8B8A8_UNORM, usage);
    assert!(matches!(zero, Err(VkError::InvalidImage { .. })), "0-sized images are a clear error");
    common::assert_clean(&gpu);
}

#[test]
fn profiler_times_passes() {
    let gpu = common::gpu();
    let mut profiler = Profiler::new(&gpu.ctx, 4).unwrap();
    assert!(profiler.enabled(), "lavapipe and NVIDIA both report timestamp bits");
    let n = 1u32 << 16;
    let input = Buffer::from_slice(&gpu.ctx, "in", &vec![1u32; n as usize]).unwrap();
    let out = Buffer::storage(&gpu.ctx, "out", 4 * n as u64).unwrap();
    let totals = Buffer::storage(&gpu.ctx, "totals", 4 * 256).unwrap();
    let params = shaders::layout::ScanParams { count: n, _pad: [0; 3] };
    gpu.run(Some(&mut profiler), |rec| {
        rec.pass("scan a", |rec| rec.dispatch_threads(&gpu.kernels.workgroup_scan, &[&input, &out, &totals], &params, [n, 1, 1]))?;
        rec.pass("scan b", |rec| rec.dispatch_threads(&gpu.kernels.workgroup_scan, &[&input, &out, &totals], &params, [n, 1, 1]))
    })
    .unwrap();
    let t = profiler.results().unwrap();
    assert_eq!(t.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["scan a", "scan b"]);
    assert!(t.iter().all(|p| p.ms.is_finite() && p.ms > 0.0 && p.ms < 60_000.0), "{t:?}");
    common::assert_clean(&gpu);
}

#[test]
fn device_selection_by_name_and_clear_errors() {
    let gpu = common::gpu();
    let name = gpu.ctx.info.name.clone();
    // A case-insensitive substring of the chosen device's name selects it.
    let part: String = name.chars().take(4).collect::<String>().to_uppercase();
    let again = host::gpu::Gpu::new(&ContextOptions { validation: true, device: Some(part), ..Default::default() }).unwrap();
    assert_eq!(again.ctx.info.name, name);
    // An unknown name is an error that lists the devices present.
    let err = host::gpu::Gpu::new(&ContextOptions { validation: false, device: Some("no-such-device-xyz".into()), ..Default::default() })
        .err()
        .expect("must fail")
        .to_string();
    assert!(err.contains("no-such-device-xyz") && err.contains(&name), "{err}");
    // The info the rest of the system relies on is read from the device, not assumed.
    let i = &gpu.ctx.info;
    assert!(i.subgroup_size.is_power_of_two() && (i.min_subgroup_size..=i.max_subgroup_size).contains(&i.subgroup_size));
    assert!(i.max_shared_memory_bytes >= 16 * 1024 && i.timestamp_period_ns > 0.0);
    common::assert_clean(&again);
    common::assert_clean(&gpu);
}

/// A storage buffer larger than one binding addresses (`maxStorageBufferRange`, kept below 2^31
/// bytes) is refused with a one-line error naming it and both sizes, before any allocation; one
/// of exactly the range is made. Staging buffers (no storage use) are not bound, so not limited.
#[test]
fn storage_buffers_past_one_binding_are_refused() {
    let gpu = common::gpu();
    let range = gpu.ctx.info.max_storage_buffer_range as u64 & !3;
    assert!(range < 1 << 31, "bindings stay below 2 GiB: {range}");
    let at = Buffer::storage(&gpu.ctx, "at the range", range).unwrap();
    assert_eq!(at.size, range);
    drop(at);
    match Buffer::storage(&gpu.ctx, "past the range", range + 4) {
        Err(e @ VkError::TooLarge { .. }) => {
            let text = e.to_string();
            assert!(text.contains("past the range") && text.contains(&range.to_string()) && !text.contains('\n'), "{text}");
        }
        Err(e) => panic!("expected TooLarge, got {e}"),
        Ok(_) => panic!("a storage buffer of {} bytes was made past the {range}-byte range", range + 4),
    }
    common::assert_clean(&gpu);
}
