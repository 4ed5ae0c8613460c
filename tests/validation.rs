//! The validation net itself: a clean run reports nothing, and deliberate API misuse and
//! deliberate synchronization hazards (between copies, between dependent dispatches) are caught,
//! so "no messages" in other tests means something; and the dispatch recorder orders dependent
//! dispatches.
mod common;
use ash::vk;
use host::gpu::Gpu;
use host::vk::{Buffer, ComputePipeline};
use shaders::layout::{ScanFixParams, ScanParams};

#[test]
fn invalid_api_use_is_reported() {
    let gpu = common::gpu();
    // A zero-sized buffer violates VUID-VkBufferCreateInfo-size-00912.
    let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    if let Ok(b) = unsafe { gpu.ctx.device.create_buffer(&info, None) } {
        unsafe { gpu.ctx.device.destroy_buffer(b, None) };
    }
    let msgs = gpu.ctx.take_validation_messages();
    assert!(msgs.iter().any(|m| m.contains("00912")), "expected VUID-VkBufferCreateInfo-size-00912, got {msgs:?}");
}

#[test]
fn synchronization_hazard_is_reported() {
    let gpu = common::gpu();
    let src = Buffer::from_slice(&gpu.ctx, "source", &[7u32; 64]).unwrap();
    let dst = Buffer::storage(&gpu.ctx, "destination", 256).unwrap();
    // Two copies into the same bytes with no barrier between them: WRITE_AFTER_WRITE.
    gpu.ctx
        .submit_and_wait(|cmd| {
            let region = [vk::BufferCopy::default().size(256)];
            unsafe {
                gpu.ctx.device.cmd_copy_buffer(cmd, src.raw, dst.raw, &region);
                gpu.ctx.device.cmd_copy_buffer(cmd, src.raw, dst.raw, &region);
            }
            Ok(())
        })
        .unwrap();
    let msgs = gpu.ctx.take_validation_messages();
    assert!(msgs.iter().any(|m| m.contains("SYNC-HAZARD")), "expected a SYNC-HAZARD report, got {msgs:?}");
}

/// The recorder orders dependent dispatches, as the layer sees it: a workgroup scan writes
/// `output` and `totals`, then `scan_add_offsets` reads `totals` and updates `output` (the two
/// steps of a scan over several workgroups). Recorded without a barrier between them, the layer
/// reports the read-after-write; recorded through the [`Recorder`](host::vk::Recorder), which
/// ends every dispatch with [`dispatch_barrier`](host::vk::pipeline::dispatch_barrier), it
/// reports nothing. This layer version does not compare two dispatches
/// of one pipeline with the same bindings, so the pair is of two kernels.
#[test]
fn recorder_orders_dependent_dispatches() {
    let gpu = common::gpu();
    let (scan, add) = (&gpu.kernels.workgroup_scan, &gpu.kernels.scan_add_offsets);
    let input = Buffer::from_slice(&gpu.ctx, "input", &[1u32; 256]).unwrap();
    let output = Buffer::storage(&gpu.ctx, "output", 1024).unwrap();
    let totals = Buffer::storage(&gpu.ctx, "totals", 16).unwrap();
    let scan_params = ScanParams { count: 256, _pad: [0; 3] };
    let add_params = ScanFixParams { count: 256, _pad: [0; 3] };
    // Without a barrier: bind, push the buffers and constants, dispatch; twice.
    gpu.ctx
        .submit_and_wait(|cmd| {
            unordered_dispatch(&gpu, cmd, scan, &[&input, &output, &totals], &scan_params);
            unordered_dispatch(&gpu, cmd, add, &[&totals, &output], &add_params);
            Ok(())
        })
        .unwrap();
    let msgs = gpu.ctx.take_validation_messages();
    assert!(msgs.iter().any(|m| m.contains("SYNC-HAZARD-READ-AFTER-WRITE")), "unordered dependent dispatches: expected SYNC-HAZARD-READ-AFTER-WRITE, got {msgs:?}");
    gpu.run(None, |rec| {
        rec.dispatch(scan, &[&input, &output, &totals], &scan_params, [1, 1, 1])?;
        rec.dispatch(add, &[&totals, &output], &add_params, [1, 1, 1])
    })
    .unwrap();
    common::assert_clean(&gpu);
}

/// One dispatch as [`Recorder::dispatch`](host::vk::Recorder::dispatch) records it, without the
/// barrier after it.
fn unordered_dispatch<P: bytemuck::Pod>(gpu: &Gpu, cmd: vk::CommandBuffer, pipe: &ComputePipeline<P>, buffers: &[&Buffer], params: &P) {
    let d = &gpu.ctx.device;
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers.iter().map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)]).collect();
    let writes: Vec<_> = infos
        .iter()
        .enumerate()
        .map(|(i, info)| vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(vk::DescriptorType::STORAGE_BUFFER).buffer_info(info))
        .collect();
    // SAFETY: the pipeline, its layout and the buffers outlive the submission, which is waited for.
    unsafe {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipe.raw);
        gpu.ctx.push_descriptor.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::COMPUTE, pipe.layout, 0, &writes);
        d.cmd_push_constants(cmd, pipe.layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(params));
        d.cmd_dispatch(cmd, 1, 1, 1);
    }
}

#[test]
fn clean_work_reports_nothing() {
    let gpu = common::gpu();
    let mut b = Buffer::from_slice(&gpu.ctx, "roundtrip", &[1u32, 2, 3]).unwrap();
    assert_eq!(b.read::<u32>(3).unwrap(), vec![1, 2, 3]);
    let empty = Buffer::from_slice::<u32>(&gpu.ctx, "empty", &[]).unwrap();
    assert!(empty.size >= 16, "zero-sized inputs still get a valid buffer");
    common::assert_clean(&gpu);
}
