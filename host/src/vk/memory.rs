//! RAII buffers on `gpu-allocator`, with upload and read-back.
//!
//! Device-local buffers (`MemoryLocation::GpuOnly`) are filled and read through a temporary
//! staging buffer and a copy on the queue; host-visible ones are mapped. Vulkan forbids
//! zero-sized buffers, so sizes are rounded up to [`MIN_BUFFER_BYTES`] (an empty input is valid,
//! it just occupies one minimal buffer).
use super::context::Context;
use super::error::{CallContext, VkError, VkResult};
use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
pub use gpu_allocator::MemoryLocation;

/// Smallest buffer made (bytes).
pub const MIN_BUFFER_BYTES: u64 = 16;

/// Usage of every storage buffer: read/written by kernels, copied to/from staging, and read as
/// indirect dispatch arguments written by a kernel.
pub const STORAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw()
        | vk::BufferUsageFlags::INDIRECT_BUFFER.as_raw(),
);

pub struct Buffer {
    ctx: Context,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// Bytes (after rounding up).
    pub size: u64,
    pub name: String,
    pub location: MemoryLocation,
}

impl Buffer {
    /// A buffer of at least `size` bytes. A storage buffer (bound whole by every kernel) larger
    /// than one binding can address ([`check_range`]) is refused before anything is allocated.
    pub fn new(ctx: &Context, name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation) -> VkResult<Self> {
        Self::new_within(ctx, name, size, usage, location, ctx.info.max_storage_buffer_range as u64)
    }

    /// [`Buffer::new`] for a storage buffer whose length no kernel reads: it may take the whole
    /// `maxStorageBufferRange` the device reports (`DeviceInfo::reported_storage_buffer_range`:
    /// 4 GiB − 1 on NVIDIA), past the 2^31 − 1 bytes of the other bindings.
    pub fn length_free(ctx: &Context, name: &str, size: u64) -> VkResult<Self> {
        Self::new_within(ctx, name, size, STORAGE, MemoryLocation::GpuOnly, ctx.info.reported_storage_buffer_range as u64)
    }

    /// [`Buffer::from_slice`] in a [`Buffer::length_free`] buffer.
    pub fn length_free_from_slice<T: Pod>(ctx: &Context, name: &str, data: &[T]) -> VkResult<Self> {
        let mut b = Self::length_free(ctx, name, std::mem::size_of_val(data) as u64)?;
        b.write(data)?;
        Ok(b)
    }

    fn new_within(ctx: &Context, name: &str, size: u64, usage: vk::BufferUsageFlags, location: MemoryLocation, range: u64) -> VkResult<Self> {
        let size = size.max(MIN_BUFFER_BYTES).next_multiple_of(4);
        if usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) && size > range {
            return Err(VkError::TooLarge { what: name.into(), bytes: size, max: range });
        }
        let d = &ctx.device;
        // With an async-compute queue, buffers are shared by both families (CONCURRENT), so work
        // on either queue can use them without ownership transfers; semaphores order the access.
        let families = [ctx.info.graphics_family, ctx.info.async_compute_family.unwrap_or(ctx.info.graphics_family)];
        let info = match ctx.info.async_compute_family {
            Some(_) => vk::BufferCreateInfo::default().sharing_mode(vk::SharingMode::CONCURRENT).queue_family_indices(&families),
            None => vk::BufferCreateInfo::default().sharing_mode(vk::SharingMode::EXCLUSIVE),
        }
        .size(size)
        .usage(usage);
        let raw = unsafe { d.create_buffer(&info, None) }.call("vkCreateBuffer")?;
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocated = ctx.allocator.lock().unwrap_or_else(|e| e.into_inner()).allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocated {
            Ok(a) => a,
            Err(source) => {
                unsafe { d.destroy_buffer(raw, None) };
                return Err(VkError::Alloc { name: name.into(), bytes: size, source });
            }
        };
        if let Err(e) = unsafe { d.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }.call("vkBindBufferMemory") {
            let _ = ctx.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(allocation);
            unsafe { d.destroy_buffer(raw, None) };
            return Err(e);
        }
        ctx.set_name(raw, name);
        Ok(Self { ctx: ctx.clone(), raw, allocation: Some(allocation), size, name: name.into(), location })
    }

    /// A device-local storage buffer of `size` bytes (contents undefined until written).
    pub fn storage(ctx: &Context, name: &str, size: u64) -> VkResult<Self> {
        Self::new(ctx, name, size, STORAGE, MemoryLocation::GpuOnly)
    }

    /// A device-local storage buffer of `size` bytes, zero once at creation: for buffers whose
    /// kernels clear what they used, so that no frame clears them at capacity.
    pub fn zeroed(ctx: &Context, name: &str, size: u64) -> VkResult<Self> {
        Self::filled(ctx, name, size, 0)
    }

    /// A device-local storage buffer of `size` bytes, every word `value` once at creation (as
    /// [`Buffer::zeroed`]).
    pub fn filled(ctx: &Context, name: &str, size: u64, value: u32) -> VkResult<Self> {
        let b = Self::storage(ctx, name, size)?;
        let dst = b.raw;
        ctx.submit_and_wait(|cmd| {
            unsafe { ctx.device.cmd_fill_buffer(cmd, dst, 0, vk::WHOLE_SIZE, value) };
            barrier(ctx, cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
            Ok(())
        })?;
        Ok(b)
    }

    /// A device-local index (and storage) buffer holding `indices` (a word for none).
    pub fn indices(ctx: &Context, name: &str, indices: &[u32]) -> VkResult<Self> {
        Self::indices_reserving(ctx, name, indices, 0)
    }

    /// [`Buffer::indices`] with room for `extra` more indices after them (written by kernels;
    /// undefined until then).
    pub fn indices_reserving(ctx: &Context, name: &str, indices: &[u32], extra: u64) -> VkResult<Self> {
        let bytes = 4 * (indices.len() as u64 + extra).max(1);
        let mut b = Self::new(ctx, name, bytes, STORAGE | vk::BufferUsageFlags::INDEX_BUFFER, MemoryLocation::GpuOnly)?;
        b.write(indices)?;
        Ok(b)
    }

    /// A device-local storage buffer holding `data`.
    pub fn from_slice<T: Pod>(ctx: &Context, name: &str, data: &[T]) -> VkResult<Self> {
        Self::from_slice_reserving(ctx, name, data, 0)
    }

    /// [`Buffer::from_slice`] with room for `extra` more elements after `data` (written by
    /// kernels; undefined until then).
    pub fn from_slice_reserving<T: Pod>(ctx: &Context, name: &str, data: &[T], extra: u64) -> VkResult<Self> {
        let bytes = std::mem::size_of::<T>() as u64 * (data.len() as u64 + extra);
        let mut b = Self::storage(ctx, name, bytes)?;
        b.write(data)?;
        Ok(b)
    }

    fn mapped(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut().and_then(|a| a.mapped_slice_mut())
    }

    /// Writes `data` at the start of the buffer (mapped, or staged and copied).
    pub fn write<T: Pod>(&mut self, data: &[T]) -> VkResult<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let need = bytes.len() as u64;
        if need > self.size {
            return Err(VkError::BufferTooSmall { name: self.name.clone(), have: self.size, need });
        }
        if need == 0 {
            return Ok(());
        }
        if let Some(m) = self.mapped() {
            m[..bytes.len()].copy_from_slice(bytes);
            return Ok(());
        }
        let mut staging = Self::new(
            &self.ctx,
            &format!("{} (upload)", self.name),
            need,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        staging.write(data)?;
        let (src, dst) = (staging.raw, self.raw);
        self.ctx.submit_and_wait(|cmd| {
            let region = [vk::BufferCopy::default().size(need)];
            unsafe { self.ctx.device.cmd_copy_buffer(cmd, src, dst, &region) };
            barrier(&self.ctx, cmd, vk::AccessFlags::TRANSFER_WRITE, vk::PipelineStageFlags::TRANSFER);
            Ok(())
        })
    }

    /// Reads the first `count` elements back to the host.
    pub fn read<T: Pod>(&mut self, count: usize) -> VkResult<Vec<T>> {
        let need = (count * std::mem::size_of::<T>()) as u64;
        if need > self.size {
            return Err(VkError::BufferTooSmall { name: self.name.clone(), have: self.size, need });
        }
        if need == 0 {
            return Ok(Vec::new());
        }
        if let Some(m) = self.mapped() {
            return Ok(bytemuck::pod_collect_to_vec(&m[..need as usize]));
        }
        let mut staging = Self::new(
            &self.ctx,
            &format!("{} (read-back)", self.name),
            need,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let (src, dst) = (self.raw, staging.raw);
        self.ctx.submit_and_wait(|cmd| {
            let region = [vk::BufferCopy::default().size(need)];
            unsafe { self.ctx.device.cmd_copy_buffer(cmd, src, dst, &region) };
            let host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            unsafe {
                self.ctx.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &[host],
                    &[],
                    &[],
                )
            };
            Ok(())
        })?;
        staging.read(count)
    }
}

/// Fails with a clear error when `bytes` exceed what one storage-buffer binding can address on
/// this device (`maxStorageBufferRange`: 128 MiB on lavapipe).
pub fn check_range(ctx: &Context, what: &str, bytes: u64) -> VkResult<()> {
    let max = ctx.info.max_storage_buffer_range as u64;
    if bytes > max {
        return Err(VkError::TooLarge { what: what.into(), bytes, max });
    }
    Ok(())
}

/// Makes prior writes (`src_access` in `src_stage`) visible to later compute shaders and copies.
pub fn barrier(ctx: &Context, cmd: vk::CommandBuffer, src_access: vk::AccessFlags, src_stage: vk::PipelineStageFlags) {
    let b = vk::MemoryBarrier::default().src_access_mask(src_access).dst_access_mask(
        vk::AccessFlags::SHADER_READ
            | vk::AccessFlags::SHADER_WRITE
            | vk::AccessFlags::TRANSFER_READ
            | vk::AccessFlags::TRANSFER_WRITE
            | vk::AccessFlags::INDIRECT_COMMAND_READ,
    );
    unsafe {
        ctx.device.cmd_pipeline_barrier(
            cmd,
            src_stage,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::DRAW_INDIRECT,
            vk::DependencyFlags::empty(),
            &[b],
            &[],
            &[],
        )
    };
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator.lock().unwrap_or_else(|e| e.into_inner()).free(a);
        }
        // SAFETY: every submission using the buffer was waited for (`submit_and_wait`).
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
    }
}
