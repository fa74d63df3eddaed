//! `Buffer`: a VkBuffer with its memory, freed on Drop.

use super::barrier::transfer_to_host;
use super::context::Gpu;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use std::sync::Arc;

/// What to create: a builder-style value, so call sites read as a description.
#[derive(Clone, Debug)]
pub struct BufferDesc {
    /// Debug name, given to the allocator and used in error messages.
    pub name: String,
    /// Size in bytes; 0 is refused.
    pub size: u64,
    /// How the buffer is used; `Buffer::new` always adds TRANSFER_SRC and TRANSFER_DST.
    pub usage: vk::BufferUsageFlags,
    /// Which memory gpu_allocator picks: device-local, host-visible for upload, or host-visible for
    /// readback.
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// A device-local buffer; TRANSFER_SRC/DST are added so it can always be read back or filled.
    pub fn gpu_only(name: &str, size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self { name: name.into(), size, usage, location: MemoryLocation::GpuOnly }
    }
    /// A host-visible buffer the CPU writes and the GPU reads.
    pub fn upload(name: &str, size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self { name: name.into(), size, usage, location: MemoryLocation::CpuToGpu }
    }
    /// A host-visible buffer the GPU writes and the CPU reads.
    pub fn readback(name: &str, size: u64, usage: vk::BufferUsageFlags) -> Self {
        Self { name: name.into(), size, usage, location: MemoryLocation::GpuToCpu }
    }
}

/// A VkBuffer bound to its own gpu_allocator allocation. It holds an `Arc<Gpu>`, so the device
/// outlives it, and on Drop destroys the buffer and frees the memory; Vulkan requires that no
/// pending submission still uses it then.
pub struct Buffer {
    gpu: Arc<Gpu>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
}

impl Buffer {
    /// Create the buffer, allocate its memory and bind it. Fails on size 0; on any failure, what
    /// was made so far is destroyed.
    pub fn new(gpu: &Arc<Gpu>, desc: &BufferDesc) -> GpuResult<Buffer> {
        if desc.size == 0 {
            return Err(GpuError::EmptyBuffer { name: desc.name.clone() });
        }
        let device = gpu.device();
        let info = vk::BufferCreateInfo::default()
            .size(desc.size)
            .usage(desc.usage | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info; the buffer is destroyed in Drop or below on failure.
        let raw = unsafe { device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` was just created on this device and is not yet bound or destroyed.
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = gpu.allocator().allocate(&AllocationCreateDesc {
            name: &desc.name,
            requirements,
            location: desc.location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` was created above on this device and never used by a command, and
                // nothing else holds the handle.
                unsafe { device.destroy_buffer(raw, None) };
                return Err(GpuError::Alloc { what: desc.name.clone(), source });
            }
        };
        // SAFETY: the allocation satisfies `requirements` and is not bound elsewhere.
        if let Err(result) = unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            // SAFETY: `raw` was created above on this device and never used by a command; it is
            // destroyed before its (unbound) allocation is freed.
            unsafe { device.destroy_buffer(raw, None) };
            let _ = gpu.allocator().free(allocation);
            return Err(GpuError::Vk { what: "vkBindBufferMemory", result });
        }
        Ok(Buffer { gpu: gpu.clone(), raw, allocation: Some(allocation), size: desc.size, name: desc.name.clone() })
    }

    /// A host-visible buffer filled with `data`.
    pub fn from_slice<T: bytemuck::Pod>(
        gpu: &Arc<Gpu>,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> GpuResult<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Buffer::new(gpu, &BufferDesc::upload(name, bytes.len() as u64, usage))?;
        buffer.write(0, data)?;
        Ok(buffer)
    }

    /// The Vulkan handle, for recording commands and descriptor writes; this `Buffer` still owns
    /// it.
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }
    /// Size in bytes, as asked for (the allocation may be larger).
    pub fn size(&self) -> u64 {
        self.size
    }
    /// The debug name given at creation.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Write `data` at byte `offset`: directly if the memory is mapped, else through a staging copy.
    pub fn write<T: bytemuck::Pod>(&mut self, offset: u64, data: &[T]) -> GpuResult<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let end = offset + bytes.len() as u64;
        if end > self.size {
            return Err(GpuError::WriteOverflow {
                name: self.name.clone(),
                offset,
                bytes: bytes.len() as u64,
                size: self.size,
            });
        }
        if let Some(mapped) = self.allocation.as_mut().and_then(|a| a.mapped_slice_mut()) {
            mapped[offset as usize..end as usize].copy_from_slice(bytes);
            return Ok(());
        }
        let staging = Buffer::from_slice(&self.gpu, "staging upload", bytes, vk::BufferUsageFlags::TRANSFER_SRC)?;
        let device = self.gpu.device();
        self.gpu.one_shot("buffer upload", |cmd| {
            let region = [vk::BufferCopy { src_offset: 0, dst_offset: offset, size: bytes.len() as u64 }];
            // SAFETY: both buffers are alive and large enough (checked above).
            unsafe { device.cmd_copy_buffer(cmd, staging.raw, self.raw, &region) };
        })
    }

    /// Read the whole buffer as `T`s (its size must be a multiple of `size_of::<T>()`).
    /// The caller must have finished the GPU work that writes it (e.g. `Gpu::one_shot` returned)
    /// and made the writes available to the host (`barrier::memory_barrier` to HOST/HOST_READ).
    pub fn read<T: bytemuck::Pod>(&self) -> GpuResult<Vec<T>> {
        let item = std::mem::size_of::<T>() as u64;
        if item == 0 || !self.size.is_multiple_of(item) {
            return Err(GpuError::ReadItems { name: self.name.clone(), size: self.size, item });
        }
        let mut out = vec![T::zeroed(); (self.size / item) as usize];
        if let Some(mapped) = self.allocation.as_ref().and_then(|a| a.mapped_slice()) {
            bytemuck::cast_slice_mut(&mut out).copy_from_slice(&mapped[..self.size as usize]);
            return Ok(out);
        }
        let staging = Buffer::new(
            &self.gpu,
            &BufferDesc::readback("staging readback", self.size, vk::BufferUsageFlags::TRANSFER_DST),
        )?;
        let device = self.gpu.device();
        self.gpu.one_shot("buffer readback", |cmd| {
            let region = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: self.size }];
            // SAFETY: both buffers are alive and of the same size.
            unsafe { device.cmd_copy_buffer(cmd, self.raw, staging.raw, &region) };
            transfer_to_host(device, cmd);
        })?;
        staging.read()
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: GPU work using this buffer has completed: every submission waits on its fence.
        unsafe { self.gpu.device().destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take()
            && let Err(e) = self.gpu.allocator().free(a)
        {
            log::error!("freeing buffer {:?}: {e}", self.name);
        }
    }
}
